//! Single-thread ray throughput of the native BVH (both builders): camera rays,
//! incoherent rays (uniform directions from the camera hits, like diffuse
//! bounces) and shadow segments (from the camera hits to points near the top of
//! the scene), over a generated mesh and, when the course scenes are present,
//! over CBbunny. Criterion's throughput is in rays per second.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use ember::accel::{Accel, Bvh, BvhBuilder};
use ember::camera::Camera;
use ember::geometry::{Aabb, Ray};
use ember::sampling::{uniform_sphere, Rng};
use ember::scene::{collada, Scene, Triangle, NO_LIGHT};
use glam::{Vec2, Vec3};
use std::path::Path;

const IMAGE: u32 = 256;

/// A bumpy sphere, `n × 2n` quads: about `4n²` triangles with shared vertices.
fn generated_mesh(n: usize) -> Scene {
    let mut positions = Vec::new();
    for i in 0..=n {
        for j in 0..=2 * n {
            let (theta, phi) = (
                std::f32::consts::PI * i as f32 / n as f32,
                std::f32::consts::PI * j as f32 / n as f32,
            );
            let r = 1.0 + 0.05 * (7.0 * theta).sin() * (5.0 * phi).cos();
            positions.push(
                r * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                ),
            );
        }
    }
    let at = |i: usize, j: usize| (i * (2 * n + 1) + j) as u32;
    let mut triangles = Vec::new();
    let mut tri = |v: [u32; 3]| {
        triangles.push(Triangle {
            v,
            n: None,
            material: 0,
            light: NO_LIGHT,
        })
    };
    for i in 0..n {
        for j in 0..2 * n {
            tri([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            tri([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let bounds = positions.iter().fold(Aabb::EMPTY, |mut b, &p| {
        b.grow(p);
        b
    });
    Scene {
        positions,
        triangles,
        bounds,
        ..Scene::default()
    }
}

struct Workload {
    camera: Vec<Ray>,
    incoherent: Vec<Ray>,
    shadow: Vec<Ray>,
}

fn workload(scene: &Scene, bvh: &Bvh) -> Workload {
    let cam = Camera::new(&scene.camera, &scene.bounds, IMAGE, IMAGE);
    let mut rng = Rng::from_seed(1);
    let camera: Vec<Ray> = (0..IMAGE * IMAGE)
        .map(|k| cam.generate_ray(k % IMAGE, k / IMAGE, Vec2::splat(0.5)))
        .collect();
    let (mut incoherent, mut shadow) = (Vec::new(), Vec::new());
    let top = scene.bounds.centre() + 0.45 * scene.bounds.diagonal().y * Vec3::Y;
    for ray in &camera {
        let Some(hit) = bvh.intersect(ray) else {
            continue;
        };
        let si = scene.interaction(ray, &hit);
        let w = uniform_sphere(rng.next_2d());
        incoherent.push(si.spawn_ray(w));
        let target = top + 0.1 * scene.bounds.diagonal().length() * uniform_sphere(rng.next_2d());
        shadow.push(si.spawn_segment(target, 1.0 - 1e-4));
    }
    Workload {
        camera,
        incoherent,
        shadow,
    }
}

fn bench_scene(c: &mut Criterion, name: &str, scene: &Scene) {
    for builder in [BvhBuilder::Sah, BvhBuilder::Midpoint] {
        let bvh = Bvh::build(scene, builder);
        let work = workload(scene, &bvh);
        let mut group = c.benchmark_group(format!("{name}/{builder:?}"));
        group.sample_size(10);
        group.measurement_time(std::time::Duration::from_secs(2));
        group.warm_up_time(std::time::Duration::from_millis(500));
        for (kind, rays) in [("camera", &work.camera), ("incoherent", &work.incoherent)] {
            group.throughput(Throughput::Elements(rays.len() as u64));
            group.bench_function(kind, |b| {
                b.iter(|| {
                    rays.iter()
                        .filter(|r| bvh.intersect(black_box(r)).is_some())
                        .count()
                })
            });
        }
        group.throughput(Throughput::Elements(work.shadow.len() as u64));
        group.bench_function("shadow", |b| {
            b.iter(|| {
                work.shadow
                    .iter()
                    .filter(|r| bvh.occluded(black_box(r)))
                    .count()
            })
        });
        group.finish();
    }
}

fn benches(c: &mut Criterion) {
    bench_scene(c, "generated-32k", &generated_mesh(90));
    let bunny = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/cs184/sky/CBbunny.dae"
    ));
    if let Ok(scene) = collada::load(bunny) {
        bench_scene(c, "CBbunny", &scene);
    }
}

criterion_group!(bvh_benches, benches);
criterion_main!(bvh_benches);
