//! Real content (issue 29 item 4): public glTF 2.0 sample models written by others, with
//! KHR_materials_transmission, _ior and _volume (attenuation, thickness textures, thin walls,
//! tinted and blended glass) and metal, at units from centimetres to metres, with node scales,
//! matrices, instanced meshes and lights of their own. They come without a camera or a floor
//! (and most without a light): each renders on the headless renderer's stage
//! (`RenderJob::stage`).
//!
//! Six are committed with their licences, two of them in reduced copies ([`COMMITTED_SAMPLES`]
//! in `assets/samples/`, whose README gives their sources and how two were reduced): they run
//! everywhere, CI included. Two more ([`SAMPLE_ASSETS`]) are public data we do not commit: they live in the
//! steering repository's `shared/khronos/<Model>/<Model>.glb` (with each model's licence), found
//! as `shared/` in the checkout, `../shared/` beside it, or the folder named by
//! `BEVY_CAUSTICS_SAMPLE_ASSETS` (`.glb`, or `.gltf` with its files beside it;
//! `BEVY_CAUSTICS_SAMPLE_LIST=A,B,...` names other models there). Where none of those holds them
//! `steering_sample_assets_render_with_every_technique` says so on stdout and checks
//! nothing (it cannot fetch them: the tests run offline); with `BEVY_CAUSTICS_SAMPLE_ASSETS` set it fails instead. The README lists them
//! all with their authors and licences.
//!
//! One test per committed model; per model and technique, at 48 x 36 with few photons and
//! frames (a model's five techniques in one app: 12 to 31 s on lavapipe, the lamp's six lights
//! the longest): the caustics image is finite and lit, some pixel above
//! [`LIT_LUX`]. The CPU reference's counters balance: the flux that struck a caster is the
//! flux deposited on receivers, escaped, absorbed (media, metals, tints), left at the bounce
//! cap and taken by Russian roulette, to [`BALANCE_TOLERANCE`].

use std::path::{Path, PathBuf};
use std::time::Instant;

use bevy_caustics::headless::{RenderJob, RenderReport, run_all};
use bevy_caustics::{CausticsTechnique, CausticsVolume};

use super::{GPU, require_gpu};

/// The committed models: folder and file stem under `assets/samples/`. The first has no light
/// of its own (the glTF viewer's test opens it).
pub const COMMITTED_SAMPLES: [&str; 6] = [
    "IridescentDishWithOlives",
    "LightsPunctualLamp",
    "AttenuationTest",
    "TransmissionRoughnessTest",
    "SunglassesKhronos",
    "TransmissionTest",
];

/// The models of the steering repository: folder and file stem under its assets folder.
pub const SAMPLE_ASSETS: [&str; 2] = ["DispersionTest", "GlassTable"];

/// A pixel is lit above this irradiance, lux: 1 % of the stage's 10 000 lux sun. An unlit
/// caustics buffer is exactly zero; the weakest model here (the glass table, whose glass is a
/// quarter-covered black tint) still concentrates well over 1 % of the sun through its three
/// quarters left clear.
const LIT_LUX: f32 = 100.0;

/// The reference's balance holds to this relative error: each event's flux is split in f32
/// (kept = flux x factor, lost = flux - kept) before the f64 sums, about 1e-7 per event over
/// paths of tens of events.
const BALANCE_TOLERANCE: f64 = 1e-4;

const W: u32 = 48;
const H: u32 = 36;

/// The models under test: [`SAMPLE_ASSETS`], or the comma-separated folder names in
/// `BEVY_CAUSTICS_SAMPLE_LIST` (other public models a developer has at hand).
fn sample_list() -> Vec<String> {
    match std::env::var("BEVY_CAUSTICS_SAMPLE_LIST") {
        Ok(list) => list.split(',').map(|s| s.trim().to_string()).collect(),
        Err(_) => SAMPLE_ASSETS.map(String::from).to_vec(),
    }
}

/// `<dir>/<name>/<name>.glb`, or `.gltf` where there is no `.glb`.
fn model_path(dir: &Path, name: &str) -> PathBuf {
    let glb = dir.join(name).join(format!("{name}.glb"));
    if glb.is_file() {
        glb
    } else {
        dir.join(name).join(format!("{name}.gltf"))
    }
}

/// Where the sample models are, or `Err` naming where they were looked for.
pub fn sample_assets_dir() -> Result<PathBuf, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let candidates: Vec<PathBuf> = std::env::var_os("BEVY_CAUSTICS_SAMPLE_ASSETS")
        .map(PathBuf::from)
        .into_iter()
        .chain([root.join("shared/khronos"), root.join("../shared/khronos")])
        .collect();
    candidates
        .iter()
        .find(|d| d.join(&sample_list()[0]).is_dir())
        .cloned()
        .ok_or_else(|| {
            format!(
                "the sample models are not in any of {candidates:?}: they live in the steering \
                 repository's shared/khronos/<Model>/<Model>.glb (see the README's sample models)"
            )
        })
}

fn job(scene: PathBuf, technique: CausticsTechnique) -> RenderJob {
    RenderJob {
        scene,
        technique,
        width: W,
        height: H,
        stage: true,
        photons: Some(match technique {
            // The reference's balance needs no image quality; its trace is the CPU's.
            CausticsTechnique::Reference => 1 << 15,
            _ => 1 << 14,
        }),
        frames: 3,
        warmup_frames: 1,
        volume: CausticsVolume {
            photons: 16_000,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// The techniques each model renders with.
const TECHNIQUES: [CausticsTechnique; 5] = [
    CausticsTechnique::Aaps,
    CausticsTechnique::PhotonMap,
    CausticsTechnique::ImageSpace,
    CausticsTechnique::Volume,
    CausticsTechnique::Reference,
];

/// One model with every technique, its five jobs in one app (`run_all`): what fails, named.
fn render_model(name: &str, path: &Path) -> Vec<String> {
    let t0 = Instant::now();
    let mut failures = Vec::new();
    let jobs = TECHNIQUES.map(|t| job(path.to_path_buf(), t)).to_vec();
    let mut reports = run_all(jobs).into_iter();
    for technique in TECHNIQUES {
        match reports.next() {
            Some(Ok(report)) => check_report(name, technique, &report, &mut failures),
            Some(Err(e)) => failures.push(format!("{name} {technique:?}: {e}")),
            None => failures.push(format!("{name} {technique:?}: not rendered")),
        }
    }
    println!("{name}: {:.1} s", t0.elapsed().as_secs_f64());
    failures
}

/// A test per committed model: it loads, every technique is finite and lit, the reference's
/// energy balance holds.
macro_rules! committed_sample {
    ($($test:ident: $index:literal,)*) => {$(
        #[test]
        fn $test() {
            let _g = GPU.slot();
            if !require_gpu() {
                return;
            }
            let name = COMMITTED_SAMPLES[$index];
            let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/samples");
            let failures = render_model(name, &model_path(&dir, name));
            assert!(failures.is_empty(), "{failures:#?}");
        }
    )*};
}

committed_sample! {
    iridescent_dish_with_olives_renders_with_every_technique: 0,
    lights_punctual_lamp_renders_with_every_technique: 1,
    attenuation_test_renders_with_every_technique: 2,
    transmission_roughness_test_renders_with_every_technique: 3,
    sunglasses_khronos_renders_with_every_technique: 4,
    transmission_test_renders_with_every_technique: 5,
}

/// The steering repository's models (or `BEVY_CAUSTICS_SAMPLE_LIST`'s) where they are, with
/// every technique as the committed ones.
#[test]
fn steering_sample_assets_render_with_every_technique() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let dir = match sample_assets_dir() {
        Ok(dir) => dir,
        Err(e) if std::env::var_os("BEVY_CAUSTICS_SAMPLE_ASSETS").is_some() => panic!("{e}"),
        Err(e) => {
            println!("steering repository's sample assets NOT RUN: {e}");
            return;
        }
    };
    let failures: Vec<String> = sample_list()
        .iter()
        .flat_map(|name| render_model(name, &model_path(&dir, name)))
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// One model's render with one technique: its caustics are finite and lit, and the
/// reference's counters balance. What fails is pushed onto `failures`.
fn check_report(
    name: &str,
    technique: CausticsTechnique,
    report: &RenderReport,
    failures: &mut Vec<String>,
) {
    let Some(img) = report.caustics.as_ref() else {
        failures.push(format!("{name} {technique:?}: no caustics image"));
        return;
    };
    let lum = |p: &glam::Vec3| p.dot(glam::Vec3::new(0.2126, 0.7152, 0.0722));
    let max = img.data.iter().map(lum).fold(0.0f32, f32::max);
    let lit = img.data.iter().filter(|p| lum(p) > LIT_LUX).count();
    println!(
        "{name:<26} {:<10} max {max:10.1} lx  lit px {lit:4}  photons {}  warnings {:?} {:?}",
        technique.name(),
        report.photons_traced,
        report.warnings,
        report.loss_warnings,
    );
    if !img.all_finite() {
        failures.push(format!("{name} {technique:?}: non-finite caustics"));
    }
    if max <= LIT_LUX {
        failures.push(format!(
            "{name} {technique:?}: not lit (max {max} lx <= {LIT_LUX})"
        ));
    }
    if let Some(s) = &report.reference_stats {
        let out = s.flux_deposited.y
            + s.flux_escaped.y
            + s.flux_absorbed.y
            + s.flux_max_depth.y
            + s.flux_roulette.y;
        let balance = out / s.flux_on_casters.y - 1.0;
        println!(
            "{name:<26} reference: on casters {:.4} lm = deposited {:.4} + escaped {:.4} + absorbed {:.4} + at the cap {:.4} + roulette {:+.4} ({balance:+.2e}); nan guards {}, tir {}",
            s.flux_on_casters.y,
            s.flux_deposited.y,
            s.flux_escaped.y,
            s.flux_absorbed.y,
            s.flux_max_depth.y,
            s.flux_roulette.y,
            s.nan_guards,
            s.tir_events
        );
        if !(s.flux_on_casters.y > 0.0 && s.flux_deposited.y > 0.0) {
            failures.push(format!("{name}: the reference deposited nothing"));
        }
        if s.nan_guards != 0 || balance.abs() > BALANCE_TOLERANCE {
            failures.push(format!(
                "{name}: reference balance {balance:+.2e}, nan guards {}",
                s.nan_guards
            ));
        }
    } else if technique == CausticsTechnique::Reference {
        failures.push(format!("{name}: the reference reported no counters"));
    }
}

/// The glTF viewer opens a committed model that brings no light (the dish) the way a user
/// would, offscreen: it puts the model on the stage (says so once on stdout), renders and
/// writes its picture, and the caustics it reports are finite and lit above [`LIT_LUX`].
#[test]
fn an_unlit_sample_opens_on_a_stage_in_the_gltf_viewer() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let name = COMMITTED_SAMPLES[0];
    let model = model_path(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/samples"),
        name,
    );
    let out = std::env::temp_dir().join(format!("bevy_caustics_viewer_{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let t0 = Instant::now();
    let run = std::process::Command::new(super::support::example_exe("gltf_viewer"))
        .arg(&model)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("CAUSTICS_EXAMPLE_OUT", &out)
        .env("CAUSTICS_EXAMPLE_SIZE", "64x48")
        .env("CAUSTICS_EXAMPLE_FRAMES", "12")
        .output()
        .expect("the gltf_viewer example is built by `cargo test --release`");
    let stdout = String::from_utf8_lossy(&run.stdout);
    println!(
        "gltf_viewer {name}: {:?} in {:.1} s\n{stdout}{}",
        run.status.code(),
        t0.elapsed().as_secs_f64(),
        String::from_utf8_lossy(&run.stderr)
    );
    assert_eq!(run.status.code(), Some(0));
    assert!(stdout.contains("it stands on a stage"), "{stdout}");
    assert!(out.join("gltf_viewer.png").is_file());
    // "caustics: finite=true max=124330 lx sum=..."
    let max: f32 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("caustics: finite=true max="))
        .and_then(|rest| rest.split(' ').next()?.parse().ok())
        .unwrap_or_else(|| panic!("no finite caustics line in {stdout}"));
    assert!(
        max > LIT_LUX,
        "the staged model's caustics peak at {max} lx"
    );
}
