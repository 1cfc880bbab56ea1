//! Validation cases and presets of pfem: scenes with their probes and
//! reference data, as the examples and tests use them.
//!
//! - [`cases`]: 2D dam break (Martin & Moyce), elastic gate (Antoci et
//!   al.), dam break on an obstacle, hydrostatic column, open tank at rest;
//! - [`cases3d`]: 3D water column, column on a cylinder, quasi-2D slab,
//!   3D tank at rest;
//! - [`exact`]: cases with exact references for convergence studies
//!   (start-up Poiseuille flow, circular Couette flow, a standing wave,
//!   the CSM cantilever, the dam break's self-convergence);
//! - [`fidelity`]: the draft/standard/fine presets.

pub mod cases;
pub mod cases3d;
pub mod exact;
pub mod fidelity;

// The paths the cases' code uses.
pub(crate) use pfem_driver::simulation;
pub(crate) use pfem_io::observe;
#[allow(unused_imports)] // in doc links
pub(crate) use pfem_io::output;
pub(crate) use pfem_scene::scene;
pub(crate) mod error {
    pub use pfem_scene::SceneError;
}
