//! WebGPU's defaults (issue 16 item 5): every technique runs on a device started with
//! `WgpuLimits::default()` (8 storage buffers and 4 storage textures per stage, 128 MiB
//! bindings) and gives the same caustics as with the adapter's own limits; without the optional
//! features `FLOAT32_BLENDABLE` and `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES` (4x MSAA of
//! `Rgba32Float`), AAPS and the volumes fall back (fixed-point splats, no small-splat MSAA)
//! instead of turning off.

use bevy::prelude::World;
use bevy::render::settings::WgpuFeatures;
use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::{Caustics, CausticsTechnique as T};

use crate::{GPU, require_gpu, scene};

/// The techniques in the order one run switches through them (volumes first: the job fits
/// their volumes when it starts on them).
const CYCLE: [T; 4] = [T::Volume, T::Aaps, T::ImageSpace, T::PhotonMap];
/// Frames each technique renders before the next one takes over.
const SEGMENT: u32 = 4;

fn cycle(world: &mut World, n: u32) {
    let technique = CYCLE[((n / SEGMENT) as usize).min(CYCLE.len() - 1)];
    for mut c in world.query::<&mut Caustics>().iter_mut(world) {
        if c.technique != technique {
            c.technique = technique;
        }
    }
}

/// One run through every technique on `name` at 32²: the total irradiance (lux · pixels,
/// summed over RGB) of each technique's last frame, in `CYCLE` order.
fn energies(name: &str, webgpu_limits: bool, disabled_features: WgpuFeatures) -> [f64; 4] {
    let report: RenderReport = run(RenderJob {
        scene: scene(name),
        technique: T::Volume,
        width: 32,
        height: 32,
        photons: Some(1 << 14),
        frames: SEGMENT * CYCLE.len() as u32,
        per_frame: Some(cycle),
        every_frame: true,
        webgpu_limits,
        disabled_features,
        // SVGF off: each frame stands alone, so the comparison does not depend on how many
        // frames the denoiser's history has accumulated when the segment ends. 256² maps: the
        // limits and features under test do not depend on the maps' side (1024² took most of
        // this test's time).
        image_space: bevy_caustics::ImageSpaceSettings {
            denoise: false,
            rsm_resolution: 256,
            ..Default::default()
        },
        ..Default::default()
    })
    .expect("render");
    // The first two readbacks are the camera's first two frames; measured frame n is at n + 2.
    let frames = &report.frame_caustics;
    assert_eq!(frames.len(), (SEGMENT as usize) * CYCLE.len() + 2);
    std::array::from_fn(|k| {
        let last = (k + 1) * SEGMENT as usize;
        let prefix = format!("caustics/{}/", CYCLE[k].name());
        // The segment's last frame ran the technique (the log of frame n holds what the
        // render world ran for frame n - 1, the headless renderer running frame by frame).
        let tail = &report.frame_passes[last - 1];
        assert!(
            tail.iter().any(|p| p.starts_with(&prefix)),
            "{name}: frame {} ran {tail:?}, not {prefix}",
            last - 1
        );
        // The segment's last frame, `last - 1`.
        let image = &frames[last + 1];
        assert!(image.all_finite(), "{name}: {:?} not finite", CYCLE[k]);
        let s = image.sum();
        s.x + s.y + s.z
    })
}

/// `glass_sphere` and `ring`, each technique: the same energy within 0.1 % with WebGPU's
/// default limits as with the adapter's. On `glass_sphere`, also without the optional
/// features: without 4x MSAA of `Rgba32Float`, AAPS draws its small splats with the plain ones
/// (still lit, the others unchanged within 0.1 %); without `FLOAT32_BLENDABLE` as well, AAPS
/// and the volumes add their splats in fixed point, within 0.1 % of the blended splats.
#[test]
fn webgpu_default_limits_and_missing_features() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-30);
    let check = |what: &str, name: &str, got: &[f64; 4], base: &[f64; 4], skip_aaps: bool| {
        for (k, t) in CYCLE.iter().enumerate() {
            println!(
                "{name} {t:?}: {what} {:.1} vs {:.1} ({:+.4} %)",
                got[k],
                base[k],
                100.0 * (got[k] - base[k]) / base[k]
            );
            // A known limit: `ring`'s bulb sits inside its fitted volume, which then seeds
            // nothing (docs/volumes.md); it must stay nothing.
            if name == "ring" && *t == T::Volume {
                assert_eq!(got[k], base[k], "{name} {t:?}: {what}");
                continue;
            }
            assert!(got[k] > 0.0, "{name} {t:?}: no caustic at all ({what})");
            if skip_aaps && *t == T::Aaps {
                continue;
            }
            assert!(
                rel(got[k], base[k]) <= 1e-3,
                "{name} {t:?}: {what} {} vs {}",
                got[k],
                base[k]
            );
        }
    };
    for name in ["glass_sphere", "ring"] {
        let own = energies(name, false, WgpuFeatures::empty());
        let webgpu = energies(name, true, WgpuFeatures::empty());
        check("WebGPU limits vs own", name, &webgpu, &own, false);
        if name != "glass_sphere" {
            continue;
        }
        let no_msaa = energies(
            name,
            true,
            WgpuFeatures::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES,
        );
        check("no Rgba32Float MSAA vs all", name, &no_msaa, &own, true);
        let bare = energies(
            name,
            true,
            WgpuFeatures::FLOAT32_BLENDABLE
                | WgpuFeatures::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES,
        );
        check("fixed point vs blending", name, &bare, &no_msaa, false);
    }
}
