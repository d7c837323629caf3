//! Thin-walled glass on the GPU (issue 32 item 2): glTF transmission without a volume
//! (thickness 0) has air on both sides, so it reflects the air-to-glass Fresnel `R` from either
//! side, passes `1 - R` straight through and never totally reflects. One scene per technique
//! holds the three cases far apart under one sun at 60 degrees from the vertical (beyond the
//! thick case's critical angle, 41.8 degrees at IOR 1.5, where the back face used to reflect
//! everything): the pane of `closed::thin_pane` lit on its front face, the same pane turned
//! over (lit on its back face), and the closed shell of `closed::thin_shell`. Each casts its
//! shadow on the floor at x = 0, the three shadows along z, seen from above; the
//! floor under each is measured against its closed form (`tests/cpu/thin.rs` holds the CPU
//! reference to the same ones).

use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::optics::{PixelFocal, dielectric_eta, fresnel_dielectric, luminance};
use bevy_caustics::reference::CausticImage;
use bevy_caustics::scenes::{self, SceneDesc, closed};
use bevy_caustics::{CausticsTechnique, CausticsVolume, ImageSpaceSettings, PhotonMapSettings};
use glam::Vec3;

use super::{GPU, require_gpu};

/// The sun's angle from the vertical (the panes' normal), degrees.
const INCIDENCE_DEG: f32 = 60.0;
/// Centre of the shadows on the floor (x = 0, y = 0) along z: front pane, back pane, shell.
const SHADOW_Z: [f32; 3] = [-1.4, 0.0, 1.5];
/// Half side of the square measured under each pane (its shadow is 1 x 1 m): 15 cm (3 pixels)
/// inside the shadow's edges, clear of the techniques' splat, gather and filter footprints.
const PANE_HALF: f32 = 0.35;
/// The shell is measured where the light crossed it at most this far from its axis (fraction of
/// its radius): the smooth middle of its shadow, far from the grazing rim and the polygonal
/// silhouette.
const SHELL_AXIS: f32 = 0.6;
/// Target (the long side along z, the three shadows).
const WIDTH: u32 = 40;
const HEIGHT: u32 = 96;

fn sun_travel() -> Vec3 {
    let a = INCIDENCE_DEG.to_radians();
    Vec3::new(a.sin(), -a.cos(), 0.0)
}

/// Where the caster must sit (its centre at height `h`) for its shadow to be centred at
/// (0, 0, z).
fn above_shadow(h: f32, z: f32) -> Vec3 {
    Vec3::new(-INCIDENCE_DEG.to_radians().tan() * h, h, z)
}

/// The three cases in one scene: `closed::thin_pane` (floor, pane, sun), the pane of
/// `closed::thin_pane(.., true)` (turned over) and the ball of `closed::thin_shell`, each
/// moved above its shadow; the camera 5 m above the middle, looking down.
fn thin_scene() -> SceneDesc {
    let a = INCIDENCE_DEG.to_radians();
    let mut s = closed::thin_pane(a, false);
    s.name = "thin_trio".into();
    let glass = s
        .materials
        .iter()
        .position(|m| m.name == "thin_glass")
        .unwrap();
    let node = |d: &SceneDesc, name: &str| d.nodes.iter().find(|n| n.name == name).unwrap().clone();
    let front = s.nodes.iter().position(|n| n.name == "pane").unwrap();
    s.nodes[front].translation = above_shadow(1.0, SHADOW_Z[0]);
    let back_desc = closed::thin_pane(a, true);
    let shell_desc = closed::thin_shell();
    for (desc, name, at) in [
        (&back_desc, "pane", above_shadow(1.0, SHADOW_Z[1])),
        (&shell_desc, "ball", shell_centre()),
    ] {
        let mut n = node(desc, name);
        assert!(desc.materials[n.material].params.thickness == 0.0);
        s.meshes.push(desc.meshes[n.mesh].clone());
        n.mesh = s.meshes.len() - 1;
        n.material = glass;
        n.name = format!("{name}_{}", s.nodes.len());
        n.translation = at;
        s.nodes.push(n);
    }
    // Tilted 11 degrees from straight down: caustics volumes draw nothing for a camera looking
    // exactly along -Y (an open question, not a thin-wall one).
    let eye = Vec3::new(0.0, 5.0, 1.0);
    s.camera = scenes::CameraDesc {
        translation: eye,
        rotation: scenes::look_at(eye, Vec3::new(0.0, 0.0, 0.05)),
        fov_y: 45f32.to_radians(),
    };
    s
}

/// Centre of the shell (the ball of `glass_sphere`, 1 m up).
fn shell_centre() -> Vec3 {
    above_shadow(1.0, SHADOW_Z[2])
}

/// The closed form of the floor's caustic irradiance at floor point `p` for case `k` (0 front
/// pane, 1 back pane, 2 shell), or `None` outside the region measured. Panes: `E cos θ (1 - R)`.
/// Shell: `E cos θ (1 - R)^2`, `R` at the incidence of the chord through `p` along the sun (the
/// same at both walls).
fn closed_form(k: usize, p: Vec3) -> Option<f32> {
    let a = INCIDENCE_DEG.to_radians();
    let e = scenes::SUN_LUX * a.cos();
    if k < 2 {
        let inside = p.x.abs() < PANE_HALF && (p.z - SHADOW_Z[k]).abs() < PANE_HALF;
        let r = fresnel_dielectric(a.cos(), dielectric_eta(closed::THIN_IOR, true, true));
        return inside.then_some(e * (1.0 - r));
    }
    let d = sun_travel();
    let w = p - shell_centre();
    let b = (w - w.dot(d) * d).length() / scenes::SPHERE_RADIUS;
    (b < SHELL_AXIS).then(|| {
        let r = fresnel_dielectric(
            (1.0 - b * b).sqrt(),
            dielectric_eta(closed::THIN_IOR, true, true),
        );
        e * (1.0 - r) * (1.0 - r)
    })
}

/// The mean irradiance (lux) the shell's paths with internal reflections add over its region:
/// the sphere traced exactly (no mesh) over a 1 mm grid across the sun's beam, each path
/// entering, reflecting `k` = 1 to 4 times inside (the same incidence at every wall of a
/// sphere) and leaving with `(1 - R)^2 R^k` of its light, the power landing in the region over
/// the region's area. Near the rim, `R` nears 1 and a path reflected once inside turns down
/// across the shadow: about 1.3 % of its middle (the CPU reference agrees).
fn shell_reflected_mean() -> f32 {
    let (d, c, r) = (sun_travel(), shell_centre(), scenes::SPHERE_RADIUS);
    let (u, v) = (Vec3::Z, sun_travel().cross(Vec3::Z).normalize());
    let eta = dielectric_eta(closed::THIN_IOR, true, true);
    let n = 1000;
    let cell = 2.0 * r / n as f32;
    let mut power = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let off = u * ((i as f32 + 0.5) * cell - r) + v * ((j as f32 + 0.5) * cell - r);
            let b = off.length();
            if b >= r {
                continue;
            }
            let h = (r * r - b * b).sqrt();
            let rf = fresnel_dielectric(h / r, eta) as f64;
            let (mut p, mut dir) = (c + off - d * h, d);
            // To the far wall, then k reflections, each followed by the chord to the next wall.
            p += dir * (-2.0 * (p - c).dot(dir));
            for k in 1..=4 {
                let nrm = (p - c) / r;
                dir = (dir - 2.0 * dir.dot(nrm) * nrm).normalize();
                p += dir * (-2.0 * (p - c).dot(dir));
                if dir.y < 0.0 && closed_form(2, p - dir * (p.y / dir.y)).is_some() {
                    power += (1.0 - rf) * (1.0 - rf) * rf.powi(k) * (cell * cell) as f64;
                }
            }
        }
    }
    let area = core::f32::consts::PI * (SHELL_AXIS * r).powi(2) / -d.y;
    (power * scenes::SUN_LUX as f64 / area as f64) as f32
}

/// Per case: the mean caustic irradiance (luminance, lux) over the pixels that see the floor in
/// its region, the closed form's mean over the same pixels, and their count.
fn measure(img: &CausticImage, desc: &SceneDesc) -> [(f32, f32, usize); 3] {
    let (_, _, cam) = desc.to_trace(WIDTH, HEIGHT);
    let focal = PixelFocal::from_fov_y(desc.camera.fov_y, WIDTH, HEIGHT);
    let eye = cam.position();
    let mut sums = [(0.0f64, 0.0f64, 0usize); 3];
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let local = Vec3::new(
                (x as f32 + 0.5 - 0.5 * WIDTH as f32) / focal.fx,
                -(y as f32 + 0.5 - 0.5 * HEIGHT as f32) / focal.fy,
                -1.0,
            );
            let dir = cam.world_from_view.transform_vector3(local).normalize();
            let p = eye - dir * (eye.y / dir.y);
            for (k, s) in sums.iter_mut().enumerate() {
                if let Some(expect) = closed_form(k, p) {
                    s.0 += luminance(img.get(x, y)) as f64;
                    s.1 += expect as f64;
                    s.2 += 1;
                }
            }
        }
    }
    let mut out = sums.map(|(m, e, n)| ((m / n as f64) as f32, (e / n as f64) as f32, n));
    out[2].1 += shell_reflected_mean();
    out
}

const CASES: [&str; 3] = ["pane 60° front", "pane 60° back", "shell"];

fn render(technique: CausticsTechnique, job: RenderJob) -> (RenderReport, [f32; 3]) {
    let dir = std::env::temp_dir().join(format!("bevy_caustics_thin_{}", std::process::id()));
    let desc = thin_scene();
    scenes::gltf::write_gltf(&desc, &dir).unwrap();
    let t = std::time::Instant::now();
    let report = run(RenderJob {
        scene: dir.join("thin_trio.gltf"),
        technique,
        width: WIDTH,
        height: HEIGHT,
        ..job
    })
    .unwrap_or_else(|e| panic!("{technique:?}: {e}"));
    let img = report.caustics.as_ref().expect("caustics");
    assert!(img.all_finite(), "{technique:?}: non-finite caustics");
    let mut errs = [0.0; 3];
    for (k, (mean, expect, px)) in measure(img, &desc).into_iter().enumerate() {
        errs[k] = mean / expect - 1.0;
        println!(
            "{technique:?} {}: floor {mean:.1} lx over {px} px vs {expect:.1} lx ({:+.2} %)",
            CASES[k],
            errs[k] * 100.0
        );
        assert!(px > 200, "{technique:?} {}: {px} px", CASES[k]);
    }
    println!("{technique:?}: {:.1} s", t.elapsed().as_secs_f64());
    (report, errs)
}

fn assert_within(technique: &str, errs: [f32; 3], tol: [f32; 3]) {
    for k in 0..3 {
        assert!(
            errs[k].abs() < tol[k],
            "{technique} {}: {:+.2} % (tolerance {} %)",
            CASES[k],
            errs[k] * 100.0,
            tol[k] * 100.0
        );
    }
}

/// AAPS (2^18 photons a frame, 4 frames): the floor under each case within 2 % of its closed
/// form (measured +0.02, +0.36, -0.15 %; the CPU reference -0.4, +0.2, -0.3 %: noise of about
/// 30 000 photons a region, and the pixels' quantisation of the regions), and no photon totally
/// reflected or at the bounce cap. Under the old back-face rule the back pane passed nothing.
#[test]
fn aaps_thin_walls_closed_form() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let (report, errs) = render(
        CausticsTechnique::Aaps,
        RenderJob {
            photons: Some(1 << 18),
            frames: 4,
            ..Default::default()
        },
    );
    let c = report.aaps.expect("AAPS counters");
    println!("AAPS counters: {c:?}");
    assert_eq!((c.tir, c.max_depth, c.nan_guards), (0, 0, 0), "{c:?}");
    assert_within("AAPS", errs, [0.02; 3]);
}

/// The photon map (2^18 photons a frame, 4 frames): the floor under each case within 2 % of its
/// closed form (measured +0.18, +0.65, -0.08 %: the same noise as AAPS, and the gather's
/// kernel), and no photon totally reflected or at the bounce cap.
#[test]
fn photon_map_thin_walls_closed_form() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let (report, errs) = render(
        CausticsTechnique::PhotonMap,
        RenderJob {
            photons: Some(1 << 18),
            frames: 4,
            photon_map: PhotonMapSettings::default(),
            ..Default::default()
        },
    );
    let c = report.photon_map.expect("photon map counters");
    println!("photon map counters: {c:?}");
    assert_eq!((c.tir, c.max_depth, c.nan_guards), (0, 0, 0), "{c:?}");
    assert_within("photon map", errs, [0.02; 3]);
}

/// Image space (2^16 photons a frame, 256² maps, 16 frames, the denoiser on as by default): the
/// floor under each case within 7 % of its closed form, and the shell's floor against the front
/// pane's within 2.5 % of the closed forms' ratio; no photon totally reflected. The 7 %: SVGF's
/// à-trous filter (up to 64 pixels wide) spreads the shadows' sharp edges, 1 m = 20 pixels
/// here, over the dark floor around them and lowers their middles alike: measured -4.7, -3.4,
/// -4.1 % (-3.5, -3.5, -3.9 % with 512² maps; without the denoiser one raw frame of 2^18
/// photons reads -2.4, +2.3, -1.2 %). The ratio cancels that common loss (measured +0.5 %):
/// a shell whose far wall passed everything would read +4.5 %, a back pane that is not lit -100 %.
#[test]
fn image_space_thin_walls_closed_form() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let (report, errs) = render(
        CausticsTechnique::ImageSpace,
        RenderJob {
            photons: Some(1 << 16),
            frames: 16,
            image_space: ImageSpaceSettings {
                rsm_resolution: 256,
                ..Default::default()
            },
            ..Default::default()
        },
    );
    let c = report.image_space.expect("image-space counters");
    println!("image-space counters: {c:?}");
    assert_eq!((c.tir, c.nan_guards), (0, 0), "{c:?}");
    assert_within("image space", errs, [0.07; 3]);
    let ratio = (1.0 + errs[2]) / (1.0 + errs[0]) - 1.0;
    println!(
        "image space: shell against front pane {:+.2} %",
        ratio * 100.0
    );
    assert!(
        ratio.abs() < 0.025,
        "shell against front pane {:+.2} %",
        ratio * 100.0
    );
}

/// Caustics volumes (one fitted around the three casters, 2^17 photons, 200² G-buffers and
/// projectors): the floor under each case within 8 % of its closed form, no photon totally
/// reflected, none left inside a medium, no thin wall ignored (a pane lit on its back and the
/// shell's far wall were: the back pane's floor read -100 %), and no more flux splatted than
/// entered. The 8 %: the volume splats about 4 % less than the flux the other techniques and
/// the reference deposit here (15 700 against 16 400 lm), the front pane's single front-face
/// crossing as much as the rest: measured -5.4, -3.5, -4.1 % (-6.0, -3.8, -4.6 % at 400²), as
/// the closed-form tests hold volumes to 10 %.
#[test]
fn volume_thin_walls_closed_form() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let (report, errs) = render(
        CausticsTechnique::Volume,
        RenderJob {
            frames: 3,
            volume: CausticsVolume {
                photons: 1 << 17,
                gbuffer_resolution: 200,
                projector_resolution: 200,
                ..Default::default()
            },
            ..Default::default()
        },
    );
    let v = report.volume.expect("volume counters");
    println!("volume counters: {v:?}");
    assert_eq!(
        (v.tir, v.nan_guards, v.left_inside, v.ignored),
        (0, 0, 0, 0),
        "{v:?}"
    );
    assert!(v.splatted_lm <= v.entered_lm * (1.0 + 1e-5), "{v:?}");
    assert_within("volume", errs, [0.08; 3]);
}
