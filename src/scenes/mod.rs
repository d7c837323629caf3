//! The test scenes, described in plain Rust: written to glTF by `examples/make_scenes.rs`
//! (`assets/scenes/*.gltf`) and turned straight into a traceable scene by the CPU tests, so the
//! analytic checks and the glTF the renderer loads come from one description.

pub mod closed;
pub mod cornell;
pub mod geometry;
pub mod gltf;
pub mod many;
pub mod stiff;

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec2, Vec3};

use crate::scene::{
    Blas, CameraProjection, Instance, MaterialParams, MeshGeometry, Tlas, TraceCamera, TraceLight,
    classify_material,
};

/// A material of a scene description.
#[derive(Clone, Debug)]
pub struct MaterialDesc {
    /// Name in the glTF.
    pub name: String,
    /// PBR parameters as glTF (and then Bevy) carries them.
    pub params: MaterialParams,
    /// Render both faces.
    pub double_sided: bool,
}

/// A placed mesh.
#[derive(Clone, Debug)]
pub struct NodeDesc {
    /// Node name.
    pub name: String,
    /// Index into `SceneDesc::meshes`.
    pub mesh: usize,
    /// Index into `SceneDesc::materials`.
    pub material: usize,
    /// Translation, metres.
    pub translation: Vec3,
    /// Rotation.
    pub rotation: Quat,
    /// Scale.
    pub scale: Vec3,
}

/// A light, in glTF `KHR_lights_punctual` units.
#[derive(Clone, Copy, Debug)]
pub enum LightKind {
    /// Illuminance in lux.
    Directional {
        /// Lux.
        lux: f32,
    },
    /// Luminous intensity in candela.
    Point {
        /// Candela.
        candela: f32,
    },
    /// Luminous intensity in candela and cone angles in radians.
    Spot {
        /// Candela.
        candela: f32,
        /// Inner cone angle, radians.
        inner: f32,
        /// Outer cone angle, radians.
        outer: f32,
    },
}

/// A light node; it shines along its local -Z.
#[derive(Clone, Debug)]
pub struct LightDesc {
    /// Node name.
    pub name: String,
    /// Kind and intensity.
    pub kind: LightKind,
    /// Linear colour.
    pub color: Vec3,
    /// Position.
    pub translation: Vec3,
    /// Orientation.
    pub rotation: Quat,
}

/// A perspective camera node (looks along local -Z).
#[derive(Clone, Debug)]
pub struct CameraDesc {
    /// Position.
    pub translation: Vec3,
    /// Orientation.
    pub rotation: Quat,
    /// Vertical field of view, radians.
    pub fov_y: f32,
}

/// A whole scene.
#[derive(Clone, Debug)]
pub struct SceneDesc {
    /// File stem.
    pub name: String,
    /// Meshes.
    pub meshes: Vec<Arc<MeshGeometry>>,
    /// Materials.
    pub materials: Vec<MaterialDesc>,
    /// Mesh nodes.
    pub nodes: Vec<NodeDesc>,
    /// Lights.
    pub lights: Vec<LightDesc>,
    /// The camera.
    pub camera: CameraDesc,
    /// Caustics volumes declared on empty nodes through glTF `extras`.
    pub volumes: Vec<VolumeNode>,
}

/// A node that declares a caustics volume (`{"caustics_volume": {...}}` in its extras).
#[derive(Clone, Debug)]
pub struct VolumeNode {
    /// Node name.
    pub name: String,
    /// Centre of the volume, metres.
    pub translation: Vec3,
    /// The `caustics_volume` object (docs/volumes.md).
    pub extras: serde_json::Value,
}

/// A camera at `eye` looking at `target` with +Y up (-Z up when it looks straight down or up,
/// where +Y is no up: `look_at_rh` would return NaN there).
pub fn look_at(eye: Vec3, target: Vec3) -> Quat {
    let dir = (target - eye).normalize_or(Vec3::NEG_Z);
    let m = if dir.cross(Vec3::Y).length_squared() < 1e-8 {
        glam::Mat4::look_at_rh(eye, eye + dir, Vec3::NEG_Z)
    } else {
        glam::Mat4::look_at_rh(eye, target, Vec3::Y)
    };
    Quat::from_mat4(&m.inverse())
}

/// The rotation that makes local -Z travel along `dir`.
pub fn shine_along(dir: Vec3) -> Quat {
    Quat::from_rotation_arc(Vec3::NEG_Z, dir.normalize())
}

impl SceneDesc {
    pub(crate) fn new(name: &str, camera: CameraDesc) -> Self {
        Self {
            name: name.into(),
            meshes: vec![],
            materials: vec![],
            nodes: vec![],
            lights: vec![],
            camera,
            volumes: vec![],
        }
    }

    /// Add a material; returns its index.
    pub fn material(&mut self, name: &str, params: MaterialParams, double_sided: bool) -> usize {
        self.materials.push(MaterialDesc {
            name: name.into(),
            params,
            double_sided,
        });
        self.materials.len() - 1
    }

    /// Add a mesh node at `translation`; returns the node index.
    pub fn add(
        &mut self,
        name: &str,
        mesh: MeshGeometry,
        material: usize,
        translation: Vec3,
    ) -> usize {
        self.meshes.push(Arc::new(mesh));
        self.nodes.push(NodeDesc {
            name: name.into(),
            mesh: self.meshes.len() - 1,
            material,
            translation,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        });
        self.nodes.len() - 1
    }

    /// Add a node that instances the mesh (and the material: glTF keeps it on the mesh) of node
    /// `of` at `translation`; returns the new node's index.
    pub fn instance(&mut self, name: &str, of: usize, translation: Vec3) -> usize {
        self.nodes.push(NodeDesc {
            name: name.into(),
            translation,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
            ..self.nodes[of].clone()
        });
        self.nodes.len() - 1
    }

    /// The traceable scene: TLAS over all nodes, lights in Bevy units (as Bevy imports
    /// them: directional lux unchanged, point and spot `candela x 4π` lumens), and the
    /// camera at `width x height`.
    pub fn to_trace(&self, width: u32, height: u32) -> (Tlas, Vec<TraceLight>, TraceCamera) {
        let blas: Vec<Arc<Blas>> = self
            .meshes
            .iter()
            .map(|m| Arc::new(Blas::build(m.clone())))
            .collect();
        let instances = self
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| {
                Instance::new(
                    blas[n.mesh].clone(),
                    Affine3A::from_scale_rotation_translation(n.scale, n.rotation, n.translation),
                    classify_material(&self.materials[n.material].params),
                    i as u64,
                )
            })
            .collect();
        let lights = self
            .lights
            .iter()
            .map(|l| {
                let dir = l.rotation * Vec3::NEG_Z;
                let four_pi = 4.0 * core::f32::consts::PI;
                match l.kind {
                    LightKind::Directional { lux } => TraceLight::Directional {
                        direction: dir,
                        illuminance: l.color * lux,
                    },
                    LightKind::Point { candela } => TraceLight::Point {
                        position: l.translation,
                        flux: l.color * candela * four_pi,
                    },
                    LightKind::Spot {
                        candela,
                        inner,
                        outer,
                    } => TraceLight::Spot {
                        position: l.translation,
                        direction: dir,
                        flux: l.color * candela * four_pi,
                        inner_angle: inner,
                        outer_angle: outer,
                    },
                }
            })
            .collect();
        let camera = TraceCamera {
            world_from_view: Affine3A::from_rotation_translation(
                self.camera.rotation,
                self.camera.translation,
            ),
            projection: CameraProjection::Perspective {
                fov_y: self.camera.fov_y,
            },
            width,
            height,
        };
        (Tlas::build(instances), lights, camera)
    }
}

/// Grey diffuse floor material.
pub(crate) fn diffuse(albedo: f32) -> MaterialParams {
    MaterialParams {
        base_color: Vec3::splat(albedo),
        metallic: 0.0,
        perceptual_roughness: 0.9,
        ..Default::default()
    }
}

/// A clear dielectric (KHR_materials_transmission + ior + volume).
pub fn glass(ior: f32, thickness: f32) -> MaterialParams {
    MaterialParams {
        base_color: Vec3::ONE,
        metallic: 0.0,
        perceptual_roughness: 0.0,
        specular_transmission: 1.0,
        ior,
        thickness,
        ..Default::default()
    }
}

/// A polished metal mirror of normal-incidence reflectance `f0`.
pub fn mirror(f0: f32) -> MaterialParams {
    MaterialParams {
        base_color: Vec3::splat(f0),
        metallic: 1.0,
        perceptual_roughness: 0.0,
        ..Default::default()
    }
}

/// Illuminance of the directional lights of the test scenes, lux.
pub const SUN_LUX: f32 = 10_000.0;
/// Incidence of the light on `mirror_wall`'s mirror, radians from the normal.
pub const MIRROR_WALL_INCIDENCE: f32 = core::f32::consts::FRAC_PI_4;
/// Incidence of the light on `glass_slab`, radians from the normal.
pub const GLASS_SLAB_INCIDENCE: f32 = core::f32::consts::FRAC_PI_6;

/// A flat mirror on the floor reflects a 45-degree sun onto a wall at x = 3 whose normal is
/// -X; the reflected beam lands on y in [2.51, 3.51], z in [-0.5, 0.5].
pub fn mirror_wall() -> SceneDesc {
    let cam = CameraDesc {
        translation: Vec3::new(-2.0, 3.0, 0.0),
        rotation: look_at(Vec3::new(-2.0, 3.0, 0.0), Vec3::new(3.0, 3.0, 0.0)),
        fov_y: 45f32.to_radians(),
    };
    let mut s = SceneDesc::new("mirror_wall", cam);
    let grey = s.material("floor", diffuse(0.8), false);
    let wall = s.material("wall", diffuse(0.8), false);
    let m = s.material("mirror", mirror(0.9), false);
    s.add("floor", geometry::quad(10.0, 10.0), grey, Vec3::ZERO);
    s.add(
        "mirror",
        geometry::quad(1.0, 1.0),
        m,
        Vec3::new(0.0, 0.01, 0.0),
    );
    let w = s.add(
        "wall",
        geometry::quad(5.0, 6.0),
        wall,
        Vec3::new(3.0, 2.5, 0.0),
    );
    // Quad normal +Y turned to -X.
    s.nodes[w].rotation = Quat::from_rotation_z(core::f32::consts::FRAC_PI_2);
    let a = MIRROR_WALL_INCIDENCE;
    s.lights.push(LightDesc {
        name: "sun".into(),
        kind: LightKind::Directional { lux: SUN_LUX },
        color: Vec3::ONE,
        translation: Vec3::new(-3.0, 3.0, 0.0),
        rotation: shine_along(Vec3::new(a.sin(), -a.cos(), 0.0)),
    });
    s
}

/// A 1 x 0.2 x 1 m slab of IOR 1.5 glass at y in [0.9, 1.1] under a 30-degree sun.
pub fn glass_slab() -> SceneDesc {
    let eye = Vec3::new(0.6, 3.0, 3.0);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::new(0.6, 0.0, 0.0)),
        fov_y: 45f32.to_radians(),
    };
    let mut s = SceneDesc::new("glass_slab", cam);
    let grey = s.material("floor", diffuse(0.8), false);
    let g = s.material("glass", glass(1.5, 0.2), false);
    s.add("floor", geometry::quad(10.0, 10.0), grey, Vec3::ZERO);
    s.add(
        "slab",
        geometry::cuboid(Vec3::new(1.0, 0.2, 1.0)),
        g,
        Vec3::new(0.0, 1.0, 0.0),
    );
    let a = GLASS_SLAB_INCIDENCE;
    s.lights.push(LightDesc {
        name: "sun".into(),
        kind: LightKind::Directional { lux: SUN_LUX },
        color: Vec3::ONE,
        translation: Vec3::new(-2.0, 4.0, 0.0),
        rotation: shine_along(Vec3::new(a.sin(), -a.cos(), 0.0)),
    });
    s
}

/// Radius of `glass_sphere`'s ball lens, metres.
pub const SPHERE_RADIUS: f32 = 0.5;
/// Segments around `glass_sphere`'s ball (its silhouette is a regular polygon of this many sides).
pub const SPHERE_SEGMENTS: u32 = 96;

/// A ball lens (IOR 1.5, radius 0.5 m, centre 1 m up) under a vertical sun, over a 40 m floor.
pub fn glass_sphere() -> SceneDesc {
    let eye = Vec3::new(0.0, 2.2, 2.6);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::new(0.0, 0.3, 0.0)),
        fov_y: 45f32.to_radians(),
    };
    let mut s = SceneDesc::new("glass_sphere", cam);
    let grey = s.material("floor", diffuse(0.8), false);
    let g = s.material("glass", glass(1.5, 1.0), false);
    s.add("floor", geometry::quad(40.0, 40.0), grey, Vec3::ZERO);
    s.add(
        "ball",
        geometry::uv_sphere(SPHERE_RADIUS, SPHERE_SEGMENTS, SPHERE_SEGMENTS / 2),
        g,
        Vec3::new(0.0, 1.0, 0.0),
    );
    s.lights.push(LightDesc {
        name: "sun".into(),
        kind: LightKind::Directional { lux: SUN_LUX },
        color: Vec3::ONE,
        translation: Vec3::new(0.0, 5.0, 0.0),
        rotation: shine_along(Vec3::NEG_Y),
    });
    s
}

/// The glass ball's floor caustic seen in a mirror: the ball of `glass_sphere` at x = 0.8
/// under a sun straight down, a 3 x 2 m mirror (reflectance 0.9) standing at z = -1.5 facing
/// +Z, and a camera that sees the caustic's reflection in the mirror past the ball.
pub fn mirror_ball() -> SceneDesc {
    let eye = Vec3::new(-1.5, 2.5, 3.5);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::new(0.3, 0.6, -1.5)),
        fov_y: 45f32.to_radians(),
    };
    let mut s = SceneDesc::new("mirror_ball", cam);
    let grey = s.material("floor", diffuse(0.8), false);
    let g = s.material("glass", glass(1.5, 1.0), false);
    let m = s.material("mirror", mirror(0.9), false);
    s.add("floor", geometry::quad(40.0, 40.0), grey, Vec3::ZERO);
    s.add(
        "ball",
        geometry::uv_sphere(SPHERE_RADIUS, SPHERE_SEGMENTS, SPHERE_SEGMENTS / 2),
        g,
        Vec3::new(0.8, 1.0, 0.0),
    );
    let k = s.add(
        "mirror",
        geometry::quad(3.0, 2.0),
        m,
        Vec3::new(0.5, 1.0, -1.5),
    );
    // Quad normal +Y turned to +Z.
    s.nodes[k].rotation = Quat::from_rotation_x(core::f32::consts::FRAC_PI_2);
    s.lights.push(LightDesc {
        name: "sun".into(),
        kind: LightKind::Directional { lux: SUN_LUX },
        color: Vec3::ONE,
        translation: Vec3::new(0.0, 5.0, 0.0),
        rotation: shine_along(Vec3::NEG_Y),
    });
    s
}

/// A wavy water surface (IOR 1.33, slightly blue) 1 m above a pool floor, camera under water.
pub fn pool() -> SceneDesc {
    let eye = Vec3::new(0.0, 0.7, 2.4);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::new(0.0, 0.0, 0.0)),
        fov_y: 50f32.to_radians(),
    };
    let mut s = SceneDesc::new("pool", cam);
    let tiles = s.material("pool_floor", diffuse(0.85), false);
    let water = s.material(
        "water",
        MaterialParams {
            attenuation_color: Vec3::new(0.85, 0.95, 1.0),
            attenuation_distance: 4.0,
            ..glass(1.33, 1.0)
        },
        true,
    );
    s.add("floor", geometry::quad(12.0, 12.0), tiles, Vec3::ZERO);
    let (k1, k2, amp) = (Vec2::new(3.1, 1.3), Vec2::new(-1.7, 2.9), 0.025);
    s.add(
        "water",
        geometry::height_field(
            8.0,
            128,
            move |x, z| amp * ((k1.x * x + k1.y * z).sin() + (k2.x * x + k2.y * z).sin()),
            move |x, z| amp * (k1 * (k1.x * x + k1.y * z).cos() + k2 * (k2.x * x + k2.y * z).cos()),
        ),
        water,
        Vec3::new(0.0, 1.0, 0.0),
    );
    let a = 20f32.to_radians();
    s.lights.push(LightDesc {
        name: "sun".into(),
        kind: LightKind::Directional { lux: SUN_LUX },
        color: Vec3::ONE,
        translation: Vec3::new(-1.0, 4.0, 0.0),
        rotation: shine_along(Vec3::new(a.sin(), -a.cos(), 0.0)),
    });
    s
}

/// A polished ring (radius 1 m, 0.25 m tall) with a point light just inside its rim: the
/// reflected light draws the cardioid on the floor.
pub fn ring() -> SceneDesc {
    let eye = Vec3::new(0.0, 3.2, 1.6);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::new(0.0, 0.0, 0.0)),
        fov_y: 45f32.to_radians(),
    };
    let mut s = SceneDesc::new("ring", cam);
    let grey = s.material("floor", diffuse(0.8), false);
    let m = s.material("ring", mirror(0.95), true);
    s.add("floor", geometry::quad(8.0, 8.0), grey, Vec3::ZERO);
    s.add("ring", geometry::ring(1.0, 0.25, 256), m, Vec3::ZERO);
    s.lights.push(LightDesc {
        name: "bulb".into(),
        kind: LightKind::Point { candela: 1000.0 },
        color: Vec3::ONE,
        translation: Vec3::new(0.97, 0.4, 0.0),
        rotation: Quat::IDENTITY,
    });
    s
}

/// A floor and a sun, no caster: nothing of the plugin may run.
pub fn empty() -> SceneDesc {
    let eye = Vec3::new(0.0, 3.0, 3.0);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::ZERO),
        fov_y: 45f32.to_radians(),
    };
    let mut s = SceneDesc::new("empty", cam);
    let grey = s.material("floor", diffuse(0.8), false);
    s.add("floor", geometry::quad(10.0, 10.0), grey, Vec3::ZERO);
    s.lights.push(LightDesc {
        name: "sun".into(),
        kind: LightKind::Directional { lux: SUN_LUX },
        color: Vec3::ONE,
        translation: Vec3::new(0.0, 4.0, 0.0),
        rotation: shine_along(Vec3::new(0.3, -1.0, 0.2)),
    });
    s
}

/// Every test scene, in the order the report lists them.
pub fn all() -> Vec<SceneDesc> {
    vec![
        mirror_wall(),
        glass_slab(),
        glass_sphere(),
        pool(),
        ring(),
        empty(),
        mirror_ball(),
        cornell::cornell_diamond(),
        cornell::cornell_ring(),
        cornell::cornell_ball(),
        cornell::cornell_blocks(),
    ]
}
