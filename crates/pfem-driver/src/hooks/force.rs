//! A force on a solid body in time: [`AppliedForce`].

use pfem_core::{Const, Dim, ParticleKind, Point, Vector};

use pfem_scene::AppliedLoad;

use super::{Hook, HookContext};
use crate::RunError;

/// A force on a solid body as a function of time: `force(t)` (N; N per
/// metre of depth in 2D) at the end of each step, `t = tₙ + Δt`, split
/// evenly among the body's free particles (not clamped or welded) that
/// start inside the box `[min, max]` (all of them without a box): a point load on a tip, a
/// traction on a face, a push on a free block. Applied through
/// [`HookContext::add_force`] before every solve; stateless, so a
/// restarted run applies the same.
#[derive(Debug, Clone)]
pub struct AppliedForce<const D: usize>
where
    Const<D>: Dim,
{
    load: AppliedLoad<D>,
    particles: Vec<usize>,
}

impl<const D: usize> AppliedForce<D>
where
    Const<D>: Dim,
{
    /// The force `force(t)` on the solid body `body`, on its particles
    /// inside `region` (`None`: all).
    pub fn new(
        body: &str,
        region: Option<(Point<D>, Point<D>)>,
        force: impl Fn(f64) -> Vector<D> + Send + Sync + 'static,
    ) -> Self {
        Self::from_load(AppliedLoad {
            body: body.into(),
            region,
            force: std::sync::Arc::new(force),
            kinks: Vec::new(),
        })
    }

    /// The times (s) at which the force's slope changes, at which the
    /// steps end ([`AppliedLoad::kinks`]).
    pub fn with_kinks(mut self, mut kinks: Vec<f64>) -> Self {
        kinks.retain(|t| t.is_finite());
        kinks.sort_by(f64::total_cmp);
        self.load.kinks = kinks;
        self
    }

    /// The hook that applies a scene's [`AppliedLoad`] (`Scene::force`).
    pub fn from_load(mut load: AppliedLoad<D>) -> Self {
        load.kinks.retain(|t| t.is_finite());
        load.kinks.sort_by(f64::total_cmp);
        Self {
            load,
            particles: Vec::new(),
        }
    }

    /// The name of the hook.
    pub const NAME: &'static str = "applied force";
}

impl<const D: usize> Hook<D> for AppliedForce<D>
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        Self::NAME
    }

    fn start(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let id = ctx.body(&self.load.body)?;
        let p = ctx.particles();
        let mut on = Vec::new();
        for i in 0..p.len() {
            if p.body()[i] != id {
                continue;
            }
            // Solids keep their particles' numbering all run (a fluid's
            // is remade by every insertion and removal; a wall's motion
            // is prescribed, so a force on it does nothing).
            if p.kind()[i] != ParticleKind::Solid {
                return Err(RunError::Hook {
                    hook: Self::NAME.into(),
                    why: format!("body `{}` is not a solid", self.load.body),
                });
            }
            // By where it started (a restart runs `start` again on moved
            // particles: the same ones must be loaded). A clamped or
            // welded particle does not move: its share would be lost
            // (before session 49 it took one, and the body felt less than
            // the force asked).
            if self.load.covers(&p.initial_positions()[i]) && !p.constraints().is_fully_fixed(i) {
                on.push(i);
            }
        }
        if on.is_empty() {
            return Err(RunError::Hook {
                hook: Self::NAME.into(),
                why: format!(
                    "no free particle of body `{}` inside the load's region (clamped and welded ones do not move)",
                    self.load.body
                ),
            });
        }
        self.particles = on;
        Ok(())
    }

    fn next_kink(&self, t: f64) -> Option<f64> {
        self.load.kinks.iter().copied().find(|&k| k > t)
    }

    fn before_solve(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let total = (self.load.force)(ctx.time() + ctx.dt());
        let share = total / self.particles.len() as f64;
        for &i in &self.particles {
            ctx.add_force(i, share)?;
        }
        Ok(())
    }
}
