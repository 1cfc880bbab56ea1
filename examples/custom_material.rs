//! A user-defined material plugged into a scene: a regularised Bingham
//! (Papanastasiou) fluid — mud — written only against the public
//! `Material` trait, collapsing as a column on a floor.
//!
//! ```text
//! cargo run --release --example custom_material -- --out out/custom_material [--spacing H] [--end-time T] [--quiet] [--no-vtu]
//! ```

use pfem::cases::front_x;
use pfem::cli::Args;
use pfem::constitutive::{History, Kinematics, MaterialKind, Unified};
use pfem::core::{Const, Dim, Tensor};
use pfem::prelude::*;

/// Papanastasiou-regularised Bingham fluid.
#[derive(Debug, Clone, Copy)]
pub struct Bingham {
    /// Density ρ (kg/m³).
    density: f64,
    /// Plastic viscosity μ_p (Pa·s).
    plastic_viscosity: f64,
    /// Yield stress τ_y (Pa).
    yield_stress: f64,
    /// Regularisation exponent m (s).
    m: f64,
    /// Bulk modulus K (Pa).
    bulk_modulus: f64,
}

impl Bingham {
    /// Equivalent shear rate `γ̇ = √(2 D' : D')`.
    fn shear_rate<const D: usize>(kin: &Kinematics<D>) -> f64
    where
        Const<D>: Dim,
    {
        let dev = kin.deviatoric_rate();
        let zz = kin.deviatoric_rate_zz();
        (2.0 * (dev.norm_squared() + zz * zz)).sqrt()
    }

    /// `μ_eff = μ_p + τ_y (1 − e^{−m γ̇}) / γ̇`, and `μ_p + m τ_y` at `γ̇ = 0`.
    fn effective_viscosity(&self, gamma_dot: f64) -> f64 {
        let x = self.m * gamma_dot;
        let factor = if x < 1e-12 {
            self.m
        } else {
            -(-x).exp_m1() / gamma_dot
        };
        self.plastic_viscosity + self.yield_stress * factor
    }
}

impl<const D: usize> Material<D> for Bingham
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "Papanastasiou Bingham fluid"
    }

    fn kind(&self) -> MaterialKind {
        MaterialKind::Fluid
    }

    fn density(&self) -> f64 {
        self.density
    }

    fn wave_speed(&self) -> f64 {
        (self.bulk_modulus / self.density).sqrt()
    }

    fn unified(&self, kin: &Kinematics<D>, _history: &History<D>) -> Unified<D> {
        // A fluid's pressure is nodal (eq. 62): the assembly adds it, so a
        // fluid element's `σ̂` is not used (the history it is given holds
        // its nodes' mean pressure, which this law does not need:
        // `Material::unified`).
        Unified::new(
            self.effective_viscosity(Self::shear_rate(kin)),
            kin.dt * self.bulk_modulus,
            Tensor::<D>::zeros(),
            0.0,
        )
    }

    fn update_history(&self, kin: &Kinematics<D>, history: &mut History<D>) {
        // The nodal pressure's update with only tr D, as for any fluid
        // (eqs. 26, 62): the default `Material::update_pressure` calls this
        // with the node's pressure and volumetric rate.
        history.pressure -= kin.dt * self.bulk_modulus * kin.volumetric_rate();
    }
}

fn mud() -> Bingham {
    Bingham {
        density: 1800.0,
        plastic_viscosity: 0.5,
        yield_stress: 40.0,
        m: 1000.0,
        bulk_modulus: 1.0e8,
    }
}

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
    let h = args.spacing.unwrap_or(0.005);
    let end_time = args.end_time.unwrap_or(0.3);
    let out = args.out_or("out/custom_material");
    let scene = Scene::<2>::new("custom_material")
        .gravity(Vector::<2>::new(0.0, -9.81))
        .settings(RunSettings {
            end_time,
            max_dt: 2e-3,
            output_interval: Some(end_time / 30.0),
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-h, -h),
                max: Point::<2>::new(0.4, 0.0),
            },
            h,
            WallMotion::Fixed,
        )
        .wall(
            "back",
            Geometry::Box {
                min: Point::<2>::new(-h, h),
                max: Point::<2>::new(0.0, 0.15),
            },
            h,
            WallMotion::Fixed,
        )
        .fluid(
            "mud",
            Box::new(mud()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(0.05, 0.1),
            },
            h,
        );
    let mut sim = args.simulation(scene, Box::new(Delaunay2::default()))?;
    let probes = vec![
        Probe::new("front_x", front_x),
        Probe::new("volume", |s: &Simulation<2>| s.fluid_volume()),
    ];
    let mut output =
        StandardOutput::new(&out, !args.no_vtu, probes, args.quiet).overwrite(args.overwrite);
    args.restart(&mut sim, &mut output, &out)?;
    sim.run(&mut [&mut output])?;
    pfem::cli::exit_if_stopped_at(&sim, &output);
    let front = output.probe_series("front_x");
    pfem::outln!(
        "Bingham mud column: front {:.4} m -> {:.4} m after {} s",
        front[0].1,
        front.last().map(|f| f.1).unwrap_or(f64::NAN),
        sim.time()
    );
    Ok(())
}
