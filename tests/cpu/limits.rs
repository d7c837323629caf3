//! The maxima of the sizes (src/limits.rs): derived from a device's limits, clamped on
//! components with one fix each, refused by `check_job` with one line naming the option.

use bevy::render::render_resource::WgpuLimits;
use bevy_caustics::components::validate::{sanitize_aaps, sanitize_caustics, sanitize_volume};
use bevy_caustics::headless::{RenderJob, check_job};
use bevy_caustics::limits::{CausticsLimits, MAX_FRAMES, MAX_REFERENCE_PHOTONS};
use bevy_caustics::{AapsSettings, Caustics, CausticsQuality, CausticsTechnique, CausticsVolume};

/// WebGPU's default device (128 MiB bindings, 256 MiB buffers, 8192² textures, 256 layers).
#[test]
fn limits_of_the_webgpu_default_device() {
    let l = CausticsLimits::default();
    assert_eq!(l.max_image_side, 8192);
    assert_eq!(l.max_binding_bytes, 128 << 20);
    // 128 MiB / 64 bytes, less the 4-splat guard.
    assert_eq!(l.max_splat_capacity, 2_097_148);
    assert_eq!(l.max_aaps_photons, 2_097_148);
    assert_eq!(l.max_atlas_resolution, 1024);
    // One slab: 128 MiB / 64 bytes; 16 slabs: a 16th.
    assert_eq!(l.max_volume_photons, 2_097_152);
    assert_eq!(l.volume_photons(16), 131_072);
    assert_eq!(l.max_volume_slabs, 64);
    // 256 MiB / 64 bytes per pixel (the 4x MSAA Rgba32Float target): 2048².
    assert_eq!(l.max_view_pixels, 2048 * 2048);
    // 64 slabs = 128 layers of 16 bytes in 256 MiB: side 362; 2 slabs: 2048; 3 slabs (6
    // layers, as the projectors): 1672; the default 200 fits either way.
    assert_eq!(l.volume_gbuffer_side(4096, 64), 362);
    assert_eq!(l.volume_gbuffer_side(4096, 2), 2048);
    assert_eq!(l.volume_gbuffer_side(4096, 3), 1672);
    assert_eq!(l.volume_gbuffer_side(200, 64), 200);
    assert_eq!(l.volume_projector_side(4096), 1672);
    assert_eq!(
        l.max_photons(CausticsTechnique::Reference),
        MAX_REFERENCE_PHOTONS
    );
    // The defaults fit the smallest device: no warning for a user who changed nothing.
    assert!(sanitize_aaps(&mut AapsSettings::default(), &l).is_empty());
    assert!(sanitize_volume(&mut CausticsVolume::default(), &l).is_empty());
    assert!(sanitize_caustics(&mut Caustics::default(), &l).is_empty());
}

/// A device with tiny limits shrinks every maximum, never to zero.
#[test]
fn limits_of_a_tiny_device() {
    let tiny = WgpuLimits {
        max_storage_buffer_binding_size: 1 << 16,
        max_buffer_size: 1 << 16,
        max_texture_dimension_2d: 64,
        max_texture_array_layers: 1,
        ..WgpuLimits::downlevel_webgl2_defaults()
    };
    let l = CausticsLimits::new(&tiny);
    assert_eq!(l.max_image_side, 64);
    assert_eq!(l.max_splat_capacity, 1020);
    assert_eq!(l.max_atlas_resolution, 64);
    assert_eq!(l.max_volume_slabs, 1);
    assert_eq!(l.max_volume_resolution, 64);
    assert!(l.volume_gbuffer_side(4096, 1) >= 16);
    assert!(l.max_view_pixels >= 1 && l.max_volume_photons >= 1);
}

/// Components: a size above the device's maximum is clamped to it, one fix per field.
#[test]
fn components_are_clamped_to_the_device() {
    let l = CausticsLimits::default();
    for (technique, max) in [
        (CausticsTechnique::Aaps, 2_097_148u64),
        (CausticsTechnique::Reference, MAX_REFERENCE_PHOTONS),
    ] {
        let mut c = Caustics {
            technique,
            quality: CausticsQuality::Custom {
                photons: 99_999_999_999_999,
            },
            ..Default::default()
        };
        let fixes = sanitize_caustics(&mut c, &l);
        assert_eq!(fixes.len(), 1, "{fixes:?}");
        assert_eq!(c.quality, CausticsQuality::Custom { photons: max });
        assert!(sanitize_caustics(&mut c, &l).is_empty());
    }
    let mut a = AapsSettings {
        splat_capacity: u32::MAX,
        atlas_resolution: 1 << 20,
        ..Default::default()
    };
    let fixed: Vec<_> = sanitize_aaps(&mut a, &l).iter().map(|f| f.0).collect();
    assert_eq!(fixed, ["atlas_resolution", "splat_capacity"]);
    assert_eq!((a.atlas_resolution, a.splat_capacity), (1024, 2_097_148));
    let mut v = CausticsVolume {
        slabs: 64,
        photons: i32::MAX,
        gbuffer_resolution: 100_000,
        projector_resolution: 100_000,
        ..Default::default()
    };
    let fixed: Vec<_> = sanitize_volume(&mut v, &l).iter().map(|f| f.0).collect();
    assert_eq!(
        fixed,
        ["photons", "projector_resolution", "gbuffer_resolution"]
    );
    assert_eq!(
        (v.photons, v.projector_resolution, v.gbuffer_resolution),
        (32_768, 1672, 362)
    );
    assert!(sanitize_volume(&mut v, &l).is_empty());
}

/// The headless job: sizes past the maxima are refused with one line naming the option.
#[test]
fn check_job_refuses_sizes_past_the_maxima() {
    let l = CausticsLimits::default();
    let ok = RenderJob {
        scene: "x.gltf".into(),
        width: 64,
        height: 64,
        ..Default::default()
    };
    assert_eq!(check_job(&ok, &l), Ok(()));
    let refused = |job: RenderJob, needle: &str| {
        let e = check_job(&job, &l).expect_err(needle);
        assert!(e.contains(needle), "{e}");
        assert!(!e.contains('\n'), "one line: {e}");
    };
    refused(
        RenderJob {
            width: 0,
            ..ok.clone()
        },
        "image size 0x64",
    );
    refused(
        RenderJob {
            height: 100_000,
            ..ok.clone()
        },
        "outside 1..=8192",
    );
    refused(
        RenderJob {
            width: 4096,
            height: 4096,
            ..ok.clone()
        },
        "this GPU allows 4194304",
    );
    refused(
        RenderJob {
            frames: 0,
            ..ok.clone()
        },
        "--frames 0",
    );
    refused(
        RenderJob {
            frames: MAX_FRAMES + 1,
            ..ok.clone()
        },
        "outside 1..=10000",
    );
    for t in [
        CausticsTechnique::Reference,
        CausticsTechnique::Aaps,
        CausticsTechnique::Volume,
    ] {
        refused(
            RenderJob {
                technique: t,
                photons: Some(99_999_999_999_999),
                ..ok.clone()
            },
            "--photons 99999999999999",
        );
        for p in [0, 1, 1 << 20] {
            let job = RenderJob {
                technique: t,
                photons: Some(p),
                ..ok.clone()
            };
            assert_eq!(check_job(&job, &l), Ok(()), "{t:?} {p}");
        }
    }
    let mut aaps = ok.clone();
    aaps.aaps.splat_capacity = u32::MAX;
    refused(aaps, "--aaps splat_capacity");
    let mut vol = ok.clone();
    vol.volume.gbuffer_resolution = 100_000;
    refused(vol, "--volume gbuffer_resolution");
}
