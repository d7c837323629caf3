//! The headless renderer: a glTF in, the caustic irradiance (EXR, lux), the final frame (PNG)
//! and statistics (JSON) out.
//!
//! ```text
//! cargo run --release --example render -- SCENE.gltf --technique reference --width 256 \
//!     --height 256 --out-exr caustics.exr --out-png frame.png --json stats.json \
//!     [--photons N] [--frames N] [--seed N] [--ev100 EV] [--compare REF.exr] [--aaps field=value,...]
//!     [--volume field=value,...] [--image-space field=value,...] [--photon-map field=value,...]
//!     [--stereo METRES] [--webgpu-limits] [--without FEATURE,...] [--settle-frames N] [--stage]
//! ```
//!
//! `--help` lists every option with its unit and default. `--webgpu-limits` starts the device
//! with WebGPU's default limits; `--without` leaves adapter features off it
//! (`float32_blendable`, `texture_adapter_specific_format_features`), to try the fallbacks a
//! browser may need. `--stage` puts a model that has no light, camera or floor (most sample
//! models) on a stage sized from its bounds: a sun, a floor and a camera framing it
//! (`bevy_caustics::headless::StageLayout`). `--settle-frames` sets `Caustics::settle_frames` (default 16; 0: every
//! frame runs the technique). An option given twice takes its last value; `--aaps`,
//! `--volume`, `--image-space`, `--photon-map` and `--without` add up.
//!
//! The scene path is relative to the working directory (its buffers and images to the glTF's
//! folder). Errors (missing, unreadable or malformed file, no camera, no lights, no adapter,
//! bad option, a size above what this adapter allows: see `bevy_caustics::limits`) print one
//! line naming the file or option and exit with status 2; no output file is written unless
//! the whole render succeeded.

use std::path::PathBuf;
use std::process::ExitCode;

use bevy::render::settings::WgpuFeatures;
use bevy_caustics::CausticsTechnique;
use bevy_caustics::headless::{RenderJob, adapter_limits, check_job, find_adapter, run};
use bevy_caustics::reference::{CausticImage, compare};
use clap::Parser;

/// The technique names `--technique` accepts.
const TECHNIQUES: &str = "reference, aaps, volume, image_space, photon_map";

/// Render a glTF headless with a caustics technique: the caustic irradiance (EXR, lux), the
/// tone-mapped frame (PNG) and statistics (JSON).
///
/// Errors (missing, unreadable or malformed file, no camera or no lights without --stage, no adapter, bad
/// option, a size above what this adapter allows) print one line and exit with status 2; no
/// output file is written unless the whole render succeeded.
#[derive(Parser, Debug)]
#[command(name = "render", args_override_self = true)]
struct Cli {
    /// The glTF (.gltf or .glb) to render, relative to the working directory; its first
    /// camera is used and its KHR_lights_punctual lights cast caustics.
    #[arg(value_name = "SCENE.gltf")]
    scene: PathBuf,
    /// Caustics technique: reference (the CPU ground truth), aaps, volume, image_space or
    /// photon_map.
    #[arg(long, value_name = "NAME", default_value = "reference", value_parser = technique)]
    technique: CausticsTechnique,
    /// Target width, pixels.
    #[arg(long, value_name = "PIXELS", default_value_t = RenderJob::default().width, value_parser = saturating_u32)]
    width: u32,
    /// Target height, pixels.
    #[arg(long, value_name = "PIXELS", default_value_t = RenderJob::default().height, value_parser = saturating_u32)]
    height: u32,
    /// Photons per light (0 traces nothing) [default: the Medium preset, 262144].
    #[arg(long, value_name = "N", value_parser = non_negative)]
    photons: Option<u64>,
    /// Number of frames measured once the caustics are ready (at least 4 run).
    #[arg(long, value_name = "N", default_value_t = RenderJob::default().frames, value_parser = saturating_u32)]
    frames: u32,
    /// Number of unchanged frames after which a still view keeps its caustics and stops
    /// running the technique (`Caustics::settle_frames`; 0: every frame runs it).
    #[arg(long, value_name = "N", default_value_t = RenderJob::default().settle_frames, value_parser = saturating_u32)]
    settle_frames: u32,
    /// Random seed of the photons.
    #[arg(long, value_name = "N", default_value_t = RenderJob::default().seed, value_parser = non_negative)]
    seed: u64,
    /// Camera exposure, EV100 (sunlit scenes of 10 000 lux look right around 13)
    /// [default: Bevy's, 9.7].
    #[arg(long, value_name = "EV100", allow_negative_numbers = true, value_parser = finite)]
    ev100: Option<f32>,
    /// Render a stereo pair with this eye separation, metres (`CausticsStereo`): the outputs
    /// are the right eye's caustics and the left eye's frame [default: one camera].
    #[arg(long, value_name = "METRES", allow_negative_numbers = true, value_parser = metres)]
    stereo: Option<f32>,
    /// Write the caustic irradiance here: float32 RGB EXR, lux, zero where no caustic lands
    /// [default: not written].
    #[arg(long, value_name = "FILE.exr")]
    out_exr: Option<PathBuf>,
    /// Write the tone-mapped frame here: RGBA8 sRGB PNG, pixels [default: not written].
    #[arg(long, value_name = "FILE.png")]
    out_png: Option<PathBuf>,
    /// Write the statistics here (adapter, technique, GPU ms per pass, photons, counters)
    /// [default: printed to stdout].
    #[arg(long, value_name = "FILE.json")]
    json: Option<PathBuf>,
    /// Compare the caustics against this EXR (lux, same size): RMSE, mean FLIP and the
    /// relative energy error go into the JSON [default: no comparison].
    #[arg(long, value_name = "REF.exr")]
    compare: Option<PathBuf>,
    /// AapsSettings fields, as field=value,... (numbers; booleans 0 or 1): atlas_resolution,
    /// target_area, variance_gain, temporal_weight, min_density, max_density,
    /// cull_solid_angle, msaa_threshold, max_anisotropy, splat_scale, max_bounces,
    /// splat_capacity, adaptive, drop_large_splats [default: AapsSettings::default()].
    #[arg(long, value_name = "FIELD=VALUE,...")]
    aaps: Vec<String>,
    /// Fields of the volumes fitted around the casters (CausticsVolume), as field=value,...:
    /// slabs, photons, projector_resolution, gbuffer_resolution, tile_size, density_photons,
    /// splat_overlap, blur_radius, lod_distance, differential, frustum_cull, progressive
    /// [default: CausticsVolume::default()].
    #[arg(long, value_name = "FIELD=VALUE,...")]
    volume: Vec<String>,
    /// ImageSpaceSettings fields, as field=value,...: rsm_resolution, luminance_cutoff,
    /// stride, hi_z, thickness, denoise, alpha_color, alpha_moments, history_cap,
    /// atrous_iterations, sigma_depth, sigma_normal, sigma_luminance, reset_on_change,
    /// internal_events
    /// [default: ImageSpaceSettings::default()].
    #[arg(long = "image-space", value_name = "FIELD=VALUE,...")]
    image_space: Vec<String>,
    /// PhotonMapSettings fields, as field=value,...: radius, max_bounces, max_grid_cells,
    /// progressive, alpha, max_frames, normal_threshold, shared_memory, mirrors, stereo_reuse
    /// [default: PhotonMapSettings::default()].
    #[arg(long = "photon-map", value_name = "FIELD=VALUE,...")]
    photon_map: Vec<String>,
    /// Put the model on a stage: once it has spawned, add a sun (10 000 lux, shadows), a
    /// floor just below its bounds and a camera framing it, all sized from its bounds; the
    /// glTF's cameras are left off, its lights stay. For models that come without a light, a
    /// camera or a floor (most sample models). Exposure EV100 13 unless --ev100 is given.
    #[arg(long)]
    stage: bool,
    /// Start the device with WebGPU's default limits instead of the adapter's.
    #[arg(long)]
    webgpu_limits: bool,
    /// Adapter features to leave off the device, to try the techniques' fallbacks:
    /// float32_blendable, texture_adapter_specific_format_features [default: none].
    #[arg(long, value_name = "FEATURE,...")]
    without: Vec<String>,
}

/// `--technique`: a technique's command-line name.
fn technique(t: &str) -> Result<CausticsTechnique, String> {
    CausticsTechnique::from_name(t)
        .ok_or_else(|| format!("unknown technique '{t}' (available: {TECHNIQUES})"))
}

/// A non-negative integer.
fn non_negative(v: &str) -> Result<u64, String> {
    v.parse::<u64>().map_err(|e| match e.kind() {
        std::num::IntErrorKind::PosOverflow => format!("{v} is too large"),
        _ => format!("expects a non-negative integer, got '{v}'"),
    })
}

/// A non-negative integer, saturating: a value past u32 stays out of range for `check_job`
/// to refuse with the option's limit.
fn saturating_u32(v: &str) -> Result<u32, String> {
    non_negative(v).map(|n| n.min(u32::MAX as u64) as u32)
}

/// A finite number.
fn finite(v: &str) -> Result<f32, String> {
    v.parse::<f32>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| format!("expects a number, got '{v}'"))
}

/// A finite distance >= 0.
fn metres(v: &str) -> Result<f32, String> {
    finite(v)
        .ok()
        .filter(|x| *x >= 0.0)
        .ok_or_else(|| format!("expects metres >= 0, got '{v}'"))
}

/// The outputs, written only once the whole render succeeded.
struct Outputs {
    exr: Option<PathBuf>,
    png: Option<PathBuf>,
    json: Option<PathBuf>,
    compare: Option<PathBuf>,
}

/// Each `field=value` of a settings list (`--aaps a=1,b=2`), with the value as a finite
/// number, given to `set`, which refuses an unknown field with `None`.
fn apply_fields(
    option: &str,
    list: &str,
    mut set: impl FnMut(&str, f32) -> Option<()>,
) -> Result<(), String> {
    for kv in list.split(',') {
        let (k, x) = kv
            .split_once('=')
            .ok_or_else(|| format!("{option} expects field=value, got '{kv}'"))?;
        let v = x
            .parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{option} {k} expects a number, got '{x}'"))?;
        set(k, v).ok_or_else(|| format!("{option}: unknown field '{k}'"))?;
    }
    Ok(())
}

impl Cli {
    fn into_job(self) -> Result<(RenderJob, Outputs), String> {
        let mut job = RenderJob {
            scene: self.scene,
            technique: self.technique,
            width: self.width,
            height: self.height,
            photons: self.photons,
            frames: self.frames,
            settle_frames: self.settle_frames,
            seed: self.seed,
            ev100: self.ev100,
            stereo: self.stereo,
            webgpu_limits: self.webgpu_limits,
            stage: self.stage,
            progress: true,
            ..Default::default()
        };
        for list in &self.aaps {
            let a = &mut job.aaps;
            apply_fields("--aaps", list, |k, v| {
                match k {
                    "atlas_resolution" => a.atlas_resolution = v as u32,
                    "target_area" => a.target_area = v,
                    "variance_gain" => a.variance_gain = v,
                    "temporal_weight" => a.temporal_weight = v,
                    "min_density" => a.min_density = v,
                    "max_density" => a.max_density = v,
                    "cull_solid_angle" => a.cull_solid_angle = v,
                    "msaa_threshold" => a.msaa_threshold = v,
                    "max_anisotropy" => a.max_anisotropy = v,
                    "splat_scale" => a.splat_scale = v,
                    "max_bounces" => a.max_bounces = v as u32,
                    "splat_capacity" => a.splat_capacity = v as u32,
                    "adaptive" => a.adaptive = v != 0.0,
                    "drop_large_splats" => a.drop_large_splats = v != 0.0,
                    _ => return None,
                }
                Some(())
            })?;
        }
        for list in &self.volume {
            let a = &mut job.volume;
            apply_fields("--volume", list, |k, v| {
                match k {
                    "slabs" => a.slabs = v as u32,
                    "photons" => a.photons = v as i32,
                    "projector_resolution" => a.projector_resolution = v as u32,
                    "gbuffer_resolution" => a.gbuffer_resolution = v as u32,
                    "tile_size" => a.tile_size = v as u32,
                    "density_photons" => a.density_photons = v.max(0.0) as u32,
                    "splat_overlap" => a.splat_overlap = v,
                    "blur_radius" => a.blur_radius = v as u32,
                    "lod_distance" => a.lod_distance = v,
                    "differential" => a.differential = v != 0.0,
                    "frustum_cull" => a.frustum_cull = v != 0.0,
                    "progressive" => a.progressive = v.max(0.0) as u32,
                    _ => return None,
                }
                Some(())
            })?;
        }
        for list in &self.image_space {
            let a = &mut job.image_space;
            apply_fields("--image-space", list, |k, v| {
                match k {
                    "rsm_resolution" => a.rsm_resolution = v as u32,
                    "luminance_cutoff" => a.luminance_cutoff = v,
                    "stride" => a.stride = v as u32,
                    "hi_z" => a.hi_z = v != 0.0,
                    "thickness" => a.thickness = v,
                    "denoise" => a.denoise = v != 0.0,
                    "alpha_color" => a.alpha_color = v,
                    "alpha_moments" => a.alpha_moments = v,
                    "history_cap" => a.history_cap = v as u32,
                    "atrous_iterations" => a.atrous_iterations = v as u32,
                    "sigma_depth" => a.sigma_depth = v,
                    "sigma_normal" => a.sigma_normal = v,
                    "sigma_luminance" => a.sigma_luminance = v,
                    "reset_on_change" => a.reset_on_change = v != 0.0,
                    "internal_events" => a.internal_events = v as u32,
                    _ => return None,
                }
                Some(())
            })?;
        }
        for list in &self.photon_map {
            let a = &mut job.photon_map;
            apply_fields("--photon-map", list, |k, v| {
                match k {
                    "radius" => a.radius = v,
                    "max_bounces" => a.max_bounces = v as u32,
                    "max_grid_cells" => a.max_grid_cells = v as u32,
                    "progressive" => a.progressive = v != 0.0,
                    "alpha" => a.alpha = v,
                    "max_frames" => a.max_frames = v as u32,
                    "normal_threshold" => a.normal_threshold = v,
                    "shared_memory" => a.shared_memory = v != 0.0,
                    "mirrors" => a.mirrors = v != 0.0,
                    "stereo_reuse" => a.stereo_reuse = v != 0.0,
                    _ => return None,
                }
                Some(())
            })?;
        }
        for name in self.without.iter().flat_map(|list| list.split(',')) {
            job.disabled_features |= match name {
                "float32_blendable" => WgpuFeatures::FLOAT32_BLENDABLE,
                "texture_adapter_specific_format_features" => {
                    WgpuFeatures::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
                }
                _ => {
                    return Err(format!(
                        "--without: unknown feature '{name}' (available: float32_blendable, texture_adapter_specific_format_features)"
                    ));
                }
            };
        }
        let out = Outputs {
            exr: self.out_exr,
            png: self.out_png,
            json: self.json,
            compare: self.compare,
        };
        Ok((job, out))
    }
}

fn main() -> ExitCode {
    bevy_caustics::headless::quiet_headless_environment();
    // A usage error (unknown option, bad value, no scene) prints clap's message and exits 2.
    let cli = Cli::parse();
    match real_main(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn real_main(cli: Cli) -> Result<(), String> {
    let (job, out) = cli.into_job()?;
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
