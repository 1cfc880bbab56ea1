//! `pfem`: runs or checks a scene file (TOML, see `pfem::scene_file`).
//!
//! ```text
//! pfem run FILE [--out DIR] [--spacing H] [--end-time T] [--quiet] [--no-vtu]
//!          [--checkpoint-every T] [--probe-interval T] [--restart CHECKPOINT]
//! pfem check FILE [--spacing H] [--end-time T]
//! pfem --help
//! ```
//!
//! `run` writes the same outputs as the bundled examples into `DIR`
//! (default `out/NAME`): `NAME.pvd` + `NAME_*.vtu` frames, `probes.csv` and
//! `summary.json`, and `checkpoint.bin` when asked or interrupted. Errors
//! print a message and exit with status 1 (a run that fails mid-way writes
//! `summary.json` marked failed first); a run interrupted by Ctrl-C (or
//! SIGTERM) writes its outputs and a final checkpoint and exits with status
//! 130; one stopped by `--max-wall-time` does the same with status 2.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
#[cfg(feature = "signals")]
use std::sync::atomic::Ordering;
use std::sync::Arc;

use pfem::cli::Args;
use pfem::core::{Const, Dim};
use pfem::geometry::{Delaunay2, Delaunay3, Tessellator};
use pfem::scene_file::{LoadedScene, SceneFile};
use pfem::{Probe, Scene, StandardOutput};

const HELP: &str = "\
pfem: Particle Finite Element Method for fluid-structure interaction

Usage:
  pfem run FILE [--out DIR] [--spacing H] [--end-time T] [--quiet] [--no-vtu]
           [--checkpoint-every T] [--probe-interval T] [--restart CHECKPOINT]
           [OPTIONS]
  pfem check FILE [--spacing H] [--end-time T] [OPTIONS]
  pfem --help

Commands:
  run     run the scene file FILE (TOML) and write into DIR (default out/NAME,
          NAME the scene's name; with --restart, the checkpoint's folder):
          NAME.pvd + NAME_*.vtu frames, probes.csv and summary.json
          (and checkpoint.bin, see --checkpoint-every); Ctrl-C stops after
          the current step, writes the outputs, a checkpoint and a
          summary marked interrupted, and exits with status 130; a run
          stopped by --max-wall-time does the same and exits with status 2;
          a run that fails writes summary.json marked failed and exits
          with status 1
  check   read FILE, validate its scene and build the simulation as run
          does (its first mesh, initial accelerations); runs no step,
          writes nothing

Options of `pfem run`:
  --checkpoint-every T
                        write DIR/checkpoint.bin every T seconds of simulated time
                        and at the end (atomically; the last one is kept)
  --probe-interval T    a row of probes.csv every T seconds of simulated time
                        and at the end time (default: every step). The rows
                        go to probes.csv, none is kept in memory; this thins
                        the file (a note is printed when it would pass 1 GB)
  --restart CHECKPOINT  continue the run that wrote CHECKPOINT (same FILE,
                        whose text the checkpoint keeps: only [run]'s end_time
                        and output_interval may change; same options, other
                        ones refused). DIR is its output folder, by default the
                        checkpoint's; another folder must be empty and gets a
                        copy of probes.csv only, so a run that wrote frames
                        continues in its own folder or a copy of it. The result
                        is the uninterrupted run's, bit for bit (to the
                        solver's tolerance, 1e-9, with the pressure stabilised
                        on systems solved by multigrid: from 1 000 pressure
                        rows in 2D, 100 in 3D; docs/robustness.md).
                        With a later --end-time, a finished run goes on
";

/// The end of the help, after the options shared with the examples.
const HELP_END: &str = "
Scene files: see examples/scenes/*.toml and the pfem::scene_file docs.
Units are SI (m, s, kg, Pa; angles in rad). 2D is per metre of depth:
volumes m²/m, forces N/m. See docs/units.md.
";

fn main() -> ExitCode {
    // `std::env::args` panics on an argument that is not UTF-8.
    let mut args = Vec::new();
    for a in std::env::args_os().skip(1) {
        match a.into_string() {
            Ok(a) => args.push(a),
            Err(a) => {
                pfem::errln!("error: argument {a:?} is not valid UTF-8");
                return ExitCode::FAILURE;
            }
        }
    }
    // A panic inside the solver is a bug; still end with status 1 and a
    // message rather than the default 101.
    let result = std::panic::catch_unwind(|| run(args));
    match result {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) if e == INTERRUPTED => ExitCode::from(130),
        Ok(Err(e)) if e == STOPPED => ExitCode::from(2),
        Ok(Err(e)) => {
            pfem::errln!("error: {e}");
            ExitCode::FAILURE
        }
        Err(_) => {
            pfem::errln!("error: internal error (a panic, see above); please report it");
            ExitCode::FAILURE
        }
    }
}

/// An error of loading `file`, with the line of the body it names when the
/// error came from validating the scene.
fn located(file: &Path, e: pfem::SceneError, parsed: &Args) -> String {
    if matches!(e, pfem::SceneError::File { .. }) {
        return e.to_string();
    }
    // A limit the command line's `--end-time` or `--spacing` set is not the
    // file's line.
    let overridden = parsed.end_time.is_some() || parsed.spacing.is_some();
    if overridden
        && matches!(
            e,
            pfem::SceneError::CannotFinish { .. } | pfem::SceneError::TooLarge { .. }
        )
    {
        return format!("{e} (with the command line's --end-time / --spacing)");
    }
    match SceneFile::read(file).ok().and_then(|f| f.locate(&e)) {
        Some(at) => format!("scene file {}: {at}: {e}", file.display()),
        None => e.to_string(),
    }
}

fn run(args: Vec<String>) -> Result<(), String> {
    if args.is_empty() {
        return Err(format!("no command given\n\n{HELP}"));
    }
    if args[0] == "help" || pfem::cli::asks(&args, ["--help", "-h"]) {
        pfem::io::console::out_part(format_args!("{HELP}\n{}\n{HELP_END}", pfem::cli::USAGE));
        return Ok(());
    }
    if pfem::cli::asks(&args, ["--version", "-V"]) {
        pfem::outln!("pfem {}", env!("CARGO_PKG_VERSION"));
        return Ok(());
    }
    let command = args[0].as_str();
    if !matches!(command, "run" | "check") {
        return Err(format!(
            "unknown command `{command}` (run, check; see pfem --help)"
        ));
    }
    let parsed = Args::parse(args[1..].iter().cloned()).map_err(|e| e.to_string())?;
    parsed
        .reject_unknown(&["checkpoint-every", "probe-interval", "restart"])
        .map_err(|e| e.to_string())?;
    let checkpoint_every = parsed
        .options
        .get("checkpoint-every")
        .map(|_| parsed.number("checkpoint-every", 1.0))
        .transpose()
        .map_err(|e| e.to_string())?;
    let probe_interval = parsed
        .options
        .get("probe-interval")
        .map(|_| parsed.number("probe-interval", 1.0))
        .transpose()
        .map_err(|e| e.to_string())?;
    let file = match parsed.positional.as_slice() {
        [f] => PathBuf::from(f),
        [] => {
            return Err(format!(
                "`pfem {command}` needs a scene file (see pfem --help)"
            ))
        }
        more => {
            return Err(format!(
                "`pfem {command}` takes one scene file, got {}: {}",
                more.len(),
                more.join(" ")
            ))
        }
    };
    match command {
        "check" => {
            if parsed.out.is_some()
                || parsed.no_vtu
                || parsed.overwrite
                || checkpoint_every.is_some()
                || probe_interval.is_some()
                || parsed.options.contains_key("restart")
            {
                return Err("`pfem check` writes nothing: --out, --no-vtu, --overwrite, --checkpoint-every, --probe-interval and --restart do not apply".into());
            }
            // The run options are checked as `run` would, and the threads
            // set: the simulation is built (its first mesh, its initial
            // accelerations) on as many as `run` would use.
            parsed.validate_options().map_err(|e| e.to_string())?;
            parsed.apply_threads().map_err(|e| e.to_string())?;
            let load = || {
                SceneFile::load(&file, parsed.spacing, parsed.end_time)
                    .map_err(|e| located(&file, e, &parsed))
            };
            // The scene twice: one to report on, one to build the
            // simulation from as `run` does (a scene is not `Clone`: its
            // materials are trait objects).
            match (load()?, load()?) {
                (LoadedScene::Two(s, p), LoadedScene::Two(again, _)) => check(
                    &file,
                    s,
                    again,
                    p.len(),
                    Box::new(Delaunay2::default()),
                    &parsed,
                ),
                (LoadedScene::Three(s, p), LoadedScene::Three(again, _)) => check(
                    &file,
                    s,
                    again,
                    p.len(),
                    Box::new(Delaunay3::default()),
                    &parsed,
                ),
                _ => Err(format!(
                    "{}: the scene file changed while it was read",
                    file.display()
                )),
            }
        }
        "run" => {
            parsed.validate_options().map_err(|e| e.to_string())?;
            parsed.apply_threads().map_err(|e| e.to_string())?;
            // As `SceneFile::load`, keeping the file: a checkpoint holds its
            // text, and a restart is refused under an edited one.
            let mut spec = SceneFile::read(&file).map_err(|e| located(&file, e, &parsed))?;
            if let Some(h) = parsed.spacing {
                spec.override_spacing(h);
            }
            if let Some(t) = parsed.end_time {
                spec.run.end_time = Some(t);
            }
            let loaded = spec.build().map_err(|e| located(&file, e, &parsed))?;
            match loaded {
                LoadedScene::Two(scene, probes) => simulate(
                    scene,
                    probes,
                    Box::new(Delaunay2::default()),
                    &parsed,
                    (checkpoint_every, probe_interval),
                    &spec,
                ),
                LoadedScene::Three(scene, probes) => simulate(
                    scene,
                    probes,
                    Box::new(Delaunay3::default()),
                    &parsed,
                    (checkpoint_every, probe_interval),
                    &spec,
                ),
            }
        }
        other => Err(format!(
            "unknown command `{other}` (run, check; see pfem --help)"
        )),
    }
}

/// Validates `scene` within the memory budget, builds its particles and
/// reports what a run would hold: particle counts (estimated and placed),
/// memory, steps, and every particle merged or welded. Then builds the simulation
/// from `again` (the same scene) as `run` would, so that whatever `run`
/// refuses before its first step (bodies inside their contact distance, a
/// first mesh that fails, initial accelerations that cannot be solved) is
/// refused here too. Runs no step and writes nothing.
fn check<const D: usize>(
    file: &Path,
    scene: Scene<D>,
    again: Scene<D>,
    probes: usize,
    mut tessellator: Box<dyn Tessellator<D>>,
    args: &Args,
) -> Result<(), String>
where
    Const<D>: Dim,
{
    args.check_dimension(D).map_err(|e| e.to_string())?;
    let budget = args.memory_budget().map_err(|e| e.to_string())?;
    let estimate = scene.validate_within(budget).map_err(|e| e.to_string())?;
    // `run`'s step ceiling (`--max-dt` overrides the scene's).
    let dt = args
        .number("max-dt", scene.settings.max_dt)
        .map_err(|e| e.to_string())?;
    let (name, bodies, t) = (
        scene.name.clone(),
        scene.bodies.len(),
        scene.settings.end_time,
    );
    let courant = scene.settings.courant;
    let kinks = scene.motion_kinks(pfem::scene::MAX_STEPS);
    // Within `--memory-budget`, as `run` builds it (before session 49 the
    // default budget: a raised one was refused here, honoured by `run`).
    let built = scene
        .build_within(budget, tessellator.as_mut())
        .map_err(|e| e.to_string())?;
    // The step count's lower bound: the largest step, or the Courant
    // limit of the initial speeds when that is tighter.
    let rate = built.particles.crossing_rate();
    let (steps, why) = if t * rate / courant > t / dt {
        (
            t * rate / courant,
            "the Courant limit of the initial speeds",
        )
    } else {
        (t / dt, "end time / max_dt")
    };
    // Each kink of a wall's motion law ends a step.
    let (steps, why) = if kinks > 0.0 {
        (
            steps + kinks,
            if why.starts_with("end") {
                "end time / max_dt, and the motion laws' kinks"
            } else {
                "the Courant limit of the initial speeds, and the motion laws' kinks"
            },
        )
    } else {
        (steps, why)
    };
    pfem::outln!(
        "{}: valid {D}D scene `{name}`: {bodies} bodies, {probes} probe columns, end time {t} s",
        file.display()
    );
    pfem::outln!(
        "  {} particles placed (estimated {:.0}), memory about {:.1} MB of a {:.1} GB budget, about {:.0} steps or more ({why})",
        built.particles.len(),
        estimate.particles,
        estimate.bytes / 1e6,
        budget / 1e9,
        steps.ceil()
    );
    for m in &built.merges {
        if m.dropped > 0 {
            pfem::outln!(
                "  warning: body `{}`: {} particles dropped (within a quarter spacing of an earlier body's particle)",
                m.body, m.dropped
            );
        }
        if m.duplicates > 0 {
            pfem::outln!(
                "  warning: body `{}`: {} particles dropped (within a quarter spacing of another of its own particles)",
                m.body, m.duplicates
            );
        }
        if m.unmeshed > 0 {
            pfem::outln!(
                "  warning: body `{}`: {} particles left out of its mesh (in no element: a corner or a part thinner than a spacing)",
                m.body, m.unmeshed
            );
        }
        if m.welded > 0 {
            pfem::outln!(
                "  body `{}`: {} wall particles replaced by a solid's, which is welded there",
                m.body,
                m.welded
            );
        }
    }
    // The simulation as `run` builds it: its first mesh, the contact
    // distances, the initial accelerations (the report's particles freed
    // first: the simulation places its own).
    drop(built);
    let drawn = drawn_fluids(&again);
    let sim = args
        .simulation(again, tessellator)
        .map_err(|e| e.to_string())?;
    pfem::outln!(
        "  simulation built: {} elements in the first mesh ({} contact)",
        sim.elements().len(),
        sim.elements().n_contact()
    );
    for w in scene_warnings(&sim, &drawn) {
        pfem::outln!("  warning: {w}");
    }
    Ok(())
}

/// What `pfem check` warns of, and `pfem run` before it starts:
/// [`spacing_warnings`] (the walls that no water touches at the start
/// compared with the finest fluid's spacing),
/// [`compressibility_warnings`], [`volume_warnings`] (the fluids of
/// `drawn`) and a 3D fluid without pressure stabilisation
/// ([`UNSTABILISED_3D`]).
fn scene_warnings<const D: usize>(sim: &pfem::Simulation<D>, drawn: &[Drawn]) -> Vec<String>
where
    Const<D>: Dim,
{
    let p = sim.particles();
    let finest_fluid = (0..p.len())
        .filter(|&i| p.kind()[i] == pfem::core::ParticleKind::Fluid)
        .map(|i| p.spacing()[i])
        .fold(f64::INFINITY, f64::min);
    let mut out = spacing_warnings(sim, finest_fluid);
    out.extend(compressibility_warnings(sim));
    out.extend(volume_warnings(sim, drawn));
    // 3D fluid on the paper's pressure (session 55's review): water
    // clings to no-slip walls and its pressures are noise.
    if D == 3 && finest_fluid.is_finite() && sim.step_params().pressure_stabilisation == 0.0 {
        out.push(UNSTABILISED_3D.to_string());
    }
    out
}

/// A fluid body as drawn: its name, the measure of its geometry
/// (`Geometry::measure`) and the geometry's kind.
type Drawn = (String, f64, &'static str);

/// The fluid bodies of `scene` whose geometry has a measure to compare
/// with their first mesh's: all but boxes (a lattice places their faces'
/// particles, and meshes them whole) and particle lists.
fn drawn_fluids<const D: usize>(scene: &Scene<D>) -> Vec<Drawn>
where
    Const<D>: Dim,
{
    use pfem::scene::Geometry;
    scene
        .bodies
        .iter()
        .filter(|b| b.kind == pfem::core::ParticleKind::Fluid)
        .filter_map(|b| {
            let kind = match &b.geometry {
                Geometry::Ball { .. } if D == 2 => "disk",
                Geometry::Ball { .. } => "ball",
                Geometry::Cylinder { .. } => "cylinder",
                Geometry::Surface(_) if D == 2 => "polygon",
                Geometry::Surface(_) => "closed surface",
                _ => return None,
            };
            Some((b.name.clone(), b.geometry.measure()?, kind))
        })
        .collect()
}

/// Fluids whose first mesh holds more than [`DRAWN_VOLUME`] less (or
/// more) than the region drawn: the mesh spans the particles' centres,
/// which a lattice filling a curved or slanted boundary leaves up to a
/// spacing inside it, and the fluid's mass is the mesh's. Measured
/// (session 55's review, 3D, h = 0.02 m): a ball of radius 0.1 m meshed
/// 3.125e-3 m³ of its 4.19e-3 (−25 %), a cylinder of radius 0.1 m and
/// height 0.2 m 5.28e-3 of 6.28e-3 (−16 %), unsaid; the ball −12 % and
/// −6 % at h = 0.01 and 0.005 m (first order); a 2D disk −16 and −8 %
/// at 5 and 10 spacings. A wall inside the region drawn (an obstacle the
/// fluid is drawn round) counts as a shortfall too: the warning names
/// both causes. Each fluid element's
/// measure is shared among its fluid particles' bodies.
fn volume_warnings<const D: usize>(sim: &pfem::Simulation<D>, drawn: &[Drawn]) -> Vec<String>
where
    Const<D>: Dim,
{
    use pfem::core::ParticleKind;
    if drawn.is_empty() {
        return Vec::new();
    }
    let p = sim.particles();
    let names = sim.body_names();
    let mut meshed = vec![0.0; names.len()];
    let mut points = [pfem::core::Point::<D>::zeros(); 4];
    for el in sim.elements().fluid().chunks_exact(D + 1) {
        for (k, &i) in el.iter().enumerate() {
            points[k] = p.x()[i as usize];
        }
        let v = pfem::core::simplex_measure::<D>(&points[..=D]).abs();
        let fluid = |i: &&u32| p.kind()[**i as usize] == ParticleKind::Fluid;
        let n = el.iter().filter(fluid).count();
        for &i in el.iter().filter(fluid) {
            meshed[p.body()[i as usize] as usize] += v / n as f64;
        }
    }
    let unit = if D == 2 { "m²/m" } else { "m³" };
    drawn
        .iter()
        .filter_map(|(name, nominal, kind)| {
            let b = names.iter().position(|n| n == name)?;
            let change = meshed[b] / nominal - 1.0;
            (change.abs() > DRAWN_VOLUME).then(|| {
                format!(
                    "fluid `{name}` is drawn as a {kind} of {nominal:.4e} {unit}, but its particles mesh {:.4e} {unit} ({:+.1} %), and the fluid's mass is the mesh's: where its boundary is curved or slanted, the mesh spans the particles' centres, up to a spacing inside it (the gap halves with the spacing: {}; refine the spacing, or draw the body larger to make up for it); where walls or solids take part of the region, their share is not water",
                    meshed[b],
                    100.0 * change,
                    if D == 2 {
                        "a disk of radius 5 and 10 spacings −16 and −8 %"
                    } else {
                        "a ball of radius 5, 10 and 20 spacings −25, −12 and −6 %"
                    }
                )
            })
        })
        .collect()
}

/// [`volume_warnings`]' bound on the relative difference.
const DRAWN_VOLUME: f64 = 0.05;

/// The warning of a 3D scene with fluid and no pressure stabilisation.
/// Measured (session 55): a 3D dam break (column 0.1 × 0.2 m, h =
/// 0.0125 m) between no-slip side walls 0.05 m apart kept 0.188 m of its
/// 0.2 m at the back wall at 0.22 s (0.091 m stabilised; its 2D twin
/// 0.095 m), its front at 0.250 m (0.393 m stabilised; Martin & Moyce
/// 0.389 m); 0.1 m apart the front ran (0.380 m) but 0.189 m still clung
/// to the back wall; fluid pressures of −66/+27 kPa (1st–99th
/// percentiles) against ρ g H ≈ 2 kPa.
const UNSTABILISED_3D: &str = "3D fluid without pressure stabilisation: water moving along no-slip walls clings to them and its pressures are noise (a 3D dam break kept 0.188 m of its 0.2 m column at the back wall at 0.22 s, against 0.091 m stabilised and 0.095 m in 2D); unless the water stays near rest, set `[run] pressure_stabilisation = 1.0` (or --pressure-stabilisation 1)";

/// Where the first mesh joins particles of spacings that do not keep water
/// at rest (a review, session 50, still water over 0.3 s):
/// - a wall and the fluid it touches, spacings more than 5 % apart: 0.015,
///   0.067, 0.11 and 0.39 m/s at wall spacings 0.8, 1.25, 1.5 and 5 times
///   the water's (10⁻¹⁴ m/s at the same spacing). Where the free surface
///   meets the wall it matters most: a floor alone 0.25 or 0.75 times the
///   water's, side walls of its spacing, kept it at rest (10⁻¹⁵ m/s,
///   session 51); the warning does not tell floors from sides. Until session 51 `check`
///   compared every wall with the scene's finest fluid, which missed a
///   fine floor under a coarse fluid; a wall that no fluid touches at the
///   start is still compared with the finest fluid (water may reach it);
/// - two fluids whose spacings differ more than [`FLUID_SPACING_RATIO`]
///   times where they meet: 4 times apart they opened a hole at rest
///   (1.35 m/s within 0.3 s, every wall of its fluid's spacing; session
///   51), 2 and 2.5 times apart they stayed at rest (10⁻¹⁵ m/s).
fn spacing_warnings<const D: usize>(sim: &pfem::Simulation<D>, finest_fluid: f64) -> Vec<String>
where
    Const<D>: Dim,
{
    use pfem::core::ParticleKind;
    let p = sim.particles();
    let names = sim.body_names();
    let nb = names.len();
    // Per wall body: the (smallest, largest) ratio of its spacing to a
    // fluid particle's it shares an element with.
    let mut wall = vec![(f64::INFINITY, 0.0_f64); nb];
    // Per pair of fluid bodies (coarse, fine): the largest ratio.
    let mut fluids: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
    for el in sim.elements().fluid().chunks_exact(D + 1) {
        for &a in el {
            let a = a as usize;
            if p.kind()[a] != ParticleKind::Fluid {
                continue;
            }
            for &b in el {
                let b = b as usize;
                let r = p.spacing()[b] / p.spacing()[a];
                let bb = p.body()[b] as usize;
                match p.kind()[b] {
                    ParticleKind::Wall if bb < nb => {
                        wall[bb] = (wall[bb].0.min(r), wall[bb].1.max(r));
                    }
                    ParticleKind::Fluid if r > 1.0 => {
                        let key = (bb, p.body()[a] as usize);
                        let e = fluids.entry(key).or_insert(r);
                        *e = e.max(r);
                    }
                    _ => {}
                }
            }
        }
    }
    let mut out = Vec::new();
    let mut seen = vec![false; nb];
    for i in 0..p.len() {
        let b = p.body()[i] as usize;
        if p.kind()[i] != ParticleKind::Wall || seen.get(b).copied().unwrap_or(true) {
            continue;
        }
        seen[b] = true;
        let (lo, hi) = wall[b];
        let far = |r: f64| !(0.95..=1.05).contains(&r);
        let leak = |r: f64| {
            if r > 1.0 {
                format!(", and water falling on a coarser one leaks into it ({WALL_LEAK})")
            } else {
                String::new()
            }
        };
        if hi > 0.0 {
            let r = if far(hi) && (!far(lo) || hi - 1.0 > 1.0 - lo) {
                hi
            } else {
                lo
            };
            if far(r) {
                out.push(format!(
                    "wall `{}` has {r:.2} times the spacing of the water it touches: water at rest beside a wall of another spacing can move (0.015 and 0.067 m/s measured with side walls 0.8 and 1.25 times the water's){}; give a wall the spacing of the water it touches",
                    names[b],
                    leak(r)
                ));
            }
        } else if finest_fluid.is_finite() {
            let r = p.spacing()[i] / finest_fluid;
            if far(r) {
                out.push(format!(
                    "wall `{}` touches no water at the start and has {r:.2} times the finest fluid's spacing ({} m against {finest_fluid} m): where water reaches it, water at rest beside a wall of another spacing can move (0.015 and 0.067 m/s measured with side walls 0.8 and 1.25 times the water's){}; give a wall the spacing of the water that will touch it",
                    names[b],
                    p.spacing()[i],
                    leak(r)
                ));
            }
        }
    }
    for ((coarse, fine), r) in fluids {
        if r > FLUID_SPACING_RATIO {
            out.push(format!(
                "fluids `{}` and `{}` meet with spacings {r:.2} times apart: 4 times apart still water opened a hole where they met (1.35 m/s within 0.3 s), {FLUID_SPACING_RATIO} times apart it stayed at rest; keep meeting fluids within {FLUID_SPACING_RATIO} times",
                names[coarse], names[fine]
            ));
        }
    }
    out
}

/// A fluid whose bulk modulus is not far above the pressures its flow
/// makes: `K < COMPRESSIBLE_BELOW ρ g H` (`H` its particles' extent along
/// gravity), a Mach number `√(2 g H) / c` above about 0.14 for a fall
/// through `H` (a review of session 54: the dam break with `K = 10⁵ Pa`,
/// 90 ρ g H, had two particles merge and blow apart at 11.8 m/s; at
/// `K = 1` the column burst at 10 times free fall). The quasi-incompressible
/// method wants `K` some 10⁴ times `ρ g H` or more (real water 2.2·10⁹ Pa).
fn compressibility_warnings<const D: usize>(sim: &pfem::Simulation<D>) -> Vec<String>
where
    Const<D>: Dim,
{
    use pfem::core::ParticleKind;
    let Some(g) = sim.gravity().filter(|g| g.norm() > 0.0) else {
        return Vec::new();
    };
    let down = g / g.norm();
    let p = sim.particles();
    // Per fluid body: its material and extent along gravity.
    let mut extent: std::collections::BTreeMap<u32, (u16, f64, f64)> = Default::default();
    for i in 0..p.len() {
        if p.kind()[i] != ParticleKind::Fluid {
            continue;
        }
        let z = p.x()[i].dot(&down);
        let e = extent.entry(p.body()[i]).or_insert((p.material()[i], z, z));
        *e = (e.0, e.1.min(z), e.2.max(z));
    }
    let managed = sim
        .hook_names()
        .iter()
        .any(|n| n == pfem::hooks::ParticleManagement::NAME);
    let mut out = Vec::new();
    for (b, (m, lo, hi)) in extent {
        let Some(law) = sim.materials().get(m as usize) else {
            continue;
        };
        let (rho, c) = (law.density(), law.wave_speed());
        let head = rho * g.norm() * (hi - lo);
        let k = rho * c * c;
        if head > 0.0 && k < COMPRESSIBLE_BELOW * head {
            out.push(format!(
                "fluid `{}` has a bulk modulus of {k:.3e} Pa, {} times the hydrostatic pressure of its {:.3} m of depth ({head:.3e} Pa): the flow will compress it visibly (at 10⁻³ times a column burst); give it {:.1e} Pa or more (real water 2.2e9){}",
                sim.body_names().get(b as usize).map_or("?", String::as_str),
                three_figures(k / head),
                hi - lo,
                COMPRESSIBLE_BELOW * head,
                if managed {
                    ""
                } else {
                    "; particles may crowd, merge and blow apart (a dam break at 90 times reached 13.1 m/s at 0.163 s, 2.07 m/s at most with a `[particle_management]` table)"
                }
            ));
        }
    }
    out
}

/// `x` to three significant figures (a ratio of 0.019 was printed "0.0").
fn three_figures(x: f64) -> String {
    if !(x.is_finite() && x > 0.0) {
        return format!("{x}");
    }
    let digits = (2 - x.log10().floor() as i64).clamp(0, 12) as usize;
    format!("{x:.digits$}")
}

/// [`compressibility_warnings`]' bound on `K / (ρ g H)`.
const COMPRESSIBLE_BELOW: f64 = 100.0;

/// What water falling on a wall coarser than itself does (session 54's
/// review: a column 0.1 m wide and high collapsing in a tank whose walls
/// are 0.02 m apart, 0.3 s).
const WALL_LEAK: &str = "a collapsing column's volume swung by 0.7, 4.8, 5.9, 11 and 23 % with walls 1.5, 2, 2.5, 3 and 4 times its spacing, 0.04 % at its own, and at 5 times half its particles passed through the floor";

/// The checkpoint section in which `pfem run` keeps its scene file: its
/// text and the `--spacing` override.
const SCENE_FILE_SECTION: &str = "pfem run: scene file";

fn encode_scene_file(spec: &SceneFile, spacing: Option<f64>) -> Vec<u8> {
    let mut e = pfem::checkpoint::Encoder::new();
    e.str(spec.source());
    e.bool(spacing.is_some());
    e.f64(spacing.unwrap_or(0.0));
    e.finish()
}

/// The scene file of [`SCENE_FILE_SECTION`] with its run's overrides, and
/// its run's `--spacing`.
fn decode_scene_file(bytes: &[u8]) -> Result<(SceneFile, Option<f64>), String> {
    let mut d = pfem::checkpoint::Decoder::new(bytes);
    let text = d.str().map_err(|e| e.to_string())?;
    let has_spacing = d.bool().map_err(|e| e.to_string())?;
    let h = d.f64().map_err(|e| e.to_string())?;
    d.end().map_err(|e| e.to_string())?;
    let mut file =
        SceneFile::parse(text, "the checkpoint's scene file").map_err(|e| e.to_string())?;
    if has_spacing {
        file.override_spacing(h);
    }
    Ok((file, has_spacing.then_some(h)))
}

/// Spacings of two fluids that meet may differ up to this factor
/// (`spacing_warnings`): measured at rest, 2.5 held, 4 opened a hole.
const FLUID_SPACING_RATIO: f64 = 2.5;

/// Runs `scene` with the standard outputs into `--out` (default `out/NAME`),
/// from the start or from `--restart`'s checkpoint.
fn simulate<const D: usize>(
    scene: Scene<D>,
    probes: Vec<Probe<D>>,
    tessellator: Box<dyn Tessellator<D>>,
    args: &Args,
    (checkpoint_every, probe_interval): (Option<f64>, Option<f64>),
    spec: &SceneFile,
) -> Result<(), String>
where
    Const<D>: Dim,
{
    // A restart continues in its checkpoint's folder unless told otherwise:
    // its real file's (a link's folder is another's; before session 49 a
    // refused restart through a link emptied the link's folder).
    let out = args.out.clone().unwrap_or_else(|| {
        let f = args.options.get("restart").map(Path::new);
        let real = f.and_then(|f| std::fs::canonicalize(f).ok());
        match real.as_deref().or(f).and_then(Path::parent) {
            // `checkpoint.bin` alone: its parent is "", the current folder.
            Some(dir) if dir.as_os_str().is_empty() => PathBuf::from("."),
            Some(dir) => dir.to_path_buf(),
            None => Path::new("out").join(&scene.name),
        }
    });
    // A restart written into a folder other than its checkpoint's continues
    // that folder's files (its probes, its summary, its checkpoint; a
    // restart clears nothing, `--overwrite` or not): a folder that holds
    // anything is refused (the review of session 45: another run's files
    // there were replaced). The checkpoint's own folder is its real file's
    // (a link to it names another).
    // (A checkpoint that cannot be found is reported by its reading.)
    let own_folder = args
        .options
        .get("restart")
        .and_then(|f| std::fs::canonicalize(f).ok())
        .and_then(|real| real.parent().map(Path::to_path_buf));
    if let (Some(f), Some(own)) = (args.options.get("restart"), own_folder) {
        let given = &out;
        let same = std::fs::canonicalize(given).is_ok_and(|b| b == own);
        let used = std::fs::read_dir(given).is_ok_and(|mut d| d.next().is_some());
        if !same && used {
            return Err(format!(
                "--restart {f} --out {}: that folder is not the checkpoint's and is not empty (its files would be replaced by this run's): continue in the checkpoint's own folder (or a copy of it)",
                given.display()
            ));
        }
    }
    let name = scene.name.clone();
    let restart = match args.options.get("restart") {
        Some(f) => {
            let budget = args.memory_budget().map_err(|e| e.to_string())?;
            Some(
                pfem::observe::read_checkpoint_within(f, budget)
                    .map_err(|e| format!("--restart {f}: {e}"))?,
            )
        }
        None => None,
    };
    // The scene file the checkpoint's run read: a restart under another is
    // refused by what differs (a moved point probe's column changed meaning
    // mid-file, another gravity was ignored and a changed force applied:
    // session 55's review). A checkpoint written before it is unchecked.
    if let (Some(ck), Some(f)) = (&restart, args.options.get("restart")) {
        if ck.section(SCENE_FILE_SECTION).is_none() {
            pfem::errln!(
                "note: --restart {f}: the checkpoint was written before pfem run kept its scene file: the file is not compared"
            );
        }
        if let Some(bytes) = ck.section(SCENE_FILE_SECTION) {
            let (before, spacing) = decode_scene_file(bytes)
                .map_err(|e| format!("--restart {f}: its scene file: {e}"))?;
            // The option first: a file unchanged but read under another
            // `--spacing` differed "in spacing, body …" (session 55's
            // review of the change).
            if spacing != args.spacing {
                let said =
                    |h: Option<f64>| h.map_or("none".to_string(), |h| format!("--spacing {h}"));
                return Err(format!(
                    "--restart {f}: its run was given {}, this one {}: restart with the run's options",
                    said(spacing),
                    said(args.spacing)
                ));
            }
            let now = spec.differences(&before);
            if !now.is_empty() {
                return Err(format!(
                    "--restart {f}: the scene file differs from the one its run read, in {}: a restart continues the same scene (only [run]'s end_time and output_interval may change); start a new run for another",
                    now.join(", ")
                ));
            }
        }
    }
    // The probe rows a checkpoint counts are its folder's `probes.csv`
    // (a checkpoint holds their count and hash, not the rows): a restart
    // into another folder (empty, above) starts from a copy of it, removed
    // again (with the folder, if made for it) when the restart is refused.
    // Whether a copy was made, and whether its folder was made for it.
    let mut copied: Option<bool> = None;
    // What the folder held before (a refused restart removes only what it
    // added).
    let before: Vec<PathBuf> = std::fs::read_dir(&out)
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    if let Some(f) = args.options.get("restart") {
        let own = std::fs::canonicalize(f)
            .ok()
            .and_then(|real| real.parent().map(Path::to_path_buf));
        let rows = own.map(|d| d.join("probes.csv")).filter(|p| p.is_file());
        let there = out.join("probes.csv");
        if let Some(rows) = rows {
            let same = std::fs::canonicalize(&rows).ok() == std::fs::canonicalize(&there).ok();
            if !same && !there.exists() {
                let made = !out.exists();
                std::fs::create_dir_all(&out)
                    .and_then(|()| std::fs::copy(&rows, &there))
                    .map_err(|e| {
                        format!(
                            "--restart {f}: copying {} into {}: {e}",
                            rows.display(),
                            out.display()
                        )
                    })?;
                copied = Some(made);
            }
        }
    }
    // What this refused restart added (the copy, a summary the failed
    // start wrote) is removed, and the folder if it was made for it;
    // nothing that was there before.
    let undo = |copied: &Option<bool>| {
        if let Some(made) = copied {
            if *made {
                let _ = std::fs::remove_dir_all(&out);
            } else if let Ok(entries) = std::fs::read_dir(&out) {
                for e in entries.flatten() {
                    if !before.contains(&e.path()) && e.path().is_file() {
                        let _ = std::fs::remove_file(e.path());
                    }
                }
            }
        }
    };
    let drawn = drawn_fluids(&scene);
    let mut sim = args.simulation(scene, tessellator).map_err(|e| {
        undo(&copied);
        e.to_string()
    })?;
    // The spacing warnings of `pfem check`, on stderr before the run: a
    // run with walls five times coarser than its water let half of it
    // through the floor and said nothing (session 54's review).
    // (Not on a restart: said when the run began.) `summary.json` lists
    // them ("warnings"), a restarted run's too: a run that warned ends
    // `finished` whatever its result (session 55's review).
    let warnings = scene_warnings(&sim, &drawn);
    if restart.is_none() {
        for w in &warnings {
            pfem::errln!("warning: {w}");
        }
    }
    let interrupted = Arc::new(AtomicBool::new(false));
    install_interrupt(&interrupted)?;
    sim.add_hook(Box::new(pfem::hooks::Interrupt::new(interrupted.clone())));
    // The rows go to probes.csv; none is kept in memory (a long run's
    // would grow with its steps).
    let mut output = StandardOutput::new(&out, !args.no_vtu, probes, args.quiet)
        .overwrite(args.overwrite)
        .checkpoint_every(checkpoint_every)
        .keep_rows(false)
        .checkpoint_section(SCENE_FILE_SECTION, encode_scene_file(spec, args.spacing));
    output.probe_interval = probe_interval;
    if !warnings.is_empty() {
        output
            .extra
            .insert("warnings".into(), serde_json::Value::from(warnings));
    }
    if let Some(ck) = &restart {
        if let Err(e) = pfem::cli::continue_from(&mut sim, &mut output, ck) {
            undo(&copied);
            return Err(format!("--restart: {e}"));
        }
    }
    pfem::errln!(
        "{name}: {D}D, {} particles, h_min = {} m, end time {} s{} -> {}",
        sim.particles().len(),
        sim.h_min(),
        sim.end_time(),
        if restart.is_some() {
            format!(", restarted at t = {} s (step {})", sim.time(), sim.steps())
        } else {
            String::new()
        },
        out.display()
    );
    // The rows go to the disk, not to memory: a file that would grow past
    // a gigabyte is said before the run (some 22 bytes a value).
    let columns = 1 + output.probe_count();
    let rows = output.rows_to_come(&sim);
    let bytes = rows * 22.0 * columns as f64;
    if bytes > 1e9 {
        pfem::errln!(
            "note: probes.csv will hold at least {rows:.0} rows of {columns} values, {:.1} GB or more ({}); --probe-interval thins it",
            bytes / 1e9,
            match probe_interval {
                Some(t) => format!("a row every {t} s"),
                None => "a row every step".into(),
            }
        );
    }
    let steps = sim.steps();
    sim.run(&mut [&mut output]).map_err(|e| {
        // Refused before its first step (the outputs could not go on
        // there): the copy goes. After a step the rows are the run's.
        if sim.steps() == steps {
            undo(&copied);
        }
        e.to_string()
    })?;
    output.report(&sim).map_err(|e| e.to_string())?;
    if let Some(reason) = sim.stopped() {
        // The run did not reach its end time: say how to go on, and end
        // with a status a script sees.
        // The command that continues: this one's arguments (a restart
        // must repeat them) with `--out` and `--restart` set, and without
        // `--overwrite` (the restart resumes the folder's series).
        let mut again: Vec<String> = Vec::new();
        let mut given = std::env::args_os()
            .skip(1)
            .map(|a| a.to_string_lossy().into_owned());
        while let Some(a) = given.next() {
            if a == "--out" || a == "--restart" {
                given.next();
            } else if a != "--overwrite" {
                again.push(a);
            }
        }
        let when = if reason.contains("at t =") {
            String::new()
        } else {
            format!(" at t = {} s", sim.time())
        };
        // Each word quoted for a POSIX shell where it needs it (a path
        // with a space).
        let quote = pfem::cli::shell_quote;
        let words: Vec<String> = again.iter().map(|w| quote(w)).collect();
        pfem::errln!(
            "{reason}{when}; continue with: pfem {} --out {} --restart {}",
            words.join(" "),
            quote(&out.to_string_lossy()),
            quote(&output.checkpoint_path().to_string_lossy())
        );
        if reason == pfem::hooks::Interrupt::REASON {
            return Err(INTERRUPTED.into());
        }
        return Err(STOPPED.into());
    }
    Ok(())
}

/// The error text of an interrupted run (exit status 130).
const INTERRUPTED: &str = "interrupted";

/// The error text of a run a hook stopped before its end time, such as
/// `--max-wall-time` (exit status 2).
const STOPPED: &str = "stopped";

/// Ctrl-C and SIGTERM set `flag`: the run stops after the current step and
/// writes its outputs and a checkpoint. A second signal ends the process at
/// once.
#[cfg(feature = "signals")]
fn install_interrupt(flag: &Arc<AtomicBool>) -> Result<(), String> {
    let f = flag.clone();
    ctrlc::set_handler(move || {
        if f.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        pfem::errln!("\ninterrupt: stopping after this step (again to quit at once)");
    })
    .map_err(|e| format!("cannot install the Ctrl-C handler: {e}"))
}

/// Without the `signals` feature Ctrl-C ends the process as usual.
#[cfg(not(feature = "signals"))]
fn install_interrupt(_flag: &Arc<AtomicBool>) -> Result<(), String> {
    Ok(())
}
