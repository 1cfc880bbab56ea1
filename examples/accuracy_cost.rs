//! What accuracy costs in time, measured where error converges: error
//! against wall time on cases with exact or converged references, along
//! the particle spacing, the time step and the Picard tolerance, with the
//! observed orders, the Pareto front of each case and the `Fidelity`
//! presets.
//!
//! ```text
//! cargo run --release --example accuracy_cost -- --out DIR [--quick]
//! ```
//!
//! Cases (`pfem::exact`, `pfem::cases`):
//! - `couette`: steady circular Couette flow, velocity RMS against
//!   `A r + B / r` (viscous flow);
//! - `poiseuille`: start-up plane Poiseuille flow of a column with free
//!   ends, velocity profile RMS against the series solution (its known
//!   defect: the ends' spurious force, see `pfem::exact::StartupPoiseuille`);
//! - `standing_wave`: first sloshing mode, frequency against linear theory
//!   (free surface, quasi-incompressible pressure);
//! - `cantilever_static`, `cantilever_vibration`: the CSM2 beam's tip
//!   deflection and first frequency against Timoshenko beam theory (solid);
//! - `water_at_rest`: hydrostatic pressure, exact to round-off (no order);
//! - `dam_break`: the surge front against a finer run of the library (a/45;
//!   a/32 in `--quick`): self-convergence, with the front error against
//!   Martin & Moyce (1952) beside it;
//! - `elastic_gate` (full study only): peak tip displacement against
//!   Antoci et al. (2007), validation, the gate in plane stress (coupling).
//!
//! Around a base point per case one knob is varied at a time: the spacing
//! (cells across the case's length scale), the time step (a factor on the
//! case's step: the Courant number 0.5 × factor where the step is
//! Courant-limited, the dam break and the gate; the fixed step × factor
//! elsewhere) and the Picard tolerance; the presets run where a case has a
//! default resolution. Writes `DIR/accuracy_cost.csv` (one row per run,
//! with the stage times of `Simulation::stats`), `DIR/accuracy_cost.md`
//! (tables, orders, Pareto fronts, the knob that buys accuracy cheapest,
//! the presets on every case) and `DIR/<case>.png` (log10 error against
//! log10 wall time: one curve per knob, the presets, the Pareto front),
//! `DIR/convergence.png` (log10 error against log10 relative spacing).
//! The full study (73 runs) took 87–91 s on 2 cores (6 December 2026, `docs/accuracy-cost.md`);
//! `--quick` runs 53 smaller ones.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use pfem::cases::{best_shift, rest_figures, ElasticGate, RestTank};
use pfem::exact::{
    observed_order, slope, Cantilever, CircularCouette, DamBreakFront, ExactRun, StandingWave,
    StartupPoiseuille,
};
use pfem::fidelity::Fidelity;
use pfem::output::{parse_reference_csv, plot_series_png, reference, PlotSeries, PlotSpec};
use pfem::prelude::*;

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

type Res<T> = Result<T, Box<dyn std::error::Error + Send + Sync>>;

/// One set of knobs.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Knobs {
    /// Cells across the case's length scale (spacing = scale / cells).
    cells: f64,
    /// Factor on the case's time step (Courant number 0.5 × step where
    /// the step is Courant-limited).
    step: f64,
    /// Picard tolerance.
    tol: f64,
}

/// What one run measured.
#[derive(Clone, Debug)]
struct Record {
    case: &'static str,
    varied: String,
    k: Knobs,
    /// Spacing (m).
    h: f64,
    /// Relative error.
    error: f64,
    /// A second error or figure (see `Case::second`).
    second: f64,
    wall: f64,
    steps: u64,
    rejected: u64,
    /// remesh, assemble, solve, update, observe (s).
    stages: [f64; 5],
    status: String,
}

/// What a case's run returns: error, second figure, spacing, the run.
struct Outcome {
    error: f64,
    second: f64,
    h: f64,
    wall: f64,
    sim: Simulation<2>,
}

impl Outcome {
    fn of(r: ExactRun, h: f64) -> Self {
        Outcome {
            error: r.error,
            second: r.value,
            h,
            wall: r.wall,
            sim: r.sim,
        }
    }
}

type RunFn = Box<dyn Fn(Knobs) -> Res<Outcome>>;

/// One case of the study.
struct Case {
    name: &'static str,
    /// What the error is, against what.
    error: &'static str,
    /// What the second column is.
    second: &'static str,
    /// The order the method should reach here, and why.
    expected: &'static str,
    run: RunFn,
    base: Knobs,
    cells: Vec<f64>,
    steps: Vec<f64>,
    tols: Vec<f64>,
    /// The case's default cells (Standard), or `None`: no presets.
    preset_cells: Option<usize>,
    presets: Vec<Fidelity>,
    /// Whether an observed order is meaningful (not for an exact case).
    has_order: bool,
    /// Wall time spent on the case's reference run (s).
    reference_wall: f64,
}

fn params(k: Knobs) -> StepParams {
    StepParams {
        picard_tolerance: k.tol,
        ..StepParams::default()
    }
}

fn cells(k: Knobs) -> usize {
    k.cells.round().max(1.0) as usize
}

fn poiseuille(k: Knobs) -> Res<Outcome> {
    let case = StartupPoiseuille {
        cells: cells(k),
        steps_at_8: (20.0 / k.step).round().max(1.0) as usize,
        ..StartupPoiseuille::default()
    };
    Ok(Outcome::of(case.run(params(k))?, case.spacing()))
}

fn couette(k: Knobs) -> Res<Outcome> {
    let case = CircularCouette {
        cells: cells(k),
        dt: 0.02 * k.step,
        ..CircularCouette::default()
    };
    Ok(Outcome::of(case.run(params(k))?, case.spacing()))
}

fn standing_wave(k: Knobs) -> Res<Outcome> {
    let case = StandingWave {
        cells: cells(k),
        steps_per_period_at_20: (40.0 / k.step).round().max(1.0) as usize,
        ..StandingWave::default()
    };
    let r = case.run(params(k))?;
    let decay = r.second_error;
    let mut o = Outcome::of(r, case.spacing());
    o.second = decay;
    Ok(o)
}

fn cantilever_static(k: Knobs) -> Res<Outcome> {
    let case = Cantilever {
        cells: cells(k),
        ..Cantilever::default()
    };
    let mut r = case.run_static(params(k))?;
    r.value *= 1e3;
    Ok(Outcome::of(r, case.spacing()))
}

fn cantilever_vibration(k: Knobs) -> Res<Outcome> {
    let case = Cantilever {
        cells: cells(k),
        ..Cantilever::default()
    };
    let steps = (40.0 / k.step).round().max(1.0) as usize;
    Ok(Outcome::of(
        case.run_vibration(params(k), 1.5, steps)?,
        case.spacing(),
    ))
}

fn water_at_rest(k: Knobs) -> Res<Outcome> {
    let case = RestTank {
        spacing: 1.0 / k.cells,
        end_time: 0.5,
        ..RestTank::default()
    };
    let mut scene = case.scene();
    scene.settings.max_dt *= k.step;
    let mut sim = Simulation::new(scene, Box::new(Delaunay2::default()), params(k))?;
    let t0 = Instant::now();
    sim.run(&mut [])?;
    let wall = t0.elapsed().as_secs_f64();
    let f = rest_figures(&sim, case.depth);
    Ok(Outcome {
        error: f.pressure_rms,
        second: f.max_speed,
        h: case.spacing,
        wall,
        sim,
    })
}

/// The dam break against `reference` (its front curve), with the front
/// error against Martin & Moyce (T ≤ 2.5, best shift) as second figure.
fn dam_break(k: Knobs, reference: &[(f64, f64)]) -> Res<Outcome> {
    let case = DamBreakFront {
        cells: cells(k),
        ..DamBreakFront::default()
    };
    let (front, r) = case.run(params(k), 0.5 * k.step)?;
    let measured = parse_reference_csv(reference::MARTIN_MOYCE_N2_2_A2_25IN_FRONT)?;
    let (_, experiment) = best_shift(&front, &measured, case.t_max, 0.5, 0.01);
    let a = pfem::cases::DamBreak::default().width;
    Ok(Outcome {
        error: case.difference(&front, reference),
        second: experiment,
        h: a / cells(k) as f64,
        wall: r.wall,
        sim: r.sim,
    })
}

/// The elastic gate (plane stress) to 0.2 s, water spacing 0.1 m / cells,
/// gate spacing 1.25 mm: peak ux against Antoci et al. (2007); second
/// figure the peak-time error (s).
fn gate(k: Knobs) -> Res<Outcome> {
    let case = ElasticGate {
        spacing: 0.1 / k.cells,
        end_time: 0.2,
        ..ElasticGate::default()
    };
    let mut scene = case.scene()?;
    scene.settings.courant = 0.5 * k.step;
    scene.settings.output_interval = None;
    let mut sim = Simulation::new(scene, Box::new(Delaunay2::default()), params(k))?;
    let probe = case
        .probes()
        .into_iter()
        .find(|q| q.name == "ux_tip")
        .ok_or("no ux_tip probe")?;
    let mut out = Vec::new();
    let t0 = Instant::now();
    {
        let mut rec = Recorder {
            f: &*probe.measure,
            data: &mut out,
        };
        sim.run(&mut [&mut rec])?;
    }
    let wall = t0.elapsed().as_secs_f64();
    let peak = |s: &[(f64, f64)]| {
        s.iter().copied().fold(
            (0.0, f64::NEG_INFINITY),
            |b, q| if q.1 > b.1 { q } else { b },
        )
    };
    let exp = parse_reference_csv(reference::ANTOCI_2007_GATE_UX)?;
    let (t_sim, u_sim) = peak(&out);
    let (t_exp, u_exp) = peak(&exp);
    Ok(Outcome {
        error: (u_sim / u_exp - 1.0).abs(),
        second: t_sim - t_exp,
        h: case.spacing,
        wall,
        sim,
    })
}

/// Records `(t, f(sim))` after every step.
struct Recorder<'a> {
    f: &'a dyn Fn(&Simulation<2>) -> f64,
    data: &'a mut Vec<(f64, f64)>,
}

impl Observer<2> for Recorder<'_> {
    fn step(&mut self, sim: &Simulation<2>) -> Result<(), pfem::RunError> {
        self.data.push((sim.time(), (self.f)(sim)));
        Ok(())
    }
}

const STEPS: [f64; 3] = [0.5, 1.0, 2.0];

fn cases(quick: bool) -> Res<Vec<Case>> {
    let tols = vec![1e-6, 1e-4, 1e-3];
    let knobs = |cells: f64| Knobs {
        cells,
        step: 1.0,
        tol: 1e-6,
    };
    let presets = if quick {
        vec![Fidelity::Draft, Fidelity::Standard]
    } else {
        Fidelity::ALL.to_vec()
    };
    let mut v = vec![
        Case {
            name: "couette",
            error: "RMS of |v − u_θ e_θ| / (ω R₁), steady circular Couette flow (R₁ = 0.5 m, R₂ = 1 m, ν = 0.25 m²/s, t = 1.5 s)",
            second: "inner wall speed (m/s)",
            expected: "2: linear elements (the steady state: the step does not enter)",
            run: Box::new(couette),
            base: knobs(8.0),
            cells: if quick { vec![4.0, 8.0, 16.0] } else { vec![4.0, 8.0, 16.0, 32.0] },
            steps: STEPS.to_vec(),
            tols: tols.clone(),
            preset_cells: Some(8),
            presets: presets.clone(),
            has_order: true,
            reference_wall: 0.0,
        },
        Case {
            name: "poiseuille",
            error: "RMS of u − u_exact over the middle section / exact centre-line speed, t = 0.2 s (ν t/H² = 0.2); a column 4 H long with free ends",
            second: "exact centre-line speed (m/s)",
            expected: "2 in the interior; the free ends add a spurious force that grows with refinement (known defect, see `pfem::exact::StartupPoiseuille`)",
            run: Box::new(poiseuille),
            base: knobs(8.0),
            cells: if quick { vec![4.0, 8.0, 16.0] } else { vec![4.0, 8.0, 16.0, 32.0] },
            steps: STEPS.to_vec(),
            tols: tols.clone(),
            preset_cells: None,
            presets: vec![],
            has_order: true,
            reference_wall: 0.0,
        },
        Case {
            name: "standing_wave",
            error: "|ω/ω_linear − 1| of the first sloshing mode from its first half period (1 m tank, 0.5 m deep, a = 1 mm)",
            second: "amplitude decay error over T/2 (|trough/crest / linear theory − 1|)",
            expected: "2 (linear elements, a second-order scheme with Δt ∝ h)",
            run: Box::new(standing_wave),
            base: knobs(20.0),
            cells: if quick { vec![10.0, 20.0, 40.0] } else { vec![10.0, 20.0, 40.0, 80.0] },
            steps: STEPS.to_vec(),
            tols: tols.clone(),
            preset_cells: Some(20),
            presets: presets.clone(),
            has_order: true,
            reference_wall: 0.0,
        },
        Case {
            name: "cantilever_static",
            error: "|δ/δ_Timoshenko − 1| of the CSM2 tip deflection (16.95 mm; the root clamped as beam theory has it: u_x = 0, its mid-thickness held), backward Euler to the static state",
            second: "tip deflection (mm)",
            expected: "2 in energy for linear triangles, less at coarse resolutions where they lock in bending",
            run: Box::new(cantilever_static),
            base: knobs(4.0),
            cells: if quick { vec![2.0, 4.0, 8.0] } else { vec![2.0, 4.0, 8.0, 16.0, 32.0] },
            steps: vec![],
            tols: tols.clone(),
            preset_cells: Some(4),
            presets: presets.clone(),
            has_order: true,
            reference_wall: 0.0,
        },
        Case {
            name: "cantilever_vibration",
            error: "|ω/ω_Timoshenko − 1| of the CSM2 beam's first bending frequency (13.50 rad/s; the same clamp), 1.5 periods",
            second: "ω (rad/s)",
            expected: "2 (frequency error of linear triangles, locking at coarse resolutions)",
            run: Box::new(cantilever_vibration),
            base: knobs(4.0),
            cells: if quick { vec![2.0, 4.0, 8.0] } else { vec![2.0, 4.0, 8.0, 16.0] },
            steps: STEPS.to_vec(),
            tols: tols.clone(),
            preset_cells: Some(4),
            presets: presets.clone(),
            has_order: true,
            reference_wall: 0.0,
        },
        Case {
            name: "water_at_rest",
            error: "RMS of p − ρg(H − y) below the surface layer / RMS of ρg(H − y), after 0.5 s (1 m tank, 0.5 m deep)",
            second: "largest speed (√(gH))",
            expected: "none: exact (linear pressure is in the P1 space, the lattice a discrete equilibrium)",
            run: Box::new(water_at_rest),
            base: knobs(20.0),
            cells: if quick { vec![10.0, 20.0, 40.0] } else { vec![10.0, 20.0, 40.0, 80.0] },
            steps: vec![],
            tols: vec![],
            preset_cells: None,
            presets: vec![],
            has_order: false,
            reference_wall: 0.0,
        },
    ];
    // The dam break's reference: a finer run of the library itself.
    let ref_cells = if quick { 32 } else { 45 };
    pfem::errln!("dam_break: the reference run at a/{ref_cells} …");
    let t0 = Instant::now();
    let (reference, _) = DamBreakFront {
        cells: ref_cells,
        ..DamBreakFront::default()
    }
    .run(StepParams::default(), 0.5)?;
    let reference_wall = t0.elapsed().as_secs_f64();
    pfem::errln!("dam_break: reference done in {reference_wall:.0} s");
    v.push(Case {
        name: "dam_break",
        error: if quick {
            "RMS relative difference of the front x/a at T = 0.5…2.5 against a run at a/32"
        } else {
            "RMS relative difference of the front x/a at T = 0.5…2.5 against a run at a/45"
        },
        second: "front error vs Martin & Moyce (T ≤ 2.5, best shift)",
        expected: "1: the front is the leading particle, resolved to one spacing",
        run: Box::new(move |k| dam_break(k, &reference)),
        base: knobs(16.0),
        cells: if quick {
            vec![8.0, 11.0, 16.0]
        } else {
            vec![8.0, 11.0, 16.0, 23.0]
        },
        steps: STEPS.to_vec(),
        tols: tols.clone(),
        preset_cells: Some(20),
        presets: presets.clone(),
        has_order: true,
        reference_wall,
    });
    if !quick {
        v.push(Case {
            name: "elastic_gate",
            error: "|peak ux / 46.0 mm − 1| against Antoci et al. 2007 (t ≤ 0.2 s; plane stress; gate spacing 1.25 mm)",
            second: "peak-time error (s)",
            expected: "none (validation against an experiment; the timing gap is known)",
            run: Box::new(gate),
            base: knobs(20.0),
            cells: vec![10.0, 13.3, 20.0, 28.6],
            steps: STEPS.to_vec(),
            tols: vec![1e-6, 1e-3],
            preset_cells: None,
            presets: vec![],
            has_order: false,
            reference_wall: 0.0,
        });
    }
    Ok(v)
}

impl Case {
    /// The runs: base point, then one knob at a time, then the presets.
    fn points(&self) -> Vec<(String, Knobs)> {
        let mut v = vec![("base".to_string(), self.base)];
        let mut add = |name: &str, k: Knobs| {
            if k != self.base {
                v.push((name.to_string(), k));
            }
        };
        for &c in &self.cells {
            add(
                "spacing",
                Knobs {
                    cells: c,
                    ..self.base
                },
            );
        }
        for &s in &self.steps {
            add(
                "step",
                Knobs {
                    step: s,
                    ..self.base
                },
            );
        }
        for &t in &self.tols {
            add(
                "picard_tol",
                Knobs {
                    tol: t,
                    ..self.base
                },
            );
        }
        if let Some(c) = self.preset_cells {
            for &f in &self.presets {
                v.push((
                    format!("preset:{}", f.name()),
                    Knobs {
                        cells: f.cells(c) as f64,
                        step: f.step_factor(),
                        tol: f.picard_tolerance(),
                    },
                ));
            }
        }
        v
    }
}

fn run() -> Res<()> {
    let mut out: Option<PathBuf> = None;
    let mut quick = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = Some(args.next().ok_or("--out needs a value")?.into()),
            "--quick" => quick = true,
            "-h" | "--help" => {
                pfem::outln!(
                    "cargo run --release --example accuracy_cost -- [--out DIR] [--quick]"
                );
                return Ok(());
            }
            other => {
                return Err(format!("unknown argument `{other}` (use --out DIR [--quick])").into())
            }
        }
    }
    let out = out.unwrap_or_else(|| "out/accuracy_cost".into());
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let started = Instant::now();
    let cases = cases(quick)?;
    let total: usize = cases.iter().map(|c| c.points().len()).sum();
    pfem::errln!(
        "accuracy_cost: {} runs ({}), writing {}",
        total,
        if quick { "quick" } else { "full" },
        out.display()
    );
    let mut records = Vec::new();
    let mut n = 0;
    for case in &cases {
        for (varied, k) in case.points() {
            n += 1;
            let rec = match (case.run)(k) {
                Ok(o) => {
                    let s = o.sim.stats();
                    Record {
                        case: case.name,
                        varied: varied.clone(),
                        k,
                        h: o.h,
                        error: o.error,
                        second: o.second,
                        wall: o.wall,
                        steps: o.sim.steps(),
                        rejected: o.sim.rejected(),
                        stages: [s.remesh.1, s.assemble.1, s.solve.1, s.update.1, s.observe.1],
                        status: "ok".into(),
                    }
                }
                Err(e) => Record {
                    case: case.name,
                    varied: varied.clone(),
                    k,
                    h: f64::NAN,
                    error: f64::NAN,
                    second: f64::NAN,
                    wall: 0.0,
                    steps: 0,
                    rejected: 0,
                    stages: [0.0; 5],
                    status: format!("error: {e}"),
                },
            };
            pfem::errln!(
                "[{n:2}/{total}] {:20} {:16} cells {:5.1}  step ×{:<4} tol {:.0e}: error {:.3e}  wall {:6.1} s  {:4} steps ({} rejected)  {}  [elapsed {:.0} s]",
                rec.case,
                rec.varied,
                rec.k.cells,
                rec.k.step,
                rec.k.tol,
                rec.error,
                rec.wall,
                rec.steps,
                rec.rejected,
                rec.status,
                started.elapsed().as_secs_f64()
            );
            records.push(rec);
            write_csv(&out, &records)?;
        }
    }
    write_outputs(
        &out,
        &records,
        &cases,
        quick,
        started.elapsed().as_secs_f64(),
    )?;
    pfem::outln!(
        "wrote {} ({} runs, {:.0} s)",
        out.display(),
        records.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

fn write_csv(out: &Path, records: &[Record]) -> Res<()> {
    let mut csv = String::from("case,varied,cells,spacing_m,step_factor,picard_tol,error,second,wall_s,steps,rejected,remesh_s,assemble_s,solve_s,update_s,observe_s,status\n");
    for r in records {
        writeln!(
            csv,
            "{},{},{},{:.6e},{},{:.0e},{:.6e},{:.6e},{:.3},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},\"{}\"",
            r.case,
            r.varied,
            r.k.cells,
            r.h,
            r.k.step,
            r.k.tol,
            r.error,
            r.second,
            r.wall,
            r.steps,
            r.rejected,
            r.stages[0],
            r.stages[1],
            r.stages[2],
            r.stages[3],
            r.stages[4],
            r.status.replace('"', "'")
        )?;
    }
    pfem::output::write_atomic(out.join("accuracy_cost.csv"), csv.as_bytes())?;
    Ok(())
}

fn usable(r: &Record) -> bool {
    r.status == "ok" && r.error.is_finite() && r.error > 0.0
}

/// The records of `case` along `knob` (the base point included), in the
/// knob's order from cheap to dear.
fn sweep<'a>(records: &'a [Record], case: &str, knob: &str) -> Vec<&'a Record> {
    let mut v: Vec<&Record> = records
        .iter()
        .filter(|r| r.case == case && (r.varied == knob || r.varied == "base"))
        .collect();
    v.sort_by(|a, b| match knob {
        "spacing" => a.k.cells.total_cmp(&b.k.cells),
        "step" => b.k.step.total_cmp(&a.k.step),
        _ => b.k.tol.total_cmp(&a.k.tol),
    });
    v
}

/// The records on the Pareto front of `case` (no other run has both a
/// smaller error and a smaller wall time), by wall time.
fn pareto<'a>(records: &'a [Record], case: &str) -> Vec<&'a Record> {
    let mut v: Vec<&Record> = records
        .iter()
        .filter(|r| r.case == case && usable(r))
        .collect();
    v.sort_by(|a, b| a.wall.total_cmp(&b.wall));
    let mut front: Vec<&Record> = Vec::new();
    for r in v {
        if front.last().is_none_or(|l| r.error < l.error) {
            front.push(r);
        }
    }
    front
}

fn label(r: &Record) -> String {
    format!(
        "{} (cells {}, step ×{}, tol {:.0e})",
        r.varied, r.k.cells, r.k.step, r.k.tol
    )
}

fn write_outputs(
    out: &Path,
    records: &[Record],
    cases: &[Case],
    quick: bool,
    elapsed: f64,
) -> Res<()> {
    let mut md = String::new();
    let kind = if quick { "quick" } else { "full" };
    writeln!(md, "# Accuracy against cost ({kind} study)\n")?;
    writeln!(
        md,
        "`cargo run --release --example accuracy_cost -- --out {}{}`: {} runs in {:.0} s (reference runs included).\n",
        out.display(),
        if quick { " --quick" } else { "" },
        records.len(),
        elapsed
    )?;
    let mut summary = String::from(
        "| case | observed order in h (runs) | expected | halving the error by refining costs | cheapest knob |\n|---|---:|---|---:|---|\n",
    );
    let mut conv: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for case in cases {
        let name = case.name;
        writeln!(md, "## {name}\n\nError: {}.\n", case.error)?;
        if case.reference_wall > 0.0 {
            writeln!(md, "The reference run took {:.0} s.\n", case.reference_wall)?;
        }
        writeln!(md, "| varied | cells | h (m) | step × | Picard tol | error | {} | wall (s) | steps | rejected | remesh (s) | assemble (s) | solve (s) | update (s) | observe (s) | status |", case.second)?;
        writeln!(
            md,
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
        )?;
        for r in records.iter().filter(|r| r.case == name) {
            writeln!(
                md,
                "| {} | {} | {:.3e} | {} | {:.0e} | {:.3e} | {:.4} | {:.2} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {} |",
                r.varied, r.k.cells, r.h, r.k.step, r.k.tol, r.error, r.second, r.wall, r.steps,
                r.rejected, r.stages[0], r.stages[1], r.stages[2], r.stages[3], r.stages[4], r.status
            )?;
        }
        writeln!(md)?;
        // Order along the spacing sweep.
        let sp: Vec<&Record> = sweep(records, name, "spacing")
            .into_iter()
            .filter(|r| usable(r))
            .collect();
        let eh: Vec<(f64, f64)> = sp.iter().map(|r| (r.h, r.error)).collect();
        let order = observed_order(&eh);
        let cost_h = slope(
            &sp.iter()
                .map(|r| (r.h.ln(), r.wall.max(1e-3).ln()))
                .collect::<Vec<_>>(),
        );
        let k = slope(
            &sp.iter()
                .map(|r| (r.error.ln(), r.wall.max(1e-3).ln()))
                .collect::<Vec<_>>(),
        );
        let halving = if case.has_order && order > 0.0 && k < 0.0 {
            format!("{:.1}×", 2f64.powf(-k))
        } else {
            "–".into()
        };
        if case.has_order {
            writeln!(
                md,
                "Spacing sweep: observed order **{order:.2}** (least-squares slope of log error against log h over {} runs; expected {}); wall time ∝ h^{cost_h:.2}; halving the error by refining costs {halving} the time.\n",
                sp.len(),
                case.expected
            )?;
        } else {
            writeln!(md, "No order: {}.\n", case.expected)?;
        }
        // The knob that buys accuracy cheapest: the steepest fall of log
        // error per log wall time along its sweep.
        let mut best: Option<(&str, f64)> = None;
        let mut knob_lines = String::new();
        for knob in ["spacing", "step", "picard_tol"] {
            let pts: Vec<(f64, f64)> = sweep(records, name, knob)
                .into_iter()
                .filter(|r| usable(r))
                .map(|r| (r.wall.max(1e-3).ln(), r.error.ln()))
                .collect();
            if pts.len() < 2 {
                continue;
            }
            let s = slope(&pts);
            writeln!(knob_lines, "- {knob}: d log(error) / d log(wall) = {s:.2}")?;
            if s < 0.0 && best.is_none_or(|b| s < b.1) {
                best = Some((knob, s));
            }
        }
        let cheapest = best.map_or("none (no knob lowers the error)".to_string(), |b| {
            format!("{} ({:.2})", b.0, b.1)
        });
        if case.has_order {
            writeln!(
                md,
                "Along each knob (negative: more time buys less error):\n\n{knob_lines}\nCheapest: **{cheapest}**.\n"
            )?;
        }
        let front = pareto(records, name);
        writeln!(
            md,
            "Pareto front (no run is both faster and more accurate):\n"
        )?;
        for r in &front {
            writeln!(md, "- {:.3e} in {:.2} s: {}", r.error, r.wall, label(r))?;
        }
        writeln!(md)?;
        writeln!(
            summary,
            "| {name} | {} | {} | {halving} | {} |",
            if case.has_order {
                format!("{order:.2} ({})", sp.len())
            } else {
                "exact / validation".into()
            },
            case.expected,
            if case.has_order {
                cheapest.as_str()
            } else {
                "–"
            }
        )?;
        if case.has_order {
            let base_h = sp.first().map_or(1.0, |r| r.h * r.k.cells);
            conv.push((
                name.to_string(),
                sp.iter()
                    .map(|r| ((r.h / base_h).log10(), r.error.log10()))
                    .collect(),
            ));
        }
        plot_case(out, records, name, &front)?;
        writeln!(md, "![{name}]({name}.png)\n")?;
    }
    // The presets on every case.
    let mut presets = String::from(
        "| case | preset | cells | step × | Picard tol | error | wall (s) | steps (rejected) |\n|---|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in records.iter().filter(|r| r.varied.starts_with("preset:")) {
        writeln!(
            presets,
            "| {} | {} | {:.1} | {} | {:.0e} | {:.3e} | {:.2} | {} ({}) |",
            r.case,
            r.varied.trim_start_matches("preset:"),
            r.k.cells,
            r.k.step,
            r.k.tol,
            r.error,
            r.wall,
            r.steps,
            r.rejected
        )?;
    }
    let head = format!(
        "## Summary\n\n{summary}\n## The presets on every case\n\n{presets}\n![convergence](convergence.png)\n\n"
    );
    let at = md.find("## ").unwrap_or(md.len());
    md.insert_str(at, &head);
    let series: Vec<PlotSeries> = conv
        .iter()
        .filter(|(_, p)| !p.is_empty())
        .map(|(l, p)| PlotSeries::line(l.as_str(), p))
        .collect();
    if !series.is_empty() {
        plot_series_png(
            out.join("convergence.png"),
            &PlotSpec {
                title: "Error against spacing (relative to each case's length scale)".into(),
                x_label: "log10(h / L)".into(),
                y_label: "log10(relative error)".into(),
                series,
                ..Default::default()
            },
        )?;
    }
    pfem::output::write_atomic(out.join("accuracy_cost.md"), md.as_bytes())?;
    Ok(())
}

/// `DIR/<case>.png`: log10 error against log10 wall time, one curve per
/// knob, the presets as markers, the Pareto front.
fn plot_case(out: &Path, records: &[Record], case: &str, front: &[&Record]) -> Res<()> {
    let xy = |r: &Record| (r.wall.max(1e-3).log10(), r.error.log10());
    let mut curves: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for knob in ["spacing", "step", "picard_tol"] {
        let pts: Vec<(f64, f64)> = sweep(records, case, knob)
            .into_iter()
            .filter(|r| usable(r))
            .map(xy)
            .collect();
        if pts.len() > 1 {
            curves.push((format!("vary {knob}"), pts));
        }
    }
    let presets: Vec<(f64, f64)> = records
        .iter()
        .filter(|r| r.case == case && r.varied.starts_with("preset") && usable(r))
        .map(xy)
        .collect();
    let front: Vec<(f64, f64)> = front.iter().map(|r| xy(r)).collect();
    let mut series: Vec<PlotSeries> = curves
        .iter()
        .map(|(l, p)| PlotSeries::line(l.as_str(), p))
        .collect();
    if !presets.is_empty() {
        series.push(PlotSeries::markers("Fidelity presets", &presets));
    }
    if !front.is_empty() {
        series.push(PlotSeries::line("Pareto front", &front));
    }
    if series.is_empty() {
        return Ok(());
    }
    plot_series_png(
        out.join(format!("{case}.png")),
        &PlotSpec {
            title: format!("{case}: error against wall time").into(),
            x_label: "log10(wall time / s)".into(),
            y_label: "log10(relative error)".into(),
            series,
            ..Default::default()
        },
    )?;
    Ok(())
}
