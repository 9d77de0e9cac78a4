//! The command line under hostile plumbing: closed pipes, full disks, bad output
//! paths, and error messages that say each cause once.

use crate::common;

use common::{command, ember, repo, run, wait, Run};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn scene() -> PathBuf {
    repo("scenes/cs184/sky/CBempty.dae")
}

fn dev_full() -> Stdio {
    Stdio::from(
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap(),
    )
}

/// Runs `cmd` with its stdout a pipe whose read end is closed before it starts, so
/// its first write fails whatever the timing (closing the end after the spawn raced
/// a quick `--help`, which could fit its text in the pipe first).
fn with_closed_stdout(cmd: &mut Command) -> Run {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let child = cmd.stdout(writer).stderr(Stdio::piped()).spawn().unwrap();
    wait(cmd, child)
}

/// A run whose stdout reader went away: one line says so, and the status is a shell's
/// for a program SIGPIPE stopped, so `set -o pipefail` sees the cut.
fn cut_short(o: &Run) {
    o.no_panic();
    assert_eq!(o.code(), Some(141), "ember {}: {}", o.args, o.stderr());
    let line = o.stderr().lines().last().unwrap_or_default().to_string();
    assert_eq!(line, ember::output::BROKEN_PIPE_MESSAGE, "ember {}", o.args);
}

#[test]
fn closed_stdout_is_said_in_one_line_and_a_non_zero_exit() {
    let info = with_closed_stdout(command().arg("info").arg(scene()));
    cut_short(&info);
    assert_eq!(info.stderr().lines().count(), 1, "{}", info.stderr());
    cut_short(&with_closed_stdout(command().arg("--help")));
}

#[test]
fn full_stdout_is_an_ordinary_error() {
    let o =
        run(command().arg("info").arg(scene()).stdout(dev_full())).fails_with("standard output");
    assert_eq!(o.code(), Some(1));
}

#[test]
fn full_stderr_does_not_stop_a_render() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    run(command()
        .args(["-s", "1", "-r", "8", "6", "-f"])
        .arg(&out)
        .arg(scene())
        .stderr(dev_full()))
    .success();
    assert_eq!(image::open(&out).unwrap().width(), 8);
}

#[test]
fn bad_output_path_fails_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let bad = [
        dir.path().join("nodir/x.png"),
        dir.path().join("x.jpeg"),
        dir.path().to_path_buf(),
    ];
    for target in bad {
        let t0 = Instant::now();
        let name = target.file_name().unwrap().to_str().unwrap();
        let o = run(command()
            .args(["-s", "4096", "-m", "5", "-r", "480", "360", "-f"])
            .arg(&target)
            .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae")))
        .fails_with(name);
        // A render of this size takes minutes; a preflight failure takes milliseconds
        // (the bound is loose so that a loaded machine does not fail the test).
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "{target:?}: too slow"
        );
        assert_eq!(o.code(), Some(1), "{}", o.stderr());
        assert!(!o.stderr().contains("samples in"), "{}", o.stderr());
        // Checked before the scene is even read: a missing scene is not what is reported.
        let o = run(command()
            .arg("-f")
            .arg(&target)
            .arg(dir.path().join("missing.dae")))
        .fails_with(name);
        assert_eq!(o.code(), Some(1));
        let err = o.stderr();
        assert!(!err.contains("missing.dae"), "{target:?}: {err}");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn output_equal_to_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let same = dir.path().join("same.png");
    std::fs::copy(scene(), &same).unwrap();
    let before = std::fs::read(&same).unwrap();
    run(command()
        .args(["-s", "1", "-r", "8", "6", "-f"])
        .arg(&same)
        .arg(&same))
    .fails_with("input");
    assert_eq!(
        std::fs::read(&same).unwrap(),
        before,
        "the scene was changed"
    );
    // Another spelling of the same file is caught through canonical paths.
    run(command()
        .args(["-s", "1", "-r", "8", "6", "-f"])
        .arg(dir.path().join(".").join("same.png"))
        .arg(&same))
    .fails_with("input");
    assert_eq!(std::fs::read(&same).unwrap(), before);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

/// `camera --save` and `export`'s copy of the `-e` map refuse to write over their
/// own input, as a render's `-f` does.
#[test]
fn camera_and_export_do_not_overwrite_their_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let same = dir.path().join("scene.dae");
    std::fs::copy(scene(), &same).unwrap();
    let before = std::fs::read(&same).unwrap();
    run(command().args(["camera", "--save"]).arg(&same).arg(&same))
        .fails_with("--save would overwrite");
    assert_eq!(
        std::fs::read(&same).unwrap(),
        before,
        "the scene was changed"
    );
    let map = dir.path().join("scene_env.exr");
    let mut env = ember::film::Image::new(8, 4);
    env.pixels.fill(ember::Vec3::ONE);
    ember::image_io::write_image(&env, &map).unwrap();
    let map_before = std::fs::read(&map).unwrap();
    run(command()
        .args(["export", "--out"])
        .arg(dir.path())
        .arg("-e")
        .arg(&map)
        .arg(&same))
    .fails_with("would overwrite this -e input");
    assert_eq!(
        std::fs::read(&map).unwrap(),
        map_before,
        "the map was changed"
    );
}

/// Flags that contradict each other, or ask for what cannot run, stop before any work.
#[test]
fn contradictory_or_impossible_flags_are_refused() {
    let out = tempfile::tempdir().unwrap();
    let f = out.path().join("x.png");
    let render = |extra: &[&str]| {
        let mut c = command();
        c.args(["-s", "1", "-r", "8", "6", "-f"])
            .arg(&f)
            .args(extra)
            .arg(scene());
        run(&mut c)
    };
    render(&["-t", "100000"]).fails_with("at most 1024 worker threads");
    render(&["-H", "--integrator", "mis"]).fails_with("two ways of sampling direct light");
    render(&["-H", "--integrator", "light-tracing"]).fails_with("light tracing");
    render(&["--rr", "off", "--rr-start", "3"]).fails_with("--rr off");
    render(&["--shading", "normals", "-a"]).fails_with("-a: adaptive");
    render(&["--shading", "bvh-cost", "--integrator", "mis"]).fails_with("--integrator");
    render(&["--shading", "normals", "-H"]).fails_with("-H");
    for (flag, value) in [
        ("--max-spp", "0"),
        ("--reference-spp", "0"),
        ("--max-seconds", "nan"),
        ("--reference-noise", "-1"),
    ] {
        run(command()
            .args(["bench", "converge", flag, value])
            .arg(scene()))
        .fails_with(flag);
    }
    run(command().args(["bench", "render", "--repeats", "0"])).fails_with("--repeats");
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0);
    render(&["-H", "--integrator", "path"]).success();
}

/// `--data` and `--simd` apply to every command, also when written before its name;
/// a render option written there is said to belong to the command.
#[test]
fn options_before_a_subcommand() {
    run(command()
        .arg("--data")
        .arg(repo(""))
        .arg("info")
        .arg(scene()))
    .success();
    let o = run(command().args(["--simd", "portable", "info"]).arg(scene())).success();
    assert!(
        o.stdout().contains("packets of 16 paths (portable)"),
        "{}",
        o.stdout()
    );
    run(command().args(["-t", "1", "info"]).arg(scene()))
        .fails_with("the options before `info` are read as its own");
}

/// A one-line error in which every ": "-separated part of the message appears once.
fn assert_said_once(o: Run) {
    let err = o.fails_with("").stderr();
    let line = err.lines().next().unwrap_or_default();
    let parts: Vec<&str> = line.split(": ").collect();
    for (i, p) in parts.iter().enumerate() {
        assert!(
            !parts[i + 1..].contains(p),
            "repeated cause {p:?} in {line:?}"
        );
    }
}

#[test]
fn errors_say_each_cause_once() {
    let dir = tempfile::tempdir().unwrap();
    let render = |out: PathBuf, scene: PathBuf| {
        run(command()
            .args(["-s", "1", "-r", "8", "6", "-f"])
            .arg(out)
            .arg(scene))
    };
    assert_said_once(render(dir.path().join("nodir/out.png"), scene()));
    let out = dir.path().join("out.png");
    assert_said_once(render(out.clone(), dir.path().join("missing.dae")));
    assert_said_once(render(out, dir.path().to_path_buf()));
    let info = |p: PathBuf| run(command().arg("info").arg(p));
    assert_said_once(info(dir.path().join("missing.dae")));
    assert_said_once(info(dir.path().join("missing.exr")));
    let garbage = dir.path().join("garbage.exr");
    std::fs::write(&garbage, b"not an exr").unwrap();
    assert_said_once(info(garbage));
    assert_said_once(render(
        dir.path().join("out.exr"),
        dir.path().join("garbage.exr"),
    ));
}

#[test]
fn metadata_round_trips_through_info() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["m.exr", "m.png"] {
        let out = dir.path().join(name);
        run(command()
            .args(["-s", "3", "-l", "2", "-m", "4", "-r", "8", "6", "-f"])
            .arg(&out)
            .arg(scene()))
        .success();
        let text = run(command().arg("info").arg(&out)).success().stdout();
        let bytes = std::fs::read(scene()).unwrap();
        let hash = ember::image_metadata::fnv1a64(&bytes);
        for line in [
            "ember.spp: 3".to_string(),
            "ember.light_samples: 2".into(),
            "ember.max_depth: 4".into(),
            "ember.resolution: 8x6".into(),
            "ember.seed: 0".into(),
            format!("ember.scene: {}", scene().display()),
            format!("ember.scene.fnv1a64: {hash:016x}"),
            format!("ember.version: {}", env!("CARGO_PKG_VERSION")),
            "ember.stopped: complete".into(),
            "ember.samples_per_pixel: mean 3.000, min 3, max 3".into(),
            "ember.pixels_rendered: 48 of 48".into(),
            "ember.roulette: throughput from bounce 5, min 0.05".into(),
            "ember.adaptive: off".into(),
            "size: 8x6".into(),
        ] {
            assert!(
                text.lines().any(|l| l == line),
                "{name}: no {line:?} in\n{text}"
            );
        }
        let cmd = text
            .lines()
            .find(|l| l.starts_with("ember.command_line: "))
            .unwrap();
        assert!(cmd.contains("-s 3 -l 2 -m 4"), "{cmd}");
        // Build, machine and the estimator auto chose: present and not empty.
        for key in [
            "ember.git_hash: ",
            "ember.cpu: ",
            "ember.estimator: ",
            "ember.backend: ",
        ] {
            let line = text.lines().find(|l| l.starts_with(key));
            assert!(
                line.is_some_and(|l| l.len() > key.len()),
                "{name}: no {key} in\n{text}"
            );
        }
        assert_eq!(ember::image_io::read_image(&out).unwrap().width, 8);
    }
}

#[test]
fn a_repeated_flag_takes_its_last_value() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r.exr");
    render_ok(
        &["-s", "1", "-s", "2", "-r", "4", "3", "-r", "8", "6"],
        &out,
        &scene(),
    );
    let meta = ember::image_io::read_metadata(&out).unwrap();
    assert_eq!(meta.get("ember.spp"), Some("2"));
    assert_eq!(meta.get("ember.resolution"), Some("8x6"));
}

/// Files in `dir` other than `keep`: temporaries or partial files a render left behind.
fn leftovers(dir: &std::path::Path, keep: &[&str]) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !keep.contains(&n.as_str()))
        .collect()
}

/// Waits (up to a minute) until `ready` holds, polling.
fn wait_for(ready: impl Fn() -> bool) {
    let t0 = Instant::now();
    while !ready() {
        assert!(t0.elapsed() < Duration::from_secs(60), "timed out");
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn send_sigint(child: &std::process::Child) {
    let st = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
}

/// A render that would take many minutes, started in the background.
fn long_render(out: &std::path::Path, extra: &[&str]) -> (Command, std::process::Child) {
    long_render_of("CBspheres_lambertian.dae", out, extra)
}

fn long_render_of(
    scene: &str,
    out: &std::path::Path,
    extra: &[&str],
) -> (Command, std::process::Child) {
    let mut cmd = command();
    cmd.args(["-t", "1", "-s", "100000", "-m", "5", "-r", "64", "48"])
        .args(extra)
        .arg("-f")
        .arg(out)
        .arg(repo("scenes/cs184/sky").join(scene))
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let child = cmd.spawn().unwrap();
    (cmd, child)
}

#[test]
fn sigint_writes_what_was_rendered_and_no_partial_file() {
    // Plain, in passes, adaptive, and light tracing (auto's choice for CBempty at -m 5).
    // Long enough to be stopped: packets render this scene at ~15 M samples/s.
    let lambertian = "CBspheres_lambertian.dae";
    for (scene, name, extra) in [
        (lambertian, "i.png", &["-s", "40000"][..]),
        (lambertian, "i.exr", &["--checkpoint", "1000"][..]),
        (
            lambertian,
            "a.exr",
            &["-s", "4000", "-a", "64", "0.00001"][..],
        ),
        ("CBempty.dae", "l.exr", &[][..]),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join(name);
        let (cmd, child) = long_render_of(scene, &out, extra);
        // The output's temporary is claimed just before the handler is installed;
        // give the render a moment to start after that.
        wait_for(|| !leftovers(dir.path(), &[]).is_empty());
        std::thread::sleep(Duration::from_millis(1500));
        send_sigint(&child);
        let o = wait(&cmd, child);
        o.no_panic();
        assert_eq!(o.code(), Some(130), "{}", o.stderr());
        let err = o.stderr();
        assert!(
            err.contains("interrupted: wrote what was rendered so far"),
            "{err}"
        );
        let rate = name.replace('.', "_rate.");
        assert_eq!(leftovers(dir.path(), &[name, &rate]), Vec::<String>::new());
        let img = ember::image_io::read_image(&out).unwrap();
        assert_eq!((img.width, img.height), (64, 48));
        let meta = ember::image_io::read_metadata(&out).unwrap();
        assert_eq!(meta.get("ember.stopped"), Some("interrupted"), "{meta:?}");
        let spp = meta.get("ember.samples_per_pixel").unwrap();
        assert!(
            spp.starts_with("mean ") && !spp.starts_with("mean 0.000"),
            "{spp}"
        );
    }
}

/// A second Ctrl-C while the first one's image is being written ends ember at once:
/// status 130, and no temporary is left (the output is there only if it was complete).
#[test]
fn second_sigint_exits_at_once_and_leaves_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("big.png");
    let mut cmd = command();
    cmd.args(["-t", "1", "-s", "100000", "-m", "5", "-r", "1600", "1200"])
        .arg("-f")
        .arg(&out)
        .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let child = cmd.spawn().unwrap();
    wait_for(|| !leftovers(dir.path(), &[]).is_empty());
    std::thread::sleep(Duration::from_millis(1500));
    send_sigint(&child);
    // Separate deliveries (pending signals of one kind coalesce), while the 1600x1200
    // PNG of the first is still being encoded.
    std::thread::sleep(Duration::from_millis(30));
    send_sigint(&child);
    let o = wait(&cmd, child);
    o.no_panic();
    assert_eq!(o.code(), Some(130), "{}", o.stderr());
    assert_eq!(leftovers(dir.path(), &["big.png"]), Vec::<String>::new());
    if out.exists() {
        assert_eq!(ember::image_io::read_image(&out).unwrap().width, 1600);
    }
}

#[test]
fn checkpoints_hold_whole_images_while_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.exr");
    let (cmd, child) = long_render(&out, &["--checkpoint", "0.2"]);
    wait_for(|| out.exists());
    // The checkpoint is complete the moment it appears (renamed into place).
    let meta = ember::image_io::read_metadata(&out).unwrap();
    assert_eq!(meta.get("ember.checkpoint"), Some("true"));
    assert_eq!(meta.get("ember.stopped"), Some("complete"));
    assert_eq!(ember::image_io::read_image(&out).unwrap().width, 64);
    send_sigint(&child);
    let o = wait(&cmd, child);
    assert_eq!(o.code(), Some(130), "{}", o.stderr());
    let meta = ember::image_io::read_metadata(&out).unwrap();
    assert_eq!(meta.get("ember.stopped"), Some("interrupted"));
    assert_eq!(leftovers(dir.path(), &["c.exr"]), Vec::<String>::new());
}

#[test]
fn time_budget_stops_and_writes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.exr");
    run(command()
        .args(["-t", "1", "-m", "5", "-r", "64", "48", "--time", "1", "-f"])
        .arg(&out)
        .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae")))
    .success();
    let meta = ember::image_io::read_metadata(&out).unwrap();
    assert_eq!(meta.get("ember.stopped"), Some("time budget spent"));
    // ember's own clock: the render stopped within a second of the budget.
    let secs: f64 = meta.get("ember.render_seconds").unwrap().parse().unwrap();
    assert!((1.0..2.0).contains(&secs), "{secs}");
    // Every pixel has the samples of the passes completed (at least the first).
    let spp = meta.get("ember.samples_per_pixel").unwrap();
    assert!(!spp.contains("min 0,"), "{spp}");
    assert_eq!(meta.get("ember.spp"), Some("no cap"));
}

#[test]
fn a_capped_time_budget_ends_at_the_cap_like_a_pass_render() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.exr");
    render_ok(
        &["-s", "6", "-r", "16", "12", "--time", "600"],
        &out,
        &scene(),
    );
    let meta = ember::image_io::read_metadata(&out).unwrap();
    assert_eq!(meta.get("ember.stopped"), Some("complete"));
    assert_eq!(
        meta.get("ember.samples_per_pixel"),
        Some("mean 6.000, min 6, max 6")
    );
    // Passes 1 + 1 + 2 + 2 (capped): four.
    assert_eq!(meta.get("ember.passes"), Some("4"));
}

#[test]
fn time_and_checkpoint_refuse_what_cannot_run_in_passes() {
    for extra in [
        &["-a"][..],
        &["--shading", "bvh-cost"],
        &["--time", "0"],
        &["--time", "-1"],
    ] {
        let o = run(command()
            .args(["-r", "8", "6", "--checkpoint", "5"])
            .args(extra)
            .arg(scene()))
        .fails_with(extra[0]);
        assert_eq!(o.code(), Some(1), "{extra:?}: {}", o.stderr());
    }
}

/// `ember ARGS -f OUT SCENE`, which must succeed.
fn render_ok(args: &[&str], out: &std::path::Path, scene: &std::path::Path) -> Run {
    run(command().args(args).arg("-f").arg(out).arg(scene)).success()
}

#[test]
fn bvh_cost_exr_holds_raw_counts_and_a_fixed_scale_colours_the_png() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = repo("scenes/cs184/sky/CBbunny.dae");
    let exr = dir.path().join("c.exr");
    render_ok(&["--shading", "bvh-cost", "-r", "32", "24"], &exr, &bunny);
    let img = ember::image_io::read_image(&exr).unwrap();
    // One ray per pixel: whole numbers of nodes + primitives, grey, some large.
    assert!(img
        .pixels
        .iter()
        .all(|p| p.x == p.x.round() && p.x == p.y && p.x >= 0.0));
    assert!(img.pixels.iter().any(|p| p.x > 4.0));
    let meta = ember::image_io::read_metadata(&exr).unwrap();
    let mean: f64 = meta
        .get("ember.mean_cost_per_ray")
        .unwrap()
        .parse()
        .unwrap();
    let expect = img.pixels.iter().map(|p| p.x as f64).sum::<f64>() / img.pixels.len() as f64;
    assert!((mean - expect).abs() < 1e-3, "{mean} vs {expect}");
    // A fixed scale: the same heat map whatever the image's own percentile.
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    let o = render_ok(
        &[
            "--shading",
            "bvh-cost",
            "--cost-scale",
            "1000",
            "-r",
            "32",
            "24",
        ],
        &a,
        &bunny,
    );
    assert!(o.stderr().contains("per camera ray"), "{}", o.stderr());
    render_ok(
        &[
            "--shading",
            "bvh-cost",
            "--cost-scale",
            "5",
            "-r",
            "32",
            "24",
        ],
        &b,
        &bunny,
    );
    let meta = ember::image_io::read_metadata(&a).unwrap();
    assert_eq!(meta.get("ember.cost_scale"), Some("1000"));
    let (a, b) = (image::open(&a).unwrap(), image::open(&b).unwrap());
    assert_ne!(a.as_bytes(), b.as_bytes());
}

#[test]
fn adaptive_rate_map_exr_holds_raw_sample_counts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.exr");
    render_ok(
        &["-a", "4", "0.2", "-s", "64", "-r", "16", "12"],
        &out,
        &scene(),
    );
    let rate = ember::image_io::read_image(&dir.path().join("a_rate.exr")).unwrap();
    for p in &rate.pixels {
        let n = p.x as u32;
        assert!(
            p.x == n as f32 && (4..=64).contains(&n) && n.is_multiple_of(4),
            "{n}"
        );
    }
}

#[test]
fn options_that_do_nothing_are_refused() {
    for args in [
        &["--shading", "bvh-cost", "--accel", "embree"][..],
        &["--bvh", "midpoint", "--accel", "embree"],
        // Refused in every build: no Embree, or Embree not in use.
        &["--embree-quality", "high", "--accel", "native"],
        &["--cost-scale", "10"],
        &["--shading", "bvh-cost", "--cost-scale", "0"],
    ] {
        let o = run(command().args(args).arg(scene())).fails_with("ember: error: --");
        assert_eq!(o.code(), Some(1), "{args:?}: {}", o.stderr());
    }
    let dir = tempfile::tempdir().unwrap();
    let o = render_ok(
        &["-l", "0", "-r", "8", "6"],
        &dir.path().join("l.png"),
        &scene(),
    );
    assert!(o.stderr().contains("warning: -l 0"), "{}", o.stderr());
}

#[test]
fn info_lists_meshes_with_names_and_the_bvh() {
    let text = run(command()
        .arg("info")
        .arg(repo("scenes/cs184/sky/CBbunny.dae")))
    .success()
    .stdout();
    assert!(text.contains("meshes: 6"), "{text}");
    assert!(text.contains(": 28576 triangles, material [0] "), "{text}");
    assert!(
        text.contains("  [1] ceiling: 2 triangles, material [1] ceiling"),
        "{text}"
    );
    let bvh = text.lines().find(|l| l.starts_with("native BVH")).unwrap();
    for word in ["nodes", "leaves", "depth", "SAH cost", "built in"] {
        assert!(bvh.contains(word), "{bvh}");
    }
}

/// Runs `args` with stdout read up to its first line and then closed (`| head -1`).
fn piped_into_head(args: &[String]) -> (Run, String) {
    use std::io::BufRead;
    let mut cmd = command();
    cmd.args(args).stdout(Stdio::piped()).stderr(Stdio::piped());
    let mut child = cmd.spawn().unwrap();
    let mut first = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    (wait(&cmd, child), first)
}

/// Every subcommand, small enough to run in a test; each prints to stdout.
fn every_subcommand(dir: &std::path::Path) -> Vec<Vec<String>> {
    let s = |p: &std::path::Path| p.to_string_lossy().into_owned();
    let scene = s(&scene());
    let out = |n: &str| s(&dir.join(n));
    let image = dir.join("img.exr");
    run(command()
        .args(["-s", "1", "-r", "8", "6", "-f"])
        .arg(&image)
        .arg(scene.clone()))
    .success();
    let mut cmds: Vec<Vec<&str>> = vec![
        vec!["--help"],
        vec!["--version"],
        vec!["info", &scene],
        vec!["export", &scene, "-r", "8", "6"],
    ];
    let (exp, img) = (out("exp"), s(&image));
    cmds[3].extend(["--out", &exp]);
    cmds.push(vec!["info", &img]);
    let (br, ba, bc, bs, be) = (out("br"), out("ba"), out("bc"), out("bs"), out("be"));
    if cfg!(feature = "bench") {
        cmds.extend([
            vec![
                "bench",
                "render",
                &scene,
                "-t",
                "1",
                "-s",
                "1",
                "-m",
                "1",
                "--repeats",
                "1",
                "--out",
                &br,
            ],
            vec![
                "bench",
                "accel",
                &scene,
                "-t",
                "1",
                "--rays",
                "1000",
                "--repeats",
                "1",
                "--no-embree-modes",
                "--out",
                &ba,
            ],
            vec![
                "bench",
                "converge",
                &scene,
                "-t",
                "1",
                "-r",
                "8",
                "6",
                "--max-spp",
                "2",
                "--reference-spp",
                "4",
                "--out",
                &bc,
            ],
            vec![
                "bench",
                "stability",
                "-t",
                "1",
                "--spp-scale",
                "0.001",
                "--out",
                &bs,
            ],
            vec![
                "bench",
                "estimators",
                &scene,
                "-t",
                "1",
                "-r",
                "8",
                "6",
                "-s",
                "1",
                "--pairs",
                "1",
                "--out",
                &be,
            ],
        ]);
    }
    cmds.into_iter()
        .map(|c| c.into_iter().map(String::from).collect())
        .collect()
}

#[test]
fn every_subcommand_survives_head_closed_stdout_and_a_full_disk() {
    let dir = tempfile::tempdir().unwrap();
    for args in every_subcommand(dir.path()) {
        let (o, first) = piped_into_head(&args);
        assert!(!first.is_empty(), "{args:?} printed nothing");
        // Whether the rest was written before head left is a race: either is right.
        if o.code() != Some(0) {
            cut_short(&o);
        }
        assert!(!o.stderr().contains("error"), "{args:?}: {}", o.stderr());
        cut_short(&with_closed_stdout(command().args(&args)));
        let full = run(command().args(&args).stdout(dev_full())).fails_with("No space left");
        assert_eq!(full.code(), Some(1), "{args:?} > /dev/full");
    }
}

#[test]
fn a_render_into_a_closed_pipe_still_writes_its_image() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.png");
    with_closed_stdout(
        command()
            .args(["-s", "1", "-r", "8", "6", "-f"])
            .arg(&out)
            .arg(scene()),
    )
    .success();
    assert_eq!(image::open(&out).unwrap().width(), 8);
}

#[test]
fn course_flags_ember_lacks_are_named_and_negative_numbers_get_a_value_message() {
    // -c, -p, -b, -d, -e are the course's; whichever ember lacks is named as such.
    for flag in ["-c", "-p", "-b", "-d", "-e"] {
        let o = run(command().args([flag, "1"]).arg(scene()));
        let err = o.stderr();
        if err.contains("unexpected argument") || err.contains("not supported") {
            assert_eq!(
                err.trim(),
                format!("ember: error: course flag {flag} is not supported")
            );
            assert_eq!(o.code(), Some(2));
        }
    }
    for args in [
        &["-s", "-5"][..],
        &["-r", "-4", "3"],
        &["-m", "-1"],
        &["--time", "-2"],
    ] {
        let o = run(command().args(args).arg(scene())).fails_with(args[1]);
        let err = o.stderr();
        assert!(
            !err.contains("-- -"),
            "{args:?}: clap's tip instead of the value: {err}"
        );
    }
    let o = ember(["bench", "render", "-s", "-3"]).fails_with("-3");
    assert!(!o.stderr().contains("-- -"), "{}", o.stderr());
}

#[test]
fn renders_in_passes_are_deterministic_whatever_the_threads() {
    let dir = tempfile::tempdir().unwrap();
    let spheres = repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let render = |name: &str, args: &[&str]| {
        let out = dir.path().join(name);
        render_ok(
            &[&["-r", "24", "18", "-m", "3"], args].concat(),
            &out,
            &spheres,
        );
        ember::image_io::read_image(&out).unwrap()
    };
    let a = render("a.exr", &["-t", "1", "-s", "6", "--checkpoint", "1000"]);
    let b = render("b.exr", &["-t", "2", "-s", "6", "--checkpoint", "1000"]);
    assert_eq!(a, b);
    // One pass is the plain render of the same seed.
    let one = render("one.exr", &["-s", "1", "--checkpoint", "1000"]);
    let plain = render("plain.exr", &["-s", "1"]);
    assert_eq!(one, plain);
    assert_ne!(a, plain);
    // Adaptive sampling works its rows in a scattered order; the image does not care.
    let a1 = render("a1.exr", &["-t", "1", "-s", "32", "-a", "8", "0.1"]);
    let a2 = render("a2.exr", &["-t", "2", "-s", "32", "-a", "8", "0.1"]);
    assert_eq!(a1, a2);
}

#[cfg(feature = "bench")]
#[test]
fn bench_accel_threads_take_a_list_not_a_scene() {
    // `--threads 1 0`: both are thread counts (0 is refused), none is a scene path.
    for args in [&["--threads", "1", "0"][..], &["-t", "1,0"]] {
        let o =
            run(command().args(["bench", "accel"]).args(args)).fails_with("--threads: each count");
        assert_eq!(o.code(), Some(1), "{args:?}: {}", o.stderr());
    }
}
