//! Water at rest in an open tank (issue 13's 2D case): 1 m wide, 0.5 m of
//! water, walls on three sides. Prints the largest and RMS fluid speed (in
//! √(gH)), the RMS pressure error against ρ g (H − y) below the free-surface
//! layer, and the fluid volume change, at intervals. The test
//! `tests/water_at_rest_2d.rs` asserts the issue's bounds on the same tank.
//!
//! ```text
//! cargo run --release --example rest_tank_2d -- [--spacing H] [--end-time T]
//! ```

use pfem::cases::{rest_figures, RestTank};
use pfem::cli::Args;
use pfem::prelude::*;

/// This example's own options, for `--help`: none.
const OPTIONS: &str =
    "  (none: it prints its figures and writes no files, so --out and --overwrite do not apply)";

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env_with(OPTIONS)?;
    args.reject_unknown(&[])?;
    args.reject_output_options("rest_tank_2d")?;
    let case = RestTank {
        spacing: args.spacing.unwrap_or(0.025),
        end_time: args.end_time.unwrap_or(2.0),
        ..RestTank::default()
    };
    let (end, depth) = (case.end_time, case.depth);
    let scene = case.scene();
    let mut sim = args.simulation(scene, Box::new(Delaunay2::default()))?;
    let v0 = sim.fluid_volume();
    let report = |sim: &Simulation<2>| {
        let f = rest_figures(sim, depth);
        let at = sim.particles().x()[f.fastest];
        pfem::outln!(
            "t = {:6.3} s  steps {:5}  max speed {:.2e} sqrt(gH) at {:.3?}  rms {:.2e}  pressure rms err {:.3} %  volume {:+.4} %",
            sim.time(),
            sim.steps(),
            f.max_speed,
            at.as_slice(),
            f.rms_speed,
            100.0 * f.pressure_rms,
            100.0 * (sim.fluid_volume() / v0 - 1.0)
        );
    };
    report(&sim);
    let mut next = 0.05;
    // (`--max-wall-time` stops the run through a hook.)
    while sim.time() < end - 1e-12 && sim.stopped().is_none() {
        sim.step()?;
        if sim.time() >= next - 1e-12 {
            report(&sim);
            next += if next < 0.2 { 0.05 } else { 0.25 };
        }
    }
    pfem::cli::exit_if_stopped(&sim);
    Ok(())
}
