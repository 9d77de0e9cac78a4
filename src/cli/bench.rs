//! `ember bench ...`: each benchmark runs, writes its report, prints its summary.

use super::args::{BenchAccelArgs, BenchCommand};
use super::convert::{
    bench_accel_options, bench_converge_options, bench_estimators_options, bench_render_options,
    bench_stability_options,
};
use anyhow::{Context, Result};
use ember::bench::{self, Report};
use std::path::{Path, PathBuf};

/// Runs one benchmark on a pool of its `-t` threads (`bench accel` measures its own list).
pub(super) fn run(which: BenchCommand) -> Result<()> {
    let threads = match &which {
        BenchCommand::Stability(a) => a.threads,
        BenchCommand::Estimators(a) => a.threads,
        BenchCommand::Converge(a) => a.threads,
        BenchCommand::Render(a) => a.threads,
        BenchCommand::Accel(_) => None,
    };
    super::commands::thread_pool(threads)?.install(|| match which {
        BenchCommand::Render(a) => {
            let out = a.out.clone();
            finish(&bench::render::run(&bench_render_options(a)?)?, &out)
        }
        BenchCommand::Accel(a) if a.scaling => bench_scaling(a),
        BenchCommand::Accel(a) => bench_accel(a),
        BenchCommand::Converge(a) => {
            let opts = bench_converge_options(a)?;
            let report = bench::converge::run(&opts, &mut |m| ember::errln!("ember: {m}"))?;
            finish(&report, &opts.out_dir)
        }
        BenchCommand::Stability(a) => {
            let report = bench::stability::run_stability(&bench_stability_options(&a)?)?;
            finish(&report, &a.out)
        }
        BenchCommand::Estimators(a) => {
            let out = a.out.clone();
            let opts = bench_estimators_options(a)?;
            let report = bench::estimators::run(&opts, &mut |m| ember::errln!("ember: {m}"))?;
            finish(&report, &out)
        }
    })
}

fn bench_scaling(a: BenchAccelArgs) -> Result<()> {
    let opts = bench::scaling::ScalingOptions {
        repeats: a.repeats.max(1),
        ..Default::default()
    };
    let out = a.out.unwrap_or_else(|| "bench-out/scaling".into());
    let report = bench::scaling::run_scaling(&opts, |line| ember::errln!("ember: {line}"))?;
    finish(&report, &out)
}

/// `ember bench accel`: the rows so far are written after every scene and thread
/// count, so a run that is stopped (Ctrl-C: after the measurement under way) or killed
/// leaves the rows it finished.
fn bench_accel(a: BenchAccelArgs) -> Result<()> {
    use bench::accel::{AccelBenchReport, Progress};
    let out: PathBuf = a.out.clone().unwrap_or_else(|| "bench-out/accel".into());
    let append = a.append;
    let opts = bench_accel_options(a)?;
    // Read what to append to before the long run, so a missing file fails at once.
    let earlier = match append {
        true => Some(AccelBenchReport::read(&out).context("--append")?),
        false => None,
    };
    let with_earlier = |r: AccelBenchReport| match &earlier {
        Some(e) => e.clone().merge(r),
        None => r,
    };
    let interrupt = super::interrupt::install()?;
    say_when_stopping(interrupt.clone());
    let mut written = Ok(());
    let report = bench::accel::run(
        &opts,
        |p| match p {
            Progress::Line(line) => ember::errln!("ember: {line}"),
            Progress::Rows(rows) => {
                if written.is_ok() {
                    written = with_earlier(rows.clone()).write(&out).map(drop);
                }
            }
        },
        &|| interrupt.load(std::sync::atomic::Ordering::Relaxed),
    )?;
    written?;
    let stopped = report.stopped.clone();
    finish(&with_earlier(report), &out)?;
    match stopped {
        Some(s) => Err(super::Interrupted(format!(
            "interrupted: {s}; wrote the rows measured to {}",
            out.display()
        ))
        .into()),
        None => Ok(()),
    }
}

/// Tells the user, once Ctrl-C is pressed, that the run ends after the measurement
/// under way (which may take a minute on a large mesh).
fn say_when_stopping(flag: std::sync::Arc<std::sync::atomic::AtomicBool>) {
    std::thread::spawn(move || loop {
        if flag.load(std::sync::atomic::Ordering::Relaxed) {
            ember::errln!(
                "ember: stopping after the measurement under way; the rows measured are written \
                 (Ctrl-C again quits at once, keeping the rows already written)"
            );
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    });
}

/// The end of every benchmark: write its report into `out`, print its summary and the files.
fn finish(report: &impl Report, out: &Path) -> Result<()> {
    let files = report.write(out)?;
    ember::outln!("{}", report.summary().trim_end())?;
    let files: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    ember::outln!("wrote {}", files.join(", "))?;
    Ok(())
}
