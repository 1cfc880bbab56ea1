//! Typed errors of assembly and linear solves.

/// What went wrong while assembling the system.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AssemblyError {
    /// An element is degenerate or inverted (`J ≤ 0`) at the iterate: the
    /// step must be rejected and retried with a smaller `Δt`.
    #[error("element {element} (particles {nodes:?}) is degenerate or inverted (J <= 0)")]
    InvertedElement {
        /// Element index in the step's mesh.
        element: usize,
        /// Its particles.
        nodes: Vec<u32>,
    },
    /// A material returned a non-finite coefficient (retried with a
    /// smaller step: a return map may fail only at large increments).
    #[error("material {material} (`{name}`) returned a non-finite constitutive triple on element {element}")]
    NonFiniteMaterial {
        /// Element index.
        element: usize,
        /// Material index.
        material: u16,
        /// The material's name ([`pfem_constitutive::Material::name`];
        /// only its index until session 54).
        name: String,
    },
    /// A material returned a constitutive triple that no step size cures
    /// (a negative `μ` or `𝒦`, a fluid's deviatoric `σ̂`): returned at once.
    #[error("material {material} (`{name}`) on element {element}: {why}")]
    InvalidMaterial {
        /// Element index.
        element: usize,
        /// Material index.
        material: u16,
        /// The material's name ([`pfem_constitutive::Material::name`]).
        name: String,
        /// What is wrong.
        why: &'static str,
    },
    /// A material panicked in one of its calls (`call`: `unified`, its
    /// constitutive triple, in the assembly; `refuses`, `update_history`
    /// or `update_pressure` in the step's update): returned at once (a
    /// panic is a fault of the material, not of the step's size). In the
    /// assembly the first element's panic is caught and the other
    /// elements are left uncomputed: the panic's message is printed once a
    /// thread, not once an element (session 55: about 150 times, then the
    /// process ended; session 56: the update's calls too).
    #[error(
        "material {material} (`{name}`) panicked in `{call}` on {} {element}: {message}",
        panic_place(call)
    )]
    MaterialPanicked {
        /// Element index (for `update_pressure`, the particle's).
        element: usize,
        /// The material's call that panicked.
        call: &'static str,
        /// Material index.
        material: u16,
        /// The material's name.
        name: String,
        /// The panic's message (its payload if it is text).
        message: String,
    },
    /// The right-hand side is not finite.
    #[error("the assembled right-hand side is not finite at unknown {dof}")]
    NonFiniteSystem {
        /// The unknown.
        dof: usize,
    },
    /// The assembled matrix holds a NaN or an infinity (an overflowing
    /// step, `Δt 𝒦` beyond `f64`): no solver is handed it.
    #[error("the assembled matrix is not finite (stored entry {entry})")]
    NonFiniteMatrix {
        /// Index of the first such stored entry (of the matrix, then of
        /// the split form's `C`).
        entry: usize,
    },
    /// The mesh and the data handed to assembly do not fit together.
    #[error("inconsistent assembly input: {what}")]
    MeshMismatch {
        /// What does not fit.
        what: &'static str,
    },
}

/// What went wrong in a linear solve.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SolveError {
    /// The right-hand side holds a NaN or an infinity.
    #[error("right-hand side is not finite at index {index}")]
    NonFinite {
        /// The offending entry.
        index: usize,
    },
    /// The solver reported success with a solution that holds a NaN or an
    /// infinity (a solver of one's own whose preconditioner broke down):
    /// refused at once, not retried with a smaller step.
    #[error("{solver} returned a solution that is not finite at index {index}")]
    NonFiniteSolution {
        /// Solver name.
        solver: String,
        /// The first offending entry.
        index: usize,
    },
    /// The solver reported success with a relative residual of 1 or more,
    /// or one that is not a number (a solver of one's own): its solution
    /// has made no progress on the system (`x = 0` has residual 1), and
    /// the Picard loop would have read it as converged. Refused at once,
    /// not retried (session 54's review: a solver returning zeros with
    /// residual 5 froze a collapsing column, and the run ended `Ok`).
    #[error("{solver} reported success with a relative residual of {residual:e}, no better than a zero solution: a solver that does not converge returns an error")]
    NoProgress {
        /// Solver name.
        solver: String,
        /// The residual it reported.
        residual: f64,
    },
    /// The factorisation failed (singular or not positive definite).
    #[error("{solver} factorisation failed: {detail}")]
    Factorization {
        /// Solver name.
        solver: &'static str,
        /// What the factorisation reported.
        detail: String,
    },
    /// The solution's residual is too large to be trusted.
    #[error("{solver} returned a solution with relative residual {residual:e} above {limit:e}")]
    Inaccurate {
        /// Solver name.
        solver: &'static str,
        /// Relative residual ‖Ax − b‖/‖b‖.
        residual: f64,
        /// Accepted limit.
        limit: f64,
    },
    /// An iterative solver ran out of iterations.
    #[error(
        "{solver} did not converge in {iterations} iterations (relative residual {residual:e})"
    )]
    NoConvergence {
        /// Solver name.
        solver: &'static str,
        /// Iterations done.
        iterations: usize,
        /// Relative residual reached.
        residual: f64,
    },
    /// A conjugate-gradient solver met a direction of non-positive curvature.
    #[error("{solver}: system is not positive definite (iteration {iteration})")]
    NotPositiveDefinite {
        /// Solver name.
        solver: &'static str,
        /// Iteration where it was found.
        iteration: usize,
    },
    /// The parts of a split system do not fit together (`C`'s row
    /// pointers, indices and values, its column indices against `A_v`, the
    /// stabilisation's sizes).
    #[error("{solver}: the split system is inconsistent: {why}")]
    InvalidSystem {
        /// Solver name.
        solver: &'static str,
        /// What does not fit.
        why: &'static str,
    },
    /// The matrix is not square, or the right-hand side or the solution
    /// vector does not have one entry per row.
    #[error("{solver}: a {rows} × {cols} matrix with a right-hand side of {rhs} and a solution of {x} entries")]
    DimensionMismatch {
        /// Solver name.
        solver: &'static str,
        /// Matrix rows.
        rows: usize,
        /// Matrix columns.
        cols: usize,
        /// Right-hand side length.
        rhs: usize,
        /// Solution length.
        x: usize,
    },
}

impl SolveError {
    /// [`SolveError::InvalidSystem`] for `solver`.
    pub fn invalid(solver: &'static str, why: &'static str) -> Self {
        SolveError::InvalidSystem { solver, why }
    }

    /// `Ok` when `a` is square and `b` and `x` have one entry per row;
    /// [`SolveError::DimensionMismatch`] otherwise. Every solver of this
    /// crate checks it first; a [`crate::LinearSolver`] of one's own
    /// should too.
    pub fn check_dimensions(
        solver: &'static str,
        rows: usize,
        cols: usize,
        rhs: usize,
        x: usize,
    ) -> Result<(), SolveError> {
        if rows == cols && rhs == rows && x == rows {
            Ok(())
        } else {
            Err(SolveError::DimensionMismatch {
                solver,
                rows,
                cols,
                rhs,
                x,
            })
        }
    }
}

/// "particle" for a nodal call (`update_pressure`), "element" otherwise.
fn panic_place(call: &str) -> &'static str {
    if call == "update_pressure" {
        "particle"
    } else {
        "element"
    }
}

/// The text of a caught panic's payload (`&str` or `String`), or a note
/// that it had none.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|m| m.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(a panic without a message)".into())
}
