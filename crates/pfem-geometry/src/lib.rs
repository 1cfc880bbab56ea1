//! pfem-geometry
