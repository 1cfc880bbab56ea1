//! The standard outputs of a run as an [`Observer`]: VTU frames and their
//! `.pvd` series, a CSV of probes, `summary.json`, and a progress bar. Each
//! is computed only when asked for.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use pfem_core::{Const, Dim, ParticleKind, Tensor};
use pfem_geometry::{classify, NodeTag};

use crate::loads::Loads;
use crate::output::{
    write_summary, CsvProbe, Encoding, Field, Frame, Progress, RunSummary, VtuSeries,
};
use crate::simulation::{Observer, Simulation};
use crate::RunError;
use pfem_driver::checkpoint::{Checkpoint, CheckpointError, Decoder, Encoder};

/// A run whose fluid volume changed by more than this fraction ends with a
/// warning ([`StandardOutput::report`]): the volume correction keeps resolved
/// runs within 0.1 %.
pub const VOLUME_WARNING: f64 = 0.05;

/// A named scalar measured on the simulation (front position, tip
/// displacement, force…).
pub struct Probe<const D: usize>
where
    Const<D>: Dim,
{
    /// Column name in `probes.csv`.
    pub name: String,
    /// The measurement.
    #[allow(clippy::type_complexity)]
    pub measure: Box<dyn Fn(&Simulation<D>) -> f64 + Send>,
}

impl<const D: usize> Probe<D>
where
    Const<D>: Dim,
{
    /// A probe from a name and a closure.
    pub fn new(name: &str, measure: impl Fn(&Simulation<D>) -> f64 + Send + 'static) -> Self {
        Self {
            name: name.into(),
            measure: Box::new(measure),
        }
    }
}

// A run's output moves to another thread with its simulation (a batch of
// runs on a pool): `Probe` and `StandardOutput` are `Send` (session 41; a
// probe's closure was not).
const _: fn() = || {
    fn send<T: Send>() {}
    send::<Probe<2>>();
    send::<StandardOutput<3>>();
};

/// Writes what a run leaves on disk into one directory: `NAME.pvd` with
/// `NAME_*.vtu` frames (if `vtu`), `probes.csv` (if there are probes) and
/// `summary.json`, and shows progress unless `quiet`.
pub struct StandardOutput<const D: usize>
where
    Const<D>: Dim,
{
    dir: PathBuf,
    vtu: bool,
    probes: Vec<Probe<D>>,
    /// Interval between probe rows (s), positive and finite (else the
    /// run's start is refused), and a row at the end time; every step when
    /// `None`.
    pub probe_interval: Option<f64>,
    series: Option<VtuSeries>,
    csv: Option<CsvProbe>,
    next_frame: f64,
    next_probe: f64,
    progress: Option<Progress>,
    quiet: bool,
    overwrite: bool,
    started: Option<Instant>,
    /// The wall time of the run's earlier invocations (s), from the
    /// checkpoint it was resumed from ([`OUTPUT_WALL_SECTION`]).
    wall_before: f64,
    /// The frames a resumed run listed, kept listed while this one writes
    /// none (`--no-vtu`): its checkpoints carry them on.
    listed: Vec<(f64, String)>,
    /// Rows of probes recorded so far ([`StandardOutput::history`]); none
    /// kept with [`StandardOutput::keep_rows`]`(false)`.
    history: Vec<ProbeRow>,
    /// Whether the rows are kept in `history` (they are written to
    /// `probes.csv` either way).
    keep_rows: bool,
    /// The number of rows recorded so far, kept or not.
    rows: u64,
    /// A hash of the rows recorded so far ([`rows_hash`]), kept as rows
    /// are recorded: a checkpoint holds it and the rows' count, not the
    /// rows, which a restart reads back from `probes.csv`.
    rows_hash: u64,
    /// Extra figures written into `summary.json`.
    pub extra: BTreeMap<String, serde_json::Value>,
    checkpoint_every: Option<f64>,
    next_checkpoint: f64,
    checkpoints: u64,
    resume: Option<Resumed>,
    restarted_at: Option<f64>,
    /// The error that ended the run ([`Observer::failed`]).
    failure: Option<String>,
    /// The program's own checkpoint sections
    /// ([`StandardOutput::checkpoint_section`]).
    sections: Vec<(String, Vec<u8>)>,
}

/// The output state read from a checkpoint, applied at the start of the
/// resumed run.
#[derive(Debug, Clone)]
struct Resumed {
    /// Whether the checkpoint's run wrote frames (`None`: a checkpoint
    /// written before session 39 does not say).
    vtu: Option<bool>,
    next_frame: f64,
    next_probe: f64,
    frames: Vec<(f64, String)>,
    /// The checkpoint's rows, if they are to be kept or written.
    history: Vec<(f64, Vec<f64>)>,
    /// Their count and hash.
    rows: u64,
    rows_hash: u64,
    /// The bytes of the folder's `probes.csv` that hold the rows (a
    /// checkpoint since session 46); `None`: the rows were the checkpoint's
    /// own, and the file is written from them.
    csv_len: Option<u64>,
}

/// The output layer's section of a checkpoint.
pub const OUTPUT_SECTION: &str = "output";

/// The output layer's wall time of the run so far (s, one `f64`), in its
/// own section: the output section stays the same bits for the same run,
/// interrupted or not.
pub const OUTPUT_WALL_SECTION: &str = "output_wall";

/// The file name of the checkpoint [`StandardOutput`] writes in its
/// directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";

/// Reads a checkpoint file ([`pfem_driver::checkpoint`]); a path that is
/// not a regular file (a device, a pipe), one that does not start as a
/// checkpoint, or one larger than the default memory budget is refused
/// ([`read_checkpoint_within`] another budget).
pub fn read_checkpoint(path: impl AsRef<std::path::Path>) -> Result<Checkpoint, RunError> {
    read_checkpoint_within(path, pfem_scene::default_memory_budget())
}

/// [`read_checkpoint`] within a memory budget of `budget` bytes (`pfem
/// run --memory-budget`).
pub fn read_checkpoint_within(
    path: impl AsRef<std::path::Path>,
    budget: f64,
) -> Result<Checkpoint, RunError> {
    let path = path.as_ref();
    let io = |e| RunError::Output(Box::new(crate::output::OutputError::io(path, e)));
    // A device or a pipe (`/dev/zero`) would be read without end.
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file",
        )));
    }
    // Its first bytes before the whole (before session 49 a 1 GB file of
    // anything was read into memory to be told it is not a checkpoint,
    // and one larger than the memory would have exhausted it).
    let mut magic = [0u8; pfem_driver::checkpoint::MAGIC.len()];
    {
        use std::io::Read;
        let mut f = std::fs::File::open(path).map_err(io)?;
        let mut got = 0;
        while got < magic.len() {
            match f.read(&mut magic[got..]).map_err(io)? {
                0 => break,
                k => got += k,
            }
        }
        if got < magic.len() || &magic != pfem_driver::checkpoint::MAGIC {
            return Err(pfem_driver::checkpoint::CheckpointError::NotACheckpoint.into());
        }
    }
    if meta.len() as f64 > budget {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "{} bytes, more than the memory budget ({budget:.3e} bytes; --memory-budget raises it)",
                meta.len()
            ),
        )));
    }
    let bytes = std::fs::read(path).map_err(io)?;
    Ok(Checkpoint::decode(&bytes)?)
}

impl<const D: usize> StandardOutput<D>
where
    Const<D>: Dim,
{
    /// Outputs into `dir`; VTU frames when `vtu` is set.
    pub fn new(dir: impl Into<PathBuf>, vtu: bool, probes: Vec<Probe<D>>, quiet: bool) -> Self {
        Self {
            dir: dir.into(),
            vtu,
            probes,
            probe_interval: None,
            series: None,
            csv: None,
            next_frame: 0.0,
            next_probe: 0.0,
            progress: None,
            quiet,
            overwrite: false,
            started: None,
            wall_before: 0.0,
            listed: Vec::new(),
            history: Vec::new(),
            keep_rows: true,
            rows: 0,
            rows_hash: ROWS_HASH_START,
            extra: BTreeMap::new(),
            checkpoint_every: None,
            next_checkpoint: f64::INFINITY,
            checkpoints: 0,
            sections: Vec::new(),
            resume: None,
            restarted_at: None,
            failure: None,
        }
    }

    /// Writes a checkpoint (`DIR/checkpoint.bin`, [`CHECKPOINT_FILE`])
    /// every `interval` seconds of simulated time and at the end of the run,
    /// atomically (a kill while writing leaves the previous one whole).
    /// Whatever this is set to, a run that stops before its end time (a
    /// hook's stop, Ctrl-C, a wall-clock limit) writes one when it stops.
    pub fn checkpoint_every(mut self, interval: Option<f64>) -> Self {
        // Checked when the run starts (a value that is not positive and
        // finite wrote no checkpoint at all, not even the last one).
        self.checkpoint_every = interval;
        self
    }

    /// Whether the probe rows are kept in memory for
    /// [`StandardOutput::history`] and [`StandardOutput::probe_series`]
    /// (the default, `true`). With `false` they are written to
    /// `probes.csv` only, and those two read nothing: a long run's rows
    /// then cost no memory (128 bytes a row for 10 probes, kept), and the
    /// run is not refused for rows beyond its memory budget
    /// ([`crate::output::OutputError::TooManyRows`]). A checkpoint and a
    /// restart work alike either way. `pfem run` keeps none. Set it before
    /// [`StandardOutput::resume`], which reads the checkpoint's rows back
    /// only if they are kept.
    pub fn keep_rows(mut self, keep: bool) -> Self {
        self.keep_rows = keep;
        self
    }

    /// Continues the outputs of the run that wrote `checkpoint` (restored
    /// into the simulation with [`Simulation::restore`]): the frames it
    /// listed stay (later ones, written after the checkpoint, are removed
    /// and written again), `probes.csv` keeps the rows up to the checkpoint
    /// (later ones are cut off), and the frame, probe and checkpoint
    /// schedules go on. The directory should be the one the run wrote into;
    /// a non-empty one is accepted. The rows are read here from the
    /// directory's `probes.csv` (a checkpoint holds their count and hash,
    /// not the rows, since session 46): a file that is missing, shorter
    /// than the count or whose rows hash otherwise is refused
    /// ([`crate::output::OutputError::Resume`]).
    pub fn resume(&mut self, checkpoint: &Checkpoint) -> Result<(), RunError> {
        // (A checkpoint before session 49 holds none: 0.)
        let wall_before = match checkpoint.section(OUTPUT_WALL_SECTION) {
            Some(b) => {
                let mut d = Decoder::new(b);
                let w = d.f64()?;
                d.end()?;
                if !(w.is_finite() && w >= 0.0) {
                    return Err(CheckpointError::Corrupt(format!("the run's wall time {w}")).into());
                }
                w
            }
            None => 0.0,
        };
        let mut d = Decoder::new(checkpoint.require(OUTPUT_SECTION)?);
        let next_frame = d.f64()?;
        let next_probe = d.f64()?;
        // (This run's interval sets its schedule: `start_resumed`.)
        let next_checkpoint = d.f64()?;
        let n = d.len(16)?;
        let mut frames = Vec::with_capacity(n);
        for _ in 0..n {
            let t = d.f64()?;
            let f = d.str()?;
            if f.contains(['/', '\\']) || f.starts_with('.') {
                return Err(CheckpointError::Corrupt(format!("frame file name `{f}`")).into());
            }
            frames.push((t, f.to_string()));
        }
        let columns = d.len(0)?;
        if columns != self.probes.len() {
            return Err(CheckpointError::Mismatch {
                what: "the number of probes",
                checkpoint: columns.to_string(),
                simulation: self.probes.len().to_string(),
            }
            .into());
        }
        let rows = d.len(16)?;
        let mut history: Vec<(f64, Vec<f64>)> = Vec::with_capacity(rows);
        for _ in 0..rows {
            let t = d.f64()?;
            let v = d.f64s()?;
            if v.len() != columns {
                return Err(CheckpointError::Corrupt("a probe row's length".into()).into());
            }
            history.push((t, v));
        }
        let vtu = if d.is_at_end() { None } else { Some(d.bool()?) };
        if !d.is_at_end() {
            let n = d.len(8)?;
            let mut names = Vec::with_capacity(n);
            for _ in 0..n {
                names.push(d.str()?.to_string());
            }
            let ours: Vec<&str> = self.probes.iter().map(|p| p.name.as_str()).collect();
            if names != ours {
                return Err(CheckpointError::Mismatch {
                    what: "the probes",
                    checkpoint: names.join(", "),
                    simulation: ours.join(", "),
                }
                .into());
            }
        }
        // Session 46 on: the rows are `probes.csv`'s first `count`, whose
        // hash the checkpoint holds.
        let in_csv = if d.is_at_end() {
            None
        } else {
            Some((d.u64()?, d.u64()?))
        };
        d.end()?;
        let mut csv_len = None;
        let (mut count, mut hash) = (history.len() as u64, rows_hash(ROWS_HASH_START, &history));
        if let Some((c, h)) = in_csv {
            if !history.is_empty() {
                return Err(CheckpointError::Corrupt("probe rows given twice".into()).into());
            }
            if c > 0 {
                let (rows, len) = self.rows_from_csv(c, h)?;
                history = rows;
                csv_len = Some(len);
            }
            (count, hash) = (c, h);
        }
        // A schedule or frame time that is not a number (an edited
        // checkpoint) would stop the frames or list `NaN` in the `.pvd`.
        let finite_or_later = |t: f64| !t.is_nan() && t > f64::NEG_INFINITY;
        if !(finite_or_later(next_frame)
            && finite_or_later(next_probe)
            && finite_or_later(next_checkpoint))
            || frames.iter().any(|(t, _)| !t.is_finite())
            || history.iter().any(|(t, _)| !t.is_finite())
        {
            return Err(CheckpointError::Corrupt("an output time is not a number".into()).into());
        }
        self.resume = Some(Resumed {
            vtu,
            next_frame,
            next_probe,
            frames,
            history,
            rows: count,
            rows_hash: hash,
            csv_len,
        });
        self.wall_before = wall_before;
        Ok(())
    }

    /// Refuses a run whose probe rows, kept in memory, would exceed its
    /// memory budget: at least one row every `max(probe_interval, max_dt)`
    /// to the end time, [`ROW_BYTES`] and 8 bytes a column each (900
    /// gauges in 3D, 3 600 columns, over 10⁶ steps held 29 GB, found after
    /// hours).
    fn rows_fit(&self, sim: &Simulation<D>) -> Result<(), RunError> {
        if self.probes.is_empty() || !self.keep_rows {
            return Ok(());
        }
        let rows = self.rows_to_come(sim) + self.rows as f64;
        let columns = self.probes.len();
        let bytes = rows * (ROW_BYTES + 8.0 * columns as f64);
        if bytes > sim.memory_budget() {
            return Err(crate::output::OutputError::TooManyRows {
                dir: self.dir.clone(),
                columns,
                rows,
                gb: bytes / 1e9,
                budget_gb: sim.memory_budget() / 1e9,
            }
            .into());
        }
        Ok(())
    }

    /// Where the checkpoint is written.
    pub fn checkpoint_path(&self) -> PathBuf {
        self.dir.join(CHECKPOINT_FILE)
    }

    /// The first `count` rows of the folder's `probes.csv`, which must head
    /// this output's probes and hash to `hash` ([`rows_hash`]): the rows a
    /// checkpoint's run had recorded, and the bytes of the file that hold
    /// them with the header. Rows after them (written after the checkpoint,
    /// before a kill) are left out. The rows are returned only if they are
    /// kept ([`StandardOutput::keep_rows`]); they are hashed either way.
    fn rows_from_csv(&self, count: u64, hash: u64) -> Result<(Vec<ProbeRow>, u64), RunError> {
        use std::io::BufRead as _;
        let path = self.dir.join("probes.csv");
        let fail = |why: String| -> RunError {
            crate::output::OutputError::Resume {
                dir: self.dir.clone(),
                why,
            }
            .into()
        };
        let file = std::fs::File::open(&path).map_err(|e| {
            fail(format!(
                "a checkpoint holds its {count} probe rows' count, not the rows, which are its folder's probes.csv; {} cannot be opened ({e}): restart in the checkpoint's folder, or copy its probes.csv here",
                path.display()
            ))
        })?;
        let mut reader = std::io::BufReader::new(file);
        let mut line = String::new();
        let mut len: u64 = 0;
        let mut next = |line: &mut String| -> Result<bool, RunError> {
            line.clear();
            let n = reader
                .read_line(line)
                .map_err(|e| fail(format!("probes.csv cannot be read: {e}")))?;
            len += n as u64;
            while line.ends_with(['\n', '\r']) {
                line.pop();
            }
            Ok(n > 0)
        };
        let mut cols = vec!["t".to_string()];
        cols.extend(self.probes.iter().map(|p| p.name.clone()));
        next(&mut line)?;
        if line != cols.join(",") {
            return Err(fail(format!(
                "probes.csv heads `{line}`, the probes `{}`",
                cols.join(",")
            )));
        }
        let mut rows = Vec::with_capacity(if self.keep_rows {
            count.min(1 << 20) as usize
        } else {
            0
        });
        let mut found = ROWS_HASH_START;
        for k in 0..count {
            if !next(&mut line)? {
                return Err(fail(format!(
                    "probes.csv holds {k} rows, the checkpoint's run had recorded {count}"
                )));
            }
            let values: Result<Vec<f64>, _> = line.split(',').map(str::parse::<f64>).collect();
            match values {
                Ok(v) if v.len() == cols.len() && v[0].is_finite() => {
                    let row = (v[0], v[1..].to_vec());
                    found = rows_hash(found, std::slice::from_ref(&row));
                    if self.keep_rows {
                        rows.push(row);
                    }
                }
                _ => {
                    return Err(fail(format!(
                        "probes.csv's row {} cannot be read: `{line}`",
                        k + 1
                    )))
                }
            }
        }
        if found != hash {
            return Err(fail(
                "probes.csv's rows are not the ones the checkpoint's run recorded (another run's file, or edited)".into(),
            ));
        }
        Ok((rows, len))
    }

    /// The output layer's section of a checkpoint: schedules, frames
    /// listed, the probe rows' count and hash (not the rows: they are
    /// `probes.csv`'s).
    fn encode_state(&self) -> Vec<u8> {
        let mut e = Encoder::new();
        e.f64(self.next_frame);
        e.f64(self.next_probe);
        e.f64(self.next_checkpoint);
        // A run continued without frames carries on the ones listed
        // before (before session 49 its checkpoint listed none and said
        // "no frames", and the run could never write frames again).
        let frames = self
            .series
            .as_ref()
            .map(|s| s.entries())
            .unwrap_or(&self.listed);
        e.u64(frames.len() as u64);
        for (t, f) in frames {
            e.f64(*t);
            e.str(f);
        }
        e.u64(self.probes.len() as u64);
        // The rows are not written here (session 46): they are
        // `probes.csv`'s, which a restart reads back, checked against their
        // count and hash below. Written here, every checkpoint held every
        // row (96 MB for 10 columns over 10⁶ rows).
        e.u64(0);
        e.bool(self.series.is_some() || !self.listed.is_empty());
        // The probes' names (session 41 on; a checkpoint without them is
        // compared by their number alone).
        e.u64(self.probes.len() as u64);
        for p in &self.probes {
            e.str(&p.name);
        }
        e.u64(self.rows);
        e.u64(self.rows_hash);
        e.finish()
    }

    /// Writes the simulation's and the outputs' state to
    /// [`StandardOutput::checkpoint_path`], atomically.
    pub fn write_checkpoint(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        // The rows the checkpoint counts are on the disk before it is.
        if let Some(csv) = self.csv.as_mut() {
            csv.sync()?;
        }
        let mut ck = sim.checkpoint();
        for (name, bytes) in &self.sections {
            // (The library's own names are not the program's to replace.)
            if ck.section(name).is_none() && name != OUTPUT_SECTION && name != OUTPUT_WALL_SECTION {
                ck.set(name, bytes.clone());
            }
        }
        ck.set(OUTPUT_SECTION, self.encode_state());
        let mut wall = Encoder::new();
        wall.f64(self.wall_total());
        ck.set(OUTPUT_WALL_SECTION, wall.finish());
        crate::output::write_atomic(self.checkpoint_path(), &ck.encode())?;
        self.checkpoints += 1;
        Ok(())
    }

    /// A section of the program's own, `bytes` under `name`, written into
    /// every checkpoint beside the simulation's and the outputs' (read back
    /// with [`Checkpoint::section`](pfem_driver::checkpoint::Checkpoint::section)
    /// before a restart: `pfem run` keeps its scene file there and refuses
    /// a restart under an edited one). A name the library's sections use
    /// (`pfem_driver::checkpoint::SIMULATION`, …) is not written; a second
    /// call with the same name replaces the first.
    pub fn checkpoint_section(mut self, name: impl Into<String>, bytes: Vec<u8>) -> Self {
        let name = name.into();
        self.sections.retain(|(n, _)| *n != name);
        self.sections.push((name, bytes));
        self
    }

    /// Whether a non-empty output directory is accepted: its previous run's
    /// files (this scene's `*.vtu` and `.pvd`, `probes.csv`,
    /// `summary.json`) are removed first (and a checkpoint, and the
    /// temporaries of a killed run's atomic writes), other files are left
    /// alone; a folder holding another scene's series (its `.pvd`) is
    /// refused ([`crate::output::OutputError::OtherScene`]). Without it (the default) a
    /// non-empty directory is refused at the start of the run
    /// ([`crate::output::OutputError::NotEmpty`]): frames of an old run must
    /// not sit beside the new ones.
    pub fn overwrite(mut self, yes: bool) -> Self {
        self.overwrite = yes;
        self
    }

    /// Checks the output directory: refuses a non-empty one, or clears the
    /// previous run's files from it when overwriting.
    fn prepare_dir(&self, name: &str) -> Result<(), crate::output::OutputError> {
        use crate::output::OutputError;
        // An empty path names no directory: reading it fails, and writing
        // into it writes into the working directory, past the check below.
        if self.dir.as_os_str().is_empty() {
            return Err(OutputError::io(
                &self.dir,
                std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    "the output directory is an empty path: name one (`.` for the working directory)",
                ),
            ));
        }
        let entries = match std::fs::read_dir(&self.dir) {
            Ok(entries) => entries,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()), // made later
            Err(e) => return Err(OutputError::io(&self.dir, e)),
        };
        let names: Vec<std::ffi::OsString> = entries.flatten().map(|e| e.file_name()).collect();
        if names.is_empty() {
            return Ok(());
        }
        if !self.overwrite {
            return Err(OutputError::NotEmpty {
                dir: self.dir.clone(),
                entries: names.len(),
                example: names[0].to_string_lossy().into_owned(),
            });
        }
        // Another scene's series here: its run's files (probes, summary,
        // checkpoint) share their names with this one's, so clearing would
        // leave it half deleted (a review in session 49): refused.
        if let Some(other) = names
            .iter()
            .map(|n| n.to_string_lossy())
            .find(|s| s.ends_with(".pvd") && *s != format!("{name}.pvd"))
        {
            return Err(OutputError::OtherScene {
                dir: self.dir.clone(),
                series: other.into_owned(),
            });
        }
        for n in names {
            let s = n.to_string_lossy();
            // This scene's series only (another scene's frames without
            // their `.pvd` are left alone).
            let ours = crate::output::frame_index(&s, name).is_some()
                || s == format!("{name}.pvd")
                || s == "probes.csv"
                || s == "summary.json"
                || s == CHECKPOINT_FILE
                // An atomic write's temporary, left by a killed run.
                || crate::output::is_atomic_temporary(&s);
            if ours {
                let p = self.dir.join(&n);
                std::fs::remove_file(&p).map_err(|e| OutputError::io(&p, e))?;
            }
        }
        Ok(())
    }

    /// The rows of probes recorded so far: `(t, values)`, one value per
    /// probe in their order (what `probes.csv` holds). None if the rows are
    /// not kept ([`StandardOutput::keep_rows`]).
    pub fn history(&self) -> &[(f64, Vec<f64>)] {
        &self.history
    }

    /// The fewest probe rows `sim`'s run will still record: one every
    /// `max(probe_interval, max_dt)` to the end time (none without
    /// probes). What a run's rows will cost is judged by it.
    pub fn rows_to_come(&self, sim: &Simulation<D>) -> f64 {
        if self.probes.is_empty() {
            return 0.0;
        }
        let every = self.probe_interval.unwrap_or(0.0).max(sim.max_dt());
        ((sim.end_time() - sim.time()).max(0.0) / every).floor()
    }

    /// The number of probes (columns of `probes.csv` after `t`).
    pub fn probe_count(&self) -> usize {
        self.probes.len()
    }

    /// Values of one probe over the run, `(t, value)`. Empty if the rows
    /// are not kept ([`StandardOutput::keep_rows`]), or if no probe has
    /// that name.
    pub fn probe_series(&self, name: &str) -> Vec<(f64, f64)> {
        match self.probes.iter().position(|p| p.name == name) {
            Some(i) => self.history.iter().map(|(t, v)| (*t, v[i])).collect(),
            None => Vec::new(),
        }
    }

    fn write_frame(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        let Some(series) = self.series.as_mut() else {
            return Ok(());
        };
        let nv = D + 1;
        let cells = sim.elements().all();
        let n_cells = cells.len() / nv;
        // Boundary tags only when a frame is written. A wall or solid
        // particle of a scene without fluid touches no fluid (5); it was
        // written "interior" (0), a fluid's tag, until session 48.
        let mut tags: Vec<i32> = sim
            .particles()
            .kind()
            .iter()
            .map(|&k| if k == ParticleKind::Fluid { 0 } else { 5 })
            .collect();
        let mut vertex_cells = Vec::new();
        if sim.stages().free_surface {
            if let Ok(cls) = classify(
                sim.particles().x(),
                sim.particles().kind(),
                sim.elements().fluid_mesh(),
                Some(sim.elements().solid()),
            ) {
                for (t, c) in tags.iter_mut().zip(&cls.tags) {
                    *t = match c {
                        NodeTag::Interior => 0,
                        NodeTag::FreeSurface => 1,
                        NodeTag::Wall => 2,
                        NodeTag::Interface => 3,
                        NodeTag::Isolated => 4,
                        // A wall or solid particle touching no fluid.
                        _ => 5,
                    };
                }
                vertex_cells = cls.isolated.clone();
            }
        }
        let kind: Vec<i32> = sim
            .particles()
            .kind()
            .iter()
            .map(|k| match k {
                ParticleKind::Fluid => 0,
                ParticleKind::Solid => 1,
                ParticleKind::Wall => 2,
            })
            .collect();
        let body: Vec<i32> = sim.particles().body().iter().map(|&b| b as i32).collect();
        // Each element's material, then each isolated particle's own (a
        // vertex cell written as 0 would show another body's material).
        let material: Vec<i32> = sim
            .elements()
            .materials()
            .iter()
            .map(|&m| m as i32)
            .chain(
                vertex_cells
                    .iter()
                    .map(|&i| sim.particles().material()[i as usize] as i32),
            )
            .collect();
        let mut stress = vec![Tensor::<D>::zeros(); n_cells];
        // The out-of-plane normal stress of plane strain (2D only).
        let mut stress_zz = vec![0.0; if D == 2 { n_cells } else { 0 }];
        for (e, h) in sim.elements().solid_history().iter().enumerate() {
            stress[e] = h.stress;
            if D == 2 {
                stress_zz[e] = h.stress_zz;
            }
        }
        // Displacement from where each particle entered the simulation.
        let displacement: Vec<pfem_core::Vector<D>> = sim
            .particles()
            .x()
            .iter()
            .zip(sim.particles().initial_positions())
            .map(|(x, x0)| x - x0)
            .collect();
        let pressure = sim.water_pressure();
        // Internal variables of the solids' materials, one cell field per
        // name (zero on elements of other materials).
        let mut internal: Vec<(String, Vec<f64>)> = Vec::new();
        let solid_mat = sim.elements().solid_material();
        for (e, h) in sim.elements().solid_history().iter().enumerate() {
            let Some(m) = sim.materials().get(solid_mat[e] as usize) else {
                continue;
            };
            for (k, name) in m.internal_variables().iter().enumerate() {
                let col = match internal.iter().position(|(n, _)| n == name) {
                    Some(c) => c,
                    None => {
                        internal.push((name.to_string(), vec![0.0; n_cells]));
                        internal.len() - 1
                    }
                };
                internal[col].1[e] = h.internal.get(k).copied().unwrap_or(0.0);
            }
        }
        let mut cell_data = vec![
            Field::int("material", &material),
            Field::sym_tensor("stress", &stress),
        ];
        if D == 2 {
            cell_data.push(Field::scalar("stress_zz", &stress_zz));
        }
        // Contact status: the normal pressure of each contact element
        // (zero on every other cell; zero on a contact element that is
        // open).
        let contact_pressure: Vec<f64> = if sim.stages().contact {
            let mut c = vec![0.0; n_cells];
            let first = n_cells - sim.elements().n_contact();
            for (k, h) in sim.elements().contact_history().iter().enumerate() {
                c[first + k] = pfem_constitutive::ContactPenalty::pressure(h);
            }
            c
        } else {
            Vec::new()
        };
        if sim.stages().contact {
            cell_data.push(Field::scalar("contact_pressure", &contact_pressure));
        }
        for (name, values) in &internal {
            cell_data.push(Field::scalar(name.as_str(), values));
        }
        let frame = Frame {
            points: sim.particles().x(),
            cells,
            vertex_cells: &vertex_cells,
            point_data: vec![
                Field::vector("displacement", &displacement),
                Field::vector("velocity", sim.particles().v()),
                Field::vector("acceleration", sim.particles().a()),
                Field::scalar("pressure", &pressure),
                Field::int("kind", &kind),
                Field::int("body", &body),
                Field::int("boundary_tag", &tags),
            ],
            cell_data,
            time: Some(sim.time()),
        };
        series.write_frame(sim.time(), &frame)?;
        Ok(())
    }

    fn record(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        if self.probes.is_empty() {
            return Ok(());
        }
        let values: Vec<f64> = self.probes.iter().map(|p| (p.measure)(sim)).collect();
        if let Some(csv) = self.csv.as_mut() {
            let mut row = vec![sim.time()];
            row.extend_from_slice(&values);
            csv.row(&row)?;
        }
        let row = (sim.time(), values);
        self.rows_hash = rows_hash(self.rows_hash, std::slice::from_ref(&row));
        self.rows += 1;
        if self.keep_rows {
            self.history.push(row);
        }
        Ok(())
    }

    /// Ends a run for a command-line program: writes `summary.json` (with
    /// the `extra` entries added since [`Observer::finish`] wrote it),
    /// prints one line of steps, simulated time, fluid volume and wall
    /// time and the output directory on stdout, and returns the summary.
    pub fn report(&self, sim: &Simulation<D>) -> Result<RunSummary, RunError> {
        let summary = self.summary(sim);
        write_summary(self.dir.join("summary.json"), &summary)?;
        let change = summary.relative_volume_change();
        let unit = if D == 2 { "m²/m" } else { "m³" };
        let inflow = summary
            .fluid_volume_intended
            .map_or(0.0, |v| v - summary.fluid_volume_initial);
        let volume = if change.is_finite() && inflow != 0.0 {
            format!(
                "fluid volume {:.6e} -> {:.6e} {unit}, {:+.6e} of it by sources ({:+.3}% off)",
                summary.fluid_volume_initial,
                summary.fluid_volume_final,
                inflow,
                100.0 * change
            )
        } else if change.is_finite() {
            format!(
                "fluid volume {:.6e} -> {:.6e} {unit} ({:+.3}%)",
                summary.fluid_volume_initial,
                summary.fluid_volume_final,
                100.0 * change
            )
        } else {
            // No fluid volume at the start (no fluid, or drops with no
            // mesh): no relative change to give.
            format!(
                "fluid volume {:.6e} -> {:.6e} {unit}",
                summary.fluid_volume_initial, summary.fluid_volume_final
            )
        };
        // A scene without fluid has no volume to report (it printed
        // "fluid volume 0.000000e0 -> 0.000000e0").
        let volume = if summary.fluid_volume_initial == 0.0 && summary.fluid_volume_final == 0.0 {
            String::new()
        } else {
            format!("{volume}, ")
        };
        crate::outln!(
            "{} steps ({} rejected), simulated {:.4} s, {volume}wall time {:.1} s",
            summary.steps,
            summary.rejected_steps,
            summary.simulated_time,
            summary.wall_time_s.get("total").copied().unwrap_or(0.0)
        );
        if change.abs() > VOLUME_WARNING {
            crate::errln!(
                "warning: the fluid volume changed by {:+.1}%: the run is likely unresolved (a soft bulk modulus, a coarse spacing, walls squeezing the water); see the README's section \"When a run fails\"",
                100.0 * change
            );
        }
        crate::outln!("wrote {}", self.dir.display());
        Ok(summary)
    }

    /// The run's wall time so far (s): this invocation's since its start,
    /// with the earlier invocations' a resumed run's checkpoint holds.
    pub fn wall_total(&self) -> f64 {
        self.wall_before
            + self
                .started
                .map(|s| s.elapsed().as_secs_f64())
                .unwrap_or(0.0)
    }

    /// The run's summary as it stands.
    pub fn summary(&self, sim: &Simulation<D>) -> RunSummary {
        let mut wall = BTreeMap::new();
        wall.insert("remesh".to_string(), sim.stats().remesh.1);
        wall.insert(
            "remesh_free_surface".to_string(),
            sim.stats().free_surface.1,
        );
        wall.insert("assemble".to_string(), sim.stats().assemble.1);
        wall.insert("solve".to_string(), sim.stats().solve.1);
        wall.insert("update".to_string(), sim.stats().update.1);
        wall.insert("hooks".to_string(), sim.stats().hooks.1);
        wall.insert("output".to_string(), sim.stats().observe.1);
        wall.insert("rejected_attempts".to_string(), sim.stats().rejected.1);
        // The whole run's, earlier invocations included, as the stage
        // timers are (before session 49 a resumed run's total was its last
        // invocation's, below the sum of its stages).
        wall.insert("total".to_string(), self.wall_total());
        let mut causes = BTreeMap::new();
        causes.insert("remeshing".to_string(), sim.volume().remeshing);
        causes.insert("solution".to_string(), sim.volume().solution);
        for (name, dv) in &sim.volume().hooks {
            causes.insert(name.clone(), *dv);
        }
        RunSummary {
            scene: sim.name().to_string(),
            dimension: D,
            particles: sim.particles().len(),
            steps: sim.steps(),
            rejected_steps: sim.rejected(),
            simulated_time: sim.time(),
            wall_time_s: wall,
            fluid_volume_initial: sim.volume().initial,
            fluid_volume_final: sim.fluid_volume(),
            fluid_volume_intended: Some(sim.volume().initial + sim.volume().sources),
            volume_change_by_cause: causes,
            extra: {
                let mut e = self.extra.clone();
                e.insert(
                    "rejected_inverted_element".into(),
                    sim.rejected_by_cause().0.into(),
                );
                e.insert(
                    "rejected_picard_divergence".into(),
                    sim.rejected_by_cause().1.into(),
                );
                e.insert("picard_iterations".into(), sim.stats().assemble.0.into());
                // Of `fluid_volume_final`, the drops in flight (a lattice
                // cell each).
                e.insert(
                    "fluid_volume_final_drops".into(),
                    // (`+ 0.0`: no `-0.0` in the summary, a review of
                    // session 53.)
                    (sim.drop_volume() + 0.0).into(),
                );
                let status = match sim.stopped() {
                    _ if self.failure.is_some() => "failed",
                    None if sim.reached_end_time() => "finished",
                    None => "running",
                    Some(pfem_driver::hooks::Interrupt::REASON) => "interrupted",
                    Some(_) => "stopped",
                };
                e.insert("status".into(), status.into());
                if let Some(r) = sim.stopped() {
                    e.insert("stop_reason".into(), r.into());
                }
                if let Some(f) = &self.failure {
                    e.insert("error".into(), f.clone().into());
                }
                if let Some(t) = self.restarted_at {
                    e.insert("restarted_at_time".into(), t.into());
                }
                if self.checkpoints > 0 {
                    e.insert(
                        "checkpoint".into(),
                        self.checkpoint_path().to_string_lossy().into_owned().into(),
                    );
                }
                e
            },
        }
    }
}

impl<const D: usize> StandardOutput<D>
where
    Const<D>: Dim,
{
    /// The start of a resumed run: the directory is kept, the series and
    /// probe file continue the checkpoint's, no initial frame or row.
    fn start_resumed(&mut self, sim: &Simulation<D>, r: Resumed) -> Result<(), RunError> {
        std::fs::create_dir_all(&self.dir)
            .map_err(|e| crate::output::OutputError::io(&self.dir, e))?;
        crate::output::remove_atomic_temporaries(&self.dir)?;
        if self.vtu && sim.output_interval().is_some() {
            // A run that wrote no frames lists none: continuing with frames
            // would remove every frame in the folder as written "after" it.
            if r.vtu == Some(false) {
                return Err(crate::output::OutputError::Resume {
                    dir: self.dir.clone(),
                    why:
                        "the checkpoint's run wrote no frames (--no-vtu): restart with --no-vtu too"
                            .into(),
                }
                .into());
            }
            self.series = Some(VtuSeries::resume(
                &self.dir,
                sim.name(),
                Encoding::Base64,
                r.frames,
            )?);
        } else if !r.frames.is_empty() {
            // No frames from here on (`--no-vtu`), but the run's listed
            // ones stay listed: the collection is put back to the
            // checkpoint's, without the frames written after it.
            VtuSeries::resume(&self.dir, sim.name(), Encoding::Base64, r.frames.clone())?;
            self.listed = r.frames;
        }
        if !self.probes.is_empty() {
            let mut cols = vec!["t"];
            cols.extend(self.probes.iter().map(|p| p.name.as_str()));
            let path = self.dir.join("probes.csv");
            self.csv = Some(match r.csv_len {
                // The rows are the file's: kept, not written again (a kill
                // while they were written again lost their only copy).
                Some(len) => CsvProbe::resume(path, &cols, len)?,
                // A checkpoint that held its rows (before session 46), or
                // none: the file is written from them.
                None => {
                    let mut csv = CsvProbe::create(path, &cols)?;
                    for (t, v) in &r.history {
                        let mut row = vec![*t];
                        row.extend_from_slice(v);
                        csv.row(&row)?;
                    }
                    csv
                }
            });
        }
        self.rows = r.rows;
        self.rows_hash = r.rows_hash;
        self.history = if self.keep_rows {
            r.history
        } else {
            Vec::new()
        };
        // The frame and probe schedules go on from the checkpoint's next
        // times if they are this run's intervals' (a multiple of one, at
        // most one interval ahead); an interval changed since (another
        // `--probe-interval`, none, or the scene's output interval) takes
        // effect at once. Taken as saved, a row every step after rows
        // every 0.1 s recorded none until the saved next time.
        let (t, now) = (sim.time(), sim.time() + 1e-9 * sim.end_time());
        self.next_frame = resumed_next(r.next_frame, t, now, sim.output_interval());
        self.next_probe = match self.probe_interval {
            // Every step.
            None => 0.0,
            every => resumed_next(r.next_probe, t, now, every),
        };
        // The checkpoint schedule is this run's: a run restarted with
        // `--checkpoint-every` from one without it (whose checkpoint, written
        // at a stop, holds no next time) writes them, and a new interval
        // takes effect at once. With the interval unchanged this is the
        // saved next time (the first multiple after the last write).
        self.next_checkpoint =
            next_after(sim.time() + 1e-9 * sim.end_time(), self.checkpoint_every);
        self.restarted_at = Some(sim.time());
        self.progress = Some(Progress::new(sim.end_time(), self.quiet));
        // The stop's summary is not this run's: left, it outlived a kill
        // of the continued run ("stopped" at 0.030 s beside rows to
        // 0.071 s, session 55's review). This run's is written at its end,
        // as a fresh run's.
        let summary = self.dir.join("summary.json");
        if summary.is_file() {
            std::fs::remove_file(&summary)
                .map_err(|e| crate::output::OutputError::io(&summary, e))?;
        }
        Ok(())
    }

    /// A fresh run's first files, in its prepared folder: the series and
    /// the probe file, the first frame and row.
    fn start_files(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        if self.vtu && sim.output_interval().is_some() {
            self.series = Some(VtuSeries::create(&self.dir, sim.name(), Encoding::Base64)?);
        }
        if !self.probes.is_empty() {
            let mut cols = vec!["t"];
            cols.extend(self.probes.iter().map(|p| p.name.as_str()));
            self.csv = Some(CsvProbe::create(self.dir.join("probes.csv"), &cols)?);
        }
        self.progress = Some(Progress::new(sim.end_time(), self.quiet));
        self.write_frame(sim)?;
        self.next_frame = sim.output_interval().unwrap_or(f64::INFINITY);
        self.record(sim)?;
        self.next_probe = self.probe_interval.unwrap_or(0.0);
        self.next_checkpoint = self.checkpoint_every.unwrap_or(f64::INFINITY);
        Ok(())
    }
}

impl<const D: usize> Observer<D> for StandardOutput<D>
where
    Const<D>: Dim,
{
    fn start(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        self.rows_fit(sim)?;
        // A second `run` with this output (a run continued past its end
        // time): the folder, frames, probes and schedules go on; only the
        // progress bar starts again. (It cleared the first run's files, or
        // refused the folder as not empty.)
        if self.progress.is_some() && self.resume.is_none() {
            self.progress = Some(Progress::new(sim.end_time(), self.quiet));
            // A failure of the last `run` is not this one's.
            self.failure = None;
            return Ok(());
        }
        self.started = Some(Instant::now());
        if let Some(t) = self.checkpoint_every {
            if !(t > 0.0 && t.is_finite()) {
                return Err(RunError::InvalidSetting {
                    name: "checkpoint_every",
                    value: t,
                    reason: "must be a positive, finite time in s",
                });
            }
        }
        if let Some(t) = self.probe_interval {
            if !(t > 0.0 && t.is_finite()) {
                return Err(RunError::InvalidSetting {
                    name: "probe_interval",
                    value: t,
                    reason: "must be positive and finite (None records every step)",
                });
            }
        }
        // A solid's internal variables become cell arrays by name: one named
        // like a built-in array, or twice by one material, would give a
        // frame two arrays of one name (ParaView shows one of them).
        for m in sim.materials() {
            let names = m.internal_variables();
            for (k, name) in names.iter().enumerate() {
                let why = if name.trim().is_empty() {
                    // (An array ParaView lists without a name: session 49.)
                    Some("is empty: name the material's internal variable")
                } else if FRAME_CELL_ARRAYS.contains(name) {
                    Some("is a built-in cell array of the frames: rename the material's internal variable")
                } else if names[..k].contains(name) {
                    Some("is given twice by one material's internal variables")
                } else {
                    None
                };
                if let Some(why) = why {
                    return Err(crate::output::OutputError::InvalidName {
                        dir: self.dir.clone(),
                        name: name.to_string(),
                        why,
                    }
                    .into());
                }
            }
        }
        if let Some(r) = self.resume.take() {
            return self.start_resumed(sim, r);
        }
        self.prepare_dir(sim.name())?;
        std::fs::create_dir_all(&self.dir)
            .map_err(|e| crate::output::OutputError::io(&self.dir, e))?;
        // The folder is this run's now: a start that fails from here on
        // (a full disk at the first frame wrote no summary: session 55's
        // review) says so in its summary, as a failed step does.
        let started = self.start_files(sim);
        if let Err(e) = &started {
            self.failure = Some(e.to_string());
            let _ = write_summary(self.dir.join("summary.json"), &self.summary(sim));
        }
        started
    }

    fn step(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        let eps = 1e-9 * sim.end_time();
        // The end time's frame too when it falls between two (a run to
        // 0.08 s at 0.0125 s frames ended its series at 0.07849 s; a
        // review of session 53), as the probe rows below: on the step
        // `run` ends on alone. A run stopped before its end time writes
        // none (its continuation is the uninterrupted run's, frame for
        // frame).
        if sim.time() + eps >= self.next_frame || sim.reached_end_time() {
            self.write_frame(sim)?;
            self.next_frame = next_after(sim.time() + eps, sim.output_interval());
        }
        // With an interval, the end time's row too when it falls between
        // two (rows at 0, 0.3, 0.6, 0.9 of a run to 1 s left out its final
        // state; session 52's review): on the step `run` ends on alone
        // (`reached_end_time`, a relative 10⁻¹²; with `eps`, two steps
        // shorter than 10⁻⁹ of the end time could each write one).
        let end = self.probe_interval.is_some() && sim.reached_end_time();
        if sim.time() + eps >= self.next_probe || end {
            self.record(sim)?;
            if self.probe_interval.is_some() {
                self.next_probe = next_after(sim.time() + eps, self.probe_interval);
            }
        }
        if sim.time() + eps >= self.next_checkpoint {
            self.next_checkpoint = next_after(sim.time() + eps, self.checkpoint_every);
            self.write_checkpoint(sim)?;
        }
        if let Some(p) = self.progress.as_mut() {
            p.update(sim.time(), sim.dt());
        }
        Ok(())
    }

    fn finish(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        if let Some(p) = self.progress.as_mut() {
            p.finish();
        }
        // A resumed run's too: its folder's checkpoint was the stop's, and
        // a restart from it re-ran the end and cut `probes.csv` back to it
        // (session 54's review).
        if self.checkpoint_every.is_some() || sim.stopped().is_some() || self.restarted_at.is_some()
        {
            self.write_checkpoint(sim)?;
        }
        write_summary(self.dir.join("summary.json"), &self.summary(sim))?;
        Ok(())
    }

    /// `summary.json` with `"status": "failed"` and the error's text
    /// (`"error"`), the figures as they stood at the last accepted step,
    /// and a last VTU frame of that step's state when it falls after the
    /// series' last frame (the series ended at the last frame on the
    /// interval, up to an interval before the failure: session 53's
    /// review). A state that is not finite, or a set not meshed, writes
    /// none.
    fn failed(&mut self, sim: &Simulation<D>, error: &RunError) {
        if let Some(p) = self.progress.as_mut() {
            p.finish();
        }
        let after_last = self
            .series
            .as_ref()
            .is_some_and(|s| s.entries().last().is_none_or(|&(t, _)| t < sim.time()));
        let finite = sim
            .particles()
            .x()
            .iter()
            .chain(sim.particles().v())
            .all(|x| x.iter().all(|c| c.is_finite()))
            && sim.particles().pressure().iter().all(|p| p.is_finite());
        if after_last && finite && sim.is_meshed() {
            let _ = self.write_frame(sim);
        }
        self.failure = Some(error.to_string());
        if self.dir.is_dir() {
            let _ = write_summary(self.dir.join("summary.json"), &self.summary(sim));
        }
    }
}

/// The memory of a probe row besides its values (bytes): the time, the
/// values' vector and the allocator's share.
pub const ROW_BYTES: f64 = 48.0;

/// One row of probes: the time and a value per probe.
type ProbeRow = (f64, Vec<f64>);

/// [`rows_hash`] of no rows.
const ROWS_HASH_START: u64 = 0xcbf2_9ce4_8422_2325;

/// FNV-1a over the bits of probe rows (time, then values), continuing from
/// `hash`: what a checkpoint holds of its rows, to know `probes.csv`'s
/// when a restart reads them back. A NaN counts as one NaN, whatever its
/// bits (the CSV writes every NaN as `NaN`).
fn rows_hash(mut hash: u64, rows: &[(f64, Vec<f64>)]) -> u64 {
    for (t, v) in rows {
        for x in std::iter::once(t).chain(v) {
            let bits = if x.is_nan() {
                f64::NAN.to_bits()
            } else {
                x.to_bits()
            };
            for byte in bits.to_le_bytes() {
                hash ^= u64::from(byte);
                hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }
    hash
}

/// The cell arrays every frame writes besides the solids' internal
/// variables.
const FRAME_CELL_ARRAYS: [&str; 4] = ["material", "stress", "stress_zz", "contact_pressure"];

/// The next time of a schedule of `interval` resumed at the clock `t`
/// (`now` with the schedules' tolerance): the checkpoint's `saved` one if
/// it is that schedule's (a multiple of the interval after `t`, at most
/// one interval ahead: the one [`next_after`] gave), else the first
/// multiple of `interval` after `now` (infinite without an interval). (Not
/// "after `now`": the tolerance is this run's end time's, and a later end
/// time would have skipped a saved time just ahead of the clock.)
fn resumed_next(saved: f64, t: f64, now: f64, interval: Option<f64>) -> f64 {
    match interval {
        Some(dt) if saved > t && saved - dt <= now && (saved / dt).round() * dt == saved => saved,
        _ => next_after(now, interval),
    }
}

/// The first multiple of `interval` after `t` (infinite without an
/// interval). Computed, not stepped: an interval too small to move a sum
/// (5e-324) cannot hang the scheduler.
fn next_after(t: f64, interval: Option<f64>) -> f64 {
    match interval {
        Some(dt) if dt > 0.0 && dt.is_finite() => {
            let next = ((t / dt).floor() + 1.0) * dt;
            if next > t {
                next
            } else {
                // Below the resolution of t: every step is a frame.
                t + t.abs() * f64::EPSILON + f64::MIN_POSITIVE
            }
        }
        _ => f64::INFINITY,
    }
}
