//! Release-mode elastic-gate validation (Antoci, Gallati & Sibilla 2007),
//! with the published E = 12 MPa, ν = 0.4. Run with `cargo test --release
//! --test suite validation_elastic_gate::` (the timing gap: `-- --ignored`).
//!
//! The gate is a 2D solid, so the 2D assumption is a modelling choice:
//! plane stress (a thin strip, `σ_zz = 0`; the case's default) or plane
//! strain (`ε_zz = 0`, 19 % stiffer in bending at ν = 0.4). The static tip
//! deflection of a linear cantilever under the initial water load is 45–46
//! mm in plane stress and 38 mm in plane strain, against the measured peak
//! of 46.0 mm at 0.162 s.
//!
//! Measured (water h, gate spacing; to 0.2–0.25 s):
//!
//! | water h | gate h | plane stress | plane strain |
//! |---|---|---|---|
//! | 0.005 m | 1.25 mm | 46.61 mm at 0.125 s (+1.3 %) | 46.59 mm at 0.128 s (+1.2 %) |
//! | 0.0025 m | 0.625 mm | 43.02 mm at 0.111 s (−6.5 %) | |
//! | 0.0025 m | 1.25 mm | 42.36 mm at 0.102 s (−8.0 %) | 39.05 mm at 0.095 s (−15.1 %) |
//!
//! Refining water and gate together (h → h/2) moves the plane-stress peak
//! by −7.7 % (session 50; −11.5 % from session 40 to 49, −9.3 % before). The gate's free end sits one water spacing above the floor,
//! so refining the water also narrows the gap under the gate. The peak
//! comes 0.035–0.06 s before the measured one at every resolution: the
//! known timing gap (a linear elastic gate's wet mode, about 5 Hz, puts
//! its peak near 0.1 s), asserted by an ignored test.

use pfem::cases::ElasticGate;
use pfem::output::{parse_reference_csv, reference};
use pfem::prelude::*;

fn peak(series: &[(f64, f64)]) -> (f64, f64) {
    series.iter().copied().fold(
        (0.0, f64::NEG_INFINITY),
        |b, p| if p.1 > b.1 { p } else { b },
    )
}

/// Peak of the gate's free-end ux `(t, ux)` at water spacing `h` and gate
/// spacing `gate_h`, to 0.2 s.
fn run(h: f64, gate_h: f64, plane_stress: bool) -> (f64, f64) {
    let case = ElasticGate {
        spacing: h,
        gate_spacing: gate_h,
        end_time: 0.2,
        plane_stress,
        ..Default::default()
    };
    let mut sim = Simulation::new(
        case.scene().unwrap(),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    // One folder per call: the tests of this file run the same case at
    // once (`--include-ignored`), and a shared folder made one run's
    // output fail under another's.
    static CALL: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALL.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!(
        "pfem-test-gate-{h}-{gate_h}-{plane_stress}-{}-{call}",
        std::process::id()
    ));
    let mut out = StandardOutput::new(&dir, false, case.probes(), true).overwrite(true);
    sim.run(&mut [&mut out]).unwrap();
    let p = peak(&out.probe_series("ux_tip"));
    // Nothing is left behind in the temporary directory.
    drop(out);
    std::fs::remove_dir_all(&dir).ok();
    eprintln!(
        "gate (water h = {h} m, gate h = {gate_h} m, {}): peak ux {:.2} mm at {:.3} s",
        if plane_stress {
            "plane stress"
        } else {
            "plane strain"
        },
        1e3 * p.1,
        p.0
    );
    p
}

fn measured_peak() -> (f64, f64) {
    let p = peak(&parse_reference_csv(reference::ANTOCI_2007_GATE_UX).unwrap());
    assert!((p.1 - 0.046).abs() < 0.001, "the measured peak is 46 mm");
    p
}

#[test]
fn plane_stress_gate_peaks_within_ten_percent_of_the_measured_46_mm() {
    let (_, ux_exp) = measured_peak();
    let (t, ux) = run(0.005, 0.00125, true);
    let err = ux / ux_exp - 1.0;
    assert!(err.abs() < 0.10, "plane stress: peak ux error {err}");
    assert!(
        (0.08..=0.20).contains(&t),
        "plane stress: peak at {t} s, outside 0.08–0.20 s"
    );
    // The plane-strain figure, reported beside it (not bounded: the
    // assumption is the modelling choice).
    let (ts, uxs) = run(0.005, 0.00125, false);
    eprintln!(
        "plane stress {:+.1} % at {t:.3} s; plane strain {:+.1} % at {ts:.3} s (measured {:.2} mm)",
        100.0 * err,
        100.0 * (uxs / ux_exp - 1.0),
        1e3 * ux_exp
    );
    assert!(uxs.is_finite() && uxs > 0.0);
}

/// `cargo test --release --test suite validation_elastic_gate::refinement`
/// (about 25 s).
///
/// Met since session 50: 46.61 → 43.02 mm at 0.111 s (−7.7 %), once the
/// solid's stress increment was taken at mid-step's volume. A known gap
/// from session 40 to 49: the h/2 peak was 41.96 mm at 0.104 s, the
/// refinement moving it by −11.5 % (bound 10 %); it was 42.97 mm (−9.3 %)
/// before the solid elements weighed `ρ₀ V₀`. The h/2 peak itself moved
/// by 2 % with the Picard tolerance (41.96 mm at 10⁻⁶ and 10⁻⁷, 42.79 mm
/// at 3·10⁻⁶), so the bound sits within the run's own spread.
#[test]
fn refinement_from_h_to_half_h_moves_the_peak_by_less_than_ten_percent() {
    let (_, ux_exp) = measured_peak();
    let (_, coarse) = run(0.005, 0.00125, true);
    let (t, fine) = run(0.0025, 0.000625, true);
    let change = fine / coarse - 1.0;
    eprintln!(
        "refinement h → h/2: {:.2} → {:.2} mm ({:+.1} %)",
        1e3 * coarse,
        1e3 * fine,
        100.0 * change
    );
    assert!(change.abs() < 0.10, "refinement moves the peak by {change}");
    assert!((fine / ux_exp - 1.0).abs() < 0.10, "h/2 peak {fine}");
    assert!((0.08..=0.20).contains(&t), "h/2 peak at {t} s");
}

/// `cargo test --release --test suite validation_elastic_gate::gate_peak_time -- --ignored`
#[test]
#[ignore = "known gap: the simulated peak comes 0.035–0.06 s before the measured one (bound 0.03 s)"]
fn gate_peak_time_within_three_hundredths_of_a_second() {
    let (t_exp, _) = measured_peak();
    let (t, _) = run(0.005, 0.00125, true);
    assert!(
        (t - t_exp).abs() < 0.03,
        "peak at {t} s, measured {t_exp} s"
    );
}
