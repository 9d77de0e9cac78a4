//! Running the `ember` binary from integration tests.

use std::process::{Command, Output};

/// The binary Cargo built for this test run.
pub fn ember() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ember"))
}

/// A process's standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
