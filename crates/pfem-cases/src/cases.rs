//! The validation cases as ready-made scenes, shared by the bundled
//! examples and the validation tests, with their probes and the comparisons
//! against the measured data in [`crate::output::reference`].

use pfem_constitutive::{Hypoelastic, Newtonian};
use pfem_core::{ParticleKind, Point, Vector};

use crate::error::SceneError;
use crate::observe::Probe;
use crate::scene::{Geometry, RunSettings, Scene, WallMotion};
use crate::simulation::Simulation;
use pfem_io::Loads;

/// The hypoelastic material of a case's solid `body` (plane stress or, by
/// default, plane strain in 2D), or [`SceneError::InvalidMaterial`] naming
/// that body.
pub(crate) fn solid_material(
    body: &str,
    density: f64,
    young: f64,
    poisson: f64,
    plane_stress: bool,
) -> Result<Hypoelastic, SceneError> {
    let m = if plane_stress {
        Hypoelastic::plane_stress(density, young, poisson)
    } else {
        Hypoelastic::new(density, young, poisson)
    };
    m.map_err(|source| SceneError::InvalidMaterial {
        body: body.into(),
        source,
    })
}

/// Standard gravity (m/s²).
pub const G: f64 = 9.81;

/// Martin & Moyce (1952) dam break: a column `width` wide and
/// `aspect · width` high (n² = aspect) against the back wall of a tank.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DamBreak {
    /// Column width `a` (m). Default 2.25 in = 0.05715 m.
    pub width: f64,
    /// Height over width, n². Default 2.
    pub aspect: f64,
    /// Tank length (m), default 10 a.
    pub tank_length: f64,
    /// Particle spacing (m), default a/20.
    pub spacing: f64,
    /// End time (s), default the time of T = t √(2g/a) = 3.2.
    pub end_time: f64,
}

impl Default for DamBreak {
    fn default() -> Self {
        let a = 0.05715;
        Self {
            width: a,
            aspect: 2.0,
            tank_length: 10.0 * a,
            spacing: a / 20.0,
            end_time: 3.2 / (2.0 * G / a).sqrt(),
        }
    }
}

/// Two layers of wall particles: the floor from `x0` to `x1` at `y = 0`
/// and below, and vertical walls at the given `x` positions from `y = 0`
/// to `top`, extending outwards (`-1` to the left, `+1` to the right).
fn tank(scene: Scene<2>, x0: f64, x1: f64, walls: &[(f64, f64, f64)], h: f64) -> Scene<2> {
    let mut s = scene.wall(
        "floor",
        Geometry::Box {
            min: Point::<2>::new(x0 - h, -h),
            max: Point::<2>::new(x1 + h, 0.0),
        },
        h,
        WallMotion::Fixed,
    );
    for (i, &(x, side, top)) in walls.iter().enumerate() {
        let (xa, xb) = if side < 0.0 { (x - h, x) } else { (x, x + h) };
        s = s.wall(
            &format!("wall{i}"),
            Geometry::Box {
                min: Point::<2>::new(xa, h),
                max: Point::<2>::new(xb, top),
            },
            h,
            WallMotion::Fixed,
        );
    }
    s
}

impl DamBreak {
    /// The scene.
    pub fn scene(&self) -> Scene<2> {
        self.scene_with(Newtonian::water())
    }

    /// The scene with another fluid than water (issue 18 measures the
    /// solver's dependence on the bulk modulus with it).
    pub fn scene_with(&self, fluid: Newtonian) -> Scene<2> {
        let a = self.width;
        let h = self.spacing;
        let height = self.aspect * a;
        let top = height * 1.5;
        let s = Scene::<2>::new("dam_break_2d")
            .gravity(Vector::<2>::new(0.0, -G))
            .settings(RunSettings {
                end_time: self.end_time,
                max_dt: 2e-3,
                courant: 0.5,
                output_interval: Some(self.end_time / 40.0),
                alpha: 1.3,
            });
        let s = tank(
            s,
            0.0,
            self.tank_length,
            &[(0.0, -1.0, top), (self.tank_length, 1.0, top)],
            h,
        );
        s.fluid(
            "water",
            Box::new(fluid),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(a, height),
            },
            h,
        )
    }

    /// Probes `front_x` (m, from the back wall), `height_at_wall` (m) and
    /// `volume` (m² per metre).
    pub fn probes(&self) -> Vec<Probe<2>> {
        let h = self.spacing;
        vec![
            Probe::new("front_x", move |s: &Simulation<2>| front_x(s)),
            Probe::new("height_at_wall", move |s: &Simulation<2>| {
                height_at_wall(s, 1.5 * h)
            }),
            Probe::new("volume", |s: &Simulation<2>| s.fluid_volume()),
        ]
    }
}

/// Fluid particles of the main body: the connected component of fluid
/// elements with the largest measure (flying drops and particles sliding
/// ahead of it do not count).
pub fn main_body(s: &Simulation<2>) -> Vec<bool> {
    crate::cases3d::main_body(s)
}

/// Leading edge of the fluid: the largest `x` of a fluid particle of the
/// main body ([`main_body`]); NaN when there is none.
pub fn front_x(s: &Simulation<2>) -> f64 {
    crate::cases3d::front_x(s)
}

/// Height of the fluid at the back wall: the largest `y` of a meshed fluid
/// particle within `band` of `x = 0` (`|x| ≤ band`); NaN when none is.
pub fn height_at_wall(s: &Simulation<2>, band: f64) -> f64 {
    crate::cases3d::height_at_wall_of(s, band, &main_body(s))
}

/// Linear interpolation of a time series at `t` (clamped at the ends).
pub fn interpolate(series: &[(f64, f64)], t: f64) -> f64 {
    if series.is_empty() {
        return f64::NAN;
    }
    if t <= series[0].0 {
        return series[0].1;
    }
    for w in series.windows(2) {
        if t <= w[1].0 {
            let f = if w[1].0 > w[0].0 {
                (t - w[0].0) / (w[1].0 - w[0].0)
            } else {
                1.0
            };
            return w[0].1 + f * (w[1].1 - w[0].1);
        }
    }
    series[series.len() - 1].1
}

/// Relative RMS error of `sim` against `measured` (both `(T, value)`),
/// over the measured points with `T ≤ t_max`, after shifting the
/// simulation by `shift` in `T` (the simulated curve is read at `T − shift`).
pub fn rms_relative(sim: &[(f64, f64)], measured: &[(f64, f64)], shift: f64, t_max: f64) -> f64 {
    let pts: Vec<&(f64, f64)> = measured
        .iter()
        .filter(|(t, _)| *t <= t_max && *t - shift >= 0.0)
        .collect();
    if pts.is_empty() {
        return f64::NAN;
    }
    let s: f64 = pts
        .iter()
        .map(|(t, z)| ((interpolate(sim, t - shift) - z) / z).powi(2))
        .sum();
    (s / pts.len() as f64).sqrt()
}

/// The single time shift in `[-max_shift, max_shift]` minimising
/// [`rms_relative`], found by a scan at `step`; returns `(shift, rms)`.
/// The scan takes at most `2·10⁶ + 1` shifts (`step` is widened to fit;
/// a `step` of zero scanned for ever); a `step` or `max_shift` that is not
/// a number scans none (the shift is then 0).
pub fn best_shift(
    sim: &[(f64, f64)],
    measured: &[(f64, f64)],
    t_max: f64,
    max_shift: f64,
    step: f64,
) -> (f64, f64) {
    const MOST: f64 = 1e6;
    let mut best = (0.0, rms_relative(sim, measured, 0.0, t_max));
    let steps = (max_shift / step.abs()).round();
    if steps.is_nan() || steps < 1.0 {
        return best;
    }
    let (n, step) = if steps > MOST {
        (MOST as i64, max_shift / MOST)
    } else {
        (steps as i64, step.abs())
    };
    for i in -n..=n {
        let sh = i as f64 * step;
        let e = rms_relative(sim, measured, sh, t_max);
        if e < best.1 {
            best = (sh, e);
        }
    }
    best
}

/// Antoci, Gallati & Sibilla (2007) elastic gate: a water column 0.1 m wide
/// and 0.14 m high held by a rubber gate 0.079 m long and 0.005 m thick,
/// clamped at its top, free at its bottom.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticGate {
    /// Particle spacing of the water (m), default 0.0025.
    pub spacing: f64,
    /// Particle spacing of the gate (m), default 0.00125: four linear
    /// triangles through its thickness. Linear triangles are stiff in
    /// bending; with two the cantilever test deflects 35% too little.
    pub gate_spacing: f64,
    /// End time (s), default 0.4.
    pub end_time: f64,
    /// Young's modulus of the gate (Pa), default 12 MPa.
    pub young: f64,
    /// Poisson's ratio of the gate, default 0.4.
    pub poisson: f64,
    /// Density of the gate (kg/m³), default 1100.
    pub density: f64,
    /// The 2D assumption for the gate: plane stress (`true`, the default: a
    /// thin strip free to contract across its width, `σ_zz = 0`) or plane
    /// strain (`false`, `ε_zz = 0`). The published E = 12 MPa, ν = 0.4
    /// leave this open; the static tip deflection of a linear cantilever
    /// under the initial water load is 45–46 mm in plane stress and 38 mm
    /// in plane strain, against the measured peak of 46 mm (see
    /// `docs/benchmarks.md`).
    pub plane_stress: bool,
}

impl Default for ElasticGate {
    fn default() -> Self {
        Self {
            spacing: 0.0025,
            gate_spacing: 0.00125,
            end_time: 0.4,
            young: 12e6,
            poisson: 0.4,
            density: 1100.0,
            plane_stress: true,
        }
    }
}

/// Gate geometry of [`ElasticGate`] (m).
pub const GATE_X: f64 = 0.1;
/// Gate thickness (m).
pub const GATE_THICKNESS: f64 = 0.005;
/// Gate length (m).
pub const GATE_LENGTH: f64 = 0.079;
/// Water column height (m).
pub const GATE_WATER_HEIGHT: f64 = 0.14;

impl ElasticGate {
    /// Bottom of the gate: one spacing above the floor, the gap under it.
    pub fn gate_bottom(&self) -> f64 {
        self.spacing
    }

    /// The scene; [`SceneError::InvalidMaterial`] when the gate's density,
    /// `young` or `poisson` is out of range.
    pub fn scene(&self) -> Result<Scene<2>, SceneError> {
        let h = self.spacing;
        let y0 = self.gate_bottom();
        let y1 = y0 + GATE_LENGTH;
        let top = GATE_WATER_HEIGHT + 0.02;
        let s = Scene::<2>::new("elastic_gate_2d")
            .gravity(Vector::<2>::new(0.0, -G))
            .settings(RunSettings {
                end_time: self.end_time,
                max_dt: 1e-3,
                courant: 0.5,
                output_interval: Some(0.01),
                alpha: 1.3,
            });
        let length = 0.5;
        let s = tank(s, 0.0, length, &[(0.0, -1.0, top)], h);
        // Rigid wall above the gate, holding the column.
        let s = s.wall(
            "gate_holder",
            Geometry::Box {
                min: Point::<2>::new(GATE_X, y1 + h),
                max: Point::<2>::new(GATE_X + GATE_THICKNESS, top),
            },
            h,
            WallMotion::Fixed,
        );
        let gate = solid_material(
            "gate",
            self.density,
            self.young,
            self.poisson,
            self.plane_stress,
        )?;
        let s = s.solid(
            "gate",
            Box::new(gate),
            Geometry::Box {
                min: Point::<2>::new(GATE_X, y0),
                max: Point::<2>::new(GATE_X + GATE_THICKNESS, y1),
            },
            self.gate_spacing,
            Some((
                Point::<2>::new(GATE_X - 1.0, y1 - 1e-9),
                Point::<2>::new(GATE_X + 1.0, y1 + 1.0),
            )),
        );
        Ok(s.fluid(
            "water",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(GATE_X, GATE_WATER_HEIGHT),
            },
            h,
        ))
    }

    /// Probes `ux_tip`, `uy_tip` (m, displacement of the gate's free end
    /// at mid-thickness) and `volume`.
    pub fn probes(&self) -> Vec<Probe<2>> {
        let y0 = self.gate_bottom();
        let tip0 = Point::<2>::new(GATE_X + 0.5 * GATE_THICKNESS, y0);
        vec![
            Probe::new("ux_tip", move |s: &Simulation<2>| gate_tip(s, tip0).x),
            Probe::new("uy_tip", move |s: &Simulation<2>| gate_tip(s, tip0).y),
            Probe::new("volume", |s: &Simulation<2>| s.fluid_volume()),
        ]
    }
}

/// Displacement of the gate's free end: mean displacement of the gate's
/// bottom-row particles (their initial positions are recorded in the
/// simulation's first state, found as the gate particles closest to `tip0`
/// in `y`).
fn gate_tip(s: &Simulation<2>, tip0: Point<2>) -> Vector<2> {
    let gate = s.body_particles("gate").unwrap_or_default();
    let mut sum = Vector::<2>::zeros();
    let mut n = 0;
    for &i in &gate {
        let x0 = s.initial_position(i);
        if (x0.y - tip0.y).abs() < 1e-9 {
            sum += s.particles().x()[i] - x0;
            n += 1;
        }
    }
    if n == 0 {
        return Vector::<2>::zeros();
    }
    sum / n as f64
}

/// Issue 13's open tank: `depth` of water at rest, `width` wide, walls on
/// three sides up to 1.2 × `depth`, open top, water's real bulk modulus.
/// `examples/rest_tank_2d.rs` and `tests/water_at_rest_2d.rs` run it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestTank {
    /// Tank width (m).
    pub width: f64,
    /// Water depth (m).
    pub depth: f64,
    /// Spacing (m).
    pub spacing: f64,
    /// End time (s).
    pub end_time: f64,
}

impl Default for RestTank {
    fn default() -> Self {
        Self {
            width: 1.0,
            depth: 0.5,
            spacing: 0.025,
            end_time: 5.0,
        }
    }
}

impl RestTank {
    /// The scene.
    pub fn scene(&self) -> Scene<2> {
        let h = self.spacing;
        let top = 1.2 * self.depth;
        let s = Scene::<2>::new("rest_tank_2d")
            .gravity(Vector::<2>::new(0.0, -G))
            .settings(RunSettings {
                end_time: self.end_time,
                max_dt: 5e-3,
                output_interval: None,
                ..Default::default()
            });
        tank(
            s,
            0.0,
            self.width,
            &[(0.0, -1.0, top), (self.width, 1.0, top)],
            h,
        )
        .fluid(
            "water",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(self.width, self.depth),
            },
            h,
        )
    }
}

/// Figures of water at rest at one instant ([`rest_figures`]): what issue
/// 13 bounds, shared by the rest-tank examples and tests in 2D and 3D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestFigures {
    /// Largest fluid particle speed, in √(g H).
    pub max_speed: f64,
    /// The particle that has it.
    pub fastest: usize,
    /// RMS fluid particle speed, in √(g H).
    pub rms_speed: f64,
    /// RMS error of the nodal fluid pressure against ρ g (H − y) over the
    /// fluid particles below the free-surface layer (`y < H − 1.5 h`),
    /// relative to the RMS of ρ g (H − y) there.
    pub pressure_rms: f64,
}

/// [`RestFigures`] of a simulation of water at rest `depth` deep over a
/// floor at `y = 0` (`y` up, 2D or 3D), gravity [`G`].
pub fn rest_figures<const D: usize>(sim: &Simulation<D>, depth: f64) -> RestFigures
where
    pfem_core::Const<D>: pfem_core::Dim,
{
    let c = (G * depth).sqrt();
    let (mut n, mut v2, mut e2, mut p2) = (0usize, 0.0, 0.0, 0.0);
    let (mut max_speed, mut fastest) = (0.0f64, 0usize);
    for i in 0..sim.particles().len() {
        if sim.particles().kind()[i] != ParticleKind::Fluid {
            continue;
        }
        n += 1;
        let s = sim.particles().v()[i].norm();
        v2 += s * s;
        if s > max_speed {
            (max_speed, fastest) = (s, i);
        }
        let y = sim.particles().x()[i][1];
        if y < depth - 1.5 * sim.particles().spacing()[i] {
            let rho = sim.materials()[sim.particles().material()[i] as usize].density();
            let exact = rho * G * (depth - y);
            e2 += (sim.particles().pressure()[i] - exact).powi(2);
            p2 += exact * exact;
        }
    }
    RestFigures {
        max_speed: max_speed / c,
        fastest,
        rms_speed: if n > 0 {
            (v2 / n as f64).sqrt() / c
        } else {
            0.0
        },
        pressure_rms: if p2 > 0.0 { (e2 / p2).sqrt() } else { 0.0 },
    }
}

/// Water at rest in a tank: a column `height` high and `width` wide.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hydrostatic {
    /// Column width (m).
    pub width: f64,
    /// Column height (m).
    pub height: f64,
    /// Spacing (m).
    pub spacing: f64,
    /// End time (s).
    pub end_time: f64,
}

impl Default for Hydrostatic {
    fn default() -> Self {
        Self {
            width: 0.5,
            height: 0.5,
            spacing: 0.0125,
            end_time: 1.0,
        }
    }
}

impl Hydrostatic {
    /// The scene.
    pub fn scene(&self) -> Scene<2> {
        let h = self.spacing;
        let s = Scene::<2>::new("hydrostatic_2d")
            .gravity(Vector::<2>::new(0.0, -G))
            .settings(RunSettings {
                end_time: self.end_time,
                max_dt: 5e-3,
                courant: 0.5,
                output_interval: Some(self.end_time / 10.0),
                alpha: 1.3,
            });
        let top = self.height * 1.2;
        let s = tank(
            s,
            0.0,
            self.width,
            &[(0.0, -1.0, top), (self.width, 1.0, top)],
            h,
        );
        s.fluid(
            "water",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(self.width, self.height),
            },
            h,
        )
    }

    /// Probes `bottom_pressure` (Pa, mean over floor particles under the
    /// column), `max_speed` (m/s) and `volume`.
    pub fn probes(&self) -> Vec<Probe<2>> {
        vec![
            Probe::new("bottom_pressure", |s: &Simulation<2>| bottom_pressure(s)),
            Probe::new("max_speed", |s: &Simulation<2>| {
                (0..s.particles().len())
                    .filter(|&i| s.particles().kind()[i] == ParticleKind::Fluid)
                    .map(|i| s.particles().v()[i].norm())
                    .fold(0.0, f64::max)
            }),
            Probe::new("volume", |s: &Simulation<2>| s.fluid_volume()),
        ]
    }
}

/// Mean pressure of the wall particles on the floor's top row (y = 0) that
/// touch the fluid, excluding the corners: 0 where that row is dry, NaN
/// where the scene has no wall particle at y = 0 (a tank raised off the
/// origin read 0, as if dry: the review of session 45).
pub fn bottom_pressure(s: &Simulation<2>) -> f64 {
    // (A set changed by hand: its elements are the old set's, session 49.)
    if !s.is_meshed() {
        return f64::NAN;
    }
    let mut in_fluid = vec![false; s.particles().len()];
    for &p in s.elements().fluid() {
        in_fluid[p as usize] = true;
    }
    let (mut sum, mut n) = (0.0, 0);
    let xs: Vec<f64> = (0..s.particles().len())
        .filter(|&i| s.particles().kind()[i] == ParticleKind::Fluid)
        .map(|i| s.particles().x()[i].x)
        .collect();
    let (xmin, xmax) = xs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    for i in 0..s.particles().len() {
        let x = s.particles().x()[i];
        if s.particles().kind()[i] == ParticleKind::Wall
            && in_fluid[i]
            && x.y.abs() < 1e-9
            && x.x > xmin + 1e-9
            && x.x < xmax - 1e-9
        {
            sum += s.particles().pressure()[i];
            n += 1;
        }
    }
    if n > 0 {
        sum / n as f64
    } else if (0..s.particles().len()).any(|i| {
        s.particles().kind()[i] == ParticleKind::Wall && s.particles().x()[i].y.abs() < 1e-9
    }) {
        0.0
    } else {
        f64::NAN
    }
}

/// A water column collapsing onto an elastic obstacle clamped to the floor:
/// the 2D analogue of the paper's §9.2 (a column as in Koshizuka et al.
/// 1995, 0.146 m wide and 0.292 m high in a 0.584 m tank; an obstacle
/// 0.03 m wide and 0.15 m high, ρ = 2500 kg/m³, E = 1 MPa, ν = 0.3, whose
/// width is the paper's cylinder diameter).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DamBreakObstacle {
    /// Water particle spacing (m), default 0.0073 (column width / 20).
    pub spacing: f64,
    /// Obstacle particle spacing (m), default 0.00375 (8 cells across).
    pub obstacle_spacing: f64,
    /// End time (s), default 1.0.
    pub end_time: f64,
    /// Obstacle's Young's modulus (Pa), default 1e6.
    pub young: f64,
}

impl Default for DamBreakObstacle {
    fn default() -> Self {
        Self {
            spacing: 0.0073,
            obstacle_spacing: 0.00375,
            end_time: 1.0,
            young: 1e6,
        }
    }
}

/// Obstacle of [`DamBreakObstacle`]: left face (m).
pub const OBSTACLE_X: f64 = 0.35;
/// Obstacle width (m).
pub const OBSTACLE_WIDTH: f64 = 0.03;
/// Obstacle height (m).
pub const OBSTACLE_HEIGHT: f64 = 0.15;

impl DamBreakObstacle {
    /// The scene; [`SceneError::InvalidMaterial`] when `young` is out of
    /// range.
    pub fn scene(&self) -> Result<Scene<2>, SceneError> {
        let h = self.spacing;
        let length = 0.584;
        let s = Scene::<2>::new("dam_break_obstacle_2d")
            .gravity(Vector::<2>::new(0.0, -G))
            .settings(RunSettings {
                end_time: self.end_time,
                max_dt: 2e-3,
                courant: 0.5,
                output_interval: Some(0.02),
                alpha: 1.3,
            });
        let s = tank(s, 0.0, length, &[(0.0, -1.0, 0.45), (length, 1.0, 0.45)], h);
        let obstacle = solid_material("obstacle", 2500.0, self.young, 0.3, false)?;
        let ho = self.obstacle_spacing;
        let s = s.solid(
            "obstacle",
            Box::new(obstacle),
            Geometry::Box {
                min: Point::<2>::new(OBSTACLE_X, ho),
                max: Point::<2>::new(OBSTACLE_X + OBSTACLE_WIDTH, OBSTACLE_HEIGHT),
            },
            ho,
            Some((
                Point::<2>::new(OBSTACLE_X - 1.0, -1.0),
                Point::<2>::new(OBSTACLE_X + 1.0, ho + 1e-9),
            )),
        );
        Ok(s.fluid(
            "water",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(0.146, 0.292),
            },
            h,
        ))
    }

    /// Probes `ux_top` (m, mean horizontal displacement of the obstacle's
    /// top row), `force_x` (N per metre, pressure force of the water on the
    /// obstacle) and `volume`.
    pub fn probes(&self) -> Vec<Probe<2>> {
        vec![
            Probe::new("ux_top", |s: &Simulation<2>| {
                let top: Vec<usize> = s
                    .body_particles("obstacle")
                    .unwrap_or_default()
                    .into_iter()
                    .filter(|&i| (s.initial_position(i).y - OBSTACLE_HEIGHT).abs() < 1e-9)
                    .collect();
                if top.is_empty() {
                    return 0.0;
                }
                top.iter()
                    .map(|&i| s.particles().x()[i].x - s.initial_position(i).x)
                    .sum::<f64>()
                    / top.len() as f64
            }),
            Probe::new("force_x", |s: &Simulation<2>| {
                s.pressure_force_on("obstacle").map_or(f64::NAN, |f| f.x)
            }),
            Probe::new("volume", |s: &Simulation<2>| s.fluid_volume()),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases3d::ColumnOnCylinder3d;

    /// A case with an impossible solid gets a typed error naming the body,
    /// not a panic.
    #[test]
    fn cases_with_invalid_solids_are_errors() {
        let gate = ElasticGate {
            poisson: 0.5,
            ..Default::default()
        };
        match gate.scene() {
            Err(SceneError::InvalidMaterial { body, .. }) => assert_eq!(body, "gate"),
            other => panic!("expected an invalid-material error, got {:?}", other.err()),
        }
        let obstacle = DamBreakObstacle {
            young: -1.0,
            ..Default::default()
        };
        let e = match obstacle.scene() {
            Err(e) => e,
            Ok(_) => panic!("a negative Young's modulus was accepted"),
        };
        assert!(e.to_string().contains("obstacle"), "{e}");
        let cylinder = ColumnOnCylinder3d {
            density: f64::NAN,
            ..Default::default()
        };
        assert!(matches!(
            cylinder.scene(),
            Err(SceneError::InvalidMaterial { .. })
        ));
        assert!(ElasticGate::default().scene().is_ok());
        // Session 44's review: a Couette with no cell or no gap (rings of
        // `usize::MAX` particles), a shift scan at a step of zero (for
        // ever).
        use crate::exact::CircularCouette;
        for c in [
            CircularCouette {
                cells: 0,
                ..Default::default()
            },
            CircularCouette {
                outer: 0.5,
                ..Default::default()
            },
            CircularCouette {
                inner: f64::NAN,
                ..Default::default()
            },
        ] {
            assert!(
                matches!(c.scene(), Err(SceneError::InvalidSetting { .. })),
                "{c:?}"
            );
        }
        assert!(CircularCouette::default().scene().is_ok());
        let curve: Vec<(f64, f64)> = (0..50).map(|i| (i as f64 * 0.1, 1.0 + i as f64)).collect();
        let shifted: Vec<(f64, f64)> = curve.iter().map(|&(t, z)| (t + 0.3, z)).collect();
        let (shift, rms) = best_shift(&curve, &shifted, 4.0, 0.5, 0.0);
        assert!((shift - 0.3).abs() < 1e-6 && rms < 1e-9, "{shift} {rms}");
        assert_eq!(best_shift(&curve, &shifted, 4.0, 0.5, f64::NAN).0, 0.0);
        let (shift, _) = best_shift(&curve, &shifted, 4.0, 0.5, 0.05);
        assert!((shift - 0.3).abs() < 1e-9, "{shift}");
    }
}
