//! The command line's process-wide overrides (`input::overrides::Overrides::prepare_process`),
//! in a process of their own: huge pages and the size of rayon's pool are set once, before the
//! input is read, and a bad thread count is refused before either is touched. (The overrides of
//! a case are unit-tested in the library.)

use mpm_solve::input::overrides::{OverrideError, Overrides, MAX_THREADS};
use mpm_solve::parallel::huge_pages;

#[test]
fn process_settings_are_made_once_and_bad_thread_counts_refused_first() {
    let with = |threads, huge_pages| Overrides {
        threads,
        huge_pages,
        ..Overrides::default()
    };
    let e = with(Some(0), true).prepare_process().unwrap_err();
    assert!(matches!(e, OverrideError::NoThreads), "{e}");
    let e = with(Some(MAX_THREADS + 1), true)
        .prepare_process()
        .unwrap_err();
    assert!(matches!(e, OverrideError::TooManyThreads { .. }), "{e}");
    assert!(!huge_pages::enabled());
    with(Some(2), true).prepare_process().unwrap();
    assert!(huge_pages::enabled());
    assert_eq!(rayon::current_num_threads(), 2);
    // rayon's pool is sized once per process.
    let e = with(Some(3), false).prepare_process().unwrap_err();
    assert_eq!(e.to_string(), "sizing the thread pool");
    assert!(std::error::Error::source(&e).is_some());
}
