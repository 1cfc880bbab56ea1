//! PETSc's answers against the pure-Rust direct solve, on split systems
//! built by hand (a velocity block, volumetric rows of water's size, with
//! and without the pressure stabilisation).
//! `cargo test --release -p pfem-petsc --features petsc`
#![cfg(feature = "petsc")]

use faer::sparse::{SparseColMat, Triplet};
use pfem_assembly::solver::Stabilisation;
use pfem_assembly::{DirectSolver, LinearSolver, SplitSystem};
use pfem_petsc::PetscSolver;

/// A 2D grid of `k × k` nodes (2 dofs each): `A_v` a mass `m` plus a
/// viscous Laplacian `mu` on each component, `C` one row per node, the
/// discrete divergence of the node's patch scaled by `s` (water: `s²` about
/// 10⁶–10⁷ times `m`).
struct Grid {
    a: SparseColMat<usize, f64>,
    c_ptr: Vec<usize>,
    c_idx: Vec<usize>,
    c_val: Vec<f64>,
    coords: Vec<f64>,
    rhs: Vec<f64>,
    l_ptr: Vec<usize>,
    l_idx: Vec<usize>,
    l_val: Vec<f64>,
    offset: Vec<f64>,
}

fn grid(k: usize, m: f64, mu: f64, s: f64) -> Grid {
    let node = |i: usize, j: usize| i * k + j;
    let n = 2 * k * k;
    let mut t = Vec::new();
    let mut lap = vec![Vec::<(usize, f64)>::new(); k * k];
    for i in 0..k {
        for j in 0..k {
            let a = node(i, j);
            let mut diag = 0.0;
            for (di, dj) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
                let (ii, jj) = (i as i64 + di, j as i64 + dj);
                if ii < 0 || jj < 0 || ii >= k as i64 || jj >= k as i64 {
                    continue;
                }
                let b = node(ii as usize, jj as usize);
                diag += 1.0;
                lap[a].push((b, -1.0));
                for d in 0..2 {
                    t.push(Triplet::new(2 * a + d, 2 * b + d, -mu));
                }
            }
            lap[a].push((a, diag));
            for d in 0..2 {
                t.push(Triplet::new(2 * a + d, 2 * a + d, m + diag * mu));
            }
        }
    }
    let a = SparseColMat::try_new_from_triplets(n, n, &t).unwrap();
    // C: central-difference divergence of the node's neighbours.
    let (mut c_ptr, mut c_idx, mut c_val) = (vec![0], vec![], vec![]);
    for i in 0..k {
        for j in 0..k {
            let mut row: Vec<(usize, f64)> = Vec::new();
            if i + 1 < k {
                row.push((2 * node(i + 1, j), s));
            }
            if i > 0 {
                row.push((2 * node(i - 1, j), -s));
            }
            if j + 1 < k {
                row.push((2 * node(i, j + 1) + 1, s));
            }
            if j > 0 {
                row.push((2 * node(i, j - 1) + 1, -s));
            }
            row.sort_by_key(|e| e.0);
            for (c, v) in row {
                c_idx.push(c);
                c_val.push(v);
            }
            c_ptr.push(c_idx.len());
        }
    }
    let coords = (0..k * k)
        .flat_map(|a| [(a / k) as f64, (a % k) as f64])
        .collect();
    let rhs = (0..n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
    let (mut l_ptr, mut l_idx, mut l_val) = (vec![0], vec![], vec![]);
    for row in &mut lap {
        row.sort_by_key(|e| e.0);
        for &(c, v) in row.iter() {
            l_idx.push(c);
            l_val.push(0.1 * v);
        }
        l_ptr.push(l_idx.len());
    }
    let offset = (0..k * k).map(|i| (i % 5) as f64 * 1e-3).collect();
    Grid {
        a,
        c_ptr,
        c_idx,
        c_val,
        coords,
        rhs,
        l_ptr,
        l_idx,
        l_val,
        offset,
    }
}

fn system(g: &Grid, stabilised: bool) -> SplitSystem<'_> {
    SplitSystem {
        a_v: g.a.as_ref(),
        c_ptr: &g.c_ptr,
        c_idx: &g.c_idx,
        c_val: &g.c_val,
        block_size: 2,
        coords: &g.coords,
        rhs: &g.rhs,
        stabilisation: stabilised.then_some(Stabilisation {
            l_ptr: &g.l_ptr,
            l_idx: &g.l_idx,
            l_val: &g.l_val,
            offset: &g.offset,
            row_ids: None,
        }),
    }
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let n: f64 = b.iter().map(|y| y * y).sum();
    (d / n).sqrt()
}

#[test]
fn petsc_solves_the_split_system_as_the_direct_solver_does() {
    // Water-like: s² / m = 10⁶ (at 10⁷ every solver, direct ones included,
    // stops at a residual of 2·10⁻⁹ on this grid).
    for (k, s) in [(12, 1.0e3), (30, 1.0e3), (30, 30.0)] {
        let g = grid(k, 1.0, 1e-2, s);
        let sys = system(&g, false);
        let whole = sys.to_matrix().unwrap();
        let mut xd = vec![0.0; g.rhs.len()];
        DirectSolver::default()
            .solve(whole.as_ref(), 0, &g.rhs, &mut xd)
            .unwrap();
        let mut petsc = PetscSolver::with_options("");
        petsc.fallback = false;
        let mut xp = vec![0.0; g.rhs.len()];
        let rep = petsc.solve_split(&sys, 0, &mut xp).unwrap();
        let d = rel_diff(&xp, &xd);
        println!(
            "k = {k}, s = {s}: {} iterations, residual {:.2e}, difference {d:.2e}, {:?}",
            rep.iterations,
            rep.residual,
            petsc.stats()
        );
        assert_eq!(petsc.stats().fallbacks, 0, "PETSc did not converge");
        assert!(rep.residual <= 1e-9, "residual {}", rep.residual);
        assert!(d < 1e-7, "PETSc and direct differ by {d}");
    }
}

#[test]
fn petsc_solves_the_stabilised_system_as_the_saddle_point_factor_does() {
    let g = grid(20, 1.0, 1e-2, 3.0e3);
    let sys = system(&g, true);
    let mut xd = vec![0.0; g.rhs.len()];
    pfem_assembly::block::solve_saddle(&sys, &mut xd).unwrap();
    let mut petsc = PetscSolver::with_options("");
    let mut xp = vec![0.0; g.rhs.len()];
    let rep = petsc.solve_split(&sys, 0, &mut xp).unwrap();
    let d = rel_diff(&xp, &xd);
    println!(
        "stabilised: {} iterations, residual {:.2e}, difference {d:.2e}",
        rep.iterations, rep.residual
    );
    assert_eq!(petsc.stats().fallbacks, 0);
    assert!(d < 1e-7, "PETSc and L D Lᵀ differ by {d}");
}

#[test]
fn petsc_options_are_used_and_bad_ones_are_errors_not_panics() {
    let g = grid(10, 1.0, 1e-2, 3.0e3);
    let sys = system(&g, false);
    // hypre's BoomerAMG on the pressure: same answer.
    let mut hypre = PetscSolver::with_options("-pfem_fieldsplit_p_pc_type hypre");
    let mut xh = vec![0.0; g.rhs.len()];
    hypre.solve_split(&sys, 0, &mut xh).unwrap();
    assert_eq!(hypre.stats().fallbacks, 0);
    // A KSP that cannot converge in one iteration: an error when the
    // fallback is off, the direct answer when it is on.
    let mut starved = PetscSolver::with_options("-pfem_ksp_max_it 1");
    starved.fallback = false;
    let mut x = vec![0.0; g.rhs.len()];
    let err = starved.solve_split(&sys, 0, &mut x).unwrap_err();
    assert!(err.to_string().contains("petsc"), "{err}");
    starved.fallback = true;
    starved.solve_split(&sys, 0, &mut x).unwrap();
    assert_eq!(starved.stats().fallbacks, 1);
    assert!(rel_diff(&x, &xh) < 1e-7);
    // An unknown PC type is PETSc's error, returned.
    let mut bad = PetscSolver::with_options("-pfem_pc_type no-such-pc");
    bad.fallback = false;
    let err = bad.solve_split(&sys, 0, &mut x).unwrap_err();
    println!("{err}");
    // A non-finite right-hand side is refused before PETSc sees it.
    let mut g2 = grid(4, 1.0, 1e-2, 3.0e3);
    g2.rhs[3] = f64::NAN;
    let sys2 = system(&g2, false);
    let mut x2 = vec![0.0; g2.rhs.len()];
    assert!(PetscSolver::with_options("")
        .solve_split(&sys2, 0, &mut x2)
        .is_err());
}
