//! The PETSc backend (issue 18, `petsc` feature) gives the pure-Rust
//! solvers' answers: the 2D dam break's front and fluid volume, and the
//! elastic gate's largest deflection, after the same simulated time.
//! Needs PETSc (Debian: `apt-get install libpetsc-real-dev`):
//! `cargo test --release --features petsc --test suite petsc:: -- --nocapture`
#![cfg(feature = "petsc")]

use pfem::assembly::{BlockSolver, LinearSolver};
use pfem::cases::{DamBreak, ElasticGate};
use pfem::petsc::PetscSolver;
use pfem::prelude::*;

/// PETSc's solver with no fallback: a solve it cannot do fails the run,
/// so a passing test means PETSc solved every system itself.
fn petsc() -> Box<dyn LinearSolver> {
    let mut p = PetscSolver::default();
    p.fallback = false;
    Box::new(p)
}

fn dam_break(solver: Box<dyn LinearSolver>, end: f64, alpha: f64) -> (f64, f64, u64, u64) {
    let mut c = DamBreak::default();
    c.spacing = c.width / 10.0;
    let params = StepParams {
        pressure_stabilisation: alpha,
        ..StepParams::default()
    };
    let mut sim = Simulation::new(c.scene(), Box::new(Delaunay2::default()), params).unwrap();
    sim.set_solver(solver);
    sim.set_end_time(end).unwrap();
    sim.run(&mut []).unwrap();
    (
        pfem::cases3d::front_x(&sim),
        sim.fluid_volume(),
        sim.steps(),
        sim.work().solver_iterations,
    )
}

/// The paper's pressure (PETSc's Cholesky on the pressure block) and the
/// stabilised one (hypre's BoomerAMG on it), against the pure-Rust path.
#[test]
fn petsc_gives_the_block_solvers_dam_break() {
    let end = 0.1;
    for alpha in [0.0, 1.0] {
        let (f0, v0, s0, _) = dam_break(Box::new(BlockSolver::default()), end, alpha);
        let (f1, v1, s1, it) = dam_break(petsc(), end, alpha);
        println!(
            "dam break to {end} s, stabilisation {alpha}: front {f0:.6} m (block, {s0} steps) vs {f1:.6} m (petsc, {s1} steps, {it} KSP iterations): {:+.3e}; volume {:+.3e}",
            f1 / f0 - 1.0,
            v1 / v0 - 1.0
        );
        assert!((f1 / f0 - 1.0).abs() < 1e-3, "front {f0} vs {f1}");
        assert!((v1 / v0 - 1.0).abs() < 1e-3, "volume {v0} vs {v1}");
    }
}

fn gate_peak(solver: Box<dyn LinearSolver>, end: f64, dir: &str) -> (f64, u64) {
    let case = ElasticGate {
        end_time: end,
        ..ElasticGate::default()
    };
    let mut sim = Simulation::new(
        case.scene().unwrap(),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    sim.set_solver(solver);
    let out = std::env::temp_dir().join(format!("pfem-petsc-test-{dir}-{}", std::process::id()));
    let mut output = StandardOutput::new(&out, false, case.probes(), true).overwrite(true);
    sim.run(&mut [&mut output]).unwrap();
    let peak = output
        .probe_series("ux_tip")
        .iter()
        .map(|p| p.1)
        .fold(f64::NEG_INFINITY, f64::max);
    let _ = std::fs::remove_dir_all(&out);
    (peak, sim.steps())
}

#[test]
fn petsc_gives_the_block_solvers_elastic_gate() {
    let end = 0.1;
    let (p0, s0) = gate_peak(Box::new(BlockSolver::default()), end, "block");
    let (p1, s1) = gate_peak(petsc(), end, "petsc");
    println!(
        "elastic gate to {end} s: largest tip ux {:.6} mm (block, {s0} steps) vs {:.6} mm (petsc, {s1} steps): {:+.3e}",
        1e3 * p0,
        1e3 * p1,
        p1 / p0 - 1.0
    );
    assert!(p0 > 0.01, "the gate did not bend: {p0}");
    assert!((p1 / p0 - 1.0).abs() < 5e-3, "gate peak {p0} vs {p1}");
}
