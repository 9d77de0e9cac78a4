//! `--camera-placement` (issue 26): a file another tool wrote keeps its camera's
//! position by default; the flag chooses either placement for `ember camera` and renders.

mod common;

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
