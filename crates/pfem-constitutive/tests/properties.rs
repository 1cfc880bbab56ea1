//! Property tests of the built-in laws over random kinematics near the
//! identity, random histories and random valid parameters, in 2D and 3D.

use pfem_constitutive::{
    Const, Dim, History, Hypoelastic, Kinematics, Material, Newtonian, Tensor,
};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

/// Nine random numbers, enough for a 3×3 tensor.
fn nine(range: f64) -> impl Strategy<Value = [f64; 9]> {
    prop::array::uniform9(-range..range)
}

fn tensor<const D: usize>(a: &[f64; 9]) -> Tensor<D>
where
    Const<D>: Dim,
{
    Tensor::<D>::from_fn(|i, j| a[3 * i + j])
}

fn sym<const D: usize>(a: &[f64; 9]) -> Tensor<D>
where
    Const<D>: Dim,
{
    let t = tensor::<D>(a);
    (t + t.transpose()) * 0.5
}

fn is_symmetric<const D: usize>(t: &Tensor<D>) -> bool
where
    Const<D>: Dim,
{
    *t == t.transpose()
}

/// `F = I + A`, `D = sym B`, with a positive Jacobian.
fn kinematics<const D: usize>(a: &[f64; 9], b: &[f64; 9], dt: f64) -> Kinematics<D>
where
    Const<D>: Dim,
{
    Kinematics::new(Tensor::<D>::identity() + tensor::<D>(a), sym::<D>(b), dt)
}

#[derive(Debug, Clone, Copy)]
struct Case {
    f: [f64; 9],
    d: [f64; 9],
    stress: [f64; 9],
    stress_zz: f64,
    pressure: f64,
    dt: f64,
}

fn cases() -> impl Strategy<Value = Case> {
    (
        nine(0.25),
        nine(50.0),
        nine(1.0e7),
        -1.0e7..1.0e7,
        -1.0e7..1.0e7,
        -6.0..-2.0f64,
    )
        .prop_map(|(f, d, stress, stress_zz, pressure, log_dt)| Case {
            f,
            d,
            stress,
            stress_zz,
            pressure,
            dt: 10f64.powf(log_dt),
        })
}

/// `(ρ, E, ν)` over the valid range, moduli log-uniform.
fn solid_params() -> impl Strategy<Value = (f64, f64, f64)> {
    (0.0..4.5f64, 2.0..12.0f64, -0.999..0.4999f64)
        .prop_map(|(lr, le, nu)| (10f64.powf(lr), 10f64.powf(le), nu))
}

/// `(ρ, μ_f, K_f)`, with zero viscosity possible.
fn fluid_params() -> impl Strategy<Value = (f64, f64, f64)> {
    (
        0.0..4.5f64,
        prop_oneof![Just(0.0), (-6.0..3.0f64).prop_map(|l| 10f64.powf(l))],
        3.0..10.0f64,
    )
        .prop_map(|(lr, mu, lk)| (10f64.powf(lr), mu, 10f64.powf(lk)))
}

fn check_solid<const D: usize>(params: (f64, f64, f64), c: Case) -> Result<(), TestCaseError>
where
    Const<D>: Dim,
{
    let solid = Hypoelastic::new(params.0, params.1, params.2).unwrap();
    let kin = kinematics::<D>(&c.f, &c.d, c.dt);
    prop_assume!(kin.j > 0.2);
    let h0 = History::<D> {
        stress: sym::<D>(&c.stress),
        stress_zz: if D == 2 { c.stress_zz } else { 0.0 },
        pressure: c.pressure,
        ..History::default()
    };
    let u = solid.unified(&kin, &h0);
    prop_assert!(u.mu.is_finite() && u.mu > 0.0);
    prop_assert!(u.kappa.is_finite() && u.kappa > 0.0);
    prop_assert!(u.sigma_hat.iter().all(|x| x.is_finite()));
    prop_assert!(u.sigma_hat_zz.is_finite());
    prop_assert!(is_symmetric(&u.sigma_hat));

    let mut h = h0;
    solid.update_history(&kin, &mut h);
    prop_assert!(h.stress.iter().all(|x| x.is_finite()) && h.stress_zz.is_finite());
    prop_assert!(is_symmetric(&h.stress));
    // update_history stores eq. 43 of the unified triple (eq. 63), to
    // rounding: σ̂ is the stress after the displacement less its part linear
    // in the velocity, which eq. 43 adds back.
    let linear = u.kappa * kin.volumetric_rate().abs() + 2.0 * u.mu * kin.d.norm();
    let scale = h.stress.norm() + h.stress_zz.abs() + linear + 1e-300;
    prop_assert!(
        (h.stress - u.cauchy_stress(&kin)).norm() <= 1e-12 * scale,
        "{} vs {}",
        h.stress,
        u.cauchy_stress(&kin)
    );
    prop_assert!((h.stress_zz - u.cauchy_stress_zz(&kin)).abs() <= 1e-12 * scale);
    // The stress follows the displacement only: the rate of the iterate
    // changes the split of σ̂ and the linear part, not the stress.
    let mut h_no_rate = h0;
    solid.update_history(
        &Kinematics {
            d: Tensor::<D>::zeros(),
            ..kin
        },
        &mut h_no_rate,
    );
    prop_assert_eq!(h_no_rate.stress, h.stress);
    prop_assert_eq!(h.pressure, c.pressure);
    if D == 3 {
        prop_assert_eq!(h.stress_zz, 0.0);
    }
    Ok(())
}

fn check_fluid<const D: usize>(params: (f64, f64, f64), c: Case) -> Result<(), TestCaseError>
where
    Const<D>: Dim,
{
    let fluid = Newtonian::new(params.0, params.1, params.2).unwrap();
    let kin = kinematics::<D>(&c.f, &c.d, c.dt);
    let h0 = History::<D> {
        pressure: c.pressure,
        ..History::default()
    };
    let u = fluid.unified(&kin, &h0);
    prop_assert!(u.mu.is_finite() && u.kappa.is_finite() && u.kappa > 0.0);
    prop_assert_eq!(u.sigma_hat, Tensor::<D>::identity() * -c.pressure);
    let sigma = u.cauchy_stress(&kin);
    prop_assert!(sigma.iter().all(|x| x.is_finite()));
    prop_assert!(is_symmetric(&sigma));

    let mut h = h0;
    fluid.update_history(&kin, &mut h);
    prop_assert!(h.pressure.is_finite());
    prop_assert_eq!(h.stress, h0.stress);
    // −pⁿ⁺¹ is the volumetric part of the unified stress: σ̂ + 𝒦 ε_v (eqs. 26–27).
    let eps_v = kin.volumetric_rate();
    prop_assert_eq!(-h.pressure, u.sigma_hat[(0, 0)] + u.kappa * eps_v);
    // ... and the mean of the full (3×3) Cauchy stress of eq. 43.
    let mean = (sigma.trace() + u.cauchy_stress_zz(&kin)) / 3.0;
    let scale = c.pressure.abs() + u.kappa * eps_v.abs() + u.mu * kin.d.norm() + 1e-300;
    prop_assert!(
        (mean + h.pressure).abs() <= 1e-12 * scale,
        "{} vs {}",
        mean,
        -h.pressure
    );

    // The nodal kinematics d = (ε_v / D) I give the same pressure.
    let nodal = Kinematics {
        d: Tensor::<D>::identity() * (eps_v / D as f64),
        ..kin
    };
    let mut hn = h0;
    fluid.update_history(&nodal, &mut hn);
    let dp = (u.kappa * eps_v).abs() + 1e-300;
    prop_assert!((hn.pressure - h.pressure).abs() <= 1e-12 * (dp + c.pressure.abs()));
    Ok(())
}

proptest! {
    #[test]
    fn solid_2d(p in solid_params(), c in cases()) {
        check_solid::<2>(p, c)?;
    }

    #[test]
    fn solid_3d(p in solid_params(), c in cases()) {
        check_solid::<3>(p, c)?;
    }

    #[test]
    fn solid_from_lame_matches_young_poisson(p in solid_params()) {
        let a = Hypoelastic::new(p.0, p.1, p.2).unwrap();
        let b = Hypoelastic::from_lame(p.0, a.lame_lambda(), a.shear_modulus()).unwrap();
        prop_assert_eq!(a, b);
        prop_assert!((b.young_modulus() - p.1).abs() <= 1e-9 * p.1);
        prop_assert!((b.poisson_ratio() - p.2).abs() <= 1e-9);
    }

    #[test]
    fn fluid_2d(p in fluid_params(), c in cases()) {
        check_fluid::<2>(p, c)?;
    }

    #[test]
    fn fluid_3d(p in fluid_params(), c in cases()) {
        check_fluid::<3>(p, c)?;
    }

    /// Any input, NaN and infinities included: a typed error or a valid
    /// material, never a panic.
    #[test]
    fn constructors_never_panic(a in prop::num::f64::ANY, b in prop::num::f64::ANY, c in prop::num::f64::ANY) {
        match Newtonian::new(a, b, c) {
            Ok(f) => prop_assert!(a > 0.0 && b >= 0.0 && c > 0.0 && f.wave_speed().is_finite()),
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
        match Hypoelastic::new(a, b, c) {
            Ok(s) => {
                prop_assert!(a > 0.0 && b > 0.0 && c > -1.0 && c < 0.5);
                prop_assert!(s.lame_lambda().is_finite() && s.shear_modulus() > 0.0);
                prop_assert!(s.bulk_modulus() > 0.0);
            }
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
        match Hypoelastic::from_lame(a, b, c) {
            Ok(s) => prop_assert!(a > 0.0 && c > 0.0 && s.bulk_modulus() > 0.0),
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
    }
}
