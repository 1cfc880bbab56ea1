//! The `Fidelity` presets meet their documented dam-break front errors
//! (Martin & Moyce 1952, n² = 2, RMS relative error for T ≤ 3 after the
//! best time shift). Release mode:
//! `cargo test --release --test presets` (Draft, Standard);
//! Fine: `cargo test --release --test presets -- --ignored`.
//!
//! Bound: the 5 % front-error target of the dam-break validation (issue 5)
//! for every preset. The runs are deterministic; the study at commit
//! 7d54ae3 (`docs/accuracy-cost.md`) measured a/10 1.4 %, a/20 4.8 %,
//! a/28.6 2.7 %: the front error does not converge with refinement, so
//! Standard passes by only 0.2 points and any library change that moves it
//! will show here.

use pfem::cases::{best_shift, DamBreak, G};
use pfem::fidelity::Fidelity;
use pfem::output::{parse_reference_csv, reference};
use pfem::prelude::*;

/// Front error and wall time of the dam break at preset `f`.
fn front_error(f: Fidelity) -> (f64, f64) {
    let mut case = DamBreak::default();
    case.spacing = f.spacing(case.spacing);
    let t_scale = (2.0 * G / case.width).sqrt();
    case.end_time = 3.0 / t_scale;
    let mut scene = case.scene();
    f.apply(&mut scene.settings);
    scene.settings.output_interval = None;
    let mut sim = Simulation::new(scene, Box::new(Delaunay2::default()), f.step_params())
        .expect("scene builds");
    let mut out = StandardOutput::new(
        std::env::temp_dir().join(format!("pfem-test-preset-{}", f.name())),
        false,
        case.probes(),
        true,
    )
    .overwrite(true);
    let t0 = std::time::Instant::now();
    sim.run(&mut [&mut out]).expect("run completes");
    let wall = t0.elapsed().as_secs_f64();
    let front: Vec<(f64, f64)> = out
        .probe_series("front_x")
        .iter()
        .map(|&(t, x)| (t * t_scale, x / case.width))
        .collect();
    let measured = parse_reference_csv(reference::MARTIN_MOYCE_N2_2_A2_25IN_FRONT).unwrap();
    let (shift, rms) = best_shift(&front, &measured, 3.0, 0.5, 0.01);
    eprintln!(
        "{}: h = {:.3e} m, C = {}, tol = {:e}: front RMS {:.2}% (shift {shift:+.2}), {} steps ({} rejected), {wall:.1} s",
        f.name(),
        case.spacing,
        f.courant(),
        f.picard_tolerance(),
        100.0 * rms,
        sim.steps(),
        sim.rejected()
    );
    (rms, wall)
}

/// Draft (a/10): study 1.58 % in 0.5 s; bound 5 %.
#[test]
fn draft_front_error_within_five_percent() {
    let (rms, _) = front_error(Fidelity::Draft);
    assert!(rms < 0.05, "front RMS error {rms}");
}

/// Standard (a/20): study 1.72 % in 11.8 s; bound 5 %.
#[test]
fn standard_front_error_within_five_percent() {
    let (rms, _) = front_error(Fidelity::Standard);
    assert!(rms < 0.05, "front RMS error {rms}");
}

/// Fine (a/28.6): study 1.54 % in 36 s; bound 5 %.
/// `cargo test --release --test presets -- --ignored`
#[test]
#[ignore = "slow: about 40 s"]
fn fine_front_error_within_five_percent() {
    let (rms, _) = front_error(Fidelity::Fine);
    assert!(rms < 0.05, "front RMS error {rms}");
}
