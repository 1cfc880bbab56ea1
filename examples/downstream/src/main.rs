//! A cantilever loaded past yield, elastic against J2 elastoplastic: the
//! user's material and hook running in pfem.
//!
//! `cargo run --release -p pfem-downstream-example`

use pfem::hooks::BodyForceRamp;
use pfem::prelude::*;
use pfem_downstream_example::{J2Plastic, PlasticityMonitor};

/// Tip deflection (m) of a clamped 0.35 m × 0.02 m cantilever under a
/// body force ramped to 2 m/s² downwards over 10 s (quasi-static), with
/// `material`; and the simulation.
fn cantilever(
    material: Box<dyn Material<2>>,
    monitor: Option<PlasticityMonitor>,
) -> Result<(f64, Simulation<2>), Box<dyn std::error::Error>> {
    let (l, t) = (0.35, 0.02);
    let scene = Scene::<2>::new("cantilever")
        .settings(RunSettings {
            end_time: 20.0,
            max_dt: 0.5,
            output_interval: None,
            ..Default::default()
        })
        .solid(
            "beam",
            material,
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(l, t),
            },
            t / 4.0,
            Some((Point::<2>::new(-1.0, -1.0), Point::<2>::new(1e-9, 1.0))),
        );
    let params = StepParams {
        scheme: Scheme::BackwardEuler,
        ..StepParams::default()
    };
    let mut sim = Simulation::new(scene, Box::new(Delaunay2::default()), params)?;
    sim.add_hook(Box::new(BodyForceRamp {
        target: Vector::<2>::new(0.0, -2.0),
        duration: 10.0,
    }));
    if let Some(m) = monitor {
        sim.add_hook(Box::new(m));
    }
    sim.run(&mut [])?;
    let p = sim.particles();
    let tip = (0..p.len())
        .filter(|&i| (sim.initial_position(i).x - l).abs() < 1e-9)
        .map(|i| p.x()[i].y - sim.initial_position(i).y)
        .sum::<f64>()
        / 5.0;
    Ok((tip, sim))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (e, nu, rho) = (5.6e6, 0.4, 1000.0);
    let (elastic, _) = cantilever(Box::new(Hypoelastic::new(rho, e, nu)?), None)?;
    let monitor = PlasticityMonitor::new(0.5);
    let record = monitor.record();
    let j2 = J2Plastic::new(rho, e, nu, 3.0e4, 1.0e5)?;
    let (plastic, sim) = cantilever(Box::new(j2), Some(monitor))?;
    let r = record.lock().map_err(|_| "poisoned")?;
    println!(
        "cantilever tip: elastic {:.3} mm, J2 (σy = 30 kPa, H = 100 kPa) {:.3} mm; {} of {} elements yielded, largest plastic strain {:.3e}; {} steps",
        1e3 * elastic,
        1e3 * plastic,
        r.yielded,
        sim.elements().n_solid(),
        r.largest,
        sim.steps()
    );
    Ok(())
}
