//! `ember report`: the write-up's figures rendered through the library, with a
//! progress bar over all of them.

use super::args::ReportArgs;
use super::convert::report_options;
use super::interrupt::{self, Interrupted};
use anyhow::Result;
use ember::report::{self, Progress};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

pub(super) fn run(a: ReportArgs) -> Result<()> {
    let opts = report_options(&a)?;
    let stop = interrupt::install()?;
    let pool = super::commands::thread_pool(a.threads)?;
    let bar = Bar::new(stop);
    let written = pool.install(|| report::run(&opts, &bar));
    bar.pb.finish_and_clear();
    let w = match written {
        Err(e) if e.is::<report::Interrupted>() => return Err(Interrupted(e.to_string()).into()),
        other => other?,
    };
    ember::outln!(
        "ember: wrote {} and {} ({} images) in {:.0} s",
        w.html.display(),
        w.markdown.display(),
        w.images,
        w.seconds
    )?;
    Ok(())
}

/// The report's progress on the terminal: one bar over every render, the current
/// figure beside it; nothing when stderr is not a terminal.
struct Bar {
    pb: ProgressBar,
    stop: Arc<AtomicBool>,
}

impl Bar {
    fn new(stop: Arc<AtomicBool>) -> Bar {
        let pb = match std::io::stderr().is_terminal() {
            true => ProgressBar::new(1),
            false => ProgressBar::hidden(),
        };
        pb.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {percent:>3}% ETA {eta:>4} {wide_msg}",
            )
            .expect("valid template"),
        );
        Bar { pb, stop }
    }
}

impl Progress for Bar {
    fn start(&self, total: u64) {
        self.pb.set_length(total.max(1));
    }

    fn step(&self, what: &str) {
        self.pb.set_message(what.to_string());
    }

    fn advance(&self, units: u64) {
        self.pb.inc(units);
    }

    fn note(&self, line: &str) {
        self.pb.suspend(|| ember::errln!("ember: {line}"));
    }

    fn should_stop(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::super::args::Cli;
    use super::super::convert::settings_from;
    use clap::Parser;
    use ember::accel::{AccelKind, BvhBuilder, EmbreeQuality};
    use ember::report::plan::{self, Budget, Scenes};

    /// Every render of the full and the quick report, its printed command parsed and
    /// converted by the CLI's own code, gives the report's settings, backend, size and
    /// scene: the command under a figure is the render that made it.
    #[test]
    fn every_printed_command_means_the_figure_s_render() {
        for (quick, budget) in [(false, Budget::full()), (true, Budget::quick())] {
            let scenes = Scenes::course(quick).expect("the course's scenes");
            let sections = plan::plan(&scenes, &budget, 7);
            let recipes = plan::recipes(&sections, &budget, 7);
            assert!(recipes.len() > 40, "{}", recipes.len());
            for r in recipes {
                let scene = r.scene.to_string_lossy().into_owned();
                let command = r.command(&scene, "out.png");
                let words: Vec<&str> = command.split(' ').collect();
                let cli = Cli::try_parse_from(&words).unwrap_or_else(|e| panic!("{command}: {e}"));
                let args = cli.render;
                let settings = settings_from(&args).expect("settings");
                assert_eq!(
                    format!("{settings:?}"),
                    format!("{:?}", r.settings()),
                    "{command}"
                );
                let kind =
                    AccelKind::new(args.accel, BvhBuilder::default(), EmbreeQuality::default());
                assert_eq!(kind, r.accel_kind(), "{command}");
                assert_eq!(args.resolution, [r.width, r.height], "{command}");
                assert_eq!(args.scene.as_deref(), Some(r.scene.as_path()), "{command}");
            }
        }
    }
}
