//! What a technique could not follow, named once in a `warn!` (issue 32): each technique
//! registers the counters that count lost light (paths at the bounce cap or the event budget,
//! photons image space cannot follow out of a caster), and the first frame one of them is
//! above zero (or above its share of another counter) the plugin says so, once per counter,
//! with what to change. The counters reach the main
//! world through Bevy's render diagnostics, so the warnings need `RenderDiagnosticsPlugin`
//! (the inspector and the headless renderer add it); without it nothing is read back.

use bevy::diagnostic::{DiagnosticPath, DiagnosticsStore};
use bevy::platform::collections::HashSet;
use bevy::prelude::*;

/// One counter of lost light: its diagnostic (`render/caustics/<technique>/<name>`) and what
/// the warning says after the count.
#[derive(Clone, Debug)]
pub struct LossCounter {
    /// The diagnostic's path.
    pub path: &'static str,
    /// What was lost and what to change, after the count ("paths stopped by ...").
    pub what: &'static str,
    /// Warn only when the count exceeds this share of another counter's value in the same
    /// frame (its diagnostic path, the share); `None`: any count above zero.
    pub share_of: Option<(&'static str, f64)>,
}

/// The registered loss counters, and the warnings logged so far (in order, the log's text).
#[derive(Resource, Default, Debug)]
pub struct CausticsLossCounters {
    counters: Vec<LossCounter>,
    /// The loss warnings logged, at most one per counter.
    pub messages: Vec<String>,
}

/// Register a technique's loss counters (called from its `build`).
pub(crate) fn register(app: &mut App, counters: &[LossCounter]) {
    if !app.world().contains_resource::<CausticsLossCounters>() {
        app.init_resource::<CausticsLossCounters>()
            .add_systems(Last, warn_losses);
    }
    app.world_mut()
        .resource_mut::<CausticsLossCounters>()
        .counters
        .extend_from_slice(counters);
}

fn warn_losses(
    store: Option<Res<DiagnosticsStore>>,
    mut losses: ResMut<CausticsLossCounters>,
    mut warned: Local<HashSet<&'static str>>,
) {
    let Some(store) = store else {
        return;
    };
    let losses = &mut *losses;
    for c in &losses.counters {
        if warned.contains(c.path) {
            continue;
        }
        let value_of = |path: &'static str| {
            store
                .get(&DiagnosticPath::new(path))
                .and_then(|d| d.value())
                .unwrap_or(0.0)
        };
        let value = value_of(c.path);
        let bound = c.share_of.map_or(0.0, |(of, share)| share * value_of(of));
        if value > bound.max(0.0) {
            let msg = match c.share_of {
                None => format!("bevy_caustics: {value:.0} {}", c.what),
                Some((of, _)) => format!(
                    "bevy_caustics: {value:.0} of {:.0} {}",
                    value_of(of),
                    c.what
                ),
            };
            warn!("{msg}");
            losses.messages.push(msg);
            warned.insert(c.path);
        }
    }
}
