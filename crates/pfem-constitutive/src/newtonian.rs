//! Nearly-incompressible Newtonian fluid (paper §3.1–3.2, eqs. 16–27).

use pfem_core::{Const, Dim, Tensor};

use crate::error::{check, check_density, MaterialError, Parameter};
use crate::material::{History, Kinematics, Material, MaterialKind, Unified};

/// A nearly-incompressible Newtonian fluid (paper §3.1–3.2).
///
/// Constitutive law, with `D' = D − ⅓ (tr D) I` the deviatoric rate:
///
/// - `σ = −p I + 2 μ_f D'` (eqs. 16, 21), `ε_v = tr D = div V` (eq. 19);
/// - pressure from the bulk modulus, `Dp/Dt = −K_f div V` (eqs. 22–23),
///   discretised implicitly as `pⁿ⁺¹ = pⁿ − Δt K_f ε_vⁿ⁺¹` (eqs. 25–26);
/// - hence `σⁿ⁺¹ = −pⁿ I + Δt K_f ε_vⁿ⁺¹ I + 2 μ_f D'ⁿ⁺¹` (eq. 27).
///
/// In the unified form of eq. 44 the triple is `μ = μ_f`, `𝒦 = Δt K_f`,
/// `σ̂ = −pⁿ I`; in 2D plane strain the out-of-plane history stress is
/// `σ̂_zz = −pⁿ` too (so `σ_zz = −pⁿ + Δt K_f ε_v − ⅔ μ_f ε_v`).
///
/// The history is the pressure alone ([`History::pressure`], positive in
/// compression); [`Material::update_history`] applies eq. 26 using only
/// `tr D` of the kinematics it is given, so it is correct for the nodal,
/// isotropic kinematics `d = (ε_v / D) I` the solver passes for the
/// averaged nodal pressure of eq. 62. It leaves [`History::stress`] and
/// [`History::stress_zz`] untouched.
///
/// The real bulk modulus of water (2.2 GPa) is accepted; lowering it
/// (artificial compressibility) is the caller's explicit choice.
///
/// ```
/// use pfem_constitutive::{History, Kinematics, Material, Newtonian};
///
/// let water = Newtonian::water();
/// assert!((water.wave_speed() - 1483.2).abs() < 0.1); // √(K/ρ)
///
/// // Uniform compression ε_v = −1e-6 1/s over Δt = 1 ms.
/// let mut kin = Kinematics::<2>::at_rest(1e-3);
/// kin.d[(0, 0)] = -0.5e-6;
/// kin.d[(1, 1)] = -0.5e-6;
/// let mut h = History::<2>::default();
/// water.update_history(&kin, &mut h);
/// assert!((h.pressure - 1e-3 * 2.2e9 * 1e-6).abs() < 1e-12); // eq. 26
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Newtonian {
    density: f64,
    viscosity: f64,
    bulk_modulus: f64,
}

impl Newtonian {
    /// A Newtonian fluid of density `ρ` (kg/m³), dynamic viscosity `μ_f`
    /// (Pa·s) and bulk modulus `K_f` (Pa).
    ///
    /// # Errors
    ///
    /// [`MaterialError::InvalidParameter`] unless every parameter is finite,
    /// `ρ > 0`, `μ_f ≥ 0` (zero is an inviscid fluid) and `K_f > 0`.
    pub fn new(density: f64, viscosity: f64, bulk_modulus: f64) -> Result<Self, MaterialError> {
        Ok(Self {
            density: check_density(density)?,
            viscosity: check(
                Parameter::Viscosity,
                viscosity,
                viscosity >= 0.0,
                "finite and ≥ 0",
            )?,
            bulk_modulus: check(
                Parameter::BulkModulus,
                bulk_modulus,
                bulk_modulus > 0.0,
                "finite and > 0",
            )?,
        })
    }

    /// Water at about 20 °C: `ρ = 1000 kg/m³`, `μ_f = 10⁻³ Pa·s`,
    /// `K_f = 2.2·10⁹ Pa`.
    pub fn water() -> Self {
        Self {
            density: 1000.0,
            viscosity: 1.0e-3,
            bulk_modulus: 2.2e9,
        }
    }

    /// Dynamic viscosity `μ_f` (Pa·s).
    pub fn viscosity(&self) -> f64 {
        self.viscosity
    }

    /// Bulk modulus `K_f` (Pa).
    pub fn bulk_modulus(&self) -> f64 {
        self.bulk_modulus
    }

    /// The same fluid with another bulk modulus `K_f` (Pa), e.g. for an
    /// explicit artificial-compressibility study.
    ///
    /// # Errors
    ///
    /// [`MaterialError::InvalidParameter`] unless `K_f` is finite and `> 0`.
    pub fn with_bulk_modulus(self, bulk_modulus: f64) -> Result<Self, MaterialError> {
        Self::new(self.density, self.viscosity, bulk_modulus)
    }

    /// Density `ρ` (kg/m³).
    pub fn density(&self) -> f64 {
        self.density
    }

    /// Speed of sound `√(K_f / ρ)` (m/s).
    pub fn wave_speed(&self) -> f64 {
        (self.bulk_modulus / self.density).sqrt()
    }
}

impl<const D: usize> Material<D> for Newtonian
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "newtonian fluid"
    }

    fn kind(&self) -> MaterialKind {
        MaterialKind::Fluid
    }

    fn density(&self) -> f64 {
        Self::density(self)
    }

    /// `√(K_f / ρ)`.
    fn wave_speed(&self) -> f64 {
        Self::wave_speed(self)
    }

    /// `μ = μ_f`, `𝒦 = Δt K_f`, `σ̂ = −pⁿ I`, `σ̂_zz = −pⁿ` in 2D (eq. 44).
    fn unified(&self, kin: &Kinematics<D>, history: &History<D>) -> Unified<D> {
        let p = history.pressure;
        Unified {
            mu: self.viscosity,                      // eq. 44
            kappa: kin.dt * self.bulk_modulus,       // eq. 44
            sigma_hat: Tensor::<D>::identity() * -p, // eq. 44
            sigma_hat_zz: if D == 2 { -p } else { 0.0 },
        }
    }

    /// `pⁿ⁺¹ = pⁿ − Δt K_f ε_v` with `ε_v = tr D` (eqs. 26, 62).
    fn update_history(&self, kin: &Kinematics<D>, history: &mut History<D>) {
        history.pressure -= kin.dt * self.bulk_modulus * kin.volumetric_rate(); // eq. 26
    }
}
