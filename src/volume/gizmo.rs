//! The lines of a caustics volume's gizmo (seed 000 section 3.1's faces and section 3.2's
//! slabs): every face of the box drawn as a rectangle inset towards its centre, so that
//! neighbouring faces' outlines do not overlap, in the colour of its role — the entry face
//! (with a cross on it), exit faces, culling faces (a face in neither list culls, as in
//! [`crate::CausticsVolume`]) — and the planes between slabs. The render pass that draws them
//! is `crate::render::volume::gizmo`.

use glam::{Affine3A, Vec3};

use super::VolumeFrame;
use crate::components::{CausticsVolume, VolumeFace};

/// What a gizmo line shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VolumeGizmoKind {
    /// The entry face's cross (and its outline when it is not also an exit).
    Entry,
    /// An exit face's outline.
    Exit,
    /// A culling face's outline.
    Culling,
    /// A plane between two slabs.
    SlabPlane,
}

/// One line segment, world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GizmoSegment {
    /// Start.
    pub a: Vec3,
    /// End.
    pub b: Vec3,
    /// Its role (and so its colour).
    pub kind: VolumeGizmoKind,
}

/// The role of `face`'s outline: exit when listed as an exit and not as a culling face (the
/// passes' exit mask), else culling; the entry face is `Entry` unless it is also an exit.
pub fn face_kind(volume: &CausticsVolume, face: VolumeFace) -> VolumeGizmoKind {
    if volume.exit.contains(&face) && !volume.culling.contains(&face) {
        VolumeGizmoKind::Exit
    } else if face == volume.entry {
        VolumeGizmoKind::Entry
    } else {
        VolumeGizmoKind::Culling
    }
}

/// The segments of one volume placed by `world_from_volume`: per face a rectangle inset by
/// `inset` (a fraction of the face's extents, clamped to [0, 0.45]; non-finite: 0) and, on the
/// entry face, its two diagonals; with `slab_planes`, one full rectangle per plane between
/// slabs (`volume.slabs - 1` of them, at most 63). The box is [`VolumeFrame`]'s, with its
/// guards (zero or non-finite extents 1 mm, a non-finite position the origin), so the lines show
/// exactly what the passes use.
pub fn volume_gizmo_segments(
    world_from_volume: &Affine3A,
    volume: &CausticsVolume,
    inset: f32,
    slab_planes: bool,
) -> Vec<GizmoSegment> {
    let slabs = volume.slabs.clamp(1, 64);
    let frame = VolumeFrame::new(world_from_volume, volume.size, volume.entry, slabs);
    let h = frame.half;
    let inset = if inset.is_finite() {
        inset.clamp(0.0, 0.45)
    } else {
        0.0
    };
    let mut out = Vec::new();
    let mut rect = |axis: usize, at: f32, shrink: f32, kind: VolumeGizmoKind, cross: bool| {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let corner = |su: f32, sv: f32| {
            let mut q = Vec3::ZERO;
            q[axis] = at;
            q[u] = su * h[u] * (1.0 - 2.0 * shrink);
            q[v] = sv * h[v] * (1.0 - 2.0 * shrink);
            frame.world(q)
        };
        let c = [
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(1.0, 1.0),
            corner(-1.0, 1.0),
        ];
        for i in 0..4 {
            out.push(GizmoSegment {
                a: c[i],
                b: c[(i + 1) % 4],
                kind,
            });
        }
        if cross {
            for (a, b) in [(0, 2), (1, 3)] {
                out.push(GizmoSegment {
                    a: c[a],
                    b: c[b],
                    kind: VolumeGizmoKind::Entry,
                });
            }
        }
    };
    for face in VolumeFace::ALL {
        let n = face.normal();
        let axis = if n.x != 0.0 {
            0
        } else if n.y != 0.0 {
            1
        } else {
            2
        };
        let sign = n[axis];
        rect(
            axis,
            sign * h[axis],
            inset,
            face_kind(volume, face),
            face == volume.entry,
        );
    }
    if slab_planes {
        let thick = frame.thickness();
        for k in 1..slabs {
            let at = frame.s * (h[frame.e] - thick * k as f32);
            rect(frame.e, at, 0.0, VolumeGizmoKind::SlabPlane, false);
        }
    }
    out
}
