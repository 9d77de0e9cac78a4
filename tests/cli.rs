//! The command line end to end: flags, errors, and never a partial output file.

use crate::common;

use common::{command, ember, repo, run};

#[test]
fn cs184_command_line_is_accepted_verbatim() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.png");
    run(command()
        .args([
            "-t", "2", "-s", "2", "-l", "2", "-m", "2", "-r", "32", "24", "-f",
        ])
        .arg(&out)
        .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae")))
    .success();
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (32, 24));
}

#[test]
fn exr_output_and_adaptive_rate_map() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    run(command()
        .args([
            "-s", "64", "-a", "8", "0.1", "-m", "1", "-r", "64", "48", "-f",
        ])
        .arg(&out)
        .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae")))
    .success();
    let img = ember::image_io::read_image(&out).unwrap();
    assert_eq!((img.width, img.height), (64, 48));
    // The light is seen directly at radiance 10: EXR keeps linear values above 1.
    assert!(img.pixels.iter().any(|p| p.x > 5.0));
    assert!(dir.path().join("x_rate.exr").exists());
}

#[test]
fn bad_flags_and_paths_fail_cleanly() {
    let scene = repo("scenes/cs184/sky/CBempty.dae");
    let scene = scene.to_str().unwrap();
    ember(["--frobnicate", scene]).fails_with("--frobnicate");
    ember(["-s", "zero", scene]).fails_with("-s");
    ember(["-o", "2", scene]).fails_with("-o");
    ember(["-r", "0", "10", scene]).fails_with("resolution");
    ember(["-f", "out.jpg", scene]).fails_with("out.jpg");
    ember(["/nonexistent/scene.dae"]).fails_with("/nonexistent/scene.dae");
    ember(["--accel", "bogus", scene]).fails_with("bogus");
    ember(["-a", "0", "0.05", scene]).fails_with("BATCH");
}

#[test]
fn unwritable_output_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("no/such/dir/out.png");
    let scene = repo("scenes/cs184/sky/CBempty.dae");
    let render = |out: &std::path::Path| {
        run(command()
            .args(["-s", "1", "-r", "8", "6", "-f"])
            .arg(out)
            .arg(&scene))
    };
    render(&target).fails_with("out.png");
    assert!(!target.exists());
    // A directory in place of the file: the write fails and the temporary is cleaned up.
    let as_dir = dir.path().join("taken.png");
    std::fs::create_dir(&as_dir).unwrap();
    render(&as_dir).fails_with("taken.png");
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
    run(command().arg("-f").arg(&out).arg(&bad)).fails_with("broken.dae");
    assert!(!out.exists());
}

/// Without Embree, `--accel embree` says how to get it (with it, it renders:
/// tests/embree_backend.rs).
#[cfg(not(any(feature = "embree", feature = "embree4")))]
#[test]
fn accel_embree_says_how_to_get_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("e.png");
    run(command()
        .args(["--accel", "embree", "-r", "8", "6", "-f"])
        .arg(&out)
        .arg(repo("scenes/cs184/sky/CBempty.dae")))
    .fails_with("rebuild with --features embree");
    assert!(!out.exists());
}

#[test]
fn info_says_what_accel_auto_picks_and_why() {
    let scene = repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let text = run(command().arg("info").arg(scene)).success().stdout();
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
    let bench = |append: bool| {
        let mut c = command();
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
        run(&mut c).success();
        std::fs::read_to_string(dir.path().join("accel.csv")).unwrap()
    };
    // Nothing to append to yet: an error naming the file, before any measuring.
    let failed = run(command()
        .args(["bench", "accel", "mesh:2000", "--append", "--out"])
        .arg(dir.path()))
    .fails_with("accel.csv: cannot read");
    let err = failed.stderr();
    assert!(!err.contains("Mrays/s"), "measured before failing: {err}");
    let backends = if cfg!(any(feature = "embree", feature = "embree4")) {
        4
    } else {
        2
    };
    let first = bench(false);
    assert_eq!(first.lines().count(), 1 + 2 * backends, "{first}");
    assert!(first
        .lines()
        .skip(1)
        .all(|l| l.starts_with("displaced sphere (2k tris),")));
    let both = bench(true);
    assert_eq!(both.lines().count(), 1 + 4 * backends, "{both}");
    let md = std::fs::read_to_string(dir.path().join("accel.md")).unwrap();
    assert_eq!(md.lines().count(), 2 + 4 * backends, "{md}");
}

#[test]
fn light_tracing_from_the_command_line_and_its_warning_on_glass() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lt.exr");
    let render = |scene: &str| {
        run(command()
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
            .arg(repo(scene)))
    };
    let r = render("scenes/cs184/sky/CBempty.dae").success();
    assert!(r.stderr().is_empty(), "{}", r.stderr());
    let img = ember::image_io::read_image(&out).unwrap();
    assert!(img.all_finite() && img.mean_luminance() > 0.0);
    // Mirrors and glass cannot be connected to a pinhole: ember says so.
    let r = render("scenes/cs184/sky/CBspheres.dae").success();
    assert!(r.stderr().contains("mirror or glass"), "{}", r.stderr());
}

/// `--simd` picks the instruction set of the packets and the node tests: the summary
/// line names it and the image is the same bit for bit with each (scalar engine too);
/// a set this CPU lacks is refused with a one-line error naming it.
#[test]
fn simd_flag_changes_the_speed_only() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cs184/sky/CBspheres.dae");
    fn has(name: &str) -> bool {
        match name {
            "portable" => true,
            #[cfg(target_arch = "x86_64")]
            "avx2" => ["avx2", "bmi1", "bmi2", "lzcnt", "popcnt"]
                .iter()
                .all(|&f| detected(f)),
            #[cfg(target_arch = "x86_64")]
            "avx512" => {
                has("avx2")
                    && ["avx512f", "avx512dq", "avx512bw", "avx512vl"]
                        .iter()
                        .all(|&f| detected(f))
            }
            _ => false,
        }
    }
    #[cfg(target_arch = "x86_64")]
    fn detected(feature: &str) -> bool {
        match feature {
            "avx2" => std::is_x86_feature_detected!("avx2"),
            "bmi1" => std::is_x86_feature_detected!("bmi1"),
            "bmi2" => std::is_x86_feature_detected!("bmi2"),
            "lzcnt" => std::is_x86_feature_detected!("lzcnt"),
            "popcnt" => std::is_x86_feature_detected!("popcnt"),
            "avx512f" => std::is_x86_feature_detected!("avx512f"),
            "avx512dq" => std::is_x86_feature_detected!("avx512dq"),
            "avx512bw" => std::is_x86_feature_detected!("avx512bw"),
            "avx512vl" => std::is_x86_feature_detected!("avx512vl"),
            _ => false,
        }
    }
    let mut images = Vec::new();
    for (simd, label) in [
        ("portable", "(portable)"),
        ("avx2", "(AVX2)"),
        ("avx512", "(AVX-512)"),
    ] {
        for engine in ["auto", "scalar"] {
            let out = dir.path().join(format!("{simd}_{engine}.exr"));
            let mut cmd = command();
            cmd.args(["--simd", simd, "--engine", engine, "-s", "4", "-m", "8"])
                .args(["-r", "40", "30", "-f"])
                .arg(&out)
                .arg(&scene);
            if !has(simd) {
                run(&mut cmd).fails_with(&format!("--simd {simd}: this CPU has no"));
                continue;
            }
            let r = run(&mut cmd).success();
            if engine == "auto" {
                assert!(r.stderr().contains(label), "{simd}: {}", r.stderr());
            }
            images.push(ember::image_io::read_image(&out).unwrap().pixels);
        }
    }
    assert!(images.windows(2).all(|w| w[0] == w[1]));
    run(command().args(["--simd", "sse9", "x.dae"])).fails_with("sse9");
}

/// `ember bench render --simds` renders each instruction set in turn, a row each,
/// named in the table, and leaves the process's cap as it was.
#[cfg(feature = "bench")]
#[test]
fn bench_render_compares_instruction_sets() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let mut c = command();
    c.args([
        "bench",
        "render",
        "--simds",
        "portable,auto",
        "--engines",
        "auto",
    ])
    .args([
        "--accel",
        "native",
        "--repeats",
        "1",
        "-s",
        "1",
        "-m",
        "1",
        "--out",
    ])
    .arg(dir.path())
    .arg(&scene);
    run(&mut c).success();
    let md = std::fs::read_to_string(dir.path().join("render.md")).unwrap();
    let rows: Vec<&str> = md.lines().skip(2).collect();
    assert_eq!(rows.len(), 2, "{md}");
    assert!(rows[0].contains("packets (portable) | portable |"), "{md}");
    assert!(
        !rows[1].contains("portable"),
        "auto is the widest set: {md}"
    );
}

/// Light-traced caustics from the command line: auto's choice for a scene with glass
/// under an area light (path tracing with -a), named in the summary line, with parts
/// (--shard, --spp-offset) and --time; refused with -a when asked for by name.
#[test]
fn caustics_from_the_command_line_and_what_it_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cornell.dae");
    let base = ["-s", "4", "-m", "4", "-r", "32", "24"];
    let render = |extra: &[&str], out: &str| {
        let out = dir.path().join(out);
        let r = run(command()
            .args(base)
            .args(extra)
            .arg("-f")
            .arg(&out)
            .arg(&scene));
        (r, out)
    };
    for (extra, estimator) in [
        (&[][..], "caustics ("),
        (&["--integrator", "caustics"][..], "caustics ("),
        (
            &["--integrator", "caustics", "--time", "1"][..],
            "caustics (",
        ),
        (&["-a", "2", "0.05"][..], "path ("),
    ] {
        let (r, out) = render(extra, "c.exr");
        let r = r.success();
        assert!(r.stderr().contains(estimator), "{extra:?}: {}", r.stderr());
        assert!(!r.stderr().contains("warning"), "{}", r.stderr());
        let img = ember::image_io::read_image(&out).unwrap();
        assert!(img.all_finite() && img.mean_luminance() > 0.0, "{extra:?}");
    }
    for part in [&["--shard", "0/2"][..], &["--spp-offset", "4"][..]] {
        let (r, out) = render(
            &[&["--integrator", "caustics"][..], part].concat(),
            "part.exr",
        );
        assert!(r.success().stderr().contains("caustics ("), "{part:?}");
        assert!(out.exists(), "{part:?}");
    }
    let (r, out) = render(&["--integrator", "caustics", "-a", "2", "0.05"], "a.exr");
    r.fails_with("-a (adaptive sampling)");
    assert!(!out.exists(), "-a: wrote {}", out.display());
}

/// The course's `*_unlit.dae` scenes have one ambient light of radiance 0: the render
/// is black, and ember says so and how to light them; with `-e` it says nothing.
#[test]
fn unlit_scenes_warn_and_hint_at_an_environment_map() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("u.png");
    for scene in ["bunny_unlit.dae", "bunny_microfacet_cu_unlit.dae"] {
        let scene = repo("scenes/cs184/sky").join(scene);
        let render = |extra: &[&str]| {
            run(command()
                .args(["-s", "1", "-r", "8", "6", "-f"])
                .arg(&out)
                .args(extra)
                .arg(&scene))
            .success()
            .stderr()
        };
        let err = render(&[]);
        let warning: Vec<&str> = err.lines().filter(|l| l.contains("warning")).collect();
        assert_eq!(warning.len(), 1, "{err}");
        assert!(
            warning[0].contains("no light in the scene emits anything")
                && warning[0].contains("-e FILE.exr"),
            "{err}"
        );
        let env = repo("scenes/env_sun.exr");
        let err = render(&["-e", env.to_str().unwrap()]);
        assert!(!err.contains("warning"), "{err}");
    }
    // A lit scene gets no such warning.
    let lit = repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let err = run(command().args(["-r", "8", "6", "-f"]).arg(&out).arg(lit))
        .success()
        .stderr();
    assert!(!err.contains("warning"), "{err}");
}

#[test]
fn adaptive_flag_values_and_cap_are_explained() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    let scene = repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let render = |args: &[&str]| {
        run(command()
            .args(["-r", "8", "6", "-f"])
            .arg(&out)
            .args(args)
            .arg(&scene))
    };
    // One value too many is named as such, not taken for a subcommand.
    render(&["-a", "64", "0.05", "0.1"])
        .fails_with("-a takes at most two values, BATCH and TOL, but was given 64 0.05 0.1");
    // -s is the most samples a pixel takes: without it (1), or below the batch, -a does nothing.
    for (args, needle) in [
        (&["-a", "64", "0.05"][..], "without -s that is 1"),
        (&["-a"][..], "without -s that is 1"),
        (&["-s", "16", "-a", "64"][..], "reaches -s 16"),
    ] {
        let err = render(args).success().stderr();
        assert!(
            err.contains("warning: -a") && err.contains(needle),
            "{args:?}: {err}"
        );
    }
    let err = render(&["-s", "256", "-a", "16", "0.05"])
        .success()
        .stderr();
    assert!(!err.contains("warning"), "{err}");
}

#[test]
fn counts_of_zero_or_less_say_at_least_one() {
    let scene = repo("scenes/cs184/sky/CBempty.dae");
    let scene = scene.to_str().unwrap();
    for args in [["-s", "0"], ["-s", "-1"], ["-t", "0"], ["-t", "-2"]] {
        let o = ember([args[0], args[1], scene]).fails_with("must be at least 1");
        assert!(!o.stderr().contains("4294967295"), "{}", o.stderr());
    }
    ember(["export", scene, "-s", "0"]).fails_with("must be at least 1");
}

/// The summary line states the resolution and what the pixels show; a cell's samples
/// are the cell's own, even when it is written in the full frame.
#[test]
fn summary_states_resolution_shading_and_the_cells_samples() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.exr");
    let scene = repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let summary = |args: &[&str]| {
        let err = run(command()
            .args(["-r", "16", "12", "-f"])
            .arg(&out)
            .args(args)
            .arg(&scene))
        .success()
        .stderr();
        let line = err.lines().find(|l| l.contains("samples in"));
        line.unwrap_or_else(|| panic!("no summary in {err}"))
            .to_string()
    };
    let radiance = summary(&["-s", "2", "-m", "3"]);
    assert!(radiance.contains("; 16x12, path ("), "{radiance}");
    // The light's outline (a few pixels wide at 48x36) had split samples of its
    // own, unless turned off (also by the flag's former name).
    let outline = |flag: &str, edges: &str| {
        let args = ["-r", "48", "36", "-s", "2", "-m", "3", flag];
        let err = run(command()
            .args(args)
            .arg(edges)
            .arg("-f")
            .arg(&out)
            .arg(&scene))
        .success()
        .stderr();
        err.contains("-l 1, 16x direct samples in ")
    };
    assert!(outline("--direct-split", "16") && !outline("--direct-split", "0"));
    assert!(!outline("--emitter-edges", "0"));
    // Split samples are numbered from the pixel samples' indices times 16: at the
    // top of the 32-bit range there are fewer per sample, not an overflow.
    let top = [
        "-r",
        "48",
        "36",
        "-s",
        "2",
        "-m",
        "0",
        "--spp-offset",
        "4294967290",
    ];
    run(command()
        .args(top)
        .arg("-f")
        .arg(dir.path().join("top.exr"))
        .arg(&scene))
    .success();
    let args = ["--direct-split", "5000"];
    run(command().args(args).arg(&scene)).fails_with("5000 is not in 0..=1024");
    assert!(
        radiance.contains("-m 3") && radiance.contains(", 2 spp,"),
        "{radiance}"
    );
    let normals = summary(&["--shading", "normals"]);
    assert!(
        normals.contains("; 16x12, --shading normals, 1 spp,"),
        "{normals}"
    );
    assert!(
        !normals.contains("estimator") && !normals.contains("-m "),
        "{normals}"
    );
    let cell = summary(&["-s", "4", "-p", "2", "3", "4", "5", "--full-frame"]);
    assert!(cell.contains("; cell 4x5 at (2, 3) of 16x12, "), "{cell}");
    assert!(
        cell.contains(", 4 spp,") && cell.contains(" 80 samples in"),
        "{cell}"
    );
}

#[test]
fn info_describes_any_image_and_says_it_takes_one() {
    let dir = tempfile::tempdir().unwrap();
    // An EXR ember did not write: size, channels and per-channel means.
    let foreign = dir.path().join("foreign.exr");
    let pixels: Vec<f32> = (0..12).flat_map(|i| [i as f32, 0.5, 2.0]).collect();
    image::Rgb32FImage::from_raw(4, 3, pixels)
        .unwrap()
        .save(&foreign)
        .unwrap();
    let text = run(command().arg("info").arg(&foreign)).success().stdout();
    for line in [
        "size: 4x3",
        "  R: mean 5.5, min 0, max 11",
        "  G: mean 0.5, min 0.5, max 0.5",
        "not written by ember (no ember.* metadata)",
    ] {
        assert!(text.lines().any(|l| l == line), "no {line:?} in\n{text}");
    }
    assert!(
        text.contains("channels: ") && text.contains("32-bit float"),
        "{text}"
    );
    // A PNG: its stored values.
    let png = dir.path().join("grey.png");
    image::GrayImage::from_pixel(2, 2, image::Luma([51]))
        .save(&png)
        .unwrap();
    let text = run(command().arg("info").arg(&png)).success().stdout();
    assert!(text.contains("channels: Y (8-bit"), "{text}");
    assert!(text.contains("  Y: mean 0.2, min 0.2, max 0.2"), "{text}");
    let help = ember(["info", "--help"]).success().stdout();
    assert!(help.contains("<SCENE_OR_IMAGE>"), "{help}");
}

#[test]
fn standard_output_is_not_an_image_destination() {
    let scene = repo("scenes/cs184/sky/CBempty.dae");
    let scene = scene.to_str().unwrap();
    ember(["-f", "-", scene]).fails_with("standard output is not an image destination");
    ember(["merge", "-", "part.exr"]).fails_with("standard output is not an image destination");
}

#[test]
fn other_scene_formats_are_named_as_not_collada() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("model.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let ply = dir.path().join("model.ply");
    std::fs::write(&ply, "ply\nformat ascii 1.0\nend_header\n").unwrap();
    let renamed = dir.path().join("model.dae");
    std::fs::copy(&obj, &renamed).unwrap();
    let out = dir.path().join("o.png");
    for (scene, needle) in [
        (&obj, "ember reads COLLADA (.dae) scenes, not .obj files"),
        (&ply, "ember reads COLLADA (.dae) scenes, not .ply files"),
        (&renamed, "not a COLLADA (.dae) scene: the file is not XML"),
    ] {
        run(command().arg("-f").arg(&out).arg(scene)).fails_with(needle);
        run(command().arg("info").arg(scene)).fails_with(needle);
        assert!(!out.exists());
    }
}

/// The `triangles:` line of `ember info SCENE`.
fn info_triangles(scene: &std::path::Path) -> String {
    let info = run(command().arg("info").arg(scene)).success().stdout();
    let line = info.lines().find(|l| l.starts_with("triangles: "));
    line.unwrap_or_else(|| panic!("{info}")).to_string()
}

/// UTF-16 text (with a byte-order mark, or opening with `<`) and `.zae` archives reach
/// the loader from the command line: `ember info` counts what the UTF-8 file holds, and
/// a render writes its image.
#[test]
fn utf16_and_zae_scenes_are_read_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let course = repo("scenes/cs184/sky/CBempty.dae");
    let text = std::fs::read_to_string(&course).unwrap();
    let units = || text.encode_utf16();
    let bom_le = [0xFF, 0xFE].into_iter();
    let variants = [
        (
            "le.dae",
            bom_le.chain(units().flat_map(u16::to_le_bytes)).collect(),
        ),
        (
            "be.dae",
            [0xFE, 0xFF]
                .into_iter()
                .chain(units().flat_map(u16::to_be_bytes))
                .collect(),
        ),
        (
            "le_no_mark.dae",
            units().flat_map(u16::to_le_bytes).collect::<Vec<u8>>(),
        ),
    ];
    let quad = repo("tests/data/collada/textured_quad.dae");
    let zae = dir.path().join("quad.zae");
    let mut z = zip::ZipWriter::new(std::fs::File::create(&zae).unwrap());
    for (name, from) in [
        ("quad.dae", quad.clone()),
        ("texture4x4.png", repo("tests/data/collada/texture4x4.png")),
    ] {
        z.start_file(name, zip::write::SimpleFileOptions::default())
            .unwrap();
        std::io::Write::write_all(&mut z, &std::fs::read(from).unwrap()).unwrap();
    }
    z.finish().unwrap();
    let mut cases = vec![(zae, quad)];
    for (name, bytes) in variants {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        cases.push((path, course.clone()));
    }
    for (scene, original) in cases {
        assert_eq!(info_triangles(&scene), info_triangles(&original));
        let out = dir.path().join("out.png");
        run(command()
            .args(["-s", "1", "-r", "8", "6", "-f"])
            .arg(&out)
            .arg(&scene))
        .success();
        let img = image::open(&out).unwrap();
        assert_eq!((img.width(), img.height()), (8, 6), "{}", scene.display());
        std::fs::remove_file(&out).unwrap();
    }
}

/// `ember --help` lists every subcommand, each with its purpose on one line.
#[test]
fn help_lists_every_subcommand_in_one_line_each() {
    let help = ember(["--help"]).success().stdout();
    let mut names = vec!["info", "merge", "camera", "export"];
    if cfg!(feature = "bench") {
        names.push("bench");
    }
    for name in names {
        let line = help
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("--help does not list {name}:\n{help}"));
        let purpose = line.trim_start()[name.len()..].trim();
        assert!(purpose.len() > 20 && purpose.len() < 100, "{line}");
    }
    if cfg!(feature = "bench") {
        let bench = help
            .lines()
            .find(|l| l.trim_start().starts_with("bench "))
            .unwrap();
        for which in ["render", "accel", "converge", "stability", "estimators"] {
            assert!(bench.contains(which), "{bench}");
        }
    }
}

/// The pixels of a PNG, as written.
fn png_pixels(path: &std::path::Path) -> Vec<u8> {
    image::open(path).unwrap().to_rgb8().into_raw()
}

#[test]
fn accel_none_renders_what_the_bvh_renders() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cs184/sky/CBbunny.dae");
    let render = |accel: &str| {
        let out = dir.path().join(format!("{accel}.png"));
        run(command()
            .args([
                "-s", "2", "-m", "2", "-r", "24", "18", "--accel", accel, "-f",
            ])
            .arg(&out)
            .arg(&scene))
        .success();
        png_pixels(&out)
    };
    assert!(
        render("none") == render("native"),
        "brute force and the BVH differ"
    );
    let bvh = ember(["--accel", "none", "--bvh", "sah", "x.dae"]);
    bvh.fails_with("it does nothing with --accel none");
}

#[test]
fn accel_none_warns_when_it_would_take_long() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("slow.png");
    // Hours of brute force over 50801 triangles; --time stops it at once.
    let run = run(command()
        .args([
            "--accel", "none", "-s", "64", "-m", "5", "--time", "0.2", "-f",
        ])
        .arg(&out)
        .arg(repo("scenes/cs184/meshedit/maxplanck.dae")))
    .success();
    let err = run.stderr();
    assert!(
        err.contains("warning:") && err.contains("hours") && err.contains("--accel native"),
        "{err}"
    );
}

#[test]
fn the_png_rate_map_has_a_legend_below_the_map() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    run(command()
        .args(["-s", "64", "-a", "8", "0.1", "-r", "160", "120", "-f"])
        .arg(&out)
        .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae")))
    .success();
    let rate = image::open(dir.path().join("a_rate.png")).unwrap();
    assert_eq!(rate.width(), 160);
    assert!(rate.height() > 120 + 20, "{}", rate.height());
    let exr = dir.path().join("a.exr");
    run(command()
        .args(["-s", "64", "-a", "8", "0.1", "-r", "160", "120", "-f"])
        .arg(&exr)
        .arg(repo("scenes/cs184/sky/CBspheres_lambertian.dae")))
    .success();
    let counts = ember::image_io::read_image(&dir.path().join("a_rate.exr")).unwrap();
    assert_eq!(
        (counts.width, counts.height),
        (160, 120),
        "the EXR holds the counts only"
    );
}

/// `bench estimators` compares path tracing with light tracing where light tracing
/// can show the image, and says why not elsewhere (mirrors and glass), and with
/// light-traced caustics where there are any, with what auto runs and whether its
/// rule or its pilot chose.
#[cfg(feature = "bench")]
#[test]
fn bench_estimators_rows_say_what_auto_runs_and_why_light_tracing_is_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let o = run(command()
        .args([
            "bench",
            "estimators",
            "-r",
            "16",
            "12",
            "-s",
            "2",
            "--pairs",
            "1",
            "--out",
        ])
        .arg(dir.path())
        .arg(repo("scenes/cs184/sky/CBempty.dae"))
        .arg(repo("scenes/cs184/sky/CBspheres.dae"))
        .arg(repo("scenes/cs184/sky/CBbunny.dae")))
    .success();
    let csv = std::fs::read_to_string(dir.path().join("estimators.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 3, "{csv}");
    let row = |name: &str| *rows.iter().find(|r| r.contains(name)).unwrap();
    assert!(row("CBempty").contains("(pilot)"), "{csv}");
    // Columns: light tracing's noise² is the sixth, caustics' the ninth.
    let cell = |name: &str, i: usize| row(name).split(',').nth(i).unwrap().to_string();
    assert!(row("CBspheres").contains("caustics (rule)"), "{csv}");
    assert!(row("CBspheres").contains("mirror or glass"), "{csv}");
    assert_ne!(cell("CBspheres", 8), "—", "caustics are measured: {csv}");
    assert!(row("CBbunny").contains("path (rule)"), "{csv}");
    assert_ne!(cell("CBbunny", 5), "—", "light tracing is measured: {csv}");
    assert!(row("CBbunny").contains("no caustics"), "{csv}");
    assert!(o.stdout().contains("| scene |"), "{}", o.stdout());
    // A scene that does not load is an error naming it, not a row left out.
    let missing = dir.path().join("missing.dae");
    run(command()
        .args(["bench", "estimators", "--out"])
        .arg(dir.path())
        .arg(&missing))
    .fails_with("missing.dae");
}

/// Exit statuses: 2 for a command line that names no job (as clap's usage errors), 1
/// for work that failed.
#[test]
fn no_scene_is_a_usage_error_and_a_missing_one_a_failure() {
    let o = run(&mut command()).fails_with("no scene given");
    assert_eq!(o.code(), Some(2));
    let o = run(command().arg("missing.dae")).fails_with("missing.dae");
    assert_eq!(o.code(), Some(1));
}
