//! # pfem: the Particle Finite Element Method for fluid–structure interaction
//!
//! pfem implements the monolithic Lagrangian method of Marti & Idelsohn
//! (2007): fluid and solid are one continuum with one momentum and one
//! continuity equation; a quasi-incompressible Newtonian fluid and a
//! hypoelastic solid share one discrete constitutive form (eqs. 43–44), so
//! one system (eqs. 55–56), advanced by a Newmark-family scheme (Bossak by
//! default) with Picard iterations (§6), moves every particle; the particles are re-meshed by Delaunay
//! tessellation every step and the free surface is found with an alpha
//! shape (§8). 2D (plane strain) and 3D share one code path.
//!
//! Units are SI throughout: m, s, kg, Pa.
//!
//! ```
//! use pfem::prelude::*;
//!
//! // A 0.2 m × 0.2 m block of water at rest on a floor.
//! let h = 0.025;
//! let scene = Scene::<2>::new("puddle")
//!     .gravity(Vector::<2>::new(0.0, -9.81))
//!     .settings(RunSettings { end_time: 0.02, max_dt: 5e-3, output_interval: None, ..Default::default() })
//!     .wall("floor", Geometry::Box { min: Point::<2>::new(-0.1, -h), max: Point::<2>::new(0.3, 0.0) }, h, WallMotion::Fixed)
//!     .fluid("water", Box::new(Newtonian::water()), Geometry::Box { min: Point::<2>::new(0.0, 0.0), max: Point::<2>::new(0.2, 0.2) }, h);
//! let mut sim = Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default())?;
//! sim.run(&mut [])?;
//! assert!(sim.time() >= 0.02 - 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
pub mod cli;
pub mod scene_file;

/// README.md's Rust snippets, compiled and run as doctests (so that the
/// README cannot drift from the API).
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;

pub use pfem_cases::{cases, cases3d, exact, fidelity};
pub use pfem_driver::{checkpoint, elements, error, particles, simulation};

/// Hooks: the seam ([`Hook`], [`HookContext`]) and the driver's own
/// (`pfem_driver::hooks`: the volume correction, wall motion laws through
/// `PrescribedMotion`, applied forces, stops), and those of `pfem-hooks`
/// (load ramps, slip planes, inflows, particle management).
pub mod hooks {
    pub use pfem_driver::hooks::*;
    pub use pfem_hooks::*;
}
pub use pfem_io::{observe, output};
pub use pfem_scene::{lattice, scene, solid_mesh};

pub use elements::Elements;
pub use error::RunError;
pub use hooks::{Hook, HookContext};
pub use observe::{Probe, StandardOutput};
pub use particles::{Particle, Particles};
pub use pfem_assembly as assembly;
pub use pfem_cases as validation;
pub use pfem_constitutive as constitutive;
pub use pfem_core as core;
pub use pfem_driver as driver;
pub use pfem_geometry as geometry;
pub use pfem_io as io;
pub use pfem_io::Loads;
/// `println!` / `eprintln!` that a closed pipe cannot turn into a panic
/// (`pfem_io::console`).
pub use pfem_io::{errln, outln};
/// The PETSc backend (`petsc` feature): [`petsc::PetscSolver`].
#[cfg(feature = "petsc")]
pub use pfem_petsc as petsc;
pub use pfem_scene::SceneError;
pub use pfem_time as time;
pub use scene::{Body, Clamp, Geometry, RunSettings, Scene, WallMotion};
pub use simulation::{Observer, Options, Simulation, StageStats, Stages, VolumeLedger, Work};

/// The names most programs need, and those a user's material, solver or
/// hook is written with.
pub mod prelude {
    pub use crate::hooks::{Hook, HookContext};
    pub use crate::observe::{Probe, StandardOutput};
    pub use crate::particles::Particles;
    pub use crate::scene::{Geometry, RunSettings, Scene, WallMotion};
    pub use crate::simulation::{Observer, Options, Simulation};
    pub use crate::{RunError, SceneError};
    pub use pfem_assembly::{LinearSolver, SolveError, SolveReport};
    pub use pfem_constitutive::{History, Kinematics, Unified};
    pub use pfem_constitutive::{Hypoelastic, Material, MaterialKind, Newtonian};
    pub use pfem_core::{Const, Dim, Tensor};
    pub use pfem_core::{ParticleKind, Point, Vector};
    pub use pfem_driver::particles::Particle;
    pub use pfem_geometry::{Delaunay2, Delaunay3, Tessellator};
    pub use pfem_io::Loads;
    pub use pfem_time::{Scheme, StepParams};
}
