//! Blender Cycles as a peer (`scripts/cycles_render.py`, used by `ember bench
//! converge --cycles`): it translates ember's Mitsuba export into `bpy`, renders to
//! the reference's mean, and refuses what it cannot translate exactly.
//!
//! Needs Blender 4.5 as a Python module: `scripts/cycles-env` installs it into
//! `.cache/cycles` (about 1 GB), or set `EMBER_CYCLES_PYTHON`. Then
//! `cargo test --test suite cycles_peer:: -- --ignored`.

use crate::common;

use common::{ember, repo};
use std::path::{Path, PathBuf};
use std::process::Command;

fn cycles_python() -> PathBuf {
    std::env::var_os("EMBER_CYCLES_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo(".cache/cycles/bin/python"))
}

/// Exports `scene` at 160x120 (the references' size) and runs the Cycles script on it.
fn cycles(scene: &str, m: u32, spp: u32, reference: Option<&str>) -> std::process::Output {
    let dir = tempfile::tempdir().unwrap();
    let scene_arg = repo(scene).to_string_lossy().into_owned();
    let (spp, m) = (spp.to_string(), m.to_string());
    let out_arg = dir.path().to_string_lossy().into_owned();
    ember([
        "export", &scene_arg, "-r", "160", "120", "-s", &spp, "-m", &m, "--out", &out_arg,
    ])
    .success();
    let stem = Path::new(scene).file_stem().unwrap().to_string_lossy();
    let mut cmd = Command::new(cycles_python());
    cmd.arg(repo("scripts/cycles_render.py"))
        .arg(dir.path().join(format!("{stem}.xml")))
        .arg("--out")
        .arg(dir.path().join("cycles.exr"));
    if let Some(r) = reference {
        cmd.arg("--reference").arg(repo(r));
    }
    cmd.output().expect("run the Cycles python")
}

/// Lambertian spheres (Cycles points) and a rectangular area light: the image mean
/// is the reference's within 1 % plus 4 standard errors (the script's check).
#[test]
#[ignore = "needs Blender Cycles: run scripts/cycles-env, then cargo test --test suite cycles_peer:: -- --ignored"]
fn cycles_renders_the_reference_mean() {
    let out = cycles(
        "scenes/cs184/sky/CBspheres_lambertian.dae",
        5,
        32,
        Some("tests/data/references/CBspheres_lambertian_m5.exr"),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("mean check:") && stderr.contains(": OK;"),
        "{stderr}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout.lines().rev().find(|l| l.starts_with('{')).unwrap();
    let v: serde_json::Value = serde_json::from_str(line).unwrap();
    assert!(v["seconds"].as_f64().unwrap() > 0.0, "{line}");
    assert_eq!(v["max_bounces"], 4);
}

/// Glass has no exact translation here: the script says which shape, and fails.
#[test]
#[ignore = "needs Blender Cycles: run scripts/cycles-env, then cargo test --test suite cycles_peer:: -- --ignored"]
fn cycles_refuses_what_it_cannot_translate() {
    let out = cycles("scenes/cs184/sky/CBspheres.dae", 5, 4, None);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("<shape>") && stderr.contains("dielectric"),
        "{stderr}"
    );
}
