//! The stiff-and-extreme-case scenes (issue: error against run time): table-driven variants
//! of the test scenes that every technique must survive with finite output, no panic and no
//! energy created. The checks specific to each case live in the tests; the gem's is a closed
//! form (every technique's receivers get the power that strikes it).

use std::sync::Arc;

use glam::{Quat, Vec3};

use super::{NodeDesc, SceneDesc, geometry, glass_slab, glass_sphere, look_at, shine_along};

/// One case.
pub struct StiffCase {
    /// Name, as the code's guard comments cite it.
    pub name: &'static str,
    /// The scene.
    pub scene: SceneDesc,
    /// Photons per light.
    pub photons: u64,
    /// Square target size, pixels.
    pub size: u32,
}

fn slab_at(deg: f32) -> SceneDesc {
    let mut d = glass_slab();
    let a = deg.to_radians();
    d.lights[0].rotation = shine_along(Vec3::new(a.sin(), -a.cos(), 0.0));
    d
}

fn slab_ior(ior: f32) -> SceneDesc {
    let mut d = glass_slab();
    d.materials[1].params.ior = ior;
    d
}

/// `d` scaled by `s` about the origin (geometry and camera).
pub fn scaled(mut d: SceneDesc, s: f32) -> SceneDesc {
    for n in &mut d.nodes {
        n.translation *= s;
        n.scale *= s;
    }
    d.camera.translation *= s;
    d
}

fn with_degenerate_caster() -> SceneDesc {
    let mut d = glass_slab();
    let mut g = geometry::cuboid(Vec3::splat(0.3));
    let n = g.positions.len() as u32;
    g.positions.push(Vec3::ZERO);
    g.positions.push(Vec3::splat(f32::NAN));
    if let Some(normals) = g.normals.as_mut() {
        normals.extend([Vec3::Y, Vec3::Y]);
    }
    // Zero-area, collinear, NaN-vertex and out-of-range triangles.
    g.indices
        .extend([[n, n, n], [0, 0, 1], [0, 1, n + 1], [0, 1, 999]]);
    d.meshes.push(Arc::new(g));
    d.nodes.push(NodeDesc {
        name: "broken".into(),
        mesh: d.meshes.len() - 1,
        material: 1,
        translation: Vec3::new(0.0, 1.6, 0.0),
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    });
    d
}

fn far_camera() -> SceneDesc {
    let mut d = glass_sphere();
    let target = Vec3::new(0.0, 0.3, 0.0);
    let dir = (d.camera.translation - target).normalize();
    d.camera.translation = target + dir * 1e4;
    d.camera.rotation = look_at(d.camera.translation, target);
    d.camera.fov_y = 0.0002;
    d
}

/// Every case, in a fixed order.
pub fn cases() -> Vec<StiffCase> {
    let case = |name, scene, photons, size| StiffCase {
        name,
        scene,
        photons,
        size,
    };
    let mut v = Vec::new();
    for (name, deg) in [
        ("light at 0 degrees", 0.0),
        ("light at 45 degrees", 45.0),
        ("light at 89 degrees", 89.0),
        ("light at 89.9 degrees", 89.9),
    ] {
        v.push(case(name, slab_at(deg), 40_000, 32));
    }
    v.push(case(
        "IOR 1.0 (only transmitted light)",
        slab_ior(1.0),
        40_000,
        32,
    ));
    for (name, ior) in [
        ("IOR 1.33", 1.33),
        ("IOR 1.5", 1.5),
        ("IOR 2.4", 2.4),
        ("IOR 4.0", 4.0),
    ] {
        v.push(case(name, slab_ior(ior), 40_000, 32));
    }
    // A brilliant in a closed room of receivers: the walls must get exactly the power that
    // strikes the gem (super::closed), so this case checks energy, not only finiteness.
    v.push(case(
        "total internal reflection paths (IOR 2.4 gem)",
        super::closed::gem_room(),
        40_000,
        32,
    ));
    v.push(case(
        "degenerate and zero-area triangles",
        with_degenerate_caster(),
        40_000,
        32,
    ));
    v.push(case(
        "caster 1e-3 m",
        scaled(glass_slab(), 1e-3),
        40_000,
        32,
    ));
    v.push(case("caster 1e4 m", scaled(glass_slab(), 1e4), 40_000, 32));
    v.push(case("camera 1e4 m away", far_camera(), 40_000, 32));
    v.push(case("zero photons", glass_sphere(), 0, 32));
    v.push(case(
        "a million photons in one small region",
        glass_sphere(),
        1 << 20,
        4,
    ));
    v
}
