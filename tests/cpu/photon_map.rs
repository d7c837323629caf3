//! The photon map's optics core at its extremes: the grid's layout and counting sort against
//! brute force and a kd-tree (kiddo), the kernel's normalisation, a uniform photon field
//! recovered, the progressive radius, the packed normals, and the settings' validation.

use bevy_caustics::optics::*;
use glam::Vec3;

fn random_points(n: usize, lo: Vec3, hi: Vec3, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed, 3);
    (0..n)
        .map(|_| lo + (hi - lo) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()))
        .collect()
}

/// Order-preserving float bits: every pair of a sorted list of extremes keeps its order, and
/// the bits round-trip.
#[test]
fn sortable_bits_keep_the_order() {
    let xs = [
        f32::NEG_INFINITY,
        -f32::MAX,
        -1e4,
        -1.0,
        -f32::MIN_POSITIVE,
        -1e-45,
        -0.0,
        0.0,
        1e-45,
        f32::MIN_POSITIVE,
        1e-3,
        1.0,
        1e4,
        f32::MAX,
        f32::INFINITY,
    ];
    for w in xs.windows(2) {
        assert!(
            sortable_bits(w[0]) <= sortable_bits(w[1]),
            "{} vs {}",
            w[0],
            w[1]
        );
    }
    for x in xs {
        assert_eq!(from_sortable_bits(sortable_bits(x)).to_bits(), x.to_bits());
    }
}

/// The layout: padding on both sides, at least 3 cells per axis, the budget respected by
/// doubling the cell, an empty grid without photons or with non-finite bounds.
#[test]
fn grid_layout_fits_and_stays_in_budget() {
    let r = 0.1;
    let l = GridLayout::fit(Vec3::ZERO, Vec3::new(1.0, 0.5, 0.0), r, 1.0 / r, 1 << 20);
    assert_eq!(l.shift, 0);
    assert_eq!(l.cell, r);
    // Photons in cells 1..=11 ((1 m + one cell) / 0.1 m), padding 0 and 12: 13 (12 by
    // rounding is allowed).
    assert!((12..=13).contains(&l.dims.x), "{:?}", l.dims);
    assert_eq!(l.dims.z, 3);
    // Every photon is at least... inside the grid and at most one cell from the padding.
    for p in [
        Vec3::ZERO,
        Vec3::new(1.0, 0.5, 0.0),
        Vec3::new(0.5, 0.25, 0.0),
    ] {
        let c = l.cell_of(p);
        assert!(
            c.cmplt(l.dims - 1).all() || c.cmple(l.dims - 2).all(),
            "{c} {:?}",
            l.dims
        );
    }
    // One point: 3 x 3 x 3.
    let one = GridLayout::fit(Vec3::ONE, Vec3::ONE, r, 1.0 / r, 1 << 20);
    assert_eq!(one.dims.to_array(), [3, 3, 3]);
    // Budget: 1e4 m at 1 cm must double the cell many times and fit.
    let big = GridLayout::fit(Vec3::splat(-5e3), Vec3::splat(5e3), 0.01, 100.0, 1 << 20);
    assert!(big.cells() <= 1 << 20 && big.cells() > 0, "{big:?}");
    assert!(big.shift > 10 && big.cell >= 0.01 * (1 << big.shift) as f32 * 0.999);
    assert!(big.origin.is_finite());
    // 1e-3 m at 1e-6 m: 1000 cells per axis, doubled to fit.
    let small = GridLayout::fit(Vec3::ZERO, Vec3::splat(1e-3), 1e-6, 1e6, 1 << 20);
    assert!(small.cells() <= 1 << 20 && small.shift >= 3, "{small:?}");
    // Empty and non-finite bounds: no cell.
    for (lo, hi) in [
        (Vec3::ONE, Vec3::ZERO),
        (Vec3::splat(f32::NEG_INFINITY), Vec3::ZERO),
        (Vec3::ZERO, Vec3::splat(f32::NAN)),
    ] {
        assert_eq!(GridLayout::fit(lo, hi, r, 1.0 / r, 1 << 20).cells(), 0);
    }
    assert!(
        GridLayout::fit(Vec3::ONE, Vec3::ZERO, r, 1.0 / r, 1 << 20)
            .rows(Vec3::ONE, 1)
            .is_none()
    );
}

/// The counting sort against brute force: every photon sits in its own cell's range, `start`
/// is monotone and ends at the count, and the row ranges of any query (inside, on the border,
/// far outside) hold every photon within the gather radius, the same set a kd-tree (kiddo)
/// finds: at the cell's radius (the 3x3x3) and at radii reaching 2, 3 and 4 cells (a pixel
/// footprint wider than the cell, `gather_reach`).
#[test]
fn grid_gather_finds_what_brute_force_and_kiddo_find() {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    let r = 0.07;
    for (budget, n) in [(1u32 << 20, 20_000usize), (4096, 20_000), (1 << 20, 1)] {
        let pts = random_points(n, Vec3::new(-1.0, 0.0, -0.5), Vec3::new(1.0, 0.3, 0.5), 9);
        let grid = build_grid(&pts, r, 1.0 / r, budget);
        let l = grid.layout;
        assert_eq!(*grid.start.last().unwrap(), n as u32);
        assert!(grid.start.windows(2).all(|w| w[0] <= w[1]));
        for (i, p) in pts.iter().enumerate() {
            let c = l.linear(l.cell_of(*p)) as usize;
            let range = grid.start[c] as usize..grid.start[c + 1] as usize;
            assert!(grid.order[range].contains(&(i as u32)));
        }
        let sorted: Vec<StoredPhoton> = grid
            .order
            .iter()
            .map(|&i| StoredPhoton {
                position: pts[i as usize],
                flux: Vec3::ONE,
                normal: Vec3::Y,
            })
            .collect();
        let tree: ImmutableKdTree<f32, 3> =
            ImmutableKdTree::new_from_slice(&pts.iter().map(|p| p.to_array()).collect::<Vec<_>>())
                .expect("kd-tree");
        let queries = random_points(
            500,
            Vec3::new(-1.3, -0.2, -0.8),
            Vec3::new(1.3, 0.5, 0.8),
            4,
        );
        let cell = l.cell;
        for (q, g_r) in queries
            .iter()
            .chain(&[Vec3::splat(100.0), Vec3::splat(-1e4)])
            .flat_map(|q| [r, 1.5 * cell, 2.5 * cell, 4.0 * cell].map(|g_r| (*q, g_r)))
        {
            let brute = pts
                .iter()
                .filter(|p| (**p - q).length_squared() < g_r * g_r)
                .count();
            let g = gather(&grid, &sorted, q, Vec3::Y, g_r, -1.0);
            assert_eq!(
                g.used as usize, brute,
                "budget {budget}: query {q} radius {g_r}"
            );
            let kd = tree
                .query(&q.to_array())
                .within::<SquaredEuclidean<f32>>(g_r * g_r)
                .unsorted()
                .execute()
                .into_iter()
                .filter(|h| h.distance < g_r * g_r)
                .count();
            assert_eq!(kd, brute, "kiddo: query {q} radius {g_r}");
            assert!(g.visited as usize >= brute);
            // Visited photons are only the neighbourhood's: never the whole map (unless tiny).
            let reach = gather_reach(g_r, l.inv_cell);
            assert_eq!(reach, (g_r / cell).ceil().max(1.0) as u32);
            let rows = l.rows(q, reach).expect("a grid");
            assert!(rows.len() <= ((2 * reach + 1) * (2 * reach + 1)) as usize);
        }
    }
}

/// The kernel integrates to 1 over its disc (midpoint rule on a 2000² grid), is zero at and
/// beyond r, and guards r = 0, NaN and infinity.
#[test]
fn gather_kernel_is_normalised() {
    let r = 0.3f32;
    let n = 2000;
    let h = 2.0 * r / n as f32;
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let x = -r + (i as f32 + 0.5) * h;
            let y = -r + (j as f32 + 0.5) * h;
            sum += f64::from(gather_kernel(x * x + y * y, r * r)) * f64::from(h * h);
        }
    }
    assert!((sum - 1.0).abs() < 1e-3, "{sum}");
    assert_eq!(gather_kernel(r * r, r * r), 0.0);
    assert_eq!(gather_kernel(4.0, 1.0), 0.0);
    for r2 in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert_eq!(gather_kernel(0.0, r2), 0.0);
    }
    assert_eq!(gather_kernel(f32::NAN, 1.0), 0.0);
}

/// A uniform photon field of known irradiance is recovered: 2 000 000 photons of 0.002 lm on a
/// 2 m x 2 m floor (1000 lx), gathered at interior points within 3 % (about 3 standard
/// deviations: ~16 000 photons per gather, Epanechnikov weights);
/// photons on a wall facing away (normal test) add nothing.
#[test]
fn uniform_field_is_recovered() {
    let n = 2_000_000;
    let mut rng = Pcg32::new(11, 2);
    let mut pos = Vec::new();
    let mut photons = Vec::new();
    for _ in 0..n {
        let p = Vec3::new(rng.next_f32() * 2.0 - 1.0, 0.0, rng.next_f32() * 2.0 - 1.0);
        pos.push(p);
        photons.push((p, Vec3::splat(0.002), Vec3::Y));
    }
    // The underside of a thin floor: 100 000 photons just below, facing down.
    for _ in 0..100_000 {
        let p = Vec3::new(
            rng.next_f32() * 2.0 - 1.0,
            -1e-4,
            rng.next_f32() * 2.0 - 1.0,
        );
        pos.push(p);
        photons.push((p, Vec3::splat(0.01), Vec3::NEG_Y));
    }
    let r = 0.1;
    let grid = build_grid(&pos, r, 1.0 / r, 1 << 20);
    let sorted: Vec<StoredPhoton> = grid
        .order
        .iter()
        .map(|&i| {
            let (position, flux, normal) = photons[i as usize];
            StoredPhoton {
                position,
                flux,
                normal,
            }
        })
        .collect();
    for q in [
        Vec3::ZERO,
        Vec3::new(0.5, 0.0, -0.4),
        Vec3::new(-0.7, 0.0, 0.6),
    ] {
        let g = gather(&grid, &sorted, q, Vec3::Y, r, 0.7);
        let e = g.irradiance.x;
        assert!(
            (e - 1000.0).abs() < 30.0,
            "at {q}: {e} lx from {} photons",
            g.used
        );
    }
}

/// The progressive radius: frame 1 keeps r², frame 2 is r²(1 + α)/2, it only shrinks, follows
/// i^(α−1) within 10 % by frame 1000, and α = 1 keeps it.
#[test]
fn progressive_radius_follows_knaus_zwicker() {
    let r2 = 0.04;
    assert_eq!(progressive_radius2(r2, 1, 0.7), r2);
    assert_eq!(progressive_radius2(r2, 0, 0.7), r2);
    assert!((progressive_radius2(r2, 2, 0.7) - r2 * 0.85).abs() < 1e-7);
    let mut prev = r2;
    for i in 2..200 {
        let v = progressive_radius2(r2, i, 0.7);
        assert!(v < prev && v > 0.0);
        prev = v;
    }
    let ratio = progressive_radius2(r2, 1000, 0.7) / r2;
    let power = 1000f32.powf(0.7 - 1.0);
    assert!((ratio / power - 1.0).abs() < 0.6, "{ratio} vs {power}");
    assert_eq!(progressive_radius2(r2, 500, 1.0), r2);
    // Out-of-range alpha is clamped, never zero or negative.
    assert!(progressive_radius2(r2, 1000, -3.0) > 0.0);
    assert!(progressive_radius2(r2, 65_536, 0.05).is_finite());
}

/// Octahedral normals round-trip within 1e-4 rad, on the axes, the diagonals and random
/// directions; zero and NaN pack +z.
#[test]
fn octahedral_normals_round_trip() {
    let mut dirs = vec![
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
        Vec3::ONE.normalize(),
        Vec3::new(1.0, -1.0, -1.0).normalize(),
    ];
    let mut rng = Pcg32::new(3, 3);
    for _ in 0..10_000 {
        dirs.push(uniform_sphere(rng.next_vec2()));
    }
    for d in dirs {
        let back = oct_decode(oct_encode(d));
        assert!((back - d).length() < 1e-4, "{d} -> {back}");
    }
    assert_eq!(oct_decode(oct_encode(Vec3::ZERO)), Vec3::Z);
    assert_eq!(oct_decode(oct_encode(Vec3::NAN)), Vec3::Z);
}

/// Out-of-range settings are clamped, one fix per field; NaN becomes the default.
#[test]
fn photon_map_settings_are_validated() {
    use bevy_caustics::PhotonMapSettings;
    use bevy_caustics::components::validate::sanitize_photon_map;
    let mut s = PhotonMapSettings {
        radius: f32::NAN,
        max_bounces: 0,
        max_grid_cells: u32::MAX,
        alpha: 7.0,
        max_frames: 0,
        normal_threshold: -4.0,
        gather_photons: -1.0,
        ..Default::default()
    };
    let fixes = sanitize_photon_map(&mut s, &Default::default());
    let fields: Vec<&str> = fixes.iter().map(|f| f.0).collect();
    assert_eq!(
        fields,
        [
            "radius",
            "max_bounces",
            "max_grid_cells",
            "alpha",
            "max_frames",
            "normal_threshold",
            "gather_photons"
        ]
    );
    assert_eq!(s.radius, PhotonMapSettings::default().radius);
    assert_eq!(s.gather_photons, 0.0);
    assert_eq!(s.max_grid_cells, MAX_GRID_CELLS);
    assert!(sanitize_photon_map(&mut s, &Default::default()).is_empty());
}

/// The footprint floor of the gather radius reaches past the cell, up to `MAX_GATHER_REACH`
/// cells (the neighbourhood a gather visits), and the reach of a radius covers it: a radius
/// of the cell reaches 1 cell, just over it 2, the cap 4; zero, negative, NaN and infinite
/// inputs stay finite.
#[test]
fn gather_radius_reaches_past_the_cell_to_the_cap() {
    let cell = 0.02;
    let inv = 1.0 / cell;
    let disc = |r: f32| core::f32::consts::PI * r * r;
    // No footprint: the progressive radius; a footprint as wide as 2.5 cells: that disc.
    assert_eq!(gather_radius(0.01, 0.0, cell), 0.01);
    let r = gather_radius(0.01, disc(2.5 * cell), cell);
    assert!((r - 2.5 * cell).abs() < 1e-6, "{r}");
    assert_eq!(gather_reach(r, inv), 3);
    // A footprint seen edge on (huge): capped at MAX_GATHER_REACH cells, reach 4.
    let cap = cell * MAX_GATHER_REACH as f32;
    for area in [
        disc(10.0 * cell),
        1e30,
        f32::MAX,
        f32::INFINITY,
        f32::NAN,
        -1.0,
    ] {
        let r = gather_radius(0.01, area, cell);
        assert!(r.is_finite() && r <= cap, "{area}: {r}");
        assert!(gather_reach(r, inv) <= MAX_GATHER_REACH);
    }
    assert_eq!(gather_radius(0.01, 1e30, cell), cap);
    assert_eq!(gather_reach(cap, inv), MAX_GATHER_REACH);
    for (r, reach) in [(0.0, 1), (cell, 1), (1.001 * cell, 2), (1e30, 4)] {
        assert_eq!(gather_reach(r, inv), reach, "{r}");
    }
    for (bad, reach) in [(f32::NAN, 1), (-1.0, 1), (f32::INFINITY, MAX_GATHER_REACH)] {
        assert_eq!(gather_reach(bad, inv), reach, "{bad}");
    }
}

/// The adaptive radius (`density_radius`): the disc at the given density holds the asked
/// photons (`π r² ρ = k`) inside the range; a density too high or too low for the range gives
/// its ends; no density (zero, negative, NaN, or one whose radius overflows) gives the top;
/// no photons asked (0, negative, NaN) or a bad `r1` gives `r1` back.
#[test]
fn density_radius_holds_the_asked_photons_within_its_range() {
    let r1 = 0.02;
    let (lo, hi) = (r1 * DENSITY_RADIUS_RANGE.0, r1 * DENSITY_RADIUS_RANGE.1);
    // 64 photons in a disc of radius r1: that density gives r1 back; a quarter of it, 2 r1.
    let rho = 64.0 / (core::f32::consts::PI * r1 * r1);
    assert!((density_radius(r1, rho, 64.0) - r1).abs() < 1e-7);
    assert!((density_radius(r1, rho / 4.0, 64.0) - 2.0 * r1).abs() < 1e-7);
    let r = density_radius(r1, rho, 16.0);
    assert!(
        (core::f32::consts::PI * r * r * rho - 16.0).abs() < 1e-3,
        "{r}"
    );
    // Past the range: its ends.
    assert_eq!(density_radius(r1, rho * 1e6, 64.0), lo);
    assert_eq!(density_radius(r1, f32::MAX, 64.0), lo);
    assert_eq!(density_radius(r1, f32::INFINITY, 64.0), lo);
    for no_density in [
        0.0,
        -1.0,
        f32::NAN,
        f32::MIN_POSITIVE,
        1e-45,
        f32::NEG_INFINITY,
    ] {
        assert_eq!(density_radius(r1, no_density, 64.0), hi, "{no_density}");
    }
    for off in [0.0, -3.0, f32::NAN] {
        assert_eq!(density_radius(r1, rho, off), r1, "photons {off}");
    }
    assert_eq!(density_radius(r1, rho, f32::INFINITY), hi);
    for bad in [0.0, -1.0, f32::INFINITY] {
        assert_eq!(density_radius(bad, rho, 64.0), bad);
    }
    assert!(
        density_radius(f32::NAN, rho, 64.0).is_nan(),
        "NaN r1 is returned as given"
    );
}
