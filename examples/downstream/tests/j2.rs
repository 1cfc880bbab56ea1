//! The J2 material against its closed forms, and in a simulation.
//! `cargo test --release -p pfem-downstream-example`

use pfem::constitutive::{History, Kinematics, Material};
use pfem::core::Tensor;
use pfem_downstream_example::{J2Plastic, PLASTIC_STRAIN};

const E: f64 = 2.0e8;
const NU: f64 = 0.3;
const SY: f64 = 2.0e5;
const H: f64 = 5.0e7;

fn material() -> J2Plastic {
    J2Plastic::new(1000.0, E, NU, SY, H).unwrap()
}

/// Uniaxial stress in 3D: stretch along x by equal log-strain steps, the
/// lateral stretch found each step so that the lateral stress vanishes.
/// Closed form in logarithmic strain ε: `σ = E ε` below yield,
/// `σ = (ε + σ_y/H) / (1/E + 1/H)` above; the plastic strain is
/// `(σ − σ_y)/H`. Within 10⁻⁶ of the yield stress at every step.
#[test]
fn uniaxial_stress_follows_the_closed_form() {
    let m = material();
    let steps = 400;
    let total = 0.01; // log strain, 10× the yield strain
    let de = total / steps as f64;
    let dt = 1e-3;
    let mut h = History::<3>::default();
    let mut worst: f64 = 0.0;
    for k in 1..=steps {
        // Lateral log-strain increment: secant iteration on σ_yy = 0.
        let stress_for = |lat: f64, h: &History<3>| {
            let f = Tensor::<3>::from_diagonal(&pfem::core::Vector::<3>::new(
                de.exp(),
                lat.exp(),
                lat.exp(),
            ));
            let kin = Kinematics::new(f, (f - Tensor::<3>::identity()) / dt, dt);
            let mut h2 = *h;
            m.update_history(&kin, &mut h2);
            h2
        };
        let (mut a, mut b) = (-NU * de, -0.5 * de);
        let (mut fa, mut fb) = (
            stress_for(a, &h).stress[(1, 1)],
            stress_for(b, &h).stress[(1, 1)],
        );
        for _ in 0..60 {
            if fb.abs() <= 1e-9 || fb == fa {
                break;
            }
            let c = b - fb * (b - a) / (fb - fa);
            a = b;
            fa = fb;
            b = c;
            fb = stress_for(b, &h).stress[(1, 1)];
        }
        h = stress_for(b, &h);
        let eps = de * k as f64;
        let want = if E * eps <= SY {
            E * eps
        } else {
            (eps + SY / H) / (1.0 / E + 1.0 / H)
        };
        let err = (h.stress[(0, 0)] - want).abs() / SY;
        worst = worst.max(err);
        let ep_want = ((want - SY) / H).max(0.0);
        assert!(
            (h.internal[PLASTIC_STRAIN] - ep_want).abs() < 1e-6 * SY / E,
            "plastic strain {} vs {ep_want} at ε = {eps}",
            h.internal[PLASTIC_STRAIN]
        );
    }
    println!("uniaxial: worst stress error {worst:.2e} of the yield stress");
    assert!(worst < 1e-6, "worst error {worst}");
}

/// Pure shear in 2D plane strain, `F = diag(e^ε, e^−ε)`: no rotation, no
/// volume change, `σ_xx − σ_yy = 2q/√3` with `q = 3G ε_eq` below yield
/// (`ε_eq = 2ε/√3`) and `q = σ_y + H ε̄ᵖ`,
/// `ε̄ᵖ = (3G ε_eq − σ_y)/(3G + H)` above. Within 10⁻⁶ of the yield stress.
#[test]
fn pure_shear_follows_the_closed_form() {
    let m = material();
    let g = E / (2.0 * (1.0 + NU));
    let steps = 300;
    let de = 0.01 / steps as f64;
    let dt = 1e-3;
    let mut h = History::<2>::default();
    let mut worst: f64 = 0.0;
    for k in 1..=steps {
        let f = Tensor::<2>::new(de.exp(), 0.0, 0.0, (-de).exp());
        let kin = Kinematics::new(f, (f - Tensor::<2>::identity()) / dt, dt);
        m.update_history(&kin, &mut h);
        let eps = de * k as f64;
        let e_eq = 2.0 * eps / 3f64.sqrt();
        let ep = ((3.0 * g * e_eq - SY) / (3.0 * g + H)).max(0.0);
        let q = if ep > 0.0 {
            SY + H * ep
        } else {
            3.0 * g * e_eq
        };
        let want = 2.0 * q / 3f64.sqrt();
        let got = h.stress[(0, 0)] - h.stress[(1, 1)];
        worst = worst.max((got - want).abs() / SY);
        assert!((h.internal[PLASTIC_STRAIN] - ep).abs() < 1e-6 * SY / E);
        assert!(
            h.stress.trace().abs() + h.stress_zz.abs() < 1e-6 * SY,
            "pressure appeared"
        );
    }
    println!("pure shear: worst stress error {worst:.2e} of the yield stress");
    assert!(worst < 1e-6, "worst error {worst}");
}

/// A rigid rotation changes neither the plastic strain nor the stress's
/// invariants: objectivity.
#[test]
fn a_rigid_rotation_only_rotates_the_stress() {
    let m = material();
    let mut h = History::<2> {
        stress: Tensor::<2>::new(3.0e5, 1.0e5, 1.0e5, -2.0e5),
        ..History::default()
    };
    h.internal[PLASTIC_STRAIN] = 0.01;
    let th: f64 = 0.7;
    let r = Tensor::<2>::new(th.cos(), -th.sin(), th.sin(), th.cos());
    let kin = Kinematics::new(r, Tensor::<2>::zeros(), 1e-3);
    let before = h;
    m.update_history(&kin, &mut h);
    let want = r * before.stress * r.transpose();
    assert!((h.stress - want).norm() < 1e-9 * want.norm());
    assert_eq!(h.internal[PLASTIC_STRAIN], 0.01);
    assert_eq!(
        <J2Plastic as Material<2>>::internal_variables(&m),
        ["equivalent_plastic_strain"]
    );
}

/// In a simulation: a cantilever loaded past yield deflects more than the
/// elastic one, only elements near the clamp yield, and the monitor hook
/// saw the plastic strain grow.
#[test]
fn a_cantilever_past_yield_deflects_more_than_an_elastic_one() {
    use pfem::prelude::*;
    use pfem_downstream_example::{cantilever, PlasticityMonitor};
    let (e, nu, rho) = (5.6e6, 0.4, 1000.0);
    let (elastic, _) = cantilever(Box::new(Hypoelastic::new(rho, e, nu).unwrap()), None).unwrap();
    let monitor = PlasticityMonitor::new(0.5);
    let record = monitor.record();
    let j2 = J2Plastic::new(rho, e, nu, 2.5e4, 1.0e6).unwrap();
    let (plastic, sim) = cantilever(Box::new(j2), Some(monitor)).unwrap();
    let r = record.lock().unwrap();
    println!(
        "tip: elastic {:.3} mm, J2 {:.3} mm; {} of {} elements yielded, largest plastic strain {:.3e}",
        1e3 * elastic,
        1e3 * plastic,
        r.yielded,
        sim.elements().n_solid(),
        r.largest
    );
    assert!(
        plastic < elastic,
        "plastic tip {plastic} vs elastic {elastic}"
    );
    assert!(r.yielded > 0 && r.yielded < sim.elements().n_solid() / 2);
    assert!(r.largest > 0.0 && r.history.windows(2).all(|w| w[1].1 >= w[0].1 - 1e-15));
    // Only near the clamp: every yielded element within a third of the span.
    let x = sim.particles().x();
    for (el, h) in sim
        .elements()
        .solid()
        .chunks_exact(3)
        .zip(sim.elements().solid_history())
    {
        if h.internal[PLASTIC_STRAIN] > 0.0 {
            let cx = el.iter().map(|&i| x[i as usize].x).sum::<f64>() / 3.0;
            assert!(cx < 0.35 / 3.0, "yielded at x = {cx}");
        }
    }
}

/// The monitor's record goes into checkpoints and comes back: a restarted
/// run goes on with it.
#[test]
fn the_monitor_record_survives_a_checkpoint() {
    use pfem::checkpoint::{Decoder, Encoder};
    use pfem::hooks::Hook;
    use pfem_downstream_example::{PlasticityMonitor, PlasticityRecord};
    let a = PlasticityMonitor::new(0.5);
    *a.record().lock().unwrap() = PlasticityRecord {
        largest: 0.25,
        yielded: 7,
        history: vec![(0.5, 0.1), (1.0, 0.25)],
    };
    let mut e = Encoder::new();
    Hook::<2>::save_state(&a, &mut e);
    let bytes = e.finish();
    let mut b = PlasticityMonitor::new(0.5);
    let mut d = Decoder::new(&bytes);
    Hook::<2>::restore_state(&mut b, &mut d).unwrap();
    d.end().unwrap();
    let ra = a.record().lock().unwrap().clone();
    let rb = b.record().lock().unwrap().clone();
    assert_eq!(ra, rb);
}
