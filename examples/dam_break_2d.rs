//! Martin & Moyce (1952) dam break in 2D: the surge front and the residual
//! height at the back wall against the measurements.
//!
//! ```text
//! cargo run --release --example dam_break_2d -- --out out/dam_break_2d \
//!     [--spacing H] [--end-time T] [--aspect N2] [--width A] [--tank-length L] [--alpha A] [--quiet] [--no-vtu]
//! ```
//! Writes `dam_break_2d.pvd` + `.vtu` frames, `probes.csv`
//! (`t, front_x, height_at_wall, volume`), `summary.json` and
//! `front.png` (and `height.png` for the square column) into the output
//! directory.

use pfem::cases::{best_shift, DamBreak, G};
use pfem::cli::Args;
use pfem::output::{parse_reference_csv, plot_series_png, reference, PlotSeries, PlotSpec};
use pfem::prelude::*;

/// This example's own options, for `--help`.
const OPTIONS: &str = "  --aspect N2           height over width of the column, 1 or 2 (Martin & Moyce's; default 2)
  --width A             column width a (m; default 0.05715)
  --tank-length L       tank length (m; default 10 a)
  --alpha A             alpha-shape parameter (default the scene's, 1.3)
  --restart CHECKPOINT  continue the run that wrote CHECKPOINT when it stopped (in its folder, with the same options)";

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env_with(OPTIONS)?;
    args.reject_unknown(&["aspect", "width", "tank-length", "alpha", "restart"])?;
    let mut case = DamBreak::default();
    case.width = args.number("width", case.width)?;
    case.aspect = args.number("aspect", case.aspect)?;
    // Martin & Moyce measured the square column (n² = 1) and the column
    // twice as high as wide (n² = 2): another aspect has no measurement.
    if case.aspect != 1.0 && case.aspect != 2.0 {
        return Err(format!(
            "--aspect {}: Martin & Moyce measured n² = 1 and n² = 2 only",
            case.aspect
        )
        .into());
    }
    case.tank_length = args.number("tank-length", 10.0 * case.width)?;
    case.spacing = args.spacing.unwrap_or(case.width / 20.0);
    let t_scale = if case.aspect == 1.0 {
        (G / (case.aspect * case.width)).sqrt()
    } else {
        (2.0 * G / case.width).sqrt()
    };
    case.end_time = args.end_time.unwrap_or(3.2 / t_scale);
    let out = args.out_or("out/dam_break_2d");

    let mut scene = case.scene();
    scene.settings.alpha = args.number("alpha", scene.settings.alpha)?;
    let mut sim = args.simulation(scene, Box::new(Delaunay2::default()))?;
    pfem::errln!(
        "dam_break_2d: {} particles, a = {} m, n² = {}, h = {} m, end time {:.3} s",
        sim.particles().len(),
        case.width,
        case.aspect,
        case.spacing,
        case.end_time
    );
    let mut output = StandardOutput::new(&out, !args.no_vtu, case.probes(), args.quiet)
        .overwrite(args.overwrite);
    args.restart(&mut sim, &mut output, &out)?;
    sim.run(&mut [&mut output])?;
    pfem::cli::exit_if_stopped_at(&sim, &output);

    // Compare with Martin & Moyce.
    let a = case.width;
    let front: Vec<(f64, f64)> = output
        .probe_series("front_x")
        .iter()
        .map(|&(t, x)| (t * t_scale, x / a))
        .collect();
    let (measured, label) = if case.aspect == 1.0 {
        (
            parse_reference_csv(reference::MARTIN_MOYCE_N2_1_FRONT)?,
            "T = t √(g/a)",
        )
    } else {
        (
            parse_reference_csv(reference::MARTIN_MOYCE_N2_2_A2_25IN_FRONT)?,
            "T = t √(2g/a)",
        )
    };
    let (shift, rms) = best_shift(&front, &measured, 3.0, 0.5, 0.01);
    pfem::outln!("surge front vs Martin & Moyce (T <= 3): RMS relative error {:.2}% after a fitted time shift of {:+.3} (in T)", 100.0 * rms, shift);
    output
        .extra
        .insert("front_rms_relative_error".into(), rms.into());
    output
        .extra
        .insert("front_time_shift_T".into(), shift.into());
    let shifted: Vec<(f64, f64)> = front.iter().map(|&(t, z)| (t + shift, z)).collect();
    plot_series_png(
        out.join("front.png"),
        &PlotSpec {
            title: format!(
                "Dam break n² = {}: surge front (shift {shift:+.2})",
                case.aspect
            )
            .into(),
            x_label: label.into(),
            y_label: "Z = x/a".into(),
            series: vec![
                PlotSeries::line("pfem", &shifted),
                PlotSeries::markers("Martin & Moyce 1952", &measured),
            ],
            ..Default::default()
        },
    )?;
    if case.aspect == 1.0 {
        let height: Vec<(f64, f64)> = output
            .probe_series("height_at_wall")
            .iter()
            .map(|&(t, y)| (t * t_scale, y / a))
            .collect();
        let measured_h = parse_reference_csv(reference::MARTIN_MOYCE_N2_1_HEIGHT)?;
        let (hs, hrms) = best_shift(&height, &measured_h, 3.0, 0.5, 0.01);
        pfem::outln!(
            "residual height vs Martin & Moyce: RMS relative error {:.2}% (shift {hs:+.3})",
            100.0 * hrms
        );
        output
            .extra
            .insert("height_rms_relative_error".into(), hrms.into());
        let shifted: Vec<(f64, f64)> = height.iter().map(|&(t, z)| (t + hs, z)).collect();
        plot_series_png(
            out.join("height.png"),
            &PlotSpec {
                title: "Dam break n² = 1: residual height at the back wall".into(),
                x_label: label.into(),
                y_label: "h/H".into(),
                series: vec![
                    PlotSeries::line("pfem", &shifted),
                    PlotSeries::markers("Martin & Moyce 1952", &measured_h),
                ],
                ..Default::default()
            },
        )?;
    }
    output.report(&sim)?;
    Ok(())
}
