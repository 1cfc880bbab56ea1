//! Outputs of pfem: what a run leaves on disk and shows on the terminal.
//!
//! - [`output`]: writers (VTU/PVD for ParaView, CSV probes, `summary.json`,
//!   PNG plots with the `plots` feature), embedded reference data, the
//!   progress display (a bar with the `progress` feature);
//! - [`observe`]: [`StandardOutput`], the observer that writes them during
//!   a run, and [`Probe`], a named measurement;
//! - [`loads`]: [`Loads`], the water's pressure at each particle and the
//!   forces on bodies, and contact forces, read from a `Simulation`;
//! - [`console`]: [`outln!`] and [`errln!`], lines for the terminal that a
//!   closed pipe cannot turn into a panic.

pub mod console;
pub mod loads;
pub mod observe;
pub mod output;

pub use loads::{ContactForce, Loads};
pub use observe::{Probe, StandardOutput, VOLUME_WARNING};

impl From<output::OutputError> for pfem_driver::RunError {
    fn from(e: output::OutputError) -> Self {
        pfem_driver::RunError::Output(Box::new(e))
    }
}

// The driver's modules under the paths the output code uses.
pub(crate) use pfem_driver::{simulation, RunError};
