//! Loads and constraints that change in time.

use pfem_core::{Const, Dim, Vector};

use pfem_driver::checkpoint::{restore_fingerprint, CheckpointError, Decoder, Encoder};
use pfem_driver::hooks::{Hook, HookContext};
use pfem_driver::RunError;

/// Ramps the body force linearly from zero to `target` over `duration`
/// seconds from `t = 0` (a load ramp: a structure loaded gently instead of
/// suddenly), in a scene with no gravity of its own: one with gravity is
/// refused when the run starts (its fluid starts hydrostatic under the
/// whole of it, which the ramp's first steps would not hold up).
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

    fn start(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        if ctx.gravity().is_some_and(|g| g.norm() > 0.0) {
            return Err(RunError::Hook {
                hook: "body-force ramp".into(),
                why: "a gravity is set already (by the scene, under which its fluid starts hydrostatic, or by a hook): ramp from a scene without gravity".into(),
            });
        }
        if !(self.duration > 0.0 && self.duration.is_finite())
            || self.target.iter().any(|c| !c.is_finite())
        {
            return Err(RunError::InvalidSetting {
                name: "body-force ramp duration",
                value: self.duration,
                reason: "must be positive and finite, with a finite target",
            });
        }
        // The body force at the start, `t₀ / T` of the target (zero from
        // rest): the first accelerations are set with it, not with the
        // first step's end-of-step value (which left `½ k Δt²` of velocity
        // too much; session 52). (Not at a restart, whose gravity is the
        // checkpoint's.)
        if ctx.steps() == 0 {
            let s = (ctx.time() / self.duration).min(1.0);
            ctx.set_gravity(Some(self.target * s))?;
        }
        Ok(())
    }

    fn before_solve(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let s = ((ctx.time() + ctx.dt()) / self.duration).min(1.0);
        ctx.set_gravity(Some(self.target * s))?;
        Ok(())
    }

    /// The ramp itself (its target and duration, exactly): a restart under
    /// another ramp, or with the ramp removed or added, is refused. The
    /// ramp saved nothing until session 53, and such a restart ran on, the
    /// checkpoint's gravity kept for good (a removed ramp) or ramped to
    /// another target (a review); such older checkpoints are read
    /// unchecked.
    fn save_state(&self, out: &mut Encoder) {
        out.str(&self.fingerprint());
    }

    fn restore_state(&mut self, from: &mut Decoder<'_>) -> Result<(), CheckpointError> {
        restore_fingerprint(from, "the body-force ramp", self.fingerprint())
    }
}

impl<const D: usize> BodyForceRamp<D>
where
    Const<D>: Dim,
{
    /// Its target and duration in std's exact float formatting (not
    /// nalgebra's `Debug`, whose format is not ours to keep).
    fn fingerprint(&self) -> String {
        format!(
            "target {:?}, duration {:?} s",
            self.target.as_slice(),
            self.duration
        )
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
