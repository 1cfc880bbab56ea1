//! The pfem driver: a [`Simulation`] advances a [`pfem_scene::Scene`] step
//! by step (remesh → hooks → Δt → hooks → Newmark–Picard step → hooks),
//! holding its state in one particle set ([`Particles`]) and one element
//! set ([`Elements`]); [`hooks`] change it while it runs; an [`Observer`]
//! reads it after every step.
//!
//! The path of one step, and where a change belongs, are in the
//! repository's `ARCHITECTURE.md`. Most programs use the facade crate
//! `pfem` and its prelude instead of this crate directly.

pub mod checkpoint;
pub mod elements;
pub mod error;
pub mod hooks;
pub mod particles;
pub mod simulation;

pub use checkpoint::{Checkpoint, CheckpointError};
pub use elements::Elements;
pub use error::RunError;
pub use hooks::{Hook, HookContext};
pub use particles::{Particle, Particles};
pub use pfem_scene::SceneError;
pub use simulation::{Observer, Options, Simulation, StageStats, Stages, VolumeLedger, Work};

// The scene modules under the paths the driver's code uses.
pub(crate) use pfem_scene::scene;
