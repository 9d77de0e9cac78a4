//! `ember export --format mitsuba`: the files are well formed and complete, and
//! Mitsuba 3 renders the exported scene to the same image mean as ember, within the
//! two renders' noise.
//!
//! The comparison needs Mitsuba, found through `EMBER_MITSUBA_PYTHON` or the project's
//! `.cache/mitsuba` environment (`scripts/mitsuba-env` creates it), so a plain
//! `cargo test` ignores it; scripts/test installs Mitsuba and runs it with `--ignored`.

use crate::common;

use common::{ember, repo};
use ember::image_io::read_image;
use std::path::{Path, PathBuf};
use std::process::Command;

fn export(scene: &str, dir: &Path, spp: u32, m: u32) -> PathBuf {
    let path = repo(scene);
    ember([
        "export",
        "--format",
        "mitsuba",
        path.to_str().unwrap(),
        "-r",
        "160",
        "120",
        "-s",
        &spp.to_string(),
        "-m",
        &m.to_string(),
        "--out",
        dir.to_str().unwrap(),
    ])
    .success();
    dir.join(format!(
        "{}.xml",
        path.file_stem().unwrap().to_string_lossy()
    ))
}

/// Triangle count of a binary PLY written by the exporter, from its header.
fn ply_faces(path: &Path) -> usize {
    let bytes = std::fs::read(path).unwrap();
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(512)]).into_owned();
    header
        .lines()
        .find_map(|l| l.strip_prefix("element face "))
        .and_then(|n| n.trim().parse().ok())
        .expect("face count in PLY header")
}

#[test]
fn export_is_complete_and_well_formed() {
    let dir = tempfile::tempdir().unwrap();
    let xml_path = export("scenes/cs184/sky/CBspheres.dae", dir.path(), 16, 5);
    let text = std::fs::read_to_string(&xml_path).unwrap();
    let doc = roxmltree::Document::parse(&text).expect("exported XML parses");
    let scene = ember::scene::collada::load(&repo("scenes/cs184/sky/CBspheres.dae")).unwrap();

    let shapes: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("shape"))
        .collect();
    let spheres = shapes
        .iter()
        .filter(|s| s.attribute("type") == Some("sphere"))
        .count();
    assert_eq!(spheres, scene.spheres.len());
    let faces: usize = shapes
        .iter()
        .filter(|s| s.attribute("type") == Some("ply"))
        .map(|s| {
            let file = s
                .children()
                .find(|c| c.attribute("name") == Some("filename"))
                .and_then(|c| c.attribute("value"))
                .unwrap();
            ply_faces(&dir.path().join(file))
        })
        .sum();
    assert_eq!(faces, scene.triangles.len(), "every triangle exported once");

    let int = |name: &str| {
        doc.descendants()
            .find(|n| n.attribute("name") == Some(name))
            .and_then(|n| n.attribute("value"))
            .unwrap()
            .to_string()
    };
    assert_eq!(int("max_depth"), "6", "Mitsuba counts segments: m + 1");
    assert_eq!(int("sample_count"), "16");
    // The area light is an emitter on its own triangles; the glass is a dielectric.
    assert!(doc
        .descendants()
        .any(|n| n.has_tag_name("emitter") && n.attribute("type") == Some("area")));
    assert!(doc
        .descendants()
        .any(|n| n.has_tag_name("bsdf") && n.attribute("type") == Some("dielectric")));
}

#[test]
fn export_writes_sky_and_point_lights() {
    let dir = tempfile::tempdir().unwrap();
    let xml = export("scenes/cs184/sky/CBempty.dae", dir.path(), 4, 1);
    let text = std::fs::read_to_string(xml).unwrap();
    assert!(text.contains("<emitter type=\"point\">"), "{text}");
}

/// The Python that imports Mitsuba: `EMBER_MITSUBA_PYTHON`, else the project's own.
fn mitsuba_python() -> PathBuf {
    let python = std::env::var_os("EMBER_MITSUBA_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo(".cache/mitsuba/bin/python"));
    let ok = Command::new(&python)
        .args(["-c", "import mitsuba, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        ok,
        "{}: no Mitsuba 3 (run scripts/mitsuba-env, or set EMBER_MITSUBA_PYTHON)",
        python.display()
    );
    python
}

/// Per-channel image means of `n` independent renders.
type Means = Vec<[f64; 3]>;

fn mitsuba_means(python: &Path, xml: &Path, n: usize) -> Means {
    let script = repo("scripts/mitsuba-render.py");
    let out = Command::new(python)
        .arg(script)
        .arg(xml)
        .args(["--variant", "scalar_rgb", "--renders", &n.to_string()])
        .output()
        .expect("run Mitsuba");
    assert!(
        out.status.success(),
        "Mitsuba failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            let m = &v["mean_rgb"];
            [0, 1, 2].map(|c| m[c].as_f64().unwrap())
        })
        .collect()
}

fn ember_means(scene: &str, dir: &Path, spp: u32, m: u32, n: usize) -> Means {
    (0..n)
        .map(|seed| {
            let out = dir.join(format!("ember{seed}.exr"));
            ember([
                "-s",
                &spp.to_string(),
                "-m",
                &m.to_string(),
                "-r",
                "160",
                "120",
                "--seed",
                &(1000 + seed).to_string(),
                "-f",
                out.to_str().unwrap(),
                repo(scene).to_str().unwrap(),
            ])
            .success();
            let mean = read_image(&out).unwrap().mean();
            [mean.x as f64, mean.y as f64, mean.z as f64]
        })
        .collect()
}

fn mean_var(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var)
}

/// Welch's t on each channel's image mean, on every reference scene and the course's
/// glossy, glass and textured ones. 8 renders a side: t beyond 5.4 has probability
/// below 0.1% per channel under the null. No slack for geometric differences between
/// the two renderers: the 1% of the mean once allowed was not needed (the largest
/// |t| over these 27 channels was 2.7, 0.17% of the mean, when measured).
#[test]
#[ignore = "needs Mitsuba 3 (scripts/mitsuba-env); scripts/test runs it"]
fn mitsuba_renders_the_exported_scene_to_embers_mean() {
    let python = mitsuba_python();
    const RENDERS: usize = 8;
    const SPP: u32 = 8;
    for (scene, m) in [
        ("scenes/cs184/sky/CBspheres_lambertian.dae", 5),
        ("scenes/cs184/sky/CBspheres.dae", 5),
        ("scenes/cs184/sky/CBbunny.dae", 5),
        ("scenes/cs184/sky/CBempty.dae", 5),
        ("scenes/cs184/sky/CBspheres_microfacet_al_ag.dae", 5),
        ("scenes/cs184/sky/CBbunny_microfacet_cu.dae", 5),
        ("scenes/cs184/sky/CBgems.dae", 8),
        ("scenes/cs184/keenan/banana.dae", 3),
        ("scenes/cs184/sky/CBcoil.dae", 5),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let xml = export(scene, dir.path(), SPP, m);
        let theirs = mitsuba_means(&python, &xml, RENDERS);
        let ours = ember_means(scene, dir.path(), SPP, m, RENDERS);
        assert_eq!(theirs.len(), RENDERS);
        for c in 0..3 {
            let (mo, vo) = mean_var(&ours.iter().map(|x| x[c]).collect::<Vec<_>>());
            let (mt, vt) = mean_var(&theirs.iter().map(|x| x[c]).collect::<Vec<_>>());
            let se = ((vo + vt) / RENDERS as f64).sqrt();
            let diff = (mo - mt).abs();
            eprintln!(
                "{scene} channel {c}: ember {mo:.5} vs Mitsuba {mt:.5}, t {:.2}, {:.3} %",
                diff / se,
                100.0 * diff / mt
            );
            assert!(
                diff <= 5.4 * se,
                "{scene} channel {c}: ember {mo:.5} vs Mitsuba {mt:.5} (se {se:.2e})"
            );
        }
    }
}

/// `--sampler` names the `<sampler>` and rounds a count it does not take, saying so.
#[test]
fn export_sampler_option_rounds_the_count_it_does_not_take() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let out = ember([
        "export",
        scene.to_str().unwrap(),
        "-s",
        "8",
        "--sampler",
        "ldsampler",
        "--out",
        dir.path().to_str().unwrap(),
    ])
    .success();
    let stderr = out.stderr();
    assert!(
        stderr.contains("ldsampler") && stderr.contains("16"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(dir.path().join("CBspheres_lambertian.xml")).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let sampler = doc
        .descendants()
        .find(|n| n.has_tag_name("sampler"))
        .unwrap();
    assert_eq!(sampler.attribute("type"), Some("ldsampler"));
    let count = sampler.first_element_child().unwrap();
    assert_eq!(count.attribute("value"), Some("16"));
}

/// `--camera-placement` moves the exported camera as it moves ember's: on a course
/// file, `auto` is the course's rule and `file` the camera node's own position.
#[test]
fn export_places_the_camera_as_the_render_flag_says() {
    let scene = repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let origin = |placement: &str| {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().to_str().unwrap();
        ember([
            "export",
            scene.to_str().unwrap(),
            "--camera-placement",
            placement,
            "--out",
            out,
        ])
        .success();
        let text = std::fs::read_to_string(dir.path().join("CBspheres_lambertian.xml")).unwrap();
        let doc = roxmltree::Document::parse(&text).unwrap();
        let lookat = doc
            .descendants()
            .find(|n| n.has_tag_name("lookat"))
            .unwrap();
        lookat.attribute("origin").unwrap().to_string()
    };
    let (auto, course, file) = (origin("auto"), origin("course"), origin("file"));
    assert_eq!(auto, course);
    assert_ne!(course, file);
}

/// ember's idea of the counts each Mitsuba sampler takes (what `ember bench converge`
/// renders and checks) is Mitsuba's own, asked of Mitsuba for the doubling sequence.
#[test]
#[ignore = "needs Mitsuba 3 (scripts/mitsuba-env); scripts/test runs it"]
fn mitsuba_samplers_round_counts_as_ember_expects() {
    use ember::export::MitsubaSampler;
    use ember::names::Named;
    let python = mitsuba_python();
    let counts: Vec<u32> = (0..11).map(|k| 1 << k).collect();
    let list = counts
        .iter()
        .map(u32::to_string)
        .collect::<Vec<_>>()
        .join(",");
    for &(sampler, name, _) in MitsubaSampler::TABLE {
        let code = format!(
            "import mitsuba as mi; mi.set_variant('scalar_rgb'); mi.set_log_level(mi.LogLevel.Error); \
             print(' '.join(str(mi.load_dict({{'type': '{name}', 'sample_count': n}}).sample_count()) \
             for n in [{list}]))"
        );
        let out = Command::new(&python).args(["-c", &code]).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let theirs: Vec<u32> = String::from_utf8_lossy(&out.stdout)
            .split_whitespace()
            .map(|n| n.parse().unwrap())
            .collect();
        let ours: Vec<u32> = counts.iter().map(|&n| sampler.sample_count(n)).collect();
        assert_eq!(ours, theirs, "{name}");
    }
}
