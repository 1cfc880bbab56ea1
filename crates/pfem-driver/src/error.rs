//! Typed errors of a run.

use pfem_geometry::GeometryError;
use pfem_time::StepError;

/// A failure while running.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// Remeshing failed.
    #[error("remeshing failed: {0}")]
    Geometry(#[from] GeometryError),
    /// The time step failed even after halving.
    #[error(transparent)]
    Step(#[from] StepError),
    /// An observer's output failed (the output layer's error, boxed so the
    /// driver does not depend on it: `pfem_io::output::OutputError` for the
    /// standard outputs).
    #[error(transparent)]
    Output(Box<dyn std::error::Error + Send + Sync>),
    /// A run option set on the `Simulation` is out of range.
    #[error("invalid setting `{name}` = {value}: {reason}")]
    InvalidSetting {
        /// The field.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The allowed range.
        reason: &'static str,
    },
    /// No body has this name.
    #[error("no body is named `{name}`")]
    UnknownBody {
        /// The name asked for.
        name: String,
    },
    /// A hook failed or was given bad input.
    #[error("hook `{hook}`: {why}")]
    Hook {
        /// The hook.
        hook: String,
        /// What is wrong.
        why: String,
    },
    /// A checkpoint could not be read or does not fit this simulation.
    #[error(transparent)]
    Checkpoint(#[from] crate::checkpoint::CheckpointError),
    /// The Courant bound asks for a step below the smallest step allowed:
    /// a particle this fast would cross many elements within the smallest
    /// step, so the run would crawl at that step (or blow up) instead of
    /// ending (a Courant number of 10⁻³⁰⁰, a flow that has blown up).
    #[error("at t = {time} s the Courant step {courant:e} × {crossing:e} s (the smallest spacing over speed, particle {particle} at {speed:e} m/s) is below the smallest step {min_dt:e} s: a flow this fast cannot be followed (has it blown up? is the Courant number too small?)")]
    CourantStepTooSmall {
        /// Time (s).
        time: f64,
        /// The Courant number.
        courant: f64,
        /// `min_i h_i / |v_i|` (s).
        crossing: f64,
        /// The particle that sets it.
        particle: usize,
        /// Its speed (m/s).
        speed: f64,
        /// The smallest step (s), `StepParams::min_dt`.
        min_dt: f64,
    },
    /// A contact layer closed through its gap at every step down to the
    /// smallest (`pfem_constitutive::contact::CLOSED_GAP`): the contact's
    /// penalty is far too soft for the load, and the solid would pass
    /// through the other body. Raise the contact stiffness
    /// (`Scene::contact_stiffness`, the scene file's `contact.stiffness`).
    #[error("at t = {time} s the contact between `{master}` and `{other}` closed through its gap at every step down to the smallest ({min_dt:e} s): {why}")]
    ContactClosed {
        /// Time (s).
        time: f64,
        /// The body whose facet gives the layer's normal.
        master: String,
        /// The other body.
        other: String,
        /// The smallest step (s).
        min_dt: f64,
        /// The contact material's reason (the closure and the penalty).
        why: String,
    },
    /// A particle added or changed by hand (`Simulation::particles_mut`)
    /// does not fit the simulation: a material that does not exist or is
    /// not a fluid's, a body past the scene's, a non-positive spacing or a
    /// non-finite value. Found when the next step meshes the changed set.
    #[error("particle {particle} does not fit the simulation: {why}")]
    InvalidParticle {
        /// The particle.
        particle: usize,
        /// What does not fit.
        why: String,
    },
    /// A measurement of the elements asked between a change of the
    /// particle set by hand and its meshing
    /// (`Simulation::is_meshed`): the elements name the old set's
    /// particles.
    #[error("the particle set changed since it was meshed (by hand): take a step, or call initialize_acceleration, before measuring the fluid's or the contacts' forces")]
    NotMeshed,
    /// A particle position became non-finite.
    #[error("particle {particle} has a non-finite position at t = {time} s")]
    NonFinite {
        /// Time (s).
        time: f64,
        /// The particle.
        particle: usize,
    },
}
