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

/// A round brilliant-cut gem of girdle `radius`, centred on the girdle, table up (+Y), flat
/// facets (each triangle its own vertices, normal = face normal, outward): an octagonal table
/// (8 triangles), a crown of 8 star and 16 upper-girdle facets at 34.5 degrees, a girdle band
/// 2 % of the radius thick (32 triangles) and a 16-facet pavilion at 40.75 degrees to the culet
/// (80 triangles). Table 56 % of the diameter, the proportions of Tolkowsky's cut: with IOR 2.4
/// most light entering the crown is totally reflected by the pavilion, often many times.
pub fn brilliant(radius: f32) -> MeshGeometry {
    let r = radius;
    let girdle = 0.02 * r;
    let table_r = 0.56 * r;
    let crown_h = (r - table_r) * 34.5f32.to_radians().tan();
    let pavilion_h = r * 40.75f32.to_radians().tan();
    let ring = |n: u32, rad: f32, y: f32, k: u32| {
        let phi = TAU * k as f32 / n as f32;
        Vec3::new(rad * phi.cos(), y, rad * phi.sin())
    };
    let table = |k: u32| ring(8, table_r, girdle + crown_h, k % 8);
    let top = |j: u32| ring(16, r, girdle, j % 16);
    let bottom = |j: u32| ring(16, r, -girdle, j % 16);
    let table_centre = Vec3::new(0.0, girdle + crown_h, 0.0);
    let culet = Vec3::new(0.0, -girdle - pavilion_h, 0.0);
    let mut tris: Vec<[Vec3; 3]> = Vec::new();
    for k in 0..8 {
        tris.push([table_centre, table(k), table(k + 1)]);
        // Star facet on the table edge, upper-girdle facets on each girdle edge.
        tris.push([table(k), table(k + 1), top(2 * k + 1)]);
        tris.push([top(2 * k), top(2 * k + 1), table(k)]);
        tris.push([top(2 * k + 1), top(2 * k + 2), table(k + 1)]);
    }
    for j in 0..16 {
        tris.push([top(j), top(j + 1), bottom(j)]);
        tris.push([top(j + 1), bottom(j + 1), bottom(j)]);
        tris.push([bottom(j), bottom(j + 1), culet]);
    }
    let mut p = Vec::new();
    let mut n = Vec::new();
    let mut idx = Vec::new();
    // The body is convex and holds the origin: a face normal points outwards when it points
    // away from the origin; the winding follows the normal.
    for [a, b, c] in tris {
        let mut nrm = (b - a).cross(c - a).normalize();
        let (b, c) = if nrm.dot(a + b + c) < 0.0 {
            nrm = -nrm;
            (c, b)
        } else {
            (b, c)
        };
        let base = p.len() as u32;
        p.extend([a, b, c]);
        n.extend([nrm; 3]);
        idx.push([base, base + 1, base + 2]);
    }
    mesh(p, n, idx)
}

/// A closed box of size `s` standing on y = 0 with its faces pointing inwards (six receiver
/// walls around whatever is inside), flat normals.
pub fn room(s: Vec3) -> MeshGeometry {
    let mut g = cuboid(s);
    for p in &mut g.positions {
        p.y += s.y * 0.5;
    }
    if let Some(normals) = g.normals.as_mut() {
        for nrm in normals {
            *nrm = -*nrm;
        }
    }
    for t in &mut g.indices {
        t.swap(1, 2);
    }
    g
}

/// A closed cylinder of `radius` and `height` standing on y = 0: smooth side normals, flat caps,
/// `segments` around, outward faces.
pub fn cylinder(radius: f32, height: f32, segments: u32) -> MeshGeometry {
    let mut p = Vec::new();
    let mut n = Vec::new();
    let mut idx = Vec::new();
    for s in 0..=segments {
        let phi = TAU * s as f32 / segments as f32;
        let d = Vec3::new(phi.cos(), 0.0, phi.sin());
        p.extend([d * radius, d * radius + Vec3::Y * height]);
        n.extend([d, d]);
    }
    for s in 0..segments {
        let a = 2 * s;
        // Counter-clockwise seen from outside (winding normal +d).
        idx.push([a, a + 1, a + 2]);
        idx.push([a + 1, a + 3, a + 2]);
    }
    for (y, normal) in [(0.0, Vec3::NEG_Y), (height, Vec3::Y)] {
        let centre = p.len() as u32;
        p.push(Vec3::Y * y);
        n.push(normal);
        for s in 0..=segments {
            let phi = TAU * s as f32 / segments as f32;
            p.push(Vec3::new(phi.cos() * radius, y, phi.sin() * radius));
            n.push(normal);
        }
        for s in 0..segments {
            let (a, b) = (centre + 1 + s, centre + 2 + s);
            if normal.y > 0.0 {
                idx.push([centre, b, a]);
            } else {
                idx.push([centre, a, b]);
            }
        }
    }
    mesh(p, n, idx)
}

/// A torus in the XZ plane centred at the origin: tube of radius `minor` around a circle of
/// radius `major`, `segments` around the circle and `sides` around the tube, smooth outward
/// normals.
pub fn torus(major: f32, minor: f32, segments: u32, sides: u32) -> MeshGeometry {
    let mut p = Vec::new();
    let mut n = Vec::new();
    for s in 0..=segments {
        let phi = TAU * s as f32 / segments as f32;
        let d = Vec3::new(phi.cos(), 0.0, phi.sin());
        for t in 0..=sides {
            let psi = TAU * t as f32 / sides as f32;
            let nrm = d * psi.cos() + Vec3::Y * psi.sin();
            p.push(d * major + nrm * minor);
            n.push(nrm);
        }
    }
    let row = sides + 1;
    let mut idx = Vec::new();
    for s in 0..segments {
        for t in 0..sides {
            let a = s * row + t;
            let b = a + row;
            idx.push([a, a + 1, b]);
            idx.push([a + 1, b + 1, b]);
        }
    }
    mesh(p, n, idx)
}
