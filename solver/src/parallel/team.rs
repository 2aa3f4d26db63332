//! The thread team (docs/design.md §5): one pool of worker threads for the whole run, optionally pinned
//! one per core, each thread always given the same contiguous range of the work (elements,
//! nodes, particles), so that what a thread first touches it later computes on.
//!
//! Results never depend on the thread count: kernels only split work whose parts are written
//! to disjoint places, and every sum is formed in an order fixed by the data (see
//! [`crate::parallel::gather`] and [`Team::sum_blocks`]).

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// The threads' element ranges start at multiples of this many elements (the last ends with
/// the mesh), so that a sum over a block of consecutive elements is formed by one thread in
/// element order: per-block partial sums (the guard rails') are the same for any thread count,
/// and there are 64 times fewer of them to write and add than per-element ones.
pub const ELEMENT_BLOCK: usize = 64;

/// How threads are placed on cores.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pin {
    /// Let the OS place them.
    None,
    /// Thread k on the k-th core available to the process, one hardware thread of every
    /// physical core before a second one ([`crate::parallel::machine::spread`]).
    Cores,
    /// Thread k on the k-th free core when every thread has a free core of its own; else left
    /// to the OS (a pinned thread sharing its core with another process stalls the team at
    /// every barrier: [`crate::parallel::machine`]).
    Auto,
}

/// Whether every thread was pinned, each to a core no other thread of the team has.
fn own_cores(pinned: &[Option<usize>]) -> bool {
    pinned
        .iter()
        .enumerate()
        .all(|(k, c)| c.is_some() && !pinned[..k].contains(c))
}

/// A team of `threads`: the calling thread and `threads - 1` workers.
pub struct Team {
    pool: crate::parallel::pool::Pool,
    /// The token of the calling thread's pin, where the team pinned it
    /// ([`crate::parallel::placement`]).
    caller_pin: Option<u64>,
    /// Number of threads.
    pub threads: usize,
    /// The core each thread was pinned to (`None` where pinning was not asked for or refused).
    pub pinned: Vec<Option<usize>>,
    /// Cores available to the process that other processes kept busy when the team started
    /// (looked at for the automatic thread count and `Pin::Auto` only), and those found taken
    /// while it ran ([`Team::recheck`]).
    pub busy: Vec<usize>,
    /// Whether the thread count was chosen here (asked for as 0): a team started again after
    /// a core was taken chooses it again.
    pub auto_threads: bool,
    /// Whether [`Team::recheck`] looks at the cores (`Pin::Auto` with pinned threads).
    watching: bool,
    /// The look under way while the team runs.
    look: Option<crate::parallel::machine::Look>,
    /// Where the team's time went since the last [`Team::take_load`].
    load: LoadCounters,
    /// Per thread: the next of its chunks to hand out in [`Team::run_chunks`].
    cursors: Vec<Padded>,
}

/// One counter on a cache line of its own, so that threads writing neighbours do not share
/// a line.
#[repr(align(128))]
#[derive(Default)]
struct Padded(AtomicU64);

/// The counters behind [`Team::take_load`] (nanoseconds).
#[derive(Default)]
struct LoadCounters {
    /// Per thread: its time inside the closure of the last [`Team::run`].
    last: Vec<Padded>,
    /// Per thread: its time inside every closure since the last [`Team::take_thread_busy`].
    total: Vec<Padded>,
    /// Sum over runs of the run's wall time (as the caller saw it).
    wall: AtomicU64,
    /// Sum over runs of the busiest thread's time in the run.
    busiest: AtomicU64,
    /// Sum over runs of all threads' time in the run.
    busy: AtomicU64,
    /// Runs counted.
    runs: AtomicU64,
}

/// Where a team's time went over some [`Team::run`] calls (seconds): a thread's time in a run
/// is its time inside the closure; the rest of the run's wall time it waited, for the busiest
/// thread (imbalance) or for the pool to start and join (overhead).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TeamLoad {
    /// Wall time of the runs, as the calling thread saw it.
    pub wall: f64,
    /// Sum over the runs of the busiest thread's time.
    pub busiest: f64,
    /// Sum over the runs of the mean thread's time.
    pub mean: f64,
    /// Number of runs.
    pub runs: u64,
}

impl TeamLoad {
    /// The share of the threads' time in the runs spent waiting: `1 − mean / wall` (0 when
    /// nothing ran).
    pub fn waiting_share(&self) -> f64 {
        if self.wall > 0.0 {
            (1.0 - self.mean / self.wall).max(0.0)
        } else {
            0.0
        }
    }
}

impl std::ops::AddAssign for TeamLoad {
    fn add_assign(&mut self, o: TeamLoad) {
        self.wall += o.wall;
        self.busiest += o.busiest;
        self.mean += o.mean;
        self.runs += o.runs;
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        // The caller's placement from before the team, unless a newer team has pinned it since
        // (or the team ends on another thread, whose placement it never changed).
        if let Some(token) = self.caller_pin {
            crate::parallel::placement::release_caller(Some(token));
        }
    }
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Team")
            .field("threads", &self.threads)
            .field("pinned", &self.pinned)
            .finish()
    }
}

/// The worker threads could not be started.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("cannot start {threads} worker threads: {reason}")]
pub struct TeamError {
    /// Threads asked for.
    pub threads: usize,
    /// What the system said.
    pub reason: String,
}

impl Team {
    /// A team of `threads` (0: one per free core available to the process, at least one): the
    /// calling thread and `threads - 1` workers started here, pinned as `pin` asks.
    pub fn new(threads: usize, pin: Pin) -> Result<Team, TeamError> {
        // A team that kept this thread pinned is being replaced: the new one looks at every
        // core the process may use.
        crate::parallel::placement::release_caller(None);
        let all = core_affinity::get_core_ids().unwrap_or_default();
        let available = std::thread::available_parallelism().map_or(1, |n| n.get());
        let look = (threads == 0 || pin == Pin::Auto) && available > 1 && all.len() > 1;
        let ids: Vec<usize> = all.iter().map(|c| c.id).collect();
        let busy = if look {
            crate::parallel::machine::busy_cores(&ids).unwrap_or_default()
        } else {
            Vec::new()
        };
        let free: Vec<core_affinity::CoreId> = all
            .iter()
            .copied()
            .filter(|c| !busy.contains(&c.id))
            .collect();
        let auto_threads = threads == 0;
        let threads = match threads {
            0 if look => free.len().clamp(1, available),
            0 => available,
            n => n,
        };
        let cores = match pin {
            Pin::Cores => all,
            Pin::Auto if threads <= free.len() => free,
            Pin::Auto | Pin::None => Vec::new(),
        };
        // Whole physical cores first (a team smaller than the machine would otherwise put two
        // threads on one core where the kernel numbers a core's threads next to each other).
        let order =
            crate::parallel::machine::spread(&cores.iter().map(|c| c.id).collect::<Vec<_>>());
        let cores: Vec<core_affinity::CoreId> = order
            .into_iter()
            .map(|id| core_affinity::CoreId { id })
            .collect();
        let granted: Vec<std::sync::Mutex<Option<usize>>> =
            (0..threads).map(|_| std::sync::Mutex::new(None)).collect();
        let granted = std::sync::Arc::new(granted);
        let g = granted.clone();
        // The caller is pinned with the team's threads; a team of one only when asked for by
        // `Pin::Cores` (`Pin::Auto` leaves a lone thread to the OS, which moves it off a busy
        // core).
        let caller_core = cores
            .first()
            .copied()
            .filter(|_| threads > 1 || pin == Pin::Cores);
        // Thread 0 is the caller's own (the pool hands it share 0 of every pass); workers
        // 1.. are started here, before the caller is pinned, so that unpinned ones do not
        // inherit its core.
        let pool = crate::parallel::pool::Pool::new(threads, move |k| {
            if !cores.is_empty() {
                let core = cores[k % cores.len()];
                if core_affinity::set_for_current(core) {
                    *g[k].lock().expect("not poisoned") = Some(core.id);
                }
            }
        })
        .map_err(|e| TeamError {
            threads,
            reason: e.to_string(),
        })?;
        // Every worker has placed itself once it has run a pass.
        pool.run(&|_| ());
        // The caller's pin lasts the team's life. rayon's pool (reading and set-up) is started
        // first, so that its threads do not inherit the caller's core either.
        let mut caller_pin = None;
        if let Some(core) = caller_core {
            let _ = rayon::current_num_threads();
            let token = crate::parallel::placement::token();
            if crate::parallel::placement::pin_caller(core.id, token) {
                *granted[0].lock().expect("not poisoned") = Some(core.id);
                caller_pin = Some(token);
            }
        }
        let pinned: Vec<Option<usize>> = granted
            .iter()
            .map(|m| *m.lock().expect("not poisoned"))
            .collect();
        // Threads with a core each wait through a pass's imbalance spinning, not asleep
        // (`pool::SPIN_OWN_CORES`); where any shares its core, or the OS places them, a
        // spinning waiter would keep a core that another thread needs.
        if threads > 1 && own_cores(&pinned) {
            pool.set_spin(crate::parallel::pool::SPIN_OWN_CORES);
        }
        let watching = pin == Pin::Auto && pinned.iter().any(Option::is_some);
        Ok(Team {
            pool,
            caller_pin,
            threads,
            pinned,
            busy,
            auto_threads,
            watching,
            look: None,
            load: LoadCounters {
                last: (0..threads).map(|_| Padded::default()).collect(),
                total: (0..threads).map(|_| Padded::default()).collect(),
                ..LoadCounters::default()
            },
            cursors: (0..threads).map(|_| Padded::default()).collect(),
        })
    }

    /// Between steps: a team that `Pin::Auto` pinned looks at its cores every
    /// [`crate::parallel::machine::RECHECK`]. Returns the cores that another process has
    /// taken part of (more than [`crate::parallel::machine::TAKEN_SHARE`] since the last look)
    /// where one of its threads is pinned: that thread now stalls the others at every barrier,
    /// and the caller starts a new team ([`Team::replacement`]). Costs a clock read per call
    /// and, once a second, reading the kernel's counters; an unpinned team never looks.
    pub fn recheck(&mut self) -> Option<Vec<usize>> {
        use crate::parallel::machine::{Look, RECHECK, TAKEN_SHARE};
        if !self.watching {
            return None;
        }
        let Some(look) = self.look.take() else {
            self.look = Look::begin();
            // Without the counters there is nothing to watch.
            self.watching = self.look.is_some();
            return None;
        };
        if look.age() < RECHECK {
            self.look = Some(look);
            return None;
        }
        let cores: Vec<usize> = self.pinned.iter().flatten().copied().collect();
        let taken = look.others_above(&cores, TAKEN_SHARE).unwrap_or_default();
        self.look = Look::begin();
        (!taken.is_empty()).then_some(taken)
    }

    /// The team to carry on with once [`Team::recheck`] found `taken` cores: with `threads`
    /// threads unpinned when given (tests), else chosen as at the start when this team's count
    /// was (one per free core, pinned there), else as many threads as now, unpinned. The cores
    /// found busy are kept in [`Team::busy`].
    pub fn replacement(&self, threads: Option<usize>, taken: &[usize]) -> Result<Team, TeamError> {
        let mut team = match threads {
            Some(n) => Team::new(n, Pin::None)?,
            None if self.auto_threads => Team::new(0, Pin::Auto)?,
            None => Team::new(self.threads, Pin::None)?,
        };
        team.auto_threads = self.auto_threads;
        for &c in self.busy.iter().chain(taken) {
            if !team.busy.contains(&c) {
                team.busy.push(c);
            }
        }
        Ok(team)
    }

    /// Runs `f(k)` on every thread k = 0..threads, `f(0)` on the calling thread and each other
    /// on its own worker, and waits. Each thread's time inside `f` is counted for
    /// [`Team::take_load`] (two clock reads per thread).
    pub fn run<F: Fn(usize) + Sync>(&self, f: F) {
        let start = Instant::now();
        let (last, total) = (&self.load.last, &self.load.total);
        let timed = |k: usize| {
            let t = Instant::now();
            f(k);
            let busy = t.elapsed().as_nanos() as u64;
            last[k].0.store(busy, Ordering::Relaxed);
            total[k].0.fetch_add(busy, Ordering::Relaxed);
        };
        self.pool.run(&timed);
        let wall = start.elapsed().as_nanos() as u64;
        // The pass has joined: every thread's store is visible here.
        let (busiest, busy) = last.iter().fold((0, 0), |(m, s), c| {
            let b = c.0.load(Ordering::Relaxed);
            (m.max(b), s + b)
        });
        let l = &self.load;
        l.wall.fetch_add(wall, Ordering::Relaxed);
        l.busiest.fetch_add(busiest, Ordering::Relaxed);
        l.busy.fetch_add(busy, Ordering::Relaxed);
        l.runs.fetch_add(1, Ordering::Relaxed);
    }

    /// How long the team's waiting threads spin before they sleep: longer where every thread
    /// has a core of its own ([`crate::parallel::pool::SPIN_OWN_CORES`]) than elsewhere
    /// ([`crate::parallel::pool::SPIN`]).
    pub fn spin(&self) -> std::time::Duration {
        self.pool.spin()
    }

    /// Each thread's time inside the runs' closures since the last call (seconds; the
    /// counters start again from zero): which threads the others waited for.
    pub fn take_thread_busy(&self) -> Vec<f64> {
        self.load
            .total
            .iter()
            .map(|c| c.0.swap(0, Ordering::Relaxed) as f64 * 1e-9)
            .collect()
    }

    /// Runs `f(t, c)` once for every chunk `c` of `owned` (one range of chunk numbers per
    /// thread, disjoint), on some thread `t`, handed out as [`Team::run_pieces`] hands out
    /// pieces: each thread takes its own chunks in order, then, its own done, the chunks still
    /// left of the others, so that a thread its core slows down does not hold the others at
    /// the barrier. Which thread runs a chunk varies from run to run: `f` must write only what
    /// belongs to the chunk, so that results do not depend on it.
    pub fn run_chunks<F: Fn(usize, usize) + Sync>(&self, owned: &[Range<usize>], f: F) {
        self.run_pieces(owned, |t, c, _| f(t, c));
    }

    /// Runs `f(t, c, owner)` once for every piece `c` of `owned` (one range of piece numbers
    /// per thread, disjoint), on some thread `t`, `owner` being the thread whose range holds
    /// `c`. Each thread takes its own pieces from the front, in order; its own done, it takes
    /// the pieces still left of the threads after it (in turn) from the back. So the pieces a
    /// thread runs of its own are always a first run of its range, taken in order, and the
    /// ones others took the rest: a scatter sums a node whose elements lie in several pieces
    /// of one thread straight into its accumulator on the owner, and only the taken pieces'
    /// shares through slots ([`crate::parallel::gather`]).
    pub fn run_pieces<F: Fn(usize, usize, usize) + Sync>(&self, owned: &[Range<usize>], f: F) {
        assert_eq!(owned.len(), self.threads, "a range of pieces per thread");
        // Each cursor holds the front (low half) and the back (high half) of the pieces left.
        let pack = |front: u64, back: u64| front | back << 32;
        for (c, r) in self.cursors.iter().zip(owned) {
            assert!(
                r.end <= u32::MAX as usize,
                "more pieces than a cursor counts"
            );
            c.0.store(pack(r.start as u64, r.end as u64), Ordering::Relaxed);
        }
        let cursors = &self.cursors;
        let threads = self.threads;
        // The broadcast orders the stores above before every worker's first claim.
        self.run(|t| {
            for v in (t..threads).chain(0..t) {
                let cursor = &cursors[v].0;
                let mut now = cursor.load(Ordering::Relaxed);
                loop {
                    let (front, back) = (now & u32::MAX as u64, now >> 32);
                    if front >= back {
                        break;
                    }
                    // The owner claims the front, the others the back: one compare-and-swap.
                    let (next, c) = if v == t {
                        (pack(front + 1, back), front)
                    } else {
                        (pack(front, back - 1), back - 1)
                    };
                    match cursor.compare_exchange_weak(
                        now,
                        next,
                        Ordering::Relaxed,
                        Ordering::Relaxed,
                    ) {
                        Ok(_) => {
                            f(t, c as usize, v);
                            now = cursor.load(Ordering::Relaxed);
                        }
                        Err(seen) => now = seen,
                    }
                }
            }
        });
    }

    /// Where the team's time went in the runs since the last call (the counters start again
    /// from zero).
    pub fn take_load(&self) -> TeamLoad {
        let l = &self.load;
        let ns = |c: &AtomicU64| c.swap(0, Ordering::Relaxed) as f64 * 1e-9;
        TeamLoad {
            wall: ns(&l.wall),
            busiest: ns(&l.busiest),
            mean: ns(&l.busy) / self.threads.max(1) as f64,
            runs: l.runs.swap(0, Ordering::Relaxed),
        }
    }

    /// Sum of `f(block)` over fixed blocks `0..n` in blocks of `BLOCK` items, added in block
    /// order: the same bits for any thread count.
    pub fn sum_blocks<F: Fn(Range<usize>) -> f64 + Sync>(&self, n: usize, f: F) -> f64 {
        const BLOCK: usize = 4096;
        let mut partial = vec![0.0; n.div_ceil(BLOCK)];
        self.for_blocks(n, BLOCK, &mut partial, f);
        partial.iter().sum()
    }

    /// `out[b] = f(block b)` for the fixed blocks `b·block..(b+1)·block` of `0..n` (the last
    /// shorter), each thread taking a contiguous run of blocks: a per-block result (a partial
    /// sum formed in item order) is then the same for any thread count, and `f` may write
    /// per-item data of its block, which no other call touches. `out` holds at least
    /// `n.div_ceil(block)` values (preallocated, so that a step allocates nothing).
    pub fn for_blocks<T: Send, F: Fn(Range<usize>) -> T + Sync>(
        &self,
        n: usize,
        block: usize,
        out: &mut [T],
        f: F,
    ) {
        let blocks = n.div_ceil(block);
        assert!(out.len() >= blocks, "fewer result slots than blocks");
        let out = Shared::new(out);
        let per = blocks.div_ceil(self.threads.max(1));
        self.run(|k| {
            for b in k * per..((k + 1) * per).min(blocks) {
                let v = f(b * block..((b + 1) * block).min(n));
                // SAFETY: block b belongs to thread k only.
                unsafe { out.write(b, v) };
            }
        });
    }
}

/// `ranges` (contiguous, covering `0..elements`) with every boundary between two moved to the
/// nearest multiple of [`ELEMENT_BLOCK`] (at most `elements`): a change of balance of at most
/// half a block per thread.
pub fn aligned_to_blocks(ranges: Vec<Range<usize>>, elements: usize) -> Vec<Range<usize>> {
    let round = |b: usize| ((b + ELEMENT_BLOCK / 2) / ELEMENT_BLOCK * ELEMENT_BLOCK).min(elements);
    let last = ranges.len() - 1;
    let mut start = 0;
    ranges
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let end = if k == last { elements } else { round(r.end) };
            let out = start..end;
            start = end;
            out
        })
        .collect()
}

/// Splits `0..weights.len()` into `parts` contiguous ranges of about equal total weight (every
/// item at least weight 1, so empty items still spread).
pub fn balanced_ranges(
    weights: impl Iterator<Item = u64> + Clone,
    parts: usize,
) -> Vec<Range<usize>> {
    let parts = parts.max(1);
    let total: u64 = weights.clone().map(|w| w + 1).sum();
    let n = weights.clone().count();
    let mut ranges = Vec::with_capacity(parts);
    let (mut start, mut acc, mut k) = (0usize, 0u64, 1u64);
    for (i, w) in weights.enumerate() {
        acc += w + 1;
        while (k as usize) < parts && acc * parts as u64 >= k * total {
            ranges.push(start..i + 1);
            start = i + 1;
            k += 1;
        }
    }
    ranges.push(start..n);
    while ranges.len() < parts {
        ranges.push(n..n);
    }
    ranges
}

/// Shared mutable access to a slice from many threads, each writing places no other thread
/// touches. The kernels guarantee disjointness by construction (fixed, disjoint ranges).
pub struct Shared<'a, T> {
    ptr: *mut T,
    len: usize,
    _life: std::marker::PhantomData<&'a mut [T]>,
}

// SAFETY: only disjoint elements are accessed concurrently (the callers' contract).
unsafe impl<T: Send> Sync for Shared<'_, T> {}
unsafe impl<T: Send> Send for Shared<'_, T> {}

impl<'a, T> Shared<'a, T> {
    /// Wraps `s`.
    pub fn new(s: &'a mut [T]) -> Self {
        Shared {
            ptr: s.as_mut_ptr(),
            len: s.len(),
            _life: std::marker::PhantomData,
        }
    }

    /// Writes element `i`.
    ///
    /// # Safety
    /// No other thread may access element `i` at the same time.
    #[inline]
    pub unsafe fn write(&self, i: usize, v: T) {
        assert!(i < self.len);
        // SAFETY: `i` is inside the borrowed slice (checked above); exclusive access to it is
        // the caller's promise.
        unsafe { self.ptr.add(i).write(v) }
    }

    /// The `N` elements from `start`, mutably, as an array.
    ///
    /// # Safety
    /// No other thread may access any of them while the array lives.
    #[inline]
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn array<const N: usize>(&self, start: usize) -> &mut [T; N] {
        assert!(start <= self.len && N <= self.len - start);
        // SAFETY: the `N` elements lie inside the borrowed slice (checked above), which
        // outlives `'a`, and an array of `N` has the layout of `N` consecutive elements;
        // exclusive access to them is the caller's promise.
        unsafe { &mut *self.ptr.add(start).cast::<[T; N]>() }
    }

    /// [`Shared::array`] without its bounds check, for a loop that checked its bounds once
    /// (checked in debug builds).
    ///
    /// # Safety
    /// `start + N` must not exceed the slice's length, and no other thread may access the
    /// elements while the array lives.
    #[inline]
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn array_unchecked<const N: usize>(&self, start: usize) -> &mut [T; N] {
        debug_assert!(start <= self.len && N <= self.len - start);
        // SAFETY: the elements lie inside the borrowed slice (the caller's promise, checked in
        // debug builds), which outlives `'a`; exclusive access is the caller's promise.
        unsafe { &mut *self.ptr.add(start).cast::<[T; N]>() }
    }

    /// The sub-slice `r`, mutably.
    ///
    /// # Safety
    /// No other thread may access any element of `r` while the slice lives.
    #[inline]
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn range(&self, r: Range<usize>) -> &mut [T] {
        assert!(r.start <= r.end && r.end <= self.len);
        // SAFETY: `r` lies inside the borrowed slice (checked above), which outlives `'a`;
        // exclusive access to it is the caller's promise.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(r.start), r.end - r.start) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shared_array_is_its_run_of_the_slice_and_stays_inside_it() {
        let mut v: Vec<u32> = (0..10).collect();
        let s = Shared::new(&mut v);
        // SAFETY: one thread, and the arrays do not outlive their statements.
        unsafe {
            assert_eq!(*s.array::<3>(7), [7, 8, 9]);
            assert_eq!(*s.array_unchecked::<3>(7), [7, 8, 9]);
            assert_eq!(*s.array::<0>(10), [0u32; 0]);
            *s.array::<2>(4) = [40, 50];
        }
        assert_eq!(v[3..7], [3, 40, 50, 6]);
        let s = Shared::new(&mut v);
        for (start, ok) in [(8, false), (11, false), (usize::MAX, false), (7, true)] {
            // SAFETY: as above.
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| unsafe {
                s.array::<3>(start)[0]
            }));
            assert_eq!(r.is_ok(), ok, "start {start}");
        }
    }

    #[test]
    fn ranges_cover_everything_in_order_and_balance() {
        let w = [5u64, 0, 0, 7, 1, 1, 1, 9, 0, 2];
        for parts in 1..6 {
            let r = balanced_ranges(w.iter().copied(), parts);
            assert_eq!(r.len(), parts);
            assert_eq!(r[0].start, 0);
            assert_eq!(r.last().unwrap().end, w.len());
            for pair in r.windows(2) {
                assert_eq!(pair[0].end, pair[1].start);
            }
        }
        let r = balanced_ranges(std::iter::repeat(1u64).take(1000), 4);
        for x in &r {
            assert_eq!(x.len(), 250);
        }
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_pinned_team_pins_its_caller_as_thread_zero_and_gives_its_placement_back() {
        // On a thread of its own: the test runner's threads keep their placement.
        std::thread::spawn(|| {
            let ids = |c: Vec<core_affinity::CoreId>| c.iter().map(|c| c.id).collect::<Vec<_>>();
            let before = ids(core_affinity::get_core_ids().unwrap());
            let team = Team::new(2, Pin::Cores).unwrap();
            let zero = team.pinned[0].expect("the caller pinned");
            // Thread 0 is the caller, on the team's first core.
            let me = std::thread::current().id();
            let caller = std::sync::Mutex::new(None);
            team.run(|k| {
                if std::thread::current().id() == me {
                    *caller.lock().unwrap() = Some(k);
                }
            });
            assert_eq!(*caller.lock().unwrap(), Some(0));
            assert_eq!(ids(core_affinity::get_core_ids().unwrap()), [zero]);
            // Threads with a core each spin through the passes' ends.
            let spin = if own_cores(&team.pinned) {
                crate::parallel::pool::SPIN_OWN_CORES
            } else {
                crate::parallel::pool::SPIN
            };
            assert_eq!(team.spin(), spin, "pinned {:?}", team.pinned);
            // A replacement sees every core, pins the caller in turn, and keeps its pin when
            // the old team ends.
            let next = team.replacement(None, &[]).unwrap();
            drop(team);
            assert!(
                next.pinned.iter().all(Option::is_none),
                "unpinned: {:?}",
                next.pinned
            );
            assert_eq!(next.spin(), crate::parallel::pool::SPIN);
            assert_eq!(ids(core_affinity::get_core_ids().unwrap()), before);
            drop(next);
            let pinned_again = Team::new(2, Pin::Cores).unwrap();
            let again = pinned_again.pinned[0].unwrap();
            let newer = Team::new(1, Pin::Cores).unwrap();
            drop(pinned_again);
            assert_eq!(
                ids(core_affinity::get_core_ids().unwrap()),
                [newer.pinned[0].unwrap()],
                "the newer team's pin stays (first team on core {again})"
            );
            drop(newer);
            assert_eq!(ids(core_affinity::get_core_ids().unwrap()), before);
        })
        .join()
        .unwrap();
    }

    #[test]
    fn only_threads_with_a_core_each_spin_long() {
        assert!(own_cores(&[Some(0), Some(1)]));
        assert!(own_cores(&[Some(3)]));
        assert!(!own_cores(&[Some(0), Some(0)]), "two threads on one core");
        assert!(!own_cores(&[Some(0), None]), "one left to the OS");
        let team = Team::new(2, Pin::None).unwrap();
        assert_eq!(team.spin(), crate::parallel::pool::SPIN);
        let one = Team::new(1, Pin::None).unwrap();
        assert_eq!(one.spin(), crate::parallel::pool::SPIN);
    }

    #[test]
    fn load_counts_each_run_and_the_waiting() {
        let team = Team::new(2, Pin::None).unwrap();
        team.take_load();
        team.take_thread_busy();
        // Thread 1 works, thread 0 waits for it.
        team.run(|k| {
            if k == 1 {
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
        });
        team.run(|_| ());
        let l = team.take_load();
        assert_eq!(l.runs, 2);
        assert!(l.busiest >= 0.02 && l.wall >= l.busiest, "{l:?}");
        assert!((l.mean - l.busiest / 2.0).abs() < 0.005, "{l:?}");
        // Thread 0 waited about half the time. Only a lower bound: the wall clock also holds
        // whatever delays the scheduler adds on a loaded machine, which raise the share (a
        // run measured 0.60 with the threads' own times exact).
        assert!(l.waiting_share() > 0.4, "{l:?}");
        assert!(
            (l.waiting_share() - (1.0 - l.mean / l.wall)).abs() < 1e-12,
            "{l:?}"
        );
        assert_eq!(team.take_load().runs, 0);
        // Thread 1 was the busy one.
        let busy = team.take_thread_busy();
        assert!(busy[1] >= 0.02 && busy[0] < 0.01, "{busy:?}");
        assert!(team.take_thread_busy().iter().all(|&b| b == 0.0));
    }

    #[test]
    fn every_chunk_runs_once_and_the_idle_thread_takes_the_slow_ones() {
        let team = Team::new(2, Pin::None).unwrap();
        let ran: Vec<AtomicU64> = (0..40).map(|_| AtomicU64::new(0)).collect();
        let by: Vec<AtomicU64> = (0..40).map(|_| AtomicU64::new(9)).collect();
        let owned = [0..20, 20..40];
        team.run_chunks(&owned, |t, c| {
            ran[c].fetch_add(1, Ordering::Relaxed);
            // Thread 0's chunks are slow: thread 1 finishes its own and takes some of them.
            if c < 20 {
                std::thread::sleep(std::time::Duration::from_millis(2));
            }
            by[c].store(t as u64, Ordering::Relaxed);
        });
        assert!(ran.iter().all(|r| r.load(Ordering::Relaxed) == 1));
        let helped = (0..20)
            .filter(|&c| by[c].load(Ordering::Relaxed) == 1)
            .count();
        assert!(helped > 0, "thread 1 took none of thread 0's chunks");
        // Run again: the cursors start over.
        team.run_chunks(&owned, |_, c| {
            ran[c].fetch_add(1, Ordering::Relaxed);
        });
        assert!(ran.iter().all(|r| r.load(Ordering::Relaxed) == 2));
    }

    #[test]
    fn a_thread_runs_a_first_run_of_its_pieces_in_order_and_the_others_take_the_rest() {
        for slow in [0, 1, 2] {
            let team = Team::new(3, Pin::None).unwrap();
            let owned = [0..6, 6..9, 9..15];
            // Per piece: the thread that ran it and the order in which it started.
            let by: Vec<AtomicU64> = (0..15).map(|_| AtomicU64::new(u64::MAX)).collect();
            let seq: Vec<AtomicU64> = (0..15).map(|_| AtomicU64::new(u64::MAX)).collect();
            let clock = AtomicU64::new(0);
            team.run_pieces(&owned, |t, c, owner| {
                assert!(
                    owned[owner].contains(&c),
                    "piece {c} given to the wrong owner"
                );
                seq[c].store(clock.fetch_add(1, Ordering::Relaxed), Ordering::Relaxed);
                assert_eq!(
                    by[c].swap(t as u64, Ordering::Relaxed),
                    u64::MAX,
                    "piece {c} ran twice"
                );
                // The slow thread's first piece waits until another thread took one of its
                // pieces (at most 2 s: a loaded machine may start the workers late).
                if t == slow && owner == slow && c == owned[slow].start {
                    let start = std::time::Instant::now();
                    while owned[slow].clone().all(|d| {
                        let b = by[d].load(Ordering::Relaxed);
                        b == u64::MAX || b == slow as u64
                    }) && start.elapsed().as_secs() < 2
                    {
                        std::thread::sleep(std::time::Duration::from_millis(1));
                    }
                }
            });
            for (v, r) in owned.iter().enumerate() {
                let ran: Vec<u64> = r.clone().map(|c| by[c].load(Ordering::Relaxed)).collect();
                assert!(
                    ran.iter().all(|&t| t != u64::MAX),
                    "a piece of {v} never ran"
                );
                // The owner's are a first run of its range, started in order.
                // (none, when a thread starts late and the others take all of its pieces).
                let mine = ran.iter().take_while(|&&t| t == v as u64).count();
                assert!(
                    ran[mine..].iter().all(|&t| t != v as u64),
                    "thread {v}'s own pieces are not a first run: {ran:?}"
                );
                let started: Vec<u64> = r
                    .clone()
                    .take(mine)
                    .map(|c| seq[c].load(Ordering::Relaxed))
                    .collect();
                assert!(started.windows(2).all(|w| w[0] < w[1]), "{started:?}");
                if v == slow {
                    assert!(mine < r.len(), "nobody took a piece of the slow thread {v}");
                }
            }
        }
    }

    #[test]
    fn block_sums_do_not_depend_on_the_thread_count() {
        let data: Vec<f64> = (0..100_000)
            .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 + 1e-9)
            .collect();
        let sums: Vec<f64> = [1, 2, 3, 4]
            .iter()
            .map(|&t| {
                let team = Team::new(t, Pin::None).unwrap();
                team.sum_blocks(data.len(), |r| data[r].iter().sum())
            })
            .collect();
        assert!(
            sums.iter().all(|s| s.to_bits() == sums[0].to_bits()),
            "{sums:?}"
        );
    }
}

/// How a run uses the machine: threads, their placement, first touch (not physics: results do
/// not depend on it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Options {
    /// Worker threads (0: one per core available).
    pub threads: usize,
    /// Thread placement.
    pub pin: Pin,
    /// Let each thread initialise (first touch) the particle arrays of its range, so that their
    /// pages are placed near it; off: the main thread's placement, for measurement.
    pub first_touch: bool,
}

impl Default for Options {
    /// One thread per free core, pinned when each has a free core of its own, first touch on.
    fn default() -> Self {
        Options {
            threads: 0,
            pin: Pin::Auto,
            first_touch: true,
        }
    }
}
