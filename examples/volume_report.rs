//! The seed's tables 4 to 6 on this machine: GPU milliseconds per slab and per projector pass
//! of caustics volumes, for G-buffers of 100², 200², 500² with 10K, 20K, 50K photons and 1 to 3
//! slabs, with the error against the cached CPU reference at the same settings. Writes
//! `report/VOLUME.md`.
//!
//! ```text
//! cargo run --release --example volume_report -- [--scenes a,b,..] [--out DIR]
//! ```
//!
//! As in the paper, optimisations are off (differential updates off) and a full update is
//! forced every frame (the sun turns by 1e-4 rad each frame); medians over the measured frames.

use std::fmt::Write as _;
use std::path::PathBuf;

use bevy::prelude::*;
use bevy_caustics::headless::{RenderJob, find_adapter, run};
use bevy_caustics::reference::{CausticImage, compare};
use bevy_caustics::{CausticsTechnique, CausticsVolume};

const CONFIGS: [(u32, i32); 3] = [(100, 10_000), (200, 20_000), (500, 50_000)];

fn turn_sun(world: &mut World, frame: u32) {
    let mut q = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
    for mut t in q.iter_mut(world) {
        t.rotate_x(if frame.is_multiple_of(2) { 1e-4 } else { -1e-4 });
    }
}

fn main() {
    bevy_caustics::headless::quiet_headless_environment();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut scenes: Vec<String> = ["mirror_wall", "glass_slab", "glass_sphere", "pool", "ring"]
        .map(String::from)
        .to_vec();
    let mut out = root.join("report");
    for w in args.chunks(2) {
        match (w[0].as_str(), w.get(1)) {
            ("--scenes", Some(v)) => scenes = v.split(',').map(String::from).collect(),
            ("--out", Some(v)) => out = PathBuf::from(v),
            (o, _) => {
                eprintln!("error: unknown option {o}");
                std::process::exit(2);
            }
        }
    }
    let adapter = find_adapter().unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2)
    });
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
                let report = run(RenderJob {
                    scene: root.join(format!("assets/scenes/{scene}.gltf")),
                    technique: CausticsTechnique::Volume,
                    width: 128,
                    height: 128,
                    frames: 8,
                    per_frame: Some(turn_sun),
                    volume: CausticsVolume {
                        slabs,
                        photons,
                        gbuffer_resolution: g,
                        projector_resolution: g,
                        differential: false,
                        ..Default::default()
                    },
                    ..Default::default()
                });
                let report = match report {
                    Ok(r) => r,
                    Err(e) => {
                        eprintln!("error: {scene}: {e}");
                        std::process::exit(2);
                    }
                };
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
                let (energy, rmse, flip) = match (&report.caustics, &reference) {
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
    std::fs::create_dir_all(&out).ok();
    let path = out.join("VOLUME.md");
    if let Err(e) = std::fs::write(&path, &md) {
        eprintln!("error: cannot write {}: {e}", path.display());
        std::process::exit(2);
    }
    println!("{md}");
}
