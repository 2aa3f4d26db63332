use super::distributed::imbalance_of;

#[test]
fn imbalance_is_the_largest_share_over_the_mean() {
    assert_eq!(imbalance_of(&[10.0, 10.0, 10.0]), 1.0);
    assert_eq!(imbalance_of(&[30.0, 10.0, 20.0]), 1.5);
    // A rank with every point of four.
    assert_eq!(imbalance_of(&[0.0, 8.0, 0.0, 0.0]), 4.0);
    assert_eq!(imbalance_of(&[0.0, 0.0]), 0.0);
}

/// The particle state of `scene` (in testdata) after `steps` steps, as bits, with the point
/// passes on their portable copies or as the processor allows.
fn state_bits<R: crate::real::Real, E: crate::element::Element>(
    scene: &str,
    steps: usize,
    portable: bool,
) -> Vec<u64> {
    state_bits_with::<R, E>(scene, steps, portable, true).concat()
}

/// [`state_bits`] field by field (the elements last), with the pore-pressure rate's
/// weights from particle to grid (`weights`) or the rate's pass point by point.
fn state_bits_with<R: crate::real::Real, E: crate::element::Element>(
    scene: &str,
    steps: usize,
    portable: bool,
    weights: bool,
) -> Vec<Vec<u64>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata");
    // A suffix of the scene's name, taken off: whether it was there.
    let flag = |scene: &mut &str, suffix: &str| match scene.strip_suffix(suffix) {
        Some(s) => {
            *scene = s;
            true
        }
        None => false,
    };
    let mut scene = scene;
    // `NAME+objective`: the scene with Anura3D's objective stress terms on, started
    // shearing; `+ten`: with ten points per element (a tetrahedron's batches of four,
    // four and two).
    let objective = flag(&mut scene, "+objective");
    let ten = flag(&mut scene, "+ten");
    // `+shear`: started moving down fast enough (a half sine over the height: a column's
    // walls hold v_x) that the middle points cross some two elements in the steps, so
    // that the passes' locate paths walk.
    let shear = flag(&mut scene, "+shear");
    // `+dry`: the scene's materials without their liquid.
    let dry = flag(&mut scene, "+dry");
    let mut case = crate::input::scene::load(&dir.join(scene)).unwrap();
    case.numerics.objective_stress |= objective;
    if ten {
        case.body
            .points_per_element
            .iter_mut()
            .for_each(|n| *n = 10);
    }
    if dry {
        case.body
            .materials
            .iter_mut()
            .flatten()
            .for_each(|m| m.liquid = None);
    }
    crate::parallel::avx2::with_portable(portable, || {
        let mut engine = super::Engine::<R, E>::new(&case, false).unwrap();
        if !weights {
            engine.pore_weights = None;
        }
        if objective {
            // A shearing start (v_x growing with y), so that the spin, and with it the
            // co-rotation, is not zero.
            let p = &mut engine.particles;
            for (v, x) in p.v.iter_mut().zip(&p.x) {
                v[0] += x[1] * R::of(0.05);
            }
        }
        if shear {
            // The element size from the mesh's extent and element count (a square
            // element's side; a triangle's area is half its square's).
            let (lo, hi) = engine.mesh.x.iter().fold(
                ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
                |(lo, hi), x| {
                    let (a, b) = (x[0].f64(), x[1].f64());
                    ([lo[0].min(a), lo[1].min(b)], [hi[0].max(a), hi[1].max(b)])
                },
            );
            let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
            let h = (2.0 * area / engine.mesh.elements() as f64).sqrt();
            // Fastest at mid-height, still at the top and the bottom (a faster top
            // surface left the mesh).
            let fastest = 2.0 * h / (steps as f64 * engine.dt);
            let p = &mut engine.particles;
            for (v, x) in p.v.iter_mut().zip(&p.x) {
                let y = (x[1].f64() - lo[1]) / (hi[1] - lo[1]);
                v[1] -= R::of(fastest * (std::f64::consts::PI * y).sin());
            }
        }
        let start = engine.particles.element.clone();
        for _ in 0..steps {
            engine.step(engine.dt, None).unwrap();
        }
        let p = &engine.particles;
        assert!(
            !shear || p.element != start,
            "{scene}: no point left its element"
        );
        let mut bits: Vec<Vec<u64>> = Vec::new();
        let mut add = |v: &[R]| bits.push(v.iter().map(|x| x.f64().to_bits()).collect());
        add(p.x.as_flattened());
        add(p.v.as_flattened());
        add(p.stress.as_flattened());
        add(&p.volume);
        add(&p.state);
        if let Some(l) = &p.liquid {
            add(&l.p);
            add(l.w.as_flattened());
        }
        bits.push(p.element.iter().map(|&e| e as u64).collect());
        bits
    })
}

/// The smoothed pore-pressure rate formed from particle to grid's weights (an element's
/// saturated points of one material summed once, `state::pore_weights`) gives the state of
/// the rate taken point by point: the same bits with one point per element, round-off with
/// three, four and ten (the products summed in another order), in both precisions and in the
/// portable copies as in the AVX2 ones.
#[test]
fn the_pore_rate_s_weights_give_the_point_by_point_rate() {
    use crate::element::{tet4::Tet4, tri3::Tri3};
    type Fields = Vec<Vec<u64>>;
    fn compare(scene: &str, with: &Fields, without: &Fields, exact: bool, tolerance: f64) {
        assert_eq!(with.len(), without.len(), "{scene}");
        if exact {
            assert!(with == without, "{scene}: not the same bits");
            return;
        }
        assert!(with != without, "{scene}: the weights were not taken");
        let (elements, values) = with.split_last().unwrap();
        assert_eq!(elements, without.last().unwrap(), "{scene}: elements");
        // Each field's values (as f64 bits) against its largest.
        for (field, (w, wo)) in values.iter().zip(without).enumerate() {
            let largest = wo
                .iter()
                .map(|&b| f64::from_bits(b).abs())
                .fold(0.0f64, f64::max);
            for (i, (&a, &b)) in w.iter().zip(wo).enumerate() {
                let (x, y) = (f64::from_bits(a), f64::from_bits(b));
                assert!(
                    a == b || (x - y).abs() <= tolerance * largest,
                    "{scene}: field {field} value {i}: {x} against {y}"
                );
            }
        }
    }
    for portable in [false, true] {
        for (scene, steps, exact) in [
            ("golden/column_saturated.toml", 60, true),
            ("oedometer.toml", 40, false),
            ("oedometer.toml+ten", 30, false),
        ] {
            let with = state_bits_with::<f64, Tet4>(scene, steps, portable, true);
            let without = state_bits_with::<f64, Tet4>(scene, steps, portable, false);
            compare(scene, &with, &without, exact, 1e-12);
            let with = state_bits_with::<f32, Tet4>(scene, steps, portable, true);
            let without = state_bits_with::<f32, Tet4>(scene, steps, portable, false);
            compare(scene, &with, &without, exact, 1e-4);
        }
        let scene = "oedometer_2d.toml";
        let with = state_bits_with::<f64, Tri3>(scene, 60, portable, true);
        let without = state_bits_with::<f64, Tri3>(scene, 60, portable, false);
        compare(scene, &with, &without, false, 1e-12);
    }
}

/// A checkpoint whose points name a material the case does not have (an edited file,
/// re-signed so that its checksum holds) is refused as corrupt, not indexed with.
#[test]
fn a_checkpoint_with_a_material_past_the_case_s_is_refused() {
    use crate::driver::checkpoint::{self, CheckpointError, Driver, Fingerprint, Series, State};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata");
    let case = crate::input::scene::load(&dir.join("golden/column_dry.toml")).unwrap();
    let mut engine = super::Engine::<f64, crate::element::tet4::Tet4>::new(&case, false).unwrap();
    let out = tempfile::tempdir().unwrap();
    let scalars = engine.checkpoint_scalars();
    let series = Series {
        pvd: vec![],
        history: String::new(),
        energy: String::new(),
        reaction: String::new(),
    };
    let save = |p: &crate::state::particles::Particles<f64>| {
        let state = State {
            fingerprint: &Fingerprint(vec![]),
            driver: Driver::default(),
            scalars: &scalars,
            particles: p,
            series: &series,
            observer: b"",
        };
        checkpoint::write(out.path(), &state).unwrap();
        checkpoint::read(out.path()).unwrap().unwrap()
    };
    // As saved, it restores.
    let saved = save(&engine.particles);
    engine.restore(&saved).unwrap();
    let mut edited = engine.particles.clone();
    let last = edited.material.len() - 1;
    edited.material[last] = engine.laws.len() as u32;
    let saved = save(&edited);
    match engine.restore(&saved) {
        Err(CheckpointError::Corrupt { what, .. }) => {
            assert!(what.contains("of material"), "{what}")
        }
        other => panic!("restored: {:?}", other.err()),
    }
}

/// The AVX2 copies of particle to grid, grid to particle and the stress pass give the bits
/// of the portable ones: dry, two-phase, Mohr-Coulomb, mixed integration and plane strain,
/// one, three, four and ten points per element, with and without the objective terms, in both
/// precisions,
/// stepped until stresses, velocities and (in the Mohr-Coulomb column) returns are well
/// under way.
#[test]
fn the_avx2_passes_give_the_portable_bits() {
    use crate::element::{tet4::Tet4, tri3::Tri3};
    if !crate::parallel::avx2::detected() {
        eprintln!("skipped: this processor has no AVX2, or the build assumes it");
        return;
    }
    for (scene, steps) in [
        ("golden/column_dry.toml", 60),
        ("golden/column_saturated.toml", 60),
        ("mc_column.toml", 60),
        // MPM-MIXED: full elements' Gauss-point tractions before their points' sums.
        ("oracle_mc_footing.toml", 20),
        // Four points per element: the stress pass's linear-elastic lanes take whole
        // batches (the columns above hold one point per element), dry and saturated, with
        // the objective terms.
        ("column_gravity.toml+objective", 40),
        ("oedometer.toml+objective", 40),
        // Ten points per element: the last two of each element in the lanes too.
        ("column_gravity.toml+ten+objective", 30),
        ("oedometer.toml+ten", 30),
    ] {
        let portable = state_bits::<f64, Tet4>(scene, steps, true);
        assert!(portable.iter().any(|&b| b != 0), "{scene}: no state");
        assert!(
            portable == state_bits::<f64, Tet4>(scene, steps, false),
            "{scene} f64"
        );
        let portable = state_bits::<f32, Tet4>(scene, steps, true);
        assert!(
            portable == state_bits::<f32, Tet4>(scene, steps, false),
            "{scene} f32"
        );
    }
    // Plane strain, three points per element: the stress pass's lanes take each
    // element's three in four lanes; dry and saturated, and with `+shear` points leave
    // their elements and are walked.
    for scene in [
        "oedometer_2d.toml",
        "oedometer_2d.toml+objective",
        "oedometer_2d.toml+shear",
        "oedometer_2d.toml+dry+shear",
    ] {
        let portable = state_bits::<f64, Tri3>(scene, 60, true);
        assert!(
            portable == state_bits::<f64, Tri3>(scene, 60, false),
            "{scene} f64"
        );
        let portable = state_bits::<f32, Tri3>(scene, 60, true);
        assert!(
            portable == state_bits::<f32, Tri3>(scene, 60, false),
            "{scene} f32"
        );
    }
}
