//! The command-line contract shared by the bundled examples and the `pfem`
//! binary: `--out DIR [--spacing H] [--end-time T] [--quiet]` plus
//! example-specific `--name value` options.

use std::collections::BTreeMap;
use std::path::PathBuf;

/// Parsed command-line options.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Args {
    /// Output directory (`--out`), default `out/NAME`.
    pub out: Option<PathBuf>,
    /// Particle spacing override (`--spacing`, m).
    pub spacing: Option<f64>,
    /// End time override (`--end-time`, s).
    pub end_time: Option<f64>,
    /// No progress bar (`--quiet`).
    pub quiet: bool,
    /// No VTU frames (`--no-vtu`).
    pub no_vtu: bool,
    /// Clear the previous run's files from a non-empty output directory
    /// (`--overwrite`); without it such a directory is refused.
    pub overwrite: bool,
    /// Other `--name value` options.
    pub options: BTreeMap<String, String>,
    /// Positional arguments.
    pub positional: Vec<String>,
}

/// A command-line error.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ArgsError(pub String);

/// Whether `args` ask for one of `names` (`-h`, `--version`): `-h` as an
/// option's value (`--out -h`) is that value, not a request.
pub fn asks(args: &[String], names: [&str; 2]) -> bool {
    let mut value = false;
    for a in args {
        if std::mem::take(&mut value) {
            continue;
        }
        if names.contains(&a.as_str()) {
            return true;
        }
        value = a.starts_with("--") && !FLAGS.contains(&a.as_str());
    }
    false
}

/// Ends an example whose run a hook stopped before its end time (the
/// wall-clock cap, `--max-wall-time`): prints why and where, and exits with
/// status 2, as `pfem run` does, so that no comparison or figure is made
/// from a series cut short. The outputs written so far stay (their
/// `summary.json` says `"stopped"`). Returns when the run was not stopped.
pub fn exit_if_stopped<const D: usize>(sim: &pfem_driver::Simulation<D>)
where
    pfem_core::Const<D>: pfem_core::Dim,
{
    exit_stopped(sim, None);
}

/// [`exit_if_stopped`] for an example that can continue: the message adds
/// the command that does (`--restart` with the checkpoint the output
/// wrote when the run stopped), as `pfem run` prints its own.
pub fn exit_if_stopped_at<const D: usize>(
    sim: &pfem_driver::Simulation<D>,
    output: &crate::StandardOutput<D>,
) where
    pfem_core::Const<D>: pfem_core::Dim,
{
    exit_stopped(sim, Some(output.checkpoint_path()));
}

/// [`exit_if_stopped`], saying how to continue from `checkpoint` when it
/// was written.
fn exit_stopped<const D: usize>(
    sim: &pfem_driver::Simulation<D>,
    checkpoint: Option<std::path::PathBuf>,
) where
    pfem_core::Const<D>: pfem_core::Dim,
{
    if let Some(reason) = sim.stopped() {
        crate::errln!(
            "the run stopped at t = {} s of {} s ({reason}): no comparison is made",
            sim.time(),
            sim.end_time()
        );
        if let Some(c) = checkpoint.filter(|c| c.is_file()) {
            crate::errln!(
                "continue with the same command and --restart {}",
                shell_quote(&c.to_string_lossy())
            );
        }
        std::process::exit(2);
    }
}

/// `w` quoted for a POSIX shell where it needs it (a path with a space),
/// for the commands a stopped run prints.
pub fn shell_quote(w: &str) -> String {
    if !w.is_empty()
        && w.chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-./:=+,@%".contains(c))
    {
        w.to_string()
    } else {
        format!("'{}'", w.replace('\'', r"'\''"))
    }
}

/// Restores `sim` from `checkpoint` and resumes `output` with it (what
/// `--restart` does, in the examples and in `pfem run`); a checkpoint at or
/// past the end time is refused: nothing to run, not a finished run (its
/// summary rewritten from a fresh remeshing's volume, a review in session
/// 49).
pub fn continue_from<const D: usize>(
    sim: &mut crate::Simulation<D>,
    output: &mut crate::StandardOutput<D>,
    checkpoint: &crate::checkpoint::Checkpoint,
) -> Result<(), String>
where
    pfem_core::Const<D>: pfem_core::Dim,
{
    sim.restore(checkpoint)
        .and_then(|()| output.resume(checkpoint))
        .map_err(|e| e.to_string())?;
    if sim.reached_end_time() {
        return Err(format!(
            "the checkpoint is at t = {} s, at or past the end time {} s: nothing to run (give a later --end-time to continue)",
            sim.time(),
            sim.end_time()
        ));
    }
    Ok(())
}

/// The options that take no value.
pub const FLAGS: [&str; 6] = [
    "--quiet",
    "-q",
    "--no-vtu",
    "--overwrite",
    "--help",
    "--version",
];

impl Args {
    /// Parses `std::env::args()` (skipping the program name), for the
    /// bundled examples: `-h`/`--help` prints the common options and
    /// `--version` the version, and both exit the process; `--threads N`
    /// sizes the worker pool (before any parallel work).
    pub fn from_env() -> Result<Self, ArgsError> {
        Self::from_env_help(USAGE.to_string())
    }

    /// [`Args::from_env`] for a program that says its own options: `own`,
    /// their help (one option a line, as [`USAGE`]'s; empty for none), is
    /// printed by `--help` after the common options ([`usage_with`]; the
    /// examples' `--help` listed the common options only: session 53's
    /// review).
    pub fn from_env_with(own: &str) -> Result<Self, ArgsError> {
        Self::from_env_help(usage_with(own))
    }

    fn from_env_help(help: String) -> Result<Self, ArgsError> {
        // `std::env::args` panics on an argument that is not UTF-8.
        let args = std::env::args_os()
            .skip(1)
            .map(|a| {
                a.into_string()
                    .map_err(|a| ArgsError(format!("argument {a:?} is not valid UTF-8")))
            })
            .collect::<Result<Vec<String>, ArgsError>>()?;
        let asked = |names: [&str; 2]| asks(&args, names);
        if asked(["-h", "--help"]) {
            crate::outln!("{help}");
            std::process::exit(0);
        }
        if asked(["--version", "-V"]) {
            crate::outln!("pfem {}", env!("CARGO_PKG_VERSION"));
            std::process::exit(0);
        }
        let parsed = Self::parse(args)?;
        parsed.reject_positional()?;
        parsed.apply_threads()?;
        Ok(parsed)
    }

    /// The output folder: `--out`, else with `--restart` the checkpoint's
    /// own folder (its real file's), else `default`.
    pub fn out_or(&self, default: impl Into<PathBuf>) -> PathBuf {
        if let Some(out) = &self.out {
            return out.clone();
        }
        let own = self
            .options
            .get("restart")
            .and_then(|f| std::fs::canonicalize(f).ok())
            .and_then(|real| real.parent().map(std::path::Path::to_path_buf));
        own.unwrap_or_else(|| default.into())
    }

    /// Continues the run from `--restart CHECKPOINT` when given (the
    /// examples' counterpart of `pfem run --restart`; before session 54 an
    /// example wrote a checkpoint on `--max-wall-time` and could not read
    /// it): reads it within the memory budget, restores `sim` from it
    /// ([`crate::Simulation::restore`]: a scene, a setting or a hook that
    /// differs from the checkpoint's is refused, naming it) and resumes
    /// `output` in its folder ([`crate::StandardOutput::resume`]). The
    /// output must write into the checkpoint's own folder ([`Args::out_or`]
    /// gives it); a checkpoint at or past the end time is refused (nothing
    /// to run). Call it after the hooks are added and before the run.
    /// Without `--restart`, does nothing.
    pub fn restart<const D: usize>(
        &self,
        sim: &mut crate::Simulation<D>,
        output: &mut crate::StandardOutput<D>,
        out: &std::path::Path,
    ) -> Result<(), Box<dyn std::error::Error>>
    where
        pfem_core::Const<D>: pfem_core::Dim,
    {
        let Some(f) = self.options.get("restart") else {
            return Ok(());
        };
        let own = std::fs::canonicalize(f)
            .map_err(|e| ArgsError(format!("--restart {f}: {e}")))?
            .parent()
            .map(std::path::Path::to_path_buf);
        let here = std::fs::canonicalize(out).ok();
        if own.is_none() || here != own {
            return Err(ArgsError(format!(
                "--restart {f} --out {}: an example continues in its checkpoint's own folder (leave --out out, or give that folder)",
                out.display()
            ))
            .into());
        }
        let ck = crate::observe::read_checkpoint_within(f, self.memory_budget()?)
            .map_err(|e| format!("--restart {f}: {e}"))?;
        continue_from(sim, output, &ck).map_err(|e| format!("--restart {f}: {e}"))?;
        crate::errln!(
            "restarted from {f} at t = {} s (step {})",
            sim.time(),
            sim.steps()
        );
        Ok(())
    }

    /// Refuses bare words: an example takes options only, and a bare word
    /// is a mistake (`-quiet`, or a folder given without `--out`), not
    /// something to ignore ([`Args::from_env`] asks).
    pub fn reject_positional(&self) -> Result<(), ArgsError> {
        match self.positional.first() {
            Some(word) => Err(ArgsError(format!(
                "unexpected argument `{word}`: the examples take `--name value` options only (see --help)"
            ))),
            None => Ok(()),
        }
    }

    /// Refuses `--out` and `--overwrite` for the examples that write no
    /// files (a user who asks for a folder expects one); `--quiet` and
    /// `--no-vtu`, which ask for less, are accepted, so that a script may
    /// pass them to every example.
    pub fn reject_output_options(&self, example: &str) -> Result<(), ArgsError> {
        if self.out.is_some() || self.overwrite {
            return Err(ArgsError(format!(
                "{example} prints its figures and writes no files: --out and --overwrite do not apply"
            )));
        }
        Ok(())
    }

    /// Sizes rayon's global pool from `--threads N` (no-op without it).
    pub fn apply_threads(&self) -> Result<(), ArgsError> {
        if let Some(v) = self.options.get("threads") {
            let n = parse_threads(v)?;
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build_global()
                .map_err(|e| ArgsError(format!("--threads {n}: {e}")))?;
        }
        Ok(())
    }

    /// Parses the given arguments (options take a value, except the
    /// [`FLAGS`]).
    pub fn parse(args: impl IntoIterator<Item = String>) -> Result<Self, ArgsError> {
        let mut out = Args::default();
        let mut it = args.into_iter();
        while let Some(a) = it.next() {
            match a.as_str() {
                "--quiet" | "-q" => out.quiet = true,
                "--no-vtu" => out.no_vtu = true,
                "--overwrite" => out.overwrite = true,
                s if s.starts_with("--") => {
                    let name = s.trim_start_matches("--").to_string();
                    // `--end-time=0.1` as well as `--end-time 0.1` (it was
                    // read as an option named `end-time=0.1` that needed a
                    // value; a review of session 53).
                    let (name, inline) = match name.split_once('=') {
                        Some((n, v)) => (n.to_string(), Some(v.to_string())),
                        None => (name, None),
                    };
                    let given = inline.is_some();
                    let value = match inline {
                        Some(v) => v,
                        None => it.next().ok_or_else(|| {
                            ArgsError(format!(
                                "--{name} needs a value (or is not an option: see --help)"
                            ))
                        })?,
                    };
                    // `--out --no-vtu` is a forgotten value, not a folder
                    // named `--no-vtu`.
                    if !given && (value.starts_with("--") || FLAGS.contains(&value.as_str())) {
                        return Err(ArgsError(format!(
                            "--{name} needs a value, got the option `{value}`"
                        )));
                    }
                    match name.as_str() {
                        "out" if value.is_empty() => {
                            return Err(ArgsError(
                                "--out needs a directory, got an empty one (`.` for the working directory)"
                                    .into(),
                            ))
                        }
                        "out" => out.out = Some(PathBuf::from(value)),
                        "spacing" => out.spacing = Some(parse_positive(&name, &value)?),
                        "end-time" => out.end_time = Some(parse_positive(&name, &value)?),
                        _ => {
                            out.options.insert(name, value);
                        }
                    }
                }
                _ => out.positional.push(a),
            }
        }
        Ok(out)
    }

    /// A positive number option `--name`, or `default`.
    pub fn number(&self, name: &str, default: f64) -> Result<f64, ArgsError> {
        match self.options.get(name) {
            Some(v) => parse_positive(name, v),
            None => Ok(default),
        }
    }

    /// Time-integration parameters from `--scheme newmark|bossak|euler`,
    /// `--picard-tol TOL`, `--picard-stop change|estimate`
    /// (`StepParams::picard_error_estimate`), `--picard-relaxation
    /// none|aitken` (`StepParams::picard_relaxation`) and `--picard-forcing F`
    /// (`StepParams::picard_forcing`; defaults: Bossak with α_B = −0.3,
    /// tolerance 1e-6, `change`, 1e-3).
    pub fn step_params(&self) -> Result<pfem_time::StepParams, ArgsError> {
        let mut p = pfem_time::StepParams::default();
        match self.options.get("scheme").map(String::as_str) {
            None | Some("bossak") => p.scheme = pfem_time::Scheme::Bossak,
            Some("newmark") => p.scheme = pfem_time::Scheme::Newmark,
            Some("euler") => p.scheme = pfem_time::Scheme::BackwardEuler,
            Some(other) => {
                return Err(ArgsError(format!(
                    "--scheme must be newmark, bossak or euler, got `{other}`"
                )))
            }
        }
        p.picard_tolerance = self.number("picard-tol", p.picard_tolerance)?;
        match self.options.get("picard-stop").map(String::as_str) {
            None | Some("change") => p.picard_error_estimate = false,
            Some("estimate") => p.picard_error_estimate = true,
            Some(other) => {
                return Err(ArgsError(format!(
                    "--picard-stop must be change or estimate, got `{other}`"
                )))
            }
        }
        match self.options.get("picard-relaxation").map(String::as_str) {
            None | Some("none") => p.picard_relaxation = false,
            Some("aitken") => p.picard_relaxation = true,
            Some(other) => {
                return Err(ArgsError(format!(
                    "--picard-relaxation must be none or aitken, got `{other}`"
                )))
            }
        }
        if let Some(x) = self.bounded(
            "picard-forcing",
            |x| (0.0..1.0).contains(&x),
            "a number in [0, 1)",
        )? {
            p.picard_forcing = x;
        }
        if let Some(x) = self.bounded(
            "pressure-stabilisation",
            |x| x >= 0.0 && x.is_finite(),
            "a number ≥ 0",
        )? {
            p.pressure_stabilisation = x;
        }
        if let Some(q) = self.bounded(
            "sliver-quality-3d",
            |q| (0.0..0.5).contains(&q),
            "a number in [0, 0.5)",
        )? {
            p.sliver_quality_3d = q;
        }
        if let Some(q) = self.bounded(
            "sliver-stabilised-3d",
            |q| (0.0..0.5).contains(&q),
            "a number in [0, 0.5)",
        )? {
            p.sliver_stabilised_3d = q;
        }
        if let Some(q) = self.bounded(
            "sliver-quality-2d",
            |q| (0.0..1.0).contains(&q),
            "a number in [0, 1)",
        )? {
            p.sliver_quality_2d = q;
        }
        match self.options.get("sliver-prediction").map(String::as_str) {
            None | Some("on") => {}
            Some("off") => p.sliver_prediction = false,
            Some(other) => {
                return Err(ArgsError(format!(
                    "--sliver-prediction must be on or off, got `{other}`"
                )))
            }
        }
        match self.options.get("first-iterate").map(String::as_str) {
            None | Some("start") => p.predict_first_iterate = false,
            Some("predicted") => p.predict_first_iterate = true,
            Some(other) => {
                return Err(ArgsError(format!(
                    "--first-iterate must be start or predicted, got `{other}`"
                )))
            }
        }
        Ok(p)
    }

    /// The linear solver chosen by
    /// `--solver block|block-amg|direct|lu|cholesky|cg|petsc` (default
    /// `block`: [`pfem_assembly::BlockSolver`], the split system by
    /// conjugate gradient; `block-amg`: the same with multigrid on the
    /// pressure; `direct`: Cholesky of the whole system with LU fallback;
    /// `petsc` with the `petsc` feature).
    pub fn solver(&self) -> Result<Box<dyn pfem_assembly::LinearSolver>, ArgsError> {
        use pfem_assembly::{
            BlockSolver, ConjugateGradient, DirectSolver, SparseCholesky, SparseLu,
        };
        Ok(match self.options.get("solver").map(String::as_str) {
            Some("direct") => Box::new(DirectSolver::default()),
            Some("lu") => Box::new(SparseLu::default()),
            Some("cholesky") => Box::new(SparseCholesky::default()),
            Some("cg") => Box::new(ConjugateGradient::default()),
            None | Some("block") => Box::new(BlockSolver::default()),
            Some("block-amg") => {
                let mut b = BlockSolver::default();
                b.pressure = pfem_assembly::PressureSolve::Multigrid;
                Box::new(b)
            }
            #[cfg(feature = "petsc")]
            Some("petsc") => Box::new(pfem_petsc::PetscSolver::default()),
            #[cfg(not(feature = "petsc"))]
            Some("petsc") => {
                return Err(ArgsError(
                    "--solver petsc needs pfem built with the `petsc` feature (and PETSc installed)"
                        .into(),
                ))
            }
            Some(other) => {
                return Err(ArgsError(format!(
                    "--solver must be block, block-amg, direct, lu, cholesky, cg or petsc, got `{other}`"
                )))
            }
        })
    }

    /// A simulation of `scene` with the time scheme, linear solver and mass
    /// correction these arguments choose (`--scheme`, `--picard-tol`,
    /// `--solver`, `--volume-correction BETA`, 0 to turn it off), and the
    /// largest step and 3D quality floor (`--max-dt`, `--min-quality-3d`)
    /// when given.
    pub fn simulation<const D: usize>(
        &self,
        scene: crate::Scene<D>,
        tessellator: Box<dyn pfem_geometry::Tessellator<D>>,
    ) -> Result<crate::Simulation<D>, Box<dyn std::error::Error>>
    where
        pfem_core::Const<D>: pfem_core::Dim,
    {
        self.check_dimension(D)?;
        let mut options = crate::Options::default();
        if let Some(b) = self.volume_correction()? {
            options.volume_correction = b;
        }
        options.memory_budget = self.memory_budget()?;
        if let Some(q) = self.min_quality_3d()? {
            options.min_quality_3d = q;
        }
        options.tessellate_far_walls = self.tessellate_far_walls()?;
        let mut scene = scene;
        scene.settings.max_dt = self.number("max-dt", scene.settings.max_dt)?;
        // Given, it is the scene's too: `StepParams`' 0 means "the
        // scene's", so `--pressure-stabilisation 0` left a scene's
        // stabilisation on (`[run] pressure_stabilisation`).
        let params = self.step_params()?;
        if self.options.contains_key("pressure-stabilisation") {
            scene = scene.pressure_stabilisation(params.pressure_stabilisation);
        }
        let mut sim = crate::Simulation::with_options(scene, tessellator, params, options)?;
        sim.set_solver(self.solver()?);
        if let Some(v) = self.options.get("max-wall-time") {
            let limit = parse_positive("max-wall-time", v)?;
            sim.add_hook(Box::new(crate::hooks::WallClockLimit::new(limit)));
        }
        Ok(sim)
    }

    /// Refuses an option of the other dimension than `d` (2 or 3): it
    /// would do nothing, yet be recorded in a checkpoint's settings and
    /// refuse a restart with another value (session 43's review).
    pub fn check_dimension(&self, d: usize) -> Result<(), ArgsError> {
        let other: &[&str] = if d == 2 {
            &[
                "min-quality-3d",
                "sliver-quality-3d",
                "sliver-stabilised-3d",
                "far-walls",
            ]
        } else {
            &["sliver-quality-2d"]
        };
        if let Some(k) = other.iter().find(|k| self.options.contains_key(**k)) {
            let (its, this) = if d == 2 { ("3D", "2D") } else { ("2D", "3D") };
            return Err(ArgsError(format!(
                "--{k} is for {its} scenes; this scene is {this}"
            )));
        }
        Ok(())
    }

    /// `--far-walls skip|tessellate` (`Options::tessellate_far_walls`;
    /// default skip).
    pub fn tessellate_far_walls(&self) -> Result<bool, ArgsError> {
        match self.options.get("far-walls").map(String::as_str) {
            None | Some("skip") => Ok(false),
            Some("tessellate") => Ok(true),
            Some(other) => Err(ArgsError(format!(
                "--far-walls must be skip or tessellate, got `{other}`"
            ))),
        }
    }

    /// The 3D quality floor `--min-quality-3d Q` (`Options::min_quality_3d`,
    /// in `[0, 0.5)`), if given.
    pub fn min_quality_3d(&self) -> Result<Option<f64>, ArgsError> {
        self.bounded(
            "min-quality-3d",
            |q| (0.0..0.5).contains(&q),
            "a number in [0, 0.5)",
        )
    }

    /// The volume correction `--volume-correction BETA`, in `[0, 1]`, if
    /// given.
    pub fn volume_correction(&self) -> Result<Option<f64>, ArgsError> {
        self.bounded(
            "volume-correction",
            |b| (0.0..=1.0).contains(&b),
            "a number in [0, 1]",
        )
    }

    /// The number option `--name`, if given, when `ok` accepts it; else
    /// "--name must be `what`, got …".
    fn bounded(
        &self,
        name: &str,
        ok: impl Fn(f64) -> bool,
        what: &str,
    ) -> Result<Option<f64>, ArgsError> {
        let Some(v) = self.options.get(name) else {
            return Ok(None);
        };
        match v.parse::<f64>() {
            Ok(x) if ok(x) => Ok(Some(x)),
            _ => Err(ArgsError(format!("--{name} must be {what}, got `{v}`"))),
        }
    }

    /// The memory budget (bytes): `--memory-budget GB`, or 80 % of the
    /// machine's memory.
    pub fn memory_budget(&self) -> Result<f64, ArgsError> {
        match self.options.get("memory-budget") {
            Some(v) => Ok(parse_positive("memory-budget", v)? * 1e9),
            None => Ok(pfem_scene::default_memory_budget()),
        }
    }

    /// Parses every common option as a run would (`--scheme`,
    /// `--picard-tol`, `--solver`, `--volume-correction`,
    /// `--memory-budget`, `--max-wall-time`, `--threads`, `--max-dt`,
    /// `--min-quality-3d`), without running.
    pub fn validate_options(&self) -> Result<(), ArgsError> {
        self.step_params()?;
        self.solver()?;
        self.memory_budget()?;
        self.min_quality_3d()?;
        self.tessellate_far_walls()?;
        self.number("max-dt", 1.0)?;
        self.volume_correction()?;
        if let Some(v) = self.options.get("max-wall-time") {
            parse_positive("max-wall-time", v)?;
        }
        if let Some(v) = self.options.get("threads") {
            parse_threads(v)?;
        }
        Ok(())
    }

    /// Fails on options not in `known` (besides the common ones,
    /// `COMMON`).
    pub fn reject_unknown(&self, known: &[&str]) -> Result<(), ArgsError> {
        for k in self.options.keys() {
            if !known.contains(&k.as_str()) && !COMMON.contains(&k.as_str()) {
                return Err(ArgsError(format!(
                    "unknown option --{k} (known: --out --spacing --end-time --quiet --no-vtu --overwrite --scheme --picard-tol --picard-stop --picard-relaxation --picard-forcing --solver --volume-correction --pressure-stabilisation --memory-budget --max-wall-time --threads --max-dt --min-quality-3d --sliver-quality-3d --sliver-stabilised-3d --sliver-quality-2d --sliver-prediction --first-iterate --far-walls{})",
                    known.iter().map(|k| format!(" --{k}")).collect::<String>()
                )));
            }
        }
        Ok(())
    }
}

/// Value options every program accepts besides `--out`, `--spacing` and
/// `--end-time`.
const COMMON: [&str; 19] = [
    "scheme",
    "picard-tol",
    "picard-stop",
    "picard-relaxation",
    "picard-forcing",
    "pressure-stabilisation",
    "solver",
    "volume-correction",
    "memory-budget",
    "max-wall-time",
    "threads",
    "max-dt",
    "min-quality-3d",
    "sliver-quality-3d",
    "sliver-stabilised-3d",
    "sliver-quality-2d",
    "sliver-prediction",
    "first-iterate",
    "far-walls",
];

/// The common options, for `--help`.
pub const USAGE: &str = "\
Options common to the bundled examples and `pfem run`:
  --out DIR             output directory
  --overwrite           clear the previous run's files from DIR (a non-empty DIR is refused without it;
                        a restart clears nothing: it continues its checkpoint's folder)
  --spacing H           particle spacing (m)
  --end-time T          simulated time (s)
  --quiet, -q           no progress bar
  --no-vtu              no VTU frames
  --scheme S            bossak (default), newmark or euler
  --picard-tol X        Picard tolerance (default 1e-6)
  --picard-stop S       change (default) or estimate (also stop on the estimated error)
  --picard-relaxation R none (default) or aitken (relax the Picard iterates: sticking
                        frictional contact)
  --picard-forcing F    iterative solvers solve a Picard iterate to F times the last
                        change (default 1e-3; 0: every iterate to the solver's target)
  --solver S            block (default), block-amg (multigrid), direct, lu, cholesky, cg
                        or petsc (built with the `petsc` feature; PETSc options in
                        PFEM_PETSC_OPTIONS, prefix -pfem_); block-amg is for a
                        stabilised pressure (without it, measured 24x slower)
  --pressure-stabilisation A
                        pressure stabilisation factor of τ (default: the scene's,
                        0 = off unless a scene file sets `[run] pressure_stabilisation`;
                        given, it overrides the scene's, 0 switching it off)
  --volume-correction B fraction of the volume error restored per step, in [0, 1] (default 1)
  --memory-budget GB    refuse scenes estimated above this (default: 80 % of the machine's memory)
  --max-wall-time S     stop the run after S seconds of wall time (outputs are kept)
  --max-dt S            largest time step (s; default: the scene's)
  --min-quality-3d Q    3D quality floor of fluid tetrahedra, in [0, 0.5) (default 1e-3)
  --sliver-quality-3d Q fluid tetrahedra below this quality keep their start-of-step shape, in [0, 0.5) (default 0.06; 0: off)
  --sliver-stabilised-3d Q
                        those of quality at least Q at the step's start carry the pressure
                        stabilisation there, in [0, 0.5) (default 0.02)
  --sliver-quality-2d Q the same for 2D triangles, in [0, 1) (default 0: off; 0.05 measured)
  --sliver-prediction on|off  also those whose predicted end-of-step quality is below it (default on)
  --first-iterate start|predicted
                        Picard's first iterate: the start of the step (default) or
                        the fluid's constant-acceleration prediction
  --far-walls skip|tessellate
                        3D remeshing: only the walls within a few spacings of a fluid
                        or solid particle (default skip), or every wall particle
  --threads N           worker threads (default: one per core)
  --version             print the version
  --help, -h            this help
Each example has its own options too (see its source's header).";

/// [`USAGE`] followed by a program's own options `own` (none: the
/// common options alone).
pub fn usage_with(own: &str) -> String {
    let common =
        USAGE.trim_end_matches("Each example has its own options too (see its source's header).");
    if own.trim().is_empty() {
        format!("{common}This program has no options of its own.")
    } else {
        format!("{common}Options of this program:\n{}", own.trim_end())
    }
}

fn parse_positive(name: &str, v: &str) -> Result<f64, ArgsError> {
    match v.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(ArgsError(format!(
            "--{name} must be a positive number, got `{v}`"
        ))),
    }
}

/// `--threads N`: a positive integer, at most four threads per core of
/// this machine (at least 8): more only slow a run, and a very large
/// number spends the run creating threads.
fn parse_threads(v: &str) -> Result<usize, ArgsError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let limit = (4 * cores).max(8);
    match v.parse::<usize>() {
        Ok(n) if n > 0 && n <= limit => Ok(n),
        Ok(n) if n > limit => Err(ArgsError(format!(
            "--threads {n} is more than {limit}, four per core of this machine's {cores}: extra threads only slow the run"
        ))),
        _ => Err(ArgsError(format!(
            "--threads must be a positive integer, got `{v}`"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A program's own options follow the common ones in its help, and a
    /// program with none says so (the examples' help listed the common
    /// options only, pointing to their sources: session 53's review).
    #[test]
    fn a_program_s_help_lists_its_own_options() {
        let own = "  --young E             Young's modulus (Pa)";
        let help = usage_with(own);
        assert!(help.starts_with("Options common"), "{help}");
        assert!(help.contains("--max-wall-time"), "{help}");
        assert!(
            help.ends_with(&format!("Options of this program:\n{own}")),
            "{help}"
        );
        assert!(!help.contains("see its source"), "{help}");
        assert!(usage_with("").ends_with("no options of its own."));
    }

    /// `-h` asks for the help, except as an option's value (session 35's
    /// review: `--out -h` printed the help and exited).
    #[test]
    fn help_is_asked_only_where_it_is_no_value() {
        let v = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let help = ["-h", "--help"];
        assert!(asks(&v(&["-h"]), help));
        assert!(asks(&v(&["--quiet", "-h"]), help));
        assert!(asks(&v(&["--out", "d", "--help"]), help));
        assert!(!asks(&v(&["--out", "-h"]), help));
        assert!(!asks(
            &v(&["--spacing", "0.01", "--out", "-h", "--quiet"]),
            help
        ));
        assert!(asks(&v(&["--no-vtu", "--version"]), ["--version", "-V"]));
        assert!(!asks(&v(&["--out", "--version"]), ["--version", "-V"]));
    }

    /// A huge `--threads` spent a tiny run creating threads (10 000 did
    /// not finish in 100 s, session 26's review): refused with the limit.
    #[test]
    fn too_many_threads_are_refused() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let limit = (4 * cores).max(8);
        let args = |n: usize| Args::parse(["--threads".into(), n.to_string()]).unwrap();
        assert!(args(limit).validate_options().is_ok());
        let why = args(limit + 1).validate_options().unwrap_err().0;
        assert!(why.contains(&format!("more than {limit}")), "{why}");
        let why = Args::parse(["--bogus".to_string()]).unwrap_err().0;
        assert!(why.contains("not an option"), "{why}");
    }

    #[test]
    fn parses_the_contract_and_rejects_bad_values() {
        let a = Args::parse(
            [
                "--out",
                "d",
                "--spacing",
                "0.01",
                "--quiet",
                "--aspect",
                "2",
            ]
            .map(String::from),
        )
        .unwrap();
        assert_eq!(a.out, Some(PathBuf::from("d")));
        assert_eq!(a.spacing, Some(0.01));
        assert!(a.quiet);
        assert_eq!(a.number("aspect", 1.0).unwrap(), 2.0);
        assert!(a.reject_unknown(&["aspect"]).is_ok());
        assert!(a.reject_unknown(&[]).is_err());
        assert!(Args::parse(["--spacing", "-1"].map(String::from)).is_err());
        assert!(Args::parse(["--out"].map(String::from)).is_err());
        // `--name=value` too (session 53's review: "--end-time=0.01 needs
        // a value").
        let eq =
            Args::parse(["--end-time=0.01", "--out=d", "--aspect=2"].map(String::from)).unwrap();
        assert_eq!(eq.end_time, Some(0.01));
        assert_eq!(eq.out, Some(PathBuf::from("d")));
        assert_eq!(eq.number("aspect", 1.0).unwrap(), 2.0);
        assert!(Args::parse(["--spacing=-1"].map(String::from)).is_err());
        // Session 42's review: an option as a value was taken for it (a
        // folder named `--no-vtu`), and bare words were ignored.
        for flag in ["--no-vtu", "--quiet", "-q", "--end-time"] {
            let e = Args::parse(["--out", flag].map(String::from)).unwrap_err();
            assert!(e.0.contains("needs a value"), "{e}");
        }
        let bare = Args::parse(["out/run1", "-quiet"].map(String::from)).unwrap();
        assert_eq!(bare.positional, ["out/run1", "-quiet"]);
        assert!(bare
            .reject_positional()
            .unwrap_err()
            .0
            .contains("`out/run1`"));
        assert!(a.reject_positional().is_ok());
        assert!(a.reject_output_options("x").is_err());
        let quiet = Args::parse(["--quiet", "--no-vtu"].map(String::from)).unwrap();
        assert!(quiet.reject_output_options("x").is_ok());
    }

    /// `--solver petsc` builds PETSc's solver with the `petsc` feature and
    /// says what is missing without it.
    #[test]
    fn the_petsc_solver_needs_its_feature() {
        let a = Args::parse(["--solver", "petsc"].map(String::from)).unwrap();
        let built = cfg!(feature = "petsc");
        match a.solver() {
            Ok(s) => assert_eq!((built, s.name()), (true, "petsc")),
            Err(e) => {
                assert!(!built);
                assert!(e.to_string().contains("`petsc` feature"), "{e}");
            }
        }
        let bad = Args::parse(["--solver", "pets"].map(String::from)).unwrap();
        assert!(bad.solver().is_err());
    }

    /// `--max-dt`, `--min-quality-3d` and `--sliver-quality-3d` reach the simulation; bad values
    /// are refused before it is built.
    #[test]
    fn the_largest_step_and_the_quality_floor_are_options() {
        let scene = || {
            crate::cases::DamBreak {
                spacing: 0.05715 / 4.0,
                ..Default::default()
            }
            .scene()
        };
        let args = |v: &[&str]| Args::parse(v.iter().map(|s| s.to_string())).unwrap();
        let a = args(&[
            "--max-dt",
            "0.0004",
            "--min-quality-3d",
            "0.06",
            "--sliver-quality-3d",
            "0.01",
        ]);
        assert!(a.reject_unknown(&[]).is_ok());
        assert!(a.validate_options().is_ok());
        assert_eq!(a.min_quality_3d().unwrap(), Some(0.06));
        assert_eq!(a.step_params().unwrap().sliver_quality_3d, 0.01);
        assert!(!a.step_params().unwrap().picard_error_estimate);
        let e = args(&["--picard-stop", "estimate"]);
        assert!(e.reject_unknown(&[]).is_ok());
        assert!(e.step_params().unwrap().picard_error_estimate);
        assert!(!a.step_params().unwrap().picard_relaxation);
        let r = args(&["--picard-relaxation", "aitken"]);
        assert!(r.reject_unknown(&[]).is_ok());
        assert!(r.step_params().unwrap().picard_relaxation);
        assert!(a.step_params().unwrap().sliver_prediction);
        let off = args(&["--sliver-prediction", "off"]);
        assert!(off.reject_unknown(&[]).is_ok());
        assert!(!off.step_params().unwrap().sliver_prediction);
        assert!(args(&["--sliver-prediction", "no"]).step_params().is_err());
        let q2 = args(&["--sliver-quality-2d", "0.1"]);
        assert!(q2.reject_unknown(&[]).is_ok());
        assert_eq!(q2.step_params().unwrap().sliver_quality_2d, 0.1);
        assert!(args(&["--sliver-quality-2d", "1.2"]).step_params().is_err());
        assert_eq!(
            a.step_params().unwrap().sliver_stabilised_3d,
            pfem_time::SLIVER_STABILISED_3D
        );
        let s3 = args(&["--sliver-stabilised-3d", "0.04"]);
        assert!(s3.reject_unknown(&[]).is_ok());
        assert_eq!(s3.step_params().unwrap().sliver_stabilised_3d, 0.04);
        assert_eq!(a.step_params().unwrap().sliver_quality_2d, 0.0);
        assert!(!a.step_params().unwrap().predict_first_iterate);
        let fi = args(&["--first-iterate", "predicted"]);
        assert!(fi.reject_unknown(&[]).is_ok());
        assert!(fi.step_params().unwrap().predict_first_iterate);
        assert!(args(&["--first-iterate", "end"]).step_params().is_err());
        assert_eq!(
            a.step_params().unwrap().picard_forcing,
            pfem_time::PICARD_FORCING
        );
        let pf = args(&["--picard-forcing", "0"]);
        assert!(pf.reject_unknown(&[]).is_ok());
        assert_eq!(pf.step_params().unwrap().picard_forcing, 0.0);
        assert!(args(&["--picard-forcing", "1"]).step_params().is_err());
        assert!(args(&["--picard-forcing", "-1e-3"]).step_params().is_err());
        // (The 2D scene refuses `a`'s 3D options; its largest step alone.)
        let sim = args(&["--max-dt", "0.0004"])
            .simulation(scene(), Box::new(pfem_geometry::Delaunay2::default()))
            .unwrap();
        // Before the first step the clock holds the largest step.
        assert_eq!(sim.dt(), 0.0004);
        for bad in [
            &["--max-dt", "0"][..],
            &["--max-dt", "nan"],
            &["--min-quality-3d", "0.5"],
            &["--min-quality-3d", "-0.1"],
            &["--sliver-quality-3d", "0.5"],
            &["--sliver-quality-3d", "-1"],
            &["--sliver-stabilised-3d", "0.5"],
            &["--sliver-stabilised-3d", "nan"],
            &["--picard-stop", "never"],
            &["--picard-relaxation", "steffensen"],
        ] {
            let a = args(bad);
            assert!(a.validate_options().is_err(), "{bad:?}");
            assert!(a
                .simulation(scene(), Box::new(pfem_geometry::Delaunay2::default()))
                .is_err());
        }
        // Good values of the other dimension's options: refused by name.
        for other in [
            &["--min-quality-3d", "0.01"][..],
            &["--sliver-quality-3d", "0.1"],
            &["--sliver-stabilised-3d", "0.1"],
            &["--far-walls", "tessellate"],
        ] {
            let a = args(other);
            assert!(a.validate_options().is_ok(), "{other:?}");
            let why = a
                .simulation(scene(), Box::new(pfem_geometry::Delaunay2::default()))
                .expect_err("refused in 2D")
                .to_string();
            assert!(why.contains("3D scenes"), "{why}");
        }
    }
}
