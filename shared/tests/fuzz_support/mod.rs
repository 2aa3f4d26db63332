//! Shared by the stable fuzz harnesses (`shared/tests/fuzz_readers.rs`,
//! `solver/tests/fuzz_scenes.rs`): structure-aware mutations of a seed file, and a guard that runs
//! one case under `catch_unwind`, a watchdog and a cap on the size of any one allocation.
//!
//! Every case is deterministic (the mutations are data, drawn by proptest from a fixed seed), so a
//! failure names its reader, seed file and mutations, and the guard saves the failing input under
//! `target/tmp/fuzz-failures/` for replay. See docs/design.md §7.5, "Fuzzing".
#![allow(dead_code)]

pub mod readers;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use proptest::prelude::*;

/// How long one case may run before it counts as a hang. Inputs are at most a few hundred KB, so
/// a reader that is linear in its input finishes in milliseconds even in a debug build.
pub const WATCHDOG: Duration = Duration::from_secs(20);

thread_local! {
    /// Largest single allocation this thread may make (`usize::MAX`: no cap).
    static CAP: Cell<usize> = const { Cell::new(usize::MAX) };
    /// Largest allocation this thread asked for above its cap (0: none).
    static OVER: Cell<usize> = const { Cell::new(0) };
}

/// Allocations above this are refused outright (the process then aborts naming the size): a
/// reader must never get there, and granting them could exhaust the CI machine.
const HARD_LIMIT: usize = 1 << 30;

/// A global allocator that notes any allocation above the running case's cap, so that a count
/// taken from the input and trusted before the data is seen fails the case by name.
pub struct CappedAlloc;

impl CappedAlloc {
    fn check(size: usize) -> bool {
        let cap = CAP.try_with(Cell::get).unwrap_or(usize::MAX);
        if size > cap {
            let _ = OVER.try_with(|o| o.set(o.get().max(size)));
            if size > HARD_LIMIT {
                return false;
            }
        }
        true
    }
}

// SAFETY: every call is forwarded to the system allocator unchanged, or refused with null, which
// the `GlobalAlloc` contract allows.
unsafe impl GlobalAlloc for CappedAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if !Self::check(layout.size()) {
            return std::ptr::null_mut();
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if !Self::check(layout.size()) {
            return std::ptr::null_mut();
        }
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if !Self::check(new_size) {
            return std::ptr::null_mut();
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// The allocation cap for an input of `len` bytes: generous for any structure built from the
/// input's own bytes, far below what a header's unchecked count would ask for.
pub fn cap_for(len: usize) -> usize {
    64 * len + (16 << 20)
}

/// Runs `f(data)` on a fresh thread under `catch_unwind`, the [`WATCHDOG`] and the allocation
/// cap. `Err` says what went wrong (panic message, hang, oversized allocation) and where the
/// input was saved.
pub fn guard(reader: &str, label: &str, data: &[u8], f: fn(&[u8])) -> Result<(), String> {
    guard_with_cap(reader, label, data, f, cap_for(data.len()))
}

/// [`guard`] with an explicit allocation cap (for inputs that name other files, or whose values
/// may size an allocation up to a documented limit).
pub fn guard_with_cap(
    reader: &str,
    label: &str,
    data: &[u8],
    f: fn(&[u8]),
    cap: usize,
) -> Result<(), String> {
    let (tx, rx) = mpsc::channel();
    let owned = data.to_vec();
    std::thread::Builder::new()
        .name(format!("fuzz-{reader}"))
        .spawn(move || {
            CAP.with(|c| c.set(cap));
            OVER.with(|o| o.set(0));
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(&owned)));
            let over = OVER.with(Cell::get);
            CAP.with(|c| c.set(usize::MAX));
            let r = match r {
                Err(p) => Err(format!("panic: {}", panic_text(&p))),
                Ok(()) if over > 0 => Err(format!(
                    "allocation of {over} bytes for an input of {} bytes (cap {cap}): a count \
                     from the input was trusted before its data was seen",
                    owned.len()
                )),
                Ok(()) => Ok(()),
            };
            let _ = tx.send(r);
        })
        .expect("spawn a fuzz case");
    let outcome = match rx.recv_timeout(WATCHDOG) {
        Ok(r) => r,
        Err(mpsc::RecvTimeoutError::Timeout) => Err(format!("hang: no result after {WATCHDOG:?}")),
        Err(mpsc::RecvTimeoutError::Disconnected) => Err("the case's thread died".into()),
    };
    outcome.map_err(|why| {
        let saved = save_failure(reader, data);
        format!(
            "{reader} ({label}): {why}; input saved to {}",
            saved.display()
        )
    })
}

fn panic_text(p: &Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "(non-text panic payload)".into()
    }
}

/// Writes a failing input where it can be copied into the corpus; returns its path.
fn save_failure(reader: &str, data: &[u8]) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("fuzz-failures")
        .join(reader);
    let _ = std::fs::create_dir_all(&dir);
    let p = dir.join(format!("{:016x}", fnv(data)));
    let _ = std::fs::write(&p, data);
    p
}

/// FNV-1a, to name saved inputs by content.
pub fn fnv(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The files of a corpus folder and its subfolders, sorted by path (none if it is missing).
pub fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.file_name().is_some_and(|n| n != "README.md") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Values that break readers: signs, zero, the edges of the integer types, counts far beyond any
/// input, reals out of range, words where numbers belong, nothing at all.
pub const SPECIALS: &[&str] = &[
    "0",
    "-1",
    "-0",
    "1",
    "2",
    "-2147483648",
    "2147483647",
    "4294967295",
    "4294967296",
    "1000000000000",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "99999999999999999999999",
    "1e308",
    "-1e308",
    "1e400",
    "1e-320",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "Infinity",
    "0.5",
    "-0.5",
    "1.5",
    "",
    "x",
    "1,2",
    "\"",
];

/// Big binary values for length headers.
pub const HUGE_U64: &[u64] = &[
    0,
    1,
    7,
    0xffff_ffff,
    1 << 40,
    1 << 62,
    u64::MAX,
    u64::MAX - 7,
];

/// One edit of an input. Positions are fractions of the current length, so a mutation means
/// something for every seed.
#[derive(Debug, Clone)]
pub enum Mutation {
    /// Keep only the first fraction of the bytes.
    Truncate(f64),
    /// Overwrite one byte.
    SetByte(f64, u8),
    /// Insert bytes.
    Insert(f64, Vec<u8>),
    /// Delete the line at the position.
    DeleteLine(f64),
    /// Repeat the line at the position.
    DuplicateLine(f64),
    /// Exchange two lines.
    SwapLines(f64, f64),
    /// Replace the number at or after the position with [`SPECIALS`]`[k]`.
    Number(f64, usize),
    /// Multiply the number at or after the position by 10^k (k in 1..=12): a count that lies.
    Scale(f64, u32),
    /// Insert a line of `n` thousand copies of a byte.
    LongLine(f64, u8, u8),
    /// Delete a section: from the keyword line at or after the position to the next one.
    DropSection(f64),
    /// Repeat a section.
    DuplicateSection(f64),
    /// Insert bytes that are not UTF-8.
    NonUtf8(f64),
    /// Overwrite 8 bytes with a little- (`true`) or big-endian [`HUGE_U64`]`[k]`.
    Word(f64, usize, bool),
    /// Swap the ids at two positions (duplicate ids, wrong references).
    CopyNumber(f64, f64),
}

/// A proptest strategy for one mutation.
pub fn mutation() -> impl Strategy<Value = Mutation> {
    let p = || 0.0f64..1.0;
    prop_oneof![
        2 => p().prop_map(Mutation::Truncate),
        2 => (p(), any::<u8>()).prop_map(|(a, b)| Mutation::SetByte(a, b)),
        1 => (p(), prop::collection::vec(any::<u8>(), 1..8)).prop_map(|(a, b)| Mutation::Insert(a, b)),
        2 => p().prop_map(Mutation::DeleteLine),
        2 => p().prop_map(Mutation::DuplicateLine),
        1 => (p(), p()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        6 => (p(), 0..SPECIALS.len()).prop_map(|(a, k)| Mutation::Number(a, k)),
        3 => (p(), 1u32..13).prop_map(|(a, k)| Mutation::Scale(a, k)),
        1 => (p(), prop::sample::select(vec![b'1', b' ', b'x', b'$', b'<', b'"']), 1u8..200)
            .prop_map(|(a, b, n)| Mutation::LongLine(a, b, n)),
        2 => p().prop_map(Mutation::DropSection),
        1 => p().prop_map(Mutation::DuplicateSection),
        1 => p().prop_map(Mutation::NonUtf8),
        2 => (p(), 0..HUGE_U64.len(), any::<bool>()).prop_map(|(a, k, le)| Mutation::Word(a, k, le)),
        2 => (p(), p()).prop_map(|(a, b)| Mutation::CopyNumber(a, b)),
    ]
}

/// A strategy for a case: which seed, then one to four mutations.
pub fn case(seeds: usize) -> impl Strategy<Value = (usize, Vec<Mutation>)> {
    (0..seeds, prop::collection::vec(mutation(), 1..5))
}

fn at(d: &[u8], f: f64) -> usize {
    ((d.len() as f64 * f) as usize).min(d.len())
}

/// The line holding byte `i`: `(start, end)` with the end after its `\n`.
fn line_around(d: &[u8], i: usize) -> (usize, usize) {
    let i = i.min(d.len());
    let s = d[..i]
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    let e = d[i..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(d.len(), |p| i + p + 1);
    (s, e)
}

fn is_number_byte(b: u8) -> bool {
    b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'+' | b'e' | b'E')
}

/// The number (a run of digits, signs, points and exponents holding a digit) at or after `i`.
fn number_at(d: &[u8], i: usize) -> Option<(usize, usize)> {
    let first = i + d.get(i..)?.iter().position(u8::is_ascii_digit)?;
    let mut s = first;
    while s > 0 && is_number_byte(d[s - 1]) {
        s -= 1;
    }
    let mut e = first;
    while e < d.len() && is_number_byte(d[e]) {
        e += 1;
    }
    Some((s, e))
}

/// A section starts at a line that begins (after blanks) with `$` (GOM, CPS, MSH), `[` (TOML),
/// ` ---` (BMS) or `<` followed by a letter (XML).
fn starts_section(line: &[u8]) -> bool {
    let t: &[u8] = {
        let k = line
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(line.len());
        &line[k..]
    };
    match t {
        [b'$', ..] | [b'[', ..] | [b'-', b'-', b'-', ..] => true,
        [b'<', c, ..] => c.is_ascii_alphabetic(),
        _ => false,
    }
}

/// The section around byte `i`: from its keyword line to the next keyword line.
fn section_around(d: &[u8], i: usize) -> Option<(usize, usize)> {
    let mut starts = Vec::new();
    let mut pos = 0;
    while pos < d.len() {
        let (s, e) = line_around(d, pos);
        if starts_section(&d[s..e]) {
            starts.push(s);
        }
        pos = e.max(pos + 1);
    }
    let k = starts
        .iter()
        .rposition(|&s| s <= i)
        .or(if starts.is_empty() { None } else { Some(0) })?;
    let end = starts.get(k + 1).copied().unwrap_or(d.len());
    Some((starts[k], end))
}

/// Applies one mutation in place.
pub fn apply(d: &mut Vec<u8>, m: &Mutation) {
    match *m {
        Mutation::Truncate(f) => d.truncate(at(d, f)),
        Mutation::SetByte(f, b) => {
            if !d.is_empty() {
                let i = at(d, f).min(d.len() - 1);
                d[i] = b;
            }
        }
        Mutation::Insert(f, ref b) => {
            let i = at(d, f);
            d.splice(i..i, b.iter().copied());
        }
        Mutation::DeleteLine(f) => {
            let (s, e) = line_around(d, at(d, f));
            d.drain(s..e);
        }
        Mutation::DuplicateLine(f) => {
            let (s, e) = line_around(d, at(d, f));
            let line = d[s..e].to_vec();
            d.splice(s..s, line);
        }
        Mutation::SwapLines(a, b) => {
            let (mut x, mut y) = (line_around(d, at(d, a)), line_around(d, at(d, b)));
            if x.0 > y.0 {
                std::mem::swap(&mut x, &mut y);
            }
            if x.1 <= y.0 {
                let (l1, l2) = (d[x.0..x.1].to_vec(), d[y.0..y.1].to_vec());
                d.splice(y.0..y.1, l1);
                d.splice(x.0..x.1, l2);
            }
        }
        Mutation::Number(f, k) => {
            if let Some((s, e)) = number_at(d, at(d, f)) {
                d.splice(s..e, SPECIALS[k].bytes());
            }
        }
        Mutation::Scale(f, k) => {
            if let Some((_, e)) = number_at(d, at(d, f)) {
                d.splice(e..e, std::iter::repeat(b'0').take(k as usize));
            }
        }
        Mutation::LongLine(f, b, n) => {
            let (s, _) = line_around(d, at(d, f));
            let mut line = vec![b; n as usize * 1000];
            line.push(b'\n');
            d.splice(s..s, line);
        }
        Mutation::DropSection(f) => {
            if let Some((s, e)) = section_around(d, at(d, f)) {
                d.drain(s..e);
            }
        }
        Mutation::DuplicateSection(f) => {
            if let Some((s, e)) = section_around(d, at(d, f)) {
                let sec = d[s..e].to_vec();
                d.splice(e..e, sec);
            }
        }
        Mutation::NonUtf8(f) => {
            let i = at(d, f);
            d.splice(i..i, [0xff, 0xfe, 0xc3, 0x28]);
        }
        Mutation::Word(f, k, le) => {
            if d.len() >= 8 {
                let i = at(d, f).min(d.len() - 8);
                let v = HUGE_U64[k];
                let b = if le { v.to_le_bytes() } else { v.to_be_bytes() };
                d[i..i + 8].copy_from_slice(&b);
            }
        }
        Mutation::CopyNumber(a, b) => {
            if let (Some(x), Some(y)) = (number_at(d, at(d, a)), number_at(d, at(d, b))) {
                if x.1 <= y.0 {
                    let v = d[x.0..x.1].to_vec();
                    d.splice(y.0..y.1, v);
                } else if y.1 <= x.0 {
                    let v = d[y.0..y.1].to_vec();
                    d.splice(x.0..x.1, v);
                }
            }
        }
    }
}

/// `seed` with `mutations` applied in order.
pub fn mutated(seed: &[u8], mutations: &[Mutation]) -> Vec<u8> {
    let mut d = seed.to_vec();
    for m in mutations {
        apply(&mut d, m);
    }
    d
}

/// A short description of a case for messages.
pub fn describe(seed: &Path, mutations: &[Mutation]) -> String {
    let mut s = format!("seed {} with {mutations:?}", seed.display());
    if s.len() > 400 {
        s.truncate(400);
        s.push_str("...");
    }
    s
}
