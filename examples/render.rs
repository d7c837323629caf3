//! The headless renderer: a glTF in, the caustic irradiance (EXR, lux), the final frame (PNG)
//! and statistics (JSON) out.
//!
//! ```text
//! cargo run --release --example render -- SCENE.gltf --technique reference --width 256 \
//!     --height 256 --out-exr caustics.exr --out-png frame.png --json stats.json \
//!     [--photons N] [--frames N] [--seed N] [--ev100 EV] [--compare REF.exr] [--aaps field=value,...]
//!     [--volume field=value,...] [--image-space field=value,...] [--photon-map field=value,...]
//!     [--stereo METRES] [--webgpu-limits] [--without FEATURE,...] [--settle-frames N]
//! ```
//!
//! `--webgpu-limits` starts the device with WebGPU's default limits; `--without` leaves
//! adapter features off it (`float32_blendable`, `texture_adapter_specific_format_features`),
//! to try the fallbacks a browser may need. `--settle-frames` sets `Caustics::settle_frames`
//! (default 16; 0: every frame runs the technique).
//!
//! The scene path is relative to the working directory (its buffers and images to the glTF's
//! folder). Errors (missing or unreadable file, no camera, no lights, no adapter, bad option, a
//! size above what this adapter allows: see `bevy_caustics::limits`) print one line naming
//! the file or option and exit with status 2; no output file is written unless the whole
//! render succeeded.

use std::path::PathBuf;
use std::process::ExitCode;

use bevy_caustics::CausticsTechnique;
use bevy_caustics::headless::{RenderJob, adapter_limits, check_job, find_adapter, run};
use bevy_caustics::reference::{CausticImage, compare};

struct Outputs {
    exr: Option<PathBuf>,
    png: Option<PathBuf>,
    json: Option<PathBuf>,
    compare: Option<PathBuf>,
}

fn parse(args: &[String]) -> Result<(RenderJob, Outputs), String> {
    let mut job = RenderJob {
        progress: true,
        ..Default::default()
    };
    let mut out = Outputs {
        exr: None,
        png: None,
        json: None,
        compare: None,
    };
    let mut scene = None;
    let mut i = 0;
    let num = |v: Option<&String>, name: &str| -> Result<u64, String> {
        let v = v.ok_or_else(|| format!("{name} needs a value"))?;
        v.parse::<u64>().map_err(|e| match e.kind() {
            std::num::IntErrorKind::PosOverflow => format!("{name} {v} is too large"),
            _ => format!("{name} expects a non-negative integer, got '{v}'"),
        })
    };
    while i < args.len() {
        let a = args[i].as_str();
        let v = args.get(i + 1);
        let path = |v: Option<&String>| {
            v.map(PathBuf::from)
                .ok_or_else(|| format!("{a} needs a path"))
        };
        match a {
            "--technique" => {
                let t = v.ok_or("--technique needs a value")?;
                job.technique = CausticsTechnique::from_name(t).ok_or_else(|| {
                    format!(
                        "unknown technique '{t}' (available: reference, aaps, volume, image_space, photon_map)"
                    )
                })?;
            }
            // Saturating: a value past u32 stays out of range for `check_job` to refuse.
            "--width" => job.width = num(v, a)?.min(u32::MAX as u64) as u32,
            "--height" => job.height = num(v, a)?.min(u32::MAX as u64) as u32,
            "--photons" => job.photons = Some(num(v, a)?),
            "--stereo" => {
                // A stereo pair this many metres apart (`CausticsStereo`; the outputs are the
                // right eye's caustics and the left eye's frame).
                let t = v.ok_or("--stereo needs the eye separation in metres")?;
                let sep: f32 = t
                    .parse()
                    .ok()
                    .filter(|x: &f32| x.is_finite() && *x >= 0.0)
                    .ok_or_else(|| format!("--stereo expects metres >= 0, got '{t}'"))?;
                job.stereo = Some(sep);
            }
            "--frames" => job.frames = num(v, a)?.min(u32::MAX as u64) as u32,
            "--settle-frames" => job.settle_frames = num(v, a)?.min(u32::MAX as u64) as u32,
            "--seed" => job.seed = num(v, a)?,
            "--ev100" => {
                let t = v.ok_or("--ev100 needs a value")?;
                let ev = t
                    .parse::<f32>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| format!("--ev100 expects a number, got '{t}'"))?;
                job.ev100 = Some(ev);
            }
            "--aaps" => {
                // AAPS settings as `field=value,field=value` (AapsSettings field names).
                let t = v.ok_or("--aaps needs field=value pairs")?;
                for kv in t.split(',') {
                    let (k, x) = kv
                        .split_once('=')
                        .ok_or_else(|| format!("--aaps expects field=value, got '{kv}'"))?;
                    let f = || {
                        x.parse::<f32>()
                            .ok()
                            .filter(|x| x.is_finite())
                            .ok_or_else(|| format!("--aaps {k} expects a number, got '{x}'"))
                    };
                    let a = &mut job.aaps;
                    match k {
                        "atlas_resolution" => a.atlas_resolution = f()? as u32,
                        "target_area" => a.target_area = f()?,
                        "variance_gain" => a.variance_gain = f()?,
                        "temporal_weight" => a.temporal_weight = f()?,
                        "min_density" => a.min_density = f()?,
                        "max_density" => a.max_density = f()?,
                        "cull_solid_angle" => a.cull_solid_angle = f()?,
                        "msaa_threshold" => a.msaa_threshold = f()?,
                        "max_anisotropy" => a.max_anisotropy = f()?,
                        "splat_scale" => a.splat_scale = f()?,
                        "max_bounces" => a.max_bounces = f()? as u32,
                        "splat_capacity" => a.splat_capacity = f()? as u32,
                        "adaptive" => a.adaptive = f()? != 0.0,
                        "drop_large_splats" => a.drop_large_splats = f()? != 0.0,
                        _ => return Err(format!("--aaps: unknown field '{k}'")),
                    }
                }
            }
            "--volume" => {
                // Settings of the fitted volumes as `field=value,...` (CausticsVolume names).
                let t = v.ok_or("--volume needs field=value pairs")?;
                for kv in t.split(',') {
                    let (k, x) = kv
                        .split_once('=')
                        .ok_or_else(|| format!("--volume expects field=value, got '{kv}'"))?;
                    let f = || {
                        x.parse::<f32>()
                            .ok()
                            .filter(|x| x.is_finite())
                            .ok_or_else(|| format!("--volume {k} expects a number, got '{x}'"))
                    };
                    let a = &mut job.volume;
                    match k {
                        "slabs" => a.slabs = f()? as u32,
                        "photons" => a.photons = f()? as i32,
                        "projector_resolution" => a.projector_resolution = f()? as u32,
                        "gbuffer_resolution" => a.gbuffer_resolution = f()? as u32,
                        "tile_size" => a.tile_size = f()? as u32,
                        "splat_overlap" => a.splat_overlap = f()?,
                        "blur_radius" => a.blur_radius = f()? as u32,
                        "lod_distance" => a.lod_distance = f()?,
                        "differential" => a.differential = f()? != 0.0,
                        "frustum_cull" => a.frustum_cull = f()? != 0.0,
                        "progressive" => a.progressive = f()?.max(0.0) as u32,
                        _ => return Err(format!("--volume: unknown field '{k}'")),
                    }
                }
            }
            "--image-space" => {
                // Image-space settings as `field=value,...` (ImageSpaceSettings names).
                let t = v.ok_or("--image-space needs field=value pairs")?;
                for kv in t.split(',') {
                    let (k, x) = kv
                        .split_once('=')
                        .ok_or_else(|| format!("--image-space expects field=value, got '{kv}'"))?;
                    let f = || {
                        x.parse::<f32>()
                            .ok()
                            .filter(|x| x.is_finite())
                            .ok_or_else(|| format!("--image-space {k} expects a number, got '{x}'"))
                    };
                    let a = &mut job.image_space;
                    match k {
                        "rsm_resolution" => a.rsm_resolution = f()? as u32,
                        "luminance_cutoff" => a.luminance_cutoff = f()?,
                        "stride" => a.stride = f()? as u32,
                        "hi_z" => a.hi_z = f()? != 0.0,
                        "thickness" => a.thickness = f()?,
                        "denoise" => a.denoise = f()? != 0.0,
                        "alpha_color" => a.alpha_color = f()?,
                        "alpha_moments" => a.alpha_moments = f()?,
                        "history_cap" => a.history_cap = f()? as u32,
                        "atrous_iterations" => a.atrous_iterations = f()? as u32,
                        "sigma_depth" => a.sigma_depth = f()?,
                        "sigma_normal" => a.sigma_normal = f()?,
                        "sigma_luminance" => a.sigma_luminance = f()?,
                        "reset_on_change" => a.reset_on_change = f()? != 0.0,
                        _ => return Err(format!("--image-space: unknown field '{k}'")),
                    }
                }
            }
            "--photon-map" => {
                // Photon-map settings as `field=value,...` (PhotonMapSettings names).
                let t = v.ok_or("--photon-map needs field=value pairs")?;
                for kv in t.split(',') {
                    let (k, x) = kv
                        .split_once('=')
                        .ok_or_else(|| format!("--photon-map expects field=value, got '{kv}'"))?;
                    let f = || {
                        x.parse::<f32>()
                            .ok()
                            .filter(|x| x.is_finite())
                            .ok_or_else(|| format!("--photon-map {k} expects a number, got '{x}'"))
                    };
                    let a = &mut job.photon_map;
                    match k {
                        "radius" => a.radius = f()?,
                        "max_bounces" => a.max_bounces = f()? as u32,
                        "max_grid_cells" => a.max_grid_cells = f()? as u32,
                        "progressive" => a.progressive = f()? != 0.0,
                        "alpha" => a.alpha = f()?,
                        "max_frames" => a.max_frames = f()? as u32,
                        "normal_threshold" => a.normal_threshold = f()?,
                        "shared_memory" => a.shared_memory = f()? != 0.0,
                        "mirrors" => a.mirrors = f()? != 0.0,
                        "stereo_reuse" => a.stereo_reuse = f()? != 0.0,
                        _ => return Err(format!("--photon-map: unknown field '{k}'")),
                    }
                }
            }
            "--out-exr" => out.exr = Some(path(v)?),
            "--out-png" => out.png = Some(path(v)?),
            "--json" => out.json = Some(path(v)?),
            "--compare" => out.compare = Some(path(v)?),
            "--without" => {
                // Leave adapter features off the device (the techniques' fallbacks).
                let t = v.ok_or("--without needs a feature list")?;
                for name in t.split(',') {
                    job.disabled_features |= match name {
                        "float32_blendable" => {
                            bevy::render::settings::WgpuFeatures::FLOAT32_BLENDABLE
                        }
                        "texture_adapter_specific_format_features" => {
                            bevy::render::settings::WgpuFeatures::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
                        }
                        _ => {
                            return Err(format!(
                                "--without: unknown feature '{name}' (available: float32_blendable, texture_adapter_specific_format_features)"
                            ));
                        }
                    };
                }
            }
            "--webgpu-limits" => {
                // The device gets WebGPU's default limits instead of the adapter's.
                job.webgpu_limits = true;
                i += 1;
                continue;
            }
            s if s.starts_with("--") => return Err(format!("unknown option {s}")),
            s => {
                if scene.replace(PathBuf::from(s)).is_some() {
                    return Err("more than one scene given".into());
                }
                i += 1;
                continue;
            }
        }
        i += 2;
    }
    job.scene = scene.ok_or("usage: render SCENE.gltf [--technique reference|aaps|volume|image_space|photon_map] [--width N] [--height N] [--out-exr F] [--out-png F] [--json F] [--photons N] [--frames N] [--seed N] [--ev100 EV] [--compare REF.exr] [--aaps field=value,...] [--volume field=value,...] [--image-space field=value,...] [--photon-map field=value,...] [--stereo METRES] [--webgpu-limits] [--without FEATURE,...] [--settle-frames N]")?;
    Ok((job, out))
}

fn main() -> ExitCode {
    bevy_caustics::headless::quiet_headless_environment();
    let args: Vec<String> = std::env::args().skip(1).collect();
    match real_main(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn real_main(args: &[String]) -> Result<(), String> {
    let (job, out) = parse(args)?;
    // Read the comparison image first: a bad --compare fails before any work.
    let reference = out
        .compare
        .as_ref()
        .map(CausticImage::read_exr)
        .transpose()?;
    if !job.scene.is_file() {
        return Err(format!("scene file not found: {}", job.scene.display()));
    }
    find_adapter()?;
    // Every size against this adapter's maxima before anything is allocated.
    let limits = if job.webgpu_limits {
        bevy_caustics::limits::CausticsLimits::default()
    } else {
        adapter_limits()?
    };
    check_job(&job, &limits)?;
    let mut job = job;
    job.limits = Some(limits);
    let (w, h) = (job.width, job.height);
    let mut report = run(job)?;
    let caustics = report
        .caustics
        .take()
        .unwrap_or_else(|| CausticImage::new(w, h));
    if let Some(r) = &reference {
        // Over every pixel: where the camera sees no diffuse surface both buffers are zero.
        report.metrics = Some(compare(&caustics, r, None).ok_or_else(|| {
            format!(
                "--compare image is {}x{}, the render is {w}x{h}",
                r.width, r.height
            )
        })?);
    }
    if let Some(p) = &out.exr {
        caustics.write_exr(p)?;
    }
    if let Some(p) = &out.png {
        image::save_buffer(p, &report.frame_rgba8, w, h, image::ColorType::Rgba8)
            .map_err(|e| format!("cannot write {}: {e}", p.display()))?;
    }
    let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    if let Some(p) = &out.json {
        std::fs::write(p, &json).map_err(|e| format!("cannot write {}: {e}", p.display()))?;
    } else {
        println!("{json}");
    }
    Ok(())
}
