//! A water column collapsing onto an elastic obstacle clamped to the
//! floor: the 2D analogue of Marti & Idelsohn's §9.2 (their Figs. 7 and 8
//! show the obstacle's displacement and the force on it).
//!
//! ```text
//! cargo run --release --example dam_break_obstacle_2d -- --out out/dam_break_obstacle_2d \
//!     [--spacing H] [--end-time T] [--young E] [--quiet] [--no-vtu]
//! ```
//! Writes the VTU series, `probes.csv` (`t, ux_top, force_x, volume`),
//! `summary.json` and `obstacle.png` (displacement and force over time).

use pfem::cases::DamBreakObstacle;
use pfem::cli::Args;
use pfem::output::{plot_series_png, PlotSeries, PlotSpec};
use pfem::prelude::*;

/// This example's own options, for `--help`.
const OPTIONS: &str = "  --young E             the obstacle's Young's modulus (Pa; default 1e6)
  --restart CHECKPOINT  continue the run that wrote CHECKPOINT when it stopped (in its folder, with the same options)";

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env_with(OPTIONS)?;
    args.reject_unknown(&["young", "restart"])?;
    let mut case = DamBreakObstacle::default();
    case.spacing = args.spacing.unwrap_or(case.spacing);
    case.obstacle_spacing = case.obstacle_spacing.min(case.spacing);
    case.end_time = args.end_time.unwrap_or(case.end_time);
    case.young = args.number("young", case.young)?;
    let out = args.out_or("out/dam_break_obstacle_2d");
    let mut sim = args.simulation(case.scene()?, Box::new(Delaunay2::default()))?;
    pfem::errln!(
        "dam_break_obstacle_2d: {} particles, end time {} s",
        sim.particles().len(),
        case.end_time
    );
    let mut output = StandardOutput::new(&out, !args.no_vtu, case.probes(), args.quiet)
        .overwrite(args.overwrite);
    args.restart(&mut sim, &mut output, &out)?;
    sim.run(&mut [&mut output])?;
    pfem::cli::exit_if_stopped_at(&sim, &output);
    let ux = output.probe_series("ux_top");
    let fx = output.probe_series("force_x");
    let (t_max, ux_max) =
        ux.iter().copied().fold(
            (0.0, f64::NEG_INFINITY),
            |b, p| if p.1 > b.1 { p } else { b },
        );
    let f_max = fx.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    pfem::outln!(
        "largest top displacement {:.2} mm at {:.3} s; largest force {:.1} N/m",
        1e3 * ux_max,
        t_max,
        f_max
    );
    output.extra.insert("max_ux_top_m".into(), ux_max.into());
    output
        .extra
        .insert("max_force_x_n_per_m".into(), f_max.into());
    let ux_mm: Vec<(f64, f64)> = ux.iter().map(|&(t, u)| (t, 1e3 * u)).collect();
    plot_series_png(
        out.join("obstacle.png"),
        &PlotSpec {
            title: "Elastic obstacle: top displacement (mm) and force (N/m / 10)".into(),
            x_label: "t (s)".into(),
            y_label: "ux_top (mm), force_x / 10 (N/m)".into(),
            series: vec![
                PlotSeries::line("ux_top (mm)", &ux_mm),
                PlotSeries::line(
                    "force_x / 10 (N/m)",
                    &fx.iter().map(|&(t, f)| (t, f / 10.0)).collect::<Vec<_>>(),
                ),
            ],
            ..Default::default()
        },
    )?;
    output.report(&sim)?;
    Ok(())
}
