//! Convergence against exact references (issue 16), coarse: each case at
//! three resolutions, the error falling at each refinement and at an
//! observed order (the least-squares slope of log error against log h)
//! near the one the method should reach: at least 1.8 where linear
//! elements and a second-order scheme give 2 (measured 2.47–2.77), and
//! for the cantilever 1.8 for its frequency (2.03) and 1.5 for its static
//! deflection (1.71: linear triangles lock in bending at two and four
//! cells through the thickness). (Before session 47 the cantilever's root
//! was held by a full clamp, stiffer than its beam-theory references'; it
//! reached 1.82 and 1.53 against them, asserted 1.5 and 1.3.) Until
//! session 39 every case asserted only 0.9, which an
//! order lost would have passed. The dam break's self-convergence asserts
//! 0.9 against a finer run of its own, which overstates an order
//! (`docs/accuracy-cost.md`). The full sweeps, with
//! wall time, are in `examples/accuracy_cost.rs` and
//! `docs/accuracy-cost.md`. Run with `cargo test --release --test
//! suite convergence:: -- --nocapture` (the dam break's self-convergence:
//! `-- --ignored`).

use pfem::cases::{rest_figures, RestTank};
use pfem::exact::{observed_order, Cantilever, CircularCouette, DamBreakFront, StandingWave};
use pfem::prelude::*;

/// Asserts that `errors` (at spacings `h`, coarsest first) fall at each
/// refinement and at an observed order ≥ `min_order`; returns the order.
fn assert_converges(name: &str, h: &[f64], errors: &[f64], min_order: f64) -> f64 {
    let pts: Vec<(f64, f64)> = h.iter().copied().zip(errors.iter().copied()).collect();
    let order = observed_order(&pts);
    eprintln!("{name}: h {h:?}, errors {errors:?}, observed order {order:.2}");
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "{name}: error does not fall: {errors:?}");
    }
    assert!(
        order >= min_order,
        "{name}: observed order {order} (at least {min_order})"
    );
    order
}

#[test]
fn circular_couette_converges() {
    let (mut h, mut e) = (Vec::new(), Vec::new());
    for n in [4, 8, 16] {
        let case = CircularCouette {
            cells: n,
            ..Default::default()
        };
        let r = case.run(StepParams::default()).unwrap();
        h.push(case.spacing());
        e.push(r.error);
    }
    assert_converges("circular Couette (steady velocity RMS)", &h, &e, 1.8);
}

#[test]
fn standing_wave_frequency_and_amplitude_converge() {
    let (mut h, mut e, mut a) = (Vec::new(), Vec::new(), Vec::new());
    for n in [10, 20, 40] {
        let case = StandingWave {
            cells: n,
            ..Default::default()
        };
        let r = case.run(StepParams::default()).unwrap();
        eprintln!(
            "standing wave {n} cells: ω = {:.4} rad/s, linear theory {:.4}; decay error {:.3e}",
            r.value,
            case.omega(),
            r.second_error
        );
        h.push(case.spacing());
        e.push(r.error);
        a.push(r.second_error);
    }
    assert_converges("standing wave (frequency)", &h, &e, 1.8);
    assert_converges("standing wave (amplitude decay over T/2)", &h, &a, 1.8);
}

#[test]
fn cantilever_static_deflection_and_frequency_converge() {
    let (mut h, mut es, mut ev) = (Vec::new(), Vec::new(), Vec::new());
    for n in [2, 4, 8] {
        let case = Cantilever {
            cells: n,
            ..Default::default()
        };
        h.push(case.spacing());
        es.push(case.run_static(StepParams::default()).unwrap().error);
        ev.push(
            case.run_vibration(StepParams::default(), 1.5, 40)
                .unwrap()
                .error,
        );
    }
    assert_converges("cantilever (static tip deflection)", &h, &es, 1.5);
    assert_converges("cantilever (first frequency)", &h, &ev, 1.8);
}

/// Water at rest is reproduced exactly: linear pressure is in the P1
/// space and the lattice is a discrete equilibrium, so there is no order
/// to observe; the error stays at round-off at every resolution.
#[test]
fn water_at_rest_is_exact_at_every_resolution() {
    for h in [0.1, 0.05, 0.025] {
        let case = RestTank {
            spacing: h,
            end_time: 0.5,
            ..Default::default()
        };
        let mut sim = Simulation::new(
            case.scene(),
            Box::new(Delaunay2::default()),
            StepParams::default(),
        )
        .unwrap();
        sim.run(&mut []).unwrap();
        let f = rest_figures(&sim, case.depth);
        eprintln!(
            "water at rest, h = {h}: pressure RMS error {:.2e}, largest speed {:.2e} √(gH)",
            f.pressure_rms, f.max_speed
        );
        assert!(f.pressure_rms < 1e-9, "h = {h}: {}", f.pressure_rms);
        assert!(f.max_speed < 1e-9, "h = {h}: {}", f.max_speed);
    }
}

/// `cargo test --release --test suite convergence::dam_break -- --ignored`
#[test]
#[ignore = "long: the reference run at a/32 takes about 40 s"]
fn dam_break_front_converges_to_a_finer_run() {
    let fine = DamBreakFront {
        cells: 32,
        ..Default::default()
    };
    let (reference, _) = fine.run(StepParams::default(), 0.5).unwrap();
    let (mut h, mut e) = (Vec::new(), Vec::new());
    for n in [8, 11, 16] {
        let case = DamBreakFront {
            cells: n,
            ..Default::default()
        };
        let (front, _) = case.run(StepParams::default(), 0.5).unwrap();
        h.push(1.0 / n as f64);
        e.push(case.difference(&front, &reference));
    }
    assert_converges("dam break front (against a/32)", &h, &e, 0.9);
}
