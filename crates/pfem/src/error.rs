//! Typed errors of the driver.

use pfem_geometry::GeometryError;
use pfem_time::StepError;

use crate::output::OutputError;

/// An impossible or malformed scene, reported before any step runs.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The scene has no body or no particle.
    #[error("the scene has no particles")]
    Empty,
    /// A run setting is out of range.
    #[error("setting `{setting}` must be a positive finite number, got {value}")]
    InvalidSetting {
        /// The setting.
        setting: &'static str,
        /// Its value.
        value: f64,
    },
    /// A particle spacing is not a positive finite number.
    #[error("body `{body}`: particle spacing must be a positive finite number, got {spacing}")]
    InvalidSpacing {
        /// Body name.
        body: String,
        /// The spacing.
        spacing: f64,
    },
    /// The spacing is larger than the body.
    #[error("body `{body}`: particle spacing {spacing} m is larger than the body ({extent} m)")]
    SpacingLargerThanBody {
        /// Body name.
        body: String,
        /// Spacing (m).
        spacing: f64,
        /// Largest extent of the body (m).
        extent: f64,
    },
    /// A geometry cannot be used.
    #[error("body `{body}`: {why}")]
    InvalidGeometry {
        /// Body name.
        body: String,
        /// What is wrong.
        why: String,
    },
    /// A body's material parameters are out of range.
    #[error("body `{body}`: {source}")]
    InvalidMaterial {
        /// Body name.
        body: String,
        /// What the material's constructor rejected.
        source: pfem_constitutive::MaterialError,
    },
    /// A fluid or solid without material.
    #[error("body `{body}` needs a material")]
    MissingMaterial {
        /// Body name.
        body: String,
    },
    /// A fluid with a solid material or the reverse.
    #[error("body `{body}`: its material's kind (fluid/solid) does not match the body's")]
    MaterialKindMismatch {
        /// Body name.
        body: String,
    },
    /// Two bodies overlap.
    #[error("bodies `{first}` and `{second}` overlap")]
    Overlap {
        /// First body.
        first: String,
        /// Second body.
        second: String,
    },
    /// A solid under gravity with nothing to hold it.
    #[error("solid `{body}` has no support: clamp it or give the scene a fluid to rest in")]
    Unsupported {
        /// Body name.
        body: String,
    },
    /// The initial mesh could not be made.
    #[error("the initial mesh could not be made: {why}")]
    Mesh {
        /// Why.
        why: String,
    },
    /// A scene file could not be read or parsed.
    #[error("scene file {path}: {why}")]
    File {
        /// The file.
        path: String,
        /// What is wrong, with the line and field where known.
        why: String,
    },
}

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
    /// Writing output failed.
    #[error(transparent)]
    Output(#[from] OutputError),
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
    /// A particle position became non-finite.
    #[error("particle {particle} has a non-finite position at t = {time} s")]
    NonFinite {
        /// Time (s).
        time: f64,
        /// The particle.
        particle: usize,
    },
}
