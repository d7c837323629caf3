//! The seed's tables 4 to 6 on this machine: GPU milliseconds per slab and per projector pass
//! of caustics volumes, for G-buffers of 100², 200², 500² with 10K, 20K, 50K photons and 1 to 3
//! slabs, with the error against the cached CPU reference at the same settings. Writes
//! `report/VOLUME.md`.
//!
//! ```text
//! cargo run --release --example volume_report -- [--scenes a,b,..] [--out DIR] [--progressive 1]
//! ```
//!
//! `--progressive 1` measures progressive mode instead (`report/VOLUME_PROGRESSIVE.md`).
//!
//! As in the paper, optimisations are off (differential updates off) and a full update is
//! forced every frame (the sun turns by 1e-4 rad each frame); medians over the measured frames.

use std::fmt::Write as _;
use std::path::PathBuf;

use bevy::prelude::*;
use bevy_caustics::headless::{RenderJob, RenderReport, find_adapter, run};
use bevy_caustics::reference::{CausticImage, compare};
use bevy_caustics::{CausticsTechnique, CausticsVolume};
use clap::Parser;

const CONFIGS: [(u32, i32); 3] = [(100, 10_000), (200, 20_000), (500, 50_000)];

fn turn_sun(world: &mut World, frame: u32) {
    let mut q = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
    for mut t in q.iter_mut(world) {
        t.rotate_x(if frame.is_multiple_of(2) { 1e-4 } else { -1e-4 });
    }
}

/// Per slab (raster + propagation) and projector GPU ms, and the error against `reference`.
fn numbers(
    report: &RenderReport,
    slabs: u32,
    reference: &Option<CausticImage>,
) -> (Vec<String>, f64, String, String, String) {
    let ms = |name: &str| report.pass_ms.get(name).copied().unwrap_or(0.0);
    let slab_ms: Vec<String> = (1..=slabs)
        .map(|k| {
            format!(
                "{:.1}",
                ms(&format!("caustics/volume/slab{k}"))
                    + ms(&format!("caustics/volume/slab{k}_gbuffer"))
            )
        })
        .collect();
    let proj: f64 = (0..6)
        .map(|f| ms(&format!("caustics/volume/projector{f}_gbuffer")))
        .sum::<f64>()
        + ms("caustics/volume/project");
    let (energy, rmse, flip) = match (&report.caustics, reference) {
        (Some(img), Some(r)) => {
            compare(img, r, None).map_or(("-".into(), "-".into(), "-".into()), |m| {
                (
                    format!("{:+.3}", m.energy_error),
                    format!("{:.1}", m.rmse),
                    format!("{:.4}", m.flip),
                )
            })
        }
        _ => ("-".into(), "-".into(), "-".into()),
    };
    (slab_ms, proj, energy, rmse, flip)
}

/// Render `scene` at 128 x 128 with `volume` (fitted), the sun turning every frame.
fn render(root: &std::path::Path, scene: &str, volume: CausticsVolume) -> RenderReport {
    run(RenderJob {
        scene: root.join(format!("assets/scenes/{scene}.gltf")),
        technique: CausticsTechnique::Volume,
        width: 128,
        height: 128,
        frames: 8,
        per_frame: Some(turn_sun),
        volume,
        ..Default::default()
    })
    .unwrap_or_else(|e| {
        eprintln!("error: {scene}: {e}");
        std::process::exit(2)
    })
}

/// Progressive mode (section 3.5) with the sun turning every frame: every frame restarts the
/// accumulation, so it traces one batch; its GPU ms per frame and the error of that one-batch
/// estimate (photons / traced scaling) against the reference, next to the full update.
fn progressive_section(root: &std::path::Path, scenes: &[String]) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Progressive mode\n\nG 200², a pool of 20 000 photons, 3 slabs, the sun turned every \
         frame (so every frame restarts and traces one batch). GPU ms of one frame's update \
         (slabs 1-3 + projectors); the error of that frame's one-batch estimate against the \
         reference. Once the pool is traced the accumulation equals the full update (test \
         `volume_progressive_mode_converges_to_the_full_update`).\n\n\
         | scene | photons per frame | slabs ms | projectors ms | update ms | energy | RMSE lx | FLIP |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|"
    );
    for scene in scenes {
        let reference =
            CausticImage::read_exr(root.join(format!("assets/reference/{scene}_128.exr"))).ok();
        for batch in [0u32, 10_000, 5_000, 2_000] {
            eprintln!("{scene}: progressive {batch}");
            let report = render(
                root,
                scene,
                CausticsVolume {
                    photons: 20_000,
                    progressive: batch,
                    ..Default::default()
                },
            );
            let (slab_ms, proj, energy, rmse, flip) = numbers(&report, 3, &reference);
            let slabs: f64 = slab_ms.iter().filter_map(|v| v.parse::<f64>().ok()).sum();
            let label = if batch == 0 {
                "20000 (off)".to_string()
            } else {
                batch.to_string()
            };
            let _ = writeln!(
                md,
                "| {scene} | {label} | {slabs:.1} | {proj:.1} | {:.1} | {energy} | {rmse} | {flip} |",
                slabs + proj
            );
        }
    }
    md
}

/// The seed's tables 4 to 6 on this adapter: GPU milliseconds per slab and per projector pass
/// of caustics volumes, for G-buffers of 100², 200², 500² with 10K, 20K, 50K photons and 1 to
/// 3 slabs, with the error against the cached CPU reference. Writes VOLUME.md (or, with
/// --progressive, VOLUME_PROGRESSIVE.md).
///
/// Renders are 128x128 pixels; a full update is forced every frame. Errors print one line and
/// exit with status 2.
#[derive(Parser, Debug)]
#[command(name = "volume_report", args_override_self = true)]
struct Cli {
    /// Scenes of assets/scenes/ to measure, comma-separated names.
    #[arg(
        long,
        value_name = "A,B,...",
        default_value = "mirror_wall,glass_slab,glass_sphere,pool,ring"
    )]
    scenes: String,
    /// Folder the report is written to.
    #[arg(long, value_name = "DIR", default_value_os_t = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("report"))]
    out: PathBuf,
    /// Measure progressive mode instead (writes VOLUME_PROGRESSIVE.md); given as
    /// `--progressive 1` (any value, or none, turns it on) [default: off].
    #[arg(long, value_name = "1", num_args = 0..=1)]
    progressive: Option<Option<String>>,
}

fn main() {
    bevy_caustics::headless::quiet_headless_environment();
    // A usage error (unknown option, bad value) prints clap's message and exits 2.
    let cli = Cli::parse();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let scenes: Vec<String> = cli.scenes.split(',').map(String::from).collect();
    let out = cli.out;
    let progressive = cli.progressive.is_some();
    let adapter = find_adapter().unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2)
    });
    if progressive {
        let mut md = format!(
            "# Caustics volumes: progressive mode\n\nAdapter: {adapter}. 128x128 camera, medians of GPU ms over the measured frames.\n\n"
        );
        md.push_str(&progressive_section(&root, &scenes));
        write_report(&out, "VOLUME_PROGRESSIVE.md", &md);
        return;
    }
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Caustics volumes: the seed's tables 4 to 6\n\nAdapter: {adapter}. 128x128 camera, \
         medians of GPU ms over the measured frames, full update every frame (differential \
         updates off, the sun turned by 1e-4 rad per frame). `slab k` = its G_near + G_far \
         rasterisation + its propagation; `projectors` = the exit faces' G-buffers + the \
         projector march and density tiles; `splat` and `blur` are per view. Error against the \
         cached CPU reference (8.4 M photons/light).\n"
    );
    for slabs in 1..=3u32 {
        let _ = writeln!(
            md,
            "## {slabs} slab(s) (table {})\n\n| scene | G | photons | {} | projectors ms | splat ms | blur ms | energy | RMSE lx | FLIP |\n|---|---:|---:|{}---:|---:|---:|---:|---:|---:|",
            3 + slabs,
            (1..=slabs)
                .map(|k| format!("slab {k} ms"))
                .collect::<Vec<_>>()
                .join(" | "),
            "---:|".repeat(slabs as usize),
        );
        for scene in &scenes {
            let reference =
                CausticImage::read_exr(root.join(format!("assets/reference/{scene}_128.exr"))).ok();
            for (g, photons) in CONFIGS {
                eprintln!("{scene}: {slabs} slab(s), G {g}, {photons} photons");
                let report = render(
                    &root,
                    scene,
                    CausticsVolume {
                        slabs,
                        photons,
                        gbuffer_resolution: g,
                        projector_resolution: g,
                        differential: false,
                        ..Default::default()
                    },
                );
                let (slab_ms, proj, energy, rmse, flip) = numbers(&report, slabs, &reference);
                let ms = |name: &str| report.pass_ms.get(name).copied().unwrap_or(0.0);
                let _ = writeln!(
                    md,
                    "| {scene} | {g}² | {photons} | {} | {proj:.1} | {:.1} | {:.1} | {energy} | {rmse} | {flip} |",
                    slab_ms.join(" | "),
                    ms("caustics/volume/splat"),
                    ms("caustics/volume/blur"),
                );
            }
        }
        md.push('\n');
    }
    write_report(&out, "VOLUME.md", &md);
}

fn write_report(out: &std::path::Path, name: &str, md: &str) {
    std::fs::create_dir_all(out).ok();
    let path = out.join(name);
    if let Err(e) = std::fs::write(&path, md) {
        eprintln!("error: cannot write {}: {e}", path.display());
        std::process::exit(2);
    }
    println!("{md}");
}
