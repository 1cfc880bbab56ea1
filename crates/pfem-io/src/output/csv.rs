//! CSV time series: the probe writer and the reference-data reader.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::OutputError;

/// A CSV time series written one row at a time (`t, front_x, …`).
///
/// The header is written on creation; each [`row`](Self::row) is formatted
/// whole and handed to the operating system in one write, so the file is
/// readable while the run goes on and a crash loses at most the row being
/// written. Numbers use the shortest text that reads back to the same
/// `f64` (`0.25`, `1e-7`, `NaN`, `inf`).
///
/// ```
/// use pfem_io::output::CsvProbe;
///
/// let path = std::env::temp_dir().join(format!("pfem-doc-probe-{}.csv", std::process::id()));
/// let mut probe = CsvProbe::create(&path, &["t", "front_x"])?;
/// probe.row(&[0.0, 0.1])?;
/// probe.row(&[0.01, 0.1025])?;
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "t,front_x\n0.0,0.1\n0.01,0.1025\n");
/// # std::fs::remove_file(&path).ok();
/// # Ok::<(), pfem_io::output::OutputError>(())
/// ```
#[derive(Debug)]
pub struct CsvProbe {
    path: PathBuf,
    file: std::fs::File,
    columns: usize,
    line: String,
}

impl CsvProbe {
    /// Creates (or truncates) `path` and writes the header line. There must
    /// be at least one column, each named once, non-empty and free of
    /// commas, quotes and control characters.
    pub fn create(path: impl Into<PathBuf>, columns: &[&str]) -> Result<Self, OutputError> {
        let path = path.into();
        // The rule body and probe names follow: non-empty, no comma, quote
        // or control character. No columns at all is a file of blank rows.
        if let Some(bad) = columns
            .iter()
            .find(|c| !pfem_scene::is_column_name(c))
            .or(columns.is_empty().then_some(&""))
        {
            return Err(OutputError::ColumnName {
                path,
                name: (*bad).to_owned(),
            });
        }
        let mut seen = std::collections::HashSet::with_capacity(columns.len());
        if let Some(name) = columns.iter().find(|c| !seen.insert(**c)) {
            return Err(OutputError::DuplicateColumn {
                path,
                name: (*name).to_owned(),
            });
        }
        let mut file = std::fs::File::create(&path).map_err(|e| OutputError::io(&path, e))?;
        let header = format!("{}\n", columns.join(","));
        file.write_all(header.as_bytes())
            .and_then(|()| file.flush())
            .map_err(|e| OutputError::io(&path, e))?;
        Ok(Self {
            path,
            file,
            columns: columns.len(),
            line: String::new(),
        })
    }

    /// Continues `path`, a file this type wrote with `columns` (its header
    /// already there), keeping its first `keep` bytes (the header and the
    /// rows a checkpoint counts: later ones, written before a kill, go) and
    /// appending after them. The kept rows are not written again: a kill
    /// while resuming loses none of them.
    pub fn resume(
        path: impl Into<PathBuf>,
        columns: &[&str],
        keep: u64,
    ) -> Result<Self, OutputError> {
        use std::io::{Read as _, Seek as _};
        let path = path.into();
        let io = |e| OutputError::io(&path, e);
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)
            .map_err(io)?;
        file.set_len(keep).map_err(io)?;
        // A last kept row cut before its line end gets one.
        if keep > 0 {
            let mut last = [0u8; 1];
            file.seek(std::io::SeekFrom::Start(keep - 1)).map_err(io)?;
            file.read_exact(&mut last).map_err(io)?;
            file.seek(std::io::SeekFrom::End(0)).map_err(io)?;
            if last[0] != b'\n' {
                file.write_all(b"\n").map_err(io)?;
            }
        }
        Ok(Self {
            path,
            file,
            columns: columns.len(),
            line: String::new(),
        })
    }

    /// Forces the rows written so far to the disk (before a checkpoint that
    /// counts them is written).
    pub fn sync(&mut self) -> Result<(), OutputError> {
        self.file
            .sync_data()
            .map_err(|e| OutputError::io(&self.path, e))
    }

    /// Appends one row; `values` must have one entry per column.
    pub fn row(&mut self, values: &[f64]) -> Result<(), OutputError> {
        if values.len() != self.columns {
            return Err(OutputError::RowLength {
                path: self.path.clone(),
                expected: self.columns,
                got: values.len(),
            });
        }
        self.line.clear();
        for (k, v) in values.iter().enumerate() {
            if k > 0 {
                self.line.push(',');
            }
            let _ = write!(self.line, "{v:?}");
        }
        self.line.push('\n');
        self.file
            .write_all(self.line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| OutputError::io(&self.path, e))
    }

    /// The file written to.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of columns.
    pub fn columns(&self) -> usize {
        self.columns
    }
}

/// Why a reference CSV text could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}: {reason}")]
pub struct ParseError {
    /// 1-based line number (0 when the whole text is at fault).
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

/// Parses reference data in the format of `data/validation/*.csv`: lines
/// starting with `#` are comments (they name the source), an optional header
/// line of column names, then rows whose first two comma-separated values
/// are returned as `(x, y)` pairs. Further columns are ignored.
///
/// ```
/// let text = "# source: a paper\nT,Z\n0.5,1.2\n1.0,1.6\n";
/// assert_eq!(pfem_io::output::parse_reference_csv(text)?, vec![(0.5, 1.2), (1.0, 1.6)]);
/// # Ok::<(), pfem_io::output::ParseError>(())
/// ```
pub fn parse_reference_csv(text: &str) -> Result<Vec<(f64, f64)>, ParseError> {
    let mut points = Vec::new();
    let mut seen_header = false;
    for (k, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut fields = line.split(',').map(str::trim);
        let first = fields.next().unwrap_or("");
        let second = fields.next();
        let x = first.parse::<f64>();
        if x.is_err() && !seen_header && points.is_empty() {
            seen_header = true;
            continue;
        }
        seen_header = true;
        let err = |reason: String| ParseError {
            line: k + 1,
            reason,
        };
        let x = x.map_err(|_| err(format!("{first:?} is not a number")))?;
        let second = second.ok_or_else(|| err("expected at least two columns".into()))?;
        let y = second
            .parse::<f64>()
            .map_err(|_| err(format!("{second:?} is not a number")))?;
        if !(x.is_finite() && y.is_finite()) {
            return Err(err("values must be finite".into()));
        }
        points.push((x, y));
    }
    if points.is_empty() {
        return Err(ParseError {
            line: 0,
            reason: "no data rows".into(),
        });
    }
    Ok(points)
}

/// Reads a reference CSV file (see [`parse_reference_csv`]).
pub fn load_reference_csv(path: impl AsRef<Path>) -> Result<Vec<(f64, f64)>, OutputError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| OutputError::io(path, e))?;
    parse_reference_csv(&text).map_err(|source| OutputError::Parse {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_errors_name_the_line() {
        let e = parse_reference_csv("# c\nT,Z\n0.1,0.2\n0.3,x\n").unwrap_err();
        assert_eq!(e.line, 4);
        assert_eq!(parse_reference_csv("# only\nT,Z\n").unwrap_err().line, 0);
        assert_eq!(
            parse_reference_csv("1,2\n3,4").unwrap(),
            vec![(1.0, 2.0), (3.0, 4.0)]
        );
        assert_eq!(parse_reference_csv("1\n").unwrap_err().line, 1);
    }
}
