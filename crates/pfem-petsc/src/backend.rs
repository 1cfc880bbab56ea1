//! [`PetscSolver`]: the FFI over `shim.c` and the [`LinearSolver`] on it.

use std::ffi::{c_char, c_int, CStr, CString};
use std::sync::Mutex;

use faer::sparse::SparseColMatRef;
use pfem_assembly::solver::{check_finite, relative_residual};
use pfem_assembly::{LinearSolver, SolveError, SolveReport, SolverWork, SplitSystem};

const NAME: &str = "petsc";

/// The options every solve of a split system starts from (prefix
/// `-pfem_`): FGMRES on the velocity–pressure form, preconditioned by a
/// full Schur factorisation with PETSc's `selfp` approximation of the
/// Schur complement, one application of each block's preconditioner. Each
/// solve adds its blocks' preconditioners ([`PetscSolver`]'s docs), then a
/// solver's own options ([`PetscSolver::with_options`],
/// `PFEM_PETSC_OPTIONS`), which override both.
pub const DEFAULT_OPTIONS: &str = "-pfem_ksp_type fgmres -pfem_ksp_rtol 1e-10 \
-pfem_ksp_atol 1e-300 -pfem_ksp_divtol 1e30 -pfem_ksp_max_it 500 -pfem_ksp_gmres_restart 100 \
-pfem_pc_fieldsplit_type schur -pfem_pc_fieldsplit_schur_fact_type full \
-pfem_pc_fieldsplit_schur_precondition selfp \
-pfem_fieldsplit_v_ksp_type preonly -pfem_fieldsplit_p_ksp_type preonly";

/// The options of a solve of one whole matrix ([`LinearSolver::solve`],
/// which the time integrator does not call for this solver: it asks for the
/// split form): PETSc's own sparse Cholesky.
const WHOLE_OPTIONS: &str = "-pfem_ksp_type preonly -pfem_pc_type cholesky";

#[allow(unsafe_code)]
mod ffi {
    use std::ffi::{c_char, c_int, c_void};
    extern "C" {
        pub fn pfem_petsc_init(msg: *mut c_char, len: usize) -> c_int;
        #[allow(clippy::too_many_arguments)]
        pub fn pfem_petsc_create(
            n: i64,
            nv: i64,
            bs: i64,
            ptr: *const i64,
            idx: *const i64,
            val: *const f64,
            options: *const c_char,
            out: *mut *mut c_void,
            msg: *mut c_char,
            len: usize,
        ) -> c_int;
        #[allow(clippy::too_many_arguments)]
        pub fn pfem_petsc_solve(
            h: *mut c_void,
            b: *const f64,
            y: *mut f64,
            nonzero_guess: c_int,
            its: *mut i64,
            reason: *mut c_int,
            msg: *mut c_char,
            len: usize,
        ) -> c_int;
        pub fn pfem_petsc_destroy(h: *mut c_void);
        pub fn pfem_petsc_has_hypre() -> c_int;
    }
}

/// PETSc is initialised once per process and is not thread safe: every
/// call holds this lock. It holds the initialisation's outcome.
static PETSC: Mutex<Option<Result<(), String>>> = Mutex::new(None);

/// What PETSc returned for one solve.
struct Outcome {
    iterations: usize,
    reason: i32,
}

/// A KSP set up on one matrix; the PETSc lock is held while it lives.
struct Ksp<'g> {
    handle: *mut std::ffi::c_void,
    n: usize,
    _guard: std::sync::MutexGuard<'g, Option<Result<(), String>>>,
}

impl Ksp<'static> {
    /// Sets up a KSP on the square CSR matrix `(ptr, idx, val)`; the first
    /// `nv` unknowns are the field `v` (no split when `nv` is every unknown).
    #[allow(unsafe_code)]
    fn new(
        ptr: &[i64],
        idx: &[i64],
        val: &[f64],
        nv: usize,
        bs: usize,
        options: &str,
    ) -> Result<Self, String> {
        let n = ptr.len().saturating_sub(1);
        if ptr.is_empty()
            || idx.len() != val.len()
            || ptr[n] as usize != idx.len()
            || nv > n
            || idx.iter().any(|&j| j < 0 || j as usize >= n)
        {
            return Err("inconsistent matrix sizes".into());
        }
        let options = CString::new(options).map_err(|_| "options hold a NUL byte".to_string())?;
        let mut guard = PETSC.lock().unwrap_or_else(|e| e.into_inner());
        let mut msg = vec![0 as c_char; 512];
        let init = guard.get_or_insert_with(|| {
            // SAFETY: `msg` is a writable buffer of the length passed.
            let code = unsafe { ffi::pfem_petsc_init(msg.as_mut_ptr(), msg.len()) };
            if code == 0 {
                Ok(())
            } else {
                Err(text(&msg))
            }
        });
        if let Err(e) = init {
            return Err(format!("PETSc did not initialise: {e}"));
        }
        let mut handle = std::ptr::null_mut();
        // SAFETY: n + 1 row pointers, ptr[n] column indices (checked in
        // range) and values; the shim copies the matrix and writes only
        // `handle` and `msg` (within its length).
        let code = unsafe {
            ffi::pfem_petsc_create(
                n as i64,
                nv as i64,
                bs as i64,
                ptr.as_ptr(),
                idx.as_ptr(),
                val.as_ptr(),
                options.as_ptr(),
                &mut handle,
                msg.as_mut_ptr(),
                msg.len(),
            )
        };
        if code != 0 || handle.is_null() {
            return Err(text(&msg));
        }
        Ok(Self {
            handle,
            n,
            _guard: guard,
        })
    }

    /// Solves `K y = b`, `y` holding the initial guess when `nonzero_guess`.
    #[allow(unsafe_code)]
    fn solve(&mut self, b: &[f64], y: &mut [f64], nonzero_guess: bool) -> Result<Outcome, String> {
        if b.len() != self.n || y.len() != self.n {
            return Err("inconsistent vector sizes".into());
        }
        let mut msg = vec![0 as c_char; 512];
        let (mut its, mut reason) = (0i64, 0 as c_int);
        // SAFETY: `handle` is a live KSP of `n` unknowns; b and y hold n
        // entries; the shim writes only y, its, reason and msg.
        let code = unsafe {
            ffi::pfem_petsc_solve(
                self.handle,
                b.as_ptr(),
                y.as_mut_ptr(),
                c_int::from(nonzero_guess),
                &mut its,
                &mut reason,
                msg.as_mut_ptr(),
                msg.len(),
            )
        };
        if code != 0 {
            return Err(text(&msg));
        }
        Ok(Outcome {
            iterations: its.max(0) as usize,
            reason,
        })
    }
}

impl Drop for Ksp<'_> {
    #[allow(unsafe_code)]
    fn drop(&mut self) {
        // SAFETY: `handle` came from pfem_petsc_create and is freed once;
        // the lock is still held (the guard drops after this).
        unsafe { ffi::pfem_petsc_destroy(self.handle) }
    }
}

/// Whether the PETSc linked has hypre.
#[allow(unsafe_code)]
fn has_hypre() -> bool {
    // SAFETY: reads a compile-time constant of the shim.
    unsafe { ffi::pfem_petsc_has_hypre() != 0 }
}

fn text(msg: &[c_char]) -> String {
    let bytes: Vec<u8> = msg
        .iter()
        .take_while(|&&c| c != 0)
        .map(|&c| c as u8)
        .collect();
    CStr::from_bytes_with_nul(&[bytes.as_slice(), &[0]].concat())
        .map(|c| c.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Counters of a [`PetscSolver`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PetscStats {
    /// Solves of a split system handed to PETSc.
    pub solves: u64,
    /// KSP iterations summed over them.
    pub iterations: u64,
    /// Solves that fell back to the pure-Rust `L D Lᵀ` (PETSc error, KSP
    /// divergence, or a residual above [`PetscSolver::residual_limit`]).
    pub fallbacks: u64,
    /// Refinement passes (a KSP solve each, with the set-up kept).
    pub refinements: u64,
}

/// The monolithic system solved by PETSc's KSP (module docs of the crate).
#[derive(Debug)]
pub struct PetscSolver {
    /// PETSc options (prefix `-pfem_`) applied after [`DEFAULT_OPTIONS`].
    pub options: String,
    /// The relative residual of the eliminated system a solve must reach,
    /// `‖f − (A_v + Cᵀ C) V‖ / ‖f‖` (the block solver's target, 10⁻⁹); for a
    /// stabilised system, of the saddle-point system.
    pub target: f64,
    /// The largest residual accepted when refinement stops improving before
    /// [`PetscSolver::target`] (round-off's floor; the block solver's
    /// `residual_limit`, 10⁻⁷).
    pub residual_limit: f64,
    /// Fall back to the pure-Rust `L D Lᵀ` when PETSc fails or misses the
    /// target (default); when false, the failure is returned as an error.
    pub fallback: bool,
    /// The velocity block gets GAMG instead of Jacobi when its
    /// off-diagonal weight `Σᵢ Σ_{j≠i} |a_ij|` exceeds this share of its
    /// diagonal's (default 0.5, the block solver's).
    pub dominance_limit: f64,
    /// Ask for the split system (default). When false, the time
    /// integrator assembles the whole matrix and [`LinearSolver::solve`]
    /// factors it with PETSc (`-pfem_pc_factor_mat_solver_type cholmod`
    /// makes that CHOLMOD: the side-by-side of issue 18).
    pub split: bool,
    /// Refinement passes allowed after the first KSP solve (default 3).
    /// With water, `‖C‖` of 10³–10⁴ amplifies the whole system's residual
    /// that much in the eliminated one; a pass removes the amplification.
    pub refinements: usize,
    stats: PetscStats,
    work: SolverWork,
    /// The last solve's `q` and the pattern generation it belongs to: the
    /// next Picard iterate's initial guess (a `q` of another mesh would be
    /// a guess far worse than none).
    last_q: (u64, Vec<f64>),
}

impl Default for PetscSolver {
    /// The default options, followed by those of the environment variable
    /// `PFEM_PETSC_OPTIONS` when it is set.
    fn default() -> Self {
        Self::with_options(std::env::var("PFEM_PETSC_OPTIONS").unwrap_or_default())
    }
}

impl PetscSolver {
    /// [`DEFAULT_OPTIONS`] followed by `options` (PETSc's syntax, prefix
    /// `-pfem_`), e.g. `"-pfem_fieldsplit_p_pc_type hypre"`.
    pub fn with_options(options: impl Into<String>) -> Self {
        Self {
            options: options.into(),
            target: 1e-9,
            residual_limit: 1e-7,
            fallback: true,
            refinements: 3,
            split: true,
            dominance_limit: 0.5,
            stats: PetscStats::default(),
            work: SolverWork::default(),
            last_q: (0, Vec::new()),
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> PetscStats {
        self.stats
    }

    /// The blocks' preconditioners for `sys` (measured in
    /// `docs/benchmarks.md`, "Issue 18: a PETSc backend"):
    /// - velocity: Jacobi when `A_v` is mass-dominated (off-diagonal weight
    ///   at most [`PetscSolver::dominance_limit`] of the diagonal's, as
    ///   water's is), else GAMG with the dimension as block size (solids);
    /// - pressure: with the stabilisation, hypre's BoomerAMG (GAMG when
    ///   PETSc has no hypre); without it, PETSc's sparse Cholesky of the
    ///   Schur approximation, since the paper's equal-order pressure has
    ///   spurious modes that no aggregation captures (about 200–300 KSP
    ///   iterations per solve with either multigrid).
    pub fn blocks(&self, sys: &SplitSystem<'_>) -> String {
        let a = sys.a_v;
        let (mut diag, mut off) = (0.0, 0.0);
        for j in 0..a.ncols() {
            for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                if i == j {
                    diag += v.abs();
                } else {
                    off += v.abs();
                }
            }
        }
        let v = if off > self.dominance_limit * diag {
            "gamg"
        } else {
            "jacobi"
        };
        let p = match (sys.stabilisation.is_some(), has_hypre()) {
            (true, true) => "hypre",
            (true, false) => "gamg",
            (false, _) => "cholesky",
        };
        format!("-pfem_fieldsplit_v_pc_type {v} -pfem_fieldsplit_p_pc_type {p}")
    }

    fn options_of(&self, base: &str) -> String {
        format!("{base} {}", self.options)
    }

    fn fall_back(
        &mut self,
        sys: &SplitSystem<'_>,
        x: &mut [f64],
        why: SolveError,
    ) -> Result<SolveReport, SolveError> {
        if !self.fallback {
            return Err(why);
        }
        self.stats.fallbacks += 1;
        self.work.factorizations += 1;
        pfem_assembly::block::solve_saddle(sys, x)
    }
}

/// `q = C x`.
fn c_times(sys: &SplitSystem<'_>, x: &[f64]) -> Vec<f64> {
    (0..sys.c_rows())
        .map(|r| {
            (sys.c_ptr[r]..sys.c_ptr[r + 1])
                .map(|p| sys.c_val[p] * x[sys.c_idx[p]])
                .sum()
        })
        .collect()
}

impl LinearSolver for PetscSolver {
    fn name(&self) -> &str {
        NAME
    }

    fn wants_split(&self, _dofs: usize) -> bool {
        self.split
    }

    fn work(&self) -> SolverWork {
        SolverWork {
            fallbacks: self.stats.fallbacks,
            ..self.work
        }
    }

    /// PETSc's sparse Cholesky on the whole matrix (the time integrator's
    /// path only when [`PetscSolver::split`] is false); accepted up to
    /// [`PetscSolver::residual_limit`], since a direct solve of this
    /// system stops where round-off does.
    fn solve(
        &mut self,
        a: SparseColMatRef<'_, usize, f64>,
        _generation: u64,
        b: &[f64],
        x: &mut [f64],
    ) -> Result<SolveReport, SolveError> {
        SolveError::check_dimensions(NAME, a.nrows(), a.ncols(), b.len(), x.len())?;
        check_finite(b)?;
        let fail = |detail: String| SolveError::Factorization {
            solver: NAME,
            detail,
        };
        // Symmetric: the CSC arrays are the CSR ones.
        let ptr: Vec<i64> = a.col_ptr().iter().map(|&p| p as i64).collect();
        let idx: Vec<i64> = a.row_idx().iter().map(|&i| i as i64).collect();
        let n = b.len();
        let mut ksp =
            Ksp::new(&ptr, &idx, a.val(), n, 1, &self.options_of(WHOLE_OPTIONS)).map_err(fail)?;
        let out = ksp.solve(b, x, false).map_err(fail)?;
        drop(ksp);
        self.work.factorizations += 1;
        self.work.symbolic_analyses += 1;
        let residual = relative_residual(a, b, x);
        if out.reason < 0 || residual.is_nan() || residual > self.residual_limit {
            return Err(SolveError::Inaccurate {
                solver: NAME,
                residual,
                limit: self.residual_limit,
            });
        }
        Ok(SolveReport {
            residual,
            iterations: out.iterations.max(1),
        })
    }

    /// KSP on the velocity–pressure form (crate docs), then up to
    /// [`PetscSolver::refinements`] passes of refinement with the same
    /// set-up until the residual reaches [`PetscSolver::target`]; the
    /// pure-Rust `L D Lᵀ` when PETSc fails ([`PetscSolver::fallback`]).
    fn solve_split(
        &mut self,
        sys: &SplitSystem<'_>,
        generation: u64,
        x: &mut [f64],
    ) -> Result<SolveReport, SolveError> {
        // The sizes and `C`'s structure first, as every solver checks them
        // (a short `x` panicked in `c_times`).
        sys.check(NAME, x)?;
        check_finite(sys.rhs)?;
        let n = sys.a_v.nrows();
        let m = sys.c_rows();
        // K = [A_v Cᵀ; C −(I + L̃)] (symmetric, both triangles) and [f; o].
        let (k, b) = pfem_assembly::block::saddle_system(sys)?;
        let k = k.as_ref();
        // K' = K with its second block row negated (CSR row i is CSC
        // column i), b' likewise: its Schur complement is positive.
        let ptr: Vec<i64> = k.col_ptr().iter().map(|&p| p as i64).collect();
        let idx: Vec<i64> = k.row_idx().iter().map(|&i| i as i64).collect();
        let mut val = k.val().to_vec();
        val[k.col_ptr()[n]..].iter_mut().for_each(|v| *v = -*v);
        let mut b_neg = b.clone();
        b_neg[n..].iter_mut().for_each(|v| *v = -*v);
        // Warm start: this iterate's V, and the last q of the same size
        // (the stabilised system's q is not C V) or else C V.
        let mut y = x.to_vec();
        if sys.stabilisation.is_some() && self.last_q.0 == generation && self.last_q.1.len() == m {
            y.extend_from_slice(&self.last_q.1);
        } else {
            y.extend(c_times(sys, x));
        }
        self.stats.solves += 1;
        let options = self.options_of(&format!("{DEFAULT_OPTIONS} {}", self.blocks(sys)));
        let run = |y: &mut Vec<f64>, stats: &mut PetscStats| -> Result<(f64, Outcome), String> {
            let mut ksp = Ksp::new(&ptr, &idx, &val, n, sys.block_size, &options)?;
            let mut out = ksp.solve(&b_neg, y, true)?;
            // r: the residual of the current y, kept as the next
            // correction's right-hand side.
            let mut r = vec![0.0; n + m];
            let mut d = vec![0.0; n + m];
            let mut residual = residual_into(sys, k, &b, y, &mut r);
            for _ in 0..self.refinements {
                if residual <= self.target || out.reason < 0 {
                    break;
                }
                // The correction's right-hand side: the eliminated residual
                // with a zero second row (eliminating gives (A_v + CᵀC) δV
                // = r), or the saddle-point residual of K' when stabilised.
                r[n..].iter_mut().for_each(|v| *v = -*v);
                let more = ksp.solve(&r, &mut d, false)?;
                out.iterations += more.iterations;
                out.reason = more.reason;
                let before = y.clone();
                y.iter_mut().zip(&d).for_each(|(y, d)| *y += d);
                stats.refinements += 1;
                let new = residual_into(sys, k, &b, y, &mut r);
                if new.is_nan() || new >= residual {
                    // At the floor that round-off allows: keep the better.
                    y.copy_from_slice(&before);
                    break;
                }
                residual = new;
            }
            Ok((residual, out))
        };
        let (residual, out) = match run(&mut y, &mut self.stats) {
            Ok(r) => r,
            Err(detail) => {
                return self.fall_back(
                    sys,
                    x,
                    SolveError::Factorization {
                        solver: NAME,
                        detail,
                    },
                )
            }
        };
        self.stats.iterations += out.iterations as u64;
        self.work.iterations += out.iterations as u64;
        self.work.factorizations += 1;
        if out.reason < 0 || residual.is_nan() || residual > self.residual_limit {
            return self.fall_back(
                sys,
                x,
                SolveError::NoConvergence {
                    solver: NAME,
                    iterations: out.iterations,
                    residual,
                },
            );
        }
        x.copy_from_slice(&y[..n]);
        self.last_q.0 = generation;
        self.last_q.1.clear();
        self.last_q.1.extend_from_slice(&y[n..]);
        Ok(SolveReport {
            residual,
            iterations: out.iterations,
        })
    }
}

/// The residual that matters for `y = [V; q]`, written to `r`, and its
/// relative norm: of the eliminated system, `r = [f − (A_v + Cᵀ C) V; 0]`
/// over `‖f‖`, for the paper's pressure (`q` is discarded); of the
/// saddle-point system, `r = b − K y` over `‖b‖`, for the stabilised one
/// (which has no sparse eliminated form).
fn residual_into(
    sys: &SplitSystem<'_>,
    k: SparseColMatRef<'_, usize, f64>,
    b: &[f64],
    y: &[f64],
    r: &mut [f64],
) -> f64 {
    let n = sys.a_v.nrows();
    let den = if sys.stabilisation.is_none() {
        let mut scratch = Vec::new();
        sys.apply(&y[..n], &mut r[..n], &mut scratch);
        r[..n]
            .iter_mut()
            .zip(sys.rhs)
            .for_each(|(r, f)| *r = f - *r);
        r[n..].iter_mut().for_each(|v| *v = 0.0);
        sys.rhs.iter().map(|f| f * f).sum::<f64>().sqrt()
    } else {
        pfem_assembly::solver::residual(k, b, y, r);
        b.iter().map(|f| f * f).sum::<f64>().sqrt()
    };
    let num = r.iter().map(|v| v * v).sum::<f64>().sqrt();
    if den > 0.0 {
        num / den
    } else {
        num
    }
}
