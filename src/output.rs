//! Terminal output that never panics: `println!` panics when stdout is a closed pipe
//! or a full disk. Reports go through [`write_stdout`] (an `io::Result` the caller
//! propagates), notes and warnings through [`write_stderr`] (errors ignored: there is
//! nowhere left to report them). [`is_broken_pipe`] lets `main` tell a reader that went
//! away from other failures: the output was cut short, so [`cut_short`] says so in one
//! line and gives [`EXIT_BROKEN_PIPE`], the status a shell reports for a program that
//! SIGPIPE stopped, so `set -o pipefail` sees it. [`error_chain_message`] prints an
//! error chain with each cause said once.

use std::error::Error;
use std::fmt;
use std::io::{self, Write};

/// The exit status after stdout's reader went away: 128 + SIGPIPE, as `cat` or `grep`
/// end in the same place.
pub const EXIT_BROKEN_PIPE: u8 = 141;

/// The one line said when stdout's reader went away.
pub const BROKEN_PIPE_MESSAGE: &str =
    "ember: standard output was closed by its reader; output cut short";

/// Says in one line that stdout's reader went away, and gives the status to exit with.
pub fn cut_short() -> std::process::ExitCode {
    write_stderr(format_args!("{BROKEN_PIPE_MESSAGE}\n"));
    std::process::ExitCode::from(EXIT_BROKEN_PIPE)
}

/// Writes to stdout and flushes, so a full disk is reported here and not lost at exit.
pub fn write_stdout(args: fmt::Arguments) -> io::Result<()> {
    let mut out = io::stdout().lock();
    out.write_fmt(args)
        .and_then(|()| out.flush())
        .map_err(|e| io::Error::new(e.kind(), format!("cannot write to standard output: {e}")))
}

/// Writes to stderr, ignoring failure (a closed or full stderr must not stop a render).
pub fn write_stderr(args: fmt::Arguments) {
    let mut err = io::stderr().lock();
    let _ = err.write_fmt(args);
    let _ = err.flush();
}

/// `println!` that returns `io::Result<()>` instead of panicking.
#[macro_export]
macro_rules! outln {
    () => { $crate::output::write_stdout(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::output::write_stdout(format_args!("{}\n", format_args!($($arg)*))) };
}

/// `print!` that returns `io::Result<()>` instead of panicking.
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => { $crate::output::write_stdout(format_args!($($arg)*)) };
}

/// `eprintln!` that never panics (a failed write to stderr is ignored).
#[macro_export]
macro_rules! errln {
    ($($arg:tt)*) => { $crate::output::write_stderr(format_args!("{}\n", format_args!($($arg)*))) };
}

/// Whether any cause in the chain is a broken pipe (the reader of stdout went away).
pub fn is_broken_pipe(err: &(dyn Error + 'static)) -> bool {
    chain(err).any(|e| {
        e.downcast_ref::<io::Error>()
            .is_some_and(|io| io.kind() == io::ErrorKind::BrokenPipe)
    })
}

/// The error and its causes joined by ": ", leaving out a cause whose text the
/// message already contains (many errors repeat their source in their own message).
pub fn error_chain_message(err: &(dyn Error + 'static)) -> String {
    let mut msg = String::new();
    for e in chain(err) {
        let text = e.to_string();
        if text.is_empty() || msg.contains(&text) {
            continue;
        }
        if !msg.is_empty() {
            msg.push_str(": ");
        }
        msg.push_str(&text);
    }
    msg
}

fn chain<'a>(err: &'a (dyn Error + 'static)) -> impl Iterator<Item = &'a (dyn Error + 'static)> {
    std::iter::successors(Some(err), |&e| e.source())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("out.png: cannot write: {source}")]
    struct Repeats {
        source: io::Error,
    }

    #[test]
    fn chain_says_each_cause_once() {
        let e = Repeats {
            source: io::Error::from(io::ErrorKind::NotFound),
        };
        let msg = error_chain_message(&e);
        let cause = io::Error::from(io::ErrorKind::NotFound).to_string();
        assert_eq!(msg.matches(&cause).count(), 1, "{msg}");
        assert!(msg.starts_with("out.png: cannot write: "), "{msg}");
    }

    #[test]
    fn broken_pipe_found_anywhere_in_the_chain() {
        let e = Repeats {
            source: io::Error::from(io::ErrorKind::BrokenPipe),
        };
        assert!(is_broken_pipe(&e));
        let e = Repeats {
            source: io::Error::from(io::ErrorKind::StorageFull),
        };
        assert!(!is_broken_pipe(&e));
    }
}
