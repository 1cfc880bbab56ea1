//! The paper's 3D examples (§9) as ready-made scenes, their probes, and a
//! quasi-2D 3D dam break to check 3D against 2D.
//!
//! - [`WaterColumn3d`]: §9.1, the collapse of a water column in the
//!   geometry of Koshizuka et al. (1995);
//! - [`ColumnOnCylinder3d`]: §9.2, the same column collapsing onto an
//!   elastic cylinder clamped at its base;
//! - [`thin_dam_break`] + [`slip_sides`]: the 2D dam break
//!   ([`crate::cases::DamBreak`]) as a slab one spacing deep whose side
//!   planes are slip walls.
//!
//! The probes ([`front_x`], [`height_at_wall`], [`main_body`]) are generic
//! over the dimension: `x` is the flow direction, `y` is up.

use pfem_constitutive::Newtonian;
use pfem_core::{shape_gradients, Const, Dim, ParticleKind, Point, Vector, MAX_NV};

use crate::cases::{solid_material, DamBreak, G};
use crate::error::SceneError;
use crate::observe::Probe;
use crate::scene::{Geometry, RunSettings, Scene, WallMotion};
use crate::simulation::Simulation;
use pfem_driver::RunError;

/// Fluid particles of the main body: the connected component of fluid
/// elements with the largest measure (2D or 3D).
pub fn main_body<const D: usize>(s: &Simulation<D>) -> Vec<bool>
where
    Const<D>: Dim,
{
    let mut m = vec![false; s.particles().len()];
    // (A set changed by hand: its elements are the old set's, session 49.)
    if !s.is_meshed() {
        return m;
    }
    let Ok(cls) = pfem_geometry::classify(
        s.particles().x(),
        s.particles().kind(),
        s.elements().fluid_mesh(),
        None,
    ) else {
        return m;
    };
    let Some(main) = (0..cls.components.len()).max_by(|&a, &b| {
        cls.components[a]
            .measure
            .total_cmp(&cls.components[b].measure)
    }) else {
        return m;
    };
    for (e, el) in s
        .elements()
        .fluid_mesh()
        .simplices
        .chunks_exact(D + 1)
        .enumerate()
    {
        if cls.component[e] as usize == main {
            for &p in el {
                if s.particles().kind()[p as usize] == ParticleKind::Fluid {
                    m[p as usize] = true;
                }
            }
        }
    }
    m
}

/// Leading edge of the fluid: the largest `x` of a fluid particle of the
/// main body ([`main_body`]).
pub fn front_x<const D: usize>(s: &Simulation<D>) -> f64
where
    Const<D>: Dim,
{
    front_x_of(s, &main_body(s))
}

/// [`front_x`] of the particles `body` marks (a [`main_body`] measured
/// once for several probes).
pub fn front_x_of<const D: usize>(s: &Simulation<D>, body: &[bool]) -> f64
where
    Const<D>: Dim,
{
    // From −∞, not 0: water wholly at negative x read 0 (the review of
    // session 45); no main body at all reads NaN, not a front.
    let front = (0..s.particles().len())
        .filter(|&i| body[i])
        .map(|i| s.particles().x()[i][0])
        .fold(f64::NEG_INFINITY, f64::max);
    if front.is_finite() {
        front
    } else {
        f64::NAN
    }
}

/// Height of the fluid at the back wall (`x = 0`): the largest `y` of a
/// fluid particle of the main body within `band` of the wall (`|x| ≤
/// band`); NaN when none is.
pub fn height_at_wall<const D: usize>(s: &Simulation<D>, band: f64) -> f64
where
    Const<D>: Dim,
{
    height_at_wall_of(s, band, &main_body(s))
}

/// [`height_at_wall`] of the particles `body` marks (a [`main_body`]
/// measured once for several probes).
pub fn height_at_wall_of<const D: usize>(s: &Simulation<D>, band: f64, body: &[bool]) -> f64
where
    Const<D>: Dim,
{
    // Within `band` of the wall on either side, from −∞: water wholly
    // below `y = 0` read 0, and so did no water at the wall (a review in
    // session 49, as `front_x_of`'s in session 45); none reads NaN.
    let height = (0..s.particles().len())
        .filter(|&i| body[i] && s.particles().x()[i][0].abs() <= band)
        .map(|i| s.particles().x()[i][1])
        .fold(f64::NEG_INFINITY, f64::max);
    if height.is_finite() {
        height
    } else {
        f64::NAN
    }
}

/// A 3D tank, walls two particle layers thick (spacing `h`): the floor
/// (`y ≤ 0`) under `[0, length] × [0, depth]`, the back wall (`x ≤ 0`), the
/// front wall (`x ≥ length`) and, if `sides`, the side walls (`z ≤ 0`,
/// `z ≥ depth`), all up to `top`.
pub fn tank3d(scene: Scene<3>, length: f64, depth: f64, top: f64, h: f64, sides: bool) -> Scene<3> {
    let (z0, z1) = if sides { (-h, depth + h) } else { (0.0, depth) };
    let b = |name: &str, s: Scene<3>, min: [f64; 3], max: [f64; 3]| {
        s.wall(
            name,
            Geometry::Box {
                min: Point::<3>::from(min),
                max: Point::<3>::from(max),
            },
            h,
            WallMotion::Fixed,
        )
    };
    let mut s = b("floor", scene, [-h, -h, z0], [length + h, 0.0, z1]);
    s = b("back_wall", s, [-h, h, 0.0], [0.0, top, depth]);
    s = b("front_wall", s, [length, h, 0.0], [length + h, top, depth]);
    if sides {
        s = b("side_wall_0", s, [-h, h, -h], [length + h, top, 0.0]);
        s = b(
            "side_wall_1",
            s,
            [-h, h, depth],
            [length + h, top, depth + h],
        );
    }
    s
}

/// Water at rest in a closed-bottom 3D tank (issue 13's 3D case):
/// `length` × `width` of water `depth` deep (`y` up), no-slip walls on all
/// four sides and the floor up to 1.2 × `depth`, open top, water's real
/// bulk modulus. `examples/rest_tank_3d.rs` and `tests/three_d.rs` run it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestTank3d {
    /// Tank length along `x` (m). Default 0.5.
    pub length: f64,
    /// Tank width along `z` (m). Default 0.25.
    pub width: f64,
    /// Water depth along `y` (m). Default 0.5.
    pub depth: f64,
    /// Spacing (m). Default `depth / 10`.
    pub spacing: f64,
    /// End time (s). Default 2.
    pub end_time: f64,
}

impl Default for RestTank3d {
    fn default() -> Self {
        Self {
            length: 0.5,
            width: 0.25,
            depth: 0.5,
            spacing: 0.05,
            end_time: 2.0,
        }
    }
}

impl RestTank3d {
    /// The scene.
    pub fn scene(&self) -> Scene<3> {
        let h = self.spacing;
        let s = Scene::<3>::new("rest_tank_3d")
            .gravity(Vector::<3>::new(0.0, -G, 0.0))
            .settings(RunSettings {
                end_time: self.end_time,
                max_dt: 5e-3,
                output_interval: None,
                ..Default::default()
            });
        tank3d(s, self.length, self.width, 1.2 * self.depth, h, true).fluid(
            "water",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<3>::new(0.0, 0.0, 0.0),
                max: Point::<3>::new(self.length, self.depth, self.width),
            },
            h,
        )
    }
}

/// §9.1: the collapse of a water column 0.146 m wide and 0.292 m high at
/// the back of a tank 0.584 m long (Koshizuka et al. 1995), `depth` deep,
/// between no-slip side walls or, with `side_walls = false`, slip side planes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaterColumn3d {
    /// Column width `a` (m). Default 0.146.
    pub width: f64,
    /// Column height (m). Default 0.292.
    pub height: f64,
    /// Tank length (m). Default 0.584.
    pub tank_length: f64,
    /// Depth of column and tank (m). Default 0.0584 (4 spacings: a slice
    /// of the 0.146 m deep experiment, to keep the run short).
    pub depth: f64,
    /// Particle spacing (m). Default `width / 10`.
    pub spacing: f64,
    /// End time (s). Default 1 (as in the paper).
    pub end_time: f64,
    /// No-slip side walls at `z = 0` and `z = depth` (default `true`). With
    /// `false` the tank has none: the side planes must then be made slip
    /// (symmetry) planes with [`slip_sides`] once the simulation is built,
    /// so the slice stands for the middle of a wide tank (what the example
    /// `water_column_3d` does).
    pub side_walls: bool,
}

impl Default for WaterColumn3d {
    fn default() -> Self {
        Self {
            width: 0.146,
            height: 0.292,
            tank_length: 0.584,
            depth: 0.0584,
            spacing: 0.0146,
            end_time: 1.0,
            side_walls: true,
        }
    }
}

impl WaterColumn3d {
    /// The scene.
    pub fn scene(&self) -> Scene<3> {
        let h = self.spacing;
        let s = Scene::<3>::new("water_column_3d")
            .gravity(Vector::<3>::new(0.0, -G, 0.0))
            .settings(RunSettings {
                end_time: self.end_time,
                max_dt: 2.5e-3,
                courant: 0.5,
                output_interval: Some(self.end_time / 50.0),
                alpha: 1.3,
            });
        let s = tank3d(
            s,
            self.tank_length,
            self.depth,
            self.height * 1.5,
            h,
            self.side_walls,
        );
        s.fluid(
            "water",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<3>::new(0.0, 0.0, 0.0),
                max: Point::<3>::new(self.width, self.height, self.depth),
            },
            h,
        )
    }

    /// Probes `front_x` (m), `height_at_wall` (m) and `volume` (m³).
    pub fn probes(&self) -> Vec<Probe<3>> {
        let h = self.spacing;
        vec![
            Probe::new("front_x", |s: &Simulation<3>| front_x(s)),
            Probe::new("height_at_wall", move |s: &Simulation<3>| {
                height_at_wall(s, 1.5 * h)
            }),
            Probe::new("volume", |s: &Simulation<3>| s.fluid_volume()),
        ]
    }
}

/// §9.2: the water column of [`WaterColumn3d`] collapsing onto an elastic
/// cylinder standing in the tank, clamped at its base (r = 1.5 cm,
/// h = 15 cm, ρ = 2500 kg/m³, E = 10⁶ Pa, ν = 0.3). The paper does not give
/// the cylinder's position; it stands at `cylinder_x` on the mid-plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColumnOnCylinder3d {
    /// The water column and tank.
    pub column: WaterColumn3d,
    /// Cylinder axis position along the tank (m). Default 0.35.
    pub cylinder_x: f64,
    /// Cylinder radius (m). Default 0.015.
    pub radius: f64,
    /// Cylinder height (m). Default 0.15.
    pub cylinder_height: f64,
    /// Particle spacing of the cylinder (m). Default `radius / 2`.
    pub cylinder_spacing: f64,
    /// Density (kg/m³). Default 2500.
    pub density: f64,
    /// Young's modulus (Pa). Default 10⁶.
    pub young: f64,
    /// Poisson's ratio. Default 0.3.
    pub poisson: f64,
}

impl Default for ColumnOnCylinder3d {
    fn default() -> Self {
        Self {
            column: WaterColumn3d::default(),
            cylinder_x: 0.35,
            radius: 0.015,
            cylinder_height: 0.15,
            cylinder_spacing: 0.0075,
            density: 2500.0,
            young: 1e6,
            poisson: 0.3,
        }
    }
}

impl ColumnOnCylinder3d {
    /// Centre of the cylinder's bottom disk: one cylinder spacing above the
    /// floor (no particle of the cylinder falls on a floor particle), on
    /// the tank's mid-plane.
    pub fn base(&self) -> Point<3> {
        Point::<3>::new(
            self.cylinder_x,
            self.cylinder_spacing,
            0.5 * self.column.depth,
        )
    }

    /// The scene; [`SceneError::InvalidMaterial`] when the cylinder's
    /// density, `young` or `poisson` is out of range.
    pub fn scene(&self) -> Result<Scene<3>, SceneError> {
        let mut s = self.column.scene();
        s.name = "column_on_cylinder_3d".into();
        let base = self.base();
        let cyl = solid_material("cylinder", self.density, self.young, self.poisson, false)?;
        Ok(s.solid(
            "cylinder",
            Box::new(cyl),
            Geometry::Cylinder {
                base,
                axis: 1,
                radius: self.radius,
                height: self.cylinder_height,
            },
            self.cylinder_spacing,
            // Clamped at its base: the bottom disk.
            Some((
                Point::<3>::new(-1.0, base.y - 1.0, -1.0),
                Point::<3>::new(1.0, base.y + 1e-9, 1.0),
            )),
        ))
    }

    /// Probes `ux_top` (m, mean `x` displacement of the top disk),
    /// `force_x` (N, see [`fluid_force`]) and `volume` (m³).
    pub fn probes(&self) -> Vec<Probe<3>> {
        let top = self.base().y + self.cylinder_height;
        vec![
            Probe::new("ux_top", move |s: &Simulation<3>| {
                // (The scene's own cylinder: neither error can arise.)
                top_displacement(s, "cylinder", top).map_or(f64::NAN, |u| u.x)
            }),
            Probe::new("force_x", |s: &Simulation<3>| {
                fluid_force(s, "cylinder").map_or(f64::NAN, |f| f.x)
            }),
            Probe::new("volume", |s: &Simulation<3>| s.fluid_volume()),
        ]
    }
}

/// Mean displacement of the particles of solid `body` that started at
/// height `y_top` (its top). An unknown body is
/// [`RunError::UnknownBody`], a height no particle of it started at
/// [`RunError::InvalidSetting`] (both gave a displacement of zero).
pub fn top_displacement<const D: usize>(
    s: &Simulation<D>,
    body: &str,
    y_top: f64,
) -> Result<Vector<D>, RunError>
where
    Const<D>: Dim,
{
    let mut sum = Vector::<D>::zeros();
    let mut n = 0;
    for i in s.body_particles(body)? {
        let x0 = s.initial_position(i);
        if (x0[1] - y_top).abs() < 1e-9 {
            sum += s.particles().x()[i] - x0;
            n += 1;
        }
    }
    if n == 0 {
        return Err(RunError::InvalidSetting {
            name: "top_displacement's y_top",
            value: y_top,
            reason: "no particle of the body started at this height",
        });
    }
    Ok(sum / n as f64)
}

/// Force of the surrounding fluid on solid `body` (N; N/m in 2D); an
/// unknown body is [`RunError::UnknownBody`] (it gave a force of zero).
///
/// For a free (not clamped) particle `i` of the solid, its share of the
/// discrete momentum balance is `mˢᵢ aᵢ = fˢᵢ + fᶠᵢ + mˢᵢ g`, with `mˢ` the
/// lumped mass of the solid's own elements (`ρ₀ V₀ / (D + 1)` each, their
/// initial volumes as the solver's, eq. 46), `fˢ` their
/// internal force `−V σ ∇Nᵢ` (Cauchy stress of the last accepted step, on
/// the current positions) and `fᶠ` what the fluid elements sharing the
/// particle transmit (their internal force less their own inertia). The
/// probe returns `Σᵢ fᶠᵢ = Σᵢ (mˢᵢ (aᵢ − g) − fˢᵢ)` over the free
/// particles: the load the fluid puts on the solid, the clamp's reaction
/// excluded. It inherits the step-to-step noise of the accelerations
/// (strong with the undamped trapezoidal rule, less with Bossak).
///
/// With Bossak's scheme the step balances the inertia
/// `mˢ [(1 − α_B) Aⁿ⁺¹ + α_B Aⁿ]`, not `mˢ Aⁿ⁺¹`: the probe, which only
/// sees the last accelerations, differs from the load the step transmitted
/// by `α_B Σ mˢ (Aⁿ⁺¹ − Aⁿ)`. Measured on `column_on_cylinder_3d` at a/10
/// (`docs/benchmarks.md`, session 14): peak 13.67 N against 13.89 N with
/// the Bossak inertia, and 4.45 % against 5.71 % step-to-step chatter.
pub fn fluid_force<const D: usize>(s: &Simulation<D>, body: &str) -> Result<Vector<D>, RunError>
where
    Const<D>: Dim,
{
    let nv = D + 1;
    let n = s.particles().len();
    let id = s
        .body_names()
        .iter()
        .position(|b| b == body)
        .ok_or_else(|| RunError::UnknownBody {
            name: body.to_string(),
        })?;
    let mut mass = vec![0.0; n];
    let mut f_int = vec![Vector::<D>::zeros(); n];
    let mut grads = [Vector::<D>::zeros(); MAX_NV];
    for (e, el) in s.elements().solid().chunks_exact(nv).enumerate() {
        if s.particles().body()[el[0] as usize] != id as u32 {
            continue;
        }
        let mut p = [Point::<D>::zeros(); MAX_NV];
        for a in 0..nv {
            p[a] = s.particles().x()[el[a] as usize];
        }
        let Some(vol) = shape_gradients::<D>(&p[..nv], &mut grads) else {
            continue;
        };
        let rho = s.materials()[s.elements().solid_material()[e] as usize].density();
        let v0 = s
            .elements()
            .reference_volumes()
            .get(e)
            .copied()
            .unwrap_or(vol);
        let sigma = s.elements().solid_history()[e].stress;
        for a in 0..nv {
            let i = el[a] as usize;
            mass[i] += rho * v0 / nv as f64;
            f_int[i] -= sigma * grads[a] * vol;
        }
    }
    let g = s.gravity().unwrap_or_else(Vector::<D>::zeros);
    let mut total = Vector::<D>::zeros();
    for i in 0..n {
        if s.particles().body()[i] != id as u32 || s.particles().constraints().is_fully_fixed(i) {
            continue;
        }
        total += (s.particles().a()[i] - g) * mass[i] - f_int[i];
    }
    Ok(total)
}

/// The 2D dam break `case` as a 3D slab one spacing deep (two particle
/// planes, `z = 0` and `z = h`); its side planes are made slip walls by
/// [`slip_sides`] once the simulation is built.
pub fn thin_dam_break(case: &DamBreak) -> Scene<3> {
    let h = case.spacing;
    let a = case.width;
    let height = case.aspect * a;
    let s = Scene::<3>::new("thin_dam_break_3d")
        .gravity(Vector::<3>::new(0.0, -G, 0.0))
        .settings(RunSettings {
            end_time: case.end_time,
            max_dt: 2e-3,
            courant: 0.5,
            output_interval: Some(case.end_time / 40.0),
            alpha: 1.3,
        });
    let s = tank3d(s, case.tank_length, h, 1.5 * height, h, false);
    s.fluid(
        "water",
        Box::new(Newtonian::water()),
        Geometry::Box {
            min: Point::<3>::new(0.0, 0.0, 0.0),
            max: Point::<3>::new(a, height, h),
        },
        h,
    )
}

/// Makes every free particle's `z` velocity zero: slip walls on the side
/// planes of a slab ([`thin_dam_break`]), so the flow stays plane; the
/// initial accelerations' `z` components are zeroed to match. A
/// [`pfem_hooks::SlipPlanes`] hook, applied from the first step.
pub fn slip_sides(sim: &mut Simulation<3>) {
    sim.add_hook(Box::new(pfem_hooks::SlipPlanes { axis: 2 }));
}
