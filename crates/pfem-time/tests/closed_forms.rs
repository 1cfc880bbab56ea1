//! Closed-form checks of the Newmark–Picard step on fixed meshes: free fall,
//! hydrostatics, patch tests, locking shown and cured.

use crate::common;

use pfem_assembly::{Constraints, StepMesh, VolumetricTreatment};
use pfem_constitutive::{History, Material, Newtonian};
use pfem_core::{Point, Vector};
use pfem_time::{Integrator, ParticleState, Scheme, StepInput, StepParams};

const G: f64 = 9.81;

fn centroid(x: &[Point<2>]) -> Point<2> {
    x.iter().fold(Point::<2>::zeros(), |a, b| a + b) / x.len() as f64
}

/// An integrator built with a setting outside its range refuses its first
/// attempt with the setting named (`StepParams::validate`); a zero Picard
/// tolerance used to show only as every step failing to converge.
#[test]
fn an_integrator_with_a_zero_tolerance_names_it() {
    let (pts, tris) = common::grid(0.0, 1.0, 0.2, 0.2, 4, 4);
    let ne = tris.len() / 3;
    let materials: Vec<Box<dyn Material<2>>> = vec![Box::new(Newtonian::water())];
    let mat = vec![0u16; ne];
    let mut history = vec![History::<2>::default(); ne];
    let constraints = Constraints::<2>::free(pts.len());
    let mut state = ParticleState::at_rest(pts);
    let mut integ = Integrator::<2>::new(StepParams {
        picard_tolerance: 0.0,
        ..StepParams::default()
    });
    let input = StepInput {
        mesh: StepMesh {
            elements: &tris,
            element_material: &mat,
            closures: &[],
            surface_cuts: Default::default(),
            reference_volumes: &[],
            node_material: &[],
        },
        materials: &materials,
        constraints: &constraints,
        body_force: Some(Vector::<2>::new(0.0, -G)),
        external_force: &[],
    };
    let err = integ
        .try_step(0.0, 1e-3, &mut state, &mut history, &input)
        .unwrap_err()
        .to_string();
    assert!(err.contains("picard_tolerance"), "{err}");
}

#[test]
fn free_fall_of_a_detached_fluid_block() {
    let (pts, tris) = common::grid(0.0, 1.0, 0.2, 0.2, 8, 8);
    let ne = tris.len() / 3;
    let materials: Vec<Box<dyn Material<2>>> = vec![Box::new(Newtonian::water())];
    let mat = vec![0u16; ne];
    let mut history = vec![History::<2>::default(); ne];
    let constraints = Constraints::<2>::free(pts.len());
    let mut state = ParticleState::at_rest(pts);
    let y0 = centroid(&state.x).y;
    let mut integ = Integrator::<2>::new(StepParams::default());
    let input = StepInput {
        mesh: StepMesh {
            elements: &tris,
            element_material: &mat,
            closures: &[],
            surface_cuts: Default::default(),
            reference_volumes: &[],
            node_material: &[],
        },
        materials: &materials,
        constraints: &constraints,
        body_force: Some(Vector::<2>::new(0.0, -G)),
        external_force: &[],
    };
    integ
        .initialize_acceleration(&mut state, &history, &input)
        .unwrap();
    let dt = 0.01;
    let mut t = 0.0;
    for _ in 0..30 {
        let rep = integ
            .advance(t, dt, &mut state, &mut history, &input)
            .unwrap();
        t += rep.dt;
    }
    let y = centroid(&state.x).y;
    let exact = y0 - 0.5 * G * t * t;
    println!(
        "free fall on a fixed mesh: relative error {:e}",
        ((y - exact) / (y0 - exact)).abs()
    );
    // Newmark is exact for a constant acceleration: measured 3.5·10⁻¹⁵
    // (the bound was 5·10⁻³ until session 42).
    assert!(
        ((y - exact) / (y0 - exact)).abs() < 1e-9,
        "centroid {y} vs {exact}"
    );
    let pmax = state.pressure.iter().fold(0.0f64, |m, p| m.max(p.abs()));
    // "near zero": far below the hydrostatic scale of a 0.2 m column.
    assert!(pmax < 1e-3 * 1000.0 * G * 0.2, "pressure {pmax}");
}

/// A water column of height `h` in a tank whose bottom and side rows of
/// particles are walls; returns (state, history, mesh, constraints).
fn tank(h: f64, n: usize) -> (ParticleState<2>, Vec<u32>, Constraints<2>) {
    let (pts, tris) = common::grid(0.0, 0.0, h, h, n, n);
    let mut constraints = Constraints::<2>::free(pts.len());
    for (i, p) in pts.iter().enumerate() {
        if p.y < 1e-9 || p.x < 1e-9 || p.x > h - 1e-9 {
            constraints.fix(i, Vector::<2>::zeros());
        }
    }
    // Elements made only of wall particles are not elements.
    let tris: Vec<u32> = tris
        .chunks(3)
        .filter(|t| t.iter().any(|&q| constraints.mask[q as usize] == 0))
        .flatten()
        .copied()
        .collect();
    (ParticleState::at_rest(pts), tris, constraints)
}

fn run_tank(
    treatment: VolumetricTreatment,
    scheme: Scheme,
    hydrostatic_start: bool,
    t_end: f64,
) -> (ParticleState<2>, f64, f64, f64) {
    let h = 0.5;
    let (mut state, tris, constraints) = tank(h, 20);
    if hydrostatic_start {
        for (p, x) in state.pressure.iter_mut().zip(&state.x) {
            *p = 1000.0 * G * (h - x.y);
        }
    }
    let ne = tris.len() / 3;
    let materials: Vec<Box<dyn Material<2>>> = vec![Box::new(Newtonian::water())];
    let mat = vec![0u16; ne];
    let mut history = vec![History::<2>::default(); ne];
    let params = StepParams {
        volumetric: treatment,
        scheme,
        ..Default::default()
    };
    let mut integ = Integrator::<2>::new(params);
    let input = StepInput {
        mesh: StepMesh {
            elements: &tris,
            element_material: &mat,
            closures: &[],
            surface_cuts: Default::default(),
            reference_volumes: &[],
            node_material: &[],
        },
        materials: &materials,
        constraints: &constraints,
        body_force: Some(Vector::<2>::new(0.0, -G)),
        external_force: &[],
    };
    let vol0 = volume(&state.x, &tris);
    let mut t = 0.0;
    let dt = 0.005;
    let mut vmax: f64 = 0.0;
    while t < t_end - 1e-12 {
        let rep = integ
            .advance(t, dt, &mut state, &mut history, &input)
            .unwrap();
        t += rep.dt;
        vmax = state.v.iter().fold(vmax, |m, v| m.max(v.norm()));
    }
    let vol = volume(&state.x, &tris);
    (state, vmax, vol0, vol)
}

fn volume(x: &[Point<2>], tris: &[u32]) -> f64 {
    tris.chunks(3)
        .map(|t| {
            pfem_core::simplex_measure::<2>(&[x[t[0] as usize], x[t[1] as usize], x[t[2] as usize]])
        })
        .sum()
}

/// Largest error of the nodal pressure of fluid particles against
/// ρ g (H − y), relative to ρ g H.
fn pressure_error(state: &ParticleState<2>, h: f64) -> f64 {
    let mut err: f64 = 0.0;
    for (p, x) in state.pressure.iter().zip(&state.x) {
        if x.y > 1e-9 && x.x > 1e-9 && x.x < h - 1e-9 {
            err = err.max((p - 1000.0 * G * (h - x.y)).abs());
        }
    }
    err / (1000.0 * G * h)
}

#[test]
fn water_at_rest_with_real_bulk_modulus_stays_hydrostatic() {
    let h = 0.5;
    let (state, vmax, vol0, vol) = run_tank(
        VolumetricTreatment::NodalAveraged,
        Scheme::Newmark,
        true,
        1.0,
    );
    let e = pressure_error(&state, h);
    assert!(e < 0.01, "pressure error {e}");
    assert!(vmax < 1e-3 * (G * h).sqrt(), "spurious velocity {vmax}");
    assert!(((vol - vol0) / vol0).abs() < 1e-3, "volume {vol0} -> {vol}");
}

#[test]
fn water_released_without_pressure_settles_to_hydrostatic() {
    // Start with p = 0: gravity compresses the column; backward Euler damps
    // the acoustic transient and the pressure settles to ρ g (H − y).
    let h = 0.5;
    let (state, _vmax, vol0, vol) = run_tank(
        VolumetricTreatment::NodalAveraged,
        Scheme::BackwardEuler,
        false,
        1.0,
    );
    let e = pressure_error(&state, h);
    assert!(e < 0.01, "pressure error {e}");
    let vend = state.v.iter().fold(0.0f64, |m, v| m.max(v.norm()));
    assert!(vend < 1e-3 * (G * h).sqrt(), "residual velocity {vend}");
    assert!(((vol - vol0) / vol0).abs() < 1e-3, "volume {vol0} -> {vol}");
}

/// Two fluids of different bulk moduli side by side, squeezed uniformly
/// (every particle's velocity prescribed, `v = −(x − x_c)/s`: the nodal
/// volumetric strain rate is −2/s everywhere). A node where the two meet
/// gets the pressure of each material's update (eq. 62) weighted by its
/// share of the node's weights, the weights of the momentum equation's
/// volume-averaged `𝒦_a`; a node of one fluid, its own. Session 40's
/// review: the update used the first element's material at an interface
/// node, so its pressure was `2 Δt K₀` or `2 Δt K₁` where the momentum
/// equation had balanced the mean.
#[test]
fn where_two_fluids_meet_the_pressure_update_weighs_both() {
    let (nx, ny) = (4, 4);
    let (pts, tris) = common::grid(0.0, 0.0, 0.4, 0.4, nx, ny);
    let ne = tris.len() / 3;
    let (k0, k1) = (2.2e9, 2.2e7);
    let materials: Vec<Box<dyn Material<2>>> = vec![
        Box::new(Newtonian::new(1000.0, 1e-3, k0).unwrap()),
        Box::new(Newtonian::new(1000.0, 1e-3, k1).unwrap()),
    ];
    // Material 1 right of x = 0.2 (by each triangle's centroid).
    let mat: Vec<u16> = tris
        .chunks_exact(3)
        .map(|t| {
            let cx = t.iter().map(|&i| pts[i as usize].x).sum::<f64>() / 3.0;
            u16::from(cx > 0.2)
        })
        .collect();
    let mut history = vec![History::<2>::default(); ne];
    let centre = Point::<2>::new(0.2, 0.2);
    let mut constraints = Constraints::<2>::free(pts.len());
    for (i, p) in pts.iter().enumerate() {
        constraints.fix(i, -(p - centre));
    }
    // Each node's weights by material: a third of each element's area.
    let mut share = vec![[0.0f64; 2]; pts.len()];
    for (t, &m) in tris.chunks_exact(3).zip(&mat) {
        let p: Vec<Point<2>> = t.iter().map(|&i| pts[i as usize]).collect();
        let area = pfem_core::simplex_measure::<2>(&p);
        for &i in t {
            share[i as usize][m as usize] += area / 3.0;
        }
    }
    let mut state = ParticleState::at_rest(pts.clone());
    for (i, p) in pts.iter().enumerate() {
        state.v[i] = -(p - centre);
    }
    let mut integ = Integrator::<2>::new(StepParams::default());
    let input = StepInput {
        mesh: StepMesh {
            elements: &tris,
            element_material: &mat,
            ..Default::default()
        },
        materials: &materials,
        constraints: &constraints,
        body_force: None,
        external_force: &[],
    };
    let dt = 1e-5;
    integ
        .try_step(0.0, dt, &mut state, &mut history, &input)
        .unwrap();
    let mut mixed = 0;
    for (i, w) in share.iter().enumerate() {
        let k = (w[0] * k0 + w[1] * k1) / (w[0] + w[1]);
        let want = 2.0 * dt * k;
        let got = state.pressure[i];
        assert!(
            (got - want).abs() < 1e-3 * want,
            "node {i} (shares {w:?}): {got} Pa against {want}"
        );
        if w[0] > 0.0 && w[1] > 0.0 {
            mixed += 1;
        }
    }
    assert_eq!(mixed, ny + 1, "the middle column meets both fluids");
}

/// A flying particle held on a slip plane (its x velocity prescribed at
/// zero) under a tilted gravity stays on the plane: it falls freely along
/// y only. Session 40's review: its stored acceleration took gravity's x
/// component too, and Bossak's next position moved it off the plane by
/// about `0.028 Δt² g_x` a step.
#[test]
fn a_flying_particle_on_a_slip_plane_stays_on_it() {
    let materials: Vec<Box<dyn Material<2>>> = vec![Box::new(Newtonian::water())];
    let mut constraints = Constraints::<2>::free(1);
    constraints.fix_component(0, 0, 0.0);
    let mut state = ParticleState::at_rest(vec![Point::<2>::new(0.0, 1.0)]);
    let mut history: Vec<History<2>> = Vec::new();
    let mut integ = Integrator::<2>::new(StepParams::default());
    let input = StepInput {
        mesh: StepMesh::default(),
        materials: &materials,
        constraints: &constraints,
        body_force: Some(Vector::<2>::new(3.0, -G)),
        external_force: &[],
    };
    integ
        .initialize_acceleration(&mut state, &history, &input)
        .unwrap();
    let dt = 1e-2;
    for k in 0..5 {
        integ
            .try_step(k as f64 * dt, dt, &mut state, &mut history, &input)
            .unwrap();
        assert_eq!(state.x[0].x, 0.0, "step {k}: off the plane");
        assert_eq!(state.a[0].x, 0.0, "step {k}: acceleration across the plane");
    }
    let t = 5.0 * dt;
    assert!(
        (state.x[0].y - (1.0 - 0.5 * G * t * t)).abs() < 1e-9,
        "{}",
        state.x[0].y
    );
}

/// Session 41 (a review of the time stepping): a non-finite body force
/// passed a particle outside every element through the step (its free
/// flight is not iterated, and `f64::max` hid the NaN in the velocity
/// floor): `try_step` returned `Ok` with the position NaN. A non-number
/// in the start state was retried at halved steps down to `min_dt`. Both
/// are the caller's input, refused at once and not retryable; so is a
/// prescribed-velocity array of the wrong length (it panicked).
#[test]
fn non_finite_or_mismatched_input_is_refused_not_stepped() {
    let materials: Vec<Box<dyn Material<2>>> = vec![Box::new(Newtonian::water())];
    let constraints = Constraints::<2>::free(1);
    let mut history: Vec<History<2>> = Vec::new();
    let mut integ = Integrator::<2>::new(StepParams::default());
    let step = |integ: &mut Integrator<2>,
                state: &mut ParticleState<2>,
                history: &mut Vec<History<2>>,
                constraints: &Constraints<2>,
                body_force: Vector<2>| {
        let input = StepInput {
            mesh: StepMesh::default(),
            materials: &materials,
            constraints,
            body_force: Some(body_force),
            external_force: &[],
        };
        integ.try_step(0.0, 1e-3, state, history, &input)
    };
    let fresh = || ParticleState::at_rest(vec![Point::<2>::new(0.0, 1.0)]);
    let mut state = fresh();
    let err = step(
        &mut integ,
        &mut state,
        &mut history,
        &constraints,
        Vector::<2>::new(f64::NAN, -G),
    )
    .unwrap_err();
    assert!(
        !err.is_retryable() && err.to_string().contains("body force"),
        "{err}"
    );
    assert!(state.x[0].iter().all(|c| c.is_finite()));
    let mut state = fresh();
    state.v[0].y = f64::INFINITY;
    let err = step(
        &mut integ,
        &mut state,
        &mut history,
        &constraints,
        Vector::<2>::new(0.0, -G),
    )
    .unwrap_err();
    assert!(
        !err.is_retryable() && err.to_string().contains("particle 0"),
        "{err}"
    );
    let mut state = fresh();
    let short = Constraints::<2> {
        mask: constraints.mask.clone(),
        velocity: Vec::new(),
    };
    let err = step(
        &mut integ,
        &mut state,
        &mut history,
        &short,
        Vector::<2>::new(0.0, -G),
    )
    .unwrap_err();
    assert!(
        !err.is_retryable() && err.to_string().contains("lengths"),
        "{err}"
    );
    // The same particle with finite input falls.
    let mut state = fresh();
    step(
        &mut integ,
        &mut state,
        &mut history,
        &constraints,
        Vector::<2>::new(0.0, -G),
    )
    .unwrap();
    assert!(state.x[0].y < 1.0);
}
