//! Criterion benchmarks: the optics core, BVH build and traversal, the reference tracer
//! (photons per second) and the main-world CPU cost of a frame for 1, 10 and 100 casters.
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

/// Main-world CPU cost of one frame (validation + gathering) when one of N casters moves.
fn bench_frame_cpu(c: &mut Criterion) {
    let mut g = c.benchmark_group("frame_cpu_reference");
    for n in [1usize, 10, 100] {
        let mut app = App::new();
        app.add_plugins((
            MinimalPlugins,
            AssetPlugin::default(),
            bevy::transform::TransformPlugin,
        ))
        .init_asset::<Mesh>()
        .init_asset::<StandardMaterial>()
        .add_plugins(bevy_caustics::CausticsPlugin);
        app.finish();
        app.cleanup();
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
        app.update();
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

criterion_group!(
    benches,
    bench_optics,
    bench_bvh,
    bench_tracer,
    bench_frame_cpu
);
criterion_main!(benches);
