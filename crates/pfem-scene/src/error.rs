//! Typed errors of scene set-up.

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
