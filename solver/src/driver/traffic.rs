//! Modelled memory traffic of a step, per phase, in bytes per particle-step: what each phase
//! must read and write at least, for the roofline (`run.json`'s `modelled_bytes_per_particle_step`,
//! docs/design.md §9).
//!
//! The point arrays come from the one field list ([`Particles::read_fields`]) and a table of
//! which phase reads or rewrites which field, so a field added to the list is counted by
//! every phase that names it. Element data (map, gradients, corners, volume) are read once per
//! element and shared by its points; a parallel sum writes the slots of the element corners at
//! the threads' borders and reads them back (W values per slot, [`crate::parallel::gather`]),
//! and the other nodes' accumulators once each way; nodal arrays are counted once per node;
//! nodal values gathered by a point are taken as cache hits (a node's neighbours read it in
//! turn). The re-sort after points change element is left out: it moves every field, but only
//! when points have moved, not every step.

use crate::element::Element;
use crate::real::{Real, V3};
use crate::state::particles::{Field, FieldReader, Particles, Value};

/// How a phase touches a point array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Access {
    Read,
    ReadWrite,
}

use Access::{Read, ReadWrite};

/// The point arrays each phase of [`crate::driver::engine::PHASES`] touches (by the field
/// list's names); arrays a case does not have are skipped.
const PHASE_FIELDS: [&[(&str, Access)]; 5] = [
    // particle to grid: both phases' mass, momentum and forces
    &[
        ("x", Read),
        ("v", Read),
        ("mass", Read),
        ("volume", Read),
        ("stress", Read),
        ("material", Read),
        ("active", Read),
        ("p", Read),
        ("w", Read),
        ("volume0", Read),
        ("bulk_pressure", Read),
    ],
    // grid update: nodes only
    &[],
    // grid to particle: velocities updated and remapped
    &[
        ("x", Read),
        ("mass", Read),
        ("volume", Read),
        ("material", Read),
        ("active", Read),
        ("volume0", Read),
        ("v", ReadWrite),
        ("w", ReadWrite),
    ],
    // stress: pore pressure, strain, law, volume and position, guard sums
    &[
        ("element", Read),
        ("material", Read),
        ("active", Read),
        ("mass", Read),
        ("x", ReadWrite),
        ("u", ReadWrite),
        ("stress", ReadWrite),
        ("volume", ReadWrite),
        ("state", ReadWrite),
        ("p", ReadWrite),
        // Written only: formed from the strain.
        ("bulk_pressure", ReadWrite),
        ("bulk_rate", ReadWrite),
    ],
    // locate: the walk from the old element
    &[("x", Read), ("active", Read), ("element", ReadWrite)],
];

/// Bytes of the point arrays `fields` names, per point (a rewritten array twice).
fn point_bytes<R: Real>(p: &Particles<R>, fields: &[(&str, Access)]) -> usize {
    struct Count<'a> {
        fields: &'a [(&'a str, Access)],
        bytes: usize,
    }
    impl FieldReader for Count<'_> {
        fn field<T: Value>(&mut self, field: Field, _: &[T]) {
            if let Some((_, access)) = self.fields.iter().find(|(n, _)| *n == field.name) {
                let times = if *access == ReadWrite { 2 } else { 1 };
                self.bytes += times * std::mem::size_of::<T>() * field.per_point;
            }
        }
    }
    let mut c = Count { fields, bytes: 0 };
    p.read_fields(&mut c);
    c.bytes
}

/// The modelled bytes per particle-step of each phase of a case with `p`'s points on a mesh of
/// `elements` elements of type `E` and `nodes` nodes, of whose element corners the share
/// `slot_share` sums through the slots ([`crate::parallel::gather::Layout::slot_share`]).
pub fn modelled_bytes<R: Real, E: Element>(
    p: &Particles<R>,
    elements: usize,
    nodes: usize,
    slot_share: f64,
) -> [f64; 5] {
    let s = std::mem::size_of::<R>();
    let liquid = p.liquid.is_some();
    let points = p.len().max(1) as f64;
    // Per element: map, gradients, corners and volume; shared by the element's points.
    let element = (std::mem::size_of::<E::Map<R>>()
        + E::NODES * (std::mem::size_of::<V3<R>>() + 4)
        + s) as f64
        * elements as f64
        / points;
    // A sum `width` values wide: the border corners' slots written, then read back; the other
    // nodes' accumulators (as many values per node) likewise, once per node.
    let slots = |width: usize| {
        let border = (2 * E::NODES * width * s) as f64 * elements as f64 * slot_share;
        let direct = (2 * width * s) as f64 * nodes as f64 * (1.0 - slot_share);
        (border + direct) / points
    };
    let per_node = |bytes: f64| bytes * nodes as f64 / points;
    let (d, v) = (E::DIM, 3 * s);
    let both = |dry: f64, wet: f64| if liquid { dry + wet } else { dry };
    let points_of = |k: usize| point_bytes(p, PHASE_FIELDS[k]) as f64;
    [
        // particle to grid: slots; mass, momentum, f_int, f_ext written (the liquid adds its
        // masses, drag, momentum, force, and its weight to f_ext)
        points_of(0)
            + both(element, element)
            + both(slots(1 + 3 * d), slots(3 + 3 * d))
            + per_node(both((s + 3 * v) as f64, (3 * s + 2 * v + 2 * v) as f64)),
        // grid update: mass, momentum, forces, loads and fixities read, acceleration written
        per_node(both((s + 5 * v + 3) as f64, (3 * s + 3 * v + 3 + v) as f64)),
        // grid to particle: slots of the remap; the nodal velocity written from mass and
        // fixities
        points_of(2)
            + both(element, element)
            + both(slots(d), slots(d))
            + per_node(both((s + 3 + v) as f64, (s + 3 + v) as f64)),
        // stress: element data; the pore-pressure rate's slots; the step's nodal energy terms
        // (mass, momentum, velocity, acceleration, forces, loads, fixities)
        points_of(3)
            + element
            + if liquid { element + slots(2) } else { 0.0 }
            + per_node(both((s + 6 * v + 3) as f64, (2 * s + 4 * v + 3) as f64)),
        // locate
        points_of(4) + element,
    ]
}

/// The point arrays grid to particle's re-mapping and the pore-rate smoothing read again on
/// a basis of its own (their passes visit points by owner computes).
const REMAP_FIELDS: &[(&str, Access)] = &[
    ("x", Read),
    ("v", Read),
    ("w", Read),
    ("mass", Read),
    ("material", Read),
    ("active", Read),
];
const SMOOTH_FIELDS: &[(&str, Access)] = &[
    ("x", Read),
    ("volume", Read),
    ("material", Read),
    ("active", Read),
];

/// What the stencil passes of a basis of its own read besides the points
/// ([`crate::basis::background::Background`]), for [`modelled_bytes_stencil`].
#[derive(Debug, Clone, Copy)]
pub struct StencilTables {
    /// Element visits per element of a pass by owner computes (1 plus the threads' halo,
    /// [`crate::parallel::reach::Reach::halo_share`]).
    pub visits: f64,
    /// Bytes of the stencil's per-element tables in all the elements.
    pub element_bytes: usize,
    /// Bytes of the stencil's per-node tables in all the nodes.
    pub node_bytes: usize,
    /// Whether a stencil evaluates the element's own map (the dual-domain gradients' weights
    /// are the element's shape functions; a grid's come from the position alone).
    pub element_map: bool,
    /// Whether the pore-pressure rate is smoothed through the nodes (a saturated grid case).
    pub smoothed_rate: bool,
}

/// The modelled bytes per particle-step of each phase of a case whose points map with a basis
/// of its own (a background grid or the dual-domain gradients), on a mesh of `elements`
/// elements of type `E` and `nodes` nodes. The stencil passes keep no slots: each thread sums
/// its own nodes, visiting every point within reach of them, so the points near a thread's
/// border are read by both threads beside it (`t.visits`), and each node's accumulators are
/// read and written once. A stencil's weights come from the point's position (and on the
/// dual-domain gradients its element's map and tables, once per element visited); its
/// nodes' tables are gathered and counted once per node per pass. Locate walks the mesh's
/// elements as [`modelled_bytes`] counts.
pub fn modelled_bytes_stencil<R: Real, E: Element>(
    p: &Particles<R>,
    elements: usize,
    nodes: usize,
    t: StencilTables,
) -> [f64; 5] {
    let s = std::mem::size_of::<R>();
    let liquid = p.liquid.is_some();
    let points = p.len().max(1) as f64;
    let per_point = |bytes: f64| bytes / points;
    let map = if t.element_map {
        std::mem::size_of::<E::Map<R>>() as f64 * elements as f64
    } else {
        0.0
    };
    // Per evaluation of every point's stencil: the element tables, then the node tables.
    let element = per_point(map + t.element_bytes as f64);
    let node_tables = per_point(t.node_bytes as f64);
    let walk = per_point(
        ((std::mem::size_of::<E::Map<R>>() + E::NODES * (std::mem::size_of::<V3<R>>() + 4) + s)
            * elements) as f64,
    );
    // A node's accumulators `width` values wide, read and written once.
    let direct = |width: usize| per_point((2 * width * s * nodes) as f64);
    let per_node = |bytes: f64| bytes * nodes as f64 / points;
    let (d, v) = (E::DIM, 3 * s);
    let both = |dry: f64, wet: f64| if liquid { dry + wet } else { dry };
    let fields = |f: &[(&str, Access)]| point_bytes(p, f) as f64;
    let smoothing = if liquid && t.smoothed_rate {
        (fields(SMOOTH_FIELDS) + element) * t.visits + node_tables + direct(2)
    } else {
        0.0
    };
    [
        // particle to grid: the points within reach of each thread's nodes, the accumulators
        (fields(PHASE_FIELDS[0]) + both(element, 0.0)) * t.visits
            + node_tables
            + both(direct(1 + 3 * d), direct(3 + 3 * d))
            + per_node(both((s + 3 * v) as f64, (3 * s + 2 * v + 2 * v) as f64)),
        // grid update: as on the elements
        per_node(both((s + 5 * v + 3) as f64, (3 * s + 3 * v + 3 + v) as f64)),
        // grid to particle: each point once (velocities), then the re-mapping by owner
        // computes
        fields(PHASE_FIELDS[2])
            + element
            + (fields(REMAP_FIELDS) + element) * t.visits
            + 2.0 * node_tables
            + both(direct(d), direct(d))
            + per_node(both((s + 3 + v) as f64, (s + 3 + v) as f64)),
        // stress: each point's stencil once; the smoothed pore-pressure rate
        fields(PHASE_FIELDS[3])
            + element
            + node_tables
            + smoothing
            + per_node(both((s + 6 * v + 3) as f64, (2 * s + 4 * v + 3) as f64)),
        // locate
        fields(PHASE_FIELDS[4]) + walk,
    ]
}

/// [`modelled_bytes`] of a run that locates its points in the stress pass (docs/design.md
/// §4.10): the stress pass also rewrites the element numbers it reads, and the locate phase
/// moves no point data of its own (its re-sort is left out, as above).
pub fn locating_in_stress(mut bytes: [f64; 5]) -> [f64; 5] {
    bytes[3] += std::mem::size_of::<u32>() as f64;
    bytes[4] = 0.0;
    bytes
}

/// [`modelled_bytes`] of a two-phase run whose pore-pressure rate takes its weights from
/// particle to grid ([`crate::state::pore_weights`]), for `elements` elements and `points`
/// points: particle to grid writes each element's Σ V N_k (four reals) and material (a u32),
/// and the rate's pass (in the stress phase) reads them back.
pub fn with_pore_weights<R: Real>(mut bytes: [f64; 5], elements: usize, points: usize) -> [f64; 5] {
    let per_element = 4 * std::mem::size_of::<R>() + std::mem::size_of::<u32>();
    let per_point = (per_element * elements) as f64 / points.max(1) as f64;
    bytes[0] += per_point;
    bytes[3] += per_point;
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tet4::Tet4;
    use crate::element::tri3::Tri3;

    fn points(n: usize, liquid: bool) -> Particles<f64> {
        let mut p = Particles::<f64>::at_rest(vec![0; n]);
        if liquid {
            p.add_liquid(|_| 0.0, false);
        }
        p
    }

    #[test]
    fn the_model_counts_the_field_list_and_what_the_liquid_adds() {
        // A dry tetrahedral column, 4 points per element, 20 points per node.
        let dry = modelled_bytes::<f64, Tet4>(&points(80, false), 20, 4, 1.0);
        // Locate: x read (24), element rewritten (8), active (1), plus the element's data
        // (map 72 + 4 x (24 + 4) gradients and corners + 8 volume = 192) over 4 points.
        assert_eq!(dry[4], 24.0 + 8.0 + 1.0 + 192.0 / 4.0);
        // The liquid adds to every phase but locate.
        let wet = modelled_bytes::<f64, Tet4>(&points(80, true), 20, 4, 1.0);
        for k in 0..4 {
            assert!(wet[k] > dry[k], "phase {k}");
        }
        assert_eq!(wet[4], dry[4]);
        // In single precision the point arrays halve (the u32 and bool arrays do not).
        let f32_points = Particles::<f32> {
            x: vec![[0.0; 3]; 80],
            element: vec![0; 80],
            active: vec![true; 80],
            ..Default::default()
        };
        let half = modelled_bytes::<f32, Tet4>(&f32_points, 20, 4, 1.0);
        assert_eq!(half[4], 12.0 + 8.0 + 1.0 + (36.0 + 4.0 * 16.0 + 4.0) / 4.0);
        // A triangle's slots are narrower: its particle-to-grid traffic per point is less.
        let tri = modelled_bytes::<f64, Tri3>(&points(60, false), 20, 4, 1.0);
        assert!(tri[0] < dry[0] + 1e-9);
        // Corners summed straight into their nodes' accumulators spare the slots: 20 elements'
        // 80 corner slots of 10 values, written and read, against 4 nodes' accumulators.
        let direct = modelled_bytes::<f64, Tet4>(&points(80, false), 20, 4, 0.0);
        assert_eq!(
            dry[0] - direct[0],
            (2.0 * 80.0 * 10.0 * 8.0 - 2.0 * 4.0 * 10.0 * 8.0) / 80.0
        );
        // Located in the stress pass: the stress pass writes the element numbers back (4
        // bytes more), the locate phase moves nothing, the other phases are unchanged.
        let fused = locating_in_stress(dry);
        assert_eq!(fused[3], dry[3] + 4.0);
        assert_eq!(fused[4], 0.0);
        assert_eq!(fused[..3], dry[..3]);
        // The pore-pressure rate's weights: 20 elements' 4 reals and a u32 (36 bytes) over 80
        // points, written by particle to grid and read by the stress phase's rate pass.
        let weighted = with_pore_weights::<f64>(wet, 20, 80);
        assert_eq!(weighted[0], wet[0] + 36.0 * 20.0 / 80.0);
        assert_eq!(weighted[3], wet[3] + 36.0 * 20.0 / 80.0);
        assert_eq!(
            [weighted[1], weighted[2], weighted[4]],
            [wet[1], wet[2], wet[4]]
        );
        assert_eq!(
            with_pore_weights::<f32>(wet, 20, 80)[0],
            wet[0] + 20.0 * 20.0 / 80.0
        );
    }

    #[test]
    fn a_stencil_basis_reads_no_slots_and_pays_its_halo_and_tables() {
        let grid = StencilTables {
            visits: 1.0,
            element_bytes: 0,
            node_bytes: 0,
            element_map: false,
            smoothed_rate: false,
        };
        // 80 points, 20 elements, 4 nodes: the points' arrays, a node's 10 accumulators read
        // and written, the nodal arrays; no element data and no slots.
        let p = points(80, false);
        let one = modelled_bytes_stencil::<f64, Tet4>(&p, 20, 4, grid);
        let fields = point_bytes(&p, PHASE_FIELDS[0]) as f64;
        let nodal = (2.0 * 10.0 * 8.0 + 8.0 + 9.0 * 8.0) * 4.0 / 80.0;
        assert_eq!(one[0], fields + nodal);
        // Against the elements' model with every corner straight to its node: the element
        // data (192 bytes an element, over 4 points) is what the grid spares.
        let direct = modelled_bytes::<f64, Tet4>(&p, 20, 4, 0.0);
        assert_eq!(direct[0] - one[0], 192.0 / 4.0);
        // Half the points read twice (threads' halo): only the owner-computes reads grow.
        let halo = modelled_bytes_stencil::<f64, Tet4>(
            &p,
            20,
            4,
            StencilTables {
                visits: 1.5,
                ..grid
            },
        );
        assert_eq!(halo[0] - one[0], 0.5 * fields);
        assert_eq!(halo[1], one[1]);
        assert!(halo[2] > one[2]);
        assert_eq!([halo[3], halo[4]], [one[3], one[4]]);
        // Per-element tables (the dual-domain gradients') are read once per element visit and
        // stencil evaluation: particle to grid, both passes of grid to particle, stress.
        let ddmp = StencilTables {
            element_bytes: 800,
            ..grid
        };
        let tables = modelled_bytes_stencil::<f64, Tet4>(&p, 20, 4, ddmp);
        assert_eq!(tables[0] - one[0], 10.0);
        assert_eq!(tables[2] - one[2], 20.0);
        assert_eq!(tables[3] - one[3], 10.0);
        // The liquid's smoothed rate adds a pass to the stress phase.
        let wet = points(80, true);
        let plain = modelled_bytes_stencil::<f64, Tet4>(&wet, 20, 4, grid);
        let smoothed = StencilTables {
            smoothed_rate: true,
            ..grid
        };
        let smoothed = modelled_bytes_stencil::<f64, Tet4>(&wet, 20, 4, smoothed);
        assert!(smoothed[3] > plain[3]);
        assert_eq!(smoothed[0], plain[0]);
    }
}
