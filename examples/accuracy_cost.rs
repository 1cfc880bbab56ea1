//! What accuracy costs in time: error against wall time for the dam break
//! (surge front vs Martin & Moyce 1952), the elastic gate (peak free-end
//! ux vs Antoci et al. 2007) and the Turek–Hron CSM2 cantilever
//! (quasi-static tip deflection vs −16.97 mm).
//!
//! ```text
//! cargo run --release --example accuracy_cost -- --out DIR [--quick]
//! ```
//!
//! Around a base point per case, one parameter is varied at a time: the
//! particle spacing (≥ 4 values), the Courant number (0.25, 0.5, 1) and the
//! Picard tolerance (1e-6, 1e-3); the dam break also runs the three
//! [`pfem::fidelity::Fidelity`] presets. Each run records its error, wall
//! time, accepted and rejected steps and the wall time of each stage
//! (`Simulation::stats`). Writes `DIR/accuracy_cost.csv`,
//! `DIR/accuracy_cost.md` (tables, observed convergence orders, cost of
//! halving the error) and `DIR/<case>_error_vs_time.png` (log10–log10),
//! `DIR/convergence.png` (log10 error against log10 h).
//!
//! The gate runs end at 0.2 s (the measured peak of ux is at 0.16 s), not
//! at the case's default 0.4 s. The full study takes about 25 minutes on
//! 2 cores, `--quick` about 3.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use pfem::cases::{best_shift, front_x, DamBreak, ElasticGate, G};
use pfem::fidelity::Fidelity;
use pfem::output::{parse_reference_csv, plot_series_png, reference, PlotSeries, PlotSpec};
use pfem::prelude::*;

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// One parameter set of one case.
#[derive(Clone, Copy, Debug)]
struct Point3 {
    spacing: f64,
    courant: f64,
    tol: f64,
}

/// What one run measured.
#[derive(Clone, Debug)]
struct Record {
    case: &'static str,
    varied: String,
    p: Point3,
    /// Primary error (relative, dimensionless).
    error: f64,
    /// Secondary figure (dam break: fitted time shift in T; gate: peak-time
    /// error in s; cantilever: tip deflection in mm).
    secondary: f64,
    wall: f64,
    steps: u64,
    rejected: u64,
    /// remesh, assemble, solve, update, observe (s).
    stages: [f64; 5],
    status: String,
}

/// Records `(t, f(sim))` after every step.
struct Recorder {
    f: Box<dyn Fn(&Simulation<2>) -> f64>,
    data: Vec<(f64, f64)>,
}

impl Observer<2> for Recorder {
    fn start(&mut self, sim: &Simulation<2>) -> Result<(), pfem::RunError> {
        self.data.push((sim.time(), (self.f)(sim)));
        Ok(())
    }
    fn step(&mut self, sim: &Simulation<2>) -> Result<(), pfem::RunError> {
        self.data.push((sim.time(), (self.f)(sim)));
        Ok(())
    }
}

/// Runs `sim` with a recorder; returns the series, the wall time and the
/// run's error (if any, as text).
fn run_recorded(
    sim: &mut Simulation<2>,
    f: Box<dyn Fn(&Simulation<2>) -> f64>,
) -> (Vec<(f64, f64)>, f64, String) {
    let mut rec = Recorder {
        f,
        data: Vec::new(),
    };
    let t0 = Instant::now();
    let status = match sim.run(&mut [&mut rec]) {
        Ok(()) => "ok".to_string(),
        Err(e) => format!("error: {e}"),
    };
    (rec.data, t0.elapsed().as_secs_f64(), status)
}

fn record(
    case: &'static str,
    varied: &str,
    p: Point3,
    sim: &Simulation<2>,
    wall: f64,
    status: String,
) -> Record {
    let s = &sim.stats();
    Record {
        case,
        varied: varied.to_string(),
        p,
        error: f64::NAN,
        secondary: f64::NAN,
        wall,
        steps: sim.steps(),
        rejected: sim.rejected(),
        stages: [s.remesh.1, s.assemble.1, s.solve.1, s.update.1, s.observe.1],
        status,
    }
}

fn params(tol: f64, scheme: Scheme) -> StepParams {
    StepParams {
        picard_tolerance: tol,
        scheme,
        ..StepParams::default()
    }
}

/// Dam break, n² = 2, a = 2.25 in, to T = 3: RMS relative front error after
/// the best time shift.
fn dam_break(varied: &str, p: Point3) -> Res<Record> {
    let mut case = DamBreak::default();
    let t_scale = (2.0 * G / case.width).sqrt();
    case.spacing = p.spacing;
    case.end_time = 3.0 / t_scale;
    let mut scene = case.scene();
    scene.settings.courant = p.courant;
    scene.settings.output_interval = None;
    let mut sim = Simulation::new(
        scene,
        Box::new(Delaunay2::default()),
        params(p.tol, Scheme::Bossak),
    )?;
    let (series, wall, status) = run_recorded(&mut sim, Box::new(front_x));
    let a = case.width;
    let front: Vec<(f64, f64)> = series.iter().map(|&(t, x)| (t * t_scale, x / a)).collect();
    let measured = parse_reference_csv(reference::MARTIN_MOYCE_N2_2_A2_25IN_FRONT)?;
    let (shift, rms) = best_shift(&front, &measured, 3.0, 0.5, 0.01);
    let mut r = record("dam_break", varied, p, &sim, wall, status);
    r.error = rms;
    r.secondary = shift;
    Ok(r)
}

/// Elastic gate to 0.2 s: relative error of the peak free-end ux and the
/// error of its time (s) against Antoci et al. (2007).
fn gate(varied: &str, p: Point3) -> Res<Record> {
    let case = ElasticGate {
        spacing: p.spacing,
        end_time: 0.2,
        ..ElasticGate::default()
    };
    let mut scene = case.scene()?;
    scene.settings.courant = p.courant;
    scene.settings.output_interval = None;
    let mut sim = Simulation::new(
        scene,
        Box::new(Delaunay2::default()),
        params(p.tol, Scheme::Bossak),
    )?;
    let probe = case
        .probes()
        .into_iter()
        .find(|q| q.name == "ux_tip")
        .ok_or("no ux_tip probe")?;
    let (ux, wall, status) = run_recorded(&mut sim, probe.measure);
    let peak = |s: &[(f64, f64)]| {
        s.iter().copied().fold(
            (0.0, f64::NEG_INFINITY),
            |b, q| if q.1 > b.1 { q } else { b },
        )
    };
    let exp = parse_reference_csv(reference::ANTOCI_2007_GATE_UX)?;
    let exp: Vec<(f64, f64)> = exp.into_iter().filter(|q| q.0 <= 0.2).collect();
    let (t_sim, u_sim) = peak(&ux);
    let (t_exp, u_exp) = peak(&exp);
    let mut r = record("elastic_gate", varied, p, &sim, wall, status);
    r.error = (u_sim / u_exp - 1.0).abs();
    r.secondary = t_sim - t_exp;
    Ok(r)
}

/// CSM2 tip deflection (m).
const CSM2_TIP: f64 = -16.97e-3;

/// Turek–Hron CSM2 cantilever (L = 0.35 m, t = 0.02 m, E = 5.6 MPa,
/// ν = 0.4, ρ = 1000 kg/m³, g = 2 m/s²), clamped at x = 0, through
/// `Simulation`: backward Euler with steps up to 5 s (far longer than the
/// 0.46 s period) to t = 40 s, so each step is a static solve. Error:
/// relative error of the tip deflection at mid-thickness against CSM2.
fn cantilever(varied: &str, p: Point3) -> Res<Record> {
    let (l, t) = (0.35, 0.02);
    let solid = Hypoelastic::new(1000.0, 5.6e6, 0.4)?;
    let scene = Scene::<2>::new("cantilever")
        .gravity(Vector::<2>::new(0.0, -2.0))
        .settings(RunSettings {
            end_time: 40.0,
            max_dt: 5.0,
            courant: p.courant,
            output_interval: None,
            alpha: 1.3,
        })
        .solid(
            "beam",
            Box::new(solid),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(l, t),
            },
            p.spacing,
            Some((Point::<2>::new(-1.0, -1.0), Point::<2>::new(1e-9, 1.0))),
        );
    let mut sim = Simulation::new(
        scene,
        Box::new(Delaunay2::default()),
        params(p.tol, Scheme::BackwardEuler),
    )?;
    let target = Point::<2>::new(l, 0.5 * t);
    let tip = (0..sim.particles().len())
        .min_by(|&a, &b| {
            (sim.particles().x()[a] - target)
                .norm()
                .total_cmp(&(sim.particles().x()[b] - target).norm())
        })
        .ok_or("empty beam")?;
    let y0 = sim.particles().x()[tip].y;
    let (series, wall, status) = run_recorded(
        &mut sim,
        Box::new(move |s: &Simulation<2>| s.particles().x()[tip].y - y0),
    );
    let deflection = series.last().map_or(f64::NAN, |q| q.1);
    let mut r = record("cantilever", varied, p, &sim, wall, status);
    r.error = (deflection / CSM2_TIP - 1.0).abs();
    r.secondary = 1e3 * deflection;
    Ok(r)
}

/// A case's sweep: base point, spacings, Courant numbers, tolerances.
struct Sweep {
    name: &'static str,
    run: fn(&str, Point3) -> Res<Record>,
    base: Point3,
    spacings: Vec<f64>,
    courants: Vec<f64>,
    tols: Vec<f64>,
    presets: Vec<Fidelity>,
    /// The case's default spacing (for the presets).
    default_spacing: f64,
}

impl Sweep {
    /// The runs: base point, then one parameter at a time (the base point is
    /// run once and counted in every sweep).
    fn points(&self) -> Vec<(String, Point3)> {
        let mut v = vec![("base".to_string(), self.base)];
        for &s in &self.spacings {
            if s != self.base.spacing {
                v.push((
                    "spacing".into(),
                    Point3 {
                        spacing: s,
                        ..self.base
                    },
                ));
            }
        }
        for &c in &self.courants {
            if c != self.base.courant {
                v.push((
                    "courant".into(),
                    Point3 {
                        courant: c,
                        ..self.base
                    },
                ));
            }
        }
        for &t in &self.tols {
            if t != self.base.tol {
                v.push((
                    "picard_tol".into(),
                    Point3 {
                        tol: t,
                        ..self.base
                    },
                ));
            }
        }
        for &f in &self.presets {
            v.push((
                format!("preset:{}", f.name()),
                Point3 {
                    spacing: f.spacing(self.default_spacing),
                    courant: f.courant(),
                    tol: f.picard_tolerance(),
                },
            ));
        }
        v
    }
}

fn sweeps(quick: bool) -> Vec<Sweep> {
    let a = DamBreak::default().width;
    let cs = vec![0.25, 0.5, 1.0];
    let tols = vec![1e-6, 1e-3];
    if quick {
        vec![
            Sweep {
                name: "dam_break",
                run: dam_break,
                base: Point3 {
                    spacing: a / 12.0,
                    courant: 0.5,
                    tol: 1e-6,
                },
                spacings: vec![a / 8.0, a / 10.0, a / 12.0, a / 16.0],
                courants: cs.clone(),
                tols: tols.clone(),
                presets: vec![Fidelity::Draft, Fidelity::Standard],
                default_spacing: a / 20.0,
            },
            Sweep {
                name: "elastic_gate",
                run: gate,
                base: Point3 {
                    spacing: 0.0075,
                    courant: 0.5,
                    tol: 1e-6,
                },
                spacings: vec![0.01, 0.0075, 0.006, 0.005],
                courants: cs.clone(),
                tols: tols.clone(),
                presets: vec![],
                default_spacing: 0.0025,
            },
            Sweep {
                name: "cantilever",
                run: cantilever,
                base: Point3 {
                    spacing: 0.02 / 4.0,
                    courant: 0.5,
                    tol: 1e-6,
                },
                spacings: vec![0.01, 0.02 / 3.0, 0.005, 0.004],
                courants: cs,
                tols,
                presets: vec![],
                default_spacing: 0.005,
            },
        ]
    } else {
        vec![
            Sweep {
                name: "dam_break",
                run: dam_break,
                base: Point3 {
                    spacing: a / 14.0,
                    courant: 0.5,
                    tol: 1e-6,
                },
                spacings: vec![a / 10.0, a / 14.0, a / 20.0, a / 28.0],
                courants: cs.clone(),
                tols: tols.clone(),
                presets: Fidelity::ALL.to_vec(),
                default_spacing: a / 20.0,
            },
            Sweep {
                name: "elastic_gate",
                run: gate,
                base: Point3 {
                    spacing: 0.005,
                    courant: 0.5,
                    tol: 1e-6,
                },
                spacings: vec![0.01, 0.0075, 0.005, 0.0035],
                courants: cs.clone(),
                tols: tols.clone(),
                presets: vec![],
                default_spacing: 0.0025,
            },
            Sweep {
                name: "cantilever",
                run: cantilever,
                base: Point3 {
                    spacing: 0.02 / 8.0,
                    courant: 0.5,
                    tol: 1e-6,
                },
                spacings: vec![0.01, 0.005, 0.0025, 0.00125, 0.000625],
                courants: cs,
                tols,
                presets: vec![],
                default_spacing: 0.0025,
            },
        ]
    }
}

/// Least-squares slope of `y` against `x`.
fn slope(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return f64::NAN;
    }
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

fn usable(r: &Record) -> bool {
    r.status == "ok" && r.error.is_finite() && r.error > 0.0
}

/// The records of `case` in the sweep of `param` (the base point included).
fn sweep_of<'a>(records: &'a [Record], case: &str, param: &str) -> Vec<&'a Record> {
    let mut v: Vec<&Record> = records
        .iter()
        .filter(|r| r.case == case && (r.varied == param || r.varied == "base"))
        .collect();
    v.sort_by(|a, b| match param {
        "spacing" => b.p.spacing.total_cmp(&a.p.spacing),
        "courant" => a.p.courant.total_cmp(&b.p.courant),
        _ => b.p.tol.total_cmp(&a.p.tol),
    });
    v
}

fn run() -> Res<()> {
    let mut out: Option<PathBuf> = None;
    let mut quick = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = Some(args.next().ok_or("--out needs a value")?.into()),
            "--quick" => quick = true,
            other => {
                return Err(format!("unknown argument `{other}` (use --out DIR [--quick])").into())
            }
        }
    }
    let out = out.unwrap_or_else(|| "out/accuracy_cost".into());
    std::fs::create_dir_all(&out)?;
    let sweeps = sweeps(quick);
    let total: usize = sweeps.iter().map(|s| s.points().len()).sum();
    eprintln!(
        "accuracy_cost: {} runs ({}), writing {}",
        total,
        if quick { "quick" } else { "full" },
        out.display()
    );
    let started = Instant::now();
    let mut records = Vec::new();
    let mut k = 0;
    for sw in &sweeps {
        for (varied, p) in sw.points() {
            k += 1;
            let rec = match (sw.run)(&varied, p) {
                Ok(r) => r,
                Err(e) => Record {
                    case: sw.name,
                    varied: varied.clone(),
                    p,
                    error: f64::NAN,
                    secondary: f64::NAN,
                    wall: 0.0,
                    steps: 0,
                    rejected: 0,
                    stages: [0.0; 5],
                    status: format!("error: {e}"),
                },
            };
            eprintln!(
                "[{k:2}/{total}] {:12} {:16} h = {:.3e} m  C = {:<4}  tol = {:.0e}: error {:6.2}%  wall {:7.1} s  {:5} steps ({} rejected)  {}  [elapsed {:.0} s]",
                rec.case,
                rec.varied,
                rec.p.spacing,
                rec.p.courant,
                rec.p.tol,
                100.0 * rec.error,
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
        &sweeps,
        quick,
        started.elapsed().as_secs_f64(),
    )?;
    println!(
        "wrote {} ({} runs, {:.0} s)",
        out.display(),
        records.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

fn write_csv(out: &std::path::Path, records: &[Record]) -> Res<()> {
    let mut csv = String::from("case,varied,spacing_m,courant,picard_tol,error,secondary,wall_s,steps,rejected,remesh_s,assemble_s,solve_s,update_s,observe_s,status\n");
    for r in records {
        writeln!(
            csv,
            "{},{},{:.6e},{},{:.0e},{:.6e},{:.6e},{:.3},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},\"{}\"",
            r.case,
            r.varied,
            r.p.spacing,
            r.p.courant,
            r.p.tol,
            r.error,
            r.secondary,
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

fn secondary_label(case: &str) -> &'static str {
    match case {
        "dam_break" => "time shift (T)",
        "elastic_gate" => "peak-time error (s)",
        _ => "tip deflection (mm)",
    }
}

fn error_label(case: &str) -> &'static str {
    match case {
        "dam_break" => "front RMS relative error vs Martin & Moyce (T ≤ 3, best shift)",
        "elastic_gate" => "relative error of peak ux vs Antoci et al. 2007 (t ≤ 0.2 s)",
        _ => "relative error of tip deflection vs CSM2 (−16.97 mm)",
    }
}

fn write_outputs(
    out: &std::path::Path,
    records: &[Record],
    sweeps: &[Sweep],
    quick: bool,
    elapsed: f64,
) -> Res<()> {
    let mut md = String::new();
    writeln!(
        md,
        "# Accuracy against cost ({} study)\n",
        if quick { "quick" } else { "full" }
    )?;
    writeln!(
        md,
        "`cargo run --release --example accuracy_cost -- --out {}{}`; {} runs in {:.0} s.\n",
        out.display(),
        if quick { " --quick" } else { "" },
        records.len(),
        elapsed
    )?;
    let mut conv_series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for sw in sweeps {
        let case = sw.name;
        writeln!(md, "## {case}\n\nError: {}.\n", error_label(case))?;
        writeln!(md, "| varied | h (m) | Courant | Picard tol | error | {} | wall (s) | steps | rejected | remesh (s) | assemble (s) | solve (s) | update (s) | observe (s) | status |", secondary_label(case))?;
        writeln!(
            md,
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
        )?;
        for r in records.iter().filter(|r| r.case == case) {
            writeln!(
                md,
                "| {} | {:.3e} | {} | {:.0e} | {:.2}% | {:.3} | {:.1} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {} |",
                r.varied,
                r.p.spacing,
                r.p.courant,
                r.p.tol,
                100.0 * r.error,
                r.secondary,
                r.wall,
                r.steps,
                r.rejected,
                r.stages[0],
                r.stages[1],
                r.stages[2],
                r.stages[3],
                r.stages[4],
                r.status
            )?;
        }
        // Convergence order and cost of halving the error.
        let sp: Vec<&Record> = sweep_of(records, case, "spacing")
            .into_iter()
            .filter(|r| usable(r))
            .collect();
        let eh: Vec<(f64, f64)> = sp
            .iter()
            .map(|r| (r.p.spacing.log10(), r.error.log10()))
            .collect();
        let order = slope(&eh);
        let ew: Vec<(f64, f64)> = sp
            .iter()
            .map(|r| (r.error.log10(), r.wall.log10()))
            .collect();
        let k = slope(&ew);
        let th: Vec<(f64, f64)> = sp
            .iter()
            .map(|r| (r.p.spacing.log10(), r.wall.log10()))
            .collect();
        let cost_h = slope(&th);
        writeln!(md)?;
        writeln!(
            md,
            "Spacing sweep: observed order {order:.2} (least-squares slope of log error against log h over {} runs); wall time ∝ h^{cost_h:.2}.",
            sp.len()
        )?;
        if order > 0.0 && k < 0.0 {
            writeln!(
                md,
                "Along the spacing sweep, wall time ∝ error^{k:.2}: halving the error costs {:.1}× the time.",
                2f64.powf(-k)
            )?;
        } else {
            writeln!(
                md,
                "The error does not decrease with refinement in this sweep (slope {order:.2}); halving it by refining alone is not possible here."
            )?;
        }
        writeln!(md)?;
        conv_series.push((case.to_string(), eh));

        // Error against wall time, one curve per varied parameter.
        let mut curves: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        for param in ["spacing", "courant", "picard_tol"] {
            let pts: Vec<(f64, f64)> = sweep_of(records, case, param)
                .into_iter()
                .filter(|r| usable(r))
                .map(|r| (r.wall.max(1e-3).log10(), r.error.log10()))
                .collect();
            if !pts.is_empty() {
                curves.push((format!("vary {param}"), pts));
            }
        }
        let presets: Vec<(f64, f64)> = records
            .iter()
            .filter(|r| r.case == case && r.varied.starts_with("preset") && usable(r))
            .map(|r| (r.wall.max(1e-3).log10(), r.error.log10()))
            .collect();
        let mut series: Vec<PlotSeries> = curves
            .iter()
            .map(|(l, p)| PlotSeries::line(l.as_str(), p))
            .collect();
        if !presets.is_empty() {
            series.push(PlotSeries::markers("Fidelity presets", &presets));
        }
        if !series.is_empty() {
            let png = format!("{case}_error_vs_time.png");
            plot_series_png(
                out.join(&png),
                &PlotSpec {
                    title: format!("{case}: error against wall time").into(),
                    x_label: "log10(wall time / s)".into(),
                    y_label: "log10(relative error)".into(),
                    series,
                    ..Default::default()
                },
            )?;
            writeln!(md, "![{case}]({png})\n")?;
        }
    }
    let series: Vec<PlotSeries> = conv_series
        .iter()
        .filter(|(_, p)| !p.is_empty())
        .map(|(l, p)| PlotSeries::line(l.as_str(), p))
        .collect();
    if !series.is_empty() {
        plot_series_png(
            out.join("convergence.png"),
            &PlotSpec {
                title: "Error against particle spacing".into(),
                x_label: "log10(h / m)".into(),
                y_label: "log10(relative error)".into(),
                series,
                ..Default::default()
            },
        )?;
        writeln!(md, "![convergence](convergence.png)")?;
    }
    pfem::output::write_atomic(out.join("accuracy_cost.md"), md.as_bytes())?;
    Ok(())
}
