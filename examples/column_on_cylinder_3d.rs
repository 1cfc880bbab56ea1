//! §9.2 of the paper in 3D: the water column of §9.1 collapsing onto an
//! elastic cylinder clamped at its base (r = 1.5 cm, h = 15 cm,
//! ρ = 2500 kg/m³, E = 10⁶ Pa, ν = 0.3). The cylinder's mesh is its own
//! (Delaunay of its particles trimmed by the alpha shape, `pfem::solid_mesh`).
//!
//! ```text
//! cargo run --release --example column_on_cylinder_3d -- --out out/column_on_cylinder_3d \
//!     [--spacing H] [--end-time T] [--depth W] [--cylinder-x X] [--quiet] [--no-vtu]
//! ```
//! `--spacing` sets the water's spacing (default 0.0146 m); the cylinder's
//! is 0.0075 m (r/2). Writes `column_on_cylinder_3d.pvd` + `.vtu` frames,
//! `probes.csv` (`t, ux_top, force_x, volume`: top displacement of the
//! cylinder, horizontal fluid force on it, see
//! `pfem::cases3d::fluid_force`) and `summary.json`.

use pfem::cases3d::ColumnOnCylinder3d;
use pfem::cli::Args;
use pfem::prelude::*;

/// This example's own options, for `--help`.
const OPTIONS: &str = "  --depth W             depth of the tank (m; default 0.0584)
  --cylinder-x X        the cylinder's axis along the tank (m; default 0.35)
  --restart CHECKPOINT  continue the run that wrote CHECKPOINT when it stopped (in its folder, with the same options)";

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env_with(OPTIONS)?;
    args.reject_unknown(&["depth", "cylinder-x", "restart"])?;
    let mut case = ColumnOnCylinder3d::default();
    case.column.spacing = args.spacing.unwrap_or(case.column.spacing);
    case.column.end_time = args.end_time.unwrap_or(case.column.end_time);
    case.column.depth = args.number("depth", case.column.depth)?;
    case.cylinder_x = args.number("cylinder-x", case.cylinder_x)?;
    let out = args.out_or("out/column_on_cylinder_3d");
    let mut sim = args.simulation(case.scene()?, Box::new(Delaunay3::default()))?;
    pfem::errln!(
        "column_on_cylinder_3d: {} particles ({} in the cylinder, {} solid elements), h = {} m, end time {} s",
        sim.particles().len(),
        sim.body_particles("cylinder")?.len(),
        sim.elements().solid_material().len(),
        case.column.spacing,
        case.column.end_time
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
            (0.0f64, 0.0f64),
            |a, b| if b.1.abs() > a.1.abs() { b } else { a },
        );
    let f_max = fx.iter().map(|&(_, f)| f.abs()).fold(0.0, f64::max);
    pfem::outln!("largest top displacement {ux_max:+.4e} m at t = {t_max:.3} s; largest |force_x| {f_max:.3} N");
    output.extra.insert("ux_top_max".into(), ux_max.into());
    output.extra.insert("ux_top_max_time".into(), t_max.into());
    output.extra.insert("force_x_abs_max".into(), f_max.into());
    output.report(&sim)?;
    Ok(())
}
