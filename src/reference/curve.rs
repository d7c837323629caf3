//! Reading an error-against-run-time curve, for the report's summary table: the run time a
//! technique needs to reach an error, and the error it reaches within a run-time budget.
//!
//! A curve is a technique's measured points `(ms, error)` on one scene, one per quality level,
//! in any order. Between neighbouring points in order of run time, both readings interpolate
//! linearly in `ln ms` and `ln error`, the axes of the report's plots. Points with a run time
//! or an error that is not finite and positive are left out (a scene without caustics has
//! error 0 everywhere: nothing to read).

/// The run time a curve needs to reach an error ([`ms_to_reach`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// The cheapest point is already at or below the error: at most this many ms.
    AtMost(f64),
    /// Reached between two measured points, interpolated.
    At(f64),
    /// No point is at or below the error.
    NotReached,
}

fn usable(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(ms, e)| ms.is_finite() && *ms > 0.0 && e.is_finite() && *e > 0.0)
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p
}

/// `ln`-linear interpolation between `a` and `b` at parameter `t` in [0, 1].
fn lerp_ln(a: f64, b: f64, t: f64) -> f64 {
    (a.ln() + (b.ln() - a.ln()) * t).exp()
}

/// The least run time at which the curve is at or below `target`: the first crossing in order
/// of run time, interpolated on the segment that crosses.
pub fn ms_to_reach(points: &[(f64, f64)], target: f64) -> Reach {
    let p = usable(points);
    if !(target.is_finite() && target > 0.0) {
        return Reach::NotReached;
    }
    let Some(first) = p.first() else {
        return Reach::NotReached;
    };
    if first.1 <= target {
        return Reach::AtMost(first.0);
    }
    for w in p.windows(2) {
        let ((m0, e0), (m1, e1)) = (w[0], w[1]);
        if e1 <= target {
            // e0 > target >= e1, so e0 > e1 and the parameter is in (0, 1].
            let t = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            return Reach::At(lerp_ln(m0, m1, t.clamp(0.0, 1.0)));
        }
    }
    Reach::NotReached
}

/// The least error the curve reaches within `budget` ms: the best measured point within it,
/// or the curve interpolated at the budget where that is lower. `None` when even the
/// cheapest point is over the budget.
pub fn error_within(points: &[(f64, f64)], budget: f64) -> Option<f64> {
    let p = usable(points);
    let mut best = p
        .iter()
        .filter(|(ms, _)| *ms <= budget)
        .map(|(_, e)| *e)
        .reduce(f64::min)?;
    if let Some(w) = p.windows(2).find(|w| w[0].0 <= budget && budget < w[1].0) {
        let ((m0, e0), (m1, e1)) = (w[0], w[1]);
        let t = (budget.ln() - m0.ln()) / (m1.ln() - m0.ln());
        best = best.min(lerp_ln(e0, e1, t.clamp(0.0, 1.0)));
    }
    Some(best)
}
