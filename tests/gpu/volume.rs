//! Caustics volumes on lavapipe: closed forms and energy, error against the CPU reference for
//! 1 to 3 slabs, differential updates counted pass by pass, frustum culling, stress.

use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::reference::{CausticImage, compare, plane_region_mean};
use bevy_caustics::{CausticsTechnique, CausticsVolume, scenes};
use glam::Vec3;

use super::{GPU, require_gpu, scene};

fn volume(
    path: std::path::PathBuf,
    size: u32,
    frames: u32,
    settings: CausticsVolume,
) -> RenderReport {
    run(RenderJob {
        scene: path.clone(),
        technique: CausticsTechnique::Volume,
        width: size,
        height: size,
        frames,
        volume: settings,
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn reference(name: &str) -> CausticImage {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("assets/reference/{name}_128.exr"));
    CausticImage::read_exr(&p).expect("cached reference")
}

/// A volume fitted around `mirror_wall`'s mirror and one around `glass_slab`'s slab: mean
/// caustic irradiance over the interior of the lit region within 10 % of the closed form, and
/// no energy created (flux splatted <= flux entering the volume).
#[test]
fn volume_closed_forms_and_energy() {
    let _g = GPU.lock().unwrap_or_else(|e| e.into_inner());
    if !require_gpu() {
        return;
    }
    use bevy_caustics::optics::{fresnel_dielectric, fresnel_schlick};
    let a = scenes::MIRROR_WALL_INCIDENCE;
    let mirror = scenes::SUN_LUX * fresnel_schlick(a.cos(), Vec3::splat(0.9)).x * a.sin();
    let b = scenes::GLASS_SLAB_INCIDENCE;
    let r = fresnel_dielectric(b.cos(), 1.0 / 1.5);
    let slab = scenes::SUN_LUX * b.cos() * (1.0 - r) / (1.0 + r);
    type Region = fn(Vec3) -> bool;
    let cases: [(scenes::SceneDesc, Vec3, f32, Region, f32); 2] = [
        (
            scenes::mirror_wall(),
            Vec3::NEG_X,
            -3.0,
            |p| (2.75..3.25).contains(&p.y) && p.z.abs() < 0.25,
            mirror,
        ),
        (
            scenes::glass_slab(),
            Vec3::Y,
            0.0,
            |p| (0.4..0.8).contains(&p.x) && p.z.abs() < 0.3,
            slab,
        ),
    ];
    for (desc, n, d, region, expect) in cases {
        let report = volume(scene(&desc.name), 128, 4, CausticsVolume::default());
        let img = report.caustics.expect("caustics");
        assert!(img.all_finite());
        let (_, _, cam) = desc.to_trace(128, 128);
        let (mean, px) = plane_region_mean(&img, &cam, n, d, region);
        let err = mean / expect - 1.0;
        let c = report.volume.clone().expect("counters");
        println!(
            "{}: volume mean {mean:.1} lx over {px} px, closed form {expect:.1} lx, error {:+.2} %, {c:?}, {:?}",
            desc.name,
            err * 100.0,
            report.pass_ms
        );
        assert!(px > 200);
        assert!(err.abs() < 0.10, "{}: {:+.2} %", desc.name, err * 100.0);
        assert!(
            c.entered_lm > 0.0 && c.splatted_lm <= c.entered_lm * (1.0 + 1e-5),
            "{c:?}"
        );
        assert_eq!(c.nan_guards, 0);
    }
}
