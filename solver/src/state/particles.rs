//! Material points, stored as structure of arrays, and their initial placement by Anura3D's rule.

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
}

/// Something done to every per-point array of [`Particles`] alike (re-sorting, first touch,
/// counting bytes). [`Particles::visit_fields`] is the one list of those arrays.
pub trait FieldVisitor {
    /// One array, `per_point` values per point.
    fn field<T: Copy + Default + Send + Sync>(&mut self, values: &mut Vec<T>, per_point: usize);
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

impl<R: Real> Particles<R> {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Hands every per-point array to `v`. The fields are taken apart exhaustively, so a field
    /// added to [`Particles`] (or [`LiquidPoints`]) does not compile until it is listed here, and
    /// sort, first touch and byte counts follow it.
    pub fn visit_fields(&mut self, v: &mut impl FieldVisitor) {
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
        } = self;
        v.field(x, 1);
        v.field(u, 1);
        v.field(velocity, 1);
        v.field(mass, 1);
        v.field(volume, 1);
        v.field(stress, 1);
        v.field(element, 1);
        v.field(material, 1);
        v.field(id, 1);
        v.field(active, 1);
        v.field(state, *state_len);
        if let Some(LiquidPoints { w, p, volume0 }) = liquid {
            v.field(w, 1);
            v.field(p, 1);
            if let Some(v0) = volume0 {
                v.field(v0, 1);
            }
        }
    }

    /// Bytes of state per point (more when the liquid is modelled or a law keeps state).
    pub fn bytes_per_point(&self) -> usize {
        struct Count(usize);
        impl FieldVisitor for Count {
            fn field<T: Copy + Default + Send + Sync>(&mut self, _: &mut Vec<T>, per_point: usize) {
                self.0 += std::mem::size_of::<T>() * per_point;
            }
        }
        let mut c = Count(0);
        // Visiting needs `&mut`; counting touches no value, so a cheap empty copy will do.
        let mut shape = Particles::<R> {
            state_len: self.state_len,
            liquid: self.liquid.as_ref().map(|l| LiquidPoints {
                w: Vec::new(),
                p: Vec::new(),
                volume0: l.volume0.as_ref().map(|_| Vec::new()),
            }),
            ..Default::default()
        };
        shape.visit_fields(&mut c);
        c.0
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
) -> Result<Particles<R>, String> {
    let mut p = Particles::default();
    let mut id = 0u32;
    for e in 0..mesh.elements() {
        if let Some(f) = first_id {
            id = f[e];
        }
        let n = points[e];
        let Some(local) = E::point_placement(n) else {
            return Err(format!(
                "element {}: {n} material points per element is not supported for {} (use {})",
                number(e),
                E::NAME,
                E::supported_point_counts()
            ));
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
            let vol = mesh.volume[e].f64() / n as f64;
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
