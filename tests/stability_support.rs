//! Shared checks of the hard-case suite (`tests/stability_*.rs`), a module
//! of the test binary `tests/suite.rs` that each of them uses.

use pfem::core::{simplex_measure, Const, Dim, ParticleKind, Point};
use pfem::geometry::Tessellator;
use pfem::prelude::*;
use pfem::RunError;

/// Fluid volume change allowed over a hard-case run (end against start):
/// issue 5's 1 %. Measured with the volume correction: every default-scheme
/// case ends within 0.01 %.
pub const VOLUME_CHANGE_TOL: f64 = 0.01;

/// Fluid volume deviation allowed after any step of a hard-case run: 5 %,
/// the per-step bound the suite has stated since it was written (long
/// sloshing). Measured largest with the volume correction: 3.85 % (splash),
/// 2.42 % (stiffness contrast), under 1 % for the others; the stricter 1 %
/// is checked by the ignored `hard_cases_keep_fluid_volume_within_one_percent`
/// tests (known gap).
pub const VOLUME_STEP_TOL: f64 = 0.05;

/// What a run did, checked after every accepted step.
#[derive(Debug, Default, Clone)]
pub struct Watch {
    /// Kinetic + gravitational potential energy of all non-wall particles
    /// at the start (J per metre of depth in 2D, J in 3D), potential
    /// measured from the lowest non-wall particle (`y` up in 2D and 3D).
    pub e0: f64,
    /// Largest energy seen.
    pub e_max: f64,
    /// Energy at the end.
    pub e_end: f64,
    /// Fluid volume at the start.
    pub v0: f64,
    /// Largest relative fluid-volume deviation from `v0`.
    pub dv_max: f64,
    /// Relative fluid-volume change at the end.
    pub dv_end: f64,
    /// Elements (fluid or solid) with a non-positive signed measure after a
    /// step, summed over steps, other than those kept in their
    /// start-of-step shape (slivers, deviation 13).
    pub inverted: usize,
    /// Elements kept in their start-of-step shape that ended a step with a
    /// non-positive measure, summed over steps (reported, allowed: the
    /// next remeshing replaces them).
    pub inverted_kept: usize,
    /// First step with an inverted element.
    pub first_inverted: Option<u64>,
    /// Steps with a non-finite position, velocity or pressure.
    pub non_finite: usize,
    /// Steps observed.
    pub steps: u64,
    /// Time (s) and step at which the energy was largest.
    pub at_e_max: (f64, u64),
    /// Largest non-wall particle speed seen (m/s) and its time (s).
    pub v_max: (f64, f64),
    /// Largest Courant number an accepted step took, as the controller
    /// reckons it: its `Δt` over the crossing time `minᵢ hᵢ/|vᵢ|` at its
    /// start ([`Simulation::crossing_time`]).
    pub courant_max: f64,
    crossing: f64,
    /// Largest accepted step (s).
    pub dt_max: f64,
    mass: Vec<f64>,
    y_ref: f64,
}

/// The solver's lumped masses of the solid particles (kg; kg/m in 2D):
/// each solid element gives `ρ V₀ / (D + 1)` to its nodes, `V₀` its initial
/// volume (eq. 46); `rho` the solids' density. Zero elsewhere.
pub fn solid_masses<const D: usize>(sim: &Simulation<D>, rho: f64) -> Vec<f64>
where
    Const<D>: Dim,
{
    let el = sim.elements();
    let mut mass = vec![0.0; sim.particles().len()];
    for (e, &v0) in el.solid().chunks_exact(D + 1).zip(el.reference_volumes()) {
        for &i in e {
            mass[i as usize] += rho * v0 / (D + 1) as f64;
        }
    }
    mass
}

/// Mass per particle: `ρ h^D` of its body (kg per metre of depth in 2D);
/// zero for walls.
fn masses<const D: usize>(sim: &Simulation<D>) -> Vec<f64>
where
    Const<D>: Dim,
{
    (0..sim.particles().len())
        .map(|i| {
            if sim.particles().kind()[i] == ParticleKind::Wall {
                0.0
            } else {
                let rho = sim.materials()[sim.particles().material()[i] as usize].density();
                rho * sim.particles().spacing()[i].powi(D as i32)
            }
        })
        .collect()
}

impl Watch {
    /// Kinetic + potential energy of the non-wall particles (gravity along
    /// `−y`, as every scene of the suite has it).
    pub fn energy<const D: usize>(&self, sim: &Simulation<D>) -> f64
    where
        Const<D>: Dim,
    {
        let g = sim.gravity().map_or(0.0, |g| -g[1]);
        (0..sim.particles().len())
            .map(|i| {
                let m = self.mass[i];
                m * (0.5 * sim.particles().v()[i].norm_squared()
                    + g * (sim.particles().x()[i][1] - self.y_ref))
            })
            .sum()
    }

    fn check<const D: usize>(&mut self, sim: &Simulation<D>)
    where
        Const<D>: Dim,
    {
        let e = self.energy(sim);
        if e > self.e_max {
            self.e_max = e;
            self.at_e_max = (sim.time(), sim.steps());
        }
        for i in 0..sim.particles().len() {
            let v = sim.particles().v()[i].norm();
            if self.mass[i] > 0.0 && v > self.v_max.0 {
                self.v_max = (v, sim.time());
            }
        }
        if sim.steps() > 0 {
            if self.crossing > 0.0 && self.crossing.is_finite() {
                self.courant_max = self.courant_max.max(sim.dt() / self.crossing);
            }
            self.dt_max = self.dt_max.max(sim.dt());
        }
        self.crossing = sim.crossing_time();
        self.e_end = e;
        if self.v0 > 0.0 {
            let dv = (sim.fluid_volume() - self.v0) / self.v0;
            self.dv_max = self.dv_max.max(dv.abs());
            self.dv_end = dv;
        }
        let (bad, kept) = inverted_elements(sim);
        if bad > 0 && self.first_inverted.is_none() {
            self.first_inverted = Some(sim.steps());
        }
        self.inverted += bad;
        self.inverted_kept += kept;
        let finite = sim
            .particles()
            .x()
            .iter()
            .all(|p| p.iter().all(|v| v.is_finite()))
            && sim
                .particles()
                .v()
                .iter()
                .all(|p| p.iter().all(|v| v.is_finite()))
            && sim.particles().pressure().iter().all(|p| p.is_finite());
        if !finite || !e.is_finite() {
            self.non_finite += 1;
        }
        self.steps = sim.steps();
    }

    /// Relative energy growth over the start: `(e_max − e0) / e0`.
    pub fn energy_growth(&self) -> f64 {
        (self.e_max - self.e0) / self.e0
    }
}

impl<const D: usize> Observer<D> for Watch
where
    Const<D>: Dim,
{
    fn start(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        self.mass = masses(sim);
        self.y_ref = (0..sim.particles().len())
            .filter(|&i| sim.particles().kind()[i] != ParticleKind::Wall)
            .map(|i| sim.particles().x()[i][1])
            .fold(f64::INFINITY, f64::min);
        self.e0 = self.energy(sim);
        self.e_max = self.e0;
        self.v0 = sim.fluid_volume();
        self.check(sim);
        Ok(())
    }
    fn step(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        self.check(sim);
        Ok(())
    }
}

/// Fluid and solid elements whose signed measure at the current positions is
/// not positive, counted as (those the step integrated on their current
/// shape, which the integrator must never accept inverted; those it kept
/// in their start-of-step shape, slivers and elements foreseen flat, which
/// may end the step inverted and which the next remeshing replaces,
/// ARCHITECTURE.md deviation 13).
pub fn inverted_elements<const D: usize>(sim: &Simulation<D>) -> (usize, usize)
where
    Const<D>: Dim,
{
    let measure = |el: &[u32]| {
        let mut p = [Point::<D>::zeros(); pfem::core::MAX_NV];
        for (p, &n) in p.iter_mut().zip(el) {
            *p = sim.particles().x()[n as usize];
        }
        simplex_measure::<D>(&p[..el.len()])
    };
    let mut count = (0, 0);
    for (e, el) in sim.elements().all().chunks_exact(D + 1).enumerate() {
        if measure(el).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            if sim.kept_in_shape(e) {
                count.1 += 1;
            } else {
                count.0 += 1;
            }
        }
    }
    count
}

/// How a run ended.
#[derive(Debug)]
pub struct Outcome {
    /// The run's checks.
    pub watch: Watch,
    /// `Ok` or the typed error it stopped with.
    pub result: Result<(), RunError>,
    /// Simulated time reached (s).
    pub time: f64,
    /// End time asked for (s).
    pub end_time: f64,
    /// Accepted and rejected steps.
    pub steps: u64,
    /// Rejected attempts.
    pub rejected: u64,
    /// Wall time (s).
    pub wall: f64,
}

impl Outcome {
    /// One line for the test log.
    pub fn report(&self, name: &str) {
        eprintln!(
            "{name}: {} at t = {:.4} s of {:.4} s, {} steps ({} rejected), energy {:.4e} -> max {:.4e} ({:+.2}%), end {:.4e}; fluid volume max |dV|/V {:.2}%, end {:+.2}%; inverted {} (first at step {:?}), kept-in-shape slivers ending inverted {}; non-finite steps {}; energy largest at t = {:.4} s (step {}); fastest particle {:.2} m/s at t = {:.4} s; largest step {:.2e} s, largest Courant number {:.2}; wall {:.1} s",
            match &self.result {
                Ok(()) => "ok".to_string(),
                Err(e) => format!("error `{e}`"),
            },
            self.time,
            self.end_time,
            self.steps,
            self.rejected,
            self.watch.e0,
            self.watch.e_max,
            100.0 * self.watch.energy_growth(),
            self.watch.e_end,
            100.0 * self.watch.dv_max,
            100.0 * self.watch.dv_end,
            self.watch.inverted,
            self.watch.first_inverted,
            self.watch.inverted_kept,
            self.watch.non_finite,
            self.watch.at_e_max.0,
            self.watch.at_e_max.1,
            self.watch.v_max.0,
            self.watch.v_max.1,
            self.watch.dt_max,
            self.watch.courant_max,
            self.wall
        );
    }

    /// The common assertions: the run reached its end time with no error
    /// ([`Outcome::assert_completed`]); no NaN; no inverted element after
    /// any step (but the slivers kept in their start-of-step shape,
    /// deviation 13); energy never above `e0 (1 + energy_tol)`. (Until
    /// session 42 a typed error passed here, so a run stopped at its first
    /// step passed every check: its energy and volume had not moved.)
    pub fn assert_stable(&self, energy_tol: f64) {
        self.assert_completed();
        assert_eq!(self.watch.non_finite, 0, "non-finite state");
        assert_eq!(
            self.watch.inverted, 0,
            "inverted elements after a step (first at step {:?})",
            self.watch.first_inverted
        );
        assert!(
            self.watch.energy_growth() <= energy_tol,
            "energy grew by {:.2}% (> {:.2}%): {:e} -> {:e}",
            100.0 * self.watch.energy_growth(),
            100.0 * energy_tol,
            self.watch.e0,
            self.watch.e_max
        );
    }

    /// The run reached its end time with no typed error.
    pub fn assert_completed(&self) {
        assert!(
            self.result.is_ok() && self.time >= self.end_time - 1e-9,
            "the run stopped at t = {} s of {} s: {:?}",
            self.time,
            self.end_time,
            self.result
        );
    }

    /// The fluid volume changed by at most `tol` (relative) over the run,
    /// end against start: issue 5's measure ("fluid volume change over
    /// each run below 1 %"). The per-step bound is [`Outcome::assert_volume`].
    pub fn assert_volume_change(&self, tol: f64) {
        assert!(
            self.watch.dv_end.abs() <= tol,
            "fluid volume changed by {:.2}% over the run (> {:.2}%)",
            100.0 * self.watch.dv_end,
            100.0 * tol
        );
    }

    /// The fluid volume stayed within `tol` (relative) at every step.
    pub fn assert_volume(&self, tol: f64) {
        assert!(
            self.watch.dv_max <= tol,
            "fluid volume deviated by {:.2}% (> {:.2}%)",
            100.0 * self.watch.dv_max,
            100.0 * tol
        );
    }
}

/// Builds and runs a 2D scene with the checks; `Simulation::new` must
/// succeed.
pub fn run_checked(scene: Scene<2>, params: StepParams) -> Outcome {
    run_checked_with(scene, Box::new(Delaunay2::default()), params)
}

/// Builds and runs a 3D scene with the checks; `Simulation::new` must
/// succeed.
pub fn run_checked_3d(scene: Scene<3>, params: StepParams) -> Outcome {
    run_checked_with(scene, Box::new(Delaunay3::default()), params)
}

/// Builds a scene with `tessellator` and runs it with the checks.
pub fn run_checked_with<const D: usize>(
    scene: Scene<D>,
    tessellator: Box<dyn Tessellator<D>>,
    params: StepParams,
) -> Outcome
where
    Const<D>: Dim,
{
    let end_time = scene.settings.end_time;
    let mut sim = Simulation::new(scene, tessellator, params).expect("scene builds");
    run_sim(&mut sim, end_time)
}

/// Runs a built simulation with the checks.
pub fn run_sim<const D: usize>(sim: &mut Simulation<D>, end_time: f64) -> Outcome
where
    Const<D>: Dim,
{
    run_sim_with(sim, end_time, None)
}

/// Calls its closure after the start and after every accepted step: a
/// case's own measurements beside the common checks.
pub struct Track<'a, const D: usize>(pub Box<dyn FnMut(&Simulation<D>) + 'a>)
where
    Const<D>: Dim;

impl<const D: usize> Observer<D> for Track<'_, D>
where
    Const<D>: Dim,
{
    fn start(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        (self.0)(sim);
        Ok(())
    }
    fn step(&mut self, sim: &Simulation<D>) -> Result<(), RunError> {
        (self.0)(sim);
        Ok(())
    }
}

/// [`run_sim`] with one more observer after the checks.
pub fn run_sim_with<const D: usize>(
    sim: &mut Simulation<D>,
    end_time: f64,
    more: Option<&mut dyn Observer<D>>,
) -> Outcome
where
    Const<D>: Dim,
{
    let mut watch = Watch::default();
    let t0 = std::time::Instant::now();
    let result = match more {
        Some(more) => sim.run(&mut [&mut watch, more]),
        None => sim.run(&mut [&mut watch]),
    };
    Outcome {
        watch,
        result,
        time: sim.time(),
        end_time,
        steps: sim.steps(),
        rejected: sim.rejected(),
        wall: t0.elapsed().as_secs_f64(),
    }
}

/// A tank: floor from `x0` to `x1` (two layers below `y = 0`) and walls at
/// `x0` (left) and `x1` (right) up to `top`, spacing `h`.
pub fn tank(scene: Scene<2>, x0: f64, x1: f64, top: f64, h: f64) -> Scene<2> {
    use pfem::scene::{Geometry, WallMotion};
    scene
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(x0 - h, -h),
                max: Point::<2>::new(x1 + h, 0.0),
            },
            h,
            WallMotion::Fixed,
        )
        .wall(
            "left",
            Geometry::Box {
                min: Point::<2>::new(x0 - h, h),
                max: Point::<2>::new(x0, top),
            },
            h,
            WallMotion::Fixed,
        )
        .wall(
            "right",
            Geometry::Box {
                min: Point::<2>::new(x1, h),
                max: Point::<2>::new(x1 + h, top),
            },
            h,
            WallMotion::Fixed,
        )
}

/// Settings with no output.
pub fn settings(end_time: f64, max_dt: f64, courant: f64) -> RunSettings {
    RunSettings {
        end_time,
        max_dt,
        courant,
        output_interval: None,
        alpha: 1.3,
    }
}

/// A box geometry.
pub fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Geometry<2> {
    Geometry::Box {
        min: Point::<2>::new(x0, y0),
        max: Point::<2>::new(x1, y1),
    }
}

/// Gravity (0, −9.81).
pub fn g() -> Vector<2> {
    Vector::<2>::new(0.0, -9.81)
}

impl Outcome {
    /// No non-wall particle faster than `limit` (m/s) at the end of any
    /// step: the splashes' free-fall bound `2 √(2 g H)`, `H` the water's
    /// highest start above its lowest (the undamped trapezoidal rule's
    /// splash reached 14 m/s against about 3).
    pub fn assert_speed(&self, limit: f64) {
        assert!(
            self.watch.v_max.0 <= limit,
            "a particle reached {:.2} m/s at t = {:.3} s (limit {limit:.2} m/s)",
            self.watch.v_max.0,
            self.watch.v_max.1
        );
    }
}

/// A fixed pseudo-random offset in `[−1, 1]` for coordinate `k` of
/// particle `i` (a hash: the same every run).
pub fn jitter(i: usize, k: usize) -> f64 {
    // (Wrapping: a debug build checks overflow.)
    let mut z = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (k as u64 + 1).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z ^= z >> 31;
    z = z.wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 29;
    2.0 * (z >> 11) as f64 / (1u64 << 53) as f64 - 1.0
}

/// Twice the free fall from `height` (m) under 9.81 m/s², `2 √(2 g H)`:
/// the splashes' speed bound (m/s).
pub fn free_fall_bound(height: f64) -> f64 {
    2.0 * (2.0 * 9.81 * height).sqrt()
}

/// Fluid particles of the set.
pub fn fluid_count<const D: usize>(sim: &Simulation<D>) -> usize
where
    Const<D>: Dim,
{
    sim.particles()
        .kind()
        .iter()
        .filter(|&&k| k == ParticleKind::Fluid)
        .count()
}
