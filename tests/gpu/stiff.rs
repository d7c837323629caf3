//! Every stiff-and-extreme case (`scenes::stiff::cases`) through the whole GPU path (glTF
//! import, caustics buffer, composite), one test per technique so the suite fills both GPU
//! slots, each rendering its cases one after another in one app (`headless::run_all`, as a game
//! loads level after level): every buffer read back is finite, the clamps are counted, the gem
//! conserves energy.

use std::path::PathBuf;

use bevy_caustics::headless::{RenderJob, RenderReport, run_all};
use bevy_caustics::scenes::stiff::{StiffCase, cases};
use bevy_caustics::{CausticsTechnique, CausticsVolume, ImageSpaceSettings, PhotonMapSettings};

use super::energy::reference_power;
use super::support::{GPU, require_gpu};

const GEM: &str = "total internal reflection paths (IOR 2.4 gem)";

/// One stiff case written as glTF: its index, the case, and the file.
struct Written {
    i: usize,
    case: StiffCase,
    path: PathBuf,
}

/// Writes every case to a temporary folder of its own (`tag` keeps tests running side by
/// side apart).
fn written(tag: &str) -> Vec<Written> {
    let dir =
        std::env::temp_dir().join(format!("bevy_caustics_stiff_{tag}_{}", std::process::id()));
    cases()
        .into_iter()
        .enumerate()
        .map(|(i, mut case)| {
            case.scene.name = format!("stiff_{i}");
            // glTF cannot carry out-of-range indices (the loader rejects the file with a clear
            // error): keep the zero-area, collinear and NaN-vertex triangles only.
            for m in &mut case.scene.meshes {
                let n = m.positions.len() as u32;
                if m.indices.iter().any(|t| t.iter().any(|&k| k >= n)) {
                    let mut g = (**m).clone();
                    g.indices.retain(|t| t.iter().all(|&k| k < n));
                    *m = std::sync::Arc::new(g);
                }
            }
            bevy_caustics::scenes::gltf::write_gltf(&case.scene, &dir).unwrap();
            let path = dir.join(format!("stiff_{i}.gltf"));
            Written { i, case, path }
        })
        .collect()
}

/// Renders `job` of every case in one app: the reports, in the cases' order (a job's error
/// panics with its case's name).
fn render_all(
    cases: &[Written],
    technique: &str,
    job: impl Fn(&Written) -> RenderJob,
) -> Vec<RenderReport> {
    let results = run_all(cases.iter().map(job).collect());
    let reports: Vec<RenderReport> = cases
        .iter()
        .zip(results)
        .map(|(w, r)| r.unwrap_or_else(|e| panic!("{} ({technique}): {e}", w.case.name)))
        .collect();
    assert_eq!(reports.len(), cases.len(), "{technique}: jobs left out");
    reports
}

/// AAPS on every case (32², up to 2^16 photons): finite caustics; in the gem's closed room of
/// receivers the flux deposited is the flux on the casters within 3 %.
#[test]
fn stiff_cases_aaps() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let cases = written("aaps");
    let reports = render_all(&cases, "aaps", |w| RenderJob {
        scene: w.path.clone(),
        technique: CausticsTechnique::Aaps,
        width: 32,
        height: 32,
        photons: Some(w.case.photons.min(1 << 16)),
        frames: 4,
        ..Default::default()
    });
    for (w, r) in cases.iter().zip(reports) {
        let name = w.case.name;
        println!("{name:<48} aaps {:?}", r.aaps);
        if name == GEM {
            let c = r.aaps.as_ref().expect("AAPS counters");
            let err = c.flux_deposited / c.flux_on_casters - 1.0;
            println!("{name:<48} aaps energy {:+.2} %", err * 100.0);
            assert!(err.abs() < 0.03, "gem (aaps): {:+.2} %", err * 100.0);
        }
        let finite = r.caustics.as_ref().unwrap().all_finite();
        assert!(finite, "{name} (aaps): non-finite caustics");
    }
}

/// Image space on every case (64² RSMs, up to 2^14 photons; odd cases march the Hi-Z
/// pyramids): finite caustics past the clamps the counters report.
#[test]
fn stiff_cases_image_space() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let cases = written("image_space");
    let reports = render_all(&cases, "image_space", |w| RenderJob {
        scene: w.path.clone(),
        technique: CausticsTechnique::ImageSpace,
        width: 32,
        height: 32,
        photons: Some(w.case.photons.min(1 << 14)),
        frames: 4,
        image_space: ImageSpaceSettings {
            rsm_resolution: 64,
            hi_z: w.i % 2 == 1,
            ..Default::default()
        },
        ..Default::default()
    });
    for (w, r) in cases.iter().zip(reports) {
        let name = w.case.name;
        println!("{name:<48} image_space {:?}", r.image_space);
        let finite = r.caustics.as_ref().unwrap().all_finite();
        assert!(finite, "{name} (image_space): non-finite caustics");
    }
}

/// The photon map on every case: odd cases with a grid far too small for the photons' bounds
/// (4096 cells at r = 1e-4 of the casters' radius: the cells must double, counted) and the
/// adaptive radius on (`gather_photons` 64); the
/// million-photon case traces 2^22 photons (the most 32-byte photons one 128 MiB binding
/// holds) and stores about a million with a radius as large as the ball, so its focus falls
/// into a handful of cells.
#[test]
fn stiff_cases_photon_map() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let million = |w: &Written| w.case.photons >= 1 << 20;
    let cases = written("photon_map");
    let reports = render_all(&cases, "photon_map", |w| {
        let settings = if million(w) {
            // One traced frame (then the mean is frozen): lavapipe traces 4 M photons in
            // about 8 s.
            PhotonMapSettings {
                radius: 1.0,
                max_frames: 1,
                ..Default::default()
            }
        } else if w.i % 2 == 1 {
            // With the adaptive radius, too (frames 2 to 4 size each pixel by its density).
            PhotonMapSettings {
                radius: 1e-4,
                max_grid_cells: 4096,
                gather_photons: 64.0,
                ..Default::default()
            }
        } else {
            Default::default()
        };
        // The million-photon case at its own 4 x 4 target: each pixel gathers from up to
        // 620 000 photons.
        let side = if million(w) { w.case.size } else { 32 };
        RenderJob {
            scene: w.path.clone(),
            technique: CausticsTechnique::PhotonMap,
            width: side,
            height: side,
            photons: Some(if million(w) {
                1 << 22
            } else {
                w.case.photons.min(1 << 16)
            }),
            frames: 4,
            photon_map: settings,
            ..Default::default()
        }
    });
    for (w, r) in cases.iter().zip(reports) {
        let name = w.case.name;
        let million = million(w);
        println!("{name:<48} photon_map {:?}", r.photon_map);
        let finite = r.caustics.as_ref().unwrap().all_finite();
        assert!(finite, "{name} (photon_map): non-finite caustics");
        let Some(c) = r.photon_map.as_ref() else {
            continue;
        };
        if w.i % 2 == 1 && !million && c.photons_stored > 1 {
            assert!(c.coarsened > 0, "{name}: grid not coarsened: {c:?}");
            assert!(c.grid_cells <= 4096, "{name}: {c:?}");
        }
        if million {
            assert!(c.photons_stored >= 950_000, "{name}: {c:?}");
        }
    }
}

/// Caustics volumes on every case (one fitted per light, 3 slabs): finite, no flux created;
/// the gem (G-buffers that resolve its facets: 200², the CLI default) splats the power on it
/// within 10 %.
#[test]
fn stiff_cases_volume() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let cases = written("volume");
    let reports = render_all(&cases, "volume", |w| {
        let g = if w.case.name == GEM { 200 } else { 64 };
        RenderJob {
            scene: w.path.clone(),
            technique: CausticsTechnique::Volume,
            width: 32,
            height: 32,
            frames: 4,
            volume: CausticsVolume {
                photons: w.case.photons.min(1 << 16) as i32,
                gbuffer_resolution: g,
                projector_resolution: g,
                ..Default::default()
            },
            ..Default::default()
        }
    });
    for (w, r) in cases.iter().zip(reports) {
        let name = w.case.name;
        let on_gem = (name == GEM).then(|| reference_power(&w.case.scene).0);
        println!("{name:<48} volume {:?}", r.volume);
        let finite = r.caustics.as_ref().unwrap().all_finite();
        assert!(finite, "{name} (volume): non-finite caustics");
        let c = r.volume.as_ref().expect("volume counters");
        assert!(
            c.splatted_lm <= c.entered_lm * (1.0 + 1e-5),
            "{name}: {c:?}"
        );
        if let Some(on_gem) = on_gem {
            let err = c.splatted_lm / on_gem - 1.0;
            println!("{name:<48} volume energy {:+.2} %", err * 100.0);
            assert!(err.abs() < 0.10, "gem (volume): {:+.2} %", err * 100.0);
        }
    }
}

/// The whole frame (the job's default technique, the CPU reference, up to 2^18 photons,
/// uploaded into the caustics buffer and composited): every linear pixel is finite.
#[test]
fn stiff_cases_whole_frame() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let cases = written("frame");
    let reports = render_all(&cases, "reference", |w| RenderJob {
        scene: w.path.clone(),
        width: 32,
        height: 32,
        photons: Some(w.case.photons.min(1 << 18)),
        frames: 4,
        linear: true,
        ..Default::default()
    });
    for (w, r) in cases.iter().zip(reports) {
        let name = w.case.name;
        let finite = r
            .linear_with
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite()));
        println!(
            "{name:<48} passes {:?} photons {} finite {finite}",
            r.passes, r.photons_traced
        );
        assert!(finite, "{name}: non-finite pixel in the frame");
        assert_eq!(r.linear_with.len(), 32 * 32, "{name}");
        assert!(r.caustics.unwrap().all_finite(), "{name}");
    }
}

/// A job later in a batch renders as it did before (nothing of the jobs between stays): in one
/// app, every technique on `glass_sphere`, then on `ring`, then on `glass_sphere` again, at 32²:
/// each technique's second `glass_sphere` against its first (the first AAPS job is the app's
/// first, as alone), energy within 0.5 % and RMSE within 2 % of the mean irradiance (measured:
/// identical). A batch stops at a job it cannot render: its error is the last result.
#[test]
fn a_batch_job_renders_as_it_did_before() {
    use bevy_caustics::CausticsTechnique as T;
    use bevy_caustics::reference::compare;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let job = |name: &str, technique| RenderJob {
        scene: super::scene(name),
        technique,
        width: 32,
        height: 32,
        photons: Some(1 << 14),
        frames: 4,
        ..Default::default()
    };
    let techniques = [T::Aaps, T::ImageSpace, T::PhotonMap, T::Volume];
    let n = techniques.len();
    let mut batch = Vec::new();
    for name in ["glass_sphere", "ring", "glass_sphere"] {
        batch.extend(techniques.map(|t| job(name, t)));
    }
    batch.push(job("no_such_scene", T::Aaps));
    let results = run_all(batch);
    assert_eq!(results.len(), 3 * n + 1);
    let last = results[3 * n].as_ref().unwrap_err();
    assert!(last.contains("no_such_scene"), "{last}");
    for (k, t) in techniques.into_iter().enumerate() {
        let caustics = |i: usize| {
            let r = results[i].as_ref().unwrap_or_else(|e| panic!("{t:?}: {e}"));
            r.caustics.clone().expect("caustics")
        };
        let (before, after) = (caustics(k), caustics(2 * n + k));
        let m = compare(&after, &before, None).expect("same size");
        let mean = before.sum().x / (32.0 * 32.0);
        println!(
            "{t:?}: glass_sphere after ring vs before: energy {:+.4} %, RMSE {:.3} lx (mean {mean:.1})",
            m.energy_error * 100.0,
            m.rmse
        );
        assert!(mean > 0.0, "{t:?}: no caustic");
        assert!(m.energy_error.abs() < 5e-3, "{t:?}: {m:?}");
        assert!(m.rmse < 0.02 * mean, "{t:?}: {m:?}");
    }
}
