//! The course's camera flags end to end: `-c` camera settings files (and `ember camera
//! --save`), `-p` cells, `-b`/`-d` thin lens. Images are compared as linear EXR, bit for bit.

use crate::common;

use common::{command, repo, run, Run};
use ember::film::Image;
use std::path::Path;

const SPHERES: &str = "scenes/cs184/sky/CBspheres_lambertian.dae";
const BUNNY: &str = "scenes/cs184/sky/CBbunny.dae";

/// `ember ARGS -f OUT SCENE`.
fn render_run(args: &[&str], out: &Path, scene: &str) -> Run {
    run(command().args(args).arg("-f").arg(out).arg(repo(scene)))
}

/// Renders and reads the image back.
fn render(args: &[&str], out: &Path, scene: &str) -> Image {
    render_run(args, out, scene).success();
    ember::image_io::read_image(out).unwrap()
}

/// Expects a one-line error containing every needle, and no image.
fn expect_error(args: &[&str], out: &Path, scene: &str, needles: &[&str]) {
    let failed = render_run(args, out, scene);
    needles.iter().fold(failed, |r, n| r.fails_with(n));
    assert!(!out.exists(), "an image was written");
}

const BASE: &[&str] = &["-q", "-s", "3", "-m", "2", "-r", "40", "30"];

fn with<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    BASE.iter().copied().chain(extra.iter().copied()).collect()
}

#[test]
fn saved_camera_renders_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    for scene in [SPHERES, BUNNY] {
        let cam = dir.path().join("view.cam");
        run(command()
            .args(["camera", "-r", "40", "30", "--save"])
            .arg(&cam)
            .arg(repo(scene)))
        .success();
        let text = std::fs::read_to_string(&cam).unwrap();
        // The course's six lines: 5, 6, 5, 9, 3, 2 numbers.
        let counts: Vec<usize> = text.lines().map(|l| l.split_whitespace().count()).collect();
        assert_eq!(counts, [5, 6, 5, 9, 3, 2], "{text}");
        let plain = render(BASE, &dir.path().join("plain.exr"), scene);
        let cam_arg = cam.to_str().unwrap();
        let loaded = render(&with(&["-c", cam_arg]), &dir.path().join("c.exr"), scene);
        assert_eq!(plain.pixels, loaded.pixels, "{scene}");
        let meta = ember::image_io::read_metadata(&dir.path().join("c.exr")).unwrap();
        assert_eq!(meta.get("ember.camera_file"), Some(cam_arg));
    }
}

#[test]
fn saved_lens_is_used_and_flags_replace_it() {
    let dir = tempfile::tempdir().unwrap();
    let cam = dir.path().join("lens.cam");
    run(command()
        .args(["camera", "-r", "40", "30", "-b", "0.1", "-d", "3", "--save"])
        .arg(&cam)
        .arg(repo(BUNNY)))
    .success();
    let cam_arg = cam.to_str().unwrap();
    let flags = render(
        &with(&["-b", "0.1", "-d", "3"]),
        &dir.path().join("flags.exr"),
        BUNNY,
    );
    let file = render(&with(&["-c", cam_arg]), &dir.path().join("file.exr"), BUNNY);
    assert_eq!(flags.pixels, file.pixels);
    let plain = render(BASE, &dir.path().join("plain.exr"), BUNNY);
    let pinhole = render(
        &with(&["-c", cam_arg, "-b", "0"]),
        &dir.path().join("pinhole.exr"),
        BUNNY,
    );
    assert_eq!(plain.pixels, pinhole.pixels);
}

#[test]
fn camera_without_save_prints_the_file() {
    let text = run(command()
        .args(["camera", "-b", "0.05", "-d", "3.5"])
        .arg(repo(SPHERES)))
    .success()
    .stdout();
    assert_eq!(text.lines().count(), 6);
    assert_eq!(text.lines().last(), Some("3.5 0.05"));
}

#[test]
fn camera_file_moves_the_view() {
    // The scene's camera moved 0.3 to its right: a different image, not an error.
    let dir = tempfile::tempdir().unwrap();
    let text = run(command()
        .args(["camera", "-r", "40", "30"])
        .arg(repo(SPHERES)))
    .success()
    .stdout();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut pos: Vec<f32> = lines[1]
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect();
    let right: Vec<f32> = lines[3]
        .split_whitespace()
        .step_by(3)
        .map(|w| w.parse().unwrap())
        .collect();
    for k in 0..3 {
        pos[k] += 0.3 * right[k];
    }
    lines[1] = pos
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(" ");
    let cam = dir.path().join("moved.cam");
    std::fs::write(&cam, lines.join("\n")).unwrap();
    let plain = render(BASE, &dir.path().join("plain.exr"), SPHERES);
    let moved = render(
        &with(&["-c", cam.to_str().unwrap()]),
        &dir.path().join("moved.exr"),
        SPHERES,
    );
    // 0.3 to the right is about 2.7 pixels at the spheres' depth: the view slides left.
    let shift = best_shift(&column_profile(&plain), &column_profile(&moved));
    assert!(
        (2..=3).contains(&shift),
        "the view moved by {shift} columns"
    );
}

/// The mean of each column of `img`, summed over channels.
fn column_profile(img: &Image) -> Vec<f64> {
    let w = img.width as usize;
    let mut cols = vec![0.0; w];
    for (i, p) in img.pixels.iter().enumerate() {
        cols[i % w] += f64::from(p.x + p.y + p.z) / f64::from(img.height);
    }
    cols
}

/// The `k` in -6..=6 for which `moved[x]` best matches `plain[x + k]` (least mean
/// squared difference over the columns both hold).
fn best_shift(plain: &[f64], moved: &[f64]) -> i32 {
    let n = plain.len() as i32;
    let error = |k: i32| {
        let xs = (0..n).filter(|&x| (0..n).contains(&(x + k)));
        let d: Vec<f64> = xs
            .map(|x| plain[(x + k) as usize] - moved[x as usize])
            .collect();
        d.iter().map(|d| d * d).sum::<f64>() / d.len() as f64
    };
    (-6..=6)
        .min_by(|&a, &b| error(a).total_cmp(&error(b)))
        .unwrap()
}

#[test]
fn malformed_camera_files_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = "49.13 37.85 1.3333 0.1 100\n0 1 5 0 1 0\n1.57 0 4 0.2 40\n\
                1 0 0 0 1 0 0 0 1\n40 30 40\n4.7 0\n";
    let cases = [
        (good.replace("1.57", "abc"), "phi"),
        (good.replace("4.7 0\n", ""), "focalDistance"),
        (good.replace("0 1 0 0 0 1", "0 1 0 0 0 3"), "c2w"),
        (good.replace("49.13", "-3"), "hFov"),
    ];
    for (i, (text, field)) in cases.iter().enumerate() {
        let cam = dir.path().join(format!("bad{i}.cam"));
        std::fs::write(&cam, text).unwrap();
        let out = dir.path().join(format!("bad{i}.exr"));
        let cam_arg = cam.to_str().unwrap();
        expect_error(&with(&["-c", cam_arg]), &out, SPHERES, &[cam_arg, field]);
    }
    let missing = dir.path().join("missing.cam");
    let out = dir.path().join("missing.exr");
    let arg = missing.to_str().unwrap();
    expect_error(&with(&["-c", arg]), &out, SPHERES, &[arg]);
}

/// Pixels `[x0, x0+w) × [y0, y0+h)` (rows from the top) of `img`.
fn crop(img: &Image, x0: u32, y0: u32, w: u32, h: u32) -> Vec<ember::Color> {
    (y0..y0 + h)
        .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
        .map(|(x, y)| img.get(x, y))
        .collect()
}

#[test]
fn cell_equals_the_full_render() {
    let dir = tempfile::tempdir().unwrap();
    for extra in [&[][..], &["-a", "2", "0.2"][..]] {
        let full = render(&with(extra), &dir.path().join("full.exr"), SPHERES);
        // X = 5, Y = 3 from the bottom, 17 x 11: rows 30-3-11 = 16 .. 27 from the top.
        let expected = crop(&full, 5, 16, 17, 11);
        for t in ["1", "2"] {
            let mut args = with(extra);
            args.extend(["-t", t, "-p", "5", "3", "17", "11"]);
            let cell = render(&args, &dir.path().join(format!("cell{t}.exr")), SPHERES);
            assert_eq!((cell.width, cell.height), (17, 11));
            assert_eq!(cell.pixels, expected, "-t {t} {extra:?}");
            let meta = ember::image_io::read_metadata(&dir.path().join(format!("cell{t}.exr")));
            let cell_note = meta.unwrap().get("ember.cell").map(String::from);
            assert!(cell_note.is_some_and(|c| c.contains("pixels 5..22 x 16..27")));
            args.push("--full-frame");
            let framed = render(&args, &dir.path().join(format!("frame{t}.exr")), SPHERES);
            assert_eq!((framed.width, framed.height), (40, 30));
            assert_eq!(crop(&framed, 5, 16, 17, 11), expected);
            let black = (0..30)
                .flat_map(|y| (0..40).map(move |x| (x, y)))
                .filter(|&(x, y)| !(5..22).contains(&x) || !(16..27).contains(&y))
                .all(|(x, y)| framed.get(x, y) == ember::Color::ZERO);
            assert!(black, "outside the cell is not black");
        }
    }
}

#[test]
fn cell_equals_the_full_render_under_light_tracing() {
    // Light tracing's paths splat anywhere: a cell is still the crop of the full image,
    // with a lens too.
    let dir = tempfile::tempdir().unwrap();
    let empty = "scenes/cs184/sky/CBempty.dae";
    let lens = ["-b", "0.1", "-d", "3", "--integrator", "light-tracing"];
    let full = render(&with(&lens), &dir.path().join("full.exr"), empty);
    let mut args = with(&lens);
    args.extend(["-p", "7", "4", "9", "6"]);
    let cell = render(&args, &dir.path().join("cell.exr"), empty);
    assert_eq!(cell.pixels, crop(&full, 7, 20, 9, 6));
}

#[test]
fn cells_outside_the_image_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    expect_error(
        &with(&["-p", "30", "0", "11", "1"]),
        &out,
        SPHERES,
        &["-p 30 0 11 1", "40x30"],
    );
    expect_error(
        &with(&["-p", "0", "25", "4", "6"]),
        &out,
        SPHERES,
        &["not inside"],
    );
    expect_error(
        &with(&["-p", "0", "0", "0", "6"]),
        &out,
        SPHERES,
        &["empty"],
    );
}

#[test]
fn zero_lens_radius_is_the_pinhole_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let plain = render(BASE, &dir.path().join("plain.exr"), SPHERES);
    let zero = render(
        &with(&["-b", "0", "-d", "2.5"]),
        &dir.path().join("b0.exr"),
        SPHERES,
    );
    assert_eq!(plain.pixels, zero.pixels);
}

#[test]
fn lens_renders_are_deterministic_and_blurred() {
    let dir = tempfile::tempdir().unwrap();
    let plain = render(BASE, &dir.path().join("plain.exr"), BUNNY);
    let lens = |t: &str| {
        render(
            &with(&["-b", "0.1", "-d", "3", "-t", t]),
            &dir.path().join(format!("lens{t}.exr")),
            BUNNY,
        )
    };
    let (a, b) = (lens("1"), lens("2"));
    assert_eq!(a.pixels, b.pixels, "image depends on -t");
    assert_ne!(a.pixels, plain.pixels);
    // A cell of a lens render is the lens render's pixels too.
    let cell = render(
        &with(&["-b", "0.1", "-d", "3", "-p", "10", "10", "8", "8"]),
        &dir.path().join("lenscell.exr"),
        BUNNY,
    );
    assert_eq!(cell.pixels, crop(&a, 10, 12, 8, 8));
}

#[test]
fn bad_lens_values_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    expect_error(&with(&["-b", "-0.5"]), &out, SPHERES, &["-b"]);
    expect_error(&with(&["-b", "0.1", "-d", "0"]), &out, SPHERES, &["-d"]);
    expect_error(&with(&["-d", "nan"]), &out, SPHERES, &["-d"]);
}

#[test]
fn help_lists_the_course_flags() {
    let help = common::ember(["--help"]).success().stdout();
    for flag in [
        "-c <FILE>",
        "-p <X> <Y> <DX> <DY>",
        "-b <RADIUS>",
        "-d <DISTANCE>",
    ] {
        assert!(help.contains(flag), "--help lacks {flag}");
    }
    // A missing value is a plain error, not clap's "use '-- -c'" tip for unknown flags.
    let failed = common::ember(["-c"]).fails_with("-c");
    let err = failed.stderr();
    assert!(
        !err.contains("-- -c") && !err.contains("unexpected argument"),
        "{err}"
    );
}
