//! Standard output for the command line's reports (the plan of `--check`, the case summary,
//! the closing lines). A reader that goes away (`mpm-solve CASE --check | head -1`) ends the
//! printing, not the run or the check; any other write error (a full disk) is reported once on
//! standard error and makes the exit status a failure ([`failed`]). `println!` would panic on
//! either.

use std::io::Write;
use std::sync::atomic::{AtomicU8, Ordering};

/// 0 while standard output takes what is written; [`CLOSED`] once its reader has gone;
/// [`BROKEN`] once another write failed.
static STATE: AtomicU8 = AtomicU8::new(0);
const CLOSED: u8 = 1;
const BROKEN: u8 = 2;

/// Writes one line to standard output (see the module's note on errors).
pub fn line(args: std::fmt::Arguments<'_>) {
    if STATE.load(Ordering::Relaxed) != 0 {
        return;
    }
    if let Err(e) = writeln!(std::io::stdout().lock(), "{args}") {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            STATE.store(CLOSED, Ordering::Relaxed);
        } else {
            STATE.store(BROKEN, Ordering::Relaxed);
            eprintln!("mpm-solve: error: cannot write to standard output: {e}");
        }
    }
}

/// Whether a write to standard output failed other than by its reader going away.
pub fn failed() -> bool {
    STATE.load(Ordering::Relaxed) == BROKEN
}

/// [`line`] with `format!`'s arguments.
macro_rules! say {
    ($($t:tt)*) => {
        $crate::console::line(format_args!($($t)*))
    };
}
pub(crate) use say;
