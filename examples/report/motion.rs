//! The report's moving scene (issue 28, item 5), written to `MOTION.md`: per technique, on
//! `glass_sphere` at 2^16 photons per light and defaults, read back at every frame
//! (`bevy_caustics::headless::motion`):
//! - still, and with unrelated motion (a cube circling 2.5 m from the caustic; the sun turning
//!   1e-5 rad back and forth): the RMSE against the converged reference and the flicker;
//! - a moving caster (the ball sliding 1 cm a frame): the RMSE against the reference of each
//!   frame's own state, and against the previous frame's state (lower there would mean the
//!   caustics trail the scene).
//!
//! The per-frame references are the converged recipe (2^23 photons per light, seed 1) with the
//! ball moved, so the still one is the cached reference itself.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicU32, Ordering};

use bevy::prelude::World;
use bevy_caustics::CausticsTechnique;
use bevy_caustics::headless::motion::{
    MEASURED, SLIDE_STEP, circle_cube, jitter_sun, mean_flicker, mean_rmse, move_ball, slide_ball,
    slide_steps,
};
use bevy_caustics::headless::{RenderJob, run};
use bevy_caustics::reference::{CausticImage, compare};

/// The scene of the moving runs.
pub const SCENE: &str = "glass_sphere";
/// Photons per light of the techniques' runs.
const PHOTONS: u64 = 1 << 16;

/// The states searched for the one a frame shows best: up to this many frames behind its own.
const LAG_SEARCH: u32 = 3;

/// Steps of [`SLIDE_STEP`] the reference being rendered has its ball moved by.
static REFERENCE_STEPS: AtomicU32 = AtomicU32::new(0);

/// Hook of a per-frame reference: the ball moved by [`REFERENCE_STEPS`].
fn offset_ball(world: &mut World) {
    let steps = REFERENCE_STEPS.load(Ordering::Relaxed);
    move_ball(world, steps as f32 * SLIDE_STEP);
}

/// One technique's row.
pub struct MotionRow {
    technique: CausticsTechnique,
    /// (RMSE lx, flicker) still, with the cube circling, with the sun jittering.
    still: (f64, f64),
    cube: (f64, f64),
    sun: (f64, f64),
    /// The sliding ball: RMSE against each frame's own state, and against the previous one's.
    slide_own: f64,
    slide_previous: f64,
    /// The mean over the measured frames of how many frames behind its own state lies the
    /// state whose reference a frame matches best (RMSE): 0 when the caustics keep up, -1 a
    /// frame ahead.
    slide_lag: f64,
}

/// The reference of the state with the ball moved by `steps` slide steps. With the variable
/// `MOTION_REFERENCE_CACHE` set to a folder, read from it when there and written to it.
fn reference_at(scene: &Path, size: u32, steps: u32) -> Result<CausticImage, String> {
    let cached = std::env::var_os("MOTION_REFERENCE_CACHE")
        .map(|d| Path::new(&d).join(format!("{SCENE}_{size}_slide_{steps}.exr")));
    if let Some(img) = cached.as_ref().and_then(|p| CausticImage::read_exr(p).ok()) {
        return Ok(img);
    }
    REFERENCE_STEPS.store(steps, Ordering::Relaxed);
    let report = run(RenderJob {
        hook: Some(offset_ball),
        ..super::converged_job(scene, SCENE, size)
    })?;
    let img = report
        .caustics
        .unwrap_or_else(|| CausticImage::new(size, size));
    if let Some(p) = cached {
        let _ = std::fs::create_dir_all(p.parent().unwrap_or(Path::new(".")));
        img.write_exr(&p)?;
    }
    Ok(img)
}

/// The references of every state the sliding runs show at [`MEASURED`] and the frame before,
/// by slide step.
pub fn slide_references(scene: &Path, size: u32) -> Result<Vec<CausticImage>, String> {
    let first = slide_steps(MEASURED.start).saturating_sub(LAG_SEARCH);
    let last = slide_steps(MEASURED.end - 1) + 1;
    (0..=last)
        .map(|steps| {
            if steps < first {
                // Never compared: an empty image keeps the indices simple.
                Ok(CausticImage::new(size, size))
            } else {
                eprint!("\r  reference with the ball moved {steps} cm   ");
                reference_at(scene, size, steps)
            }
        })
        .collect()
}

/// The caustics of every frame of one run.
fn frames(
    scene: &Path,
    size: u32,
    technique: CausticsTechnique,
    per_frame: Option<fn(&mut World, u32)>,
) -> Result<Vec<CausticImage>, String> {
    let report = run(RenderJob {
        scene: scene.to_path_buf(),
        technique,
        width: size,
        height: size,
        photons: Some(PHOTONS),
        frames: MEASURED.end as u32,
        every_frame: true,
        per_frame,
        ..Default::default()
    })?;
    let frames = report.frame_caustics;
    if frames.len() < MEASURED.end {
        return Err(format!(
            "{}: {} frames read back",
            technique.name(),
            frames.len()
        ));
    }
    Ok(frames)
}

/// One technique's runs, measured.
pub fn measure(
    scene: &Path,
    size: u32,
    technique: CausticsTechnique,
    converged: &CausticImage,
    slide: &[CausticImage],
) -> Result<MotionRow, String> {
    let unrelated = |per_frame| -> Result<(f64, f64), String> {
        let f = frames(scene, size, technique, per_frame)?;
        Ok((mean_rmse(&f, |_| converged), mean_flicker(&f)))
    };
    let still = unrelated(None)?;
    let cube = unrelated(Some(circle_cube))?;
    let sun = unrelated(Some(jitter_sun))?;
    let f = frames(scene, size, technique, Some(slide_ball))?;
    let own = |i: usize| &slide[slide_steps(i) as usize];
    let previous = |i: usize| &slide[slide_steps(i).saturating_sub(1) as usize];
    Ok(MotionRow {
        technique,
        still,
        cube,
        sun,
        slide_own: mean_rmse(&f, own),
        slide_previous: mean_rmse(&f, previous),
        slide_lag: mean_lag(&f, slide),
    })
}

/// [`MotionRow::slide_lag`] of the sliding run `f`.
fn mean_lag(f: &[CausticImage], slide: &[CausticImage]) -> f64 {
    let lags = MEASURED.map(|i| {
        let own = slide_steps(i);
        let best = (own.saturating_sub(LAG_SEARCH)..=own + 1)
            .filter_map(|s| compare(&f[i], &slide[s as usize], None).map(|m| (s, m.rmse)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(own, |(s, _)| s);
        own as f64 - best as f64
    });
    lags.sum::<f64>() / MEASURED.len() as f64
}

/// `MOTION.md`.
pub fn markdown(adapter: &str, size: u32, minutes: f64, rows: &[MotionRow]) -> String {
    let mut md = String::from("# bevy_caustics: caustics in a scene that moves\n\n");
    let _ = writeln!(
        md,
        "Adapter: **{adapter}**. `{SCENE}` at {size}x{size}, {PHOTONS} photons per light, defaults, the caustics buffer read back at every frame. This run took {minutes:.1} minutes. Regenerate: `cargo run --release --example report -- --part motion`.\n"
    );
    let _ = writeln!(
        md,
        "RMSE: luminance in lux, the mean over frames {} to {} (past the default `settle_frames`, 16). Flicker: the mean frame-to-frame relative change `Σ|ΔL| / ΣL` over the same frames. Unrelated motion: a 0.3 m diffuse cube circling 2.5 m from the caustic, 0.05 rad a frame; the sun turning 1e-5 rad back and forth. Moving caster: the ball sliding {} m a frame, against the reference of each frame's own state and of the previous frame's (the converged recipe, 2^23 photons per light, with the ball moved); *frames behind*: the mean of how far behind its own state lies the state (of {} behind to one ahead) whose reference each frame matches best. Issue 28 asks: unrelated motion within 1.1x the still RMSE and flicker at most 0.01; the moving caster within 1.3x the still RMSE and no lower against the previous state than against its own.\n",
        MEASURED.start + 1,
        MEASURED.end,
        SLIDE_STEP,
        LAG_SEARCH
    );
    let _ = writeln!(
        md,
        "| technique | RMSE still | circling cube | sun jitter | flicker still | flicker, cube | flicker, sun | sliding ball, own state | previous state | frames behind |"
    );
    let _ = writeln!(
        md,
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for r in rows {
        let x = |v: f64| format!("{v:.1} ({:.2}x)", v / r.still.0);
        let _ = writeln!(
            md,
            "| {} | {:.1} | {} | {} | {:.4} | {:.4} | {:.4} | {} | {:.1} | {:.2} |",
            r.technique.name(),
            r.still.0,
            x(r.cube.0),
            x(r.sun.0),
            r.still.1,
            r.cube.1,
            r.sun.1,
            x(r.slide_own),
            r.slide_previous,
            r.slide_lag
        );
    }
    md
}
