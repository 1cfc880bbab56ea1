//! An iterative path for the monolithic system that keeps the nodal
//! volumetric term apart: the split system ([`SplitSystem`],
//! `(A_v + Cᵀ C) V = f`), solved by [`BlockSolver`].
//!
//! With real water the eliminated matrix `A = A_v + Cᵀ C` is dominated by
//! the nodal volumetric term `Cᵀ C` (`Δt 𝒦` is 10⁶–10⁷ times the viscous
//! term), which defeats plain Krylov methods and plain algebraic multigrid.
//! Its structure is what makes it cheap: `A_v` (inertia, viscosity, solid
//! stiffness) is nearly its diagonal `Â` for water, and `C` has one row per
//! fluid node. Two ways are offered ([`PressureSolve`]):
//!
//! - **[`PressureSolve::Cholesky`]** (what [`PressureSolve::Auto`], the
//!   default, chooses for the paper's unstabilised pressure and for small
//!   stabilised systems): conjugate gradient on `A`
//!   itself, preconditioned by `M = Â + Cᵀ C` applied exactly through the
//!   Woodbury identity
//!
//!   `M⁻¹ = Â⁻¹ − Â⁻¹ Cᵀ Ŝ⁻¹ C Â⁻¹`, `Ŝ = I + C Â⁻¹ Cᵀ`,
//!
//!   with `Ŝ` (one unknown per fluid node, a pressure Laplacian plus a mass
//!   term) factored by sparse Cholesky. `M` is symmetric positive definite
//!   and differs from `A` only by the off-diagonal part of `A_v`, so a few
//!   iterations reach the direct solver's residual; the factor is `D`
//!   times smaller in unknowns and `D³` in flops than the whole system's.
//!   An older `M` is still symmetric positive definite, only further from
//!   `A`: with water's volumetric term `10⁶` times the rest, a relative
//!   move `δ` of `C` perturbs `M` by about `10⁶ δ` against `Â`. So a
//!   later Picard iterate of the same pattern keeps the factor of an
//!   earlier one only while `C` has moved by at most
//!   [`BlockSolver::keep_factor_below`] since it: on the column on a
//!   cylinder at a/20, the loop's second and third iterates move it by
//!   10⁻²–10⁻³ (an old factor took 140–2 000 iterations), its fourth by
//!   about 10⁻⁴ (6–13 on the third's factor), later ones by 10⁻⁵ and
//!   less (3–6 on the fourth's), against 2 on a factor of their own
//!   (session 32). A kept factor's iteration aims at a hundredth of the
//!   target, where a new factor's two iterations land; one that has not
//!   converged in [`BlockSolver::kept_factor_iterations`] is renewed and
//!   the iteration goes on. Nothing is kept from one Picard loop to the
//!   next ([`LinearSolver::begin_loop`]). ([`BlockSolver::reuse_setup`] keeps the
//!   set-up for every iterate of a step, whatever the move.)
//! - **[`PressureSolve::Multigrid`]**: MINRES on the equivalent
//!   saddle-point system `[A_v Cᵀ; C −I] [V; q] = [f; 0]` (`q = C V`, the
//!   scaled nodal pressure increment; eliminating `q` gives eq. 55 back)
//!   with the block-diagonal preconditioner `diag(Â_v, Ŝ)`, `Â_v` Jacobi or
//!   one V-cycle of smoothed aggregation ([`crate::amg`], rigid-body modes)
//!   and `Ŝ` one V-cycle of smoothed aggregation, inside passes of
//!   refinement on the eliminated residual. Its cost per iteration grows
//!   linearly, but its iterations do not stay bounded yet: the equal-order
//!   nodal pressure's spurious modes (fields with zero mean on every
//!   element, which `Cᵀ` does not see) are near-null vectors of `Ŝ` that
//!   aggregation does not capture (measured on the 2D dam break at a/20:
//!   143 iterations of multigrid-preconditioned CG on `Ŝ` alone), so
//!   without stabilisation it is not the default. With the pressure
//!   stabilisation (`Assembler::set_pressure_stabilisation`,
//!   [`SplitSystem::stabilisation`]) they are gone: the iteration runs on
//!   `[A_v Cᵀ; C −(I + L̃)]` with `Ŝ` grown by `L̃`, warm-started from the
//!   last Picard iterate's `q` and keeping the multigrid set-up across the
//!   iterates of a step ([`BlockSolver::stabilised_reuse`]) and carrying
//!   its pressure hierarchy over to the next steps' patterns, row by row
//!   through their particles ([`BlockSolver::carry_steps`]), and its
//!   iterations stay nearly flat in size and in the bulk modulus
//!   (`crates/pfem-assembly/tests/split_system.rs`). By default
//!   ([`Krylov::Gmres`]) it is GMRES preconditioned on the right by the
//!   block upper-triangular `[Â_v Cᵀ; 0 −Ŝ]`: with exact blocks that would
//!   converge in two iterations, where the block-diagonal preconditioner
//!   leaves MINRES the two eigenvalue clusters near `1` and `(1 ± √5)/2`;
//!   and right preconditioning minimises the very residual the solve stops
//!   on. Measured on the running 2D dam break (session 20), 11.6 and 13.4
//!   iterations per solve at 15k and 109k particles against MINRES's 31.5
//!   and 36.6, half the solve time.
//!
//! A stabilised system has no sparse eliminated matrix: with
//! [`PressureSolve::Cholesky`], with [`PressureSolve::Auto`] below
//! [`BlockSolver::multigrid_from`] pressure rows, and in every other
//! solver's default `solve_split`, it is solved by one sparse `L D Lᵀ` of
//! its saddle-point form ([`solve_saddle`]).

use std::time::Instant;

use rayon::prelude::*;

use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LdltRef, LltRef, SymbolicCholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Par, Side};

use crate::amg::{
    for_each_row, for_each_row2, par_dot as dot, product_plus_into, spmv_parts,
    transpose_structure_into, Addend, Amg, AmgOptions, Csr, ProductScratch,
};
use crate::solver::{
    DirectSolver, LinearSolver, SolveReport, SolverWork, SplitSystem, Workspace,
    DEFAULT_PARALLELISM,
};
use crate::SolveError;

/// How [`BlockSolver`] applies the inverse of the pressure matrix `Ŝ`
/// (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PressureSolve {
    /// Sparse Cholesky of `Ŝ`, inside conjugate gradient on the
    /// eliminated system.
    Cholesky,
    /// One V-cycle of smoothed aggregation, inside MINRES on the
    /// saddle-point form.
    Multigrid,
    /// By size: a stabilised system with at least
    /// [`BlockSolver::multigrid_from`] pressure rows by
    /// [`PressureSolve::Multigrid`], every other system by
    /// [`PressureSolve::Cholesky`] (the paper's unstabilised pressure
    /// defeats the multigrid, module docs).
    #[default]
    Auto,
}

/// The Krylov method of the stabilised multigrid path
/// ([`PressureSolve::Multigrid`] on a stabilised system).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Krylov {
    /// Restarted GMRES ([`BlockSolver::restart`]) preconditioned on the
    /// right by the block upper-triangular `[Â_v Cᵀ; 0 −Ŝ]`; stops on the
    /// saddle-point residual itself.
    #[default]
    Gmres,
    /// MINRES with the block-diagonal `diag(Â_v, Ŝ)`, in passes of
    /// refinement each aimed at the target; the symmetric method, a
    /// short recurrence (no stored basis), about three times the
    /// iterations.
    Minres,
}

/// The preconditioner of the velocity block `A_v`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VelocityBlock {
    /// `diag(A_v)`: enough while the block is mass dominated (fluids).
    Jacobi,
    /// One V-cycle of smoothed aggregation with rigid-body modes.
    Amg,
    /// Jacobi while the off-diagonal part of `A_v` is small against its
    /// diagonal (measured each set-up, [`BlockSolver::dominance_limit`]),
    /// multigrid otherwise.
    #[default]
    Auto,
}

/// The iterative solver of the split system (module docs).
#[derive(Debug)]
pub struct BlockSolver {
    /// How the pressure matrix `Ŝ` is inverted.
    pub pressure: PressureSolve,
    /// Relative residual `‖f − (A_v + CᵀC) V‖/‖f‖` of the eliminated
    /// system (the one the direct solver reports) at which the solve stops.
    pub target: f64,
    /// The unstabilised multigrid path: the reduction of the preconditioned
    /// residual at which each MINRES pass stops (module docs: passes of
    /// refinement on the eliminated system). The stabilised path's MINRES
    /// ([`Krylov::Minres`]) aims each pass at the target instead.
    pub tolerance: f64,
    /// The largest relative residual accepted when the iteration limit is
    /// reached first.
    pub residual_limit: f64,
    /// Iteration limit.
    pub max_iterations: usize,
    /// [`PressureSolve::Auto`]: the smallest stabilised system (in
    /// pressure rows, one per fluid node) solved by multigrid, in 2D and
    /// in 3D (the direct factor fills faster in 3D, so multigrid pays
    /// from fewer rows).
    pub multigrid_from: [usize; 2],
    /// Systems of fewer unknowns (velocity dofs) are assembled whole and
    /// factored by the direct solver ([`LinearSolver::wants_split`]);
    /// stabilised systems are always split.
    pub split_from: usize,
    /// [`PressureSolve::Multigrid`]: how the velocity block is
    /// preconditioned.
    pub velocity: VelocityBlock,
    /// [`VelocityBlock::Auto`] chooses multigrid when
    /// `Σᵢ Σ_{j≠i} |a_ij| / Σᵢ a_ii` exceeds this.
    pub dominance_limit: f64,
    /// [`PressureSolve::Multigrid`]: options of both hierarchies (block
    /// size and near-null space are set per block).
    pub amg: AmgOptions,
    /// Keep the preconditioners across solves with the same pattern
    /// generation (the Picard iterates of one step).
    pub reuse_setup: bool,
    /// The Cholesky path: a later Picard iterate of the same pattern runs
    /// its conjugate gradient on the factor of an earlier one while the
    /// volumetric rows have moved by at most this since it,
    /// `‖C − C_f‖ / ‖C_f‖`, and so has `A_v` between the stiff (solid)
    /// dofs the factor keeps whole (0: a new factor for every solve); never
    /// across Picard loops ([`LinearSolver::begin_loop`]). The loop's
    /// first iterates move `C` by 10⁻²–10⁻³ and an old factor would cost
    /// hundreds of iterations; its last ones by 10⁻⁵ and less (module
    /// docs). Default [`KEEP_FACTOR_BELOW`].
    pub keep_factor_below: f64,
    /// The Cholesky path: conjugate gradient iterations on a kept factor
    /// ([`BlockSolver::keep_factor_below`]) after which the factor is
    /// renewed and the solve goes on from where it stands. Default
    /// [`KEPT_FACTOR_ITERATIONS`].
    pub kept_factor_iterations: usize,
    /// The stabilised multigrid path: keep the multigrid set-up across
    /// solves with the same pattern generation within one Picard loop (the
    /// iterates of an attempt; a retried attempt builds anew).
    pub stabilised_reuse: bool,
    /// The stabilised multigrid path: carry the pressure hierarchy over
    /// to the next pattern (the next step's remeshing) for at most this
    /// many patterns in a row (0: build anew for every pattern). A
    /// carried hierarchy keeps the last aggregates and coarse levels, row
    /// by row through the particles the rows belong to
    /// ([`crate::solver::Stabilisation::row_ids`]), and takes the new
    /// `Ŝ` on its finest level; the velocity block's Jacobi is new. It is
    /// built anew when the rows do not name their particles, when more
    /// than one row in twenty is new, when the mean diagonal of `Ŝ − I`
    /// has moved by more than a factor 4 from the hierarchy's (the time
    /// step changed; within it the coarse levels are rescaled), and after a solve on it took more
    /// than `max(1.5 n, n + 3)` iterations, `n` the most a solve took on
    /// the hierarchy when it was new.
    pub carry_steps: u32,
    /// The stabilised multigrid path's Krylov method.
    pub krylov: Krylov,
    /// [`Krylov::Gmres`]: the basis vectors kept before a restart (each
    /// the size of the saddle-point system).
    pub restart: usize,
    setup: Option<Setup>,
    /// The factor of the stabilised saddle-point system
    /// ([`solve_saddle`]), kept for its symbolic analysis.
    saddle: QuasiDefinite,
    /// The stabilised iteration's last `q` and the pattern generation it
    /// belongs to: the next Picard iterate's initial guess.
    last_q: (u64, Vec<f64>),
    /// The multigrid path's CSR blocks, kept across the solves of one
    /// pattern generation.
    blocks: Blocks,
    /// The last pressure matrix `Ŝ` formed, kept for its arrays: the next
    /// one is formed into them (`product_plus_into`).
    schur_matrix: Csr,
    /// The chunks of the product that forms `Ŝ`, kept for their arrays.
    product_scratch: ProductScratch,
    /// The stabilised iteration's vectors, kept for their arrays.
    solve_scratch: SolveScratch,
    /// The last stabilised multigrid solve ran on a carried hierarchy.
    used_carried: bool,
    /// The set-up (the Cholesky path's factor, the stabilised path's
    /// hierarchy) was built in the current Picard loop
    /// ([`LinearSolver::begin_loop`]) and may be kept.
    keepable: bool,
    /// The caller's accuracy ([`LinearSolver::set_accuracy`]): the
    /// multigrid iterations stop at the looser of it and
    /// [`BlockSolver::target`] (the Cholesky path keeps its target).
    accuracy: Option<f64>,
    direct: DirectSolver,
    work: SolverWork,
    stats: BlockStats,
}

/// What a [`BlockSolver`] has done.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BlockStats {
    /// Solves.
    pub solves: u64,
    /// Krylov iterations summed over solves.
    pub iterations: u64,
    /// Largest iteration count of one solve.
    pub max_iterations: usize,
    /// Preconditioner set-ups (factorisations of `Ŝ` or multigrid
    /// hierarchies).
    pub setups: u64,
    /// Set-ups whose velocity block used multigrid
    /// ([`PressureSolve::Multigrid`]).
    pub velocity_amg: u64,
    /// Set-ups that kept stiff (solid) rows whole
    /// ([`PressureSolve::Cholesky`]).
    pub stiff_setups: u64,
    /// Of those, set-ups whose reduced system was refilled on the kept
    /// pattern of the same mesh and stiff set (not built and sorted
    /// anew).
    pub stiff_refills: u64,
    /// Cholesky-path solves that ran on a factor kept from an earlier
    /// Picard iterate ([`BlockSolver::keep_factor_below`]).
    pub kept_factors: u64,
    /// Of those, solves whose kept factor was renewed midway
    /// ([`BlockSolver::kept_factor_iterations`]).
    pub kept_renewed: u64,
    /// Solves handed to the direct solver because the iteration could
    /// not set up or did not converge.
    pub fallbacks: u64,
    /// Set-ups that carried the last pattern's pressure hierarchy over
    /// ([`BlockSolver::carry_steps`]), among [`BlockStats::setups`].
    pub carried: u64,
    /// Solves on a carried hierarchy that did not converge, and were
    /// solved again on a new one.
    pub carry_failures: u64,
    /// Wall time in set-ups (s).
    pub setup_seconds: f64,
    /// Wall time in iterations (s).
    pub iterate_seconds: f64,
}

enum VelocityPrec {
    Jacobi(Vec<f64>),
    Amg(Box<Amg>),
}

/// A symmetric quasi-definite matrix factored as `L D Lᵀ` (faer; any
/// fill-reducing order is stable for such matrices), with its symbolic
/// analysis kept while the pattern stays the same.
#[derive(Default)]
pub(crate) struct QuasiDefinite {
    symbolic: Option<(Vec<usize>, Vec<usize>, SymbolicCholesky<usize>)>,
    values: Vec<f64>,
    ws: Workspace,
    /// Factored as `L Lᵀ` (positive definite), not `L D Lᵀ`.
    definite: bool,
}

impl std::fmt::Debug for QuasiDefinite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("QuasiDefinite")
            .field("factored", &self.symbolic.is_some())
            .finish()
    }
}

impl QuasiDefinite {
    /// Factors the symmetric `r` (CSR of both triangles or of the upper
    /// one: the factorisation reads only that); `signs` gives the
    /// expected sign of each pivot (+1 velocity, −1 pressure), `None` for
    /// a positive definite `r` (Cholesky, faster). Counts a new symbolic
    /// analysis in `work`.
    pub(crate) fn factorise(
        &mut self,
        r: &Csr,
        signs: Option<&[i8]>,
        work: &mut SolverWork,
    ) -> Result<(), String> {
        self.factorise_parts(r.nrows, &r.ptr, &r.idx, &r.val, signs, work)
    }

    /// [`QuasiDefinite::factorise`] of the `n × n` matrix with the CSR
    /// arrays `ptr`, `idx`, `val` (both triangles, or the upper one: the
    /// factorisation reads only that).
    pub(crate) fn factorise_parts(
        &mut self,
        n: usize,
        ptr: &[usize],
        idx: &[usize],
        val: &[f64],
        signs: Option<&[i8]>,
        work: &mut SolverWork,
    ) -> Result<(), String> {
        // faer can panic inside a numeric factorisation (see
        // `solver.rs`): a failed set-up here (the solve falls back), never a
        // panic of the run.
        let done = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            self.factorise_inner(n, ptr, idx, val, signs, work)
        }));
        done.unwrap_or_else(|_| {
            self.symbolic = None;
            Err("the factorisation panicked".into())
        })
    }

    fn factorise_inner(
        &mut self,
        n: usize,
        ptr: &[usize],
        idx: &[usize],
        val: &[f64],
        signs: Option<&[i8]>,
        work: &mut SolverWork,
    ) -> Result<(), String> {
        // Symmetric: its CSR arrays are its CSC arrays.
        let sym = SymbolicSparseColMatRef::new_checked(n, n, ptr, None, idx);
        let a = SparseColMatRef::new(sym, val);
        let same = self
            .symbolic
            .as_ref()
            .is_some_and(|(p, i, _)| p == ptr && i == idx);
        if !same {
            self.symbolic = None;
            let sc = factorize_symbolic_cholesky(
                a.symbolic(),
                Side::Lower,
                Default::default(),
                Default::default(),
            )
            .map_err(|e| format!("{e:?}"))?;
            self.symbolic = Some((ptr.to_vec(), idx.to_vec(), sc));
            work.symbolic_analyses += 1;
        }
        let Some((_, _, sc)) = self.symbolic.as_ref() else {
            return Err("no symbolic factorisation".into());
        };
        self.values.resize(sc.len_val(), 0.0);
        let par = DEFAULT_PARALLELISM;
        self.definite = signs.is_none();
        let Some(signs) = signs else {
            let stack = self
                .ws
                .stack(sc.factorize_numeric_llt_scratch::<f64>(par, Default::default()))?;
            return sc
                .factorize_numeric_llt::<f64>(
                    &mut self.values,
                    a,
                    Side::Lower,
                    Default::default(),
                    par,
                    stack,
                    Default::default(),
                )
                .map(|_| ())
                .map_err(|e| format!("{e:?}"));
        };
        let stack = self
            .ws
            .stack(sc.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()))?;
        let reg = LdltRegularization {
            dynamic_regularization_signs: Some(signs),
            dynamic_regularization_delta: 0.0,
            dynamic_regularization_epsilon: 0.0,
        };
        sc.factorize_numeric_ldlt::<f64>(
            &mut self.values,
            a,
            Side::Lower,
            reg,
            par,
            stack,
            Default::default(),
        )
        .map(|_| ())
        .map_err(|e| format!("{e:?}"))
    }

    pub(crate) fn solve_in_place(&mut self, x: &mut [f64]) -> Result<(), String> {
        let Some((_, _, sc)) = self.symbolic.as_ref() else {
            return Err("not factored".into());
        };
        let stack = self
            .ws
            .stack(sc.solve_in_place_scratch::<f64>(1, Par::Seq))?;
        if self.definite {
            LltRef::new(sc, &self.values).solve_in_place_with_conj(
                Conj::No,
                faer::col::ColMut::from_slice_mut(x).as_mat_mut(),
                Par::Seq,
                stack,
            );
            return Ok(());
        }
        LdltRef::new(sc, &self.values).solve_in_place_with_conj(
            Conj::No,
            faer::col::ColMut::from_slice_mut(x).as_mat_mut(),
            Par::Seq,
            stack,
        );
        Ok(())
    }
}

const NONE: usize = usize::MAX;

/// The saddle-point matrix of a stabilised [`SplitSystem`],
/// `K = [A_v Cᵀ; C −(I + L̃)]` (CSR of both triangles, symmetric
/// quasi-definite), and its right-hand side `[f; o]`.
fn saddle(sys: &SplitSystem<'_>) -> Result<(Csr, Vec<f64>), SolveError> {
    let a = sys.a_v;
    let n = a.nrows();
    let m = sys.c_rows();
    let mut t: Vec<(usize, usize, f64)> = Vec::with_capacity(
        a.compute_nnz() + 2 * sys.c_idx.len() + m + sys.stabilisation.map_or(0, |s| s.l_idx.len()),
    );
    for j in 0..a.ncols() {
        for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            t.push((i, j, *v));
        }
    }
    for r in 0..m {
        for p in sys.c_ptr[r]..sys.c_ptr[r + 1] {
            let j = sys.c_idx[p];
            t.push((n + r, j, sys.c_val[p]));
            t.push((j, n + r, sys.c_val[p]));
        }
        t.push((n + r, n + r, -1.0));
    }
    let mut rhs = Vec::with_capacity(n + m);
    rhs.extend_from_slice(sys.rhs);
    match sys.stabilisation {
        Some(st) => {
            for r in 0..m {
                for p in st.l_ptr[r]..st.l_ptr[r + 1] {
                    t.push((n + r, n + st.l_idx[p], -st.l_val[p]));
                }
            }
            rhs.extend_from_slice(st.offset);
        }
        None => rhs.resize(n + m, 0.0),
    }
    let k = Csr::try_from_triplets(n + m, n + m, &t).map_err(|e| SolveError::Factorization {
        solver: SADDLE,
        detail: format!("cannot form the saddle-point matrix: {e}"),
    })?;
    Ok((k, rhs))
}

const SADDLE: &str = "saddle-point LDLT";

/// The saddle-point form `K [V; q] = [f; o]` of a split system,
/// `K = [A_v Cᵀ; C −(I + L̃)]` (`L̃ = 0`, `o = 0` without stabilisation), as
/// a faer matrix (both triangles) and its right-hand side: what
/// [`crate::MatrixExport`] writes for a stabilised system.
pub fn saddle_system(
    sys: &SplitSystem<'_>,
) -> Result<(faer::sparse::SparseColMat<usize, f64>, Vec<f64>), SolveError> {
    let (k, b) = saddle(sys)?;
    let n = k.nrows;
    // Symmetric: the CSR arrays are the CSC arrays.
    let sym = faer::sparse::SymbolicSparseColMat::new_checked(n, n, k.ptr, None, k.idx);
    Ok((faer::sparse::SparseColMat::new(sym, k.val), b))
}

/// Solves a stabilised [`SplitSystem`] (or an unstabilised one, in its
/// saddle-point form) by one sparse `L D Lᵀ` of `K = [A_v Cᵀ; C −(I + L̃)]`
/// (quasi-definite, so any fill-reducing order is stable) with passes of
/// refinement; the residual reported is `‖[f; o] − K [V; q]‖ / ‖[f; o]‖`.
/// `x` receives `V`. What the default [`LinearSolver::solve_split`] does
/// with a stabilised system.
pub fn solve_saddle(sys: &SplitSystem<'_>, x: &mut [f64]) -> Result<SolveReport, SolveError> {
    sys.check("saddle-point LDLᵀ", x)?;
    let mut factor = QuasiDefinite::default();
    let mut work = SolverWork::default();
    solve_saddle_with(sys, &mut factor, &mut work, x)
}

fn solve_saddle_with(
    sys: &SplitSystem<'_>,
    factor: &mut QuasiDefinite,
    work: &mut SolverWork,
    x: &mut [f64],
) -> Result<SolveReport, SolveError> {
    // Its callers checked `sys` (`solve_saddle`, `BlockSolver::solve_split`).
    crate::solver::check_finite(sys.rhs)?;
    let n = sys.a_v.nrows();
    let (k, b) = saddle(sys)?;
    crate::solver::check_finite(&b)?;
    let signs: Vec<i8> = (0..k.nrows).map(|i| if i < n { 1 } else { -1 }).collect();
    factor
        .factorise(&k, Some(&signs), work)
        .map_err(|detail| SolveError::Factorization {
            solver: SADDLE,
            detail,
        })?;
    work.factorizations += 1;
    let den = dot(&b, &b).sqrt();
    let rel = |num: f64| if den > 0.0 { num / den } else { num };
    let mut y = b.clone();
    factor
        .solve_in_place(&mut y)
        .map_err(|detail| SolveError::Factorization {
            solver: SADDLE,
            detail,
        })?;
    let mut r = vec![0.0; b.len()];
    let mut residual = f64::INFINITY;
    // `y` before the last correction, restored when the correction made
    // the residual worse (the residual reported is `y`'s).
    let mut before = y.clone();
    for pass in 0..3 {
        k.spmv(&y, &mut r);
        r.iter_mut().zip(&b).for_each(|(r, b)| *r = b - *r);
        let new = rel(dot(&r, &r).sqrt());
        if new.is_nan() || new >= residual {
            if pass > 0 {
                std::mem::swap(&mut y, &mut before);
            }
            break;
        }
        residual = new;
        if residual <= 1e-13 || pass == 2 {
            break;
        }
        before.copy_from_slice(&y);
        factor
            .solve_in_place(&mut r)
            .map_err(|detail| SolveError::Factorization {
                solver: SADDLE,
                detail,
            })?;
        y.iter_mut().zip(&r).for_each(|(y, d)| *y += d);
    }
    if let Some(index) = y.iter().position(|v| !v.is_finite()) {
        return Err(SolveError::NonFinite { index });
    }
    // A direct solve's acceptance (`LinearSolver::solve`'s contract): its
    // relative residual below `DIRECT_RESIDUAL_LIMIT`, or its normwise
    // backward error `‖r‖ / (‖K‖_F ‖y‖ + ‖b‖)` below
    // `DIRECT_BACKWARD_ERROR_LIMIT` (a small `b` beside `K y`'s terms).
    if residual.is_nan() || residual > crate::solver::DIRECT_RESIDUAL_LIMIT {
        k.spmv(&y, &mut r);
        r.iter_mut().zip(&b).for_each(|(r, b)| *r = b - *r);
        let nk = dot(&k.val, &k.val).sqrt();
        let den = nk * dot(&y, &y).sqrt() + den;
        let backward = dot(&r, &r).sqrt() / den;
        if backward.is_nan() || backward > crate::solver::DIRECT_BACKWARD_ERROR_LIMIT {
            return Err(SolveError::Inaccurate {
                solver: SADDLE,
                residual,
                limit: crate::solver::DIRECT_RESIDUAL_LIMIT,
            });
        }
    }
    x.copy_from_slice(&y[..n]);
    Ok(SolveReport {
        residual,
        iterations: 1,
    })
}

/// The preconditioner `M = Ã + Cᵀ C` (module docs), `Ã` the velocity
/// block with the rows of its *stiff* nodes (solids: off-diagonal weight
/// above [`BlockSolver::dominance_limit`] of the diagonal) kept whole and
/// every other row cut to its diagonal `Â`, applied exactly through the
/// quasi-definite system it reduces to (`S` the stiff dofs, `F` the
/// others):
///
/// `[A_SS  C_Sᵀ; C_S  −Ŝ_F] [z_S; s] = [r_S; −C_F Â_F⁻¹ r_F]`,
/// `Ŝ_F = I + C_F Â_F⁻¹ C_Fᵀ`, `z_F = Â_F⁻¹ (r_F − C_Fᵀ s)`.
///
/// With water alone it is `Â⁻¹ − Â⁻¹ Cᵀ Ŝ⁻¹ C Â⁻¹` (Woodbury). It keeps
/// its own copies of what it needs, so that it stays one symmetric
/// positive definite operator while the system's values move.
struct Woodbury {
    /// `Â⁻¹` on `F` dofs (0 on `S` dofs).
    inv: Vec<f64>,
    /// Position of each `S` dof in the reduced system (NONE for `F`).
    pos: Vec<usize>,
    /// `S` dofs.
    stiff: Vec<usize>,
    /// The patterns of `C`, `Cᵀ` and `Ŝ_F` for the mesh, kept across
    /// set-ups while the mesh is the same.
    plan: SchurProduct,
    /// Values of `C`, of `Cᵀ` and of `Ŝ_F` on `plan`'s patterns.
    c_val: Vec<f64>,
    ct_val: Vec<f64>,
    s_val: Vec<f64>,
    /// The values of `A_v` between stiff dofs it was factored with, in
    /// the order of [`stiff_entries`].
    a_ss: Vec<f64>,
    /// The reduced system with stiff rows (its upper triangle; empty without
    /// them): refilled, not rebuilt, while the mesh and the stiff set are
    /// the same ([`ReducedParts::rows`]).
    reduced: Csr,
    factor: QuasiDefinite,
    /// `Cᵀ`'s values of the system being solved ([`Woodbury::product`]):
    /// the set-up's own, until [`Woodbury::follow`] takes a later
    /// iterate's for a kept factor.
    ct_now: Vec<f64>,
    /// Scratch: reduced right-hand side, `C`'s rows, dofs.
    red: Vec<f64>,
    t: Vec<f64>,
    u: Vec<f64>,
}

impl Woodbury {
    /// The set-up from the split system itself: `A_v` is read in its CSC
    /// form (no CSR copy), and `Ŝ_F` is refilled on the patterns of the
    /// `old` set-up (with its factor's symbolic analysis and its storage)
    /// while the mesh `generation` and `C`'s pattern are the same; so is
    /// the reduced system with stiff rows while the stiff set is also the
    /// same. Returns the set-up, its number of stiff dofs and whether the
    /// reduced system was refilled.
    fn new(
        sys: &SplitSystem<'_>,
        generation: u64,
        old: Option<Box<Woodbury>>,
        limit: f64,
        work: &mut SolverWork,
    ) -> Result<(Box<Self>, usize, bool), SolveError> {
        let a = sys.a_v;
        let n = a.nrows();
        let m = sys.c_rows();
        // Diagonal and off-diagonal weight of each row, from its column
        // (`A_v` is symmetric), in parallel.
        let mut diag = vec![0.0; n];
        let mut off = vec![0.0; n];
        for_each_row2(&mut diag, &mut off, |j, d, o| {
            for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                if i == j {
                    *d += v;
                } else {
                    *o += v.abs();
                }
            }
        });
        if let Some(i) = diag.iter().position(|&v| !(v > 0.0 && v.is_finite())) {
            return Err(SolveError::Factorization {
                solver: NAME,
                detail: format!("velocity block has diagonal {} at dof {i}", diag[i]),
            });
        }
        // Stiff nodes: a row whose off-diagonal weight passes the limit
        // makes its node's dofs stiff.
        let block = sys.block_size.max(1);
        let mut stiff_node = vec![false; n.div_ceil(block)];
        for i in 0..n {
            if off[i] > limit * diag[i] {
                stiff_node[i / block] = true;
            }
        }
        let mut pos = vec![NONE; n];
        let mut stiff = Vec::new();
        for i in 0..n {
            if stiff_node[i / block] {
                pos[i] = stiff.len();
                stiff.push(i);
            }
        }
        let ns = stiff.len();
        // `A_v` between stiff dofs, as factored (none without stiff dofs).
        let mut a_ss = Vec::new();
        let inv: Vec<f64> = (0..n)
            .map(|i| if pos[i] == NONE { 1.0 / diag[i] } else { 0.0 })
            .collect();
        let (plan, mut factor, mut c_val, mut ct_val, mut s_val, kept) = match old {
            Some(w) if w.plan.fits(generation, sys.c_ptr, sys.c_idx) => {
                let w = *w;
                // The reduced pattern also needs the same stiff set.
                let kept = (w.stiff == stiff).then_some(w.reduced);
                (w.plan, w.factor, w.c_val, w.ct_val, w.s_val, kept)
            }
            old => (
                SchurProduct::new(generation, sys.c_ptr, sys.c_idx, n),
                old.map(|w| w.factor).unwrap_or_default(),
                Vec::new(),
                Vec::new(),
                Vec::new(),
                None,
            ),
        };
        let mut reduced = kept.unwrap_or_default();
        let mut refilled = false;
        c_val.clear();
        c_val.extend_from_slice(sys.c_val);
        plan.transpose_values(&c_val, &mut ct_val);
        let fail = |detail: String| SolveError::Factorization {
            solver: NAME,
            detail: format!("reduced system: {detail}"),
        };
        // Ŝ_F = I + C_F Â_F⁻¹ C_Fᵀ (the S columns weigh 0 in `inv`); with no
        // stiff rows `Ŝ_F s = C_F Â_F⁻¹ r_F`, positive definite, and its
        // upper triangle is all the factorisation reads.
        plan.product(&c_val, &ct_val, &inv, &mut s_val);
        if ns == 0 {
            let (ptr, idx) = &plan.upper;
            factor
                .factorise_parts(m, ptr, idx, &s_val, None, work)
                .map_err(fail)?;
        } else {
            stiff_entries(a, &pos, |_, _, v| a_ss.push(v));
            // The reduced matrix's upper triangle, written row by row in
            // its CSR order: refilled in place on the same mesh and stiff
            // set (each entry checked against the kept pattern, a rebuild
            // if any differs), else built anew.
            let parts = ReducedParts {
                a,
                stiff: &stiff,
                pos: &pos,
                plan: &plan,
                ct_val: &ct_val,
                s_val: &s_val,
            };
            refilled = reduced.nrows == ns + m;
            if refilled {
                let (mut k, mut row) = (0, 0);
                let Csr { ptr, idx, val, .. } = &mut reduced;
                parts.rows(|end, j, v| {
                    if end {
                        row += 1;
                        refilled &= ptr.get(row) == Some(&k);
                    } else if idx.get(k) == Some(&j) {
                        val[k] = v;
                        k += 1;
                    } else {
                        refilled = false;
                    }
                });
                refilled &= k == idx.len();
            }
            if !refilled {
                reduced = Csr {
                    nrows: ns + m,
                    ncols: ns + m,
                    ptr: vec![0],
                    idx: Vec::with_capacity(plan.upper.1.len() + c_val.len()),
                    val: Vec::with_capacity(plan.upper.1.len() + c_val.len()),
                };
                let Csr { ptr, idx, val, .. } = &mut reduced;
                parts.rows(|end, j, v| {
                    if end {
                        ptr.push(idx.len());
                    } else {
                        idx.push(j);
                        val.push(v);
                    }
                });
            }
            let signs: Vec<i8> = (0..ns + m).map(|k| if k < ns { 1 } else { -1 }).collect();
            factor
                .factorise(&reduced, Some(&signs), work)
                .map_err(fail)?;
        }
        let ct_now = ct_val.clone();
        Ok((
            Box::new(Self {
                inv,
                pos,
                stiff,
                plan,
                c_val,
                ct_val,
                s_val,
                a_ss,
                reduced,
                factor,
                ct_now,
                red: vec![0.0; ns + m],
                t: vec![0.0; m],
                u: vec![0.0; n],
            }),
            ns,
            refilled,
        ))
    }

    /// How far `sys` (mesh `generation`) is from what this set-up was
    /// factored with: the larger relative move of the volumetric rows,
    /// `‖C − C_f‖ / ‖C_f‖`, and of `A_v` between stiff dofs (a solid's
    /// stiffness, kept whole in the factor); infinite for another mesh or
    /// pattern.
    fn moved(&self, sys: &SplitSystem<'_>, generation: u64) -> f64 {
        if !self.plan.fits(generation, sys.c_ptr, sys.c_idx) || self.c_val.len() != sys.c_val.len()
        {
            return f64::INFINITY;
        }
        let relative = |d2: f64, c2: f64| {
            if c2 > 0.0 {
                (d2 / c2).sqrt()
            } else if d2 == 0.0 {
                0.0
            } else {
                f64::INFINITY
            }
        };
        let (mut d2, mut c2) = (0.0, 0.0);
        for (a, b) in self.c_val.iter().zip(sys.c_val) {
            d2 += (a - b) * (a - b);
            c2 += a * a;
        }
        let (mut e2, mut s2, mut k) = (0.0, 0.0, 0);
        stiff_entries(sys.a_v, &self.pos, |_, _, v| {
            if let Some(&a) = self.a_ss.get(k) {
                e2 += (a - v) * (a - v);
                s2 += a * a;
            }
            k += 1;
        });
        if k != self.a_ss.len() {
            return f64::INFINITY;
        }
        relative(d2, c2).max(relative(e2, s2))
    }

    /// Takes `sys`'s values of `C` (transposed, [`Woodbury::product`]
    /// reads them), which have moved since the set-up when its factor is
    /// kept for a later iterate.
    fn follow(&mut self, sys: &SplitSystem<'_>) {
        if self.plan.ct_src.len() == sys.c_val.len() {
            self.plan.transpose_values(sys.c_val, &mut self.ct_now);
        } else {
            self.ct_now.clear();
        }
    }

    /// `y = (A_v + Cᵀ C) x` for `sys` of mesh `generation`, as
    /// [`SplitSystem::apply`] but row by row in parallel: `A_v` is
    /// symmetric, so its CSC columns are its rows, and `Cᵀ`'s rows are
    /// this set-up's plan with the values [`Woodbury::follow`] took from
    /// `sys`. Each row is summed in an order fixed by the patterns, the
    /// same for any number of threads. Another mesh than the plan's:
    /// [`SplitSystem::apply`].
    fn product(
        &self,
        sys: &SplitSystem<'_>,
        generation: u64,
        x: &[f64],
        y: &mut [f64],
        q: &mut Vec<f64>,
    ) {
        let (plan, ct_now) = (&self.plan, &self.ct_now);
        if plan.generation != generation
            || ct_now.len() != sys.c_val.len()
            || plan.ct_ptr.len() != y.len() + 1
        {
            sys.apply(x, y, q);
            return;
        }
        q.resize(sys.c_rows(), 0.0);
        spmv_parts(sys.c_ptr, sys.c_idx, sys.c_val, x, q);
        let (a, q) = (sys.a_v, &*q);
        for_each_row(y, |j, yj| {
            let mut s = 0.0;
            for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                s += v * x[i];
            }
            for k in plan.ct_ptr[j]..plan.ct_ptr[j + 1] {
                s += ct_now[k] * q[plan.ct_idx[k]];
            }
            *yj = s;
        });
    }

    /// `z ← M⁻¹ r`.
    fn apply(&mut self, r: &[f64], z: &mut [f64]) -> Result<(), SolveError> {
        let ns = self.stiff.len();
        // u = Â_F⁻¹ r_F (zero on S).
        self.u
            .iter_mut()
            .zip(r)
            .zip(&self.inv)
            .for_each(|((u, r), d)| *u = r * d);
        let plan = &self.plan;
        spmv_parts(&plan.c_ptr, &plan.c_idx, &self.c_val, &self.u, &mut self.t);
        for (k, &i) in self.stiff.iter().enumerate() {
            self.red[k] = r[i];
        }
        // The reduced system's second row is `−Ŝ_F` (the positive `Ŝ_F`
        // alone when there are no stiff rows).
        let sign = if ns == 0 { 1.0 } else { -1.0 };
        for (red, t) in self.red[ns..].iter_mut().zip(&self.t) {
            *red = sign * t;
        }
        self.factor
            .solve_in_place(&mut self.red)
            .map_err(|detail| SolveError::Factorization {
                solver: NAME,
                detail,
            })?;
        // z_F = Â_F⁻¹ (r_F − C_Fᵀ s), z_S from the reduced solve.
        spmv_parts(&plan.ct_ptr, &plan.ct_idx, &self.ct_val, &self.red[ns..], z);
        for i in 0..z.len() {
            z[i] = if self.pos[i] == NONE {
                self.u[i] - self.inv[i] * z[i]
            } else {
                self.red[self.pos[i]]
            };
        }
        Ok(())
    }
}

/// What the reduced system with stiff rows is made of (`Woodbury::new`):
/// `[A_SS  C_Sᵀ; C_S  −Ŝ_F]`, the `ns` stiff dofs first, of which the
/// factorisation reads the upper triangle alone (CSR rows read as CSC
/// columns: the lower triangle of its transpose, the same matrix).
struct ReducedParts<'a> {
    a: faer::sparse::SparseColMatRef<'a, usize, f64>,
    /// The stiff dofs, and each dof's place among them (or [`NONE`]).
    stiff: &'a [usize],
    pos: &'a [usize],
    /// `Cᵀ`'s pattern (every entry of `C` on a stiff column, zero or not,
    /// so that the pattern does not change with the values, which cost a
    /// new ordering each time it did) and `Ŝ_F`'s upper triangle.
    plan: &'a SchurProduct,
    ct_val: &'a [f64],
    s_val: &'a [f64],
}

impl ReducedParts<'_> {
    /// Writes the upper triangle row by row in CSR order, columns
    /// increasing, in an order fixed by the patterns and the stiff set
    /// alone: `f(false, column, value)` for each entry, `f(true, 0, 0.0)`
    /// at the end of each row. A stiff row `s` (dof `j`) holds `A_v`
    /// between `j` and the stiff dofs from `j` on (read from column `j`:
    /// `A_v` is symmetric), then `C_Sᵀ`'s row `j`; a pressure row, `−Ŝ_F`'s
    /// upper row.
    fn rows(&self, mut f: impl FnMut(bool, usize, f64)) {
        let (ns, pos, plan) = (self.stiff.len(), self.pos, self.plan);
        for &j in self.stiff {
            for (i, &v) in self.a.row_idx_of_col(j).zip(self.a.val_of_col(j)) {
                if i >= j && pos[i] != NONE {
                    f(false, pos[i], v);
                }
            }
            for p in plan.ct_ptr[j]..plan.ct_ptr[j + 1] {
                f(false, ns + plan.ct_idx[p], self.ct_val[p]);
            }
            f(true, 0, 0.0);
        }
        let (ptr, idx) = &plan.upper;
        for r in 0..ptr.len() - 1 {
            for p in ptr[r]..ptr[r + 1] {
                f(false, ns + idx[p], -self.s_val[p]);
            }
            f(true, 0, 0.0);
        }
    }
}

/// Visits the entries of `a` (CSC, symmetric) between stiff dofs (`pos`
/// not [`NONE`]), column by column: `f(pos[i], pos[j], a_ij)`.
fn stiff_entries(
    a: faer::sparse::SparseColMatRef<'_, usize, f64>,
    pos: &[usize],
    mut f: impl FnMut(usize, usize, f64),
) {
    for j in 0..a.ncols() {
        if pos[j] == NONE {
            continue;
        }
        for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            if pos[i] != NONE {
                f(pos[i], pos[j], v);
            }
        }
    }
}

/// Rows per range when `m` rows of `Ŝ` are shared among the threads:
/// four ranges a thread above 4 096 rows, one range below.
fn rows_per_range(m: usize) -> usize {
    let ranges = if m > 4096 {
        (rayon::current_num_threads() * 4).max(1)
    } else {
        1
    };
    m.div_ceil(ranges).max(1)
}

/// The patterns of `C`, of `Cᵀ` and of `Ŝ = I + C D Cᵀ` (`D` diagonal)
/// for one mesh: built once per pattern generation, so that each Picard
/// iterate only refills values (Gustavson's product with the pattern
/// known: no sorting, no allocation per row).
struct SchurProduct {
    generation: u64,
    /// `C`'s pattern (CSR).
    c_ptr: Vec<usize>,
    c_idx: Vec<usize>,
    /// `Cᵀ`'s pattern and, for each of its entries, the entry of `C` it
    /// copies.
    ct_ptr: Vec<usize>,
    ct_idx: Vec<usize>,
    ct_src: Vec<usize>,
    /// For each entry `(i, k)` of `C`, where `Cᵀ`'s row `k` holds it: its
    /// columns from `i` on (rows of `Cᵀ` are sorted) start there.
    ct_of: Vec<usize>,
    /// `Ŝ`'s upper triangle (sorted rows, the diagonal always present):
    /// all the symmetric factorisations read.
    upper: (Vec<usize>, Vec<usize>),
}

impl std::fmt::Debug for SchurProduct {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SchurProduct")
            .field("generation", &self.generation)
            .field("rows", &self.c_ptr.len().saturating_sub(1))
            .field("upper_nnz", &self.upper.1.len())
            .finish()
    }
}

impl SchurProduct {
    /// The patterns for `C` (CSR `c_ptr`, `c_idx`, `n` columns).
    fn new(generation: u64, c_ptr: &[usize], c_idx: &[usize], n: usize) -> Self {
        let m = c_ptr.len().saturating_sub(1);
        let mut ct_ptr = vec![0usize; n + 1];
        for &j in c_idx {
            ct_ptr[j + 1] += 1;
        }
        for j in 0..n {
            ct_ptr[j + 1] += ct_ptr[j];
        }
        let mut next = ct_ptr.clone();
        let mut ct_idx = vec![0usize; c_idx.len()];
        let mut ct_src = vec![0usize; c_idx.len()];
        let mut ct_of = vec![0usize; c_idx.len()];
        for i in 0..m {
            for k in c_ptr[i]..c_ptr[i + 1] {
                let j = c_idx[k];
                ct_idx[next[j]] = i;
                ct_src[next[j]] = k;
                ct_of[k] = next[j];
                next[j] += 1;
            }
        }
        // Each row's columns `j ≥ i` in parallel row ranges, joined in
        // order: the same pattern for any number of threads. `Cᵀ`'s rows
        // are sorted, so the columns below `i` are a prefix skipped.
        let (ct_p, ct_i, ct_o) = (&ct_ptr, &ct_idx, &ct_of);
        let rows = rows_per_range(m);
        let parts: Vec<(Vec<usize>, Vec<usize>)> = (0..m.div_ceil(rows))
            .into_par_iter()
            .map(|c| {
                let (r0, r1) = (c * rows, ((c + 1) * rows).min(m));
                let mut marker = vec![usize::MAX; m];
                let mut lens = Vec::with_capacity(r1 - r0);
                let mut idx = Vec::new();
                for i in r0..r1 {
                    let row0 = idx.len();
                    marker[i] = i;
                    idx.push(i);
                    for ka in c_ptr[i]..c_ptr[i + 1] {
                        let k = c_idx[ka];
                        for &j in &ct_i[ct_o[ka] + 1..ct_p[k + 1]] {
                            if marker[j] != i {
                                marker[j] = i;
                                idx.push(j);
                            }
                        }
                    }
                    idx[row0..].sort_unstable();
                    lens.push(idx.len() - row0);
                }
                (lens, idx)
            })
            .collect();
        let mut upper = (Vec::with_capacity(m + 1), Vec::new());
        upper.0.push(0);
        for (lens, idx) in &parts {
            for &l in lens {
                let last = upper.0[upper.0.len() - 1];
                upper.0.push(last + l);
            }
            upper.1.extend_from_slice(idx);
        }
        Self {
            generation,
            c_ptr: c_ptr.to_vec(),
            c_idx: c_idx.to_vec(),
            ct_ptr,
            ct_idx,
            ct_src,
            ct_of,
            upper,
        }
    }

    /// Whether these are the patterns of a `C` with `c_ptr`, `c_idx`.
    fn fits(&self, generation: u64, c_ptr: &[usize], c_idx: &[usize]) -> bool {
        self.generation == generation && self.c_ptr == c_ptr && self.c_idx == c_idx
    }

    /// `Cᵀ`'s values from `C`'s, into `out`.
    fn transpose_values(&self, c_val: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.extend(self.ct_src.iter().map(|&k| c_val[k]));
    }

    /// The values of `I + C diag(d) Cᵀ` on its upper triangle, into
    /// `out`; `ct_val` from [`SchurProduct::transpose_values`]. Each entry
    /// sums its terms in the order of `C`'s row, as [`Csr::matmul`] does.
    fn product(&self, c_val: &[f64], ct_val: &[f64], d: &[f64], out: &mut Vec<f64>) {
        let (ptr, idx) = &self.upper;
        let (c_ptr, c_idx, ct_ptr, ct_idx) = (&self.c_ptr, &self.c_idx, &self.ct_ptr, &self.ct_idx);
        let ct_of = &self.ct_of;
        let m = ptr.len() - 1;
        out.clear();
        out.resize(idx.len(), 0.0);
        // Row ranges of about equal work, each filling its own slice.
        let rows = rows_per_range(m);
        let mut parts = Vec::with_capacity(m.div_ceil(rows));
        let mut rest = out.as_mut_slice();
        let mut r0 = 0;
        while r0 < m {
            let r1 = (r0 + rows).min(m);
            let (head, tail) = rest.split_at_mut(ptr[r1] - ptr[r0]);
            parts.push((r0, r1, head));
            rest = tail;
            r0 = r1;
        }
        parts.into_par_iter().for_each(|(r0, r1, out)| {
            let mut acc = vec![0.0f64; m];
            let base = ptr[r0];
            for i in r0..r1 {
                for ka in c_ptr[i]..c_ptr[i + 1] {
                    let k = c_idx[ka];
                    let a = c_val[ka] * d[k];
                    // `Cᵀ`'s rows are sorted: its columns from `i` on.
                    for kb in ct_of[ka]..ct_ptr[k + 1] {
                        acc[ct_idx[kb]] += a * ct_val[kb];
                    }
                }
                for p in ptr[i]..ptr[i + 1] {
                    let j = idx[p];
                    out[p - base] = if j == i { acc[j] + 1.0 } else { acc[j] };
                    acc[j] = 0.0;
                }
            }
        });
    }
}

enum Prec {
    Woodbury(Box<Woodbury>),
    Blocks {
        velocity: Box<VelocityPrec>,
        schur: Box<Amg>,
    },
}

struct Setup {
    generation: u64,
    n: usize,
    m: usize,
    prec: Prec,
    /// The stabilised multigrid path: the pressure rows' identities
    /// ([`crate::solver::Stabilisation::row_ids`]) and the steps the
    /// hierarchy has been carried over ([`BlockSolver::carry`]).
    ids: Vec<u32>,
    age: u32,
    /// The most Krylov iterations a solve took on the hierarchy when it
    /// was new.
    fresh_iterations: usize,
    /// [`schur_scale`] of the `Ŝ` the hierarchy was built on.
    scale: f64,
}

impl std::fmt::Debug for Setup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Setup")
            .field("generation", &self.generation)
            .field("n", &self.n)
            .field("m", &self.m)
            .finish()
    }
}

impl Default for BlockSolver {
    fn default() -> Self {
        Self {
            target: 1e-9,
            tolerance: 1e-6,
            residual_limit: 1e-7,
            max_iterations: 2000,
            pressure: PressureSolve::Auto,
            multigrid_from: MULTIGRID_FROM,
            split_from: SPLIT_FROM,
            velocity: VelocityBlock::Auto,
            dominance_limit: 0.5,
            amg: AmgOptions::default(),
            reuse_setup: false,
            keep_factor_below: KEEP_FACTOR_BELOW,
            kept_factor_iterations: KEPT_FACTOR_ITERATIONS,
            stabilised_reuse: true,
            carry_steps: CARRY_STEPS,
            krylov: Krylov::Gmres,
            restart: 30,
            setup: None,
            saddle: QuasiDefinite::default(),
            last_q: (u64::MAX, Vec::new()),
            accuracy: None,
            used_carried: false,
            keepable: false,
            blocks: Blocks::default(),
            schur_matrix: Csr::default(),
            product_scratch: ProductScratch::default(),
            solve_scratch: SolveScratch::default(),
            direct: DirectSolver::default(),
            work: SolverWork::default(),
            stats: BlockStats::default(),
        }
    }
}

const NAME: &str = "block-split iterative";

/// Default [`BlockSolver::multigrid_from`] (pressure rows, 2D and 3D):
/// where multigrid overtakes the stabilised system's `L D Lᵀ`, measured
/// on the running stabilised 2D dam break and 3D water column
/// (`docs/benchmarks.md`, session 20: with GMRES, multigrid was faster
/// from 800 rows in 2D, and in 3D at 343, 1 728, 2 744 and 5 184 rows but
/// not at 1 000). It was 100 000 and 4 000 with MINRES (session 18), and
/// 2 000 in 3D until session 53, when the stabilised 3D water column
/// solved 2.6, 3.0 and 2.9 times faster by multigrid than by the
/// saddle-point `L D Lᵀ` at 150, 452 and 1 000 fluid particles (its 3D
/// fill grows faster than the multigrid's work).
pub const MULTIGRID_FROM: [usize; 2] = [1_000, 100];

/// Default [`BlockSolver::carry_steps`]: on the running stabilised 3D
/// water column (31k particles, 20 steps) a hierarchy carried over 19
/// patterns took no more GMRES iterations than new ones
/// (`docs/benchmarks.md`, session 28).
pub const CARRY_STEPS: u32 = 20;

/// How far the scale of `Ŝ − I` may move from a carried hierarchy's
/// before it is built anew ([`BlockSolver::carry_steps`]). Within it, the
/// coarse levels are rescaled (`AmgOptions::rescalable`): they would
/// otherwise keep the old balance of `I` against the pressure Laplacian,
/// which the time step sets. On the 2D dam break's first steps the scale
/// changed 1.25–37 times from one step to the next, and a hierarchy
/// carried without rescaling took 13–68 GMRES iterations a solve against
/// 4–11 for new ones; rescaled, carried across a fourfold change, 3–9
/// against 3–8 (session 28).
pub(crate) const SCALE_DRIFT: f64 = 4.0;

/// The mean diagonal of `Ŝ − I = L̃ + C Â⁻¹ Cᵀ` (`inv` = `Â⁻¹`), without
/// forming `Ŝ`: the scale of its pressure Laplacian against the identity.
fn schur_scale(c: &Csr, inv: &[f64], st: &crate::solver::Stabilisation<'_>) -> f64 {
    let m = c.nrows;
    let mut sum = 0.0;
    for i in 0..m {
        for k in c.ptr[i]..c.ptr[i + 1] {
            sum += c.val[k] * c.val[k] * inv[c.idx[k]];
        }
        for k in st.l_ptr[i]..st.l_ptr[i + 1] {
            if st.l_idx[k] == i {
                sum += st.l_val[k];
            }
        }
    }
    sum / m.max(1) as f64
}

/// For rows named `new` (their particles), the row of each among rows
/// named `old` (`u32::MAX` for a particle without one), or `None` when
/// more than one row in twenty is new: the map by which a hierarchy is
/// carried over to a new pattern ([`BlockSolver::carry_steps`]).
pub(crate) fn rows_from(old: &[u32], new: &[u32]) -> Option<Vec<u32>> {
    let top = old.iter().chain(new).copied().max().unwrap_or(0) as usize + 1;
    let from: Vec<u32> = if top <= 4 * (old.len() + new.len()) + 1024 {
        let mut row_of = vec![u32::MAX; top];
        for (r, &p) in old.iter().enumerate() {
            row_of[p as usize] = r as u32;
        }
        new.iter().map(|&p| row_of[p as usize]).collect()
    } else {
        // Sparse identities: by search, not a table as large as the largest.
        let mut sorted: Vec<(u32, u32)> = old
            .iter()
            .enumerate()
            .map(|(r, &p)| (p, r as u32))
            .collect();
        sorted.sort_unstable();
        new.iter()
            .map(|&p| match sorted.binary_search_by_key(&p, |e| e.0) {
                Ok(k) => sorted[k].1,
                Err(_) => u32::MAX,
            })
            .collect()
    };
    let missing = from.iter().filter(|&&k| k == u32::MAX).count();
    (missing * 20 <= from.len()).then_some(from)
}

/// Default [`BlockSolver::keep_factor_below`]. From checkpoints at a/20,
/// the same steps with each threshold (`docs/benchmarks.md`, session 32):
/// the column on a cylinder's solve took 0.857 s a step with a new factor
/// for every solve, 0.631 s with 10⁻⁵, 0.597 s with 3·10⁻⁵ and 0.599 s
/// with 10⁻⁴; the water column's 0.480, 0.417 (3·10⁻⁵) and 0.441 s
/// (10⁻⁴). (These with the kept factor's iteration stopping at the
/// target; aiming at a hundredth of it, as now, the cylinder's took 0.852,
/// 0.664 and 0.671 s.)
pub const KEEP_FACTOR_BELOW: f64 = 3e-5;

/// A solve on a kept factor ([`BlockSolver::keep_factor_below`]) iterates
/// to this fraction of the target (and is accepted at the target).
const KEPT_FACTOR_AIM: f64 = 0.01;

/// Default [`BlockSolver::kept_factor_iterations`]: a solve on a kept
/// factor took 3–6 iterations (on the column on a cylinder at a/20),
/// against 2 on a factor of its own, which cost about as much as 15
/// there (0.09 s against 6 ms an iteration).
pub const KEPT_FACTOR_ITERATIONS: usize = 15;

/// Default [`BlockSolver::split_from`] (unknowns): measured in
/// `docs/benchmarks.md` (session 18).
pub const SPLIT_FROM: usize = 0;

/// The rigid-body modes of nodes at `coords` (`d` per node), centred:
/// `d` translations and `d (d − 1) / 2` rotations, column-major.
fn rigid_modes(coords: &[f64], d: usize) -> (Vec<f64>, usize) {
    let nn = coords.len() / d.max(1);
    let n = nn * d;
    let mut c = vec![0.0; d];
    for p in coords.chunks_exact(d) {
        for k in 0..d {
            c[k] += p[k] / nn.max(1) as f64;
        }
    }
    let m = d + d * (d - 1) / 2;
    let mut b = vec![0.0; n * m];
    for (i, p) in coords.chunks_exact(d).enumerate() {
        for k in 0..d {
            b[k * n + i * d + k] = 1.0;
        }
        let x: Vec<f64> = (0..d).map(|k| p[k] - c[k]).collect();
        // Rotations in the planes (k, l), k < l: u_k = −x_l, u_l = x_k.
        let mut col = d;
        for k in 0..d {
            for l in k + 1..d {
                b[col * n + i * d + k] = -x[l];
                b[col * n + i * d + l] = x[k];
                col += 1;
            }
        }
    }
    (b, m)
}

impl BlockSolver {
    /// What this solver has done so far.
    pub fn stats(&self) -> BlockStats {
        self.stats
    }

    /// The pressure solve used for `sys`: [`PressureSolve::Auto`]
    /// resolved by its kind and size.
    pub fn pressure_for(&self, sys: &SplitSystem<'_>) -> PressureSolve {
        match self.pressure {
            PressureSolve::Auto
                if sys.stabilisation.is_some()
                    && sys.c_rows() >= self.multigrid_from[usize::from(sys.block_size == 3)] =>
            {
                PressureSolve::Multigrid
            }
            PressureSolve::Auto => PressureSolve::Cholesky,
            p => p,
        }
    }

    /// A new set-up ([`BlockSolver::build`]) for the solves that follow,
    /// counted, which later iterates of the same Picard loop may keep.
    fn set_up(
        &mut self,
        pressure: PressureSolve,
        blocks: Option<(&Csr, &Csr, &Csr)>,
        sys: &SplitSystem<'_>,
        generation: u64,
    ) -> Result<(), SolveError> {
        let s = self.build(pressure, blocks, sys, generation)?;
        self.setup = Some(s);
        self.keepable = true;
        self.work.factorizations += 1;
        self.stats.setups += 1;
        Ok(())
    }

    /// The preconditioner for `sys`: the Cholesky path reads the split
    /// system itself, the multigrid path its blocks as CSR (`A_v`, `C`,
    /// `Cᵀ`; [`Blocks`]).
    fn build(
        &mut self,
        pressure: PressureSolve,
        blocks: Option<(&Csr, &Csr, &Csr)>,
        sys: &SplitSystem<'_>,
        generation: u64,
    ) -> Result<Setup, SolveError> {
        let (mut ids, mut scale) = (Vec::new(), 0.0);
        let prec = match (pressure, blocks) {
            (PressureSolve::Cholesky | PressureSolve::Auto, _) => {
                // The last set-up gives its storage and, for the same
                // mesh, its patterns and its symbolic analysis.
                let old = match self.setup.take().map(|s| s.prec) {
                    Some(Prec::Woodbury(w)) => Some(w),
                    _ => None,
                };
                let (w, ns, refilled) =
                    Woodbury::new(sys, generation, old, self.dominance_limit, &mut self.work)?;
                if ns > 0 {
                    self.stats.stiff_setups += 1;
                }
                if refilled {
                    self.stats.stiff_refills += 1;
                }
                Prec::Woodbury(w)
            }
            (PressureSolve::Multigrid, None) => {
                return Err(SolveError::Factorization {
                    solver: NAME,
                    detail: "the multigrid set-up needs the blocks as CSR".into(),
                })
            }
            (PressureSolve::Multigrid, Some((a, c, ct))) => {
                let n = a.nrows;
                let diag = a.diagonal();
                if let Some(i) = diag.iter().position(|&v| !(v > 0.0 && v.is_finite())) {
                    return Err(SolveError::Factorization {
                        solver: NAME,
                        detail: format!("velocity block has diagonal {} at dof {i}", diag[i]),
                    });
                }
                let inv: Vec<f64> = diag.iter().map(|v| 1.0 / v).collect();
                // Ŝ = I + L̃ + C Â⁻¹ Cᵀ (without a stabilisation, L̃ = 0;
                // the Cholesky path forms its own, with the stiff dofs
                // left out, in `Woodbury::new`).
                let none = vec![0; c.nrows + 1];
                let l = match sys.stabilisation {
                    Some(st) => {
                        let (m, k) = (c.nrows, st.l_val.len());
                        crate::amg::check_structure(m, m, st.l_ptr, st.l_idx, k).map_err(|e| {
                            SolveError::Factorization {
                                solver: NAME,
                                detail: format!("stabilisation matrix: {e}"),
                            }
                        })?;
                        (st.l_ptr, st.l_idx, st.l_val, 1.0)
                    }
                    None => (&none[..], &[][..], &[][..], 1.0),
                };
                let s = self.form_schur(c, &inv, ct, l);
                // What carrying the hierarchy over needs (`carry`).
                if let Some(st) = sys.stabilisation {
                    ids = st.row_ids.map(<[u32]>::to_vec).unwrap_or_default();
                    scale = schur_scale(c, &inv, &st);
                }
                let amg_err = |what: &str, e: crate::amg::AmgError| SolveError::Factorization {
                    solver: NAME,
                    detail: format!("{what} multigrid: {e}"),
                };
                let use_amg = match self.velocity {
                    VelocityBlock::Jacobi => false,
                    VelocityBlock::Amg => true,
                    VelocityBlock::Auto => {
                        let off: f64 = (0..n).map(|i| off_diagonal(a, i)).sum();
                        off > self.dominance_limit * diag.iter().sum::<f64>()
                    }
                };
                let velocity = if use_amg {
                    let d = sys.block_size;
                    let (modes, m) = rigid_modes(sys.coords, d);
                    let opts = AmgOptions {
                        block_size: d,
                        ..self.amg.clone()
                    };
                    self.stats.velocity_amg += 1;
                    VelocityPrec::Amg(Box::new(
                        Amg::new(a, Some((&modes, m)), &opts)
                            .map_err(|e| amg_err("velocity", e))?,
                    ))
                } else {
                    VelocityPrec::Jacobi(inv)
                };
                let opts = AmgOptions {
                    block_size: 1,
                    rescalable: self.amg.rescalable
                        || (self.carry_steps > 0
                            && sys.stabilisation.is_some_and(|st| st.row_ids.is_some())),
                    ..self.amg.clone()
                };
                let schur = Amg::new(&s, None, &opts).map_err(|e| amg_err("pressure", e));
                self.schur_matrix = s;
                let schur = schur?;
                Prec::Blocks {
                    velocity: Box::new(velocity),
                    schur: Box::new(schur),
                }
            }
        };
        Ok(Setup {
            generation,
            n: sys.a_v.nrows(),
            m: sys.c_rows(),
            prec,
            ids,
            age: 0,
            fresh_iterations: 0,
            scale,
        })
    }
}

/// `Σ_{j≠i} |a_ij|` of row `i`.
fn off_diagonal(a: &Csr, i: usize) -> f64 {
    (a.ptr[i]..a.ptr[i + 1])
        .filter(|&p| a.idx[p] != i)
        .map(|p| a.val[p].abs())
        .sum()
}

impl LinearSolver for BlockSolver {
    fn name(&self) -> &str {
        NAME
    }

    fn settings(&self) -> String {
        // Every public field (the kept state is not a setting).
        let Self {
            pressure,
            target,
            tolerance,
            residual_limit,
            max_iterations,
            multigrid_from,
            split_from,
            velocity,
            dominance_limit,
            amg,
            reuse_setup,
            keep_factor_below,
            kept_factor_iterations,
            stabilised_reuse,
            carry_steps,
            krylov,
            restart,
            ..
        } = self;
        format!(
            "{NAME}: pressure {pressure:?}, target {target:e}, tolerance {tolerance:e}, \
             residual_limit {residual_limit:e}, max_iterations {max_iterations}, \
             multigrid_from {multigrid_from:?}, split_from {split_from}, velocity {velocity:?}, \
             dominance_limit {dominance_limit:e}, amg {amg:?}, reuse_setup {reuse_setup}, \
             keep_factor_below {keep_factor_below:e}, kept_factor_iterations {kept_factor_iterations}, \
             stabilised_reuse {stabilised_reuse}, carry_steps {carry_steps}, krylov {krylov:?}, \
             restart {restart}"
        )
    }

    /// Without a split (a caller that assembled the whole matrix): the
    /// direct solver.
    fn solve(
        &mut self,
        a: faer::sparse::SparseColMatRef<'_, usize, f64>,
        generation: u64,
        b: &[f64],
        x: &mut [f64],
    ) -> Result<SolveReport, SolveError> {
        self.direct.solve(a, generation, b, x)
    }

    fn wants_split(&self, dofs: usize) -> bool {
        dofs >= self.split_from
    }

    /// The iteration; when it cannot set up or does not converge, the
    /// direct solver on the whole matrix ([`BlockStats::fallbacks`]).
    fn solve_split(
        &mut self,
        sys: &SplitSystem<'_>,
        generation: u64,
        x: &mut [f64],
    ) -> Result<SolveReport, SolveError> {
        sys.check(NAME, x)?;
        let pressure = self.pressure_for(sys);
        // A stabilised run whose size crossed `multigrid_from` keeps one
        // path's storage only.
        if sys.stabilisation.is_some() && pressure == PressureSolve::Cholesky {
            self.setup = None;
            self.stats.solves += 1;
            return solve_saddle_with(sys, &mut self.saddle, &mut self.work, x);
        }
        let done = if sys.stabilisation.is_some() {
            self.saddle = QuasiDefinite::default();
            match self.iterate_stabilised(sys, generation, x) {
                // A carried hierarchy that failed: once more on a new one
                // (the failure dropped it) before the direct fallback.
                Err(SolveError::NoConvergence { .. }) if self.used_carried => {
                    self.stats.carry_failures += 1;
                    self.iterate_stabilised(sys, generation, x)
                }
                done => done,
            }
        } else {
            self.iterate(sys, pressure, generation, x)
        };
        match done {
            Ok(r) => Ok(r),
            Err(e @ SolveError::NonFinite { .. }) => Err(e),
            Err(_) if sys.stabilisation.is_some() => {
                self.stats.fallbacks += 1;
                solve_saddle_with(sys, &mut self.saddle, &mut self.work, x)
            }
            Err(_) => {
                self.stats.fallbacks += 1;
                let a = sys.to_matrix()?;
                self.direct.solve(a.as_ref(), generation, sys.rhs, x)
            }
        }
    }

    fn work(&self) -> SolverWork {
        let mut w = self.work + self.direct.work();
        w.fallbacks = self.stats.fallbacks;
        w
    }

    fn set_accuracy(&mut self, relative_residual: Option<f64>) {
        self.accuracy = relative_residual.filter(|a| a.is_finite() && *a > 0.0);
    }

    fn begin_loop(&mut self) {
        self.keepable = false;
    }

    fn saddle_increment(&self, generation: u64) -> Option<&[f64]> {
        let (g, q) = &self.last_q;
        (*g == generation && !q.is_empty()).then_some(q.as_slice())
    }
}

impl BlockSolver {
    /// The relative residual the iterations stop at: the looser of
    /// [`BlockSolver::target`] and the caller's accuracy
    /// ([`LinearSolver::set_accuracy`]).
    fn target(&self) -> f64 {
        self.accuracy.map_or(self.target, |a| a.max(self.target))
    }

    /// The stabilised saddle-point system `[A_v Cᵀ; C −(I + L̃)] [V; q] =
    /// [f; o]` by [`BlockSolver::krylov`]: GMRES with the block
    /// upper-triangular preconditioner `[Â_v Cᵀ; 0 −Ŝ]` or MINRES with the
    /// block-diagonal `diag(Â_v, Ŝ)`, `Ŝ = I + L̃ + C Â⁻¹ Cᵀ` by one
    /// V-cycle of smoothed aggregation; passes of refinement on the whole
    /// residual. The residual reported is the saddle-point system's.
    fn iterate_stabilised(
        &mut self,
        sys: &SplitSystem<'_>,
        generation: u64,
        x: &mut [f64],
    ) -> Result<SolveReport, SolveError> {
        let Some(st) = sys.stabilisation else {
            let pressure = self.pressure_for(sys);
            return self.iterate(sys, pressure, generation, x);
        };
        crate::solver::check_finite(sys.rhs)?;
        crate::solver::check_finite(st.offset)?;
        let t0 = Instant::now();
        let mut blocks = std::mem::take(&mut self.blocks);
        blocks.refresh(sys, generation);
        let (a, c, ct, l) = (&blocks.a, &blocks.c, &blocks.ct, &blocks.l);
        let (n, m) = (a.nrows, c.nrows);
        // Kept within one Picard loop only: a retried attempt (the step
        // halved on the same mesh) has another `Δt`, and `C Â⁻¹ Cᵀ` moves
        // with it (session 42's review: the failed attempt's hierarchy
        // served the retry unscaled).
        let keep = self.stabilised_reuse
            && self.keepable
            && self
                .setup
                .as_ref()
                .is_some_and(|s| s.generation == generation && s.n == n && s.m == m);
        let setup = match self.setup.take() {
            Some(s) if keep => {
                self.work.resolves += 1;
                s
            }
            old => {
                let carried = old.and_then(|o| self.carry(o, sys, a, c, ct, generation));
                let s = match carried {
                    Some(s) => {
                        self.stats.carried += 1;
                        self.work.carried += 1;
                        s
                    }
                    None => {
                        self.build(PressureSolve::Multigrid, Some((a, c, ct)), sys, generation)?
                    }
                };
                self.work.factorizations += 1;
                self.stats.setups += 1;
                s
            }
        };
        self.used_carried = setup.age > 0;
        self.keepable = true;
        let t1 = Instant::now();
        self.stats.setup_seconds += (t1 - t0).as_secs_f64();
        let Prec::Blocks { velocity, schur } = &setup.prec else {
            return Err(SolveError::Factorization {
                solver: NAME,
                detail: "the stabilised iteration needs the block preconditioner".into(),
            });
        };
        let apply_k = |y: &[f64], out: &mut [f64], tmp: &mut [f64]| {
            apply_saddle(a, c, ct, Some(l), y, out, tmp);
        };
        let apply_p = |r: &[f64], z: &mut [f64]| apply_blocks(velocity, schur, n, r, z);
        let nt = n + m;
        // The solve's vectors, in the arrays the last solve used.
        let mut scratch = std::mem::take(&mut self.solve_scratch);
        let SolveScratch {
            basis,
            b,
            y,
            tmp,
            r,
            d,
        } = &mut scratch;
        let fresh = |v: &mut Vec<f64>, len: usize| {
            v.clear();
            v.resize(len, 0.0);
        };
        b.clear();
        b.extend_from_slice(sys.rhs);
        b.extend_from_slice(st.offset);
        let b = &*b;
        let den = dot(b, b).sqrt();
        fresh(y, nt);
        y[..n].copy_from_slice(x);
        // The last Picard iterate's `q` on the same pattern.
        if self.last_q.0 == generation && self.last_q.1.len() == m {
            y[n..].copy_from_slice(&self.last_q.1);
        }
        fresh(tmp, n);
        fresh(r, nt);
        fresh(d, nt);
        let residual_of = |y: &[f64], r: &mut [f64], tmp: &mut [f64]| {
            apply_k(y, r, tmp);
            for_each_row(r, |i, r| *r = b[i] - *r);
            let num = dot(r, r).sqrt();
            if den > 0.0 {
                num / den
            } else {
                num
            }
        };
        let (y, tmp, r, d) = (&mut y[..], &mut tmp[..], &mut r[..], &mut d[..]);
        let mut residual = residual_of(y, r, tmp);
        let mut iterations = 0;
        let apply_t = |r: &[f64], z: &mut [f64], tmp: &mut [f64]| {
            apply_upper(velocity, schur, ct, n, r, z, tmp)
        };
        let apply_tk = |r: &[f64], z: &mut [f64], w: &mut [f64], tmp: &mut [f64]| {
            apply_upper_then_saddle(velocity, schur, (a, c, ct, Some(l)), r, z, w, tmp)
        };
        let target = self.target();
        let absolute = target * if den > 0.0 { den } else { 1.0 };
        while residual > target && iterations < self.max_iterations {
            for_each_row(d, |_, v| *v = 0.0);
            let left = self.max_iterations - iterations;
            let it = match self.krylov {
                Krylov::Gmres => gmres(
                    &apply_k,
                    &apply_t,
                    Some(&apply_tk),
                    r,
                    d,
                    tmp,
                    absolute,
                    self.restart,
                    left,
                    basis,
                ),
                Krylov::Minres => minres(
                    &apply_k,
                    &apply_p,
                    r,
                    d,
                    tmp,
                    pass_tolerance(target, residual),
                    left,
                ),
            };
            iterations += it.max(1);
            for_each_row(y, |i, y| *y += d[i]);
            let new = residual_of(y, r, tmp);
            // A pass that gained less than a tenth ends the solve too
            // (see `STAGNATION`).
            if new.is_nan() || new >= STAGNATION * residual {
                residual = new;
                break;
            }
            residual = new;
        }
        let mut setup = setup;
        if setup.age == 0 {
            setup.fresh_iterations = setup.fresh_iterations.max(iterations);
        } else if iterations > (setup.fresh_iterations * 3 / 2).max(setup.fresh_iterations + 3) {
            // A carried hierarchy that has stopped fitting: the next
            // pattern builds anew.
            setup.age = u32::MAX;
        }
        self.setup = Some(setup);
        self.blocks = blocks;
        self.finish(t1, iterations, residual, target, y)?;
        x.copy_from_slice(&y[..n]);
        self.last_q.0 = generation;
        self.last_q.1.clear();
        self.last_q.1.extend_from_slice(&y[n..]);
        self.solve_scratch = scratch;
        Ok(SolveReport {
            residual,
            iterations,
        })
    }

    /// `Ŝ = I + L̃ + C Â⁻¹ Cᵀ` (`inv` the inverse of `Â`, `l` the
    /// addend `I + L̃`), formed into the arrays of the last `Ŝ`, which the
    /// caller hands back to `schur_matrix` once the hierarchy is built.
    fn form_schur(&mut self, c: &Csr, inv: &[f64], ct: &Csr, l: Addend<'_>) -> Csr {
        let mut s = std::mem::take(&mut self.schur_matrix);
        product_plus_into(c, Some(inv), ct, Some(l), &mut s, &mut self.product_scratch);
        s
    }

    /// The last step's pressure hierarchy carried over to this pattern
    /// (`Amg::with_finest`), when the rows name their particles and most
    /// of them had a row before: the velocity block's Jacobi and `Ŝ` are
    /// new, the aggregates and coarse levels old.
    fn carry(
        &mut self,
        old: Setup,
        sys: &SplitSystem<'_>,
        a: &Csr,
        c: &Csr,
        ct: &Csr,
        generation: u64,
    ) -> Option<Setup> {
        let st = sys.stabilisation?;
        let ids = st.row_ids?;
        if old.age >= self.carry_steps
            || old.generation == generation
            || old.ids.is_empty()
            || ids.len() != c.nrows
            || crate::amg::check_structure(c.nrows, c.nrows, st.l_ptr, st.l_idx, st.l_val.len())
                .is_err()
        {
            return None;
        }
        let Prec::Blocks { schur, velocity } = old.prec else {
            return None;
        };
        if !matches!(*velocity, VelocityPrec::Jacobi(_)) || self.velocity == VelocityBlock::Amg {
            return None;
        }
        let from = rows_from(&old.ids, ids)?;
        let diag = a.diagonal();
        if diag.iter().any(|&v| !(v > 0.0 && v.is_finite())) {
            return None;
        }
        if self.velocity == VelocityBlock::Auto {
            let off: f64 = (0..a.nrows).map(|i| off_diagonal(a, i)).sum();
            if off > self.dominance_limit * diag.iter().sum::<f64>() {
                return None;
            }
        }
        let inv: Vec<f64> = diag.iter().map(|v| 1.0 / v).collect();
        let scale = schur_scale(c, &inv, &st);
        if !(scale <= old.scale * SCALE_DRIFT && scale * SCALE_DRIFT >= old.scale) {
            return None;
        }
        let rho = scale / old.scale;
        let l = (st.l_ptr, st.l_idx, st.l_val, 1.0);
        let s = self.form_schur(c, &inv, ct, l);
        let schur = schur.with_finest(&s, &from, rho);
        self.schur_matrix = s;
        let schur = schur?;
        Some(Setup {
            generation,
            n: a.nrows,
            m: c.nrows,
            prec: Prec::Blocks {
                velocity: Box::new(VelocityPrec::Jacobi(inv)),
                schur: Box::new(schur),
            },
            ids: ids.to_vec(),
            age: old.age + 1,
            fresh_iterations: old.fresh_iterations,
            scale: old.scale,
        })
    }

    /// Books an iteration that started its work at `t1`, and refuses it
    /// when it did not converge (`y` the solution it returns, `target` the
    /// residual it aimed at: one looser than the residual limit is
    /// accepted).
    fn finish(
        &mut self,
        t1: Instant,
        iterations: usize,
        residual: f64,
        target: f64,
        y: &[f64],
    ) -> Result<(), SolveError> {
        self.stats.iterate_seconds += t1.elapsed().as_secs_f64();
        self.stats.solves += 1;
        self.stats.iterations += iterations as u64;
        self.work.iterations += iterations as u64;
        self.stats.max_iterations = self.stats.max_iterations.max(iterations);
        let limit = self.residual_limit.max(target);
        if residual.is_nan() || residual > limit || y.iter().any(|v| !v.is_finite()) {
            // A stale set-up may be what failed: the next call builds anew.
            self.setup = None;
            return Err(SolveError::NoConvergence {
                solver: NAME,
                iterations,
                residual,
            });
        }
        Ok(())
    }

    fn iterate(
        &mut self,
        sys: &SplitSystem<'_>,
        pressure: PressureSolve,
        generation: u64,
        x: &mut [f64],
    ) -> Result<SolveReport, SolveError> {
        crate::solver::check_finite(sys.rhs)?;
        let t0 = Instant::now();
        // The CSR blocks only for the multigrid path; the Cholesky path
        // reads the split system.
        let mut blocks = std::mem::take(&mut self.blocks);
        let multigrid = pressure == PressureSolve::Multigrid;
        if multigrid {
            blocks.refresh(sys, generation);
        }
        let abc = multigrid.then_some((&blocks.a, &blocks.c, &blocks.ct));
        let (n, m) = (sys.a_v.nrows(), sys.c_rows());
        let same = self
            .setup
            .as_ref()
            .is_some_and(|s| s.generation == generation && s.n == n && s.m == m);
        // The Cholesky path: the factor of an earlier iterate while `C` has
        // moved little since (`keep_factor_below`).
        let mut stale = same
            && self.keepable
            && !self.reuse_setup
            && match self.setup.as_ref().map(|s| &s.prec) {
                Some(Prec::Woodbury(w)) => {
                    self.keep_factor_below > 0.0
                        && w.moved(sys, generation) <= self.keep_factor_below
                }
                _ => false,
            };
        let keep = same && (self.reuse_setup || stale);
        if stale {
            self.stats.kept_factors += 1;
        }
        if !keep {
            self.set_up(pressure, abc, sys, generation)?;
        } else {
            self.work.resolves += 1;
        }
        let mut t1 = Instant::now();
        self.stats.setup_seconds += (t1 - t0).as_secs_f64();
        // The residual of the eliminated system, the one the direct path
        // reports: `e ← f − (A_v + CᵀC) v`, returns ‖e‖/‖f‖.
        // (`e` holds `(A_v + CᵀC) v` on entry: `Woodbury::product` on the
        // Cholesky path, in parallel rows.)
        let den = dot(sys.rhs, sys.rhs).sqrt();
        let eliminated = |e: &mut [f64]| {
            for_each_row(e, |i, e| *e = sys.rhs[i] - *e);
            let num = dot(e, e).sqrt();
            if den > 0.0 {
                num / den
            } else {
                num
            }
        };
        let mut r = vec![0.0; n];
        let mut q = Vec::new();
        match self.setup.as_mut().map(|s| &mut s.prec) {
            Some(Prec::Woodbury(w)) => {
                if keep {
                    w.follow(sys);
                }
                w.product(sys, generation, x, &mut r, &mut q);
            }
            _ => sys.apply(x, &mut r, &mut q),
        }
        let mut residual = eliminated(&mut r);
        // The caller's accuracy relaxes the multigrid iteration only: the
        // Cholesky path's CG is nearly a direct solve (one or two
        // iterations), with nothing to save.
        let target = if multigrid {
            self.target()
        } else {
            self.target
        };
        let (max_iterations, tolerance) = (self.max_iterations, self.tolerance);
        let mut iterations = 0;
        loop {
            let Some(setup) = self.setup.as_mut() else {
                return Err(SolveError::Factorization {
                    solver: NAME,
                    detail: "no preconditioner".into(),
                });
            };
            match &mut setup.prec {
                Prec::Woodbury(w) => {
                    // Preconditioned conjugate gradient on A, with the true
                    // residual's recurrence; on a kept factor for at most
                    // `kept_factor_iterations`.
                    let limit = if stale {
                        (iterations + self.kept_factor_iterations).min(max_iterations)
                    } else {
                        max_iterations
                    };
                    // A kept factor's iteration aims where a new factor's
                    // lands (two iterations overshoot the target about a
                    // hundredfold): at the target itself, the inflow of
                    // `tests/hooks.rs` filled 2.76 % too fast against
                    // 1.08 % (session 32).
                    let aim = if stale {
                        target * KEPT_FACTOR_AIM
                    } else {
                        target
                    };
                    let mut z = vec![0.0; n];
                    let mut d = vec![0.0; n];
                    let mut ad = vec![0.0; n];
                    if residual > aim {
                        w.apply(&r, &mut z)?;
                        d.copy_from_slice(&z);
                        let mut rz = dot(&r, &z);
                        while iterations < limit {
                            w.product(sys, generation, &d, &mut ad, &mut q);
                            let curvature = dot(&d, &ad);
                            if curvature.is_nan() || curvature <= 0.0 {
                                break;
                            }
                            let alpha = rz / curvature;
                            x.iter_mut().zip(&d).for_each(|(x, d)| *x += alpha * d);
                            r.iter_mut().zip(&ad).for_each(|(r, a)| *r -= alpha * a);
                            iterations += 1;
                            let rn = dot(&r, &r).sqrt();
                            residual = if den > 0.0 { rn / den } else { rn };
                            if residual <= aim {
                                break;
                            }
                            w.apply(&r, &mut z)?;
                            let rz_new = dot(&r, &z);
                            let beta = rz_new / rz;
                            rz = rz_new;
                            d.iter_mut().zip(&z).for_each(|(d, z)| *d = z + beta * *d);
                        }
                        w.product(sys, generation, x, &mut r, &mut q);
                        residual = eliminated(&mut r);
                    }
                    let unmet = residual.is_nan() || residual > target;
                    if stale && unmet && iterations < max_iterations {
                        // The kept factor is too far from this iterate: a new
                        // one, and the iteration goes on from `x`.
                        stale = false;
                        self.stats.kept_renewed += 1;
                        let tr = Instant::now();
                        self.set_up(pressure, None, sys, generation)?;
                        let spent = tr.elapsed();
                        self.stats.setup_seconds += spent.as_secs_f64();
                        t1 += spent;
                        continue;
                    }
                }
                Prec::Blocks { velocity, schur } => {
                    let Some((a, c, ct)) = abc else {
                        return Err(SolveError::Factorization {
                            solver: NAME,
                            detail: "the multigrid iteration needs the blocks as CSR".into(),
                        });
                    };
                    let apply_k = |y: &[f64], out: &mut [f64], tmp: &mut [f64]| {
                        apply_saddle(a, c, ct, None, y, out, tmp);
                    };
                    let apply_p = |r: &[f64], z: &mut [f64]| apply_blocks(velocity, schur, n, r, z);
                    let nt = n + m;
                    let mut y = vec![0.0; nt];
                    let mut tmp = vec![0.0; n];
                    let mut rhs = vec![0.0; nt];
                    // Refinement on the eliminated system: each pass solves the
                    // saddle-point form for the correction of the current
                    // residual, `K [δV; δq] = [e; 0]`, to `tolerance` in the
                    // preconditioner's norm. That norm weighs the second row's
                    // residual lightly, and `Cᵀ` magnifies it in `e`, so one pass
                    // reaches a few digits of `e`, never all: the passes
                    // recompute `e` exactly.
                    while residual > target && iterations < max_iterations {
                        rhs[..n].copy_from_slice(&r);
                        rhs[n..].iter_mut().for_each(|v| *v = 0.0);
                        y.iter_mut().for_each(|v| *v = 0.0);
                        let it = minres(
                            &apply_k,
                            &apply_p,
                            &rhs,
                            &mut y,
                            &mut tmp,
                            tolerance,
                            max_iterations - iterations,
                        );
                        iterations += it.max(1);
                        x.iter_mut().zip(&y[..n]).for_each(|(x, d)| *x += d);
                        sys.apply(x, &mut r, &mut q);
                        let new = eliminated(&mut r);
                        if new.is_nan() || new >= residual {
                            residual = new;
                            break;
                        }
                        residual = new;
                    }
                }
            }
            break;
        }
        self.blocks = blocks;
        self.finish(t1, iterations, residual, target, x)?;
        Ok(SolveReport {
            residual,
            iterations,
        })
    }
}

/// The reduction of the preconditioned residual a pass of the stabilised
/// path's MINRES aims at: the one that would take the relative residual
/// from `residual` to `target`, no looser than ½. A fixed 10⁻⁶ per pass
/// overshot the target by two to three orders of magnitude in its last
/// pass after needing a second pass anyway: aiming at the target took a
/// third fewer iterations on the 2D dam break (session 20). (The
/// unstabilised path keeps [`BlockSolver::tolerance`]: aimed passes
/// stagnated there above the residual limit.) The floor keeps the aim
/// above what the recurrence resolves.
fn pass_tolerance(target: f64, residual: f64) -> f64 {
    (target / residual).clamp(1e-14, 0.5)
}

/// The CSR blocks of a split system, `A_v`, `C`, `Cᵀ` and `L̃`, kept
/// across the solves of one pattern generation (the Picard iterates of a
/// step): their structures, and where each entry of `Cᵀ` comes from, are
/// found once; a solve refreshes the values only (at 58k particles in 3D
/// the conversion took 0.2 s of each 0.8 s solve, session 21). A new
/// pattern is written into the arrays the last one used (session 31: at
/// 289k particles in 3D, fresh arrays for each step's pattern cost 1.2–3.1 s
/// a step, most of it the system zeroing new pages).
#[derive(Debug, Default)]
struct Blocks {
    /// The generation the structures belong to (`None`: none yet).
    generation: Option<u64>,
    /// `A_v`'s column pointers in CSC, to recognise the same pattern.
    a_col_ptr: Vec<usize>,
    /// `A_v` as CSR. `A_v` is symmetric ([`SplitSystem::a_v`]), so its
    /// rows are its CSC columns: the CSC arrays themselves, gathered when
    /// the columns are not contiguous (`a_from`, empty when they are).
    a: Csr,
    a_from: Vec<usize>,
    /// `C` as CSR (its own arrays copied).
    c: Csr,
    /// `Cᵀ`, entry `k` from `C`'s value `ct_from[k]`.
    ct: Csr,
    ct_from: Vec<usize>,
    /// `L̃` (empty without stabilisation).
    l: Csr,
}

/// The vectors of one stabilised solve ([`BlockSolver`]'s
/// `iterate_stabilised`), kept from solve to solve for their allocations:
/// new ones each solve (twelve a step at 289k particles in 3D, the Krylov
/// basis a hundred megabytes) had the system zero their pages again.
#[derive(Debug, Default)]
struct SolveScratch {
    /// The Krylov basis (GMRES).
    basis: Vec<f64>,
    /// The right-hand side `[f; o]`.
    b: Vec<f64>,
    /// The iterate `[V; q]`.
    y: Vec<f64>,
    /// Scratch of the velocity size.
    tmp: Vec<f64>,
    /// The residual.
    r: Vec<f64>,
    /// A pass's correction.
    d: Vec<f64>,
}

/// `dst ← src`, in the allocation `dst` already holds.
fn copy_into<T: Copy>(dst: &mut Vec<T>, src: &[T]) {
    dst.clear();
    dst.extend_from_slice(src);
}

impl Blocks {
    /// Brings the blocks to `sys`: the structures when the generation or
    /// the pattern changed, the values always.
    fn refresh(&mut self, sys: &SplitSystem<'_>, generation: u64) {
        let a_v = sys.a_v;
        let n = a_v.nrows();
        let col_ptr = a_v.col_ptr();
        let col_nnz = a_v.col_nnz();
        let same = self.generation == Some(generation)
            && self.a_col_ptr == col_ptr
            && self.a.nrows == n
            && self.c.ptr == sys.c_ptr
            && self.c.idx == sys.c_idx
            && match sys.stabilisation {
                Some(st) => {
                    self.l.nrows == sys.c_rows() && self.l.ptr == st.l_ptr && self.l.idx == st.l_idx
                }
                None => self.l.nrows == 0 && self.l.idx.is_empty(),
            };
        if !same {
            // `A_v`: symmetric, so row `i` of its CSR is column `i` of its
            // CSC, entry for entry (the structure is symmetric and the
            // values are).
            copy_into(&mut self.a_col_ptr, col_ptr);
            self.a.nrows = n;
            self.a.ncols = a_v.ncols();
            self.a_from.clear();
            match col_nnz {
                None => {
                    copy_into(&mut self.a.ptr, col_ptr);
                    copy_into(&mut self.a.idx, &a_v.row_idx()[..col_ptr[n]]);
                }
                Some(nnz) => {
                    self.a.ptr.clear();
                    self.a.ptr.push(0);
                    self.a.idx.clear();
                    for j in 0..n {
                        let range = col_ptr[j]..col_ptr[j] + nnz[j];
                        self.a.idx.extend_from_slice(&a_v.row_idx()[range.clone()]);
                        self.a_from.extend(range);
                        self.a.ptr.push(self.a.idx.len());
                    }
                }
            }
            self.a.val.clear();
            self.a.val.resize(self.a.idx.len(), 0.0);
            self.c.nrows = sys.c_rows();
            self.c.ncols = n;
            copy_into(&mut self.c.ptr, sys.c_ptr);
            copy_into(&mut self.c.idx, sys.c_idx);
            self.c.val.clear();
            self.c.val.resize(sys.c_idx.len(), 0.0);
            let c = &self.c;
            transpose_structure_into(
                c.nrows,
                n,
                |r| c.ptr[r]..c.ptr[r + 1],
                &c.idx,
                &mut self.ct.ptr,
                &mut self.ct.idx,
                &mut self.ct_from,
            );
            self.ct.nrows = n;
            self.ct.ncols = c.nrows;
            self.ct.val.clear();
            self.ct.val.resize(self.ct.idx.len(), 0.0);
            match sys.stabilisation {
                Some(st) => {
                    self.l.nrows = sys.c_rows();
                    self.l.ncols = sys.c_rows();
                    copy_into(&mut self.l.ptr, st.l_ptr);
                    copy_into(&mut self.l.idx, st.l_idx);
                    self.l.val.clear();
                    self.l.val.resize(st.l_idx.len(), 0.0);
                }
                None => self.l = Csr::default(),
            }
            self.generation = Some(generation);
        }
        let values = a_v.val();
        if self.a_from.is_empty() {
            let values = &values[..self.a.val.len()];
            self.a
                .val
                .par_chunks_mut(8192)
                .zip(values.par_chunks(8192))
                .for_each(|(v, src)| v.copy_from_slice(src));
        } else {
            let a_from = &self.a_from;
            self.a
                .val
                .par_chunks_mut(8192)
                .zip(a_from.par_chunks(8192))
                .for_each(|(v, f)| v.iter_mut().zip(f).for_each(|(v, &k)| *v = values[k]));
        }
        self.c.val.copy_from_slice(sys.c_val);
        let c_val = sys.c_val;
        self.ct
            .val
            .iter_mut()
            .zip(&self.ct_from)
            .for_each(|(v, &k)| *v = c_val[k]);
        if let Some(st) = sys.stabilisation {
            self.l.val.copy_from_slice(st.l_val);
        }
    }
}

/// `out ← K y` for `y = [V; q]`, `K = [A Cᵀ; C −(I + L̃)]` (`L̃ = 0` when
/// `l` is `None`); `tmp` is scratch of the velocity size.
fn apply_saddle(
    a: &Csr,
    c: &Csr,
    ct: &Csr,
    l: Option<&Csr>,
    y: &[f64],
    out: &mut [f64],
    tmp: &mut [f64],
) {
    let n = a.nrows;
    let (yv, yq) = y.split_at(n);
    let (ov, oq) = out.split_at_mut(n);
    // Each row's terms in the order of separate products and sums.
    for_each_row(tmp, |i, t| *t = ct.row_dot4(i, yq));
    let tmp: &[f64] = tmp;
    for_each_row(ov, |i, o| *o = a.row_dot4(i, yv) + tmp[i]);
    pressure_rows(c, l, yv, yq, oq);
}

/// `o ← C v − q − L̃ q` (`L̃ = 0` when `l` is `None`): the pressure rows
/// of the saddle-point operator, each row summed as `(C v)ᵢ − qᵢ − (L̃
/// q)ᵢ`.
fn pressure_rows(c: &Csr, l: Option<&Csr>, v: &[f64], q: &[f64], o: &mut [f64]) {
    match l {
        Some(l) => for_each_row(o, |i, o| {
            *o = c.row_dot4(i, v) - q[i] - l.row_dot4(i, q);
        }),
        None => for_each_row(o, |i, o| *o = c.row_dot4(i, v) - q[i]),
    }
}

/// `z ← diag(Â_v, Ŝ)⁻¹ r` approximately: the velocity block's Jacobi or
/// V-cycle, one V-cycle on the pressure block (`n` velocity dofs first).
fn apply_blocks(velocity: &VelocityPrec, schur: &Amg, n: usize, r: &[f64], z: &mut [f64]) {
    let (rv, rq) = r.split_at(n);
    let (zv, zq) = z.split_at_mut(n);
    velocity_step(velocity, rv, zv);
    schur.apply(rq, zq);
}

/// `z ← P⁻¹ r` for the block upper-triangular `P = [Â_v Cᵀ; 0 −Ŝ]`:
/// `z_q = −Ŝ⁻¹ r_q`, then `z_v = Â_v⁻¹ (r_v − Cᵀ z_q)`, each inverse by
/// the block's own preconditioner (`tmp` of the velocity size). With
/// exact blocks `K P⁻¹ = [I 0; C Â_v⁻¹ I]`, so GMRES would need two
/// iterations.
fn apply_upper(
    velocity: &VelocityPrec,
    schur: &Amg,
    ct: &Csr,
    n: usize,
    r: &[f64],
    z: &mut [f64],
    tmp: &mut [f64],
) {
    let (rv, rq) = r.split_at(n);
    let (zv, zq) = z.split_at_mut(n);
    schur_step(schur, rq, zq);
    let zq: &[f64] = zq;
    for_each_row(tmp, |i, t| *t = rv[i] - ct.row_dot4(i, zq));
    velocity_step(velocity, tmp, zv);
}

/// `z_q = −Ŝ⁻¹ r_q`, the pressure row of the block preconditioners.
fn schur_step(schur: &Amg, rq: &[f64], zq: &mut [f64]) {
    schur.apply(rq, zq);
    for_each_row(zq, |_, v| *v = -*v);
}

/// `z_v = Â⁻¹ t`, the velocity row of the block preconditioners.
fn velocity_step(velocity: &VelocityPrec, t: &[f64], zv: &mut [f64]) {
    match velocity {
        VelocityPrec::Jacobi(inv) => for_each_row(zv, |i, z| *z = t[i] * inv[i]),
        VelocityPrec::Amg(amg) => amg.apply(t, zv),
    }
}

/// `z = P⁻¹ r` ([`apply_upper`]) and then `w = K z` ([`apply_saddle`]),
/// with the same results: `Cᵀ z_q`, which both need, is formed once (one
/// sparse product fewer per GMRES iteration). `tmp` is scratch of the
/// velocity size.
#[allow(clippy::too_many_arguments)]
fn apply_upper_then_saddle(
    velocity: &VelocityPrec,
    schur: &Amg,
    (a, c, ct, l): (&Csr, &Csr, &Csr, Option<&Csr>),
    r: &[f64],
    z: &mut [f64],
    w: &mut [f64],
    tmp: &mut [f64],
) {
    let n = a.nrows;
    let (rv, rq) = r.split_at(n);
    let (zv, zq) = z.split_at_mut(n);
    let (wv, wq) = w.split_at_mut(n);
    schur_step(schur, rq, zq);
    // `w_v` holds `r_v − Cᵀ z_q` until `K z` overwrites it.
    for_each_row2(tmp, wv, |i, t, w| {
        *t = ct.row_dot4(i, zq);
        *w = rv[i] - *t;
    });
    velocity_step(velocity, wv, zv);
    let tmp: &[f64] = tmp;
    for_each_row(wv, |i, w| *w = a.row_dot4(i, zv) + tmp[i]);
    pressure_rows(c, l, zv, zq, wq);
}

/// `z = P⁻¹ v` and `w = K z` in one call, for operators that share work
/// ([`apply_upper_then_saddle`]); the last argument is scratch.
type Fused<'a> = &'a dyn Fn(&[f64], &mut [f64], &mut [f64], &mut [f64]);

/// A restart cycle of GMRES, or a pass of refinement around it, whose
/// residual is above this fraction of the one before has stagnated and
/// ends the solve ([`BlockSolver::max_iterations`] bounds it otherwise).
const STAGNATION: f64 = 0.9;

/// Right-preconditioned restarted GMRES (Saad, alg. 9.5; modified
/// Gram–Schmidt, Givens rotations): `y` holds the initial guess on entry
/// and the iterate on return. Stops when the residual `‖b − K y‖`, which
/// right preconditioning leaves unweighted, falls to `target` (absolute),
/// or after `max_iter` iterations. Returns the iterations done.
/// `apply_pk`, when given, does `apply_p` and then `apply_k` of the
/// basis vector in one call. `basis` holds the Krylov basis; its
/// allocation is the caller's, kept from solve to solve.
#[allow(clippy::too_many_arguments)]
fn gmres(
    apply_k: Operator<'_>,
    apply_p: Operator<'_>,
    apply_pk: Option<Fused<'_>>,
    b: &[f64],
    y: &mut [f64],
    tmp: &mut [f64],
    target: f64,
    restart: usize,
    max_iter: usize,
    basis: &mut Vec<f64>,
) -> usize {
    let nt = b.len();
    // More basis vectors than iterations or unknowns are never used; a
    // huge `restart` ("never restart") must not allocate them.
    let restart = restart.min(max_iter).min(nt).max(1);
    // The basis, vector `i` at `i nt..(i + 1) nt`: one allocation, reused
    // by every restart and, through the caller, every solve (pages are
    // touched as vectors come; a new allocation each solve had the system
    // zero them again, session 31).
    basis.clear();
    basis.reserve((restart + 1) * nt);
    let mut h = vec![vec![0.0; restart]; restart + 1];
    let (mut cs, mut sn) = (vec![0.0; restart], vec![0.0; restart]);
    let mut g = vec![0.0; restart + 1];
    let mut z = vec![0.0; nt];
    let mut w = vec![0.0; nt];
    let mut done = 0;
    let mut last_beta = f64::INFINITY;
    // The vector operations run in parallel row chunks above `PAR_ROWS`
    // (`for_each_row`), each entry's arithmetic as in a serial pass.
    while done < max_iter {
        if y.iter().all(|&v| v == 0.0) {
            // `K 0 = 0`: the residual is `b` (the caller's correction solves
            // start so), without a product.
            w.copy_from_slice(b);
        } else {
            apply_k(y, &mut w, tmp);
            for_each_row(&mut w, |i, w| *w = b[i] - *w);
        }
        let beta = dot(&w, &w).sqrt();
        if beta.is_nan() || beta <= target {
            break;
        }
        // A whole restart cycle that gained less than a tenth: the
        // residual sits at the accuracy this system allows (a 3D column
        // on a stiff cylinder ground through 2 000 iterations at 3.6·10⁻⁹
        // once, session 31); the caller judges what was reached.
        if beta > STAGNATION * last_beta {
            break;
        }
        last_beta = beta;
        basis.clear();
        basis.resize(nt, 0.0);
        for_each_row(basis, |i, v| *v = w[i] / beta);
        g.iter_mut().for_each(|v| *v = 0.0);
        g[0] = beta;
        let mut k = 0;
        let mut converged = false;
        while k < restart && done < max_iter {
            let v = &basis[k * nt..(k + 1) * nt];
            match apply_pk {
                Some(pk) => pk(v, &mut z, &mut w, tmp),
                None => {
                    apply_p(v, &mut z, tmp);
                    apply_k(&z, &mut w, tmp);
                }
            }
            for (i, v) in basis.chunks_exact(nt).enumerate() {
                let hik = dot(&w, v);
                h[i][k] = hik;
                for_each_row(&mut w, |j, w| *w -= hik * v[j]);
            }
            let norm = dot(&w, &w).sqrt();
            h[k + 1][k] = norm;
            for i in 0..k {
                let t = cs[i] * h[i][k] + sn[i] * h[i + 1][k];
                h[i + 1][k] = -sn[i] * h[i][k] + cs[i] * h[i + 1][k];
                h[i][k] = t;
            }
            let rho = h[k][k].hypot(h[k + 1][k]);
            if rho.is_nan() || rho <= 0.0 || rho.is_infinite() {
                break;
            }
            cs[k] = h[k][k] / rho;
            sn[k] = h[k + 1][k] / rho;
            h[k][k] = rho;
            h[k + 1][k] = 0.0;
            g[k + 1] = -sn[k] * g[k];
            g[k] *= cs[k];
            k += 1;
            done += 1;
            if g[k].abs() <= target || norm.is_nan() || norm <= 0.0 {
                converged = true;
                break;
            }
            let start = basis.len();
            basis.resize(start + nt, 0.0);
            for_each_row(&mut basis[start..], |i, v| *v = w[i] / norm);
        }
        if k == 0 {
            break;
        }
        // Coefficients of the basis: `H α = g` (upper triangular).
        let mut alpha = vec![0.0; k];
        for i in (0..k).rev() {
            let mut v = g[i];
            for j in i + 1..k {
                v -= h[i][j] * alpha[j];
            }
            alpha[i] = v / h[i][i];
        }
        // `w = Σ αⱼ vⱼ`, each entry summed over the basis in order.
        let basis_ref = &basis;
        for_each_row(&mut w, |i, w| {
            let mut s = 0.0;
            for (j, a) in alpha.iter().enumerate() {
                s += a * basis_ref[j * nt + i];
            }
            *w = s;
        });
        apply_p(&w, &mut z, tmp);
        for_each_row(y, |i, y| *y += z[i]);
        if converged {
            break;
        }
    }
    done
}

/// Preconditioned MINRES (Paige & Saunders; the three-term form of Elman,
/// Silvester & Wathen, alg. 4.1) for a symmetric `K` and a symmetric
/// positive definite preconditioner `P⁻¹`. `y` holds the initial guess on
/// entry. Stops when the `P⁻¹`-norm of the residual has fallen by `tol`.
/// Returns the iterations done.
/// `out ← K y` with scratch of the velocity size.
type Operator<'a> = &'a dyn Fn(&[f64], &mut [f64], &mut [f64]);

fn minres(
    apply_k: Operator<'_>,
    apply_p: &dyn Fn(&[f64], &mut [f64]),
    b: &[f64],
    y: &mut [f64],
    tmp: &mut [f64],
    tol: f64,
    max_iter: usize,
) -> usize {
    let nt = b.len();
    let mut v_old = vec![0.0; nt];
    let mut v = vec![0.0; nt];
    apply_k(y, &mut v, tmp);
    v.iter_mut().zip(b).for_each(|(v, b)| *v = b - *v);
    let mut z = vec![0.0; nt];
    apply_p(&v, &mut z);
    let mut gamma = dot(&z, &v).max(0.0).sqrt();
    if gamma == 0.0 || !gamma.is_finite() {
        return 0;
    }
    let gamma1 = gamma;
    let mut gamma_old = 1.0;
    let mut eta = gamma;
    let (mut s_old, mut s) = (0.0, 0.0);
    let (mut c_old, mut c) = (1.0, 1.0);
    let mut w_old = vec![0.0; nt];
    let mut w = vec![0.0; nt];
    let mut kz = vec![0.0; nt];
    let mut z_new = vec![0.0; nt];
    for it in 1..=max_iter {
        z.iter_mut().for_each(|x| *x /= gamma);
        apply_k(&z, &mut kz, tmp);
        let delta = dot(&kz, &z);
        // v_new = K z − (δ/γ) v − (γ/γ_old) v_old, stored in v_old.
        let (f1, f2) = (delta / gamma, gamma / gamma_old);
        v_old
            .iter_mut()
            .zip(&kz)
            .zip(&v)
            .for_each(|((vo, k), v)| *vo = k - f1 * v - f2 * *vo);
        std::mem::swap(&mut v_old, &mut v); // v = v_new, v_old = v
        apply_p(&v, &mut z_new);
        let gamma_new = dot(&z_new, &v).max(0.0).sqrt();
        let a0 = c * delta - c_old * s * gamma;
        let a1 = (a0 * a0 + gamma_new * gamma_new).sqrt();
        let a2 = s * delta + c_old * c * gamma;
        let a3 = s_old * gamma;
        if a1 == 0.0 || !a1.is_finite() {
            return it;
        }
        let c_new = a0 / a1;
        let s_new = gamma_new / a1;
        // w_new = (z − a3 w_old − a2 w) / a1, stored in w_old.
        w_old
            .iter_mut()
            .zip(&z)
            .zip(&w)
            .for_each(|((wo, z), w)| *wo = (z - a3 * *wo - a2 * w) / a1);
        std::mem::swap(&mut w_old, &mut w);
        let step = c_new * eta;
        y.iter_mut().zip(&w).for_each(|(y, w)| *y += step * w);
        eta *= -s_new;
        gamma_old = gamma;
        gamma = gamma_new;
        (c_old, c) = (c, c_new);
        (s_old, s) = (s, s_new);
        std::mem::swap(&mut z, &mut z_new);
        if eta.abs() <= tol * gamma1 || gamma == 0.0 {
            return it;
        }
    }
    max_iter
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `C` of `rows` rows (rows are filled in parallel chunks above
    /// 4 096) with a few scattered entries per row, and a positive
    /// diagonal `d`.
    fn sample(rows: usize, cols: usize, seed: u64) -> (Csr, Vec<f64>) {
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize
        };
        let mut t = Vec::new();
        for r in 0..rows {
            // Row 7 stays empty (a fluid node with no element).
            if r == 7 {
                continue;
            }
            for _ in 0..4 {
                let j = (r * cols / rows + next() % 9) % cols;
                t.push((r, j, (next() % 1000) as f64 / 250.0 - 2.0));
            }
        }
        let d = (0..cols)
            .map(|_| 0.5 + (next() % 100) as f64 / 50.0)
            .collect();
        (Csr::from_triplets(rows, cols, &t), d)
    }

    /// A split system of block size 1 with `C`, and with `L̃` and the
    /// offset when given.
    fn split<'a>(
        a_v: faer::sparse::SparseColMatRef<'a, usize, f64>,
        c: &'a Csr,
        stabilisation: Option<(&'a Csr, &'a [f64])>,
        coords: &'a [f64],
        rhs: &'a [f64],
    ) -> SplitSystem<'a> {
        SplitSystem {
            a_v,
            c_ptr: &c.ptr,
            c_idx: &c.idx,
            c_val: &c.val,
            block_size: 1,
            coords,
            rhs,
            stabilisation: stabilisation.map(|(l, offset)| crate::solver::Stabilisation {
                l_ptr: &l.ptr,
                l_idx: &l.idx,
                l_val: &l.val,
                offset,
                row_ids: None,
            }),
        }
    }

    /// The blocks kept across the solves of a generation are the blocks
    /// converted afresh: after new values on the same pattern, and after a
    /// new pattern (a new generation, and the same generation with the
    /// stabilisation added).
    /// The map by which a hierarchy is carried over (session 28): each
    /// new row's old row through its particle, and none when more than
    /// one row in twenty is new.
    #[test]
    fn rows_are_carried_over_through_their_particles() {
        let old = [7u32, 3, 9, 1];
        assert_eq!(rows_from(&old, &[1, 7, 3, 9]), Some(vec![3, 0, 1, 2]));
        let mut old: Vec<u32> = (0..40).collect();
        let mut new: Vec<u32> = (0..40).rev().collect();
        new[0] = 99;
        new[1] = 98;
        let from = rows_from(&old, &new).unwrap();
        assert_eq!(&from[..3], &[u32::MAX, u32::MAX, 37]);
        new[2] = 97;
        assert_eq!(rows_from(&old, &new), None);
        old.clear();
        assert_eq!(rows_from(&old, &[]), Some(vec![]));
        // Identities far apart (a caller's global numbers) take no table
        // as large as the largest.
        let far = [4_000_000_000u32, 7, 3_000_000_000];
        assert_eq!(
            rows_from(&far, &[3_000_000_000, 4_000_000_000, 7]),
            Some(vec![2, 0, 1])
        );
    }

    #[test]
    fn kept_blocks_follow_the_values_and_the_pattern() {
        // A full symmetric `A_v` as CSC (a path graph of `n` dofs).
        let csc = |n: usize, scale: f64| {
            let (mut ptr, mut idx, mut val) = (vec![0], Vec::new(), Vec::new());
            for j in 0..n {
                for i in j.saturating_sub(1)..(j + 2).min(n) {
                    idx.push(i);
                    val.push(if i == j {
                        4.0 * scale
                    } else {
                        -scale * (1 + i + j) as f64
                    });
                }
                ptr.push(idx.len());
            }
            (ptr, idx, val)
        };
        let mut blocks = Blocks::default();
        for (round, (n, generation, scale, stabilised)) in [
            (30, 1, 1.0, false),
            (30, 1, 2.5, false),
            (30, 1, 0.5, true),
            (44, 2, 1.0, true),
        ]
        .into_iter()
        .enumerate()
        {
            let (ptr, idx, val) = csc(n, scale);
            let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, &ptr, None, &idx);
            let a_v = faer::sparse::SparseColMatRef::new(sym, &val);
            let (mut c, _) = sample(n / 3, n, n as u64);
            c.val.iter_mut().for_each(|v| *v *= scale);
            let empty = vec![0; c.nrows + 1];
            let identity = Some((&empty[..], &[][..], &[][..], 1.0));
            let l = crate::amg::product_plus(&c, None, &c.transpose(), identity);
            let offset = vec![0.0; c.nrows];
            let coords = vec![0.0; n];
            let rhs = vec![1.0; n];
            let sys = split(
                a_v,
                &c,
                stabilised.then_some((&l, &offset[..])),
                &coords,
                &rhs,
            );
            blocks.refresh(&sys, generation);
            assert_eq!(blocks.a, Csr::from_faer_csc(a_v), "round {round}");
            assert_eq!(blocks.c, c, "round {round}");
            assert_eq!(blocks.ct, c.transpose(), "round {round}");
            if stabilised {
                assert_eq!(blocks.l, l, "round {round}");
            } else {
                assert_eq!(blocks.l, Csr::default(), "round {round}");
            }
        }
        // Columns with room between them (`col_nnz`): gathered, on a new
        // pattern and then with new values on it.
        let n = 20;
        let (ptr, idx, val) = csc(n, 1.0);
        let (mut gptr, mut gidx, mut gval, mut nnz) = (vec![0], Vec::new(), Vec::new(), Vec::new());
        for j in 0..n {
            gidx.extend_from_slice(&idx[ptr[j]..ptr[j + 1]]);
            gval.extend_from_slice(&val[ptr[j]..ptr[j + 1]]);
            nnz.push(ptr[j + 1] - ptr[j]);
            // Two slots of slack, with values that must not be read.
            gidx.extend_from_slice(&[0, 0]);
            gval.extend_from_slice(&[f64::NAN, f64::NAN]);
            gptr.push(gidx.len());
        }
        let (c, _) = sample(n / 3, n, 5);
        let (coords, rhs) = (vec![0.0; n], vec![1.0; n]);
        for (generation, factor) in [(3, 1.0), (3, -2.0)] {
            let vals: Vec<f64> = gval.iter().map(|v| v * factor).collect();
            let sym =
                faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, &gptr, Some(&nnz), &gidx);
            let a_v = faer::sparse::SparseColMatRef::new(sym, &vals);
            blocks.refresh(&split(a_v, &c, None, &coords, &rhs), generation);
            let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, &ptr, None, &idx);
            let want: Vec<f64> = val.iter().map(|v| v * factor).collect();
            let compact = faer::sparse::SparseColMatRef::new(sym, &want);
            assert_eq!(blocks.a, Csr::from_faer_csc(compact), "factor {factor}");
        }
    }

    /// The product on a kept pattern equals the upper triangle of the
    /// general sparse product `I + (C D) Cᵀ` bit for bit, pattern and
    /// values, in one row range and in parallel ones (5 000 rows), and
    /// stays right when `C`'s values change on the same pattern.
    #[test]
    fn the_kept_product_pattern_gives_the_general_product() {
        for rows in [300, 5000] {
            let (mut c, d) = sample(rows, rows * 3, 11);
            let plan = SchurProduct::new(4, &c.ptr, &c.idx, c.ncols);
            let (mut ct_val, mut val) = (Vec::new(), Vec::new());
            for round in 0..2 {
                if round == 1 {
                    c.val.iter_mut().for_each(|v| *v = *v * 1.5 - 0.25);
                }
                assert!(plan.fits(4, &c.ptr, &c.idx));
                assert!(!plan.fits(5, &c.ptr, &c.idx));
                plan.transpose_values(&c.val, &mut ct_val);
                let ct = c.transpose();
                assert_eq!(
                    (&plan.ct_ptr, &plan.ct_idx, &ct_val),
                    (&ct.ptr, &ct.idx, &ct.val)
                );
                let empty = vec![0; rows + 1];
                let identity = Some((&empty[..], &[][..], &[][..], 1.0));
                let want = crate::amg::product_plus(&c, Some(&d), &ct, identity);
                plan.product(&c.val, &ct_val, &d, &mut val);
                let upper = Csr {
                    nrows: rows,
                    ncols: rows,
                    ptr: plan.upper.0.clone(),
                    idx: plan.upper.1.clone(),
                    val: val.clone(),
                };
                for i in 0..rows {
                    let row: Vec<(usize, f64)> = (want.ptr[i]..want.ptr[i + 1])
                        .filter(|&p| want.idx[p] >= i)
                        .map(|p| (want.idx[p], want.val[p]))
                        .collect();
                    let got: Vec<(usize, f64)> = (upper.ptr[i]..upper.ptr[i + 1])
                        .map(|p| (upper.idx[p], upper.val[p]))
                        .collect();
                    assert_eq!(got, row, "row {i}");
                }
                assert_eq!(upper.ptr[rows], upper.idx.len());
            }
        }
    }

    /// GMRES solves a non-symmetric system to its target, with and
    /// without restarts, from a non-zero start.
    /// A residual GMRES cannot reduce (a direction the preconditioner
    /// maps to zero) ends the solve after a restart cycle without gain,
    /// instead of grinding to the iteration limit (session 31: 2 000
    /// iterations at a stiff cylinder's accuracy floor). Without the
    /// rule this runs all 1 000 iterations. (What the iterate is worth
    /// is not asserted: a singular preconditioner leaves the small
    /// least-squares problem singular too; the solver judges a solve by
    /// its true residual afterwards.)
    #[test]
    fn gmres_stops_when_a_restart_cycle_gains_nothing() {
        let n = 60;
        let k = |y: &[f64], out: &mut [f64], _: &mut [f64]| out.copy_from_slice(y);
        let p = |r: &[f64], z: &mut [f64], _: &mut [f64]| {
            z.copy_from_slice(r);
            z[0] = 0.0;
        };
        let b: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
        let (mut y, mut tmp, mut basis) = (vec![0.0; n], vec![0.0; n], Vec::new());
        let it = gmres(
            &k, &p, None, &b, &mut y, &mut tmp, 1e-12, 10, 1000, &mut basis,
        );
        assert!(it < 100, "{it} iterations");
    }

    #[test]
    fn gmres_solves_a_nonsymmetric_system_through_restarts() {
        let n = 40;
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 4.0 + (i % 3) as f64));
            if i + 1 < n {
                t.push((i, i + 1, -1.5));
            }
            if i >= 2 {
                t.push((i, i - 2, 0.7));
            }
        }
        let a = Csr::from_triplets(n, n, &t);
        let exact: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut b = vec![0.0; n];
        a.spmv(&exact, &mut b);
        let k = |y: &[f64], out: &mut [f64], _: &mut [f64]| a.spmv(y, out);
        // Jacobi on the right.
        let p = |r: &[f64], z: &mut [f64], _: &mut [f64]| {
            for i in 0..n {
                z[i] = r[i] / (4.0 + (i % 3) as f64);
            }
        };
        let norm_b = dot(&b, &b).sqrt();
        // `usize::MAX` ("never restart") overflowed the basis' size. One
        // basis serves every solve, as the solver's does.
        let mut basis = Vec::new();
        for restart in [50, 4, usize::MAX] {
            let mut y = vec![1.0; n];
            let mut tmp = vec![0.0; n];
            let it = gmres(
                &k,
                &p,
                None,
                &b,
                &mut y,
                &mut tmp,
                1e-12 * norm_b,
                restart,
                500,
                &mut basis,
            );
            let mut r = vec![0.0; n];
            a.spmv(&y, &mut r);
            let res = r
                .iter()
                .zip(&b)
                .map(|(r, b)| (b - r) * (b - r))
                .sum::<f64>()
                .sqrt();
            let err = y
                .iter()
                .zip(&exact)
                .map(|(y, e)| (y - e).abs())
                .fold(0.0, f64::max);
            assert!(it < 500, "restart {restart}: {it} iterations");
            assert!(
                res <= 1.01e-12 * norm_b,
                "restart {restart}: residual {res:e}"
            );
            assert!(err < 1e-10, "restart {restart}: error {err:e}");
        }
    }

    /// A mass-dominated velocity block on `n` dofs (a path graph: 3 on the
    /// diagonal, −1 beside it), as CSC arrays.
    fn path_graph(n: usize) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let (mut ptr, mut idx, mut val) = (vec![0], Vec::new(), Vec::new());
        for j in 0..n {
            for i in j.saturating_sub(1)..(j + 2).min(n) {
                idx.push(i);
                val.push(if i == j { 3.0 } else { -1.0 });
            }
            ptr.push(idx.len());
        }
        (ptr, idx, val)
    }

    /// A stabilised split system on `n` velocity dofs: a mass-dominated
    /// velocity block (a path graph), `C` on `n/3` pressure rows and a
    /// stabilisation Laplacian `L̃ = ε C Cᵀ`, owned.
    struct StabilisedPath {
        n: usize,
        a: (Vec<usize>, Vec<usize>, Vec<f64>),
        c: Csr,
        l: Csr,
        offset: Vec<f64>,
        coords: Vec<f64>,
        rhs: Vec<f64>,
    }

    impl StabilisedPath {
        fn new(n: usize) -> Self {
            let (mut c, _) = sample(n / 3, n, 5);
            c.val.iter_mut().for_each(|v| *v *= 30.0);
            let mut l = c.matmul(&c.transpose());
            l.val.iter_mut().for_each(|v| *v *= 1e-3);
            Self {
                n,
                a: path_graph(n),
                offset: (0..c.nrows).map(|i| (i as f64 * 0.1).cos()).collect(),
                coords: (0..n).map(|i| i as f64).collect(),
                rhs: (0..n).map(|i| (i as f64 * 0.37).sin()).collect(),
                c,
                l,
            }
        }

        fn sys(&self) -> SplitSystem<'_> {
            let (ptr, idx, val) = &self.a;
            let sym =
                faer::sparse::SymbolicSparseColMatRef::new_checked(self.n, self.n, ptr, None, idx);
            let a_v = faer::sparse::SparseColMatRef::new(sym, val);
            split(
                a_v,
                &self.c,
                Some((&self.l, &self.offset[..])),
                &self.coords,
                &self.rhs,
            )
        }
    }

    /// The caller's accuracy ([`LinearSolver::set_accuracy`]): a solve
    /// asked for less stops earlier, at a residual within what it was
    /// asked, and is accepted although that is above the residual limit;
    /// asked for nothing, it goes back to its own target.
    #[test]
    fn a_solve_asked_for_less_stops_earlier() {
        // 400 pressure rows.
        let n: usize = 1200;
        let path = StabilisedPath::new(n);
        let sys = path.sys();
        let mut solver = BlockSolver {
            pressure: PressureSolve::Multigrid,
            ..BlockSolver::default()
        };
        let run = |solver: &mut BlockSolver, accuracy: Option<f64>| {
            solver.set_accuracy(accuracy);
            let mut x = vec![0.0; n];
            let r = solver.solve_split(&sys, 1, &mut x).unwrap();
            assert_eq!(solver.stats.fallbacks, 0);
            r
        };
        let full = run(&mut solver, None);
        solver.last_q.1.clear();
        let relaxed = run(&mut solver, Some(1e-4));
        solver.last_q.1.clear();
        let again = run(&mut solver, None);
        assert!(full.residual <= solver.target, "{full:?}");
        assert!(relaxed.residual <= 1e-4, "{relaxed:?}");
        assert!(relaxed.residual > solver.residual_limit, "{relaxed:?}");
        assert!(
            3 * relaxed.iterations <= 2 * full.iterations,
            "{relaxed:?} against {full:?}"
        );
        assert_eq!(again, full);
    }

    /// The stabilised multigrid set-up serves the later solves of its own
    /// Picard loop and no other: a retried attempt (a new loop on the same
    /// mesh, with another `Δt`) builds anew (session 42's review: it kept
    /// the failed attempt's hierarchy).
    #[test]
    fn the_stabilised_set_up_is_kept_within_its_picard_loop_only() {
        let n: usize = 600;
        let path = StabilisedPath::new(n);
        let sys = path.sys();
        let mut solver = BlockSolver {
            pressure: PressureSolve::Multigrid,
            ..BlockSolver::default()
        };
        let mut x = vec![0.0; n];
        solver.begin_loop();
        solver.solve_split(&sys, 1, &mut x).unwrap();
        solver.solve_split(&sys, 1, &mut x).unwrap();
        assert_eq!(solver.stats.setups, 1, "kept within the loop");
        solver.begin_loop();
        solver.solve_split(&sys, 1, &mut x).unwrap();
        assert_eq!(solver.stats.setups, 2, "built anew in the next loop");
        assert_eq!(solver.stats.fallbacks, 0);
    }

    /// The Cholesky path runs a later solve of the same pattern on the
    /// factor of an earlier one while `C` moved by at most
    /// `keep_factor_below`, factors anew when it moved more, and renews a
    /// kept factor midway when it does not reach the target within
    /// `kept_factor_iterations`; a new Picard loop starts with a new
    /// factor; every answer meets the target and agrees with a solve on a
    /// factor of its own.
    #[test]
    fn a_kept_factor_serves_while_the_volumetric_rows_move_little() {
        // A mass-dominated velocity block (a path graph) and a volumetric
        // term that dominates it, as water's does.
        let n: usize = 1200;
        let (ptr, idx, val) = path_graph(n);
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, &ptr, None, &idx);
        let a_v = faer::sparse::SparseColMatRef::new(sym, &val);
        let (mut c, _) = sample(n / 3, n, 5);
        c.val.iter_mut().for_each(|v| *v *= 300.0);
        let coords: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let rhs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        // `C` moved by about `by` relatively.
        let moved = |by: f64| {
            let mut m = c.clone();
            m.val
                .iter_mut()
                .enumerate()
                .for_each(|(k, v)| *v *= 1.0 + by * (k as f64 * 0.7).sin());
            m
        };
        let solve = |solver: &mut BlockSolver, c: &Csr| {
            let sys = split(a_v, c, None, &coords, &rhs);
            let mut x = vec![0.0; n];
            let r = solver.solve_split(&sys, 1, &mut x).unwrap();
            assert!(r.residual <= solver.target, "{r:?}");
            assert_eq!(solver.stats.fallbacks, 0);
            // A solver of its own, a factor of its own.
            let mut y = vec![0.0; n];
            BlockSolver::default().solve_split(&sys, 1, &mut y).unwrap();
            let (d, s) = x.iter().zip(&y).fold((0.0, 0.0), |(d, s), (a, b)| {
                (d + (a - b) * (a - b), s + b * b)
            });
            assert!((d / s).sqrt() < 1e-6, "{}", (d / s).sqrt());
            r
        };
        let mut solver = BlockSolver::default();
        assert_eq!(
            solver.pressure_for(&split(a_v, &c, None, &coords, &rhs)),
            PressureSolve::Cholesky
        );
        solve(&mut solver, &c);
        assert_eq!((solver.stats.setups, solver.stats.kept_factors), (1, 0));
        // Moved by 10⁻⁶: the factor is kept.
        let kept = solve(&mut solver, &moved(1e-6));
        assert_eq!((solver.stats.setups, solver.stats.kept_factors), (1, 1));
        assert!(kept.iterations >= 1, "{kept:?}");
        // A new Picard loop: a new factor, however little `C` moved.
        solver.begin_loop();
        solve(&mut solver, &moved(1e-6));
        assert_eq!((solver.stats.setups, solver.stats.kept_factors), (2, 1));
        // Moved by 10⁻²: a new factor.
        solve(&mut solver, &moved(1e-2));
        assert_eq!((solver.stats.setups, solver.stats.kept_factors), (3, 1));
        // Kept whatever the move, one iteration allowed on it: a move of
        // 30 % is not solved in one, and the factor is renewed midway.
        solver.keep_factor_below = f64::INFINITY;
        solver.kept_factor_iterations = 1;
        solve(&mut solver, &moved(0.3));
        assert_eq!(solver.stats.kept_factors, 2);
        assert_eq!((solver.stats.kept_renewed, solver.stats.setups), (1, 4));
        // Off: every solve factors.
        solver.keep_factor_below = 0.0;
        solve(&mut solver, &moved(0.3));
        assert_eq!((solver.stats.kept_factors, solver.stats.setups), (2, 5));
    }

    /// The reduced system with stiff rows keeps one pattern on one mesh
    /// whatever the values: an entry of `C` on a stiff column that is
    /// exactly zero in one Picard iterate and not in the next once cost a
    /// new ordering and symbolic analysis (1–3 a step on the a/20 column
    /// on a cylinder). Refilled on the kept pattern, the solve is bit for
    /// bit the one of a solver set up afresh; another stiff set on the
    /// same mesh is built anew.
    #[test]
    fn the_reduced_system_keeps_its_pattern_whatever_its_values() {
        // Dofs 0..200 mass-dominated, 201..299 stiff (off-diagonal weight
        // above `dominance_limit` of the diagonal).
        let n: usize = 300;
        let (mut ptr, mut idx, mut val) = (vec![0], Vec::new(), Vec::new());
        for j in 0..n {
            let stiff = j >= 200;
            for i in j.saturating_sub(1)..(j + 2).min(n) {
                idx.push(i);
                val.push(match (i == j, stiff && i >= 200) {
                    (true, true) => 3.0,
                    (true, false) => 10.0,
                    (false, true) => -1.0,
                    (false, false) => -0.1,
                });
            }
            ptr.push(idx.len());
        }
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, &ptr, None, &idx);
        let a_v = faer::sparse::SparseColMatRef::new(sym, &val);
        let (c, _) = sample(n / 3, n, 3);
        // An entry of `C` on a stiff column.
        let k = (0..c.idx.len())
            .find(|&k| (201..n - 1).contains(&c.idx[k]))
            .expect("a stiff column in C");
        let coords: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let rhs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let fresh = || BlockSolver {
            keep_factor_below: 0.0,
            ..BlockSolver::default()
        };
        // The same dofs less stiff from 250 on: another stiff set on the
        // same pattern.
        let softer: Vec<f64> = (0..n)
            .flat_map(|j| (ptr[j]..ptr[j + 1]).map(move |p| (j, p)))
            .map(|(j, p)| {
                if idx[p] == j && j >= 250 {
                    30.0
                } else {
                    val[p]
                }
            })
            .collect();
        let a_soft = faer::sparse::SparseColMatRef::new(sym, &softer);
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        let mut solver = fresh();
        let rounds = [
            (0.0, a_v),
            (0.7, a_v),
            (0.0, a_v),
            (-1.3, a_v),
            (0.2, a_soft),
        ];
        for (round, (value, a)) in rounds.into_iter().enumerate() {
            let mut c = c.clone();
            c.val[k] = value;
            c.val
                .iter_mut()
                .for_each(|v| *v *= 1.0 + 0.01 * round as f64);
            let sys = split(a, &c, None, &coords, &rhs);
            assert_eq!(solver.pressure_for(&sys), PressureSolve::Cholesky);
            let mut x = vec![0.0; n];
            solver.solve_split(&sys, 1, &mut x).unwrap();
            // One ordering for the first stiff set, one for the second.
            let analyses = if round < 4 { 1 } else { 2 };
            assert_eq!(solver.work().symbolic_analyses, analyses, "round {round}");
            let mut y = vec![0.0; n];
            fresh().solve_split(&sys, 1, &mut y).unwrap();
            assert_eq!(bits(&x), bits(&y), "round {round}");
            // What `moved` compares against: `A_v`'s stiff block as set up.
            let Some(Prec::Woodbury(w)) = solver.setup.as_ref().map(|s| &s.prec) else {
                panic!("the Cholesky path");
            };
            let mut a_ss = Vec::new();
            stiff_entries(a, &w.pos, |_, _, v| a_ss.push(v));
            assert_eq!(bits(&w.a_ss), bits(&a_ss), "round {round}");
            assert!(!a_ss.is_empty());
        }
        assert_eq!((solver.stats.setups, solver.stats.stiff_setups), (5, 5));
        // Rounds 1–3 refilled; round 4 (another stiff set) built anew.
        assert_eq!(solver.stats.stiff_refills, 3);
        assert_eq!(solver.stats.fallbacks, 0);
    }

    /// The fused preconditioner-and-operator gives, bit for bit, the
    /// preconditioner ([`apply_upper`]) followed by the operator
    /// ([`apply_saddle`]), with Jacobi and with multigrid on the velocity.
    #[test]
    fn the_fused_operator_is_the_two_in_turn() {
        let (n, m) = (600, 200);
        // A mass-dominated SPD velocity block (a path graph), C, L̃ = ε C Cᵀ.
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 3.0 + (i % 5) as f64));
            if i + 1 < n {
                t.push((i, i + 1, -1.0));
                t.push((i + 1, i, -1.0));
            }
        }
        let a = Csr::from_triplets(n, n, &t);
        let (c, _) = sample(m, n, 9);
        let ct = c.transpose();
        let mut l = c.matmul(&ct);
        l.val.iter_mut().for_each(|v| *v *= 1e-2);
        let inv: Vec<f64> = a.diagonal().iter().map(|d| 1.0 / d).collect();
        let empty = vec![0; m + 1];
        let s = crate::amg::product_plus(&c, Some(&inv), &ct, Some((&empty, &[], &[], 1.0)));
        let schur = Amg::new(&s, None, &AmgOptions::default()).unwrap();
        let coords: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let (modes, k) = rigid_modes(&coords, 1);
        let amg = Amg::new(&a, Some((&modes, k)), &AmgOptions::default()).unwrap();
        let r: Vec<f64> = (0..n + m).map(|i| (i as f64 * 0.73).sin()).collect();
        for velocity in [
            VelocityPrec::Jacobi(inv.clone()),
            VelocityPrec::Amg(Box::new(amg)),
        ] {
            let mut tmp = vec![0.0; n];
            let (mut z0, mut w0) = (vec![0.0; n + m], vec![0.0; n + m]);
            apply_upper(&velocity, &schur, &ct, n, &r, &mut z0, &mut tmp);
            apply_saddle(&a, &c, &ct, Some(&l), &z0, &mut w0, &mut tmp);
            let (mut z1, mut w1) = (vec![0.0; n + m], vec![0.0; n + m]);
            let blocks = (&a, &c, &ct, Some(&l));
            apply_upper_then_saddle(&velocity, &schur, blocks, &r, &mut z1, &mut w1, &mut tmp);
            assert_eq!(z0, z1);
            assert_eq!(w0, w1);
        }
    }
}
