//! Geometry for pfem: Delaunay tessellation, alpha shapes (§8 of Marti &
//! Idelsohn 2007, "the paper" in this crate's comments), boundary
//! classification, particle management and mesh quality.
//!
//! One remeshing step of the driver, in 2D:
//!
//! ```
//! use pfem_core::{ParticleKind, Point};
//! use pfem_geometry::{
//!     alpha_shape, classify, AlphaShapeParams, Delaunay2, NodeTag, Tessellation, Tessellator,
//! };
//!
//! // A 10 x 10 block of fluid particles at spacing h = 0.1 m.
//! let h = 0.1;
//! let points: Vec<Point<2>> = (0..100)
//!     .map(|i| Point::<2>::new((i % 10) as f64 * h, (i / 10) as f64 * h))
//!     .collect();
//! let kinds = vec![ParticleKind::Fluid; points.len()];
//! let spacing = vec![h; points.len()];
//!
//! let mut delaunay = Tessellation::default();
//! Delaunay2::default().tessellate(&points, &mut delaunay)?;
//! let fluid = alpha_shape(&points, &kinds, &spacing, &delaunay, &AlphaShapeParams::default())?;
//! let cls = classify(&points, &kinds, &fluid.mesh, None)?;
//!
//! assert!((fluid.kept_measure - 0.81).abs() < 1e-12); // (9 h)²
//! assert_eq!(cls.boundary_loops, Some(1));
//! assert_eq!(cls.tags[0], NodeTag::FreeSurface);
//! assert_eq!(cls.tags[55], NodeTag::Interior);
//! # Ok::<(), pfem_geometry::GeometryError>(())
//! ```
//!
//! Everything but the tessellators ([`Delaunay2`] in 2D, [`Delaunay3`] in
//! 3D) is generic over the dimension `D` (2 or 3),
//! so the 3D tessellator plugs into the same alpha shape, classification,
//! particle management and quality code.
pub mod alpha;
pub mod classify;
pub mod contact;
pub mod delaunay2;
pub mod delaunay3;
pub mod error;
pub mod particles;
pub mod quality;
pub mod reach;
pub mod tessellation;

pub use alpha::{
    alpha_shape, alpha_shape_cutting_into, alpha_shape_into, AlphaShape, AlphaShapeParams,
    MIN_ELEMENT_QUALITY_3D, MIN_SHAPE_QUALITY,
};
pub use classify::{
    classify, classify_into, BoundaryFacet, Classification, Component, FacetKind, NodeTag,
};
pub use contact::{contact_elements, ContactCandidate};
pub use delaunay2::{Delaunay2, Delaunay2Params};
pub use delaunay3::Delaunay3;
pub use error::GeometryError;
pub use particles::{
    manage_particles, Origin, ParticleManagementParams, ParticleMap, ParticleUpdate, VolumeChange,
    REMOVED,
};
pub use quality::{mesh_quality, radius_ratio, QualityParams, QualityReport};
pub use reach::{near_matter, tessellate_subset};
pub use tessellation::{tessellate_or_empty, Tessellation, Tessellator, NO_NEIGHBOR, SEALED};
