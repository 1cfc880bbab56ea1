//! Everything a run leaves on disk: VTK frames and their time series, probe
//! time series, the run summary, comparison plots against measurements, and
//! the progress line on the terminal.
//!
//! | what | type / function | file |
//! |---|---|---|
//! | one mesh + particle frame | [`Frame`], [`write_vtu`] | `.vtu` (VTK XML unstructured grid) |
//! | a series of frames | [`VtuSeries`], [`PvdWriter`] | `.pvd` + one `.vtu` per frame |
//! | probes (front position, …) | [`CsvProbe`] | `.csv`, one row per sample |
//! | end-of-run figures | [`RunSummary`] | `summary.json` |
//! | simulation vs experiment | `plot_series_png` (feature `plots`, on by default) | `.png` |
//! | measured reference data | [`reference`](mod@reference), [`load_reference_csv`] | `data/validation/*.csv` |
//! | terminal progress | [`Progress`] | stderr |
//!
//! Whole files (`.vtu`, `.pvd`, `summary.json`, `.png`) are written through
//! [`write_atomic`]: to a temporary name in the same directory, then renamed,
//! so a crash never leaves a truncated file behind. The CSV probe is a stream
//! and is flushed after every complete row instead.
//!
//! Writing a 2D frame with one triangle, one isolated particle and a velocity
//! field, and a series around it:
//!
//! ```
//! use pfem_io::output::{Encoding, Field, Frame, VtuSeries};
//! use pfem_core::{Point, Vector};
//!
//! let dir = std::env::temp_dir().join(format!("pfem-doc-output-{}", std::process::id()));
//! let points = [
//!     Point::<2>::new(0.0, 0.0),
//!     Point::<2>::new(1.0, 0.0),
//!     Point::<2>::new(0.0, 1.0),
//!     Point::<2>::new(2.0, 2.0),
//! ];
//! let velocity = [Vector::<2>::new(1.0, 0.0); 4];
//! let frame = Frame {
//!     points: &points,
//!     cells: &[0, 1, 2],
//!     vertex_cells: &[3],
//!     point_data: vec![Field::vector("velocity", &velocity)],
//!     ..Default::default()
//! };
//! let mut series = VtuSeries::create(&dir, "dam_break", Encoding::Base64)?;
//! let file = series.write_frame(0.0, &frame)?;
//! assert!(file.ends_with("dam_break_000000.vtu"));
//! assert!(dir.join("dam_break.pvd").exists());
//! # std::fs::remove_dir_all(&dir).ok();
//! # Ok::<(), pfem_io::output::OutputError>(())
//! ```

mod atomic;
mod base64;
mod csv;
mod error;
#[cfg(feature = "plots")]
mod plot;
mod progress;
mod pvd;
pub(crate) use pvd::frame_index;
pub mod reference;
mod summary;
mod vtu;

pub use atomic::{is_atomic_temporary, remove_atomic_temporaries, write_atomic};
pub use csv::{load_reference_csv, parse_reference_csv, CsvProbe, ParseError};
pub use error::OutputError;
#[cfg(feature = "plots")]
pub use plot::{plot_series_png, PlotSeries, PlotSpec, SeriesStyle};
pub use progress::{Progress, LOG_EVERY};
pub use pvd::{PvdWriter, VtuSeries};
pub use summary::{write_summary, RunSummary};
pub use vtu::{encode_vtu, write_vtu, Encoding, Field, FieldData, Frame, FrameError};
