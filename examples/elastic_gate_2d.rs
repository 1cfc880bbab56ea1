//! Antoci, Gallati & Sibilla (2007): a water column released against a
//! rubber gate clamped at its top; the gate's free-end displacements against
//! the measurements.
//!
//! ```text
//! cargo run --release --example elastic_gate_2d -- --out out/elastic_gate_2d \
//!     [--spacing H] [--end-time T] [--young E] [--gate-spacing H]
//!     [--model plane-stress|plane-strain] [--quiet] [--no-vtu]
//! ```
//! The gate is a 2D solid in plane stress by default (a thin strip,
//! `σ_zz = 0`), with the published E = 12 MPa, ν = 0.4; `--model
//! plane-strain` makes it plane strain (`ε_zz = 0`, about 19 % stiffer in
//! bending at ν = 0.4). The run prints which.
//! Writes `elastic_gate_2d.pvd` + `.vtu` frames, `probes.csv`
//! (`t, ux_tip, uy_tip, volume`), `summary.json` and `gate.png`.

use pfem::cases::ElasticGate;
use pfem::cli::Args;
use pfem::output::{parse_reference_csv, plot_series_png, reference, PlotSeries, PlotSpec};
use pfem::prelude::*;

/// This example's own options, for `--help`.
const OPTIONS: &str = "  --young E             the gate's Young's modulus (Pa; default 12e6)
  --gate-spacing H      the gate's particle spacing (m; default 0.00125)
  --model M             plane-stress (default) or plane-strain
  --restart CHECKPOINT  continue the run that wrote CHECKPOINT when it stopped (in its folder, with the same options)";

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

/// Largest value of a series and its time.
fn peak(series: &[(f64, f64)]) -> (f64, f64) {
    series.iter().copied().fold(
        (0.0, f64::NEG_INFINITY),
        |b, p| if p.1 > b.1 { p } else { b },
    )
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env_with(OPTIONS)?;
    args.reject_unknown(&["young", "gate-spacing", "model", "restart"])?;
    let mut case = ElasticGate::default();
    case.spacing = args.spacing.unwrap_or(case.spacing);
    case.end_time = args.end_time.unwrap_or(case.end_time);
    case.young = args.number("young", case.young)?;
    case.gate_spacing = args.number("gate-spacing", case.gate_spacing)?;
    case.plane_stress = match args.options.get("model").map(String::as_str) {
        None | Some("plane-stress") => true,
        Some("plane-strain") => false,
        Some(other) => {
            return Err(format!("--model {other}: use plane-stress or plane-strain").into())
        }
    };
    let out = args.out_or("out/elastic_gate_2d");
    let mut sim = args.simulation(case.scene()?, Box::new(Delaunay2::default()))?;
    pfem::errln!(
        "elastic_gate_2d: {} particles, h = {} m, gate in {}, E = {} Pa, ν = {}, end time {} s",
        sim.particles().len(),
        case.spacing,
        if case.plane_stress {
            "plane stress"
        } else {
            "plane strain"
        },
        case.young,
        case.poisson,
        case.end_time
    );
    let mut output = StandardOutput::new(&out, !args.no_vtu, case.probes(), args.quiet)
        .overwrite(args.overwrite);
    args.restart(&mut sim, &mut output, &out)?;
    sim.run(&mut [&mut output])?;
    pfem::cli::exit_if_stopped_at(&sim, &output);

    let ux = output.probe_series("ux_tip");
    let uy = output.probe_series("uy_tip");
    let ux_exp = parse_reference_csv(reference::ANTOCI_2007_GATE_UX)?;
    let uy_exp = parse_reference_csv(reference::ANTOCI_2007_GATE_UY)?;
    let (t_sim, ux_sim) = peak(&ux);
    let (t_exp, ux_max) = peak(&ux_exp);
    let (ty_sim, uy_sim) = peak(&uy);
    let (ty_exp, uy_max) = peak(&uy_exp);
    pfem::outln!(
        "peak ux: {:.2} mm at {:.3} s (experiment {:.2} mm at {:.3} s): {:+.1}%",
        1e3 * ux_sim,
        t_sim,
        1e3 * ux_max,
        t_exp,
        100.0 * (ux_sim / ux_max - 1.0)
    );
    pfem::outln!(
        "peak uy: {:.2} mm at {:.3} s (experiment {:.2} mm at {:.3} s): {:+.1}%",
        1e3 * uy_sim,
        ty_sim,
        1e3 * uy_max,
        ty_exp,
        100.0 * (uy_sim / uy_max - 1.0)
    );
    output.extra.insert(
        "gate_model".into(),
        if case.plane_stress {
            "plane stress"
        } else {
            "plane strain"
        }
        .into(),
    );
    output.extra.insert("peak_ux_m".into(), ux_sim.into());
    output.extra.insert("peak_ux_time_s".into(), t_sim.into());
    output.extra.insert(
        "peak_ux_relative_error".into(),
        (ux_sim / ux_max - 1.0).into(),
    );
    output.extra.insert(
        "peak_uy_relative_error".into(),
        (uy_sim / uy_max - 1.0).into(),
    );
    plot_series_png(
        out.join("gate.png"),
        &PlotSpec {
            title: "Elastic gate: free-end displacement".into(),
            x_label: "t (s)".into(),
            y_label: "displacement (m)".into(),
            series: vec![
                PlotSeries::line("pfem ux", &ux),
                PlotSeries::markers("Antoci et al. 2007 ux", &ux_exp),
                PlotSeries::line("pfem uy", &uy),
                PlotSeries::markers("Antoci et al. 2007 uy", &uy_exp),
            ],
            ..Default::default()
        },
    )?;
    output.report(&sim)?;
    Ok(())
}
