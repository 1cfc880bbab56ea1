//! pfem-time
