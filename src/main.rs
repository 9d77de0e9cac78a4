//! The `ember` command line: the CS184 path tracer's flags, plus subcommands.

mod cli;

use ember::output::{cut_short, error_chain_message, is_broken_pipe};
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = match cli::parse() {
        Ok(args) => args,
        Err(code) => return code,
    };
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our output went away (`ember info x.dae | head -1`).
        Err(e) if is_broken_pipe(e.as_ref()) => cut_short(),
        Err(e) if e.is::<cli::UsageError>() => {
            ember::errln!("ember: error: {e}");
            ExitCode::from(cli::EXIT_USAGE)
        }
        // Ctrl-C: what was rendered is written; say so, and exit as an interrupted program.
        Err(e) if e.is::<cli::Interrupted>() => {
            ember::errln!("ember: {e}");
            ExitCode::from(cli::EXIT_INTERRUPTED)
        }
        Err(e) => {
            ember::errln!("ember: error: {}", error_chain_message(e.as_ref()));
            ExitCode::FAILURE
        }
    }
}
