//! WGSL twins of the optics core, the BVH traversal and the quadtree walk, each run as a plain
//! wgpu compute dispatch on lavapipe and compared with the Rust function; and the temporal
//! stage's clamp rescale against its contract.

use super::{GPU, require_gpu};

/// The WGSL closest-hit traversal (`src/render/bvh.wgsl`) against the CPU BVH on thousands of
/// random rays through three scenes: same instance and triangle (or a tie at the same
/// distance on a shared edge), t within 1e-4 relative. Runs as a plain wgpu compute dispatch.
#[test]
fn wgsl_bvh_matches_cpu_bvh() {
    use bevy_caustics::optics::{Pcg32, uniform_sphere};
    use bevy_caustics::scene::gpu::GpuBvh;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let kernel = r#"
@group(0) @binding(3) var<storage, read> rays: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> hits: array<vec4<u32>>;
@compute @workgroup_size(64)
fn trace_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&hits) { return; }
    let h = bvh_closest_hit(rays[2u * i].xyz, rays[2u * i + 1u].xyz, 0.0, BVH_FAR);
    hits[i] = vec4(bitcast<u32>(h.t), h.instance, h.triangle, 0u);
}
"#;
    let src = format!("{}\n{kernel}", include_str!("../../src/render/bvh.wgsl"));
    for (total, desc) in [
        bevy_caustics::scenes::glass_sphere(),
        bevy_caustics::scenes::pool(),
        bevy_caustics::scenes::ring(),
    ]
    .into_iter()
    .enumerate()
    {
        let (tlas, _, _) = desc.to_trace(8, 8);
        let gpu = GpuBvh::from_tlas(&tlas);
        let mut rng = Pcg32::new(17, total as u64);
        let n = 4096usize;
        let rays: Vec<(glam::Vec3, glam::Vec3)> = (0..n)
            .map(|_| {
                let o = glam::Vec3::new(
                    rng.next_f32() * 4.0 - 2.0,
                    rng.next_f32() * 2.5,
                    rng.next_f32() * 4.0 - 2.0,
                );
                (o, uniform_sphere(rng.next_vec2()))
            })
            .collect();
        let ray_data: Vec<[f32; 4]> = rays
            .iter()
            .flat_map(|(o, d)| [[o.x, o.y, o.z, 0.0], [d.x, d.y, d.z, 0.0]])
            .collect();
        let [nodes, triangles, instances] = gpu.packed();
        let inputs = [nodes, triangles, instances, f4_bytes(&ray_data)];
        let data = run_compute(&src, "trace_rays", 0, &inputs, n);
        let (mut hit_count, mut ties) = (0, 0);
        for (i, (o, d)) in rays.iter().enumerate() {
            let w = |k: usize| {
                u32::from_le_bytes(data[i * 16 + 4 * k..i * 16 + 4 * k + 4].try_into().unwrap())
            };
            let (gt, ginst, gtri) = (f32::from_bits(w(0)), w(1), w(2));
            match tlas.closest_hit(*o, *d, 0.0, f32::INFINITY, |_| false) {
                Some(h) => {
                    hit_count += 1;
                    assert_ne!(
                        ginst,
                        u32::MAX,
                        "{}: ray {i} hit on the CPU, missed on the GPU",
                        desc.name
                    );
                    assert!(
                        (gt - h.t).abs() <= 1e-4 * h.t.max(1.0),
                        "{}: ray {i}: t {gt} vs {}",
                        desc.name,
                        h.t
                    );
                    if (ginst, gtri) != (h.instance, h.triangle) {
                        // A shared edge: both triangles are hit at the same distance.
                        assert!(
                            (gt - h.t).abs() <= 1e-6 * h.t.max(1.0),
                            "{}: ray {i}: ({ginst},{gtri}) vs ({},{})",
                            desc.name,
                            h.instance,
                            h.triangle
                        );
                        ties += 1;
                    }
                }
                None => assert_eq!(
                    ginst,
                    u32::MAX,
                    "{}: ray {i} missed on the CPU, hit on the GPU at {gt}",
                    desc.name
                ),
            }
        }
        println!(
            "{}: {n} rays, {hit_count} hits, {ties} edge ties, all match",
            desc.name
        );
        assert!(hit_count > n / 4);
    }
}

/// Run `entry` of the WGSL module `src` on a plain wgpu device, one invocation per output
/// element: `inputs` are bound read-only at bindings `first_binding..`, the output (`out_len`
/// 16-byte elements) at the binding after them. Returns the output bytes.
pub(super) fn run_compute(
    src: &str,
    entry: &str,
    first_binding: u32,
    inputs: &[Vec<u8>],
    out_len: usize,
) -> Vec<u8> {
    use wgpu::util::DeviceExt;
    let (device, queue) = plain_device();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(entry),
        source: wgpu::ShaderSource::Wgsl(src.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });
    let bufs: Vec<wgpu::Buffer> = inputs
        .iter()
        .map(|b| {
            let mut b = b.clone();
            if b.len() < 16 {
                b.resize(16, 0);
            }
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: None,
                contents: &b,
                usage: wgpu::BufferUsages::STORAGE,
            })
        })
        .collect();
    let size = (out_len * 16) as u64;
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("out"),
        size,
        usage,
        mapped_at_creation: false,
    });
    let usage = wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST;
    let read = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read"),
        size,
        usage,
        mapped_at_creation: false,
    });
    let mut entries: Vec<wgpu::BindGroupEntry> = bufs
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: first_binding + i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    entries.push(wgpu::BindGroupEntry {
        binding: first_binding + bufs.len() as u32,
        resource: out.as_entire_binding(),
    });
    let layout = pipeline.get_bind_group_layout(0);
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &entries,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((out_len as u32).div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&out, 0, &read, 0, size);
    queue.submit([enc.finish()]);
    read.slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.expect("map"));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("poll");
    read.slice(..).get_mapped_range().to_vec()
}

/// A plain wgpu device on the default adapter (no Bevy), for compute-only tests.
pub(super) fn plain_device() -> (wgpu::Device, wgpu::Queue) {
    let instance = wgpu::Instance::default();
    let adapter =
        bevy::tasks::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
            .expect("adapter");
    bevy::tasks::block_on(adapter.request_device(&wgpu::DeviceDescriptor::default()))
        .expect("device")
}

pub(super) fn f4_bytes(v: &[[f32; 4]]) -> Vec<u8> {
    v.iter()
        .flat_map(|x| x.iter().flat_map(|c| c.to_le_bytes()))
        .collect()
}

/// The WGSL twins of the optics core (`src/render/optics.wgsl`) against the Rust functions on
/// 8192 inputs, extremes included (grazing, normal incidence, IOR 1, 1/4 and 4): Fresnel,
/// refraction (including which side of TIR), reflection and the equal-area map to 1e-5,
/// floor_square exactly, and `dielectric_eta` (thin and thick, both sides, IOR below 1
/// guarded) to 1e-6 relative.
#[test]
fn wgsl_optics_match_rust() {
    use bevy_caustics::optics::*;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let kernel = r#"
@group(0) @binding(0) var<storage, read> inputs: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> outputs: array<vec4<f32>>;
@compute @workgroup_size(64)
fn optics_test(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&outputs) / 4u { return; }
    let a = inputs[2u * i];
    let b = inputs[2u * i + 1u];
    let h = optics_pcg_hash(i * 2654435761u);
    outputs[4u * i] = vec4(optics_fresnel_dielectric(a.w, b.w), f32(optics_floor_square(a.w * 40.0)), optics_hash_unit(i, i * 7u + 3u), optics_dielectric_eta(b.w, (i & 1u) == 0u, (i & 2u) != 0u));
    outputs[4u * i + 1u] = optics_refract(a.xyz, b.xyz, b.w);
    outputs[4u * i + 2u] = vec4(optics_reflect(a.xyz, b.xyz), f32(h & 0xffffffu));
    outputs[4u * i + 3u] = vec4(optics_equal_area_square_to_sphere(vec2(a.w, b.w / 4.0)), f32(h >> 8u));
}
"#;
    let src = format!("{}\n{kernel}", include_str!("../../src/render/optics.wgsl"));
    let mut rng = Pcg32::new(99, 1);
    let mut cases: Vec<(glam::Vec3, glam::Vec3, f32, f32)> = Vec::new();
    for k in 0..8192 {
        let d = uniform_sphere(rng.next_vec2());
        let n = uniform_sphere(rng.next_vec2());
        let (c, eta) = match k {
            0 => (0.0, 1.0 / 1.5),
            1 => (1.0, 1.0),
            2 => (1e-7, 4.0),
            3 => (0.5, 0.25),
            _ => (rng.next_f32(), 0.25 + rng.next_f32() * 3.75),
        };
        cases.push((d, n, c, eta));
    }
    let input: Vec<[f32; 4]> = cases
        .iter()
        .flat_map(|(d, n, c, eta)| [[d.x, d.y, d.z, *c], [n.x, n.y, n.z, *eta]])
        .collect();
    let data = run_compute(&src, "optics_test", 0, &[f4_bytes(&input)], cases.len() * 4);
    let f = |i: usize| f32::from_le_bytes(data[4 * i..4 * i + 4].try_into().unwrap());
    let v = |e: usize| glam::Vec3::new(f(4 * e), f(4 * e + 1), f(4 * e + 2));
    let mut worst = [0.0f32; 5];
    for (i, (d, n, c, eta)) in cases.iter().enumerate() {
        let e = 4 * i;
        let fr = fresnel_dielectric(*c, *eta);
        // The IOR is the case's eta (1/4 to 4); entering on even cases, thin on cases 2, 3 mod 4.
        let (entering, thin) = ((i & 1) == 0, (i & 2) != 0);
        let de = dielectric_eta(*eta, entering, thin);
        let de_err = (f(4 * e + 3) - de).abs() / de;
        worst[4] = worst[4].max(de_err);
        assert!(
            de_err < 1e-6,
            "dielectric_eta({eta}, {entering}, {thin}): {} vs {de}",
            f(4 * e + 3)
        );
        worst[0] = worst[0].max((f(4 * e) - fr).abs());
        assert!(
            (f(4 * e) - fr).abs() < 1e-5,
            "fresnel({c}, {eta}): {} vs {fr}",
            f(4 * e)
        );
        assert_eq!(
            f(4 * e + 1) as u32,
            floor_square(c * 40.0),
            "floor_square({})",
            c * 40.0
        );
        match refract(*d, *n, *eta) {
            Some(t) => {
                assert_eq!(
                    f(4 * (e + 1) + 3),
                    1.0,
                    "refract {d} {n} {eta}: TIR on the GPU only"
                );
                worst[1] = worst[1].max((v(e + 1) - t).length());
                assert!((v(e + 1) - t).length() < 1e-5, "refract {d} {n} {eta}");
            }
            None => assert_eq!(
                f(4 * (e + 1) + 3),
                0.0,
                "refract {d} {n} {eta}: TIR on the CPU only"
            ),
        }
        let r = reflect(*d, *n);
        worst[2] = worst[2].max((v(e + 2) - r).length());
        assert!((v(e + 2) - r).length() < 1e-5);
        // Bit for bit: the hash (low and high 24 bits, exact in f32) and the uniform from it.
        let (iu, h) = (i as u32, pcg_hash((i as u32).wrapping_mul(2654435761)));
        assert_eq!(f(4 * (e + 2) + 3), (h & 0xff_ffff) as f32, "pcg_hash({i})");
        assert_eq!(f(4 * (e + 3) + 3), (h >> 8) as f32, "pcg_hash({i})");
        assert_eq!(f(4 * e + 2), hash_unit(iu, iu * 7 + 3), "hash_unit({i})");
        let m = equal_area_square_to_sphere(glam::Vec2::new(*c, eta / 4.0));
        worst[3] = worst[3].max((v(e + 3) - m).length());
        assert!(
            (v(e + 3) - m).length() < 1e-5,
            "equal area ({c}, {})",
            eta / 4.0
        );
    }
    println!(
        "WGSL vs Rust over {} cases, worst |difference|: fresnel {:.1e}, refract {:.1e}, reflect {:.1e}, equal-area {:.1e}, dielectric_eta (relative) {:.1e}",
        cases.len(),
        worst[0],
        worst[1],
        worst[2],
        worst[3],
        worst[4]
    );
}

/// The WGSL quadtree walk (`src/render/quadtree.wgsl`) against `SumQuadtree::walk` for every task
/// of a random 32x32 density texture, plus tasks past the total, and its sample positions
/// (rotated by seven frames' rotations) against `leaf_sample_uv_rotated`.
#[test]
fn wgsl_quadtree_walk_matches_rust() {
    use bevy_caustics::optics::{Pcg32, SumQuadtree};
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let kernel = r#"
@group(0) @binding(8) var<storage, read_write> walks: array<vec4<u32>>;
@compute @workgroup_size(64)
fn walk_test(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&walks) / 2u { return; }
    let w = quadtree_walk(32u, id.x);
    walks[2u * id.x] = w;
    walks[2u * id.x + 1u] = vec4(bitcast<vec2<u32>>(quadtree_leaf_sample_uv_rotated(w.xy, w.z, 32u, quadtree_frame_rotation(id.x % 7u))), 0u, 0u);
}
"#;
    let src = format!(
        "{}\n{}\n{kernel}",
        include_str!("../../src/render/optics.wgsl"),
        include_str!("../../src/render/quadtree.wgsl")
    );
    let size = 32u32;
    let mut rng = Pcg32::new(3, 9);
    let density: Vec<f32> = (0..size * size)
        .map(|_| 4.0 + rng.next_f32() * 60.0)
        .collect();
    let tree = SumQuadtree::build(&density, size).unwrap();
    let flat: Vec<u8> = tree
        .levels
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let n = tree.total() as usize + 100;
    let data = run_compute(&src, "walk_test", 7, &[flat], 2 * n);
    let u = |i: usize| u32::from_le_bytes(data[4 * i..4 * i + 4].try_into().unwrap());
    let mut worst_uv = 0.0f32;
    for task in 0..n {
        let gpu = [
            u(8 * task),
            u(8 * task + 1),
            u(8 * task + 2),
            u(8 * task + 3),
        ];
        match tree.walk(task as u32) {
            Some((texel, sample, count)) => {
                assert_eq!(gpu, [texel.x, texel.y, sample, count], "task {task}");
                // The sample position in the texel (leaf_sample_uv_rotated, with the rotation
                // of frame `task % 7`, frame_rotation).
                let uv = glam::Vec2::new(
                    f32::from_bits(u(8 * task + 4)),
                    f32::from_bits(u(8 * task + 5)),
                );
                let rotation = bevy_caustics::optics::frame_rotation(task as u32 % 7);
                let want =
                    bevy_caustics::optics::leaf_sample_uv_rotated(texel, sample, size, rotation);
                worst_uv = worst_uv.max((uv - want).abs().max_element());
                assert!(
                    (uv - want).abs().max_element() < 1e-6,
                    "task {task}: uv {uv} vs {want}"
                );
            }
            None => assert_eq!(gpu[3], 0, "task {task} past the total"),
        }
    }
    println!(
        "quadtree walk: {} tasks match, leaf sample uv worst |difference| {worst_uv:.1e}",
        tree.total()
    );
}

/// The WGSL twins the AAPS passes use (`src/render/optics.wgsl`): Schlick, Beer-Lambert, spot
/// falloff, Duff basis, scale-aware ray offset, differential transfer, the splat ellipse and
/// the density update (suggested density, blend, budget), against the Rust core on random and
/// extreme inputs (zero and huge offsets, grazing and parallel rays, scenes from 1e-3 to 1e4 m);
/// and the photon map's Russian roulette (`roulette_survival` on throughputs from negative to
/// far above 1 and a zero emitted flux, to 2e-6; `ROULETTE_DEPTH` exactly).
#[test]
fn wgsl_aaps_optics_match_rust() {
    use bevy_caustics::optics::*;
    use glam::Vec3;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let kernel = r#"
@group(0) @binding(0) var<storage, read> inputs: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> outputs: array<vec4<f32>>;
@compute @workgroup_size(64)
fn aaps_test(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&outputs) / 9u { return; }
    let a = inputs[4u * i];
    let b = inputs[4u * i + 1u];
    let c = inputs[4u * i + 2u];
    let d = inputs[4u * i + 3u];
    let f0 = abs(d.xyz) / (vec3(1.0) + abs(d.xyz));
    let o = 9u * i;
    let split = optics_budget_split(d.w * 100.0, a.w * 1.2 - 0.1, c.w * 4.0e5, i % 1000u, (i * 7u) % 3000u, 4.0);
    outputs[o] = vec4(optics_fresnel_schlick(a.w, f0), split.x);
    outputs[o + 1u] = vec4(optics_beer_lambert(f0, b.w * 10.0, c.w * 10.0), split.y);
    var prev: array<f32, 5>;
    prev[0] = b.w * 100.0;
    prev[1] = c.w * 100.0;
    prev[2] = d.w;
    prev[3] = a.w * 100.0;
    prev[4] = 5.0;
    let count = 1u + (i % 5u);
    outputs[o + 2u] = vec4(
        optics_spot_attenuation(a.w * 2.0 - 1.0, 0.9, 0.7),
        optics_suggested_density(b.w * 100.0, c.w * 50.0, d.w * 0.01 - 1.0, a.w * 2.0, 16.0),
        optics_blend_density(c.w * 300.0, prev, count, a.w, 4.0, select(0.0, 200.0, (i & 1u) == 1u)),
        optics_budget_density(d.w, (i & 2u) == 0u, c.w * 100.0, a.w, 4.0, select(0.0, 300.0, (i & 4u) == 0u)),
    );
    let tb = optics_orthonormal_basis(c.xyz);
    outputs[o + 3u] = vec4(tb[0], optics_roulette_survival(d.xyz, select(b.w * 40.0, 0.0, (i % 16u) == 5u)));
    outputs[o + 4u] = vec4(tb[1], optics_roulette_survival(f0, c.w));
    let scale = pow(10.0, b.w * 7.0 - 3.0);
    outputs[o + 5u] = vec4(optics_offset_ray_origin(d.xyz * scale, c.xyz, scale), f32(OPTICS_ROULETTE_DEPTH));
    outputs[o + 6u] = optics_transfer_to_plane(d.xyz, a.xyz, b.xyz, c.xyz);
    let s = optics_splat_from_differentials(a.xyz, b.xyz, c.xyz, 16.0, 1.0e-4, 10.0);
    outputs[o + 7u] = vec4(s.a, select(0.0, 1.0, s.clamped));
    outputs[o + 8u] = vec4(s.b, 0.0);
}
"#;
    let src = format!("{}\n{kernel}", include_str!("../../src/render/optics.wgsl"));
    let mut rng = Pcg32::new(7, 5);
    let n_cases = 4096;
    let mut input: Vec<[f32; 4]> = Vec::new();
    for k in 0..n_cases {
        let c = uniform_sphere(rng.next_vec2());
        let mut r3 = |s: f32| (uniform_sphere(rng.next_vec2()) * s * rng.next_f32()).to_array();
        let (mut a, mut b, d) = (r3(2.0), r3(2.0), r3(50.0));
        // Extremes: zero offsets, one collapsed axis, huge offsets, a ray parallel to the plane.
        match k % 16 {
            0 => (a, b) = ([0.0; 3], [0.0; 3]),
            1 => b = a,
            2 => a = [1e30, 0.0, 0.0],
            3 => a = c.any_orthonormal_vector().to_array(),
            _ => {}
        }
        let w = [
            rng.next_f32(),
            rng.next_f32(),
            rng.next_f32(),
            rng.next_f32() * 1e4,
        ];
        input.push([a[0], a[1], a[2], w[0]]);
        input.push([b[0], b[1], b[2], w[1]]);
        input.push([c.x, c.y, c.z, w[2]]);
        input.push([d[0], d[1], d[2], w[3]]);
    }
    let data = run_compute(&src, "aaps_test", 0, &[f4_bytes(&input)], n_cases * 9);
    let f = |i: usize| f32::from_le_bytes(data[4 * i..4 * i + 4].try_into().unwrap());
    let v4 = |e: usize| [f(4 * e), f(4 * e + 1), f(4 * e + 2), f(4 * e + 3)];
    let v = |e: usize| Vec3::new(f(4 * e), f(4 * e + 1), f(4 * e + 2));
    let close = |x: Vec3, y: Vec3, tol: f32| (x - y).length() <= tol * (1.0 + y.length());
    let mut worst = 0.0f32;
    for k in 0..n_cases {
        let i4 = |j: usize| input[4 * k + j];
        let (a, b, c, d) = (i4(0), i4(1), i4(2), i4(3));
        let xyz = |q: [f32; 4]| Vec3::new(q[0], q[1], q[2]);
        let f0 = xyz(d).abs() / (Vec3::ONE + xyz(d).abs());
        let o = 9 * k;
        let check = |name: &str, gpu: Vec3, cpu: Vec3, tol: f32| {
            assert!(
                close(gpu, cpu, tol),
                "case {k}: {name}: gpu {gpu} cpu {cpu}"
            );
            assert!(gpu.is_finite(), "case {k}: {name} not finite");
        };
        check("schlick", v(o), fresnel_schlick(a[3], f0), 1e-5);
        check(
            "beer",
            v(o + 1),
            beer_lambert(f0, b[3] * 10.0, c[3] * 10.0),
            1e-4,
        );
        let s = v4(o + 2);
        let sp = spot_attenuation(a[3] * 2.0 - 1.0, 0.9f32.acos(), 0.7f32.acos());
        assert!((s[0] - sp).abs() < 1e-4, "case {k}: spot {} vs {sp}", s[0]);
        let sd = suggested_density(
            b[3] * 100.0,
            c[3] * 50.0,
            d[3] * 0.01 - 1.0,
            a[3] * 2.0,
            16.0,
        );
        assert!(
            (s[1] - sd).abs() <= 1e-5 * (1.0 + sd),
            "case {k}: suggested {} vs {sd}",
            s[1]
        );
        let prev = [b[3] * 100.0, c[3] * 100.0, d[3], a[3] * 100.0, 5.0];
        let count = 1 + k % 5;
        let pairs: Vec<(f32, f32)> = prev[..count].iter().map(|p| (1.0, *p)).collect();
        let max = if k % 2 == 1 { 200.0 } else { 0.0 };
        let bd = blend_density(c[3] * 300.0, &pairs, a[3], 4.0, max);
        assert_eq!(s[2], bd, "case {k}: blend");
        let max = if k & 4 == 0 { 300.0 } else { 0.0 };
        let bd = budget_density(d[3], k & 2 == 0, c[3] * 100.0, a[3], 4.0, max);
        assert_eq!(s[3], bd, "case {k}: budget density");
        let kk = k as u32;
        let (fl, sc) = budget_split(
            d[3] * 100.0,
            a[3] * 1.2 - 0.1,
            c[3] * 4e5,
            kk % 1000,
            (kk * 7) % 3000,
            4.0,
        );
        assert!(
            (f(4 * o + 3) - fl).abs() <= 1e-5 * (1.0 + fl),
            "case {k}: budget floor {} vs {fl}",
            f(4 * o + 3)
        );
        assert!(
            (f(4 * (o + 1) + 3) - sc).abs() <= 1e-5 * (1.0 + sc),
            "case {k}: budget scale {} vs {sc}",
            f(4 * (o + 1) + 3)
        );
        let (t, bb) = orthonormal_basis(xyz(c));
        check("basis t", v(o + 3), t, 1e-5);
        check("basis b", v(o + 4), bb, 1e-5);
        // Roulette: `d` spans negative to 50, the emitted flux 0 (every 16th case) to 40; and
        // Fresnel-like throughputs in [0, 1) against an emitted flux in [0, 1).
        let flux0 = if k % 16 == 5 { 0.0 } else { b[3] * 40.0 };
        for (e, q) in [
            (o + 3, roulette_survival(xyz(d), flux0)),
            (o + 4, roulette_survival(f0, c[3])),
        ] {
            let g = f(4 * e + 3);
            assert!((g - q).abs() <= 2e-6, "case {k}: roulette {g} vs {q}");
        }
        assert_eq!(f(4 * (o + 5) + 3), ROULETTE_DEPTH as f32, "roulette depth");
        let scale = 10f32.powf(b[3] * 7.0 - 3.0);
        let off = offset_ray_origin(xyz(d) * scale, xyz(c), scale);
        check("offset", v(o + 5), off, 1e-6);
        let (q, ok) = transfer_to_plane(xyz(d), xyz(a), xyz(b), xyz(c));
        let g = v4(o + 6);
        assert_eq!(g[3] == 1.0, ok, "case {k}: transfer success");
        if ok {
            let rel = (Vec3::new(g[0], g[1], g[2]) - q).length() / (1.0 + q.length());
            // Near-parallel rays amplify rounding; the tolerance grows with 1/|d.n|.
            let den = xyz(a).normalize_or_zero().dot(xyz(c)).abs().max(1e-6);
            assert!(rel < 1e-5 / den, "case {k}: transfer {g:?} vs {q}");
        }
        let (sp, clamped) = splat_from_differentials(xyz(a), xyz(b), xyz(c), 16.0, 1e-4, 10.0);
        let (ga, gb) = (v(o + 7), v(o + 8));
        // Axes are defined up to sign.
        let err = |g: Vec3, c: Vec3| (g - c).length().min((g + c).length()) / (1.0 + c.length());
        let e = err(ga, sp.a).max(err(gb, sp.b));
        worst = worst.max(e);
        assert!(e < 1e-3, "case {k}: splat a {ga} b {gb} vs {:?}", sp);
        assert_eq!(v4(o + 7)[3] == 1.0, clamped, "case {k}: splat clamp flag");
    }
    println!("WGSL AAPS twins over {n_cases} cases: worst splat-axis difference {worst:.1e}");
}

/// The caustics-volume splat footprint twins (`vol_texel_area`, `vol_splat_axes` in
/// src/render/volume/common.wgsl) against `projector_texel_area` and `volume_splat_axes`:
/// 4096 random cases plus extremes (zero and huge areas, grazing and normal incidence, zero,
/// non-finite and huge directions and radii).
#[test]
fn wgsl_volume_splat_matches_rust() {
    use bevy_caustics::optics::*;
    use bevy_caustics::volume::{projector_texel_area, volume_splat_axes};
    use glam::Vec3;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let kernel = r#"
@group(0) @binding(7) var<uniform> vp: VolParams;
@group(0) @binding(0) var<storage, read> inputs: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> outputs: array<vec4<f32>>;
@compute @workgroup_size(64)
fn vol_test(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&outputs) / 3u { return; }
    let a = inputs[4u * i];
    let b = inputs[4u * i + 1u];
    let c = inputs[4u * i + 2u];
    let d = inputs[4u * i + 3u];
    let ax = vol_splat_axes(a.xyz, b.xyz, a.w, 4.0, b.w, 0.5, 16.0, c.w);
    outputs[3u * i] = vec4(ax[0], 0.0);
    outputs[3u * i + 1u] = vec4(ax[1], 0.0);
    let area = vol_texel_area(d.w, d.x, d.y, d.z, 200u, normalize(c.xyz), vec3(0.0, 0.0, 1.0), b.xyz);
    outputs[3u * i + 2u] = vec4(area, 0.0, 0.0, 0.0);
}
"#;
    let src = format!(
        "{}\n{}\n{kernel}",
        include_str!("../../src/render/optics.wgsl"),
        include_str!("../../src/render/volume/common.wgsl")
    );
    let mut rng = Pcg32::new(11, 3);
    let n_cases = 4096;
    let mut input: Vec<[f32; 4]> = Vec::new();
    for k in 0..n_cases {
        let dir = uniform_sphere(rng.next_vec2()) * (0.1 + 10.0 * rng.next_f32());
        let mut n = uniform_sphere(rng.next_vec2());
        let mut area = 10f32.powf(rng.next_f32() * 8.0 - 7.0);
        let mut len = rng.next_f32() * 5.0;
        let mut rmin = 10f32.powf(rng.next_f32() * 6.0 - 7.0);
        let mut d = dir;
        match k % 12 {
            0 => d = Vec3::ZERO,
            1 => d = n * 3.0,
            2 => d = n.any_orthonormal_vector(),
            3 => area = 0.0,
            4 => area = 1e30,
            5 => len = 0.0,
            6 => rmin = 0.0,
            7 => n = Vec3::ZERO,
            8 => d = Vec3::splat(1e30),
            _ => {}
        }
        let c = uniform_sphere(rng.next_vec2());
        let h = Vec3::new(
            0.1 + rng.next_f32(),
            0.1 + rng.next_f32(),
            0.1 + rng.next_f32(),
        );
        input.push([d.x, d.y, d.z, area]);
        input.push([n.x, n.y, n.z, len]);
        input.push([c.x, c.y, c.z, rmin]);
        input.push([h.x, h.y, h.z, 0.1 + 20.0 * rng.next_f32()]);
    }
    let data = run_compute(&src, "vol_test", 0, &[f4_bytes(&input)], n_cases * 3);
    let f = |i: usize| f32::from_le_bytes(data[4 * i..4 * i + 4].try_into().unwrap());
    let v = |e: usize| Vec3::new(f(4 * e), f(4 * e + 1), f(4 * e + 2));
    let mut worst = 0.0f32;
    for k in 0..n_cases {
        let i4 = |j: usize| input[4 * k + j];
        let xyz = |q: [f32; 4]| Vec3::new(q[0], q[1], q[2]);
        let (a, b, c, d) = (i4(0), i4(1), i4(2), i4(3));
        let (ra, rb) = volume_splat_axes(xyz(a), xyz(b), a[3], 4.0, b[3], 0.5, 16.0, c[3]);
        let (ga, gb) = (v(3 * k), v(3 * k + 1));
        assert!(ga.is_finite() && gb.is_finite(), "case {k}: {ga} {gb}");
        let rel = |g: f32, r: f32| (g - r).abs() / (1e-30 + r.abs());
        // The lengths always agree; the directions only where the disc is stretched (a
        // circle's axes are any orthonormal pair in the surface plane).
        let e = rel(ga.length(), ra.length()).max(rel(gb.length(), rb.length()));
        let e = if ra.length() > rb.length() * 1.001 {
            let err = |g: Vec3, r: Vec3| (g - r).length().min((g + r).length()) / r.length();
            e.max(err(ga, ra)).max(err(gb, rb))
        } else {
            let n = xyz(b).normalize_or(Vec3::Y);
            let plane = (ga.dot(n) / ga.length())
                .abs()
                .max((gb.dot(n) / gb.length()).abs());
            e.max(plane)
                .max((ga.dot(gb) / (ga.length() * gb.length())).abs())
        };
        worst = worst.max(e);
        assert!(e < 1e-4, "case {k}: gpu {ga} {gb} cpu {ra} {rb}");
        let area = projector_texel_area(
            d[3],
            d[0],
            d[1],
            d[2],
            200,
            xyz(c).normalize(),
            Vec3::Z,
            xyz(b),
        );
        let g = f(4 * (3 * k + 2));
        // Grazing receivers amplify rounding by 1 / |ray . n|.
        let den = xyz(c).normalize().dot(xyz(b)).abs().max(1e-3);
        assert!(
            (g - area).abs() <= (1e-5 + 1e-6 / den) * (1e-30 + area),
            "case {k}: texel area gpu {g} cpu {area}"
        );
    }
    println!("volume splat twins: worst relative axis difference {worst:.2e}");
}

/// The WGSL twins of the image-space optics (`optics_r2_point`, `optics_march_crossing`,
/// `optics_classify_reprojection`, `optics_inside_layers`, `optics_fixed_point_word`,
/// `optics_svgf_weight`, `optics_pixel_footprint_area`) against the Rust functions on 4096
/// inputs with extremes (parallel segments, zero, empty, equal and non-finite depths, huge
/// irradiance): R2 points, cases and words exactly, the rest to 1e-5 relative.
#[test]
fn wgsl_image_space_optics_match_rust() {
    use bevy_caustics::optics::*;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let kernel = r#"
@group(0) @binding(0) var<storage, read> inputs: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> outputs: array<vec4<f32>>;
@compute @workgroup_size(64)
fn is_test(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&outputs) / 2u { return; }
    let a = inputs[2u * i];
    let b = inputs[2u * i + 1u];
    let r2 = optics_r2_point(i * 7919u, vec2(bitcast<u32>(b.z), bitcast<u32>(b.w)));
    let w = optics_fixed_point_word(a.x * 1000.0, 256.0, b.x);
    outputs[2u * i] = vec4(r2, optics_march_crossing(a.x, a.y, a.z, a.w), f32(optics_classify_reprojection(a.x, a.z, b.y) + 4u * optics_inside_layers(a.x, a.z - 10.0, a.w)));
    outputs[2u * i + 1u] = vec4(bitcast<f32>(w.x), f32(w.y), optics_svgf_weight(a.x - a.z, b.y, b.x, 128.0, a.y - a.w, b.y * 10.0), optics_pixel_footprint_area(a.y, b.x, b.y, vec2(a.z, a.w)));
}
"#;
    let src = format!("{}\n{kernel}", include_str!("../../src/render/optics.wgsl"));
    let mut rng = Pcg32::new(7, 3);
    let mut cases: Vec<([f32; 4], [f32; 4])> = Vec::new();
    for k in 0..4096u32 {
        let mut a = [0.0f32; 4].map(|_| 0.1 + rng.next_f32() * 20.0);
        let mut b = [rng.next_f32(), rng.next_f32() * 0.1, 0.0, 0.0];
        b[2] = f32::from_bits(pcg_hash(k));
        b[3] = f32::from_bits(pcg_hash(k ^ 0xdead));
        match k {
            0 => a = [1.0, 2.0, 1.0, 2.0],      // parallel segments
            1 => a = [f32::NAN, 1.0, 1.0, 1.0], // non-finite
            2 => a = [1.0, 1.0, f32::INFINITY, 1.0],
            3 => a = [5.0e9, 1.0, 1.0, 1.0], // a clamped word
            4 => b[1] = 0.0,                 // zero thickness
            5 => a = [3.0, 13.0, 13.0, 3.0], // on both layers
            6 => a = [4.0, 1.0, 10.0, 0.0],  // an empty back layer
            _ => {}
        }
        // NaN payloads are not preserved by every GPU path: keep the rotation words finite.
        for w in [2, 3] {
            if !b[w].is_finite() {
                b[w] = f32::from_bits(b[w].to_bits() & 0x3fff_ffff);
            }
        }
        cases.push((a, b));
    }
    let input: Vec<[f32; 4]> = cases.iter().flat_map(|(a, b)| [*a, *b]).collect();
    let data = run_compute(&src, "is_test", 0, &[f4_bytes(&input)], cases.len() * 2);
    let f = |i: usize| f32::from_le_bytes(data[4 * i..4 * i + 4].try_into().unwrap());
    let close = |g: f32, c: f32| g == c || (g - c).abs() <= 1e-5 * c.abs().max(1e-3);
    for (k, (a, b)) in cases.iter().enumerate() {
        let e = 8 * k;
        let rot = [b[2].to_bits(), b[3].to_bits()];
        let p = r2_point(k as u32 * 7919, rot);
        assert_eq!((f(e), f(e + 1)), (p.x, p.y), "r2 {k}");
        let u = march_crossing(a[0], a[1], a[2], a[3]);
        assert!(close(f(e + 2), u), "crossing {a:?}: {} vs {u}", f(e + 2));
        let case = classify_reprojection(a[0], a[2], b[1]) as u32;
        assert_eq!(f(e + 3) as u32 % 4, case, "classify {a:?} {b:?}");
        let inside = inside_layers(a[0], a[2] - 10.0, a[3]) as u32;
        assert_eq!(f(e + 3) as u32 / 4, inside, "inside {a:?}");
        let (w, clamped) = fixed_point_word(a[0] * 1000.0, FIXED_POINT_SCALE, b[0]);
        assert_eq!(f(e + 4).to_bits(), w, "word {}", a[0] * 1000.0);
        assert_eq!(f(e + 5) as u32 == 1, clamped, "clamped {}", a[0] * 1000.0);
        let sw = svgf_weight(a[0] - a[2], b[1], b[0], 128.0, a[1] - a[3], b[1] * 10.0);
        let loose = (f(e + 6) - sw).abs() <= 1e-4 * sw.abs().max(1e-6);
        assert!(loose, "svgf {a:?} {b:?}: {} vs {sw}", f(e + 6));
        let area = pixel_footprint_area(a[1], b[0], b[1], PixelFocal { fx: a[2], fy: a[3] });
        assert!(
            close(f(e + 7), area),
            "footprint {a:?} {b:?}: {} vs {area}",
            f(e + 7)
        );
    }
}

/// The temporal stage's history clamp rescales a colour to the window's luminance
/// (`with_luminance` in `src/render/temporal/accumulate.wgsl`): on random colours and on
/// colours whose luminance lies near the smallest normal floats (with zero channels), the
/// result is finite, non-negative and of the asked luminance (relative 1e-4). Before the
/// rescale was bounded, a prior of luminance 2e-38 lux scaled to 100 lux gave inf and 0 x inf
/// = NaN (seen as NaN pixels with image space at 3 or 4 à-trous iterations).
#[test]
fn wgsl_stage_clamp_rescale_stays_finite() {
    use bevy_caustics::optics::Pcg32;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    // The stage's own bindings are 0 to 9; an entry point's layout holds only what it uses.
    let kernel = r#"
@group(0) @binding(10) var<storage, read> rescale_in: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> rescale_out: array<vec4<f32>>;
@compute @workgroup_size(64)
fn rescale_test(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&rescale_out) { return; }
    let a = rescale_in[2u * i];
    let b = rescale_in[2u * i + 1u];
    rescale_out[i] = vec4(with_luminance(a.rgb, b.rgb, a.w), 0.0);
}
"#;
    let src = format!(
        "{}\n{kernel}",
        include_str!("../../src/render/temporal/accumulate.wgsl")
    );
    // (prior rgb, target luminance), (estimate rgb, 0).
    let mut cases: Vec<[[f32; 4]; 2]> = vec![
        [[1.0e-37, 0.0, 0.0, 100.0], [0.0; 4]],
        [[0.0, 0.0, 3.0e-37, 5.0e4], [2.0, 0.0, 0.0, 0.0]],
        [[1.0e-37, 0.0, 0.0, 100.0], [0.0, 2.0e-37, 0.0, 0.0]],
        [[0.0; 4], [0.0, 0.0, 1.0e-36, 1.0e3]],
        [[1.0, 1.0, 1.0, 1.0e-30], [0.0; 4]],
        [[0.0, 5.0, 0.0, 0.0], [1.0; 4]],
    ];
    let mut rng = Pcg32::new(3, 11);
    for _ in 0..1024 {
        let mut v = || rng.next_f32() * 1.0e4;
        cases.push([[v(), v(), v(), v()], [v(), v(), v(), 0.0]]);
    }
    let data = run_compute(
        &src,
        "rescale_test",
        10,
        &[f4_bytes(&cases.concat())],
        cases.len(),
    );
    let lum = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    for (i, case) in cases.iter().enumerate() {
        let out: [f32; 3] = std::array::from_fn(|k| {
            f32::from_le_bytes(data[i * 16 + 4 * k..i * 16 + 4 * k + 4].try_into().unwrap())
        });
        let want = case[0][3];
        assert!(
            out.iter().all(|c| c.is_finite() && *c >= 0.0),
            "case {i} {case:?}: {out:?}"
        );
        assert!(
            (lum(out) - want).abs() <= 1.0e-4 * want,
            "case {i} {case:?}: luminance {} for {want}",
            lum(out)
        );
    }
}
