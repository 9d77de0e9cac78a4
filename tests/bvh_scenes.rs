//! Every CS184 scene through both BVH builders against an exhaustive oracle:
//! `RAYS_PER_SCENE` random rays each (origins inside, on and outside the bounds;
//! uniform, axis-aligned and aimed directions; some finite intervals), nearest
//! hit and occlusion.
//!
//! Plain brute force over 100k rays × ~220k distinct primitives would be ~10^10
//! triangle tests, minutes on this machine, so the bulk check uses
//! `SegmentOracle` (brute force that skips, by a conservative f64 slab test,
//! primitives whose padded bounds the ray segment misses). `BruteForce` itself
//! checks the first `BRUTE_RAYS` rays of every scene, which also validates the
//! oracle's pruning on the same rays.

use crate::bvh_common;

use bvh_common::*;
use ember::geometry::Ray;
use ember::sampling::Rng;
use ember::scene::{collada, Scene};
use std::collections::HashSet;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::{Path, PathBuf};

const RAYS_PER_SCENE: usize = 100_000;
const BRUTE_RAYS: usize = 1_000;

fn scene_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut dirs = vec![dir.to_path_buf()];
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).expect("scene directory") {
            let p = entry.expect("entry").path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|e| e == "dae") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Identifies a scene's geometry: variants differing only in materials or lights
/// build the same tree and give the same answers, so they are checked once.
fn geometry_key(scene: &Scene) -> u64 {
    let mut h = DefaultHasher::new();
    for p in &scene.positions {
        p.to_array().map(f32::to_bits).hash(&mut h);
    }
    scene.triangles.iter().for_each(|t| t.v.hash(&mut h));
    for s in &scene.spheres {
        (s.centre.to_array().map(f32::to_bits), s.radius.to_bits()).hash(&mut h);
    }
    h.finish()
}

#[test]
fn bvh_agrees_with_oracle_on_course_scenes() {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cs184"));
    let files = scene_files(dir);
    assert!(
        files.len() >= 10,
        "only {} scenes in {}",
        files.len(),
        dir.display()
    );
    let mut seen = HashSet::new();
    for file in &files {
        let scene = collada::load(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        assert!(scene.num_prims() > 0, "{}: no primitives", file.display());
        if !seen.insert(geometry_key(&scene)) {
            continue;
        }
        let mut rng = Rng::from_seed(geometry_key(&scene));
        let aims = sample_targets(&scene, &mut rng);
        let bounds = scene_bounds(&scene);
        let rays: Vec<Ray> = (0..RAYS_PER_SCENE)
            .map(|_| random_ray(&mut rng, &bounds, &aims))
            .collect();
        check_against_brute(&scene, &rays[..BRUTE_RAYS]);
        check_against_oracle(&scene, &rays);
    }
    assert!(seen.len() >= 10, "only {} distinct geometries", seen.len());
}
