//! Error against run time, for every scene and technique: `report/REPORT.md` with a summary
//! table and, per scene, one SVG of FLIP and one of RMSE against milliseconds.
//!
//! ```text
//! cargo run --release --example report -- [--scenes a,b,..] \
//!     [--techniques reference,aaps,volume,image_space,photon_map] [--out DIR] [--size N]
//! ```
//!
//! Each scene of `assets/scenes/` is compared against a converged reference image that is
//! computed once (by the reference technique at `CONVERGED_PHOTONS` photons per light, seed
//! `CONVERGED_SEED`) and cached in `assets/reference/` with a JSON that records how it was
//! made; a cache whose recipe differs is recomputed. Every sweep point renders through the same
//! headless renderer as `examples/render.rs` (seed 2, so it is independent of the reference).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use bevy::prelude::{DirectionalLight, Transform, With, World};
use bevy_caustics::headless::{RenderJob, find_adapter, run};
use bevy_caustics::reference::curve::{Reach, error_within, ms_to_reach};
use bevy_caustics::reference::{CausticImage, ImageMetrics, compare};
use bevy_caustics::{
    AapsSettings, CausticsTechnique, CausticsVolume, ImageSpaceSettings, PhotonMapSettings,
};
use clap::Parser;

mod motion;
use plotters::coord::combinators::BindKeyPoints;
use plotters::prelude::*;

use bevy_caustics::reference::cache::{
    CONVERGED_PHOTONS, CONVERGED_SEED, POOL_PHOTONS, converged_photons, converged_recipe,
};
const SWEEP_SEED: u64 = 2;

struct Point {
    scene: String,
    technique: String,
    quality: String,
    photons: u64,
    splats: Option<u64>,
    cpu_ms: f64,
    gpu_ms: f64,
    passes: String,
    metrics: ImageMetrics,
}

impl Point {
    /// Run time of one frame update: the CPU trace (reference) plus the GPU passes.
    fn ms(&self) -> f64 {
        self.cpu_ms + self.gpu_ms
    }
}

/// The FLIP the summary asks each technique to reach, and its two run-time budgets (ms).
const FLIP_TARGET: f64 = 0.05;
const BUDGETS: [f64; 2] = [16.0, 100.0];
/// Frames measured per run (after the technique's first frame); the pass times are medians
/// over all but the first three, and the photon map accumulates over all of them.
const FRAMES: u32 = 8;

/// The image-space quality levels: (name, photons per light and frame, RSM side).
const IMAGE_SPACE_LEVELS: [(&str, u64, u32); 3] = [
    ("low: 2^16/light, RSM 512", 1 << 16, 512),
    ("medium: 2^18/light, RSM 1024", 1 << 18, 1024),
    ("high: 2^20/light, RSM 1024", 1 << 20, 1024),
];

/// The photon-map quality levels: (name, photons per light and frame), default settings
/// (progressive: the measured frames accumulate) but for caustics seen in mirrors, which the
/// reference does not hold.
const PHOTON_MAP_LEVELS: [(&str, u64); 3] = [
    ("low: 2^16/light", 1 << 16),
    ("medium: 2^18/light", 1 << 18),
    ("high: 2^20/light", 1 << 20),
];

/// The caustics-volume quality levels: (name, photons per volume and update), default
/// settings otherwise (3 slabs, 200² slab G-buffers, 400² projectors).
const VOLUME_LEVELS: [(&str, i32); 3] = [
    ("low: 20 000 photons", 20_000),
    ("medium: 80 000 photons", 80_000),
    ("high: 320 000 photons", 320_000),
];

/// The reference technique's sweep (photons per light).
const REFERENCE_SWEEP: [u64; 4] = [1 << 14, 1 << 16, 1 << 18, 1 << 20];

/// Volumes update only when something in them changes; turning the sun by 1e-4 rad every frame
/// makes every measured frame a full update, whose passes the report times.
fn turn_sun(world: &mut World, frame: u32) {
    let mut q = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
    for mut t in q.iter_mut(world) {
        t.rotate_x(if frame.is_multiple_of(2) { 1e-4 } else { -1e-4 });
    }
}

/// One quality level of one technique: its name and the job's settings for it.
fn levels(technique: CausticsTechnique) -> Vec<(String, RenderJob)> {
    let job = |photons: u64| RenderJob {
        technique,
        photons: Some(photons),
        ..Default::default()
    };
    match technique {
        CausticsTechnique::Reference => REFERENCE_SWEEP
            .iter()
            .map(|p| (format!("{p} photons/light"), job(*p)))
            .collect(),
        CausticsTechnique::Aaps => bevy_caustics::reference::cache::AAPS_LEVELS
            .iter()
            .map(|(name, budget, target)| {
                let aaps = AapsSettings {
                    target_area: *target,
                    ..Default::default()
                };
                (
                    name.to_string(),
                    RenderJob {
                        aaps,
                        ..job(*budget)
                    },
                )
            })
            .collect(),
        CausticsTechnique::Volume => VOLUME_LEVELS
            .iter()
            .map(|(name, photons)| {
                let volume = CausticsVolume {
                    photons: *photons,
                    ..Default::default()
                };
                let j = RenderJob {
                    volume,
                    per_frame: Some(turn_sun),
                    ..job(*photons as u64)
                };
                (name.to_string(), j)
            })
            .collect(),
        CausticsTechnique::ImageSpace => IMAGE_SPACE_LEVELS
            .iter()
            .map(|(name, photons, rsm)| {
                let image_space = ImageSpaceSettings {
                    rsm_resolution: *rsm,
                    ..Default::default()
                };
                (
                    name.to_string(),
                    RenderJob {
                        image_space,
                        ..job(*photons)
                    },
                )
            })
            .collect(),
        CausticsTechnique::PhotonMap => PHOTON_MAP_LEVELS
            .iter()
            .map(|(name, photons)| {
                let photon_map = PhotonMapSettings {
                    mirrors: false,
                    ..Default::default()
                };
                (
                    name.to_string(),
                    RenderJob {
                        photon_map,
                        ..job(*photons)
                    },
                )
            })
            .collect(),
    }
}

/// The scenes measured by default.
const SCENES: &str = "mirror_wall,glass_slab,glass_sphere,pool,ring,empty";
/// The techniques measured by default.
const TECHNIQUES: &str = "reference,aaps,volume,image_space,photon_map";

/// Error against run time for every scene and technique: writes REPORT.md (a summary table,
/// every run) and, per scene, one SVG of FLIP and one of RMSE against milliseconds.
///
/// Each scene is compared against a converged reference image (the reference technique at
/// 2^23 photons per light, 2^28 for pool) cached in assets/reference/, computed first when
/// missing or made by another recipe. About 10 minutes on lavapipe. Errors print one line and exit
/// with status 2.
#[derive(Parser, Debug)]
#[command(name = "report", args_override_self = true)]
struct Cli {
    /// Scenes of assets/scenes/ to measure, comma-separated names (any other scene there
    /// works too: its reference is computed first).
    #[arg(long, value_name = "A,B,...", default_value = SCENES)]
    scenes: String,
    /// Techniques to measure, comma-separated: reference, aaps, volume, image_space,
    /// photon_map.
    #[arg(long, value_name = "A,B,...", default_value = TECHNIQUES)]
    techniques: String,
    /// Folder REPORT.md and the SVGs are written to.
    #[arg(long, value_name = "DIR", default_value_os_t = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("report"))]
    out: PathBuf,
    /// Side of the square renders, pixels.
    #[arg(long, value_name = "PIXELS", default_value_t = 128, value_parser = integer)]
    size: u32,
    /// What to measure: `sweep` (REPORT.md and its plots), `motion` (MOTION.md: the moving
    /// scene, about 5 minutes on lavapipe) or `all`.
    #[arg(long, value_name = "PART", default_value = "all", value_parser = ["all", "sweep", "motion"])]
    part: String,
}

/// `--size`: an integer.
fn integer(v: &str) -> Result<u32, String> {
    v.parse()
        .map_err(|_| format!("expects an integer, got '{v}'"))
}

fn main() {
    bevy_caustics::headless::quiet_headless_environment();
    // A usage error (unknown option, bad value) prints clap's message and exits 2.
    let cli = Cli::parse();
    if let Err(e) = real_main(cli) {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

fn real_main(cli: Cli) -> Result<(), String> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let scenes: Vec<String> = cli.scenes.split(',').map(String::from).collect();
    let techniques = cli
        .techniques
        .split(',')
        .map(|t| {
            CausticsTechnique::from_name(t).ok_or_else(|| {
                format!("unknown technique '{t}' (available: reference, aaps, volume, image_space, photon_map)")
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let out = cli.out;
    let size = cli.size;
    let adapter = find_adapter()?;
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    if cli.part != "motion" {
        sweep(&root, &out, size, &adapter, &scenes, &techniques)?;
    }
    if cli.part != "sweep" {
        moving(&root, &out, size, &adapter, &techniques)?;
    }
    Ok(())
}

/// REPORT.md and its plots: every quality level of every technique on every scene.
fn sweep(
    root: &Path,
    out: &Path,
    size: u32,
    adapter: &str,
    scenes: &[String],
    techniques: &[CausticsTechnique],
) -> Result<(), String> {
    let runs: Vec<(CausticsTechnique, Vec<(String, RenderJob)>)> =
        techniques.iter().map(|t| (*t, levels(*t))).collect();
    let total = scenes.len() * (1 + runs.iter().map(|(_, l)| l.len()).sum::<usize>());
    let started = std::time::Instant::now();
    let mut step = 0;
    let mut points = Vec::new();
    for scene in scenes {
        let path = root.join("assets/scenes").join(format!("{scene}.gltf"));
        step += 1;
        progress(step, total, &format!("{scene}: converged reference"));
        let reference = converged(root, &path, scene, size)?;
        for (technique, levels) in &runs {
            for (quality, job) in levels {
                step += 1;
                progress(
                    step,
                    total,
                    &format!("{scene}: {} {quality}", technique.name()),
                );
                let report = run(RenderJob {
                    scene: path.clone(),
                    width: size,
                    height: size,
                    seed: SWEEP_SEED,
                    frames: FRAMES,
                    ..job.clone()
                })?;
                let image = report
                    .caustics
                    .clone()
                    .unwrap_or_else(|| CausticImage::new(size, size));
                let passes = report
                    .pass_ms
                    .iter()
                    .map(|(k, v)| format!("{} {v:.2}", k.rsplit('/').next().unwrap_or(k)))
                    .collect::<Vec<_>>()
                    .join(", ");
                points.push(Point {
                    scene: scene.clone(),
                    technique: technique.name().into(),
                    quality: quality.clone(),
                    photons: report.photons_traced,
                    splats: report.aaps.as_ref().map(|a| a.splats),
                    cpu_ms: report.reference_seconds * 1e3,
                    gpu_ms: report.pass_ms.values().fold(0.0, |a, b| a + b),
                    passes,
                    metrics: compare(&image, &reference, None).ok_or("size mismatch")?,
                });
            }
        }
    }
    eprintln!();
    let minutes = started.elapsed().as_secs_f64() / 60.0;
    let md = markdown(adapter, size, minutes, scenes, &runs, &points);
    for scene in scenes {
        for metric in METRICS {
            plot(
                &out.join(format!("{scene}_{}.svg", metric.file)),
                scene,
                &metric,
                &points,
            )?;
        }
    }
    // The one-SVG-per-scene plots of earlier reports are replaced by the two above.
    for scene in scenes {
        let _ = std::fs::remove_file(out.join(format!("{scene}.svg")));
    }
    let report = out.join("REPORT.md");
    std::fs::write(&report, md).map_err(|e| format!("cannot write {}: {e}", report.display()))?;
    println!("wrote {} in {minutes:.1} min", report.display());
    Ok(())
}

/// MOTION.md: the moving scene ([`motion`]), for every technique but the reference.
fn moving(
    root: &Path,
    out: &Path,
    size: u32,
    adapter: &str,
    techniques: &[CausticsTechnique],
) -> Result<(), String> {
    let started = std::time::Instant::now();
    let scene = root
        .join("assets/scenes")
        .join(format!("{}.gltf", motion::SCENE));
    eprintln!("moving scene: the converged and per-frame references");
    let converged = converged(root, &scene, motion::SCENE, size)?;
    let slide = motion::slide_references(&scene, size)?;
    let mut rows = Vec::new();
    for &technique in techniques {
        if technique == CausticsTechnique::Reference {
            continue;
        }
        eprintln!("\nmoving scene: {}", technique.name());
        rows.push(motion::measure(
            &scene, size, technique, &converged, &slide,
        )?);
    }
    let minutes = started.elapsed().as_secs_f64() / 60.0;
    let path = out.join("MOTION.md");
    std::fs::write(&path, motion::markdown(adapter, size, minutes, &rows))
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    println!("wrote {} in {minutes:.1} min", path.display());
    Ok(())
}

/// A summary cell: the run time to reach the FLIP target.
fn reach_cell(r: Reach) -> String {
    match r {
        Reach::AtMost(ms) => format!("≤ {}", tick(ms)),
        Reach::At(ms) => tick(ms),
        Reach::NotReached => "not reached".into(),
    }
}

fn markdown(
    adapter: &str,
    size: u32,
    minutes: f64,
    scenes: &[String],
    runs: &[(CausticsTechnique, Vec<(String, RenderJob)>)],
    points: &[Point],
) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# bevy_caustics: error against run time\n");
    let _ = writeln!(
        md,
        "Adapter: **{adapter}**. Target {size}x{size}. This run took {minutes:.0} minutes. Milliseconds compare only on one adapter: lavapipe runs the GPU passes on the CPU, 100 to 1000 times slower than a GPU, so read the ratios between techniques, not the absolute times.\n"
    );
    let _ = writeln!(
        md,
        "Reference images: the reference technique at {CONVERGED_PHOTONS} photons per light ({POOL_PHOTONS} on pool), seed {CONVERGED_SEED} (cached in `assets/reference/`). Sweep seed {SWEEP_SEED}. Metrics over all pixels (pixels without caustics are zero in both): RMSE of luminance in lux, relative RMSE (RMSE / mean reference luminance), mean FLIP (LDR, both images scaled by the reference's 99th percentile), relative energy error.\n"
    );
    let _ = writeln!(
        md,
        "**Run time** (`ms`) is that of one frame update: for the reference technique, which runs on the CPU, its trace (wall clock, all cores); for the others, the sum of the median GPU times of their passes over the measured frames ({FRAMES} frames, the first three left out of the medians). AAPS's task buffer adapts during the frames from a uniform start. Volumes: every frame is a full update (the sun turns by 1e-4 rad each frame; without a change a volume only splats). Photon map: progressive, so its error is that of {FRAMES} accumulated frames at this per-frame time, and without caustics seen in mirrors (`mirrors: false`), which the reference images do not hold. On lavapipe a GPU span only holds its compute work with the plugin's span settling (`render/span.rs`); earlier reports under-timed compute passes.\n"
    );
    let _ = writeln!(md, "Quality levels:\n");
    for (technique, levels) in runs {
        let names: Vec<&str> = levels.iter().map(|(n, _)| n.as_str()).collect();
        let _ = writeln!(md, "- {}: {}", technique.name(), names.join("; "));
    }
    let _ = writeln!(
        md,
        "\nThe converged image has noise of its own: at {CONVERGED_PHOTONS} photons its RMSE is about 1/sqrt({}) of the reference sweep's last point's, so that point's error is overstated by about {:.0} %.\n",
        CONVERGED_PHOTONS / REFERENCE_SWEEP[3],
        ((1.0 + REFERENCE_SWEEP[3] as f64 / CONVERGED_PHOTONS as f64).sqrt() - 1.0) * 100.0
    );
    let _ = writeln!(
        md,
        "A known limit shows here: a caustics volume seeds nothing when its light is inside it (`ring`'s bulb sits inside the ring, so its volume rows have energy error -1; docs/volumes.md).\n"
    );
    let _ = writeln!(md, "Regenerate: `cargo run --release --example report`.\n");
    let _ = writeln!(md, "## Summary\n");
    let _ = writeln!(
        md,
        "Per scene and technique: the run time needed to reach a mean FLIP of {FLIP_TARGET} (interpolated in log-log on the measured curve; `≤ x` when the cheapest level already reaches it), and the lowest FLIP reached within {} ms and {} ms on this adapter (interpolated the same way; `over budget` when even the cheapest level costs more). A scene without caustics has nothing to reach.\n",
        BUDGETS[0], BUDGETS[1]
    );
    let _ = writeln!(
        md,
        "| scene | technique | ms to FLIP {FLIP_TARGET} | FLIP within {} ms | FLIP within {} ms | best FLIP (ms) |",
        BUDGETS[0], BUDGETS[1]
    );
    let _ = writeln!(md, "| --- | --- | ---: | ---: | ---: | ---: |");
    for scene in scenes {
        for (technique, _) in runs {
            let pts: Vec<&Point> = points
                .iter()
                .filter(|p| &p.scene == scene && p.technique == technique.name())
                .collect();
            let curve: Vec<(f64, f64)> = pts.iter().map(|p| (p.ms(), p.metrics.flip)).collect();
            if curve.iter().all(|(_, f)| *f <= 0.0) {
                let _ = writeln!(
                    md,
                    "| {scene} | {} | no caustic | - | - | - |",
                    technique.name()
                );
                continue;
            }
            let within = |b: f64| {
                error_within(&curve, b).map_or("over budget".into(), |f| format!("{f:.4}"))
            };
            let best = pts
                .iter()
                .filter(|p| p.metrics.flip > 0.0)
                .min_by(|a, b| a.metrics.flip.total_cmp(&b.metrics.flip))
                .map_or("-".into(), |p| {
                    format!("{:.4} ({})", p.metrics.flip, tick(p.ms()))
                });
            let _ = writeln!(
                md,
                "| {scene} | {} | {} | {} | {} | {best} |",
                technique.name(),
                reach_cell(ms_to_reach(&curve, FLIP_TARGET)),
                within(BUDGETS[0]),
                within(BUDGETS[1]),
            );
        }
    }
    let _ = writeln!(md);
    for scene in scenes {
        let _ = writeln!(md, "## {scene}\n");
        for metric in METRICS {
            let _ = writeln!(
                md,
                "![{scene}: {}]({scene}_{}.svg)\n",
                metric.label, metric.file
            );
        }
        let _ = writeln!(
            md,
            "| technique | quality | photons | splats | cpu ms | gpu ms | RMSE (lx) | rel. RMSE | FLIP | energy error | GPU ms per pass |"
        );
        let _ = writeln!(
            md,
            "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"
        );
        for p in points.iter().filter(|p| &p.scene == scene) {
            let m = &p.metrics;
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {:.1} | {:.3} | {:.2} | {:.4} | {:.4} | {:+.4} | {} |",
                p.technique,
                p.quality,
                p.photons,
                p.splats.map_or("-".to_string(), |s| s.to_string()),
                p.cpu_ms,
                p.gpu_ms,
                m.rmse,
                m.relative_rmse,
                m.flip,
                m.energy_error,
                p.passes
            );
        }
        let _ = writeln!(md);
    }
    md
}

fn progress(step: usize, total: usize, what: &str) {
    let width = 30;
    let filled = step * width / total.max(1);
    eprint!(
        "\r[{}{}] {step}/{total} {what:<50}",
        "#".repeat(filled),
        ".".repeat(width - filled)
    );
}

/// The cached converged reference of a scene, computed if missing or made differently.
fn converged(
    root: &Path,
    scene_path: &Path,
    scene: &str,
    size: u32,
) -> Result<CausticImage, String> {
    let dir = root.join("assets/reference");
    let exr = dir.join(format!("{scene}_{size}.exr"));
    let meta = dir.join(format!("{scene}_{size}.json"));
    let recipe = converged_recipe(scene, size);
    if let (Ok(m), Ok(img)) = (std::fs::read_to_string(&meta), CausticImage::read_exr(&exr))
        && serde_json::from_str::<serde_json::Value>(&m).ok().as_ref() == Some(&recipe)
    {
        return Ok(img);
    }
    let report = run(converged_job(scene_path, scene, size))?;
    let img = report
        .caustics
        .unwrap_or_else(|| CausticImage::new(size, size));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    img.write_exr(&exr)?;
    std::fs::write(&meta, serde_json::to_string_pretty(&recipe).unwrap())
        .map_err(|e| e.to_string())?;
    Ok(img)
}

/// The reference technique's job for the converged image of `scene` at `size²` (the recipe of
/// [`converged_recipe`]).
fn converged_job(scene_path: &Path, scene: &str, size: u32) -> RenderJob {
    RenderJob {
        scene: scene_path.to_path_buf(),
        width: size,
        height: size,
        photons: Some(converged_photons(scene)),
        seed: CONVERGED_SEED,
        frames: 4,
        ..Default::default()
    }
}

/// A plotted error metric.
struct Metric {
    label: &'static str,
    file: &'static str,
    value: fn(&ImageMetrics) -> f64,
}

const METRICS: [Metric; 2] = [
    Metric {
        label: "mean FLIP (unitless)",
        file: "flip",
        value: |m| m.flip,
    },
    Metric {
        label: "RMSE of luminance (lx)",
        file: "rmse",
        value: |m| m.rmse,
    },
];

/// An axis label with sensible digits: two significant figures, no float noise, powers of
/// ten for very large or small values.
fn tick(v: f64) -> String {
    if !v.is_finite() || v == 0.0 {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor();
    if !(-3.0..5.0).contains(&mag) {
        return format!("{v:.0e}");
    }
    let decimals = (1.0 - mag).max(0.0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Tick values for a log axis over [lo, hi]: 1, 2, 5 times the powers of ten, thinned to
/// powers of ten where the range spans more than three decades.
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let decades = (hi / lo).log10();
    let steps: &[f64] = if decades > 3.0 {
        &[1.0]
    } else {
        &[1.0, 2.0, 5.0]
    };
    let mut out = Vec::new();
    let mut p = 10f64.powf(lo.log10().floor());
    while p <= hi {
        for s in steps {
            let v = p * s;
            if v >= lo && v <= hi {
                out.push(v);
            }
        }
        p *= 10.0;
    }
    out
}

/// Fixed colours per technique, so a technique looks the same on every plot.
fn colour(technique: &str) -> RGBColor {
    match technique {
        "reference" => RGBColor(90, 90, 90),
        "aaps" => RGBColor(31, 119, 180),
        "volume" => RGBColor(44, 160, 44),
        "image_space" => RGBColor(214, 39, 40),
        "photon_map" => RGBColor(148, 103, 189),
        _ => RGBColor(255, 127, 14),
    }
}

/// One scene's metric against run time, log-log, every technique a line with its levels as
/// dots; the budgets as vertical lines (and the FLIP target as a horizontal one); the legend
/// to the right of the plot, so it covers no curve.
fn plot(path: &Path, scene: &str, metric: &Metric, points: &[Point]) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<_>| e.to_string();
    let pts: Vec<&Point> = points
        .iter()
        .filter(|p| p.scene == scene && (metric.value)(&p.metrics) > 0.0 && p.ms() > 0.0)
        .collect();
    let root = SVGBackend::new(path, (900, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let (area, legend) = root.split_horizontally(720);
    if pts.is_empty() {
        area.draw(&Text::new(
            format!("{scene}: no caustic, {} is 0 everywhere", metric.label),
            (40, 220),
            ("sans-serif", 18),
        ))
        .map_err(e)?;
        return root.present().map_err(|e| e.to_string());
    }
    let xs = pts.iter().map(|p| p.ms());
    let ys = pts.iter().map(|p| (metric.value)(&p.metrics));
    let (x_lo, x_hi) = xs.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    let (y_lo, y_hi) = ys.fold((f64::MAX, f64::MIN), |(a, b), y| (a.min(y), b.max(y)));
    let (x_lo, x_hi) = (x_lo.min(BUDGETS[0]) / 1.5, x_hi * 1.5);
    let (mut y_lo, mut y_hi) = (y_lo / 1.5, y_hi * 1.5);
    if metric.file == "flip" {
        y_lo = y_lo.min(FLIP_TARGET / 1.5);
        y_hi = y_hi.max(FLIP_TARGET * 1.5);
    }
    let mut chart = ChartBuilder::on(&area)
        .caption(
            format!("{scene}: {} against run time", metric.label),
            ("sans-serif", 18),
        )
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(
            (x_lo..x_hi).log_scale().with_key_points(ticks(x_lo, x_hi)),
            (y_lo..y_hi).log_scale().with_key_points(ticks(y_lo, y_hi)),
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("run time of one frame update, ms (log)")
        .y_desc(format!("{} (log)", metric.label))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .bold_line_style(BLACK.mix(0.12))
        .light_line_style(TRANSPARENT)
        .draw()
        .map_err(e)?;
    let guide = BLACK.mix(0.45).stroke_width(1);
    for b in BUDGETS.iter().filter(|b| (x_lo..x_hi).contains(*b)) {
        chart
            .draw_series(LineSeries::new([(*b, y_lo), (*b, y_hi)], guide))
            .map_err(e)?;
        chart
            .draw_series([Text::new(
                format!("{b} ms"),
                (*b * 1.05, y_hi / 1.25),
                ("sans-serif", 13),
            )])
            .map_err(e)?;
    }
    if metric.file == "flip" {
        chart
            .draw_series(LineSeries::new(
                [(x_lo, FLIP_TARGET), (x_hi, FLIP_TARGET)],
                guide,
            ))
            .map_err(e)?;
        chart
            .draw_series([Text::new(
                format!("FLIP {FLIP_TARGET}"),
                (x_lo * 1.1, FLIP_TARGET * 1.08),
                ("sans-serif", 13),
            )])
            .map_err(e)?;
    }
    let mut techniques: Vec<&str> = Vec::new();
    for p in &pts {
        if !techniques.contains(&p.technique.as_str()) {
            techniques.push(&p.technique);
        }
    }
    for t in &techniques {
        let c = colour(t);
        let mut series: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.technique == *t)
            .map(|p| (p.ms(), (metric.value)(&p.metrics)))
            .collect();
        series.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(series.clone(), c.stroke_width(2)))
            .map_err(e)?;
        chart
            .draw_series(series.iter().map(|p| Circle::new(*p, 4, c.filled())))
            .map_err(e)?;
    }
    for (k, t) in techniques.iter().enumerate() {
        let c = colour(t);
        let y = 60 + 28 * k as i32;
        legend
            .draw(&PathElement::new(vec![(8, y), (40, y)], c.stroke_width(2)))
            .map_err(e)?;
        legend
            .draw(&Circle::new((24, y), 4, c.filled()))
            .map_err(e)?;
        legend
            .draw(&Text::new(t.to_string(), (48, y - 8), ("sans-serif", 15)))
            .map_err(e)?;
    }
    root.present().map_err(|e| e.to_string())
}
