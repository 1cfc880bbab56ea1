//! Scenes for pfem: what a simulation is made of, validated before any
//! step runs.
//!
//! - [`scene`]: [`Scene`] (bodies, gravity, run settings) and its builder;
//!   [`Body`], [`Geometry`], [`Clamp`], [`WallMotion`], initial fields;
//! - [`lattice`]: particles filling boxes, balls and cylinders, the
//!   structured mesh of a box, a hash grid for near-coincident particles,
//!   grids by spacing class, the check for a fluid drawn inside another
//!   body;
//! - `hydrostatic` (private): the hydrostatic start, column by column;
//! - [`solid_mesh`]: the own mesh of a non-box solid (Delaunay of its
//!   particles trimmed by the alpha shape);
//! - [`surface`]: bodies bounded by a polygon (2D) or a closed triangle
//!   surface read from STL (3D), filled with particles;
//! - [`motion`]: wall motion laws ([`motion::MotionLaw`],
//!   [`motion::Sinusoidal`], [`motion::PiecewiseLinear`],
//!   [`motion::Rotation`]);
//! - [`build`]: [`Scene::build`] → [`build::Built`], the particles and
//!   meshes a simulation starts from;
//! - [`SceneError`]: what an impossible scene is.
//!
//! The driver (`pfem-driver`) turns a scene into a running simulation.
//! Units are SI: m, s, kg, Pa.

pub mod build;
pub mod error;
mod hydrostatic;
pub mod lattice;
pub mod motion;
pub mod scene;
pub mod solid_mesh;
pub mod surface;

pub use build::{Built, Cloud, Merge, Particle, NO_MATERIAL};
pub use error::SceneError;
pub use scene::{
    default_memory_budget, file_name_fault, is_column_name, AppliedLoad, Body, Clamp,
    ContactSettings, Estimate, FieldFn, Geometry, InitialField, RunSettings, Scene, WallMotion,
};
