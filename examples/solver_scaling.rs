//! What a step costs as the particle count grows, direct solver against the
//! block-preconditioned iterative path (issue 18): the 2D dam break and the
//! 3D water column at several spacings, a few steps each, every
//! (case, size, solver) in a child process of its own so that its peak
//! memory is its own.
//!
//! ```text
//! cargo run --release --example solver_scaling -- \
//!     [--case dam2d|column3d|all] [--sizes 20,40,80] [--steps 10] [--warmup 0] \
//!     [--solvers direct,block,amg] [--stabilisation A] [--bulk K] \
//!     [--scheme S] [--picard-tol X] [--picard-stop change|estimate] \
//!     [--first-iterate start|predicted] [--picard-forcing F]
//! ```
//! The last five are the examples' options of the same names
//! (`pfem::cli::Args::step_params`).
//! `--warmup W` runs `W` untimed steps before the `--steps` timed ones
//! (the first steps from rest reject attempts at every size).
//! `block` is the default `BlockSolver` (it chooses its pressure solve by
//! size); `block-ldlt` keeps it on the Cholesky path whatever the size;
//! `block-reuse` keeps the block solver's set-up across a step's Picard
//! iterates (`BlockSolver::reuse_setup`); `amg` is the block solver with
//! multigrid on the pressure
//! (`PressureSolve::Multigrid`), `amg-fresh` the same building its
//! pressure hierarchy anew for every pattern (`BlockSolver::carry_steps`
//! = 0, as before session 28; the 3D increments' hierarchy, in the
//! assembler, is carried either way), `amg-minres` the same with MINRES
//! (`Krylov::Minres`); `petsc`, with `--features petsc`, is
//! `pfem::petsc::PetscSolver` (options in `PFEM_PETSC_OPTIONS`), and
//! `cholmod` the whole system factored by CHOLMOD through PETSc, beside
//! `direct` (faer's Cholesky of the same matrix); `--stabilisation A` runs every solver on
//! the stabilised system (`StepParams::pressure_stabilisation`, default 0);
//! `--bulk K` sets the 2D water's bulk modulus (Pa, default 2.2e9).
//! `--sizes` are spacings as fractions of the column width (a/n); defaults
//! 20,40,80 (2D) and 10,14,18 (3D). Prints, per run: particles, unknowns,
//! seconds per accepted step and per stage (remesh, assemble, solve, the
//! rest), Picard iterations per step, Krylov iterations per solve (over
//! every solve, those of rejected attempts included; until session 20 the
//! sum was divided by the accepted attempts' solves only),
//! rejected attempts and peak memory; then the fitted exponent of time per
//! step against particles for each solver.
//!
//! One run alone, writing the whole system of its third solve (the first
//! step's third Picard iterate) as Matrix Market (`STEM.mtx`,
//! `STEM_rhs.mtx`) for solvers outside the library:
//! ```text
//! cargo run --release --example solver_scaling -- --one dam2d:40:block --steps 1 --export out/dam2d_a40
//! ```

use std::process::Command;
use std::time::Instant;

use pfem::cases::DamBreak;
use pfem::cases3d::WaterColumn3d;
use pfem::prelude::*;

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// Peak resident memory of this process (MB), from /proc (0 elsewhere).
fn peak_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(0.0)
}

fn solver(name: &str) -> Res<Box<dyn pfem::assembly::LinearSolver>> {
    Ok(match name {
        "direct" => Box::new(pfem::assembly::DirectSolver::default()),
        "block" => Box::new(pfem::assembly::BlockSolver::default()),
        "block-reuse" => {
            let mut b = pfem::assembly::BlockSolver::default();
            b.reuse_setup = true;
            Box::new(b)
        }
        // The Cholesky path whatever the size (a stabilised system: its
        // saddle point's `L D Lᵀ`), as `block` was before it chose by size.
        "block-ldlt" => {
            let mut b = pfem::assembly::BlockSolver::default();
            b.pressure = pfem::assembly::PressureSolve::Cholesky;
            Box::new(b)
        }
        "amg" => {
            let mut b = pfem::assembly::BlockSolver::default();
            b.pressure = pfem::assembly::PressureSolve::Multigrid;
            Box::new(b)
        }
        // The multigrid path with a new pressure hierarchy for every
        // pattern (`BlockSolver::carry_steps` = 0), as before session 28.
        "amg-fresh" => {
            let mut b = pfem::assembly::BlockSolver::default();
            b.pressure = pfem::assembly::PressureSolve::Multigrid;
            b.carry_steps = 0;
            Box::new(b)
        }
        // The stabilised multigrid path with MINRES and the block-diagonal
        // preconditioner (its Krylov method until session 20).
        "amg-minres" => {
            let mut b = pfem::assembly::BlockSolver::default();
            b.pressure = pfem::assembly::PressureSolve::Multigrid;
            b.krylov = pfem::assembly::Krylov::Minres;
            Box::new(b)
        }
        #[cfg(feature = "petsc")]
        "petsc" => Box::new(pfem::petsc::PetscSolver::default()),
        // The whole system by CHOLMOD (through PETSc), beside `direct`
        // (faer's Cholesky of the same matrix).
        #[cfg(feature = "petsc")]
        "cholmod" => {
            let mut p =
                pfem::petsc::PetscSolver::with_options("-pfem_pc_factor_mat_solver_type cholmod");
            p.split = false;
            Box::new(p)
        }
        other => {
            return Err(format!(
                "unknown solver {other} (direct, block, block-reuse, block-ldlt, amg, amg-fresh, amg-minres; petsc, cholmod with --features petsc)"
            )
            .into())
        }
    })
}

/// One run, in this process: prints one `RESULT` line.
fn one<const D: usize>(
    mut sim: Simulation<D>,
    solver_name: &str,
    steps: u64,
    warmup: u64,
    export: Option<String>,
) -> Res<()>
where
    pfem::core::Const<D>: pfem::core::Dim,
{
    match export {
        Some(stem) => sim.set_solver(Box::new(pfem::assembly::MatrixExport::new(
            solver(solver_name)?,
            stem,
            2,
        ))),
        None => sim.set_solver(solver(solver_name)?),
    }
    let n = sim.particles().len();
    // Untimed steps first (`--warmup`): the figures are the differences.
    while sim.steps() < warmup {
        sim.step()?;
    }
    let (st0, w0, rej0) = (sim.stats().clone(), sim.work(), sim.rejected());
    let t0 = Instant::now();
    while sim.steps() < warmup + steps {
        sim.step()?;
    }
    let wall = t0.elapsed().as_secs_f64();
    let st = sim.stats().clone();
    let w = sim.work();
    let k = steps as f64;
    let d = |a: (u64, f64), b: (u64, f64)| (a.0 - b.0, a.1 - b.1);
    let (remesh, assemble, solve, rejected) = (
        d(st.remesh, st0.remesh),
        d(st.assemble, st0.assemble),
        d(st.solve, st0.solve),
        d(st.rejected, st0.rejected),
    );
    pfem::outln!(
        "RESULT {n} {:.4e} {:.4e} {:.4e} {:.4e} {:.4e} {:.2} {:.1} {} {:.0} {:.4e}",
        wall / k,
        remesh.1 / k,
        assemble.1 / k,
        solve.1 / k,
        rejected.1 / k,
        solve.0 as f64 / k,
        (w.solver_iterations - w0.solver_iterations) as f64
            / (w.linear_solves - w0.linear_solves).max(1) as f64,
        sim.rejected() - rej0,
        peak_mb(),
        sim.time(),
    );
    // The stages the RESULT line leaves out (s per step).
    pfem::outln!(
        "STAGES free_surface {:.4e} update {:.4e} observe {:.4e} hooks {:.4e}",
        (st.free_surface.1 - st0.free_surface.1) / k,
        (st.update.1 - st0.update.1) / k,
        (st.observe.1 - st0.observe.1) / k,
        (st.hooks.1 - st0.hooks.1) / k,
    );
    Ok(())
}

/// The examples' options of the time scheme and the Picard loop that
/// `solver_scaling` takes too.
const PICARD_OPTIONS: [&str; 5] = [
    "scheme",
    "picard-tol",
    "picard-stop",
    "picard-forcing",
    "first-iterate",
];

fn run() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let opt = |name: &str| {
        args.iter()
            .position(|a| a == &format!("--{name}"))
            .and_then(|i| args.get(i + 1).cloned())
    };
    // Every `--name` must be one this program reads (a typo such as
    // `--solver` for `--solvers` ran the defaults without a word).
    const KNOWN: [&str; 9] = [
        "steps",
        "warmup",
        "stabilisation",
        "bulk",
        "export",
        "one",
        "case",
        "solvers",
        "sizes",
    ];
    for a in args.iter().filter(|a| a.starts_with("--")) {
        let name = &a[2..];
        if !KNOWN.contains(&name) && !PICARD_OPTIONS.contains(&name) {
            return Err(format!("unknown option {a} (see the doc comment)").into());
        }
    }
    let steps: u64 = opt("steps")
        .map(|s| s.parse().map_err(|e| format!("--steps {s}: {e}")))
        .transpose()?
        .unwrap_or(10);
    if steps == 0 {
        return Err("--steps must be at least 1".into());
    }
    // Steps run before the timed ones (the first steps from rest reject
    // attempts at every size; a running flow says more).
    let warmup: u64 = opt("warmup").map(|s| s.parse()).transpose()?.unwrap_or(0);
    // Pressure stabilisation factor (StepParams::pressure_stabilisation).
    let stab = opt("stabilisation").unwrap_or_else(|| "0".into());
    // The 2D water's bulk modulus (Pa).
    let bulk = opt("bulk").unwrap_or_else(|| "2.2e9".into());
    // The time scheme and the Picard loop's options, read as the examples
    // read them (`pfem::cli::Args::step_params`) and passed on to the
    // children as given.
    let forwarded: Vec<String> = PICARD_OPTIONS
        .iter()
        .filter_map(|name| opt(name).map(|v| [format!("--{name}"), v]))
        .flatten()
        .collect();
    let params = StepParams {
        pressure_stabilisation: stab.parse()?,
        ..pfem::cli::Args::parse(forwarded.iter().cloned())?.step_params()?
    };
    // Child: one case, one size, one solver.
    let export = opt("export");
    if let Some(spec) = opt("one") {
        let parts: Vec<&str> = spec.split(':').collect();
        let [case, n, solver_name] = parts[..] else {
            return Err("--one CASE:N:SOLVER".into());
        };
        let n: f64 = n.parse()?;
        return match case {
            "dam2d" => {
                let mut c = DamBreak::default();
                c.spacing = c.width / n;
                let water = pfem::constitutive::Newtonian::water();
                let fluid = pfem::constitutive::Newtonian::new(
                    water.density(),
                    water.viscosity(),
                    bulk.parse()?,
                )?;
                let sim =
                    Simulation::new(c.scene_with(fluid), Box::new(Delaunay2::default()), params)?;
                one(sim, solver_name, steps, warmup, export)
            }
            "column3d" => {
                let mut c = WaterColumn3d {
                    side_walls: false,
                    ..Default::default()
                };
                c.spacing = c.width / n;
                let mut sim = Simulation::new(c.scene(), Box::new(Delaunay3::default()), params)?;
                pfem::cases3d::slip_sides(&mut sim);
                one(sim, solver_name, steps, warmup, export)
            }
            other => Err(format!("unknown case {other}").into()),
        };
    }
    let case = opt("case").unwrap_or_else(|| "all".into());
    let solvers = opt("solvers").unwrap_or_else(|| "direct,block".into());
    let cases: Vec<&str> = match case.as_str() {
        "all" => vec!["dam2d", "column3d"],
        "dam2d" => vec!["dam2d"],
        "column3d" => vec!["column3d"],
        other => return Err(format!("--case {other}: all, dam2d or column3d").into()),
    };
    let mut failed = 0usize;
    let exe = std::env::current_exe()?;
    pfem::outln!(
        "{:<9} {:>4} {:<7} {:>8} {:>9} {:>8} {:>8} {:>8} {:>8} {:>7} {:>8} {:>5} {:>8}",
        "case",
        "a/n",
        "solver",
        "particles",
        "s/step",
        "remesh",
        "assemble",
        "solve",
        "rejected",
        "picard",
        "krylov",
        "rej",
        "peak MB"
    );
    for case in cases {
        let sizes = opt("sizes").unwrap_or_else(|| {
            if case == "dam2d" {
                "20,40,80".into()
            } else {
                "10,14,18".into()
            }
        });
        let mut fits: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        for n in sizes.split(',') {
            for s in solvers.split(',') {
                let out = Command::new(&exe)
                    .args([
                        "--one",
                        &format!("{case}:{n}:{s}"),
                        "--steps",
                        &steps.to_string(),
                        "--stabilisation",
                        &stab,
                        "--bulk",
                        &bulk,
                        "--warmup",
                        &warmup.to_string(),
                    ])
                    .args(&forwarded)
                    .output()?;
                let text = String::from_utf8_lossy(&out.stdout);
                let Some(line) = text.lines().find(|l| l.starts_with("RESULT")) else {
                    pfem::outln!(
                        "{case:<9} {n:>4} {s:<7} failed: {}",
                        String::from_utf8_lossy(&out.stderr).trim()
                    );
                    failed += 1;
                    continue;
                };
                let v: Vec<f64> = line
                    .split_whitespace()
                    .skip(1)
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect();
                pfem::outln!(
                    "{case:<9} {n:>4} {s:<7} {:>8} {:>9.4} {:>8.4} {:>8.4} {:>8.4} {:>8.4} {:>7.2} {:>8.1} {:>5} {:>8.0}",
                    v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9]
                );
                match fits.iter_mut().find(|(name, _)| name == s) {
                    Some((_, pts)) => pts.push((v[0].ln(), v[1].ln())),
                    None => fits.push((s.to_string(), vec![(v[0].ln(), v[1].ln())])),
                }
            }
        }
        for (s, pts) in &fits {
            pfem::outln!(
                "{case}: {s}: time per step grows as N^{:.2} over these sizes",
                pfem::exact::slope(pts)
            );
        }
    }
    if failed > 0 {
        return Err(format!("{failed} of the runs failed (above)").into());
    }
    Ok(())
}
