//! Runs the default `bench accel --scaling` until the CLI flag is wired:
//! `cargo run --release --features embree --example bench_scaling -- [out_dir]`.

use ember::bench::scaling::{run_scaling, ScalingOptions};

fn main() -> anyhow::Result<()> {
    let mut opts = ScalingOptions::default();
    if let Some(dir) = std::env::args().nth(1) {
        opts.out_dir = dir.into();
    }
    let start = std::time::Instant::now();
    let report = run_scaling(&opts, |line| eprintln!("ember: {line}"))?;
    println!("{}", report.to_markdown());
    eprintln!(
        "ember: scaling run took {:.0} s",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
