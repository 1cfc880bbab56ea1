//! Typed errors of material construction.

use std::fmt;

/// A material parameter, as named by [`MaterialError`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Parameter {
    /// Density `ρ` (kg/m³).
    Density,
    /// Dynamic viscosity `μ_f` (Pa·s).
    Viscosity,
    /// Bulk modulus `K_f` (Pa).
    BulkModulus,
    /// Young's modulus `E` (Pa).
    YoungModulus,
    /// Poisson's ratio `ν` (dimensionless).
    PoissonRatio,
    /// First Lamé parameter `λ_h` (Pa).
    LameLambda,
    /// Shear modulus, the second Lamé parameter `μ_h` (Pa).
    ShearModulus,
}

impl Parameter {
    /// The parameter's name, symbol and unit, e.g. `"density ρ (kg/m³)"`.
    pub fn describe(self) -> &'static str {
        match self {
            Parameter::Density => "density ρ (kg/m³)",
            Parameter::Viscosity => "dynamic viscosity μ_f (Pa·s)",
            Parameter::BulkModulus => "bulk modulus K_f (Pa)",
            Parameter::YoungModulus => "Young's modulus E (Pa)",
            Parameter::PoissonRatio => "Poisson's ratio ν",
            Parameter::LameLambda => "Lamé parameter λ_h (Pa)",
            Parameter::ShearModulus => "shear modulus μ_h (Pa)",
        }
    }
}

impl fmt::Display for Parameter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.describe())
    }
}

/// Why a material could not be built.
///
/// ```
/// use pfem_constitutive::{Hypoelastic, MaterialError, Parameter};
///
/// let err = Hypoelastic::new(1100.0, 12.0e6, 0.5).unwrap_err();
/// assert!(matches!(
///     err,
///     MaterialError::InvalidParameter { parameter: Parameter::PoissonRatio, .. }
/// ));
/// assert_eq!(
///     err.to_string(),
///     "Poisson's ratio ν = 0.5 is invalid: must be finite with -1 < ν < 0.5"
/// );
/// ```
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MaterialError {
    /// A parameter is NaN, infinite, or outside its allowed range.
    #[error("{parameter} = {value} is invalid: must be {allowed}")]
    InvalidParameter {
        /// Which parameter.
        parameter: Parameter,
        /// The value given.
        value: f64,
        /// The allowed range, in words.
        allowed: &'static str,
    },
    /// Every parameter is valid alone, but together they give a wave speed
    /// that is zero or not finite (e.g. `K/ρ` overflows), which would break
    /// time-step control.
    #[error(
        "wave speed {wave_speed} m/s is not finite and positive: \
         the moduli and the density are too far apart"
    )]
    DegenerateWaveSpeed {
        /// The wave speed the parameters give (m/s).
        wave_speed: f64,
    },
    /// A material names more internal variables than a history holds
    /// ([`crate::MAX_INTERNAL`]).
    #[error("{count} internal variables, more than a history holds ({limit})")]
    TooManyInternalVariables {
        /// How many the material names.
        count: usize,
        /// [`crate::MAX_INTERNAL`].
        limit: usize,
    },
    /// A fluid material that names internal variables: a fluid's elements
    /// are made anew at every remeshing, so per-element state would be
    /// reset every step without a word (a fluid's state lives at the
    /// nodes, as its pressure does).
    #[error("a fluid keeps no internal variables (its elements are made anew every step); it names {count}")]
    FluidWithInternalVariables {
        /// How many the material names.
        count: usize,
    },
    /// A solid's [`crate::Material::initial_history`] with an entry that is
    /// NaN or infinite.
    #[error("its initial history (stress, internal variables) is not finite")]
    NonFiniteInitialHistory,
    /// A setting that holds in one dimension only, used in another (plane
    /// stress in 3D).
    #[error("{what} does not apply in {dimension}D")]
    NotInDimension {
        /// The setting.
        what: &'static str,
        /// The dimension the material is used in.
        dimension: usize,
    },
}

impl MaterialError {
    /// The parameter at fault, if a single one is.
    pub fn parameter(&self) -> Option<Parameter> {
        match self {
            MaterialError::InvalidParameter { parameter, .. } => Some(*parameter),
            MaterialError::DegenerateWaveSpeed { .. }
            | MaterialError::TooManyInternalVariables { .. }
            | MaterialError::FluidWithInternalVariables { .. }
            | MaterialError::NotInDimension { .. }
            | MaterialError::NonFiniteInitialHistory => None,
        }
    }
}

/// Checks a derived wave speed is finite and positive.
pub(crate) fn check_wave_speed(wave_speed: f64) -> Result<(), MaterialError> {
    if wave_speed.is_finite() && wave_speed > 0.0 {
        Ok(())
    } else {
        Err(MaterialError::DegenerateWaveSpeed { wave_speed })
    }
}

/// Checks `value` is finite and satisfies `ok`; otherwise the typed error.
pub(crate) fn check(
    parameter: Parameter,
    value: f64,
    ok: bool,
    allowed: &'static str,
) -> Result<f64, MaterialError> {
    if value.is_finite() && ok {
        Ok(value)
    } else {
        Err(MaterialError::InvalidParameter {
            parameter,
            value,
            allowed,
        })
    }
}

/// `ρ`: finite and `> 0`.
pub(crate) fn check_density(rho: f64) -> Result<f64, MaterialError> {
    check(Parameter::Density, rho, rho > 0.0, "finite and > 0")
}
