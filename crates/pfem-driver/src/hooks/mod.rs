//! Hooks: code that may change a simulation at defined points of a step.
//!
//! A [`Hook`] is called with a narrow mutable [`HookContext`] at three
//! points of every step (see `ARCHITECTURE.md`, "One time step"):
//!
//! 1. [`Hook::after_remesh`]: the step's mesh is made, `Δt` is not chosen.
//!    Move particles, change pressures, remove or insert particles (the
//!    driver remeshes again at once when a hook changes the particle set).
//! 2. [`Hook::before_solve`]: `Δt` is chosen ([`HookContext::dt`]). Set the
//!    boundary conditions and body force for `[t, t + Δt]`.
//! 3. [`Hook::after_step`]: the step is accepted. Correct positions, record,
//!    ask the run to stop ([`HookContext::stop`]).
//!
//! What a hook does to the fluid volume is measured by the driver and
//! booked in the [`VolumeLedger`](crate::VolumeLedger) under the hook's
//! [`Hook::name`]. Hooks run in the order they were added; the driver adds
//! its own first: [`Domain`] (a scene's domain box), those of its options
//! ([`crate::Options`]), then those of the scene's motion laws and forces.
//!
//! Here: the driver's own [`Domain`], [`VolumeCorrection`] and
//! [`FreeSurfacePressureZero`], [`PrescribedMotion`] (a wall along a motion
//! law of `pfem_scene::motion`), [`AppliedForce`], [`StopWhen`],
//! [`WallClockLimit`], [`Interrupt`] and [`FnHook`] (a hook from closures).
//! Load ramps, slip planes, inflows and particle management are in the
//! `pfem-hooks` crate (`pfem::hooks` re-exports both).
//!
//! ```
//! use pfem_constitutive::Newtonian;
//! use pfem_core::{Point, Vector};
//! use pfem_driver::hooks::{Hook, HookContext};
//! use pfem_driver::{RunError, Simulation};
//! use pfem_geometry::Delaunay2;
//! use pfem_scene::{Geometry, RunSettings, Scene, WallMotion};
//! use pfem_time::StepParams;
//!
//! /// Stops the run when the water's fastest particle exceeds 1 m/s.
//! struct SpeedLimit;
//! impl Hook<2> for SpeedLimit {
//!     fn name(&self) -> &str { "speed limit" }
//!     fn after_step(&mut self, ctx: &mut HookContext<'_, 2>) -> Result<(), RunError> {
//!         if ctx.particles().v().iter().any(|v| v.norm() > 1.0) {
//!             ctx.stop("a particle exceeded 1 m/s");
//!         }
//!         Ok(())
//!     }
//! }
//! # let h = 0.05;
//! # let scene = Scene::<2>::new("drop")
//! #     .gravity(Vector::<2>::new(0.0, -9.81))
//! #     .settings(RunSettings { end_time: 1.0, max_dt: 5e-3, output_interval: None, ..Default::default() })
//! #     .wall("floor", Geometry::Box { min: Point::<2>::new(-0.1, -h), max: Point::<2>::new(0.3, 0.0) }, h, WallMotion::Fixed)
//! #     .fluid("water", Box::new(Newtonian::water()), Geometry::Box { min: Point::<2>::new(0.0, 0.3), max: Point::<2>::new(0.1, 0.4) }, h);
//! let mut sim = Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default())?;
//! sim.add_hook(Box::new(SpeedLimit));
//! sim.run(&mut [])?;
//! assert!(sim.stopped().is_some());
//! assert!(sim.time() < 0.2); // free fall reaches 1 m/s at 0.10 s
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod domain;
mod force;
mod management;
mod motion;
mod volume;

pub use domain::Domain;
pub use force::AppliedForce;
pub use management::ParticleManagement;
pub use motion::PrescribedMotion;
pub use pfem_scene::motion::{MotionLaw, PiecewiseLinear, Rotation, Sinusoidal};
pub use volume::{FreeSurfacePressureZero, VolumeCorrection};

use pfem_assembly::Constraints;
use pfem_constitutive::Material;
use pfem_core::{Const, Dim, Point, Vector};
use pfem_geometry::{AlphaShapeParams, ParticleManagementParams, Tessellation, Tessellator};

use crate::checkpoint::{CheckpointError, Decoder, Encoder};
use crate::elements::Elements;
use crate::particles::{Particle, Particles};
use crate::RunError;

/// Code called at defined points of every step with a narrow mutable view
/// of the simulation. Object safe; every method but [`Hook::name`] does
/// nothing by default; `()` is the hook that does nothing.
pub trait Hook<const D: usize>: Send
where
    Const<D>: Dim,
{
    /// Name, for the volume ledger and messages. It is also the key that
    /// gives a hook its saved state on [`crate::Simulation::restore`] (the
    /// k-th hook of a name takes the k-th saved state of that name): keep
    /// it stable from run to run, and distinct between hooks that keep
    /// state.
    fn name(&self) -> &str;

    /// Whether the fluid volume this hook's changes add or remove is fluid
    /// entering or leaving the domain (an inflow, an outflow), which the
    /// volume correction must keep, rather than an error it must undo
    /// (particle management, moved walls). Default false. The driver books
    /// such changes in [`crate::VolumeLedger::sources`] too.
    fn sources_fluid(&self) -> bool {
        false
    }

    /// The body whose motion this hook prescribes (a wall's motion law,
    /// [`PrescribedMotion`]), if any. Two hooks that drive one body are
    /// refused when the run starts: each would prescribe its own velocity
    /// and reset the positions to its own path, and the later one alone
    /// moved the wall (a scene's law and an added one, session 53's
    /// review). Default `None`.
    fn drives_body(&self) -> Option<&str> {
        None
    }

    /// The first time after `t` at which what the hook prescribes jumps
    /// (a motion law's kink, [`MotionLaw::next_kink`]): the driver ends a
    /// step there, as at the end time. Default `None`.
    fn next_kink(&self, t: f64) -> Option<f64> {
        let _ = t;
        None
    }

    /// Once, before the first step (the initial mesh and state are there).
    fn start(&mut self, _ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        Ok(())
    }

    /// After remeshing, before `Δt` is chosen.
    fn after_remesh(&mut self, _ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        Ok(())
    }

    /// Before the solve, with `Δt` chosen; again, with the halved `Δt`,
    /// after each rejected attempt (so that what a hook prescribes for
    /// `t + Δt` is for the step taken). Write it to be repeated. Before
    /// the first step it runs once more first, with the clock moved back
    /// by `Δt` (`time()` is then `t₀ − Δt`, which may be negative), so that
    /// what it gives for `time() + dt()` is the load at `t₀`: the first
    /// accelerations are set with it.
    fn before_solve(&mut self, _ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        Ok(())
    }

    /// After an accepted step.
    fn after_step(&mut self, _ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        Ok(())
    }

    /// Writes the hook's own state into a checkpoint
    /// ([`crate::checkpoint`]): what it accumulated since [`Hook::start`]
    /// that the particles do not hold (counters, a position within a
    /// period, a target). Default: nothing. A hook that keeps such state
    /// and does not save it makes a restarted run differ from an
    /// uninterrupted one.
    fn save_state(&self, _out: &mut Encoder) {}

    /// Reads back what [`Hook::save_state`] wrote. On a restored run
    /// [`Hook::start`] has run first, on the scene's initial state.
    fn restore_state(&mut self, _from: &mut Decoder<'_>) -> Result<(), CheckpointError> {
        Ok(())
    }
}

impl<const D: usize> Hook<D> for ()
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "nothing"
    }
}

/// What a hook may see and change. Built by the driver for each call.
pub struct HookContext<'a, const D: usize>
where
    Const<D>: Dim,
{
    pub(crate) time: f64,
    pub(crate) dt: f64,
    pub(crate) steps: u64,
    pub(crate) runs: u64,
    pub(crate) particles: &'a mut Particles<D>,
    pub(crate) elements: &'a Elements<D>,
    pub(crate) materials: &'a [Box<dyn Material<D>>],
    pub(crate) body_names: &'a [String],
    /// Which bodies are walls' or solids' (`Simulation`'s, fixed for the run).
    pub(crate) fixed_body: &'a [bool],
    /// Solid particles welded to a wall, with the wall's body.
    pub(crate) welds: &'a [(u32, u32)],
    pub(crate) gravity: &'a mut Option<Vector<D>>,
    pub(crate) stop: &'a mut Option<String>,
    pub(crate) external_force: &'a mut Vec<Vector<D>>,
    pub(crate) tessellator: &'a mut dyn Tessellator<D>,
    pub(crate) delaunay: &'a Tessellation,
    pub(crate) alpha: &'a AlphaShapeParams,
    pub(crate) initial_volume: f64,
    pub(crate) initial_drops: f64,
    pub(crate) sources: f64,
    pub(crate) moved: bool,
    /// Whether the hook took any mutable access to the particles (the
    /// driver then checks they are all finite).
    pub(crate) touched: bool,
    /// The particle set's generation the mesh (`elements`, `delaunay`)
    /// was made for: a set this hook changed is meshed when it returns.
    pub(crate) mesh_generation: u64,
    /// The generation the external forces are numbered in.
    pub(crate) forces_generation: u64,
    /// The solid elements binned on a grid, made by the first
    /// `insert_fluid` of the call (and again after `particles_mut`).
    pub(crate) solid_bins: Option<SolidBins<D>>,
    /// The name of the hook called, for the errors of `insert_fluid` and
    /// `manage_particles` (they named themselves alone: session 54's
    /// review).
    pub(crate) hook_name: String,
}

impl<const D: usize> std::fmt::Debug for HookContext<'_, D>
where
    Const<D>: Dim,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HookContext")
            .field("time", &self.time)
            .field("dt", &self.dt)
            .field("particles", &self.particles.len())
            .finish_non_exhaustive()
    }
}

impl<'a, const D: usize> HookContext<'a, D>
where
    Const<D>: Dim,
{
    /// Simulated time (s): `t_n` before the solve, `t_{n+1}` after the
    /// step.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The step size (s): the one about to be tried in
    /// [`Hook::before_solve`] (a rejected attempt halves it), the one taken
    /// in [`Hook::after_step`], the last one taken otherwise.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Accepted steps so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// How many times `Simulation::run` has been called, this run
    /// included (0 for steps taken by `Simulation::step` before any run): a
    /// hook that measures something per run (`WallClockLimit`) sees a new
    /// run begin when it changes.
    pub fn runs(&self) -> u64 {
        self.runs
    }

    /// Adds the force `f` (N; N per metre of depth in 2D) on particle `i`
    /// to the coming step's momentum balance (beside the body force, eq.
    /// 59): a point load, or a traction or a pressure spread over a
    /// body's boundary particles by the hook. Call it in
    /// [`Hook::before_solve`]: every attempt starts with no external force
    /// (a rejected attempt, retried smaller, calls those hooks again), and
    /// when a later hook changes the particle set the forces on fluid
    /// particles are dropped with the old numbering (walls' and solids'
    /// stay: their indices do not change). A particle outside every element (a flying
    /// drop) has no mass in the system and does not feel it; a prescribed
    /// velocity component wins over it. A force that is not finite, or a
    /// particle out of range, is an error. Forces added after this hook
    /// changed the set are on the new numbering and kept (those added
    /// before it on fluid particles are dropped; until session 48 the
    /// later ones were dropped too).
    pub fn add_force(&mut self, i: usize, f: Vector<D>) -> Result<(), RunError> {
        let n = self.particles.len();
        if i >= n || f.iter().any(|c| !c.is_finite()) {
            return Err(RunError::InvalidSetting {
                name: "external force",
                value: if i >= n { i as f64 } else { f.norm() },
                reason: "on a particle of the set, and finite",
            });
        }
        if self.particles.generation() != self.forces_generation {
            // The set changed in this call: the walls' and solids' forces
            // (a prefix that keeps its indices) stay, the fluid's were on
            // the old numbering.
            self.external_force.truncate(self.particles.fixed_prefix());
            self.forces_generation = self.particles.generation();
        }
        self.external_force.resize(n, Vector::<D>::zeros());
        self.external_force[i] += f;
        Ok(())
    }

    /// The external forces added so far for the coming step (N; empty
    /// when none, and after the step): [`HookContext::add_force`]. After
    /// this hook changed the set and before its next `add_force`, they are
    /// on the old numbering (the fluid's are dropped when it returns).
    pub fn external_forces(&self) -> &[Vector<D>] {
        self.external_force
    }

    /// The particles.
    pub fn particles(&self) -> &Particles<D> {
        self.particles
    }

    /// The particles, to change (positions, velocities, pressures,
    /// constraints). The driver measures the fluid volume after the call.
    pub fn particles_mut(&mut self) -> &mut Particles<D> {
        self.moved = true;
        self.touched = true;
        // (The solids may be moved through it.)
        self.solid_bins = None;
        self.particles
    }

    /// The velocity constraints, to change (a wall's prescribed velocity,
    /// an inlet's drive): unlike [`HookContext::particles_mut`] the driver
    /// does not measure the fluid volume again after the call, since no
    /// particle moved.
    pub fn constraints_mut(&mut self) -> &mut Constraints<D> {
        self.touched = true;
        self.particles.constraints_mut()
    }

    /// The velocities, to change (m/s); as [`HookContext::constraints_mut`],
    /// no particle moves, so the fluid volume is not measured again.
    pub fn v_mut(&mut self) -> &mut [Vector<D>] {
        self.touched = true;
        self.particles.v_mut()
    }

    /// The elements of the step (the mesh of the current step: after a
    /// hook changes the particle set it is remade before the next hook;
    /// within the hook that changed it, it is the old set's:
    /// [`HookContext::set_changed`]).
    pub fn elements(&self) -> &Elements<D> {
        self.elements
    }

    /// The materials.
    pub fn materials(&self) -> &[Box<dyn Material<D>>] {
        self.materials
    }

    /// Index of body `name`.
    pub fn body(&self, name: &str) -> Result<u32, RunError> {
        self.body_names
            .iter()
            .position(|b| b == name)
            .map(|i| i as u32)
            .ok_or_else(|| RunError::UnknownBody {
                name: name.to_string(),
            })
    }

    /// The solid particles welded to wall `body` (a solid particle placed
    /// on a wall's replaces it and takes its velocity): a hook that moves
    /// the wall must move them too, or refuse (`PrescribedMotion` refuses).
    pub fn welded_to(&self, body: u32) -> impl Iterator<Item = usize> + '_ {
        self.welds
            .iter()
            .filter(move |&&(_, w)| w == body)
            .map(|&(i, _)| i as usize)
    }

    /// Body names, by index.
    pub fn body_names(&self) -> &[String] {
        self.body_names
    }

    /// Body force per unit mass (m/s²).
    pub fn gravity(&self) -> Option<Vector<D>> {
        *self.gravity
    }

    /// Sets the body force per unit mass (m/s²) from now on.
    ///
    /// Errors: [`RunError::Hook`] for a non-finite component (a ramp
    /// `g t / t_ramp` with `t_ramp = 0`), which would reach the solve as a
    /// misleading step failure; the body force is then unchanged.
    pub fn set_gravity(&mut self, g: Option<Vector<D>>) -> Result<(), RunError> {
        if let Some(v) = g {
            if v.iter().any(|c| !c.is_finite()) {
                return Err(RunError::Hook {
                    hook: "set_gravity".into(),
                    why: format!("a body force of {:?} m/s² is not finite", v.as_slice()),
                });
            }
        }
        *self.gravity = g;
        Ok(())
    }

    /// Asks the run to stop after this step, for `reason`:
    /// [`crate::Simulation::run`] returns `Ok` and
    /// [`crate::Simulation::stopped`] gives the reason.
    pub fn stop(&mut self, reason: impl Into<String>) {
        *self.stop = Some(reason.into());
    }

    /// Fluid volume of the current mesh at the current positions (m³; m²
    /// per metre in 2D), wall pockets and drops included
    /// ([`crate::Simulation::fluid_volume`]). NaN while
    /// [`HookContext::set_changed`]: the mesh names the old set until the
    /// driver meshes the new one, when the hook returns (it read past the
    /// end of a shrunk set, a review of session 48).
    pub fn fluid_volume(&self) -> f64 {
        if self.set_changed() {
            return f64::NAN;
        }
        self.elements.fluid_volume(self.particles.x()) + self.drop_volume()
    }

    /// Whether the set differs from the one the mesh was made for (this
    /// hook removed or inserted particles, or a change by hand is not yet
    /// meshed): the mesh it reads ([`HookContext::elements`], the
    /// tessellation) is then the old set's.
    pub fn set_changed(&self) -> bool {
        self.particles.generation() != self.mesh_generation
    }

    /// Of [`HookContext::fluid_volume`], the fluid flying as drops
    /// ([`crate::Elements::drop_volume`]).
    pub fn drop_volume(&self) -> f64 {
        if self.set_changed() {
            return f64::NAN;
        }
        self.elements
            .drop_volume(self.particles.kind(), self.particles.spacing())
    }

    /// Fluid volume at the start of the run.
    pub fn initial_fluid_volume(&self) -> f64 {
        self.initial_volume
    }

    /// Of [`HookContext::initial_fluid_volume`], the fluid that started
    /// flying as drops.
    pub fn initial_drop_volume(&self) -> f64 {
        self.initial_drops
    }

    /// The fluid volume the run should have now: the initial volume plus
    /// what sources (inflows, outflows: [`Hook::sources_fluid`]) added.
    pub fn intended_fluid_volume(&self) -> f64 {
        self.initial_volume + self.sources
    }

    /// Appends a fluid particle (acceleration zero, no constraint); the mesh
    /// is remade before the next hook runs. Returns its index. A particle
    /// inside a solid's mesh is refused, naming the solid (it was accepted,
    /// and the fluid mesh then overlapped the solid's: session 53's
    /// review).
    pub fn insert_fluid(&mut self, p: Particle<D>) -> Result<usize, RunError> {
        if let Some(why) = crate::particles::fluid_particle_fault(
            &p,
            self.materials,
            self.body_names,
            self.fixed_body,
        ) {
            return Err(RunError::Hook {
                hook: format!("{} (insert_fluid)", self.hook_name),
                why,
            });
        }
        if let Some(e) = self.solid_element_holding(&p.x) {
            let nv = D + 1;
            let first = self.elements.solid()[e * nv] as usize;
            let body = self.particles.body()[first] as usize;
            let name = self.body_names.get(body).map_or("?", String::as_str);
            return Err(RunError::Hook {
                hook: format!("{} (insert_fluid)", self.hook_name),
                why: format!(
                    "a fluid particle at {:?} lies inside or on the surface of solid `{name}` (its element {e}): insert fluid outside the solids",
                    p.x.as_slice()
                ),
            });
        }
        self.moved = true;
        self.touched = true;
        let hook = format!("{} (insert_fluid)", self.hook_name);
        self.particles.push(p).map_err(|e| RunError::Hook {
            hook,
            why: e.to_string(),
        })
    }

    /// The solid element (index in [`Elements::solid`]) that holds `x`
    /// (inside or on a side, to 10⁻⁹ of its size), if any. The solid
    /// elements are binned once per hook call on a grid of their mean size
    /// (made again after `particles_mut`), so that a point costs the
    /// elements of its cell: 10 000 points inserted into the hollow of an
    /// L-shaped solid of 15 201 triangles took 0.74 s scanning them all
    /// (session 54's review).
    fn solid_element_holding(&mut self, x: &Point<D>) -> Option<usize> {
        let nv = D + 1;
        let solid = self.elements.solid();
        if solid.is_empty() {
            return None;
        }
        let xs = self.particles.x();
        let bins = self
            .solid_bins
            .get_or_insert_with(|| SolidBins::new(solid, xs));
        let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
        let mut g = [Vector::<D>::zeros(); pfem_core::MAX_NV];
        for &e in bins.candidates(x) {
            let e = e as usize;
            for a in 0..nv {
                p[a] = xs[solid[e * nv + a] as usize];
            }
            if pfem_core::shape_gradients::<D>(&p[..nv], &mut g[..nv]).is_none() {
                continue;
            }
            // The barycentric coordinates, `λ_a(x) = λ_a(p₀) + ∇λ_a · (x − p₀)`.
            // (On an element's side counts: a point on a side between two
            // of the solid's elements is inside the solid, and one on its
            // surface would make a flat fluid element.)
            let d = x - p[0];
            let inside = (0..nv).all(|a| {
                let at_p0 = if a == 0 { 1.0 } else { 0.0 };
                at_p0 + g[a].dot(&d) > -1e-9
            });
            if inside {
                return Some(e);
            }
        }
        None
    }

    /// Removes crowding fluid particles and inserts particles into oversized
    /// fluid elements ([`pfem_geometry::manage_particles`] on the current
    /// Delaunay tessellation and alpha shape), carrying every per-particle
    /// array ([`Particles::remap`]). Returns `(removed, inserted)`.
    pub fn manage_particles(
        &mut self,
        params: &ParticleManagementParams,
    ) -> Result<(usize, usize), RunError> {
        // The mesh it reads is the set's the hook was called with: a
        // second call in one hook, or one after a `remap`, read the old
        // set's Delaunay for the new particles (a review of session 48).
        if self.set_changed() {
            return Err(RunError::Hook {
                hook: format!("{} (manage_particles)", self.hook_name),
                why: "the particles were removed or inserted since the mesh was made (in this hook call, or by hand): call it once per hook call (the driver meshes the new set when the hook returns)".into(),
            });
        }
        let upd = pfem_geometry::manage_particles(
            self.tessellator,
            self.particles.x(),
            self.particles.kind(),
            self.particles.spacing(),
            self.delaunay,
            self.elements.shape(),
            self.alpha,
            params,
        )
        .map_err(RunError::Geometry)?;
        if upd.removed == 0 && upd.inserted == 0 {
            return Ok((0, 0));
        }
        let hook = format!("{} (manage_particles)", self.hook_name);
        self.particles.remap(&upd.map).map_err(|e| RunError::Hook {
            hook,
            why: e.to_string(),
        })?;
        self.moved = true;
        self.touched = true;
        Ok((upd.removed, upd.inserted))
    }
}

/// The solid elements binned on a uniform grid of their mean bounding-box
/// size, for [`HookContext::insert_fluid`]'s inside-a-solid check: each
/// element is listed in every cell its bounding box (widened by 10⁻⁹ of
/// its size) meets.
#[derive(Debug)]
pub(crate) struct SolidBins<const D: usize>
where
    Const<D>: Dim,
{
    lo: Point<D>,
    cell: f64,
    bins: std::collections::HashMap<[i64; 3], Vec<u32>>,
}

impl<const D: usize> SolidBins<D>
where
    Const<D>: Dim,
{
    fn new(solid: &[u32], x: &[Point<D>]) -> Self {
        let nv = D + 1;
        let boxes: Vec<(Point<D>, Point<D>)> = solid
            .chunks_exact(nv)
            .map(|el| {
                let mut lo = x[el[0] as usize];
                let mut hi = lo;
                for &i in &el[1..] {
                    lo = lo.inf(&x[i as usize]);
                    hi = hi.sup(&x[i as usize]);
                }
                let t = 1e-9 * (hi - lo).norm();
                (lo.map(|v| v - t), hi.map(|v| v + t))
            })
            .collect();
        let mut lo = boxes[0].0;
        let mut size = 0.0;
        for (a, b) in &boxes {
            lo = lo.inf(a);
            size += (b - a).norm();
        }
        let cell = (size / boxes.len() as f64).max(f64::MIN_POSITIVE);
        let mut bins: std::collections::HashMap<[i64; 3], Vec<u32>> =
            std::collections::HashMap::new();
        for (e, (a, b)) in boxes.iter().enumerate() {
            let (ka, kb) = (Self::key(&lo, cell, a), Self::key(&lo, cell, b));
            // (At most a few cells a side: an element is about a cell.)
            let span = |k: usize| ka[k]..=kb[k].min(ka[k] + 64);
            for i in span(0) {
                for j in span(1) {
                    for l in span(2) {
                        bins.entry([i, j, l]).or_default().push(e as u32);
                    }
                }
            }
        }
        Self { lo, cell, bins }
    }

    fn key(lo: &Point<D>, cell: f64, x: &Point<D>) -> [i64; 3] {
        let mut k = [0i64; 3];
        for (d, kd) in k.iter_mut().enumerate().take(D) {
            *kd = ((x[d] - lo[d]) / cell).floor().clamp(-1e15, 1e15) as i64;
        }
        k
    }

    /// The elements listed in the cell of `x`.
    fn candidates(&self, x: &Point<D>) -> &[u32] {
        self.bins
            .get(&Self::key(&self.lo, self.cell, x))
            .map_or(&[], Vec::as_slice)
    }
}

/// Stops the run when a condition on the particles holds.
pub struct StopWhen<const D: usize>
where
    Const<D>: Dim,
{
    reason: String,
    #[allow(clippy::type_complexity)]
    when: Box<dyn FnMut(f64, &Particles<D>) -> bool + Send>,
}

impl<const D: usize> StopWhen<D>
where
    Const<D>: Dim,
{
    /// Stops after the first accepted step at which `when(t, particles)`
    /// holds, giving `reason`.
    pub fn new(
        reason: impl Into<String>,
        when: impl FnMut(f64, &Particles<D>) -> bool + Send + 'static,
    ) -> Self {
        Self {
            reason: reason.into(),
            when: Box::new(when),
        }
    }
}

impl<const D: usize> Hook<D> for StopWhen<D>
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "stop when"
    }
    fn after_step(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        if (self.when)(ctx.time(), ctx.particles()) {
            ctx.stop(self.reason.clone());
        }
        Ok(())
    }
}

/// Stops the run after the current step once a shared flag is set: the way
/// a signal handler (Ctrl-C) or another thread asks a run to end cleanly,
/// with its outputs and a final checkpoint written. The stop reason is
/// [`Interrupt::REASON`].
#[derive(Debug, Clone, Default)]
pub struct Interrupt {
    flag: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Interrupt {
    /// The reason [`crate::Simulation::stopped`] gives.
    pub const REASON: &'static str = "interrupted";

    /// Watches `flag`.
    pub fn new(flag: std::sync::Arc<std::sync::atomic::AtomicBool>) -> Self {
        Self { flag }
    }
}

impl<const D: usize> Hook<D> for Interrupt
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "interrupt"
    }
    fn after_step(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        if self.flag.load(std::sync::atomic::Ordering::SeqCst) {
            ctx.stop(Self::REASON);
        }
        Ok(())
    }
}

/// Stops the run once it has taken `limit` seconds of wall time (from its
/// start), keeping what was written: a wall-clock limit. Each
/// `Simulation::run` has the whole limit: a run continued after the stop
/// (`Simulation::clear_stop`, then `run`) starts its clock again at its
/// first step (it stopped after one step, the review of session 45).
#[derive(Debug, Clone, Copy)]
pub struct WallClockLimit {
    limit: f64,
    /// The run ([`HookContext::runs`]) the clock started in, and when.
    started: Option<(u64, std::time::Instant)>,
}

impl WallClockLimit {
    /// A limit of `seconds` of wall time. A limit that is not a number
    /// stops the run at once when it starts ([`Hook::start`] refuses it
    /// with [`RunError::Hook`]): it would never stop it.
    pub fn new(seconds: f64) -> Self {
        Self {
            limit: seconds,
            started: None,
        }
    }
}

impl<const D: usize> Hook<D> for WallClockLimit
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "wall-clock limit"
    }
    fn start(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        if self.limit.is_nan() {
            return Err(RunError::Hook {
                hook: "wall-clock limit".into(),
                why: "a limit of NaN seconds would never stop the run".into(),
            });
        }
        self.started = Some((ctx.runs(), std::time::Instant::now()));
        Ok(())
    }
    fn after_remesh(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        // The first step of another run: its own clock.
        if self.started.is_some_and(|(run, _)| run != ctx.runs()) {
            self.started = Some((ctx.runs(), std::time::Instant::now()));
        }
        Ok(())
    }
    fn after_step(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        if self
            .started
            .is_some_and(|(_, t)| t.elapsed().as_secs_f64() >= self.limit)
        {
            ctx.stop(format!(
                "wall-clock limit of {} s reached at t = {} s",
                self.limit,
                ctx.time()
            ));
        }
        Ok(())
    }
}

/// A closure run at one point of every step.
type StepFn<const D: usize> =
    Box<dyn FnMut(&mut HookContext<'_, D>) -> Result<(), RunError> + Send>;

/// A hook from closures, one per point of the step (each optional).
/// What its closures capture is not saved in a checkpoint: a counter
/// moved into one starts again from its initial value in a restored run
/// (session 54's review: a hook acting at its 15th step acted 10 steps
/// late after a restart at step 10). A hook with state of its own that
/// must survive a restart is a type implementing [`Hook::save_state`] and
/// [`Hook::restore_state`]; an `FnHook` may read the clock instead
/// (`HookContext::time`, `HookContext::steps`), which a restart restores.
pub struct FnHook<const D: usize>
where
    Const<D>: Dim,
{
    name: String,
    start: Option<StepFn<D>>,
    after_remesh: Option<StepFn<D>>,
    before_solve: Option<StepFn<D>>,
    after_step: Option<StepFn<D>>,
    sources_fluid: bool,
}

impl<const D: usize> FnHook<D>
where
    Const<D>: Dim,
{
    /// A hook named `name` that does nothing yet.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            start: None,
            after_remesh: None,
            before_solve: None,
            after_step: None,
            sources_fluid: false,
        }
    }
    /// Declares the fluid this hook adds or removes as entering or leaving
    /// the domain ([`Hook::sources_fluid`]: an inflow or an outflow written
    /// as a closure), which the volume correction keeps instead of undoing.
    /// Off by default: what a hook removes is then a loss the correction
    /// puts back into the remaining water.
    pub fn sources_fluid(mut self, yes: bool) -> Self {
        self.sources_fluid = yes;
        self
    }
    /// Runs `f` once, before the first step it sees ([`Hook::start`]).
    pub fn start(
        mut self,
        f: impl FnMut(&mut HookContext<'_, D>) -> Result<(), RunError> + Send + 'static,
    ) -> Self {
        self.start = Some(Box::new(f));
        self
    }
    /// Runs `f` after remeshing.
    pub fn after_remesh(
        mut self,
        f: impl FnMut(&mut HookContext<'_, D>) -> Result<(), RunError> + Send + 'static,
    ) -> Self {
        self.after_remesh = Some(Box::new(f));
        self
    }
    /// Runs `f` before the solve.
    pub fn before_solve(
        mut self,
        f: impl FnMut(&mut HookContext<'_, D>) -> Result<(), RunError> + Send + 'static,
    ) -> Self {
        self.before_solve = Some(Box::new(f));
        self
    }
    /// Runs `f` after each accepted step.
    pub fn after_step(
        mut self,
        f: impl FnMut(&mut HookContext<'_, D>) -> Result<(), RunError> + Send + 'static,
    ) -> Self {
        self.after_step = Some(Box::new(f));
        self
    }
}

impl<const D: usize> Hook<D> for FnHook<D>
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        &self.name
    }
    fn sources_fluid(&self) -> bool {
        self.sources_fluid
    }
    fn start(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        self.start.as_mut().map_or(Ok(()), |f| f(ctx))
    }
    fn after_remesh(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        self.after_remesh.as_mut().map_or(Ok(()), |f| f(ctx))
    }
    fn before_solve(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        self.before_solve.as_mut().map_or(Ok(()), |f| f(ctx))
    }
    fn after_step(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        self.after_step.as_mut().map_or(Ok(()), |f| f(ctx))
    }
}

/// Particles of body `id`.
pub fn body_particles<const D: usize>(particles: &Particles<D>, id: u32) -> Vec<usize>
where
    Const<D>: Dim,
{
    (0..particles.len())
        .filter(|&i| particles.body()[i] == id)
        .collect()
}
