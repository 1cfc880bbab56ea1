//! The error type of the output layer.

use std::path::PathBuf;

use super::csv::ParseError;
use super::vtu::FrameError;

/// What went wrong while writing or reading an output file; every variant
/// names the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// The output directory holds files already (a previous run's?), and
    /// overwriting was not asked for.
    #[error("output directory {dir} is not empty ({entries} entries, e.g. `{example}`): pass --overwrite (StandardOutput::overwrite) to replace a previous run's files, or choose another directory")]
    NotEmpty {
        /// The directory.
        dir: PathBuf,
        /// How many entries it holds.
        entries: usize,
        /// One of them.
        example: String,
    },
    /// `--overwrite` (`StandardOutput::overwrite`) into a folder that holds
    /// another scene's series: clearing this scene's files there would
    /// take that run's `probes.csv`, `summary.json` and checkpoint and
    /// leave its frames.
    #[error("output directory {dir} holds another scene's series (`{series}`): --overwrite clears this scene's run only; choose another directory")]
    OtherScene {
        /// The directory.
        dir: PathBuf,
        /// The other series' collection file.
        series: String,
    },
    /// The operating system refused a read, write, rename or directory
    /// creation.
    #[error("I/O error on {path}: {source}")]
    Io {
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The frame handed to the VTK writer is inconsistent (a cell index out
    /// of range, a field of the wrong length…).
    #[error("cannot write {path}: {source}")]
    InvalidFrame {
        /// The file that was to be written.
        path: PathBuf,
        /// What is inconsistent.
        #[source]
        source: FrameError,
    },
    /// A name that cannot be written: a series name that is not one plain
    /// file-name component (it would write outside the chosen folder, or
    /// give a collection whose frames ParaView cannot find), or a
    /// material's internal variable named like a built-in array of the
    /// frames.
    #[error("{dir}: the name {name:?} {why}")]
    InvalidName {
        /// The output folder.
        dir: PathBuf,
        /// The rejected name (at most 64 characters of it).
        name: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// A CSV column name is given twice (a probe named `t`, two probes of
    /// one name): readers would take the first for both.
    #[error("{path}: the column {name:?} is given twice")]
    DuplicateColumn {
        /// The CSV file.
        path: PathBuf,
        /// The repeated name.
        name: String,
    },
    /// A collection entry with a NaN or infinite time, which ParaView
    /// cannot place.
    #[error("{path}: the time {time} of a frame is not finite")]
    NonFiniteTime {
        /// The collection file.
        path: PathBuf,
        /// The time.
        time: f64,
    },
    /// A CSV probe row does not have one value per column.
    #[error("{path}: row has {got} values but the header has {expected} columns")]
    RowLength {
        /// The CSV file.
        path: PathBuf,
        /// Number of columns in the header.
        expected: usize,
        /// Number of values in the rejected row.
        got: usize,
    },
    /// A CSV column name would break the file (empty, or contains a comma,
    /// quote or line break).
    #[error("{path}: invalid column name {name:?}")]
    ColumnName {
        /// The CSV file.
        path: PathBuf,
        /// The rejected name.
        name: String,
    },
    /// A reference CSV file could not be parsed.
    #[error("{path}: {source}")]
    Parse {
        /// The CSV file (`<embedded>` for text that came from no file).
        path: PathBuf,
        /// Line and reason.
        #[source]
        source: ParseError,
    },
    /// `serde_json` could not serialise the run summary.
    #[error("cannot serialise {path}: {source}")]
    Json {
        /// The JSON file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: serde_json::Error,
    },
    /// A restart's outputs cannot continue in this folder: it is not the
    /// one the checkpoint's run wrote (a frame it lists is missing), or
    /// that run wrote no frames and this one would.
    #[error("cannot continue the run's outputs in {dir}: {why}")]
    Resume {
        /// The output folder.
        dir: PathBuf,
        /// What does not match.
        why: String,
    },
    /// The probe rows a run would keep in memory exceed its memory budget
    /// (a row every step, or every probe interval, to the end time).
    #[error("{dir}: {columns} probe columns over at least {rows:.0} rows would hold {gb:.1} GB in memory, more than the memory budget ({budget_gb:.1} GB): give the probes an interval (StandardOutput::probe_interval), fewer columns, or keep the rows in probes.csv only (StandardOutput::keep_rows(false))")]
    TooManyRows {
        /// The output folder.
        dir: PathBuf,
        /// Columns (probes).
        columns: usize,
        /// The fewest rows the run would record.
        rows: f64,
        /// Their memory (GB).
        gb: f64,
        /// The budget (GB).
        budget_gb: f64,
    },
    /// Drawing or encoding a plot failed.
    #[error("cannot draw {path}: {reason}")]
    Plot {
        /// The image file.
        path: PathBuf,
        /// What failed.
        reason: String,
    },
}

impl OutputError {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}
