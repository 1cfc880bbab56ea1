//! Geometry for pfem: Delaunay tessellation, alpha shapes (paper §8),
//! boundary classification, particle management and mesh quality.
pub mod delaunay3;
pub mod error;
pub mod tessellation;

pub use delaunay3::Delaunay3;
pub use error::GeometryError;
pub use tessellation::{Tessellation, Tessellator, NO_NEIGHBOR};
