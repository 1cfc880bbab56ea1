//! A user-defined material written only through the public trait: a
//! regularised Bingham fluid (Papanastasiou 1987).
//!
//! A Bingham fluid flows only above a yield stress `τ_y`, then with plastic
//! viscosity `μ_p`. Papanastasiou's regularisation makes the effective
//! viscosity finite everywhere:
//!
//! `μ_eff(γ̇) = μ_p + τ_y (1 − e^{−m γ̇}) / γ̇`, with
//! `γ̇ = √(2 D' : D')` (plane strain: `D'_zz` included),
//!
//! which tends to `μ_p + m τ_y` at rest and to the Bingham law
//! `τ = τ_y + μ_p γ̇` for `m γ̇ ≫ 1`. Pressure follows eq. 26 as for the
//! Newtonian fluid, so the unified triple (eq. 44) is
//! `(μ_eff, Δt K, −pⁿ I)`.

use pfem_constitutive::{Const, Dim, History, Kinematics, Material, MaterialKind, Tensor, Unified};

/// Papanastasiou-regularised Bingham fluid.
#[derive(Debug, Clone, Copy)]
struct Bingham {
    /// Density ρ (kg/m³).
    density: f64,
    /// Plastic viscosity μ_p (Pa·s).
    plastic_viscosity: f64,
    /// Yield stress τ_y (Pa).
    yield_stress: f64,
    /// Regularisation exponent m (s).
    m: f64,
    /// Bulk modulus K (Pa).
    bulk_modulus: f64,
}

impl Bingham {
    /// Equivalent shear rate `γ̇ = √(2 D' : D')`.
    fn shear_rate<const D: usize>(kin: &Kinematics<D>) -> f64
    where
        Const<D>: Dim,
    {
        let dev = kin.deviatoric_rate();
        let zz = kin.deviatoric_rate_zz();
        (2.0 * (dev.norm_squared() + zz * zz)).sqrt()
    }

    /// `μ_eff = μ_p + τ_y (1 − e^{−m γ̇}) / γ̇`, and `μ_p + m τ_y` at `γ̇ = 0`.
    fn effective_viscosity(&self, gamma_dot: f64) -> f64 {
        let x = self.m * gamma_dot;
        let factor = if x < 1e-12 {
            self.m
        } else {
            -(-x).exp_m1() / gamma_dot
        };
        self.plastic_viscosity + self.yield_stress * factor
    }
}

impl<const D: usize> Material<D> for Bingham
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "Papanastasiou Bingham fluid"
    }

    fn kind(&self) -> MaterialKind {
        MaterialKind::Fluid
    }

    fn density(&self) -> f64 {
        self.density
    }

    fn wave_speed(&self) -> f64 {
        (self.bulk_modulus / self.density).sqrt()
    }

    fn unified(&self, kin: &Kinematics<D>, history: &History<D>) -> Unified<D> {
        let p = history.pressure;
        Unified::new(
            self.effective_viscosity(Self::shear_rate(kin)),
            kin.dt * self.bulk_modulus,
            Tensor::<D>::identity() * -p,
            if D == 2 { -p } else { 0.0 },
        )
    }

    fn update_history(&self, kin: &Kinematics<D>, history: &mut History<D>) {
        // Nodal update with only tr D, as for any fluid (eqs. 26, 62).
        history.pressure -= kin.dt * self.bulk_modulus * kin.volumetric_rate();
    }
}

fn mud() -> Bingham {
    Bingham {
        density: 1800.0,
        plastic_viscosity: 0.5,
        yield_stress: 40.0,
        m: 1000.0,
        bulk_modulus: 1.0e8,
    }
}

fn shear_kinematics<const D: usize>(gamma_dot: f64, dt: f64) -> Kinematics<D>
where
    Const<D>: Dim,
{
    let mut d = Tensor::<D>::zeros();
    d[(0, 1)] = 0.5 * gamma_dot;
    d[(1, 0)] = 0.5 * gamma_dot;
    Kinematics {
        d,
        ..Kinematics::at_rest(dt)
    }
}

fn drives_through_the_trait<const D: usize>()
where
    Const<D>: Dim,
{
    let b = mud();
    let material: Box<dyn Material<D>> = Box::new(b);
    assert_eq!(material.kind(), MaterialKind::Fluid);
    assert_eq!(material.density(), 1800.0);
    assert!((material.wave_speed() - (1.0e8f64 / 1800.0).sqrt()).abs() < 1e-12);

    // The trait alone, with a pressure in the history: in a simulation a
    // fluid element is given `History::default()` (its pressure is nodal,
    // eq. 62, and its `σ̂` unused; `examples/custom_material.rs`).
    let p0 = 2.0e3;
    let history = History::<D> {
        pressure: p0,
        ..History::default()
    };

    // At rest: the regularised viscosity is μ_p + m τ_y.
    let rest = material.unified(&Kinematics::at_rest(1e-3), &history);
    assert_eq!(rest.mu, 0.5 + 1000.0 * 40.0);

    for gamma_dot in [1e-4, 0.01, 1.0, 10.0, 1e3] {
        let kin = shear_kinematics::<D>(gamma_dot, 1e-3);
        let u = material.unified(&kin, &history);
        // Effective viscosity of the Papanastasiou law.
        let mu_eff = 0.5 + 40.0 * (1.0 - (-1000.0 * gamma_dot).exp()) / gamma_dot;
        assert!((u.mu - mu_eff).abs() <= 1e-12 * mu_eff, "γ̇ = {gamma_dot}");
        // Shear stress τ = μ_eff γ̇ = τ_y (1 − e^{−m γ̇}) + μ_p γ̇ (eq. 43).
        let sigma = u.cauchy_stress(&kin);
        let tau = 40.0 * (1.0 - (-1000.0 * gamma_dot).exp()) + 0.5 * gamma_dot;
        assert!(
            (sigma[(0, 1)] - tau).abs() <= 1e-12 * tau,
            "γ̇ = {gamma_dot}"
        );
        assert_eq!(sigma[(0, 1)], sigma[(1, 0)]);
        // Isochoric shear: normal stresses are −pⁿ.
        for i in 0..D {
            assert_eq!(sigma[(i, i)], -p0);
        }
        assert_eq!(u.cauchy_stress_zz(&kin), if D == 2 { -p0 } else { 0.0 });
    }

    // Above m γ̇ ≫ 1 it is a Bingham fluid: τ ≈ τ_y + μ_p γ̇.
    let kin = shear_kinematics::<D>(10.0, 1e-3);
    let tau = material.unified(&kin, &history).cauchy_stress(&kin)[(0, 1)];
    assert!((tau - (40.0 + 0.5 * 10.0)).abs() < 1e-9);

    // Pressure history through the trait (eq. 26).
    let mut h = history;
    let kin = Kinematics {
        d: Tensor::<D>::identity() * (-1e-3 / D as f64),
        ..Kinematics::at_rest(1e-3)
    };
    material.update_history(&kin, &mut h);
    assert!((h.pressure - (p0 + 1e-3 * 1.0e8 * 1e-3)).abs() < 1e-9);
}

#[test]
fn bingham_through_trait_object_2d() {
    drives_through_the_trait::<2>();
}

#[test]
fn bingham_through_trait_object_3d() {
    drives_through_the_trait::<3>();
}

#[test]
fn bingham_sits_beside_builtin_materials() {
    let materials: Vec<Box<dyn Material<2>>> = vec![
        Box::new(pfem_constitutive::Newtonian::water()),
        Box::new(mud()),
        Box::new(pfem_constitutive::Hypoelastic::new(1100.0, 12.0e6, 0.4).unwrap()),
    ];
    let names: Vec<&str> = materials.iter().map(|m| m.name()).collect();
    assert_eq!(
        names,
        [
            "newtonian fluid",
            "Papanastasiou Bingham fluid",
            "hypoelastic solid"
        ]
    );
    let kin = shear_kinematics::<2>(1.0, 1e-3);
    for m in &materials {
        let u = m.unified(&kin, &History::default());
        assert!(u.mu > 0.0 && u.kappa > 0.0);
    }
}
