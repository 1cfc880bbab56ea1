//! Isotropic hypoelastic solid with the Truesdell rate (paper §3.3–3.4,
//! eqs. 28–42).

use pfem_core::{Const, Dim, Tensor};

use crate::error::{check, check_density, MaterialError, Parameter};
use crate::material::{History, Kinematics, Material, MaterialKind, Unified};

/// An isotropic hypoelastic solid (paper §3.3–3.4), in the Updated
/// Lagrangian form the solver uses.
///
/// Rate law: the Truesdell rate of the Kirchhoff stress `τ = J σ` is linear
/// in the rate of deformation,
/// `τ^△ = 2 μ_h D + λ_h (tr D) I` (eq. 28), `τ^△ = τ̇ − L τ − τ Lᵀ = F Ṡ Fᵀ`
/// (eq. 29). Discretised implicitly over a step with the reference at `t_n`
/// (eqs. 31–36 with `f = F`, `Jⁿ = 1`):
///
/// - `μ̄ = μ_h Δt / J`, `λ̄ = λ_h Δt / J` (eq. 37);
/// - `σ̂ = F σⁿ Fᵀ / J` (eq. 38);
/// - `𝒦 = λ̄ + ⅔ μ̄ = (λ_h + ⅔ μ_h) Δt / J` (eq. 41);
/// - `σⁿ⁺¹ = σ̂ + 𝒦 ε_v I + 2 μ̄ D'` (eqs. 39–42, 63).
///
/// These are the unified triple of eq. 44; [`Material::update_history`]
/// stores exactly [`Unified::cauchy_stress`] (and
/// [`Unified::cauchy_stress_zz`]) of that triple.
///
/// **2D is plane strain.** `F_zz = 1`, `D_zz = 0`, but the out-of-plane
/// stress [`History::stress_zz`] evolves: `σ̂_zz = σ_zzⁿ / J` and
/// `σ_zzⁿ⁺¹ = σ̂_zz + 𝒦 ε_v + 2 μ̄ D'_zz` with `D'_zz = −⅓ tr D`. In the
/// small-strain limit this gives `σ_zz = ν (σ_xx + σ_yy)`. In 3D
/// `stress_zz` is unused and left at zero.
///
/// The Truesdell rate is objective: under a rigid rotation `F = R`
/// (`J = 1`, `D = 0`) the update is `σⁿ⁺¹ = R σⁿ Rᵀ`.
///
/// `J` is taken from [`Kinematics::j`]; the solver rejects steps with
/// `J ≤ 0` (an inverted element), for which the result is meaningless
/// (but no panic occurs).
///
/// ```
/// use pfem_constitutive::{History, Hypoelastic, Kinematics, Material};
///
/// let rubber = Hypoelastic::new(1100.0, 12.0e6, 0.4).unwrap();
/// let kin = Kinematics::<2>::at_rest(1e-4);
/// let u = rubber.unified(&kin, &History::default());
/// assert!((u.mu - rubber.shear_modulus() * 1e-4).abs() < 1e-12); // eq. 37
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hypoelastic {
    density: f64,
    lambda: f64,
    mu: f64,
}

impl Hypoelastic {
    /// A hypoelastic solid of density `ρ` (kg/m³), Young's modulus `E` (Pa)
    /// and Poisson's ratio `ν`: `μ_h = E / (2 (1 + ν))`,
    /// `λ_h = E ν / ((1 + ν)(1 − 2ν))`.
    ///
    /// # Errors
    ///
    /// [`MaterialError::InvalidParameter`] unless every parameter is finite,
    /// `ρ > 0`, `E > 0` and `−1 < ν < 0.5`.
    pub fn new(density: f64, young: f64, poisson: f64) -> Result<Self, MaterialError> {
        let density = check_density(density)?;
        let e = check(
            Parameter::YoungModulus,
            young,
            young > 0.0,
            "finite and > 0",
        )?;
        let nu = check(
            Parameter::PoissonRatio,
            poisson,
            poisson > -1.0 && poisson < 0.5,
            "finite with -1 < ν < 0.5",
        )?;
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        // Extreme but valid inputs (E near f64::MAX, ν next to 0.5) can
        // overflow the Lamé parameters: report that rather than store ∞.
        let lambda = check(
            Parameter::LameLambda,
            lambda,
            true,
            "finite (E ν / ((1 + ν)(1 − 2ν)) overflowed)",
        )?;
        Self::from_lame(density, lambda, mu)
    }

    /// A hypoelastic solid of density `ρ` (kg/m³) and Lamé parameters
    /// `λ_h`, `μ_h` (Pa).
    ///
    /// # Errors
    ///
    /// [`MaterialError::InvalidParameter`] unless every parameter is finite,
    /// `ρ > 0`, `μ_h > 0` and `λ_h > −⅔ μ_h` (positive bulk modulus; the
    /// same as `−1 < ν < 0.5`).
    pub fn from_lame(density: f64, lambda: f64, mu: f64) -> Result<Self, MaterialError> {
        let density = check_density(density)?;
        let mu = check(Parameter::ShearModulus, mu, mu > 0.0, "finite and > 0")?;
        let lambda = check(
            Parameter::LameLambda,
            lambda,
            lambda + 2.0 / 3.0 * mu > 0.0,
            "finite with λ_h + ⅔ μ_h > 0",
        )?;
        Ok(Self {
            density,
            lambda,
            mu,
        })
    }

    /// First Lamé parameter `λ_h` (Pa).
    pub fn lame_lambda(&self) -> f64 {
        self.lambda
    }

    /// Shear modulus `μ_h` (Pa), the second Lamé parameter.
    pub fn shear_modulus(&self) -> f64 {
        self.mu
    }

    /// Bulk modulus `λ_h + ⅔ μ_h` (Pa).
    pub fn bulk_modulus(&self) -> f64 {
        self.lambda + 2.0 / 3.0 * self.mu
    }

    /// Young's modulus `E = μ_h (3 λ_h + 2 μ_h) / (λ_h + μ_h)` (Pa).
    pub fn young_modulus(&self) -> f64 {
        self.mu * (3.0 * self.lambda + 2.0 * self.mu) / (self.lambda + self.mu)
    }

    /// Poisson's ratio `ν = λ_h / (2 (λ_h + μ_h))`.
    pub fn poisson_ratio(&self) -> f64 {
        self.lambda / (2.0 * (self.lambda + self.mu))
    }

    /// Density `ρ` (kg/m³).
    pub fn density(&self) -> f64 {
        self.density
    }

    /// Longitudinal (P-) wave speed `√((λ_h + 2 μ_h) / ρ)` (m/s).
    pub fn wave_speed(&self) -> f64 {
        ((self.lambda + 2.0 * self.mu) / self.density).sqrt()
    }
}

impl<const D: usize> Material<D> for Hypoelastic
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "hypoelastic solid"
    }

    fn kind(&self) -> MaterialKind {
        MaterialKind::Solid
    }

    fn density(&self) -> f64 {
        Self::density(self)
    }

    /// Longitudinal wave speed `√((λ_h + 2 μ_h) / ρ)`.
    fn wave_speed(&self) -> f64 {
        Self::wave_speed(self)
    }

    /// `μ = μ_h Δt / J`, `𝒦 = (λ_h + ⅔ μ_h) Δt / J`, `σ̂ = F σⁿ Fᵀ / J`
    /// (eqs. 37–38, 41, 44); in 2D `σ̂_zz = σ_zzⁿ / J` (`F_zz = 1`).
    ///
    /// `σ̂` is symmetrised (`½ (A + Aᵀ)`) so that rounding never makes the
    /// stress unsymmetric.
    fn unified(&self, kin: &Kinematics<D>, history: &History<D>) -> Unified<D> {
        let dt_over_j = kin.dt / kin.j;
        let a = kin.f * history.stress * kin.f.transpose() / kin.j; // eq. 38
        let sigma_hat: Tensor<D> = (a + a.transpose()) * 0.5;
        Unified {
            mu: self.mu * dt_over_j,                                // eq. 37
            kappa: (self.lambda + 2.0 / 3.0 * self.mu) * dt_over_j, // eq. 41
            sigma_hat,
            sigma_hat_zz: if D == 2 {
                history.stress_zz / kin.j
            } else {
                0.0
            },
        }
    }

    /// `σⁿ⁺¹ = σ̂ + 𝒦 ε_v I + 2 μ̄ D'` (eqs. 42, 63), and in 2D
    /// `σ_zzⁿ⁺¹ = σ̂_zz + 𝒦 ε_v − ⅔ μ̄ ε_v`. The pressure is not touched.
    fn update_history(&self, kin: &Kinematics<D>, history: &mut History<D>) {
        let u = <Self as Material<D>>::unified(self, kin, history);
        history.stress = u.cauchy_stress(kin); // eq. 63
        history.stress_zz = u.cauchy_stress_zz(kin);
    }
}
