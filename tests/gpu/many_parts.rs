//! Many-part models (issue 32 item 3): a sheet of 24 glass balls with label quads and an
//! engine-like block of 30 glass and metal parts (`scenes::many`), every technique against the
//! CPU reference tracer on the same camera. The caustic total (the luminance of the caustic
//! irradiance summed over the image's receiver pixels) must be finite, non-zero and within
//! 20 % of the reference's for AAPS and the photon map (both trace full paths: what remains is
//! their splat or gather footprint at the image's edges and the receivers' silhouettes), and
//! within 35 % for image space and caustics volumes (image space follows one interface plus the
//! exit of each caster seen from the light; a volume's slabs resolve a few interactions per
//! slab). One run per technique per model at 96 x 72, few frames.

use std::time::Instant;

use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::reference::{CausticImage, TraceSettings, compare, trace};
use bevy_caustics::scenes::{self, SceneDesc, many};
use bevy_caustics::{CausticsTechnique, CausticsVolume};

use super::{GPU, require_gpu};

const W: u32 = 96;
const H: u32 = 72;

fn write(desc: &SceneDesc) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("bevy_caustics_many_{}", std::process::id()));
    scenes::gltf::write_gltf(desc, &dir).unwrap();
    dir.join(format!("{}.gltf", desc.name))
}

/// The CPU reference's caustic image at `W x H` (2^21 photons: the total's noise is well
/// under 1 %).
fn reference(desc: &SceneDesc) -> CausticImage {
    let (tlas, lights, cam) = desc.to_trace(W, H);
    let out = trace(
        &tlas,
        &lights,
        &cam,
        &TraceSettings {
            photons_per_light: 1 << 21,
            ..Default::default()
        },
        None,
    );
    assert!(
        out.image.all_finite(),
        "{}: reference not finite",
        desc.name
    );
    println!(
        "{}: reference on casters {:.0} lm, deposited {:.0} lm, in view {} photons, at the cap {}, tir {}",
        desc.name,
        out.stats.flux_on_casters.y,
        out.stats.flux_deposited.y,
        out.stats.photons_in_view,
        out.stats.photons_max_depth,
        out.stats.tir_events
    );
    out.image
}

fn render(path: &std::path::Path, technique: CausticsTechnique) -> (RenderReport, f64) {
    let t0 = Instant::now();
    let report = run(RenderJob {
        scene: path.to_path_buf(),
        technique,
        width: W,
        height: H,
        photons: Some(1 << 17),
        frames: 4,
        warmup_frames: 2,
        volume: CausticsVolume {
            photons: 40_000,
            ..Default::default()
        },
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("{}: {technique:?}: {e}", path.display()));
    (report, t0.elapsed().as_secs_f64())
}

/// What each technique says it lost, one line for the table.
fn counters(r: &RenderReport) -> String {
    if let Some(c) = &r.aaps {
        format!(
            "tasks {} splats {} dropped {} max_depth {} tir {} nan {}",
            c.tasks, c.splats, c.dropped, c.max_depth, c.tir, c.nan_guards
        )
    } else if let Some(c) = &r.photon_map {
        format!(
            "on casters {:.0} lm deposited {:.0} lm at the cap {:.1} lm, missed {} overflow {} tir {} nan {}",
            c.flux_on_casters,
            c.flux_deposited,
            c.flux_max_depth,
            c.missed,
            c.overflow,
            c.tir,
            c.nan_guards
        )
    } else if let Some(c) = &r.image_space {
        format!(
            "emitted {} light_misses {} misses {} normal_rejects {} tir {} nan {}",
            c.photons_emitted, c.light_misses, c.misses, c.normal_rejects, c.tir, c.nan_guards
        )
    } else if let Some(v) = &r.volume {
        format!(
            "entered {:.0} lm splatted {:.0} lm, missed {} step_limit {} specular_outside {} tir {} nan {}",
            v.entered_lm,
            v.splatted_lm,
            v.missed,
            v.step_limit,
            v.specular_outside,
            v.tir,
            v.nan_guards
        )
    } else {
        String::new()
    }
}

/// Every technique's caustic total on both many-part models within its band of the reference's.
#[test]
fn many_part_models_agree_with_reference() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let bands = [
        (CausticsTechnique::Aaps, 0.20),
        (CausticsTechnique::PhotonMap, 0.20),
        (CausticsTechnique::ImageSpace, 0.35),
        (CausticsTechnique::Volume, 0.35),
    ];
    let mut failures = vec![];
    for desc in [many::glass_sheet(), many::glass_engine()] {
        let path = write(&desc);
        let truth = reference(&desc);
        for (technique, band) in bands {
            let (report, wall) = render(&path, technique);
            let image = report.caustics.as_ref().expect("caustics read back");
            let m = compare(image, &truth, None).expect("same size");
            let ratio = 1.0 + m.energy_error;
            let frame = report.frame_ms.iter().sum::<f64>() / report.frame_ms.len().max(1) as f64;
            println!(
                "| {} | {technique:?} | {ratio:.3} | {frame:.0} ms/frame | {wall:.1} s run | {}",
                desc.name,
                counters(&report)
            );
            if !image.all_finite() {
                failures.push(format!("{} {technique:?}: non-finite", desc.name));
            } else if (ratio - 1.0).abs() >= band {
                failures.push(format!(
                    "{} {technique:?}: total {ratio:.3}x the reference (band ±{:.0} %)",
                    desc.name,
                    band * 100.0
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
