//! The team's worker threads and the hand-over of each parallel pass to them (docs/design.md
//! §5.1).
//!
//! A time step hands a dozen and more passes to the team, each a few microseconds to a few
//! milliseconds of work. A general-purpose pool (rayon's `broadcast`, used until 2026-11-26)
//! puts its idle workers to sleep and its caller too, so every pass paid two or three
//! wake-ups of the operating system: on the README's default job (4,104 points, about a
//! millisecond of work per step) that was 45 % of a one-thread run. Here the workers wait for
//! the next pass spinning for a short while (50 µs; 5 ms where every thread has a core of its
//! own, [`SPIN_OWN_CORES`]) before they sleep; between the passes of a
//! step nobody sleeps, and a run that stops stepping (output, the end) leaves its workers
//! asleep after that.
//!
//! The caller is the team's thread 0: it hands the pass over, runs share 0 itself and then
//! waits (spinning, then asleep) for the workers. A team of N threads is N threads, not N
//! workers and a waiting caller: with the caller waiting beside N workers on N cores (until
//! 2026-11-28) one core held two runnable threads, and the caller's spinning and yielding
//! cost the worker beside it a switch of context per yield (measured on 2 cores, 2 threads,
//! the BCN column collapse: 580,000–910,000 context switches per run against 12,000–20,000,
//! docs/design.md §5.1).
//!
//! A pass is handed over as a borrowed closure: [`Pool::run`] does not return before every
//! worker has finished with it (and has let go of it), which is what makes lending the
//! borrow to the workers sound. A panic does not take the others down: a worker's is caught,
//! the caller's is held, the pass completes on the other threads, and [`Pool::run`] resumes it
//! on the caller.

use std::any::Any;
use std::cell::UnsafeCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering::SeqCst};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a waiting thread spins before it sleeps, by default: longer than the gap between
/// two passes of a step (a reduction, a few node loops), far shorter than a time slice.
pub const SPIN: Duration = Duration::from_micros(50);

/// How long a waiting thread spins before it sleeps in a team whose every thread has a core
/// of its own ([`Pool::set_spin`]): longer than a pass's imbalance on a large model (a thread
/// done first waits for the last chunks of the others, a few hundred microseconds on the
/// 1M-point columns), so that it does not sleep through the end of the pass and start the next
/// one late. Measured on the 2-core VM, 2 pinned threads, 1M-point dry column, the two limits
/// alternated rep by rep: 1.05–1.06× the particle-steps/s of [`SPIN`], near the noise
/// (docs/design.md §5.1).
pub const SPIN_OWN_CORES: Duration = Duration::from_millis(5);

/// A pass: the closure every worker runs with its index, its lifetime erased (see
/// [`Pool::run`]).
type Job = *const (dyn Fn(usize) + Sync);

/// What the caller and the workers share.
struct Shared {
    /// Incremented for every pass; a worker runs the job when it sees a new value.
    epoch: AtomicU64,
    /// The current pass: written by the caller only while no worker runs one (before the
    /// epoch that announces it), read by the workers after they saw that epoch.
    job: UnsafeCell<Option<SendJob>>,
    /// Workers still running the current pass.
    remaining: AtomicUsize,
    /// The first panic of the current pass.
    panic: Mutex<Option<Box<dyn Any + Send>>>,
    /// Set when the pool is dropped.
    stop: AtomicBool,
    /// Workers asleep (or going to sleep) on `wake`.
    sleepers: AtomicUsize,
    wake_lock: Mutex<()>,
    wake: Condvar,
    /// Whether the caller is asleep (or going to sleep) on `done`.
    caller_sleeps: AtomicBool,
    done_lock: Mutex<()>,
    done: Condvar,
    /// How long a waiting thread spins before it sleeps (nanoseconds).
    spin_ns: AtomicU64,
}

/// The job pointer, sent to the workers.
#[derive(Clone, Copy)]
struct SendJob(Job);

// SAFETY: the closure behind the pointer is `Sync` (shared by reference between threads), and
// it outlives every use: `Pool::run` waits for all workers before it returns.
unsafe impl Send for SendJob {}

// SAFETY: every field but `job` is a synchronisation type; `job` is written by the caller only
// while every worker waits for the next epoch, and read by a worker only after it has seen the
// epoch the write came before (sequentially consistent store and load: the write happens
// before the read), so no read and write of it overlap.
unsafe impl Sync for Shared {}

/// A team of `threads`: the caller, which runs share 0 of every pass itself, and
/// `threads - 1` workers, each started by `start(k)` (its placement) and then waiting for
/// passes.
pub struct Pool {
    shared: Arc<Shared>,
    handles: Vec<JoinHandle<()>>,
}

impl Pool {
    /// A pool for a team of `threads` (at least 1): starts workers `mpm-worker-K` for
    /// K = 1..threads; each first runs `start(K)`. Share 0 is the caller's.
    pub fn new(
        threads: usize,
        start: impl Fn(usize) + Send + Sync + 'static,
    ) -> std::io::Result<Pool> {
        let shared = Arc::new(Shared {
            epoch: AtomicU64::new(0),
            job: UnsafeCell::new(None),
            remaining: AtomicUsize::new(0),
            panic: Mutex::new(None),
            stop: AtomicBool::new(false),
            sleepers: AtomicUsize::new(0),
            wake_lock: Mutex::new(()),
            wake: Condvar::new(),
            caller_sleeps: AtomicBool::new(false),
            done_lock: Mutex::new(()),
            done: Condvar::new(),
            spin_ns: AtomicU64::new(SPIN.as_nanos() as u64),
        });
        let start = Arc::new(start);
        let mut pool = Pool {
            shared: shared.clone(),
            handles: Vec::with_capacity(threads.saturating_sub(1)),
        };
        for k in 1..threads {
            let (shared, start) = (shared.clone(), start.clone());
            let handle = std::thread::Builder::new()
                .name(format!("mpm-worker-{k}"))
                .spawn(move || {
                    start(k);
                    worker(&shared, k);
                })?;
            // A failed spawn drops `pool`, which stops and joins the workers started so far.
            pool.handles.push(handle);
        }
        Ok(pool)
    }

    /// How long a waiting thread (a worker between passes, the caller at a pass's end) spins
    /// before it sleeps: [`SPIN`] unless set here. Spinning longer is for threads with a core
    /// each; where cores are shared, a spinning thread keeps a core another needs.
    pub fn set_spin(&self, spin: Duration) {
        let ns = u64::try_from(spin.as_nanos()).unwrap_or(u64::MAX);
        self.shared.spin_ns.store(ns, SeqCst);
    }

    /// The spin limit in force ([`Pool::set_spin`]).
    pub fn spin(&self) -> Duration {
        self.shared.spin()
    }

    /// Runs `f(0)` on the caller and `f(k)` on every worker k, and returns when all have
    /// finished; a panic (the caller's first, else a worker's) is resumed here once all are
    /// done.
    pub fn run(&self, f: &(dyn Fn(usize) + Sync)) {
        let s = &*self.shared;
        let n = self.handles.len();
        if n == 0 {
            f(0);
            return;
        }
        // SAFETY: only the lifetime is erased (same fat pointer); the workers drop their copy
        // before they count themselves done, and this function returns (or unwinds) only after
        // every worker has (below), so the closure is never used after its borrow ends.
        let job: Job = unsafe {
            std::mem::transmute::<&(dyn Fn(usize) + Sync), &'static (dyn Fn(usize) + Sync)>(f)
        };
        debug_assert_eq!(s.remaining.load(SeqCst), 0, "a pass still running");
        // SAFETY: no worker reads `job` now: the last pass ended (every worker counted itself
        // done, so each waits for the next epoch), and the next read follows the epoch below.
        unsafe { *s.job.get() = Some(SendJob(job)) };
        s.remaining.store(n, SeqCst);
        s.epoch.fetch_add(1, SeqCst);
        // A worker that went to sleep before the new epoch is woken; one that counts itself a
        // sleeper after it reads the epoch again under the lock (sequentially consistent on
        // both sides, so one of the two sees the other).
        if s.sleepers.load(SeqCst) > 0 {
            let _g = s.wake_lock.lock().expect("not poisoned");
            s.wake.notify_all();
        }
        // The caller's own share: a panic is held until the workers are done with the closure.
        let mine = catch_unwind(AssertUnwindSafe(|| f(0)));
        wait_until(
            s.spin(),
            || s.remaining.load(SeqCst) == 0,
            || {
                let mut g = s.done_lock.lock().expect("not poisoned");
                s.caller_sleeps.store(true, SeqCst);
                while s.remaining.load(SeqCst) != 0 {
                    g = s.done.wait(g).expect("not poisoned");
                }
                s.caller_sleeps.store(false, SeqCst);
            },
        );
        debug_assert_eq!(s.remaining.load(SeqCst), 0, "a worker still on the pass");
        // Out of the lock before unwinding (a guard held through a panic poisons it).
        let panic = s.panic.lock().expect("not poisoned").take();
        if let Err(p) = mine {
            resume_unwind(p);
        }
        if let Some(p) = panic {
            resume_unwind(p);
        }
    }
}

impl Drop for Pool {
    fn drop(&mut self) {
        let s = &*self.shared;
        s.stop.store(true, SeqCst);
        {
            let _g = s.wake_lock.lock().unwrap_or_else(|e| e.into_inner());
            s.wake.notify_all();
        }
        for h in self.handles.drain(..) {
            // A worker's own panics are caught per pass; a join error has nothing left to say.
            let _ = h.join();
        }
    }
}

impl Shared {
    /// The spin limit in force.
    fn spin(&self) -> Duration {
        Duration::from_nanos(self.spin_ns.load(SeqCst))
    }
}

/// Spins on `ready` for `spin`, then calls `sleep` (which returns once ready).
fn wait_until(spin: Duration, ready: impl Fn() -> bool, sleep: impl FnOnce()) {
    if ready() {
        return;
    }
    let t = Instant::now();
    let mut spins = 0u32;
    while !ready() {
        std::hint::spin_loop();
        spins += 1;
        // The clock only now and then: spinning is for the next few microseconds.
        if spins % 64 == 0 {
            if t.elapsed() > spin {
                sleep();
                return;
            }
            // Let a thread that shares this core have it: the caller's serial work between
            // passes on a machine with no core to spare, or another process (measured: on 2
            // cores, 2 threads spinning without yielding ran the default job 4× slower).
            std::thread::yield_now();
        }
    }
}

/// A worker: waits for each new epoch, runs the pass, counts itself done.
fn worker(s: &Shared, k: usize) {
    let mut seen = 0u64;
    loop {
        wait_until(
            s.spin(),
            || s.epoch.load(SeqCst) != seen || s.stop.load(SeqCst),
            || {
                let mut g = s.wake_lock.lock().expect("not poisoned");
                s.sleepers.fetch_add(1, SeqCst);
                while s.epoch.load(SeqCst) == seen && !s.stop.load(SeqCst) {
                    g = s.wake.wait(g).expect("not poisoned");
                }
                s.sleepers.fetch_sub(1, SeqCst);
            },
        );
        if s.stop.load(SeqCst) {
            return;
        }
        seen = s.epoch.load(SeqCst);
        // SAFETY: the caller wrote the job before the epoch this worker saw, and writes it
        // again only after this worker counts itself done (below).
        let job = unsafe { *s.job.get() }.expect("a job with the epoch");
        // SAFETY: `Pool::run` keeps the closure alive until `remaining` reaches 0, which this
        // worker's decrement below comes after.
        let f = unsafe { &*job.0 };
        if let Err(p) = catch_unwind(AssertUnwindSafe(|| f(k))) {
            let mut first = s.panic.lock().expect("not poisoned");
            if first.is_none() {
                *first = Some(p);
            }
        }
        if s.remaining.fetch_sub(1, SeqCst) == 1 && s.caller_sleeps.load(SeqCst) {
            let _g = s.done_lock.lock().expect("not poisoned");
            s.done.notify_one();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_worker_runs_every_pass_once() {
        let pool = Pool::new(3, |_| ()).unwrap();
        let count: Vec<AtomicUsize> = (0..3).map(|_| AtomicUsize::new(0)).collect();
        for pass in 0..2000 {
            pool.run(&|k| {
                count[k].fetch_add(1, SeqCst);
            });
            // Now and then a pause long enough for the workers to fall asleep.
            if pass % 500 == 0 {
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        assert!(count.iter().all(|c| c.load(SeqCst) == 2000));
    }

    #[test]
    fn passes_complete_whatever_the_spin_and_the_limit_is_the_one_set() {
        let pool = Pool::new(3, |_| ()).unwrap();
        assert_eq!(pool.spin(), SPIN);
        let count: Vec<AtomicUsize> = (0..3).map(|_| AtomicUsize::new(0)).collect();
        // No spin at all (every wait sleeps), then the long one (pauses shorter and longer
        // than it between passes).
        for (limit, pause) in [(Duration::ZERO, 1), (SPIN_OWN_CORES, 7)] {
            pool.set_spin(limit);
            assert_eq!(pool.spin(), limit);
            for pass in 0..200 {
                pool.run(&|k| {
                    count[k].fetch_add(1, SeqCst);
                });
                if pass % 50 == 0 {
                    std::thread::sleep(Duration::from_millis(pause));
                }
            }
        }
        assert!(count.iter().all(|c| c.load(SeqCst) == 400));
    }

    #[test]
    fn a_panicking_worker_reaches_the_caller_and_the_pool_goes_on() {
        let pool = Pool::new(2, |_| ()).unwrap();
        let r = catch_unwind(AssertUnwindSafe(|| {
            pool.run(&|k| {
                if k == 1 {
                    panic!("worker one");
                }
            })
        }));
        assert!(r.is_err());
        let ran = AtomicUsize::new(0);
        pool.run(&|_| {
            ran.fetch_add(1, SeqCst);
        });
        assert_eq!(ran.load(SeqCst), 2);
    }

    #[test]
    fn workers_start_placed_and_stop_when_dropped() {
        let started = Arc::new(Mutex::new(Vec::new()));
        let s = started.clone();
        let pool = Pool::new(4, move |k| {
            s.lock().unwrap().push(k);
        })
        .unwrap();
        pool.run(&|_| ());
        // Share 0 is the caller's: workers 1 to 3 only.
        let mut k = started.lock().unwrap().clone();
        k.sort_unstable();
        assert_eq!(k, [1, 2, 3]);
        drop(pool);
    }

    #[test]
    fn the_caller_runs_share_zero_and_its_panic_waits_for_the_workers() {
        let pool = Pool::new(3, |_| ()).unwrap();
        let me = std::thread::current().id();
        let on_caller: Vec<AtomicBool> = (0..3).map(|_| AtomicBool::new(false)).collect();
        pool.run(&|k| on_caller[k].store(std::thread::current().id() == me, SeqCst));
        let on: Vec<bool> = on_caller.iter().map(|b| b.load(SeqCst)).collect();
        assert_eq!(on, [true, false, false]);
        // The caller's panic comes back only after the slow workers are done with the pass.
        let finished = AtomicUsize::new(0);
        let r = catch_unwind(AssertUnwindSafe(|| {
            pool.run(&|k| {
                if k == 0 {
                    panic!("the caller's share");
                }
                std::thread::sleep(Duration::from_millis(20));
                finished.fetch_add(1, SeqCst);
            })
        }));
        assert!(r.is_err());
        assert_eq!(finished.load(SeqCst), 2);
        // A pool of one runs everything on the caller.
        let one = Pool::new(1, |_| ()).unwrap();
        let ran = AtomicUsize::new(0);
        one.run(&|k| {
            assert_eq!((k, std::thread::current().id()), (0, me));
            ran.fetch_add(1, SeqCst);
        });
        assert_eq!(ran.load(SeqCst), 1);
    }
}
