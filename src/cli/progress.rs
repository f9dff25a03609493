//! The render's progress bar: an `indicatif` bar with an ETA on stderr,
//! shown only once a render has run for [`SHOW_AFTER`] (quick renders
//! draw nothing) and only when stderr is a terminal (logs and pipes get
//! no control characters).

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use ibeam::render::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How long a render runs before its bar appears.
pub const SHOW_AFTER: Duration = Duration::from_millis(500);

/// A bar that starts hidden; [`Bar::report`] feeds it from the render.
pub struct Bar {
    bar: ProgressBar,
}

impl Bar {
    /// A bar for this render, or `None` with `--quiet` or when stderr is
    /// not a terminal.
    pub fn new(quiet: bool) -> Option<Bar> {
        if quiet || !std::io::stderr().is_terminal() {
            return None;
        }
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        if let Ok(style) = ProgressStyle::with_template(
            "rendering {bar:40} {pos}/{len} tiles, {elapsed} elapsed, ETA {eta}",
        ) {
            bar.set_style(style);
        }
        Some(Bar { bar })
    }

    /// The render's progress callback: sets the bar to (done, total) and
    /// turns drawing on once the render has run [`SHOW_AFTER`].
    pub fn report(&self) -> Progress {
        let bar = self.bar.clone();
        let start = Instant::now();
        let shown = Arc::new(AtomicBool::new(false));
        Box::new(move |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
            if start.elapsed() >= SHOW_AFTER && !shown.swap(true, Ordering::Relaxed) {
                bar.set_draw_target(ProgressDrawTarget::stderr());
            }
        })
    }

    /// Removes the bar, so the summary prints on a clean line.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quiet_renders_get_no_bar() {
        assert!(Bar::new(true).is_none());
    }

    // A bar fed before it is due stays hidden; the report never panics on
    // any count.
    #[test]
    fn reports_before_the_delay_draw_nothing() {
        let bar = Bar {
            bar: ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden()),
        };
        let report = bar.report();
        report(1, 4);
        report(4, 4);
        assert!(bar.bar.is_hidden());
        assert_eq!(bar.bar.position(), 4);
        bar.finish();
    }
}
