//! What a new user meets first (issue 12): the caustic without opting in to deferred
//! rendering, a warning naming each forward-rendered receiver, and the command line's answer to
//! bad files, relative paths and absurd numbers; malformed glTFs refused in one line and a
//! JPEG-textured glTF loaded (issue 32).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::reference::CausticImage;

use super::{GPU, render_example, require_gpu, scene};

/// Light the composite added: Σ over pixels of (frame with caustics − twin without), green,
/// against what it should add, Σ albedo / π · E · exposure (floor albedo 0.8).
fn added_and_expected(r: &RenderReport) -> (f64, f64) {
    let e = r.caustics.as_ref().expect("caustics buffer");
    let added: f64 = r
        .linear_with
        .iter()
        .zip(&r.linear_without)
        .map(|(w, wo)| (w[1] - wo[1]) as f64)
        .sum();
    let expected: f64 = e
        .data
        .iter()
        .map(|v| (0.8 / std::f32::consts::PI * v.y * r.exposure) as f64)
        .sum();
    (added, expected)
}

fn glass_sphere_job(forward: bool) -> RenderJob {
    RenderJob {
        scene: scene("glass_sphere"),
        width: 64,
        height: 64,
        photons: Some(1 << 16),
        frames: 4,
        linear: true,
        forward,
        ..Default::default()
    }
}

/// A minimal app (DefaultPlugins + CausticsPlugin, no `DefaultOpaqueRendererMethod` of its
/// own): the plugin makes deferred the default and the caustic is in the frame. The twin
/// camera without `Caustics` sees the same scene, so the difference is the composite's.
#[test]
fn caustic_without_opting_in_to_deferred() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let r = run(glass_sphere_job(false)).expect("render");
    let (added, expected) = added_and_expected(&r);
    println!("deferred by default: added {added:.4}, expected {expected:.4}");
    assert!(expected > 1.0, "no caustic to composite: {expected}");
    // Pixels that see the floor through the glass (the forward transmissive pass) show the
    // caustic too, those that see the glass hide some: within 10 % (measured -1.8 %).
    assert!(
        (added / expected - 1.0).abs() < 0.10,
        "added {added}, expected {expected}"
    );
    assert!(
        !r.warnings.iter().any(|w| w.contains("rendered forward")),
        "{:?}",
        r.warnings
    );
}

/// The app keeps forward rendering (inserted after the plugin): no caustic can be
/// composited, and the floor is named in one warning.
#[test]
fn forward_receiver_is_named_in_a_warning() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let r = run(glass_sphere_job(true)).expect("render");
    let (added, expected) = added_and_expected(&r);
    println!(
        "forward: added {added:.4}, expected {expected:.4}; {:?}",
        r.warnings
    );
    assert!(expected > 1.0);
    assert!(added.abs() < 0.01 * expected, "added {added}");
    let forward: Vec<_> = r
        .warnings
        .iter()
        .filter(|w| w.contains("rendered forward"))
        .collect();
    assert_eq!(forward.len(), 1, "{:?}", r.warnings);
    assert!(forward[0].contains("floor)"), "{}", forward[0]);
}

/// One run of the command-line renderer with a deadline: (exit code, stderr, seconds). A
/// process killed by a signal (an abort) has no exit code and fails the case.
pub(crate) fn cli_timed(
    args: &[&str],
    cwd: &Path,
    deadline: Duration,
) -> (Option<i32>, String, f64) {
    run_timed(&render_example(), args, cwd, deadline, &[])
}

/// One run of `exe` with a deadline and extra environment, without a display: (exit code,
/// stderr, seconds).
fn run_timed(
    exe: &Path,
    args: &[&str],
    cwd: &Path,
    deadline: Duration,
    env: &[(&str, &str)],
) -> (Option<i32>, String, f64) {
    let start = Instant::now();
    let mut child = Command::new(exe)
        .args(args)
        .current_dir(cwd)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("RUST_LOG")
        .envs(env.iter().copied())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("run {} (build the examples first): {e}", exe.display()));
    loop {
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        if start.elapsed() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} ran past {deadline:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().expect("output");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code(), err, start.elapsed().as_secs_f64())
}

/// The edge cases of the command line: each is refused with one `error:` line naming what was
/// wrong and exit status 2, or renders (exit 0), never a signal, never past its deadline
/// (refusals 20 s, renders 90 s; the times are printed).
#[test]
fn cli_edge_cases() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("bevy_caustics_edge_{}", std::process::id()));
    let sub = dir.join("sub");
    std::fs::create_dir_all(&sub).unwrap();
    let ring = scene("ring");
    let text = std::fs::read_to_string(&ring).unwrap();
    std::fs::copy(&ring, dir.join("ring.gltf")).unwrap();
    std::fs::copy(ring.with_extension("bin"), dir.join("ring.bin")).unwrap();
    std::fs::write(
        dir.join("garbage.gltf"),
        [0x9fu8, 0x00, 0xff, 0x13, 0x37].repeat(50),
    )
    .unwrap();
    std::fs::write(dir.join("truncated.gltf"), &text[..text.len() / 2]).unwrap();
    // The same document in a folder without its buffer file.
    std::fs::write(sub.join("nobuffer.gltf"), &text).unwrap();

    enum Want {
        Refused(&'static str),
        Renders,
    }
    use Want::*;
    let small = ["--width", "32", "--height", "32", "--frames", "1"];
    let mut cases: Vec<(String, Vec<String>, &Path, Want)> = vec![
        (
            "garbage file".into(),
            vec!["garbage.gltf".into()],
            &dir,
            Refused("garbage.gltf"),
        ),
        (
            "truncated glTF".into(),
            vec!["truncated.gltf".into()],
            &dir,
            Refused("truncated.gltf"),
        ),
        (
            "missing buffer".into(),
            vec!["nobuffer.gltf".into()],
            &sub,
            Refused("nobuffer.gltf"),
        ),
        (
            "missing file".into(),
            vec!["absent.gltf".into()],
            &dir,
            Refused("absent.gltf"),
        ),
        (
            "file name in its folder".into(),
            vec!["ring.gltf".into()],
            &dir,
            Renders,
        ),
        (
            "relative path from another folder".into(),
            vec!["../ring.gltf".into()],
            &sub,
            Renders,
        ),
        (
            "--frames 0".into(),
            vec!["ring.gltf".into(), "--frames".into(), "0".into()],
            &dir,
            Refused("--frames 0"),
        ),
        (
            "--frames 1e9".into(),
            vec!["ring.gltf".into(), "--frames".into(), "1000000000".into()],
            &dir,
            Refused("--frames 1000000000"),
        ),
    ];
    for t in ["reference", "aaps", "volume"] {
        let with = |extra: &[&str]| {
            let mut a = vec!["ring.gltf".to_string(), "--technique".into(), t.into()];
            a.extend(extra.iter().map(|s| s.to_string()));
            a
        };
        cases.push((
            format!("{t} --photons 0"),
            with(&["--photons", "0"]),
            &dir,
            Renders,
        ));
        cases.push((
            format!("{t} --photons 1"),
            with(&["--photons", "1"]),
            &dir,
            Renders,
        ));
        cases.push((
            format!("{t} --photons 1e14"),
            with(&["--photons", "99999999999999"]),
            &dir,
            Refused("--photons 99999999999999"),
        ));
        cases.push((
            format!("{t} --width 0"),
            with(&["--width", "0"]),
            &dir,
            Refused("image size 0x"),
        ));
        cases.push((
            format!("{t} --height 1e5"),
            with(&["--height", "100000"]),
            &dir,
            Refused("outside 1..="),
        ));
    }
    // Settings that size memory or work: (technique, field=value, the field the line names).
    for (technique, field, named) in [
        ("aaps", "splat_capacity=1e9", "splat_capacity"),
        ("aaps", "atlas_resolution=1e5", "atlas_resolution"),
        ("volume", "gbuffer_resolution=1e5", "gbuffer_resolution"),
        ("volume", "slabs=0", "slabs"),
        ("volume", "photons=1e14", "photons"),
    ] {
        let option = format!("--{technique}");
        let a = vec![
            "ring.gltf".into(),
            "--technique".into(),
            technique.into(),
            option.clone(),
            field.into(),
        ];
        let needle: &'static str = format!("{option} {named}").leak();
        cases.push((format!("{option} {field}"), a, &dir, Refused(needle)));
    }
    let mut failures = Vec::new();
    for (name, args, cwd, want) in &cases {
        let mut a: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
        // Small renders; a later --width/--height/--frames of the case wins over these.
        let mut full: Vec<&str> = vec![a.remove(0)];
        full.extend(small);
        full.extend(a);
        let out = PathBuf::from(cwd).join("never.exr");
        let _ = std::fs::remove_file(&out);
        let out_s = out.to_string_lossy().into_owned();
        full.extend(["--out-exr", &out_s]);
        // Deadlines against a hang, with room for a cold shader cache and a second test's
        // app beside this one (a 20 s deadline killed a refusal in the clean-clone run).
        let deadline = Duration::from_secs(match want {
            Refused(_) => 60,
            Renders => 120,
        });
        let (code, err, secs) = cli_timed(&full, cwd, deadline);
        let errors: Vec<_> = err.lines().filter(|l| l.starts_with("error:")).collect();
        println!("{name}: exit {code:?} in {secs:.1} s: {errors:?}");
        let ok = match want {
            Refused(needle) => {
                code == Some(2) && errors.len() == 1 && errors[0].contains(needle) && !out.exists()
            }
            Renders => code == Some(0) && errors.is_empty() && out.exists(),
        };
        if !ok {
            failures.push(format!("{name}: exit {code:?}\n{err}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n---\n"));
}

/// Malformed glTFs (issue 32), one per class in `assets/malformed/`: a JSON value of the wrong
/// type, an accessor index out of range (the `gltf` crate panics), infinite positions, a
/// missing buffer file, an unknown extension and Draco compression in `extensionsRequired`
/// (each named in the line, Draco with its remedy), a node that is its own child, a node
/// cycle, no scene. The CLI refuses each with exit status 2 and one stderr line
/// naming the file (no asset-server ERROR, doubled, with a backtrace; no panic message), or
/// renders it with finite output; the glTF viewer refuses as the CLI does. With the tools'
/// default log (`headless::tool_log_plugin`: warnings and errors, no start-up INFO lines, no
/// "software rendering" warning), that line is the whole of stderr. Tiny renders, about 1 s a
/// refusal on lavapipe.
#[test]
fn malformed_files_are_refused_in_one_line() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/malformed");
    let out = std::env::temp_dir().join(format!("bevy_caustics_malformed_{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".gltf"))
        .collect();
    files.sort();
    assert!(files.len() >= 9, "{files:?}");
    let quiet: [(&str, &str); 0] = [];
    // Against a hang (see cli_edge_cases).
    let deadline = Duration::from_secs(60);
    // One line naming the file, nothing else (a refusal).
    let refused = |name: &str, code: Option<i32>, err: &str| {
        let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
        code == Some(2)
            && lines.len() == 1
            && lines[0].starts_with("error:")
            && lines[0].contains(name)
    };
    // A file that requires an extension the loader does not read is told by its name (not by
    // "Missing data" for every accessor it compresses), with the remedy where there is one.
    let names_extension = |name: &str, err: &str| match name {
        "unknown_required_extension.gltf" => {
            err.contains("requires glTF extension EXT_bevy_caustics_unknown that")
        }
        "draco_compressed.gltf" => {
            err.contains("requires glTF extension KHR_draco_mesh_compression that")
                && err.contains("gltf-transform/cli copy")
        }
        _ => true,
    };
    let mut failures = Vec::new();
    for name in &files {
        let exr = out.join(format!("{name}.exr"));
        let _ = std::fs::remove_file(&exr);
        let exr_s = exr.to_string_lossy().into_owned();
        let args = [
            name.as_str(),
            "--width",
            "32",
            "--height",
            "24",
            "--frames",
            "1",
            "--photons",
            "1000",
            "--out-exr",
            &exr_s,
        ];
        let (code, err, secs) = run_timed(&render_example(), &args, &dir, deadline, &quiet);
        let ok = match code {
            Some(0) => {
                let finite = CausticImage::read_exr(&exr)
                    .is_ok_and(|img| img.data.iter().all(|v| v.is_finite()));
                println!("{name}: rendered in {secs:.1} s, finite: {finite}");
                finite && !err.contains("ERROR") && !err.contains("panicked")
            }
            _ => {
                println!("{name}: exit {code:?} in {secs:.1} s: {}", err.trim_end());
                refused(name, code, &err) && !exr.exists() && names_extension(name, &err)
            }
        };
        if !ok {
            failures.push(format!("{name}: exit {code:?}\n{err}"));
        }
    }
    // The glTF viewer, offscreen, on a file the parser refuses and one whose loader panics.
    let viewer = super::support::example_exe("gltf_viewer");
    for name in ["wrong_type.gltf", "accessor_out_of_range.gltf"] {
        let env = [
            ("CAUSTICS_EXAMPLE_OUT", out.to_str().unwrap()),
            ("CAUSTICS_EXAMPLE_SIZE", "32x24"),
            ("CAUSTICS_EXAMPLE_FRAMES", "1"),
        ];
        let (code, err, secs) = run_timed(&viewer, &[name], &dir, deadline, &env);
        println!(
            "gltf_viewer {name}: exit {code:?} in {secs:.1} s: {}",
            err.trim_end()
        );
        if !refused(name, code, &err) {
            failures.push(format!("gltf_viewer {name}: exit {code:?}\n{err}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n---\n"));
}

/// A glTF with a JPEG base-colour texture in a file beside it (the examples' and tests' Bevy
/// has the `jpeg` feature) loads in the CLI: no error, finite caustics, and the floor shows
/// the texture's green and white checker (a texture that failed to load leaves the floor
/// grey, or the frame black).
#[test]
fn jpeg_textured_gltf_loads_in_the_cli() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textured");
    let out = std::env::temp_dir().join(format!("bevy_caustics_jpeg_{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let (exr, png) = (out.join("jpeg.exr"), out.join("jpeg.png"));
    let (exr_s, png_s) = (exr.to_string_lossy(), png.to_string_lossy());
    let args = [
        "jpeg_floor.gltf",
        "--width",
        "32",
        "--height",
        "24",
        "--frames",
        "1",
        "--photons",
        "1000",
        "--ev100",
        "13",
        "--out-exr",
        &exr_s,
        "--out-png",
        &png_s,
    ];
    let (code, err, secs) = run_timed(
        &render_example(),
        &args,
        &dir,
        Duration::from_secs(90),
        &[("RUST_LOG", "error")],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("ERROR"), "{err}");
    let caustics = CausticImage::read_exr(&exr).expect("caustics EXR");
    assert!(caustics.data.iter().all(|v| v.is_finite()));
    let frame = image::open(&png).expect("frame PNG").to_rgb8();
    let n = (frame.width() * frame.height()) as f64;
    let mean: Vec<f64> = (0..3)
        .map(|c| frame.pixels().map(|p| p.0[c] as f64).sum::<f64>() / n)
        .collect();
    println!("jpeg_floor: {secs:.1} s, mean frame RGB {mean:.1?}");
    assert!(mean[1] > 20.0, "the frame is black: {mean:?}");
    assert!(
        mean[1] > 1.25 * mean[0] && mean[1] > 1.25 * mean[2],
        "no green texture on the floor: {mean:?}"
    );
}

/// A shader that does not compile fails the render with one line naming the pipeline (it
/// rendered on without it, and the command line exited 0 with empty caustics): the hook
/// breaks every AAPS shader as a WGSL error in our code would (`set` is a reserved word).
#[test]
fn a_shader_that_does_not_compile_fails_the_render() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    fn break_aaps_shaders(world: &mut bevy::prelude::World) {
        use bevy::shader::{Shader, Source};
        let mut shaders = world.resource_mut::<bevy::prelude::Assets<Shader>>();
        let ours: Vec<_> = shaders
            .iter()
            .filter(|(_, s)| s.path.contains("aaps"))
            .map(|(id, _)| id)
            .collect();
        assert!(!ours.is_empty(), "no AAPS shader to break");
        for id in ours {
            let mut shader = shaders.get_mut(id).unwrap();
            if let Source::Wgsl(code) = &mut shader.source {
                *code =
                    format!("{code}\nfn broken() -> u32 {{ let set = 1u; return set; }}\n").into();
            }
        }
    }
    let job = RenderJob {
        technique: bevy_caustics::CausticsTechnique::Aaps,
        width: 32,
        height: 32,
        hook: Some(break_aaps_shaders),
        ..glass_sphere_job(true)
    };
    let Err(e) = run(job) else {
        panic!("the render succeeded without its AAPS pipelines");
    };
    println!("{e}");
    assert!(
        e.contains("could not be built") && e.contains("aaps"),
        "{e}"
    );
    assert!(e.contains("reserved"), "the compiler's message: {e}");
    assert_eq!(e.lines().count(), 1, "{e}");
}
