//! Runs `ember bench accel` with its default options (or `--quick`) and prints the
//! Markdown table, until the CLI grows the subcommand.

use ember::bench::accel::{run, AccelBenchOptions};

fn main() -> anyhow::Result<()> {
    let mut opts = AccelBenchOptions::default();
    if std::env::args().any(|a| a == "--quick") {
        opts.rays = 20_000;
        opts.repeats = 1;
        opts.width = 120;
        opts.height = 90;
        opts.scenes.pop();
    }
    let report = run(&opts, |line| eprintln!("{line}"))?;
    println!("{}", report.to_markdown());
    Ok(())
}
