//! Water at rest in a 3D tank (issue 13's 3D case): 0.5 m × 0.25 m, 0.5 m of
//! water, walls on four sides and the floor. Prints the largest and RMS fluid speed (in
//! √(gH)), the RMS pressure error against ρ g (H − y) below the free-surface
//! layer, and the fluid volume change, at intervals. The test
//! `tests/three_d.rs` asserts the issue's bounds on the same tank.
//!
//! ```text
//! cargo run --release --example rest_tank_3d -- [--spacing H] [--end-time T]
//! ```

use pfem::cases::G;
use pfem::cases3d::RestTank3d;
use pfem::cli::Args;
use pfem::core::ParticleKind;
use pfem::prelude::*;

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env()?;
    args.reject_unknown(&[])?;
    let case = RestTank3d {
        spacing: args.spacing.unwrap_or(0.05),
        end_time: args.end_time.unwrap_or(2.0),
        ..RestTank3d::default()
    };
    let (h, end, depth) = (case.spacing, case.end_time, case.depth);
    let scene = case.scene();
    let mut sim = args.simulation(scene, Box::new(Delaunay3::default()))?;
    let v0 = sim.fluid_volume();
    let c = (G * depth).sqrt();
    let fluid: Vec<usize> = (0..sim.state.len())
        .filter(|&i| sim.kind[i] == ParticleKind::Fluid)
        .collect();
    let report = |sim: &Simulation<3>| {
        let (mut vmax, mut at, mut v2) = (0.0f64, Point::<3>::zeros(), 0.0);
        let (mut e2, mut p2) = (0.0, 0.0);
        for &i in &fluid {
            let s = sim.state.v[i].norm();
            v2 += s * s;
            if s > vmax {
                vmax = s;
                at = sim.state.x[i];
            }
            let y = sim.state.x[i].y;
            if y < depth - 1.5 * h {
                let pe = 1000.0 * G * (depth - y);
                e2 += (sim.state.pressure[i] - pe).powi(2);
                p2 += pe * pe;
            }
        }
        println!(
            "t = {:6.3} s  steps {:5}  max speed {:.2e} sqrt(gH) at ({:.3}, {:.3}, {:.3})  rms {:.2e}  pressure rms err {:.3} %  volume {:+.4} %",
            sim.time,
            sim.steps,
            vmax / c,
            at.x,
            at.y,
            at.z,
            (v2 / fluid.len() as f64).sqrt() / c,
            100.0 * (e2 / p2).sqrt(),
            100.0 * (sim.fluid_volume() / v0 - 1.0)
        );
    };
    report(&sim);
    let mut next = 0.05;
    while sim.time < end - 1e-12 {
        sim.step()?;
        if sim.time >= next - 1e-12 {
            report(&sim);
            next += if next < 0.2 { 0.05 } else { 0.25 };
        }
    }
    Ok(())
}
