//! The calling thread's placement while a team works on it (docs/design.md §5.1).
//!
//! A team's thread 0 is the thread that calls it ([`crate::parallel::pool`]). Where the team
//! pins its threads, that thread is pinned too, for the team's life only: the caller gets its
//! own placement back when the team ends, and before a new team looks at the cores (a team
//! replacing another must see every core the process may use, and its unpinned workers must
//! not inherit one core).
//!
//! Each pin is owned by the team that made it (a token), so that an old team ending after its
//! replacement has pinned the caller leaves the new pin alone.

use std::sync::atomic::{AtomicU64, Ordering};

/// Tokens for the teams that pin their caller (0: none).
static NEXT_TOKEN: AtomicU64 = AtomicU64::new(1);

/// A new owner token for [`pin_caller`].
pub fn token() -> u64 {
    NEXT_TOKEN.fetch_add(1, Ordering::Relaxed)
}

#[cfg(target_os = "linux")]
mod os {
    use std::cell::Cell;

    thread_local! {
        /// The thread's placement from before a team pinned it, while one keeps it pinned.
        static HOME: Cell<Option<libc::cpu_set_t>> = const { Cell::new(None) };
        /// The token of the team that pinned the thread (0: none).
        static OWNER: Cell<u64> = const { Cell::new(0) };
    }

    /// The calling thread's CPU mask.
    fn mask() -> Option<libc::cpu_set_t> {
        // SAFETY: `cpu_set_t` is plain data, for which all zeros is the empty set.
        let mut set: libc::cpu_set_t = unsafe { std::mem::zeroed() };
        // SAFETY: the kernel writes at most the size given into the set, which is that big.
        let rc =
            unsafe { libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set) };
        (rc == 0).then_some(set)
    }

    /// Sets the calling thread's CPU mask.
    fn set_mask(set: &libc::cpu_set_t) -> bool {
        // SAFETY: the kernel reads the size given from the set, which is that big.
        let rc = unsafe { libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), set) };
        rc == 0
    }

    pub fn pin(core: usize, owner: u64) -> bool {
        let Some(home) = HOME.get().or_else(mask) else {
            return false;
        };
        if !core_affinity::set_for_current(core_affinity::CoreId { id: core }) {
            return false;
        }
        HOME.set(Some(home));
        OWNER.set(owner);
        true
    }

    pub fn release(owner: Option<u64>) {
        if owner.is_some_and(|o| o != OWNER.get()) {
            return;
        }
        if let Some(home) = HOME.take() {
            // Best effort: a thread that cannot be given its placement back stays where it is.
            let _ = set_mask(&home);
        }
        OWNER.set(0);
    }

    pub fn owner() -> u64 {
        OWNER.get()
    }
}

#[cfg(not(target_os = "linux"))]
mod os {
    // Without a way to give a thread its placement back, the caller is not pinned.
    pub fn pin(_core: usize, _owner: u64) -> bool {
        false
    }
    pub fn release(_owner: Option<u64>) {}
    pub fn owner() -> u64 {
        0
    }
}

/// Pins the calling thread to `core` for the team holding `owner`, keeping the placement it
/// had before (once, however many teams pin it in turn). False where the system refused.
pub fn pin_caller(core: usize, owner: u64) -> bool {
    os::pin(core, owner)
}

/// Gives the calling thread back the placement it had before a team pinned it: whichever
/// team pinned it (`None`), or only if the team holding `owner` did.
pub fn release_caller(owner: Option<u64>) {
    os::release(owner)
}

/// The token of the team that keeps the calling thread pinned (0: none).
pub fn caller_owner() -> u64 {
    os::owner()
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    #[test]
    fn a_pin_is_released_by_its_owner_only_and_restores_the_placement() {
        // On a thread of its own: the test runner's threads are left as they were.
        std::thread::spawn(|| {
            let before = core_affinity::get_core_ids().unwrap();
            let core = before[before.len() - 1].id;
            let (first, second) = (token(), token());
            assert!(pin_caller(core, first));
            assert_eq!(core_affinity::get_core_ids().unwrap().len(), 1);
            // A second team pins it in turn; the first one ending leaves that pin.
            assert!(pin_caller(core, second));
            release_caller(Some(first));
            assert_eq!(caller_owner(), second);
            assert_eq!(core_affinity::get_core_ids().unwrap().len(), 1);
            // Its owner ending gives back the placement from before the first pin.
            release_caller(Some(second));
            assert_eq!(caller_owner(), 0);
            let after = core_affinity::get_core_ids().unwrap();
            assert_eq!(
                after.iter().map(|c| c.id).collect::<Vec<_>>(),
                before.iter().map(|c| c.id).collect::<Vec<_>>()
            );
        })
        .join()
        .unwrap();
    }
}
