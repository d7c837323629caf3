//! The geometry of a caustics volume (seed 000 sections 3.1 to 3.4): its rigid frame, the slabs
//! parallel to the entry face with their orthographic probes, the exit-face projectors, and
//! which slabs a box touches (differential updates, section 3.5).
//!
//! Coordinates: `q = R^T (p - c)` in metres (the volume's rotation without its scale), the box
//! is `|q_i| <= h_i`. The entry face is local axis `e` with sign `s` (`PosY`: e = 1, s = +1);
//! the slab depth `w = h_e - s q_e` runs from 0 at the entry face to `2 h_e` at the face
//! opposite it. The lateral axes `j`, `k` follow [`super::face_frame`] (`PosY`: Z then X).

use glam::{Affine3A, Mat3, Mat4, Vec3, Vec4};

use crate::components::VolumeFace;

/// A volume's frame and slab layout.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeFrame {
    /// Centre, world.
    pub centre: Vec3,
    /// Local axes in world space (unit columns).
    pub axes: Mat3,
    /// Half extents along the local axes, metres (> 0).
    pub half: Vec3,
    /// Entry axis index (0 x, 1 y, 2 z).
    pub e: usize,
    /// +1 when the entry face is the positive side of its axis, else -1.
    pub s: f32,
    /// Lateral axis indices (u, v of the slab probes).
    pub j: usize,
    /// Second lateral axis index.
    pub k: usize,
    /// Slab count (>= 1).
    pub slabs: u32,
}

/// Face code of a [`VolumeFace`] (the enum's order: +X, -X, +Y, -Y, +Z, -Z).
pub fn face_code(f: VolumeFace) -> u32 {
    match f {
        VolumeFace::PosX => 0,
        VolumeFace::NegX => 1,
        VolumeFace::PosY => 2,
        VolumeFace::NegY => 3,
        VolumeFace::PosZ => 4,
        VolumeFace::NegZ => 5,
    }
}

impl VolumeFrame {
    /// The frame of a volume of `size` placed by `world_from_volume` (its scale multiplies the
    /// size; shear is ignored). Guards: non-finite or zero extents become 1e-3 m, a singular
    /// rotation becomes the identity, `slabs` is at least 1.
    pub fn new(world_from_volume: &Affine3A, size: Vec3, entry: VolumeFace, slabs: u32) -> Self {
        let m = Mat3::from(world_from_volume.matrix3);
        let mut axes = [Vec3::X, Vec3::Y, Vec3::Z];
        let mut half = Vec3::splat(5e-4);
        for i in 0..3 {
            let col = m.col(i);
            let len = col.length();
            if len.is_finite() && len > 0.0 {
                axes[i] = col / len;
                let h = 0.5 * size[i] * len;
                half[i] = if h.is_finite() { h.max(5e-4) } else { 5e-4 };
            }
        }
        let axes = Mat3::from_cols(axes[0], axes[1], axes[2]);
        let axes = if axes.determinant().abs() > 0.5 {
            axes
        } else {
            Mat3::IDENTITY
        };
        let centre = Vec3::from(world_from_volume.translation);
        let centre = if centre.is_finite() {
            centre
        } else {
            Vec3::ZERO
        };
        let (e, s) = match entry {
            VolumeFace::PosX => (0, 1.0),
            VolumeFace::NegX => (0, -1.0),
            VolumeFace::PosY => (1, 1.0),
            VolumeFace::NegY => (1, -1.0),
            VolumeFace::PosZ => (2, 1.0),
            VolumeFace::NegZ => (2, -1.0),
        };
        let (j, k) = match e {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        Self {
            centre,
            axes,
            half,
            e,
            s,
            j,
            k,
            slabs: slabs.max(1),
        }
    }

    /// Local coordinates of a world point.
    pub fn local(&self, p: Vec3) -> Vec3 {
        self.axes.transpose() * (p - self.centre)
    }

    /// World point of local coordinates.
    pub fn world(&self, q: Vec3) -> Vec3 {
        self.centre + self.axes * q
    }

    /// Slab thickness, metres.
    pub fn thickness(&self) -> f32 {
        2.0 * self.half[self.e] / self.slabs as f32
    }

    /// Slab depth of a local point (0 at the entry face).
    pub fn depth(&self, q: Vec3) -> f32 {
        self.half[self.e] - self.s * q[self.e]
    }

    /// World from "slab space" (x = u/h_j, y = v/h_k in [-1, 1], z = w in metres): the
    /// affine map the slab probes are built on.
    fn world_from_slab(&self) -> Mat4 {
        let (aj, ak, ae) = (
            self.axes.col(self.j) * self.half[self.j],
            self.axes.col(self.k) * self.half[self.k],
            -self.axes.col(self.e) * self.s,
        );
        let origin = self.centre + self.axes.col(self.e) * (self.s * self.half[self.e]);
        Mat4::from_cols(
            aj.extend(0.0),
            ak.extend(0.0),
            ae.extend(0.0),
            origin.extend(1.0),
        )
    }

    /// The orthographic probe of slab `slab` (seed 000 section 3.2): clip space of a render
    /// pass whose x, y cover the face and whose z in [0, 1] is the slab's depth range, so the
    /// rasteriser keeps "the geometry found within the boundaries of the current slab" only.
    /// Texel `(x, y)` of a `res`² target holds `u/h_j = (x + 0.5) / res * 2 - 1` and
    /// `v/h_k = 1 - (y + 0.5) / res * 2`.
    pub fn slab_clip_from_world(&self, slab: u32) -> Mat4 {
        let t = self.thickness();
        let w0 = t * slab as f32;
        // z_clip = (w - w0) / t.
        let clip_from_slab = Mat4::from_cols(
            Vec4::X,
            Vec4::Y,
            Vec4::new(0.0, 0.0, 1.0 / t, 0.0),
            Vec4::new(0.0, 0.0, -w0 / t, 1.0),
        );
        clip_from_slab * self.world_from_slab().inverse()
    }

    /// The plane whose value `dot(xyz, p) + w` is a world point's slab depth `w`.
    pub fn depth_plane(&self) -> Vec4 {
        // w = h_e - s a_e . (p - c).
        let a = self.axes.col(self.e);
        (-a * self.s).extend(self.half[self.e] + self.s * a.dot(self.centre))
    }

    /// The projector of face `code` (seed 000 section 3.4, "we emulate the generation process
    /// of a cube-map"): a perspective camera at the centre whose frustum passes through the
    /// face's four edges, near plane on the face, far plane `far` metres from the centre along
    /// the face axis. Every point outside the box lies in exactly one face's frustum (the axis
    /// of largest `|q_i| / h_i`), in front of its near plane. Returns clip-from-world and the
    /// plane giving the stored depth `|q_i|`.
    pub fn projector(&self, code: u32, far: f32) -> (Mat4, Vec4) {
        let i = (code / 2) as usize % 3;
        let sign = if code.is_multiple_of(2) { 1.0 } else { -1.0 };
        let (a, b) = match i {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        let h = self.half;
        let near = h[i];
        let far = far.max(near * 1.001 + 1e-3);
        // View space: x along axis a scaled, y along b, z forward = sign * axis i.
        let fwd = self.axes.col(i) * sign;
        let xa = self.axes.col(a);
        let yb = self.axes.col(b) * sign;
        let view_from_world = Mat4::from_cols(
            Vec4::new(xa.x, yb.x, fwd.x, 0.0),
            Vec4::new(xa.y, yb.y, fwd.y, 0.0),
            Vec4::new(xa.z, yb.z, fwd.z, 0.0),
            Vec4::new(
                -xa.dot(self.centre),
                -yb.dot(self.centre),
                -fwd.dot(self.centre),
                1.0,
            ),
        );
        // x_ndc = (x / h_a) / (z / h_i), z_ndc = far (z - near) / (z (far - near)).
        let sx = h[i] / h[a];
        let sy = h[i] / h[b];
        let c = far / (far - near);
        let clip_from_view = Mat4::from_cols(
            Vec4::new(sx, 0.0, 0.0, 0.0),
            Vec4::new(0.0, sy, 0.0, 0.0),
            Vec4::new(0.0, 0.0, c, 1.0),
            Vec4::new(0.0, 0.0, -c * near, 0.0),
        );
        (
            clip_from_view * view_from_world,
            fwd.extend(-fwd.dot(self.centre)),
        )
    }

    /// The slabs a world box (min, max) touches, or `None` when it misses the volume.
    pub fn slabs_touched(&self, lo: Vec3, hi: Vec3) -> Option<(u32, u32)> {
        if !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let (mut qlo, mut qhi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for c in 0..8 {
            let p = Vec3::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            );
            let q = self.local(p);
            qlo = qlo.min(q);
            qhi = qhi.max(q);
        }
        if (0..3).any(|i| qhi[i] < -self.half[i] || qlo[i] > self.half[i]) {
            return None;
        }
        let (d0, d1) = {
            let a = self.depth(qlo);
            let b = self.depth(qhi);
            (a.min(b), a.max(b))
        };
        let t = self.thickness();
        let last = self.slabs - 1;
        let k0 = ((d0 / t).floor().max(0.0) as u32).min(last);
        let k1 = ((d1 / t).floor().max(0.0) as u32).min(last);
        Some((k0, k1))
    }

    /// The eight corners, world.
    pub fn corners(&self) -> [Vec3; 8] {
        core::array::from_fn(|c| {
            self.world(
                Vec3::new(
                    if c & 1 == 0 { -1.0 } else { 1.0 },
                    if c & 2 == 0 { -1.0 } else { 1.0 },
                    if c & 4 == 0 { -1.0 } else { 1.0 },
                ) * self.half,
            )
        })
    }

    /// Outside the view: every corner beyond one of the clip planes of `clip_from_world`
    /// (left, right, bottom, top, behind the eye).
    pub fn outside_frustum(&self, clip_from_world: &Mat4) -> bool {
        let c = self.corners().map(|p| *clip_from_world * p.extend(1.0));
        let planes: [fn(Vec4) -> bool; 5] = [
            |h| h.x < -h.w,
            |h| h.x > h.w,
            |h| h.y < -h.w,
            |h| h.y > h.w,
            |h| h.w <= 0.0,
        ];
        planes.iter().any(|out| c.iter().all(|h| out(*h)))
    }
}
