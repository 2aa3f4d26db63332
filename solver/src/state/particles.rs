//! Material points, stored as structure of arrays, and their initial placement by Anura3D's rule.

use crate::element::locate::{walk, Found};
use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};

/// Material-point state (one entry per point in every array).
#[derive(Debug, Clone, Default)]
pub struct Particles<R: Real> {
    /// Position.
    pub x: Vec<V3<R>>,
    /// Displacement since the start.
    pub u: Vec<V3<R>>,
    /// Velocity.
    pub v: Vec<V3<R>>,
    /// Mass (t).
    pub mass: Vec<R>,
    /// Volume (m³).
    pub volume: Vec<R>,
    /// Stress (kPa, tension positive): xx yy zz xy yz zx.
    pub stress: Vec<[R; 6]>,
    /// Element holding the point.
    pub element: Vec<u32>,
    /// Material index (1-based, as in the GOM).
    pub material: Vec<u32>,
    /// Id in the input numbering (1-based, in element order as Anura3D counts).
    pub id: Vec<u32>,
    /// False once a point has left the mesh under `--drop-lost`.
    pub active: Vec<bool>,
    /// The constitutive laws' state: [`Particles::state_len`] values per point (empty when no
    /// law keeps state).
    pub state: Vec<R>,
    /// State values per point.
    pub state_len: usize,
    /// Liquid state, present only when the case has a saturated material.
    pub liquid: Option<LiquidPoints<R>>,
    /// Bulk viscosity state, present only when the case damps with it.
    pub bulk: Option<BulkPoints<R>>,
}

/// How a per-point array appears in the particle files (`particles_NNNNN.vtu`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Written {
    /// Not written: working data.
    No,
    /// The points' coordinates.
    Position,
    /// A point-data array of this name.
    As(&'static str),
    /// A point-data array of this name, 0-based indices written 1-based.
    OneBased(&'static str),
}

/// One per-point array of the field list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Field {
    /// The array's name in [`Particles`].
    pub name: &'static str,
    /// Values per point.
    pub per_point: usize,
    /// How the particle files show it.
    pub written: Written,
}

/// A value type of a per-point array, and how its components are written.
pub trait Value: Copy + Default + Send + Sync + 'static {
    /// Components per value.
    const COMPONENTS: usize;
    /// Written as integers (else as 64-bit floats).
    const INTEGER: bool;
    /// Appends the components as f64.
    fn push_f64(&self, out: &mut Vec<f64>);
    /// Appends the components as i32, plus `offset`.
    fn push_i32(&self, offset: i32, out: &mut Vec<i32>);
    /// Bytes of one value in a checkpoint.
    const BYTES: usize;
    /// Appends the value's bits, little-endian (a checkpoint round-trips exactly).
    fn put_bits(&self, out: &mut Vec<u8>);
    /// The value of exactly [`Value::BYTES`] bytes written by [`Value::put_bits`] (`None` when
    /// they are not such a value).
    fn from_bits(b: &[u8]) -> Option<Self>;
}

impl<R: Real> Value for R {
    const COMPONENTS: usize = 1;
    const INTEGER: bool = false;
    const BYTES: usize = R::BYTES;
    fn put_bits(&self, out: &mut Vec<u8>) {
        Real::put_bits(*self, out);
    }
    fn from_bits(b: &[u8]) -> Option<Self> {
        <R as Real>::from_bits(b)
    }
    fn push_f64(&self, out: &mut Vec<f64>) {
        out.push(self.f64());
    }
    fn push_i32(&self, offset: i32, out: &mut Vec<i32>) {
        out.push(self.f64() as i32 + offset);
    }
}

impl<R: Real, const N: usize> Value for [R; N]
where
    [R; N]: Default,
{
    const COMPONENTS: usize = N;
    const INTEGER: bool = false;
    const BYTES: usize = N * R::BYTES;
    fn put_bits(&self, out: &mut Vec<u8>) {
        for &v in self {
            Real::put_bits(v, out);
        }
    }
    fn from_bits(b: &[u8]) -> Option<Self> {
        if b.len() != Self::BYTES {
            return None;
        }
        let mut out = [R::ZERO; N];
        for (o, c) in out.iter_mut().zip(b.chunks_exact(R::BYTES)) {
            *o = <R as Real>::from_bits(c)?;
        }
        Some(out)
    }
    fn push_f64(&self, out: &mut Vec<f64>) {
        out.extend(self.iter().map(|v| v.f64()));
    }
    fn push_i32(&self, offset: i32, out: &mut Vec<i32>) {
        out.extend(self.iter().map(|v| v.f64() as i32 + offset));
    }
}

impl Value for u32 {
    const COMPONENTS: usize = 1;
    const INTEGER: bool = true;
    const BYTES: usize = 4;
    fn put_bits(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn from_bits(b: &[u8]) -> Option<Self> {
        Some(u32::from_le_bytes(b.try_into().ok()?))
    }
    fn push_f64(&self, out: &mut Vec<f64>) {
        out.push(f64::from(*self));
    }
    fn push_i32(&self, offset: i32, out: &mut Vec<i32>) {
        out.push(*self as i32 + offset);
    }
}

impl Value for bool {
    const COMPONENTS: usize = 1;
    const INTEGER: bool = true;
    const BYTES: usize = 1;
    fn put_bits(&self, out: &mut Vec<u8>) {
        out.push(u8::from(*self));
    }
    fn from_bits(b: &[u8]) -> Option<Self> {
        match b {
            [0] => Some(false),
            [1] => Some(true),
            _ => None,
        }
    }
    fn push_f64(&self, out: &mut Vec<f64>) {
        out.push(f64::from(u8::from(*self)));
    }
    fn push_i32(&self, offset: i32, out: &mut Vec<i32>) {
        out.push(i32::from(*self) + offset);
    }
}

/// Something done to every per-point array of [`Particles`] alike that changes them
/// (re-sorting, first touch). [`Particles::visit_fields`] hands over the one field list.
pub trait FieldVisitor {
    /// One array of the list.
    fn field<T: Value>(&mut self, field: Field, values: &mut Vec<T>);
}

/// Something done to every per-point array of [`Particles`] alike that only reads them
/// (counting bytes, writing the particle files). [`Particles::read_fields`] hands over the same
/// list as [`Particles::visit_fields`].
pub trait FieldReader {
    /// One array of the list.
    fn field<T: Value>(&mut self, field: Field, values: &[T]);
}

/// The one list of per-point arrays, for [`Particles::visit_fields`] and
/// [`Particles::read_fields`]. The fields are taken apart exhaustively, so a field added to
/// [`Particles`] (or [`LiquidPoints`]) does not compile until it is listed here; the order is
/// that of the arrays in the particle files.
macro_rules! field_list {
    ($particles:expr, $visitor:expr) => {{
        let Particles {
            x,
            u,
            v: velocity,
            mass,
            volume,
            stress,
            element,
            material,
            id,
            active,
            state,
            state_len,
            liquid,
            bulk,
        } = $particles;
        let one = |name, written| Field {
            name,
            per_point: 1,
            written,
        };
        $visitor.field(one("x", Written::Position), x);
        $visitor.field(one("u", Written::As("displacement")), u);
        $visitor.field(one("v", Written::As("velocity")), velocity);
        $visitor.field(one("mass", Written::No), mass);
        $visitor.field(one("volume", Written::No), volume);
        $visitor.field(one("stress", Written::As("stress")), stress);
        $visitor.field(one("material", Written::As("material")), material);
        $visitor.field(one("element", Written::OneBased("element")), element);
        $visitor.field(one("id", Written::As("id")), id);
        $visitor.field(one("active", Written::No), active);
        let per_point = *state_len;
        $visitor.field(
            Field {
                name: "state",
                per_point,
                written: Written::No,
            },
            state,
        );
        if let Some(LiquidPoints { w, p, volume0 }) = liquid {
            $visitor.field(one("p", Written::As("pore_pressure")), p);
            $visitor.field(one("w", Written::As("liquid_velocity")), w);
            if let Some(v0) = volume0 {
                $visitor.field(one("volume0", Written::No), v0);
            }
        }
        if let Some(BulkPoints { pressure, rate }) = bulk {
            $visitor.field(one("bulk_pressure", Written::No), pressure);
            $visitor.field(one("bulk_rate", Written::No), rate);
        }
    }};
}

/// Liquid state of the material points (one entry per point; zero at points of dry materials).
#[derive(Debug, Clone, Default)]
pub struct LiquidPoints<R: Real> {
    /// Liquid velocity.
    pub w: Vec<V3<R>>,
    /// Pore pressure (kPa, compression negative, as Anura3D).
    pub p: Vec<R>,
    /// The volume a point's liquid mass, weight and drag are taken on, when it is held at the
    /// initial volume (Anura3D keeps a point's liquid mass constant); `None`: the current
    /// volume (the liquid mass n ρw V follows the point's volume at constant porosity).
    pub volume0: Option<Vec<R>>,
}

/// Bulk viscosity state of the material points ([`crate::step::bulk_viscosity`]).
#[derive(Debug, Clone, Default)]
pub struct BulkPoints<R: Real> {
    /// The viscous pressure q (kPa, tension positive) the stress pass formed, which the next
    /// step's internal force adds to the normal stresses.
    pub pressure: Vec<R>,
    /// The volumetric strain rate tr Δε / Δt (1/s) it was formed from, which the critical step
    /// reads.
    pub rate: Vec<R>,
}

impl<R: Real> Particles<R> {
    /// Points at rest at the origin, one per entry of `element` (their elements), of unit mass
    /// and volume, unstressed, active, of material 0 (for tests).
    #[cfg(test)]
    pub(crate) fn at_rest(element: Vec<u32>) -> Self {
        let n = element.len();
        Self {
            x: vec![[R::ZERO; 3]; n],
            u: vec![[R::ZERO; 3]; n],
            v: vec![[R::ZERO; 3]; n],
            mass: vec![R::ONE; n],
            volume: vec![R::ONE; n],
            stress: vec![[R::ZERO; 6]; n],
            element,
            material: vec![0; n],
            id: (0..n as u32).collect(),
            active: vec![true; n],
            ..Default::default()
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Hands every per-point array to `v`, to change them alike (the one field list, in particle-file order).
    pub fn visit_fields(&mut self, v: &mut impl FieldVisitor) {
        field_list!(self, v);
    }

    /// Hands every per-point array to `r`, to read them alike (the same list as [`Particles::visit_fields`]).
    pub fn read_fields(&self, r: &mut impl FieldReader) {
        field_list!(self, r);
    }

    /// Bytes of state per point (more when the liquid is modelled or a law keeps state).
    pub fn bytes_per_point(&self) -> usize {
        struct Count(usize);
        impl FieldReader for Count {
            fn field<T: Value>(&mut self, field: Field, _: &[T]) {
                self.0 += std::mem::size_of::<T>() * field.per_point;
            }
        }
        let mut c = Count(0);
        self.read_fields(&mut c);
        c.0
    }

    /// Appends point `i` of every array, as bits (the field list's order): a point leaving for
    /// another rank or gathered for the output files. [`Particles::push_encoded`] reads it back.
    pub fn put_point(&self, i: usize, out: &mut Vec<u8>) {
        struct Put<'a>(usize, &'a mut Vec<u8>);
        impl FieldReader for Put<'_> {
            fn field<T: Value>(&mut self, field: Field, values: &[T]) {
                let k = field.per_point;
                for v in &values[k * self.0..k * (self.0 + 1)] {
                    v.put_bits(self.1);
                }
            }
        }
        self.read_fields(&mut Put(i, out));
    }

    /// Bytes [`Particles::put_point`] writes per point.
    pub fn encoded_len(&self) -> usize {
        struct Len(usize);
        impl FieldReader for Len {
            fn field<T: Value>(&mut self, field: Field, _: &[T]) {
                self.0 += T::BYTES * field.per_point;
            }
        }
        let mut l = Len(0);
        self.read_fields(&mut l);
        l.0
    }

    /// Appends the points that [`Particles::put_point`] wrote into `bytes` (from arrays of the
    /// same fields). Returns how many.
    pub fn push_encoded(&mut self, bytes: &[u8]) -> usize {
        let size = self.encoded_len();
        assert!(size > 0 && bytes.len() % size == 0, "whole encoded points");
        let n = bytes.len() / size;
        struct Push<'a> {
            bytes: &'a [u8],
            size: usize,
            offset: usize,
            n: usize,
        }
        impl FieldVisitor for Push<'_> {
            fn field<T: Value>(&mut self, field: Field, values: &mut Vec<T>) {
                let k = field.per_point;
                for p in 0..self.n {
                    for c in 0..k {
                        let at = p * self.size + self.offset + c * T::BYTES;
                        values.push(
                            T::from_bits(&self.bytes[at..at + T::BYTES]).expect("encoded value"),
                        );
                    }
                }
                self.offset += k * T::BYTES;
            }
        }
        self.visit_fields(&mut Push {
            bytes,
            size,
            offset: 0,
            n,
        });
        n
    }

    /// Rotates the first `n` points right by `by` (the last `by` of them come first).
    pub fn rotate_front(&mut self, n: usize, by: usize) {
        struct Rotate(usize, usize);
        impl FieldVisitor for Rotate {
            fn field<T: Value>(&mut self, field: Field, values: &mut Vec<T>) {
                let k = field.per_point;
                values[..k * self.0].rotate_right(k * self.1);
            }
        }
        self.visit_fields(&mut Rotate(n, by));
    }

    /// Keeps the points whose `keep[i]` is true, in order.
    pub fn retain(&mut self, keep: &[bool]) {
        struct Retain<'a>(&'a [bool]);
        impl FieldVisitor for Retain<'_> {
            fn field<T: Value>(&mut self, field: Field, values: &mut Vec<T>) {
                let k = field.per_point;
                let mut to = 0;
                for (i, &kept) in self.0.iter().enumerate() {
                    if kept {
                        values.copy_within(k * i..k * (i + 1), k * to);
                        to += 1;
                    }
                }
                values.truncate(k * to);
            }
        }
        self.visit_fields(&mut Retain(keep));
    }

    /// Adds the liquid state, every point starting at rest with pore pressure `p0(material)`;
    /// with `fixed_liquid_mass`, the liquid's mass is kept at that of the initial volume.
    pub fn add_liquid(&mut self, p0: impl Fn(u32) -> f64, fixed_liquid_mass: bool) {
        self.liquid = Some(LiquidPoints {
            w: vec![[R::ZERO; 3]; self.len()],
            p: self.material.iter().map(|&m| R::of(p0(m))).collect(),
            volume0: fixed_liquid_mass.then(|| self.volume.clone()),
        });
    }

    /// Adds the bulk viscosity state, every point without a viscous pressure.
    pub fn add_bulk(&mut self) {
        self.bulk = Some(BulkPoints {
            pressure: vec![R::ZERO; self.len()],
            rate: vec![R::ZERO; self.len()],
        });
    }
}

/// An element asks for a number of material points its type cannot place.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("element {element}: {count} material points per element is not supported for {elements} (use {supported})")]
pub struct PlacementError {
    /// The element's 1-based input number.
    pub element: u32,
    /// Points asked for.
    pub count: u32,
    /// The element type, plural.
    pub elements: &'static str,
    /// The counts that are supported, in words.
    pub supported: &'static str,
}

/// Places `points[e]` material points in every element `e` of material `material[e]` (0 = empty),
/// each with an equal share of the element's volume and mass `density[material] · V / n`.
/// Ids follow element order, `points[e]` per element, as Anura3D numbers them.
///
/// `first_id[e]`, when given, is the number of points before element e in the input's element
/// order (the solver may have reordered the elements): ids then stay those of the input.
/// `number(e)` is element e's 1-based input number, for messages.
pub fn place<E: Element, R: Real>(
    mesh: &Mesh<E, R>,
    points: &[u32],
    material: &[u32],
    first_id: Option<&[u32]>,
    number: &dyn Fn(usize) -> u32,
    density: impl Fn(u32) -> f64,
) -> Result<Particles<R>, PlacementError> {
    let mut p = Particles::default();
    let mut id = 0u32;
    debug_assert!(points.len() <= mesh.elements());
    // One count per owned element (a rank's halo elements, after them, get none here).
    for e in 0..points.len() {
        if let Some(f) = first_id {
            id = f[e];
        }
        let n = points[e];
        let Some(local) = E::point_placement(n) else {
            return Err(PlacementError {
                element: number(e),
                count: n,
                elements: E::NAME,
                supported: E::supported_point_counts(),
            });
        };
        for l in local {
            id += 1;
            if material[e] == 0 {
                continue;
            }
            let c = mesh.corners[e].as_ref();
            let mut x = [R::ZERO; 3];
            for (k, &l) in l.as_ref().iter().enumerate() {
                let xk = mesh.x[c[k] as usize];
                for a in 0..3 {
                    x[a] += R::of(l) * xk[a];
                }
            }
            // An axisymmetric section's points hold their volume and mass per radian: the
            // area's share times the radius (the axis is at x = 0), as Anura3D does.
            let per_radian = if E::AXISYMMETRIC { x[0].f64() } else { 1.0 };
            let vol = mesh.volume[e].f64() / n as f64 * per_radian;
            p.x.push(x);
            p.u.push([R::ZERO; 3]);
            p.v.push([R::ZERO; 3]);
            p.volume.push(R::of(vol));
            p.mass.push(R::of(density(material[e]) * vol));
            p.stress.push([R::ZERO; 6]);
            p.element.push(e as u32);
            p.material.push(material[e]);
            p.id.push(id);
            p.active.push(true);
        }
    }
    Ok(p)
}

/// Places material points at given positions: `positions(e, out)` lists the points that
/// element `e` of material `material[e]` (0 = empty) seeds (none for most elements; the
/// background grid's cells seed their regular points from one element each, [`place`]'s
/// `points[e]` of them, numbered from `first_id[e]` as [`place`] numbers them), each with
/// volume `volume(e, x)`. Each point goes to the element that holds it (walked from its seed,
/// [`walk`]), and the points are ordered by element (stably: a seed's points in its order).
pub fn place_at<E: Element, R: Real>(
    mesh: &Mesh<E, R>,
    (points, material, first_id): (&[u32], &[u32], Option<&[u32]>),
    positions: &dyn Fn(usize, &mut Vec<V3<R>>),
    volume: &dyn Fn(usize, &V3<R>) -> f64,
    density: impl Fn(u32) -> f64,
) -> Particles<R> {
    // (element, id, seed, position)
    let mut placed: Vec<(u32, u32, u32, V3<R>)> = Vec::new();
    let (mut id, mut at) = (0u32, Vec::new());
    for e in 0..points.len() {
        if let Some(f) = first_id {
            id = f[e];
        }
        at.clear();
        if material[e] != 0 && points[e] > 0 {
            positions(e, &mut at);
            debug_assert_eq!(at.len(), points[e] as usize);
        }
        for (q, x) in at.iter().enumerate() {
            let (Found::In(home) | Found::Outside(home) | Found::Beyond(home)) =
                walk(mesh, e as u32, x);
            placed.push((home, id + q as u32 + 1, e as u32, *x));
        }
        id += points[e];
    }
    placed.sort_by_key(|&(home, id, ..)| (home, id));
    let mut p = Particles::default();
    for (home, id, seed, x) in placed {
        let m = material[seed as usize];
        let vol = volume(seed as usize, &x);
        p.x.push(x);
        p.u.push([R::ZERO; 3]);
        p.v.push([R::ZERO; 3]);
        p.volume.push(R::of(vol));
        p.mass.push(R::of(density(m) * vol));
        p.stress.push([R::ZERO; 6]);
        p.element.push(home);
        p.material.push(m);
        p.id.push(id);
        p.active.push(true);
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Names(Vec<(&'static str, Written)>);
    impl FieldReader for Names {
        fn field<T: Value>(&mut self, field: Field, _: &[T]) {
            self.0.push((field.name, field.written));
        }
    }

    #[test]
    fn the_field_list_names_every_array_once_in_file_order() {
        let mut p = Particles::<f64> {
            liquid: Some(LiquidPoints {
                volume0: Some(Vec::new()),
                ..Default::default()
            }),
            state_len: 2,
            bulk: Some(BulkPoints::default()),
            ..Default::default()
        };
        let mut names = Names(Vec::new());
        p.read_fields(&mut names);
        let written: Vec<&str> = names
            .0
            .iter()
            .filter_map(|(_, w)| match w {
                Written::As(n) | Written::OneBased(n) => Some(*n),
                _ => None,
            })
            .collect();
        assert_eq!(
            written,
            [
                "displacement",
                "velocity",
                "stress",
                "material",
                "element",
                "id",
                "pore_pressure",
                "liquid_velocity"
            ]
        );
        let mut all: Vec<&str> = names.0.iter().map(|(n, _)| *n).collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 16, "every array once");
        // x u v (3 × 24) mass volume (16) stress (48) element material id (12) active (1),
        // 2 state values (16), then p w volume0 (8 + 24 + 8), bulk pressure and rate (16).
        assert_eq!(p.bytes_per_point(), 72 + 16 + 48 + 12 + 1 + 16 + 40 + 16);
        p.liquid = None;
        p.bulk = None;
        p.state_len = 0;
        assert_eq!(p.bytes_per_point(), 149);
    }
}
