//! The integration tests, one file per subject, built as one test binary: each
//! binary is a compile and a link of its own, and thirty of them were a third of
//! CI's default build. Run one subject with a filter on its module path, e.g.
//! `cargo test --test suite references::`. (The Embree tests are `tests/embree.rs`.)
//!
//! Cargo.toml sets `autotests = false`: a new file in tests/ is a module here, or in
//! tests/embree.rs, and `every_test_file_is_a_module` fails until it is.

mod bvh_common;
mod common;

#[cfg(feature = "bench")]
mod bench_scaling;
mod bsdf;
mod bvh_brute_force;
mod bvh_scenes;
mod camera_flags;
mod camera_placement;
mod cli;
mod cli_hardening;
mod cycles_peer;
mod direct_split;
mod env_light;
mod export_mitsuba;
mod farm_dask;
mod lights;
mod loader_bad_input;
mod loader_exporters;
mod loader_fuzz;
mod loader_scenes;
mod loader_semantics;
mod loader_skins;
mod packet_engine;
mod pinned_images;
mod references;
#[cfg(feature = "bench")]
mod report;
mod shards;
#[cfg(feature = "bench")]
mod stability;
mod textures_spots;
mod thin_lens;
mod transport_analytic;
mod transport_scenes;

/// Every `tests/*.rs` file is a module of this crate or of tests/embree.rs (with
/// autotests off, a file that is in neither would never run).
#[test]
fn every_test_file_is_a_module() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let roots = ["suite.rs", "embree.rs"];
    let declared: String = roots
        .iter()
        .map(|root| std::fs::read_to_string(dir.join(root)).expect("read a test crate root"))
        .collect();
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("read tests/") {
        let name = entry
            .expect("a tests/ entry")
            .file_name()
            .into_string()
            .unwrap();
        let Some(module) = name.strip_suffix(".rs") else {
            continue;
        };
        if !roots.contains(&name.as_str()) && !declared.contains(&format!("\nmod {module};")) {
            missing.push(name);
        }
    }
    assert!(
        missing.is_empty(),
        "not declared in tests/suite.rs or tests/embree.rs: {missing:?}"
    );
}
