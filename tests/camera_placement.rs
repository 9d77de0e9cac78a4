//! `--camera-placement` (issue 26): a file another tool wrote keeps its camera's
//! position by default; the flag chooses either placement for `ember camera` and renders.

use crate::common;

use common::ember;

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/collada/spot_plane.dae"
);

/// The eye (`pos`) of the course camera file `ember camera` prints.
fn eye(placement: Option<&str>) -> Vec<f64> {
    let mut args = vec!["camera", "-r", "8", "8", SCENE];
    if let Some(p) = placement {
        args.extend(["--camera-placement", p]);
    }
    let text = ember(args).success().stdout();
    let line = text.lines().nth(1).unwrap();
    line.split_whitespace()
        .take(3)
        .map(|v| v.parse().unwrap())
        .collect()
}

#[test]
fn the_flag_overrides_the_loaders_placement() {
    // spot_plane.dae names an authoring tool other than the course's: its camera node at
    // (0, 1.5, 0) is the eye.
    assert_eq!(eye(None), vec![0.0, 1.5, 0.0]);
    assert_eq!(eye(Some("auto")), vec![0.0, 1.5, 0.0]);
    assert_eq!(eye(Some("file")), vec![0.0, 1.5, 0.0]);
    // The course's rule: the floor's centre (0, 0, 0), 1.5 diagonals (8√2) back along −Y.
    let course = eye(Some("course"));
    assert!(
        (course[1] - 1.5 * 8.0 * 2f64.sqrt()).abs() < 1e-4,
        "{course:?}"
    );
    ember(["camera", "--camera-placement", "nowhere", SCENE]).fails_with("--camera-placement");
}

/// The `placement:` and `why:` lines of `ember info` with `args` before the scene.
fn info_placement(args: &[&str], scene: &str) -> (String, String) {
    let mut all = vec!["info"];
    all.extend(args);
    all.push(scene);
    let text = ember(all).success().stdout();
    let line = |key: &str| {
        let found = text.lines().map(str::trim).find(|l| l.starts_with(key));
        found.unwrap_or_else(|| panic!("{text}")).to_string()
    };
    (line("placement: "), line("why: "))
}

#[test]
fn info_takes_the_flag_and_says_which_placement_and_why() {
    let (placement, why) = info_placement(&[], SCENE);
    assert_eq!(placement, "placement: the file's camera position");
    assert!(
        why.contains("\"ember test scenes\", not by the course's exporter"),
        "{why}"
    );
    let (placement, why) = info_placement(&["--camera-placement", "course"], SCENE);
    assert!(
        placement.starts_with("placement: course rule (centre"),
        "{placement}"
    );
    assert_eq!(why, "why: --camera-placement course");
    let (placement, why) = info_placement(&["--camera-placement", "file"], SCENE);
    assert_eq!(placement, "placement: the file's camera position");
    assert_eq!(why, "why: --camera-placement file");
    ember(["info", "--camera-placement", "nowhere", SCENE]).fails_with("--camera-placement");
}

#[test]
fn info_agrees_with_itself_when_the_file_has_no_camera() {
    // Another tool's file without a camera: the course's rule, and the reason says so.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(SCENE).unwrap();
    let cut = text.replace(r##"<instance_camera url="#cam"/>"##, "");
    assert_ne!(cut, text);
    let scene = dir.path().join("no_camera.dae");
    std::fs::write(&scene, cut).unwrap();
    let scene = scene.to_str().unwrap();
    for args in [&[][..], &["--camera-placement", "file"]] {
        let (placement, why) = info_placement(args, scene);
        assert_eq!(placement, "placement: course rule (the file has no camera)");
        assert!(
            why.ends_with("the file has no camera, so the course's rule places the eye"),
            "{why}"
        );
        assert!(!why.contains("the file's placement"), "{why}");
    }
}
