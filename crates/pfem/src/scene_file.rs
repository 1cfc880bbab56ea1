//! Scenes from TOML files: the serde description of a 2D or 3D scene
//! ([`SceneFile`]) and its conversion into a [`Scene`] and its probes.
//!
//! Units are SI throughout (m, s, kg, Pa; angles in rad); 2D is per metre
//! of depth (volumes m²/m, forces N/m; `docs/units.md`). A file looks like this (the
//! bundled ones are in `examples/scenes/`):
//!
//! ```toml
//! name = "puddle"
//! dimension = 2              # 2 (a slice of unit depth) or 3
//! gravity = [0.0, -9.81]     # m/s²; omit for none
//! spacing = 0.025            # m, default particle spacing of every body
//! probes = ["volume", "max_speed"]   # columns of probes.csv
//!
//! [run]                      # every key optional (defaults of RunSettings)
//! end_time = 0.02            # s
//! max_dt = 5e-3              # s
//! courant = 0.5
//! output_interval = 0.01     # s between VTU frames
//! alpha = 1.3                # alpha-shape parameter
//!
//! [[body]]
//! name = "floor"
//! kind = "wall"              # fluid | solid | wall
//! geometry.box = { min = [-0.1, -0.025], max = [0.3, 0.0] }   # m
//!
//! [[body]]
//! name = "water"
//! kind = "fluid"
//! material.newtonian = { density = 1000.0, viscosity = 1e-3, bulk_modulus = 2.2e9 }
//! geometry.box = { min = [0.0, 0.0], max = [0.2, 0.2] }
//! ```
//!
//! Loading it:
//!
//! ```
//! use pfem::scene_file::SceneFile;
//! # let text = r#"
//! # name = "puddle"
//! # dimension = 2
//! # gravity = [0.0, -9.81]
//! # spacing = 0.025
//! # probes = ["volume", "max_speed"]
//! # [run]
//! # end_time = 0.02
//! # [[body]]
//! # name = "floor"
//! # kind = "wall"
//! # geometry.box = { min = [-0.1, -0.025], max = [0.3, 0.0] }
//! # [[body]]
//! # name = "water"
//! # kind = "fluid"
//! # material.newtonian = { density = 1000.0, viscosity = 1e-3, bulk_modulus = 2.2e9 }
//! # geometry.box = { min = [0.0, 0.0], max = [0.2, 0.2] }
//! # "#;
//! let file = SceneFile::parse(text, "puddle.toml")?;
//! assert_eq!(file.dimension(), 2);
//! let scene = file.scene::<2>()?; // validated
//! assert_eq!(scene.bodies.len(), 2);
//! let probes = file.probes_2d()?;
//! assert_eq!(probes[0].name, "volume");
//! # Ok::<(), pfem::SceneError>(())
//! ```
//!
//! Keys:
//!
//! | key | meaning |
//! |---|---|
//! | `name` | scene name (output file names); default: the file's stem |
//! | `dimension` | `2` or `3` |
//! | `gravity` | body force per unit mass (m/s²), `D` numbers; omit for none |
//! | `spacing` | default particle spacing of every body (m) |
//! | `domain` | `{ min, max }` (m): fluid particles that leave this box are removed at the start of the next step (after its remeshing, before the volume correction), booked as fluid leaving ([`Scene::domain`]); every fluid body must start inside; omit for none |
//! | `[particle_management]` | `every` (steps between passes, default 1), `removal_fraction` (a fluid particle closer than this fraction of the spacing to another is removed, in `[0, 1)`, default 0.3), `insertion_factor` (a fluid element over this many times the regular one of its spacing gets a particle at its centroid, ≥ 1, default 2, `inf` for none): fluid particles removed where they crowd and added where they thin out ([`Scene::particle_management`]); omit for none (the paper's fixed particle set) |
//! | `[run]` | `end_time` (s), `max_dt` (s), `courant`, `output_interval` (s), `alpha`; each defaults to [`RunSettings::default`]; `pressure_stabilisation` (factor α ≥ 0, default 0: [`Scene::pressure_stabilisation`]) |
//! | `[[body]]` | `name`, `kind` (`fluid`, `solid`, `wall`), `material`, `geometry`, `spacing` (m), `velocity` (initial, m/s), `wall_velocity` (walls, m/s), `motion` (walls: `sinusoidal = { amplitude, period, ramp }` (m, s, s), `table = [[t, dx, dy], …]` (s, m) or `rotation = { center, axis (3D), rate, amplitude, period, ramp }` (m, –, rad/s, rad, s, s)), `clamp` (solids: `{ min, max }`, m), `clamps` (solids: a list of such boxes), `velocity_field` and `pressure_field` (fluids/solids and fluids: `{ points = [[x, y], …], values = […] }` (points m; values m/s or Pa), the nearest sample's value; points whose box misses the body's by more than two spacings are refused) |
//! | `material` | `newtonian = { density, viscosity, bulk_modulus }` (kg/m³, Pa·s, Pa) or `hypoelastic = { density, young, poisson, plane_stress }` (kg/m³, Pa, –; `plane_stress = true` in 2D for a thin strip, plane strain by default) |
//! | `[contact]` | `stiffness` (Pa), `damping` (dimensionless: the dashpot's time constant in steps, default 0.1), `onset` (the penalty's rounded onset, a fraction of the contact distance, half the sum of the two bodies' spacings, in `[0, 0.5]`, default 0.01), `friction = [{ bodies = ["a", "b"], mu = 0.3 }, …]`, `clamped` (`true`: clamped solids too, default `false`): contact of free solids (no clamp) with walls and other solids |
//! | `geometry` | `box = { min, max }`, `ball = { center, radius }`, `cylinder = { base, axis, radius, height }` (3D; `axis` the index of the coordinate axis it runs along, 0, 1 or 2, not a vector; `base` the centre of its bottom face, m), `polygon = [[x, y], …]` (2D, a closed polygon), `stl = { file, scale, offset }` (3D, a closed triangle surface; `file` relative to the scene file, `scale` to metres, default 1) or `particles = [[x, y], …]` (m) |
//! | `probes` | columns of `probes.csv`: see [`ProbeSpec`] |
//! | `[[force]]` | a force on a solid in time, split evenly among the body's free (not clamped or welded) particles in `region`: `body`, `region = { min, max }` (m, optional: the whole body), and `value = [fx, fy]` (N; N/m in 2D) with an optional `ramp` (s), or `table = [[t, fx, fy], …]` (s, N): [`ForceSpec`] |
//!
//! A malformed file (syntax, unknown key, wrong type, wrong number of
//! coordinates) is a [`SceneError::File`] naming the line; impossible values
//! (negative spacing, `end_time ≤ 0`, a fluid without material…) are the
//! typed errors of [`Scene::validate`].

use std::ops::Range;
use std::path::Path;

use pfem_constitutive::{Hypoelastic, Material, Newtonian};
use pfem_core::{Const, Dim, ParticleKind, Point, Vector};
use serde::Deserialize;
use toml::Spanned;

use crate::observe::Probe;
use crate::scene::{Geometry, RunSettings, Scene, WallMotion};
use crate::simulation::Simulation;
use crate::SceneError;
use pfem_io::Loads;
use std::sync::{Arc, Mutex};

/// A list of coordinates (`[x, y]` or `[x, y, z]`) with its place in the
/// file, so that a wrong length can name its line.
pub type Coords = Spanned<Vec<f64>>;

/// A scene file: the top-level table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Scene name (output file names, summary); default: the file's stem.
    #[serde(default)]
    pub name: Option<String>,
    /// Dimension: 2 (a slice of unit depth: plane strain, or plane stress
    /// for a solid that asks) or 3.
    pub dimension: Spanned<u32>,
    /// Body force per unit mass (m/s²); `None` for none.
    #[serde(default)]
    pub gravity: Option<Coords>,
    /// Default particle spacing (m) of the bodies that give none.
    #[serde(default)]
    pub spacing: Option<f64>,
    /// Run settings.
    #[serde(default)]
    pub run: RunSpec,
    /// The bodies (`[[body]]` tables), in order.
    #[serde(default, rename = "body")]
    pub bodies: Vec<Spanned<BodySpec>>,
    /// The probes written to `probes.csv`, in order.
    #[serde(default)]
    pub probes: Vec<Spanned<ProbeSpec>>,
    /// Contact between free solids (also clamped ones with
    /// `clamped = true`) and walls or solids (the `[contact]` table).
    #[serde(default)]
    pub contact: Option<Spanned<ContactSpec>>,
    /// Forces on solids in time (`[[force]]` tables), in order.
    #[serde(default, rename = "force")]
    pub forces: Vec<Spanned<ForceSpec>>,
    /// The domain box, `domain = { min = [..], max = [..] }` (m): fluid
    /// particles that leave it are removed (`Scene::domain`).
    #[serde(default)]
    pub domain: Option<BoxSpec>,
    /// Particle management (the `[particle_management]` table), `None`
    /// for none.
    #[serde(default)]
    pub particle_management: Option<ManagementSpec>,
    /// The file's text, to turn spans into line numbers.
    #[serde(skip)]
    source: String,
    /// The file's path, for messages.
    #[serde(skip)]
    path: String,
}

/// The `[run]` table; every key defaults to [`RunSettings::default`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// End time (s).
    pub end_time: Option<f64>,
    /// Largest time step (s).
    pub max_dt: Option<f64>,
    /// Courant number.
    pub courant: Option<f64>,
    /// Interval between VTU frames (s).
    pub output_interval: Option<f64>,
    /// Alpha of the alpha shape.
    pub alpha: Option<f64>,
    /// Pressure stabilisation factor ([`Scene::pressure_stabilisation`]).
    pub pressure_stabilisation: Option<f64>,
}

/// What a body is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BodyKind {
    /// A fluid (needs a `newtonian` material).
    Fluid,
    /// A solid (needs a `hypoelastic` material; any geometry).
    Solid,
    /// A rigid wall (no material).
    Wall,
}

/// A `[[body]]` table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name, used by probes and in messages.
    pub name: String,
    /// Fluid, solid or wall.
    pub kind: BodyKind,
    /// Material (fluids and solids).
    #[serde(default)]
    pub material: Option<Spanned<MaterialSpec>>,
    /// Where its particles are.
    pub geometry: Spanned<GeometrySpec>,
    /// Particle spacing (m); default the file's top-level `spacing`.
    #[serde(default)]
    pub spacing: Option<f64>,
    /// Initial velocity (m/s) of a fluid or solid.
    #[serde(default)]
    pub velocity: Option<Coords>,
    /// Prescribed velocity (m/s) of a wall; fixed when omitted.
    #[serde(default)]
    pub wall_velocity: Option<Coords>,
    /// Initial velocity per particle of a fluid or solid, as sample points:
    /// `velocity_field = { points = [[x, y], …], values = [[vx, vy], …] }`
    /// (m, m/s); each particle takes the value of the nearest point.
    #[serde(default)]
    pub velocity_field: Option<Spanned<FieldSpec>>,
    /// Initial pressure per particle of a fluid, as sample points:
    /// `pressure_field = { points = [[x, y], …], values = [p, …] }` (m, Pa);
    /// each particle takes the value of the nearest point (instead of the
    /// hydrostatic start).
    #[serde(default)]
    pub pressure_field: Option<Spanned<FieldSpec>>,
    /// A wall's motion law in time (instead of `wall_velocity`):
    /// `motion.sinusoidal = { amplitude = [ax, ay], period = T, ramp = R }`
    /// (m, s, s; `ramp` optional) or `motion.table = [[t, dx, dy], …]`
    /// (s, m; from `t = 0` with zero displacement, linear in between).
    #[serde(default)]
    pub motion: Option<Spanned<MotionSpec>>,
    /// Solids: particles in this box are clamped (zero velocity).
    #[serde(default)]
    pub clamp: Option<BoxSpec>,
    /// Solids: more clamps, `clamps = [{ min = …, max = … }, …]` (a plate
    /// held at both ends).
    #[serde(default)]
    pub clamps: Vec<BoxSpec>,
}

/// A material table: `newtonian = { … }` or `hypoelastic = { … }`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum MaterialSpec {
    /// A quasi-incompressible Newtonian fluid.
    Newtonian {
        /// Density (kg/m³).
        density: f64,
        /// Dynamic viscosity (Pa·s).
        viscosity: f64,
        /// Bulk modulus (Pa).
        bulk_modulus: f64,
    },
    /// A hypoelastic solid.
    Hypoelastic {
        /// Density (kg/m³).
        density: f64,
        /// Young's modulus (Pa).
        young: f64,
        /// Poisson's ratio.
        poisson: f64,
        /// 2D only: plane stress (a thin strip, `σ_zz = 0`) instead of the
        /// default plane strain.
        #[serde(default)]
        plane_stress: bool,
    },
}

/// The `[contact]` table: `stiffness` (Pa), `damping`, `onset`, `friction =
/// [{ bodies = ["a", "b"], mu = 0.3 }, …]` and `clamped`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Normal penalty stiffness (Pa); default, for each contact element, the
    /// smallest P-wave modulus of its solids (`pfem::scene::ContactSettings::stiffness`).
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Normal damping, dimensionless (the dashpot `c Δt K_c`: its time
    /// constant in steps), default 0.1.
    #[serde(default)]
    pub damping: Option<f64>,
    /// Width of the penalty's rounded onset, a fraction of the contact
    /// distance in `[0, 0.5]` (`pfem::scene::ContactSettings::onset`),
    /// default 1e-2; 0 for the plain penalty.
    #[serde(default)]
    pub onset: Option<f64>,
    /// Friction coefficients by pair of bodies.
    #[serde(default)]
    pub friction: Vec<FrictionSpec>,
    /// Clamped solids take part in contact too
    /// (`pfem::scene::ContactSettings::clamped`), default `false`.
    #[serde(default)]
    pub clamped: bool,
}

/// A `[[force]]` table: a force on a solid in time
/// ([`Scene::force`]): `body`, `region = { min, max }` (m; optional: the
/// whole body) and either `value = [fx, fy]` (N; N per metre of depth in
/// 2D) with `ramp` (s, optional: grown linearly from 0 over it) or
/// `table = [[t, fx, fy], …]` (s, N; linear between rows, the last row's
/// value after it, the first's before it).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    /// The solid body's name.
    pub body: String,
    /// The box its loaded particles start in (m); the whole body if absent.
    #[serde(default)]
    pub region: Option<BoxSpec>,
    /// A constant force (N; N/m in 2D).
    #[serde(default)]
    pub value: Option<Coords>,
    /// Ramp of `value` from 0 (s).
    #[serde(default)]
    pub ramp: Option<f64>,
    /// A table of `[t, f…]` rows (s, N).
    #[serde(default)]
    pub table: Option<Spanned<Vec<Vec<f64>>>>,
}

/// `{ bodies = ["a", "b"], mu = 0.3 }`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionSpec {
    /// The two bodies (exactly two names).
    #[serde(deserialize_with = "two_names")]
    pub bodies: [String; 2],
    /// Coulomb coefficient (≥ 0).
    pub mu: f64,
}

/// Exactly two names: a sequence of any other length is refused (read as
/// `[String; 2]`, the extra names were dropped unseen).
fn two_names<'de, De: serde::Deserializer<'de>>(d: De) -> Result<[String; 2], De::Error> {
    let names = Vec::<String>::deserialize(d)?;
    let n = names.len();
    <[String; 2]>::try_from(names)
        .map_err(|_| serde::de::Error::custom(format!("expected exactly 2 body names, got {n}")))
}

/// The `[particle_management]` table ([`Scene::particle_management`]):
/// every key optional.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ManagementSpec {
    /// Steps between two passes; default 1.
    pub every: Option<u64>,
    /// A fluid particle closer than this fraction of the spacing to another
    /// is removed; default 0.3, 0 for no removal.
    pub removal_fraction: Option<f64>,
    /// A fluid element larger than this many times the regular one of its
    /// spacing gets a particle at its centroid; default 2, `inf` for no
    /// insertion.
    pub insertion_factor: Option<f64>,
}

/// An axis-aligned box `{ min = [..], max = [..] }` (m).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Lower corner (m).
    pub min: Coords,
    /// Upper corner (m).
    pub max: Coords,
}

/// A geometry table: `box = { … }`, `ball = { … }`, `cylinder = { … }`,
/// `polygon = [ … ]`, `stl = { … }` or `particles = [ … ]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum GeometrySpec {
    /// An axis-aligned box filled with a lattice.
    Box(BoxSpec),
    /// A disk (2D) or ball (3D) filled with a lattice.
    Ball {
        /// Centre (m).
        center: Coords,
        /// Radius (m).
        radius: f64,
    },
    /// The particles themselves (m).
    Particles(Vec<Coords>),
    /// A right circular cylinder (3D): `{ base, axis, radius, height }`.
    Cylinder {
        /// Centre of the bottom disk (m).
        base: Coords,
        /// Coordinate axis (0, 1 or 2).
        axis: usize,
        /// Radius (m).
        radius: f64,
        /// Height (m).
        height: f64,
    },
    /// The inside of a closed polygon (2D): `[[x, y], …]` (m), in order.
    Polygon(Vec<Coords>),
    /// The inside of the closed triangle surface of an STL file (3D).
    Stl(StlSpec),
}

/// An STL file `{ file = "part.stl", scale = 0.001, offset = [x, y, z] }`:
/// `file` relative to the scene file's folder; coordinates times `scale`
/// (default 1; 0.001 for millimetres) plus `offset` (m, default 0).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StlSpec {
    /// The file, relative to the scene file's folder.
    pub file: String,
    /// Scale from the file's unit to metres.
    #[serde(default = "one")]
    pub scale: f64,
    /// Offset added after scaling (m).
    #[serde(default)]
    pub offset: Option<Coords>,
}

fn one() -> f64 {
    1.0
}

/// Sampled values of an initial field: each particle takes the value of the
/// nearest sample point. Two or more points whose box misses the body's by
/// more than two spacings (given in millimetres) are refused.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldSpec {
    /// Sample points (m).
    pub points: Vec<Vec<f64>>,
    /// One value per point: a number (pressure) or a vector (velocity).
    pub values: Vec<FieldValue>,
}

/// A sample value: a scalar or a vector.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum FieldValue {
    /// A number.
    Scalar(f64),
    /// A vector.
    Vector(Vec<f64>),
}

/// A wall's motion law in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum MotionSpec {
    /// `d(t) = A sin(2π t/T)`, its amplitude ramped from 0 over `ramp`.
    Sinusoidal {
        /// Amplitude vector (m).
        amplitude: Coords,
        /// Period (s).
        period: f64,
        /// Ramp duration (s), 0 by default.
        #[serde(default)]
        ramp: f64,
    },
    /// Rows `[t, dx, dy(, dz)]` (s, m), linear in between.
    Table(Vec<Vec<f64>>),
    /// A rotation about `center` (and `axis` in 3D) by
    /// `θ(t) = rate t + amplitude sin(2π t/period)` (rad), the amplitude
    /// ramped from 0 over `ramp` (a flap hinged at `center`).
    Rotation {
        /// Centre of rotation (m).
        center: Coords,
        /// Axis (3D only).
        #[serde(default)]
        axis: Option<Coords>,
        /// Steady rate (rad/s), 0 by default.
        #[serde(default)]
        rate: f64,
        /// Oscillation amplitude (rad), 0 by default.
        #[serde(default)]
        amplitude: f64,
        /// Oscillation period (s); needed with an amplitude.
        #[serde(default)]
        period: f64,
        /// Ramp duration (s), 0 by default.
        #[serde(default)]
        ramp: f64,
    },
}

/// A probe: a column of `probes.csv`, sampled after every step. Written as
/// a name (`"volume"`) or, with parameters, as a one-key table
/// (`{ body_displacement = { body = "gate", point = [0.1025, 0.0025] } }`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ProbeSpec {
    /// `volume`: fluid volume (m³; m² per metre in 2D).
    Volume,
    /// `max_speed`: largest fluid particle speed (m/s).
    MaxSpeed,
    /// `front_x`: largest `x` of the main fluid body (m), as
    /// [`crate::cases::front_x`] (3D: [`crate::cases3d::front_x`]); NaN
    /// with no main body.
    FrontX,
    /// `height_at_wall`: height (`y`) of the main fluid body within 1.5
    /// spacings of `x = 0` (m), as [`crate::cases::height_at_wall`] (3D:
    /// [`crate::cases3d::height_at_wall`]).
    HeightAtWall,
    /// `bottom_pressure` (2D): mean pressure of the wetted floor particles
    /// at `y = 0` (Pa), as [`crate::cases::bottom_pressure`]: the dam
    /// break's layout, a floor whose top row is at `y = 0` (NaN without
    /// one, 0 where it is dry).
    BottomPressure,
    /// `body_displacement`: displacement (m) of the particles of `body`
    /// that started within `radius` of `point` (the nearest one when
    /// `radius` is omitted or no particle is that close); columns
    /// `ux_NAME`, `uy_NAME` (and `uz_NAME`), `NAME` defaulting to the body.
    /// Meant for solids, whose particles stay: on a fluid body whose
    /// particles are removed or inserted (a domain, particle management,
    /// an inflow) the particles are chosen again at each change, from
    /// where each entered the simulation, so the series may jump.
    BodyDisplacement {
        /// The body.
        body: String,
        /// Initial position of the point followed (m).
        point: Coords,
        /// Radius around `point` (m).
        #[serde(default)]
        radius: Option<f64>,
        /// Column suffix; default the body's name.
        #[serde(default)]
        name: Option<String>,
    },
    /// `force`: the pressure force of the fluid on `body` (N; N per metre
    /// in 2D), `pfem_io::Loads::pressure_force_on`; columns `fx_NAME`,
    /// `fy_NAME` (and `fz_NAME`), `NAME` defaulting to the body.
    Force {
        /// The body.
        body: String,
        /// Column suffix; default the body's name.
        #[serde(default)]
        name: Option<String>,
    },
    /// `contact_force`: the contact force body `from` exerts on body `on`
    /// (N; N per metre in 2D), `pfem_io::Loads::contact_force`, both walls
    /// or solids; columns `cfx_NAME`, `cfy_NAME` (and `cfz_NAME`), its
    /// component along the mean contact normal `cn_NAME` (positive when it
    /// pushes) and the magnitude of the rest `ct_NAME` (friction), `NAME`
    /// defaulting to `ON_FROM`. Zero while they do not touch. (The `force`
    /// probe reads the water's pressure only: a block resting on a floor
    /// gave no scene-file probe of its contact: session 54's review.)
    ContactForce {
        /// The body acted on.
        on: String,
        /// The body acting.
        from: String,
        /// Column suffix; default `ON_FROM`.
        #[serde(default)]
        name: Option<String>,
    },
    /// `point`: the fluid's pressure (Pa) and velocity (m/s) at a fixed
    /// point, interpolated in the fluid element holding it (NaN where no
    /// fluid element does: a dry point); columns `p_NAME`, `vx_NAME`,
    /// `vy_NAME` (and `vz_NAME`).
    Point {
        /// The point (m).
        at: Coords,
        /// Column suffix.
        name: String,
    },
}

impl ProbeSpec {
    fn label(&self) -> &'static str {
        match self {
            ProbeSpec::Volume => "volume",
            ProbeSpec::MaxSpeed => "max_speed",
            ProbeSpec::FrontX => "front_x",
            ProbeSpec::HeightAtWall => "height_at_wall",
            ProbeSpec::BottomPressure => "bottom_pressure",
            ProbeSpec::BodyDisplacement { .. } => "body_displacement",
            ProbeSpec::Force { .. } => "force",
            ProbeSpec::ContactForce { .. } => "contact_force",
            ProbeSpec::Point { .. } => "point",
        }
    }
}

/// A loaded scene of either dimension with its probes.
pub enum LoadedScene {
    /// A 2D (plane strain) scene.
    Two(Scene<2>, Vec<Probe<2>>),
    /// A 3D scene.
    Three(Scene<3>, Vec<Probe<3>>),
}

impl std::fmt::Debug for LoadedScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names = |p: &mut dyn Iterator<Item = &String>| p.cloned().collect::<Vec<_>>();
        match self {
            LoadedScene::Two(s, p) => f
                .debug_tuple("Two")
                .field(s)
                .field(&names(&mut p.iter().map(|p| &p.name)))
                .finish(),
            LoadedScene::Three(s, p) => f
                .debug_tuple("Three")
                .field(s)
                .field(&names(&mut p.iter().map(|p| &p.name)))
                .finish(),
        }
    }
}

/// What parsing a scene file holds per byte of its text, an upper bound
/// (measured 75: a 20 MB file of numbers took 1.5 GB): [`SceneFile::parse`]
/// refuses a text whose parse would not fit
/// [`pfem_scene::default_memory_budget`].
pub const PARSE_BYTES_PER_BYTE: f64 = 100.0;

/// Why a text of `len` bytes cannot be parsed within `budget` bytes, if so.
fn parse_fits(len: usize, budget: f64) -> Result<(), String> {
    let need = PARSE_BYTES_PER_BYTE * len as f64;
    if need > budget {
        return Err(format!(
            "{len} bytes would take about {need:.2e} bytes to parse, over the memory budget of {budget:.2e} (particles and fields this large belong in files of their own)"
        ));
    }
    Ok(())
}

/// Largest scene file [`SceneFile::read`] reads (bytes): 256 MiB (and
/// less where parsing it would not fit the memory budget,
/// [`PARSE_BYTES_PER_BYTE`]).
pub const MAX_SCENE_FILE_BYTES: u64 = 256 << 20;

impl SceneFile {
    /// Reads and parses the file at `path`: a regular file of at most
    /// [`MAX_SCENE_FILE_BYTES`].
    ///
    /// # Errors
    ///
    /// [`SceneError::File`] if it cannot be read or is malformed (with the
    /// line and the field).
    pub fn read(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        let path = path.as_ref();
        let fail = |why: String| SceneError::File {
            path: path.display().to_string(),
            why,
        };
        // A device or a pipe (`/dev/zero`) would be read without end.
        let meta = std::fs::metadata(path).map_err(|e| fail(e.to_string()))?;
        if !meta.is_file() {
            return Err(fail("not a regular file".into()));
        }
        if meta.len() > MAX_SCENE_FILE_BYTES {
            return Err(fail(format!(
                "{} bytes, more than a scene file's {MAX_SCENE_FILE_BYTES} (particles and fields this large belong in files of their own)",
                meta.len()
            )));
        }
        // Its parse's memory, before the text is read.
        parse_fits(meta.len() as usize, pfem_scene::default_memory_budget()).map_err(fail)?;
        let text = std::fs::read_to_string(path).map_err(|e| fail(e.to_string()))?;
        let mut file = Self::parse(&text, &path.display().to_string())?;
        if file.name.is_none() {
            file.name = path.file_stem().map(|s| s.to_string_lossy().into_owned());
        }
        Ok(file)
    }

    /// Parses `text`; `path` only names the file in messages.
    ///
    /// # Errors
    ///
    /// [`SceneError::File`] if the text is malformed: TOML syntax, an
    /// unknown or missing key, a value of the wrong type, a dimension other
    /// than 2 or 3. The message names the line and column.
    pub fn parse(text: &str, path: &str) -> Result<Self, SceneError> {
        // The TOML parser holds about 75 bytes per byte of text (a 20 MB
        // file of numbers took 1.5 GB, session 45): a file whose parse
        // would not fit the memory budget is refused before it starts.
        parse_fits(text.len(), pfem_scene::default_memory_budget()).map_err(|why| {
            SceneError::File {
                path: path.to_string(),
                why,
            }
        })?;
        let mut file: SceneFile = toml::from_str(text).map_err(|e| {
            let why = match e.span() {
                Some(span) => {
                    let (line, col) = line_col(text, span.start);
                    let key = key_before(text, span.start)
                        .map(|k| format!("`{k}`: "))
                        .unwrap_or_default();
                    format!("line {line}, column {col}: {key}{}", e.message().trim_end())
                }
                None => e.message().trim_end().to_string(),
            };
            SceneError::File {
                path: path.to_string(),
                why,
            }
        })?;
        file.source = text.to_string();
        file.path = path.to_string();
        let d = *file.dimension.get_ref();
        if d != 2 && d != 3 {
            return Err(file.error(
                file.dimension.span(),
                format!("`dimension` must be 2 or 3, got {d}"),
            ));
        }
        Ok(file)
    }

    /// Reads the file at `path` and builds its scene (validated) and
    /// probes in the file's dimension, after the overrides: `spacing`
    /// replaces every body's spacing, `end_time` the run's end time.
    ///
    /// # Errors
    ///
    /// [`SceneError::File`] for a malformed file, the typed errors of
    /// [`Scene::validate`] for impossible values.
    pub fn load(
        path: impl AsRef<Path>,
        spacing: Option<f64>,
        end_time: Option<f64>,
    ) -> Result<LoadedScene, SceneError> {
        let mut file = Self::read(path)?;
        if let Some(h) = spacing {
            file.override_spacing(h);
        }
        if let Some(t) = end_time {
            file.run.end_time = Some(t);
        }
        file.build()
    }

    /// Builds the scene (validated) and the probes in the file's dimension.
    ///
    /// # Errors
    ///
    /// As [`SceneFile::scene`] and [`SceneFile::probes_2d`].
    pub fn build(&self) -> Result<LoadedScene, SceneError> {
        Ok(match self.dimension() {
            2 => LoadedScene::Two(self.scene::<2>()?, self.probes_2d()?),
            _ => LoadedScene::Three(self.scene::<3>()?, self.probes_3d()?),
        })
    }

    /// The dimension, 2 or 3.
    pub fn dimension(&self) -> usize {
        *self.dimension.get_ref() as usize
    }

    /// The scene name: `name`, else the file's stem, else `"scene"`.
    pub fn scene_name(&self) -> String {
        self.name.clone().unwrap_or_else(|| "scene".into())
    }

    /// The file's text, as read.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// What differs between this file and `other` as a restart sees it:
    /// the names of the keys (a body's by its name) whose values differ,
    /// in the file's order; empty when they describe the same run. The run
    /// may go on to another end time and write frames at another interval:
    /// `[run]`'s `end_time` and `output_interval` are not compared, nor the
    /// scene's name (a checkpoint names its scene) or layout and comments.
    /// Compare the files after the same overrides
    /// ([`SceneFile::override_spacing`]).
    pub fn differences(&self, other: &SceneFile) -> Vec<String> {
        let mut out = Vec::new();
        let mut differs = |same: bool, key: &str| {
            if !same {
                out.push(key.to_string());
            }
        };
        differs(self.dimension == other.dimension, "dimension");
        differs(self.gravity == other.gravity, "gravity");
        differs(self.spacing == other.spacing, "spacing");
        let run = |r: &RunSpec| RunSpec {
            end_time: None,
            output_interval: None,
            ..*r
        };
        differs(run(&self.run) == run(&other.run), "[run]");
        differs(self.domain == other.domain, "domain");
        differs(
            self.particle_management == other.particle_management,
            "[particle_management]",
        );
        let names = |f: &SceneFile| -> Vec<String> {
            f.bodies.iter().map(|b| b.get_ref().name.clone()).collect()
        };
        if names(self) != names(other) {
            differs(false, "the bodies (their names or order)");
        } else {
            for (a, b) in self.bodies.iter().zip(&other.bodies) {
                differs(a == b, &format!("body `{}`", a.get_ref().name));
            }
        }
        differs(self.contact == other.contact, "[contact]");
        differs(self.forces == other.forces, "[[force]]");
        differs(self.probes == other.probes, "probes");
        out
    }

    /// Replaces the spacing of every body (and the default) by `h` (m).
    pub fn override_spacing(&mut self, h: f64) {
        self.spacing = Some(h);
        for b in &mut self.bodies {
            b.get_mut().spacing = Some(h);
        }
    }

    /// The run settings: the `[run]` table over [`RunSettings::default`].
    pub fn settings(&self) -> RunSettings {
        let d = RunSettings::default();
        let r = &self.run;
        RunSettings {
            end_time: r.end_time.unwrap_or(d.end_time),
            max_dt: r.max_dt.unwrap_or(d.max_dt),
            courant: r.courant.unwrap_or(d.courant),
            output_interval: r.output_interval.or(d.output_interval),
            alpha: r.alpha.unwrap_or(d.alpha),
        }
    }

    /// The scene in `D` dimensions, checked with [`Scene::validate`].
    ///
    /// # Errors
    ///
    /// [`SceneError::File`] (with the line) if `D` is not the file's
    /// dimension, a coordinate list has the wrong length, a body has no
    /// spacing, a material's parameters are invalid or a key does not fit
    /// the body's kind (a wall's material, a fluid's clamp…);
    /// [`SceneError::MissingMaterial`] for a fluid or solid without one;
    /// any error of [`Scene::validate`].
    pub fn scene<const D: usize>(&self) -> Result<Scene<D>, SceneError>
    where
        Const<D>: Dim,
    {
        if self.dimension() != D {
            return Err(self.error(
                self.dimension.span(),
                format!(
                    "the file is a {}D scene, not {D}D",
                    self.dimension.get_ref()
                ),
            ));
        }
        let mut scene = Scene::<D>::new(self.scene_name())
            .settings(self.settings())
            .pressure_stabilisation(self.run.pressure_stabilisation.unwrap_or(0.0));
        if let Some(g) = &self.gravity {
            scene = scene.gravity(self.vector::<D>(g, "gravity")?);
        }
        if let Some(d) = &self.domain {
            scene = scene.domain(
                Point::from(self.vector::<D>(&d.min, "domain.min")?),
                Point::from(self.vector::<D>(&d.max, "domain.max")?),
            );
        }
        if let Some(m) = &self.particle_management {
            let d = pfem_geometry::ParticleManagementParams::default();
            scene = scene.particle_management(
                pfem_geometry::ParticleManagementParams {
                    removal_fraction: m.removal_fraction.unwrap_or(d.removal_fraction),
                    insertion_factor: m.insertion_factor.unwrap_or(d.insertion_factor),
                },
                m.every.unwrap_or(1),
            );
        }
        for spanned in &self.bodies {
            let b = spanned.get_ref();
            let at = spanned.span();
            let what = |key: &str| format!("body `{}`: `{key}`", b.name);
            let spacing = b.spacing.or(self.spacing).ok_or_else(|| {
                self.error(
                    at.clone(),
                    format!(
                        "body `{}` has no `spacing` (give it in the body or at the top)",
                        b.name
                    ),
                )
            })?;
            let geometry = self.geometry::<D>(&b.geometry, &b.name)?;
            // Where a field's samples must reach (a field given in
            // millimetres lies far outside the body it is for).
            let reach = {
                let (lo, hi) = geometry.bounds();
                (lo, hi, spacing)
            };
            let material = match (&b.material, b.kind) {
                (Some(m), BodyKind::Wall) => {
                    return Err(self.error(
                        m.span(),
                        format!("body `{}`: a wall has no material", b.name),
                    ))
                }
                (Some(m), _) => Some(self.material::<D>(m, &b.name)?),
                (None, BodyKind::Wall) => None,
                (None, _) => {
                    return Err(SceneError::MissingMaterial {
                        body: b.name.clone(),
                    })
                }
            };
            if b.kind != BodyKind::Wall {
                if let Some(m) = &b.motion {
                    return Err(
                        self.error(m.span(), format!("{} is for walls only", what("motion")))
                    );
                }
                if let Some(w) = &b.wall_velocity {
                    return Err(self.error(
                        w.span(),
                        format!("{} is for walls only", what("wall_velocity")),
                    ));
                }
            }
            if b.kind == BodyKind::Wall {
                if let Some(v) = &b.velocity {
                    return Err(self.error(
                        v.span(),
                        format!(
                            "{} is the initial velocity of a fluid or solid; a wall moves with `wall_velocity`",
                            what("velocity")
                        ),
                    ));
                }
            }
            if b.kind != BodyKind::Solid {
                if let Some(c) = b.clamp.as_ref().or(b.clamps.first()) {
                    return Err(self.error(
                        c.min.span(),
                        format!("{} is for solids only", what("clamp")),
                    ));
                }
            }
            scene = match (b.kind, material) {
                // (A fluid or solid without material returned above.)
                (BodyKind::Wall, _) | (_, None) => {
                    let motion = match (&b.wall_velocity, &b.motion) {
                        (Some(_), Some(m)) => {
                            return Err(self.error(
                                m.span(),
                                format!(
                                    "{} and {} exclude each other",
                                    what("wall_velocity"),
                                    what("motion")
                                ),
                            ))
                        }
                        (Some(w), None) => {
                            WallMotion::Velocity(self.vector::<D>(w, &what("wall_velocity"))?)
                        }
                        (None, Some(m)) => {
                            WallMotion::Law(self.motion_law::<D>(m, &what("motion"))?)
                        }
                        (None, None) => WallMotion::Fixed,
                    };
                    scene.wall(&b.name, geometry, spacing, motion)
                }
                (BodyKind::Fluid, Some(m)) => scene.fluid(&b.name, m, geometry, spacing),
                (BodyKind::Solid, Some(m)) => {
                    let clamp = match &b.clamp {
                        Some(c) => Some((
                            Point::from(self.vector::<D>(&c.min, &what("clamp.min"))?),
                            Point::from(self.vector::<D>(&c.max, &what("clamp.max"))?),
                        )),
                        None => None,
                    };
                    let mut s = scene.solid(&b.name, m, geometry, spacing, clamp);
                    for c in &b.clamps {
                        s = s.clamp_box(
                            Point::from(self.vector::<D>(&c.min, &what("clamps.min"))?),
                            Point::from(self.vector::<D>(&c.max, &what("clamps.max"))?),
                        );
                    }
                    s
                }
            };
            if let Some(v) = &b.velocity {
                scene = scene.with_velocity(self.vector::<D>(v, &what("velocity"))?);
            }
            if let Some(f) = &b.velocity_field {
                if b.velocity.is_some() {
                    return Err(self.error(
                        f.span(),
                        format!(
                            "{} and {} exclude each other",
                            what("velocity"),
                            what("velocity_field")
                        ),
                    ));
                }
                if b.kind == BodyKind::Wall {
                    return Err(self.error(
                        f.span(),
                        format!("{} is for fluids and solids", what("velocity_field")),
                    ));
                }
                let (pts, vals) = self.samples::<D>(f, D, &what("velocity_field"), reach)?;
                let pts = Nearest::new(pts);
                scene = scene.with_velocity_field(move |x| {
                    let v = &vals[pts.nearest(x)];
                    Vector::<D>::from_fn(|k, _| v[k])
                });
            }
            if let Some(f) = &b.pressure_field {
                if b.kind != BodyKind::Fluid {
                    return Err(self.error(
                        f.span(),
                        format!("{} is for fluids", what("pressure_field")),
                    ));
                }
                let (pts, vals) = self.samples::<D>(f, 1, &what("pressure_field"), reach)?;
                let pts = Nearest::new(pts);
                scene = scene.with_pressure_field(move |x| vals[pts.nearest(x)][0]);
            }
        }
        if let Some(c) = &self.contact {
            let spec = c.get_ref();
            for f in &spec.friction {
                for b in &f.bodies {
                    if !self.bodies.iter().any(|x| &x.get_ref().name == b) {
                        return Err(self.error(
                            c.span(),
                            format!("`contact.friction` names `{b}`, which is no body"),
                        ));
                    }
                }
                scene = scene.friction(&f.bodies[0], &f.bodies[1], f.mu);
            }
            if let Some(k) = spec.stiffness {
                scene = scene.contact_stiffness(k);
            }
            if let Some(d) = spec.damping {
                scene = scene.contact_damping(d);
            }
            if let Some(d) = spec.onset {
                scene = scene.contact_onset(d);
            }
            scene = scene.contact_clamped(spec.clamped);
        }
        for f in &self.forces {
            let (span, spec) = (f.span(), f.get_ref());
            let region = match &spec.region {
                Some(r) => Some((
                    Point::from(self.vector::<D>(&r.min, "force.region.min")?),
                    Point::from(self.vector::<D>(&r.max, "force.region.max")?),
                )),
                None => None,
            };
            // The times at which the force's slope changes (a ramp's end, a
            // table's rows): steps end there.
            let mut kinks = Vec::new();
            let law: Box<dyn Fn(f64) -> Vector<D> + Send + Sync> = match (&spec.value, &spec.table)
            {
                (Some(v), None) => {
                    let v = self.vector::<D>(v, "force.value")?;
                    let ramp = spec.ramp.unwrap_or(0.0);
                    if !(ramp >= 0.0 && ramp.is_finite()) {
                        return Err(self.error(
                            span,
                            format!("force.ramp must be non-negative and finite, got {ramp}"),
                        ));
                    }
                    if ramp > 0.0 {
                        kinks.push(ramp);
                    }
                    Box::new(move |t| {
                        if ramp > 0.0 {
                            v * (t / ramp).clamp(0.0, 1.0)
                        } else {
                            v
                        }
                    })
                }
                (None, Some(table)) => {
                    let rows = table.get_ref().clone();
                    let good = !rows.is_empty()
                        && rows
                            .iter()
                            .all(|r| r.len() == D + 1 && r.iter().all(|x| x.is_finite()))
                        && rows.windows(2).all(|w| w[1][0] > w[0][0]);
                    if !good || spec.ramp.is_some() {
                        return Err(self.error(
                                table.span(),
                                format!(
                                    "force.table needs rows of {} finite numbers [t, f…] with increasing t (and no ramp)",
                                    D + 1
                                ),
                            ));
                    }
                    kinks.extend(rows.iter().map(|r| r[0]));
                    Box::new(move |t| {
                        let k = rows.partition_point(|r| r[0] <= t);
                        let at = |r: &Vec<f64>| Vector::<D>::from_fn(|i, _| r[i + 1]);
                        if k == 0 {
                            at(&rows[0])
                        } else if k == rows.len() {
                            at(&rows[k - 1])
                        } else {
                            let (a, b) = (&rows[k - 1], &rows[k]);
                            let s = (t - a[0]) / (b[0] - a[0]);
                            at(a) * (1.0 - s) + at(b) * s
                        }
                    })
                }
                _ => {
                    return Err(self.error(
                        span,
                        "a [[force]] needs `value` (with an optional `ramp`) or `table`, not both"
                            .into(),
                    ))
                }
            };
            scene = scene.force_with_kinks(&spec.body, region, law, kinks);
        }
        scene.validate()?;
        Ok(scene)
    }

    /// Where in the file a validation error belongs: `line L, column C` of
    /// the body it names, or `None` (the file's own errors carry their line
    /// already; typed errors stay typed, and `pfem` prints this beside
    /// them).
    pub fn locate(&self, e: &SceneError) -> Option<String> {
        let body = match e {
            SceneError::InvalidSpacing { body, .. }
            | SceneError::SpacingLargerThanBody { body, .. }
            | SceneError::InvalidGeometry { body, .. }
            | SceneError::InvalidMaterial { body, .. }
            | SceneError::MissingMaterial { body }
            | SceneError::MaterialKindMismatch { body }
            | SceneError::Unsupported { body } => Some(body.clone()),
            SceneError::Overlap { second, .. } => Some(second.clone()),
            _ => None,
        };
        if let Some(b) = body {
            let spec = self.bodies.iter().rev().find(|s| s.get_ref().name == b)?;
            let (line, col) = line_col(&self.source, spec.span().start);
            return Some(format!("line {line}, column {col}"));
        }
        // Settings: the line of their key, else of the `[run]` table. The
        // `[contact]` table's keys drop the `contact_` of the setting's name.
        let keys: &[&str] = match e {
            SceneError::InvalidSetting { setting, .. }
            | SceneError::OutOfRange { setting, .. }
            | SceneError::NonFinite { setting } => match *setting {
                "contact_damping" => &["damping"],
                "contact_onset" => &["onset"],
                "contact_stiffness" => &["stiffness"],
                // (The `[particle_management]` table's keys, else the table.)
                "particle_management.every" => &["every", "[particle_management]"],
                "particle_management.removal_fraction" => {
                    &["removal_fraction", "[particle_management]"]
                }
                "particle_management.insertion_factor" => {
                    &["insertion_factor", "[particle_management]"]
                }
                _ => std::slice::from_ref(setting),
            },
            // The scene's own `name`, above the first table: a name taken
            // from the file's stem has no line (before session 49 a body's
            // `name` line was given).
            SceneError::InvalidName { .. } => {
                let top = self
                    .source
                    .lines()
                    .take_while(|l| !l.trim_start().starts_with('['))
                    .collect::<Vec<_>>()
                    .join("\n");
                return key_line(&top, "name").map(|at| format!("line {at}"));
            }
            SceneError::CannotFinish { what, .. } if what.contains("output frames") => {
                &["output_interval", "end_time"]
            }
            SceneError::CannotFinish { what, .. } if what.contains("Courant") => {
                &["velocity", "wall_velocity", "courant", "end_time"]
            }
            SceneError::CannotFinish { .. } => &["max_dt", "end_time"],
            SceneError::TooLarge { .. } => &["spacing"],
            _ => &[],
        };
        let at = keys
            .iter()
            .find_map(|k| key_line(&self.source, k))
            .or_else(|| {
                (!keys.is_empty())
                    .then(|| key_line(&self.source, "[run]"))
                    .flatten()
            })?;
        Some(format!("line {at}"))
    }

    /// The probes of a 2D file.
    ///
    /// # Errors
    ///
    /// [`SceneError::File`] for a probe naming an unknown body, a point of
    /// the wrong dimension or a repeated column.
    pub fn probes_2d(&self) -> Result<Vec<Probe<2>>, SceneError> {
        let mut out = Vec::new();
        let shared = RowShared::new(1.5 * self.fluid_spacing());
        for p in &self.probes {
            match p.get_ref() {
                ProbeSpec::BottomPressure => out
                    .push(Probe::new("bottom_pressure", |s: &Simulation<2>| {
                        crate::cases::bottom_pressure(s)
                    })),
                _ => out.extend(self.any_dimension_probe::<2>(p, &shared)?),
            }
        }
        self.unique(&out)?;
        Ok(out)
    }

    /// The probes of a 3D file.
    ///
    /// # Errors
    ///
    /// As [`SceneFile::probes_2d`], and [`SceneError::File`] for the 2D-only
    /// probe `bottom_pressure`. `front_x` and `height_at_wall` are the 3D
    /// dam break's (`pfem::cases3d`; they were refused before session 43):
    /// the main body's largest `x`, and its largest `y` within 1.5 spacings
    /// of `x = 0`, as in 2D.
    pub fn probes_3d(&self) -> Result<Vec<Probe<3>>, SceneError> {
        let mut out = Vec::new();
        let shared = RowShared::new(1.5 * self.fluid_spacing());
        for p in &self.probes {
            match p.get_ref() {
                ProbeSpec::BottomPressure => {
                    return Err(self.error(
                        p.span(),
                        format!("probe `{}` is for 2D scenes only", p.get_ref().label()),
                    ))
                }
                _ => out.extend(self.any_dimension_probe::<3>(p, &shared)?),
            }
        }
        self.unique(&out)?;
        Ok(out)
    }

    /// Smallest spacing of the fluid bodies (of all bodies if none).
    fn fluid_spacing(&self) -> f64 {
        let of = |b: &BodySpec| b.spacing.or(self.spacing).unwrap_or(f64::INFINITY);
        let fluid = self
            .bodies
            .iter()
            .map(|b| b.get_ref())
            .filter(|b| b.kind == BodyKind::Fluid)
            .map(of)
            .fold(f64::INFINITY, f64::min);
        if fluid.is_finite() {
            fluid
        } else {
            self.bodies
                .iter()
                .map(|b| of(b.get_ref()))
                .fold(f64::INFINITY, f64::min)
        }
    }

    fn any_dimension_probe<const D: usize>(
        &self,
        p: &Spanned<ProbeSpec>,
        shared: &RowShared<D>,
    ) -> Result<Vec<Probe<D>>, SceneError>
    where
        Const<D>: Dim,
    {
        // A given name ends the probe's column names: empty, it named the
        // columns `p_`, `vx_` (session 52's review).
        let given = match p.get_ref() {
            ProbeSpec::BodyDisplacement { name, .. }
            | ProbeSpec::Force { name, .. }
            | ProbeSpec::ContactForce { name, .. } => name.as_deref(),
            ProbeSpec::Point { name, .. } => Some(name.as_str()),
            _ => None,
        };
        if given.is_some_and(|n| n.trim().is_empty()) {
            return Err(self.error(
                p.span(),
                format!(
                    "probe `{}`: `name` must be non-empty (it ends the probe's column names)",
                    p.get_ref().label()
                ),
            ));
        }
        Ok(match p.get_ref() {
            ProbeSpec::FrontX => {
                let body = shared.body.clone();
                vec![Probe::new("front_x", move |s: &Simulation<D>| {
                    main_body_of(&body, s, |m| crate::cases3d::front_x_of(s, m))
                })]
            }
            ProbeSpec::HeightAtWall => {
                let (body, band) = (shared.body.clone(), shared.band);
                vec![Probe::new("height_at_wall", move |s: &Simulation<D>| {
                    main_body_of(&body, s, |m| crate::cases3d::height_at_wall_of(s, band, m))
                })]
            }
            ProbeSpec::Volume => vec![Probe::new("volume", |s: &Simulation<D>| s.fluid_volume())],
            ProbeSpec::MaxSpeed => vec![Probe::new("max_speed", |s: &Simulation<D>| {
                (0..s.particles().len())
                    .filter(|&i| s.particles().kind()[i] == ParticleKind::Fluid)
                    .map(|i| s.particles().v()[i].norm())
                    .fold(0.0, f64::max)
            })],
            ProbeSpec::BodyDisplacement {
                body,
                point,
                radius,
                name,
            } => {
                if !self.bodies.iter().any(|b| &b.get_ref().name == body) {
                    return Err(self.error(
                        p.span(),
                        format!("probe `body_displacement`: no body `{body}`"),
                    ));
                }
                let point = Point::from(self.vector::<D>(point, "body_displacement.point")?);
                if radius.is_some_and(|r| !(r > 0.0 && r.is_finite())) {
                    return Err(self.error(
                        p.span(),
                        format!(
                            "probe `body_displacement`: radius must be positive and finite, got {}",
                            radius.unwrap_or_default()
                        ),
                    ));
                }
                let suffix = name.clone().unwrap_or_else(|| body.clone());
                // The particles followed, chosen again whenever particles
                // come or go (their indices then shift), once for the D
                // columns.
                let chosen: Shared<(u64, Vec<usize>)> = Arc::default();
                (0..D)
                    .map(|k| {
                        let body = body.clone();
                        let radius = *radius;
                        let chosen = chosen.clone();
                        Probe::new(
                            &format!("u{}_{suffix}", ["x", "y", "z"][k]),
                            move |s: &Simulation<D>| {
                                let generation = s.particles().generation();
                                let mut chosen = chosen.lock().unwrap_or_else(|e| e.into_inner());
                                if chosen.as_ref().is_none_or(|c| c.0 != generation) {
                                    *chosen =
                                        Some((generation, followed(s, &body, &point, radius)));
                                }
                                let idx: &[usize] = chosen.as_ref().map_or(&[], |c| &c.1);
                                if idx.is_empty() {
                                    return f64::NAN;
                                }
                                idx.iter()
                                    .map(|&i| s.particles().x()[i][k] - s.initial_position(i)[k])
                                    .sum::<f64>()
                                    / idx.len() as f64
                            },
                        )
                    })
                    .collect()
            }
            ProbeSpec::Force { body, name } => {
                match self.bodies.iter().find(|b| &b.get_ref().name == body) {
                    None => {
                        return Err(self.error(p.span(), format!("probe `force`: no body `{body}`")))
                    }
                    // The water's force on a body; on water itself it read
                    // a round-off 10⁻¹² every row (a review in session 49).
                    Some(b) if b.get_ref().kind == BodyKind::Fluid => {
                        return Err(self.error(
                            p.span(),
                            format!("probe `force`: `{body}` is a fluid (the probe measures the fluids' pressure force on a wall or solid)"),
                        ))
                    }
                    Some(_) => {}
                }
                let suffix = name.clone().unwrap_or_else(|| body.clone());
                // The force, measured once a row for its D columns.
                let force: Shared<(RowKey, Vector<D>)> = Arc::default();
                (0..D)
                    .map(|k| {
                        let body = body.clone();
                        let force = force.clone();
                        Probe::new(
                            &format!("f{}_{suffix}", ["x", "y", "z"][k]),
                            move |s: &Simulation<D>| {
                                let key = row_key(s);
                                let mut f = force.lock().unwrap_or_else(|e| e.into_inner());
                                if f.as_ref().is_none_or(|f| f.0 != key) {
                                    let v = s
                                        .pressure_force_on(&body)
                                        .unwrap_or_else(|_| Vector::<D>::repeat(f64::NAN));
                                    *f = Some((key, v));
                                }
                                f.as_ref().map_or(f64::NAN, |f| f.1[k])
                            },
                        )
                    })
                    .collect()
            }
            ProbeSpec::ContactForce { on, from, name } => {
                for b in [on, from] {
                    match self.bodies.iter().find(|x| &x.get_ref().name == b) {
                        None => {
                            return Err(self.error(
                                p.span(),
                                format!("probe `contact_force`: no body `{b}`"),
                            ))
                        }
                        Some(x) if x.get_ref().kind == BodyKind::Fluid => {
                            return Err(self.error(
                                p.span(),
                                format!("probe `contact_force`: `{b}` is a fluid (contact is between walls and solids)"),
                            ))
                        }
                        Some(_) => {}
                    }
                }
                if on == from {
                    return Err(self.error(
                        p.span(),
                        format!("probe `contact_force`: `on` and `from` are both `{on}`"),
                    ));
                }
                let suffix = name.clone().unwrap_or_else(|| format!("{on}_{from}"));
                // Measured once a row for its D + 2 columns.
                let contact: Shared<(RowKey, Vec<f64>)> = Arc::default();
                let labels: Vec<String> = (0..D)
                    .map(|k| format!("cf{}_{suffix}", ["x", "y", "z"][k]))
                    .chain([format!("cn_{suffix}"), format!("ct_{suffix}")])
                    .collect();
                labels
                    .into_iter()
                    .enumerate()
                    .map(|(k, label)| {
                        let (on, from) = (on.clone(), from.clone());
                        let contact = contact.clone();
                        Probe::new(&label, move |s: &Simulation<D>| {
                            let key = row_key(s);
                            let mut c = contact.lock().unwrap_or_else(|e| e.into_inner());
                            if c.as_ref().is_none_or(|c| c.0 != key) {
                                let v = match s.contact_force(&on, &from) {
                                    Ok(f) => f
                                        .force
                                        .iter()
                                        .copied()
                                        .chain([f.normal, f.tangential])
                                        .collect(),
                                    Err(_) => vec![f64::NAN; D + 2],
                                };
                                *c = Some((key, v));
                            }
                            c.as_ref().map_or(f64::NAN, |c| c.1[k])
                        })
                    })
                    .collect()
            }
            ProbeSpec::Point { at, name } => {
                let at = Point::from(self.vector::<D>(at, "point.at")?);
                // Every point probe of the scene is measured in one pass
                // over the fluid elements, once a row.
                let points = &shared.points;
                let index = {
                    let mut c = points.lock().unwrap_or_else(|e| e.into_inner());
                    c.points.push(at);
                    c.points.len() - 1
                };
                let column = move |k: usize| {
                    let points = points.clone();
                    move |s: &Simulation<D>| {
                        let key = row_key(s);
                        let mut c = points.lock().unwrap_or_else(|e| e.into_inner());
                        if c.key != Some(key) {
                            c.values = s.fluid_at_points(&c.points);
                            c.key = Some(key);
                        }
                        // Column 0 the pressure, 1..=D the velocity.
                        c.values[index].map_or(f64::NAN, |(p, u)| if k == 0 { p } else { u[k - 1] })
                    }
                };
                let mut v = vec![Probe::new(&format!("p_{name}"), column(0))];
                v.extend((0..D).map(|k| {
                    Probe::new(&format!("v{}_{name}", ["x", "y", "z"][k]), column(k + 1))
                }));
                v
            }
            // The 2D-only probes are handled by the callers.
            _ => Vec::new(),
        })
    }

    fn unique<const D: usize>(&self, probes: &[Probe<D>]) -> Result<(), SceneError>
    where
        Const<D>: Dim,
    {
        // (A set: a million probes compared each against every earlier one
        // took hours, the review of session 45.)
        let mut seen = std::collections::HashSet::with_capacity(probes.len());
        for p in probes {
            // The names head `probes.csv`'s columns.
            if !pfem_scene::is_column_name(&p.name) {
                return Err(SceneError::File {
                    path: self.path.clone(),
                    why: format!(
                        "probe column {:?}: a name must be non-empty, without commas, quotes or control characters (it heads a CSV column)",
                        p.name
                    ),
                });
            }
            if !seen.insert(p.name.as_str()) {
                return Err(SceneError::File {
                    path: self.path.clone(),
                    why: format!("probe column `{}` appears twice", p.name),
                });
            }
        }
        Ok(())
    }

    fn geometry<const D: usize>(
        &self,
        g: &Spanned<GeometrySpec>,
        body: &str,
    ) -> Result<Geometry<D>, SceneError>
    where
        Const<D>: Dim,
    {
        let what = |key: &str| format!("body `{body}`: `geometry.{key}`");
        Ok(match g.get_ref() {
            GeometrySpec::Box(b) => Geometry::Box {
                min: Point::from(self.vector::<D>(&b.min, &what("box.min"))?),
                max: Point::from(self.vector::<D>(&b.max, &what("box.max"))?),
            },
            GeometrySpec::Ball { center, radius } => Geometry::Ball {
                center: Point::from(self.vector::<D>(center, &what("ball.center"))?),
                radius: *radius,
            },
            GeometrySpec::Cylinder {
                base,
                axis,
                radius,
                height,
            } => Geometry::Cylinder {
                base: Point::from(self.vector::<D>(base, &what("cylinder.base"))?),
                axis: *axis,
                radius: *radius,
                height: *height,
            },
            GeometrySpec::Polygon(ps) => {
                if D != 2 {
                    return Err(self.error(
                        g.span(),
                        format!("{} is 2D (use `stl` in 3D)", what("polygon")),
                    ));
                }
                let mut vertices = Vec::with_capacity(ps.len());
                for p in ps {
                    vertices.push(Point::from(self.vector::<D>(p, &what("polygon"))?));
                }
                Geometry::Surface(pfem_scene::surface::ClosedSurface::polygon(vertices))
            }
            GeometrySpec::Stl(stl) => {
                if D != 3 {
                    return Err(self.error(
                        g.span(),
                        format!("{} is 3D (use `polygon` in 2D)", what("stl")),
                    ));
                }
                let offset = match &stl.offset {
                    Some(o) => {
                        let v = self.vector::<3>(o, &what("stl.offset"))?;
                        [v[0], v[1], v[2]]
                    }
                    None => [0.0; 3],
                };
                if !(stl.scale.is_finite() && stl.scale > 0.0) {
                    return Err(self.error(
                        g.span(),
                        format!("{} must be positive, got {}", what("stl.scale"), stl.scale),
                    ));
                }
                let file = Path::new(&self.path)
                    .parent()
                    .unwrap_or(Path::new(""))
                    .join(&stl.file);
                let surface =
                    pfem_scene::surface::ClosedSurface::<3>::read_stl(&file, stl.scale, offset)
                        .map_err(|why| self.error(g.span(), format!("{}: {why}", what("stl"))))?;
                // One code path for every dimension: the 3D surface as a
                // D-dimensional one (D is 3 here).
                Geometry::Surface(pfem_scene::surface::ClosedSurface {
                    vertices: surface
                        .vertices
                        .iter()
                        .map(|v| Point::<D>::from_column_slice(v.as_slice()))
                        .collect(),
                    facets: surface.facets,
                })
            }
            GeometrySpec::Particles(ps) => {
                if ps.is_empty() {
                    return Err(self.error(g.span(), format!("{} is empty", what("particles"))));
                }
                Geometry::Particles(
                    ps.iter()
                        .map(|p| self.vector::<D>(p, &what("particles")))
                        .collect::<Result<_, _>>()?,
                )
            }
        })
    }

    fn material<const D: usize>(
        &self,
        m: &Spanned<MaterialSpec>,
        body: &str,
    ) -> Result<Box<dyn Material<D>>, SceneError>
    where
        Const<D>: Dim,
    {
        let made: Result<Box<dyn Material<D>>, _> = match *m.get_ref() {
            MaterialSpec::Newtonian {
                density,
                viscosity,
                bulk_modulus,
            } => Newtonian::new(density, viscosity, bulk_modulus)
                .map(|n| Box::new(n) as Box<dyn Material<D>>),
            MaterialSpec::Hypoelastic {
                density,
                young,
                poisson,
                plane_stress,
            } => {
                if plane_stress && D != 2 {
                    return Err(self.error(
                        m.span(),
                        format!("body `{body}`: `plane_stress` is a 2D assumption"),
                    ));
                }
                if plane_stress {
                    Hypoelastic::plane_stress(density, young, poisson)
                } else {
                    Hypoelastic::new(density, young, poisson)
                }
                .map(|h| Box::new(h) as Box<dyn Material<D>>)
            }
        };
        made.map_err(|e| self.error(m.span(), format!("body `{body}`: material: {e}")))
    }

    /// A field's sample points and values, checked: one value of `width`
    /// numbers per point of `D` coordinates, all finite, and (two points or
    /// more) a box of points that reaches within two spacings of the
    /// body's box (`reach`: its corners and spacing).
    #[allow(clippy::type_complexity)]
    fn samples<const D: usize>(
        &self,
        f: &Spanned<FieldSpec>,
        width: usize,
        what: &str,
        reach: (Point<D>, Point<D>, f64),
    ) -> Result<(Vec<Vec<f64>>, Vec<Vec<f64>>), SceneError> {
        let spec = f.get_ref();
        let bad = |why: String| self.error(f.span(), format!("{what}: {why}"));
        if spec.points.is_empty() || spec.points.len() != spec.values.len() {
            return Err(bad(format!(
                "{} points and {} values (one value per point, at least one)",
                spec.points.len(),
                spec.values.len()
            )));
        }
        let mut vals = Vec::with_capacity(spec.values.len());
        for (p, v) in spec.points.iter().zip(&spec.values) {
            let v = match v {
                FieldValue::Scalar(s) => vec![*s],
                FieldValue::Vector(v) => v.clone(),
            };
            if p.len() != D || v.len() != width {
                return Err(bad(format!(
                    "points need {D} coordinates and values {width} number(s), got {} and {}",
                    p.len(),
                    v.len()
                )));
            }
            if p.iter().chain(&v).any(|c| !c.is_finite()) {
                return Err(bad("non-finite number".into()));
            }
            vals.push(v);
        }
        // Every particle takes its nearest sample however far: samples
        // whose box misses the body's (given in millimetres, or for another
        // body) would set it from a far point without a word (the review
        // of session 45). A coarse grid around the body, or one sample
        // anywhere (a constant field), passes. (A spacing or a box that is
        // not a number is left to the scene's own check.)
        let (lo, hi, h) = reach;
        let sane = h.is_finite()
            && h > 0.0
            && (0..D).all(|k| lo[k] <= hi[k] && (hi[k] - lo[k]).is_finite());
        if sane && spec.points.len() > 1 {
            let (mut plo, mut phi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for p in &spec.points {
                for k in 0..D {
                    plo[k] = plo[k].min(p[k]);
                    phi[k] = phi[k].max(p[k]);
                }
            }
            let misses = (0..D).any(|k| phi[k] < lo[k] - 2.0 * h || plo[k] > hi[k] + 2.0 * h);
            if misses {
                return Err(bad(format!(
                    "its {} points span {:?} to {:?}, which misses the body's box {:?} to {:?} by more than two spacings; the points are in metres",
                    spec.points.len(),
                    &plo[..D],
                    &phi[..D],
                    lo.as_slice(),
                    hi.as_slice()
                )));
            }
        }
        Ok((spec.points.clone(), vals))
    }

    fn motion_law<const D: usize>(
        &self,
        m: &Spanned<MotionSpec>,
        what: &str,
    ) -> Result<std::sync::Arc<dyn pfem_scene::motion::MotionLaw<D>>, SceneError>
    where
        Const<D>: Dim,
    {
        use pfem_scene::motion::{PiecewiseLinear, Sinusoidal};
        Ok(match m.get_ref() {
            MotionSpec::Sinusoidal {
                amplitude,
                period,
                ramp,
            } => {
                if !(*period > 0.0 && period.is_finite() && *ramp >= 0.0 && ramp.is_finite()) {
                    return Err(self.error(
                        m.span(),
                        format!(
                            "{what}: period must be positive and ramp non-negative, both finite"
                        ),
                    ));
                }
                std::sync::Arc::new(Sinusoidal {
                    amplitude: self.vector::<D>(amplitude, &format!("{what}.amplitude"))?,
                    period: *period,
                    ramp: *ramp,
                })
            }
            MotionSpec::Table(rows) => {
                let mut table = Vec::with_capacity(rows.len());
                for r in rows {
                    if r.len() != D + 1 {
                        return Err(self.error(
                            m.span(),
                            format!("{what}: each row is [t, d1..d{D}], got {} numbers", r.len()),
                        ));
                    }
                    table.push((r[0], Vector::<D>::from_fn(|k, _| r[k + 1])));
                }
                std::sync::Arc::new(
                    PiecewiseLinear::new(table)
                        .map_err(|e| self.error(m.span(), format!("{what}: {e}")))?,
                )
            }
            MotionSpec::Rotation {
                center,
                axis,
                rate,
                amplitude,
                period,
                ramp,
            } => {
                let center = Point::from(self.vector::<D>(center, &format!("{what}.center"))?);
                let axis = match axis {
                    Some(a) if D == 3 => {
                        let v = self.vector::<3>(a, &format!("{what}.axis"))?;
                        Some([v[0], v[1], v[2]])
                    }
                    Some(_) => {
                        return Err(self.error(
                            m.span(),
                            format!("{what}: a 2D rotation has no axis (it turns x towards y)"),
                        ))
                    }
                    None => None,
                };
                std::sync::Arc::new(
                    pfem_scene::motion::Rotation::<D>::new(
                        center, axis, *rate, *amplitude, *period, *ramp,
                    )
                    .map_err(|e| self.error(m.span(), format!("{what}: {e}")))?,
                )
            }
        })
    }

    fn vector<const D: usize>(&self, c: &Coords, what: &str) -> Result<Vector<D>, SceneError>
    where
        Const<D>: Dim,
    {
        let v = c.get_ref();
        if v.len() != D {
            return Err(self.error(
                c.span(),
                format!("{what} needs {D} numbers in a {D}D scene, got {}", v.len()),
            ));
        }
        if v.iter().any(|x| !x.is_finite()) {
            return Err(self.error(c.span(), format!("{what} must be finite, got {v:?}")));
        }
        Ok(Vector::<D>::from_column_slice(v))
    }

    fn error(&self, span: Range<usize>, why: String) -> SceneError {
        let (line, col) = line_col(&self.source, span.start);
        SceneError::File {
            path: self.path.clone(),
            why: if self.source.is_empty() {
                why
            } else {
                format!("line {line}, column {col}: {why}")
            },
        }
    }
}

/// The first line (1-based) that sets `key` (`key = …`, outside comments)
/// or, for a table header such as `[run]`, that opens it.
fn key_line(source: &str, key: &str) -> Option<usize> {
    source
        .lines()
        .position(|l| {
            let l = l.trim_start();
            if key.starts_with('[') {
                return l.starts_with(key);
            }
            l.strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with('='))
        })
        .map(|i| i + 1)
}

/// What identifies the state a row of probes measures
/// ([`Simulation::state_version`]: it changes with every step and every
/// change by hand, and no two simulations share it).
type RowKey = u64;

fn row_key<const D: usize>(s: &Simulation<D>) -> RowKey
where
    Const<D>: Dim,
{
    s.state_version()
}

/// What a scene's probes share within a row: the point probes' measurement,
/// the main body (`front_x`, `height_at_wall`), and the band of
/// `height_at_wall` (1.5 fluid spacings).
struct RowShared<const D: usize>
where
    Const<D>: Dim,
{
    points: SharedPoints<D>,
    body: SharedBody,
    band: f64,
}

impl<const D: usize> RowShared<D>
where
    Const<D>: Dim,
{
    fn new(band: f64) -> Self {
        Self {
            points: SharedPoints::default(),
            body: SharedBody::default(),
            band,
        }
    }
}

/// The main body of the fluid ([`crate::cases3d::main_body`]) as measured
/// for the row of the state it names.
type SharedBody = Shared<(RowKey, Vec<bool>)>;

/// A measurement shared by the columns of one probe (or several).
type Shared<T> = Arc<Mutex<Option<T>>>;

/// `f` of the main body of `s`, classified once a row.
fn main_body_of<const D: usize>(
    body: &SharedBody,
    s: &Simulation<D>,
    f: impl FnOnce(&[bool]) -> f64,
) -> f64
where
    Const<D>: Dim,
{
    let key = row_key(s);
    let mut b = body.lock().unwrap_or_else(|e| e.into_inner());
    if b.as_ref().is_none_or(|b| b.0 != key) {
        *b = Some((key, crate::cases3d::main_body(s)));
    }
    f(b.as_ref().map_or(&[], |b| &b.1))
}

/// A scene's point probes, measured together
/// ([`crate::Loads::fluid_at_points`]) once a row.
struct PointCache<const D: usize>
where
    Const<D>: Dim,
{
    points: Vec<Point<D>>,
    key: Option<RowKey>,
    values: Vec<Option<(f64, Vector<D>)>>,
}

impl<const D: usize> Default for PointCache<D>
where
    Const<D>: Dim,
{
    fn default() -> Self {
        Self {
            points: Vec::new(),
            key: None,
            values: Vec::new(),
        }
    }
}

type SharedPoints<const D: usize> = Arc<Mutex<PointCache<D>>>;

/// The particles of `body` that started within `radius` of `point`, or the
/// nearest one.
fn followed<const D: usize>(
    s: &Simulation<D>,
    body: &str,
    point: &Point<D>,
    radius: Option<f64>,
) -> Vec<usize>
where
    Const<D>: Dim,
{
    let all = s.body_particles(body).unwrap_or_default();
    let dist = |i: usize| (s.initial_position(i) - point).norm();
    if let Some(r) = radius {
        let near: Vec<usize> = all.iter().copied().filter(|&i| dist(i) <= r).collect();
        if !near.is_empty() {
            return near;
        }
    }
    all.iter()
        .copied()
        .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
        .into_iter()
        .collect()
}

/// 1-based line and column (in characters) of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

/// The key whose value starts at byte `offset`: the dotted key before the
/// last `=` on the same line, if any (for messages about a value).
fn key_before(text: &str, offset: usize) -> Option<&str> {
    let before = text.get(..offset.min(text.len()))?;
    let line = &before[before.rfind('\n').map_or(0, |i| i + 1)..];
    let key = line[..line.rfind('=')?].trim_end();
    let start = key
        .rfind(|c: char| !(c.is_alphanumeric() || c == '_' || c == '-' || c == '.'))
        .map_or(0, |i| i + c_len(key, i));
    let key = &key[start..];
    (!key.is_empty()).then_some(key)
}

/// Length in bytes of the character at byte `i` of `s`.
fn c_len(s: &str, i: usize) -> usize {
    s[i..].chars().next().map_or(1, char::len_utf8)
}

/// The sample points of a field, binned in a grid of about one point a
/// cell, for the nearest point to each particle: about constant time a
/// query instead of a pass over every sample (10⁵ samples on 10⁵
/// particles took 2·10¹⁰ distances until session 41).
struct Nearest {
    points: Vec<Vec<f64>>,
    lo: Vec<f64>,
    width: f64,
    cells: Vec<usize>,
    bins: Vec<Vec<u32>>,
}

impl Nearest {
    fn new(points: Vec<Vec<f64>>) -> Self {
        let d = points.first().map_or(1, Vec::len).max(1);
        let mut lo = vec![f64::INFINITY; d];
        let mut hi = vec![f64::NEG_INFINITY; d];
        for p in &points {
            for k in 0..d {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if points.is_empty() {
            lo = vec![0.0; d];
            hi = vec![0.0; d];
        }
        let extent = (0..d).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let side = (points.len() as f64).powf(1.0 / d as f64).ceil().max(1.0);
        // A width that underflows (samples a few subnormals apart) or
        // overflows would make a cell count of `usize::MAX + 1`, wrapped to
        // no cell at all (an index out of bounds, the review of session
        // 45): one cell instead, and never more than `side + 1` per axis.
        let width = extent / side;
        let width = if width.is_normal() && width.is_finite() {
            width
        } else {
            1.0
        };
        let cells: Vec<usize> = (0..d)
            .map(|k| {
                let c = ((hi[k] - lo[k]) / width).floor();
                if c.is_finite() && c >= 0.0 {
                    (c.min(side) as usize).saturating_add(1)
                } else {
                    1
                }
            })
            .collect();
        let mut grid = Self {
            points: Vec::new(),
            lo,
            width,
            bins: vec![Vec::new(); cells.iter().product()],
            cells,
        };
        for (i, p) in points.iter().enumerate() {
            let c = grid.cell_of(p);
            let b = grid.index(&c);
            grid.bins[b].push(i as u32);
        }
        grid.points = points;
        grid
    }

    fn cell_of(&self, x: &[f64]) -> Vec<usize> {
        (0..self.cells.len())
            .map(|k| {
                let c = ((x[k] - self.lo[k]) / self.width).floor();
                (c.max(0.0) as usize).min(self.cells[k] - 1)
            })
            .collect()
    }

    fn index(&self, c: &[usize]) -> usize {
        c.iter()
            .zip(&self.cells)
            .fold(0, |a, (&ck, &nk)| a * nk + ck)
    }

    /// Index of the sample point nearest `x` (the first such, as a pass
    /// in order would give).
    fn nearest(&self, x: &[f64]) -> usize {
        let d = self.cells.len();
        let d2 = |i: usize| {
            self.points[i]
                .iter()
                .zip(x)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
        };
        let c = self.cell_of(x);
        let mut best: Option<(f64, usize)> = None;
        let reach = self.cells.iter().copied().max().unwrap_or(1);
        // Far outside the samples the rings grow without finding one: past
        // as many cells as samples, a plain pass is cheaper.
        let mut visited = 0usize;
        for r in 0..=reach {
            if visited > self.points.len().max(64) {
                return (0..self.points.len())
                    .min_by(|&a, &b| d2(a).total_cmp(&d2(b)))
                    .unwrap_or(0);
            }
            // The cells at Chebyshev distance r from `c`.
            let lo: Vec<usize> = c.iter().map(|&ck| ck.saturating_sub(r)).collect();
            let hi: Vec<usize> = c
                .iter()
                .zip(&self.cells)
                .map(|(&ck, &nk)| (ck + r).min(nk - 1))
                .collect();
            let span: Vec<usize> = (0..d).map(|k| hi[k] - lo[k] + 1).collect();
            visited += span.iter().product::<usize>();
            let mut cur = vec![0usize; d];
            for m in 0..span.iter().product::<usize>() {
                let mut rest = m;
                for k in (0..d).rev() {
                    cur[k] = lo[k] + rest % span[k];
                    rest /= span[k];
                }
                if !(0..d).any(|k| cur[k] + r == c[k] || cur[k] == c[k] + r) {
                    continue;
                }
                for &i in &self.bins[self.index(&cur)] {
                    let (i, e) = (i as usize, d2(i as usize));
                    if best.is_none_or(|(b, j)| e < b || (e == b && i < j)) {
                        best = Some((e, i));
                    }
                }
            }
            // Any cell beyond this ring is at least this far from `x`
            // (infinite once the ring has covered the grid).
            let bound = (0..d)
                .map(|k| {
                    let below = if c[k] > r {
                        x[k] - (self.lo[k] + (c[k] - r) as f64 * self.width)
                    } else {
                        f64::INFINITY
                    };
                    let above = if c[k] + r + 1 < self.cells[k] {
                        self.lo[k] + (c[k] + r + 1) as f64 * self.width - x[k]
                    } else {
                        f64::INFINITY
                    };
                    below.min(above)
                })
                .fold(f64::INFINITY, f64::min)
                .max(0.0);
            if bound == f64::INFINITY || best.is_some_and(|(b, _)| b < bound * bound) {
                break;
            }
        }
        best.map_or(0, |(_, i)| i)
    }
}

#[cfg(test)]
mod tests {
    use super::Nearest;

    /// The grid gives the sample a pass over every sample gives (the first
    /// of equals), for queries inside and far outside the samples, in 2D
    /// and 3D, with repeated points and a flat cloud.
    #[test]
    fn the_nearest_sample_is_the_brute_force_one() {
        let mut seed = 12345u64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for d in [2usize, 3] {
            for flat in [false, true] {
                let mut pts: Vec<Vec<f64>> = (0..500)
                    .map(|_| {
                        (0..d)
                            .map(|k| if flat && k == 1 { 0.5 } else { rnd() })
                            .collect()
                    })
                    .collect();
                pts.push(pts[7].clone());
                let grid = Nearest::new(pts.clone());
                for _ in 0..2000 {
                    let x: Vec<f64> = (0..d).map(|_| 3.0 * rnd() - 1.0).collect();
                    let d2 = |p: &Vec<f64>| {
                        p.iter()
                            .zip(&x)
                            .map(|(a, b)| (a - b) * (a - b))
                            .sum::<f64>()
                    };
                    let brute = (0..pts.len())
                        .min_by(|&a, &b| d2(&pts[a]).total_cmp(&d2(&pts[b])))
                        .unwrap();
                    assert_eq!(grid.nearest(&x), brute, "{d}D flat {flat}: {x:?}");
                }
                assert_eq!(grid.nearest(&pts[7]), 7);
            }
        }
        let one = Nearest::new(vec![vec![1.0, 2.0]]);
        assert_eq!(one.nearest(&[-5.0, 9.0]), 0);

        // Samples a subnormal apart (their cell width underflowed: no
        // cell, an index out of bounds) or spanning the whole range of
        // f64 (the width overflows).
        let tiny = Nearest::new(vec![vec![0.0, 0.0], vec![5e-324, 0.0]]);
        assert!(tiny.nearest(&[1.0, 0.0]) < 2);
        let huge = Nearest::new(vec![vec![-1e308, 0.0], vec![1e308, 0.0], vec![0.0, 1.0]]);
        assert_eq!(huge.nearest(&[0.0, 0.9]), 2);
    }

    /// The parse's memory (session 45's review: a 250 MB file would have
    /// taken about 25 GB while the TOML parser held it): refused over the
    /// budget, named.
    #[test]
    fn a_text_too_large_to_parse_within_the_budget_is_refused() {
        assert!(super::parse_fits(20_000_000, 19e9).is_ok());
        let why = super::parse_fits(250 << 20, 19e9).unwrap_err();
        assert!(why.contains("memory budget"), "{why}");
    }
}
