//! A user's extension of pfem, written only against its public traits:
//!
//! - [`J2Plastic`], an elastoplastic solid (von Mises yield, linear
//!   isotropic hardening) that keeps its equivalent plastic strain as an
//!   internal variable of [`pfem::constitutive::History`];
//! - [`PlasticityMonitor`], a hook that reads that internal variable after
//!   every step, records its largest value and stops the run past a limit.

use pfem::constitutive::{
    History, Hypoelastic, Kinematics, Material, MaterialError, MaterialKind, Unified,
};
use pfem::core::{Const, Dim, Tensor};
use pfem::hooks::BodyForceRamp;
use pfem::hooks::{Hook, HookContext};
use pfem::prelude::*;
use pfem::RunError;
use std::sync::{Arc, Mutex};

/// Index of the equivalent plastic strain in [`History::internal`].
pub const PLASTIC_STRAIN: usize = 0;

/// Why a [`J2Plastic`] could not be made.
#[derive(Debug, Clone, PartialEq)]
pub enum J2Error {
    /// The elastic constants are invalid.
    Elastic(MaterialError),
    /// The yield stress must be positive and finite.
    YieldStress(f64),
    /// The hardening modulus must be non-negative and finite.
    Hardening(f64),
}

impl std::fmt::Display for J2Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            J2Error::Elastic(e) => write!(f, "{e}"),
            J2Error::YieldStress(v) => write!(f, "yield stress {v} Pa must be positive and finite"),
            J2Error::Hardening(v) => write!(f, "hardening modulus {v} Pa must be ≥ 0 and finite"),
        }
    }
}

impl std::error::Error for J2Error {}

impl From<MaterialError> for J2Error {
    fn from(e: MaterialError) -> Self {
        J2Error::Elastic(e)
    }
}

/// A hypoelastic–plastic solid: von Mises yield `q = σ_y + H ε̄ᵖ` with
/// linear isotropic hardening, radial return on the elastic trial stress of
/// each step.
///
/// The trial stress is the stress at `t_n` rotated by the step's rotation
/// `R = V⁻¹ F` plus Hooke's law on the step's logarithmic strain increment
/// (`Kinematics::strain_increment`), scaled by nothing else: a Hencky-type
/// hypoelastic law, so that under rotation-free loading (uniaxial stress,
/// pure shear) the response is the small-strain closed form in logarithmic
/// strain and Cauchy stress. The unified triple (eq. 44) uses the elastic
/// moduli (an initial-stiffness Picard iteration: linear convergence once
/// yielding, slower as the hardening goes to zero) with `σ̂` chosen so that eq. 43
/// returns the returned stress exactly at every iterate. 2D is plane strain
/// (the out-of-plane stress takes part in the yield function).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct J2Plastic {
    elastic: Hypoelastic,
    /// Initial yield stress `σ_y` (Pa).
    pub yield_stress: f64,
    /// Hardening modulus `H` (Pa).
    pub hardening: f64,
}

impl J2Plastic {
    /// A J2 solid of density `ρ` (kg/m³), Young's modulus `E` (Pa),
    /// Poisson's ratio `ν`, yield stress `σ_y` (Pa) and hardening modulus
    /// `H` (Pa, ≥ 0).
    pub fn new(
        density: f64,
        young: f64,
        poisson: f64,
        yield_stress: f64,
        hardening: f64,
    ) -> Result<Self, J2Error> {
        let elastic = Hypoelastic::new(density, young, poisson)?;
        if !(yield_stress > 0.0 && yield_stress.is_finite()) {
            return Err(J2Error::YieldStress(yield_stress));
        }
        if !(hardening >= 0.0 && hardening.is_finite()) {
            return Err(J2Error::Hardening(hardening));
        }
        Ok(Self {
            elastic,
            yield_stress,
            hardening,
        })
    }

    /// Shear modulus `G` (Pa).
    pub fn shear_modulus(&self) -> f64 {
        self.elastic.shear_modulus()
    }

    /// The stress at the end of the step and the new equivalent plastic
    /// strain: `(σ, σ_zz, ε̄ᵖ)`.
    pub fn stress_after<const D: usize>(
        &self,
        kin: &Kinematics<D>,
        history: &History<D>,
    ) -> (Tensor<D>, f64, f64)
    where
        Const<D>: Dim,
    {
        let g = self.elastic.shear_modulus();
        let lambda = self.elastic.lame_lambda();
        let de = kin.strain_increment();
        // The step's rotation R = V⁻¹ F.
        let r = kin
            .left_stretch()
            .try_inverse()
            .map_or(Tensor::<D>::identity(), |vi| vi * kin.f);
        let tr = de.trace();
        let trial = r * history.stress * r.transpose()
            + Tensor::<D>::identity() * (lambda * tr)
            + de * (2.0 * g);
        let trial = (trial + trial.transpose()) * 0.5;
        let trial_zz = if D == 2 {
            history.stress_zz + lambda * tr
        } else {
            0.0
        };
        // Deviator with the out-of-plane component in 2D (plane strain).
        let p = (trial.trace() + trial_zz) / 3.0;
        let s = trial - Tensor::<D>::identity() * p;
        let s_zz = if D == 2 { trial_zz - p } else { 0.0 };
        let q = (1.5 * (s.norm_squared() + s_zz * s_zz)).sqrt();
        let ep = history.internal[PLASTIC_STRAIN];
        let f = q - (self.yield_stress + self.hardening * ep);
        if f <= 0.0 || q == 0.0 {
            return (trial, trial_zz, ep);
        }
        // Radial return: Δγ = f / (3G + H).
        let dgamma = f / (3.0 * g + self.hardening);
        let scale = 1.0 - 3.0 * g * dgamma / q;
        let sigma = s * scale + Tensor::<D>::identity() * p;
        let sigma_zz = if D == 2 { s_zz * scale + p } else { 0.0 };
        (sigma, sigma_zz, ep + dgamma)
    }
}

impl<const D: usize> Material<D> for J2Plastic
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "J2 elastoplastic"
    }

    fn kind(&self) -> MaterialKind {
        MaterialKind::Solid
    }

    fn density(&self) -> f64 {
        self.elastic.density()
    }

    fn wave_speed(&self) -> f64 {
        self.elastic.wave_speed()
    }

    fn internal_variables(&self) -> &[&str] {
        &["equivalent_plastic_strain"]
    }

    // What identifies this material in a checkpoint beside its answers to
    // fixed probes (which a yield stress above their stress would not
    // change): a restart under another yield stress is refused.
    fn parameters(&self) -> Vec<f64> {
        vec![self.yield_stress, self.hardening]
    }

    fn unified(&self, kin: &Kinematics<D>, history: &History<D>) -> Unified<D> {
        let w_over_j = kin.displacement_weight / kin.j;
        let g = self.elastic.shear_modulus();
        let mu = g * w_over_j;
        let kappa = (self.elastic.lame_lambda() + 2.0 / 3.0 * g) * w_over_j;
        let (sigma, sigma_zz, _) = self.stress_after(kin, history);
        Unified::returning(mu, kappa, sigma, sigma_zz, kin)
    }

    fn update_history(&self, kin: &Kinematics<D>, history: &mut History<D>) {
        let (sigma, sigma_zz, ep) = self.stress_after(kin, history);
        history.stress = sigma;
        history.stress_zz = sigma_zz;
        history.internal[PLASTIC_STRAIN] = ep;
    }
}

/// What a [`PlasticityMonitor`] recorded.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlasticityRecord {
    /// Largest equivalent plastic strain seen.
    pub largest: f64,
    /// Yielded elements at the last step.
    pub yielded: usize,
    /// `(time, largest now)` after every step.
    pub history: Vec<(f64, f64)>,
}

/// A hook that watches the equivalent plastic strain of every solid
/// element after each step: it records the largest value, and stops the
/// run once it exceeds `limit`. The record is shared
/// ([`PlasticityMonitor::record`]) so the caller can read it after the
/// simulation took the hook.
#[derive(Debug, Clone)]
pub struct PlasticityMonitor {
    /// Stop past this equivalent plastic strain.
    pub limit: f64,
    record: Arc<Mutex<PlasticityRecord>>,
}

impl PlasticityMonitor {
    /// A monitor that stops the run past `limit`.
    pub fn new(limit: f64) -> Self {
        Self {
            limit,
            record: Arc::default(),
        }
    }

    /// A handle on the record.
    pub fn record(&self) -> Arc<Mutex<PlasticityRecord>> {
        self.record.clone()
    }
}

impl<const D: usize> Hook<D> for PlasticityMonitor
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "plasticity monitor"
    }

    fn after_step(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let h = ctx.elements().solid_history();
        let now = h
            .iter()
            .map(|h| h.internal[PLASTIC_STRAIN])
            .fold(0.0, f64::max);
        {
            let mut r = self.record.lock().map_err(|_| RunError::Hook {
                hook: "plasticity monitor".into(),
                why: "the record's lock is poisoned".into(),
            })?;
            r.yielded = h
                .iter()
                .filter(|h| h.internal[PLASTIC_STRAIN] > 0.0)
                .count();
            r.largest = r.largest.max(now);
            r.history.push((ctx.time(), now));
        }
        if now > self.limit {
            ctx.stop(format!(
                "equivalent plastic strain {now:.3e} passed {:.3e}",
                self.limit
            ));
        }
        Ok(())
    }

    // A hook that keeps a record saves it in checkpoints, so that a
    // restarted run goes on with it (its name finds its state again).
    fn save_state(&self, out: &mut pfem::checkpoint::Encoder) {
        if let Ok(r) = self.record.lock() {
            out.f64(r.largest);
            out.u64(r.yielded as u64);
            out.u64(r.history.len() as u64);
            for &(t, v) in &r.history {
                out.f64(t);
                out.f64(v);
            }
        }
    }

    fn restore_state(
        &mut self,
        from: &mut pfem::checkpoint::Decoder<'_>,
    ) -> Result<(), pfem::checkpoint::CheckpointError> {
        let largest = from.f64()?;
        let yielded = from.len(0)?;
        let n = from.len(16)?;
        let mut history = Vec::with_capacity(n);
        for _ in 0..n {
            history.push((from.f64()?, from.f64()?));
        }
        let mut r = self.record.lock().map_err(|_| {
            pfem::checkpoint::CheckpointError::Corrupt("the record's lock is poisoned".into())
        })?;
        *r = PlasticityRecord {
            largest,
            yielded,
            history,
        };
        Ok(())
    }
}

/// Tip deflection (m) of a clamped 0.35 m × 0.02 m cantilever under a
/// body force ramped to 2 m/s² downwards over 10 s (quasi-static), with
/// `material`; and the simulation.
pub fn cantilever(
    material: Box<dyn Material<2>>,
    monitor: Option<PlasticityMonitor>,
) -> Result<(f64, Simulation<2>), Box<dyn std::error::Error>> {
    let (l, t) = (0.35, 0.02);
    let scene = Scene::<2>::new("cantilever")
        .settings(RunSettings {
            end_time: 20.0,
            max_dt: 0.5,
            output_interval: None,
            ..Default::default()
        })
        .solid(
            "beam",
            material,
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(l, t),
            },
            t / 4.0,
            Some((Point::<2>::new(-1.0, -1.0), Point::<2>::new(1e-9, 1.0))),
        );
    let params = StepParams {
        scheme: Scheme::BackwardEuler,
        ..StepParams::default()
    };
    let mut sim = Simulation::new(scene, Box::new(Delaunay2::default()), params)?;
    sim.add_hook(Box::new(BodyForceRamp {
        target: Vector::<2>::new(0.0, -2.0),
        duration: 10.0,
    }));
    if let Some(m) = monitor {
        sim.add_hook(Box::new(m));
    }
    sim.run(&mut [])?;
    let p = sim.particles();
    let tip = (0..p.len())
        .filter(|&i| (sim.initial_position(i).x - l).abs() < 1e-9)
        .map(|i| p.x()[i].y - sim.initial_position(i).y)
        .sum::<f64>()
        / 5.0;
    Ok((tip, sim))
}
