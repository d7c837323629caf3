//! Paying only for what the scene needs (issue 16): specialised trace pipelines give the same
//! caustics as the tracer with everything (and their time is printed), and GPU memory follows
//! use: a technique's buffers and textures exist only while a camera uses it, and switching a
//! camera's technique back and forth leaves the count (`render::memory`, the JSON's
//! `gpu_bytes`) where it started.

use bevy_caustics::CausticsTechnique;
use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::reference::compare;

use super::{GPU, require_gpu, scene};

/// Frames at the starting technique before and after the switching.
pub(crate) const SETTLE: u32 = 4;
/// Switches: one every frame.
pub(crate) const SWITCHES: u32 = 100;

/// `mirror_wall` (a mirror and a sun: no dielectric, no point light) with AAPS, the photon
/// map and image space, the trace pipeline specialised (default) and not
/// (`TraceSpecialization(false)`): the
/// same caustics (energy within 1e-4, FLIP below 1e-3; AAPS's splats are blended in any
/// order, so not bit for bit), and the trace pass's GPU time of each, printed for the note.
#[test]
fn specialised_tracer_matches_the_general_one() {
    use bevy::prelude::World;
    use bevy_caustics::render::trace::TraceSpecialization;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    fn general(world: &mut World) {
        world.insert_resource(TraceSpecialization(false));
    }
    for (technique, pass) in [
        (CausticsTechnique::Aaps, "caustics/aaps/trace"),
        (CausticsTechnique::PhotonMap, "caustics/photon_map/trace"),
        (CausticsTechnique::ImageSpace, "caustics/image_space/trace"),
    ] {
        let render = |hook: Option<fn(&mut World)>| -> RenderReport {
            run(RenderJob {
                scene: scene("mirror_wall"),
                technique,
                width: 64,
                height: 64,
                photons: Some(1 << 16),
                frames: 8,
                hook,
                ..Default::default()
            })
            .expect("render")
        };
        let special = render(None);
        let all = render(Some(general));
        let (a, b) = (
            special.caustics.as_ref().expect("caustics"),
            all.caustics.as_ref().expect("caustics"),
        );
        let m = compare(a, b, None).expect("same size");
        let (ms_special, ms_all) = (special.pass_ms[pass], all.pass_ms[pass]);
        println!(
            "{}: trace {ms_special:.2} ms specialised, {ms_all:.2} ms with everything ({:.2}x); energy {:+.2e}, FLIP {:.2e}",
            technique.name(),
            ms_all / ms_special,
            m.energy_error,
            m.flip
        );
        assert!(b.data.iter().any(|v| v.y > 0.0), "no caustic");
        assert!(m.energy_error.abs() < 1e-4, "{m:?}");
        assert!(m.flip < 1e-3, "{m:?}");
    }
}
