//! Constitutive laws for pfem.
pub mod material;
pub use material::*;
