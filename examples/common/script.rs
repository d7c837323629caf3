//! A scripted window run, for the tests that run an example as a game runs: in a real window
//! (Xvfb on CI), for hundreds of frames, still, resized, with the camera and the scene changed.
//!
//! `CAUSTICS_EXAMPLE_SCRIPT` holds space-separated steps `ACTION@FRAME[=ARG]`; frames count
//! from the first frame whose caustics passes ran (frame 1): a window compiles the pipelines
//! asynchronously, and on a CPU driver that takes a few seconds of frames without caustics.
//! The actions:
//!
//! - `shot`: a screenshot of the primary window (Bevy's `Screenshot`) written to
//!   `<CAUSTICS_EXAMPLE_OUT>/<example>-<frame>.png`, and a readback of the caustics buffer of
//!   the same frame; a line `shot frame=F sum=S max=M finite=B` (lux) is printed for each,
//!   and `passes before=F count=N`: the caustics passes other than the composite dispatched
//!   since the previous shot (0 while a settled view keeps its buffer).
//! - `hide` / `show`: the caustics composite off (`CausticsDebugView::Hidden`) / on again. A
//!   settled view keeps its buffer (hiding is not a change of its inputs), so the frame after
//!   `hide` shows the same view without caustics, to compare.
//! - `resize=WxH`: the window's resolution, in logical pixels.
//! - `pan=M`: every caustics camera moved `M` metres to its right.
//! - `light=K`: every caustic light's `intensity_scale` multiplied by `K` (a scene change).
//! - `exit`: the app exits (success), once every shot is written.
//!
//! `CAUSTICS_EXAMPLE_TECHNIQUE` (`aaps`, `volume`, `image_space`, `photon_map`) sets every
//! caustics camera's technique; for `volume` a `CausticsVolume` is fitted around the
//! transmissive and mirror meshes when the scene has none. `CAUSTICS_EXAMPLE_PHOTONS` sets
//! every caustics camera's photon budget per light (`CausticsQuality::Custom`).

use bevy::camera::primitives::Aabb;
use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy_caustics::render::readback::CausticsReadback;
use bevy_caustics::{
    CausticLight, Caustics, CausticsDebugView, CausticsDispatchLog, CausticsQuality,
    CausticsTechnique, CausticsVolume,
};

/// One step of the script.
#[derive(Clone, Debug, PartialEq)]
enum Action {
    Shot,
    Hide,
    Show,
    Resize(u32, u32),
    Pan(f32),
    Light(f32),
    Exit,
}

fn parse_step(s: &str) -> Option<(u32, Action)> {
    let (action, rest) = s.split_once('@')?;
    let (frame, arg) = match rest.split_once('=') {
        Some((f, a)) => (f, Some(a)),
        None => (rest, None),
    };
    let frame = frame.parse().ok()?;
    let action = match (action, arg) {
        ("shot", None) => Action::Shot,
        ("hide", None) => Action::Hide,
        ("show", None) => Action::Show,
        ("exit", None) => Action::Exit,
        ("resize", Some(a)) => {
            let (w, h) = a.split_once('x')?;
            Action::Resize(w.parse().ok()?, h.parse().ok()?)
        }
        ("pan", Some(a)) => Action::Pan(a.parse().ok()?),
        ("light", Some(a)) => Action::Light(a.parse().ok()?),
        _ => return None,
    };
    Some((frame, action))
}

/// The script's state.
#[derive(Resource)]
struct Script {
    steps: Vec<(u32, Action)>,
    frame: u32,
    dir: std::path::PathBuf,
    name: String,
    /// Shot frames whose readback has not been polled yet, oldest first.
    readbacks: std::collections::VecDeque<u32>,
    /// Caustics passes other than the composite dispatched since the last shot.
    passes: usize,
    /// Screenshots asked for and not written yet.
    writing: u32,
    exiting: bool,
    technique: Option<CausticsTechnique>,
    photons: Option<u64>,
}

/// Adds the scripted run when `CAUSTICS_EXAMPLE_SCRIPT` is set (window mode).
pub struct WindowScript {
    pub name: String,
}

impl Plugin for WindowScript {
    fn build(&self, app: &mut App) {
        let Ok(text) = std::env::var("CAUSTICS_EXAMPLE_SCRIPT") else {
            return;
        };
        let mut steps = Vec::new();
        for s in text.split_whitespace() {
            match parse_step(s) {
                Some(step) => steps.push(step),
                None => panic!("CAUSTICS_EXAMPLE_SCRIPT: cannot read step {s:?}"),
            }
        }
        let technique =
            std::env::var("CAUSTICS_EXAMPLE_TECHNIQUE")
                .ok()
                .map(|t| match t.as_str() {
                    "aaps" => CausticsTechnique::Aaps,
                    "volume" => CausticsTechnique::Volume,
                    "image_space" => CausticsTechnique::ImageSpace,
                    "photon_map" => CausticsTechnique::PhotonMap,
                    other => panic!("CAUSTICS_EXAMPLE_TECHNIQUE: unknown technique {other:?}"),
                });
        let dir = std::env::var_os("CAUSTICS_EXAMPLE_OUT")
            .map(std::path::PathBuf::from)
            .unwrap_or_default();
        app.insert_resource(Script {
            steps,
            frame: 0,
            passes: 0,
            dir,
            name: self.name.clone(),
            readbacks: Default::default(),
            writing: 0,
            exiting: false,
            technique,
            photons: std::env::var("CAUSTICS_EXAMPLE_PHOTONS")
                .ok()
                .map(|p| p.parse().expect("CAUSTICS_EXAMPLE_PHOTONS: a number")),
        })
        .add_systems(Update, set_technique)
        .add_systems(Last, run_script);
    }
}

/// The technique of `CAUSTICS_EXAMPLE_TECHNIQUE` on every caustics camera; a volume around
/// the casters for `volume` (once their bounds are known).
fn set_technique(
    mut commands: Commands,
    script: Res<Script>,
    mut cameras: Query<&mut Caustics>,
    volumes: Query<(), With<CausticsVolume>>,
    lights: Query<&GlobalTransform, With<CausticLight>>,
    casters: Query<(&Aabb, &GlobalTransform, &MeshMaterial3d<StandardMaterial>)>,
    materials: Res<Assets<StandardMaterial>>,
) {
    for mut c in &mut cameras {
        if let Some(photons) = script.photons
            && c.quality != (CausticsQuality::Custom { photons })
        {
            c.quality = CausticsQuality::Custom { photons };
        }
        if let Some(technique) = script.technique
            && c.technique != technique
        {
            c.technique = technique;
        }
    }
    let Some(technique) = script.technique else {
        return;
    };
    if technique != CausticsTechnique::Volume || !volumes.is_empty() {
        return;
    }
    let Some(light) = lights.iter().next() else {
        return;
    };
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for (aabb, transform, material) in &casters {
        let Some(m) = materials.get(&material.0) else {
            continue;
        };
        let caster =
            m.specular_transmission > 0.0 || (m.metallic >= 0.9 && m.perceptual_roughness <= 0.2);
        if !caster {
            continue;
        }
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            let local = Vec3::from(aabb.center) + Vec3::from(aabb.half_extents) * corner;
            let p = transform.transform_point(local);
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    if lo.x > hi.x {
        return;
    }
    let (volume, transform) = CausticsVolume::fit((lo, hi), light.forward().into(), 0.1);
    commands.spawn((volume, transform, Name::new("scripted caustics volume")));
}

#[allow(clippy::too_many_arguments)]
fn run_script(
    mut commands: Commands,
    mut script: ResMut<Script>,
    mut cameras: Query<(&mut Caustics, &mut Transform), Without<CausticLight>>,
    mut lights: Query<&mut CausticLight>,
    mut windows: Query<&mut Window>,
    readback: Res<CausticsReadback>,
    log: Res<CausticsDispatchLog>,
    mut exit: MessageWriter<AppExit>,
) {
    while let Some(frame) = script.readbacks.front().copied() {
        let Some(snap) = readback.poll() else { break };
        script.readbacks.pop_front();
        let max = snap
            .image
            .data
            .iter()
            .map(|v| v.max_element())
            .fold(0.0f32, f32::max);
        println!(
            "shot frame={frame} sum={:.6e} max={max:.1} finite={}",
            snap.image.sum().element_sum(),
            snap.image.all_finite()
        );
    }
    if script.exiting {
        if script.readbacks.is_empty() && script.writing == 0 {
            exit.write(AppExit::Success);
        }
        return;
    }
    script.passes += log
        .take()
        .iter()
        .filter(|p| **p != bevy_caustics::render::composite::COMPOSITE_PASS)
        .count();
    if cameras.is_empty() || script.passes == 0 && script.frame == 0 {
        return;
    }
    script.frame += 1;
    let frame = script.frame;
    let due: Vec<Action> = script
        .steps
        .iter()
        .filter(|(f, _)| *f == frame)
        .map(|(_, a)| a.clone())
        .collect();
    for action in due {
        match action {
            Action::Shot => {
                println!("passes before={frame} count={}", script.passes);
                script.passes = 0;
                let path = script.dir.join(format!("{}-{frame}.png", script.name));
                script.writing += 1;
                script.readbacks.push_back(frame);
                readback.request();
                commands.spawn(Screenshot::primary_window()).observe(
                    move |ev: On<ScreenshotCaptured>, mut script: ResMut<Script>| {
                        if let Err(e) = super::save_rgb_png(&ev.image, &path) {
                            error!("cannot write {}: {e}", path.display());
                        }
                        script.writing = script.writing.saturating_sub(1);
                    },
                );
            }
            Action::Hide | Action::Show => {
                let view = if action == Action::Hide {
                    CausticsDebugView::Hidden
                } else {
                    CausticsDebugView::Off
                };
                for (mut c, _) in &mut cameras {
                    c.debug_view = view;
                }
            }
            Action::Resize(w, h) => {
                for mut window in &mut windows {
                    window.resolution.set(w as f32, h as f32);
                }
            }
            Action::Pan(m) => {
                for (_, mut t) in &mut cameras {
                    let right = t.right();
                    t.translation += right * m;
                }
            }
            Action::Light(k) => {
                for mut l in &mut lights {
                    l.intensity_scale *= k;
                }
            }
            Action::Exit => script.exiting = true,
        }
    }
}
