//! Material-point identity across element reorderings.
//!
//! Anura3D numbers material points element by element in the GOM's element order: element 1's
//! points are 1..n1, element 2's follow, and so on. A point's id is meant to be a property of the
//! input case, not of the element order, so [`crate::Model::reordered`] records each element's
//! number in the original input in the per-element section [`INPUT_ELEMENTS`] (composing with an
//! existing one, so chained reorders keep the original numbers). Input ids count the points in
//! that original order; file ids count them in the order the elements stand in the file, as
//! Anura3D does. [`PointIds`] converts between the two.
//!
//! A CPS whose `$$OUTPUT_MATERIAL_POINTS` were remapped to file ids (`sfcb --cps`, so that
//! Anura3D itself picks the same points in the ordered GOM) says so with the key
//! [`CPS_FILE_ORDER`]: its value names the element count and the [`checksum`] of the input
//! numbers of the GOM it was remapped for, so that a mismatched pair is refused.

use crate::error::{Error, Location, Result};
use crate::model::{Body, Model, Table, Token};

pub use crate::cps::CPS_FILE_ORDER;
pub use crate::model::INPUT_ELEMENTS;

/// Checks that `rows` (one row per element) give every element one distinct input number in
/// `1..=rows.len()`; returns the 0-based input element of each element, or the first problem
/// (row number 1-based, message).
pub fn parse_input_elements(rows: &Table) -> std::result::Result<Vec<u32>, (usize, String)> {
    let n = rows.len();
    let mut out = Vec::with_capacity(n);
    let mut owner = vec![u32::MAX; n];
    for (e, r) in rows.rows().enumerate() {
        let v = match r {
            [Token::Int(v)] if *v >= 1 && (*v as usize) <= n => *v as usize,
            _ => {
                return Err((
                    e + 1,
                    format!("expected one input element number in 1..={n} per element"),
                ))
            }
        };
        if owner[v - 1] != u32::MAX {
            return Err((
                e + 1,
                format!(
                    "input element number {v} is also given to element {}",
                    owner[v - 1] + 1
                ),
            ));
        }
        owner[v - 1] = e as u32;
        out.push(v as u32 - 1);
    }
    Ok(out)
}

impl Model {
    /// The 0-based original input element of each element, from [`INPUT_ELEMENTS`]; `None`
    /// when the model carries no such section (its element order is then the input's).
    pub fn input_elements(&self) -> Result<Option<Vec<u32>>> {
        let Some(rows) = self.per_element(INPUT_ELEMENTS) else {
            return Ok(None);
        };
        parse_input_elements(rows).map(Some).map_err(|(row, m)| {
            Error::invalid(
                Location::new("", 0, Some(&format!("$${INPUT_ELEMENTS}"))),
                format!("row {row}: {m}"),
            )
        })
    }

    /// Records `input_of` (0-based original input element of each element) as the
    /// [`INPUT_ELEMENTS`] section, replacing an existing one or adding it at the end.
    pub fn set_input_elements(&mut self, input_of: &[u32]) {
        let mut rows = Table::with_capacity(input_of.len(), 1);
        for &k in input_of {
            rows.push_row([Token::Int(k as i64 + 1)]);
        }
        match self.section_mut(INPUT_ELEMENTS) {
            Some(s) => s.body = Body::PerElement(rows),
            None => self.sections.push(crate::model::Section {
                keyword: INPUT_ELEMENTS.into(),
                body: Body::PerElement(rows),
            }),
        }
    }
}

/// A fingerprint of an input-element map (FNV-1a over the numbers), so that a CPS remapped for
/// one ordered GOM is not used with another.
pub fn checksum(input_of: &[u32]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &k in input_of {
        for b in k.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// The value line of [`CPS_FILE_ORDER`] for a GOM with this input-element map:
/// `ELEMENTS CHECKSUM` (numbers only, so Anura3D's CPS reader passes over it silently).
pub fn file_order_tag(input_of: &[u32]) -> String {
    format!("{} {}", input_of.len(), checksum(input_of))
}

/// The material points a CPS names (`$$OUTPUT_MATERIAL_POINTS`) as input ids of `model`.
///
/// Unmarked ids already are input ids. Ids marked with [`CPS_FILE_ORDER`] are file ids of the
/// ordered GOM the marker describes: they are converted through `model`'s
/// [`INPUT_ELEMENTS`], and refused when `model` is not that GOM (no section, or another one),
/// since the points they mean cannot then be recovered.
pub fn cps_input_ids(cps: &crate::cps::Cps, model: &Model) -> Result<Vec<u32>> {
    let ids = cps.output_material_points()?;
    let Some(marker) = cps.get(CPS_FILE_ORDER) else {
        return Ok(ids);
    };
    let at = Location::new(&cps.file, marker.line, Some(&format!("$${CPS_FILE_ORDER}")));
    let input_of = model.input_elements()?;
    let Some(input_of) = input_of else {
        return Err(Error::invalid(
            at,
            "the material-point ids were remapped (sfcb --cps) for an ordered GOM, but this GOM carries no $$START_INPUT_ELEMENT_NUMBERS; use the GOM sfcb wrote with this CPS, or the CPS from before sfcb --cps",
        ));
    };
    let tag = file_order_tag(&input_of);
    let given = marker.lines.first().map(|l| l.trim()).unwrap_or("");
    if given != tag {
        return Err(Error::invalid(
            at,
            format!(
                "the material-point ids were remapped (sfcb --cps) for another ordered GOM (tag '{given}', this GOM's is '{tag}'); use the GOM sfcb wrote with this CPS, or the CPS from before sfcb --cps"
            ),
        ));
    }
    let points = model.material_points_per_element().ok_or_else(|| {
        Error::invalid(
            at.clone(),
            "the GOM has no $$START_NUMBER_OF_MATERIAL_POINTS to number its material points",
        )
    })?;
    let numbering = PointIds::new(&points, Some(&input_of));
    ids.iter()
        .map(|&id| {
            numbering.to_input(id).ok_or_else(|| {
                Error::invalid(
                    at.clone(),
                    format!(
                        "$$OUTPUT_MATERIAL_POINTS names material point {id}, but the GOM has {}",
                        numbering.total()
                    ),
                )
            })
        })
        .collect()
}

/// Sets `cps`'s `$$OUTPUT_MATERIAL_POINTS` to the file ids, in `model`, of the points with input
/// ids `input_ids`, so that Anura3D picks the same points in `model`; marks them with
/// [`CPS_FILE_ORDER`] when `model` carries [`INPUT_ELEMENTS`] (without it, file ids are input
/// ids and no mark is needed).
pub fn remap_cps(cps: &mut crate::cps::Cps, input_ids: &[u32], model: &Model) -> Result<()> {
    let at = Location::new(&cps.file, 0, Some("$$OUTPUT_MATERIAL_POINTS"));
    let points = model.material_points_per_element().ok_or_else(|| {
        Error::invalid(
            at.clone(),
            "the GOM has no $$START_NUMBER_OF_MATERIAL_POINTS to number its material points",
        )
    })?;
    let input_of = model.input_elements()?;
    let numbering = PointIds::new(&points, input_of.as_deref());
    let ids = input_ids
        .iter()
        .map(|&id| {
            numbering.to_file(id).ok_or_else(|| {
                Error::invalid(
                    at.clone(),
                    format!(
                        "names material point {id}, but the mesh has {}",
                        numbering.total()
                    ),
                )
            })
        })
        .collect::<Result<Vec<u32>>>()?;
    cps.set_output_material_points(&ids);
    match &input_of {
        Some(m) => cps.set(CPS_FILE_ORDER, vec![file_order_tag(m)]),
        None => cps.remove(CPS_FILE_ORDER),
    }
    Ok(())
}

/// Converts material-point ids between file order and original input order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PointIds {
    /// Points before each element in file order.
    file_first: Vec<u64>,
    /// Points before each element (indexed by file position) in input order.
    input_first: Vec<u64>,
    /// Points before each input element (indexed by input position) in input order.
    input_first_by_input: Vec<u64>,
    /// File position of each input element.
    file_of_input: Vec<u32>,
    /// All points.
    total: u64,
}

impl PointIds {
    /// The numbering of `points[e]` points per element `e` (file order), whose original input
    /// element is `input_of[e]` (0-based; `None`: the file order is the input's). `input_of`
    /// must be a permutation (as [`Model::input_elements`] returns).
    pub fn new(points: &[u32], input_of: Option<&[u32]>) -> PointIds {
        let n = points.len();
        let file_of_input: Vec<u32> = match input_of {
            Some(m) => {
                let mut f = vec![0u32; n];
                for (e, &k) in m.iter().enumerate() {
                    f[k as usize] = e as u32;
                }
                f
            }
            None => (0..n as u32).collect(),
        };
        let mut file_first = Vec::with_capacity(n);
        let mut acc = 0u64;
        for &p in points {
            file_first.push(acc);
            acc += p as u64;
        }
        let mut input_first = vec![0u64; n];
        let mut input_first_by_input = Vec::with_capacity(n);
        let mut acc = 0u64;
        for &e in &file_of_input {
            input_first[e as usize] = acc;
            input_first_by_input.push(acc);
            acc += points[e as usize] as u64;
        }
        PointIds {
            file_first,
            input_first,
            input_first_by_input,
            file_of_input,
            total: acc,
        }
    }

    /// Number of points.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// Points before element `e` (file position) in input order: its first point's input id
    /// is this plus 1.
    pub fn input_first(&self, e: usize) -> u64 {
        self.input_first[e]
    }

    /// The input id of the point with file id `id` (1-based); `None` if there is no such point.
    pub fn to_input(&self, id: u32) -> Option<u32> {
        let k = (id as u64).checked_sub(1).filter(|&k| k < self.total)?;
        // The last element starting at or before k holds it (empty elements start where the
        // next one does).
        let e = self.file_first.partition_point(|&f| f <= k) - 1;
        Some((self.input_first[e] + k - self.file_first[e] + 1) as u32)
    }

    /// The file id of the point with input id `id` (1-based); `None` if there is no such point.
    pub fn to_file(&self, id: u32) -> Option<u32> {
        let k = (id as u64).checked_sub(1).filter(|&k| k < self.total)?;
        let i = self.input_first_by_input.partition_point(|&f| f <= k) - 1;
        let e = self.file_of_input[i] as usize;
        Some((self.file_first[e] + k - self.input_first_by_input[i] + 1) as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_convert_both_ways_with_empty_elements() {
        // File order: elements with 4, 0, 1, 4 points; input order 3, 1, 4, 2 (1-based).
        let points = [4, 0, 1, 4];
        let input_of = [2, 0, 3, 1];
        let ids = PointIds::new(&points, Some(&input_of));
        assert_eq!(ids.total(), 9);
        // Input order: file element 2 (0 points), file 4 (4), file 1 (4), file 3 (1).
        let want = [5, 6, 7, 8, 9, 1, 2, 3, 4];
        for (f, &i) in want.iter().enumerate() {
            assert_eq!(ids.to_input(f as u32 + 1), Some(i), "file id {}", f + 1);
            assert_eq!(ids.to_file(i), Some(f as u32 + 1));
        }
        assert_eq!(ids.to_input(0), None);
        assert_eq!(ids.to_input(10), None);
        assert_eq!(ids.to_file(10), None);
        assert_eq!(ids.input_first(0), 4);
        let plain = PointIds::new(&points, None);
        assert!((1..=9).all(|i| plain.to_input(i) == Some(i) && plain.to_file(i) == Some(i)));
    }

    #[test]
    fn input_numbers_must_be_a_permutation() {
        let table = |v: &[i64]| {
            let mut t = Table::new();
            for &x in v {
                t.push_row([Token::Int(x)]);
            }
            t
        };
        assert_eq!(parse_input_elements(&table(&[2, 3, 1])), Ok(vec![1, 2, 0]));
        let e = parse_input_elements(&table(&[2, 2, 1])).unwrap_err();
        assert_eq!(e.0, 2);
        assert!(e.1.contains("also given to element 1"), "{}", e.1);
        assert_eq!(parse_input_elements(&table(&[1, 4, 2])).unwrap_err().0, 2);
    }

    /// A permutation of `0..n` from a seed (a linear congruential shuffle).
    fn shuffle(n: usize, mut seed: u64) -> Vec<u32> {
        let mut v: Vec<u32> = (0..n as u32).collect();
        for i in (1..n).rev() {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            v.swap(i, (seed >> 33) as usize % (i + 1));
        }
        v
    }

    #[test]
    fn input_numbers_compose_through_two_reorders_and_a_file() {
        let model = crate::generate::box_mesh([3, 2, 2], [1.0; 3], crate::ElementType::Tet4);
        let n = model.element_count();
        assert_eq!(model.input_elements().unwrap(), None);
        let nodes = model.node_count();
        let (o1, o2) = (shuffle(n, 1), shuffle(n, 2));
        let once = model.reordered(&o1, &shuffle(nodes, 3)).unwrap();
        assert_eq!(once.input_elements().unwrap().as_deref(), Some(&o1[..]));
        let twice = once.reordered(&o2, &shuffle(nodes, 4)).unwrap();
        // Element e of the second result is element o2[e] of the first, which was input
        // element o1[o2[e]].
        let want: Vec<u32> = o2.iter().map(|&e| o1[e as usize]).collect();
        assert_eq!(twice.input_elements().unwrap().as_deref(), Some(&want[..]));
        // The same elements stand where the input had them.
        for (e, &k) in want.iter().enumerate() {
            let corners = |m: &Model, e: usize| {
                let mut c: Vec<Vec<u64>> = m
                    .element(e)
                    .iter()
                    .map(|&i| m.node(i as usize).iter().map(|x| x.to_bits()).collect())
                    .collect();
                c.sort();
                c
            };
            assert_eq!(corners(&twice, e), corners(&model, k as usize));
        }
        // The section survives a write and a read, and a bad one is refused with its line.
        let text = crate::gom::write(&twice);
        let back = crate::gom::read(&text, "t.GOM").unwrap();
        assert_eq!(back.input_elements().unwrap().as_deref(), Some(&want[..]));
        let s = String::from_utf8(text).unwrap();
        let at = s.find("$$START_INPUT_ELEMENT_NUMBERS\n").unwrap();
        let mut bad = s.clone();
        let first = &s[at..].lines().nth(1).unwrap().to_string();
        let other = if first == "1" { "2" } else { "1" };
        let line_start = at + "$$START_INPUT_ELEMENT_NUMBERS\n".len();
        bad.replace_range(line_start..line_start + first.len(), other);
        let e = crate::gom::read(bad.as_bytes(), "t.GOM")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("t.GOM:")
                && e.contains("$$START_INPUT_ELEMENT_NUMBERS")
                && e.contains("also given to element"),
            "{e}"
        );
    }

    #[test]
    fn checksum_tells_maps_apart() {
        assert_ne!(checksum(&[0, 1, 2]), checksum(&[0, 2, 1]));
        assert_eq!(file_order_tag(&[1, 0]), format!("2 {}", checksum(&[1, 0])));
    }
}
