//! Ctrl-C and SIGTERM during a render: the first sets a flag that the render loop
//! reads (it stops, and ember writes what was rendered); a second ends ember at once
//! with status 130, removing the temporaries of unwritten outputs and leaving any
//! earlier output untouched.

use anyhow::{Context, Result};
use signal_hook::consts::{SIGINT, SIGTERM};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Exit status after an interrupt (128 + SIGINT), as shells report it.
pub const EXIT_INTERRUPTED: u8 = 130;

/// Installs the handlers; the returned flag is set by the first signal.
pub(super) fn install() -> Result<Arc<AtomicBool>> {
    let flag = Arc::new(AtomicBool::new(false));
    for sig in [SIGINT, SIGTERM] {
        // Registered first, so it sees the flag as the previous signal left it.
        let seen = flag.clone();
        let second = move || {
            if seen.load(Ordering::SeqCst) {
                ember::image_io::remove_claimed_temporaries();
                signal_hook::low_level::exit(EXIT_INTERRUPTED as i32);
            }
        };
        // SAFETY: the action only loads an atomic, unlinks files and calls `_exit`,
        // all async-signal-safe.
        unsafe { signal_hook::low_level::register(sig, second) }
            .context("cannot install the Ctrl-C handler")?;
        signal_hook::flag::register(sig, flag.clone())
            .context("cannot install the Ctrl-C handler")?;
    }
    Ok(flag)
}

/// A render that was interrupted: `main` prints the message and exits with
/// [`EXIT_INTERRUPTED`] instead of reporting an error.
#[derive(Debug)]
pub struct Interrupted(pub String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}
