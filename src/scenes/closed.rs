//! Closed-form energy scenes (issue: accuracy where light bounces many times). A caster that
//! absorbs nothing, inside a room whose six walls are all receivers, must hand every watt that
//! strikes it to the walls: `caustic power on the walls = power striking the caster`, whatever
//! the number of internal reflections. No path cap passes that by luck. And an absorbing slab
//! under a perpendicular sun passes `E A (1 - R)^2 T / (1 - R^2 T^2)` to the floor (Beer-Lambert
//! along the slab, every even number of internal reflections). Thin-walled glass (glTF
//! thickness 0) has air on both sides: a thin pane passes `1 - R` of its light from either
//! side, a closed thin shell `(1 - R)^2` of the light that crosses it, and neither ever
//! totally reflects.

use glam::Vec3;

use super::{
    CameraDesc, LightDesc, LightKind, SUN_LUX, SceneDesc, diffuse, geometry, glass, look_at,
    shine_along,
};
use crate::scene::MaterialParams;

/// Size of the closed room, metres (x, y, z), standing on y = 0.
pub const ROOM: Vec3 = Vec3::new(4.0, 3.0, 4.0);
/// Centre of the caster in the room.
pub const CASTER_AT: Vec3 = Vec3::new(0.0, 1.2, 0.0);

fn room_scene(
    name: &str,
    caster: crate::scene::MeshGeometry,
    ior: f32,
    light: LightDesc,
) -> SceneDesc {
    let eye = Vec3::new(1.6, 2.4, 1.6);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::new(0.0, 0.6, 0.0)),
        fov_y: 70f32.to_radians(),
    };
    let mut s = SceneDesc::new(name, cam);
    let walls = s.material("walls", diffuse(0.8), false);
    let g = s.material("glass", glass(ior, 1.0), false);
    s.add("room", geometry::room(ROOM), walls, Vec3::ZERO);
    s.add("caster", caster, g, CASTER_AT);
    s.lights.push(light);
    s
}

/// A round brilliant (girdle radius 0.5 m, IOR 2.4) in a closed room, lit from above by a spot
/// whose cone just holds the gem: most light entering the crown is totally reflected by the
/// pavilion, many paths take dozens of internal reflections.
pub fn gem_room() -> SceneDesc {
    room_scene(
        "gem_room",
        geometry::brilliant(0.5),
        2.4,
        gem_spot(CASTER_AT),
    )
}

/// The spot above a gem centred at `gem`, its cone just holding the gem.
fn gem_spot(gem: Vec3) -> LightDesc {
    let at = gem + Vec3::new(0.3, 1.4, 0.2);
    LightDesc {
        name: "spot".into(),
        kind: LightKind::Spot {
            candela: 20_000.0,
            inner: 0.25,
            outer: 0.4,
        },
        color: Vec3::ONE,
        translation: at,
        rotation: shine_along((gem - at).normalize()),
    }
}

/// The brilliant of [`gem_room`] 0.8 m above an open floor under the same spot, seen from
/// above. No closed form: a brilliant sends most of its light back up, so the floor's caustic
/// depends on where every path leaves the gem, which a closed room cannot tell (its walls take
/// the light wherever it goes). Checked against the reference.
pub fn gem_floor() -> SceneDesc {
    let eye = Vec3::new(0.0, 4.0, 3.0);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::ZERO),
        fov_y: 60f32.to_radians(),
    };
    let mut s = SceneDesc::new("gem_floor", cam);
    let grey = s.material("floor", diffuse(0.8), false);
    let g = s.material("glass", glass(2.4, 1.0), false);
    s.add("floor", geometry::quad(20.0, 20.0), grey, Vec3::ZERO);
    let at = Vec3::new(0.0, 0.8, 0.0);
    s.add("gem", geometry::brilliant(0.5), g, at);
    s.lights.push(gem_spot(at));
    s
}

/// A smooth ball (radius 0.5 m, IOR 4.0: 36 % reflected at normal incidence) in a closed room
/// lit by a point light.
pub fn ball_room() -> SceneDesc {
    room_scene(
        "ball_room",
        geometry::uv_sphere(0.5, 64, 32),
        4.0,
        LightDesc {
            name: "bulb".into(),
            kind: LightKind::Point { candela: 20_000.0 },
            color: Vec3::ONE,
            translation: CASTER_AT + Vec3::new(-0.6, 1.3, 0.4),
            rotation: glam::Quat::IDENTITY,
        },
    )
}

/// Thickness of [`absorbing_slab`], metres.
pub const ABSORBING_THICKNESS: f32 = 0.2;
/// Colour [`absorbing_slab`] keeps after [`ABSORBING_DISTANCE`] metres.
pub const ABSORBING_COLOR: Vec3 = Vec3::new(0.3, 0.6, 0.9);
/// Attenuation distance of [`absorbing_slab`], metres.
pub const ABSORBING_DISTANCE: f32 = 0.25;
/// IOR of [`absorbing_slab`].
pub const ABSORBING_IOR: f32 = 1.5;

/// A 1 x 0.2 x 1 m slab of coloured glass (IOR 1.5, Beer-Lambert) at y in [0.9, 1.1] under a
/// vertical sun of [`SUN_LUX`] over a floor.
pub fn absorbing_slab() -> SceneDesc {
    let eye = Vec3::new(0.6, 3.0, 3.0);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::new(0.0, 0.0, 0.0)),
        fov_y: 45f32.to_radians(),
    };
    let mut s = SceneDesc::new("absorbing_slab", cam);
    let grey = s.material("floor", diffuse(0.8), false);
    let g = s.material(
        "coloured_glass",
        MaterialParams {
            attenuation_color: ABSORBING_COLOR,
            attenuation_distance: ABSORBING_DISTANCE,
            ..glass(ABSORBING_IOR, ABSORBING_THICKNESS)
        },
        false,
    );
    s.add("floor", geometry::quad(10.0, 10.0), grey, Vec3::ZERO);
    s.add(
        "slab",
        geometry::cuboid(Vec3::new(1.0, ABSORBING_THICKNESS, 1.0)),
        g,
        Vec3::new(0.0, 1.0, 0.0),
    );
    s.lights.push(LightDesc {
        name: "sun".into(),
        kind: LightKind::Directional { lux: SUN_LUX },
        color: Vec3::ONE,
        translation: Vec3::new(0.0, 4.0, 0.0),
        rotation: shine_along(Vec3::NEG_Y),
    });
    s
}

/// The power the floor receives under [`absorbing_slab`], per channel (lm): the slab's top
/// face (1 m²) at [`SUN_LUX`], Fresnel `R` at normal incidence on each face, internal
/// transmittance `T = c^(t / d)` per crossing, and every even number of internal reflections:
/// `E A (1 - R)^2 T / (1 - R^2 T^2)`.
pub fn absorbing_slab_power() -> Vec3 {
    let r = crate::optics::fresnel_dielectric(1.0, 1.0 / ABSORBING_IOR);
    let t = crate::optics::beer_lambert(ABSORBING_COLOR, ABSORBING_DISTANCE, ABSORBING_THICKNESS);
    SUN_LUX * (1.0 - r) * (1.0 - r) * t / (Vec3::ONE - r * r * t * t)
}

/// IOR of [`thin_pane`] and [`thin_shell`].
pub const THIN_IOR: f32 = 1.5;

/// A 1 x 1 m single-sided pane of thin-walled glass (IOR [`THIN_IOR`], thickness 0: glTF
/// transmission without a volume) 1 m above a floor, under a sun of [`SUN_LUX`] at
/// `incidence` radians from the pane's normal, travelling along +X as it descends. With
/// `from_back` the pane is turned over (normal -Y), so the sun strikes its back face. Either
/// way the floor receives `E cos(incidence) (1 - R)` over the pane's shadow, centred at
/// `x = tan(incidence)`, with `R` the air-to-glass Fresnel reflectance: a thin wall has air on
/// both sides and never totally reflects (beyond 41.8 degrees the back face used to).
pub fn thin_pane(incidence: f32, from_back: bool) -> SceneDesc {
    let x = incidence.tan();
    let eye = Vec3::new(x, 3.0, 3.0);
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::new(x, 0.0, 0.0)),
        fov_y: 45f32.to_radians(),
    };
    let name = if from_back {
        "thin_pane_back"
    } else {
        "thin_pane"
    };
    let mut s = SceneDesc::new(name, cam);
    let grey = s.material("floor", diffuse(0.8), false);
    let g = s.material("thin_glass", glass(THIN_IOR, 0.0), false);
    s.add("floor", geometry::quad(12.0, 12.0), grey, Vec3::ZERO);
    let pane = s.add(
        "pane",
        geometry::quad(1.0, 1.0),
        g,
        Vec3::new(0.0, 1.0, 0.0),
    );
    if from_back {
        s.nodes[pane].rotation = glam::Quat::from_rotation_x(core::f32::consts::PI);
    }
    s.lights.push(LightDesc {
        name: "sun".into(),
        kind: LightKind::Directional { lux: SUN_LUX },
        color: Vec3::ONE,
        translation: Vec3::new(-2.0, 4.0, 0.0),
        rotation: shine_along(Vec3::new(incidence.sin(), -incidence.cos(), 0.0)),
    });
    s
}

/// The ball of [`super::glass_sphere`] as a closed shell of thin-walled glass (IOR
/// [`THIN_IOR`], thickness 0) under the same vertical sun: light crossing it passes both walls
/// unbent, `(1 - R)^2` of it at the incidence of its chord (the same at both walls), and light
/// reflected inside meets the walls at that incidence again and leaves, never trapped by total
/// internal reflection.
pub fn thin_shell() -> SceneDesc {
    let mut s = super::glass_sphere();
    s.name = "thin_shell".into();
    s.materials[1].name = "thin_glass".into();
    s.materials[1].params = glass(THIN_IOR, 0.0);
    s
}

/// Part counts of the trace-cost benchmark (`examples/gpu_timings.rs --parts`).
pub const PARTS: [usize; 3] = [1, 10, 30];

/// `n` glass parts (1 to 30) on a 6 x 5 grid 1.2 m up, lit by a bulb under the ceiling: the
/// scene of the trace-cost benchmark (issue 32 item 1: the cost follows the budget, not the
/// asset's chains of internal reflections). The parts cycle through a brilliant-cut gem
/// (IOR 2.4, dozens of internal reflections), a thick glass ball (IOR 1.5) and a thin-walled
/// shell (glTF thickness 0). `closed`: inside the closed room of receivers, where no light
/// leaves (every path ends on a wall, the cap or the budget); otherwise over an open floor.
pub fn glass_parts(n: usize, closed: bool) -> SceneDesc {
    let name = format!("glass_parts_{n}_{}", if closed { "room" } else { "open" });
    let eye = Vec3::new(2.4, 2.7, 2.4) * if closed { 0.7 } else { 1.0 };
    let cam = CameraDesc {
        translation: eye,
        rotation: look_at(eye, Vec3::new(0.0, 0.6, 0.0)),
        fov_y: 70f32.to_radians(),
    };
    let mut s = SceneDesc::new(&name, cam);
    let walls = s.material("walls", diffuse(0.8), false);
    if closed {
        s.add("room", geometry::room(ROOM), walls, Vec3::ZERO);
    } else {
        s.add("floor", geometry::quad(20.0, 20.0), walls, Vec3::ZERO);
    }
    let gem = s.material("gem", glass(2.4, 1.0), false);
    let ball = s.material("glass", glass(1.5, 1.0), false);
    let shell = s.material("thin_glass", glass(THIN_IOR, 0.0), false);
    for i in 0..n.clamp(1, 30) {
        let at = Vec3::new(
            (i % 6) as f32 * 0.6 - 1.5,
            CASTER_AT.y,
            (i / 6) as f32 * 0.6 - 1.2,
        );
        let (mesh, material) = match i % 3 {
            0 => (geometry::brilliant(0.2), gem),
            1 => (geometry::uv_sphere(0.2, 24, 12), ball),
            _ => (geometry::uv_sphere(0.2, 24, 12), shell),
        };
        s.add(&format!("part_{i}"), mesh, material, at);
    }
    s.lights.push(LightDesc {
        name: "bulb".into(),
        kind: LightKind::Point { candela: 20_000.0 },
        color: Vec3::ONE,
        translation: Vec3::new(0.1, ROOM.y - 0.3, 0.2),
        rotation: glam::Quat::IDENTITY,
    });
    s
}
