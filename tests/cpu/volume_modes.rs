//! Caustics volumes in plain Rust, continued: the update schedule with progressive mode
//! (seed 000 section 3.5), the progressive photon order, and the volume gizmo's lines.

use super::*;
use bevy_caustics::volume::{
    GizmoSegment, VolumeGizmoKind, VolumeRun, face_kind, progressive_batch, progressive_order,
    progressive_scale, schedule_run, volume_gizmo_segments,
};
use bevy_caustics::{CausticsVolume, VolumeFace};
use glam::{Affine3A, Quat};

/// Apply runs from a change until nothing is left to run; returns the runs.
fn drain(change: Option<u32>, slabs: u32, live: u32, progressive: u32) -> Vec<VolumeRun> {
    let mut runs = Vec::new();
    let mut traced = 0;
    let mut change = change;
    while let Some(run) = schedule_run(change, slabs, live, traced, progressive) {
        runs.push(run);
        traced = run.traced_after;
        change = None;
        assert!(runs.len() <= live as usize + 2, "does not terminate");
    }
    runs
}

#[test]
fn volume_schedule_without_progressive_mode() {
    // Differential updates: a change in slab k re-runs from k over the whole list.
    for k in 0..3 {
        let r = schedule_run(Some(k), 3, 1000, 1000, 0).unwrap();
        assert_eq!(r.first_slab, k);
        assert_eq!(
            (r.trace, r.project, r.traced_after),
            ((0, 1000), (0, 1000), 1000)
        );
        assert_eq!(r.restarts(), k == 0);
    }
    // Outside the volume only: projectors over everything.
    let r = schedule_run(Some(3), 3, 1000, 1000, 0).unwrap();
    assert_eq!((r.first_slab, r.trace, r.project), (3, (0, 0), (0, 1000)));
    assert!(!r.restarts());
    // Nothing changed: nothing runs.
    assert_eq!(schedule_run(None, 3, 1000, 1000, 0), None);
    // A batch at least the list is the same as off.
    assert_eq!(progressive_batch(1000, 1000), 1000);
    assert_eq!(progressive_batch(5000, 1000), 1000);
    assert_eq!(progressive_batch(0, 1000), 1000);
    assert_eq!(drain(Some(0), 3, 1000, 1000), drain(Some(0), 3, 1000, 0));
    assert_eq!(drain(Some(0), 3, 1000, 0).len(), 1);
}

#[test]
fn volume_schedule_progressive_batches_partition_the_list() {
    for (live, batch) in [
        (1000u32, 300u32),
        (1000, 1),
        (1000, 999),
        (7, 2),
        (20_000, 5_000),
    ] {
        let runs = drain(Some(1), 3, live, batch);
        assert_eq!(runs.len() as u32, live.div_ceil(batch), "{live} {batch}");
        let mut next = 0;
        for (n, r) in runs.iter().enumerate() {
            // Every batch traces all slabs: a change inside restarts from slab 0.
            assert_eq!(r.first_slab, 0);
            assert_eq!(r.trace.0, next, "contiguous, no overlap");
            assert!(r.trace.1 > r.trace.0 && r.trace.1 - r.trace.0 <= batch);
            // The first projection clears; later ones add exactly their batch.
            assert_eq!(r.project, if n == 0 { (0, r.trace.1) } else { r.trace });
            assert_eq!(r.restarts(), n == 0);
            next = r.trace.1;
            assert_eq!(r.traced_after, next);
        }
        assert_eq!(next, live, "the whole list, up to the maximum");
    }
}

#[test]
fn volume_schedule_progressive_changes() {
    // A change inside the volume mid-accumulation restarts it.
    let r = schedule_run(Some(2), 3, 1000, 600, 300).unwrap();
    assert_eq!(
        (r.first_slab, r.trace, r.project, r.traced_after),
        (0, (0, 300), (0, 300), 300)
    );
    // A change outside mid-accumulation: next batch, and everything re-projected.
    let r = schedule_run(Some(3), 3, 1000, 600, 300).unwrap();
    assert_eq!(
        (r.first_slab, r.trace, r.project, r.traced_after),
        (0, (600, 900), (0, 900), 900)
    );
    // A change outside once complete: the projectors over everything.
    let r = schedule_run(Some(3), 3, 1000, 1000, 300).unwrap();
    assert_eq!(
        (r.first_slab, r.trace, r.project, r.traced_after),
        (3, (0, 0), (0, 1000), 1000)
    );
    // Complete and nothing changed: nothing.
    assert_eq!(schedule_run(None, 3, 1000, 1000, 300), None);
    // Extremes: an empty list, a stale traced count above the list, zero slabs, u32 bounds.
    assert_eq!(drain(Some(0), 3, 0, 300).len(), 1);
    assert_eq!(schedule_run(None, 3, 0, 0, 300), None);
    let r = schedule_run(None, 3, 1000, 5000, 300);
    assert_eq!(r, None);
    let r = schedule_run(Some(0), 0, 10, 0, 3).unwrap();
    assert_eq!(r.trace, (0, 3));
    let r = schedule_run(None, 1, u32::MAX, u32::MAX - 5, u32::MAX - 1).unwrap();
    assert_eq!(r.trace, (u32::MAX - 5, u32::MAX));
}

#[test]
fn volume_progressive_scale() {
    assert_eq!(progressive_scale(1000, 1000), 1.0);
    assert_eq!(progressive_scale(1000, 250), 4.0);
    assert_eq!(progressive_scale(1000, 0), 1.0);
    assert_eq!(progressive_scale(0, 0), 1.0);
    assert_eq!(progressive_scale(1000, 4000), 1.0);
    let s = progressive_scale(u32::MAX, 1);
    assert!(s.is_finite() && s > 4e9);
}

#[test]
fn volume_progressive_order_spreads_every_prefix() {
    // A 100 x 100 grid of photons (row-major, as seeded); the first quarter of the order.
    let n = 100u32;
    let order = progressive_order(&(0..n * n).collect::<Vec<_>>());
    let mut sorted = order.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, (0..n * n).collect::<Vec<_>>(), "a permutation");
    for quarter in [1usize, 2, 3] {
        let prefix = &order[..(n * n) as usize * quarter / 4];
        // Every 10 x 10 block gets its share (25 per quarter) within +-40 %.
        let mut blocks = [0u32; 100];
        for &i in prefix {
            blocks[((i / n / 10) * 10 + (i % n) / 10) as usize] += 1;
        }
        let want = 25.0 * quarter as f32;
        for (b, &c) in blocks.iter().enumerate() {
            assert!(
                (c as f32 - want).abs() <= 0.4 * want,
                "block {b}: {c} of {want} in the first {quarter}/4"
            );
        }
    }
    // The identity order would put the first quarter in the top 25 rows only.
    assert!(progressive_order(&[]).is_empty());
    assert_eq!(progressive_order(&[7]), vec![7]);
}

proptest! {
    #![proptest_config(cases(64))]
    #[test]
    fn volume_progressive_order_is_a_permutation(v in proptest::collection::vec(0u32..1_000_000, 0..2000)) {
        let mut a = progressive_order(&v);
        let mut b = v.clone();
        a.sort_unstable();
        b.sort_unstable();
        prop_assert_eq!(a, b);
    }

    #[test]
    fn volume_schedule_always_terminates(live in 0u32..5000, batch in 0u32..6000, slabs in 0u32..66, k in 0u32..70) {
        let runs = drain(Some(k.min(slabs.max(1))), slabs, live, batch);
        let last = runs.last().map_or(0, |r| r.traced_after);
        prop_assert!(runs.len() as u32 <= live.div_ceil(progressive_batch(batch, live).max(1)).max(1) + 1);
        prop_assert!(last == live || runs.iter().all(|r| r.first_slab > 0));
    }
}

fn local(s: &GizmoSegment, world_from_volume: &Affine3A) -> (Vec3, Vec3) {
    let inv = world_from_volume.inverse();
    (inv.transform_point3(s.a), inv.transform_point3(s.b))
}

#[test]
fn volume_gizmo_segments_of_the_default_volume() {
    let v = CausticsVolume::default(); // entry +Y, exit -Y, 3 slabs, unit box
    let t =
        Affine3A::from_rotation_translation(Quat::from_rotation_z(0.3), Vec3::new(1.0, 2.0, 3.0));
    let segs = volume_gizmo_segments(&t, &v, 0.02, true);
    let count = |k| segs.iter().filter(|s| s.kind == k).count();
    // 6 faces x 4 edges, the entry cross (2), 2 slab planes x 4.
    assert_eq!(segs.len(), 34);
    assert_eq!(count(VolumeGizmoKind::Entry), 6);
    assert_eq!(count(VolumeGizmoKind::Exit), 4);
    assert_eq!(count(VolumeGizmoKind::Culling), 16);
    assert_eq!(count(VolumeGizmoKind::SlabPlane), 8);
    for s in &segs {
        let (a, b) = local(s, &t);
        for q in [a, b] {
            assert!(q.abs().max_element() <= 0.5 + 1e-5, "{q}");
        }
        match s.kind {
            // Face outlines inset by 2 % of the face: on the face plane, 0.48 from its centre.
            VolumeGizmoKind::Exit => {
                assert!((a.y + 0.5).abs() < 1e-5 && (b.y + 0.5).abs() < 1e-5);
                assert!((a.x.abs() - 0.48).abs() < 1e-5 && (a.z.abs() - 0.48).abs() < 1e-5);
            }
            VolumeGizmoKind::Entry => assert!((a.y - 0.5).abs() < 1e-5 && (b.y - 0.5).abs() < 1e-5),
            // Slab planes at depths 1/3 and 2/3 below the entry face, across the whole box.
            VolumeGizmoKind::SlabPlane => {
                let d = 0.5 - a.y;
                assert!(
                    (d - 1.0 / 3.0).abs() < 1e-5 || (d - 2.0 / 3.0).abs() < 1e-5,
                    "{d}"
                );
                assert!((a.y - b.y).abs() < 1e-6);
                assert!((a.x.abs() - 0.5).abs() < 1e-5);
            }
            VolumeGizmoKind::Culling => assert!(a.y.abs() < 0.5 + 1e-5),
        }
    }
    // No slab planes when asked, or with one slab.
    assert_eq!(volume_gizmo_segments(&t, &v, 0.02, false).len(), 26);
    let one = CausticsVolume {
        slabs: 1,
        ..v.clone()
    };
    assert_eq!(volume_gizmo_segments(&t, &one, 0.02, true).len(), 26);
}

#[test]
fn volume_gizmo_face_roles() {
    let (fitted, t) = CausticsVolume::fit((Vec3::ZERO, Vec3::ONE), Vec3::NEG_Y, 0.1);
    // Every face an exit: the entry outline is an exit's, its cross the entry's.
    let segs = volume_gizmo_segments(&t.compute_affine(), &fitted, 0.02, false);
    assert_eq!(
        segs.iter()
            .filter(|s| s.kind == VolumeGizmoKind::Exit)
            .count(),
        24
    );
    assert_eq!(
        segs.iter()
            .filter(|s| s.kind == VolumeGizmoKind::Entry)
            .count(),
        2
    );
    // Culling wins over exit, as in the passes' exit mask.
    let v = CausticsVolume {
        exit: vec![VolumeFace::NegY, VolumeFace::PosX],
        culling: vec![VolumeFace::PosX],
        ..Default::default()
    };
    assert_eq!(face_kind(&v, VolumeFace::PosX), VolumeGizmoKind::Culling);
    assert_eq!(face_kind(&v, VolumeFace::NegY), VolumeGizmoKind::Exit);
    assert_eq!(face_kind(&v, VolumeFace::PosY), VolumeGizmoKind::Entry);
    assert_eq!(face_kind(&v, VolumeFace::NegZ), VolumeGizmoKind::Culling);
    // Entry on -Z: the cross is on z = -0.5 and slab planes are z = const.
    let v = CausticsVolume {
        entry: VolumeFace::NegZ,
        ..Default::default()
    };
    let t = Affine3A::IDENTITY;
    for s in volume_gizmo_segments(&t, &v, 0.0, true) {
        match s.kind {
            VolumeGizmoKind::Entry => assert!((s.a.z + 0.5).abs() < 1e-6),
            VolumeGizmoKind::SlabPlane => {
                assert!((s.a.z - s.b.z).abs() < 1e-6);
                let d = s.a.z + 0.5;
                assert!((d - 1.0 / 3.0).abs() < 1e-5 || (d - 2.0 / 3.0).abs() < 1e-5);
            }
            _ => {}
        }
    }
}

#[test]
fn volume_gizmo_extremes() {
    let v = CausticsVolume {
        slabs: 64,
        ..Default::default()
    };
    for scale in [1e-3f32, 1e4] {
        let t = Affine3A::from_scale(Vec3::splat(scale));
        let segs = volume_gizmo_segments(&t, &v, 0.02, true);
        assert_eq!(segs.len(), 26 + 63 * 4);
        assert!(segs.iter().all(|s| s.a.is_finite() && s.b.is_finite()));
    }
    // Non-finite placement: at the origin; zero size: 1 mm (the frame's guards, as the passes).
    let nan = Affine3A::from_translation(Vec3::NAN);
    let segs = volume_gizmo_segments(&nan, &v, 0.02, true);
    assert_eq!(segs.len(), 26 + 63 * 4);
    assert!(
        segs.iter()
            .all(|s| s.a.is_finite() && s.a.abs().max_element() <= 0.5 + 1e-6)
    );
    let flat = CausticsVolume {
        size: Vec3::new(1.0, 0.0, 1.0),
        ..Default::default()
    };
    let segs = volume_gizmo_segments(&Affine3A::IDENTITY, &flat, 0.02, true);
    assert!(
        segs.iter()
            .all(|s| s.a.y.abs() <= 5e-4 + 1e-7 && s.b.y.abs() <= 5e-4 + 1e-7)
    );
    for inset in [f32::NAN, f32::INFINITY, -1.0, 10.0] {
        let segs = volume_gizmo_segments(&Affine3A::IDENTITY, &v, inset, false);
        assert_eq!(segs.len(), 26);
        assert!(segs.iter().all(|s| s.a.is_finite() && s.b.is_finite()));
    }
    // Slab counts outside the validator's range are clamped, as the passes do.
    let many = CausticsVolume {
        slabs: 1000,
        ..Default::default()
    };
    assert_eq!(
        volume_gizmo_segments(&Affine3A::IDENTITY, &many, 0.0, true).len(),
        26 + 63 * 4
    );
}
