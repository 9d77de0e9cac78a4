use ember::geometry::triangle::intersect_triangle;
use ember::geometry::Ray;
use glam::Vec3;
fn main() {
    let scene = ember::scene::collada::load(std::path::Path::new(
        "../shared/scenes/cs184/keenan/building.dae",
    ))
    .unwrap();
    let ray = Ray {
        o: Vec3::new(-0.52676046, -0.00011339248, 0.44290173),
        d: Vec3::new(0.06229403, 0.5960256, -0.80054545),
        t_min: 0.0,
        t_max: f32::INFINITY,
    };
    let [a, b, c] = scene.triangle_positions(39498);
    println!(
        "{a} {b} {c} {:?} {:?}",
        intersect_triangle(&ray, a, b, c),
        scene.prim_bounds(39498)
    );
    println!("hit point {}", ray.at(0.00019021626));
}
