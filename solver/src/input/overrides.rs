//! The command line's overrides of a case (`mpm-solve`'s options): worker threads and their
//! placement, first touch, huge pages, the ordering of the mesh, the Darcy drag's time
//! integration, the precision, the energy tolerance, extra probes and `--force`. The binary
//! fills an [`Overrides`] from its options; [`Overrides::check`] and
//! [`Overrides::prepare_process`] run before the input is read, [`apply`] on the case read.

use crate::input::case::{
    Case, CourantError, Drag, Gradient, Precision, Reorder, ReorderError, Scheme,
};
use crate::parallel::team::Pin;

/// The most worker threads a run may ask for: each is started before the input is read, and a
/// mistyped count (`--threads 99999`) would start them for minutes before any message.
pub const MAX_THREADS: usize = 1024;

/// The options that override a case's own settings; [`Default`] gives the command line's
/// defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct Overrides {
    /// Worker threads (`--threads`; `None`: one per core no other process keeps busy).
    pub threads: Option<usize>,
    /// Thread placement (`--pin`).
    pub pin: Pin,
    /// Each thread first touches the data it computes on (`--first-touch`).
    pub first_touch: bool,
    /// Large arrays on 2 MiB pages (`--huge-pages`).
    pub huge_pages: bool,
    /// The ordering of the mesh before computing (`--reorder`).
    pub reorder: Reorder,
    /// Time integration of the Darcy drag (`--drag`).
    pub drag: Drag,
    /// Precision of the particle and grid state (`--precision`; `None`: the case's).
    pub precision: Option<Precision>,
    /// The points' gradients on the mesh's elements (`--basis`; `None`: the case's).
    pub gradient: Option<Gradient>,
    /// How a two-phase case is stepped (`--scheme`; `None`: the case's). Asking for the
    /// semi-implicit scheme keeps a scene's own tolerance.
    pub scheme: Option<Scheme>,
    /// The energy balance's tolerance (`--energy-tolerance`): `Some(None)` not checked,
    /// `Some(Some(share))` that share; `None`: the case's.
    pub energy_tolerance: Option<Option<f64>>,
    /// Material-point ids (1-based) written to history.csv besides the case's (`--probe`).
    pub probes: Vec<u32>,
    /// Run a Courant number above 1 (`--force`).
    pub force: bool,
}

impl Default for Overrides {
    fn default() -> Self {
        Overrides {
            threads: None,
            pin: Pin::Auto,
            first_touch: true,
            huge_pages: false,
            reorder: Reorder::Morton,
            drag: Drag::Implicit,
            precision: None,
            gradient: None,
            scheme: None,
            energy_tolerance: None,
            probes: Vec::new(),
            force: false,
        }
    }
}

/// An override refused.
#[derive(Debug, thiserror::Error)]
pub enum OverrideError {
    /// `--threads 0`.
    #[error("--threads must be at least 1")]
    NoThreads,
    /// More than [`MAX_THREADS`] threads.
    #[error("--threads {asked}: at most {MAX_THREADS} (this machine has {cores} cores)")]
    TooManyThreads {
        /// The count asked for.
        asked: usize,
        /// The cores of this machine.
        cores: usize,
    },
    /// The process's thread pool could not be sized.
    #[error("sizing the thread pool")]
    Pool(#[source] rayon::ThreadPoolBuildError),
    /// A Courant number above 1 without `--force`.
    #[error(transparent)]
    Courant(#[from] CourantError),
    /// The mesh could not be ordered.
    #[error(transparent)]
    Reorder(#[from] ReorderError),
    /// `--basis ddmp` on a case computed on a background grid.
    #[error(
        "--basis: the dual-domain gradients are the mesh's elements'; this case is computed on \
         a background grid ([grid]), whose basis has its own"
    )]
    BasisOnGrid,
}

impl Overrides {
    /// Refuses a thread count of 0 or above [`MAX_THREADS`]: before anything is started.
    pub fn check(&self) -> Result<(), OverrideError> {
        match self.threads {
            Some(0) => Err(OverrideError::NoThreads),
            Some(n) if n > MAX_THREADS => Err(OverrideError::TooManyThreads {
                asked: n,
                cores: std::thread::available_parallelism().map_or(1, |c| c.get()),
            }),
            _ => Ok(()),
        }
    }

    /// The settings of the whole process, made before the input is read: huge pages for the
    /// large arrays allocated from then on, and rayon's pool (reading, ordering and set-up run
    /// on it) sized as the run's team. Once per process.
    pub fn prepare_process(&self) -> Result<(), OverrideError> {
        self.check()?;
        crate::parallel::huge_pages::set_enabled(self.huge_pages);
        if let Some(n) = self.threads {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build_global()
                .map_err(OverrideError::Pool)?;
        }
        Ok(())
    }

    /// The ordering `case` gets: a GOM with sections this solver cannot renumber is computed
    /// in its own order (with a warning) rather than refused.
    fn reorder_of(&self, case: &Case) -> Reorder {
        match case.model.first_unremappable() {
            Some(k) if self.reorder != Reorder::None => {
                log::warn!(
                    "section $${k} cannot follow a renumbering; computing in the input's order"
                );
                Reorder::None
            }
            _ => self.reorder,
        }
    }
}

/// `case` with the overrides applied: drag, precision, gradients, the Courant check (`force`), energy
/// tolerance, probes (added, sorted, each once), the engine's threads, pinning and first touch,
/// and the mesh ordered as asked.
pub fn apply(mut case: Case, o: &Overrides) -> Result<Case, OverrideError> {
    case.numerics.drag = o.drag;
    if let Some(p) = o.precision {
        case.numerics.precision = p;
    }
    if let Some(g) = o.gradient {
        if case.numerics.grid.is_some() && g != Gradient::Element {
            return Err(OverrideError::BasisOnGrid);
        }
        case.numerics.gradient = g;
    }
    match (o.scheme, case.numerics.scheme) {
        (Some(Scheme::SemiImplicit { .. }), Scheme::SemiImplicit { .. }) | (None, _) => {}
        (Some(s), _) => case.numerics.scheme = s,
    }
    case.check_courant(o.force)?;
    if let Some(t) = o.energy_tolerance {
        case.run.guards.energy_tolerance = t;
    }
    case.run.probes.extend(&o.probes);
    case.run.probes.sort_unstable();
    case.run.probes.dedup();
    if o.threads == Some(0) {
        return Err(OverrideError::NoThreads);
    }
    case.run.engine = crate::parallel::team::Options {
        threads: o.threads.unwrap_or(0),
        pin: o.pin,
        first_touch: o.first_touch,
    };
    let how = o.reorder_of(&case);
    Ok(case.reordered(how)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::case::{MaterialSpec, DEFAULT_ENERGY_TOLERANCE};
    use mpm_shared::generate::box_mesh;
    use mpm_shared::ElementType;

    /// A small elastic box (Courant `courant`) with probes 5 and 2.
    fn case(courant: f64) -> Case {
        let model = box_mesh([2, 2, 2], [1.0, 1.0, 1.0], ElementType::Tet4);
        let material = MaterialSpec::new("soil", 2000.0, 1e4, 0.3).unwrap();
        let fixed = vec![[false; 3]; model.node_count()];
        let mut c = Case::single_material("box", model, material, 1, fixed);
        c.time.courant = courant;
        c.run.probes = vec![5, 2];
        c
    }

    #[test]
    fn the_defaults_leave_a_case_as_it_is_but_ordered() {
        let c = case(0.5);
        let ordered = c.clone().reordered(Reorder::Morton).unwrap();
        let a = apply(c, &Overrides::default()).unwrap();
        assert_eq!(a.numerics.drag, Drag::Implicit);
        assert_eq!(a.numerics.precision, Precision::F64);
        assert_eq!(
            a.run.guards.energy_tolerance,
            Some(DEFAULT_ENERGY_TOLERANCE)
        );
        assert_eq!(a.run.probes, vec![2, 5]);
        assert_eq!(a.run.engine, crate::parallel::team::Options::default());
        assert_eq!(a.model.coords, ordered.model.coords);
        assert_eq!(a.model.connectivity, ordered.model.connectivity);
    }

    #[test]
    fn each_override_sets_its_setting() {
        let o = Overrides {
            threads: Some(3),
            pin: Pin::Cores,
            first_touch: false,
            huge_pages: true,
            reorder: Reorder::None,
            drag: Drag::Explicit,
            precision: Some(Precision::F32),
            gradient: Some(Gradient::Ddmp),
            scheme: Some(Scheme::SemiImplicit { tolerance: 1e-6 }),
            energy_tolerance: Some(Some(0.25)),
            probes: vec![7, 2, 7],
            force: false,
        };
        let c = case(0.5);
        let (coords, connectivity) = (c.model.coords.clone(), c.model.connectivity.clone());
        let a = apply(c, &o).unwrap();
        assert_eq!(a.numerics.drag, Drag::Explicit);
        assert_eq!(a.numerics.precision, Precision::F32);
        assert_eq!(a.numerics.gradient, Gradient::Ddmp);
        assert_eq!(a.numerics.scheme, Scheme::SemiImplicit { tolerance: 1e-6 });
        assert_eq!(a.run.guards.energy_tolerance, Some(0.25));
        assert_eq!(a.run.probes, vec![2, 5, 7]);
        assert_eq!(a.run.engine.threads, 3);
        assert_eq!(a.run.engine.pin, Pin::Cores);
        assert!(!a.run.engine.first_touch);
        // `none` keeps the input's order.
        assert_eq!(a.model.coords, coords);
        assert_eq!(a.model.connectivity, connectivity);
        let off = Overrides {
            energy_tolerance: Some(None),
            reorder: Reorder::Hilbert,
            ..Overrides::default()
        };
        assert_eq!(
            apply(case(0.5), &off).unwrap().run.guards.energy_tolerance,
            None
        );
        // Asking for the semi-implicit scheme keeps a case's own tolerance; asking for the
        // explicit one sets it.
        let mut semi = case(0.5);
        semi.numerics.scheme = Scheme::SemiImplicit { tolerance: 1e-8 };
        let again = Overrides {
            scheme: Some(Scheme::SemiImplicit { tolerance: 1e-10 }),
            ..Overrides::default()
        };
        let kept = apply(semi.clone(), &again).unwrap().numerics.scheme;
        assert_eq!(kept, Scheme::SemiImplicit { tolerance: 1e-8 });
        let back = Overrides {
            scheme: Some(Scheme::Explicit),
            ..Overrides::default()
        };
        assert_eq!(
            apply(semi, &back).unwrap().numerics.scheme,
            Scheme::Explicit
        );
    }

    #[test]
    fn the_dual_domain_gradients_are_refused_on_a_grid() {
        let mut c = case(0.5);
        c.numerics.grid = Some(crate::basis::grid::GridSpec {
            origin: [0.0; 3],
            cell: [0.5; 3],
            cells: [2; 3],
            dim: 3,
            shape: crate::basis::spline::Shape::Linear,
            points_per_axis: None,
        });
        let ddmp = Overrides {
            gradient: Some(Gradient::DdmpBlended),
            ..Overrides::default()
        };
        let e = apply(c.clone(), &ddmp).unwrap_err();
        assert!(e.to_string().contains("background grid"), "{e}");
        let element = Overrides {
            gradient: Some(Gradient::Element),
            ..Overrides::default()
        };
        assert!(apply(c, &element).is_ok());
    }

    #[test]
    fn a_courant_number_above_one_needs_force() {
        let e = apply(case(1.5), &Overrides::default()).unwrap_err();
        assert!(matches!(e, OverrideError::Courant(_)), "{e}");
        let forced = Overrides {
            force: true,
            ..Overrides::default()
        };
        assert_eq!(apply(case(1.5), &forced).unwrap().time.courant, 1.5);
    }

    #[test]
    fn thread_counts_of_zero_or_above_the_limit_are_refused() {
        let with = |n| Overrides {
            threads: Some(n),
            ..Overrides::default()
        };
        assert_eq!(
            with(0).check().unwrap_err().to_string(),
            "--threads must be at least 1"
        );
        assert!(matches!(
            apply(case(0.5), &with(0)).unwrap_err(),
            OverrideError::NoThreads
        ));
        let e = with(MAX_THREADS + 1).check().unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "--threads {}: at most 1024 (this machine has ",
                MAX_THREADS + 1
            )),
            "{e}"
        );
        assert!(with(MAX_THREADS).check().is_ok());
        assert!(Overrides::default().check().is_ok());
    }
}
