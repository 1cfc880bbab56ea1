//! ParaView data collections (`.pvd`): a time series of `.vtu` frames.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use pfem_core::{Const, Dim};

use super::vtu::{encode_vtu_at, escape_xml_into};
use super::{write_atomic, Encoding, Frame, OutputError};

/// A `.pvd` collection file listing `(time, file)` pairs.
///
/// Created or resumed, the file is written whole and atomically; each
/// [`push`](Self::push) then writes its entry and the closing tags over
/// the old closing tags, in one write, not synced: a run killed at any
/// point leaves a valid collection of the frames written so far, but a
/// write cut short (a full disk, a power cut) may leave it without its
/// closing tags (a restart writes it whole again from the checkpoint). Rewriting the whole
/// collection at every frame, as until session 41, wrote about 40 N²
/// bytes over N frames (4 GB at 10⁴ frames) with two syncs a frame.
#[derive(Debug, Clone)]
pub struct PvdWriter {
    path: PathBuf,
    entries: Vec<(f64, String)>,
    /// Where the closing tags start in the file as last written.
    tail: u64,
}

/// The closing tags of a collection.
const PVD_FOOTER: &str = "  </Collection>\n</VTKFile>\n";

/// One entry's line.
fn pvd_entry(t: f64, file: &str, s: &mut String) {
    let _ = write!(
        s,
        "    <DataSet timestep=\"{t:?}\" group=\"\" part=\"0\" file=\""
    );
    escape_xml_into(file, s);
    s.push_str("\"/>\n");
}

impl PvdWriter {
    /// Starts a collection at `path`, writing it empty right away (so a bad
    /// path fails now, not after the first frame). An existing file is
    /// replaced.
    pub fn create(path: impl Into<PathBuf>) -> Result<Self, OutputError> {
        let mut writer = Self {
            path: path.into(),
            entries: Vec::new(),
            tail: 0,
        };
        writer.rewrite()?;
        Ok(writer)
    }

    /// Continues a collection at `path` with the `(time, file)` pairs of an
    /// earlier run (a restart), rewriting it with them at once.
    pub fn resume(
        path: impl Into<PathBuf>,
        entries: Vec<(f64, String)>,
    ) -> Result<Self, OutputError> {
        let path = path.into();
        // As `push` refuses (a `timestep="NaN"` that ParaView cannot read).
        if let Some(&(time, _)) = entries.iter().find(|(t, _)| !t.is_finite()) {
            return Err(OutputError::NonFiniteTime { path, time });
        }
        let mut writer = Self {
            path,
            entries,
            tail: 0,
        };
        writer.rewrite()?;
        Ok(writer)
    }

    /// Adds the dataset `file` at simulated time `time` (s) and rewrites the
    /// collection. `file` is stored as given: make it relative to the
    /// `.pvd`'s directory so that the output folder can be moved.
    pub fn push(&mut self, time: f64, file: impl AsRef<Path>) -> Result<(), OutputError> {
        if !time.is_finite() {
            return Err(OutputError::NonFiniteTime {
                path: self.path.clone(),
                time,
            });
        }
        // Forward slashes read on every platform ParaView runs on.
        let file = file.as_ref().to_string_lossy().replace('\\', "/");
        let mut line = String::with_capacity(96 + file.len());
        pvd_entry(time, &file, &mut line);
        let at = self.tail;
        line.push_str(PVD_FOOTER);
        self.entries.push((time, file));
        let appended = (|| {
            use std::io::{Seek, SeekFrom, Write};
            let mut f = std::fs::OpenOptions::new().write(true).open(&self.path)?;
            if f.metadata()?.len() != at + PVD_FOOTER.len() as u64 {
                // Not the file as this writer left it: written whole below.
                return Err(std::io::Error::other("changed"));
            }
            f.seek(SeekFrom::Start(at))?;
            f.write_all(line.as_bytes())
        })();
        match appended {
            Ok(()) => {
                self.tail = at + (line.len() - PVD_FOOTER.len()) as u64;
                Ok(())
            }
            Err(_) => self.rewrite(),
        }
    }

    /// The collection file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The `(time, file)` pairs written so far.
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    fn rewrite(&mut self) -> Result<(), OutputError> {
        let mut s = String::with_capacity(160 + 80 * self.entries.len());
        s.push_str(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" \
             byte_order=\"LittleEndian\">\n  <Collection>\n",
        );
        for (t, file) in &self.entries {
            pvd_entry(*t, file, &mut s);
        }
        self.tail = s.len() as u64;
        s.push_str(PVD_FOOTER);
        write_atomic(&self.path, s.as_bytes())
    }
}

/// A time series of frames in one directory: `NAME_000000.vtu`,
/// `NAME_000001.vtu`, … and the collection `NAME.pvd` that ParaView opens.
///
/// Each frame is written before the collection that lists it, both
/// atomically: after a crash every listed file exists and is complete.
#[derive(Debug)]
pub struct VtuSeries {
    dir: PathBuf,
    name: String,
    encoding: Encoding,
    pvd: PvdWriter,
}

/// Refuses a series name that is not one plain file-name component
/// (`pfem_scene::file_name_fault`: `../x` or `/tmp/x` would write outside
/// `dir`; `case/x` would give a collection whose frames are not found).
fn check_series_name(dir: &std::path::Path, name: &str) -> Result<(), OutputError> {
    match pfem_scene::file_name_fault(name) {
        Some(why) => Err(OutputError::InvalidName {
            dir: dir.to_path_buf(),
            name: name.chars().take(64).collect(),
            why,
        }),
        None => Ok(()),
    }
}

/// The number `N` of a frame file `NAME_NNNNNN.vtu` of the series `name`,
/// or `None` for any other file.
pub(crate) fn frame_index(file: &str, name: &str) -> Option<usize> {
    file.strip_prefix(name)
        .and_then(|r| r.strip_prefix('_'))
        .and_then(|r| r.strip_suffix(".vtu"))
        .filter(|r| r.len() >= 6 && r.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|r| r.parse().ok())
}

impl VtuSeries {
    /// Creates `dir` (and its parents) if needed and starts an empty
    /// collection `dir/NAME.pvd`, replacing any earlier one.
    pub fn create(
        dir: impl Into<PathBuf>,
        name: &str,
        encoding: Encoding,
    ) -> Result<Self, OutputError> {
        let dir = dir.into();
        check_series_name(&dir, name)?;
        std::fs::create_dir_all(&dir).map_err(|e| OutputError::io(&dir, e))?;
        let pvd = PvdWriter::create(dir.join(format!("{name}.pvd")))?;
        Ok(Self {
            dir,
            name: name.to_owned(),
            encoding,
            pvd,
        })
    }

    /// Continues the series of an earlier run (a restart) whose collection
    /// listed `entries`: the collection is rewritten with them, and frames
    /// `NAME_*.vtu` numbered from `entries.len()` on (written by the earlier
    /// run after the state it restarts from) are removed, since this run
    /// writes them again.
    pub fn resume(
        dir: impl Into<PathBuf>,
        name: &str,
        encoding: Encoding,
        entries: Vec<(f64, String)>,
    ) -> Result<Self, OutputError> {
        let dir = dir.into();
        check_series_name(&dir, name)?;
        // Before any frame is removed.
        if let Some(&(time, _)) = entries.iter().find(|(t, _)| !t.is_finite()) {
            return Err(OutputError::NonFiniteTime {
                path: dir.join(format!("{name}.pvd")),
                time,
            });
        }
        std::fs::create_dir_all(&dir).map_err(|e| OutputError::io(&dir, e))?;
        let kept = entries.len();
        // The folder must be the run's own: every frame the checkpoint
        // lists is in it (otherwise the frames removed below would be
        // another run's).
        if let Some((_, f)) = entries.iter().find(|(_, f)| !dir.join(f).is_file()) {
            return Err(OutputError::Resume {
                dir,
                why: format!(
                    "it does not hold `{f}`, a frame the checkpoint lists: continue in the folder the run wrote its frames to, or in a copy of that folder (a new folder gets its probes.csv only)"
                ),
            });
        }
        if let Ok(list) = std::fs::read_dir(&dir) {
            for e in list.flatten() {
                let f = e.file_name();
                let f = f.to_string_lossy();
                if frame_index(&f, name).is_some_and(|i| i >= kept) {
                    let p = e.path();
                    std::fs::remove_file(&p).map_err(|e| OutputError::io(&p, e))?;
                }
            }
        }
        let pvd = PvdWriter::resume(dir.join(format!("{name}.pvd")), entries)?;
        Ok(Self {
            dir,
            name: name.to_owned(),
            encoding,
            pvd,
        })
    }

    /// The `(time, file)` pairs written so far.
    pub fn entries(&self) -> &[(f64, String)] {
        self.pvd.entries()
    }

    /// Writes `frame` as the next `.vtu` file, with `TimeValue = time` (s),
    /// adds it to the collection, and returns the path written.
    pub fn write_frame<const D: usize>(
        &mut self,
        time: f64,
        frame: &Frame<'_, D>,
    ) -> Result<PathBuf, OutputError>
    where
        Const<D>: Dim,
    {
        let file = format!("{}_{:06}.vtu", self.name, self.pvd.entries().len());
        let path = self.dir.join(&file);
        let bytes = encode_vtu_at(frame, self.encoding, Some(time)).map_err(|source| {
            OutputError::InvalidFrame {
                path: path.clone(),
                source,
            }
        })?;
        write_atomic(&path, &bytes)?;
        self.pvd.push(time, &file)?;
        Ok(path)
    }

    /// Number of frames written.
    pub fn len(&self) -> usize {
        self.pvd.entries().len()
    }

    /// Whether no frame has been written yet.
    pub fn is_empty(&self) -> bool {
        self.pvd.entries().is_empty()
    }

    /// The collection file (`dir/NAME.pvd`).
    pub fn pvd_path(&self) -> &Path {
        self.pvd.path()
    }

    /// The directory the frames are written to.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A series name that is not one plain file-name component is refused
    /// and nothing is written: `../x` and `/tmp/x` wrote outside the
    /// folder, `case/x` wrote a collection whose frames were not found.
    #[test]
    fn a_series_name_with_a_path_is_refused() {
        let dir =
            std::env::temp_dir().join(format!("pfem-test-series-name-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for name in ["../escape", "/tmp/escape", "case/a20", "", ".hidden"] {
            let err = VtuSeries::create(&dir, name, Encoding::Base64).map(|_| ());
            assert!(
                matches!(err, Err(OutputError::InvalidName { .. })),
                "{name:?}: {err:?}"
            );
            let err = VtuSeries::resume(&dir, name, Encoding::Base64, Vec::new()).map(|_| ());
            assert!(
                matches!(err, Err(OutputError::InvalidName { .. })),
                "{name:?}"
            );
        }
        assert!(!dir.exists(), "nothing created");
        assert!(!dir.parent().unwrap().join("escape.pvd").exists());
        VtuSeries::create(&dir, "case", Encoding::Base64).unwrap();
        assert!(dir.join("case.pvd").is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A NaN or infinite time is refused: the collection wrote
    /// `timestep="NaN"`, which ParaView cannot place.
    #[test]
    fn a_non_finite_time_is_refused() {
        let dir = std::env::temp_dir().join(format!("pfem-test-pvd-time-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut pvd = PvdWriter::create(dir.join("c.pvd")).unwrap();
        for t in [f64::NAN, f64::INFINITY] {
            let err = pvd.push(t, "c_000000.vtu").unwrap_err();
            assert!(matches!(err, OutputError::NonFiniteTime { .. }), "{err}");
        }
        assert!(pvd.entries().is_empty());
        pvd.push(0.0, "c_000000.vtu").unwrap();
        // Nor taken from a restart's entries (session 44's review), and a
        // series keeps its frames.
        let entries = vec![
            (0.0, "c_000000.vtu".to_string()),
            (f64::NAN, "c_000001.vtu".into()),
        ];
        let err = PvdWriter::resume(dir.join("d.pvd"), entries.clone()).map(|_| ());
        assert!(
            matches!(err, Err(OutputError::NonFiniteTime { .. })),
            "{err:?}"
        );
        std::fs::write(dir.join("c_000001.vtu"), "frame").unwrap();
        let err = VtuSeries::resume(&dir, "c", Encoding::Base64, entries).map(|_| ());
        assert!(
            matches!(err, Err(OutputError::NonFiniteTime { .. })),
            "{err:?}"
        );
        assert!(dir.join("c_000001.vtu").is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Frames from the millionth on have seven digits and are frames of
    /// the series all the same (removed by `--overwrite` and a resume).
    #[test]
    fn frame_numbers_of_six_digits_and_more_are_frames() {
        assert_eq!(frame_index("run_000042.vtu", "run"), Some(42));
        assert_eq!(frame_index("run_1000000.vtu", "run"), Some(1_000_000));
        assert_eq!(frame_index("run_00042.vtu", "run"), None);
        assert_eq!(frame_index("run_00004a.vtu", "run"), None);
        assert_eq!(frame_index("other_000042.vtu", "run"), None);
    }

    /// Session 41: a push appends its entry over the closing tags instead
    /// of rewriting the collection; the file is, byte for byte, the one
    /// written whole with the same entries, after every push. A file
    /// changed behind the writer's back is written whole again.
    #[test]
    fn a_pushed_collection_is_the_collection_written_whole() {
        let dir = std::env::temp_dir().join(format!("pfem-pvd-append-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.pvd"), dir.join("b.pvd"));
        let mut w = PvdWriter::create(&a).unwrap();
        for k in 0..300 {
            w.push(k as f64 * 0.01, format!("run_{k:06}.vtu")).unwrap();
            if k % 37 == 0 || k == 299 {
                PvdWriter::resume(&b, w.entries().to_vec()).unwrap();
                assert_eq!(
                    std::fs::read(&a).unwrap(),
                    std::fs::read(&b).unwrap(),
                    "after {k}"
                );
            }
        }
        std::fs::write(&a, "clobbered").unwrap();
        w.push(3.0, "run_000300.vtu").unwrap();
        PvdWriter::resume(&b, w.entries().to_vec()).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
