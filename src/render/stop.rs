//! When a render should end early: an interrupt (Ctrl-C, set by the caller's signal
//! handler) or a time budget. The render loop asks before each pixel, so a stopped
//! render is a set of whole pixels, each with all the samples it was given, and it
//! stops within one pixel's time. Nothing here knows about signals: the CLI owns them.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Why a render stopped before finishing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The interrupt flag was set (Ctrl-C or SIGTERM).
    Interrupted,
    /// The time budget was spent.
    TimeUp,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StopReason::Interrupted => "interrupted",
            StopReason::TimeUp => "time budget spent",
        })
    }
}

/// A cheap, shareable question "stop now?": an optional flag and an optional deadline.
#[derive(Clone, Debug, Default)]
pub struct StopToken {
    flag: Option<Arc<AtomicBool>>,
    deadline: Option<Instant>,
}

impl StopToken {
    /// A token that never stops a render.
    pub fn never() -> Self {
        StopToken::default()
    }

    /// Stops once `flag` is set (e.g. by a signal handler).
    pub fn with_flag(mut self, flag: Arc<AtomicBool>) -> Self {
        self.flag = Some(flag);
        self
    }

    /// Stops at `deadline`.
    pub fn with_deadline(mut self, deadline: Instant) -> Self {
        self.deadline = Some(deadline);
        self
    }

    /// Why the render should stop now, if it should (an interrupt wins over the clock).
    pub fn reason(&self) -> Option<StopReason> {
        if self
            .flag
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
        {
            return Some(StopReason::Interrupted);
        }
        if self.deadline.is_some_and(|d| Instant::now() >= d) {
            return Some(StopReason::TimeUp);
        }
        None
    }

    #[inline]
    pub fn should_stop(&self) -> bool {
        self.reason().is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn flag_and_deadline_stop_with_their_reason() {
        assert_eq!(StopToken::never().reason(), None);
        let flag = Arc::new(AtomicBool::new(false));
        let t = StopToken::never()
            .with_flag(flag.clone())
            .with_deadline(Instant::now() + Duration::from_secs(3600));
        assert_eq!(t.reason(), None);
        flag.store(true, Ordering::Relaxed);
        assert_eq!(t.reason(), Some(StopReason::Interrupted));
        let past = StopToken::never().with_deadline(Instant::now());
        assert_eq!(past.reason(), Some(StopReason::TimeUp));
    }
}
