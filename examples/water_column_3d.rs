//! §9.1 of the paper in 3D: the collapse of a water column 0.146 m wide and
//! 0.292 m high at the back of a tank 0.584 m long (Koshizuka et al. 1995).
//! The slice's side planes are slip (symmetry) planes (`cases3d::slip_sides`):
//! it stands for the middle of the wide tank, as no-slip side walls three
//! spacings apart would brake the whole flow.
//!
//! ```text
//! cargo run --release --example water_column_3d -- --out out/water_column_3d \
//!     [--spacing H] [--end-time T] [--depth W] [--solver direct|block|cg] [--quiet] [--no-vtu]
//! ```
//! Defaults: h = 0.0146 m (a/10), depth 0.0584 m (a slice of the
//! experiment's 0.146 m), end time 1 s. Writes
//! `water_column_3d.pvd` + `.vtu` frames (tetrahedra), `probes.csv`
//! (`t, front_x, height_at_wall, volume`) and `summary.json`.

use pfem::cases3d::WaterColumn3d;
use pfem::cli::Args;
use pfem::prelude::*;

/// This example's own options, for `--help`.
const OPTIONS: &str = "  --depth W             depth of the slice (m; default 0.0584)
  --restart CHECKPOINT  continue the run that wrote CHECKPOINT when it stopped (in its folder, with the same options)";

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env_with(OPTIONS)?;
    args.reject_unknown(&["depth", "restart"])?;
    let mut case = WaterColumn3d {
        side_walls: false,
        ..Default::default()
    };
    case.spacing = args.spacing.unwrap_or(case.spacing);
    case.end_time = args.end_time.unwrap_or(case.end_time);
    case.depth = args.number("depth", case.depth)?;
    let out = args.out_or("out/water_column_3d");
    let mut sim = args.simulation(case.scene(), Box::new(Delaunay3::default()))?;
    pfem::cases3d::slip_sides(&mut sim);
    pfem::errln!(
        "water_column_3d: {} particles ({} fluid), h = {} m, depth {} m, end time {} s",
        sim.particles().len(),
        sim.particles()
            .kind()
            .iter()
            .filter(|&&k| k == pfem::core::ParticleKind::Fluid)
            .count(),
        case.spacing,
        case.depth,
        case.end_time
    );
    let mut output = StandardOutput::new(&out, !args.no_vtu, case.probes(), args.quiet)
        .overwrite(args.overwrite);
    args.restart(&mut sim, &mut output, &out)?;
    sim.run(&mut [&mut output])?;
    pfem::cli::exit_if_stopped_at(&sim, &output);
    // Surge front at the paper's snapshot times.
    let front = output.probe_series("front_x");
    // (Only those the run reached: a run to 0.1 s printed the front at
    // 0.2–0.4 s as its last value; a review of session 53.)
    for t in [0.1, 0.2, 0.3, 0.4] {
        if t > sim.time() + 1e-9 {
            break;
        }
        let x = pfem::cases::interpolate(&front, t);
        pfem::outln!(
            "t = {t:.1} s: front at x = {x:.3} m (x/a = {:.2})",
            x / case.width
        );
        output.extra.insert(format!("front_x_at_{t:.1}s"), x.into());
    }
    output.report(&sim)?;
    Ok(())
}
