//! A cantilever loaded past yield, elastic against J2 elastoplastic: the
//! user's material and hook running in pfem.
//!
//! `cargo run --release -p pfem-downstream-example`

use pfem::prelude::*;
use pfem_downstream_example::{cantilever, J2Plastic, PlasticityMonitor};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (e, nu, rho) = (5.6e6, 0.4, 1000.0);
    let (elastic, _) = cantilever(Box::new(Hypoelastic::new(rho, e, nu)?), None)?;
    let monitor = PlasticityMonitor::new(0.5);
    let record = monitor.record();
    let j2 = J2Plastic::new(rho, e, nu, 2.5e4, 1.0e6)?;
    let (plastic, sim) = cantilever(Box::new(j2), Some(monitor))?;
    let r = record.lock().map_err(|_| "poisoned")?;
    pfem::outln!(
        "cantilever tip: elastic {:.3} mm, J2 (σy = 25 kPa, H = 1 MPa) {:.3} mm; {} of {} elements yielded, largest plastic strain {:.3e}; {} steps",
        1e3 * elastic,
        1e3 * plastic,
        r.yielded,
        sim.elements().n_solid(),
        r.largest,
        sim.steps()
    );
    Ok(())
}
