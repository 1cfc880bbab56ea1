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
}
