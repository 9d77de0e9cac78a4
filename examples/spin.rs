use ember::accel::{
    Accel, AccelBuilder, EmbreeMode, EmbreeQuality, EmbreeQueries, EmbreeSelfHits, EmbreeSpheres,
};
fn threads() -> String {
    let mut out = String::new();
    for e in std::fs::read_dir("/proc/self/task").unwrap() {
        let s = std::fs::read_to_string(e.unwrap().path().join("stat")).unwrap();
        let f: Vec<&str> = s.rsplit(')').next().unwrap().split_whitespace().collect();
        out += &format!("{}/{} ", f[11], f[12]);
    }
    out
}
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let scene = ember::scene::collada::load(std::path::Path::new(&path)).unwrap();
    let base = EmbreeMode::robust(EmbreeQuality::Medium);
    let modes = [
        ("default", base),
        (
            "embree spheres",
            EmbreeMode {
                spheres: EmbreeSpheres::Embree,
                ..base
            },
        ),
        (
            "single",
            EmbreeMode {
                queries: EmbreeQueries::Single,
                ..base
            },
        ),
        (
            "packet16 filter",
            EmbreeMode {
                queries: EmbreeQueries::Packet16,
                self_hits: EmbreeSelfHits::Filter,
                ..base
            },
        ),
        ("before", EmbreeMode::before(EmbreeQuality::Medium)),
    ];
    let pool = ember::accel::tracing_pool(Some(1)).unwrap();
    for (name, mode) in modes {
        pool.install(|| {
            let b = AccelBuilder::new(1);
            let a = b.build_embree(&scene, mode).unwrap();
            let r = ember::geometry::Ray::new(scene.bounds.centre(), glam::Vec3::X);
            for _ in 0..1000 {
                std::hint::black_box(a.intersect(&r));
            }
        });
        std::thread::sleep(std::time::Duration::from_millis(1500));
        println!("{name}: {}", threads());
    }
}
