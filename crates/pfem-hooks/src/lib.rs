//! Hooks for scenes that change while they run, written against the
//! driver's public [`Hook`](pfem_driver::Hook) seam (as a user's own hooks
//! are):
//!
//! - [`BodyForceRamp`]: a load ramp on the body force;
//! - [`SlipPlanes`]: symmetry planes normal to an axis;
//! - [`Inflow`]: fluid entering through a face at a prescribed velocity;
//! - [`ParticleManagement`]: removal of crowding fluid particles and
//!   insertion into oversized elements, every few steps.
//!
//! The driver's own hooks (the volume correction, `p = 0` on the free
//! surface, `PrescribedMotion` for walls with a motion law, `AppliedForce`,
//! `StopWhen`, `WallClockLimit`, `FnHook`) are in `pfem_driver::hooks`; the
//! motion laws themselves (`Sinusoidal`, `PiecewiseLinear`, `Rotation`) in
//! `pfem_scene::motion`.

mod motion;
mod particles;

pub use motion::{BodyForceRamp, SlipPlanes};
pub use particles::{Inflow, MAX_LAYER, UPSTREAM_CLEARANCE};
/// (Defined in the driver, which installs it for a scene that asks.)
pub use pfem_driver::hooks::ParticleManagement;
