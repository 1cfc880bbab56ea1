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
    /// A particle position became non-finite.
    #[error("particle {particle} has a non-finite position at t = {time} s")]
    NonFinite {
        /// Time (s).
        time: f64,
        /// The particle.
        particle: usize,
    },
}
