//! Running the `ember` binary from integration tests: the one way to run it
//! ([`ember`], or [`run`] for a command given its own directory or streams) and to
//! check what it did ([`Run::success`], [`Run::fails_with`]).

use std::ffi::OsStr;
use std::path::Path;
use std::process::{Child, Command, Output};

/// The binary Cargo built for this test run, for a test that sets its working
/// directory or streams, or spawns it; [`run`] runs it and checks it like [`ember`].
pub fn command() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ember"))
}

/// `ember ARGS`, run to its end.
pub fn ember<S: AsRef<OsStr>>(args: impl IntoIterator<Item = S>) -> Run {
    run(command().args(args))
}

/// `ember ARGS` run in `dir`, where relative paths in ARGS are read and written.
pub fn ember_in<S: AsRef<OsStr>>(dir: &Path, args: impl IntoIterator<Item = S>) -> Run {
    run(command().current_dir(dir).args(args))
}

/// `cmd` (made by [`command`]) run to its end.
pub fn run(cmd: &mut Command) -> Run {
    let output = cmd.output().expect("run ember");
    Run {
        args: args_of(cmd),
        output,
    }
}

/// A child spawned from `cmd` (made by [`command`], with piped stdout and stderr),
/// waited for to its end: for a test that signals it or closes its pipes first. A
/// child still running after [`HANG_LIMIT`] is killed, so a signal that stopped
/// working fails the test ("killed by a signal") instead of blocking the suite.
pub fn wait(cmd: &Command, child: Child) -> Run {
    use std::sync::mpsc;
    let pid = child.id().to_string();
    let (done, finished) = mpsc::channel::<()>();
    let watchdog = std::thread::spawn(move || {
        if finished.recv_timeout(HANG_LIMIT).is_err() {
            let _ = Command::new("kill").args(["-KILL", &pid]).status();
        }
    });
    let output = child.wait_with_output().expect("wait for ember");
    let _ = done.send(());
    let _ = watchdog.join();
    Run {
        args: args_of(cmd),
        output,
    }
}

/// How long [`wait`] lets a child run: a hang guard, far above any test's run time.
pub const HANG_LIMIT: std::time::Duration = std::time::Duration::from_secs(120);

fn args_of(cmd: &Command) -> String {
    let args: Vec<String> = cmd
        .get_args()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    args.join(" ")
}

/// What one run of ember did.
pub struct Run {
    /// The arguments, for failure messages.
    pub args: String,
    pub output: Output,
}

impl Run {
    pub fn stdout(&self) -> String {
        String::from_utf8_lossy(&self.output.stdout).into_owned()
    }

    pub fn stderr(&self) -> String {
        String::from_utf8_lossy(&self.output.stderr).into_owned()
    }

    /// The exit status; `None` if a signal ended it.
    pub fn code(&self) -> Option<i32> {
        self.output.status.code()
    }

    /// Ended by itself, not by a panic (status 101, or the panic message) or a signal.
    pub fn no_panic(&self) -> &Self {
        let code = self.code();
        assert!(code.is_some(), "ember {}: killed by a signal", self.args);
        assert_ne!(
            code,
            Some(101),
            "ember {} panicked: {}",
            self.args,
            self.stderr()
        );
        assert!(
            !self.stderr().contains("panicked"),
            "ember {}: {}",
            self.args,
            self.stderr()
        );
        self
    }

    /// Exit status 0.
    pub fn success(self) -> Self {
        self.no_panic();
        assert!(
            self.output.status.success(),
            "ember {} failed: {}",
            self.args,
            self.stderr()
        );
        self
    }

    /// A non-zero exit, without a panic, whose error is one line containing `needle`:
    /// the last line of stderr is `ember: error: ...`, and every line before it is a
    /// note or warning of its own (`ember: ...`), not an error or its continuation.
    pub fn fails_with(self, needle: &str) -> Self {
        self.no_panic();
        let err = self.stderr();
        assert!(
            !self.output.status.success(),
            "ember {} succeeded: {err}",
            self.args
        );
        let lines: Vec<&str> = err.lines().collect();
        let one_line = lines.split_last().is_some_and(|(last, before)| {
            last.starts_with("ember: error: ")
                && (before.iter()).all(|l| l.starts_with("ember: ") && !l.contains("error"))
        });
        assert!(
            one_line,
            "ember {}: not a one-line error: {err:?}",
            self.args
        );
        assert!(
            lines[lines.len() - 1].contains(needle),
            "ember {}: {err:?} does not contain {needle:?}",
            self.args
        );
        self
    }
}
