//! Which cores are free: a short look at the kernel's per-core counters (`/proc/stat`) before
//! the team starts, so that a run on a shared machine neither pins a thread to a core another
//! process keeps busy nor waits at every barrier for the thread that shares it (docs/design.md
//! §5.1). The team's start consults it, and a team pinned by [`crate::parallel::team::Pin::Auto`]
//! looks again every [`RECHECK`] while it runs; results never depend on it.

use std::time::Duration;

/// How long the counters are watched: five of the kernel's 10 ms ticks per core.
pub const WINDOW: Duration = Duration::from_millis(50);

/// A core counts as busy when others used more than this share of it during the window.
pub const BUSY_SHARE: f64 = 0.5;

/// While the team runs, a core one of its pinned threads keeps busy counts as taken when
/// others used more than this share of it since the last look: the kernel shares a core about
/// evenly, so a competitor gets at most about half of it, and far less than that already
/// stalls the team at its barriers.
pub const TAKEN_SHARE: f64 = 0.2;

/// How often a pinned team looks at its cores while it runs.
pub const RECHECK: Duration = Duration::from_secs(1);

/// Per-core (busy, total) jiffies from the text of `/proc/stat`: the `cpuN` lines, busy being
/// everything but idle and iowait. Lines that do not parse are skipped.
pub fn parse_stat(text: &str) -> Vec<(usize, u64, u64)> {
    let mut out = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        let Some(name) = words.next() else { continue };
        let Some(Ok(core)) = name.strip_prefix("cpu").map(str::parse::<usize>) else {
            continue;
        };
        let counts: Vec<u64> = words.map_while(|w| w.parse().ok()).collect();
        if counts.len() < 4 {
            continue;
        }
        let total: u64 = counts.iter().sum();
        let idle = counts[3] + counts.get(4).copied().unwrap_or(0);
        out.push((core, total.saturating_sub(idle), total));
    }
    out
}

/// The cores of `cores` whose busy share between the samples `before` and `after` (from
/// [`parse_stat`]) exceeds `share` ([`BUSY_SHARE`] before the team starts). A core missing from
/// either sample, or without ticks in between, is taken as free.
pub fn busy_between(
    cores: &[usize],
    before: &[(usize, u64, u64)],
    after: &[(usize, u64, u64)],
    share: f64,
) -> Vec<usize> {
    let find = |s: &[(usize, u64, u64)], c| s.iter().find(|e| e.0 == c).map(|e| (e.1, e.2));
    cores
        .iter()
        .copied()
        .filter(|&c| match (find(before, c), find(after, c)) {
            (Some((b0, t0)), Some((b1, t1))) if t1 > t0 => {
                b1.saturating_sub(b0) as f64 / (t1 - t0) as f64 > share
            }
            _ => false,
        })
        .collect()
}

/// This process's threads: per thread id, (busy jiffies, the core it last ran on), from
/// `/proc/self/task/*/stat` (utime, stime and processor: fields 14, 15 and 39).
fn own_threads() -> Vec<(u64, u64, usize)> {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for entry in dir.flatten() {
        let Ok(tid) = entry.file_name().to_string_lossy().parse::<u64>() else {
            continue;
        };
        let Ok(text) = std::fs::read_to_string(entry.path().join("stat")) else {
            continue;
        };
        // The command name, in parentheses, may hold spaces: fields count from after it.
        let Some(rest) = text.rfind(')').map(|i| &text[i + 1..]) else {
            continue;
        };
        let f: Vec<&str> = rest.split_whitespace().collect();
        let num = |i: usize| f.get(i).and_then(|w| w.parse::<u64>().ok());
        if let (Some(u), Some(s), Some(core)) = (num(11), num(12), num(36)) {
            out.push((tid, u + s, core as usize));
        }
    }
    out
}

/// A look at the cores under way: the counters when it began.
#[derive(Debug)]
pub struct Look {
    at: std::time::Instant,
    cores: Vec<(usize, u64, u64)>,
    own: Vec<(u64, u64, usize)>,
}

impl Look {
    /// Begins a look (`None` where `/proc/stat` cannot be read).
    pub fn begin() -> Option<Look> {
        let text = std::fs::read_to_string("/proc/stat").ok()?;
        Some(Look {
            at: std::time::Instant::now(),
            cores: parse_stat(&text),
            own: own_threads(),
        })
    }

    /// Ends the look, at least [`WINDOW`] after it began (sleeping the rest): the cores of
    /// `cores` that other processes kept busy. This process's own work in the meantime (the
    /// input being read) is taken off the core each of its threads last ran on.
    pub fn busy(self, cores: &[usize]) -> Option<Vec<usize>> {
        if let Some(rest) = WINDOW.checked_sub(self.at.elapsed()) {
            std::thread::sleep(rest);
        }
        self.others_above(cores, BUSY_SHARE)
    }

    /// How long ago the look began.
    pub fn age(&self) -> Duration {
        self.at.elapsed()
    }

    /// Ends the look now, without waiting: the cores of `cores` of which other processes used
    /// more than `share` since it began, this process's own threads taken off the cores they
    /// last ran on (a pinned worker always runs on its own).
    pub fn others_above(self, cores: &[usize], share: f64) -> Option<Vec<usize>> {
        let own = own_threads();
        let mut after = parse_stat(&std::fs::read_to_string("/proc/stat").ok()?);
        for &(tid, ticks, core) in &own {
            let before = self.own.iter().find(|t| t.0 == tid).map_or(0, |t| t.1);
            if let Some(c) = after.iter_mut().find(|c| c.0 == core) {
                c.1 = c.1.saturating_sub(ticks.saturating_sub(before));
            }
        }
        Some(busy_between(cores, &self.cores, &after, share))
    }
}

/// The look begun at the program's start ([`begin_early`]), if any.
static EARLY: std::sync::Mutex<Option<Look>> = std::sync::Mutex::new(None);

/// Begins the look now, so that reading the input overlaps its window; the team takes it.
pub fn begin_early() {
    if let Ok(mut early) = EARLY.lock() {
        *early = Look::begin();
    }
}

/// The cores of `cores` that other processes keep busy: from the look begun early, or from
/// one begun now (watched for [`WINDOW`]); `None` where the counters cannot be read (not
/// Linux, no `/proc`).
pub fn busy_cores(cores: &[usize]) -> Option<Vec<usize>> {
    let early = EARLY.lock().ok().and_then(|mut e| e.take());
    early.or_else(Look::begin)?.busy(cores)
}

/// Whether the process may run on fewer cores than the machine has online: a launcher
/// (`mpirun --bind-to`, `taskset`, a batch system's cgroup) gave it cores of its own. `false`
/// where the counters cannot be read.
pub fn bound_to_some_cores() -> bool {
    let Ok(text) = std::fs::read_to_string("/proc/stat") else {
        return false;
    };
    let online = parse_stat(&text).len();
    let mine = core_affinity::get_core_ids().map_or(0, |c| c.len());
    mine > 0 && mine < online
}

/// The order in which threads are pinned to `cores` (logical cpu ids, as the process may use
/// them): one hardware thread of each physical core first, in the given order, then the second
/// thread of each, and so on, so that a team smaller than the machine gets whole cores (on a
/// machine that numbers a core's two threads next to each other, 0 and 1, two threads pinned to
/// cores 0 and 1 would share one core). The topology is the kernel's
/// (`/sys/devices/system/cpu/cpuN/topology`); where it cannot be read, the given order.
pub fn spread(cores: &[usize]) -> Vec<usize> {
    let read = |c: usize, what: &str| -> Option<u32> {
        std::fs::read_to_string(format!("/sys/devices/system/cpu/cpu{c}/topology/{what}"))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    spread_by(cores, |c| {
        Some((read(c, "physical_package_id")?, read(c, "core_id")?))
    })
}

/// [`spread`] with the physical core of each logical cpu from `core` (package, core); the
/// given order when any is unknown.
pub fn spread_by(cores: &[usize], core: impl Fn(usize) -> Option<(u32, u32)>) -> Vec<usize> {
    let Some(keys) = cores.iter().map(|&c| core(c)).collect::<Option<Vec<_>>>() else {
        return cores.to_vec();
    };
    // Each cpu's rank among the cpus of its physical core, in the given order.
    let rank: Vec<usize> = (0..cores.len())
        .map(|i| keys[..i].iter().filter(|&&k| k == keys[i]).count())
        .collect();
    let mut order: Vec<usize> = (0..cores.len()).collect();
    order.sort_by_key(|&i| rank[i]);
    order.into_iter().map(|i| cores[i]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threads_take_whole_cores_first_whatever_the_numbering() {
        // Siblings numbered next to each other (0 and 1 share core 0), as many VMs do.
        let adjacent = |c: usize| Some((0, (c / 2) as u32));
        assert_eq!(
            spread_by(&[0, 1, 2, 3, 4, 5, 6, 7], adjacent),
            vec![0, 2, 4, 6, 1, 3, 5, 7]
        );
        // Siblings half the machine apart (bare-metal Linux): the order stands.
        let apart = |c: usize| Some((0, (c % 4) as u32));
        assert_eq!(
            spread_by(&[0, 1, 2, 3, 4, 5, 6, 7], apart),
            vec![0, 1, 2, 3, 4, 5, 6, 7]
        );
        // Two sockets with the same core ids: different cores.
        let sockets = |c: usize| Some(((c / 4) as u32, (c % 2) as u32));
        assert_eq!(spread_by(&[0, 1, 4, 5], sockets), vec![0, 1, 4, 5]);
        // An unknown topology keeps the given order; so does a restricted set.
        assert_eq!(spread_by(&[3, 1, 2], |_| None), vec![3, 1, 2]);
        assert_eq!(spread_by(&[1, 0], adjacent), vec![1, 0]);
    }

    const SAMPLE: &str = "cpu  100 0 50 1000 10 0 0 0 0 0\n\
cpu0 50 0 25 500 5 0 0 0 0 0\n\
cpu1 50 0 25 500 5 0 0 0 0 0\n\
intr 12345 1 2\n\
ctxt 999\n";

    #[test]
    fn the_per_core_lines_are_read_and_the_summary_line_skipped() {
        let s = parse_stat(SAMPLE);
        assert_eq!(s, vec![(0, 75, 580), (1, 75, 580)]);
        assert!(parse_stat("cpuX 1 2 3 4\ncpu3 1 2\n").is_empty());
    }

    #[test]
    fn a_core_used_mostly_by_others_is_busy() {
        let before = vec![(0, 75, 580), (1, 75, 580), (2, 0, 10)];
        // Core 0: 4 of 5 ticks busy; core 1: 1 of 5; core 2: no ticks; core 3 unknown.
        let after = vec![(0, 79, 585), (1, 76, 585), (2, 0, 10)];
        assert_eq!(
            busy_between(&[0, 1, 2, 3], &before, &after, BUSY_SHARE),
            vec![0]
        );
        // While the team runs, a quarter of a core taken by others is enough.
        let after = vec![(0, 76, 584), (1, 75, 584), (2, 0, 10)];
        assert!(busy_between(&[0, 1], &before, &after, BUSY_SHARE).is_empty());
        assert_eq!(busy_between(&[0, 1], &before, &after, TAKEN_SHARE), vec![0]);
    }

    #[test]
    fn this_machine_can_be_looked_at() {
        // On Linux the counters read; the answer depends on the machine's load.
        if std::path::Path::new("/proc/stat").exists() {
            assert!(busy_cores(&[0]).is_some());
        }
    }
}
