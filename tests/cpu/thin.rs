//! Thin-walled glass in the reference tracer (issue 32 item 2): glTF transmission without a
//! volume (thickness 0) has air on both sides, so it reflects the air-to-glass Fresnel `R` from
//! either side, passes `1 - R` straight through, and never totally reflects. A pane seen from
//! the front and from the back, at normal-ish incidence and beyond the critical angle of the
//! thick case (41.8 degrees at IOR 1.5); a closed thin shell lets through `(1 - R)^2` of the
//! light that crosses it with no photon trapped up to the bounce cap.

use bevy_caustics::optics::{dielectric_eta, fresnel_dielectric};
use bevy_caustics::reference::{TraceOutput, TraceSettings, plane_region_mean, trace};
use bevy_caustics::scenes::{self, closed};

const PHOTONS: u64 = 1 << 20;

fn run(desc: &scenes::SceneDesc, seed: u64) -> (TraceOutput, bevy_caustics::scene::TraceCamera) {
    let (tlas, lights, cam) = desc.to_trace(128, 128);
    let out = trace(
        &tlas,
        &lights,
        &cam,
        &TraceSettings {
            photons_per_light: PHOTONS,
            seed,
            ..Default::default()
        },
        None,
    );
    assert!(out.image.all_finite(), "{}: non-finite pixel", desc.name);
    assert_eq!(out.stats.nan_guards, 0, "{}", desc.name);
    (out, cam)
}

/// A thin pane passes `1 - R(θ)` of the light striking it, from the front and from the back:
/// the straight-through power against the power on the pane within 0.5 % (binomial noise at
/// 0.6 M photons on the pane: 0.03 % at 30 degrees, 0.1 % at 60), and the floor's irradiance
/// under it, `E cos θ (1 - R)`, within 2 % (as the thick slab's closed form). At 60 degrees the
/// back face used to totally reflect everything (eta = ior).
#[test]
fn reference_thin_pane_both_sides_closed_form() {
    for deg in [30.0f32, 60.0] {
        let a = deg.to_radians();
        let r = fresnel_dielectric(a.cos(), 1.0 / closed::THIN_IOR);
        for from_back in [false, true] {
            let desc = closed::thin_pane(a, from_back);
            let (out, cam) = run(&desc, 21 + from_back as u64);
            let s = &out.stats;
            let through = s.flux_per_path.get(&(0, 1)).map_or(0.0, |v| v.y);
            let ratio = through / s.flux_on_casters.y;
            let expect = 1.0 - r as f64;
            let flux_err = ratio / expect - 1.0;
            // The floor under the middle of the pane's shadow (1 x 1 m, as the horizontal
            // pane, centred at x = tan θ).
            let c = a.tan();
            let region = move |p: glam::Vec3| (p.x - c).abs() < 0.3 && p.z.abs() < 0.3;
            let (mean, px) = plane_region_mean(&out.image, &cam, glam::Vec3::Y, 0.0, region);
            let e_expect = scenes::SUN_LUX * a.cos() * (1.0 - r);
            let e_err = mean / e_expect - 1.0;
            println!(
                "{} at {deg} deg: through {ratio:.5} of the light on the pane vs 1 - R = {expect:.5} ({:+.3} %); floor {mean:.1} lx over {px} px vs {e_expect:.1} lx ({:+.3} %); tir {}, at the cap {}",
                desc.name,
                flux_err * 100.0,
                e_err * 100.0,
                s.tir_events,
                s.photons_max_depth
            );
            assert!(s.photons_emitted > 0 && s.flux_on_casters.y > 0.0);
            assert_eq!(s.tir_events, 0, "{} at {deg} deg", desc.name);
            assert_eq!(s.photons_max_depth, 0, "{} at {deg} deg", desc.name);
            assert!(
                flux_err.abs() < 0.005,
                "{} at {deg} deg: {:+.3} %",
                desc.name,
                flux_err * 100.0
            );
            assert!(px > 200, "{}: {px} px", desc.name);
            assert!(
                e_err.abs() < 0.02,
                "{} at {deg} deg: floor {:+.3} %",
                desc.name,
                e_err * 100.0
            );
            // Everything that struck the pane went through or was reflected away: nothing is
            // kept, nothing trapped.
            let balance = (s.flux_deposited.y + s.flux_escaped.y) / s.flux_on_casters.y - 1.0;
            assert!(balance.abs() < 1e-9, "{}: balance {balance}", desc.name);
        }
    }
}

/// A closed thin shell (the glass ball at thickness 0) lets through `(1 - R)^2` of the light
/// that crosses it, `R` at the incidence of each chord (the same at both walls), integrated
/// over the ball's polygonal silhouette: within 2 % (as the thick ball's closed form). No
/// photon reaches the bounce cap, none is totally reflected, and every watt that struck the
/// shell leaves it.
#[test]
fn reference_thin_shell_closed_form() {
    let desc = closed::thin_shell();
    let (out, _) = run(&desc, 23);
    let s = &out.stats;
    let r = scenes::SPHERE_RADIUS as f64;
    let steps = 20_000;
    let eta = dielectric_eta(closed::THIN_IOR, true, true);
    let mut expect = 0.0f64;
    for i in 0..steps {
        let b = (i as f64 + 0.5) / steps as f64 * r;
        let cos_i = (1.0 - (b / r).powi(2)).sqrt() as f32;
        let t = 1.0 - fresnel_dielectric(cos_i, eta) as f64;
        expect += t * t * 2.0 * std::f64::consts::PI * b * (r / steps as f64);
    }
    // The mesh's silhouette is a regular polygon, not a circle.
    let n = scenes::SPHERE_SEGMENTS as f64;
    expect *= n / (2.0 * std::f64::consts::PI) * (2.0 * std::f64::consts::PI / n).sin();
    expect *= scenes::SUN_LUX as f64;
    let tt = s.flux_per_path.get(&(0, 2)).map_or(0.0, |v| v.y);
    let err = tt / expect - 1.0;
    let longest = s
        .flux_per_path
        .keys()
        .map(|(a, b)| a + b)
        .max()
        .unwrap_or(0);
    println!(
        "thin_shell: straight-through power {tt:.1} lm vs closed form {expect:.1} lm ({:+.3} %); on the shell {:.1} lm, out {:.1} lm; tir {}, at the cap {}, longest path {longest} events",
        err * 100.0,
        s.flux_on_casters.y,
        s.flux_deposited.y + s.flux_escaped.y,
        s.tir_events,
        s.photons_max_depth
    );
    assert!(err.abs() < 0.02, "{:+.3} %", err * 100.0);
    assert_eq!(s.tir_events, 0);
    assert_eq!(s.photons_max_depth, 0);
    assert_eq!(s.flux_max_depth, glam::DVec3::ZERO);
    // Clear glass: roulette never ends a path whose flux the chain did not reduce.
    assert_eq!(s.photons_roulette, 0);
    let balance = (s.flux_deposited.y + s.flux_escaped.y) / s.flux_on_casters.y - 1.0;
    assert!(balance.abs() < 1e-9, "balance {balance}");
}
