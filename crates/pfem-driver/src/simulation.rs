//! The simulation loop: remesh → assemble → solve (Picard) → update →
//! observe, with only the stages a scene calls for.

use std::time::Instant;

use pfem_constitutive::{History, Kinematics, Material, MaterialError, MaterialKind};
use pfem_core::{Const, Dim, ParticleKind, Point, Tensor, Vector};
use pfem_geometry::{
    alpha_shape_cutting_into, near_matter, tessellate_or_empty, tessellate_subset,
    AlphaShapeParams, Tessellation, Tessellator,
};
use pfem_time::{CourantController, Integrator, StepInput, StepParams};

use crate::checkpoint::{
    Checkpoint, CheckpointError, Decoder, Encoder, CONTACT, SETTINGS, SIMULATION, TIMINGS,
};
use crate::elements::Elements;
use crate::hooks::{FreeSurfacePressureZero, Hook, HookContext, VolumeCorrection};
use crate::particles::{Particles, NO_MATERIAL};
use crate::scene::Scene;
use crate::{RunError, SceneError};

/// Contact elements join particles closer than this many spacings
/// (every edge), about the diagonal of a lattice cell with room to move:
/// 1.6 in 2D (a square cell's diagonal is √2), 1.8 in 3D (a cube cell's
/// is √3).
///
/// In 3D it was 1.6 until session 56, below the cube cell's diagonal:
/// between a block's bottom row and a floor's top row, aligned, every
/// tetrahedron of a cell split holding that diagonal was left out (76
/// contact elements of about 300 under the 3D block of
/// `contact::a_free_block_rests_on_a_floor_in_3d`), and the third of the
/// layer kept changed as a block slid: on a 35° slope with μ = 0.5 it slid
/// +5.5 % too far, 1.55 mm sideways, lifting 0.30 mm
/// (`contact::a_block_slides_straight_down_a_slope_with_friction_in_3d`);
/// at 1.8, +2.6 %, 0.04 mm and 0.002 mm. Session 41 had tried 1.8 and
/// 1.96, and the 3D Hertz ball took ×1.77 its energy or failed on an
/// inverted contact element: the longer elements at a curved surface
/// formed already closed while a contact element's gap was the height
/// over its master facet's plane. Measured to the facet itself (session
/// 56, `pfem_geometry::contact`), the ball keeps its energy to ×1.028 at
/// 1.8 (×1.040 at 1.6), and a cube landing on its edge loses energy at
/// each bounce (+5.8 % on its first at 1.6).
const CONTACT_REACH: [f64; 2] = [1.6, 1.8];

/// Contact elements flatter than this fraction of a spacing are slivers of
/// the tessellation, not gaps: left out. A layer that a step closes that
/// far is refused within the step instead
/// (`pfem_constitutive::contact::CLOSED_GAP`, the same fraction of its
/// contact distance): left out at the next remeshing, its solid would pass
/// through unseen.
const CONTACT_MIN_GAP: f64 = 0.05;

/// Two bodies not yet joined by a contact element may close in one step to
/// the distance `√(g₀² + (D − 1) APPROACH_OFFSET H²)`, no nearer
/// (`Simulation::approach_time`; `g₀` the pair's contact distance, `H` the
/// larger of their spacings): a particle over the midpoint of two of the
/// other body's particles `H` apart (2D, `H²/4`), or over the centre of a
/// square cell of them (3D, `H²/2`), is that far from the nearest when its
/// gap is `g₀`. (1.118 g₀ in 2D and 1.225 g₀ in 3D for one spacing; a
/// first version took 1.118 g₀ in 3D too, which let a particle over a
/// cell's centre come to a gap of 0.87 g₀ with no element, a review.)
const APPROACH_OFFSET: f64 = 0.25;

/// Two bodies that a step turns from closing along a pushing contact
/// element's normal to not closing have had an impact the step did not
/// resolve when they closed faster than the body force accelerates in
/// this many steps (`IMPACT_SPEED_STEPS |b| Δt`) and than `IMPACT_TURN`
/// of the contact distance a step (`Simulation::forget_impacts`). Slower
/// turns (a body settling onto a floor, the chatter of a block the water
/// pushes against a wall, the turning point of a contact resolved over
/// many steps) are left to the scheme.
const IMPACT_SPEED_STEPS: f64 = 2.0;

/// An impact's closing speed is also above this fraction of the contact
/// distance a step (`Simulation::forget_impacts`): a contact resolved
/// over many steps turns its bodies round slower (an elastic disk in zero
/// gravity, whose turn on its floor was an impact without this floor).
const IMPACT_TURN: f64 = 0.01;

/// The remeshing tessellates the wall particles within this many
/// `α h_max` of a fluid or solid particle, unless
/// [`Options::tessellate_far_walls`]: every simplex the alpha shape keeps
/// or uses reaches at most `2.2 α h` from such a particle, contact
/// `CONTACT_REACH h` (see `pfem_geometry::reach`).
const WALL_REACH: f64 = 3.0;

/// Where in a step the hooks run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum HookPoint {
    Start,
    AfterRemesh,
    BeforeSolve,
    AfterStep,
}

/// The stages a step runs, derived from the scene: a scene pays only for
/// the effects it has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stages {
    /// Delaunay remeshing and alpha shape every step (scenes with a fluid,
    /// or with contact).
    pub remesh: bool,
    /// Nodal pressure update, eq. 62 (scenes with a fluid).
    pub pressure: bool,
    /// Solid stress update, eq. 63 (scenes with a solid).
    pub solid_stress: bool,
    /// Body-force assembly (scenes with gravity).
    pub body_force: bool,
    /// Flying-particle handling: particles outside every element fly
    /// ballistically (scenes with a fluid that has a free surface).
    pub free_surface: bool,
    /// Contact elements between solids that take part in contact (free
    /// ones, and clamped ones when the scene asks,
    /// `ContactSettings::clamped`) and walls or other solids (scenes with
    /// such a solid and another solid or a wall); the particles are
    /// tessellated every step for it, fluid or not.
    pub contact: bool,
}

/// The items of a settings print (`Simulation::settings_print`), `name:
/// value` each: split at `;`, `,`, `{` and `}` outside brackets, so that an
/// array setting stays whole (`multigrid_from: [1000, 100]` was shown as
/// "2000] in the checkpoint, 100] here", a review of session 53).
fn setting_items(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut depth = 0i32;
    for ch in s.chars() {
        match ch {
            '[' | '(' => {
                depth += 1;
                cur.push(ch);
            }
            ']' | ')' => {
                depth -= 1;
                cur.push(ch);
            }
            ';' | ',' | '{' | '}' if depth <= 0 => out.push(std::mem::take(&mut cur)),
            _ => cur.push(ch),
        }
    }
    out.push(cur);
    out.into_iter()
        .map(|t| t.trim().to_string())
        .filter(|t| !t.is_empty())
        .collect()
}

/// Wall time and call count of each stage.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageStats {
    /// Remeshing: calls and seconds.
    pub remesh: (u64, f64),
    /// Free-surface detection: the alpha shape (§8) and the fluid elements
    /// and boundary it gives, calls and seconds. A part of `remesh`.
    pub free_surface: (u64, f64),
    /// Assembly: calls (steps) and seconds.
    pub assemble: (u64, f64),
    /// Linear solves: calls (steps) and seconds.
    pub solve: (u64, f64),
    /// History and state update, and the step's bookkeeping (volume
    /// ledger, Courant bound, finite check): calls and seconds.
    pub update: (u64, f64),
    /// Observers (output): calls and seconds.
    pub observe: (u64, f64),
    /// Hooks ([`crate::hooks`], the volume correction among them): calls
    /// (points of a step at which hooks ran) and seconds.
    pub hooks: (u64, f64),
    /// Rejected step attempts (inverted element, Picard divergence, failed
    /// solve): count and seconds. `assemble`, `solve` and `update` count
    /// accepted attempts only.
    pub rejected: (u64, f64),
    /// Steps that updated a nodal pressure (eq. 62), as the integrator
    /// reports (`StepReport::pressure_updates`).
    pub pressure_updates: u64,
    /// Steps that updated a solid element's stress (eq. 63), as the
    /// integrator reports (`StepReport::stress_updates`).
    pub stress_updates: u64,
}

/// Something called after every accepted step (outputs, probes, checks).
/// Every method has a do-nothing default; `()` observes nothing.
pub trait Observer<const D: usize>
where
    Const<D>: Dim,
{
    /// Called at the start of every [`Simulation::run`], before its first
    /// step. An observer given to a second `run` (a run continued past its
    /// end time with [`Simulation::set_end_time`]) should go on from where
    /// it stood, as `pfem_io::StandardOutput` does.
    fn start(&mut self, _sim: &Simulation<D>) -> Result<(), RunError> {
        Ok(())
    }
    /// Called after every accepted step.
    fn step(&mut self, _sim: &Simulation<D>) -> Result<(), RunError> {
        Ok(())
    }
    /// Called once after the last step. Every observer's is called, one
    /// failing or not; `run` returns the first error.
    fn finish(&mut self, _sim: &Simulation<D>) -> Result<(), RunError> {
        Ok(())
    }
    /// Called once when [`Simulation::run`] fails (a step's or an
    /// observer's error, passed here before `run` returns it) on every
    /// observer that started, instead of [`Observer::finish`] (or after
    /// its own `finish` failed): a last record of the run, on a
    /// best-effort basis (its own failures are not reported). An observer
    /// whose `start` failed is not called.
    fn failed(&mut self, _sim: &Simulation<D>, _error: &RunError) {}
}

impl<const D: usize> Observer<D> for () where Const<D>: Dim {}

/// Fluid volume changes by cause (m³, m² per metre in 2D).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VolumeLedger {
    /// Fluid volume at the start (m³; m² per metre in 2D, as every field
    /// here).
    pub initial: f64,
    /// Change by remeshing (Delaunay + alpha shape deletions/creations).
    pub remeshing: f64,
    /// Change during the solution (quasi-incompressibility, flow).
    pub solution: f64,
    /// Change by each hook that moved, removed or inserted particles, by
    /// the hook's name ([`crate::hooks::Hook::name`]), in the order they
    /// first changed it; the volume correction books here as
    /// [`crate::hooks::VolumeCorrection::NAME`].
    pub hooks: Vec<(String, f64)>,
    /// Of the hooks' changes, the fluid that entered or left the domain
    /// ([`crate::hooks::Hook::sources_fluid`]): the intended volume is
    /// `initial + sources`.
    pub sources: f64,
    /// Of `initial`, the fluid that started flying as drops
    /// ([`Simulation::drop_volume`]).
    pub initial_drops: f64,
}

impl VolumeLedger {
    /// Change booked under hook `name` (0 if none).
    pub fn by(&self, name: &str) -> f64 {
        self.hooks
            .iter()
            .filter(|(n, _)| n == name)
            .map(|(_, v)| v)
            .sum()
    }

    /// Change by the volume correction.
    pub fn correction(&self) -> f64 {
        self.by(crate::hooks::VolumeCorrection::NAME)
    }

    /// The volume the ledger accounts for: the initial volume plus every
    /// change.
    pub fn accounted(&self) -> f64 {
        self.initial
            + self.remeshing
            + self.solution
            + self.hooks.iter().map(|(_, v)| v).sum::<f64>()
    }

    fn book(&mut self, name: &str, dv: f64) {
        if dv == 0.0 {
            return;
        }
        match self.hooks.iter_mut().find(|(n, _)| n == name) {
            Some((_, v)) => *v += dv,
            None => self.hooks.push((name.to_string(), dv)),
        }
    }
}

/// The work a run has done ([`Simulation::work`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Work {
    /// Delaunay tessellations + alpha shapes (the initial one included).
    pub remeshes: u64,
    /// Sparsity patterns built by the assembler (once per step when the
    /// mesh changes; once per run when it does not).
    pub patterns_built: u64,
    /// Elements assembled, summed over Picard iterations.
    pub elements_assembled: u64,
    /// Symbolic analyses of the linear solver.
    pub symbolic_analyses: u64,
    /// Numeric factorisations (direct) or preconditioner set-ups
    /// (iterative) of the linear solver.
    pub factorizations: u64,
    /// Preconditioner set-ups carried over from an earlier pattern
    /// instead of built anew (among `factorizations`;
    /// `pfem_assembly::BlockSolver::carry_steps`).
    pub setups_carried: u64,
    /// Krylov iterations of the linear solver (0 for a direct one).
    pub solver_iterations: u64,
    /// Linear solves, rejected attempts included: factorisations or
    /// preconditioner set-ups plus the solves that reused one
    /// (`solver_iterations / linear_solves` is the Krylov iterations per
    /// solve); for a solver that reports no work (a user's, whose
    /// `LinearSolver::work` is the default), the solves the integrator
    /// asked of it (it was 0, session 54's review).
    pub linear_solves: u64,
    /// Solves an iterative solver handed to its direct fallback
    /// (`pfem_assembly::BlockStats::fallbacks`; 0 for a direct solver).
    pub solver_fallbacks: u64,
}

/// Driver options chosen at construction ([`Simulation::with_options`]):
/// the deviations from the paper that can be switched, and the hooks the
/// driver installs itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Volume correction: the fraction `β ∈ [0, 1]` of the fluid's volume
    /// error each step restores ([`crate::hooks::VolumeCorrection`],
    /// deviation 5). Default 1; 0 installs no correction.
    pub volume_correction: f64,
    /// Impose `p = 0` on free-surface nodes after each remeshing
    /// ([`crate::hooks::FreeSurfacePressureZero`]). Default false.
    pub free_surface_pressure_zero: bool,
    /// Close the sealed voids of the fluid mesh for the pressure terms
    /// (deviation 8). Default true. Measured on 3D water at rest (0.5 ×
    /// 0.25 × 0.5 m, h = H/10): without closures the first layer of water
    /// above the floor starts at 14 m/s² along the floor from rest.
    pub close_sealed_voids: bool,
    /// Count the wall pockets in the fluid volume (deviation 9). Default
    /// true.
    pub count_wall_pockets: bool,
    /// Smallest quality `measure / R³` of a fluid tetrahedron (3D):
    /// flatter ones are slivers, not elements
    /// (`pfem_geometry::AlphaShapeParams::min_quality_3d`). Default
    /// [`pfem_geometry::MIN_SHAPE_QUALITY`] (only nearly flat ones);
    /// [`pfem_geometry::MIN_ELEMENT_QUALITY_3D`] (0.06) removes the 3D water
    /// column's rejected attempts (142 of 450 steps to 0.3 s → 0 of 144)
    /// but changes the column-on-cylinder's top displacement (50.96
    /// against 61.15 mm with 0.4 ms steps, and more scatter over step
    /// sizes), so it is not the default; keeping those tetrahedra in
    /// their start-of-step shape instead
    /// (`pfem_time::StepParams::sliver_quality_3d`, the default) removes
    /// the rejections without leaving them out. In `[0, 0.5)`.
    pub min_quality_3d: f64,
    /// Cut the dry bridges against free solids (no clamp, no weld) at the
    /// water line instead of keeping or dropping them whole (deviation 7;
    /// `pfem_geometry::AlphaShapeParams::cut_dry_bridges`,
    /// `pfem_geometry::alpha_shape_cutting_into`): for floating bodies.
    /// Default true. Measured (issue 19): a block half as dense as water,
    /// its rows half a spacing off the water's, keeps its draft to 0.00 %
    /// over 5 s with the water at rest with it, where without it the water
    /// never comes to rest and the block sinks (+5.4 %,
    /// `tests/floating.rs`). Clamped structures are never cut, as walls are
    /// not: cut too, the force on the elastic obstacle of the 2D dam break
    /// spiked to 10.4 kN/m for one step (572 N/m without), and the cylinder
    /// under a 3D water column deflected 56.6 mm at its top instead of
    /// 62.3 mm.
    pub cut_dry_bridges: bool,
    /// Memory budget (bytes): a scene whose estimate
    /// ([`pfem_scene::Scene::estimate`]) is above it is refused before a
    /// particle is placed. Default [`pfem_scene::default_memory_budget`]
    /// (80 % of the machine's memory).
    pub memory_budget: f64,
    /// A free solid (no clamp, no weld) starts as a rigid body under its net
    /// load: its particles' initial accelerations are the rigid motion (a
    /// translation and a rotation, mass-weighted least squares) of those
    /// the stress-free start gives (deviation 3). Default true. A body put
    /// at rest in water or on a floor carries its load through a stress it
    /// does not have at `t = 0`; started stress-free, its interior falls at
    /// `g` for the first step and the water round it rings: a block half as
    /// dense as water shook the water to 2.9·10⁻³ √(gH) within 0.015 s
    /// whatever its stiffness (`tests/floating.rs`). A clamped structure
    /// keeps the stress-free start (the elastic gate is released loaded).
    pub free_solids_start_rigid: bool,
    /// Tessellate every wall particle at each remeshing (3D), also those
    /// farther than a few spacings from every fluid and solid particle.
    /// Default false: those take part in no element, so the remeshing
    /// leaves them out ([`pfem_geometry::near_matter`]); the elements, the
    /// slivers and the wall pockets are the same, in another order, so
    /// results agree to round-off. On `column_on_cylinder_3d` at a/20
    /// (29 299 particles, 22 000 of them walls) it tessellates 14 000 and
    /// the remeshing takes 2.4× less time (`docs/benchmarks.md`, session
    /// 23). 2D always tessellates every wall: `Delaunay2` (spade) splits a
    /// lattice's square (four cocircular points) by insertion order, so a
    /// subset may split it along the other diagonal (1 208 of the elastic
    /// gate's 4 563 resting water elements did), and a 2D wall is a line
    /// of particles, cheap to keep.
    pub tessellate_far_walls: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            volume_correction: 1.0,
            free_surface_pressure_zero: false,
            close_sealed_voids: true,
            count_wall_pockets: true,
            min_quality_3d: pfem_geometry::MIN_SHAPE_QUALITY,
            cut_dry_bridges: true,
            memory_budget: pfem_scene::default_memory_budget(),
            free_solids_start_rigid: true,
            tessellate_far_walls: false,
        }
    }
}

/// The scratch of a step: the tessellator and its output, the integrator.
struct Stepper<const D: usize>
where
    Const<D>: Dim,
{
    tessellator: Box<dyn Tessellator<D>>,
    integrator: Integrator<D>,
    tess: Tessellation,
    /// [`Options::tessellate_far_walls`].
    far_walls: bool,
    /// The particles the last remeshing tessellated (empty: all).
    near: Vec<u32>,
    /// Their coordinates.
    scratch: Vec<Point<D>>,
    /// The particles' generation at the last step (`None`: no step yet;
    /// `u64::MAX` after a restore): when it changes, the integrator is
    /// told that the indices changed (`Integrator::particles_renumbered`).
    numbering: Option<u64>,
}

/// Counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Clock {
    time: f64,
    dt: f64,
    steps: u64,
    rejected: u64,
    rejected_by_cause: (u64, u64),
}

/// A running simulation: the particles ([`Particles`]), the elements of the
/// step ([`Elements`]), the materials, the hooks that may change it
/// ([`Hook`]), and the scratch of a step.
pub struct Simulation<const D: usize>
where
    Const<D>: Dim,
{
    name: String,
    particles: Particles<D>,
    elements: Elements<D>,
    materials: Vec<Box<dyn Material<D>>>,
    body_names: Vec<String>,
    /// Which bodies are walls' or solids' (a fluid particle may not join
    /// one): fixed for the run, since walls and solids never come or go.
    fixed_body: Vec<bool>,
    /// Solid particles welded to a wall, with the wall's body
    /// (`pfem_scene::Built::welds`; walls and solids keep their indices).
    welds: Vec<(u32, u32)>,
    hooks: Vec<Box<dyn Hook<D>>>,
    /// External forces the hooks added for the coming attempt (N; empty
    /// for none): `HookContext::add_force`.
    external_force: Vec<Vector<D>>,
    /// How many of `hooks` have had their `start` (a hook added during a
    /// run has it before the next step).
    started: usize,
    /// How many times [`Simulation::run`] was called ([`HookContext::runs`]).
    runs: u64,
    /// [`Simulation::state_version`].
    version: u64,
    stop: Option<String>,
    stages: Stages,
    stats: StageStats,
    clock: Clock,
    volume: VolumeLedger,
    volume_now: f64,
    gravity: Option<Vector<D>>,
    end_time: f64,
    output_interval: Option<f64>,
    controller: CourantController,
    alpha: AlphaShapeParams,
    /// Per particle (walls and solids, the first of the particles, whose
    /// indices hold for the run): a dry bridge may be cut against it, it
    /// belongs to a free solid ([`Options::cut_dry_bridges`]).
    cut_against: Vec<bool>,
    /// [`Options::free_solids_start_rigid`].
    start_rigid: bool,
    /// The driver options the simulation was built with (their print goes
    /// into checkpoints: [`Simulation::settings_print`]).
    options: Options,
    /// `min_dt` as the program and the scene set it, before the end
    /// time's floor (`end_time · 2⁻⁵⁰`): what a restart must repeat (a
    /// later `--end-time` raises the floor past 1.1·10⁶ s).
    min_dt_set: f64,
    /// The particles' generation the mesh was last made for: a set changed
    /// by hand since ([`Simulation::particles_mut`]) is remeshed by the
    /// next step.
    meshed: u64,
    /// Before the first step, the positions the mesh was last made at:
    /// the first step does not remesh, so positions changed by hand since
    /// are meshed first ([`Simulation::particles_mut`]). Empty after it.
    meshed_at: Vec<Point<D>>,
    /// Positions moved by hand before the first step wait for the start's
    /// check of bodies in contact ([`Simulation::too_close_at_start`]).
    start_check: bool,
    /// The gravity the accelerations were last set with
    /// ([`Simulation::initialize_acceleration`]): a first step under
    /// another one (a hook's) sets them again.
    accelerated_with: Option<Vector<D>>,
    stepper: Stepper<D>,
    contact: ContactSetup<D>,
}

/// Two bodies closer than the start accepts
/// ([`Simulation::too_close_at_start`]).
struct TooClose {
    /// The body named first.
    body: String,
    /// One of its particles in the closest contact element.
    particle: usize,
    /// What the error says.
    why: String,
}

/// What contact needs each step.
#[derive(Debug, Clone)]
struct ContactSetup<const D: usize>
where
    Const<D>: Dim,
{
    /// Per body: the index of the contact material it brings (the
    /// penalty of its solid, [`pfem_scene::ContactSettings::stiffness`]),
    /// `NO_MATERIAL` for a body without one; an element takes its
    /// softest solid's (since session 50; the stiffest before).
    material: Vec<u16>,
    /// Per body: its penalty stiffness (Pa), 0 for walls and fluids.
    stiffness: Vec<f64>,
    /// Per body: a free solid (no clamp, not welded).
    free: Vec<bool>,
    /// Per body: takes part in contact (the free solids, and every solid
    /// with [`pfem_scene::ContactSettings::clamped`]).
    in_contact: Vec<bool>,
    /// Friction by pair of bodies, as the scene gave them.
    friction: Vec<(u32, u32, f64)>,
    /// The same, each pair as (lower, higher) body, sorted: looked up
    /// for each contact element (a pass over the pairs for each cost
    /// 10¹⁰ comparisons a remeshing for 10⁶ pairs and 10⁴ elements).
    friction_by_pair: Vec<((u32, u32), f64)>,
    /// The candidates of the step (buffer).
    candidates: Vec<pfem_geometry::ContactCandidate<D>>,
    /// The penalty's rounded onset
    /// ([`pfem_scene::ContactSettings::onset`]).
    onset: f64,
    /// Per body: the mean velocity of its particles at the step's start
    /// (`Simulation::forget_impacts`; set before each step's solve).
    start_velocity: Vec<Vector<D>>,
}

impl<const D: usize> std::fmt::Debug for Simulation<D>
where
    Const<D>: Dim,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("name", &self.name)
            .field("particles", &self.particles.len())
            .field("time", &self.clock.time)
            .field("steps", &self.clock.steps)
            .finish_non_exhaustive()
    }
}

impl<const D: usize> Simulation<D>
where
    Const<D>: Dim,
{
    /// Builds the particles, solid meshes and constraints of a validated
    /// scene with the default [`Options`]. `tessellator` remeshes the fluid
    /// each step; `params` sets the time scheme and Picard loop.
    pub fn new(
        scene: Scene<D>,
        tessellator: Box<dyn Tessellator<D>>,
        params: StepParams,
    ) -> Result<Self, SceneError> {
        Self::with_options(scene, tessellator, params, Options::default())
    }

    /// [`Simulation::new`] with driver options.
    pub fn with_options(
        scene: Scene<D>,
        mut tessellator: Box<dyn Tessellator<D>>,
        params: StepParams,
        options: Options,
    ) -> Result<Self, SceneError> {
        if !(0.0..=1.0).contains(&options.volume_correction) {
            return Err(SceneError::InvalidSetting {
                setting: "volume_correction",
                value: options.volume_correction,
            });
        }
        if !(0.0..0.5).contains(&options.min_quality_3d) {
            return Err(SceneError::InvalidSetting {
                setting: "min_quality_3d",
                value: options.min_quality_3d,
            });
        }
        // The time scheme's and the Picard loop's parameters, named here
        // rather than found as failed steps.
        params.validate().map_err(|e| SceneError::OutOfRange {
            setting: e.setting,
            value: e.value,
            range: e.range,
        })?;
        // A step below `end_time · 2⁻⁵⁰` (four units in the last place of
        // the end time) may not move the clock: the run would not end. The
        // smallest step is raised to it (a long run's default `min_dt` of
        // 10⁻⁹ s is below it past 1.1·10⁶ s).
        let mut params = params;
        // (The same rule without the floor, for the restart's check.)
        let min_dt_set = if params.min_dt > scene.settings.max_dt
            && params.min_dt == StepParams::default().min_dt
        {
            1e-3 * scene.settings.max_dt
        } else {
            params.min_dt
        };
        params.min_dt = params
            .min_dt
            .max(scene.settings.end_time * MIN_DT_OF_END_TIME);
        scene.validate()?;
        // The controller keeps every step within [min_dt, max_dt]: a
        // floor above the ceiling would run every step at `min_dt`,
        // above the scene's `max_dt`, without a word. The default floor
        // (10⁻⁹ s) goes under a scene's finer `max_dt` (a thousandth of
        // it); one the program set is refused.
        let floor = scene.settings.end_time * MIN_DT_OF_END_TIME;
        if params.min_dt > scene.settings.max_dt
            && params.min_dt == StepParams::default().min_dt.max(floor)
        {
            params.min_dt = (1e-3 * scene.settings.max_dt).max(floor);
        }
        if params.min_dt > scene.settings.max_dt {
            return Err(SceneError::OutOfRange {
                setting: "min_dt",
                value: params.min_dt,
                range: "at most the scene's max_dt (min_dt is raised to end_time · 2⁻⁵⁰ at least)",
            });
        }
        // The scene's pressure stabilisation, unless the program set one.
        if params.pressure_stabilisation == 0.0 {
            params.pressure_stabilisation = scene.pressure_stabilisation;
        }
        let built = scene.build_within(options.memory_budget, tessellator.as_mut())?;
        let pfem_scene::Built {
            name,
            particles: cloud,
            materials,
            body_names,
            solid_elements,
            solid_material,
            gravity,
            settings,
            merges: _,
            laws,
            forces,
            free_solids,
            welds,
            in_contact,
            friction,
            contact_stiffness,
            contact_damping,
            contact_onset,
            domain,
            particle_management,
        } = built;
        let can_touch = cloud.solid_can_touch();
        let particles = Particles::from_cloud(cloud);
        // Walls and solids come first and keep their indices.
        let cut_against: Vec<bool> = particles
            .kind()
            .iter()
            .zip(particles.body())
            .take_while(|(k, _)| **k != ParticleKind::Fluid)
            .map(|(k, &b)| *k == ParticleKind::Solid && free_solids[b as usize])
            .collect();
        let cut_dry_bridges = options.cut_dry_bridges && cut_against.contains(&true);
        let has_fluid = particles.kind().contains(&ParticleKind::Fluid);
        let has_solid = particles.kind().contains(&ParticleKind::Solid);
        let contact = in_contact.iter().any(|&f| f) && can_touch;
        let stages = Stages {
            remesh: has_fluid || contact,
            pressure: has_fluid,
            solid_stress: has_solid,
            body_force: gravity.is_some_and(|g| g.norm() > 0.0),
            free_surface: has_fluid,
            contact,
        };
        let mut materials = materials;
        // One contact material per distinct penalty, in body order.
        let mut contact_material = vec![NO_MATERIAL; contact_stiffness.len()];
        if contact {
            let mut made: Vec<(f64, u16)> = Vec::new();
            for (b, &k) in contact_stiffness.iter().enumerate() {
                if k <= 0.0 {
                    continue;
                }
                contact_material[b] = match made.iter().find(|m| m.0 == k) {
                    Some(m) => m.1,
                    None => {
                        materials.push(Box::new(pfem_constitutive::ContactPenalty::new(
                            k,
                            k,
                            contact_damping,
                            contact_onset,
                        )));
                        let index = (materials.len() - 1) as u16;
                        made.push((k, index));
                        index
                    }
                };
            }
        }
        let controller = CourantController {
            courant: settings.courant,
            dt_max: settings.max_dt,
            dt_min: params.min_dt,
            growth: 1.25,
        };
        // (Each field was checked above; this keeps it so if those rules
        // change.)
        controller.validate().map_err(|e| SceneError::OutOfRange {
            setting: e.setting,
            value: e.value,
            range: e.range,
        })?;
        let mut hooks: Vec<Box<dyn Hook<D>>> = Vec::new();
        // The domain first: after each remeshing the fluid it removes is
        // booked as leaving before the volume correction measures the
        // step's water.
        if let Some((lo, hi)) = domain.filter(|_| has_fluid) {
            // (`Scene::validate` checked the box.)
            hooks.push(Box::new(crate::hooks::Domain::new(lo, hi).map_err(
                |_| SceneError::OutOfRange {
                    setting: "domain",
                    value: f64::NAN,
                    range: "finite corners, max above min along every axis",
                },
            )?));
        }
        if has_fluid && options.volume_correction > 0.0 {
            hooks.push(Box::new(
                VolumeCorrection::new(options.volume_correction).map_err(|_| {
                    SceneError::InvalidSetting {
                        setting: "volume_correction",
                        value: options.volume_correction,
                    }
                })?,
            ));
        }
        if has_fluid && options.free_surface_pressure_zero {
            hooks.push(Box::new(FreeSurfacePressureZero));
        }
        for (body, law) in laws {
            hooks.push(Box::new(crate::hooks::PrescribedMotion::new(body, law)));
        }
        for load in forces {
            hooks.push(Box::new(crate::hooks::AppliedForce::from_load(load)));
        }
        // Last of the driver's own, where a program's would run.
        if let Some((params, every)) = particle_management.filter(|_| has_fluid) {
            hooks.push(Box::new(crate::hooks::ParticleManagement::new(
                params, every,
            )));
        }
        // The solid elements weigh their initial volume (eq. 46).
        let mut elements = Elements::new(
            solid_elements,
            solid_material,
            particles.initial_positions(),
            options.close_sealed_voids,
            options.count_wall_pockets,
        );
        // Each solid element's state at `t₀`, from its material at its
        // centroid (a prestress, an initial plastic strain; zero by
        // default).
        let start = initial_solid_history(&elements, &materials, &particles, &body_names)?;
        elements.set_solid_history(&start);
        let fixed_body = particles.fixed_bodies(body_names.len());
        let mut sim = Self {
            name,
            particles,
            elements,
            materials,
            body_names,
            fixed_body,
            welds,
            hooks,
            external_force: Vec::new(),
            started: 0,
            runs: 0,
            version: next_state_version(),
            stop: None,
            stages,
            stats: StageStats::default(),
            clock: Clock {
                dt: settings.max_dt,
                ..Clock::default()
            },
            volume: VolumeLedger::default(),
            volume_now: 0.0,
            gravity: if stages.body_force { gravity } else { None },
            end_time: settings.end_time,
            output_interval: settings.output_interval,
            controller,
            alpha: AlphaShapeParams {
                // Above the water line is against gravity (dry bridges).
                up: up_of(gravity),
                min_quality_3d: options.min_quality_3d,
                cut_dry_bridges,
                ..AlphaShapeParams::with_alpha(settings.alpha)
            },
            cut_against,
            start_rigid: options.free_solids_start_rigid,
            options,
            min_dt_set,
            meshed: u64::MAX,
            meshed_at: Vec::new(),
            start_check: false,
            accelerated_with: None,
            stepper: Stepper {
                tessellator,
                integrator: Integrator::new(params),
                tess: Tessellation::default(),
                far_walls: options.tessellate_far_walls,
                near: Vec::new(),
                scratch: Vec::new(),
                numbering: None,
            },
            contact: ContactSetup {
                material: contact_material,
                stiffness: contact_stiffness,
                free: free_solids,
                in_contact,
                friction_by_pair: {
                    let mut by: Vec<((u32, u32), f64)> = friction
                        .iter()
                        .map(|&(a, b, mu)| ((a.min(b), a.max(b)), mu))
                        .collect();
                    by.sort_by_key(|f| f.0);
                    by
                },
                friction,
                candidates: Vec::new(),
                onset: contact_onset,
                start_velocity: Vec::new(),
            },
        };
        sim.remesh()
            .map_err(|e| SceneError::Mesh { why: e.to_string() })?;
        // Two bodies in contact that start closer than their contact
        // distance (beyond the penalty's rounded onset) would start under a
        // pressure of a third to a half of the penalty's modulus and be
        // kicked apart at the first step (session 44's review: a fine
        // block one of its spacings over a floor twice as coarse, a block
        // on a floor with its lattice offset). Refused, naming the pair.
        if let Some(close) = sim.too_close_at_start() {
            return Err(SceneError::InvalidGeometry {
                body: close.body,
                why: close.why,
            });
        }
        sim.volume.initial = sim.fluid_volume();
        sim.volume.initial_drops = sim.drop_volume();
        sim.volume_now = sim.volume.initial;
        sim.initialize_acceleration()
            .map_err(|e| SceneError::Mesh { why: e.to_string() })?;
        Ok(sim)
    }

    /// Sets the accelerations consistent with the current state (`M A =
    /// F + f_int`, [`Integrator::initialize_acceleration`]; `F` the body
    /// force and the external forces the hooks added, none before the
    /// first step's). `new` does it, and the first step again when a hook
    /// adds a force or sets another gravity before it (the accelerations
    /// a program set by hand are then replaced); call it again after changing
    /// velocities, pressures or constraints by hand before the first step.
    pub fn initialize_acceleration(&mut self) -> Result<(), RunError> {
        self.accelerations(true)
    }

    /// [`Simulation::initialize_acceleration`]; `by_hand`: called from
    /// outside a step, where positions moved since the first mesh were
    /// moved by hand (within the first step, by its hooks, whose mesh the
    /// step solves).
    fn accelerations(&mut self, by_hand: bool) -> Result<(), RunError> {
        self.version = next_state_version();
        rayon::scope(|_| self.mesh_a_set_changed_by_hand(by_hand))?;
        // Before the first step, without the contact layers: a layer
        // closed by the scene's placement (a solid set within its contact
        // distance of a floor) is an error of the placement, not a load,
        // and its penalty, carried into the first step's velocity by the
        // scheme (`(1 − γ) Δt Aⁿ`), threw a stiff block set at 99 % of the
        // distance off the floor at 57 m/s (session 54's review). The
        // first step's implicit solve lets the layer push it out, as at an
        // impact (`Simulation::forget_impacts`).
        let contact_len = if self.clock.steps == 0 {
            self.elements.contact().len()
        } else {
            0
        };
        let (mut mesh, history) = self.elements.step_mesh();
        let kept = mesh.elements.len() - contact_len;
        mesh.elements = &mesh.elements[..kept];
        mesh.element_material = &mesh.element_material[..kept / (D + 1)];
        let history = &history[..kept / (D + 1)];
        mesh.node_material = self.particles.material();
        // (Forces may cover a prefix of the particles after a hook's
        // renumbering: the integrator reads each particle's, if any.)
        let input = StepInput {
            mesh,
            materials: &self.materials,
            constraints: self.particles.constraints(),
            body_force: self.gravity,
            external_force: &self.external_force,
        };
        let mut state = self.particles.state().clone();
        self.stepper
            .integrator
            .initialize_acceleration(&mut state, history, &input)?;
        self.accelerated_with = self.gravity;
        if self.start_rigid {
            // Free solids: the rigid part of their particles' accelerations
            // (Options::free_solids_start_rigid).
            let assembler = self.stepper.integrator.assembler();
            let kind = self.particles.kind();
            let body = self.particles.body();
            // (particle, mass) per free body, in one pass over the walls
            // and solids (they come first).
            let mut members: Vec<Vec<(usize, f64)>> = vec![Vec::new(); self.contact.free.len()];
            for i in (0..kind.len()).take_while(|&i| kind[i] != ParticleKind::Fluid) {
                let b = body[i] as usize;
                if !self.contact.free[b] {
                    continue;
                }
                if let Some(m) = assembler.system_node(i).map(|s| assembler.mass()[s]) {
                    if m > 0.0 {
                        members[b].push((i, m));
                    }
                }
            }
            for members in members.iter().filter(|m| !m.is_empty()) {
                rigid_part::<D>(members, &state.x, &mut state.a);
                for &(i, _) in members {
                    for k in 0..D {
                        if self.particles.constraints().is_fixed(i, k) {
                            state.a[i][k] = 0.0;
                        }
                    }
                }
            }
        }
        // A prescribed component keeps the acceleration it has (a moving
        // wall's law's, set by `PrescribedMotion`; 0 at `new`), where the
        // integrator puts 0.
        let before = &self.particles.state().a;
        for (i, a) in state.a.iter_mut().enumerate() {
            for k in 0..D {
                if self.particles.constraints().is_fixed(i, k) {
                    a[k] = before[i][k];
                }
            }
        }
        self.particles.state_mut().a = state.a;
        Ok(())
    }

    /// Adds a hook, run after those added before it (and after the
    /// driver's own: the scene's domain, those of [`Options`], the
    /// scene's motion laws, forces and particle management). A hook added after the run has started
    /// has its `start` before the next step, seeing the state of then.
    pub fn add_hook(&mut self, hook: Box<dyn Hook<D>>) {
        self.hooks.push(hook);
    }

    /// Names of the hooks, in the order they run.
    pub fn hook_names(&self) -> Vec<String> {
        self.hooks.iter().map(|h| h.name().to_string()).collect()
    }

    /// Fluid volume: the measure of the current fluid elements and of the
    /// wall pockets ([`Elements::wall_pockets`]), and the drops' lattice
    /// cells ([`Simulation::drop_volume`]) (m³; m² per metre of depth in
    /// 2D). NaN while the set is not meshed: after a change by hand
    /// ([`Simulation::particles_mut`]) or a failed remeshing, until the
    /// next mesh.
    pub fn fluid_volume(&self) -> f64 {
        if let Some(v) = self.volume_without_mesh() {
            return v;
        }
        self.elements.fluid_volume(self.particles.x())
            + self
                .elements
                .drop_volume(self.particles.kind(), self.particles.spacing())
    }

    /// Whether the elements are the current particle set's: false between
    /// a change of the set (particles removed or added through
    /// [`Simulation::particles_mut`], or by a hook within its call) and the
    /// next meshing (a step, `run`,
    /// [`Simulation::initialize_acceleration`]). The fluid and contact
    /// elements name the old set's particles then: what reads them (the
    /// fluid volume, `pfem::Loads`, the probes of `pfem::cases`) gives NaN,
    /// nothing or an error until then.
    pub fn is_meshed(&self) -> bool {
        self.particles.generation() == self.meshed
    }

    /// The fluid volume when the mesh cannot give it: 0 in a scene
    /// without fluid (none, nor can it gain any: a fluid particle needs a
    /// fluid material; no pass over the particles), NaN while the set is
    /// not meshed (changed by hand, or its remeshing failed: the elements
    /// name the old set's particles).
    fn volume_without_mesh(&self) -> Option<f64> {
        if !self.stages.pressure {
            Some(0.0)
        } else if self.particles.generation() != self.meshed {
            Some(f64::NAN)
        } else {
            None
        }
    }

    /// Of [`Simulation::fluid_volume`], the fluid flying as drops: each
    /// fluid particle in no fluid element counts its lattice cell `hᵢ^D`
    /// ([`Elements::drop_volume`]).
    pub fn drop_volume(&self) -> f64 {
        if let Some(v) = self.volume_without_mesh() {
            return v;
        }
        self.elements
            .drop_volume(self.particles.kind(), self.particles.spacing())
    }

    /// Regenerates the fluid mesh: Delaunay of all particles, alpha shape
    /// (§8), one fluid material per element from its fluid nodes.
    fn remesh(&mut self) -> Result<(), RunError> {
        // A set changed since the last mesh (by a hook, particle management
        // or by hand) has its fluid particles checked first; a refused set
        // is checked again at the next try.
        let generation = self.particles.generation();
        if generation != self.meshed {
            self.check_fluid_particles()?;
        }
        if !self.stages.remesh {
            self.meshed = generation;
            return Ok(());
        }
        // (`meshed` is set once the mesh is made: a failed remeshing left
        // the set marked meshed with an empty fluid range, and its fluid
        // volume read as the drops' alone; a review of session 48.)
        self.meshed = u64::MAX;
        let t0 = Instant::now();
        let x = self.particles.x();
        let st = &mut self.stepper;
        // Only the walls a fluid or solid particle can reach
        // (pfem_geometry::reach).
        let h_max = self
            .particles
            .spacing()
            .iter()
            .fold(0.0, |a: f64, &h| a.max(h));
        let reach = WALL_REACH * self.alpha.alpha * h_max;
        // The whole set when the subset cannot be tessellated (a flat
        // layer of inflowing fluid far from every wall), which also reports
        // a real failure with its particle indices.
        let subset = D == 3
            && !st.far_walls
            && near_matter(x, self.particles.kind(), reach, &mut st.near)
            && tessellate_subset(
                st.tessellator.as_mut(),
                x,
                &st.near,
                &mut st.scratch,
                &mut st.tess,
            )
            .is_ok();
        if !subset {
            st.near.clear();
            // Fewer than D + 1 particles, or all on one line (2D) or plane
            // (3D): no simplex has a measure, so there is no mesh and every
            // fluid particle flies (§8's isolated particles). It was a
            // fatal error: a single falling drop could not be simulated
            // (session 40's review).
            tessellate_or_empty(st.tessellator.as_mut(), x, &mut st.tess)
                .map_err(RunError::Geometry)?;
        }
        let ts = Instant::now();
        let mut shape = self.elements.take_shape();
        alpha_shape_cutting_into(
            x,
            self.particles.kind(),
            self.particles.spacing(),
            &self.stepper.tess,
            &self.alpha,
            Some(&self.cut_against),
            &mut shape,
        )
        .map_err(RunError::Geometry)?;
        let kind = self.particles.kind();
        let material = self.particles.material();
        // The material most of the element's fluid nodes have (ties to the
        // lower index): where two fluids meet, the first fluid node in the
        // tessellation's vertex order decided, so one element of two water
        // nodes and one oil node could be oil under one rotation and water
        // under another (session 42's review).
        self.elements.set_fluid(shape, self.alpha.up, |el| {
            majority_fluid_material(el, kind, material)
        });
        // (Without fluid the alpha shape returns at once, after checking
        // the tessellation the contact reads: no free surface to count.)
        if self.stages.free_surface {
            self.stats.free_surface.0 += 1;
            self.stats.free_surface.1 += ts.elapsed().as_secs_f64();
        }
        if self.stages.contact {
            // Contact elements: simplices joining a solid in contact (free,
            // or clamped when asked) to a wall or another solid, no fluid
            // between (pfem_geometry::contact).
            let mut cands = std::mem::take(&mut self.contact.candidates);
            pfem_geometry::contact_elements(
                self.particles.x(),
                self.particles.kind(),
                self.particles.body(),
                self.particles.spacing(),
                &self.contact.in_contact,
                &self.stepper.tess,
                CONTACT_REACH[usize::from(D == 3)],
                CONTACT_MIN_GAP,
                &mut cands,
            )
            .map_err(RunError::Geometry)?;
            let friction = &self.contact.friction_by_pair;
            let mu = |a: u32, b: u32| {
                friction
                    .binary_search_by_key(&(a.min(b), a.max(b)), |f| f.0)
                    .map_or(0.0, |k| friction[k].1)
            };
            // The softest penalty among the element's solids: a wall brings
            // none, and an element may join three bodies (two walls at a
            // corner and a solid) whatever its two named ones. (The
            // stiffest until session 50: a soft block (E = 10⁴ Pa) resting
            // on a free steel one met a penalty 2·10⁷ times its own modulus
            // and inverted its elements at 0.2 s, a review; on a wall it
            // meets its own.)
            let (stiffness, material) = (&self.contact.stiffness, &self.contact.material);
            let body = self.particles.body();
            // (A body past the scene's, from particles pushed by hand,
            // brings none; an element with no penalty at all gets
            // `NO_MATERIAL`, which the assembly refuses with a typed error.)
            let k = |b: usize| stiffness.get(b).copied().unwrap_or(0.0);
            let element_material = |nodes: &[u32]| {
                nodes
                    .iter()
                    .map(|&p| body[p as usize] as usize)
                    .filter(|&b| k(b) > 0.0)
                    .min_by(|&a, &b| k(a).total_cmp(&k(b)))
                    .and_then(|b| material.get(b).copied())
                    .unwrap_or(NO_MATERIAL)
            };
            self.elements.set_contact(
                &cands,
                &element_material,
                body,
                self.particles.spacing(),
                &mu,
            );
            self.elements
                .set_contact_stress_at_rest(&self.materials, self.clock.dt);
            self.contact.candidates = cands;
        }
        if self.clock.steps == 0 {
            self.meshed_at.clear();
            self.meshed_at.extend_from_slice(self.particles.x());
        } else {
            self.meshed_at = Vec::new();
        }
        self.stats.remesh.0 += 1;
        self.stats.remesh.1 += t0.elapsed().as_secs_f64();
        self.meshed = generation;
        Ok(())
    }

    /// `Hook::start` of the hooks that have not had it yet.
    fn start_hooks(&mut self) -> Result<(), RunError> {
        self.start_hooks_then(true)
    }

    /// [`Simulation::start_hooks`]; `accelerations`: a gravity a hook's
    /// start set before the first step sets the accelerations (not when
    /// `restore` starts the hooks on the fresh state it then replaces).
    fn start_hooks_then(&mut self, accelerations: bool) -> Result<(), RunError> {
        // Hooks that may be installed once: two volume corrections (the
        // driver's own and one added, e.g. `with_target_volume`) would
        // pull the free surface to two targets, out and back every step;
        // two particle managements (the scene's and one added) would book
        // their passes under one name and restore their states by it.
        for (name, what, advice) in [
            (
                VolumeCorrection::NAME,
                "volume corrections",
                "set Options::volume_correction to 0 to add one of your own",
            ),
            (
                crate::hooks::ParticleManagement::NAME,
                "particle managements",
                "the scene asks for one, `Scene::particle_management`; leave it out to add one of your own",
            ),
        ] {
            let count = self.hooks.iter().filter(|h| h.name() == name).count();
            if count > 1 {
                return Err(RunError::Hook {
                    hook: name.into(),
                    why: format!("{count} {what}: one at most ({advice})"),
                });
            }
        }
        // Two motion laws on one wall: the later hook alone moved it (a
        // scene's law and an added `PrescribedMotion`, session 53's
        // review).
        let driven: Vec<(usize, &str)> = self
            .hooks
            .iter()
            .enumerate()
            .filter_map(|(k, h)| h.drives_body().map(|b| (k, b)))
            .collect();
        for (n, &(k, body)) in driven.iter().enumerate() {
            if let Some(&(j, _)) = driven[n + 1..].iter().find(|(_, b)| *b == body) {
                return Err(RunError::Hook {
                    hook: self.hooks[j].name().to_string(),
                    why: format!(
                        "body `{body}` is driven by two hooks (the {} and the {}, hooks {k} and {j}; a scene's motion law counts as one): give each wall one motion law",
                        self.hooks[k].name(),
                        self.hooks[j].name()
                    ),
                });
            }
        }
        let first = self.started;
        if first < self.hooks.len() {
            self.started = self.hooks.len();
            self.run_hooks_from(HookPoint::Start, first)?;
            // A gravity a hook's start set before the first step is the
            // load at `t₀`: the accelerations are set with it now (a
            // ramp's zero), not with the first step's end-of-step gravity
            // (a ramp from zero kept `½ k Δt²` of velocity too much, for
            // good: session 52's review).
            if accelerations && self.clock.steps == 0 && self.gravity != self.accelerated_with {
                self.accelerations(false)?;
            }
        }
        Ok(())
    }

    fn run_hooks(&mut self, point: HookPoint) -> Result<(), RunError> {
        self.run_hooks_from(point, 0)
    }

    /// Runs the hooks from the `first` at one point of the step, booking
    /// their volume changes; a hook that changes the particle set has the
    /// mesh remade before the next hook runs.
    fn run_hooks_from(&mut self, point: HookPoint, first: usize) -> Result<(), RunError> {
        // Each attempt's external forces are those its `before_solve`
        // hooks add (`HookContext::add_force`).
        if point == HookPoint::BeforeSolve && first == 0 {
            self.external_force.clear();
        }
        if self.hooks.len() <= first {
            return Ok(());
        }
        let t0 = Instant::now();
        let mut hooks = std::mem::take(&mut self.hooks);
        let mut result = Ok(());
        for (k, hook) in hooks.iter_mut().enumerate().skip(first) {
            let generation = self.particles.generation();
            // (At the start, whether the hook moved a particle.)
            let x_before = (point == HookPoint::Start).then(|| self.particles.x().to_vec());
            let mut ctx = HookContext {
                time: self.clock.time,
                dt: self.clock.dt,
                steps: self.clock.steps,
                runs: self.runs,
                particles: &mut self.particles,
                elements: &self.elements,
                materials: &self.materials,
                body_names: &self.body_names,
                fixed_body: &self.fixed_body,
                welds: &self.welds,
                gravity: &mut self.gravity,
                stop: &mut self.stop,
                external_force: &mut self.external_force,
                tessellator: self.stepper.tessellator.as_mut(),
                delaunay: &self.stepper.tess,
                alpha: &self.alpha,
                initial_volume: self.volume.initial,
                initial_drops: self.volume.initial_drops,
                sources: self.volume.sources,
                moved: false,
                touched: false,
                // (The set the mesh was made for: a set changed by hand
                // and not yet meshed reads as changed from the start.)
                mesh_generation: self.meshed,
                forces_generation: generation,
                solid_bins: None,
                hook_name: hook.name().to_string(),
            };
            let r = match point {
                HookPoint::Start => hook.start(&mut ctx),
                HookPoint::AfterRemesh => hook.after_remesh(&mut ctx),
                HookPoint::BeforeSolve => hook.before_solve(&mut ctx),
                HookPoint::AfterStep => hook.after_step(&mut ctx),
            };
            // A particle set changed by any means (`insert_fluid`,
            // `manage_particles`, or `Particles::remap` / `push` through
            // `particles_mut`) has its mesh remade: the elements' indices
            // are the old set's.
            let (moved, touched) = (ctx.moved, ctx.touched);
            // (Forces the hook added after its last change of the set are
            // on the new numbering.)
            let forces_current = ctx.forces_generation == ctx.particles.generation();
            let remesh = self.particles.generation() != generation;
            // Forces added on the old numbering: walls and solids come
            // first and keep their indices through any change of the set,
            // so theirs stay; a fluid particle's are dropped (whether the
            // hook failed or not).
            if remesh && !forces_current {
                self.external_force.truncate(self.particles.fixed_prefix());
            }
            let moved = moved || remesh;
            // A non-number a hook left in the state is named with the
            // hook: after the last step it would reach the outputs (and the
            // final checkpoint, which a restore then refuses) with the run
            // `Ok`; before the solve the step would refuse it naming no one.
            // (Scanned only after a hook that took mutable access.)
            let r = r.and_then(
                |()| match touched.then(|| self.particles.non_finite()).flatten() {
                    Some((i, what)) => Err(RunError::Hook {
                        hook: hook.name().to_string(),
                        why: format!("left particle {i}'s {what} not finite"),
                    }),
                    None => Ok(()),
                },
            );
            if let Err(e) = r {
                // A set changed before the hook failed keeps no mesh of
                // the old set's indices (outputs written after the error
                // read it).
                let mut meshed = true;
                if remesh {
                    if matches!(point, HookPoint::AfterRemesh | HookPoint::BeforeSolve) {
                        self.elements.keep_stash();
                    }
                    self.elements.clear_fluid();
                    // Its own failure leaves the fluid range empty; the
                    // hook's error is the one to report.
                    meshed = self.remesh().is_ok();
                    if meshed && point == HookPoint::AfterStep {
                        self.elements.keep_stash();
                    }
                }
                // What it changed before it failed is booked under its
                // name, so that the failed run's ledger closes (and a
                // program that steps on does not have the correction undo
                // a partial inflow layer as remeshing).
                if moved && meshed {
                    self.book_hook_change(hook.name(), hook.sources_fluid());
                }
                // A hook that failed to start, and those after it, start
                // at the next try (they were marked started and never
                // started: the review of session 45).
                if point == HookPoint::Start {
                    self.started = self.started.min(k);
                }
                result = Err(e);
                break;
            }
            // A hook that moves particles at its start (a wall put on its
            // law's path) has the mesh remade like a changed set: the
            // first step meshes nothing before its solve.
            let remesh = remesh
                || (point == HookPoint::Start
                    && x_before.is_some_and(|x| x.as_slice() != self.particles.x()));
            if remesh {
                // Before the solve the contact range was formed this step
                // and never solved: its tractions are the stash's, averaged
                // at the particles. The next range carries from the same
                // stash, not from this one (averaged a second time, stick's
                // memory would fade with every such remesh). Wall and
                // solid particles keep their indices through any change of
                // the set, so the stash still names them.
                if matches!(point, HookPoint::AfterRemesh | HookPoint::BeforeSolve) {
                    self.elements.keep_stash();
                }
                self.elements.clear_fluid();
                // Named with the hook after which it failed: a particle
                // inserted onto another failed as a bare "remeshing failed"
                // naming neither the hook nor the insertion (session 53's
                // review). (Not blamed on it: an earlier hook's moves or
                // the step's may be the cause, session 54's.)
                if let Err(e) = self.remesh() {
                    result = Err(match e {
                        RunError::Geometry(g) => RunError::Hook {
                            hook: hook.name().to_string(),
                            why: format!("remeshing after it changed the particles failed (the cause may be this change, an earlier hook's or the step's): {g}"),
                        },
                        e => e,
                    });
                    break;
                }
                // After the step the solved range went to the stash
                // (`clear_fluid`), and the range just formed from it is for
                // the outputs: the next step's carries from the stash too
                // (session 44's review: it carried from this one). So
                // does a hook started mid-run, before the step's remeshing.
                if point == HookPoint::AfterStep
                    || (point == HookPoint::Start && self.clock.steps > 0)
                {
                    self.elements.keep_stash();
                }
            }
            if moved || remesh {
                self.book_hook_change(hook.name(), hook.sources_fluid());
            }
        }
        self.hooks = hooks;
        self.gravity_changed();
        self.stats.hooks.0 += 1;
        self.stats.hooks.1 += t0.elapsed().as_secs_f64();
        result
    }

    /// Books the change of the fluid volume since the last measure under
    /// a hook's `name` (and in `sources` when it is a source); a volume
    /// that is not a number (a hook's NaN position, refused) is not booked.
    fn book_hook_change(&mut self, name: &str, sources: bool) {
        let after = self.fluid_volume();
        if !after.is_finite() {
            return;
        }
        let dv = after - self.volume_now;
        self.volume.book(name, dv);
        if sources {
            self.volume.sources += dv;
        }
        self.volume_now = after;
    }

    /// What follows from the body force when a hook or a restore has set
    /// it: its stage, and the alpha shape's `up` (the water line's
    /// direction for dry bridges; a scene whose gravity only a ramp sets
    /// had none before).
    fn gravity_changed(&mut self) {
        self.stages.body_force = self.gravity.is_some_and(|g| g.norm() > 0.0);
        self.alpha.up = up_of(self.gravity);
    }

    /// The smallest particle spacing `h_min` (reported; the Courant
    /// controller bounds the step by each particle's own spacing,
    /// `minᵢ hᵢ / |vᵢ|`).
    pub fn h_min(&self) -> f64 {
        self.particles
            .spacing()
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }

    /// The time before two bodies that no contact element joins yet come
    /// within a margin over their contact distance (s; infinite when no
    /// such pair closes): over the edges of the step's tessellation
    /// joining particles of two bodies, neither fluid, one taking part in
    /// contact, not both already nodes of contact elements (of any pair),
    /// the first time `t` with `|r + u t| = d`, `d² = g₀² + (D − 1)
    /// APPROACH_OFFSET H²` (`r` their separation, `u` the relative
    /// velocity of their bodies (the mean of each body's particles) at
    /// the step's start, `g₀` half the sum of their spacings,
    /// `H` the larger), or half the time to `|r + u t| = g₀` if
    /// that is later; a pair that passes by farther than `g₀` is not
    /// counted. A pair whose bodies' mean accelerations bring them together
    /// (a body let fall from rest, which has no velocity yet) takes the
    /// time to close along the line between them instead,
    /// `c_v t + ½ c_a t² = |r| − d` (session 54). The step is bounded by it
    /// ([`Simulation::step`]): contact elements join edges shorter than
    /// `CONTACT_REACH` spacings only (within 1.25 spacings of a floor for
    /// an aligned lattice), so a body faster than a quarter spacing a step
    /// went from beyond that reach to inside its contact distance with no
    /// element to stop it, and the element formed at the next remeshing
    /// started pushing from its penetration (session 51: a steel block
    /// falling at 3 m/s came 1.8 mm inside its 10 mm contact distance in
    /// such a step, the next left it at +3.8 m/s, the one after at
    /// +6.3 m/s, 4.8 times its energy). The margin over `g₀` covers a
    /// particle over the midpoint of two of the other body's, or over a
    /// cell's centre in 3D (`APPROACH_OFFSET`), so that the elements form
    /// open. A pair already within the margin and joined by no element
    /// is not bounded.
    fn approach_time(&self) -> f64 {
        if !self.stages.contact {
            return f64::INFINITY;
        }
        let p = &self.particles;
        let (x, kind, body, spacing) = (p.x(), p.kind(), p.body(), p.spacing());
        // The bodies' mean velocities, not the particles': a stiff solid's
        // particles ring at speeds far above its motion after an impact
        // (a steel cube resting after a 5 cm drop took steps of 0.5 ms
        // where 5 ms were allowed, and then rose to 14.5 times its drop).
        let mean = self.body_means(p.v());
        let velocity = |i: usize| {
            mean.get(body[i] as usize)
                .copied()
                .unwrap_or_else(Vector::<D>::zeros)
        };
        // And their mean accelerations: a body that starts at rest above
        // another (a block let fall onto a floor) has no velocity to
        // bound the first step by, and a first step of 0.1 s took it from
        // 4 spacings above the floor to 9.5 % of its contact distance with
        // no element to stop it; the element formed at the next remeshing
        // threw it 6 times its drop height (session 54's review).
        let mean_a = self.body_means(p.a());
        let acceleration = |i: usize| {
            mean_a
                .get(body[i] as usize)
                .copied()
                .unwrap_or_else(Vector::<D>::zeros)
        };
        let takes = |i: usize| {
            self.contact
                .in_contact
                .get(body[i] as usize)
                .copied()
                .unwrap_or(false)
        };
        let mut joined = vec![false; p.len()];
        for &i in self.elements.contact() {
            joined[i as usize] = true;
        }
        let nv = D + 1;
        let mut t = f64::INFINITY;
        for s in self.stepper.tess.simplices.chunks_exact(nv) {
            for a in 0..nv {
                for b in a + 1..nv {
                    let (i, j) = (s[a] as usize, s[b] as usize);
                    if i >= x.len()
                        || j >= x.len()
                        || kind[i] == ParticleKind::Fluid
                        || kind[j] == ParticleKind::Fluid
                        || body[i] == body[j]
                        || !(takes(i) || takes(j))
                        || (joined[i] && joined[j])
                    {
                        continue;
                    }
                    let r = x[j] - x[i];
                    let u = velocity(j) - velocity(i);
                    let g0 = 0.5 * (spacing[i] + spacing[j]);
                    let cell = spacing[i].max(spacing[j]);
                    let g = (g0 * g0 + (D - 1) as f64 * APPROACH_OFFSET * cell * cell).sqrt();
                    let (rr, ru, uu) = (r.dot(&r), r.dot(&u), u.dot(&u));
                    if rr <= g * g {
                        continue;
                    }
                    // Accelerated towards each other: the time to close
                    // along the line between them, `c_v t + ½ c_a t² =
                    // |r| − d` (`c_v`, `c_a` the closing velocity and
                    // acceleration along it; sideways motion, which could
                    // only take the pair past, left out: a bound on the
                    // safe side).
                    let closing_a = -r.dot(&(acceleration(j) - acceleration(i))) / rr.sqrt();
                    if closing_a > 0.0 && closing_a.is_finite() {
                        let closing_v = -ru / rr.sqrt();
                        let first = |d: f64| {
                            let gap = rr.sqrt() - d;
                            let root = (closing_v * closing_v + 2.0 * closing_a * gap).sqrt();
                            2.0 * gap / (closing_v + root)
                        };
                        let bound = first(g).max(0.5 * first(g0));
                        if bound.is_finite() && bound > 0.0 {
                            t = t.min(bound);
                        }
                        continue;
                    }
                    // Opening, or at rest: nothing to bound.
                    if !(ru < 0.0 && uu > 0.0) {
                        continue;
                    }
                    // The first time the pair is `d` apart, the smaller root
                    // of uu t² + 2 ru t + rr − d² = 0 (rr > d²: both
                    // positive; written without cancellation); none when
                    // it passes farther apart than `d`.
                    let first = |d: f64| {
                        let disc = ru * ru - uu * (rr - d * d);
                        (disc >= 0.0).then(|| (rr - d * d) / (-ru + disc.sqrt()))
                    };
                    // A pair that passes by outside its contact distance is
                    // left alone. Else the step ends at the margin, or
                    // halfway to the contact distance if that is later: the
                    // margin alone sent a pair that the mesh did not join
                    // there into steps ever shorter.
                    if let (Some(to_margin), Some(to_contact)) = (first(g), first(g0)) {
                        let bound = to_margin.max(0.5 * to_contact);
                        if bound.is_finite() {
                            t = t.min(bound);
                        }
                    }
                }
            }
        }
        t
    }

    /// Shortest time a particle needs to cross its own spacing,
    /// `min_i h_i / |v_i|` (s); infinite when nothing moves. Moving walls
    /// count: within the walls' reach of a fluid or solid particle at a
    /// spacing no coarser than the finest fluid or solid one, beyond it at
    /// the reach (a fixed wall's velocity is zero): skipped until session 44,
    /// a wall moved by a law or at a constant velocity into resting water
    /// took the scene's `max_dt` and could cross more than a spacing in
    /// one step (inverted elements, or a contact layer formed a step
    /// late).
    pub fn crossing_time(&self) -> f64 {
        self.crossing().1
    }

    /// The particle of the smallest `hᵢ/|vᵢ|` and that time (`(0, ∞)` when
    /// none is finite; a NaN is passed over, as `f64::min` passes it over).
    fn crossing(&self) -> (usize, f64) {
        let p = &self.particles;
        // A wall's own spacing may be coarser than the matter it moves
        // into: it counts at most the finest fluid or solid spacing.
        let h_matter = (0..p.len())
            .filter(|&i| p.kind()[i] != ParticleKind::Wall)
            .map(|i| p.spacing()[i])
            .fold(f64::INFINITY, f64::min);
        // A moving wall within the walls' reach of matter (the remeshing's,
        // `pfem_geometry::near_matter`) at that spacing; one beyond it (a
        // gate lifted clear of the water, a flap's dry top, far 3D walls)
        // at the reach itself: it may not set the step to a fluid
        // spacing, yet may not jump into the water within one step.
        let moving = p
            .kind()
            .iter()
            .zip(p.v())
            .any(|(k, v)| *k == ParticleKind::Wall && v.norm() > 0.0);
        let h_max = p.spacing().iter().fold(0.0, |a: f64, &h| a.max(h));
        let reach = WALL_REACH * self.alpha.alpha * h_max;
        // The particles within reach, increasing (`None`: every one, or
        // no wall moves).
        let kept = moving
            .then(|| {
                let mut kept = Vec::new();
                near_matter(p.x(), p.kind(), reach, &mut kept).then_some(kept)
            })
            .flatten();
        let near = |i: usize| {
            kept.as_ref()
                .is_none_or(|k| k.binary_search(&(i as u32)).is_ok())
        };
        let h = |i: usize| match p.kind()[i] {
            ParticleKind::Wall if near(i) => p.spacing()[i].min(h_matter),
            ParticleKind::Wall => reach,
            _ => p.spacing()[i],
        };
        (0..p.len())
            .map(|i| (i, h(i) / p.v()[i].norm()))
            .fold(
                (0, f64::INFINITY),
                |best, c| if c.1 < best.1 { c } else { best },
            )
    }

    /// Largest particle speed (m/s).
    pub fn v_max(&self) -> f64 {
        self.particles
            .v()
            .iter()
            .map(|v| v.norm())
            .fold(0.0, f64::max)
    }

    /// One accepted step: remesh (if the scene has a fluid or contact), the hooks
    /// after remeshing, `Δt`, the hooks before the solve, the
    /// Newmark–Picard step with rejection and retry, the hooks after the
    /// step.
    ///
    /// `Δt` is the Courant controller's, within `[min_dt, max_dt]`; the step
    /// that reaches the end time ends on it exactly, and so does one that
    /// reaches a kink of a prescribed motion (a table's row,
    /// [`Hook::next_kink`]). Called past the end time (a program's own
    /// loop), the step is the controller's, cut only at kinks.
    ///
    /// The step runs on a worker of rayon's global pool (the calling thread
    /// waits), so that the parallel loops inside it (meshing, element
    /// kernels) are entered from inside the pool. Called from outside the
    /// pool, every parallel loop would hand its work over and back, and the
    /// pool's idle workers would compete for the cores with the calling
    /// thread's serial work (measured: 1.8× slower on 2 cores,
    /// `docs/benchmarks.md`).
    pub fn step(&mut self) -> Result<(), RunError> {
        // Before and after: a step that fails may have changed the state.
        self.version = next_state_version();
        let (last_dt, steps) = (self.clock.dt, self.clock.steps);
        let remeshes = self.stats.remesh.0;
        let r = rayon::scope(|_| self.step_in_pool());
        self.version = next_state_version();
        // A failed step's forces were its own: a set changed by hand after
        // it and `initialize_acceleration` read them on the new numbering
        // (a review of session 48). Its attempts' steps were not taken:
        // `dt` is the last one taken again (before session 49 it was the
        // last attempt's, near `min_dt` after a step too small, and the
        // next step grew from it by 1.25 a step).
        // (A step that failed after it was taken, at the non-finite check
        // or in an after-step hook, keeps its `dt` and its solved range.)
        if r.is_err() {
            self.external_force.clear();
        }
        if r.is_err() && self.clock.steps == steps {
            self.clock.dt = last_dt;
            // A contact range formed by its remeshing was never solved: the
            // next range carries the tangential tractions from the last
            // solved one, as the failed step did (before session 49 it
            // carried from the unsolved one, whose tractions were that
            // step's averages, so stick's memory was averaged twice, and a
            // checkpoint then wrote them, a review). Not at step 0, whose
            // retry solves the range it has (as `restore` keeps it).
            if steps > 0 && self.stats.remesh.0 > remeshes {
                self.elements.keep_stash();
            }
        }
        r
    }

    /// The largest time step (s): the scene's `max_dt`.
    pub fn max_dt(&self) -> f64 {
        self.controller.dt_max
    }

    /// The memory budget (bytes) the simulation was built within
    /// ([`Options::memory_budget`]): what an observer checks what it will
    /// keep against (`StandardOutput`'s probe rows).
    pub fn memory_budget(&self) -> f64 {
        self.options.memory_budget
    }

    /// A number that changes whenever this simulation's state may have
    /// changed (a step, `particles_mut`, `restore`, `run`'s start,
    /// `initialize_acceleration`) and that no other simulation of the
    /// process shares: what a measurement taken once and read by several
    /// probes (a scene file's point probes, a force's columns) keys its
    /// cache on.
    pub fn state_version(&self) -> u64 {
        self.version
    }

    /// The fluid particles of a set changed since the last mesh (by hand,
    /// [`Particles::push`] through [`Simulation::particles_mut`], by a hook,
    /// or restored from a checkpoint): each must name a fluid material and
    /// a fluid body of the scene, with a positive spacing and finite
    /// values (`fluid_particle_fault`, which [`HookContext::insert_fluid`]
    /// shares). Walls and solids cannot be appended.
    fn check_fluid_particles(&self) -> Result<(), RunError> {
        let p = &self.particles;
        for i in p.fixed_prefix()..p.len() {
            if let Some(why) = crate::particles::fluid_particle_fault(
                &p.get(i),
                &self.materials,
                &self.body_names,
                &self.fixed_body,
            ) {
                return Err(RunError::InvalidParticle { particle: i, why });
            }
        }
        Ok(())
    }

    /// A step that could not be taken because a contact layer closed
    /// through its gap at every size ([`RunError::ContactClosed`], with the
    /// bodies named); any other failure as it is.
    fn name_a_closed_contact(&self, e: pfem_time::StepError) -> RunError {
        if let pfem_time::StepError::StepTooSmall {
            time, min_dt, last, ..
        } = &e
        {
            if let pfem_time::StepError::Refused { element, why, .. } = last.as_ref() {
                let first = self.elements.n_solid() + self.elements.n_fluid();
                let pair = element
                    .checked_sub(first)
                    .and_then(|c| self.elements.contact_bodies().get(c));
                if let Some(&(a, b)) = pair {
                    let name = |i: u32| {
                        self.body_names
                            .get(i as usize)
                            .cloned()
                            .unwrap_or_else(|| format!("body {i}"))
                    };
                    return RunError::ContactClosed {
                        time: *time,
                        master: name(a),
                        other: name(b),
                        min_dt: *min_dt,
                        why: why.clone(),
                    };
                }
            }
        }
        RunError::Step(e)
    }

    /// The closest pair of bodies in contact on the current mesh, if
    /// closer than the start accepts: `Simulation::new` refuses such a
    /// scene, and the first step positions moved by hand before it.
    fn too_close_at_start(&self) -> Option<TooClose> {
        use pfem_constitutive::contact::GAP_RATIO;
        // (An element whose every particle is held, a clamped or welded
        // solid beside a wall, carries no load: it is left alone.)
        let nv = D + 1;
        let held = |el: &[u32]| {
            el.iter()
                .all(|&i| self.particles.constraints().is_fully_fixed(i as usize))
        };
        let (ratio, el, (a, b)) = self
            .elements
            .contact()
            .chunks_exact(nv)
            .zip(self.elements.contact_history())
            .zip(self.elements.contact_bodies())
            .filter(|((el, _), _)| !held(el))
            .map(|((el, h), b)| (h.internal[GAP_RATIO], el, *b))
            .min_by(|a, b| a.0.total_cmp(&b.0))?;
        // Accepted: a closure within the onset, and a starting
        // pressure no higher than the default onset's bound
        // (`K_c δ₀/2`): a wide onset (up to ½) took bodies half their
        // contact distance apart at a quarter of the penalty's
        // modulus (session 47's review). Past `δ₀` the closure
        // `√(δ δ₀)` starts at `K_c δ₀/2` on the onset's parabola.
        let (onset, usual) = (
            self.contact.onset.max(0.0),
            pfem_scene::scene::CONTACT_ONSET,
        );
        let least = 1.0
            - if onset > usual {
                (onset * usual).sqrt()
            } else {
                onset
            };
        if ratio >= least - 1e-9 {
            return None;
        }
        let name = |i: u32| self.body_names[i as usize].clone();
        // 3D has no corner rule (`pfem_geometry::contact`): a
        // solid one spacing from two faces of one wall body (a
        // tank drawn as one surface) is measured across the
        // corner, at 1/√2 of its distance. Two bodies are not.
        let wall = |i: u32| {
            self.particles
                .body()
                .iter()
                .zip(self.particles.kind())
                .any(|(&bi, &k)| bi == i && k == ParticleKind::Wall)
        };
        let corner = if D == 3 && (wall(a) || wall(b)) {
            "; in 3D a solid in the corner of one wall body (a tank drawn as one surface) is measured across the corner: give the walls that meet there as separate bodies"
        } else {
            ""
        };
        // A particle of body `a` in the element, else its first.
        let particle = el
            .iter()
            .map(|&i| i as usize)
            .find(|&i| self.particles.body()[i] == a)
            .unwrap_or(el[0] as usize);
        Some(TooClose {
            body: name(a),
            particle,
            why: format!(
                "it starts at {:.1} % of its contact distance from body `{}` (half the sum of the two spacings; at least {:.1} % is accepted, by the contact's onset): place them that far apart, or a solid on a wall's lattice, where it is welded{corner}",
                100.0 * ratio,
                name(b),
                100.0 * least
            ),
        })
    }

    /// A set changed by hand since the last mesh (`particles_mut`) is
    /// meshed before anything reads the elements (a hook, an observer's
    /// first frame, the accelerations' start), whose indices are the old
    /// set's.
    fn mesh_a_set_changed_by_hand(&mut self, positions: bool) -> Result<(), RunError> {
        // Positions moved by hand before the first step, which solves the
        // mesh `new` made (session 47's review: a particle moved far from
        // the water stayed in its elements, and a solid moved towards a
        // wall kept a contact layer of the old gap). Not within the first
        // step (`positions` false): its hooks' moves are the step's, on
        // the mesh they saw.
        let moved = positions
            && self.clock.steps == 0
            && !self.meshed_at.is_empty()
            && self.meshed_at.as_slice() != self.particles.x();
        if self.particles.generation() != self.meshed || moved {
            self.elements.clear_fluid();
            self.remesh()?;
            // The step remeshes again (after its first): it carries from
            // the solved range, not from this one formed from it.
            if self.clock.steps > 0 {
                self.elements.keep_stash();
            }
            // Booked as remeshing: the ledger still closes.
            let after = self.fluid_volume();
            self.volume.remeshing += after - self.volume_now;
            self.volume_now = after;
            self.start_check |= moved;
        }
        // Moved by hand before the first step: the start's check of bodies
        // in contact again (session 47 left it), until it passes (a second
        // `step` after a refusal found the positions meshed and ran).
        if self.start_check && self.clock.steps == 0 {
            if let Some(close) = self.too_close_at_start() {
                return Err(RunError::InvalidParticle {
                    particle: close.particle,
                    why: format!(
                        "moved by hand before the first step, its body `{}`: {}",
                        close.body, close.why
                    ),
                });
            }
            self.start_check = false;
        }
        Ok(())
    }

    /// The mean velocity of each body's particles (by body index; zero for
    /// a body with none).
    fn body_velocities(&self) -> Vec<Vector<D>> {
        self.body_means(self.particles.v())
    }

    /// The mean of `values` (one per particle) over each body's particles.
    fn body_means(&self, values: &[Vector<D>]) -> Vec<Vector<D>> {
        let nb = self.contact.in_contact.len();
        let mut sum = vec![(Vector::<D>::zeros(), 0usize); nb];
        for (&b, v) in self.particles.body().iter().zip(values) {
            if let Some(m) = sum.get_mut(b as usize) {
                m.0 += v;
                m.1 += 1;
            }
        }
        sum.into_iter()
            .map(|(v, k)| if k > 0 { v / k as f64 } else { v })
            .collect()
    }

    /// An impact's force is not carried into the next step. The contact
    /// layer's period (some 10⁻⁶ s for steel) is far below the step, so a
    /// body that strikes a wall or another body is stopped and sent back
    /// within a step or two, and the end-of-step acceleration of its
    /// particles holds the impact's whole force. The Newmark family
    /// carries that acceleration into the next step's velocity
    /// (`(1 − γ) Δt Aⁿ` there), where the layer has let go: a kick out of
    /// the floor. Measured (session 51): a steel block (E = 2·10¹¹ Pa)
    /// dropped 5 cm onto a floor came down at 0.98 m/s, left the impact
    /// step at 0.41 m/s and the next at 1.06 m/s, with 31 % more energy
    /// than it fell with, and rose to 5.85 times its drop over 0.5 s
    /// (3.98 times with the trapezoidal rule; backward Euler, which
    /// carries no acceleration, stopped it dead).
    ///
    /// So, after a step in which two bodies, as wholes (their particles'
    /// mean velocities), went from closing along a contact element's
    /// normal faster than `max(IMPACT_SPEED_STEPS |b| Δt, IMPACT_TURN
    /// g₀/Δt)` to not closing, and the element still pushes, the
    /// particles of those elements lose those elements' part of their
    /// acceleration, `C / ((1 − α_B) m)` (`C` the elements' nodal force
    /// `−V σ ∇N`, `m` the lumped mass of the step's system): an impact
    /// the steps do not resolve is plastic, as implicit codes treat
    /// contact impact, and the velocity the step left stands. An impact
    /// resolved over many steps (a ball or a disk flattening on a floor
    /// and leaving it, over a hundred) turns no body round within one
    /// step, or slowly, and keeps the scheme; bodies at rest never close.
    /// The two bodies' parts are opposite, so the momentum of two free
    /// solids is kept. The mean velocity is a proxy: a body landing while
    /// it turns, or a clamped or very flexible one, may not turn round as
    /// a whole and keeps the kick. Not under backward Euler (it carries no
    /// acceleration).
    fn forget_impacts(&mut self, dt: f64) {
        let params = self.stepper.integrator.params;
        let alpha = match params.scheme {
            pfem_time::Scheme::BackwardEuler => return,
            pfem_time::Scheme::Bossak => params.bossak_alpha,
            pfem_time::Scheme::Newmark => 0.0,
        };
        if !self.stages.contact || self.elements.n_contact() == 0 {
            return;
        }
        let nv = D + 1;
        let n = self.particles.len();
        let before = &self.contact.start_velocity;
        let after = self.body_velocities();
        let at = |v: &[Vector<D>], b: u32| {
            v.get(b as usize)
                .copied()
                .unwrap_or_else(Vector::<D>::zeros)
        };
        let slow = IMPACT_SPEED_STEPS * self.gravity.map_or(0.0, |g| g.norm()) * dt;
        let contact = self.elements.contact();
        let history = self.elements.contact_history();
        let spacing = self.particles.spacing();
        let body = self.particles.body();
        let mut impact = vec![false; history.len()];
        let mut hit = vec![false; n];
        let mut any = false;
        for (e, ((el, h), &(a, b))) in contact
            .chunks_exact(nv)
            .zip(history)
            .zip(self.elements.contact_bodies())
            .enumerate()
        {
            if pfem_constitutive::ContactPenalty::pressure(h) <= 0.0 {
                continue;
            }
            // The normal points from body `a` into body `b`: they close
            // while `(V_b − V_a) · n < 0`.
            let normal =
                Vector::<D>::from_fn(|k, _| h.internal[pfem_constitutive::contact::NORMAL + k]);
            let closing = |v: &[Vector<D>]| -(at(v, b) - at(v, a)).dot(&normal);
            // Fast: beyond what the body force gives in a few steps, and
            // beyond `IMPACT_TURN` of the contact distance `g₀` a step: a
            // contact resolved over many steps turns its bodies round at
            // a speed well below that, whatever the gravity (without this
            // floor, a disk in zero gravity turning on its floor was an
            // impact).
            let g0 = crate::elements::contact_distance(el, (a, b), body, spacing);
            let fast = slow.max(IMPACT_TURN * g0 / dt);
            if closing(before) > fast && closing(&after) <= 0.0 {
                for &i in el {
                    hit[i as usize] = true;
                }
                impact[e] = true;
                any = true;
            }
        }
        if !any {
            return;
        }
        // The impacts' own force: the particles' other contacts (a floor
        // under a block that strikes a side wall) are left as they are,
        // so that the two bodies' parts stay opposite.
        let mut force = vec![Vector::<D>::zeros(); n];
        self.elements.contact_nodal_forces(
            self.particles.x(),
            |e| impact[e],
            |_, i, f| force[i] += f,
        );
        // The lumped mass the step's system gave each particle (eq. 46
        // for its solid elements, the fluid's as the assembly lumps it).
        let assembler = self.stepper.integrator.assembler();
        let mass = |i: usize| {
            assembler
                .system_node(i)
                .and_then(|s| assembler.mass().get(s).copied())
                .unwrap_or(0.0)
        };
        // The contact's part of each particle's acceleration, its
        // prescribed components kept.
        let constraints = self.particles.constraints();
        let cut: Vec<(usize, Vector<D>)> = (0..n)
            .filter(|&i| hit[i] && mass(i) > 0.0)
            .map(|i| {
                let mut da = force[i] / ((1.0 - alpha) * mass(i));
                for k in 0..D {
                    if constraints.is_fixed(i, k) {
                        da[k] = 0.0;
                    }
                }
                (i, da)
            })
            .collect();
        let a = self.particles.a_mut();
        for (i, da) in cut {
            a[i] -= da;
        }
    }

    /// A non-number set by hand between steps (or before `run`), named as
    /// such before a hook could be blamed for it (a hook's start that takes
    /// mutable access would be, and a NaN position would fail the mesh).
    fn no_non_number_by_hand(&self) -> Result<(), RunError> {
        if let Some((particle, what)) = self.particles.non_finite() {
            return Err(RunError::InvalidParticle {
                particle,
                why: format!("its {what} is not finite (set by hand since the last step?)"),
            });
        }
        Ok(())
    }

    fn step_in_pool(&mut self) -> Result<(), RunError> {
        self.no_non_number_by_hand()?;
        self.mesh_a_set_changed_by_hand(true)?;
        self.start_hooks()?;
        // The fluid volume at the end of the last step is `volume_now`; it is
        // measured once after remeshing and once after the solution.
        // The step's bookkeeping (volume ledger, Courant bound, finite
        // check) is booked under `update`.
        let mut book = 0.0;
        if self.clock.steps > 0 {
            self.remesh()?;
            let tb = Instant::now();
            let after = self.fluid_volume();
            self.volume.remeshing += after - self.volume_now;
            self.volume_now = after;
            book += tb.elapsed().as_secs_f64();
        }
        self.run_hooks(HookPoint::AfterRemesh)?;
        let tb = Instant::now();
        // Courant bound per particle, on its own spacing: Δt ≤ C min_i h_i/|v_i|,
        // passed to the controller as (h, v) = (min_i h_i/|v_i|, 1). It keeps
        // particles from crossing elements between remeshings: a scene that
        // never remeshes (solids only) is bounded by `max_dt` alone.
        let crossing = if self.stages.remesh {
            self.crossing_time()
        } else {
            f64::INFINITY
        };
        if crossing.is_finite() && self.controller.courant * crossing < self.controller.dt_min {
            let particle = self.crossing().0;
            return Err(RunError::CourantStepTooSmall {
                time: self.clock.time,
                courant: self.controller.courant,
                crossing,
                particle,
                speed: self
                    .particles
                    .v()
                    .get(particle)
                    .map_or(f64::NAN, |v| v.norm()),
                min_dt: self.controller.dt_min,
            });
        }
        let mut dt = if crossing.is_finite() {
            self.controller.next(crossing, 1.0, self.clock.dt)
        } else {
            self.controller.next(0.0, 0.0, self.clock.dt)
        };
        // Nor may two bodies come within their contact distance in a step
        // that has no contact element between them (`approach_time`).
        let approach = self.approach_time();
        if approach < dt {
            dt = approach.max(self.controller.dt_min);
        }
        // The step that ends the run lands on the end time: one within
        // `END_SNAP` of it is stretched to it, and the rest, if shorter
        // than two steps, is taken in two equal halves, so that neither
        // the clock's round-off (about 10⁻¹⁰ s after 10⁵ steps) nor an end
        // time off the steps' grid leaves a sliver to take (session 47's
        // review: a sliver of 5·10⁻⁹ s ended a run, whose continuation
        // grew its step back by 1.25 a step, and whose last acceleration
        // `(v − vⁿ)/(γΔt)` magnified the Picard loop's error by 1/Δt). A
        // rest below `min_dt` (an end time set just after the clock) is
        // taken as one step, not one of `min_dt` past it. Past the end time
        // (`step` called by hand) the step is the controller's.
        // So does a step that would cross a kink of a hook's prescribed
        // motion (a table's row, `Hook::next_kink`): kinks closer than
        // `min_dt` to the clock, or to the end time, are passed over (a
        // step there could not be halved; a row just before the end time
        // would have the last step of `min_dt` overshoot it), and so is a
        // kink a faulty hook gives at or before the clock.
        let (t, dt_min) = (self.clock.time, self.controller.dt_min);
        let kink = self
            .hooks
            .iter()
            .filter_map(|h| h.next_kink(t))
            .filter(|&k| k - t >= dt_min && (self.end_time <= t || self.end_time - k >= dt_min))
            .fold(f64::INFINITY, f64::min);
        let landing = if kink < self.end_time || self.end_time <= t {
            kink
        } else {
            self.end_time
        };
        let remaining = landing - t;
        if remaining > 0.0 && remaining <= dt * (1.0 + END_SNAP) {
            // (A kink is at least `min_dt` ahead.)
            dt = remaining;
        } else if remaining > 0.0 && remaining < 2.0 * dt {
            // Two equal steps to a kink or the end, not a full one and a
            // sliver (the controller grows the step back by 1.25 a step: a
            // sliver of 10⁻³ of it cost some 30 steps more), nor one past
            // `max_dt`. A rest below `2 min_dt` (the step at its floor) is
            // one step: two halves would be below `min_dt`, and one of
            // `min_dt` would leave a sliver (the review of the change).
            dt = if 0.5 * remaining >= dt_min {
                0.5 * remaining
            } else {
                remaining
            };
        }
        self.clock.dt = dt;
        book += tb.elapsed().as_secs_f64();
        // A load on from the start: `new`'s accelerations did not know it,
        // and Bossak's stored acceleration lagged (the run kept `F Δt₁/2`
        // of momentum too little, for good). Before the first step the
        // hooks' `before_solve` runs once with the clock moved back by the
        // step, so that what each gives for `time + dt` (a force, a
        // gravity, a wall's velocity) is its value at `t₀`, and the
        // accelerations are set again with those loads when there are
        // any. They were set with the first step's end-of-step loads, `t₀
        // + Δt`, until session 53: exact for a constant load, but a force
        // ramped from zero kept `½ k Δt²` of momentum too much for good
        // (a review; `BodyForceRamp`'s gravity was mended in session 52 by
        // its start). The step's own pass follows.
        if self.clock.steps == 0 && !self.hooks.is_empty() {
            let t = self.clock.time;
            self.clock.time = t - dt;
            let at_start = self.run_hooks(HookPoint::BeforeSolve);
            self.clock.time = t;
            at_start?;
            if !self.external_force.is_empty() || self.gravity != self.accelerated_with {
                self.accelerations(false)?;
            }
        } else if self.clock.steps == 0 && self.gravity != self.accelerated_with {
            // A gravity set by the program before the first step
            // (`set_gravity`): the load at `t₀`.
            self.accelerations(false)?;
        }
        self.run_hooks(HookPoint::BeforeSolve)?;
        // The attempts, halving the step after each rejected one; the hooks
        // before the solve run again for each smaller step, so that what
        // they prescribe for `t + Δt` (a wall's velocity, a ramped body
        // force, an inflow's drive) is for the step taken (with
        // `Integrator::advance` a retried step kept the first attempt's).
        if self.stages.contact {
            self.contact.start_velocity = self.body_velocities();
        }
        let mut rejected = pfem_time::Rejections::default();
        let rep = loop {
            // (Checked at each attempt: a hook run again may change the set.)
            let numbering = self.particles.generation();
            if self.stepper.numbering.is_some_and(|n| n != numbering) {
                self.stepper.integrator.particles_renumbered();
            }
            self.stepper.numbering = Some(numbering);
            if !self.external_force.is_empty() {
                self.external_force
                    .resize(self.particles.len(), Vector::<D>::zeros());
            }
            let (mut mesh, history) = self.elements.step_mesh();
            let (state, constraints, material) = self.particles.state_and_constraints();
            mesh.node_material = material;
            let input = StepInput {
                mesh,
                materials: &self.materials,
                constraints,
                body_force: self.gravity,
                external_force: &self.external_force,
            };
            let t0 = Instant::now();
            match self
                .stepper
                .integrator
                .try_step(self.clock.time, dt, state, history, &input)
            {
                Ok(mut rep) => {
                    rejected.report(&mut rep);
                    break rep;
                }
                Err(e) => {
                    let min_dt = self.stepper.integrator.params.min_dt;
                    dt = rejected
                        .reject(e, self.clock.time, dt, min_dt, t0.elapsed())
                        .map_err(|e| self.name_a_closed_contact(e))?;
                    self.clock.dt = dt;
                    self.run_hooks(HookPoint::BeforeSolve)?;
                }
            }
        };
        // The forces were the step's.
        self.external_force.clear();
        self.forget_impacts(rep.dt);
        self.clock.time = if rep.dt == remaining {
            landing
        } else {
            self.clock.time + rep.dt
        };
        self.clock.dt = rep.dt;
        self.clock.steps += 1;
        self.clock.rejected += rep.rejections as u64;
        self.clock.rejected_by_cause.0 += rep.rejected_inverted as u64;
        self.clock.rejected_by_cause.1 += rep.rejected_picard as u64;
        self.stats.assemble.0 += rep.iterations as u64;
        self.stats.assemble.1 += rep.assemble_seconds;
        self.stats.solve.0 += rep.iterations as u64;
        self.stats.solve.1 += rep.solve_seconds;
        self.stats.update.0 += 1;
        self.stats.update.1 += rep.update_seconds;
        self.stats.rejected.0 += rep.rejections as u64;
        self.stats.rejected.1 += rep.rejected_seconds;
        // What the step did, not what the stages promised.
        if rep.pressure_updates > 0 {
            self.stats.pressure_updates += 1;
        }
        if rep.stress_updates > 0 {
            self.stats.stress_updates += 1;
        }
        let tb = Instant::now();
        let end = self.fluid_volume();
        self.volume.solution += end - self.volume_now;
        self.volume_now = end;
        // The step's own positions are checked before the hooks after it,
        // which are checked each (a NaN of the step's was blamed on the
        // first of them).
        if let Some(i) = self
            .particles
            .x()
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite()))
        {
            return Err(RunError::NonFinite {
                time: self.clock.time,
                particle: i,
            });
        }
        book += tb.elapsed().as_secs_f64();
        self.stats.update.1 += book;
        self.run_hooks(HookPoint::AfterStep)?;
        Ok(())
    }

    /// Runs to the end time (or until a hook stops it,
    /// [`Simulation::stopped`]), calling the observers after every step.
    /// Called again after [`Simulation::set_end_time`], it goes on from
    /// where the last call ended. A run a hook stopped stays stopped (`run`
    /// takes no step: it starts the hooks not yet started and calls the
    /// observers' `start` and `finish`, which write their outputs again)
    /// until [`Simulation::clear_stop`].
    pub fn run(&mut self, observers: &mut [&mut dyn Observer<D>]) -> Result<(), RunError> {
        self.runs += 1;
        // (Before the hooks start: the review of session 45 found a NaN set
        // by hand blamed on the first hook that started.)
        self.no_non_number_by_hand()?;
        rayon::scope(|_| self.mesh_a_set_changed_by_hand(true))?;
        // The hooks start before the observers, so that the first frame
        // shows what they set at the start: a moving wall's velocity (it
        // showed at rest at t = 0, session 44's review), a wall a law
        // displaces at t = 0 on its path. A hook that fails to start still
        // has the observers start and record the failure.
        let started = rayon::scope(|_| self.start_hooks());
        if let Err(e) = started {
            self.version = next_state_version();
            // The hook's error is the one returned; an observer that cannot
            // start records nothing.
            for o in observers.iter_mut() {
                if o.start(self).is_ok() {
                    o.failed(self, &e);
                }
            }
            return Err(e);
        }
        // What the start changed (a set meshed again, a hook's start).
        self.version = next_state_version();
        // An observer that cannot start fails the run: the ones started
        // before it are told (`Observer::failed`: their summary says so),
        // as a step's failure tells them all (before session 49 they were
        // left started, without a summary, a review).
        for k in 0..observers.len() {
            if let Err(e) = observers[k].start(self) {
                for o in observers[..k].iter_mut() {
                    o.failed(self, &e);
                }
                return Err(e);
            }
        }
        let steps = (|| -> Result<(), RunError> {
            // (A step lands on the end time exactly; the tolerance is for
            // a clock restored or set within round-off of it.)
            while !self.reached_end_time() && self.stop.is_none() {
                self.step()?;
                let t0 = Instant::now();
                for o in observers.iter_mut() {
                    o.step(self)?;
                }
                self.stats.observe.0 += 1;
                self.stats.observe.1 += t0.elapsed().as_secs_f64();
            }
            Ok(())
        })();
        if let Err(e) = steps {
            for o in observers.iter_mut() {
                o.failed(self, &e);
            }
            return Err(e);
        }
        // Every observer finishes, one failing or not (a full disk for one
        // output is not the others'); the first error is returned, and the
        // one that failed is told.
        let mut first: Option<RunError> = None;
        for o in observers.iter_mut() {
            if let Err(e) = o.finish(self) {
                o.failed(self, &e);
                first.get_or_insert(e);
            }
        }
        first.map_or(Ok(()), Err)
    }

    /// The work done so far: remeshes, sparsity patterns built, elements
    /// assembled, symbolic analyses and factorisations. What a scene pays
    /// for, counted rather than timed.
    pub fn work(&self) -> Work {
        let a = self.stepper.integrator.assembler().work();
        let s = self.stepper.integrator.solver_work();
        Work {
            remeshes: self.stats.remesh.0,
            patterns_built: a.patterns_built,
            elements_assembled: a.elements_assembled,
            symbolic_analyses: s.symbolic_analyses,
            factorizations: s.factorizations,
            setups_carried: s.carried,
            solver_iterations: s.iterations,
            // A user's solver may report no work of its own
            // (`LinearSolver::work`'s default): the integrator's count.
            linear_solves: if s.factorizations + s.resolves > 0 {
                s.factorizations + s.resolves
            } else {
                self.stepper.integrator.solves()
            },
            solver_fallbacks: s.fallbacks,
        }
    }

    /// Why a hook stopped the run, if one did.
    pub fn stopped(&self) -> Option<&str> {
        self.stop.as_deref()
    }

    /// Forgets a hook's stop ([`Simulation::stopped`]), so that the next
    /// [`Simulation::run`] goes on (until a hook stops it again). Returns
    /// the reason it had.
    pub fn clear_stop(&mut self) -> Option<String> {
        self.stop.take()
    }

    /// The time-integration parameters in use (those given to
    /// [`Simulation::new`], with the scene's pressure stabilisation when
    /// they set none).
    pub fn step_params(&self) -> StepParams {
        self.stepper.integrator.params
    }

    /// Replaces the linear solver (default: [`pfem_assembly::BlockSolver`];
    /// [`pfem_assembly::DirectSolver`] is sparse Cholesky of the whole
    /// system with an LU fallback). With the pressure stabilisation on, a
    /// solver that does not override `LinearSolver::solve_split` is not
    /// called: the trait's default solves the saddle-point system itself
    /// (see `LinearSolver::solve`).
    pub fn set_solver(&mut self, solver: Box<dyn pfem_assembly::LinearSolver>) {
        let params = self.stepper.integrator.params;
        self.stepper.integrator = Integrator::with_solver(params, solver);
    }

    /// Scene name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The particles.
    pub fn particles(&self) -> &Particles<D> {
        &self.particles
    }

    /// The particles, to change by hand between steps (a hook is the
    /// structured way). After changing velocities or pressures before the
    /// first step, call [`Simulation::initialize_acceleration`]. A set
    /// changed in number ([`Particles::remap`], [`Particles::push`]) is
    /// remeshed by the next step, its first included, and so are positions
    /// moved before the first step (every later step remeshes); until
    /// then the elements are the old set's, or the old positions', and
    /// [`Simulation::fluid_volume`] and [`Simulation::drop_volume`] are
    /// NaN and [`Simulation::meshed_fluid_particles`] marks none (they
    /// panicked after a removal until session 48: the elements named
    /// particles that were gone).
    ///
    /// Water added or removed by hand is booked as remeshing, not as
    /// fluid entering or leaving: the volume correction then restores the
    /// intended volume over the next steps. A source or a sink is a hook
    /// with [`crate::hooks::Hook::sources_fluid`] (an `FnHook` with
    /// `sources_fluid(true)`), or a scene's domain.
    pub fn particles_mut(&mut self) -> &mut Particles<D> {
        self.version = next_state_version();
        &mut self.particles
    }

    /// The elements of the current step.
    pub fn elements(&self) -> &Elements<D> {
        &self.elements
    }

    /// The materials, by index ([`Particles::material`]).
    pub fn materials(&self) -> &[Box<dyn Material<D>>] {
        &self.materials
    }

    /// Body names, by index ([`Particles::body`]).
    pub fn body_names(&self) -> &[String] {
        &self.body_names
    }

    /// Index of body `name`, or [`RunError::UnknownBody`].
    pub fn body_id(&self, name: &str) -> Result<u32, RunError> {
        self.body_names
            .iter()
            .position(|b| b == name)
            .map(|i| i as u32)
            .ok_or_else(|| RunError::UnknownBody {
                name: name.to_string(),
            })
    }

    /// The stages this scene runs.
    pub fn stages(&self) -> Stages {
        self.stages
    }

    /// Whether element `e` (an index into [`crate::Elements::all`]) was kept in
    /// its start-of-step shape through the last step: a fluid sliver, or
    /// an element foreseen flat (ARCHITECTURE.md deviation 13). Such an
    /// element may end the step flat or inverted; the next remeshing
    /// replaces it. Every other element ends a step with a positive
    /// measure (the step is rejected otherwise).
    pub fn kept_in_shape(&self, e: usize) -> bool {
        self.stepper.integrator.assembler().is_frozen(e)
    }

    /// Stage timings and counters.
    pub fn stats(&self) -> &StageStats {
        &self.stats
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.clock.time
    }

    /// Last time step (s).
    pub fn dt(&self) -> f64 {
        self.clock.dt
    }

    /// Accepted steps.
    pub fn steps(&self) -> u64 {
        self.clock.steps
    }

    /// Rejected attempts.
    pub fn rejected(&self) -> u64 {
        self.clock.rejected
    }

    /// Rejected attempts by cause: (inverted element, Picard divergence).
    pub fn rejected_by_cause(&self) -> (u64, u64) {
        self.clock.rejected_by_cause
    }

    /// The volume ledger.
    pub fn volume(&self) -> &VolumeLedger {
        &self.volume
    }

    /// Body force per unit mass (m/s²).
    pub fn gravity(&self) -> Option<Vector<D>> {
        self.gravity
    }

    /// Sets the body force per unit mass (m/s²) from the next step on, as
    /// a hook may ([`HookContext::set_gravity`](crate::hooks::HookContext::set_gravity)):
    /// after a [`Simulation::restore`], whose gravity is the checkpoint's,
    /// a program that means another sets it here. Before the first step
    /// the initial accelerations are taken again under it, but the
    /// fluid's initial pressure stays the scene's (hydrostatic under the
    /// scene's gravity, `pfem_scene::Scene::build`): a scene meant to
    /// start at rest under another gravity is built with it
    /// ([`pfem_scene::Scene::gravity`]), and a gravity ramped from zero
    /// is a scene without gravity and a `BodyForceRamp` hook.
    ///
    /// Errors: [`RunError::InvalidSetting`] for a non-finite component;
    /// the body force is then unchanged.
    pub fn set_gravity(&mut self, g: Option<Vector<D>>) -> Result<(), RunError> {
        if let Some(c) = g.iter().flat_map(|v| v.iter()).find(|c| !c.is_finite()) {
            return Err(RunError::InvalidSetting {
                name: "gravity",
                value: *c,
                reason: "every component must be finite (m/s²)",
            });
        }
        self.gravity = g;
        self.gravity_changed();
        self.version = next_state_version();
        Ok(())
    }

    /// End time (s).
    pub fn end_time(&self) -> f64 {
        self.end_time
    }

    /// Whether the clock has reached the end time: `run` takes no step
    /// then. (A step lands on the end time exactly; a clock restored or
    /// set within a relative 10⁻¹² of it has reached it too.)
    pub fn reached_end_time(&self) -> bool {
        self.end_time - self.clock.time <= END_REACHED * self.end_time
    }

    /// Sets the end time (s), e.g. to continue a finished run.
    pub fn set_end_time(&mut self, t: f64) -> Result<(), RunError> {
        if !(t.is_finite() && t > 0.0) {
            return Err(RunError::InvalidSetting {
                name: "end_time",
                value: t,
                reason: "must be positive and finite",
            });
        }
        // The smallest step goes up with a later end time, so that every
        // step moves the clock (`Simulation::new`).
        let floor = t * MIN_DT_OF_END_TIME;
        if floor > self.controller.dt_max {
            return Err(RunError::InvalidSetting {
                name: "end_time",
                value: t,
                reason: "too late for max_dt: a step of max_dt would not move the clock",
            });
        }
        if self.controller.dt_min < floor {
            self.controller.dt_min = floor;
            self.stepper.integrator.params.min_dt = floor;
        }
        self.end_time = t;
        Ok(())
    }

    /// Output interval (s), `None` for no VTU output.
    pub fn output_interval(&self) -> Option<f64> {
        self.output_interval
    }

    /// Alpha-shape parameters.
    pub fn alpha(&self) -> &AlphaShapeParams {
        &self.alpha
    }

    /// Position of particle `i` when it entered the simulation (m).
    ///
    /// # Panics
    /// Panics if `i` is not below `particles().len()`, as indexing does.
    pub fn initial_position(&self, i: usize) -> Point<D> {
        self.particles.initial_positions()[i]
    }

    /// Particles of body `name`, or [`RunError::UnknownBody`].
    pub fn body_particles(&self, name: &str) -> Result<Vec<usize>, RunError> {
        let id = self.body_id(name)?;
        Ok((0..self.particles.len())
            .filter(|&i| self.particles.body()[i] == id)
            .collect())
    }

    /// Particles of fluid bodies that are in at least one fluid element;
    /// none while the set is not meshed ([`Simulation::particles_mut`]).
    pub fn meshed_fluid_particles(&self) -> Vec<bool> {
        let mut m = vec![false; self.particles.len()];
        if self.volume_without_mesh().is_some() {
            return m; // no fluid, or the elements are the old set's
        }
        for &p in self.elements.fluid() {
            if self.particles.kind()[p as usize] == ParticleKind::Fluid {
                m[p as usize] = true;
            }
        }
        m
    }

    /// Whether materials of this simulation include a solid.
    pub fn has_solid(&self) -> bool {
        self.materials
            .iter()
            .any(|m| m.kind() == MaterialKind::Solid)
    }
}

impl<const D: usize> Simulation<D>
where
    Const<D>: Dim,
{
    /// What decides a run's path besides its scene and state: the time
    /// integration's parameters, the step controller, the linear solver
    /// and the driver options, printed. A restart under other settings
    /// (`--scheme`, `--solver`, `--pressure-stabilisation`, a changed
    /// `max_dt`) would not continue the run it claims to, so
    /// [`Simulation::restore`] refuses it.
    /// (The memory budget is left out: it follows the machine's memory,
    /// and a run may continue on another machine.) `min_dt` is printed as
    /// set, before the end time's floor, unless `floored` (what a
    /// checkpoint before session 47 holds): a run continued to a later end
    /// time raises the floor past 1.1·10⁶ s, and was refused for it.
    fn settings_print(&self, floored: bool) -> String {
        let mut params = self.stepper.integrator.params;
        let mut controller = self.controller;
        if !floored {
            params.min_dt = self.min_dt_set;
            controller.dt_min = self.min_dt_set;
        }
        let options = Options {
            memory_budget: 0.0,
            ..self.options
        };
        // The alpha shape's parameters less `up`, which follows the body
        // force (restored with the state).
        let alpha = pfem_geometry::AlphaShapeParams {
            up: None,
            ..self.alpha
        };
        format!(
            "{:?}; {:?}; solver {}; {:?}; {:?}",
            params,
            controller,
            self.stepper.integrator.solver_settings(),
            options,
            alpha
        )
    }

    /// The run's state as a checkpoint ([`crate::checkpoint`]): sections
    /// [`SIMULATION`] (particles, materials, solid histories, clock, volume ledger,
    /// body force, hook states), [`TIMINGS`], [`SETTINGS`] (the settings the run must be
    /// continued under) and [`CONTACT`] (who takes part in contact, friction by pair). Add an observer's own
    /// sections, encode and write it; [`Simulation::restore`] continues a
    /// simulation built from the same scene and options from it, bit for
    /// bit.
    pub fn checkpoint(&self) -> Checkpoint {
        let mut e = Encoder::new();
        e.u64(D as u64);
        e.str(&self.name);
        e.u64(self.body_names.len() as u64);
        for b in &self.body_names {
            e.str(b);
        }
        e.u64(self.materials.len() as u64);
        for m in &self.materials {
            let (name, kind, density, wave_speed, response) = material_signature(m.as_ref());
            e.str(&name);
            e.u64(kind);
            e.f64(density);
            e.f64(wave_speed);
            e.u64(response);
        }
        let c = &self.clock;
        e.f64(c.time);
        e.f64(c.dt);
        e.u64(c.steps);
        e.u64(c.rejected);
        e.u64(c.rejected_by_cause.0);
        e.u64(c.rejected_by_cause.1);
        self.particles.encode(&mut e);
        self.elements.encode_solid(&mut e);
        self.elements.encode_contact(&mut e);
        let v = &self.volume;
        e.f64(v.initial);
        e.f64(v.remeshing);
        e.f64(v.solution);
        e.f64(v.sources);
        e.f64(v.initial_drops);
        e.u64(v.hooks.len() as u64);
        for (n, dv) in &v.hooks {
            e.str(n);
            e.f64(*dv);
        }
        e.f64(self.volume_now);
        e.bool(self.gravity.is_some());
        let g = self.gravity.unwrap_or_else(Vector::<D>::zeros);
        for k in 0..D {
            e.f64(g[k]);
        }
        e.u64(self.hooks.len() as u64);
        for h in &self.hooks {
            let mut he = Encoder::new();
            h.save_state(&mut he);
            e.str(h.name());
            e.bytes(&he.finish());
        }
        let mut t = Encoder::new();
        let s = &self.stats;
        for (n, sec) in [
            s.remesh,
            s.free_surface,
            s.assemble,
            s.solve,
            s.update,
            s.observe,
            s.hooks,
            s.rejected,
        ] {
            t.u64(n);
            t.f64(sec);
        }
        t.u64(s.pressure_updates);
        t.u64(s.stress_updates);
        let mut ck = Checkpoint::default();
        ck.set(SIMULATION, e.finish());
        ck.set(TIMINGS, t.finish());
        let mut st = Encoder::new();
        st.str(&self.settings_print(false));
        ck.set(SETTINGS, st.finish());
        let mut cs = Encoder::new();
        cs.str(&self.contact_print());
        ck.set(CONTACT, cs.finish());
        ck
    }

    /// Which bodies take part in contact and the friction by pair, as the
    /// checkpoint's [`CONTACT`] section records them.
    fn contact_print(&self) -> String {
        format!(
            "in contact {:?}; friction {:?}",
            self.contact.in_contact, self.contact.friction
        )
    }

    /// Continues from `checkpoint` ([`Simulation::checkpoint`]): this
    /// simulation must be built from the same scene with the same options
    /// (the dimension, scene and body names, materials (name, kind,
    /// density, wave speed, response to two fixed probes) and solid meshes
    /// are checked; [`crate::checkpoint::CheckpointError::Mismatch`]
    /// otherwise). The hooks' [`Hook::start`] runs first on the initial
    /// state (those not started yet: a simulation that has run keeps its
    /// started hooks; for a checkpoint of step 0 none: they all start at
    /// the first step, on the restored state, as a fresh simulation's
    /// do), then each hook's saved state is read back by name (a hook
    /// added since starts fresh if it keeps no state, and is refused if it
    /// does). The fluid mesh is
    /// remade from the restored positions; a stop asked for before the
    /// checkpoint is not carried over. The end time stays this
    /// simulation's, so a finished run may be continued further. The
    /// gravity is the checkpoint's (a hook may have changed it during the
    /// run, [`HookContext::gravity`](crate::hooks::HookContext)), whatever
    /// this simulation's scene gave: a program that wants another sets it
    /// after the restore ([`Simulation::set_gravity`]). What a scene
    /// describes that is not state (its forces' and motion laws' formulas,
    /// its probes) is not compared: `pfem run` keeps its scene file in the
    /// checkpoint and refuses a restart under an edited one.
    ///
    /// A refused checkpoint (any error) leaves the simulation as it was
    /// before the call: everything is read and checked before anything
    /// changes, and what can fail after (a hook reading its state, the
    /// remeshing) puts the state back, each hook reading back its own state
    /// saved just before ([`Hook::save_state`] then [`Hook::restore_state`]
    /// must give the hook back, as every checkpoint assumes). The one
    /// change kept is the hooks' [`Hook::start`], which a fresh simulation
    /// runs at its first step anyway.
    pub fn restore(&mut self, checkpoint: &Checkpoint) -> Result<(), RunError> {
        self.version = next_state_version();
        let mut d = Decoder::new(checkpoint.require(SIMULATION)?);
        let mismatch = |what, checkpoint: String, simulation: String| {
            RunError::Checkpoint(CheckpointError::Mismatch {
                what,
                checkpoint,
                simulation,
            })
        };
        let dim = d.u64()?;
        if dim != D as u64 {
            return Err(mismatch("the dimension", dim.to_string(), D.to_string()));
        }
        let name = d.str()?;
        if name != self.name {
            return Err(mismatch("the scene name", name.into(), self.name.clone()));
        }
        let nb = d.len(8)?;
        let bodies = (0..nb)
            .map(|_| d.str().map(str::to_string))
            .collect::<Result<Vec<_>, _>>()?;
        if bodies != self.body_names {
            return Err(mismatch(
                "the body names",
                bodies.join(", "),
                self.body_names.join(", "),
            ));
        }
        let nm = d.len(0)?;
        if nm != self.materials.len() {
            return Err(mismatch(
                "the number of materials",
                nm.to_string(),
                self.materials.len().to_string(),
            ));
        }
        // Each material's name, kind, density, wave speed and response: a
        // bulk or Young's modulus, a viscosity or a contact stiffness
        // changed in the scene file since the checkpoint would otherwise
        // continue the run as another material.
        for m in &self.materials {
            let saved = (d.str()?.to_string(), d.u64()?, d.f64()?, d.f64()?, d.u64()?);
            let now = material_signature(m.as_ref());
            let same = saved.0 == now.0
                && saved.1 == now.1
                && saved.2.to_bits() == now.2.to_bits()
                && saved.3.to_bits() == now.3.to_bits()
                && saved.4 == now.4;
            if !same {
                let show = |(name, _, rho, c, r): &(String, u64, f64, f64, u64)| {
                    format!(
                        "`{name}` with density {rho} kg/m³, wave speed {c} m/s and response \
                         {r:016x}"
                    )
                };
                return Err(mismatch("a material", show(&saved), show(&now)));
            }
        }
        // Contact (checkpoints of session 36 on): a restart that turned
        // contact for clamped solids on or off, or changed a friction
        // pair, would otherwise go on as another run.
        if let Some(bytes) = checkpoint.section(CONTACT) {
            let mut cd = Decoder::new(bytes);
            let saved = cd.str()?.to_string();
            cd.end()?;
            let now = self.contact_print();
            if saved != now {
                return Err(mismatch("the contact settings", saved, now));
            }
        }
        // The settings (format 3 checkpoints of session 35 on; older
        // ones have no such section and are not checked).
        if let Some(bytes) = checkpoint.section(SETTINGS) {
            let mut sd = Decoder::new(bytes);
            let saved = sd.str()?.to_string();
            sd.end()?;
            let now = self.settings_print(false);
            if saved != now && saved != self.settings_print(true) {
                // The first setting that differs, `name: value` each.
                let (a, b) = (setting_items(&saved), setting_items(&now));
                let at = (0..a.len().max(b.len()))
                    .find(|&i| a.get(i) != b.get(i))
                    .unwrap_or(0);
                let show = |v: &[String]| v.get(at).cloned().unwrap_or_default();
                return Err(mismatch(
                    "a time-integration, solver or driver setting",
                    show(&a),
                    show(&b),
                ));
            }
        }
        let clock = Clock {
            time: d.f64()?,
            dt: d.f64()?,
            steps: d.u64()?,
            rejected: d.u64()?,
            rejected_by_cause: (d.u64()?, d.u64()?),
        };
        // A checksum guards against damage, not against an edited file:
        // a time or a state that is not a number would run on as one.
        if !(clock.time.is_finite() && clock.time >= 0.0 && clock.dt.is_finite() && clock.dt >= 0.0)
        {
            return Err(CheckpointError::Corrupt(format!(
                "its time {} s and step {} s must be finite, not negative",
                clock.time, clock.dt
            ))
            .into());
        }
        let particles = Particles::<D>::decode(&mut d)?;
        let finite = |v: &[Vector<D>]| v.iter().position(|v| !v.iter().all(|c| c.is_finite()));
        if let Some(i) = finite(particles.x())
            .or_else(|| finite(particles.initial_positions()))
            .or_else(|| finite(particles.v()))
            .or_else(|| finite(particles.a()))
            .or_else(|| particles.pressure().iter().position(|p| !p.is_finite()))
        {
            return Err(CheckpointError::Corrupt(format!(
                "particle {i}'s position, initial position, velocity, acceleration or pressure is not finite"
            ))
            .into());
        }
        // (Only the prescribed components' velocities: the step reads
        // those alone, so a run could write a checkpoint its own restore
        // refused.)
        let c = particles.constraints();
        let prescribed_not_finite = || {
            (0..c.velocity.len().min(c.mask.len())).find(|&i| {
                (0..D).any(|k| c.mask[i] & (1 << k) != 0 && !c.velocity[i][k].is_finite())
            })
        };
        if let Some(i) = particles
            .spacing()
            .iter()
            .position(|h| !(h.is_finite() && *h > 0.0))
            .or_else(prescribed_not_finite)
        {
            return Err(CheckpointError::Corrupt(format!(
                "particle {i}'s spacing or prescribed velocity is not a finite (positive) number"
            ))
            .into());
        }
        // Walls and solids keep their indices for the whole run.
        let fixed = |p: &Particles<D>| {
            p.kind()
                .iter()
                .zip(p.body())
                .filter(|(k, _)| **k != ParticleKind::Fluid)
                .map(|(k, b)| (*k, *b))
                .collect::<Vec<_>>()
        };
        // ... and come first: a fluid particle moved before them would
        // shift every solid element's and the contact stash's indices.
        let prefix = particles.fixed_prefix();
        if let Some(i) = particles.kind()[prefix..]
            .iter()
            .position(|k| *k != ParticleKind::Fluid)
        {
            return Err(CheckpointError::Corrupt(format!(
                "particle {} is a wall's or a solid's after fluid particle {prefix}: walls and solids come first",
                prefix + i
            ))
            .into());
        }
        if fixed(&particles) != fixed(&self.particles) {
            return Err(mismatch(
                "the count of wall and solid particles (another spacing or geometry?)",
                fixed(&particles).len().to_string(),
                fixed(&self.particles).len().to_string(),
            ));
        }
        // ... where they started: a wall or a solid moved in the scene
        // since the checkpoint (same count) ran on at the checkpoint's
        // place without a word (a review of session 53: a wall moved by
        // 4 cm). To 10⁻⁶ of a spacing, against round-off.
        let (old, new) = (
            particles.initial_positions(),
            self.particles.initial_positions(),
        );
        if let Some(i) =
            (0..prefix).find(|&i| (old[i] - new[i]).norm() > 1e-6 * self.particles.spacing()[i])
        {
            let body = self
                .body_names
                .get(self.particles.body()[i] as usize)
                .cloned()
                .unwrap_or_default();
            let at = |p: &Point<D>| {
                let c: Vec<String> = p.iter().map(|c| format!("{c}")).collect();
                format!(
                    "particle {i} of body `{body}` starting at ({})",
                    c.join(", ")
                )
            };
            return Err(mismatch(
                "a wall or solid particle's start",
                at(&old[i]),
                at(&new[i]),
            ));
        }
        if particles
            .material()
            .iter()
            .any(|&m| m != crate::particles::NO_MATERIAL && m as usize >= self.materials.len())
            || particles.body().iter().any(|&b| b as usize >= nb)
        {
            return Err(CheckpointError::Corrupt(
                "a particle's material or body is out of range".into(),
            )
            .into());
        }
        let solid_history = self.elements.decode_solid(&mut d)?;
        let stash = Elements::<D>::decode_contact(&mut d, particles.len())?;
        let mut volume = VolumeLedger {
            initial: d.f64()?,
            remeshing: d.f64()?,
            solution: d.f64()?,
            sources: d.f64()?,
            initial_drops: d.f64()?,
            hooks: Vec::new(),
        };
        for _ in 0..d.len(16)? {
            let n = d.str()?.to_string();
            volume.hooks.push((n, d.f64()?));
        }
        let volume_now = d.f64()?;
        let has_gravity = d.bool()?;
        let mut g = Vector::<D>::zeros();
        for k in 0..D {
            g[k] = d.f64()?;
        }
        // The rest of the state must be numbers too: a gravity, a solid's
        // stress or internal variable, a contact element's history or the
        // volume ledger that is not would run on as one (or turn the
        // volume correction off without a word).
        let what = if !g.iter().all(|c| c.is_finite()) {
            Some("its gravity is not finite".to_string())
        } else if let Some(e) = solid_history.iter().position(|h| !h.is_finite()) {
            Some(format!(
                "solid element {e}'s stress or internal variables are not finite"
            ))
        } else if let Some(e) = stash.1.iter().position(|h| !h.is_finite()) {
            Some(format!("contact element {e}'s history is not finite"))
        } else if ![
            volume.initial,
            volume.remeshing,
            volume.solution,
            volume.sources,
            volume.initial_drops,
            volume_now,
        ]
        .iter()
        .chain(volume.hooks.iter().map(|(_, v)| v))
        .all(|v| v.is_finite())
        {
            Some("its fluid volume ledger is not finite".to_string())
        } else if !(0.0..=volume.initial.max(0.0) * (1.0 + 1e-9)).contains(&volume.initial_drops) {
            // A share of drops outside [0, initial] would switch the
            // volume correction off (or on) without a word.
            Some(format!(
                "its drops' share {} of the initial volume {} is outside [0, the initial volume]",
                volume.initial_drops, volume.initial
            ))
        } else {
            None
        };
        if let Some(what) = what {
            return Err(CheckpointError::Corrupt(what).into());
        }
        let nh = d.len(16)?;
        let mut saved = Vec::with_capacity(nh);
        for _ in 0..nh {
            saved.push((d.str()?, d.bytes()?));
        }
        d.end()?;
        // The k-th hook of a name takes the k-th saved state of that name.
        let mut used = vec![false; self.hooks.len()];
        let mut hook_states = Vec::with_capacity(saved.len());
        for (name, bytes) in saved {
            let slot = self
                .hooks
                .iter()
                .enumerate()
                .position(|(i, h)| !used[i] && h.name() == name);
            match slot {
                Some(i) => {
                    used[i] = true;
                    hook_states.push((i, bytes));
                }
                None if bytes.is_empty() => {}
                None => {
                    return Err(mismatch(
                        "the hooks",
                        format!("a state for hook `{name}`"),
                        format!("no hook `{name}`"),
                    ))
                }
            }
        }
        // A hook with a state that the checkpoint's run did not have (a
        // motion law, an inflow or particle management added since) would
        // start fresh mid-run: another run, not this one continued.
        for (i, hook) in self.hooks.iter().enumerate() {
            if used[i] {
                continue;
            }
            let mut e = Encoder::new();
            hook.save_state(&mut e);
            if !e.finish().is_empty() {
                return Err(mismatch(
                    "the hooks",
                    format!("no state for hook `{}`", hook.name()),
                    format!("a hook `{}` with a state", hook.name()),
                ));
            }
        }
        let stats = match checkpoint.section(TIMINGS) {
            Some(t) => {
                let mut d = Decoder::new(t);
                let mut pair =
                    || -> Result<(u64, f64), CheckpointError> { Ok((d.u64()?, d.f64()?)) };
                let s = StageStats {
                    remesh: pair()?,
                    free_surface: pair()?,
                    assemble: pair()?,
                    solve: pair()?,
                    update: pair()?,
                    observe: pair()?,
                    hooks: pair()?,
                    rejected: pair()?,
                    pressure_updates: d.u64()?,
                    stress_updates: d.u64()?,
                };
                d.end()?;
                Some(s)
            }
            None => None,
        };
        // Nothing has changed so far. Hooks see the scene's initial state
        // at their start, as in the uninterrupted run; their saved state is
        // read after. (A set changed by hand before is meshed first, as
        // `run` and `step` do: the hooks' start read the old set's mesh.)
        self.mesh_a_set_changed_by_hand(false)?;
        // A checkpoint of step 0 holds the scene's initial state, before
        // the hooks' start acted on it or after (every bundled `start` sets
        // what it sets again alike): its hooks start at the first step, on
        // the restored state, as a fresh simulation's do. Before session
        // 49 they started here and the restored particles then replaced
        // what they had set (a moving wall's velocity at t = 0: the
        // restored run's first step differed, a review).
        let start_at_first_step = clock.steps == 0;
        if !start_at_first_step {
            self.start_hooks_then(false)?;
        }
        let before = Backup {
            particles: self.particles.clone(),
            elements: self.elements.clone(),
            contact: self.contact.clone(),
            tess: self.stepper.tess.clone(),
            near: self.stepper.near.clone(),
            stop: self.stop.clone(),
            clock: self.clock,
            volume: self.volume.clone(),
            volume_now: self.volume_now,
            gravity: self.gravity,
            body_force: self.stages.body_force,
            meshed: self.meshed,
            hooks: self
                .hooks
                .iter()
                .map(|h| {
                    let mut e = Encoder::new();
                    h.save_state(&mut e);
                    e.finish()
                })
                .collect(),
        };
        let result = (|| -> Result<(), RunError> {
            for (i, bytes) in hook_states {
                let mut hd = Decoder::new(bytes);
                self.hooks[i].restore_state(&mut hd)?;
                hd.end()?;
            }
            self.particles = particles;
            // The masses of the run that wrote the checkpoint: its own
            // initial positions, not the scene's (which may have been
            // edited and still pass the connectivity check).
            self.elements
                .set_reference_volumes(self.particles.initial_positions());
            self.clock = clock;
            self.volume = volume;
            self.volume_now = volume_now;
            self.gravity = has_gravity.then_some(g);
            self.gravity_changed();
            self.stop = None;
            self.elements.set_solid_history(&solid_history);
            self.elements.set_stash(stash);
            self.elements.clear_fluid();
            // The checkpoint's particles are checked as a changed set's
            // (`check_fluid_particles`): its generation may equal the one
            // this simulation last meshed.
            self.meshed = u64::MAX;
            self.remesh()?;
            // The next step carries from the stash, not from this range
            // re-formed from it; but the first step does not remesh: it
            // solves this range, as a new simulation's first step solves
            // the one `new` formed, and keeps its tractions (session 47's
            // review: a checkpoint of step 0 lost them).
            if self.clock.steps > 0 {
                self.elements.keep_stash();
            }
            Ok(())
        })();
        match result {
            Ok(()) => {
                if start_at_first_step {
                    self.started = 0;
                }
                // The solver's carried preconditioners name particles by
                // index: the next step tells it the indices may have
                // changed (only when they did: a refused checkpoint left
                // them, and before session 49 it dropped the carried
                // hierarchies all the same).
                self.stepper.numbering = Some(u64::MAX);
                if let Some(s) = stats {
                    self.stats = s;
                }
            }
            Err(_) => {
                self.particles = before.particles;
                self.elements = before.elements;
                self.contact = before.contact;
                self.stepper.tess = before.tess;
                self.stepper.near = before.near;
                self.stop = before.stop;
                self.meshed = before.meshed;
                self.clock = before.clock;
                self.volume = before.volume;
                self.volume_now = before.volume_now;
                self.gravity = before.gravity;
                self.stages.body_force = before.body_force;
                self.alpha.up = up_of(before.gravity);
                for (h, bytes) in self.hooks.iter_mut().zip(&before.hooks) {
                    // A hook's own state read back: cannot fail for a hook
                    // whose save and restore agree; if it did, the
                    // checkpoint's error is still the one to report.
                    let _ = h.restore_state(&mut Decoder::new(bytes));
                }
            }
        }
        result
    }
}

/// The state [`Simulation::restore`] puts back when it refuses a
/// checkpoint.
struct Backup<const D: usize>
where
    Const<D>: Dim,
{
    particles: Particles<D>,
    elements: Elements<D>,
    contact: ContactSetup<D>,
    /// The last tessellation, which a hook's `manage_particles` reads in a
    /// step that does not remesh first.
    tess: Tessellation,
    near: Vec<u32>,
    stop: Option<String>,
    clock: Clock,
    volume: VolumeLedger,
    volume_now: f64,
    gravity: Option<Vector<D>>,
    body_force: bool,
    hooks: Vec<Vec<u8>>,
    meshed: u64,
}

/// The smallest `min_dt` over the end time: `2⁻⁵⁰`, four units in the
/// last place, so that every step moves the clock.
const MIN_DT_OF_END_TIME: f64 = 1.0 / (1u64 << 50) as f64;

/// A step within this fraction of itself of the end time is stretched to
/// it (`Simulation::step`; a rest shorter than two steps is taken in two
/// halves): the last step lands on the end time, with no sliver after it.
const END_SNAP: f64 = 1e-6;

/// A run has reached its end time when less than this share of it is
/// left (relative: an absolute 10⁻¹² s took no step of a run 5·10⁻¹³ s
/// long).
const END_REACHED: f64 = 1e-12;

/// What a checkpoint records of a material to recognise it: its name, kind
/// (0 fluid, 1 solid), density and wave speed (which moves with its bulk
/// or Young's modulus).
fn material_signature<const D: usize>(m: &dyn Material<D>) -> (String, u64, f64, f64, u64)
where
    Const<D>: Dim,
{
    let kind = match m.kind() {
        MaterialKind::Fluid => 0,
        MaterialKind::Solid => 1,
    };
    (
        m.name().to_string(),
        kind,
        m.density(),
        m.wave_speed(),
        material_response(m),
    )
}

/// Each solid element's history at `t₀`: its material's
/// [`Material::initial_history`] at the element's centroid in the initial
/// configuration. One that is not finite is refused, naming the body.
fn initial_solid_history<const D: usize>(
    elements: &Elements<D>,
    materials: &[Box<dyn Material<D>>],
    particles: &Particles<D>,
    body_names: &[String],
) -> Result<Vec<History<D>>, SceneError>
where
    Const<D>: Dim,
{
    let x0 = particles.initial_positions();
    let mut start = Vec::with_capacity(elements.solid_material().len());
    for (el, &m) in elements
        .solid()
        .chunks_exact(D + 1)
        .zip(elements.solid_material())
    {
        let centroid = el
            .iter()
            .fold(Point::<D>::zeros(), |c, &i| c + x0[i as usize])
            / (D + 1) as f64;
        let h = materials[m as usize].initial_history(&centroid);
        if !h.is_finite() {
            let body = particles.body()[el[0] as usize] as usize;
            return Err(SceneError::InvalidMaterial {
                body: body_names.get(body).cloned().unwrap_or_default(),
                source: MaterialError::NonFiniteInitialHistory,
            });
        }
        start.push(h);
    }
    Ok(start)
}

/// A fingerprint of a material: its [`Material::parameters`], the names
/// of its internal variables, and what it
/// answers ([`Material::unified`], [`Material::update_history`],
/// [`Material::update_pressure`]) to two fixed probes, at rest and under a
/// stressed shearing compression with internal variables. The parameters
/// the trait does not expose (a viscosity, a shear modulus, a yield stress
/// the probes do not reach, a contact stiffness) change it, and the same
/// material gives the same bits. (Before session 39 the parameters and
/// `update_history` were not in it: two plastic solids differing only in a
/// yield stress above the probe's stress had one fingerprint. The `Debug`
/// text, tried first, is not deterministic for every material: a map's
/// order, an address.)
fn material_response<const D: usize>(m: &dyn Material<D>) -> u64
where
    Const<D>: Dim,
{
    let dt = 1e-3;
    let f = Tensor::<D>::from_fn(|i, j| {
        if i == j {
            1.0 - 1e-4
        } else {
            1e-3 * (i as f64 + 1.0)
        }
    });
    let d = Tensor::<D>::from_fn(|i, j| if i == j { -0.1 } else { 0.5 });
    let stressed = History::<D> {
        stress: Tensor::<D>::from_fn(|i, j| if i == j { -2e4 } else { 5e3 }),
        stress_zz: -2e4,
        pressure: 2e4,
        // Internal variables in (0, 1): a contact element pressed to 0.9
        // of its gap with friction 0.5, a plastic strain…
        internal: [0.9, 0.5, 0.6, 0.8, 0.3, 1e-3, 2e-3, 3e-3],
    };
    let mut bytes: Vec<u8> = m
        .parameters()
        .iter()
        .flat_map(|v| v.to_bits().to_le_bytes())
        .collect();
    for name in m.internal_variables() {
        bytes.extend_from_slice(name.as_bytes());
        bytes.push(0);
    }
    for (kin, history) in [
        (Kinematics::<D>::at_rest(dt), History::<D>::default()),
        (Kinematics::<D>::new(f, d, dt), stressed),
    ] {
        let u = m.unified(&kin, &history);
        let layer = u.layer.map(|l| (l.normal, l.slip));
        let values = [u.mu, u.kappa, u.sigma_hat_zz]
            .into_iter()
            .chain(u.sigma_hat.iter().copied())
            .chain(
                layer
                    .iter()
                    .flat_map(|(n, m)| n.iter().chain(m.iter()).copied()),
            )
            .chain([m.update_pressure(history.pressure, -0.1, dt)]);
        let mut after = history;
        m.update_history(&kin, &mut after);
        let after = after
            .stress
            .iter()
            .copied()
            .chain([after.stress_zz, after.pressure])
            .chain(after.internal);
        for v in values.chain(after) {
            bytes.extend_from_slice(&v.to_bits().to_le_bytes());
        }
    }
    crate::checkpoint::fingerprint(&bytes)
}

/// Replaces the accelerations `a` of the particles `members` (index, mass)
/// by their rigid part: the translation and rotation whose accelerations
/// best fit them in the mass-weighted least-squares sense (net force and
/// torque about the centre of mass kept).
fn rigid_part<const D: usize>(members: &[(usize, f64)], x: &[Point<D>], a: &mut [Vector<D>])
where
    Const<D>: Dim,
{
    let mass: f64 = members.iter().map(|&(_, m)| m).sum();
    if members.is_empty() || mass.is_nan() || mass <= 0.0 {
        return;
    }
    let centre = members
        .iter()
        .fold(Vector::<D>::zeros(), |c, &(i, m)| c + x[i] * m)
        / mass;
    let mean = members
        .iter()
        .fold(Vector::<D>::zeros(), |c, &(i, m)| c + a[i] * m)
        / mass;
    let r = |i: usize| x[i] - centre;
    if D == 2 {
        // α = Σ m (r × a) / Σ m |r|²; a = ā + α ẑ × r.
        let (mut torque, mut inertia) = (0.0, 0.0);
        for &(i, m) in members {
            let q = r(i);
            torque += m * (q[0] * a[i][1] - q[1] * a[i][0]);
            inertia += m * q.norm_squared();
        }
        let alpha = if inertia > 0.0 { torque / inertia } else { 0.0 };
        for &(i, _) in members {
            let q = r(i);
            a[i] = mean;
            a[i][0] -= alpha * q[1];
            a[i][1] += alpha * q[0];
        }
    } else {
        // I α = Σ m r × a, I = Σ m (|r|² 1 − r rᵀ); a = ā + α × r.
        let v3 = |v: Vector<D>| nalgebra::Vector3::new(v[0], v[1], v[2]);
        let mut torque = nalgebra::Vector3::zeros();
        let mut inertia = nalgebra::Matrix3::zeros();
        for &(i, m) in members {
            let q = v3(r(i));
            torque += q.cross(&v3(a[i])) * m;
            inertia += (nalgebra::Matrix3::identity() * q.norm_squared() - q * q.transpose()) * m;
        }
        let alpha = inertia
            .try_inverse()
            .map_or(nalgebra::Vector3::zeros(), |inv| inv * torque);
        for &(i, _) in members {
            let spin = alpha.cross(&v3(r(i)));
            a[i] = mean;
            for k in 0..3 {
                a[i][k] += spin[k];
            }
        }
    }
}

/// The alpha shape's `up`: against a non-zero body force, 3 components
/// whatever the dimension.
fn up_of<const D: usize>(gravity: Option<Vector<D>>) -> Option<[f64; 3]>
where
    Const<D>: Dim,
{
    // Scaled by its largest component first: the norm of a gravity of
    // 10²⁰⁰ overflows (an `up` of zero, refused by the alpha shape with a
    // confusing error) and that of 10⁻²⁰⁰ underflows (no `up` at all).
    gravity
        .map(|g| (g, g.amax()))
        .filter(|(_, m)| *m > 0.0 && m.is_finite())
        .map(|(g, m)| {
            let g = g / m;
            let u = -g / g.norm();
            [u[0], u[1], if D == 3 { u[D - 1] } else { 0.0 }]
        })
}

/// The material most of a fluid element's fluid nodes have, ties to the
/// lower index; [`NO_MATERIAL`] with no fluid node. Independent of the
/// order of `el`.
pub(crate) fn majority_fluid_material(el: &[u32], kind: &[ParticleKind], material: &[u16]) -> u16 {
    let fluid = |p: &u32| kind[*p as usize] == ParticleKind::Fluid;
    let mut best = (0usize, NO_MATERIAL);
    for p in el.iter().filter(|p| fluid(p)) {
        let m = material[*p as usize];
        let count = el
            .iter()
            .filter(|q| fluid(q) && material[**q as usize] == m)
            .count();
        if count > best.0 || (count == best.0 && m < best.1) {
            best = (count, m);
        }
    }
    best.1
}

/// The next number of [`Simulation::state_version`], unique in the process.
fn next_state_version() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The direction against gravity whatever its size: 10²⁰⁰ overflowed
    /// the norm (an `up` of zero) and 10⁻²⁰⁰ underflowed it (no `up`).
    #[test]
    fn up_is_against_gravity_at_any_size() {
        for s in [1e-200, 1.0, 9.81, 1e200] {
            let up = up_of(Some(Vector::<3>::new(0.0, -3.0 * s, -4.0 * s))).unwrap();
            assert!(
                (up[1] - 0.6).abs() < 1e-15 && (up[2] - 0.8).abs() < 1e-15,
                "{s}: {up:?}"
            );
        }
        assert_eq!(up_of(Some(Vector::<2>::zeros())), None);
        assert_eq!(up_of::<2>(None), None);
    }

    /// A fluid element takes its fluid nodes' majority material, whatever
    /// their order (session 42: the first fluid node decided, so a
    /// triangle of two water nodes and one oil node was oil under one of
    /// its three rotations), ties to the lower index.
    #[test]
    fn a_fluid_element_takes_its_nodes_majority_material() {
        use ParticleKind::{Fluid, Wall};
        let kind = [Fluid, Fluid, Fluid, Wall];
        let material = [3u16, 3, 1, NO_MATERIAL];
        for el in [[0u32, 1, 2], [1, 2, 0], [2, 0, 1]] {
            assert_eq!(majority_fluid_material(&el, &kind, &material), 3);
        }
        for el in [[2u32, 0, 3], [3, 0, 2], [0, 3, 2]] {
            assert_eq!(majority_fluid_material(&el, &kind, &material), 1);
        }
        assert_eq!(
            majority_fluid_material(&[3, 3, 3], &kind, &material),
            NO_MATERIAL
        );
    }

    /// The rigid part keeps a rigid field (translation + rotation) as it is,
    /// keeps the net force and torque of any field, and removes a field
    /// with neither (a body squeezed from two sides).
    #[test]
    fn the_rigid_part_keeps_net_force_and_torque() {
        // 2D: four particles of unequal mass.
        let x = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(1.0, 2.0),
            Point::<2>::new(0.0, 2.0),
        ];
        let members = [(0, 1.0), (1, 2.0), (2, 1.5), (3, 0.5)];
        let rigid = |p: &Point<2>| Vector::<2>::new(0.3 - 0.7 * p[1], -1.0 + 0.7 * p[0]);
        let mut a: Vec<Vector<2>> = x.iter().map(rigid).collect();
        rigid_part::<2>(&members, &x, &mut a);
        for (p, ai) in x.iter().zip(&a) {
            assert!((ai - rigid(p)).norm() < 1e-12);
        }
        // Squeezed along x at mid-height: no net force, no torque.
        let mut a = vec![
            Vector::<2>::new(1.0, 0.0),
            Vector::<2>::new(-0.5, 0.0),
            Vector::<2>::new(-1.0 / 1.5, 0.0),
            Vector::<2>::new(2.0, 0.0),
        ];
        rigid_part::<2>(&members, &x, &mut a);
        for ai in &a {
            assert!(ai.norm() < 1e-12, "{ai}");
        }
        // 3D: a random field keeps its net force and torque.
        let x3 = [
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(1.0, 0.1, 0.0),
            Point::<3>::new(0.2, 1.0, 0.3),
            Point::<3>::new(0.1, 0.2, 1.0),
            Point::<3>::new(1.0, 1.0, 1.0),
        ];
        let m3 = [(0, 1.0), (1, 2.0), (2, 0.5), (3, 1.5), (4, 1.0)];
        let before: Vec<Vector<3>> = (0..5)
            .map(|i| Vector::<3>::new((i as f64).sin(), (2.0 * i as f64).cos(), 0.3 * i as f64))
            .collect();
        let mut after = before.clone();
        rigid_part::<3>(&m3, &x3, &mut after);
        let moments = |a: &[Vector<3>]| {
            let f: Vector<3> = m3.iter().map(|&(i, m)| a[i] * m).sum();
            let t: Vector<3> = m3.iter().map(|&(i, m)| x3[i].cross(&a[i]) * m).sum();
            (f, t)
        };
        let (f0, t0) = moments(&before);
        let (f1, t1) = moments(&after);
        assert!((f0 - f1).norm() < 1e-12 && (t0 - t1).norm() < 1e-12);
        // And it is rigid: the accelerations' gradient is antisymmetric.
        let g = |i: usize, j: usize| (after[i] - after[j]).dot(&(x3[i] - x3[j]));
        assert!(g(1, 0).abs() < 1e-12 && g(4, 2).abs() < 1e-12);
    }

    /// A settings print's items keep an array whole.
    #[test]
    fn setting_items_keep_arrays_whole() {
        let items = super::setting_items(
            "scheme: Bossak; solver: block {target: 1e-9, multigrid_from: [1000, 100], split_from: 0}",
        );
        assert_eq!(
            items,
            [
                "scheme: Bossak",
                "solver: block",
                "target: 1e-9",
                "multigrid_from: [1000, 100]",
                "split_from: 0"
            ]
        );
    }
}
