//! Nearly-incompressible Newtonian fluid (paper §3.1–3.2, eqs. 16–27).

use pfem_core::{Const, Dim, Tensor};

use crate::error::{check, check_density, check_wave_speed, MaterialError, Parameter};
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
/// The pressure is updated with the rate at the step's end (backward
/// Euler in `p`) while the positions follow the Newmark scheme: as in the
/// paper, this acts as a bulk viscosity `K_f Δt / 2` under the
/// trapezoidal rule, a damping ratio of about `ω Δt / 4` on an acoustic
/// mode of frequency `ω`: the stiff water's pressure waves, unresolved by
/// the step, are damped; a wave the step resolves is barely touched.
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
    /// `ρ > 0`, `μ_f ≥ 0` (zero is an inviscid fluid) and `K_f > 0`;
    /// [`MaterialError::DegenerateWaveSpeed`] if `√(K_f/ρ)` is not finite
    /// and positive.
    pub fn new(density: f64, viscosity: f64, bulk_modulus: f64) -> Result<Self, MaterialError> {
        let fluid = Self {
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
        };
        check_wave_speed(fluid.wave_speed())?;
        Ok(fluid)
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
        Unified::new(
            self.viscosity,                // eq. 44
            kin.dt * self.bulk_modulus,    // eq. 44
            Tensor::<D>::identity() * -p,  // eq. 44
            if D == 2 { -p } else { 0.0 }, // out of plane
        )
    }

    /// `pⁿ⁺¹ = pⁿ − Δt K_f ε_v` with `ε_v = tr D` (eqs. 26, 62).
    fn update_history(&self, kin: &Kinematics<D>, history: &mut History<D>) {
        history.pressure -= kin.dt * self.bulk_modulus * kin.volumetric_rate(); // eq. 26
    }

    /// `pⁿ⁺¹ = pⁿ − Δt K_f ε_v` at a node (eqs. 26, 62).
    fn update_pressure(&self, p_n: f64, volumetric_rate: f64, dt: f64) -> f64 {
        p_n - dt * self.bulk_modulus * volumetric_rate // eq. 26
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn simple_shear<const D: usize>()
    where
        Const<D>: Dim,
    {
        let fluid = Newtonian::new(1000.0, 0.8, 2.0e9).unwrap();
        let gamma_dot = 3.5;
        let mut d = Tensor::<D>::zeros();
        d[(0, 1)] = 0.5 * gamma_dot;
        d[(1, 0)] = 0.5 * gamma_dot;
        let kin = Kinematics {
            d,
            ..Kinematics::<D>::at_rest(1e-3)
        };
        let h = History::<D> {
            pressure: 1.0e5,
            ..History::default()
        };
        let sigma = fluid.unified(&kin, &h).cauchy_stress(&kin);
        // τ = μ γ̇ (eq. 21); the normal stresses are −p.
        assert!((sigma[(0, 1)] - 0.8 * gamma_dot).abs() < 1e-12);
        assert_eq!(sigma[(1, 0)], sigma[(0, 1)]);
        for i in 0..D {
            assert_eq!(sigma[(i, i)], -1.0e5);
        }
    }

    #[test]
    fn simple_shear_gives_mu_gamma_dot_2d() {
        simple_shear::<2>();
    }

    #[test]
    fn simple_shear_gives_mu_gamma_dot_3d() {
        simple_shear::<3>();
    }

    fn compression<const D: usize>()
    where
        Const<D>: Dim,
    {
        let water = Newtonian::water();
        let (dt, eps_v, p0) = (2e-4, -3.0e-3, 1234.5);
        // Nodal kinematics as the solver passes them: d = (ε_v / D) I.
        let kin = Kinematics {
            d: Tensor::<D>::identity() * (eps_v / D as f64),
            ..Kinematics::<D>::at_rest(dt)
        };
        let mut h = History::<D> {
            pressure: p0,
            ..History::default()
        };
        let u = water.unified(&kin, &h);
        water.update_history(&kin, &mut h);
        let expected = p0 - dt * 2.2e9 * eps_v; // eq. 26
        assert!((h.pressure - expected).abs() <= 1e-12 * expected);
        assert_eq!(h.stress, Tensor::<D>::zeros());
        // Mean stress of eq. 27 is −pⁿ⁺¹ (3D trace; in 2D with σ_zz).
        let s = u.cauchy_stress(&kin);
        let mean = (s.trace() + u.cauchy_stress_zz(&kin)) / 3.0;
        assert!((mean + h.pressure).abs() <= 1e-12 * expected);
    }

    #[test]
    fn compression_updates_pressure_2d() {
        compression::<2>();
    }

    #[test]
    fn compression_updates_pressure_3d() {
        compression::<3>();
    }

    #[test]
    fn unified_triple_matches_eq_44() {
        let f = Newtonian::new(900.0, 0.1, 1.0e7).unwrap();
        let kin = Kinematics::<2>::at_rest(1e-3);
        let h = History::<2> {
            pressure: 50.0,
            ..History::default()
        };
        let u = f.unified(&kin, &h);
        assert_eq!(u.mu, 0.1);
        assert_eq!(u.kappa, 1e-3 * 1.0e7);
        assert_eq!(u.sigma_hat, Tensor::<2>::identity() * -50.0);
        assert_eq!(u.sigma_hat_zz, -50.0);
        let u3 = f.unified(
            &Kinematics::<3>::at_rest(1e-3),
            &History {
                pressure: 50.0,
                ..History::default()
            },
        );
        assert_eq!(u3.sigma_hat_zz, 0.0);
    }

    #[test]
    fn water_is_valid_and_fast() {
        let w = Newtonian::water();
        assert_eq!(Newtonian::new(1000.0, 1e-3, 2.2e9), Ok(w));
        assert!((w.wave_speed() - (2.2e6f64).sqrt()).abs() < 1e-12);
        assert_eq!(<Newtonian as Material<3>>::wave_speed(&w), w.wave_speed());
        assert_eq!(<Newtonian as Material<2>>::density(&w), 1000.0);
        assert_eq!(<Newtonian as Material<2>>::kind(&w), MaterialKind::Fluid);
        let soft = w.with_bulk_modulus(2.2e6).unwrap();
        assert_eq!(soft.bulk_modulus(), 2.2e6);
        assert_eq!(soft.viscosity(), 1e-3);
    }

    #[test]
    fn invalid_parameters_are_typed_errors() {
        use Parameter::*;
        assert!(Newtonian::new(1000.0, 0.0, 2.2e9).is_ok()); // inviscid is fine
        let cases = [
            ((0.0, 1e-3, 2.2e9), Density),
            ((-1.0, 1e-3, 2.2e9), Density),
            ((f64::NAN, 1e-3, 2.2e9), Density),
            ((f64::INFINITY, 1e-3, 2.2e9), Density),
            ((1e3, -1e-3, 2.2e9), Viscosity),
            ((1e3, f64::NAN, 2.2e9), Viscosity),
            ((1e3, f64::INFINITY, 2.2e9), Viscosity),
            ((1e3, 1e-3, 0.0), BulkModulus),
            ((1e3, 1e-3, -2.2e9), BulkModulus),
            ((1e3, 1e-3, f64::NAN), BulkModulus),
            ((1e3, 1e-3, f64::INFINITY), BulkModulus),
        ];
        for ((rho, mu, k), p) in cases {
            let err = Newtonian::new(rho, mu, k).unwrap_err();
            assert_eq!(err.parameter(), Some(p));
            assert!(err.to_string().contains(p.describe()));
        }
    }
}
