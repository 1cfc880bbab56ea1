//! Element kernels, parallel sparse assembly of the monolithic PFEM system
//! (Marti & Idelsohn 2007, eqs. 55–59) and linear solvers.
//!
//! One time step's mesh (fluid elements from the tessellation, solid
//! elements from each solid's own mesh) is handed to
//! [`Assembler::prepare`], which builds the sparsity pattern once; each
//! Picard iteration then calls [`Assembler::assemble`] and a
//! [`LinearSolver`].
pub mod amg;
pub mod assembler;
pub mod block;
pub mod error;
pub mod export;
pub mod kernels;
pub mod pattern;
pub mod solver;

pub use assembler::{
    Assembler, AssemblerWork, AssemblyInfo, AssemblyInput, Constraints, Inertia, NodalRate,
    StepMesh, SurfaceCuts,
};
pub use block::{
    BlockSolver, BlockStats, Krylov, PressureSolve, VelocityBlock, CARRY_STEPS, KEEP_FACTOR_BELOW,
    KEPT_FACTOR_ITERATIONS, MULTIGRID_FROM, SPLIT_FROM,
};
pub use error::{AssemblyError, SolveError};
pub use export::MatrixExport;
/// The sparse-matrix crate of [`LinearSolver::solve`]'s signature, so that a
/// user's solver names the same version.
pub use faer;
pub use faer::Par;
pub use kernels::VolumetricTreatment;
pub use solver::{
    ConjugateGradient, DirectSolver, LinearSolver, SolveReport, SolverWork, SparseCholesky,
    SparseLu, SplitSystem, DEFAULT_PARALLELISM,
};
