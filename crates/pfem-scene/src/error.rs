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
    /// A setting outside its sensible range.
    #[error("setting `{setting}` = {value} is outside {range}")]
    OutOfRange {
        /// The setting.
        setting: &'static str,
        /// Its value.
        value: f64,
        /// The range, with why.
        range: &'static str,
    },
    /// A setting that must be finite is not (NaN or infinite).
    #[error("setting `{setting}` must be finite")]
    NonFinite {
        /// The setting.
        setting: &'static str,
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
    /// A wall motion law whose parameters or table cannot hold (the law's
    /// constructor; the scene names the wall it moves).
    #[error("{law}: {why}")]
    InvalidMotion {
        /// The law ("a piecewise-linear motion", "a rotation").
        law: &'static str,
        /// What is wrong.
        why: String,
    },
    /// A call of the scene builder that had nothing to act on, or
    /// settings of a body that exclude each other.
    #[error("scene: {why}")]
    Misuse {
        /// What was called, and why it cannot hold.
        why: String,
    },
    /// A solid under gravity with nothing to hold it: no clamp, no fluid
    /// to rest in, no wall or other solid to land on.
    #[error("solid `{body}` has no support: clamp it, or give the scene a fluid to rest in or a wall or solid to land on")]
    Unsupported {
        /// Body name.
        body: String,
    },
    /// A scene name that cannot name files.
    #[error("scene name `{name}`: {why}")]
    InvalidName {
        /// The name.
        name: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// Settings that cannot finish: too many steps or frames.
    #[error("{what}: about {count:.3e}, more than the {limit:.0e} allowed")]
    CannotFinish {
        /// What would run away (steps, frames).
        what: String,
        /// How many it would take.
        count: f64,
        /// The limit.
        limit: f64,
    },
    /// The scene would need more memory than the budget.
    #[error("the scene has about {particles:.3e} particles and would need about {bytes:.2e} bytes, over the memory budget of {budget:.2e} bytes (coarsen the spacing, or raise the budget){largest}")]
    TooLarge {
        /// Estimated particles.
        particles: f64,
        /// Estimated bytes.
        bytes: f64,
        /// The budget (bytes).
        budget: f64,
        /// The body that places the most particles, with its count,
        /// spacing and extent (`"; the largest, body …"`), or empty where
        /// one lattice is refused.
        largest: String,
    },
    /// A setting the scene's dimension does not support (yet).
    #[error("setting `{setting}` is not supported in {dim}D: {why}")]
    NotInDimension {
        /// The setting.
        setting: &'static str,
        /// The scene's dimension.
        dim: usize,
        /// Why.
        why: &'static str,
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
