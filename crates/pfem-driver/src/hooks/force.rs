//! A force on a solid body in time: [`AppliedForce`].

use pfem_core::{Const, Dim, ParticleKind, Point, Vector};

use super::{Hook, HookContext};
use crate::RunError;

/// A force on a solid body as a function of time: `force(t)` (N; N per
/// metre of depth in 2D) at the end of each step, `t = tₙ + Δt`, split
/// evenly among the body's particles that start inside the box
/// `[min, max]` (all of them without a box): a point load on a tip, a
/// traction on a face, a push on a free block. Applied through
/// [`HookContext::add_force`] before every solve; stateless, so a
/// restarted run applies the same.
#[derive(Clone)]
pub struct AppliedForce<const D: usize>
where
    Const<D>: Dim,
{
    body: String,
    region: Option<(Point<D>, Point<D>)>,
    #[allow(clippy::type_complexity)]
    force: std::sync::Arc<dyn Fn(f64) -> Vector<D> + Send + Sync>,
    particles: Vec<usize>,
}

impl<const D: usize> std::fmt::Debug for AppliedForce<D>
where
    Const<D>: Dim,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AppliedForce")
            .field("body", &self.body)
            .field("region", &self.region)
            .field("particles", &self.particles.len())
            .finish_non_exhaustive()
    }
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
        Self {
            body: body.into(),
            region,
            force: std::sync::Arc::new(force),
            particles: Vec::new(),
        }
    }

    /// [`AppliedForce::new`] with the force shared (a scene's
    /// [`pfem_scene::AppliedLoad`]).
    #[allow(clippy::type_complexity)]
    pub fn shared(
        body: &str,
        region: Option<(Point<D>, Point<D>)>,
        force: std::sync::Arc<dyn Fn(f64) -> Vector<D> + Send + Sync>,
    ) -> Self {
        Self {
            body: body.into(),
            region,
            force,
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
        let id = ctx.body(&self.body)?;
        let p = ctx.particles();
        let inside = |x: &Point<D>| {
            self.region
                .is_none_or(|(lo, hi)| (0..D).all(|k| x[k] >= lo[k] && x[k] <= hi[k]))
        };
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
                    why: format!("body `{}` is not a solid", self.body),
                });
            }
            // By where it started (a restart runs `start` again on moved
            // particles: the same ones must be loaded).
            if inside(&p.initial_positions()[i]) {
                on.push(i);
            }
        }
        if on.is_empty() {
            return Err(RunError::Hook {
                hook: Self::NAME.into(),
                why: format!(
                    "no particle of body `{}` inside the load's region",
                    self.body
                ),
            });
        }
        self.particles = on;
        Ok(())
    }

    fn before_solve(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let total = (self.force)(ctx.time() + ctx.dt());
        let share = total / self.particles.len() as f64;
        for &i in &self.particles {
            ctx.add_force(i, share)?;
        }
        Ok(())
    }
}
