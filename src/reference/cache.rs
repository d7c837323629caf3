//! The converged reference images cached in `assets/reference/` (made by `examples/report.rs`,
//! read by the GPU tests and the report): how they are made, written next to each image as a
//! JSON recipe, so a cache made by other settings is recognised as stale.

use super::TraceSettings;

/// Photons per light of a converged reference.
pub const CONVERGED_PHOTONS: u64 = 1 << 23;
/// Photons per light of the `pool` reference: at [`CONVERGED_PHOTONS`] two references of
/// different seeds differ by RMSE 2516 lx (about 1780 lx of noise each), more than AAPS's
/// error on pool, so no AAPS budget could show that error falling. 2^28 takes 265 s on 2 cores.
pub const POOL_PHOTONS: u64 = 1 << 28;

/// Seed of a converged reference (other renders use other seeds, so their noise is independent).
pub const CONVERGED_SEED: u64 = 1;

/// Photons per light of the converged reference of `scene`.
pub fn converged_photons(scene: &str) -> u64 {
    if scene == "pool" {
        POOL_PHOTONS
    } else {
        CONVERGED_PHOTONS
    }
}

/// The recipe of the converged reference of `scene` at `size²`: photons, seed and every
/// tracer setting that changes the result (the path cap and the roulette depth of
/// [`TraceSettings::default`]).
pub fn converged_recipe(scene: &str, size: u32) -> serde_json::Value {
    let t = TraceSettings::default();
    serde_json::json!({
        "scene": scene,
        "width": size,
        "height": size,
        "photons_per_light": converged_photons(scene),
        "seed": CONVERGED_SEED,
        "technique": "reference",
        "max_specular_events": t.max_specular_events,
        "roulette_depth": t.roulette_depth,
    })
}

/// The AAPS quality levels measured against these references by the report and by the
/// budget test (`aaps_error_falls_with_budget`): (name, photon budget per light, target splat
/// area in px).
pub const AAPS_LEVELS: [(&str, u64, f32); 3] = [
    ("low: 2^16/light, A_t 19", 1 << 16, 19.0),
    ("medium: 2^18/light, A_t 4", 1 << 18, 4.0),
    ("high: 2^20/light, A_t 1", 1 << 20, 1.0),
];
