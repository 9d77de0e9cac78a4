//! Rendering in parts (`--shard K/N` bands, `--spp-offset` sample ranges) and merging
//! them (`ember merge`): bands merge bit for bit into the whole render, sample ranges
//! into the render of all their samples (to f32 rounding), and bad merges are refused.

use crate::common;

use common::{ember_in, job, load, repo};
use ember::accel::{AccelKind, BvhBuilder};
use ember::film::Image;
use ember::image_metadata::ImageMetadata;
use ember::integrators::Estimator;
use ember::render::{Adaptive, PixelRect, RenderJob, RenderSettings};
use ember::shard::{merge, MergeError, Part, Shard};

const SCENE: &str = "scenes/cs184/sky/CBspheres_lambertian.dae";
/// Mirror and glass under an area light: `--integrator auto` renders it with
/// light-traced caustics, whose light paths land anywhere and are numbered by sample.
const CAUSTICS_SCENE: &str = "scenes/cs184/sky/CBspheres.dae";
const SIZE: (u32, u32) = (40, 30);

fn settings(adaptive: bool) -> RenderSettings {
    RenderSettings {
        spp: if adaptive { 32 } else { 4 },
        max_depth: 3,
        adaptive: adaptive.then(|| Adaptive::new(4, 0.05)),
        seed: 3,
        // `--integrator auto`, as the command line renders parts.
        estimator: None,
        ..Default::default()
    }
}

/// Pixels `rect` of `job` rendered with `s` as a part, with the header the CLI writes.
fn part(job: &RenderJob, s: &RenderSettings, rect: PixelRect, name: &str) -> Part {
    scene_part(SCENE, job, s, rect, name)
}

/// As [`part`], for the job of scene file `scene`.
fn scene_part(
    scene: &str,
    job: &RenderJob,
    s: &RenderSettings,
    rect: PixelRect,
    name: &str,
) -> Part {
    let out = job.render_rect(s, rect, &|_| {});
    Part {
        name: name.into(),
        meta: ImageMetadata::for_render(&repo(scene), job, s, 0.0),
        frame: SIZE,
        rect,
        image: out.image,
        samples: out.samples,
    }
}

fn bits(img: &Image) -> Vec<[u32; 3]> {
    img.pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

#[test]
fn merged_bands_are_bit_identical_to_the_whole_render() {
    for (path, adaptive) in [(SCENE, false), (SCENE, true), (CAUSTICS_SCENE, false)] {
        let scene = load(path);
        let job = job(&scene, SIZE.0, SIZE.1, AccelKind::Native(BvhBuilder::Sah));
        let s = settings(adaptive);
        let want = [Estimator::Path, Estimator::Caustics][usize::from(path == CAUSTICS_SCENE)];
        assert_eq!(job.estimator(&s), want, "{path}");
        let full = pool(1).install(|| job.render(&s));
        if adaptive {
            let min = full.samples.iter().min().unwrap();
            let max = full.samples.iter().max().unwrap();
            assert!(min < max, "adaptive sampling should vary the sample count");
        }
        for threads in [1, 2] {
            for n in [1, 2, 3, 7] {
                let parts: Vec<Part> = (0..n)
                    .map(|k| {
                        let rect = Shard { index: k, count: n }.rect(SIZE.0, SIZE.1);
                        let name = format!("{k}/{n}");
                        pool(threads).install(|| scene_part(path, &job, &s, rect, &name))
                    })
                    .collect();
                let merged = merge(&parts).unwrap_or_else(|e| panic!("N={n}: {e}"));
                let what = format!("{path} N={n} -t {threads} adaptive={adaptive}");
                assert!(
                    bits(&merged.image) == bits(&full.image),
                    "{what}: pixels differ"
                );
                assert_eq!(merged.samples, full.samples, "{what}: sample counts");
                assert_eq!(merged.meta.get("ember.spp"), Some(&*s.spp.to_string()));
            }
        }
    }
}

#[test]
fn merged_sample_ranges_equal_the_render_of_all_samples_to_rounding() {
    for path in [SCENE, CAUSTICS_SCENE] {
        merged_sample_ranges_of(path);
    }
}

fn merged_sample_ranges_of(path: &str) {
    let scene = load(path);
    let job = job(&scene, SIZE.0, SIZE.1, AccelKind::Native(BvhBuilder::Sah));
    let all = RenderSettings {
        spp: 8,
        ..settings(false)
    };
    let full = job.render(&all);
    // Uneven ranges 0..1, 1..4, 4..8, given out of order, over two bands for 4..8.
    let range = |offset, spp| RenderSettings {
        spp,
        spp_offset: offset,
        ..all.clone()
    };
    let frame = PixelRect::full(SIZE.0, SIZE.1);
    let top = Shard { index: 0, count: 2 }.rect(SIZE.0, SIZE.1);
    let bottom = Shard { index: 1, count: 2 }.rect(SIZE.0, SIZE.1);
    let parts = vec![
        scene_part(path, &job, &range(1, 3), frame, "1..4"),
        scene_part(path, &job, &range(4, 4), bottom, "4..8 bottom"),
        scene_part(path, &job, &range(0, 1), frame, "0..1"),
        scene_part(path, &job, &range(4, 4), top, "4..8 top"),
    ];
    // Per-range images only make sense if they differ from the whole render.
    assert!(bits(&parts[2].image) != bits(&full.image));
    let merged = merge(&parts).unwrap();
    assert_eq!(merged.meta.get("ember.spp"), Some("8"));
    assert!(merged.samples.iter().all(|&n| n == 8));
    // The same samples summed in another order: equal to a few f32 ulp (radiance ≥ 0,
    // so the relative rounding error of a sum of 8 terms is below 8·2⁻²⁴ ≈ 5e-7).
    let mut worst = 0f32;
    for (m, f) in merged.image.pixels.iter().zip(&full.image.pixels) {
        for (a, b) in m.to_array().into_iter().zip(f.to_array()) {
            let rel = (a - b).abs() / b.abs().max(f32::MIN_POSITIVE);
            worst = worst.max(if a == b { 0.0 } else { rel });
        }
    }
    assert!(worst < 2e-6, "{path}: largest relative difference {worst}");
}

/// Two bands of 4 spp and the same bands as sample ranges 0..2, 2..4.
fn good_parts(job: &RenderJob) -> Vec<Part> {
    let s = settings(false);
    let half = |o| RenderSettings {
        spp: 2,
        spp_offset: o,
        ..s.clone()
    };
    let band = |k| Shard { index: k, count: 2 }.rect(SIZE.0, SIZE.1);
    vec![
        part(job, &half(0), band(0), "top0.exr"),
        part(job, &half(2), band(0), "top2.exr"),
        part(job, &half(0), band(1), "bottom0.exr"),
        part(job, &half(2), band(1), "bottom2.exr"),
    ]
}

#[test]
fn bad_merges_are_refused_naming_the_file() {
    let scene = load(SCENE);
    let job = job(&scene, SIZE.0, SIZE.1, AccelKind::Native(BvhBuilder::Sah));
    let good = good_parts(&job);
    merge(&good).expect("the good parts merge");
    let without = |i: usize| -> Vec<Part> {
        let mut v = good.clone();
        v.remove(i);
        v
    };
    let err = |parts: &[Part]| merge(parts).unwrap_err();

    assert_eq!(err(&[]), MergeError::NoParts);
    // A band missing entirely: a gap of pixels.
    let e = err(&[good[0].clone(), good[1].clone()]);
    assert!(matches!(e, MergeError::PixelGap { y: 15, .. }), "{e}");
    // A sample range missing in one band.
    let e = err(&without(1));
    assert!(matches!(e, MergeError::UnevenSamples { .. }), "{e}");
    let e = err(&without(2));
    assert!(
        e.to_string().contains("bottom2.exr") && e.to_string().contains("0..2"),
        "{e}"
    );
    // Duplicate.
    let mut dup = good.clone();
    dup.push(good[3].clone());
    assert_eq!(
        err(&dup).to_string(),
        "bottom2.exr: duplicate of bottom2.exr (same pixels and samples)"
    );
    // Overlapping bands: a third of the image over the halves.
    let mut over = good.clone();
    let third = Shard { index: 1, count: 3 }.rect(SIZE.0, SIZE.1);
    let s = RenderSettings {
        spp: 2,
        ..settings(false)
    };
    over.push(part(&job, &s, third, "third.exr"));
    let e = err(&over);
    assert!(
        matches!(&e, MergeError::Overlap { file, .. } if file == "third.exr"),
        "{e}"
    );
    // Overlapping sample ranges.
    let mut over = good.clone();
    let s13 = RenderSettings {
        spp: 2,
        spp_offset: 1,
        ..settings(false)
    };
    over.push(part(&job, &s13, good[0].rect, "top1.exr"));
    let e = err(&over);
    assert!(
        matches!(&e, MergeError::Overlap { file, .. } if file == "top1.exr"),
        "{e}"
    );
    // Headers that disagree: seed, scene hash, version, settings.
    for (key, value) in [
        ("ember.seed", "4"),
        ("ember.scene.fnv1a64", "0123456789abcdef"),
        ("ember.version", "9.9.9"),
        ("ember.max_depth", "5"),
    ] {
        let mut bad = good.clone();
        for e in bad[2].meta.entries.iter_mut().filter(|(k, _)| k == key) {
            e.1 = value.into();
        }
        let e = err(&bad);
        assert!(
            matches!(&e, MergeError::Mismatch { file, key: k, .. } if file == "bottom0.exr" && k == key),
            "{key}: {e}"
        );
    }
    // A part without a sample offset is not a part.
    let mut bad = good.clone();
    bad[1].meta.entries.retain(|(k, _)| k != "ember.spp_offset");
    let e = err(&bad);
    assert!(
        matches!(&e, MergeError::NotAPart { file, .. } if file == "top2.exr"),
        "{e}"
    );
}

#[test]
fn cli_shards_merge_into_the_whole_render_and_bad_merges_fail() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = repo(SCENE).display().to_string();
    let render = |extra: &[&str], out: &str| {
        let mut a = vec!["-q", "-s", "4", "-m", "2", "-r", "40", "30", "-f", out];
        a.extend_from_slice(extra);
        a.push(&scene);
        ember_in(d, &a).success();
    };
    render(&["-t", "2"], "full.exr");
    for k in 0..3 {
        let shard = format!("{k}/3");
        render(&["-t", "1", "--shard", &shard], &format!("b{k}.exr"));
    }
    ember_in(d, ["merge", "merged.exr", "b2.exr", "b0.exr", "b1.exr"]).success();
    let full = ember::image_io::read_image(&d.join("full.exr")).unwrap();
    let merged = ember::image_io::read_image(&d.join("merged.exr")).unwrap();
    assert!(bits(&merged) == bits(&full));
    ember_in(d, ["merge", "merged.png", "b0.exr", "b1.exr", "b2.exr"]).success();
    assert!(d.join("merged.png").exists());
    let meta = ember::image_io::read_metadata(&d.join("merged.exr")).unwrap();
    assert_eq!(meta.get("ember.merged_parts"), Some("3"));
    assert!(meta.get("ember.scene.fnv1a64").is_some());

    // Refusals: each names the file at fault, exits non-zero and writes nothing.
    render(&["--shard", "1/3", "--seed", "9"], "seed9.exr");
    render(&["--spp-offset", "0"], "s0.exr");
    for (args, needle) in [
        (
            vec!["b0.exr", "b1.exr"],
            "gap: no part covers pixel (0, 20)",
        ),
        (
            vec!["b0.exr", "b1.exr", "b1.exr", "b2.exr"],
            "b1.exr: duplicate of b1.exr",
        ),
        (
            vec!["b0.exr", "seed9.exr", "b2.exr"],
            "seed9.exr: ember.seed is \"9\"",
        ),
        (vec!["b0.exr", "b1.exr", "b2.exr", "s0.exr"], "overlap"),
        (
            vec!["b0.exr", "full.exr"],
            "full.exr: cannot read image: no samples channel",
        ),
        (vec!["b0.exr", "missing.exr"], "missing.exr"),
    ] {
        let mut a = vec!["merge", "bad.exr"];
        a.extend(args);
        ember_in(d, &a).fails_with(needle);
        assert!(!d.join("bad.exr").exists());
    }
    for (extra, needle) in [
        (
            vec!["--spp-offset", "4", "-a", "4", "0.05"],
            "--spp-offset cannot be used with adaptive",
        ),
        (
            vec!["--shard", "3/3"],
            "--shard: expected K/N with 0 <= K < N",
        ),
        (
            vec!["--shard", "0/31"],
            "31 bands but the image has 30 rows",
        ),
        (
            vec!["--shard", "0/2", "--shading", "bvh-cost"],
            "bvh-cost cannot be rendered in parts",
        ),
        (
            vec!["--shard", "0/2", "-p", "0", "0", "8", "8"],
            "-p cannot be used with --shard",
        ),
    ] {
        let mut a = vec!["-q", "-r", "40", "30", "-f", "p.exr"];
        a.extend(extra);
        a.push(&scene);
        ember_in(d, &a).fails_with(needle);
    }
    ember_in(d, ["-q", "--shard", "0/2", "-f", "p.png", &scene]).fails_with("p.png: a part");
    // Light tracing (auto's choice for CBempty at -m 5) splats anywhere: no parts.
    let empty = repo("scenes/cs184/sky/CBempty.dae").display().to_string();
    for flag in ["--shard", "--spp-offset"] {
        let value = if flag == "--shard" { "0/2" } else { "4" };
        ember_in(
            d,
            [
                "-q", "-m", "5", "-r", "40", "30", flag, value, "-f", "lt.exr", &empty,
            ],
        )
        .fails_with("cannot be used with light tracing");
        assert!(!d.join("lt.exr").exists());
    }
}
