//! Error against run time, for every scene and technique: `REPORT.md` plus one SVG per scene.
//!
//! ```text
//! cargo run --release --example report -- [--scenes a,b,..] [--techniques reference,aaps,image_space,photon_map] \
//!     [--out DIR] [--size N]
//! ```
//!
//! Each scene of `assets/scenes/` is compared against a converged reference image that is
//! computed once (by the reference technique at `CONVERGED_PHOTONS` photons per light, seed
//! `CONVERGED_SEED`) and cached in `assets/reference/` with a JSON that records how it was
//! made; a cache whose recipe differs is recomputed. Every sweep point renders through the same
//! headless renderer as `examples/render.rs` (seed 2, so it is independent of the reference).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use bevy_caustics::CausticsTechnique;
use bevy_caustics::headless::{RenderJob, find_adapter, run};
use bevy_caustics::reference::{CausticImage, ImageMetrics, compare};
use plotters::prelude::*;

use bevy_caustics::reference::cache::{
    AAPS_LEVELS, CONVERGED_PHOTONS, CONVERGED_SEED, POOL_PHOTONS, converged_photons,
    converged_recipe,
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

/// The image-space quality levels: (name, photons per light and frame, RSM side).
const IMAGE_SPACE_LEVELS: [(&str, u64, u32); 3] = [
    ("low: 2^16/light, RSM 512", 1 << 16, 512),
    ("medium: 2^18/light, RSM 1024", 1 << 18, 1024),
    ("high: 2^20/light, RSM 1024", 1 << 20, 1024),
];

/// The photon-map quality levels: (name, photons per light and frame), default settings
/// (progressive: the 12 measured frames accumulate).
const PHOTON_MAP_LEVELS: [(&str, u64); 3] = [
    ("low: 2^16/light", 1 << 16),
    ("medium: 2^18/light", 1 << 18),
    ("high: 2^20/light", 1 << 20),
];

fn main() {
    bevy_caustics::headless::quiet_headless_environment();
    if let Err(e) = real_main() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

fn real_main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut scenes: Vec<String> = [
        "mirror_wall",
        "glass_slab",
        "glass_sphere",
        "pool",
        "ring",
        "empty",
    ]
    .map(String::from)
    .to_vec();
    let mut techniques = vec![
        CausticsTechnique::Reference,
        CausticsTechnique::Aaps,
        CausticsTechnique::ImageSpace,
        CausticsTechnique::PhotonMap,
    ];
    let mut out = root.join("report");
    let mut size = 128u32;
    let mut i = 0;
    while i < args.len() {
        let v = args
            .get(i + 1)
            .ok_or_else(|| format!("{} needs a value", args[i]))?;
        match args[i].as_str() {
            "--scenes" => scenes = v.split(',').map(String::from).collect(),
            "--techniques" => {
                techniques = v
                    .split(',')
                    .map(|t| {
                        CausticsTechnique::from_name(t).ok_or_else(|| {
                            format!("unknown technique '{t}' (available: reference, aaps, volume, image_space, photon_map)")
                        })
                    })
                    .collect::<Result<_, _>>()?
            }
            "--out" => out = PathBuf::from(v),
            "--size" => {
                size = v
                    .parse()
                    .map_err(|_| format!("--size expects an integer, got '{v}'"))?
            }
            o => return Err(format!("unknown option {o}")),
        }
        i += 2;
    }
    let adapter = find_adapter()?;
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let sweep: Vec<u64> = vec![1 << 14, 1 << 16, 1 << 18, 1 << 20];
    let total = scenes.len() * (1 + techniques.len() * sweep.len().max(AAPS_LEVELS.len()));
    let mut step = 0;
    let mut points = Vec::new();
    for scene in &scenes {
        let path = root.join("assets/scenes").join(format!("{scene}.gltf"));
        step += 1;
        progress(step, total, &format!("{scene}: converged reference"));
        let reference = converged(&root, &path, scene, size)?;
        for technique in &techniques {
            type Run = (
                String,
                u64,
                bevy_caustics::AapsSettings,
                bevy_caustics::ImageSpaceSettings,
            );
            let runs: Vec<Run> = match technique {
                CausticsTechnique::Aaps => AAPS_LEVELS
                    .iter()
                    .map(|(name, budget, target)| {
                        let settings = bevy_caustics::AapsSettings {
                            target_area: *target,
                            ..Default::default()
                        };
                        (name.to_string(), *budget, settings, Default::default())
                    })
                    .collect(),
                CausticsTechnique::ImageSpace => IMAGE_SPACE_LEVELS
                    .iter()
                    .map(|(name, photons, rsm)| {
                        let settings = bevy_caustics::ImageSpaceSettings {
                            rsm_resolution: *rsm,
                            ..Default::default()
                        };
                        (name.to_string(), *photons, Default::default(), settings)
                    })
                    .collect(),
                CausticsTechnique::PhotonMap => PHOTON_MAP_LEVELS
                    .iter()
                    .map(|(name, photons)| {
                        (
                            name.to_string(),
                            *photons,
                            Default::default(),
                            Default::default(),
                        )
                    })
                    .collect(),
                _ => sweep
                    .iter()
                    .map(|p| {
                        let name = format!("{p} photons/light");
                        (name, *p, Default::default(), Default::default())
                    })
                    .collect(),
            };
            for (quality, photons, settings, image_space) in runs {
                step += 1;
                progress(
                    step,
                    total,
                    &format!("{scene}: {} {quality}", technique.name()),
                );
                let report = run(RenderJob {
                    scene: path.clone(),
                    technique: *technique,
                    width: size,
                    height: size,
                    photons: Some(photons),
                    seed: SWEEP_SEED,
                    frames: 12,
                    aaps: settings,
                    image_space,
                    ..Default::default()
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
                    quality,
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
    let mut md = String::new();
    let _ = writeln!(md, "# bevy_caustics: error against run time\n");
    let _ = writeln!(
        md,
        "Adapter: **{adapter}**. Target {size}x{size}. Milliseconds compare only on one adapter.\n"
    );
    let _ = writeln!(
        md,
        "Reference images: the reference technique at {CONVERGED_PHOTONS} photons per light ({POOL_PHOTONS} on pool), seed {CONVERGED_SEED} (cached in `assets/reference/`). Sweep seed {SWEEP_SEED}. Metrics over all pixels (pixels without caustics are zero in both): RMSE of luminance in lux, relative RMSE (RMSE / mean reference luminance), mean FLIP (LDR, both images scaled by the reference's 99th percentile), relative energy error.\n"
    );
    let _ = writeln!(
        md,
        "The reference technique runs on the CPU: `cpu ms` is its trace (wall clock, all cores). `gpu ms` is the sum of the median GPU times of the caustics passes over the measured frames (12 frames; AAPS's task buffer adapts during them, from a uniform start); the last column lists each pass. AAPS quality levels: photon budget per light (a ceiling) and target splat area; `splats` counts the splats drawn in the last frame. Image-space quality levels: photons per light and frame (`photons` counts those that started on a caster texel) and the side of the reflective shadow maps, with the default settings (Hi-Z march, SVGF). Photon-map quality levels: photons per light and frame with the default settings, so the 12 measured frames accumulate progressively (`photons` counts those emitted in the last frame).\n"
    );
    let _ = writeln!(
        md,
        "The converged image has noise of its own: at {CONVERGED_PHOTONS} photons its RMSE is about 1/sqrt({}) of the last sweep point's, so that point's error is overstated by about {:.0} %.\n",
        CONVERGED_PHOTONS / sweep[sweep.len() - 1],
        ((1.0 + sweep[sweep.len() - 1] as f64 / CONVERGED_PHOTONS as f64).sqrt() - 1.0) * 100.0
    );
    let _ = writeln!(
        md,
        "A scene whose technique dispatches no pass (no caster or no caustic light) shows 0 photons and 0 ms.\n"
    );
    let _ = writeln!(md, "Regenerate: `cargo run --release --example report`.\n");
    for scene in &scenes {
        let _ = writeln!(md, "## {scene}\n\n![{scene}]({scene}.svg)\n");
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
        plot(&out.join(format!("{scene}.svg")), scene, &points)?;
    }
    let report = out.join("REPORT.md");
    std::fs::write(&report, md).map_err(|e| format!("cannot write {}: {e}", report.display()))?;
    println!("wrote {}", report.display());
    Ok(())
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
    let report = run(RenderJob {
        scene: scene_path.to_path_buf(),
        width: size,
        height: size,
        photons: Some(converged_photons(scene)),
        seed: CONVERGED_SEED,
        frames: 4,
        ..Default::default()
    })?;
    let img = report
        .caustics
        .unwrap_or_else(|| CausticImage::new(size, size));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    img.write_exr(&exr)?;
    std::fs::write(&meta, serde_json::to_string_pretty(&recipe).unwrap())
        .map_err(|e| e.to_string())?;
    Ok(img)
}

fn plot(path: &Path, scene: &str, points: &[Point]) -> Result<(), String> {
    let pts: Vec<&Point> = points.iter().filter(|p| p.scene == scene).collect();
    let root = SVGBackend::new(path, (960, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let panels = root.split_evenly((1, 2));
    let ms = |p: &Point| (p.cpu_ms + p.gpu_ms).max(1e-3);
    let x_max = pts.iter().map(|p| ms(p)).fold(1.0f64, f64::max) * 2.0;
    let x_min = pts
        .iter()
        .map(|p| ms(p))
        .fold(f64::MAX, f64::min)
        .min(x_max / 4.0)
        / 2.0;
    let techniques: Vec<String> = {
        let mut t: Vec<String> = pts.iter().map(|p| p.technique.clone()).collect();
        t.dedup();
        t
    };
    type Metric = (&'static str, fn(&ImageMetrics) -> f64);
    let metrics: [Metric; 2] = [
        ("mean FLIP (unitless)", |m| m.flip),
        ("RMSE of luminance (lx)", |m| m.rmse),
    ];
    for (panel, (label, f)) in panels.iter().zip(metrics) {
        let ys: Vec<f64> = pts
            .iter()
            .map(|p| f(&p.metrics))
            .filter(|y| *y > 0.0)
            .collect();
        if ys.is_empty() {
            panel
                .draw(&Text::new(
                    format!("{scene}: {label} is 0 everywhere (no caustic)"),
                    (40, 200),
                    ("sans-serif", 16),
                ))
                .map_err(|e| e.to_string())?;
            continue;
        }
        let y_max = ys.iter().cloned().fold(f64::MIN, f64::max) * 2.0;
        let y_min = ys.iter().cloned().fold(f64::MAX, f64::min) / 2.0;
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("{scene}: {label}"), ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((x_min..x_max).log_scale(), (y_min..y_max).log_scale())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("run time per frame update, ms (cpu + gpu)")
            .y_desc(label)
            .draw()
            .map_err(|e| e.to_string())?;
        for (k, t) in techniques.iter().enumerate() {
            let color = Palette99::pick(k).to_rgba();
            let series: Vec<(f64, f64)> = pts
                .iter()
                .filter(|p| &p.technique == t && f(&p.metrics) > 0.0)
                .map(|p| (ms(p), f(&p.metrics)))
                .collect();
            chart
                .draw_series(LineSeries::new(series.clone(), color.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(t.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
            chart
                .draw_series(series.iter().map(|p| Circle::new(*p, 4, color.filled())))
                .map_err(|e| e.to_string())?;
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())
}
