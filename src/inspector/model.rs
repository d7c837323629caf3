//! The panel's data, apart from egui and the ECS so it can be tested without a GPU: pass
//! timings and technique counters from the render diagnostics, and the list of caustics
//! entities.

use std::collections::BTreeMap;

/// One pass's GPU (or CPU) milliseconds, newest last.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PassTiming {
    /// The pass (`caustics/aaps/trace`).
    pub pass: String,
    /// "gpu" or "cpu": the clock.
    pub clock: &'static str,
    /// Rolling history, ms, oldest first.
    pub history: Vec<f64>,
}

impl PassTiming {
    /// The median of the history, ms.
    pub fn median(&self) -> f64 {
        let mut v: Vec<f64> = self
            .history
            .iter()
            .copied()
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            return 0.0;
        }
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    }
}

/// The timings and counters the panel shows, gathered from `render/caustics/**` diagnostics.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Per pass, in the order of their names.
    pub timings: Vec<PassTiming>,
    /// Counter name (`aaps/photons_emitted`) to its last value.
    pub counters: BTreeMap<String, f64>,
}

/// The fields of a pass's diagnostics: `elapsed_gpu`, `elapsed_cpu` and pipeline statistics.
const PASS_FIELDS: [&str; 7] = [
    "elapsed_gpu",
    "elapsed_cpu",
    "vertex_shader_invocations",
    "clipper_invocations",
    "clipper_primitives_out",
    "fragment_shader_invocations",
    "compute_shader_invocations",
];

impl Stats {
    /// From `(path, history)` pairs of the diagnostics store (`render/caustics/aaps/trace/elapsed_gpu`
    /// with its values, oldest first). A pass with a GPU time shows that; one with only a CPU
    /// time (a device without timestamp queries) shows the CPU time. Anything under
    /// `render/caustics/` that is not a pass field is a counter (its last value).
    pub fn from_diagnostics<'a>(entries: impl IntoIterator<Item = (&'a str, Vec<f64>)>) -> Self {
        let mut gpu: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        let mut cpu: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        let mut counters = BTreeMap::new();
        for (path, values) in entries {
            let Some(rest) = path.strip_prefix("render/caustics/") else {
                continue;
            };
            let (head, field) = rest.rsplit_once('/').unwrap_or(("", rest));
            let pass = format!("caustics/{head}");
            match field {
                "elapsed_gpu" => {
                    gpu.insert(pass, values);
                }
                "elapsed_cpu" => {
                    cpu.insert(pass, values);
                }
                f if PASS_FIELDS.contains(&f) => {}
                _ => {
                    if let Some(v) = values.last() {
                        counters.insert(rest.to_string(), *v);
                    }
                }
            }
        }
        let mut timings: Vec<PassTiming> = gpu
            .into_iter()
            .map(|(pass, history)| PassTiming {
                pass,
                clock: "gpu",
                history,
            })
            .collect();
        for (pass, history) in cpu {
            if !timings.iter().any(|t| t.pass == pass) {
                timings.push(PassTiming {
                    pass,
                    clock: "cpu",
                    history,
                });
            }
        }
        timings.sort_by(|a, b| a.pass.cmp(&b.pass));
        Self { timings, counters }
    }

    /// Sum of the passes' medians, ms.
    pub fn total_ms(&self) -> f64 {
        self.timings.iter().map(PassTiming::median).sum()
    }
}

/// What an entity is to the caustics plugin, for the panel's list.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum EntityKind {
    /// A camera with `Caustics`.
    Camera,
    /// A light with `CausticLight`.
    Light,
    /// A `CausticsVolume`.
    Volume,
    /// A mesh that casts caustics (glass, water, mirror), by its `CausticMaterial` or derived.
    Caster,
}

impl EntityKind {
    /// The list's heading.
    pub fn heading(self) -> &'static str {
        match self {
            Self::Camera => "Cameras",
            Self::Light => "Lights",
            Self::Volume => "Volumes",
            Self::Caster => "Casters",
        }
    }
}

/// A false-colour ramp for irradiance: `t` in [0, 1] (log scale, see [`log_scale`]) to linear
/// RGB, a five-stop approximation of the turbo ramp (dark blue, cyan, green, yellow, red). The
/// WGSL twin is `ramp` in src/inspector/images.wgsl.
pub fn ramp(t: f32) -> [f32; 3] {
    const STOPS: [[f32; 3]; 5] = [
        [0.05, 0.03, 0.35],
        [0.0, 0.55, 0.9],
        [0.1, 0.85, 0.2],
        [0.95, 0.85, 0.05],
        [0.8, 0.05, 0.02],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
    ]
}

/// Position of `value` on the legend's log scale from `lo` to `hi` (both > 0): 0 at or below
/// `lo` (and for zero, negative or non-finite values), 1 at or above `hi`.
pub fn log_scale(value: f32, lo: f32, hi: f32) -> f32 {
    let inside = value > lo && lo.is_finite() && hi > lo;
    if !inside {
        return 0.0;
    }
    let t = (value / lo).ln() / (hi / lo).ln();
    if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        1.0
    }
}
