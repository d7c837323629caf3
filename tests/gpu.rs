//! GPU tests on whatever Vulkan adapter exists (lavapipe in CI). They never skip: without an
//! adapter they fail (set BEVY_CAUSTICS_ALLOW_NO_GPU=1 to skip on a developer machine).
//! Bevy apps run one at a time (a global lock), each on a small target.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use bevy_caustics::headless::{RenderJob, run};
use support::{GPU, require_gpu};

#[path = "gpu/aaps.rs"]
mod aaps;
#[path = "gpu/energy.rs"]
mod energy;
#[path = "gpu/examples.rs"]
mod examples;
#[path = "gpu/first_use.rs"]
mod first_use;
#[path = "gpu/image_space.rs"]
mod image_space;
#[path = "gpu/many_parts.rs"]
mod many_parts;
#[path = "gpu/motion.rs"]
mod motion;
#[path = "gpu/pay_for_use.rs"]
mod pay_for_use;
#[path = "gpu/per_frame/mod.rs"]
mod per_frame;
#[path = "gpu/photon_map.rs"]
mod photon_map;
#[path = "gpu/stiff.rs"]
mod stiff;
#[path = "gpu/support.rs"]
mod support;
#[path = "gpu/thin.rs"]
mod thin;
#[path = "gpu/twins.rs"]
mod twins;
#[path = "gpu/volume.rs"]
mod volume;

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(format!("{name}.gltf"))
}

/// A closed-form case: scene, receiver plane (n, d with n . p = d), region on it, expected
/// mean caustic irradiance (lux).
type ClosedForm = (
    bevy_caustics::scenes::SceneDesc,
    glam::Vec3,
    f32,
    fn(glam::Vec3) -> bool,
    f32,
);

/// `mirror_wall` (a 0.9 Schlick mirror lighting the wall) and `glass_slab` (IOR 1.5, the
/// floor under the slab, Fresnel in and out): the closed forms the GPU techniques are held to.
fn closed_form_cases() -> [ClosedForm; 2] {
    use bevy_caustics::optics::{fresnel_dielectric, fresnel_schlick};
    use bevy_caustics::scenes;
    use glam::Vec3;
    let a = scenes::MIRROR_WALL_INCIDENCE;
    let mirror = scenes::SUN_LUX * fresnel_schlick(a.cos(), Vec3::splat(0.9)).x * a.sin();
    let b = scenes::GLASS_SLAB_INCIDENCE;
    let r = fresnel_dielectric(b.cos(), 1.0 / 1.5);
    let slab = scenes::SUN_LUX * b.cos() * (1.0 - r) / (1.0 + r);
    [
        (
            scenes::mirror_wall(),
            Vec3::NEG_X,
            -3.0,
            |p| (2.75..3.25).contains(&p.y) && p.z.abs() < 0.25,
            mirror,
        ),
        (
            scenes::glass_slab(),
            Vec3::Y,
            0.0,
            |p| (0.4..0.8).contains(&p.x) && p.z.abs() < 0.3,
            slab,
        ),
    ]
}

/// `glass_sphere` with its light made a spot aimed away from every caster, written as glTF
/// under `dir`: the path. No technique may dispatch a pass for it.
fn spot_away_scene(dir: &Path) -> PathBuf {
    use bevy_caustics::scenes;
    let mut away = scenes::glass_sphere();
    away.name = "spot_away".into();
    away.lights[0].kind = scenes::LightKind::Spot {
        candela: 5000.0,
        inner: 0.2,
        outer: 0.3,
    };
    away.lights[0].translation = glam::Vec3::new(0.0, 3.0, 0.0);
    away.lights[0].rotation = scenes::shine_along(glam::Vec3::Y);
    scenes::gltf::write_gltf(&away, dir).unwrap();
    dir.join("spot_away.gltf")
}

/// The cached CPU reference of scene `name` at 128² (`assets/reference/`).
fn reference(name: &str) -> bevy_caustics::reference::CausticImage {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("assets/reference/{name}_128.exr"));
    bevy_caustics::reference::CausticImage::read_exr(&p).expect("cached reference")
}

/// The caustics image `img` of closed-form case `case` (from [`closed_form_cases`]) at 128²:
/// asserts it is finite and the region covers more than 200 pixels; returns the region's mean
/// irradiance (lux), its pixels and the relative error against the closed form.
fn closed_form_error(
    case: &ClosedForm,
    img: &bevy_caustics::reference::CausticImage,
) -> (f32, usize, f32) {
    let (desc, n, d, region, expect) = case;
    assert!(img.all_finite(), "{}: non-finite caustics", desc.name);
    let (_, _, cam) = desc.to_trace(128, 128);
    let (mean, px) = bevy_caustics::reference::plane_region_mean(img, &cam, *n, *d, region);
    assert!(px > 200, "{}: {px} px in the region", desc.name);
    (mean, px, mean / expect - 1.0)
}

/// The composite adds exactly albedo / π · E · exposure: the frame with caustics minus the
/// same frame from a twin camera without `Caustics` equals that, pixel by pixel, for the
/// known buffer E (the reference image uploaded into the caustics buffer).
#[test]
fn composite_adds_albedo_over_pi_times_irradiance() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let report = run(RenderJob {
        scene: scene("glass_sphere"),
        width: 128,
        height: 128,
        photons: Some(1 << 18),
        frames: 6,
        linear: true,
        ..Default::default()
    })
    .expect("render");
    println!("report: {}", serde_json::to_string(&report).unwrap());
    let e = report.caustics.as_ref().expect("caustics buffer");
    assert_eq!(report.passes, ["caustics/composite"]);
    assert_eq!(report.linear_with.len(), 128 * 128);
    assert_eq!(report.linear_without.len(), 128 * 128);
    let albedo = 0.8f32; // the floor of glass_sphere
    // Pixels where the eye sees the glass first show the screen through refraction (forward
    // transmissive pass), caustics included: the composite's own contribution is checked on the
    // pixels that see the floor directly.
    let (tlas, _, cam) = bevy_caustics::scenes::glass_sphere().to_trace(128, 128);
    let focal = bevy_caustics::optics::PixelFocal::from_fov_y(45f32.to_radians(), 128, 128);
    let sees_floor = |i: usize| {
        let (x, y) = ((i % 128) as f32 + 0.5, (i / 128) as f32 + 0.5);
        let local = glam::Vec3::new((x - 64.0) / focal.fx, -(y - 64.0) / focal.fy, -1.0);
        let d = cam.world_from_view.transform_vector3(local).normalize();
        tlas.closest_hit(cam.position(), d, 0.0, f32::INFINITY, |_| false)
            .is_some_and(|h| !tlas.instances[h.instance as usize].surface.is_specular())
    };
    let (mut checked, mut worst) = (0, 0.0f32);
    for (i, (w, wo)) in report
        .linear_with
        .iter()
        .zip(&report.linear_without)
        .enumerate()
    {
        if !sees_floor(i) {
            continue;
        }
        let expect = albedo / std::f32::consts::PI * e.data[i] * report.exposure;
        for c in 0..3 {
            let got = w[c] - wo[c];
            assert!(w[c].is_finite());
            // f16 target: about 1e-3 relative precision on each of the two frames.
            let tol = 4e-3 * w[c].abs().max(wo[c].abs()) + 1e-4;
            let err = (got - expect[c]).abs();
            assert!(
                err <= tol.max(0.01 * expect[c]),
                "pixel {i} channel {c}: got {got}, expected {}",
                expect[c]
            );
            // Relative error where the caustic is a sizeable part of the pixel (elsewhere the
            // f16 rounding of the lit floor dominates and is covered by `tol`).
            if expect[c] > 0.2 * wo[c].abs() && expect[c] > 0.0 {
                worst = worst.max(err / expect[c]);
            }
        }
        if e.data[i].x > 0.0 {
            checked += 1;
        }
    }
    println!(
        "composite: {checked} caustic pixels checked, worst relative error {worst:.2e}, exposure {}",
        report.exposure
    );
    assert!(checked > 300, "too few caustic pixels: {checked}");
    // Where the caustic is a sizeable part of the pixel, the composite's contribution is exact
    // to the f16 target's rounding (measured 8.0e-3).
    assert!(worst < 0.02, "worst relative error {worst:.2e}");
    println!("composite pass: {:?} ({})", report.pass_ms, report.timing);
}

/// A scene without a caster dispatches no caustics pass and leaves the buffer empty.
#[test]
fn empty_scene_dispatches_nothing() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let report = run(RenderJob {
        scene: scene("empty"),
        width: 64,
        height: 64,
        frames: 6,
        ..Default::default()
    })
    .expect("render");
    assert!(
        report.passes.is_empty(),
        "passes dispatched: {:?}",
        report.passes
    );
    assert_eq!(report.photons_traced, 0);
    assert!(
        report
            .caustics
            .unwrap()
            .data
            .iter()
            .all(|v| *v == glam::Vec3::ZERO)
    );
}

fn render_example() -> PathBuf {
    support::example_exe("render")
}

fn cli(args: &[&str]) -> (i32, String) {
    let deadline = std::time::Duration::from_secs(120);
    let (code, err, _) = first_use::cli_timed(args, Path::new("."), deadline);
    (code.unwrap_or(-1), err)
}

/// The CLI renders, writes its three files, and compares against an EXR; bad input gives one
/// clear line and exit status 2 with nothing written.
#[test]
fn cli_outputs_and_errors() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("bevy_caustics_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |f: &str| dir.join(f).to_string_lossy().into_owned();
    let ring = scene("ring").to_string_lossy().into_owned();
    let (code, err) = cli(&[
        &ring,
        "--technique",
        "reference",
        "--width",
        "64",
        "--height",
        "64",
        "--photons",
        "100000",
        "--frames",
        "5",
        "--out-exr",
        &p("a.exr"),
        "--out-png",
        &p("a.png"),
        "--json",
        &p("a.json"),
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = cli(&[
        &ring,
        "--width",
        "64",
        "--height",
        "64",
        "--photons",
        "100000",
        "--frames",
        "5",
        "--json",
        &p("b.json"),
        "--compare",
        &p("a.exr"),
    ]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("b.json")).unwrap()).unwrap();
    assert!(json["adapter"].as_str().unwrap().len() > 3);
    assert_eq!(json["passes"][0], "caustics/composite");
    assert!(json["photons_traced"].as_u64().unwrap() == 100_000);
    // Same seed, same photons: the comparison is exact.
    assert_eq!(json["metrics"]["rmse"].as_f64(), Some(0.0), "{json}");
    assert!(std::fs::metadata(p("a.png")).unwrap().len() > 100);

    // A glTF without a camera and one without lights.
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(scene("ring")).unwrap()).unwrap();
    std::fs::copy(scene("ring").with_extension("bin"), dir.join("ring.bin")).unwrap();
    let strip = |doc: &serde_json::Value, key: &str| {
        let mut d = doc.clone();
        let nodes: Vec<_> = d["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|n| n.get(key).is_none() && n.pointer(&format!("/extensions/{key}")).is_none())
            .cloned()
            .collect();
        d["scenes"][0]["nodes"] = serde_json::json!((0..nodes.len()).collect::<Vec<_>>());
        d["nodes"] = serde_json::json!(nodes);
        d
    };
    std::fs::write(dir.join("nocam.gltf"), strip(&doc, "camera").to_string()).unwrap();
    std::fs::write(
        dir.join("nolight.gltf"),
        strip(&doc, "KHR_lights_punctual").to_string(),
    )
    .unwrap();
    for (args, needle) in [
        (vec![p("missing.gltf")], "not found"),
        (vec![p("nocam.gltf")], "no camera"),
        (vec![p("nolight.gltf")], "no lights"),
        (
            vec![ring.clone(), "--technique".into(), "raytraced".into()],
            "unknown technique",
        ),
        (
            vec![ring.clone(), "--width".into(), "wide".into()],
            "non-negative integer",
        ),
    ] {
        let out_exr = p("never.exr");
        let mut a: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
        a.extend(["--out-exr", &out_exr]);
        let (code, err) = cli(&a);
        assert_eq!(code, 2, "{args:?}: {err}");
        let last = err
            .lines()
            .filter(|l| l.starts_with("error:"))
            .collect::<Vec<_>>();
        assert_eq!(last.len(), 1, "{args:?}: {err}");
        assert!(last[0].contains(needle), "{args:?}: {err}");
        assert!(
            !dir.join("never.exr").exists(),
            "an output was written on error"
        );
    }
}

/// Invalid component values: each clamped case logs exactly one warning naming the entity and
/// the field, and the scene still renders.
#[test]
fn bad_input_warns_once_and_renders() {
    use bevy::prelude::*;
    use bevy_caustics::{CausticLight, CausticMaterial, CausticsVolume};
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    fn hook(world: &mut World) {
        world.spawn((
            Name::new("bad_volume"),
            CausticsVolume {
                slabs: 0,
                size: Vec3::ZERO,
                photons: -5,
                ..default()
            },
        ));
        let ball = world
            .query::<(Entity, &Name)>()
            .iter(world)
            .find(|(_, n)| n.as_str() == "ball")
            .map(|(e, _)| e)
            .expect("ball");
        world.entity_mut(ball).insert(CausticMaterial::glass(0.5));
        let light = world
            .query_filtered::<Entity, With<DirectionalLight>>()
            .single(world)
            .expect("sun");
        world.entity_mut(light).insert(CausticLight {
            intensity_scale: -3.0,
        });
    }
    let report = run(RenderJob {
        scene: scene("glass_sphere"),
        width: 64,
        height: 64,
        photons: Some(20_000),
        frames: 10,
        hook: Some(hook),
        ..Default::default()
    })
    .expect("render");
    for w in &report.warnings {
        println!("{w}");
    }
    let expect = [
        ("CausticsVolume.size", "bad_volume"),
        ("CausticsVolume.slabs", "bad_volume"),
        ("CausticsVolume.photons", "bad_volume"),
        ("CausticMaterial.ior", "ball"),
        ("CausticLight.intensity_scale", "sun"),
    ];
    assert_eq!(
        report.warnings.len(),
        expect.len(),
        "{:#?}",
        report.warnings
    );
    for (field, who) in expect {
        assert_eq!(
            report
                .warnings
                .iter()
                .filter(|w| w.contains(field) && w.contains(who))
                .count(),
            1,
            "{field} on {who}"
        );
    }
    // It rendered: the frame came back and the buffer is finite (the clamped light scale 0
    // leaves it black).
    assert_eq!(report.frame_rgba8.len(), 64 * 64 * 4);
    assert!(report.caustics.unwrap().all_finite());
}
