//! Mesh builders for the test scenes.

use core::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::scene::MeshGeometry;

fn mesh(positions: Vec<Vec3>, normals: Vec<Vec3>, indices: Vec<[u32; 3]>) -> MeshGeometry {
    MeshGeometry {
        positions,
        normals: Some(normals),
        indices,
    }
}

/// A `w x d` quad in the XZ plane, normal +Y, centred at the origin.
pub fn quad(w: f32, d: f32) -> MeshGeometry {
    let (x, z) = (w * 0.5, d * 0.5);
    mesh(
        vec![
            Vec3::new(-x, 0.0, -z),
            Vec3::new(-x, 0.0, z),
            Vec3::new(x, 0.0, z),
            Vec3::new(x, 0.0, -z),
        ],
        vec![Vec3::Y; 4],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

/// An axis-aligned box of size `s`, centred at the origin, outward faces, flat normals.
pub fn cuboid(s: Vec3) -> MeshGeometry {
    let h = s * 0.5;
    let mut p = Vec::new();
    let mut n = Vec::new();
    let mut idx = Vec::new();
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    for (normal, u, v) in faces {
        // u x v == normal for a counter-clockwise front face.
        let (u, v) = if u.cross(v).dot(normal) > 0.0 {
            (u, v)
        } else {
            (v, u)
        };
        let base = p.len() as u32;
        for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            p.push((normal + u * a + v * b) * h);
            n.push(normal);
        }
        idx.push([base, base + 1, base + 2]);
        idx.push([base, base + 2, base + 3]);
    }
    mesh(p, n, idx)
}

/// A UV sphere of `radius` with `segments` around and `rings` from pole to pole, smooth normals.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> MeshGeometry {
    let mut p = Vec::new();
    let mut n = Vec::new();
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = TAU * s as f32 / segments as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            p.push(d * radius);
            n.push(d);
        }
    }
    let row = segments + 1;
    let mut idx = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            let b = a + row;
            if r != 0 {
                idx.push([a, a + 1, b]);
            }
            if r != rings - 1 {
                idx.push([a + 1, b + 1, b]);
            }
        }
    }
    mesh(p, n, idx)
}

/// A height field `y = f(x, z)` over a `size x size` square with `res x res` cells, normals
/// from the analytic gradient `grad`.
pub fn height_field(
    size: f32,
    res: u32,
    f: impl Fn(f32, f32) -> f32,
    grad: impl Fn(f32, f32) -> Vec2,
) -> MeshGeometry {
    let mut p = Vec::new();
    let mut n = Vec::new();
    for j in 0..=res {
        for i in 0..=res {
            let x = (i as f32 / res as f32 - 0.5) * size;
            let z = (j as f32 / res as f32 - 0.5) * size;
            p.push(Vec3::new(x, f(x, z), z));
            let g = grad(x, z);
            n.push(Vec3::new(-g.x, 1.0, -g.y).normalize());
        }
    }
    let row = res + 1;
    let mut idx = Vec::new();
    for j in 0..res {
        for i in 0..res {
            let a = j * row + i;
            idx.push([a, a + row, a + 1]);
            idx.push([a + 1, a + row, a + row + 1]);
        }
    }
    mesh(p, n, idx)
}

/// An open cylinder wall (no caps) of `radius` and `height` standing on y = 0, normals pointing
/// inwards (the reflective side of a ring; render it double-sided).
pub fn ring(radius: f32, height: f32, segments: u32) -> MeshGeometry {
    let mut p = Vec::new();
    let mut n = Vec::new();
    for s in 0..=segments {
        let phi = TAU * s as f32 / segments as f32;
        let d = Vec3::new(phi.cos(), 0.0, phi.sin());
        p.push(d * radius);
        p.push(d * radius + Vec3::Y * height);
        n.push(-d);
        n.push(-d);
    }
    let mut idx = Vec::new();
    for s in 0..segments {
        let a = 2 * s;
        // Counter-clockwise seen from inside, so the winding normal is -d.
        idx.push([a, a + 2, a + 1]);
        idx.push([a + 1, a + 2, a + 3]);
    }
    mesh(p, n, idx)
}
