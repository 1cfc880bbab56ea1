//! Scenes: the bodies of a simulation (fluids, solids, walls), their
//! materials, geometry and particle spacing, the body forces and the run
//! settings. Built with [`Scene::new`] and its builder methods, validated by
//! [`Scene::validate`] before any step runs.

use pfem_constitutive::{Material, MaterialKind};
use pfem_core::{Const, Dim, ParticleKind, Point, Vector};
use pfem_geometry::ParticleManagementParams;

use crate::SceneError;

/// Where a body's particles are.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry<const D: usize>
where
    Const<D>: Dim,
{
    /// An axis-aligned box (rectangle in 2D) filled with a lattice of
    /// spacing `h` whose nodes include the box's corners.
    Box {
        /// Lower corner (m).
        min: Point<D>,
        /// Upper corner (m).
        max: Point<D>,
    },
    /// A disk (2D) or ball (3D): for a fluid the lattice nodes inside it;
    /// for a solid or a wall concentric rings or shells a spacing apart
    /// ([`crate::lattice::shell_points`]), round at the particle scale.
    Ball {
        /// Centre (m).
        center: Point<D>,
        /// Radius (m).
        radius: f64,
    },
    /// A right circular cylinder (3D only) standing on `base` (the centre
    /// of its bottom disk) along coordinate axis `axis` (0, 1 or 2): the
    /// disks of lattice nodes inside `radius`, one every spacing from
    /// `base` to `base + height` along the axis. In 2D it is rejected by
    /// [`Scene::validate`] (use a box).
    Cylinder {
        /// Centre of the bottom disk (m).
        base: Point<D>,
        /// Coordinate axis of the cylinder (0, 1 or 2).
        axis: usize,
        /// Radius (m).
        radius: f64,
        /// Height along the axis (m).
        height: f64,
    },
    /// The user's own particles (m).
    Particles(Vec<Point<D>>),
    /// The lattice nodes inside a closed boundary: a polygon in 2D
    /// ([`Geometry::polygon`]) or a closed triangle surface in 3D
    /// ([`Geometry::stl`]); see [`crate::surface`].
    Surface(crate::surface::ClosedSurface<D>),
}

impl Geometry<2> {
    /// The inside of the closed polygon through `points` (m), in order
    /// (either orientation; the last point is joined to the first).
    ///
    /// ```
    /// use pfem_core::Point;
    /// use pfem_scene::Geometry;
    /// let wedge = Geometry::polygon(vec![
    ///     Point::<2>::new(0.0, 0.0),
    ///     Point::<2>::new(0.2, 0.0),
    ///     Point::<2>::new(0.2, 0.05),
    /// ]);
    /// let (lo, hi) = wedge.bounds();
    /// assert_eq!(hi[0] - lo[0], 0.2);
    /// ```
    pub fn polygon(points: Vec<Point<2>>) -> Self {
        Geometry::Surface(crate::surface::ClosedSurface::polygon(points))
    }
}

impl Geometry<3> {
    /// The inside of the closed triangle surface of an STL file (ASCII or
    /// binary), its coordinates times `scale` (0.001 for millimetres) plus
    /// `offset` (m). The surface is checked when the scene is validated.
    pub fn stl(
        path: impl AsRef<std::path::Path>,
        scale: f64,
        offset: [f64; 3],
    ) -> Result<Self, crate::SceneError> {
        if !(scale.is_finite() && scale > 0.0) || offset.iter().any(|v| !v.is_finite()) {
            return Err(crate::SceneError::InvalidGeometry {
                body: String::new(),
                why: format!("STL scale {scale} must be positive and the offset finite"),
            });
        }
        crate::surface::ClosedSurface::read_stl(path.as_ref(), scale, offset)
            .map(Geometry::Surface)
            .map_err(|why| crate::SceneError::InvalidGeometry {
                body: String::new(),
                why,
            })
    }
}

impl<const D: usize> Geometry<D>
where
    Const<D>: Dim,
{
    /// The measure of the region drawn (m³; m² per metre of depth in 2D):
    /// a box's, a disk's or ball's, a cylinder's (3D), the area or volume a
    /// closed surface encloses; `None` for a list of particles. A fluid's
    /// mass is its particles' mesh's, which spans their centres: a
    /// lattice filling a curved or slanted boundary meshes less (a ball of
    /// radius 5 spacings 25 % less; `pfem check` warns).
    pub fn measure(&self) -> Option<f64> {
        use std::f64::consts::PI;
        match self {
            Geometry::Box { min, max } => Some((max - min).iter().product()),
            Geometry::Ball { radius, .. } => Some(if D == 2 {
                PI * radius * radius
            } else {
                4.0 / 3.0 * PI * radius.powi(3)
            }),
            Geometry::Cylinder { radius, height, .. } => Some(PI * radius * radius * height),
            Geometry::Particles(_) => None,
            Geometry::Surface(s) => Some(s.enclosed_measure()),
        }
    }

    /// Lower and upper corners of the bounding box.
    pub fn bounds(&self) -> (Point<D>, Point<D>) {
        match self {
            Geometry::Box { min, max } => (*min, *max),
            Geometry::Ball { center, radius } => (
                center - Vector::<D>::repeat(*radius),
                center + Vector::<D>::repeat(*radius),
            ),
            Geometry::Cylinder {
                base,
                axis,
                radius,
                height,
            } => {
                let mut lo = base - Vector::<D>::repeat(*radius);
                let mut hi = base + Vector::<D>::repeat(*radius);
                if *axis < D {
                    lo[*axis] = base[*axis];
                    hi[*axis] = base[*axis] + height;
                }
                (lo, hi)
            }
            Geometry::Particles(p) => {
                let mut lo = Point::<D>::repeat(f64::INFINITY);
                let mut hi = Point::<D>::repeat(f64::NEG_INFINITY);
                for q in p {
                    lo = lo.inf(q);
                    hi = hi.sup(q);
                }
                (lo, hi)
            }
            Geometry::Surface(s) => s.bounds(),
        }
    }
}

/// Prescribed motion of a wall.
#[derive(Debug, Clone)]
pub enum WallMotion<const D: usize>
where
    Const<D>: Dim,
{
    /// At rest.
    Fixed,
    /// Moving at a constant velocity (m/s).
    Velocity(Vector<D>),
    /// Moving rigidly along a law of time ([`crate::motion::Sinusoidal`]: a
    /// wave-maker; [`crate::motion::PiecewiseLinear`]: a table). The driver
    /// follows it with a `PrescribedMotion` hook: velocity prescribed for
    /// each step, positions set to the law's after it.
    Law(std::sync::Arc<dyn crate::motion::MotionLaw<D>>),
}

/// Where a solid is clamped (its velocity held at zero).
#[derive(Clone)]
pub enum Clamp<const D: usize>
where
    Const<D>: Dim,
{
    /// The solid's particles inside this box (lower and upper corners, m;
    /// a tolerance of 10⁻¹² m).
    Box(Point<D>, Point<D>),
    /// The solid's particles at whose initial position the predicate holds.
    Where(std::sync::Arc<dyn Fn(&Point<D>) -> bool + Send + Sync>),
}

impl<const D: usize> Clamp<D>
where
    Const<D>: Dim,
{
    /// Whether the particle at `p` is clamped.
    pub fn holds(&self, p: &Point<D>) -> bool {
        match self {
            Clamp::Box(lo, hi) => (0..D).all(|k| p[k] >= lo[k] - 1e-12 && p[k] <= hi[k] + 1e-12),
            Clamp::Where(f) => f(p),
        }
    }
}

impl<const D: usize> std::fmt::Debug for Clamp<D>
where
    Const<D>: Dim,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Clamp::Box(lo, hi) => write!(f, "Clamp::Box({:?}, {:?})", lo.as_slice(), hi.as_slice()),
            Clamp::Where(_) => write!(f, "Clamp::Where(..)"),
        }
    }
}

/// A function of a particle's coordinates (m).
pub type FieldFn<T> = dyn Fn(&[f64]) -> T + Send + Sync;

/// A field over a body's particles at `t = 0`: a function of the
/// particle's position.
#[derive(Clone)]
pub struct InitialField<T>(pub std::sync::Arc<FieldFn<T>>);

impl<T> std::fmt::Debug for InitialField<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "InitialField(..)")
    }
}

/// A body of a scene.
#[derive(Debug)]
pub struct Body<const D: usize>
where
    Const<D>: Dim,
{
    /// Name used in messages and output.
    pub name: String,
    /// Fluid, solid or wall.
    pub kind: ParticleKind,
    /// Material (none for a wall).
    pub material: Option<Box<dyn Material<D>>>,
    /// Where its particles are.
    pub geometry: Geometry<D>,
    /// Particle spacing `h` (m).
    pub spacing: f64,
    /// Initial velocity (m/s), uniform; see also [`Body::velocity_field`].
    pub velocity: Vector<D>,
    /// Initial velocity per particle (m/s) from its position (its
    /// coordinates as a slice), replacing [`Body::velocity`] where set.
    pub velocity_field: Option<InitialField<Vector<D>>>,
    /// Initial pressure per particle (Pa) from its position, replacing the
    /// hydrostatic start of a fluid where set.
    pub pressure_field: Option<InitialField<f64>>,
    /// Wall motion (walls only).
    pub motion: WallMotion<D>,
    /// Solids only: where the solid is clamped (any number of clamps).
    pub clamps: Vec<Clamp<D>>,
}

/// Run settings of a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSettings {
    /// End time (s).
    pub end_time: f64,
    /// Largest time step (s).
    pub max_dt: f64,
    /// Courant number `C` bounding `Δt ≤ C minᵢ hᵢ / |vᵢ|` (each particle
    /// against its own spacing).
    pub courant: f64,
    /// Interval between outputs (s); `None` for no VTU output.
    pub output_interval: Option<f64>,
    /// Alpha of the alpha shape (§8).
    pub alpha: f64,
}

impl Default for RunSettings {
    fn default() -> Self {
        Self {
            end_time: 1.0,
            max_dt: 1e-3,
            courant: 0.5,
            output_interval: Some(0.02),
            alpha: 1.3,
        }
    }
}

/// Memory per particle of a 2D run, for [`Scene::estimate`]: measured
/// 26 MB peak for the 1 446-particle dam break (18 KB per particle with the
/// process's fixed part), rounded up.
pub const BYTES_PER_PARTICLE_2D: f64 = 20e3;

/// Memory per particle of a 3D run, for [`Scene::estimate`]: measured
/// 96 MB for the 6 995-particle column on a cylinder (14 KB), and the sparse
/// factor's fill grows with size in 3D; 50 KB is a conservative bound.
pub const BYTES_PER_PARTICLE_3D: f64 = 50e3;

/// A body whose coordinates reach farther from the origin than this many
/// of its spacings is refused (`2³²`: there a double resolves positions to
/// about `2.4·10⁻⁷` of the spacing).
pub const MAX_COORDINATE_SPACINGS: f64 = 4_294_967_296.0;

/// A scene's estimated size ([`Scene::estimate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Particles.
    pub particles: f64,
    /// Memory of a run (bytes).
    pub bytes: f64,
}

/// The most bodies a scene may have: materials are numbered in 16 bits
/// (`u16::MAX` marks none), one a body and one contact penalty a body at
/// most.
pub const MAX_BODIES: usize = 30_000;

/// The default memory budget of a run: 80 % of the machine's memory
/// (`/proc/meminfo`'s `MemTotal`), or 8 GiB where it cannot be read.
pub fn default_memory_budget() -> f64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("MemTotal:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<f64>().ok())
        })
        .map_or(8.0 * 1024f64.powi(3), |kb| 0.8 * kb * 1024.0)
}

/// A force on a solid body in time ([`Scene::force`]): `force(t)` (N; N
/// per metre of depth in 2D) split evenly among the body's free particles
/// (not clamped or welded) that start inside `region` (all of them
/// without one; a region that holds none is refused). The driver applies it
/// with its `AppliedForce` hook.
#[derive(Clone)]
pub struct AppliedLoad<const D: usize>
where
    Const<D>: Dim,
{
    /// The solid body's name.
    pub body: String,
    /// The box `[min, max]` its loaded particles start in (`None`: all).
    pub region: Option<(Point<D>, Point<D>)>,
    /// The total force at time `t` (s).
    #[allow(clippy::type_complexity)]
    pub force: std::sync::Arc<dyn Fn(f64) -> Vector<D> + Send + Sync>,
    /// Times (s) at which the force's slope changes (a table's rows, a
    /// ramp's end): the driver ends a step at each, so that the trapezoidal
    /// rule integrates a piecewise-linear force's impulse exactly (a step
    /// across a row was off by up to `F Δt / 2`; a review of session 53).
    /// Empty for a force given as a closure ([`Scene::force`]).
    pub kinks: Vec<f64>,
}

impl<const D: usize> AppliedLoad<D>
where
    Const<D>: Dim,
{
    /// Whether a particle starting at `x` lies in the load's region (every
    /// one without a region).
    pub fn covers(&self, x: &Point<D>) -> bool {
        self.region
            .is_none_or(|(lo, hi)| (0..D).all(|k| x[k] >= lo[k] && x[k] <= hi[k]))
    }
}

impl<const D: usize> std::fmt::Debug for AppliedLoad<D>
where
    Const<D>: Dim,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AppliedLoad")
            .field("body", &self.body)
            .field("region", &self.region)
            .finish_non_exhaustive()
    }
}

/// A scene: bodies, body force and run settings.
#[derive(Debug)]
pub struct Scene<const D: usize>
where
    Const<D>: Dim,
{
    /// Scene name (file names, summary).
    pub name: String,
    /// The bodies.
    pub bodies: Vec<Body<D>>,
    /// Body force per unit mass (m/s²), `None` for none.
    pub gravity: Option<Vector<D>>,
    /// Run settings.
    pub settings: RunSettings,
    /// Contact between free solids (and clamped ones when asked)
    /// and walls or other solids.
    pub contact: ContactSettings,
    /// The pressure stabilisation factor this scene asks for (0: none;
    /// `pfem_time::StepParams::pressure_stabilisation`, ARCHITECTURE.md
    /// deviation 12). The driver applies it unless the program's
    /// `StepParams` sets one.
    pub pressure_stabilisation: f64,
    /// Calls of the builder that had nothing to act on (a per-body setting
    /// such as [`Scene::with_velocity`] called before any body), found as
    /// they were made and refused by [`Scene::validate`].
    pub misuse: Vec<String>,
    /// Forces on solid bodies in time ([`Scene::force`]).
    pub forces: Vec<AppliedLoad<D>>,
    /// The domain box (lower and upper corners, m), `None` for none
    /// ([`Scene::domain`]): fluid particles that leave it are removed.
    pub domain: Option<(Point<D>, Point<D>)>,
    /// Particle management ([`Scene::particle_management`]): its
    /// thresholds and the steps between two passes; `None` for none.
    pub particle_management: Option<(ParticleManagementParams, u64)>,
}

/// Contact settings ([`Scene::friction`], [`Scene::contact_stiffness`],
/// [`Scene::contact_clamped`]). Contact acts between a *free* solid (no
/// clamp, not welded to a wall) and any wall or other solid it comes
/// within reach of, and with [`ContactSettings::clamped`] between every
/// solid and what it reaches; a scene without such a solid near another
/// body pays nothing for it.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSettings {
    /// Coulomb friction coefficients by pair of body names (order free);
    /// pairs not listed are frictionless.
    pub friction: Vec<(String, String, f64)>,
    /// Normal penalty stiffness `K_c` (Pa), for every pair of bodies: the
    /// slope of the contact pressure against the gap's closure beyond the
    /// rounded onset (a gap closed entirely: `K_c (1 − δ/2)`,
    /// `pfem_constitutive::ContactPenalty`). Default, for each contact
    /// element: the smallest P-wave modulus `λ + 2μ` of the solids among
    /// its particles' bodies (a wall counts as none), so the penetration
    /// under a stress `σ` is `σ/K_c` of the spacing, the softer solid's
    /// own strain: the layer is one more cell of it. (Before session 36
    /// the default was the scene's stiffest solid's for every pair: a soft
    /// body then met a wall with a penalty many times its own stiffness;
    /// until session 50 the stiffest of the element's own: a soft block
    /// on a free steel one inverted its elements.)
    pub stiffness: Option<f64>,
    /// Normal damping of the contact layer, in steps
    /// (`pfem_constitutive::ContactPenalty::damping`): damping ratio
    /// `c ω Δt / 2` on a contact mode of frequency `ω`. Default 0.1; 0
    /// for an undamped (energy-conserving) contact.
    pub damping: f64,
    /// Width of the penalty's rounded onset, as a fraction of the contact
    /// distance (`pfem_constitutive::ContactPenalty::onset`, `[0, ½]`).
    /// Default [`CONTACT_ONSET`]; 0 for the plain penalty, whose kink at
    /// the contact distance, where bodies at rest sit, made the Picard
    /// loop reject steps of resting and ringing contacts.
    pub onset: f64,
    /// Clamped solids take part in contact too (default `false`): a
    /// flexible structure that may bend or be pressed into a wall or
    /// another solid (a flap against its stop, a soft post crushed onto
    /// the floor). Off, a clamped solid passes through what it reaches;
    /// on, every scene with a solid near another body remeshes each step,
    /// solid-only ones included. In 3D since session 38: until the
    /// contact dashpot grew in over the onset
    /// (`pfem_constitutive::contact::DASHPOT_RAMP`), the Picard loop
    /// rejected a fifth to a third of the steps of clamped solids in
    /// contact under a wave, and 3D scenes were refused
    /// (`tests/stability_3d.rs`: 220 of 744 steps in session 37, none of
    /// 150 now).
    pub clamped: bool,
}

/// Default width of the contact penalty's rounded onset
/// ([`ContactSettings::onset`]): 10⁻² of the contact distance. Measured
/// (session 37) on a 3D elastic block resting on a floor
/// (`tests/contact.rs`), its mean floor force over 0.2–0.3 s against its
/// weight and the steps Picard rejected: with the kink −4.4 %, 26 of 189;
/// `δ` = 3·10⁻⁴ −8.8 %, 23 of 186; 10⁻³ +2.4 %, 3·10⁻³ +0.43 %, 10⁻²
/// −0.04 %, 3·10⁻² −0.36 %, none of 150 each. It closes 5.4·10⁻³ of the
/// gap at 10⁻² (2.2·10⁻³ with the kink).
pub const CONTACT_ONSET: f64 = 1e-2;

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            friction: Vec::new(),
            stiffness: None,
            damping: 0.1,
            onset: CONTACT_ONSET,
            clamped: false,
        }
    }
}

impl<const D: usize> Scene<D>
where
    Const<D>: Dim,
{
    /// An empty scene.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            bodies: Vec::new(),
            gravity: None,
            settings: RunSettings::default(),
            contact: ContactSettings::default(),
            pressure_stabilisation: 0.0,
            misuse: Vec::new(),
            forces: Vec::new(),
            domain: None,
            particle_management: None,
        }
    }

    /// Particle management every `every` steps (≥ 1): after the step's
    /// remeshing, fluid particles closer than
    /// [`ParticleManagementParams::removal_fraction`] of the spacing to
    /// another are removed, and fluid elements grown beyond
    /// [`ParticleManagementParams::insertion_factor`] times the regular
    /// one get a particle at their centroid
    /// (`pfem_geometry::manage_particles`; the driver installs the hook
    /// `pfem_driver::hooks::ParticleManagement`, and the volume ledger
    /// books the changes under its name). For fluids that crowd: a soft
    /// bulk modulus lets two particles close on each other until their
    /// elements flatten and blow apart. Default: none (the paper's fixed
    /// particle set).
    pub fn particle_management(mut self, params: ParticleManagementParams, every: u64) -> Self {
        self.particle_management = Some((params, every));
        self
    }

    /// The domain: the box `[min, max]` (m) outside which fluid particles
    /// are removed at the start of the next step, after its remeshing and
    /// before the volume correction, as fluid leaving (an outflow:
    /// the volume ledger books it in `sources`, and the volume correction
    /// keeps the water that is left). A drop that flies off an open tank
    /// with nothing under it otherwise falls for the rest of the run, and
    /// its growing speed shortens every step (the Courant bound counts
    /// it). Every fluid body must start inside; walls and solids may
    /// reach out of it and are never removed (a scene without fluid
    /// installs no domain). Default: none.
    pub fn domain(mut self, min: Point<D>, max: Point<D>) -> Self {
        self.domain = Some((min, max));
        self
    }

    /// Asks for the pressure stabilisation with factor `alpha` (≥ 0; see
    /// [`Scene::pressure_stabilisation`]): violent impacts on light
    /// bodies, where the paper's nodal pressure swings from step to step.
    pub fn pressure_stabilisation(mut self, alpha: f64) -> Self {
        self.pressure_stabilisation = alpha;
        self
    }

    /// Coulomb friction `mu` (≥ 0) between bodies `a` and `b` in contact.
    pub fn friction(mut self, a: &str, b: &str, mu: f64) -> Self {
        self.contact.friction.push((a.into(), b.into(), mu));
        self
    }

    /// The normal damping of contact ([`ContactSettings::damping`]; 0 for
    /// none).
    pub fn contact_damping(mut self, c: f64) -> Self {
        self.contact.damping = c;
        self
    }

    /// The width of the contact penalty's rounded onset, a fraction of the
    /// contact distance in `[0, ½]` ([`ContactSettings::onset`]; 0 for the
    /// plain penalty).
    pub fn contact_onset(mut self, delta: f64) -> Self {
        self.contact.onset = delta;
        self
    }

    /// Whether clamped solids take part in contact too
    /// ([`ContactSettings::clamped`]; default `false`).
    pub fn contact_clamped(mut self, on: bool) -> Self {
        self.contact.clamped = on;
        self
    }

    /// How many kinks a wall's motion law has before the end time
    /// ([`crate::motion::MotionLaw::next_kink`]: a table's rows where the
    /// velocity changes), each a step's end: the most of any one wall's
    /// (walls on one table share their kinks), counted up to a little past
    /// `most` (the count stops there).
    pub fn motion_kinks(&self, most: f64) -> f64 {
        let end = self.settings.end_time;
        let mut largest: f64 = 0.0;
        for b in &self.bodies {
            let WallMotion::Law(law) = &b.motion else {
                continue;
            };
            let (mut t, mut count) = (0.0, 0.0);
            while let Some(k) = law.next_kink(t) {
                if !(k > t && k < end) || count > most {
                    break;
                }
                count += 1.0;
                t = k;
            }
            largest = largest.max(count);
        }
        largest
    }

    /// The normal penalty stiffness of contact (Pa), instead of the
    /// default ([`ContactSettings::stiffness`]).
    pub fn contact_stiffness(mut self, k: f64) -> Self {
        self.contact.stiffness = Some(k);
        self
    }

    /// Sets the gravity (m/s²).
    pub fn gravity(mut self, g: Vector<D>) -> Self {
        self.gravity = Some(g);
        self
    }

    /// Sets the run settings.
    pub fn settings(mut self, settings: RunSettings) -> Self {
        self.settings = settings;
        self
    }

    /// Adds a fluid body.
    pub fn fluid(
        mut self,
        name: &str,
        material: Box<dyn Material<D>>,
        geometry: Geometry<D>,
        spacing: f64,
    ) -> Self {
        self.bodies.push(Body {
            name: name.into(),
            kind: ParticleKind::Fluid,
            material: Some(material),
            geometry,
            spacing,
            velocity: Vector::<D>::zeros(),
            velocity_field: None,
            pressure_field: None,
            motion: WallMotion::Fixed,
            clamps: Vec::new(),
        });
        self
    }

    /// Adds a solid body, clamped where `clamp` (a box) says; more clamps
    /// with [`Scene::clamp_box`] and [`Scene::clamp_where`]. A solid may
    /// touch a wall: where one of its particles falls within a quarter
    /// spacing of a wall particle, the wall particle is dropped and the
    /// solid particle is welded to the wall (it moves with it).
    pub fn solid(
        mut self,
        name: &str,
        material: Box<dyn Material<D>>,
        geometry: Geometry<D>,
        spacing: f64,
        clamp: Option<(Point<D>, Point<D>)>,
    ) -> Self {
        self.bodies.push(Body {
            name: name.into(),
            kind: ParticleKind::Solid,
            material: Some(material),
            geometry,
            spacing,
            velocity: Vector::<D>::zeros(),
            velocity_field: None,
            pressure_field: None,
            motion: WallMotion::Fixed,
            clamps: clamp
                .map(|(lo, hi)| Clamp::Box(lo, hi))
                .into_iter()
                .collect(),
        });
        self
    }

    /// Adds a wall.
    pub fn wall(
        mut self,
        name: &str,
        geometry: Geometry<D>,
        spacing: f64,
        motion: WallMotion<D>,
    ) -> Self {
        self.bodies.push(Body {
            name: name.into(),
            kind: ParticleKind::Wall,
            material: None,
            geometry,
            spacing,
            velocity: Vector::<D>::zeros(),
            velocity_field: None,
            pressure_field: None,
            motion,
            clamps: Vec::new(),
        });
        self
    }

    /// A force `force(t)` (N; N per metre of depth in 2D, `t` in s) on the
    /// solid `body`, split evenly among its free particles (not clamped or
    /// welded) that start inside `region` (`None`: all of them; a region
    /// that holds none is refused): a tip load, a traction on a face,
    /// a push. Applied at the end of each step (`t = tₙ + Δt`).
    pub fn force(
        self,
        body: &str,
        region: Option<(Point<D>, Point<D>)>,
        force: impl Fn(f64) -> Vector<D> + Send + Sync + 'static,
    ) -> Self {
        self.force_with_kinks(body, region, force, Vec::new())
    }

    /// [`Scene::force`] with the times at which the force's slope changes
    /// ([`AppliedLoad::kinks`]: a table's rows, a ramp's end), at which
    /// the steps end: a piecewise-linear force's impulse is then exact.
    pub fn force_with_kinks(
        mut self,
        body: &str,
        region: Option<(Point<D>, Point<D>)>,
        force: impl Fn(f64) -> Vector<D> + Send + Sync + 'static,
        kinks: Vec<f64>,
    ) -> Self {
        self.forces.push(AppliedLoad {
            body: body.into(),
            region,
            force: std::sync::Arc::new(force),
            kinks,
        });
        self
    }

    /// Sets the initial velocity of the last body added.
    pub fn with_velocity(mut self, v: Vector<D>) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.velocity = v;
        } else {
            self.misuse
                .push("`with_velocity` called before any body: it sets the last body added".into());
        }
        self
    }

    /// Sets the initial velocity of each particle of the last body added
    /// from its position: `f(x)` with `x` the particle's coordinates (m).
    /// The initial accelerations are computed from it.
    pub fn with_velocity_field(
        mut self,
        f: impl Fn(&[f64]) -> Vector<D> + Send + Sync + 'static,
    ) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.velocity_field = Some(InitialField(std::sync::Arc::new(f)));
        } else {
            self.misuse.push(
                "`with_velocity_field` called before any body: it sets the last body added".into(),
            );
        }
        self
    }

    /// Sets the initial pressure (Pa) of each particle of the last body
    /// added (a fluid) from its position, instead of the hydrostatic start.
    pub fn with_pressure_field(
        mut self,
        f: impl Fn(&[f64]) -> f64 + Send + Sync + 'static,
    ) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.pressure_field = Some(InitialField(std::sync::Arc::new(f)));
        } else {
            self.misuse.push(
                "`with_pressure_field` called before any body: it sets the last body added".into(),
            );
        }
        self
    }

    /// Clamps the particles of the last body added (a solid) inside the box
    /// `[min, max]`, besides its other clamps.
    pub fn clamp_box(mut self, min: Point<D>, max: Point<D>) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.clamps.push(Clamp::Box(min, max));
        } else {
            self.misuse
                .push("`clamp_box` called before any body: it sets the last body added".into());
        }
        self
    }

    /// Clamps the particles of the last body added (a solid) whose initial
    /// position satisfies `f`, besides its other clamps.
    pub fn clamp_where(mut self, f: impl Fn(&Point<D>) -> bool + Send + Sync + 'static) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.clamps.push(Clamp::Where(std::sync::Arc::new(f)));
        } else {
            self.misuse
                .push("`clamp_where` called before any body: it sets the last body added".into());
        }
        self
    }

    /// Estimated particle count and memory of the scene, from its
    /// geometries and spacings, without placing a particle. Its cost grows
    /// with the surfaces' fill work (`ClosedSurface::fill_work`);
    /// [`Scene::validate_within`] bounds it by the budget it checks.
    pub fn estimate(&self) -> Estimate {
        self.estimate_up_to(f64::INFINITY)
    }

    /// The particles body `b` is estimated to place (its geometry's
    /// measure over its lattice cell), as [`Scene::estimate`] counts them.
    fn body_particles(b: &Body<D>) -> f64 {
        let h = b.spacing;
        match &b.geometry {
            Geometry::Box { min, max } => (0..D)
                .map(|k| ((max[k] - min[k]) / h).round().max(0.0) + 1.0)
                .product::<f64>(),
            Geometry::Ball { radius, .. } => {
                let r = radius / h + 1.0;
                if D == 2 {
                    std::f64::consts::PI * r * r
                } else {
                    4.0 / 3.0 * std::f64::consts::PI * r * r * r
                }
            }
            Geometry::Cylinder { radius, height, .. } => {
                let r = radius / h + 1.0;
                std::f64::consts::PI * r * r * (height / h + 1.0)
            }
            Geometry::Particles(p) => p.len() as f64,
            // The enclosed measure over a lattice cell, plus a layer.
            Geometry::Surface(s) => {
                let (lo, hi) = s.bounds();
                let cells: f64 = (0..D).map(|k| (hi[k] - lo[k]) / h + 1.0).product();
                cells.min(s.enclosed_measure() / h.powi(D as i32) * 1.5 + 8.0)
            }
        }
    }

    /// [`Scene::estimate`], its count of the surfaces' fill work stopped
    /// once the bytes exceed `budget` (the estimate is then above `budget`,
    /// not exact): the particles are counted first, the fill work, whose
    /// count costs a step a slab of lattice lines, after.
    fn estimate_up_to(&self, budget: f64) -> Estimate {
        let particles: f64 = self.bodies.iter().map(Self::body_particles).sum();
        let per_particle = if D == 2 {
            BYTES_PER_PARTICLE_2D
        } else {
            BYTES_PER_PARTICLE_3D
        };
        let mut bytes = particles * per_particle;
        // A surface's fill stores a (line, facet) pair for each lattice
        // line near each facet (`ClosedSurface::fill_work`), 16 bytes each.
        for b in &self.bodies {
            if let Geometry::Surface(s) = &b.geometry {
                if bytes.is_nan() || bytes > budget {
                    break;
                }
                bytes += 16.0 * s.fill_work_up_to(b.spacing, (budget - bytes) / 16.0);
            }
        }
        Estimate { particles, bytes }
    }

    /// The body with the most estimated particles, named with its count,
    /// spacing and extent, for [`SceneError::TooLarge`]: a model in
    /// millimetres read as metres (an STL without `scale`) was refused
    /// naming no body (a review of session 53).
    fn largest_body(&self) -> String {
        let Some(b) = self
            .bodies
            .iter()
            .max_by(|a, b| Self::body_particles(a).total_cmp(&Self::body_particles(b)))
        else {
            return String::new();
        };
        let (lo, hi) = b.geometry.bounds();
        let extent: Vec<String> = (0..D).map(|k| format!("{:.3e}", hi[k] - lo[k])).collect();
        // The hint where a surface spans more than 10 m (a model in
        // millimetres read as metres), not whenever the largest body is a
        // surface.
        let widest = (0..D).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let mm = if matches!(b.geometry, Geometry::Surface(_)) && widest > 10.0 {
            "; a surface in millimetres needs `scale = 0.001` (a scene file's `stl` key)"
        } else {
            ""
        };
        format!(
            "; the largest, body `{}`: about {:.3e} particles at spacing {:e} m over {} m{mm}",
            b.name,
            Self::body_particles(b),
            b.spacing,
            extent.join(" × ")
        )
    }

    /// [`Scene::validate`], then refuses a scene whose
    /// [`estimate`](Scene::estimate) exceeds `budget` bytes: before a
    /// particle is placed.
    pub fn validate_within(&self, budget: f64) -> Result<Estimate, SceneError> {
        // A budget that is not a number would compare false with every
        // estimate: the guard off, unseen. Infinity is "no limit".
        if budget.is_nan() || budget <= 0.0 {
            return Err(SceneError::OutOfRange {
                setting: "memory_budget",
                value: budget,
                range: "(0, ∞] bytes",
            });
        }
        self.validate()?;
        let e = self.estimate_up_to(budget);
        if e.bytes.is_nan() || e.bytes > budget {
            return Err(SceneError::TooLarge {
                particles: e.particles,
                bytes: e.bytes,
                budget,
                largest: self.largest_body(),
            });
        }
        Ok(e)
    }

    /// Checks the scene before any step runs: positive finite spacing no
    /// larger than its body, materials where needed and of the right kind,
    /// valid run settings, cylinders in 3D only, solids supported, fluids not overlapping other
    /// bodies' interiors.
    pub fn validate(&self) -> Result<(), SceneError> {
        if let Some(why) = self.misuse.first() {
            return Err(SceneError::Misuse { why: why.clone() });
        }
        let s = &self.settings;
        for (what, v) in [
            ("end_time", s.end_time),
            ("max_dt", s.max_dt),
            ("courant", s.courant),
            ("alpha", s.alpha),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(SceneError::InvalidSetting {
                    setting: what,
                    value: v,
                });
            }
        }
        let ps = self.pressure_stabilisation;
        if !(ps >= 0.0 && ps.is_finite()) {
            return Err(SceneError::OutOfRange {
                setting: "pressure_stabilisation",
                value: ps,
                range: "[0, ∞) (0 = off)",
            });
        }
        if !(ALPHA_RANGE.0..=ALPHA_RANGE.1).contains(&s.alpha) {
            return Err(SceneError::OutOfRange {
                setting: "alpha",
                value: s.alpha,
                range: "[1, 10] (the alpha shape keeps simplices of circumradius up to alpha times the spacing; 1.2 to 1.5 is usual; below 1 it drops a lattice's own simplices)",
            });
        }
        if let Some(dt) = s.output_interval {
            if !(dt > 0.0 && dt.is_finite()) {
                return Err(SceneError::InvalidSetting {
                    setting: "output_interval",
                    value: dt,
                });
            }
        }
        if let Some(g) = self.gravity {
            if g.iter().any(|v| !v.is_finite()) {
                return Err(SceneError::NonFinite { setting: "gravity" });
            }
        }
        if self.bodies.is_empty() {
            return Err(SceneError::Empty);
        }
        if let Some((lo, hi)) = self.domain {
            if let Some(v) = lo.iter().chain(hi.iter()).find(|v| !v.is_finite()) {
                return Err(SceneError::OutOfRange {
                    setting: "domain",
                    value: *v,
                    range: "finite corners (m)",
                });
            }
            if let Some(k) = (0..D).find(|&k| lo[k] >= hi[k]) {
                return Err(SceneError::OutOfRange {
                    setting: "domain",
                    value: hi[k] - lo[k],
                    range: "a positive width along every axis (max above min)",
                });
            }
            for b in &self.bodies {
                if b.kind != ParticleKind::Fluid {
                    continue;
                }
                let (blo, bhi) = b.geometry.bounds();
                if (0..D).any(|k| blo[k] < lo[k] || bhi[k] > hi[k]) {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: format!(
                            "it reaches out of the domain [{:?}, {:?}] (its bounds [{:?}, {:?}]): a fluid must start inside the domain, outside which its particles are removed",
                            lo.as_slice(),
                            hi.as_slice(),
                            blo.as_slice(),
                            bhi.as_slice()
                        ),
                    });
                }
            }
        }
        if let Some((params, every)) = &self.particle_management {
            if *every == 0 {
                return Err(SceneError::OutOfRange {
                    setting: "particle_management.every",
                    value: 0.0,
                    range: "1..: a number of steps",
                });
            }
            params.validate().map_err(|e| match e {
                pfem_geometry::GeometryError::InvalidParameter {
                    name,
                    value,
                    reason,
                } => match name {
                    "removal_fraction" => SceneError::OutOfRange {
                        setting: "particle_management.removal_fraction",
                        value,
                        range: "[0, 1): a fraction of the spacing, 0 for no removal",
                    },
                    "insertion_factor" => SceneError::OutOfRange {
                        setting: "particle_management.insertion_factor",
                        value,
                        range:
                            "1 or more: times the regular simplex's measure, inf for no insertion",
                    },
                    other => SceneError::OutOfRange {
                        setting: other,
                        value,
                        range: reason,
                    },
                },
                _ => SceneError::InvalidSetting {
                    setting: "particle_management",
                    value: f64::NAN,
                },
            })?;
        }
        if self.bodies.len() > MAX_BODIES {
            return Err(SceneError::OutOfRange {
                setting: "the number of bodies",
                value: self.bodies.len() as f64,
                range:
                    "1..=30000 (each body's material and contact penalty is numbered in 16 bits)",
            });
        }
        for b in &self.bodies {
            // Body names head probe columns and name bodies in messages.
            if !is_column_name(&b.name) {
                return Err(SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: "a body name must be non-empty, without commas, quotes or control characters".into(),
                });
            }
            if !(b.spacing > 0.0 && b.spacing.is_finite()) {
                return Err(SceneError::InvalidSpacing {
                    body: b.name.clone(),
                    spacing: b.spacing,
                });
            }
            if let Geometry::Particles(ps) = &b.geometry {
                if let Some((k, q)) = ps
                    .iter()
                    .enumerate()
                    .find(|(_, q)| q.iter().any(|v| !v.is_finite()))
                {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: format!(
                            "particle {} at {:?} has a non-finite coordinate",
                            k + 1,
                            q.as_slice()
                        ),
                    });
                }
            }
            let (lo, hi) = b.geometry.bounds();
            if lo.iter().chain(hi.iter()).any(|v| !v.is_finite()) {
                return Err(SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: "non-finite or empty geometry".into(),
                });
            }
            // Far from the origin a double cannot tell lattice nodes apart
            // (at 10¹⁵ m its spacing is 0.125 m): a body there would run
            // with particles merged or misplaced.
            let far = lo
                .iter()
                .chain(hi.iter())
                .fold(0.0f64, |a, v| a.max(v.abs()));
            if far > MAX_COORDINATE_SPACINGS * b.spacing {
                return Err(SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: format!(
                        "a coordinate of {far:e} m is more than {MAX_COORDINATE_SPACINGS:e} spacings ({:e} m) from the origin, where a double resolves positions only to {:e} m: move the scene nearer the origin, or coarsen a spacing this fine",
                        b.spacing,
                        far * f64::EPSILON
                    ),
                });
            }
            if let Geometry::Box { min, max } = &b.geometry {
                if (0..D).any(|k| max[k] < min[k]) {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: "box max below min".into(),
                    });
                }
                // A solid box thinner than half a spacing is one layer of
                // particles: no element holds them (a free one then ran to
                // a NaN residual).
                if b.kind == ParticleKind::Solid {
                    if let Some(k) = (0..D).find(|&k| ((max[k] - min[k]) / b.spacing).round() < 1.0)
                    {
                        return Err(SceneError::InvalidGeometry {
                            body: b.name.clone(),
                            why: format!(
                                "a solid box spans {} m along axis {k}, less than its spacing {} m: one layer of particles makes no element",
                                max[k] - min[k],
                                b.spacing
                            ),
                        });
                    }
                }
            }
            let extent = (hi - lo).max();
            if let Geometry::Ball { radius, .. } = b.geometry {
                if radius.is_nan() || radius <= 0.0 {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: "radius must be positive".into(),
                    });
                }
            }
            if let Geometry::Cylinder {
                axis,
                radius,
                height,
                ..
            } = b.geometry
            {
                let why = if D != 3 {
                    Some("a cylinder is a 3D geometry (use a box in 2D)")
                } else if axis >= D {
                    Some("cylinder axis must be 0, 1 or 2")
                } else if !(radius > 0.0 && height > 0.0) {
                    Some("cylinder radius and height must be positive")
                } else {
                    None
                };
                if let Some(why) = why {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: why.into(),
                    });
                }
            }
            if let Geometry::Surface(surface) = &b.geometry {
                surface.check().map_err(|why| SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why,
                })?;
            }
            if !matches!(b.geometry, Geometry::Particles(_)) && b.spacing > extent + 1e-12 {
                return Err(SceneError::SpacingLargerThanBody {
                    body: b.name.clone(),
                    spacing: b.spacing,
                    extent,
                });
            }
            if let Geometry::Box { min, max } = &b.geometry {
                if (0..D).any(|k| max[k] < min[k]) {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: "box max below min".into(),
                    });
                }
            }
            if let Some(m) = &b.material {
                // (A material's error, not a geometry's: session 48's
                // review.)
                let (rho, c) = (m.density(), m.wave_speed());
                let source = if !(rho > 0.0 && rho.is_finite()) {
                    Some(pfem_constitutive::MaterialError::InvalidParameter {
                        parameter: pfem_constitutive::Parameter::Density,
                        value: rho,
                        allowed: "positive and finite (kg/m³)",
                    })
                } else if !(c > 0.0 && c.is_finite()) {
                    Some(pfem_constitutive::MaterialError::DegenerateWaveSpeed { wave_speed: c })
                } else {
                    None
                };
                if let Some(source) = source {
                    return Err(SceneError::InvalidMaterial {
                        body: b.name.clone(),
                        source,
                    });
                }
            }
            if let Some(m) = &b.material {
                let count = m.internal_variables().len();
                if count > 0 && m.kind() == MaterialKind::Fluid {
                    return Err(SceneError::InvalidMaterial {
                        body: b.name.clone(),
                        source: pfem_constitutive::MaterialError::FluidWithInternalVariables {
                            count,
                        },
                    });
                }
                if count > pfem_constitutive::MAX_INTERNAL {
                    return Err(SceneError::InvalidMaterial {
                        body: b.name.clone(),
                        source: pfem_constitutive::MaterialError::TooManyInternalVariables {
                            count,
                            limit: pfem_constitutive::MAX_INTERNAL,
                        },
                    });
                }
            }
            match (b.kind, &b.material) {
                (ParticleKind::Wall, _) => {}
                (_, None) => {
                    return Err(SceneError::MissingMaterial {
                        body: b.name.clone(),
                    })
                }
                (ParticleKind::Fluid, Some(m)) if m.kind() != MaterialKind::Fluid => {
                    return Err(SceneError::MaterialKindMismatch {
                        body: b.name.clone(),
                    })
                }
                (ParticleKind::Solid, Some(m)) if m.kind() != MaterialKind::Solid => {
                    return Err(SceneError::MaterialKindMismatch {
                        body: b.name.clone(),
                    })
                }
                _ => {}
            }
            if b.kind == ParticleKind::Wall
                && (b.velocity != Vector::<D>::zeros() || b.velocity_field.is_some())
            {
                return Err(SceneError::Misuse {
                    why: format!("wall `{}` given an initial velocity: a wall moves by its motion (WallMotion), not by one", b.name),
                });
            }
            if b.velocity != Vector::<D>::zeros() && b.velocity_field.is_some() {
                return Err(SceneError::Misuse {
                    why: format!("body `{}` given both an initial velocity and a velocity field: they exclude each other", b.name),
                });
            }
            if let Some(m) = &b.material {
                m.check_dimension()
                    .map_err(|source| SceneError::InvalidMaterial {
                        body: b.name.clone(),
                        source,
                    })?;
            }
            if b.kind == ParticleKind::Solid {
                // Boxes keep a structured mesh; any other geometry is meshed
                // by `solid_mesh` (Delaunay of its particles + alpha shape).
                // A free solid lands on a wall or another solid through
                // contact, whether it starts on it or above it: one its box
                // meets when swept along gravity (within a spacing). Not a
                // ceiling, nor a wall beside it.
                let gravity = self.gravity.filter(|g| g.norm() > 0.0);
                let lands = |w: &Body<D>| {
                    let Some(g) = gravity else {
                        return true;
                    };
                    // The solid's box swept along gravity meets `w`'s.
                    let (b0, b1) = b.geometry.bounds();
                    let (w0, w1) = w.geometry.bounds();
                    let tol = b.spacing.max(w.spacing);
                    (0..D).all(|k| {
                        // Along `+k` the sweep reaches `+∞` if `g` points
                        // that way, along `−k` likewise.
                        let up_to = g[k] > 0.0 || w0[k] <= b1[k] + tol;
                        let down_to = g[k] < 0.0 || w1[k] >= b0[k] - tol;
                        up_to && down_to
                    })
                };
                // (A box touching the solid's holds it too: it rests on
                // it, or is welded to it where their particles meet.)
                let touches = self.bodies.iter().any(|w| {
                    !std::ptr::eq(w, b)
                        && matches!(w.kind, ParticleKind::Wall | ParticleKind::Solid)
                        && (boxes_touch(&b.geometry, &w.geometry, b.spacing.min(w.spacing))
                            || lands(w))
                });
                let supported = !b.clamps.is_empty() || touches || gravity.is_none();
                let floating = self.bodies.iter().any(|o| o.kind == ParticleKind::Fluid);
                if !supported && !floating {
                    return Err(SceneError::Unsupported {
                        body: b.name.clone(),
                    });
                }
            }
        }
        // Overlap: a box body's interior (shrunk by half a spacing) must not
        // contain another body's box interior.
        for (i, a) in self.bodies.iter().enumerate() {
            for b in self.bodies.iter().skip(i + 1) {
                if let (Geometry::Box { min: a0, max: a1 }, Geometry::Box { min: b0, max: b1 }) =
                    (&a.geometry, &b.geometry)
                {
                    let m = 0.5 * a.spacing.min(b.spacing);
                    let overlap = (0..D).all(|k| a0[k] + m < b1[k] - m && b0[k] + m < a1[k] - m);
                    if overlap {
                        return Err(SceneError::Overlap {
                            first: a.name.clone(),
                            second: b.name.clone(),
                        });
                    }
                }
            }
        }
        // Clamps and fields on bodies of the wrong kind.
        for b in &self.bodies {
            if !b.clamps.is_empty() && b.kind != ParticleKind::Solid {
                return Err(SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: "only a solid can be clamped".into(),
                });
            }
            for (k, c) in b.clamps.iter().enumerate() {
                if let Clamp::Box(lo, hi) = c {
                    let finite = lo.iter().chain(hi.iter()).all(|v| v.is_finite());
                    if !finite || (0..D).any(|i| hi[i] < lo[i]) {
                        return Err(SceneError::InvalidGeometry {
                            body: b.name.clone(),
                            why: format!(
                                "clamp {} (box {:?} to {:?}) must have finite corners, max not below min",
                                k + 1,
                                lo.as_slice(),
                                hi.as_slice()
                            ),
                        });
                    }
                }
            }
            if b.pressure_field.is_some() && b.kind != ParticleKind::Fluid {
                return Err(SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: "only a fluid has an initial pressure field".into(),
                });
            }
        }
        for load in &self.forces {
            let why = match self.bodies.iter().find(|b| b.name == load.body) {
                None => Some("names a body the scene does not have"),
                Some(b) if b.kind != ParticleKind::Solid => Some("acts on solids only"),
                Some(_) => match load.region {
                    Some((lo, hi))
                        if !(lo.iter().chain(hi.iter()).all(|v| v.is_finite())
                            && (0..D).all(|k| lo[k] <= hi[k])) =>
                    {
                        Some("its region must have finite corners, max not below min")
                    }
                    _ => None,
                },
            };
            if let Some(why) = why {
                return Err(SceneError::InvalidGeometry {
                    body: load.body.clone(),
                    why: format!("an applied force {why}"),
                });
            }
        }
        check_name(&self.name)?;
        // Settings that cannot finish.
        let steps = s.end_time / s.max_dt;
        if steps > MAX_STEPS {
            return Err(SceneError::CannotFinish {
                what: format!(
                    "steps at max_dt = {:e} s to end_time = {:e} s",
                    s.max_dt, s.end_time
                ),
                count: steps,
                limit: MAX_STEPS,
            });
        }
        if let Some(dt) = s.output_interval {
            let frames = s.end_time / dt;
            if frames > MAX_FRAMES {
                return Err(SceneError::CannotFinish {
                    what: format!(
                        "output frames every {dt:e} s to end_time = {:e} s",
                        s.end_time
                    ),
                    count: frames,
                    limit: MAX_FRAMES,
                });
            }
        }
        for b in &self.bodies {
            if let WallMotion::Law(law) = &b.motion {
                law.check().map_err(|why| SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: format!("its motion law: {why}"),
                })?;
            }
        }
        // Each kink of a motion law ends a step (a table's rows 10⁻⁸ s
        // apart took a step each, past the count above: the review of
        // session 45).
        let kinks = self.motion_kinks(MAX_STEPS - steps);
        if steps + kinks > MAX_STEPS {
            return Err(SceneError::CannotFinish {
                what: format!(
                    "steps at max_dt = {:e} s to end_time = {:e} s, and one more at each of the motion laws' kinks (a table's rows where the velocity changes)",
                    s.max_dt, s.end_time
                ),
                count: steps + kinks,
                limit: MAX_STEPS,
            });
        }
        // The Courant bound on the initial velocities: Δt ≤ C h / |v|.
        let h_min = self
            .bodies
            .iter()
            .map(|b| b.spacing)
            .fold(f64::INFINITY, f64::min);
        let v_max = self
            .bodies
            .iter()
            .map(|b| match &b.motion {
                WallMotion::Velocity(w) if b.kind == ParticleKind::Wall => w.norm(),
                // A law's largest speed over the wall's box (a period of
                // 10⁻³⁰⁰ s would move it at 10³⁰⁰ m/s, or give NaN
                // positions when 2π/T overflows).
                WallMotion::Law(law) if b.kind == ParticleKind::Wall => {
                    let (lo, hi) = b.geometry.bounds();
                    law.max_speed(&lo, &hi).unwrap_or(0.0)
                }
                _ => b.velocity.norm(),
            })
            .fold(0.0, |a: f64, v| {
                if a.is_nan() || v.is_nan() {
                    f64::NAN
                } else {
                    a.max(v)
                }
            });
        let courant_steps = s.end_time * v_max / (s.courant * h_min);
        if courant_steps.is_nan() || courant_steps > MAX_STEPS {
            return Err(SceneError::CannotFinish {
                what: format!(
                    "steps at the Courant limit (largest initial or wall speed {v_max:e} m/s, spacing {h_min:e} m)"
                ),
                count: courant_steps,
                limit: MAX_STEPS,
            });
        }
        // (Maps: a million pairs among a thousand bodies, each looked up
        // in the bodies and compared with every earlier pair, took hours:
        // the review of session 45.)
        let mut by_name: std::collections::HashMap<&str, &Body<D>> =
            std::collections::HashMap::with_capacity(self.bodies.len());
        for b in &self.bodies {
            // The first body of a name, as a search would find.
            by_name.entry(b.name.as_str()).or_insert(b);
        }
        let mut pairs = std::collections::HashSet::with_capacity(self.contact.friction.len());
        for (a, b, mu) in &self.contact.friction {
            for n in [a, b] {
                match by_name.get(n.as_str()).copied() {
                    None => {
                        return Err(SceneError::InvalidGeometry {
                            body: n.clone(),
                            why: "friction names a body the scene does not have".into(),
                        })
                    }
                    Some(x) if x.kind == ParticleKind::Fluid => {
                        return Err(SceneError::InvalidGeometry {
                            body: n.clone(),
                            why:
                                "friction acts between solids and walls in contact, not on a fluid"
                                    .into(),
                        })
                    }
                    Some(_) => {}
                }
            }
            // Contact is between two bodies; a pair given twice would be
            // ambiguous. A pair of which no body takes part in contact (a
            // free solid, or a clamped one with `contact_clamped`) would
            // have a coefficient that never acts (session 47's review: two
            // walls, or a clamped beam and the floor it passes through).
            let takes_part = |n: &String| {
                by_name.get(n.as_str()).is_some_and(|x| {
                    x.kind == ParticleKind::Solid && (x.clamps.is_empty() || self.contact.clamped)
                })
            };
            let why = if a == b {
                Some("a body has no contact with itself")
            } else if !takes_part(a) && !takes_part(b) {
                Some("neither body takes part in contact (a free solid does, and a clamped one with contact_clamped): the coefficient would never act")
            } else if !pairs.insert(if a < b { (a, b) } else { (b, a) }) {
                Some("this pair's friction is given twice")
            } else {
                None
            };
            if let Some(why) = why {
                return Err(SceneError::InvalidGeometry {
                    body: format!("{a}` and `{b}"),
                    why: format!("friction: {why}"),
                });
            }
            if !(mu.is_finite() && *mu >= 0.0) {
                return Err(SceneError::OutOfRange {
                    setting: "friction",
                    value: *mu,
                    range: "[0, ∞)",
                });
            }
        }
        if !(self.contact.damping.is_finite() && self.contact.damping >= 0.0) {
            return Err(SceneError::OutOfRange {
                setting: "contact_damping",
                value: self.contact.damping,
                range: "[0, ∞)",
            });
        }
        if !(self.contact.onset.is_finite() && (0.0..=0.5).contains(&self.contact.onset)) {
            return Err(SceneError::OutOfRange {
                setting: "contact_onset",
                value: self.contact.onset,
                range: "[0, 0.5]",
            });
        }
        if let Some(k) = self.contact.stiffness {
            if !(k.is_finite() && k > 0.0) {
                return Err(SceneError::InvalidSetting {
                    setting: "contact_stiffness",
                    value: k,
                });
            }
        }
        let mut names: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
        names.sort_unstable();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(SceneError::InvalidGeometry {
                body: w[0].to_string(),
                why: "two bodies have this name".into(),
            });
        }
        Ok(())
    }
}

/// Most steps a scene may ask for (`end_time / max_dt`, or at the Courant
/// limit of its initial velocities): 10⁸, days of computing for the
/// smallest scene.
pub const MAX_STEPS: f64 = 1e8;

/// Accepted range of the alpha-shape parameter. The paper asks for α
/// "close to, but greater than one" (§8). The lower bound keeps a scene's
/// own lattices whole: a square lattice's triangles have circumradius
/// `h/√2` and a cubic lattice's tetrahedra `√3 h/2`, so below those the
/// alpha shape keeps no fluid element at all and the water starts as
/// flying particles that fall through the floor (until session 42 the
/// bound was 0.5, and α = 0.6 did that without a word).
pub const ALPHA_RANGE: (f64, f64) = (1.0, 10.0);

/// Most output frames a scene may ask for (`end_time / output_interval`).
pub const MAX_FRAMES: f64 = 1e6;

/// Whether `name` can head a CSV column (body names head probe columns):
/// non-empty, without commas, quotes or control characters.
pub fn is_column_name(name: &str) -> bool {
    !name.is_empty() && !name.chars().any(|c| c.is_control() || c == ',' || c == '"')
}

/// A scene name becomes file names (`NAME.pvd`, `NAME_000001.vtu`): it must
/// be one plain path component.
fn check_name(name: &str) -> Result<(), SceneError> {
    match file_name_fault(name) {
        Some(why) => Err(SceneError::InvalidName {
            name: name.chars().take(64).collect(),
            why,
        }),
        None => Ok(()),
    }
}

/// Why `name` cannot be the stem of a file in a chosen folder (empty, over
/// 128 bytes, a path separator, a leading dot, a control character or
/// `:`), or `None` when it can: one plain path component, so that nothing
/// is written outside the folder.
pub fn file_name_fault(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("is empty")
    } else if name.len() > 128 {
        Some("is longer than 128 bytes")
    } else if name.contains(['/', '\\']) {
        Some("contains a path separator")
    } else if name.starts_with('.') {
        Some("starts with a dot (`..` or a hidden file)")
    } else if name.chars().any(|c| c.is_control() || c == ':') {
        Some("contains a control character or `:`")
    } else {
        None
    }
}

/// Whether the bounding boxes of two geometries touch (within `tol`).
fn boxes_touch<const D: usize>(a: &Geometry<D>, b: &Geometry<D>, tol: f64) -> bool
where
    Const<D>: Dim,
{
    let (a0, a1) = a.bounds();
    let (b0, b1) = b.bounds();
    (0..D).all(|k| a0[k] <= b1[k] + tol && b0[k] <= a1[k] + tol)
}
