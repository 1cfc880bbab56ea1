//! Water at rest in a tank with the real bulk modulus of water: the bottom
//! pressure against ρ g H, spurious velocities and volume over time.
//!
//! ```text
//! cargo run --release --example hydrostatic_2d -- --out out/hydrostatic_2d [--spacing H] [--end-time T] [--quiet] [--no-vtu]
//! ```

use pfem::cases::{Hydrostatic, G};
use pfem::cli::Args;
use pfem::prelude::*;

/// This example's own options, for `--help`.
const OPTIONS: &str = "  --restart CHECKPOINT  continue the run that wrote CHECKPOINT when it stopped (in its folder, with the same options)";

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env_with(OPTIONS)?;
    args.reject_unknown(&["restart"])?;
    let mut case = Hydrostatic::default();
    case.spacing = args.spacing.unwrap_or(case.spacing);
    case.end_time = args.end_time.unwrap_or(case.end_time);
    let out = args.out_or("out/hydrostatic_2d");
    let mut sim = args.simulation(case.scene(), Box::new(Delaunay2::default()))?;
    let mut output = StandardOutput::new(&out, !args.no_vtu, case.probes(), args.quiet)
        .overwrite(args.overwrite);
    args.restart(&mut sim, &mut output, &out)?;
    sim.run(&mut [&mut output])?;
    pfem::cli::exit_if_stopped_at(&sim, &output);
    let p = output.probe_series("bottom_pressure");
    let vmax = output
        .probe_series("max_speed")
        .iter()
        .map(|v| v.1)
        .fold(0.0, f64::max);
    let exact = 1000.0 * G * case.height;
    let p_end = p.last().map(|v| v.1).unwrap_or(f64::NAN);
    pfem::outln!(
        "bottom pressure {:.1} Pa vs rho g H = {:.1} Pa ({:+.2}%)",
        p_end,
        exact,
        100.0 * (p_end / exact - 1.0)
    );
    pfem::outln!(
        "largest fluid speed {:.2e} m/s = {:.2e} sqrt(gH)",
        vmax,
        vmax / (G * case.height).sqrt()
    );
    output.extra.insert(
        "bottom_pressure_relative_error".into(),
        (p_end / exact - 1.0).into(),
    );
    output.extra.insert(
        "max_speed_over_sqrt_gh".into(),
        (vmax / (G * case.height).sqrt()).into(),
    );
    output.report(&sim)?;
    Ok(())
}
