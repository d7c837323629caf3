//! Criterion benchmarks: the optics core, BVH build and traversal, the reference tracer
//! (photons per second), the main-world CPU cost of a frame for 1, 10 and 100 casters of which
//! one moves and for 1, 100 and 1000 still ones (against the same app without the plugin), the
//! render-world CPU cost of a still frame for 1, 100 and 1000 casters (the renderer on the
//! adapter, lavapipe in CI), the photon map's CPU baselines (seed 001 tables 1 and 2: a kd-tree against the hash grid, a
//! k-nearest max-heap against all photons within the radius).
//!
//! `cargo bench --bench caustics` (release profile). Under `cargo test` each runs once.

use std::hint::black_box;
use std::sync::Arc;

use bevy::prelude::*;
use bevy_caustics::optics::{self, Pcg32};
use bevy_caustics::reference::{TraceSettings, trace};
use bevy_caustics::scene::{Blas, CausticsScene};
use bevy_caustics::scenes;
use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};

fn bench_optics(c: &mut Criterion) {
    let mut g = c.benchmark_group("optics");
    let mut rng = Pcg32::new(1, 1);
    let dirs: Vec<glam::Vec3> = (0..1024)
        .map(|_| optics::uniform_sphere(rng.next_vec2()))
        .collect();
    g.throughput(Throughput::Elements(dirs.len() as u64));
    g.bench_function("fresnel_dielectric", |b| {
        b.iter(|| {
            dirs.iter()
                .map(|d| optics::fresnel_dielectric(black_box(d.y), 1.0 / 1.5))
                .sum::<f32>()
        })
    });
    g.bench_function("refract", |b| {
        b.iter(|| {
            dirs.iter()
                .filter_map(|d| optics::refract(black_box(*d), glam::Vec3::Y, 1.0 / 1.5))
                .count()
        })
    });
    let focal = optics::PixelFocal::from_fov_y(0.8, 256, 256);
    g.bench_function("pixel_footprint_area", |b| {
        b.iter(|| {
            dirs.iter()
                .map(|d| optics::pixel_footprint_area(5.0, black_box(d.z), d.y, focal))
                .sum::<f32>()
        })
    });
    g.finish();
}

fn bench_bvh(c: &mut Criterion) {
    let mut g = c.benchmark_group("bvh");
    let sphere = Arc::new(scenes::geometry::uv_sphere(1.0, 256, 128));
    g.throughput(Throughput::Elements(sphere.indices.len() as u64));
    g.bench_function("build_blas_65k_triangles", |b| {
        b.iter(|| Blas::build(black_box(sphere.clone())))
    });
    let (tlas, _, _) = scenes::pool().to_trace(8, 8);
    let mut rng = Pcg32::new(2, 2);
    let rays: Vec<(glam::Vec3, glam::Vec3)> = (0..4096)
        .map(|_| {
            let o = glam::Vec3::new(rng.next_f32() * 6.0 - 3.0, 2.0, rng.next_f32() * 6.0 - 3.0);
            (
                o,
                optics::to_world(
                    optics::uniform_cone(rng.next_vec2(), 0.5),
                    glam::Vec3::NEG_Y,
                ),
            )
        })
        .collect();
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("closest_hit_pool_scene", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|(o, d)| {
                    tlas.closest_hit(*o, *d, 0.0, f32::INFINITY, |_| false)
                        .is_some()
                })
                .count()
        })
    });
    g.finish();
}

fn bench_tracer(c: &mut Criterion) {
    let mut g = c.benchmark_group("reference_tracer");
    g.sample_size(10);
    for desc in [scenes::glass_sphere(), scenes::pool(), scenes::ring()] {
        let (tlas, lights, cam) = desc.to_trace(128, 128);
        let photons = 1u64 << 17;
        g.throughput(Throughput::Elements(photons * lights.len() as u64));
        let settings = TraceSettings {
            photons_per_light: photons,
            ..Default::default()
        };
        g.bench_function(format!("{}_photons", desc.name), |b| {
            b.iter(|| trace(&tlas, &lights, &cam, &settings, None))
        });
    }
    g.finish();
}

/// An app with the plugin's main world (no renderer) and `n` glass casters in a row, a sun and
/// a still caustics camera, after its first frame; or the same without the plugin (the
/// baseline of Bevy's own frame). Returns the app and the first caster.
fn frame_app(n: usize, plugin: bool) -> (App, Entity) {
    let mut app = App::new();
    // One thread and single-threaded schedules: on 2 cores the multi-threaded executor's
    // wake-ups cost about 270 µs a frame and vary by tens of µs, more than the plugin's
    // systems.
    app.add_plugins((
        MinimalPlugins.set(TaskPoolPlugin {
            task_pool_options: TaskPoolOptions::with_num_threads(1),
        }),
        AssetPlugin::default(),
        bevy::transform::TransformPlugin,
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>();
    if plugin {
        app.add_plugins(bevy_caustics::CausticsPlugin);
    }
    app.finish();
    app.cleanup();
    let single = |s: &mut bevy::ecs::schedule::Schedule| {
        s.set_executor(bevy::ecs::schedule::SingleThreadedExecutor::new());
    };
    app.edit_schedule(First, single)
        .edit_schedule(PreUpdate, single)
        .edit_schedule(Update, single)
        .edit_schedule(PostUpdate, single)
        .edit_schedule(Last, single);
    let w = app.world_mut();
    let mesh = w
        .resource_mut::<Assets<Mesh>>()
        .add(Sphere::new(0.5).mesh().uv(32, 16));
    let mat = w
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            specular_transmission: 1.0,
            ..default()
        });
    let first = (0..n)
        .map(|i| {
            w.spawn((
                Mesh3d(mesh.clone()),
                MeshMaterial3d(mat.clone()),
                Transform::from_xyz(i as f32, 1.0, 0.0),
            ))
            .id()
        })
        .collect::<Vec<_>>()[0];
    w.spawn((
        DirectionalLight::default(),
        bevy_caustics::CausticLight::default(),
    ));
    if plugin {
        w.spawn((
            bevy_caustics::Caustics::default(),
            Transform::from_xyz(0.0, 3.0, 6.0).looking_at(Vec3::ZERO, Vec3::Y),
        ));
    }
    app.update();
    app.update();
    (app, first)
}

/// Main-world CPU cost of one frame (validation + gathering) when one of N casters moves.
fn bench_frame_cpu(c: &mut Criterion) {
    let mut g = c.benchmark_group("frame_cpu_reference");
    for n in [1usize, 10, 100] {
        let (mut app, first) = frame_app(n, true);
        let mut k = 0.0f32;
        g.bench_function(format!("{n}_casters_one_moves"), |b| {
            b.iter_batched(
                || {},
                |_| {
                    k += 0.001;
                    app.world_mut()
                        .entity_mut(first)
                        .insert(Transform::from_xyz(0.0, 1.0 + k, 0.0));
                    app.update();
                },
                BatchSize::PerIteration,
            )
        });
        assert_eq!(app.world().resource::<CausticsScene>().casters, n);
    }
    g.finish();
}

/// Main-world CPU cost of a frame in which nothing changed (issue 16 item 4: targets 20, 50 and
/// 200 µs for 1, 100 and 1000 static casters and a still camera), with the same app without
/// the plugin as the baseline: the plugin's cost is the difference.
fn bench_frame_cpu_static(c: &mut Criterion) {
    let mut g = c.benchmark_group("frame_cpu_static");
    for n in [1usize, 100, 1000] {
        for plugin in [true, false] {
            let (mut app, _) = frame_app(n, plugin);
            let name = if plugin {
                format!("{n}_casters_still")
            } else {
                format!("{n}_casters_still_without_plugin")
            };
            g.bench_function(name, |b| b.iter(|| app.update()));
            if plugin {
                assert_eq!(app.world().resource::<CausticsScene>().casters, n);
            }
        }
    }
    g.finish();
}

/// An app with the renderer (headless, the camera rendering into a 32² image) and the plugin,
/// `n` glass balls in a row over a floor, a sun and a still AAPS camera, after 40 frames: the
/// view has settled (`Caustics::settle_frames` 16) and keeps its caustics buffer. `None` when
/// there is no adapter.
fn render_app(n: usize) -> Option<App> {
    use bevy::asset::RenderAssetUsages;
    use bevy::camera::RenderTarget;
    use bevy::render::RenderPlugin;
    use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};
    use bevy::window::ExitCondition;
    bevy_caustics::headless::find_adapter().ok()?;
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(RenderPlugin {
                synchronous_pipeline_compilation: true,
                ..default()
            })
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .disable::<bevy::winit::WinitPlugin>()
            // The render world stays a sub-app the benchmark can reach.
            .disable::<bevy::render::pipelined_rendering::PipelinedRenderingPlugin>(),
    )
    .add_plugins(bevy_caustics::CausticsPlugin);
    app.finish();
    app.cleanup();
    let w = app.world_mut();
    let mut image = Image::new_fill(
        Extent3d {
            width: 32,
            height: 32,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        &[0u8; 4],
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::default(),
    );
    image.texture_descriptor.usage |= TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC;
    let target = w.resource_mut::<Assets<Image>>().add(image);
    let ball = w
        .resource_mut::<Assets<Mesh>>()
        .add(Sphere::new(0.4).mesh().uv(16, 8));
    let floor = w
        .resource_mut::<Assets<Mesh>>()
        .add(Plane3d::default().mesh().size(4.0 * n as f32 + 4.0, 6.0));
    let glass = w
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            specular_transmission: 1.0,
            ior: 1.5,
            perceptual_roughness: 0.0,
            ..default()
        });
    let grey = w
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::from(Color::srgb(0.6, 0.6, 0.6)));
    for i in 0..n {
        w.spawn((
            Mesh3d(ball.clone()),
            MeshMaterial3d(glass.clone()),
            Transform::from_xyz(i as f32, 1.0, 0.0),
        ));
    }
    w.spawn((Mesh3d(floor), MeshMaterial3d(grey)));
    w.spawn((
        DirectionalLight {
            illuminance: 10_000.0,
            ..default()
        },
        Transform::default().looking_to(Vec3::new(0.2, -1.0, 0.1), Vec3::Y),
        bevy_caustics::CausticLight::default(),
    ));
    w.spawn((
        Camera3d::default(),
        RenderTarget::Image(target.into()),
        Msaa::Off,
        bevy_caustics::Caustics {
            quality: bevy_caustics::CausticsQuality::Custom { photons: 4096 },
            ..default()
        },
        Transform::from_xyz(0.0, 3.0, 6.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    for _ in 0..40 {
        app.update();
    }
    Some(app)
}

/// Render-world CPU cost of a still frame (issue 16 item 4): the plugin's render-world systems
/// of a frame (`render::add_frame_systems_for_bench`: settle tracking, buffers, scene uploads,
/// every technique's view preparation, pipeline variants, the memory count; not the extraction
/// and not the passes, of which a settled view runs only the composite) on the render world of
/// a renderer that has drawn 40 frames of a still scene with 1, 100 and 1000 casters.
fn bench_frame_cpu_render_static(c: &mut Criterion) {
    let mut g = c.benchmark_group("frame_cpu_render_static");
    for n in [1usize, 100, 1000] {
        let Some(mut app) = render_app(n) else {
            eprintln!("frame_cpu_render_static: no GPU adapter, skipped");
            return;
        };
        let mut schedule = bevy::ecs::schedule::Schedule::default();
        schedule.set_executor(bevy::ecs::schedule::SingleThreadedExecutor::new());
        bevy_caustics::render::add_frame_systems_for_bench(&mut schedule);
        let world = app
            .get_sub_app_mut(bevy::render::RenderApp)
            .expect("render app")
            .world_mut();
        let views = world
            .query::<&bevy_caustics::render::settle::ViewSettle>()
            .iter(world)
            .filter(|s| s.keep)
            .count();
        assert_eq!(views, 1, "the view has not settled");
        g.bench_function(format!("{n}_casters_still"), |b| {
            b.iter(|| schedule.run(world))
        });
    }
    g.finish();
}

/// A caustic-like photon set on a 2 m x 2 m floor: half uniform, half in a focus (a Gaussian
/// of 0.1 m), the way a glass ball's photons land.
fn photon_set(n: usize, seed: u64) -> Vec<glam::Vec3> {
    let mut rng = Pcg32::new(seed, 7);
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                glam::Vec3::new(rng.next_f32() * 2.0 - 1.0, 0.0, rng.next_f32() * 2.0 - 1.0)
            } else {
                // Box-Muller.
                let (u, v) = (rng.next_f32().max(1e-7), rng.next_f32());
                let m = 0.1 * (-2.0 * u.ln()).sqrt();
                let a = core::f32::consts::TAU * v;
                glam::Vec3::new(m * a.cos(), 0.0, m * a.sin())
            }
        })
        .collect()
}

/// The seed's rows: (photons per side of the launch grid, radii in metres).
const TABLE_1: [(usize, [f32; 3]); 3] = [
    (512, [0.02, 0.05, 0.1]),
    (256, [0.05, 0.1, 0.2]),
    (128, [0.05, 0.1, 0.2]),
];
const TABLE_2: [(usize, [f32; 3]); 2] = [(512, [0.02, 0.05, 0.1]), (256, [0.05, 0.1, 0.2])];
/// Gather points per frame: a 64 x 64 view of the floor (CI runs each bench once).
const QUERIES: usize = 64 * 64;
/// The max-heap's size of table 2 (the k nearest photons).
const HEAP_K: usize = 64;

fn queries() -> Vec<glam::Vec3> {
    let side = (QUERIES as f32).sqrt() as usize;
    (0..QUERIES)
        .map(|i| {
            let (x, z) = ((i % side) as f32, (i / side) as f32);
            glam::Vec3::new(
                x / side as f32 * 1.6 - 0.8,
                0.0,
                z / side as f32 * 1.6 - 0.8,
            )
        })
        .collect()
}

fn stored(grid: &optics::PhotonGrid, pts: &[glam::Vec3]) -> Vec<optics::StoredPhoton> {
    grid.order
        .iter()
        .map(|&i| optics::StoredPhoton {
            position: pts[i as usize],
            flux: glam::Vec3::splat(1e-3),
            normal: glam::Vec3::Y,
        })
        .collect()
}

/// Every photon within `r` of each query (the hash grid's gather, no heap), summed.
fn gather_all(
    grid: &optics::PhotonGrid,
    ph: &[optics::StoredPhoton],
    qs: &[glam::Vec3],
    r: f32,
) -> f32 {
    qs.iter()
        .map(|q| {
            optics::gather(grid, ph, *q, glam::Vec3::Y, r, -1.0)
                .irradiance
                .x
        })
        .sum()
}

/// Seed 001 table 1: build + one radius query per gather point, kd-tree (kiddo) against the
/// hash grid (`optics::build_grid` + `optics::gather`, the GPU's twin), on the CPU.
fn bench_photon_map_table1(c: &mut Criterion) {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    let mut g = c.benchmark_group("photon_map_table1");
    g.sample_size(10);
    let qs = queries();
    for (side, radii) in TABLE_1 {
        let pts = photon_set(side * side, side as u64);
        let arr: Vec<[f32; 3]> = pts.iter().map(|p| p.to_array()).collect();
        for r in radii {
            g.bench_function(format!("{side}x{side}_r{r}/kd_tree"), |b| {
                b.iter(|| {
                    let tree: ImmutableKdTree<f32, 3> =
                        ImmutableKdTree::new_from_slice(&arr).expect("tree");
                    qs.iter()
                        .map(|q| {
                            tree.query(&q.to_array())
                                .within::<SquaredEuclidean<f32>>(r * r)
                                .unsorted()
                                .execute()
                                .iter()
                                .map(|h| optics::gather_kernel(h.distance, r * r))
                                .sum::<f32>()
                        })
                        .sum::<f32>()
                })
            });
            g.bench_function(format!("{side}x{side}_r{r}/hash_grid"), |b| {
                b.iter(|| {
                    let grid = optics::build_grid(&pts, r, 1.0 / r, optics::MAX_GRID_CELLS);
                    let ph = stored(&grid, &pts);
                    gather_all(&grid, &ph, &qs, r)
                })
            });
        }
    }
    g.finish();
}

/// Seed 001 table 2: the gather over the hash grid keeping the k nearest photons in a max-heap
/// (radius = the k-th distance, Jensen's estimate) against every photon within r (ours).
fn bench_photon_map_table2(c: &mut Criterion) {
    use std::collections::BinaryHeap;
    let mut g = c.benchmark_group("photon_map_table2");
    g.sample_size(10);
    let qs = queries();
    for (side, radii) in TABLE_2 {
        let pts = photon_set(side * side, side as u64);
        for r in radii {
            let grid = optics::build_grid(&pts, r, 1.0 / r, optics::MAX_GRID_CELLS);
            let ph = stored(&grid, &pts);
            g.bench_function(format!("{side}x{side}_r{r}/heap_k{HEAP_K}"), |b| {
                b.iter(|| {
                    let mut heap: BinaryHeap<(u32, u32)> = BinaryHeap::with_capacity(HEAP_K + 1);
                    qs.iter()
                        .map(|q| {
                            heap.clear();
                            for (a, e) in grid.layout.rows(*q, 1).into_iter().flatten() {
                                let range = grid.start[a as usize]..grid.start[e as usize];
                                for i in range {
                                    let d2 = (ph[i as usize].position - *q).length_squared();
                                    if d2 < r * r {
                                        heap.push((d2.to_bits(), i));
                                        if heap.len() > HEAP_K {
                                            heap.pop();
                                        }
                                    }
                                }
                            }
                            let r2 = heap.peek().map_or(0.0, |h| f32::from_bits(h.0));
                            heap.iter()
                                .map(|&(_, i)| ph[i as usize].flux.x)
                                .sum::<f32>()
                                / (core::f32::consts::PI * r2).max(1e-12)
                        })
                        .sum::<f32>()
                })
            });
            g.bench_function(format!("{side}x{side}_r{r}/all_within_r"), |b| {
                b.iter(|| gather_all(&grid, &ph, &qs, r))
            });
        }
    }
    g.finish();
}

criterion_group!(
    benches,
    bench_optics,
    bench_bvh,
    bench_tracer,
    bench_frame_cpu,
    bench_frame_cpu_static,
    bench_frame_cpu_render_static,
    bench_photon_map_table1,
    bench_photon_map_table2
);
criterion_main!(benches);
