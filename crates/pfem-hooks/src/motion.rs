//! Boundary conditions and loads that change in time.

use pfem_core::{Const, Dim, ParticleKind, Point, Vector};

use pfem_driver::hooks::{body_particles, Hook, HookContext};
use pfem_driver::RunError;

/// A prescribed rigid motion: where a point that was at `x0` at `t = 0` is
/// at time `t`, and its velocity. Laws must be continuous in time and give
/// the velocity that is the derivative of the position.
pub trait MotionLaw<const D: usize>: Send + Sync + std::fmt::Debug
where
    Const<D>: Dim,
{
    /// Position at `t` of the point that was at `x0` at `t = 0` (m).
    fn position(&self, x0: &Point<D>, t: f64) -> Point<D>;
    /// Its velocity (m/s).
    fn velocity(&self, x0: &Point<D>, t: f64) -> Vector<D>;
}

/// A sinusoidal translation `d(t) = A sin(2π t / T)`: a piston or flap
/// wave-maker's stroke.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoidal<const D: usize>
where
    Const<D>: Dim,
{
    /// Amplitude `A` (m), a vector: the stroke's direction and half-length.
    pub amplitude: Vector<D>,
    /// Period `T` (s).
    pub period: f64,
    /// Duration of a linear ramp of the amplitude from 0 (s); 0 for none.
    /// A ramp over a period or two spares the fluid the start-up jerk.
    pub ramp: f64,
}

impl<const D: usize> Sinusoidal<D>
where
    Const<D>: Dim,
{
    fn factor(&self, t: f64) -> (f64, f64) {
        if self.ramp > 0.0 && t < self.ramp {
            (t / self.ramp, 1.0 / self.ramp)
        } else {
            (1.0, 0.0)
        }
    }
}

impl<const D: usize> MotionLaw<D> for Sinusoidal<D>
where
    Const<D>: Dim,
{
    fn position(&self, x0: &Point<D>, t: f64) -> Point<D> {
        let w = 2.0 * std::f64::consts::PI / self.period;
        let (r, _) = self.factor(t);
        x0 + self.amplitude * (r * (w * t).sin())
    }
    fn velocity(&self, _x0: &Point<D>, t: f64) -> Vector<D> {
        let w = 2.0 * std::f64::consts::PI / self.period;
        let (r, dr) = self.factor(t);
        self.amplitude * (r * w * (w * t).cos() + dr * (w * t).sin())
    }
}

/// A translation interpolated linearly in a table of `(t, displacement)`
/// rows (times increasing, the first at 0 with zero displacement); constant
/// after the last row.
#[derive(Debug, Clone, PartialEq)]
pub struct PiecewiseLinear<const D: usize>
where
    Const<D>: Dim,
{
    rows: Vec<(f64, Vector<D>)>,
}

impl<const D: usize> PiecewiseLinear<D>
where
    Const<D>: Dim,
{
    /// A table law; its rows must start at `t = 0` with zero displacement,
    /// with finite, strictly increasing times and finite displacements.
    pub fn new(rows: Vec<(f64, Vector<D>)>) -> Result<Self, RunError> {
        let bad = |why: &str| RunError::Hook {
            hook: "piecewise-linear motion".into(),
            why: why.into(),
        };
        let Some(first) = rows.first() else {
            return Err(bad("the table is empty"));
        };
        if first.0 != 0.0 || first.1.norm() != 0.0 {
            return Err(bad("the first row must be t = 0 with zero displacement"));
        }
        if rows
            .iter()
            .any(|(t, d)| !t.is_finite() || d.iter().any(|c| !c.is_finite()))
        {
            return Err(bad("non-finite time or displacement"));
        }
        if rows.windows(2).any(|w| w[1].0 <= w[0].0) {
            return Err(bad("times must increase strictly"));
        }
        Ok(Self { rows })
    }

    fn at(&self, t: f64) -> (Vector<D>, Vector<D>) {
        let k = self.rows.partition_point(|r| r.0 <= t);
        if k == 0 {
            return (Vector::<D>::zeros(), Vector::<D>::zeros());
        }
        if k == self.rows.len() {
            return (self.rows[k - 1].1, Vector::<D>::zeros());
        }
        let (t0, d0) = self.rows[k - 1];
        let (t1, d1) = self.rows[k];
        let s = (t - t0) / (t1 - t0);
        (d0 + (d1 - d0) * s, (d1 - d0) / (t1 - t0))
    }
}

impl<const D: usize> MotionLaw<D> for PiecewiseLinear<D>
where
    Const<D>: Dim,
{
    fn position(&self, x0: &Point<D>, t: f64) -> Point<D> {
        x0 + self.at(t).0
    }
    fn velocity(&self, _x0: &Point<D>, t: f64) -> Vector<D> {
        self.at(t).1
    }
}

/// Moves the particles of a wall along a [`MotionLaw`]: before each solve
/// their velocity is prescribed as the law's at the end of the step, and
/// after each step their positions are set to the law's (the time scheme
/// integrates the velocity to `O(Δt³)` per step; the reset keeps the wall
/// on its path however long the run). Velocities stay smooth, which
/// prescribing positions alone would not give with the trapezoidal rule.
#[derive(Debug)]
pub struct PrescribedMotion<const D: usize>
where
    Const<D>: Dim,
{
    body: String,
    law: Box<dyn MotionLaw<D>>,
    particles: Vec<usize>,
}

impl<const D: usize> PrescribedMotion<D>
where
    Const<D>: Dim,
{
    /// Moves wall `body` along `law`.
    pub fn new(body: impl Into<String>, law: Box<dyn MotionLaw<D>>) -> Self {
        Self {
            body: body.into(),
            law,
            particles: Vec::new(),
        }
    }
}

impl<const D: usize> Hook<D> for PrescribedMotion<D>
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "prescribed motion"
    }

    fn start(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let id = ctx.body(&self.body)?;
        self.particles = body_particles(ctx.particles(), id);
        if self
            .particles
            .iter()
            .any(|&i| ctx.particles().kind()[i] != ParticleKind::Wall)
        {
            return Err(RunError::Hook {
                hook: "prescribed motion".into(),
                why: format!("body `{}` is not a wall", self.body),
            });
        }
        let t = ctx.time();
        let p = ctx.particles_mut();
        for &i in &self.particles {
            let x0 = p.initial_positions()[i];
            let v = self.law.velocity(&x0, t);
            p.v_mut()[i] = v;
            p.constraints_mut().fix(i, v);
        }
        Ok(())
    }

    fn before_solve(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let t1 = ctx.time() + ctx.dt();
        let p = ctx.particles_mut();
        for &i in &self.particles {
            let x0 = p.initial_positions()[i];
            let v = self.law.velocity(&x0, t1);
            p.constraints_mut().fix(i, v);
        }
        Ok(())
    }

    fn after_step(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let t = ctx.time();
        let p = ctx.particles_mut();
        for &i in &self.particles {
            let x0 = p.initial_positions()[i];
            p.x_mut()[i] = self.law.position(&x0, t);
        }
        Ok(())
    }
}

/// Ramps the body force linearly from zero to `target` over `duration`
/// seconds (a load ramp: a structure loaded gently instead of suddenly).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyForceRamp<const D: usize>
where
    Const<D>: Dim,
{
    /// The body force at the end of the ramp (m/s²).
    pub target: Vector<D>,
    /// Duration of the ramp (s).
    pub duration: f64,
}

impl<const D: usize> Hook<D> for BodyForceRamp<D>
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "body-force ramp"
    }

    fn start(&mut self, _ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        if !(self.duration > 0.0 && self.duration.is_finite())
            || self.target.iter().any(|c| !c.is_finite())
        {
            return Err(RunError::InvalidSetting {
                name: "body-force ramp duration",
                value: self.duration,
                reason: "must be positive and finite, with a finite target",
            });
        }
        Ok(())
    }

    fn before_solve(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let s = ((ctx.time() + ctx.dt()) / self.duration).min(1.0);
        ctx.set_gravity(Some(self.target * s));
        Ok(())
    }
}

/// Slip (symmetry) planes normal to coordinate `axis`: every particle that
/// is not fully constrained has its velocity component along `axis` held at
/// zero, from the start (its velocity and acceleration components zeroed
/// too) and before every solve (so inserted particles slip as well). A 3D
/// slab one spacing deep with slip sides is a quasi-2D flow.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlipPlanes {
    /// The axis normal to the planes (0, 1 or 2).
    pub axis: usize,
}

impl<const D: usize> Hook<D> for SlipPlanes
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "slip planes"
    }

    fn start(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        if self.axis >= D {
            return Err(RunError::Hook {
                hook: "slip planes".into(),
                why: format!("axis {} in {D}D", self.axis),
            });
        }
        let k = self.axis;
        let p = ctx.particles_mut();
        for i in 0..p.len() {
            if !p.constraints().is_fully_fixed(i) {
                p.constraints_mut().fix_component(i, k, 0.0);
                p.a_mut()[i][k] = 0.0;
                p.v_mut()[i][k] = 0.0;
            }
        }
        Ok(())
    }

    fn before_solve(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let k = self.axis;
        let p = ctx.particles();
        let fresh: Vec<usize> = (0..p.len())
            .filter(|&i| !p.constraints().is_fixed(i, k))
            .collect();
        if fresh.is_empty() {
            return Ok(());
        }
        let p = ctx.particles_mut();
        for i in fresh {
            p.constraints_mut().fix_component(i, k, 0.0);
            p.v_mut()[i][k] = 0.0;
        }
        Ok(())
    }
}
