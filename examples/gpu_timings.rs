//! One command that measures every GPU technique's per-pass milliseconds, for the sessions
//! that are lent a real GPU for a few minutes: `scripts/gpu-timings.sh`, or
//!
//! ```text
//! cargo run --release --example gpu_timings -- [--width 1920] [--height 1080] [--frames 100]
//!     [--warmup 20] [--out docs/gpu-timings.md] [--techniques aaps,image_space,photon_map,volume]
//!     [--scene NAME] [--no-sweep]
//! ```
//!
//! Each technique renders headless ([`bevy_caustics::headless`]) on a scene of `assets/scenes/`
//! like its seed's: AAPS and image space on `pool` (seed 004's Pool scene, seed 003's flooded
//! scenes), the photon map and volumes on `glass_sphere` (seed 000's glass ball). Every run is
//! at the technique's default settings, with `Caustics::settle_frames` 0 (every frame runs the
//! technique) and, for volumes, the sun turned by 1e-4 rad each frame (every frame a full
//! update, as the seed measured). Then AAPS and image space again at seed 003's photon counts
//! (0.5 M, 1 M, 2 M per light; image space with seed 003's 2048² RSMs), unless `--no-sweep`.
//! Per run: the warm-up frames, then the measured ones; the median GPU ms of every pass and of
//! the frame's sum of the caustics passes, from Bevy's render diagnostics (per-pass timestamp
//! spans, `render/span.rs`). The Markdown table goes to `--out` and stdout, with the seeds'
//! published figures beside it (checked in the seed documents, sections cited).
//!
//! Where the adapter has no timestamp queries inside passes, Bevy records CPU spans only; the
//! table then says its figures are CPU recording times, not GPU times. On lavapipe (Mesa's
//! Vulkan on the CPU) the figures are real GPU spans of a CPU "GPU", 100 to 1000 times a real
//! GPU's: use them for ratios between passes, never against the seeds.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use bevy::prelude::{DirectionalLight, Or, PointLight, SpotLight, Transform, With, World};
use bevy_caustics::headless::{
    RenderJob, RenderReport, adapter_limits, check_job, find_adapter, run,
};
use bevy_caustics::limits::CausticsLimits;
use bevy_caustics::{CausticsQuality, CausticsTechnique, CausticsVolume, ImageSpaceSettings};
use clap::Parser;

/// Per-pass GPU milliseconds of every caustics technique, as a Markdown table.
#[derive(Parser)]
#[command(name = "gpu_timings")]
struct Args {
    /// Target width, pixels.
    #[arg(long, default_value_t = 1920)]
    width: u32,
    /// Target height, pixels.
    #[arg(long, default_value_t = 1080)]
    height: u32,
    /// Measured frames per run, after the warm-up; the medians are over these.
    #[arg(long, default_value_t = 100)]
    frames: u32,
    /// Warm-up frames per run, left out of the medians (AAPS's task buffer settles in about
    /// 16; diagnostics arrive a few frames late).
    #[arg(long, default_value_t = 20)]
    warmup: u32,
    /// Where the Markdown table is written (its folder is created).
    #[arg(long, default_value = "docs/gpu-timings.md")]
    out: PathBuf,
    /// Techniques to time, comma separated (of aaps, image_space, photon_map, volume).
    #[arg(long, value_delimiter = ',', default_value = "aaps,image_space,photon_map,volume",
          value_parser = parse_technique)]
    techniques: Vec<CausticsTechnique>,
    /// Render every technique on this scene of assets/scenes/ (e.g. pool, glass_sphere)
    /// instead of each one's own.
    #[arg(long)]
    scene: Option<String>,
    /// Skip the runs of AAPS and image space at seed 003's photon counts (0.5 M, 1 M, 2 M).
    #[arg(long)]
    no_sweep: bool,
    /// Instead, the trace-cost benchmark: every technique on generated scenes of this many
    /// glass parts (comma separated, e.g. 1,10,30; `scenes::closed::glass_parts`), over an
    /// open floor and in a closed room, with the specular events traced and the paths the
    /// event budget stopped.
    #[arg(long, value_delimiter = ',')]
    parts: Vec<usize>,
    /// With `--parts`: AAPS's and the photon map's `bounce_budget` values to run (specular
    /// events per photon per frame, comma separated; the default is 8; 128 lets every path
    /// run to `max_bounces`).
    #[arg(long, value_delimiter = ',', default_value = "8")]
    bounce_budget: Vec<f32>,
}

fn parse_technique(s: &str) -> Result<CausticsTechnique, String> {
    match CausticsTechnique::from_name(s) {
        Some(CausticsTechnique::Reference) | None => Err(format!(
            "'{s}' is not a GPU technique (aaps, image_space, photon_map, volume)"
        )),
        Some(t) => Ok(t),
    }
}

/// Seed 003's photon counts per light (section 4.2, table 1).
const SWEEP: [u64; 3] = [500_000, 1_000_000, 2_000_000];

/// One render to time.
struct Run {
    technique: CausticsTechnique,
    scene: String,
    /// What the photon count is: "262144/light (default)", ...
    photons: String,
    job: RenderJob,
    /// The seeds' figure to print beside it.
    seed: &'static str,
}

/// A timed run: the report, or the error that stopped it, and its wall-clock seconds.
struct Timed {
    run: Run,
    result: Result<RenderReport, String>,
    seconds: f64,
}

fn main() {
    bevy_caustics::headless::quiet_headless_environment();
    let args = Args::parse();
    if let Err(e) = real_main(&args) {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

fn real_main(args: &Args) -> Result<(), String> {
    let adapter = find_adapter()?;
    let limits = adapter_limits()?;
    let runs = if args.parts.is_empty() {
        plan(args, &repo_root(), &limits)
    } else {
        plan_parts(args, &limits)?
    };
    validate(&runs, &limits)?;
    let count = runs.len();
    let started = Instant::now();
    let mut timed = Vec::new();
    for (i, r) in runs.into_iter().enumerate() {
        eprintln!(
            "[{}/{}] {} on {}, {} ...",
            i + 1,
            count,
            r.technique.name(),
            r.scene,
            r.photons
        );
        let t = Instant::now();
        let result = run(r.job.clone());
        let seconds = t.elapsed().as_secs_f64();
        match &result {
            Ok(rep) => eprintln!("  total {} in {seconds:.1} s", total_cell(rep)),
            Err(e) => eprintln!("  failed after {seconds:.1} s: {e}"),
        }
        timed.push(Timed {
            run: r,
            result,
            seconds,
        });
    }
    let minutes = started.elapsed().as_secs_f64() / 60.0;
    let md = if args.parts.is_empty() {
        markdown(args, &adapter, &timed, minutes)
    } else {
        parts_markdown(args, &adapter, &timed, minutes)
    };
    println!("{md}");
    write_out(&args.out, &md)?;
    println!("wrote {} ({minutes:.1} min)", args.out.display());
    Ok(())
}

/// The repository whose `assets/scenes/` to render: the working directory when it has one (a
/// packed binary run on another machine, `scripts/gpu-timings.sh --packed`), else this crate's.
fn repo_root() -> PathBuf {
    if std::path::Path::new("assets/scenes").is_dir() {
        PathBuf::from(".")
    } else {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    }
}

/// The runs: each technique at its defaults, then the photon sweep.
fn plan(args: &Args, root: &std::path::Path, limits: &CausticsLimits) -> Vec<Run> {
    let default_photons = CausticsQuality::default().photons_per_light();
    let mut runs = Vec::new();
    for &technique in &args.techniques {
        let scene = args
            .scene
            .clone()
            .unwrap_or_else(|| default_scene(technique).to_string());
        let mut job = RenderJob {
            scene: root.join(format!("assets/scenes/{scene}.gltf")),
            technique,
            width: args.width,
            height: args.height,
            frames: args.warmup.saturating_add(args.frames.max(1)),
            warmup_frames: args.warmup,
            settle_frames: 0,
            limits: Some(limits.clone()),
            ..Default::default()
        };
        let photons = if technique == CausticsTechnique::Volume {
            job.per_frame = Some(turn_sun);
            format!("{}/volume (default)", CausticsVolume::default().photons)
        } else {
            format!("{default_photons}/light (default)")
        };
        let seed = seed_figure(technique, None);
        runs.push(Run {
            technique,
            scene: scene.clone(),
            photons,
            job: job.clone(),
            seed,
        });
        if !args.no_sweep {
            runs.extend(sweep(technique, &scene, &job));
        }
    }
    runs
}

/// The trace-cost benchmark's runs: every technique at its defaults on `glass_parts(n, room)`
/// for each part count, open and closed (the scenes written to a temporary folder).
fn plan_parts(args: &Args, limits: &CausticsLimits) -> Result<Vec<Run>, String> {
    let dir = std::env::temp_dir().join(format!("bevy_caustics_parts_{}", std::process::id()));
    let mut runs = Vec::new();
    for &n in &args.parts {
        for closed in [false, true] {
            let desc = bevy_caustics::scenes::closed::glass_parts(n, closed);
            bevy_caustics::scenes::gltf::write_gltf(&desc, &dir)
                .map_err(|e| format!("cannot write {}: {e}", desc.name))?;
            for &technique in &args.techniques {
                runs.extend(parts_runs(args, technique, &desc.name, &dir, limits));
            }
        }
    }
    Ok(runs)
}

/// One technique's runs on one scene of the trace-cost benchmark: one per event budget for
/// AAPS and the photon map, one for the others (volumes with the lights nudged every frame, so
/// every frame is a full update).
fn parts_runs(
    args: &Args,
    technique: CausticsTechnique,
    scene: &str,
    dir: &std::path::Path,
    limits: &CausticsLimits,
) -> Vec<Run> {
    let budgets = match technique {
        CausticsTechnique::Aaps | CausticsTechnique::PhotonMap => args.bounce_budget.clone(),
        _ => vec![8.0],
    };
    budgets
        .into_iter()
        .map(|bounce_budget| Run {
            technique,
            scene: scene.to_string(),
            photons: format!("bounce_budget {bounce_budget}"),
            job: RenderJob {
                scene: dir.join(format!("{scene}.gltf")),
                technique,
                width: args.width,
                height: args.height,
                frames: args.warmup.saturating_add(args.frames.max(1)),
                warmup_frames: args.warmup,
                settle_frames: 0,
                limits: Some(limits.clone()),
                per_frame: (technique == CausticsTechnique::Volume).then_some(nudge_lights as _),
                aaps: bevy_caustics::AapsSettings {
                    bounce_budget,
                    ..Default::default()
                },
                photon_map: bevy_caustics::PhotonMapSettings {
                    bounce_budget,
                    ..Default::default()
                },
                ..Default::default()
            },
            seed: "",
        })
        .collect()
}

/// Moves every point and spot light by 0.1 mm back and forth: volumes re-propagate fully.
fn nudge_lights(world: &mut World, frame: u32) {
    let mut q = world.query_filtered::<&mut Transform, Or<(With<PointLight>, With<SpotLight>)>>();
    for mut t in q.iter_mut(world) {
        t.translation.x += if frame.is_multiple_of(2) { 1e-4 } else { -1e-4 };
    }
}

/// The trace-cost benchmark's document: per technique and scene, the technique's median GPU ms,
/// its trace pass's, and what the trace did (events, paths the budget stopped).
fn parts_markdown(args: &Args, adapter: &str, timed: &[Timed], minutes: f64) -> String {
    let mut md = String::from(
        "# bevy_caustics: trace cost against the number of glass parts

",
    );
    md.push_str(&header(args, adapter, timed, minutes));
    md.push_str(
        "| technique | scene | bounce budget | total ms (median) | trace ms (median) | photons traced | specular events | per photon | stopped by the budget | at the bounce cap | wall s |\n\
         | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for t in timed {
        let row = match &t.result {
            Ok(rep) => parts_row(rep),
            Err(e) => format!("failed: {} | | | | | | |", e.replace('|', "/")),
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {row} | {:.1} |",
            t.run.technique.name(),
            t.run.scene,
            t.run.photons,
            t.seconds
        );
    }
    md.push_str(PARTS_NOTES);
    md
}

/// The measured cells of one run of the trace-cost benchmark.
fn parts_row(rep: &RenderReport) -> String {
    let trace: Vec<f64> = rep
        .pass_ms
        .iter()
        .filter(|(name, _)| name.ends_with("/trace") || name.ends_with("volume/project"))
        .map(|(_, ms)| *ms)
        .collect();
    let trace = if trace.is_empty() {
        "-".to_string()
    } else {
        format!("{:.3}", trace.iter().sum::<f64>())
    };
    let (events, stopped, cap) = if let Some(a) = &rep.aaps {
        (
            a.events.to_string(),
            a.budget_stopped.to_string(),
            a.max_depth.to_string(),
        )
    } else if let Some(p) = &rep.photon_map {
        (
            p.events.to_string(),
            p.budget_stopped.to_string(),
            p.max_depth.to_string(),
        )
    } else {
        ("-".into(), "-".into(), "-".into())
    };
    let per_photon = events.parse::<f64>().map_or("-".into(), |e| {
        format!("{:.2}", e / rep.photons_traced.max(1) as f64)
    });
    format!(
        "{} | {trace} | {} | {events} | {per_photon} | {stopped} | {cap}",
        median(&rep.frame_ms).map_or("-".into(), |ms| format!("{ms:.3}")),
        rep.photons_traced
    )
}

const PARTS_NOTES: &str = "
The scenes are `scenes::closed::glass_parts(n, closed)`: `n` parts cycling through a \
brilliant-cut gem (IOR 2.4), a thick glass ball (IOR 1.5) and a thin-walled shell, lit by one \
bulb; `_open` over a floor, `_room` inside a closed room of receivers. Every technique at its \
defaults (2^18 photons per light). AAPS and the photon map trace at most \
`photons · bounce_budget` specular events per frame (default 8 per photon), whatever the \
scene: `per photon` is what the scene asked for, `stopped by the budget` the paths it cut \
(their flux counted). Image space follows one interface and the exit per photon and volumes \
propagate each photon once per slab, so their trace cost does not depend on the chains of \
internal reflections at all. `trace ms` is the trace pass (AAPS, photon map, image space) or \
the volumes' projection pass.
";

/// Refuse, before minutes of rendering, what a run would fail on: a missing scene, a size or
/// photon count above this adapter's maxima.
fn validate(runs: &[Run], limits: &CausticsLimits) -> Result<(), String> {
    for r in runs {
        if !r.job.scene.is_file() {
            return Err(format!("scene not found: {}", r.job.scene.display()));
        }
        check_job(&r.job, limits)
            .map_err(|e| format!("{} ({}): {e}", r.technique.name(), r.photons))?;
    }
    Ok(())
}

/// AAPS and image space at seed 003's photon counts (image space with its 2048² RSMs).
fn sweep(technique: CausticsTechnique, scene: &str, job: &RenderJob) -> Vec<Run> {
    let image_space = ImageSpaceSettings {
        rsm_resolution: 2048,
        ..Default::default()
    };
    let (rsm, image_space) = match technique {
        CausticsTechnique::Aaps => ("", job.image_space.clone()),
        CausticsTechnique::ImageSpace => (", RSM 2048²", image_space),
        _ => return Vec::new(),
    };
    SWEEP
        .iter()
        .map(|&p| Run {
            technique,
            scene: scene.to_string(),
            photons: format!("{p}/light{rsm}"),
            job: RenderJob {
                photons: Some(p),
                image_space: image_space.clone(),
                ..job.clone()
            },
            seed: seed_figure(technique, Some(p)),
        })
        .collect()
}

/// The scene most like the one the technique's seed measured.
fn default_scene(technique: CausticsTechnique) -> &'static str {
    match technique {
        CausticsTechnique::Aaps | CausticsTechnique::ImageSpace => "pool",
        _ => "glass_sphere",
    }
}

/// Volumes update only when something in them changes; turning the sun by 1e-4 rad every frame
/// makes every frame a full update (as seed 000 measured, and `examples/report.rs` does).
fn turn_sun(world: &mut World, frame: u32) {
    let mut q = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
    for mut t in q.iter_mut(world) {
        t.rotate_x(if frame.is_multiple_of(2) { 1e-4 } else { -1e-4 });
    }
}

/// The seeds' published figure for a technique (at a sweep photon count), as checked in
/// the seed documents (the conditions are in the notes below the table).
fn seed_figure(technique: CausticsTechnique, photons: Option<u64>) -> &'static str {
    match (technique, photons) {
        (CausticsTechnique::Aaps, None) => {
            "2.6 ms (Pool, target area 19 as ours); 0.47 (Cornell) to 14 ms; 1920x960 [004 §4.4]"
        }
        (CausticsTechnique::Aaps, Some(_)) => {
            "0.47 ms (Cornell baseline) to 14 ms (Pool), 1920x960 [004 §4.4]"
        }
        (CausticsTechnique::ImageSpace, Some(500_000)) => "22.00 ms at 0.5 M [003 §4.2 T1]",
        (CausticsTechnique::ImageSpace, Some(1_000_000)) => "34.68 ms at 1 M [003 §4.2 T1]",
        (CausticsTechnique::ImageSpace, Some(2_000_000)) => "56.10 ms at 2 M [003 §4.2 T1]",
        (CausticsTechnique::ImageSpace, _) => "22.00 ms at 0.5 M to 56.10 ms at 2 M [003 §4.2 T1]",
        (CausticsTechnique::PhotonMap, _) => "3.03-6.15 ms per frame, small radii [001 §4.2 T1]",
        (CausticsTechnique::Volume, _) => "14-141 ms per slab or projector pass [000 §4 T4-6]",
        (CausticsTechnique::Reference, _) => "-",
    }
}

/// "12.345 ms": the median of the measured frames' sums.
fn total_cell(report: &RenderReport) -> String {
    match median(&report.frame_ms) {
        Some(ms) => format!("{ms:.3} ms"),
        None => "no frame measured".into(),
    }
}

fn median(values: &[f64]) -> Option<f64> {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

/// "aaps/trace 1.23 · aaps/splat 0.45 · composite 0.03", in dispatch order.
fn passes_cell(report: &RenderReport) -> String {
    let mut names: Vec<&String> = report
        .passes
        .iter()
        .filter(|p| report.pass_ms.contains_key(*p))
        .collect();
    names.extend(report.pass_ms.keys().filter(|p| !report.passes.contains(p)));
    names
        .iter()
        .map(|p| {
            let short = p.strip_prefix("caustics/").unwrap_or(p);
            format!("{short} {:.3}", report.pass_ms[*p])
        })
        .collect::<Vec<_>>()
        .join(" · ")
}

/// "aaps 41.2 MiB · temporal 31.6 MiB": the GPU memory each part held at the last frame.
fn memory_cell(report: &RenderReport) -> String {
    let parts: Vec<String> = report
        .gpu_bytes
        .iter()
        .filter(|(_, b)| **b > 0)
        .map(|(k, b)| format!("{k} {:.1} MiB", *b as f64 / (1024.0 * 1024.0)))
        .collect();
    if parts.is_empty() {
        "-".into()
    } else {
        parts.join(" · ")
    }
}

/// The whole Markdown document: header, the table, the seeds' conditions.
fn markdown(args: &Args, adapter: &str, timed: &[Timed], minutes: f64) -> String {
    let mut md = String::from("# bevy_caustics: GPU milliseconds per pass\n\n");
    md.push_str(&header(args, adapter, timed, minutes));
    md.push_str(&table(timed));
    md.push_str(SEED_NOTES);
    md
}

/// Adapter, driver, resolution, frames, the clock, and a warning on a CPU adapter.
fn header(args: &Args, adapter: &str, timed: &[Timed], minutes: f64) -> String {
    let reports: Vec<&RenderReport> = timed
        .iter()
        .filter_map(|t| t.result.as_ref().ok())
        .collect();
    let driver = reports
        .first()
        .map_or("(no run finished)", |r| r.driver.as_str());
    let mut s = String::new();
    let _ = writeln!(s, "- Adapter: **{adapter}**; driver: {driver}");
    let _ = writeln!(
        s,
        "- Resolution {}x{}; per run {} warm-up frames, then {} measured frames (medians over \
         those whose diagnostics arrived: column `n`); `settle_frames` 0. This run took \
         {minutes:.1} min.",
        args.width, args.height, args.warmup, args.frames
    );
    let _ = writeln!(
        s,
        "- Command: `cargo run --release --example gpu_timings -- {}`",
        std::env::args().skip(1).collect::<Vec<_>>().join(" ")
    );
    if reports.iter().any(|r| r.timing != "gpu") {
        let _ = writeln!(
            s,
            "- **No GPU timestamps** on this adapter for some runs (clock `cpu` below): Bevy \
             records timestamps inside passes only with `TIMESTAMP_QUERY` and \
             `TIMESTAMP_QUERY_INSIDE_PASSES` (Vulkan, DX12). Those figures are the CPU time of \
             recording each pass, not GPU time: they are not measurements of the GPU."
        );
    }
    if driver.contains("(Cpu)") {
        let _ = writeln!(
            s,
            "- **CPU adapter** (lavapipe?): its GPU spans are real (settled, `render/span.rs`), \
             but 100 to 1000 times a real GPU's; compare passes with each other, not with the seeds."
        );
    }
    s.push('\n');
    s
}

/// One row per run: technique, scene, photons, clock, frames, total and per-pass medians,
/// wall time, and the seeds' figure beside it.
fn table(timed: &[Timed]) -> String {
    let mut s = String::from(
        "| technique | scene | photons | clock | n | total ms (median) | per pass, median ms | GPU memory | wall s | seeds' figure |\n\
         | --- | --- | --- | --- | ---: | ---: | --- | --- | ---: | --- |\n",
    );
    for t in timed {
        let r = &t.run;
        let (clock, n, total, passes, memory) = match &t.result {
            Ok(rep) => (
                rep.timing.clone(),
                rep.frame_ms.len().to_string(),
                median(&rep.frame_ms).map_or("-".into(), |ms| format!("{ms:.3}")),
                passes_cell(rep),
                memory_cell(rep),
            ),
            Err(e) => (
                "-".into(),
                "0".into(),
                "failed".into(),
                e.replace('|', "/"),
                "-".into(),
            ),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {clock} | {n} | {total} | {passes} | {memory} | {:.1} | {} |",
            r.technique.name(),
            r.scene,
            r.photons,
            t.seconds,
            r.seed
        );
    }
    s.push('\n');
    s
}

/// The seeds' figures with their conditions, as read in the seed documents.
const SEED_NOTES: &str = "\
## The seeds' figures and their conditions

- **AAPS**, seed 004 (van Casteren, MSc thesis), section 4.4 (\"All performance data was \
recorded at a resolution of 1920x960\"), DirectX 12 + DXR (hardware ray tracing), density \
texture 256². §4.4.2: baseline 0.47 ms on an RX 6900 XT and 0.52 ms on an RTX 3080 (Cornell \
scene, maximum target area: ray tracing 0.24 ms, task buffer 0.16 / 0.23 ms, copy 0.03 ms). \
Fig. 25: 14, 2.6, 1.2 and 1.0 ms at four target-area settings; Pool scene: 14 ms at a small \
target area without anti-aliasing (fig. 35), 2.6 ms at target area 19 (fig. 31, our default \
`target_area`). Photon counts appear only on the graphs' axes (figs. 24-27); \
fig. 1 quotes 180 000 photons recorded (1920x1080, with the indirect-caustics extension, \
< 10 ms).
- **Image space**, seed 003 (Meenrattanakorn & Lambers), section 4.2, table 1, flooded Sponza, \
1920x1080 with 2048² RSMs (section 4), RX 6500 XT as an eGPU over Thunderbolt 3: 0.5 M \
photons 22.00 ms (tracing 11.67, storing 0.39, denoising 9.94), 1 M 34.68 ms, 2 M 56.10 ms.
- **Caustics volumes**, seed 000 (De Barro et al.), section 4, tables 4-6: per slab (S_k) and \
projector (Proj) pass 14 to 141 ms (summarised as 20 to 140 ms in the seeds' README), Unity, \
with GPU-to-CPU copies between slabs, optimisations off, G-buffers 100² / 10K photons to \
500² / 50K photons, 1 to 3 slabs; the GPU is not named. Ours keeps everything on the GPU.
- **Hash-grid photon map**, seed 001 (VR photon mapping, CUDA/OptiX), section 4.2, table 1 \
(hash grid column), RTX 2060 SUPER, frame times (the mean of 100 consecutive \
frames): 3.03 ms (128² = 16 384 photons, r 0.05), 5.73 ms (128², r 0.1), 6.15 ms (512², \
r 0.02), 7.05 ms (256², r 0.05); up to 567.70 ms at 512², r 0.1.

Our `total` is the median over the measured frames of the sum of the caustics passes' spans \
(the technique's passes and `caustics/composite`); Bevy's own passes (G-buffer, lighting) are \
left out, as seed 004 leaves out acceleration-structure builds and direct lighting. A pass \
drawn twice under one name in a frame (a volume slab's near and far G-buffers) counts both. \
In these still scenes image space draws its reflective shadow maps only once (they are redrawn \
when the scene changes), so its measured frames hold none, as seed 003's table 1 has none; \
the photon map accumulates progressively, each frame one trace, grid build and gather.
";

fn write_out(out: &std::path::Path, md: &str) -> Result<(), String> {
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    std::fs::write(out, md).map_err(|e| format!("cannot write {}: {e}", out.display()))
}
