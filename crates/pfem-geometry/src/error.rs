//! Typed errors of the geometry layer.

/// What went wrong while tessellating or classifying a particle cloud.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GeometryError {
    /// A coordinate is NaN or infinite.
    #[error("particle {index} has a non-finite coordinate")]
    NonFinite {
        /// Index of the offending particle.
        index: usize,
    },
    /// Fewer than `D + 1` affinely independent points: nothing to mesh.
    #[error("{count} particles span no {dim}-dimensional simplex (all coincident, collinear or coplanar)")]
    Degenerate {
        /// Number of particles given.
        count: usize,
        /// Spatial dimension.
        dim: usize,
    },
    /// Two particles are closer than the tolerance the tessellator can
    /// resolve (exact duplicates included).
    #[error("particles {first} and {second} are {distance:e} m apart, closer than the tolerance {tolerance:e} m")]
    NearCoincident {
        /// The particle kept.
        first: usize,
        /// The particle that coincides with it.
        second: usize,
        /// Their distance (m).
        distance: f64,
        /// The tolerance (m).
        tolerance: f64,
    },
    /// A coordinate is finite but outside the range the exact predicates
    /// of the tessellator can handle without overflow, even after the
    /// exact power-of-two rescaling the tessellator applies.
    #[error(
        "particle {index} has coordinate {value:e}, outside the range the tessellator supports"
    )]
    OutOfRange {
        /// Index of the offending particle.
        index: usize,
        /// The offending coordinate (m).
        value: f64,
    },
    /// More particles than `u32` indices can address.
    #[error("{count} particles exceed the supported maximum of {max}")]
    TooManyPoints {
        /// Number of particles given.
        count: usize,
        /// Largest supported number.
        max: usize,
    },
    /// Two per-particle (or per-simplex) arrays that must have the same
    /// length do not.
    #[error("{what} has length {found}, expected {expected}")]
    LengthMismatch {
        /// Which argument.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A parameter is outside its valid range.
    #[error("parameter `{name}` = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Parameter name (the struct field).
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the valid range is.
        reason: &'static str,
    },
    /// A particle spacing `h` is not finite and positive.
    #[error("particle {index} has invalid spacing h = {value}")]
    InvalidSpacing {
        /// Index of the offending particle.
        index: usize,
        /// The spacing given (m).
        value: f64,
    },
    /// A connectivity array refers to a particle that does not exist, or its
    /// length is not a multiple of the vertices per simplex.
    #[error("invalid connectivity: {reason}")]
    InvalidConnectivity {
        /// What is wrong.
        reason: &'static str,
    },
    /// The underlying triangulation library failed unexpectedly. This is a
    /// bug (ours or the library's), reported instead of panicking.
    #[error("internal tessellator failure: {message}")]
    Internal {
        /// What the library reported.
        message: String,
    },
}
