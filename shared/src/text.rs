//! Low-level text scanning and number formatting shared by the ASCII formats.
//!
//! The readers work on the whole file as bytes: lines are found with `memchr`, tokens are split on
//! Fortran list-directed separators (blanks, tabs, commas) and numbers are parsed without
//! allocation. The writers format integers with `itoa` and reals with `ryu`, which gives the
//! shortest decimal string that reads back to the same `f64`, so a write loses no precision.

/// Iterator over the lines of a byte buffer, yielding `(1-based line number, line)` with the line
/// terminator (`\n` or `\r\n`) removed.
#[derive(Clone)]
pub struct Lines<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    /// Lines of `data`, numbered from `first_line`.
    pub fn new(data: &'a [u8], first_line: usize) -> Self {
        Lines {
            data,
            pos: 0,
            line: first_line.saturating_sub(1),
        }
    }

    /// Byte offset of the next line in the buffer.
    pub fn offset(&self) -> usize {
        self.pos
    }

    /// Number of the line that `next` returned last (0 before the first).
    pub fn line_number(&self) -> usize {
        self.line
    }

    /// Moves to the start of the next line that begins (after blanks) with `$$`, counting the
    /// lines skipped. Data lines never hold `$`, so this scans at memchr speed instead of line by
    /// line.
    pub fn skip_to_keyword(&mut self) {
        let rest = &self.data[self.pos..];
        for p in memchr::memchr_iter(b'$', rest) {
            if rest.get(p + 1) != Some(&b'$') {
                continue;
            }
            let ls = rest[..p]
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |i| i + 1);
            if rest[ls..p].iter().all(|&b| is_separator(b)) {
                self.line += memchr::memchr_iter(b'\n', &rest[..ls]).count();
                self.pos += ls;
                return;
            }
        }
        self.line += memchr::memchr_iter(b'\n', rest).count();
        if !rest.is_empty() && rest[rest.len() - 1] != b'\n' {
            self.line += 1;
        }
        self.pos = self.data.len();
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.data.len() {
            return None;
        }
        let rest = &self.data[self.pos..];
        let (mut line, advance) = match memchr::memchr(b'\n', rest) {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        if let [head @ .., b'\r'] = line {
            line = head;
        }
        self.pos += advance;
        self.line += 1;
        Some((self.line, line))
    }
}

/// True for the separators of Fortran list-directed input.
#[inline]
pub fn is_separator(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b',' | b'\r' | b'\x0c' | b'\x0b')
}

/// Splits a line into tokens. A token that starts with a quote runs to the matching quote, so
/// quoted names keep their blanks.
#[derive(Clone)]
pub struct Tokens<'a> {
    line: &'a [u8],
    pos: usize,
}

impl<'a> Tokens<'a> {
    /// Tokens of `line`.
    #[inline]
    pub fn new(line: &'a [u8]) -> Self {
        Tokens { line, pos: 0 }
    }
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    #[inline]
    fn next(&mut self) -> Option<&'a [u8]> {
        let l = self.line;
        let mut i = self.pos;
        while i < l.len() && is_separator(l[i]) {
            i += 1;
        }
        if i >= l.len() {
            self.pos = i;
            return None;
        }
        let start = i;
        if l[i] == b'"' || l[i] == b'\'' {
            let q = l[i];
            i += 1;
            while i < l.len() && l[i] != q {
                i += 1;
            }
            i = (i + 1).min(l.len());
        } else {
            while i < l.len() && !is_separator(l[i]) {
                i += 1;
            }
        }
        self.pos = i;
        Some(&l[start..i])
    }
}

/// True when the line holds nothing but separators.
#[inline]
pub fn is_blank(line: &[u8]) -> bool {
    line.iter().all(|&b| is_separator(b))
}

/// Trims separators at both ends.
pub fn trim(line: &[u8]) -> &[u8] {
    let start = line
        .iter()
        .position(|&b| !is_separator(b))
        .unwrap_or(line.len());
    let end = line
        .iter()
        .rposition(|&b| !is_separator(b))
        .map_or(start, |e| e + 1);
    &line[start..end]
}

/// Parses a decimal integer with optional sign; `None` for anything else (including overflow).
#[inline]
pub fn parse_int(tok: &[u8]) -> Option<i64> {
    let (neg, digits) = match tok.first()? {
        b'-' => (true, &tok[1..]),
        b'+' => (false, &tok[1..]),
        _ => (false, tok),
    };
    if digits.is_empty() || digits.len() > 18 {
        return parse_int_slow(tok);
    }
    let mut v: i64 = 0;
    for &d in digits {
        let x = d.wrapping_sub(b'0');
        if x > 9 {
            return None;
        }
        v = v * 10 + x as i64;
    }
    Some(if neg { -v } else { v })
}

#[cold]
fn parse_int_slow(tok: &[u8]) -> Option<i64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Parses an unsigned 1-based id as found in connectivity and node lists.
#[inline]
pub fn parse_u32(tok: &[u8]) -> Option<u32> {
    if tok.is_empty() || tok.len() > 10 {
        return None;
    }
    let mut v: u64 = 0;
    for &d in tok {
        let x = d.wrapping_sub(b'0');
        if x > 9 {
            return None;
        }
        v = v * 10 + x as u64;
    }
    u32::try_from(v).ok()
}

/// Parses a finite real in any of the forms Fortran list-directed input accepts for numbers
/// (`1`, `-0.5`, `.5`, `1e-3`, `1.0E+000`, `1.0D0`). Words such as `inf` or `NaN` are not
/// numbers here.
#[inline]
pub fn parse_real(tok: &[u8]) -> Option<f64> {
    let first = *tok.first()?;
    if !(first.is_ascii_digit() || first == b'-' || first == b'+' || first == b'.') {
        return None;
    }
    let v: f64 = match std::str::from_utf8(tok).ok()?.parse() {
        Ok(v) => v,
        Err(_) => parse_fortran_d(tok)?,
    };
    v.is_finite().then_some(v)
}

#[cold]
fn parse_fortran_d(tok: &[u8]) -> Option<f64> {
    if !tok.iter().any(|&b| b == b'd' || b == b'D') {
        return None;
    }
    let s: String = tok
        .iter()
        .map(|&b| {
            if b == b'd' || b == b'D' {
                'e'
            } else {
                b as char
            }
        })
        .collect();
    s.parse().ok()
}

/// Appends the shortest decimal form of `v` that reads back to the same value. The text always
/// contains a `.` or an exponent, so a reader can tell it from an integer.
#[inline]
pub fn push_real(out: &mut Vec<u8>, v: f64) {
    if v.is_finite() {
        let mut b = ryu::Buffer::new();
        out.extend_from_slice(b.format_finite(v).as_bytes());
    } else if v.is_nan() {
        out.extend_from_slice(b"NaN");
    } else if v > 0.0 {
        out.extend_from_slice(b"Infinity");
    } else {
        out.extend_from_slice(b"-Infinity");
    }
}

/// Appends a decimal integer.
#[inline]
pub fn push_int<I: itoa::Integer>(out: &mut Vec<u8>, v: I) {
    let mut b = itoa::Buffer::new();
    out.extend_from_slice(b.format(v).as_bytes());
}

/// Shortest round-trip text of `v` as a `String` (see [`push_real`]).
pub fn real_to_string(v: f64) -> String {
    let mut out = Vec::with_capacity(24);
    push_real(&mut out, v);
    String::from_utf8(out).expect("ryu writes ASCII")
}

/// Lossy, short rendering of a byte slice for error messages.
pub fn show(bytes: &[u8]) -> String {
    const MAX: usize = 80;
    let s = String::from_utf8_lossy(bytes);
    if s.chars().count() > MAX {
        let cut: String = s.chars().take(MAX).collect();
        format!("'{cut}...'")
    } else {
        format!("'{s}'")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_strip_crlf_and_count() {
        let data = b"a\r\nb\n\nc";
        let v: Vec<_> = Lines::new(data, 1).collect();
        assert_eq!(
            v,
            vec![
                (1, &b"a"[..]),
                (2, &b"b"[..]),
                (3, &b""[..]),
                (4, &b"c"[..])
            ]
        );
    }

    #[test]
    fn tokens_split_on_fortran_separators_and_keep_quotes() {
        let t: Vec<_> = Tokens::new(b" 1\t2,3  \"a b\" 'c' x ").collect();
        assert_eq!(
            t,
            vec![
                &b"1"[..],
                &b"2"[..],
                &b"3"[..],
                &b"\"a b\""[..],
                &b"'c'"[..],
                &b"x"[..]
            ]
        );
    }

    #[test]
    fn numbers_parse_like_fortran() {
        assert_eq!(parse_int(b"-12"), Some(-12));
        assert_eq!(parse_int(b"1.0"), None);
        assert_eq!(parse_u32(b"4294967295"), Some(u32::MAX));
        assert_eq!(parse_u32(b"4294967296"), None);
        assert_eq!(parse_real(b"1.0E+000"), Some(1.0));
        assert_eq!(parse_real(b"2.5D-1"), Some(0.25));
        assert_eq!(parse_real(b".5"), Some(0.5));
        assert_eq!(parse_real(b"NaN"), None);
        assert_eq!(parse_real(b"inf"), None);
        assert_eq!(parse_real(b"1e400"), None);
    }

    #[test]
    fn reals_round_trip_shortest() {
        for v in [0.1, 1.0, -0.0, 1e-300, 123456.789, 2.0f64.sqrt(), 6.02e23] {
            let s = real_to_string(v);
            assert!(s.contains('.') || s.contains('e'), "{s}");
            assert_eq!(parse_real(s.as_bytes()), Some(v));
        }
        assert_eq!(real_to_string(0.1), "0.1");
    }
}
