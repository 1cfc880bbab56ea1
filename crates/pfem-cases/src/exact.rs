//! Cases with exact references, for convergence studies (issue 16): each
//! has a closed-form solution and a measure of the error against it that
//! falls with resolution.
//!
//! - [`CircularCouette`]: viscous flow between a turning and a fixed
//!   cylinder, its steady state against `A r + B / r`;
//! - [`StartupPoiseuille`]: viscous flow between two plates started from
//!   rest by a body force along the channel, against the series solution
//!   (a column with free ends: see its known defect);
//! - [`StandingWave`]: the first sloshing mode of a tank, its frequency
//!   against linear theory;
//! - [`Cantilever`]: the Turek–Hron CSM beam, its static tip deflection
//!   and its first free-vibration frequency against Timoshenko beam theory;
//! - water at rest: [`crate::cases::RestTank`] and
//!   [`crate::cases::rest_figures`] (the method is exact there: see
//!   `docs/accuracy-cost.md`).
//!
//! Each case sets its time step with its spacing (`max_dt ∝ h`), so a
//! spacing sweep refines space and time together.

use std::f64::consts::PI;

use pfem_constitutive::Newtonian;
use pfem_core::{ParticleKind, Point, Vector};

use crate::cases::{solid_material, G};
use crate::error::SceneError;
use crate::scene::{Geometry, RunSettings, Scene, WallMotion};
use crate::simulation::Simulation;

/// A Newtonian fluid body's material, or [`SceneError::InvalidMaterial`]
/// naming the body `fluid`.
fn fluid(density: f64, viscosity: f64, bulk_modulus: f64) -> Result<Newtonian, SceneError> {
    Newtonian::new(density, viscosity, bulk_modulus).map_err(|source| SceneError::InvalidMaterial {
        body: "fluid".into(),
        source,
    })
}

/// Start-up of plane Poiseuille flow: fluid between two no-slip plates
/// `y = 0` and `y = width`, at rest at `t = 0`, driven by a body force
/// `forcing` along `x`. The channel's fluid is `length` long with free ends
/// (no gravity across the channel, so no pressure away from the ends);
/// the plates extend half a length beyond each end.
///
/// Exact velocity (Batchelor 1967 §4.3; the sine series of the steady
/// parabola times its decay), with `ν = μ/ρ`:
///
/// `u(y, t) = Σ_{n odd} 4 f H² / (ν π³ n³) · sin(nπy/H) · (1 − e^{−n²π²νt/H²})`.
///
/// The error ([`StartupPoiseuille::profile_error`]) is the RMS of `u − u_exact`
/// over the fluid particles that started within half a width of the
/// channel's middle, two widths from either end, relative to the exact
/// centre-line speed.
///
/// **Known defect, measured**: the free ends drive the whole column faster
/// than the exact solution by an amount that grows with refinement and
/// falls as `1/length` (at 32 cells across, error 1.55·10⁻², 7.3·10⁻³,
/// 3.6·10⁻³ for lengths 2, 4, 8 `H`; the middle section runs uniformly
/// +0.7 % fast at 32 cells, +0.4 % at 16 beyond the interior error; at
/// 32 cells the step (×2, ×½: 7.31, 7.68·10⁻³), the bulk modulus
/// (2.2·10⁷ Pa: 7.49·10⁻³), the volume correction (off: 7.13·10⁻³) and
/// `p = 0` on the surface (off: 7.50·10⁻³) barely move it, α some (1.15:
/// 7.44·10⁻³, 1.6: 5.93·10⁻³)). The profile error therefore converges from 4
/// to 16 cells (order 3.1 in the study of 6 December 2026) and rises at 32. The column's ends are moving
/// contact lines on no-slip plates, where the continuum stress is
/// singular (Huh & Scriven 1971) and the discrete model regularises it at
/// the spacing: a force there that changes with `h` is expected, though
/// not its forward sign. Ruled out: the wall particles' own nodal
/// volumetric force (eq. 58, one-sided patches at a contact line);
/// dropping it made the channel worse (3.5·10⁻³ at 16 cells, 8.4·10⁻³ at
/// 32).
/// [`CircularCouette`], which has no ends, measures viscous convergence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartupPoiseuille {
    /// Channel width `H` (m), default 0.1.
    pub width: f64,
    /// Length of fluid (m), default 4 `H`.
    pub length: f64,
    /// Density (kg/m³), default 1000.
    pub density: f64,
    /// Dynamic viscosity (Pa·s), default 10 (`ν = 0.01` m²/s, so the
    /// diffusion time `H²/ν` is 1 s).
    pub viscosity: f64,
    /// Body force along the channel (m/s²), default 1.
    pub forcing: f64,
    /// Bulk modulus (Pa), default water's 2.2 GPa.
    pub bulk_modulus: f64,
    /// Cells across the width (`h = H / cells`), default 8.
    pub cells: usize,
    /// Time steps over the run at 8 cells, default 20; the step scales
    /// with the spacing.
    pub steps_at_8: usize,
    /// End time (s), default 0.2 (`ν t / H² = 0.2`: the profile still
    /// developing).
    pub end_time: f64,
}

impl Default for StartupPoiseuille {
    fn default() -> Self {
        Self {
            width: 0.1,
            length: 0.4,
            density: 1000.0,
            viscosity: 10.0,
            forcing: 1.0,
            bulk_modulus: Newtonian::water().bulk_modulus(),
            cells: 8,
            steps_at_8: 20,
            end_time: 0.2,
        }
    }
}

impl StartupPoiseuille {
    /// Particle spacing (m).
    pub fn spacing(&self) -> f64 {
        self.width / self.cells as f64
    }

    /// Largest time step (s): `end_time / steps_at_8` at 8 cells, ∝ `h`.
    pub fn max_dt(&self) -> f64 {
        self.end_time / self.steps_at_8 as f64 * 8.0 / self.cells as f64
    }

    /// The scene.
    pub fn scene(&self) -> Result<Scene<2>, SceneError> {
        let (h, w, l) = (self.spacing(), self.width, self.length);
        let fluid = fluid(self.density, self.viscosity, self.bulk_modulus)?;
        // Plates from half a length before to half a length after the
        // fluid, on the same lattice (l/2 is a whole number of spacings
        // when `length` is).
        let x0 = -(0.5 * l / h).round() * h;
        let x1 = l - x0;
        let s = Scene::<2>::new("startup_poiseuille_2d")
            .gravity(Vector::<2>::new(self.forcing, 0.0))
            .settings(RunSettings {
                end_time: self.end_time,
                max_dt: self.max_dt(),
                courant: 0.5,
                output_interval: None,
                alpha: 1.3,
            })
            .wall(
                "bottom",
                Geometry::Box {
                    min: Point::<2>::new(x0, -h),
                    max: Point::<2>::new(x1, 0.0),
                },
                h,
                WallMotion::Fixed,
            )
            .wall(
                "top",
                Geometry::Box {
                    min: Point::<2>::new(x0, w),
                    max: Point::<2>::new(x1, w + h),
                },
                h,
                WallMotion::Fixed,
            );
        Ok(s.fluid(
            "fluid",
            Box::new(fluid),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(l, w),
            },
            h,
        ))
    }

    /// Exact velocity along the channel at height `y` and time `t` (m/s).
    pub fn exact(&self, y: f64, t: f64) -> f64 {
        let nu = self.viscosity / self.density;
        let hh = self.width;
        let mut u = 0.0;
        for k in 0..200 {
            let n = (2 * k + 1) as f64;
            let decay = (-(n * PI / hh).powi(2) * nu * t).exp();
            u += 4.0 * self.forcing * hh * hh / (nu * PI.powi(3) * n.powi(3))
                * (n * PI * y / hh).sin()
                * (1.0 - decay);
        }
        u
    }

    /// RMS error of the velocity along the channel over the middle section
    /// (fluid particles that started within `H/2` of `x = length/2`),
    /// relative to the exact centre-line speed at the simulation's time.
    pub fn profile_error(&self, sim: &Simulation<2>) -> f64 {
        let t = sim.time();
        let mid = 0.5 * self.length;
        let (mut e2, mut n) = (0.0, 0usize);
        for i in 0..sim.particles().len() {
            if sim.particles().kind()[i] != ParticleKind::Fluid
                || (sim.initial_position(i).x - mid).abs() > 0.5 * self.width + 1e-12
            {
                continue;
            }
            let x = sim.particles().x()[i];
            let v = sim.particles().v()[i];
            e2 += (v.x - self.exact(x.y, t)).powi(2) + v.y * v.y;
            n += 1;
        }
        let centre = self.exact(0.5 * self.width, t);
        if n == 0 || centre == 0.0 {
            return f64::NAN;
        }
        (e2 / n as f64).sqrt() / centre
    }
}

/// Circular Couette flow: fluid between a cylinder of radius `inner`
/// turning at `rate` and a fixed one of radius `outer` (2D, no gravity),
/// from rest to its steady state. The annulus has no ends and no free
/// surface, so it measures the viscous discretisation alone (the straight
/// channel of [`StartupPoiseuille`] has free ends, whose effect does not
/// vanish with refinement: see its docs).
///
/// Exact steady velocity (Batchelor 1967 §4.5): azimuthal,
/// `u_θ(r) = A r + B / r` with `A = −ω R₁² / (R₂² − R₁²)` and
/// `B = ω R₁² R₂² / (R₂² − R₁²)`. With the defaults the diffusion time
/// `(R₂ − R₁)²/ν` is 1 s and the run ends at 1.5 s, when the slowest
/// transient has decayed by e⁻¹⁵ (its rate `ν λ₁²`, `λ₁` = 6.39 m⁻¹).
///
/// Particles lie on rings `h` apart (two wall rings each side), `round(2π
/// r / h)` per ring, alternate rings turned by half a spacing. The error
/// ([`CircularCouette::velocity_error`]) is the RMS of `|v − u_θ e_θ|`
/// over the fluid particles, relative to the wall speed `ω R₁`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CircularCouette {
    /// Inner radius `R₁` (m), default 0.5.
    pub inner: f64,
    /// Outer radius `R₂` (m), default 1.
    pub outer: f64,
    /// Angular velocity of the inner cylinder `ω` (rad/s), default 0.1.
    pub rate: f64,
    /// Density (kg/m³), default 1000.
    pub density: f64,
    /// Dynamic viscosity (Pa·s), default 250 (`ν = 0.25` m²/s).
    pub viscosity: f64,
    /// Cells across the gap (`h = (R₂ − R₁) / cells`), default 8.
    pub cells: usize,
    /// Time step (s), default 0.02: the answer is the steady state, so the
    /// step does not scale with the spacing.
    pub dt: f64,
    /// End time (s), default 1.5.
    pub end_time: f64,
}

impl Default for CircularCouette {
    fn default() -> Self {
        Self {
            inner: 0.5,
            outer: 1.0,
            rate: 0.1,
            density: 1000.0,
            viscosity: 250.0,
            cells: 8,
            dt: 0.02,
            end_time: 1.5,
        }
    }
}

impl CircularCouette {
    /// Particle spacing (m).
    pub fn spacing(&self) -> f64 {
        (self.outer - self.inner) / self.cells as f64
    }

    /// Particles on the rings `r = r0 + k h`, `k = 0 .. rings`.
    fn rings(&self, r0: f64, rings: usize) -> Vec<Point<2>> {
        let h = self.spacing();
        let mut pts = Vec::new();
        for k in 0..rings {
            let r = r0 + k as f64 * h;
            // The ring's index from the inner wall sets the stagger.
            let index = ((r - self.inner) / h).round() as i64;
            let n = ((2.0 * PI * r / h).round() as usize).max(3);
            let shift = if index.rem_euclid(2) == 1 { 0.5 } else { 0.0 };
            for j in 0..n {
                let a = 2.0 * PI * (j as f64 + shift) / n as f64;
                pts.push(Point::<2>::new(r * a.cos(), r * a.sin()));
            }
        }
        pts
    }

    /// The scene (water's bulk modulus). At least two cells across the gap
    /// and `0 < inner < outer`, finite (a zero gap or no cell made rings
    /// of `usize::MAX` particles).
    pub fn scene(&self) -> Result<Scene<2>, SceneError> {
        if self.cells < 2 {
            return Err(SceneError::InvalidSetting {
                setting: "cells",
                value: self.cells as f64,
            });
        }
        for (setting, value, ok) in [
            ("inner", self.inner, self.inner > 0.0),
            ("outer", self.outer, self.outer > self.inner),
        ] {
            if !(ok && value.is_finite()) {
                return Err(SceneError::InvalidSetting { setting, value });
            }
        }
        let h = self.spacing();
        let fluid = fluid(
            self.density,
            self.viscosity,
            Newtonian::water().bulk_modulus(),
        )?;
        let spin =
            pfem_scene::motion::Rotation::new(Point::<2>::zeros(), None, self.rate, 0.0, 1.0, 0.0)?;
        Ok(Scene::<2>::new("circular_couette_2d")
            .settings(RunSettings {
                end_time: self.end_time,
                max_dt: self.dt,
                courant: 0.5,
                output_interval: None,
                alpha: 1.3,
            })
            .wall(
                "inner",
                Geometry::Particles(self.rings(self.inner - h, 2)),
                h,
                WallMotion::Law(std::sync::Arc::new(spin)),
            )
            .wall(
                "outer",
                Geometry::Particles(self.rings(self.outer, 2)),
                h,
                WallMotion::Fixed,
            )
            .fluid(
                "fluid",
                Box::new(fluid),
                Geometry::Particles(self.rings(self.inner + h, self.cells - 1)),
                h,
            ))
    }

    /// Exact steady azimuthal velocity at radius `r` (m/s).
    pub fn exact(&self, r: f64) -> f64 {
        let (r1, r2) = (self.inner * self.inner, self.outer * self.outer);
        let a = -self.rate * r1 / (r2 - r1);
        let b = self.rate * r1 * r2 / (r2 - r1);
        a * r + b / r
    }

    /// RMS of `|v − u_θ(r) e_θ|` over the fluid particles, relative to
    /// `ω R₁`.
    pub fn velocity_error(&self, sim: &Simulation<2>) -> f64 {
        let (mut e2, mut n) = (0.0, 0usize);
        for i in 0..sim.particles().len() {
            if sim.particles().kind()[i] != ParticleKind::Fluid {
                continue;
            }
            let x = sim.particles().x()[i];
            let r = x.norm();
            if r == 0.0 {
                continue;
            }
            let e_theta = Vector::<2>::new(-x.y / r, x.x / r);
            e2 += (sim.particles().v()[i] - e_theta * self.exact(r)).norm_squared();
            n += 1;
        }
        if n == 0 {
            return f64::NAN;
        }
        (e2 / n as f64).sqrt() / (self.rate * self.inner)
    }

    /// Runs the case with `params`; the error is
    /// [`CircularCouette::velocity_error`] at the end time, the value the
    /// wall speed `ω R₁` (m/s).
    pub fn run(&self, params: pfem_time::StepParams) -> Result<ExactRun, CaseError> {
        let mut sim = simulation(self.scene()?, params)?;
        let (_, wall) = run_series(&mut sim, |_| 0.0)?;
        Ok(ExactRun {
            second_error: f64::NAN,
            error: self.velocity_error(&sim),
            value: self.rate * self.inner,
            wall,
            sim,
        })
    }
}

/// The first sloshing mode of a tank `length` wide holding water `depth`
/// deep (no-slip walls on three sides, open top), started at `t = 0` with a
/// flat surface and the mode's potential-flow velocity, so that the surface
/// elevation is `η(x, t) = a cos(kx) sin(ωt)` with `k = π / length` and
/// linear theory's frequency `ω² = g k tanh(k · depth)` (Lamb 1932 §227).
///
/// [`StandingWave::mode_amplitude`] projects the surface particles'
/// elevation on `cos(kx)`; [`StandingWave::frequency`] reads `ω` from its
/// first zero crossing after the start, at `T/2`. The error is `|ω / ω_exact − 1|`. Linear elements and
/// a second-order time scheme with the step ∝ `h` should give second
/// order; the no-slip side walls, which hold the velocity at zero where the
/// mode's vertical velocity is largest, add an `O(h)` part that would show
/// at fine resolutions (measured: order 2.6 from 10 to 40 cells in the
/// accuracy study, `docs/accuracy-cost.md`; `tests/convergence.rs`
/// asserts at least 1.8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StandingWave {
    /// Tank width (m), default 1.
    pub length: f64,
    /// Water depth (m), default 0.5.
    pub depth: f64,
    /// Surface amplitude `a` (m), default 0.001 (`k a = 0.0031`). The
    /// frequency read grows with it: with `a` = 5 mm it was 1.8·10⁻³ high
    /// at 80 cells, at 1 mm 1.4·10⁻⁴ (12.6 times less; the cause, the
    /// wave's nonlinearity or the particles' Lagrangian elevation, is not
    /// separated: `docs/accuracy-cost.md`).
    pub amplitude: f64,
    /// Cells across the width (`h = length / cells`), default 20.
    pub cells: usize,
    /// Time steps per period at 20 cells, default 40; the step scales with
    /// the spacing.
    pub steps_per_period_at_20: usize,
    /// Run length in periods, default 0.82: the frequency is read from the
    /// first half period (the crossing at `T/2`), the decay from the crest
    /// at `T/4` and the trough at `3T/4`. Later, from about
    /// 0.85 `T`, the surface particles beside the left wall sink by up to
    /// 2 cm at some resolutions (29 and 80 cells): the wall–free-surface
    /// corner of issue 13, in motion.
    pub periods: f64,
}

impl Default for StandingWave {
    fn default() -> Self {
        Self {
            length: 1.0,
            depth: 0.5,
            amplitude: 0.001,
            cells: 20,
            steps_per_period_at_20: 40,
            periods: 0.82,
        }
    }
}

impl StandingWave {
    /// Wave number `k = π / length` (1/m).
    pub fn wave_number(&self) -> f64 {
        PI / self.length
    }

    /// Linear theory's angular frequency (rad/s).
    pub fn omega(&self) -> f64 {
        let k = self.wave_number();
        (G * k * (k * self.depth).tanh()).sqrt()
    }

    /// Period of linear theory (s).
    pub fn period(&self) -> f64 {
        2.0 * PI / self.omega()
    }

    /// Particle spacing (m).
    pub fn spacing(&self) -> f64 {
        self.length / self.cells as f64
    }

    /// The scene (water, walls on three sides up to 1.2 × depth).
    pub fn scene(&self) -> Scene<2> {
        let h = self.spacing();
        let dt = self.period() / self.steps_per_period_at_20 as f64 * 20.0 / self.cells as f64;
        // The open tank of water at rest, with the wave's step and length.
        let mut scene = crate::cases::RestTank {
            width: self.length,
            depth: self.depth,
            spacing: h,
            end_time: self.periods * self.period(),
        }
        .scene();
        scene.name = "standing_wave_2d".into();
        scene.settings.max_dt = dt;
        scene
    }

    /// Sets the fluid particles' velocity to the mode's at `t = 0`
    /// (`u = −aω cosh(ky)/sinh(kH) sin(kx)`, `v = aω sinh(ky)/sinh(kH)
    /// cos(kx)`) and the accelerations to match.
    pub fn start(&self, sim: &mut Simulation<2>) -> Result<(), pfem_driver::RunError> {
        let (k, w, a, hh) = (self.wave_number(), self.omega(), self.amplitude, self.depth);
        let n = sim.particles().len();
        for i in 0..n {
            if sim.particles().kind()[i] != ParticleKind::Fluid {
                continue;
            }
            let x = sim.particles().x()[i];
            let c = a * w / (k * hh).sinh();
            sim.particles_mut().v_mut()[i] = Vector::<2>::new(
                -c * (k * x.y).cosh() * (k * x.x).sin(),
                c * (k * x.y).sinh() * (k * x.x).cos(),
            );
        }
        sim.initialize_acceleration()
    }

    /// The mode's amplitude now (m): the surface particles' (those that
    /// started at `y = depth`) elevation projected on `cos(kx)`,
    /// `Σ η_i cos(k x_i) / Σ cos²(k x_i)`.
    pub fn mode_amplitude(&self, sim: &Simulation<2>) -> f64 {
        let k = self.wave_number();
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..sim.particles().len() {
            if sim.particles().kind()[i] != ParticleKind::Fluid
                || (sim.initial_position(i).y - self.depth).abs() > 1e-9
            {
                continue;
            }
            let x = sim.particles().x()[i];
            let c = (k * sim.initial_position(i).x).cos();
            num += (x.y - self.depth) * c;
            den += c * c;
        }
        if den > 0.0 {
            num / den
        } else {
            f64::NAN
        }
    }

    /// Error of the amplitude's decay over half a period against linear
    /// theory: the trough after `T/2` over the crest before it, against
    /// `exp(−2 ν k² T/2)` (Lamb 1932 §348, water's ν = 10⁻⁶ m²/s: 1 − 10⁻⁵),
    /// as `|ratio / theory − 1|`; `NaN` when the series does not reach a
    /// trough after `T/2`. The crest itself is not compared with `a`: the
    /// no-slip side walls hold the mode's largest vertical velocity at zero
    /// from the start and lose `O(h)` of its energy (crest 6.7, 4.0, 2.2 %
    /// low at 10, 20, 40 cells: order 0.8, tending to 1).
    pub fn decay_error(&self, series: &[(f64, f64)]) -> f64 {
        let half = 0.5 * self.period();
        let crest = series
            .iter()
            .filter(|q| q.0 <= half)
            .map(|q| q.1)
            .fold(f64::NEG_INFINITY, f64::max);
        let trough = series
            .iter()
            .filter(|q| q.0 > half)
            .map(|q| q.1)
            .fold(f64::INFINITY, f64::min);
        // The trough must be an interior minimum, not the series' end.
        let end = series.last().map_or(f64::NAN, |q| q.1);
        if !(crest > 0.0 && trough < 0.0) || trough == end {
            return f64::NAN;
        }
        let nu = 1e-6;
        let k = self.wave_number();
        let theory = (-2.0 * nu * k * k * half).exp();
        (-trough / crest / theory - 1.0).abs()
    }

    /// Angular frequency (rad/s) read from a time series: `π` over the
    /// mean spacing of its zero crossings after `t = 0` (linearly
    /// interpolated), counting `t = 0` as one when `starts_at_zero` (the
    /// wave starts with a flat surface), or `NaN` with fewer than two.
    pub fn frequency(series: &[(f64, f64)], starts_at_zero: bool) -> f64 {
        let mut crossings = Vec::new();
        if starts_at_zero {
            crossings.push(0.0);
        }
        for w in series.windows(2) {
            let ((t0, y0), (t1, y1)) = (w[0], w[1]);
            if t0 > 0.0 && y0 != 0.0 && y0.signum() != y1.signum() {
                crossings.push(t0 + (t1 - t0) * y0 / (y0 - y1));
            }
        }
        if crossings.len() < 2 {
            return f64::NAN;
        }
        let span = crossings[crossings.len() - 1] - crossings[0];
        PI * (crossings.len() - 1) as f64 / span
    }
}

/// The Turek–Hron CSM beam (Turek & Hron 2006): `length` 0.35 m,
/// `thickness` 0.02 m, `ρ` = 1000 kg/m³, ν = 0.4, E = 5.6 MPa (CSM2),
/// clamped at `x = 0`, under gravity `gravity` = 2 m/s² along `−y`.
///
/// References (Timoshenko beam theory with the shear coefficient
/// `κ = 5/6`; `E' = E/(1−ν²)` in plane strain, `E` in plane stress;
/// `q = ρ g t`, `I = t³/12`, `A = t`, `G = E/(2(1+ν))`):
/// - static tip deflection `δ = q L⁴/(8 E' I) + q L²/(2 κ G A)`: 16.95 mm
///   for CSM2 in plane strain, against Turek & Hron's nonlinear 16.97 mm;
/// - first bending frequency `ω₁ = β₁² √(E' I / (ρ A L⁴))`, `β₁ =
///   1.8751`, less its shear and rotary-inertia correction to first order,
///   `ω ≈ ω₁ (1 − ½ (β₁ r/L)² (1 + E'/(κ G)))`, `r² = I/A` (Han, Benaroya
///   & Wei 1999): a 0.3 % correction here.
///
/// The clamp is beam theory's (`Cantilever::simulation`): the root's
/// cross-section is held straight and vertical (`u_x = 0` on every root
/// particle) and its mid-thickness held still (`u = 0`), so that the root
/// contracts across the thickness as the beam's Poisson ratio has it.
/// Holding both components on the whole root (the scene's box clamp,
/// until session 47) is a stiffer problem in plane strain at ν = 0.4: a
/// review's independent 2D linear-elastic solve converged to 16.86 mm and
/// 13.53 rad/s for it (−0.56 % and +0.2 % from these references), and
/// 16.97 mm and 13.48 rad/s with this clamp (+0.1 %, −0.1 %).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cantilever {
    /// Length (m).
    pub length: f64,
    /// Thickness (m).
    pub thickness: f64,
    /// Density (kg/m³).
    pub density: f64,
    /// Young's modulus (Pa).
    pub young: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// Gravity (m/s², along −y).
    pub gravity: f64,
    /// Plane stress (`true`) or plane strain (`false`, the default).
    pub plane_stress: bool,
    /// Cells through the thickness (`h = thickness / cells`), default 4.
    pub cells: usize,
}

impl Default for Cantilever {
    fn default() -> Self {
        Self {
            length: 0.35,
            thickness: 0.02,
            density: 1000.0,
            young: 5.6e6,
            poisson: 0.4,
            gravity: 2.0,
            plane_stress: false,
            cells: 4,
        }
    }
}

impl Cantilever {
    /// Particle spacing (m).
    pub fn spacing(&self) -> f64 {
        self.thickness / self.cells as f64
    }

    fn bending_modulus(&self) -> f64 {
        if self.plane_stress {
            self.young
        } else {
            self.young / (1.0 - self.poisson * self.poisson)
        }
    }

    fn shear_modulus(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }

    /// Timoshenko's static tip deflection under the beam's weight (m,
    /// positive down).
    pub fn static_deflection(&self) -> f64 {
        let t = self.thickness;
        self.section()
            .tip_deflection(self.density * self.gravity * t)
    }

    /// The beam per unit depth: rectangle `thickness` × 1.
    fn section(&self) -> BeamSection {
        let t = self.thickness;
        BeamSection {
            length: self.length,
            area: t,
            second_moment: t.powi(3) / 12.0,
            bending_modulus: self.bending_modulus(),
            shear_modulus: self.shear_modulus(),
            density: self.density,
        }
    }

    /// First bending frequency with the first-order shear and rotary
    /// inertia correction (rad/s).
    pub fn omega(&self) -> f64 {
        self.section().first_frequency()
    }

    /// The scene: the beam held at the mid-thickness of its root `x = 0`
    /// (the particles within half a spacing of it), gravity switched on at
    /// `t = 0` (so it vibrates about its static deflection), to `end_time`
    /// with steps up to `max_dt`. [`Cantilever::simulation`] adds the rest
    /// of the clamp (`u_x = 0` on the root).
    pub fn scene(&self, end_time: f64, max_dt: f64) -> Result<Scene<2>, SceneError> {
        let m = solid_material(
            "beam",
            self.density,
            self.young,
            self.poisson,
            self.plane_stress,
        )?;
        Ok(Scene::<2>::new("cantilever_2d")
            .gravity(Vector::<2>::new(0.0, -self.gravity))
            .settings(RunSettings {
                end_time,
                max_dt,
                courant: 0.5,
                output_interval: None,
                alpha: 1.3,
            })
            .solid(
                "beam",
                Box::new(m),
                Geometry::Box {
                    min: Point::<2>::new(0.0, 0.0),
                    max: Point::<2>::new(self.length, self.thickness),
                },
                self.spacing(),
                Some((
                    Point::<2>::new(-1.0, 0.5 * (self.thickness - self.spacing()) - 1e-9),
                    Point::<2>::new(1e-9, 0.5 * (self.thickness + self.spacing()) + 1e-9),
                )),
            ))
    }

    /// The simulation of [`Cantilever::scene`] with beam theory's clamp:
    /// every root particle (`x = 0`) has `u_x = 0` too, and the
    /// accelerations are set again for it.
    pub fn simulation(
        &self,
        end_time: f64,
        max_dt: f64,
        params: pfem_time::StepParams,
    ) -> Result<Simulation<2>, CaseError> {
        let mut sim = simulation(self.scene(end_time, max_dt)?, params)?;
        let root: Vec<usize> = (0..sim.particles().len())
            .filter(|&i| sim.initial_position(i).x <= 1e-9)
            .collect();
        let p = sim.particles_mut();
        for &i in &root {
            if !p.constraints().is_fully_fixed(i) {
                p.constraints_mut().fix_component(i, 0, 0.0);
                p.v_mut()[i].x = 0.0;
            }
        }
        sim.initialize_acceleration()?;
        Ok(sim)
    }

    /// The particle at the free end's mid-thickness.
    pub fn tip(&self, sim: &Simulation<2>) -> usize {
        let target = Point::<2>::new(self.length, 0.5 * self.thickness);
        (0..sim.particles().len())
            .min_by(|&a, &b| {
                (sim.initial_position(a) - target)
                    .norm()
                    .total_cmp(&(sim.initial_position(b) - target).norm())
            })
            .unwrap_or(0)
    }
}

/// A clamped-free beam for Timoshenko's closed forms (shear factor 5/6):
/// the 2D [`Cantilever`] per unit depth, or a 3D beam of any section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamSection {
    /// Length (m).
    pub length: f64,
    /// Cross-section area (m², or m per unit depth in 2D).
    pub area: f64,
    /// Second moment of the section about its bending axis (m⁴, or m³).
    pub second_moment: f64,
    /// Bending modulus (Pa): `E`, or `E / (1 − ν²)` in plane strain.
    pub bending_modulus: f64,
    /// Shear modulus `G` (Pa).
    pub shear_modulus: f64,
    /// Density (kg/m³).
    pub density: f64,
}

impl BeamSection {
    /// Static tip deflection under a uniform load `q` per unit length (m,
    /// along the load): bending plus shear.
    pub fn tip_deflection(&self, q: f64) -> f64 {
        let (l, e, i) = (self.length, self.bending_modulus, self.second_moment);
        q * l.powi(4) / (8.0 * e * i)
            + q * l * l / (2.0 * 5.0 / 6.0 * self.shear_modulus * self.area)
    }

    /// First bending frequency with the first-order shear and rotary
    /// inertia correction (rad/s).
    pub fn first_frequency(&self) -> f64 {
        let (l, e, i) = (self.length, self.bending_modulus, self.second_moment);
        let beta = 1.875_104_068_711_96;
        let w1 = beta * beta * (e * i / (self.density * self.area * l.powi(4))).sqrt();
        let r2 = i / self.area;
        w1 * (1.0 - 0.5 * beta * beta * r2 / (l * l) * (1.0 + e / (5.0 / 6.0 * self.shear_modulus)))
    }
}

/// A finished run of an exact-reference case.
pub struct ExactRun {
    /// Relative error against the exact reference.
    pub error: f64,
    /// The case's second figure: the measured frequency (rad/s) for
    /// [`StandingWave`] and the vibrating [`Cantilever`], the tip deflection
    /// (m) for the static one, the centre-line speed (m/s) for
    /// [`StartupPoiseuille`].
    pub value: f64,
    /// A second relative error where the case has one, `NaN` elsewhere:
    /// the standing wave's amplitude decay over half a period
    /// ([`StandingWave::decay_error`]).
    pub second_error: f64,
    /// Wall time of the run (s).
    pub wall: f64,
    /// The simulation at its end (statistics, steps, rejected steps).
    pub sim: Simulation<2>,
}

/// Errors of an exact-reference run: the scene or the run.
pub type CaseError = Box<dyn std::error::Error + Send + Sync>;

/// Records `(t, f(sim))` at the start and after every step.
struct Series<F: Fn(&Simulation<2>) -> f64> {
    f: F,
    data: Vec<(f64, f64)>,
}

impl<F: Fn(&Simulation<2>) -> f64> crate::simulation::Observer<2> for Series<F> {
    fn start(&mut self, sim: &Simulation<2>) -> Result<(), pfem_driver::RunError> {
        self.data.push((sim.time(), (self.f)(sim)));
        Ok(())
    }
    fn step(&mut self, sim: &Simulation<2>) -> Result<(), pfem_driver::RunError> {
        self.data.push((sim.time(), (self.f)(sim)));
        Ok(())
    }
}

/// Runs `sim` to its end, recording `f`; the series and the wall time.
fn run_series(
    sim: &mut Simulation<2>,
    f: impl Fn(&Simulation<2>) -> f64,
) -> Result<(Vec<(f64, f64)>, f64), CaseError> {
    let mut rec = Series {
        f,
        data: Vec::new(),
    };
    let t0 = std::time::Instant::now();
    sim.run(&mut [&mut rec])?;
    Ok((rec.data, t0.elapsed().as_secs_f64()))
}

fn simulation(scene: Scene<2>, params: pfem_time::StepParams) -> Result<Simulation<2>, CaseError> {
    Ok(Simulation::new(
        scene,
        Box::new(pfem_geometry::Delaunay2::default()),
        params,
    )?)
}

impl StartupPoiseuille {
    /// Runs the case with `params`; the error is
    /// [`StartupPoiseuille::profile_error`] at the end time.
    pub fn run(&self, params: pfem_time::StepParams) -> Result<ExactRun, CaseError> {
        let mut sim = simulation(self.scene()?, params)?;
        let (_, wall) = run_series(&mut sim, |_| 0.0)?;
        Ok(ExactRun {
            second_error: f64::NAN,
            error: self.profile_error(&sim),
            value: self.exact(0.5 * self.width, sim.time()),
            wall,
            sim,
        })
    }
}

impl StandingWave {
    /// Runs the case with `params` from the mode's velocity
    /// ([`StandingWave::start`]); the error is `|ω / ω_exact − 1|` with `ω`
    /// from [`StandingWave::frequency`].
    pub fn run(&self, params: pfem_time::StepParams) -> Result<ExactRun, CaseError> {
        let mut sim = simulation(self.scene(), params)?;
        self.start(&mut sim)?;
        let (series, wall) = run_series(&mut sim, |s| self.mode_amplitude(s))?;
        let w = Self::frequency(&series, true);
        Ok(ExactRun {
            second_error: self.decay_error(&series),
            error: (w / self.omega() - 1.0).abs(),
            value: w,
            wall,
            sim,
        })
    }
}

impl Cantilever {
    /// Quasi-static run: backward Euler (`params.scheme` is overridden)
    /// with steps up to 5 s, about 11 periods of its first mode, to t = 40 s, so that each
    /// step is a static solve. The error is that of the tip deflection
    /// against [`Cantilever::static_deflection`].
    pub fn run_static(&self, params: pfem_time::StepParams) -> Result<ExactRun, CaseError> {
        let params = pfem_time::StepParams {
            scheme: pfem_time::Scheme::BackwardEuler,
            ..params
        };
        let mut sim = self.simulation(40.0, 5.0, params)?;
        let tip = self.tip(&sim);
        let y0 = sim.initial_position(tip).y;
        let (series, wall) = run_series(&mut sim, |s| s.particles().x()[tip].y - y0)?;
        let d = -series.last().map_or(f64::NAN, |q| q.1);
        Ok(ExactRun {
            second_error: f64::NAN,
            error: (d / self.static_deflection() - 1.0).abs(),
            value: d,
            wall,
            sim,
        })
    }

    /// Free vibration: gravity switched on at `t = 0`, `periods` periods of
    /// linear theory with `steps_per_period` steps each (the step also
    /// held below the Courant limit of `params`); the frequency from the
    /// zero crossings of the tip's deflection about the mean of its
    /// extremes. The error is `|ω / ω_exact − 1|`.
    pub fn run_vibration(
        &self,
        params: pfem_time::StepParams,
        periods: f64,
        steps_per_period: usize,
    ) -> Result<ExactRun, CaseError> {
        let period = 2.0 * PI / self.omega();
        let mut sim =
            self.simulation(periods * period, period / steps_per_period as f64, params)?;
        let tip = self.tip(&sim);
        let y0 = sim.initial_position(tip).y;
        let (series, wall) = run_series(&mut sim, |s| s.particles().x()[tip].y - y0)?;
        let w = frequency_about_mean(&series);
        Ok(ExactRun {
            second_error: f64::NAN,
            error: (w / self.omega() - 1.0).abs(),
            value: w,
            wall,
            sim,
        })
    }
}

/// Angular frequency (rad/s) of a vibration recorded as `(t, y)`: the
/// zero crossings of `y` about the mean of its extremes
/// ([`StandingWave::frequency`] of the centred series). What
/// [`Cantilever::run_vibration`] reads, for other vibrating cases too;
/// `NaN` with fewer than two crossings (or no samples).
pub fn frequency_about_mean(series: &[(f64, f64)]) -> f64 {
    let (lo, hi) = series
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
            (a.min(q.1), b.max(q.1))
        });
    let mid = 0.5 * (lo + hi);
    let centred: Vec<(f64, f64)> = series.iter().map(|&(t, y)| (t, y - mid)).collect();
    StandingWave::frequency(&centred, false)
}

/// The 2D dam break ([`crate::cases::DamBreak`], n² = 2) for a
/// self-convergence study: no closed form exists, so the reference is a
/// finer run of the library itself. [`DamBreakFront::run`] records the
/// front `x/a` against `T = t √(2g/a)` up to `t_max`;
/// [`DamBreakFront::difference`] is the RMS relative difference between two
/// such curves at `T = 0.5, 0.6, …, t_max` (the surge is under way and the
/// front has not reached the far wall). The front is the largest `x` of
/// the main body's particles, so its resolution is one spacing: first
/// order is what it can show.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DamBreakFront {
    /// Particles across the column's width (`h = a / cells`).
    pub cells: usize,
    /// End of the comparison, in `T` (default 2.5).
    pub t_max: f64,
}

impl Default for DamBreakFront {
    fn default() -> Self {
        Self {
            cells: 10,
            t_max: 2.5,
        }
    }
}

impl DamBreakFront {
    /// Runs the dam break at `a / cells` with the case's Courant number
    /// and `params` to `T = t_max`; the front curve `(T, x/a)` and the run
    /// (its `error` NaN until compared, its `value` the front at `t_max`).
    pub fn run(
        &self,
        params: pfem_time::StepParams,
        courant: f64,
    ) -> Result<(Vec<(f64, f64)>, ExactRun), CaseError> {
        let mut case = crate::cases::DamBreak::default();
        let a = case.width;
        let t_scale = (2.0 * G / a).sqrt();
        case.spacing = a / self.cells as f64;
        case.end_time = self.t_max / t_scale;
        let mut scene = case.scene();
        scene.settings.courant = courant;
        scene.settings.output_interval = None;
        let mut sim = simulation(scene, params)?;
        let (series, wall) = run_series(&mut sim, crate::cases::front_x)?;
        let front: Vec<(f64, f64)> = series.iter().map(|&(t, x)| (t * t_scale, x / a)).collect();
        let value = front.last().map_or(f64::NAN, |q| q.1);
        Ok((
            front,
            ExactRun {
                error: f64::NAN,
                second_error: f64::NAN,
                value,
                wall,
                sim,
            },
        ))
    }

    /// RMS relative difference of `front` against `reference` at `T = 0.5,
    /// 0.6, …, t_max`.
    pub fn difference(&self, front: &[(f64, f64)], reference: &[(f64, f64)]) -> f64 {
        let n = ((self.t_max - 0.5) / 0.1).round() as usize;
        let samples: Vec<(f64, f64)> = (0..=n)
            .map(|k| {
                let t = 0.5 + 0.1 * k as f64;
                (t, crate::cases::interpolate(reference, t))
            })
            .collect();
        crate::cases::rms_relative(front, &samples, 0.0, self.t_max + 1e-9)
    }
}

/// Observed order of convergence: the least-squares slope of `log e`
/// against `log h` over `(h, e)` pairs (`NaN` with fewer than two, or with
/// a non-positive value).
///
/// ```
/// use pfem_cases::exact::observed_order;
/// let pts = [(0.1, 0.04), (0.05, 0.01), (0.025, 0.0025)];
/// assert!((observed_order(&pts) - 2.0).abs() < 1e-12);
/// ```
pub fn observed_order(points: &[(f64, f64)]) -> f64 {
    if points.iter().any(|&(h, e)| !(h > 0.0 && e > 0.0)) {
        return f64::NAN;
    }
    let logs: Vec<(f64, f64)> = points.iter().map(|&(h, e)| (h.ln(), e.ln())).collect();
    slope(&logs)
}

/// Least-squares slope of `y` against `x` over `(x, y)` pairs (`NaN` with
/// fewer than two).
pub fn slope(points: &[(f64, f64)]) -> f64 {
    if points.len() < 2 {
        return f64::NAN;
    }
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x / n, b + y / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), &(x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    sxy / sxx
}
