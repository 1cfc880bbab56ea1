//! Hertz (issue 19): an elastic ball thrown at a rigid floor, no gravity,
//! no friction, the undamped trapezoidal rule. Its contact lasts Hertz's
//! `t = 2.868 (m² / (R E*² v))^{1/5}` (`E* = E / (1 − ν²)` against a rigid
//! floor) within 20 %, it does not close more than 5 % of the gap to the
//! floor's particles, and it leaves with its energy within 5 %.
//!
//! The ball is sampled on shells (`Geometry::Ball` for a solid,
//! `pfem::lattice::shell_points`) and the contact stiffness is 30
//! times the default. Measured (2 December 2026, R = 8 h, 1 m/s):
//!
//! | ball | `K_c` | contact (Hertz 15.41 ms) | gap closed | rebound |
//! |---|---|---|---|---|
//! | shells | default (1.35 MPa) | 14.6 ms (−5.3 %) | 15.5 % | 1.004 |
//! | shells | 10 × | 14.0 ms (−9.2 %) | 7.4 % | 1.024 |
//! | shells | 30 × | 13.8 ms (−10.5 %) | 1.6 % | 1.007 |
//! | lattice (`Geometry::Ball`) | default | — | passes through | — |
//! | lattice | 10 × | — | the step collapses at 13.7 ms | — |
//!
//! Since the penalty's rounded onset (session 37, 5 December 2026), the
//! shells at 30 ×: 14.0 ms (−9.2 %), 2.1 % of the gap closed, rebound
//! kinetic energy ×1.036 (unchanged by session 38).
//!
//! A lattice ball meets the floor with one particle a spacing below a flat
//! disk of about 45 (its next layer): that particle alone carries the
//! load until the disk comes within reach, and the point load crushes the
//! ball's own elements round it (a barrier law `K_c (g₀/g − 1)` in place
//! of the linear penalty did not stop it: it is the ball's mesh that
//! gives). Solid balls are therefore sampled on shells; a lattice ball from
//! `Geometry::Ball` passed through the floor before
//! (`a_solid_ball_does_not_pass_through_a_floor`). Solid cylinders
//! (`Geometry::Cylinder`) are still lattices.
//!
//! The whole energy (kinetic and strain) is not kept: a known gap, the
//! last test below.
//!
//! `cargo test --release --test suite hertz_3d:: -- --ignored --nocapture` (2 min)

use pfem::constitutive::Hypoelastic;
use pfem::prelude::*;

/// What [`throw`] measured.
struct Bounce {
    /// Contact duration and Hertz's (s).
    duration: Option<f64>,
    hertz: f64,
    /// The lowest any ball particle came, over the spacing (the floor's top
    /// row is at 0).
    deepest: f64,
    /// Vertical velocity of the ball's centre of mass at the end (m/s).
    vy: f64,
    /// Kinetic plus strain energy at the end over the start.
    energy: f64,
}

/// Mass of each particle (lumped from the solid's own elements, `ρ V₀ / 4`
/// each with `V₀` the initial volume, as the solver's, eq. 46) and the
/// strain energy `Σ V ((1 + ν) σ:σ − ν (tr σ)²) / (2E)` of the solid's
/// elements.
fn masses_and_strain(s: &Simulation<3>, rho: f64, young: f64, nu: f64) -> (Vec<f64>, f64) {
    let x = s.particles().x();
    let el = s.elements();
    let mass = crate::stability_support::solid_masses(s, rho);
    let mut strain = 0.0;
    for (e, h) in el.solid().chunks_exact(4).zip(el.solid_history()) {
        let p: Vec<Point<3>> = e.iter().map(|&i| x[i as usize]).collect();
        let vol = pfem::core::simplex_measure::<3>(&p);
        let sig = h.stress;
        let tr = sig.trace();
        strain += vol * ((1.0 + nu) * sig.norm_squared() - nu * tr * tr) / (2.0 * young);
    }
    (mass, strain)
}

/// A ball of radius `r` (particle spacing `h`, `Geometry::Ball`) thrown at
/// a rigid floor at 1 m/s from two spacings above it, with contact
/// stiffness `k_c` (`None`: the default), to 0.03 s.
fn throw(h: f64, r: f64, k_c: Option<f64>) -> Bounce {
    let (rho, young, nu, v0) = (1000.0, 1e6, 0.3, 1.0);
    let e_star = young / (1.0 - nu * nu);
    let floor = 1.5 * r;
    let mut scene = Scene::<3>::new("ball")
        .settings(RunSettings {
            end_time: 0.03,
            max_dt: 2e-4,
            output_interval: None,
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<3>::new(-floor, -h, -floor),
                max: Point::<3>::new(floor, 0.0, floor),
            },
            h,
            WallMotion::Fixed,
        )
        .solid(
            "ball",
            Box::new(Hypoelastic::new(rho, young, nu).unwrap()),
            Geometry::Ball {
                center: Point::<3>::new(0.0, r + 2.0 * h, 0.0),
                radius: r,
            },
            h,
            None,
        )
        .with_velocity(Vector::<3>::new(0.0, -v0, 0.0))
        .contact_damping(0.0);
    if let Some(k) = k_c {
        scene = scene.contact_stiffness(k);
    }
    let params = StepParams {
        scheme: Scheme::Newmark,
        ..StepParams::default()
    };
    let mut s = Simulation::new(scene, Box::new(Delaunay3::default()), params).unwrap();
    let ball = s.body_particles("ball").unwrap();
    // The ball's mass: its particles' lumped masses are not exposed; the
    // ball's measured volume (its own mesh) times ρ.
    let volume: f64 = s
        .elements()
        .solid()
        .chunks_exact(4)
        .map(|e| {
            let p: Vec<Point<3>> = e.iter().map(|&i| s.particles().x()[i as usize]).collect();
            pfem::core::simplex_measure::<3>(&p)
        })
        .sum();
    let m = rho * volume;
    let hertz = 2.868 * (m * m / (r * e_star * e_star * v0)).powf(0.2);
    let total_energy = |s: &Simulation<3>| {
        let (mass, strain) = masses_and_strain(s, rho, young, nu);
        let v = s.particles().v();
        strain
            + ball
                .iter()
                .map(|&i| 0.5 * mass[i] * v[i].norm_squared())
                .sum::<f64>()
    };
    let e0 = total_energy(&s);
    let (mut t_on, mut t_off) = (None, None);
    let mut deepest = f64::INFINITY;
    while s.time() < s.end_time() - 1e-12 {
        s.step().unwrap();
        for &i in &ball {
            deepest = deepest.min(s.particles().x()[i][1]);
        }
        let pushing = s.contact_force("ball", "floor").unwrap().normal > 0.0;
        if pushing && t_on.is_none() {
            t_on = Some(s.time() - s.dt());
        }
        if !pushing && t_on.is_some() && t_off.is_none() {
            t_off = Some(s.time() - s.dt());
        }
    }
    // The centre of mass's velocity: the particles' lumped masses differ
    // (a shell particle's is about half an inner one's), so the plain mean
    // of their velocities moves with the ball's vibration.
    let (mass, _) = masses_and_strain(&s, rho, young, nu);
    let m_ball: f64 = ball.iter().map(|&i| mass[i]).sum();
    let vy = ball
        .iter()
        .map(|&i| mass[i] * s.particles().v()[i][1])
        .sum::<f64>()
        / m_ball;
    let energy = total_energy(&s) / e0;
    let duration = t_off.zip(t_on).map(|(b, a)| b - a);
    println!(
        "ball R = {:.1} h, K_c {k_c:?}: {} particles, {} steps ({} rejected); m {m:.4} kg; contact {:?} s against Hertz {hertz:.5} s; deepest point {:.3} h above the floor's top row; rebound {vy:.4} m/s (rigid kinetic energy ratio {:.3}; kinetic and strain energy ratio {energy:.4})",
        r / h,
        ball.len(),
        s.steps(),
        s.rejected(),
        duration,
        deepest / h,
        (vy / v0).powi(2)
    );
    Bounce {
        duration,
        hertz,
        deepest: deepest / h,
        vy,
        energy,
    }
}

#[test]
#[ignore = "2 minutes: cargo test --release --test suite hertz_3d:: -- --ignored --nocapture"]
fn an_elastic_ball_bounces_off_a_floor_for_hertz_s_contact_time() {
    // 30 times the default (the ball's P-wave modulus, 1.35 MPa).
    let b = throw(0.00625, 0.05, Some(4.05e7));
    let duration = b.duration.expect("the ball did not leave the floor");
    assert!(
        (duration / b.hertz - 1.0).abs() < 0.2,
        "{duration} against {}",
        b.hertz
    );
    assert!(b.deepest > 0.95, "closed the gap to {} h", b.deepest);
    // The rigid motion's kinetic energy after the bounce against before.
    let energy = b.vy.powi(2);
    assert!(
        (energy - 1.0).abs() < 0.05,
        "rebound {} m/s: energy ratio {energy}",
        b.vy
    );
}

/// The bug this fixed: a solid `Geometry::Ball` was a lattice, and at the
/// default contact stiffness a ball R = 8 h thrown at 1 m/s passed through
/// the floor (its lowest particle 3.7 h below the floor's top row) after
/// its lowest particle alone met the floor and crushed the elements round
/// it. Sampled on shells a smaller ball (R = 4 h, quicker) bounces at the
/// default stiffness and stays above the floor.
#[test]
fn a_solid_ball_does_not_pass_through_a_floor() {
    let b = throw(0.0125, 0.05, None);
    assert!(b.duration.is_some(), "the ball did not leave the floor");
    assert!(b.vy > 0.5, "rebound {} m/s", b.vy);
    assert!(b.deepest > 0.5, "the ball came to {} h", b.deepest);
}

/// The bug this fixed (session 56): a contact tetrahedron's gap was the
/// height over the master facet's plane (3 + 1) or the distance between
/// the two edges' lines (2 + 2), so where a curved ball's particle stood
/// beside the floor's triangle, or a ball's edge slanted across a floor
/// edge, the element formed already closed, and each remeshing stored
/// penalty energy that no motion had put in. The ball R = 4 h at the
/// default stiffness left with ×1.132 of its kinetic and strain energy
/// and stayed in contact 18.2 ms against Hertz's 15.27 ms; with the gap
/// to the facet itself, ×1.017 and 15.4 ms (×1.016 and 15.2 ms with the
/// 3D reach of 1.8 spacings since). (A ball R = 2.5 h dropped
/// from a scene file gained 22 % on its first bounce, and lost 3 % with
/// the dashpot since.)
#[test]
fn a_ball_at_the_default_stiffness_keeps_its_energy_and_hertz_s_contact_time() {
    let b = throw(0.0125, 0.05, None);
    let duration = b.duration.expect("the ball did not leave the floor");
    assert!(
        (duration / b.hertz - 1.0).abs() < 0.1,
        "contact {duration} s against Hertz's {} s",
        b.hertz
    );
    assert!(
        (b.energy - 1.0).abs() < 0.05,
        "kinetic and strain energy after over before: {}",
        b.energy
    );
}

/// The ball's whole energy, kinetic (every particle's) and strain, after
/// the bounce against before. Since session 56 (the gap to the master's
/// facet, not its plane: the test above) ×1.040, rigid ×1.013, contact
/// 14.0 ms, and ×1.028 (rigid ×1.012) with the 3D reach of 1.8 spacings:
/// within the bound. Before, a known gap (sessions 39–40). Since session
/// 40 a solid element weighs its initial volume (eq. 46): the whole energy
/// is ×1.061 (rigid ×1.016) at the test's step, the ledger falling to
/// 0.948 under load and rising to 1.058 as the ball leaves; Bossak ×1.017.
/// The rest of this note is session 39's, with the masses following the
/// volume. The test above
/// bounds the rigid motion's kinetic energy (×1.035, the centre of mass's
/// velocity); the whole energy is ×1.269 at the test's step (2·10⁻⁴ s),
/// the ball leaving in strong vibration. A ledger per step (a scratch
/// driver adding the contact layers' stored energy, `V* ∫p dx`) shows it
/// falling to 0.937 of the start while the ball is pressed and rising to
/// 1.227 as it leaves, in jumps of up to 6 % a step, also once the contact
/// layer holds under 1 % of the energy. With the penalty's kink instead
/// of its rounded onset (`contact_onset(0)`) it is ×1.049; at the default
/// stiffness (30 times less) ×1.019; with Bossak's scheme ×1.017 (kink
/// ×1.020); at a step of 10⁻⁴ s the undamped run stops at t = 0.019 s (kink:
/// 0.012 s) with an inverted element, while Bossak's gives ×1.018. A free
/// ball vibrating without contact keeps 0.95 of its energy over the same
/// time. Carrying the closure of an element that the next tessellation
/// forms on the same particles (so that its pressure is a function of its
/// volume alone) did not cure it (the run stopped at t = 0.017 s). The 2D
/// disk of `tests/contact.rs` keeps its energy to +0.18 %.
/// `cargo test --release --test suite hertz_3d:: -- --ignored --nocapture`
#[test]
#[ignore = "2 minutes: cargo test --release --test suite hertz_3d:: -- --ignored --nocapture"]
fn an_elastic_ball_leaves_with_the_energy_it_came_with() {
    let b = throw(0.00625, 0.05, Some(4.05e7));
    assert!(
        (b.energy - 1.0).abs() < 0.05,
        "kinetic and strain energy after over before: {}",
        b.energy
    );
}
