//! The split system (`Assembler::set_split`, issue 18) is the unsplit one:
//! `A_v + Cᵀ C` and its right-hand side equal the assembled matrix and
//! right-hand side entry by entry, prescribed velocities included, and the
//! block-preconditioned solver returns the direct solver's solution.

use pfem_assembly::{
    Assembler, AssemblyInput, BlockSolver, Constraints, DirectSolver, Inertia, LinearSolver,
    PressureSolve, StepMesh, VolumetricTreatment,
};
use pfem_constitutive::{History, Hypoelastic, Material, Newtonian};
use pfem_core::{Point, Vector};

struct Tank {
    x: Vec<Point<2>>,
    v: Vec<Vector<2>>,
    a: Vec<Vector<2>>,
    p: Vec<f64>,
    tris: Vec<u32>,
    mat: Vec<u16>,
    history: Vec<History<2>>,
    constraints: Constraints<2>,
    materials: Vec<Box<dyn Material<2>>>,
}

/// Water on an `n × n` grid of cells 1 m wide, walls on three sides; the
/// left wall moves (a prescribed non-zero velocity) and the water has a
/// velocity field, so that prescribed columns reach the right-hand side.
fn tank(n: usize) -> Tank {
    tank_with(n, false)
}

/// [`tank`], with the lower half a stiff elastic solid when `solid`.
fn tank_with(n: usize, solid: bool) -> Tank {
    let mut x = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (fi, fj) = (i as f64 / n as f64, j as f64 / n as f64);
            // A slightly perturbed lattice: no symmetric accident.
            x.push(Point::<2>::new(
                fi + 0.01 * (fj * 7.0).sin() / n as f64,
                fj + 0.01 * (fi * 5.0).cos() / n as f64,
            ));
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            tris.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    let np = x.len();
    let mut constraints = Constraints::<2>::free(np);
    for i in 0..=n {
        for j in 0..=n {
            let k = id(i, j) as usize;
            if i == 0 {
                constraints.fix(k, Vector::<2>::new(0.1, 0.02));
            } else if j == 0 || i == n {
                constraints.fix(k, Vector::<2>::zeros());
            }
        }
    }
    let v = x
        .iter()
        .map(|q| Vector::<2>::new((3.0 * q.y).sin() * 0.1, (2.0 * q.x).cos() * 0.05))
        .collect();
    let ne = tris.len() / 3;
    // Element e lies in cell row e / (2n).
    let mat: Vec<u16> = (0..ne)
        .map(|e| u16::from(solid && e / (2 * n) < n / 2))
        .collect();
    Tank {
        v,
        a: vec![Vector::<2>::zeros(); np],
        p: x.iter().map(|q| 9810.0 * (1.0 - q.y)).collect(),
        x,
        tris,
        mat,
        history: vec![History::default(); ne],
        constraints,
        materials: vec![
            Box::new(Newtonian::water()),
            Box::new(Hypoelastic::new(1000.0, 1e9, 0.3).unwrap()),
        ],
    }
}

fn assembled(t: &Tank, split: bool) -> Assembler<2> {
    let dt = 1e-3;
    let mut asm = Assembler::<2>::new(VolumetricTreatment::NodalAveraged);
    asm.set_split(split);
    asm.prepare(
        t.x.len(),
        StepMesh {
            elements: &t.tris,
            element_material: &t.mat,
            closures: &[],
            surface_cuts: Default::default(),
        },
        &t.materials,
    )
    .unwrap();
    asm.assemble(&AssemblyInput {
        x: &t.x,
        x_n: &t.x,
        v: &t.v,
        v_n: &t.v,
        a_n: &t.a,
        pressure_n: &t.p,
        element_history: &t.history,
        materials: &t.materials,
        constraints: &t.constraints,
        body_force: Some(Vector::<2>::new(0.0, -9.81)),
        dt,
        inertia: Inertia {
            mass_factor: 2.0 / dt,
            acceleration_factor: 1.0,
            displacement_weight: 0.5 * dt,
        },
    })
    .unwrap();
    asm
}

fn dense(a: faer::sparse::SparseColMatRef<'_, usize, f64>) -> Vec<Vec<f64>> {
    let mut d = vec![vec![0.0; a.ncols()]; a.nrows()];
    for j in 0..a.ncols() {
        for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            d[i][j] += v;
        }
    }
    d
}

#[test]
fn the_split_system_is_the_assembled_one() {
    let t = tank(6);
    let whole = assembled(&t, false);
    let split = assembled(&t, true);
    assert!(whole.split_system().is_none());
    let sys = split.split_system().unwrap();
    assert!(
        sys.a_v.compute_nnz() < whole.matrix().compute_nnz(),
        "the split matrix keeps only element couplings"
    );
    let a = dense(whole.matrix());
    let b = dense(sys.to_matrix().unwrap().as_ref());
    let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for (ra, rb) in a.iter().zip(&b) {
        for (x, y) in ra.iter().zip(rb) {
            worst = worst.max((x - y).abs());
        }
    }
    assert!(
        worst <= 1e-12 * scale,
        "matrix differs by {worst:e} of {scale:e}"
    );
    let fscale = whole.rhs().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (x, y) in whole.rhs().iter().zip(sys.rhs) {
        assert!((x - y).abs() <= 1e-12 * fscale, "rhs {x} vs {y}");
    }
}

/// Solves the tank with the direct solver and with `block`; returns the
/// relative difference of the solutions.
fn against_direct(t: &Tank, block: &mut BlockSolver, label: &str) -> f64 {
    let whole = assembled(t, false);
    let split = assembled(t, true);
    let n = whole.dofs();
    let mut x0 = vec![0.0; n];
    DirectSolver::default()
        .solve(whole.matrix(), 1, whole.rhs(), &mut x0)
        .unwrap();
    let mut x1 = vec![0.0; n];
    let rep = block
        .solve_split(&split.split_system().unwrap(), 1, &mut x1)
        .unwrap();
    let norm = x0.iter().map(|v| v * v).sum::<f64>().sqrt();
    let diff = x0
        .iter()
        .zip(&x1)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt();
    println!(
        "{label}: {} iterations, residual {:.2e}, difference from direct {:.2e}",
        rep.iterations,
        rep.residual,
        diff / norm
    );
    diff / norm
}

#[test]
fn the_block_solver_solves_the_split_system_as_the_direct_one_does() {
    let mut block = BlockSolver::default();
    let d = against_direct(
        &tank(12),
        &mut block,
        "water, Cholesky of the pressure matrix",
    );
    assert!(d <= 1e-8, "{d}");
    assert_eq!(block.stats().stiff_setups, 0);
    assert_eq!(block.stats().fallbacks, 0);
    // A stiff solid below the water: its rows are kept whole.
    let mut block = BlockSolver::default();
    let d = against_direct(&tank_with(12, true), &mut block, "water on a stiff solid");
    assert!(d <= 1e-8, "{d}");
    assert_eq!(block.stats().stiff_setups, 1);
    assert_eq!(block.stats().fallbacks, 0);
    // The multigrid path reaches the same solution (more iterations).
    let mut block = BlockSolver::default();
    block.pressure = PressureSolve::Multigrid;
    let d = against_direct(&tank(12), &mut block, "water, multigrid");
    assert!(d <= 1e-6, "{d}");
    assert_eq!(block.stats().fallbacks, 0);
}
