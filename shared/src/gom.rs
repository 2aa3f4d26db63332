//! Anura3D geometry files (`.GOM`, `.GOM_stageN`): reader and writer.
//!
//! Layout: a version line `### Anura3D_20XX ###`, then `$$KEYWORD` lines each followed by their
//! data lines (free format), then `$$FINISH`. Node `i` is the i-th line after `$$STARTNODES`,
//! element `e` the e-th after `$$STARTELEMCON` (both 1-based). See docs/design.md §2.1.
//!
//! The reader validates counts and id ranges and reports the file, line and section of the
//! first problem. The writer keeps the section order of the model, writes one blank between
//! values, integers as integers and reals in shortest round-trip form, so `read(write(m)) == m`.

use std::io::{self, Write};

use rayon::prelude::*;

use crate::error::{Error, Location, Result};
use crate::model::{
    classify, Body, Dimension, ElementType, IdKind, Kind, LineEnding, Model, Refs, Section, Table,
    Token,
};
use crate::text::{self, Lines, Tokens};

/// One raw section found by the first pass: keyword and the byte range of its data lines.
struct RawSection<'a> {
    keyword: &'a str,
    /// Line number of the `$$KEYWORD` line.
    line: usize,
    /// The data lines (up to the next keyword).
    body: &'a [u8],
    /// Line number of the first data line.
    body_line: usize,
}

/// Sections larger than this many bytes are parsed in parallel chunks.
const PARALLEL_BYTES: usize = 1 << 20;

/// Reads a GOM from memory. `file` names the input in error messages.
pub fn read(data: &[u8], file: &str) -> Result<Model> {
    let mut lines = Lines::new(data, 1);
    let (version, line_ending) = version_line(&mut lines, data, file)?;
    let raw = split_sections(&mut lines, data, file)?;
    // Geometry header first: it decides how the other sections are read.
    let header = read_header(&raw, file)?;
    let mut bodies = Bodies {
        file,
        header,
        coords: Vec::new(),
        connectivity: Vec::new(),
        seen_geometry: [false; 5],
    };
    let mut sections = Vec::with_capacity(raw.len());
    for s in &raw {
        let body = bodies.read(s)?;
        sections.push(Section {
            keyword: s.keyword.to_string(),
            body,
        });
    }
    bodies.check_geometry()?;
    Ok(Model {
        version,
        line_ending,
        dimension: header.dimension,
        element_type: header.element_type,
        coords: bodies.coords,
        connectivity: bodies.connectivity,
        sections,
    })
}

/// Reads the version line (`### Anura3D_20XX ###`, after any blank lines) and notes whether the
/// file ends its lines with CR LF.
fn version_line(lines: &mut Lines, data: &[u8], file: &str) -> Result<(String, LineEnding)> {
    loop {
        let Some((n, l)) = lines.next() else {
            return Err(Error::format(
                Location::new(file, 0, None),
                "empty file: expected a GOM version line such as '### Anura3D_2021 ###'",
            ));
        };
        if text::is_blank(l) {
            continue;
        }
        let t = text::trim(l);
        if !t.starts_with(b"###") {
            return Err(Error::format(
                Location::new(file, n, None),
                format!(
                    "expected a GOM version line such as '### Anura3D_2021 ###', found {}",
                    text::show(l)
                ),
            ));
        }
        let crlf = data.get(lines.offset().wrapping_sub(2)) == Some(&b'\r');
        let ending = if crlf {
            LineEnding::CrLf
        } else {
            LineEnding::Lf
        };
        return Ok((String::from_utf8_lossy(t).into_owned(), ending));
    }
}

/// The first pass: splits the rest of the file into its `$$KEYWORD` sections, up to
/// `$$FINISH`, which must be there.
fn split_sections<'a>(
    lines: &mut Lines<'a>,
    data: &'a [u8],
    file: &str,
) -> Result<Vec<RawSection<'a>>> {
    let at = |line: usize| Location::new(file, line, None);
    let mut raw: Vec<RawSection> = Vec::new();
    loop {
        if !raw.is_empty() {
            lines.skip_to_keyword();
        }
        let Some((n, l)) = lines.next() else { break };
        let t = text::trim(l);
        if let Some(kw) = t.strip_prefix(b"$$") {
            let keyword = std::str::from_utf8(kw)
                .map_err(|_| Error::format(at(n), "keyword is not valid UTF-8 text"))?;
            if let Some(prev) = raw.last_mut() {
                let start = prev.body.as_ptr() as usize - data.as_ptr() as usize;
                let end = lines.offset() - l.len() - line_terminator_len(data, lines.offset());
                prev.body = &data[start..end.max(start)];
            }
            if keyword == "FINISH" {
                return Ok(raw);
            }
            if keyword.is_empty() {
                return Err(Error::format(at(n), "empty keyword '$$'"));
            }
            raw.push(RawSection {
                keyword,
                line: n,
                body: &data[lines.offset()..],
                body_line: n + 1,
            });
        } else if raw.is_empty() && !text::is_blank(l) {
            return Err(Error::format(
                at(n),
                format!("expected a '$$KEYWORD' line, found {}", text::show(l)),
            ));
        }
    }
    let section = raw.last().map(|s| format!("$${}", s.keyword));
    Err(Error::format(
        Location::new(file, lines.line_number(), section.as_deref()),
        "file ends without '$$FINISH' (truncated?)",
    ))
}

/// What the geometry header says: the dimension, the element type and the counts that the
/// other sections are checked against.
#[derive(Clone, Copy)]
struct Header {
    dimension: Dimension,
    element_type: ElementType,
    /// Elements, from `$$STARTCOUNTERS`.
    n_el: usize,
    /// Nodes, from `$$STARTCOUNTERS`.
    n_nodes: usize,
}

/// Reads `$$DIMENSION`, `$$ELEMENTTYPE` and `$$STARTCOUNTERS`, which must be there and agree.
fn read_header(raw: &[RawSection], file: &str) -> Result<Header> {
    let at = |line: usize, section: Option<&str>| Location::new(file, line, section);
    let find = |k: &str| raw.iter().find(|s| s.keyword == k);
    let need = |k: &str| {
        find(k).ok_or_else(|| {
            Error::format(at(0, None), format!("required section '$${k}' is missing"))
        })
    };
    let dim_raw = need("DIMENSION")?;
    let dim_value = single_value(dim_raw, file)?;
    let dimension = Dimension::from_keyword(&dim_value).ok_or_else(|| {
        Error::format(
            at(dim_raw.body_line, Some("$$DIMENSION")),
            format!("expected 2D-plane_strain, 2D-axisymmetric, 3D-cartesian or 3D-cylindric, found '{dim_value}'"),
        )
    })?;
    let et_raw = need("ELEMENTTYPE")?;
    let et_value = single_value(et_raw, file)?;
    let element_type = ElementType::from_keyword(&et_value).ok_or_else(|| Error::Unsupported {
        at: at(et_raw.body_line, Some("$$ELEMENTTYPE")),
        message: format!(
            "element type '{et_value}' (supported: triangular_3-noded, tetrahedral_4-noded, tetrahedral_old)"
        ),
    })?;
    if element_type.dim() != dimension.coords() {
        return Err(Error::invalid(
            at(et_raw.body_line, Some("$$ELEMENTTYPE")),
            format!(
                "element type {} does not fit dimension {}",
                element_type.keyword(),
                dimension.keyword()
            ),
        ));
    }
    let counters = need("STARTCOUNTERS")?;
    let (n_el, n_nodes) = read_counters(counters, file)?;
    Ok(Header {
        dimension,
        element_type,
        n_el,
        n_nodes,
    })
}

/// The second pass: reads each section's body by its kind, keeping the node coordinates and
/// the connectivity out of the section list.
struct Bodies<'f> {
    file: &'f str,
    header: Header,
    coords: Vec<f64>,
    connectivity: Vec<u32>,
    /// Whether `$$DIMENSION`, `$$ELEMENTTYPE`, `$$STARTCOUNTERS`, `$$STARTNODES` and
    /// `$$STARTELEMCON` were seen.
    seen_geometry: [bool; 5],
}

impl Bodies<'_> {
    /// Reads the body of section `s`.
    fn read(&mut self, s: &RawSection) -> Result<Body> {
        let file = self.file;
        let Header {
            dimension,
            element_type,
            n_el,
            n_nodes,
        } = self.header;
        let seen = &mut self.seen_geometry;
        Ok(match classify(s.keyword, element_type) {
            Kind::Dimension => once(&mut seen[0], s, file, Body::Dimension)?,
            Kind::ElementType => once(&mut seen[1], s, file, Body::ElementType)?,
            Kind::Counters => once(&mut seen[2], s, file, Body::Counters)?,
            Kind::Nodes => {
                let b = once(&mut seen[3], s, file, Body::Nodes)?;
                self.coords = read_reals(s, dimension.coords(), n_nodes, file)?;
                b
            }
            Kind::Connectivity => {
                let b = once(&mut seen[4], s, file, Body::Connectivity)?;
                self.connectivity = read_ids(s, element_type.nodes(), n_el, n_nodes, file)?;
                b
            }
            Kind::PerElement => self.per_element(s)?,
            Kind::Counted(refs) => self.counted(s, refs)?,
            Kind::Uncounted(refs) => Body::Table {
                counted: false,
                refs,
                rows: read_rows(s, file, Some(refs), n_el, n_nodes)?,
            },
            Kind::Text => Body::Text(text_lines(s.body)),
            Kind::Opaque => Body::Opaque(text_lines(s.body)),
        })
    }

    /// Reads a section of one line per element.
    fn per_element(&self, s: &RawSection) -> Result<Body> {
        let Header { n_el, n_nodes, .. } = self.header;
        let sec = format!("$${}", s.keyword);
        let at = |line: usize| Location::new(self.file, line, Some(&sec));
        let rows = read_rows(s, self.file, None, n_el, n_nodes)?;
        if rows.len() != n_el {
            return Err(Error::invalid(
                at(s.line),
                format!(
                    "expected one line per element ({n_el} from $$STARTCOUNTERS), found {}",
                    rows.len()
                ),
            ));
        }
        // Point ids are derived from the input numbers: a bad map is refused here,
        // where the file and line are known.
        if s.keyword == crate::model::INPUT_ELEMENTS {
            crate::points::parse_input_elements(&rows)
                .map_err(|(row, m)| Error::invalid(at(s.line), format!("element {row}: {m}")))?;
        }
        Ok(Body::PerElement(rows))
    }

    /// Reads a section whose rows follow a line with their count.
    fn counted(&self, s: &RawSection, refs: Refs) -> Result<Body> {
        let Header { n_el, n_nodes, .. } = self.header;
        let (count, count_line, rest, rest_line) = count_line(s, self.file)?;
        let sub = RawSection {
            keyword: s.keyword,
            line: s.line,
            body: rest,
            body_line: rest_line,
        };
        let rows = read_rows(&sub, self.file, Some(refs), n_el, n_nodes)?;
        if rows.len() != count {
            return Err(Error::invalid(
                Location::new(self.file, count_line, Some(&format!("$${}", s.keyword))),
                format!("count line says {count} entries, found {}", rows.len()),
            ));
        }
        Ok(Body::Table {
            counted: true,
            refs,
            rows,
        })
    }

    /// Checks that the file had its nodes and its connectivity.
    fn check_geometry(&self) -> Result<()> {
        let seen = &self.seen_geometry;
        if !seen[3] || !seen[4] {
            let k = if seen[3] {
                "STARTELEMCON"
            } else {
                "STARTNODES"
            };
            return Err(Error::format(
                Location::new(self.file, 0, None),
                format!("required section '$${k}' is missing"),
            ));
        }
        Ok(())
    }
}

/// Length of the terminator of the line that ends right before `offset`.
fn line_terminator_len(data: &[u8], offset: usize) -> usize {
    if offset == 0 || data[offset - 1] != b'\n' {
        0
    } else if offset >= 2 && data[offset - 2] == b'\r' {
        2
    } else {
        1
    }
}

/// `body`, noting that section `s` was seen; a geometry section that appears twice is refused.
fn once(seen: &mut bool, s: &RawSection, file: &str, body: Body) -> Result<Body> {
    if *seen {
        return Err(Error::format(
            Location::new(file, s.line, Some(&format!("$${}", s.keyword))),
            "section appears twice",
        ));
    }
    *seen = true;
    Ok(body)
}

/// The first non-blank data line of a one-value section, trimmed.
fn single_value(s: &RawSection, file: &str) -> Result<String> {
    Lines::new(s.body, s.body_line)
        .find(|(_, l)| !text::is_blank(l))
        .map(|(_, l)| String::from_utf8_lossy(text::trim(l)).into_owned())
        .ok_or_else(|| {
            Error::format(
                Location::new(file, s.line, Some(&format!("$${}", s.keyword))),
                "expected a value line after the keyword",
            )
        })
}

/// Reads `$$STARTCOUNTERS`: the element and node counts.
fn read_counters(s: &RawSection, file: &str) -> Result<(usize, usize)> {
    let at = |n| Location::new(file, n, Some("$$STARTCOUNTERS"));
    let (n, l) = Lines::new(s.body, s.body_line)
        .find(|(_, l)| !text::is_blank(l))
        .ok_or_else(|| Error::format(at(s.line), "expected a line 'NEl NNodes'"))?;
    let mut t = Tokens::new(l);
    let mut next = |what: &str| {
        let tok = t.next().ok_or_else(|| {
            Error::format(at(n), format!("expected 'NEl NNodes', missing {what}"))
        })?;
        text::parse_u32(tok).map(|v| v as usize).ok_or_else(|| {
            Error::format(
                at(n),
                format!(
                    "expected {what} as a non-negative integer, found {}",
                    text::show(tok)
                ),
            )
        })
    };
    let n_el = next("the element count")?;
    let n_nodes = next("the node count")?;
    Ok((n_el, n_nodes))
}

/// Splits a counted section into its count and the rows that follow.
fn count_line<'a>(s: &RawSection<'a>, file: &str) -> Result<(usize, usize, &'a [u8], usize)> {
    let mut lines = Lines::new(s.body, s.body_line);
    for (n, l) in lines.by_ref() {
        if text::is_blank(l) {
            continue;
        }
        let mut toks = Tokens::new(l);
        let tok = toks.next().unwrap_or_default();
        let count = text::parse_u32(tok).ok_or_else(|| {
            Error::format(
                Location::new(file, n, Some(&format!("$${}", s.keyword))),
                format!("expected the number of entries, found {}", text::show(l)),
            )
        })?;
        let off = lines.offset();
        return Ok((count as usize, n, &s.body[off..], n + 1));
    }
    Err(Error::format(
        Location::new(file, s.line, Some(&format!("$${}", s.keyword))),
        "expected a count line after the keyword",
    ))
}

/// The non-blank lines of `body`, without trailing blanks.
fn text_lines(body: &[u8]) -> Vec<String> {
    Lines::new(body, 1)
        .filter(|(_, l)| !text::is_blank(l))
        .map(|(_, l)| {
            let end = l
                .iter()
                .rposition(|&b| !text::is_separator(b))
                .map_or(0, |e| e + 1);
            String::from_utf8_lossy(&l[..end]).into_owned()
        })
        .collect()
}

/// Splits `body` into pieces of about `PARALLEL_BYTES` at line boundaries, each with the number
/// of its first line.
fn chunks(body: &[u8], first_line: usize) -> Vec<(&[u8], usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    let mut line = first_line;
    while start < body.len() {
        let mut end = (start + PARALLEL_BYTES).min(body.len());
        if end < body.len() {
            end = match memchr::memchr(b'\n', &body[end..]) {
                Some(i) => end + i + 1,
                None => body.len(),
            };
        }
        let piece = &body[start..end];
        out.push((piece, line));
        line += memchr::memchr_iter(b'\n', piece).count();
        start = end;
    }
    out
}

/// Reads `count` lines of exactly `width` values each into one array, in parallel chunks that
/// parse straight into their part of the result. `parse` reads one token (or says what it
/// expected); `what` names a row in messages ("coordinates per node").
fn read_fixed<T, P>(
    s: &RawSection,
    width: usize,
    count: usize,
    file: &str,
    what: (&str, &str),
    parse: P,
) -> Result<Vec<T>>
where
    T: Copy + Default + Send + Sync,
    P: Fn(&[u8]) -> Result<T, String> + Sync,
{
    let sec = format!("$${}", s.keyword);
    let pieces = if s.body.len() > PARALLEL_BYTES {
        chunks(s.body, s.body_line)
    } else {
        vec![(s.body, s.body_line)]
    };
    // Rows per piece first, so each piece knows where its rows go.
    let rows: Vec<usize> = pieces
        .par_iter()
        .map(|(p, _)| Lines::new(p, 1).filter(|(_, l)| !text::is_blank(l)).count())
        .collect();
    let total: usize = rows.iter().sum();
    if total != count {
        return Err(Error::invalid(
            Location::new(file, s.line, Some(&sec)),
            format!(
                "expected {count} {} (from $$STARTCOUNTERS), found {total}",
                what.1
            ),
        ));
    }
    let mut out = vec![T::default(); count * width];
    let mut slices = Vec::with_capacity(pieces.len());
    let mut rest = &mut out[..];
    for &r in &rows {
        let (head, tail) = rest.split_at_mut(r * width);
        slices.push(head);
        rest = tail;
    }
    pieces
        .into_par_iter()
        .zip(slices)
        .try_for_each(|((piece, first), dst)| -> Result<()> {
            let mut k = 0;
            for (n, l) in Lines::new(piece, first) {
                let mut got = 0;
                for tok in Tokens::new(l) {
                    if got == width {
                        got += 1;
                        break;
                    }
                    dst[k + got] = parse(tok)
                        .map_err(|m| Error::format(Location::new(file, n, Some(&sec)), m))?;
                    got += 1;
                }
                if got != 0 && got != width {
                    let found = Tokens::new(l).count();
                    return Err(Error::format(
                        Location::new(file, n, Some(&sec)),
                        format!("expected {width} {}, found {found}", what.0),
                    ));
                }
                k += got;
            }
            Ok(())
        })?;
    Ok(out)
}

/// Reads `count` lines of exactly `width` reals (node coordinates).
fn read_reals(s: &RawSection, width: usize, count: usize, file: &str) -> Result<Vec<f64>> {
    read_fixed(
        s,
        width,
        count,
        file,
        ("coordinates per node", "nodes"),
        |tok| {
            text::parse_real(tok).ok_or_else(|| {
                format!(
                    "expected a coordinate (real number), found {}",
                    text::show(tok)
                )
            })
        },
    )
}

/// Reads `count` lines of exactly `width` 1-based node ids, returned 0-based.
fn read_ids(
    s: &RawSection,
    width: usize,
    count: usize,
    n_nodes: usize,
    file: &str,
) -> Result<Vec<u32>> {
    read_fixed(
        s,
        width,
        count,
        file,
        ("node ids per element", "elements"),
        |tok| {
            let id = text::parse_u32(tok).ok_or_else(|| {
                format!(
                    "expected a node id (positive integer), found {}",
                    text::show(tok)
                )
            })?;
            if id == 0 || id as usize > n_nodes {
                return Err(format!("node id {id} out of range 1..={n_nodes}"));
            }
            Ok(id - 1)
        },
    )
}

/// Reads every non-blank line as a row of tokens; when `refs` is given, checks that the id
/// columns are integers in range.
fn read_rows(
    s: &RawSection,
    file: &str,
    refs: Option<Refs>,
    n_el: usize,
    n_nodes: usize,
) -> Result<Table> {
    let sec = format!("$${}", s.keyword);
    let parse_piece = |(piece, first): (&[u8], usize)| -> Result<Table> {
        let mut t = Table::with_capacity(piece.len() / 4, 2);
        for (n, l) in Lines::new(piece, first) {
            if text::is_blank(l) {
                continue;
            }
            t.push_row(Tokens::new(l).map(Token::parse));
            if let Some(refs) = refs {
                check_ids(t.row(t.len() - 1), refs, n_el, n_nodes)
                    .map_err(|m| Error::invalid(Location::new(file, n, Some(&sec)), m))?;
            }
        }
        Ok(t)
    };
    if s.body.len() > PARALLEL_BYTES {
        let parts: Vec<Table> = chunks(s.body, s.body_line)
            .into_par_iter()
            .map(parse_piece)
            .collect::<Result<_>>()?;
        let mut t = Table::with_capacity(parts.iter().map(Table::len).sum(), 2);
        for p in parts {
            t.append(p);
        }
        Ok(t)
    } else {
        parse_piece((s.body, s.body_line))
    }
}

/// Checks that the columns of `row` that `refs` names hold node or element ids in range.
fn check_ids(row: &[Token], refs: Refs, n_el: usize, n_nodes: usize) -> Result<(), String> {
    let cols = refs.columns();
    let need = cols.iter().map(|c| c.0 + 1).max().unwrap_or(0);
    if row.len() < need {
        return Err(format!(
            "expected at least {need} values with ids in columns {:?}, found {} value(s)",
            cols.iter().map(|c| c.0 + 1).collect::<Vec<_>>(),
            row.len()
        ));
    }
    for (c, kind) in cols {
        let (max, what) = match kind {
            IdKind::Node => (n_nodes, "node"),
            IdKind::Element => (n_el, "element"),
        };
        match &row[c] {
            Token::Int(i) if *i >= 1 && (*i as usize) <= max => {}
            Token::Int(i) => return Err(format!("{what} id {i} out of range 1..={max}")),
            other => {
                return Err(format!(
                    "expected a {what} id (integer) in column {}, found {}",
                    c + 1,
                    token_text(other)
                ))
            }
        }
    }
    Ok(())
}

/// `t` as it reads in a message.
fn token_text(t: &Token) -> String {
    let mut v = Vec::new();
    t.push_to(&mut v);
    format!("'{}'", String::from_utf8_lossy(&v))
}

/// Writes a model in GOM layout to memory.
pub fn write(model: &Model) -> Vec<u8> {
    let mut out = Vec::with_capacity(model.coords.len() * 20 + model.connectivity.len() * 8 + 4096);
    write_to(model, &mut out).expect("writing to memory cannot fail");
    out
}

/// Bytes collected before they are handed to the writer.
const FLUSH_BYTES: usize = 1 << 20;

/// Rows per parallel formatting task.
const WRITE_CHUNK: usize = 1 << 14;

/// Buffers small pieces and streams large sections to the writer in order.
struct Sink<'w> {
    w: &'w mut dyn Write,
    buf: Vec<u8>,
    /// Chunk buffers reused from batch to batch: fresh megabyte allocations would be returned
    /// to the system and page-faulted in again every time.
    pool: Vec<Vec<u8>>,
}

impl Sink<'_> {
    /// Buffers `bytes`, writing the buffer out once it is large.
    fn put(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.buf.extend_from_slice(bytes);
        if self.buf.len() >= FLUSH_BYTES {
            self.flush()?;
        }
        Ok(())
    }

    /// Writes the buffer out.
    fn flush(&mut self) -> io::Result<()> {
        self.w.write_all(&self.buf)?;
        self.buf.clear();
        Ok(())
    }

    /// Formats rows `0..n` in parallel chunks of `WRITE_CHUNK` with `fmt` and writes them in
    /// order; a batch of chunks at a time keeps memory bounded.
    fn rows<F>(&mut self, n: usize, fmt: F) -> io::Result<()>
    where
        F: Fn(std::ops::Range<usize>, &mut Vec<u8>) + Sync,
    {
        if n <= WRITE_CHUNK {
            let mut b = std::mem::take(&mut self.buf);
            fmt(0..n, &mut b);
            self.buf = b;
            return if self.buf.len() >= FLUSH_BYTES {
                self.flush()
            } else {
                Ok(())
            };
        }
        self.flush()?;
        let chunks = n.div_ceil(WRITE_CHUNK);
        let batch = 4 * rayon::current_num_threads().max(1);
        if self.pool.len() < batch {
            self.pool
                .resize_with(batch, || Vec::with_capacity(WRITE_CHUNK * 64));
        }
        for first in (0..chunks).step_by(batch) {
            let count = batch.min(chunks - first);
            self.pool[..count]
                .par_iter_mut()
                .enumerate()
                .for_each(|(j, b)| {
                    let c = first + j;
                    b.clear();
                    fmt(c * WRITE_CHUNK..((c + 1) * WRITE_CHUNK).min(n), b);
                });
            for b in &self.pool[..count] {
                self.w.write_all(b)?;
            }
        }
        Ok(())
    }
}

/// Writes a model in GOM layout, streaming: large sections are formatted in parallel batches
/// and written in order, so the bytes do not depend on the number of threads.
pub fn write_to(model: &Model, w: &mut dyn Write) -> io::Result<()> {
    let eol = model.line_ending.bytes();
    let mut out = Sink {
        w,
        buf: Vec::with_capacity(FLUSH_BYTES + 4096),
        pool: Vec::new(),
    };
    let line = |out: &mut Sink, l: &[u8]| -> io::Result<()> {
        out.put(l)?;
        out.put(eol)
    };
    line(&mut out, model.version.as_bytes())?;
    for s in &model.sections {
        out.put(b"$$")?;
        line(&mut out, s.keyword.as_bytes())?;
        match &s.body {
            Body::Dimension => line(&mut out, model.dimension.keyword().as_bytes())?,
            Body::ElementType => line(&mut out, model.element_type.keyword().as_bytes())?,
            Body::Counters => {
                let mut b = Vec::new();
                text::push_int(&mut b, model.element_count());
                b.push(b' ');
                text::push_int(&mut b, model.node_count());
                line(&mut out, &b)?;
            }
            Body::Nodes => {
                let d = model.dimension.coords();
                out.rows(model.node_count(), |r, b| {
                    for node in model.coords[r.start * d..r.end * d].chunks_exact(d) {
                        for (j, &c) in node.iter().enumerate() {
                            if j > 0 {
                                b.push(b' ');
                            }
                            text::push_real(b, c);
                        }
                        b.extend_from_slice(eol);
                    }
                })?
            }
            Body::Connectivity => {
                let per = model.element_type.nodes();
                out.rows(model.element_count(), |r, b| {
                    for el in model.connectivity[r.start * per..r.end * per].chunks_exact(per) {
                        for (j, &id) in el.iter().enumerate() {
                            if j > 0 {
                                b.push(b' ');
                            }
                            text::push_int(b, id + 1);
                        }
                        b.extend_from_slice(eol);
                    }
                })?
            }
            Body::Table { counted, rows, .. } => {
                if *counted {
                    let mut b = Vec::new();
                    text::push_int(&mut b, rows.len());
                    line(&mut out, &b)?;
                }
                write_rows(&mut out, rows, eol)?;
            }
            Body::PerElement(rows) => write_rows(&mut out, rows, eol)?,
            Body::Text(lines) | Body::Opaque(lines) => {
                for l in lines {
                    line(&mut out, l.as_bytes())?;
                }
            }
        }
    }
    line(&mut out, b"$$FINISH")?;
    out.flush()
}

/// Writes the rows of a table, values separated by one blank, each row ended by `eol`.
fn write_rows(out: &mut Sink, rows: &Table, eol: &[u8]) -> io::Result<()> {
    out.rows(rows.len(), |r, b| {
        for i in r {
            for (j, t) in rows.row(i).iter().enumerate() {
                if j > 0 {
                    b.push(b' ');
                }
                t.push_to(b);
            }
            b.extend_from_slice(eol);
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "### Anura3D_2021 ###   \n$$DIMENSION\n2D-plane_strain\n$$ELEMENTTYPE\ntriangular_3-noded\n$$FORMULATION\nsingle-point\n$$STARTCOUNTERS\n2 4\n$$STARTNODES\n0 0\n1.0 0\n1 1\n0 1\n$$STARTELEMCON\n1 2 3\n1 3 4\n$$START_FIXITY_LINE_SOLID\n2\n1 1 1\n2 0 1\n$$START_BODY_CONTACT_2D\n1\n2 1 \"Column\" 0.2 0.0 \"NAN\" 0.0 0.0\n$$NUMBER_OF_MATERIALS\n1\n$$MATERIAL_INDEX\n1\n$$MATERIAL_NAME\nSandy soil\n$$MATERIAL_TYPE\ndry_material\n$$YOUNG_MODULUS\n1.0E+004\n$$STARTELMMAT\n1\n1\n$$START_NUMBER_OF_MATERIAL_POINTS\n3 0\n3 0\n\n$$FINISH\n";

    #[test]
    fn reads_a_small_model() {
        let m = read(SMALL.as_bytes(), "small.gom").unwrap();
        assert_eq!(m.version, "### Anura3D_2021 ###");
        assert_eq!(m.node_count(), 4);
        assert_eq!(m.element_count(), 2);
        assert_eq!(m.element(1), &[0, 2, 3]);
        assert_eq!(m.node(1), &[1.0, 0.0]);
        let fix = m.table("START_FIXITY_LINE_SOLID").unwrap();
        assert_eq!(fix.row(1), &[Token::Int(2), Token::Int(0), Token::Int(1)]);
        let mats = m.materials();
        assert_eq!(mats.len(), 1);
        assert_eq!(mats[0].name, "Sandy soil");
        assert_eq!(mats[0].get_f64("YOUNG_MODULUS"), Some(1e4));
        assert_eq!(m.material_points_per_element(), Some(vec![3, 3]));
        assert_eq!(m.first_unremappable(), None);
    }

    #[test]
    fn round_trips_and_writes_deterministically() {
        let m = read(SMALL.as_bytes(), "small.gom").unwrap();
        let w1 = write(&m);
        let m2 = read(&w1, "w1").unwrap();
        assert_eq!(m, m2);
        assert_eq!(w1, write(&m2));
        let s = String::from_utf8(w1).unwrap();
        assert!(s.starts_with("### Anura3D_2021 ###\n$$DIMENSION\n2D-plane_strain\n"));
        assert!(s.contains("$$STARTNODES\n0.0 0.0\n1.0 0.0\n"));
        assert!(s.contains("$$START_FIXITY_LINE_SOLID\n2\n1 1 1\n2 0 1\n"));
        assert!(s.contains("2 1 \"Column\" 0.2 0.0 \"NAN\" 0.0 0.0\n"));
        assert!(s.ends_with("3 0\n$$FINISH\n"));
    }

    #[test]
    fn keeps_crlf() {
        let crlf = SMALL.replace('\n', "\r\n");
        let m = read(crlf.as_bytes(), "crlf.gom").unwrap();
        assert_eq!(m.line_ending, LineEnding::CrLf);
        let w = write(&m);
        assert!(w.ends_with(b"$$FINISH\r\n"));
        assert_eq!(read(&w, "w").unwrap(), m);
    }

    fn err(src: &str) -> String {
        read(src.as_bytes(), "bad.gom").unwrap_err().to_string()
    }

    #[test]
    fn errors_name_file_line_and_section() {
        let e = err(&SMALL.replace("1 3 4\n", "1 3 9\n"));
        assert!(
            e.contains("bad.gom:17 (in $$STARTELEMCON): node id 9 out of range"),
            "{e}"
        );
        let e = err(&SMALL.replace("1.0 0\n", "1.0 x\n"));
        assert!(e.contains("bad.gom:12 (in $$STARTNODES)"), "{e}");
        let e = err(&SMALL.replace("$$FINISH\n", ""));
        assert!(e.contains("without '$$FINISH'"), "{e}");
        let e = err(&SMALL.replace("2\n1 1 1\n", "3\n1 1 1\n"));
        assert!(e.contains("count line says 3 entries, found 2"), "{e}");
        let e = err(&SMALL.replace("2 0 1\n", "5 0 1\n"));
        assert!(e.contains("node id 5 out of range 1..=4"), "{e}");
        let e = err(&SMALL.replace("2 4\n", "3 4\n"));
        assert!(e.contains("expected 3 elements"), "{e}");
        let e = err(&SMALL.replace("triangular_3-noded", "quadrilateral_4-noded"));
        assert!(e.contains("unsupported"), "{e}");
        let e = err("hello\n");
        assert!(e.contains("version line"), "{e}");
    }

    #[test]
    fn unknown_sections_are_kept_and_flagged() {
        let src = SMALL.replace("$$FINISH", "$$SOMETHING_NEW\n3 4 5\n$$FINISH");
        let m = read(src.as_bytes(), "x").unwrap();
        assert_eq!(m.first_unremappable(), Some("SOMETHING_NEW"));
        let w = String::from_utf8(write(&m)).unwrap();
        assert!(w.contains("$$SOMETHING_NEW\n3 4 5\n$$FINISH"));
    }
}
