//! The `ember` command line in three layers, as ripgrep splits its flags: `args`
//! defines the flags, `convert` turns them into library settings, and `commands` has
//! one short function per subcommand. Nothing in the library depends on this module.

mod args;
#[cfg(feature = "bench")]
mod bench;
mod commands;
mod convert;
mod interrupt;

pub use args::Cli;
use args::Command;
pub use interrupt::{Interrupted, EXIT_INTERRUPTED};

/// The course binary's getopt string: flags a CS184 script may pass.
const COURSE_FLAGS: &str = "s:l:t:m:o:e:h:H:f:r:c:b:d:a:p:";

/// Parses the command line. Help and version go through [`ember::out!`], so a full
/// disk is an error and a closed pipe is quiet; a course flag that ember does not
/// have yet is named as such rather than as an unknown argument.
pub fn parse() -> Result<Cli, std::process::ExitCode> {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    use clap::Parser;
    use std::process::ExitCode;
    let e = match Cli::try_parse() {
        Ok(cli) => return Ok(cli),
        Err(e) => e,
    };
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            let mut text = e.render().to_string();
            if !text.ends_with('\n') {
                text.push('\n');
            }
            return Err(match ember::out!("{text}") {
                Ok(()) => ExitCode::SUCCESS,
                Err(io) if io.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
                Err(io) => {
                    ember::errln!("ember: error: {io}");
                    ExitCode::FAILURE
                }
            });
        }
        ErrorKind::UnknownArgument => {
            if let Some(ContextValue::String(arg)) = e.get(ContextKind::InvalidArg) {
                if let Some(letter) = arg.strip_prefix('-').filter(|l| l.len() == 1) {
                    if COURSE_FLAGS.split(':').any(|f| f == letter) {
                        ember::errln!("ember: error: course flag {arg} is not supported");
                        return Err(ExitCode::from(2));
                    }
                }
            }
        }
        _ => {}
    }
    e.exit()
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    if let Some(dir) = cli.data {
        ember::data::set_root(dir);
    }
    match cli.command {
        Some(Command::Info { scene, resolution }) => {
            commands::info(&scene, resolution[0], resolution[1])
        }
        Some(Command::Export(args)) => commands::export(args),
        Some(Command::Merge { out, parts }) => commands::merge(&out, &parts),
        Some(Command::Camera(args)) => commands::camera(args),
        #[cfg(feature = "bench")]
        Some(Command::Bench { which }) => bench::run(which),
        None => commands::render(cli.render),
    }
}
