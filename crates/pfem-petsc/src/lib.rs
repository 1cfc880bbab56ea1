//! A PETSc backend behind pfem's linear solver seam
//! ([`pfem_assembly::LinearSolver`]), built only with the `petsc` feature.
//!
//! [`PetscSolver`] takes the monolithic system in split form
//! ([`pfem_assembly::SplitSystem`]: `A_v` and the nodal volumetric rows `C`,
//! with or without the pressure stabilisation) and hands PETSc its
//! velocity–pressure form, the second block row negated so that the pressure
//! Schur complement is positive definite:
//!
//! `[A_v  Cᵀ; −C  I + L̃] [V; q] = [f; −o]`
//!
//! (`L̃ = 0`, `o = 0` without stabilisation; eliminating `q` gives back
//! `(A_v + Cᵀ C) V = f`, the paper's eq. 56 system). The default KSP is
//! FGMRES preconditioned by PCFIELDSPLIT's full Schur factorisation with
//! PETSc's `selfp` approximation of the Schur complement,
//! `I + L̃ + C diag(A_v)⁻¹ Cᵀ` (a pressure Laplacian plus a mass term).
//! The blocks' preconditioners are chosen per solve
//! ([`PetscSolver::blocks`]): Jacobi or GAMG on the velocity, hypre's
//! BoomerAMG on the stabilised pressure, PETSc's sparse Cholesky on the
//! paper's pressure (whose spurious modes defeat multigrid). Passes of
//! refinement with the same set-up follow when the eliminated residual
//! needs them.
//! Every choice is a PETSc option with the prefix `-pfem_`, so that
//! `PetscSolver::with_options("-pfem_fieldsplit_p_pc_type gamg")` puts
//! GAMG on the pressure whatever the system. Each solve's options are its own
//! PETSc options database; two solvers do not see each other's.
//!
//! The answer is checked in Rust, as every pfem solver's is: the residual of
//! the eliminated system, `‖f − (A_v + Cᵀ C) V‖ / ‖f‖`, must reach
//! [`PetscSolver::target`] (or, where round-off stops the refinement
//! first, [`PetscSolver::residual_limit`]); otherwise, or when PETSc reports
//! an error, the solve falls back to the pure-Rust sparse `L D Lᵀ` of the
//! same system ([`pfem_assembly::block::solve_saddle`]) and counts it
//! ([`PetscStats::fallbacks`]).
//!
//! PETSc runs sequentially here (`PETSC_COMM_SELF`); it is initialised once
//! per process, without its signal handlers, and its errors are returned,
//! not printed. Calls are serialised by a lock, since PETSc is not thread
//! safe. This is the seam through which pfem will later run distributed
//! under MPI.
//!
//! Build and test (Debian: `apt-get install libpetsc-real-dev`):
//!
//! ```text
//! cargo test --release -p pfem-petsc --features petsc
//! ```
//!
//! Without the `petsc` feature this crate is empty.
// The docs name the backend's items, which exist with the feature only.
#![cfg_attr(not(feature = "petsc"), allow(rustdoc::broken_intra_doc_links))]

#[cfg(feature = "petsc")]
mod backend;

#[cfg(feature = "petsc")]
pub use backend::{PetscSolver, PetscStats, DEFAULT_OPTIONS};
