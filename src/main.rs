//! The `ember` command line: the CS184 path tracer's flags, plus subcommands.

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ember: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
