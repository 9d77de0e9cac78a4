//! The command line end to end: flags, errors, and never a partial output file.

mod common;

use common::{ember, repo};

#[test]
fn cs184_command_line_is_accepted_verbatim() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.png");
    let st = ember()
        .args([
            "-t", "2", "-s", "2", "-l", "2", "-m", "2", "-r", "32", "24", "-f",
        ])
        .arg(&out)
        .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae"))
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (32, 24));
}

#[test]
fn exr_output_and_adaptive_rate_map() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    let st = ember()
        .args([
            "-s", "64", "-a", "8", "0.1", "-m", "1", "-r", "64", "48", "-f",
        ])
        .arg(&out)
        .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae"))
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let img = ember::image_io::read_image(&out).unwrap();
    assert_eq!((img.width, img.height), (64, 48));
    // The light is seen directly at radiance 10: EXR keeps linear values above 1.
    assert!(img.pixels.iter().any(|p| p.x > 5.0));
    assert!(dir.path().join("x_rate.exr").exists());
}

fn fails_with(args: &[&str], needle: &str) {
    let st = ember().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(!st.status.success(), "{args:?} succeeded");
    assert!(
        err.contains(needle),
        "{args:?}: stderr {err:?} lacks {needle:?}"
    );
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
}

#[test]
fn bad_flags_and_paths_fail_cleanly() {
    let scene = repo("scenes/cs184/sky/CBempty.dae");
    let scene = scene.to_str().unwrap();
    fails_with(&["--frobnicate", scene], "--frobnicate");
    fails_with(&["-s", "zero", scene], "-s");
    fails_with(&["-o", "2", scene], "-o");
    fails_with(&["-r", "0", "10", scene], "resolution");
    fails_with(&["-f", "out.jpg", scene], "out.jpg");
    fails_with(&["/nonexistent/scene.dae"], "/nonexistent/scene.dae");
    fails_with(&["--accel", "bogus", scene], "bogus");
    fails_with(&["-a", "0", "0.05", scene], "BATCH");
}

#[test]
fn unwritable_output_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("no/such/dir/out.png");
    let st = ember()
        .args(["-s", "1", "-r", "8", "6", "-f"])
        .arg(&target)
        .arg(repo("scenes/cs184/sky/CBempty.dae"))
        .output()
        .unwrap();
    assert!(!st.status.success());
    assert!(String::from_utf8_lossy(&st.stderr).contains("out.png"));
    assert!(!target.exists());
    // A directory in place of the file: the write fails and the temporary is cleaned up.
    let as_dir = dir.path().join("taken.png");
    std::fs::create_dir(&as_dir).unwrap();
    let st = ember()
        .args(["-s", "1", "-r", "8", "6", "-f"])
        .arg(&as_dir)
        .arg(repo("scenes/cs184/sky/CBempty.dae"))
        .output()
        .unwrap();
    assert!(!st.status.success());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        leftovers,
        vec![std::ffi::OsString::from("taken.png")],
        "a temporary file was left behind"
    );
}

#[test]
fn malformed_scene_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken.dae");
    std::fs::write(
        &bad,
        "<COLLADA><library_geometries><geometry id=\"g\"><mesh>",
    )
    .unwrap();
    let out = dir.path().join("o.png");
    let st = ember().arg("-f").arg(&out).arg(&bad).output().unwrap();
    assert!(!st.status.success());
    assert!(String::from_utf8_lossy(&st.stderr).contains("broken.dae"));
    assert!(!out.exists());
}

#[test]
fn embree_request_without_feature_says_how_to_get_it() {
    if cfg!(any(feature = "embree", feature = "embree4")) {
        return;
    }
    let st = ember()
        .args(["--accel", "embree", "-r", "8", "6"])
        .arg(repo("scenes/cs184/sky/CBempty.dae"))
        .output()
        .unwrap();
    assert!(!st.status.success());
    assert!(String::from_utf8_lossy(&st.stderr).contains("rebuild with --features embree"));
}

#[test]
fn info_says_what_accel_auto_picks_and_why() {
    let st = ember()
        .arg("info")
        .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae"))
        .output()
        .unwrap();
    assert!(st.status.success());
    let text = String::from_utf8_lossy(&st.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("--accel auto"))
        .unwrap_or_else(|| panic!("no auto line in {text}"));
    // 14 primitives: the native BVH, whether or not this build has Embree.
    assert!(line.contains("picks native SAH"), "{line}");
    assert!(
        line.contains("14 primitives") || line.contains("no Embree"),
        "{line}"
    );
}

/// `-t 1 2` takes both counts (not `2` as a scene), and `--append` adds a second
/// run's rows to the tables already written.
#[cfg(feature = "bench")]
#[test]
fn bench_accel_takes_several_thread_counts_and_appends() {
    let dir = tempfile::tempdir().unwrap();
    let run = |append: bool| {
        let mut c = ember();
        c.args([
            "bench",
            "accel",
            "mesh:2000",
            "--rays",
            "2000",
            "--repeats",
            "1",
        ])
        .args(["--no-embree-modes", "--out"])
        .arg(dir.path())
        .args(["-t", "1", "2"]);
        if append {
            c.arg("--append");
        }
        let st = c.output().unwrap();
        assert!(
            st.status.success(),
            "{}",
            String::from_utf8_lossy(&st.stderr)
        );
        std::fs::read_to_string(dir.path().join("accel.csv")).unwrap()
    };
    // Nothing to append to yet: an error naming the file, before any measuring.
    let st = ember()
        .args(["bench", "accel", "mesh:2000", "--append", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(!st.status.success());
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(err.contains("accel.csv: cannot read"), "{err}");
    assert!(!err.contains("Mrays/s"), "measured before failing: {err}");
    let backends = if cfg!(any(feature = "embree", feature = "embree4")) {
        4
    } else {
        2
    };
    let first = run(false);
    assert_eq!(first.lines().count(), 1 + 2 * backends, "{first}");
    assert!(first
        .lines()
        .skip(1)
        .all(|l| l.starts_with("displaced sphere (2k tris),")));
    let both = run(true);
    assert_eq!(both.lines().count(), 1 + 4 * backends, "{both}");
    let md = std::fs::read_to_string(dir.path().join("accel.md")).unwrap();
    assert_eq!(md.lines().count(), 2 + 4 * backends, "{md}");
}

#[test]
fn light_tracing_from_the_command_line_and_its_warning_on_glass() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lt.exr");
    let run = |scene: &str| {
        ember()
            .args([
                "--integrator",
                "light-tracing",
                "-s",
                "2",
                "-m",
                "3",
                "-r",
                "32",
                "24",
                "-q",
                "-f",
            ])
            .arg(&out)
            .arg(repo(scene))
            .output()
            .unwrap()
    };
    let st = run("scenes/cs184/sky/CBempty.dae");
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    assert!(String::from_utf8_lossy(&st.stderr).is_empty());
    let img = ember::image_io::read_image(&out).unwrap();
    assert!(img.all_finite() && img.mean_luminance() > 0.0);
    // Mirrors and glass cannot be connected to a pinhole: ember says so.
    let st = run("scenes/cs184/sky/CBspheres.dae");
    assert!(st.status.success());
    assert!(String::from_utf8_lossy(&st.stderr).contains("mirror or glass"));
}
