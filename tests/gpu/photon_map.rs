//! The photon-map technique on lavapipe: the GPU grid build against its CPU twin (exactly),
//! closed forms, energy against the CPU reference, progressive convergence, and nothing
//! dispatched without work. 128² targets, 65 536 photons per light.

use bevy_caustics::CausticsTechnique;
use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::optics::{GridLayout, PhotonGrid, build_grid};
use bevy_caustics::render::photon_map::pipelines::{GRID_ENTRIES, grid_dispatches, grid_source};
use bevy_caustics::render::photon_map::view::{
    H_CELL, H_COUNT, H_DIMS, H_INV, H_ORIGIN, H_SHIFT, HEADER_WORDS,
};
use glam::Vec3;

use super::{GPU, closed_form_cases, closed_form_error, require_gpu, scene, spot_away_scene};

/// Photons per light and frame.
pub(crate) const PHOTONS: u64 = 1 << 16;

pub(crate) fn photon_map(job: RenderJob) -> RenderReport {
    photon_map_sized(job, 128)
}

fn photon_map_sized(job: RenderJob, side: u32) -> RenderReport {
    let name = job.scene.display().to_string();
    run(RenderJob {
        technique: CausticsTechnique::PhotonMap,
        width: side,
        height: side,
        photons: job.photons.or(Some(PHOTONS)),
        ..job
    })
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// What the GPU build left: the header words, `cells[0..=X·Y·Z]` and each sorted photon's id.
struct GpuGrid {
    header: Vec<u32>,
    start: Vec<u32>,
    ids: Vec<u32>,
}

/// Run the grid module's entry points (`GRID_ENTRIES`, sized by `grid_dispatches` as the plugin
/// does) on `positions` on a plain wgpu device. Photon `i` carries `i` in its direction word.
fn gpu_grid(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    positions: &[Vec3],
    r: f32,
    budget: u32,
) -> GpuGrid {
    use wgpu::util::DeviceExt;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("grid"),
        source: wgpu::ShaderSource::Wgsl(grid_source().into()),
    });
    let storage = |read_only: bool| wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    let mut entries = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }];
    for b in 1..7 {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: b,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: storage(b == 1),
            count: None,
        });
    }
    let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &entries,
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&bgl)],
        immediate_size: 0,
    });
    let pipelines: Vec<_> = GRID_ENTRIES
        .iter()
        .map(|e| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(e),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(e),
                compilation_options: Default::default(),
                cache: None,
            })
        })
        .collect();
    let capacity = (positions.len() as u32).max(1);
    let mut photons = Vec::with_capacity(capacity as usize * 32);
    for (i, p) in positions.iter().enumerate() {
        for v in [
            p.x.to_bits(),
            p.y.to_bits(),
            p.z.to_bits(),
            i as u32,
            0,
            0,
            0,
            0,
        ] {
            photons.extend_from_slice(&v.to_le_bytes());
        }
    }
    photons.resize((capacity as usize * 32).max(32), 0);
    let mut params = Vec::new();
    for v in [r.to_bits(), (1.0 / r).to_bits(), budget, capacity] {
        params.extend_from_slice(&v.to_le_bytes());
    }
    let mut header = vec![0u8; HEADER_WORDS as usize * 4];
    header[H_COUNT * 4..H_COUNT * 4 + 4].copy_from_slice(&(positions.len() as u32).to_le_bytes());
    let cell_words = budget + 1;
    let init = |label, contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    };
    let su = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let bufs = [
        init("params", &params, wgpu::BufferUsages::UNIFORM),
        init("photons", &photons, su),
        init("sorted", &vec![0u8; photons.len()], su),
        init("header", &header, su),
        init("cells", &vec![0u8; cell_words as usize * 4], su),
        init(
            "blocks",
            &vec![0u8; (cell_words.div_ceil(1024) as usize * 4).max(16)],
            su,
        ),
        init("photon_cell", &vec![0u8; capacity as usize * 4], su),
    ];
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &bgl,
        entries: &bufs
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect::<Vec<_>>(),
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_bind_group(0, &bind, &[]);
        for (p, n) in pipelines.iter().zip(grid_dispatches(capacity, cell_words)) {
            pass.set_pipeline(p);
            pass.dispatch_workgroups(n[0], n[1], n[2]);
        }
    }
    let read = |enc: &mut wgpu::CommandEncoder, b: &wgpu::Buffer| {
        let r = device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: b.size(),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        enc.copy_buffer_to_buffer(b, 0, &r, 0, b.size());
        r
    };
    let staged = [
        read(&mut enc, &bufs[3]),
        read(&mut enc, &bufs[4]),
        read(&mut enc, &bufs[2]),
    ];
    queue.submit([enc.finish()]);
    for s in &staged {
        s.slice(..)
            .map_async(wgpu::MapMode::Read, |r| r.expect("map"));
    }
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("poll");
    let words = |b: &wgpu::Buffer| -> Vec<u32> {
        b.slice(..)
            .get_mapped_range()
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let header = words(&staged[0]);
    let cells: u64 = (0..3).map(|a| u64::from(header[H_DIMS + a])).product();
    let start = words(&staged[1])[..=cells as usize].to_vec();
    let sorted = words(&staged[2]);
    let ids = (0..positions.len()).map(|i| sorted[i * 8 + 3]).collect();
    GpuGrid { header, start, ids }
}

/// The GPU build equals `optics::build_grid`: layout (origin, cell, 1 / cell, dims, shift) bit
/// for bit, `startIdx` word for word, and each cell's photons the same set.
fn assert_same(case: &str, gpu: &GpuGrid, cpu: &PhotonGrid) {
    let l: &GridLayout = &cpu.layout;
    let h = &gpu.header;
    let f = |w: usize| f32::from_bits(h[w]);
    assert_eq!(
        [h[H_DIMS], h[H_DIMS + 1], h[H_DIMS + 2]],
        l.dims.to_array(),
        "{case}: dims"
    );
    assert_eq!(h[H_SHIFT], l.shift, "{case}: shift");
    if l.cells() > 0 {
        let origin = [f(H_ORIGIN), f(H_ORIGIN + 1), f(H_ORIGIN + 2)];
        assert_eq!(
            origin.map(f32::to_bits),
            l.origin.to_array().map(f32::to_bits),
            "{case}: origin {origin:?} vs {}",
            l.origin
        );
        assert_eq!(f(H_CELL).to_bits(), l.cell.to_bits(), "{case}: cell");
        assert_eq!(f(H_INV).to_bits(), l.inv_cell.to_bits(), "{case}: 1 / cell");
    }
    assert_eq!(gpu.start.len(), cpu.start.len(), "{case}: cells");
    if let Some(c) = gpu.start.iter().zip(&cpu.start).position(|(a, b)| a != b) {
        panic!(
            "{case}: startIdx[{c}] GPU {} vs CPU {}",
            gpu.start[c], cpu.start[c]
        );
    }
    for c in 0..l.cells() as usize {
        let (a, b) = (cpu.start[c] as usize, cpu.start[c + 1] as usize);
        let mut g = gpu.ids[a..b].to_vec();
        let mut k = cpu.order[a..b].to_vec();
        g.sort_unstable();
        k.sort_unstable();
        assert_eq!(g, k, "{case}: photons of cell {c}");
    }
}

/// The WGSL grid build (bounds, layout, count, two-level scan, scatter) matches the CPU twin
/// exactly on random and degenerate photon sets: random in a box, all in one cell (2^18 at one
/// point), one photon, none, photons on cell boundaries (a lattice at multiples of r), 1e-3 m
/// and 1e4 m extents, and a budget so small the cells must double.
#[test]
fn wgsl_grid_build_matches_cpu_exactly() {
    use bevy_caustics::optics::Pcg32;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let (device, queue) = super::twins::plain_device();
    let mut rng = Pcg32::new(5, 1);
    let mut random = |n: usize, lo: Vec3, hi: Vec3| -> Vec<Vec3> {
        (0..n)
            .map(|_| lo + (hi - lo) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()))
            .collect()
    };
    let lattice: Vec<Vec3> = (0..4096)
        .map(|i| {
            let (x, y, z) = (i % 16, (i / 16) % 16, i / 256);
            Vec3::new(0.3, -1.7, 2.1) + Vec3::new(x as f32, y as f32, z as f32) * 0.05
        })
        .collect();
    let cases: Vec<(&str, Vec<Vec3>, f32, u32)> = vec![
        (
            "random",
            random(20_000, Vec3::new(-1.5, 0.0, -1.0), Vec3::new(1.5, 1.0, 1.0)),
            0.05,
            1 << 20,
        ),
        (
            "one cell",
            vec![Vec3::new(0.37, 0.11, -0.52); 1 << 18],
            0.05,
            1 << 20,
        ),
        ("one photon", vec![Vec3::new(-3.0, 2.0, 1.0)], 0.05, 1 << 20),
        ("none", Vec::new(), 0.05, 1 << 20),
        ("cell boundaries", lattice, 0.05, 1 << 20),
        (
            "1e-3 m",
            random(5000, Vec3::splat(-5e-4), Vec3::splat(5e-4)),
            1e-5,
            1 << 20,
        ),
        (
            "1e4 m",
            random(5000, Vec3::splat(-5e3), Vec3::splat(5e3)),
            0.5,
            1 << 20,
        ),
        (
            "budget too small",
            random(20_000, Vec3::new(-1.5, 0.0, -1.0), Vec3::new(1.5, 1.0, 1.0)),
            0.01,
            4096,
        ),
    ];
    for (case, positions, r, budget) in cases {
        let cpu = build_grid(&positions, r, 1.0 / r, budget);
        let gpu = gpu_grid(&device, &queue, &positions, r, budget);
        assert_same(case, &gpu, &cpu);
        println!(
            "{case}: {} photons, dims {:?}, shift {}, {} cells, GPU = CPU",
            positions.len(),
            cpu.layout.dims,
            cpu.layout.shift,
            cpu.layout.cells()
        );
    }
}

/// Mean caustic irradiance over the interior of the lit region of `mirror_wall` and
/// `glass_slab` within 5 % of the closed form after 16 progressive frames.
#[test]
fn photon_map_closed_forms() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    for case in closed_form_cases() {
        let (desc, expect) = (&case.0, case.4);
        let report = photon_map(RenderJob {
            scene: scene(&desc.name),
            frames: 16,
            ..Default::default()
        });
        let (mean, px, err) = closed_form_error(&case, report.caustics.as_ref().expect("caustics"));
        println!(
            "{}: photon-map mean {mean:.1} lx over {px} px after 16 frames, closed form {expect:.1} lx, error {:+.2} %, {:?}, passes {:?}",
            desc.name,
            err * 100.0,
            report.photon_map,
            report.pass_ms
        );
        assert!(err.abs() < 0.05, "{}: {:+.2} %", desc.name, err * 100.0);
    }
}

/// No light, a spot aimed away from every caster, or zero photons: no photon-map pass.
#[test]
fn photon_map_dispatches_nothing_without_work() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("bevy_caustics_pm_{}", std::process::id()));
    for (path, photons) in [
        (scene("empty"), PHOTONS),
        (spot_away_scene(&dir), PHOTONS),
        (scene("glass_sphere"), 0),
    ] {
        let report = run(RenderJob {
            scene: path.clone(),
            technique: CausticsTechnique::PhotonMap,
            width: 32,
            height: 32,
            photons: Some(photons),
            frames: 4,
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            report.passes.is_empty(),
            "{}: {:?}",
            path.display(),
            report.passes
        );
    }
}

/// Algorithm 1 (tiles whose pixels share a centre cell gather through workgroup memory) gives
/// the same irradiance as the per-pixel gather, pixel by pixel within 1e-4 of the image's
/// peak (the sums run in another order); with a radius as large as the ball most tiles take
/// the shared path (counted; tiles on a cell boundary or the horizon fall back). Its speed
/// (table 4) is measured with the command-line renderer over 24 frames (see the module doc of
/// `render::photon_map`).
#[test]
fn photon_map_shared_memory_matches_per_pixel() {
    use bevy_caustics::PhotonMapSettings;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let render = |shared_memory: bool| {
        photon_map_sized(
            RenderJob {
                scene: scene("glass_sphere"),
                frames: 8,
                photon_map: PhotonMapSettings {
                    radius: 1.0,
                    progressive: false,
                    shared_memory,
                    ..Default::default()
                },
                ..Default::default()
            },
            64,
        )
    };
    let (plain, shared) = (render(false), render(true));
    let c = shared.photon_map.as_ref().expect("counters");
    println!(
        "shared tiles {}, fallback tiles {}",
        c.shared_tiles, c.fallback_tiles
    );
    assert!(c.shared_tiles > 0, "{c:?}");
    assert_eq!(plain.photon_map.as_ref().unwrap().shared_tiles, 0);
    let (a, b) = (plain.caustics.unwrap(), shared.caustics.unwrap());
    let peak = a
        .data
        .iter()
        .map(|p| p.max_element())
        .fold(0.0f32, f32::max);
    assert!(peak > 0.0);
    for (i, (x, y)) in a.data.iter().zip(&b.data).enumerate() {
        assert!(
            (*x - *y).abs().max_element() <= 1e-4 * peak,
            "pixel {i}: {x} vs {y} (peak {peak})"
        );
    }
}

/// Caustics seen in a mirror (`mirror_ball`: the glass ball's floor caustic in a standing
/// mirror). The value the GPU shows at the pixels it marks as mirror pixels equals, summed
/// within 10 %, what the CPU twin finds at the same pixels: the camera ray through the pixel
/// centre on the CPU BVH, reflected by the mirror (normal +Z) to the floor (normal +Y), the
/// CPU grid built from the GPU's own photons (read back), `optics::gather` there with the
/// path's footprint radius, times Schlick's F of the mirror and the floor's albedo.
#[test]
fn photon_map_caustics_seen_in_mirror() {
    use bevy_caustics::PhotonMapSettings;
    use bevy_caustics::optics::{
        PixelFocal, StoredPhoton, fresnel_schlick, gather, gather_radius, pixel_footprint_area,
    };
    use bevy_caustics::render::photon_map::view::base_radius;
    use bevy_caustics::render::trace::scene::caster_sphere;
    use bevy_caustics::scene::Surface;
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let settings = PhotonMapSettings {
        progressive: false,
        ..Default::default()
    };
    let report = photon_map(RenderJob {
        scene: scene("mirror_ball"),
        frames: 4,
        read_photons: true,
        photon_map: settings.clone(),
        ..Default::default()
    });
    let c = report.photon_map.clone().expect("counters");
    let img = report.caustics.expect("caustics");
    let desc = bevy_caustics::scenes::mirror_ball();
    let (w, h) = (img.width, img.height);
    let (tlas, _, cam) = desc.to_trace(w, h);
    let photons = &report.photon_map_photons;
    assert_eq!(photons.len() as u64, c.photons_stored);
    let r0 = base_radius(&settings, caster_sphere(&tlas).expect("casters").1);
    let positions: Vec<Vec3> = photons.iter().map(|p| p.position).collect();
    let grid = build_grid(&positions, r0, 1.0 / r0, settings.max_grid_cells);
    assert_eq!(
        grid.layout.shift as u64, c.coarsened,
        "the CPU grid is the GPU's"
    );
    let sorted: Vec<StoredPhoton> = grid.order.iter().map(|&i| photons[i as usize]).collect();
    let fov = 45f32.to_radians();
    let focal = PixelFocal::from_fov_y(fov, w, h);
    let eye = cam.position();
    let rot = cam.world_from_view.matrix3;
    let forward: Vec3 = (rot * glam::Vec3A::NEG_Z).into();
    let (mut gpu, mut cpu, mut pixels) = (Vec3::ZERO, Vec3::ZERO, 0);
    let tan = (0.5 * fov).tan();
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            if report.caustics_alpha[i] >= 0.0 {
                continue;
            }
            let ndc = glam::Vec2::new(
                (x as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
            );
            let view = Vec3::new(ndc.x * tan * w as f32 / h as f32, ndc.y * tan, -1.0);
            let d: Vec3 = (rot * glam::Vec3A::from(view)).normalize().into();
            let Some(m) = tlas.closest_hit(eye, d, 0.0, f32::INFINITY, |_| false) else {
                continue;
            };
            let Surface::Conductor { f0 } = tlas.instances[m.instance as usize].surface else {
                continue;
            };
            let p = eye + d * m.t;
            let d2 = bevy_caustics::optics::reflect(d, Vec3::Z);
            let Some(f) = tlas.closest_hit(p + Vec3::Z * 1e-4, d2, 0.0, f32::INFINITY, |_| false)
            else {
                continue;
            };
            let Surface::Diffuse { albedo } = tlas.instances[f.instance as usize].surface else {
                continue;
            };
            let q = p + Vec3::Z * 1e-4 + d2 * f.t;
            let area = pixel_footprint_area(m.t + f.t, d.dot(forward), d2.y.abs(), focal);
            let r = gather_radius(r0, area, grid.layout.cell);
            let e = gather(&grid, &sorted, q, Vec3::Y, r, settings.normal_threshold).irradiance;
            cpu += fresnel_schlick(-d.dot(Vec3::Z), f0) * albedo * e;
            gpu += img.data[i];
            pixels += 1;
        }
    }
    let ratio = gpu.x / cpu.x;
    println!(
        "mirror pixels: GPU marked {} ({} checked); shown {:.0} lx·albedo summed, CPU twin {:.0}: ratio {ratio:.4}; {c:?}",
        c.mirror_pixels, pixels, gpu.x, cpu.x
    );
    assert!(pixels > 200, "only {pixels} mirror pixels");
    assert!(cpu.x > 0.0, "the mirror shows no caustic");
    assert!((ratio - 1.0).abs() < 0.10, "ratio {ratio}");
}

/// Caustics seen through glass (item 6): the composite writes the caustic into the opaque frame
/// before Bevy's transmissive pass copies it, so glass in front of a caustic shows it. A thin,
/// grey glass pane (`specular_transmission` 1, `thickness` 0, IOR 1.5, base colour 0.6) fills
/// the view 0.5 m in front of the camera of `glass_sphere`. Bevy's screen-space transmission of
/// such a pane samples the frame behind it at the same pixel and scales it by
/// `(1 - F_schlick(0.04, cos θt)) · specular_transmission · base_color` (bevy_pbr
/// `transmission.wgsl`), about 0.576 at these angles. So at every pixel whose ray, past the
/// pane, meets the floor, the frame with caustics minus the twin without must be that factor
/// times the composite's term `albedo / π · E · exposure`: not 0 (the caustic does not reach
/// the image through glass) and not 1 (it is added over the glass).
#[test]
fn photon_map_caustics_seen_through_glass() {
    use bevy::prelude::*;
    use bevy_caustics::{CausticMaterial, Caustics};
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    const PANE_DISTANCE: f32 = 0.5;
    const PANE_GREY: f32 = 0.6;
    fn pane(world: &mut World) {
        let eye = world
            .query_filtered::<&Transform, With<Caustics>>()
            .iter(world)
            .next()
            .copied()
            .expect("caustics camera");
        let mesh = world
            .resource_mut::<Assets<Mesh>>()
            .add(Rectangle::new(8.0, 8.0));
        let material = world
            .resource_mut::<Assets<StandardMaterial>>()
            .add(StandardMaterial {
                base_color: Color::linear_rgb(PANE_GREY, PANE_GREY, PANE_GREY),
                specular_transmission: 1.0,
                thickness: 0.0,
                ior: 1.5,
                perceptual_roughness: 0.0,
                ..default()
            });
        world.spawn((
            Name::new("pane"),
            Mesh3d(mesh),
            MeshMaterial3d(material),
            CausticMaterial::Dielectric {
                ior: 1.5,
                attenuation_color: Color::WHITE,
                attenuation_distance: f32::INFINITY,
                thin: true,
            },
            eye * Transform::from_xyz(0.0, 0.0, -PANE_DISTANCE),
        ));
    }
    let side = 64u32;
    let report = photon_map_sized(
        RenderJob {
            scene: scene("glass_sphere"),
            frames: 4,
            linear: true,
            hook: Some(pane),
            ..Default::default()
        },
        side,
    );
    let e = report.caustics.as_ref().expect("caustics buffer");
    // Which pixels see the floor past the pane (the pane is not in the CPU scene).
    let (tlas, _, cam) = bevy_caustics::scenes::glass_sphere().to_trace(side, side);
    let focal = bevy_caustics::optics::PixelFocal::from_fov_y(45f32.to_radians(), side, side);
    let half = side as f32 * 0.5;
    let (mut added, mut expected, mut floor_pixels, mut lit) = (0.0f64, 0.0f64, 0, 0);
    for (i, (w, wo)) in report
        .linear_with
        .iter()
        .zip(&report.linear_without)
        .enumerate()
    {
        assert!(w.iter().chain(wo).all(|c| c.is_finite()), "pixel {i}");
        let (x, y) = (
            (i as u32 % side) as f32 + 0.5,
            (i as u32 / side) as f32 + 0.5,
        );
        let local = glam::Vec3::new((x - half) / focal.fx, -(y - half) / focal.fy, -1.0);
        let d = cam.world_from_view.transform_vector3(local).normalize();
        let Some(hit) = tlas.closest_hit(cam.position(), d, 0.0, f32::INFINITY, |_| false) else {
            continue;
        };
        if tlas.instances[hit.instance as usize].surface.is_specular() {
            continue;
        }
        floor_pixels += 1;
        // Bevy's Fresnel term, at the refracted angle inside the pane (its normal faces the eye).
        let cos_i = -local.normalize().z;
        let cos_t = (1.0 - (1.0 - cos_i * cos_i) / (1.5 * 1.5)).sqrt();
        let fresnel = 0.04 + 0.96 * (1.0 - cos_t).powi(5);
        let through = (1.0 - fresnel) * PANE_GREY;
        let term = 0.8 / std::f32::consts::PI * e.data[i].y * report.exposure;
        added += (w[1] - wo[1]) as f64;
        expected += (through * term) as f64;
        if term > 0.0 {
            lit += 1;
        }
    }
    let ratio = added / expected;
    println!(
        "through glass: {floor_pixels} floor pixels behind the pane ({lit} with caustic): added {added:.4}, \
         expected {expected:.4} (ratio {ratio:.4}); pane factor ≈ {:.3}",
        0.96 * PANE_GREY
    );
    assert!(lit > 100, "only {lit} caustic pixels behind the pane");
    // f16 frames and the pane's own reflection (the same in both frames) leave about 1 %.
    assert!((ratio - 1.0).abs() < 0.03, "ratio {ratio}");
}

/// The photon map's adaptive radius (`optics_density_radius` in `src/render/optics.wgsl`)
/// against `optics::density_radius` to 1e-6 relative: inside its range, past both ends, no
/// density (0, negative, NaN, subnormal, infinite), photons off (0, negative, NaN), and bad
/// first radii (0, negative, infinite); on random inputs over 12 decades of density.
#[test]
fn wgsl_density_radius_matches_rust() {
    use bevy_caustics::optics::{Pcg32, density_radius};
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let kernel = r#"
@group(0) @binding(0) var<storage, read> radius_in: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> radius_out: array<vec4<f32>>;
@compute @workgroup_size(64)
fn radius_test(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&radius_out) { return; }
    let a = radius_in[i];
    radius_out[i] = vec4(optics_density_radius(a.x, a.y, a.z), 0.0, 0.0, 0.0);
}
"#;
    let src = format!("{}\n{kernel}", include_str!("../../src/render/optics.wgsl"));
    let rho = 64.0 / (core::f32::consts::PI * 0.02 * 0.02);
    let mut cases: Vec<[f32; 4]> = vec![[0.02, rho, 64.0, 0.0], [0.02, rho * 1e6, 64.0, 0.0]];
    for d in [0.0, -1.0, f32::NAN, 1e-45, f32::INFINITY, f32::MAX] {
        cases.push([0.02, d, 64.0, 0.0]);
    }
    for k in [0.0, -3.0, f32::NAN, f32::INFINITY] {
        cases.push([0.02, rho, k, 0.0]);
    }
    for r1 in [0.0, -1.0, f32::INFINITY] {
        cases.push([r1, rho, 64.0, 0.0]);
    }
    let mut rng = Pcg32::new(5, 17);
    for _ in 0..1024 {
        let r1 = 1e-3 + rng.next_f32();
        let density = 10f32.powf(rng.next_f32() * 12.0 - 2.0);
        cases.push([r1, density, 1.0 + rng.next_f32() * 255.0, 0.0]);
    }
    let data = super::twins::run_compute(
        &src,
        "radius_test",
        0,
        &[super::twins::f4_bytes(&cases)],
        cases.len(),
    );
    for (i, c) in cases.iter().enumerate() {
        let gpu = f32::from_le_bytes(data[i * 16..i * 16 + 4].try_into().unwrap());
        let cpu = density_radius(c[0], c[1], c[2]);
        let same = gpu == cpu || (gpu - cpu).abs() <= 1e-6 * cpu.abs();
        assert!(same, "case {i} {c:?}: GPU {gpu}, CPU {cpu}");
    }
}
