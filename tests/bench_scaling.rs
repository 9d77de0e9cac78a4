//! A tiny `bench accel --scaling` run: every mesh, size and backend gets a row of
//! finite positive figures, and the CSV, Markdown and charts land in the output folder.

use ember::bench::scaling::{run_scaling, ScalingMesh, ScalingOptions};
use ember::bench::Report;

#[test]
fn tiny_scaling_run_reports_every_row_and_writes_files() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("scaling");
    let opts = ScalingOptions {
        sizes: vec![1_000, 4_000],
        rays: 2_000,
        threads: 2,
        repeats: 1,
        ..ScalingOptions::default()
    };
    let mut lines = 0;
    let report = run_scaling(&opts, |_| lines += 1).unwrap();
    let files = report.write(&out_dir).unwrap();
    assert!(files.iter().all(|f| f.exists()), "{files:?}");

    let backends = if cfg!(any(feature = "embree", feature = "embree4")) {
        5
    } else {
        2
    };
    assert_eq!(report.rows.len(), 2 * 2 * backends);
    assert_eq!(lines, report.rows.len());
    for mesh in ScalingMesh::ALL {
        for size in [1_000, 4_000] {
            let rows: Vec<_> = report
                .rows
                .iter()
                .filter(|r| r.mesh == mesh && r.triangles.abs_diff(size) <= size / 10)
                .collect();
            assert_eq!(rows.len(), backends, "{mesh:?} at {size}");
        }
    }
    for r in &report.rows {
        for (what, v) in [
            ("build", r.measured.build_ms),
            ("memory", r.measured.memory_mb),
            ("camera", r.measured.camera_mrays),
            ("incoherent", r.measured.incoherent_mrays),
            ("shadow", r.measured.shadow_mrays),
        ] {
            assert!(v.is_finite() && v > 0.0, "{what} of {r:?}");
        }
    }

    let csv = std::fs::read_to_string(out_dir.join("scaling.csv")).unwrap();
    assert_eq!(csv.lines().count(), report.rows.len() + 1);
    let md = std::fs::read_to_string(out_dir.join("scaling.md")).unwrap();
    assert!(md.contains("build ~ N^b") && md.contains("log2 N"), "{md}");
    assert!(md.contains("| random soup | native SAH | N^"), "{md}");
    for mesh in ["sphere", "soup"] {
        for metric in ["build", "memory", "camera", "incoherent", "shadow"] {
            for ext in ["png", "svg"] {
                let path = out_dir.join(format!("{mesh}_{metric}.{ext}"));
                let len = std::fs::metadata(&path).map_or(0, |m| m.len());
                assert!(len > 1000, "{} missing or empty", path.display());
            }
        }
    }
}
