//! The `ember` command line in three layers, as ripgrep splits its flags: `args`
//! defines the flags, `convert` turns them into library settings, and `commands` has
//! one short function per subcommand. Nothing in the library depends on this module.

mod args;
#[cfg(feature = "bench")]
mod bench;
mod commands;
mod convert;
mod interrupt;
#[cfg(feature = "bench")]
mod report;

pub use args::Cli;
use args::Command;
pub use interrupt::{Interrupted, EXIT_INTERRUPTED};

/// The course binary's getopt string: flags a CS184 script may pass.
const COURSE_FLAGS: &str = "s:l:t:m:o:e:h:H:f:r:c:b:d:a:p:";

/// A command line that names no job (no scene): `main` exits with [`EXIT_USAGE`], as
/// clap does for its usage errors, not 1, which is for work that failed.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// The exit status of a usage error (clap's).
pub const EXIT_USAGE: u8 = 2;

/// Parses the command line. Help and version go through [`ember::out!`], so a full
/// disk is an error and a closed pipe is said in one line; a course flag that ember does not
/// have yet is named as such rather than as an unknown argument; any other error is
/// one line, as every error of ember is.
pub fn parse() -> Result<Cli, std::process::ExitCode> {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    use clap::Parser;
    use std::process::ExitCode;
    let e = match Cli::try_parse() {
        Ok(cli) => return Ok(cli),
        Err(e) => e,
    };
    // `ember --data DIR info x.dae`: options before a subcommand make clap read the
    // subcommand's name as a scene. Read again with them after it.
    let e = match (e.kind(), subcommand_first()) {
        (ErrorKind::ArgumentConflict, Some(args)) => {
            let name = args[1].to_string_lossy().into_owned();
            match Cli::try_parse_from(args) {
                Ok(cli) => return Ok(cli),
                Err(e) if e.kind() == ErrorKind::UnknownArgument => {
                    ember::errln!(
                        "ember: error: the options before `{name}` are read as its own: {}",
                        one_line(&e)
                    );
                    return Err(ExitCode::from(e.exit_code().clamp(1, 255) as u8));
                }
                Err(e) => e,
            }
        }
        _ => e,
    };
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            let mut text = e.render().to_string();
            if !text.ends_with('\n') {
                text.push('\n');
            }
            return Err(match ember::out!("{text}") {
                Ok(()) => ExitCode::SUCCESS,
                Err(io) if io.kind() == std::io::ErrorKind::BrokenPipe => {
                    ember::output::cut_short()
                }
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
    if let Some(values) = extra_adaptive_values() {
        ember::errln!(
            "ember: error: -a takes at most two values, BATCH and TOL, but was given {}",
            values.join(" ")
        );
        return Err(ExitCode::from(2));
    }
    ember::errln!("ember: error: {}", one_line(&e));
    Err(ExitCode::from(e.exit_code().clamp(1, 255) as u8))
}

/// The command line with the options before its first subcommand name moved to the
/// end (`ember --data D bench render x.dae` → `ember bench render x.dae --data D`),
/// if it names one after some options.
fn subcommand_first() -> Option<Vec<std::ffi::OsString>> {
    use clap::CommandFactory;
    let mut args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let cmd = Cli::command();
    let is_subcommand = |a: &std::ffi::OsString| {
        let a = a.to_str().unwrap_or("");
        cmd.get_subcommands().any(|s| s.get_name() == a)
    };
    let at = args.iter().skip(1).position(is_subcommand)? + 1;
    if at == 1 || !args[1].to_str().is_some_and(|a| a.starts_with('-')) {
        return None;
    }
    let options: Vec<_> = args.drain(1..at).collect();
    args.extend(options);
    Some(args)
}

/// `-a 64 0.05 0.1 scene.dae`: clap gives `-a` two values and takes `0.1` for the scene
/// and `scene.dae` for a subcommand. Parsed again with `-a` taking every value up to
/// the next flag (and the last, if not a number, as the scene), its values if more than two.
fn extra_adaptive_values() -> Option<Vec<String>> {
    use clap::CommandFactory;
    let cmd = Cli::command().mut_arg("adaptive", |a| a.num_args(0..));
    let matches = cmd.try_get_matches().ok()?;
    let mut values: Vec<String> = matches.get_many::<String>("adaptive")?.cloned().collect();
    let scene_given = matches.get_one::<std::path::PathBuf>("scene").is_some();
    if !scene_given && values.last().is_some_and(|v| v.parse::<f64>().is_err()) {
        values.pop();
    }
    (values.len() > 2).then_some(values)
}

/// Clap's error (message, tips, usage, each on its own lines) as one line: the message,
/// its tips, and the usage of the command it concerns.
fn one_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let message = lines
        .iter()
        .take_while(|l| !l.is_empty())
        .map(|l| l.trim_start_matches("error: "))
        .collect::<Vec<_>>()
        .join(" ");
    let mut parts = vec![message];
    // Not the tip to pass a flag-like word as a scene path ("use '-- --frobnicate'").
    let tips = lines.iter().filter_map(|l| l.strip_prefix("tip: "));
    parts.extend(
        tips.filter(|t| !t.contains("'-- "))
            .map(|t| format!("tip: {t}")),
    );
    parts.extend(
        (lines.iter().filter_map(|l| l.strip_prefix("Usage: "))).map(|u| format!("usage: {u}")),
    );
    parts.join("; ")
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    if let Some(dir) = cli.data {
        ember::data::set_root(dir);
    }
    convert::limit_simd(cli.simd)?;
    match cli.command {
        Some(Command::Info {
            path,
            resolution,
            placement,
        }) => commands::info(&path, resolution[0], resolution[1], &placement),
        Some(Command::Export(args)) => commands::export(args),
        Some(Command::Merge { out, parts }) => commands::merge(&out, &parts),
        Some(Command::Camera(args)) => commands::camera(args),
        #[cfg(feature = "bench")]
        Some(Command::Bench { which }) => bench::run(which),
        #[cfg(feature = "bench")]
        Some(Command::Report(args)) => report::run(args),
        None => commands::render(cli.render),
    }
}
