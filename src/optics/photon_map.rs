//! The hash-grid photon map (seed 001 sections 3.1 and 3.2): the grid's layout, each photon's
//! cell, the counting sort into `startIdx`, the row ranges of a query, the gather kernel, the
//! progressive radius and the photon's packed directions. The GPU build
//! (src/render/photon_map/grid.wgsl) makes the same choices with the same `f32` operations and
//! is tested for exact equality against [`build_grid`] (tests/gpu/photon_map.rs).
//!
//! Layout (section 3.1): the cell size is the gather radius `r`, the origin is the photons'
//! minimum less one cell (one layer of padding cells on each side, which hold no photon), and
//! cell `(x, y, z)` is stored at `z·X·Y + y·X + x`. A gather of radius `r` visits the cells
//! within `⌈r / cell⌉` of its own (the 3x3x3 while the radius is the cell's; a pixel whose
//! footprint is wider reaches further, [`gather_radius`]).
//! `start[c]` is the index of cell `c`'s first photon in the sorted photons, `start[cells]`
//! their count.
//!
//! Our choice where the seed is silent: the grid has a memory budget in cells. When the
//! photons' bounds need more cells at `r`, the cell size doubles until they fit (`shift`
//! doublings). Cells stay at least `r` wide, so the 3x3x3 gather is still exact; a pixel only
//! visits more photons. A power of two keeps `origin` and `1 / cell` exact scalings of the
//! uploaded `r` and `1 / r`, so the CPU and the GPU assign every photon the same cell.

use glam::{UVec3, Vec3};

/// Bytes of one stored photon: position, packed incoming direction, flux (RGB, lm), packed
/// surface normal (`Photon` in src/render/photon_map/trace.wgsl).
pub const PHOTON_BYTES: u64 = 32;

/// Cells of one block of the GPU prefix sum (256 threads x 4 cells).
pub const SCAN_BLOCK: u32 = 1024;

/// The largest grid budget (cells): the top level of the two-level scan holds 2048 block sums.
pub const MAX_GRID_CELLS: u32 = 1 << 20;

/// An `f32` as a `u32` whose unsigned order is the float order (Bevy's
/// `f32_bits_to_sortable_u32`), so bounds can be found with integer atomics.
#[inline]
pub fn sortable_bits(x: f32) -> u32 {
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// The inverse of [`sortable_bits`].
#[inline]
pub fn from_sortable_bits(u: u32) -> f32 {
    if u & 0x8000_0000 != 0 {
        f32::from_bits(u & 0x7fff_ffff)
    } else {
        f32::from_bits(!u)
    }
}

/// Where the grid lies and how it is cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridLayout {
    /// The corner of cell (0, 0, 0): the photons' minimum less one cell.
    pub origin: Vec3,
    /// Cell size, metres: `r · 2^shift`.
    pub cell: f32,
    /// `1 / cell`, as `(1 / r) · 2^-shift`.
    pub inv_cell: f32,
    /// Cells along x, y, z (zero when there is no photon).
    pub dims: UVec3,
    /// Doublings of the cell size the budget forced (0: cells are the radius).
    pub shift: u32,
}

impl GridLayout {
    /// Cells in the grid, `X·Y·Z`.
    pub fn cells(&self) -> u32 {
        self.dims.x * self.dims.y * self.dims.z
    }

    /// The grid around photons within `[lo, hi]` for radius `r` (`inv_r` = `1 / r` as the
    /// caller computed it once), at most `budget` cells.
    ///
    /// `X = max(⌊(hi.x − origin.x) / cell⌋ + 2, 3)`: the photon at `hi` falls in cell `X − 2`,
    /// the last cell is padding. At least 3 cells per axis: `lo − origin` is one cell only up
    /// to rounding, so a single photon can land in cell 0 and the axis would otherwise have 2. Guards: no photon (`lo > hi`) gives an empty grid; non-finite bounds or
    /// a radius of 0 double the cell until the grid fits or 126 doublings (then an empty grid).
    pub fn fit(lo: Vec3, hi: Vec3, r: f32, inv_r: f32, budget: u32) -> Self {
        let empty = Self {
            origin: Vec3::ZERO,
            cell: r,
            inv_cell: inv_r,
            dims: UVec3::ZERO,
            shift: 0,
        };
        if !(lo.cmple(hi).all()) {
            return empty;
        }
        for shift in 0..127u32 {
            let s = f32::from_bits((127 + shift) << 23); // 2^shift, exact
            let si = f32::from_bits((127 - shift) << 23); // 2^-shift, exact
            let cell = r * s;
            let inv_cell = inv_r * si;
            let origin = lo - Vec3::splat(cell);
            let f = ((hi - origin) * inv_cell).floor() + Vec3::splat(2.0);
            let n = f.max(Vec3::splat(3.0));
            if f.is_finite() && origin.is_finite() && n.x * n.y * n.z <= budget as f32 {
                return Self {
                    origin,
                    cell,
                    inv_cell,
                    dims: UVec3::new(n.x as u32, n.y as u32, n.z as u32),
                    shift,
                };
            }
        }
        empty
    }

    /// The cell holding point `p`, clamped into the grid.
    #[inline]
    pub fn cell_of(&self, p: Vec3) -> UVec3 {
        let hi = (self.dims.max(UVec3::ONE) - UVec3::ONE).as_vec3();
        let f = ((p - self.origin) * self.inv_cell)
            .floor()
            .clamp(Vec3::ZERO, hi);
        UVec3::new(f.x as u32, f.y as u32, f.z as u32)
    }

    /// The linear hash `z·X·Y + y·X + x`.
    #[inline]
    pub fn linear(&self, c: UVec3) -> u32 {
        (c.z * self.dims.y + c.y) * self.dims.x + c.x
    }

    /// The contiguous cell ranges `[first, last)` (rows along x) of the neighbourhood that
    /// holds every photon within `reach` cells of `p` (seed 001's offset table is the 3x3x3 of
    /// `reach` 1): the centre cell, `p`'s cell clamped into the grid, and `reach` cells on each
    /// side of it, cut at the grid's faces. `(2 reach + 1)²` rows at most. A point outside the
    /// grid takes the neighbourhood of the cell it clamps to, which holds every cell it could
    /// reach (the outer layer of cells is padding, without photons). `reach` is clamped to
    /// `[1, MAX_GATHER_REACH]`. Empty grid or non-finite `p`: `None`.
    pub fn rows(&self, p: Vec3, reach: u32) -> Option<Vec<(u32, u32)>> {
        if self.dims.min_element() < 3 {
            return None;
        }
        let hi = (self.dims - UVec3::ONE).as_vec3();
        let f = ((p - self.origin) * self.inv_cell)
            .floor()
            .clamp(Vec3::ZERO, hi);
        if !f.is_finite() {
            return None;
        }
        let c = UVec3::new(f.x as u32, f.y as u32, f.z as u32);
        let m = UVec3::splat(reach.clamp(1, MAX_GATHER_REACH));
        let lo = c.saturating_sub(m);
        let top = (c + m).min(self.dims - UVec3::ONE);
        let mut out = Vec::with_capacity(((top.y - lo.y + 1) * (top.z - lo.z + 1)) as usize);
        for z in lo.z..=top.z {
            for y in lo.y..=top.y {
                let first = self.linear(UVec3::new(lo.x, y, z));
                out.push((first, first + top.x - lo.x + 1));
            }
        }
        Some(out)
    }
}

/// A built grid: the layout, `start` (`cells + 1` entries) and the sorted order (`order[i]` is
/// the input index of the `i`-th sorted photon).
#[derive(Clone, Debug)]
pub struct PhotonGrid {
    /// Layout.
    pub layout: GridLayout,
    /// Prefix sums: cell `c`'s photons are `order[start[c]..start[c + 1]]`.
    pub start: Vec<u32>,
    /// Sorted photon indices (within a cell, in input order; the GPU's order within a cell
    /// is any permutation).
    pub order: Vec<u32>,
}

/// The photons' bounds `(min, max)`, the way the GPU finds them (integer atomics over
/// [`sortable_bits`]); `None` without photons.
pub fn photon_bounds(positions: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let mut lo = [u32::MAX; 3];
    let mut hi = [0u32; 3];
    for p in positions {
        for a in 0..3 {
            let s = sortable_bits(p[a]);
            lo[a] = lo[a].min(s);
            hi[a] = hi[a].max(s);
        }
    }
    (!positions.is_empty()).then(|| {
        let f = |v: [u32; 3]| Vec3::from_array(v.map(from_sortable_bits));
        (f(lo), f(hi))
    })
}

/// The counting sort of seed 001 section 3.1: count photons per cell, prefix-sum, scatter.
/// `inv_r` is `1 / r` as computed once by the caller (the GPU gets the same value).
pub fn build_grid(positions: &[Vec3], r: f32, inv_r: f32, budget: u32) -> PhotonGrid {
    let layout = match photon_bounds(positions) {
        Some((lo, hi)) => GridLayout::fit(lo, hi, r, inv_r, budget),
        None => GridLayout::fit(Vec3::ONE, Vec3::ZERO, r, inv_r, budget),
    };
    let cells = layout.cells() as usize;
    let mut start = vec![0u32; cells + 1];
    if cells == 0 {
        return PhotonGrid {
            layout,
            start,
            order: Vec::new(),
        };
    }
    let keys: Vec<u32> = positions
        .iter()
        .map(|p| layout.linear(layout.cell_of(*p)))
        .collect();
    for &k in &keys {
        start[k as usize + 1] += 1;
    }
    for c in 0..cells {
        start[c + 1] += start[c];
    }
    let mut cursor = start.clone();
    let mut order = vec![0u32; positions.len()];
    for (i, &k) in keys.iter().enumerate() {
        order[cursor[k as usize] as usize] = i as u32;
        cursor[k as usize] += 1;
    }
    PhotonGrid {
        layout,
        start,
        order,
    }
}

/// The Epanechnikov kernel normalised over the disc of radius `r` (`r2` = r²):
/// `K(d) = 2 / (π r²) · (1 − d² / r²)` for `d < r`, else 0. It integrates to 1 over the disc,
/// so a uniform photon field of density `Φ / A` gathers to `Φ / A`; against seed 001's uniform
/// kernel (formula 1) it weights near photons more, so caustics stay sharper at the same `r`,
/// and it falls to zero at the rim, so photons on a cell boundary in the CPU and GPU grids
/// weigh nothing either way. Guards: `r2 ≤ 0` or non-finite gives 0.
#[inline]
pub fn gather_kernel(d2: f32, r2: f32) -> f32 {
    let inside = r2 > 0.0 && r2.is_finite() && d2 < r2;
    if !inside {
        return 0.0;
    }
    2.0 / (core::f32::consts::PI * r2) * (1.0 - d2 / r2)
}

/// The most cells a gather reaches from its centre cell along each axis ([`GridLayout::rows`]):
/// a pixel's footprint may be wider than the progressive radius (the grid's cell), and its
/// gather then visits `(2 reach + 1)²` rows of cells instead of the 3x3x3. Capped so that a
/// pixel seeing a surface edge on (whose footprint grows as `1 / cos`) visits at most 81 rows.
pub const MAX_GATHER_REACH: u32 = 4;

/// The cells a gather of radius `r` reaches from its centre cell, `⌈r / cell⌉` in
/// `[1, MAX_GATHER_REACH]` (`inv_cell` = `1 / cell`). NaN: 1; infinite: the cap.
#[inline]
pub fn gather_reach(r: f32, inv_cell: f32) -> u32 {
    let m = (r * inv_cell).ceil();
    if m > 1.0 {
        (m.min(16.0) as u32).min(MAX_GATHER_REACH)
    } else {
        1
    }
}

/// The radius a pixel gathers with: the progressive radius `r`, but never less than the radius
/// of the disc as large as the pixel's footprint on the surface (`footprint_area`,
/// [`super::pixel_footprint_area`]), and never more than [`MAX_GATHER_REACH`] cells (the
/// neighbourhood [`GridLayout::rows`] visits).
///
/// Why the floor: a pixel shows the mean irradiance over its footprint, and that is what the
/// reference bins. Below the footprint the gather estimates the irradiance at the pixel's
/// centre instead, which differs wherever the caustic is sharper than a pixel (a caustic
/// curve's peak), so progressive frames would converge to another image. Measured on `ring`
/// (the point light's nephroid), RMSE after 64 frames: 125 lx without the floor, falling
/// below the first frame's with it. The floor reaches past the cell (it was capped at one
/// cell): at 128² a pixel's footprint is wider than the cell on `mirror_wall`, whose mirrored
/// rectangle's edges the gather then sampled at the pixel centres; its RMSE stayed at 64 lx
/// from 2^16 to 2^20 photons (the aliasing, not noise). Guards: a non-finite or negative area
/// is ignored; the result is finite, at most `MAX_GATHER_REACH · cell`.
#[inline]
pub fn gather_radius(r: f32, footprint_area: f32, cell: f32) -> f32 {
    let fp = if footprint_area.is_finite() && footprint_area > 0.0 {
        (footprint_area * core::f32::consts::FRAC_1_PI).sqrt()
    } else {
        0.0
    };
    let cell = if cell.is_finite() { cell.max(0.0) } else { 0.0 };
    let r = if r.is_finite() { r.max(0.0) } else { 0.0 };
    r.max(fp).min(cell * MAX_GATHER_REACH as f32)
}

/// The range of [`density_radius`], as multiples of the radius the pixel would have had.
pub const DENSITY_RADIUS_RANGE: (f32, f32) = (0.25, 2.0);

/// A pixel's gather radius from the photon density its earlier frames found there
/// ([`crate::PhotonMapSettings::gather_photons`]): the radius of the disc that holds `photons`
/// photons at `density` (photons per m² per frame, the running mean of the pixel's frames),
/// `r = sqrt(k / (π ρ))`, kept within [`DENSITY_RADIUS_RANGE`] of `r1` (the radius every pixel
/// would have had). This is the k-nearest-neighbour radius of Jensen's photon map (the seed's
/// section 3.2 gathers at a fixed radius instead, with no k-nearest heap), a balloon estimator
/// of adaptive kernel density estimation (Terrell and Scott 1992): where photons are sparse the
/// gather widens and its noise falls, in a bright focus it narrows and keeps the focus sharp.
/// Unlike Jensen's, the density comes from frames before this one, so the radius does not
/// depend on the photons it gathers and each frame stays a plain kernel estimate at the pixel.
/// Guards: `photons` zero, negative or NaN: `r1` (off); `r1` zero, negative or not finite:
/// `r1` as given (the caller's guard: the GPU gathers with it only where it is positive);
/// density zero, negative or NaN (no photon seen), or so small the radius overflows: the
/// range's top; an infinite density: the bottom.
#[inline]
pub fn density_radius(r1: f32, density: f32, photons: f32) -> f32 {
    if photons.is_nan() || photons <= 0.0 || !r1.is_finite() || r1 <= 0.0 {
        return r1;
    }
    let (lo, hi) = (r1 * DENSITY_RADIUS_RANGE.0, r1 * DENSITY_RADIUS_RANGE.1);
    let r = (photons / (core::f32::consts::PI * density)).sqrt();
    if density > 0.0 && r.is_finite() {
        r.clamp(lo, hi)
    } else {
        hi
    }
}

/// The squared radius of frame `frame` (1-based) of progressive photon mapping in the
/// memoryless form (Knaus and Zwicker 2011, eq. 20): `r_i² = r_{i−1}² (i − 1 + α) / i`, so
/// `r_i ∝ i^((α−1)/2)` and the mean of the frames converges. `alpha` is clamped to
/// `[0.05, 1]`; frame 0 is treated as 1. Computed in `f64` from `r1_sq`.
pub fn progressive_radius2(r1_sq: f32, frame: u32, alpha: f32) -> f32 {
    let a = f64::from(alpha.clamp(0.05, 1.0));
    let mut r2 = f64::from(r1_sq);
    for i in 2..=frame.max(1) {
        r2 *= (f64::from(i) - 1.0 + a) / f64::from(i);
    }
    r2 as f32
}

/// Pack a unit vector into 32 bits: the octahedral map, 16 bits signed-normalised per axis
/// (WGSL `pack2x16snorm`). Error below 1e-4 rad. Guard: a zero or non-finite vector packs
/// +z.
pub fn oct_encode(n: Vec3) -> u32 {
    let n = n.try_normalize().unwrap_or(Vec3::Z);
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    let mut v = glam::Vec2::new(n.x, n.y) / l1;
    if n.z < 0.0 {
        let s = glam::Vec2::new(
            if v.x >= 0.0 { 1.0 } else { -1.0 },
            if v.y >= 0.0 { 1.0 } else { -1.0 },
        );
        v = (glam::Vec2::ONE - glam::Vec2::new(v.y.abs(), v.x.abs())) * s;
    }
    let q = |x: f32| ((x.clamp(-1.0, 1.0) * 32767.0).round() as i32 as u32) & 0xffff;
    q(v.x) | (q(v.y) << 16)
}

/// The inverse of [`oct_encode`].
pub fn oct_decode(w: u32) -> Vec3 {
    let f = |b: u32| ((b as u16 as i16) as f32 / 32767.0).max(-1.0);
    let v = glam::Vec2::new(f(w & 0xffff), f(w >> 16));
    let mut n = Vec3::new(v.x, v.y, 1.0 - v.x.abs() - v.y.abs());
    let t = (-n.z).max(0.0);
    n.x += if n.x >= 0.0 { -t } else { t };
    n.y += if n.y >= 0.0 { -t } else { t };
    n.try_normalize().unwrap_or(Vec3::Z)
}

/// One stored photon as the gather sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StoredPhoton {
    /// Where it landed.
    pub position: Vec3,
    /// Flux, lm per channel.
    pub flux: Vec3,
    /// The receiver's normal, facing the side the photon came from.
    pub normal: Vec3,
}

/// What a gather found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gathered {
    /// Irradiance, lux per channel.
    pub irradiance: Vec3,
    /// Photons whose distance was tested.
    pub visited: u32,
    /// Photons within `r` that passed the normal test.
    pub used: u32,
}

/// The gather of seed 001 section 3.2 at point `x` with normal `n`: every photon of the row
/// ranges of `x`'s neighbourhood ([`gather_reach`] cells) within `r` (no k-nearest heap) whose normal has a cosine of at least `cos_min` with
/// `n` adds `Φ · K(d)` ([`gather_kernel`]). `photons` are in sorted order.
pub fn gather(
    grid: &PhotonGrid,
    photons: &[StoredPhoton],
    x: Vec3,
    n: Vec3,
    r: f32,
    cos_min: f32,
) -> Gathered {
    let mut g = Gathered::default();
    let reach = gather_reach(r, grid.layout.inv_cell);
    let Some(rows) = grid.layout.rows(x, reach) else {
        return g;
    };
    let r2 = r * r;
    for (a, b) in rows {
        for p in &photons[grid.start[a as usize] as usize..grid.start[b as usize] as usize] {
            g.visited += 1;
            let d2 = (p.position - x).length_squared();
            if d2 < r2 && p.normal.dot(n) >= cos_min {
                g.used += 1;
                g.irradiance += p.flux * gather_kernel(d2, r2);
            }
        }
    }
    g
}
