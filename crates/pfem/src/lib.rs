//! pfem
