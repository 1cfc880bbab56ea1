//! A wall moving along a motion law.

use pfem_core::{Const, Dim, ParticleKind, Vector};
use pfem_scene::motion::MotionLaw;

use super::{body_particles, Hook, HookContext};
use crate::checkpoint::{restore_fingerprint, CheckpointError, Decoder, Encoder};
use crate::RunError;

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
    law: std::sync::Arc<dyn MotionLaw<D>>,
    particles: Vec<usize>,
}

impl<const D: usize> PrescribedMotion<D>
where
    Const<D>: Dim,
{
    /// Moves wall `body` along `law`.
    pub fn new(body: impl Into<String>, law: std::sync::Arc<dyn MotionLaw<D>>) -> Self {
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

    /// The body and its law as text: a restart under another law (or with
    /// the law removed, which left the wall moving at the checkpoint's last
    /// velocity) is refused.
    fn save_state(&self, out: &mut Encoder) {
        out.str(&self.fingerprint());
    }

    fn restore_state(&mut self, from: &mut Decoder<'_>) -> Result<(), CheckpointError> {
        restore_fingerprint(from, "a wall's motion law", self.fingerprint())
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
        // A solid welded to the wall would stay where it started while the
        // wall moved through it (a law moves the wall's own particles): the
        // scene refuses a motion law on such a wall, and a hook added to
        // the simulation is refused the same way (session 52's review).
        if let Some(i) = ctx.welded_to(id).next() {
            let solid = ctx
                .body_names()
                .get(ctx.particles().body()[i] as usize)
                .cloned()
                .unwrap_or_default();
            return Err(RunError::Hook {
                hook: "prescribed motion".into(),
                why: format!(
                    "solid `{solid}` is welded to wall `{}` (its particle {i} lies on the wall's lattice): a solid cannot be welded to a moving wall (it would stay where it started); leave a spacing between them, or clamp the solid",
                    self.body
                ),
            });
        }
        // A wall the scene moves at a constant velocity
        // (`WallMotion::Velocity`) is not a hook, so `Hook::drives_body`
        // does not see it: the law took it over silently (session 54's
        // review). (Its particles' prescribed velocity is the scene's
        // until a law sets it; another hook's law is `drives_body`'s.)
        let c = ctx.particles().constraints();
        if let Some(&i) = self
            .particles
            .iter()
            .find(|&&i| c.is_fully_fixed(i) && c.velocity[i] != Vector::<D>::zeros())
        {
            return Err(RunError::Hook {
                hook: "prescribed motion".into(),
                why: format!(
                    "wall `{}` moves already, at the velocity {:?} m/s the scene (or another hook) gives it (its particle {i}): give it one motion, the scene's or this law",
                    self.body,
                    c.velocity[i].as_slice()
                ),
            });
        }
        let t = ctx.time();
        let p = ctx.particles_mut();
        for &i in &self.particles {
            let x0 = p.initial_positions()[i];
            // On the law's path from the start: a hook added mid-run, or a
            // law that displaces at `t = 0`, jumped there after its first
            // step. (Within round-off of it, the particle is left as it is.)
            let x = self.law.position(&x0, t);
            self.finite(x, "position", t)?;
            if (x - p.x()[i]).norm() > 1e-12 * p.spacing()[i] {
                p.x_mut()[i] = x;
            }
            let v = self.finite(self.law.velocity(&x0, t), "velocity", t)?;
            p.v_mut()[i] = v;
            p.constraints_mut().fix(i, v);
            if let Some(a) = self.law.acceleration(&x0, t) {
                p.a_mut()[i] = self.finite(a, "acceleration", t)?;
            }
        }
        Ok(())
    }

    fn next_kink(&self, t: f64) -> Option<f64> {
        self.law.next_kink(t)
    }

    fn drives_body(&self) -> Option<&str> {
        Some(&self.body)
    }

    fn before_solve(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let t1 = ctx.time() + ctx.dt();
        // Constraints only: no particle moves, so the driver does not
        // measure the fluid volume again at each attempt. The velocity
        // arriving at `t1` (a step that ends on a kink prescribes the
        // segment it ends, not the next).
        for &i in &self.particles {
            let x0 = ctx.particles().initial_positions()[i];
            let v = self.finite(self.law.velocity_arriving(&x0, t1), "velocity", t1)?;
            ctx.constraints_mut().fix(i, v);
        }
        Ok(())
    }

    fn after_step(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let t = ctx.time();
        let p = ctx.particles_mut();
        for &i in &self.particles {
            let x0 = p.initial_positions()[i];
            let x = self.law.position(&x0, t);
            self.finite(x, "position", t)?;
            p.x_mut()[i] = x;
            // The law's acceleration where it gives one (the scheme's
            // alternated about it under the trapezoidal rule, from a zero
            // start: session 40's review).
            if let Some(a) = self.law.acceleration(&x0, t) {
                p.a_mut()[i] = self.finite(a, "acceleration", t)?;
            }
            // The velocity leaving `t` (at a kink, the next segment's), so
            // that the next step starts from it; elsewhere the one the step
            // prescribed, to round-off.
            p.v_mut()[i] = self.finite(self.law.velocity(&x0, t), "velocity", t)?;
        }
        Ok(())
    }
}

impl<const D: usize> PrescribedMotion<D>
where
    Const<D>: Dim,
{
    fn fingerprint(&self) -> String {
        format!("body `{}`: {:?}", self.body, self.law)
    }

    /// `v` if every component is finite; otherwise an error naming the body
    /// and the time. A law is user code (a `Sinusoidal` built by hand with
    /// a zero period, a law of one's own): a NaN wall would otherwise show
    /// only as failed steps.
    fn finite(&self, v: Vector<D>, what: &str, t: f64) -> Result<Vector<D>, RunError> {
        if v.iter().all(|c| c.is_finite()) {
            Ok(v)
        } else {
            Err(RunError::Hook {
                hook: "prescribed motion".into(),
                why: format!(
                    "the motion law of body `{}` gives the non-finite {what} {:?} at t = {t} s",
                    self.body,
                    v.as_slice()
                ),
            })
        }
    }
}
