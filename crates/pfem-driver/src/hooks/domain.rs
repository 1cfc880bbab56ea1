//! The scene's domain box: [`Domain`] removes the fluid particles that
//! leave it.

use pfem_core::{Const, Dim, ParticleKind, Point};
use pfem_geometry::{Origin, ParticleMap, REMOVED};

use super::{Hook, HookContext};
use crate::checkpoint::{CheckpointError, Decoder, Encoder};
use crate::RunError;

/// Removes, at the start of each step (after its remeshing, before the
/// volume correction and the step size), the fluid particles outside the
/// box `[min, max]` (m): fluid leaving the domain, an outflow. The driver
/// installs it for a scene with a domain (`pfem_scene::Scene::domain`),
/// first among its hooks; the volume ledger books what it removes in
/// `sources` ([`Hook::sources_fluid`]), so the volume correction keeps the
/// water that is left. Walls and solids are never removed. (At the end of
/// a step the change would be measured against the step's solved mesh:
/// the step's remeshing change, booked as leaving, would never be
/// corrected; a review of session 48.)
///
/// Without it a drop that flies off an open tank with nothing under it
/// falls for the rest of the run, and the Courant bound of its growing
/// speed shortens every step (after 20 s of fall at a spacing of 7 mm,
/// some 5·10⁵ steps from that drop alone).
#[derive(Debug, Clone, PartialEq)]
pub struct Domain<const D: usize>
where
    Const<D>: Dim,
{
    min: Point<D>,
    max: Point<D>,
    /// Fluid particles removed so far.
    pub removed: usize,
}

impl<const D: usize> Domain<D>
where
    Const<D>: Dim,
{
    /// Its name in the volume ledger.
    pub const NAME: &'static str = "domain";

    /// The domain `[min, max]` (m): finite corners, `min < max` along
    /// every axis, else [`RunError::Hook`].
    pub fn new(min: Point<D>, max: Point<D>) -> Result<Self, RunError> {
        if !(min.iter().chain(max.iter()).all(|v| v.is_finite()) && (0..D).all(|k| min[k] < max[k]))
        {
            return Err(RunError::Hook {
                hook: Self::NAME.into(),
                why: format!(
                    "the domain [{:?}, {:?}] must have finite corners and max above min along every axis",
                    min.as_slice(),
                    max.as_slice()
                ),
            });
        }
        Ok(Self {
            min,
            max,
            removed: 0,
        })
    }

    /// Whether `x` is inside the box (its faces included).
    pub fn holds(&self, x: &Point<D>) -> bool {
        (0..D).all(|k| x[k] >= self.min[k] && x[k] <= self.max[k])
    }
}

impl<const D: usize> Hook<D> for Domain<D>
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        Self::NAME
    }

    fn sources_fluid(&self) -> bool {
        true
    }

    fn after_remesh(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let p = ctx.particles();
        let out = |i: usize| p.kind()[i] == ParticleKind::Fluid && !self.holds(&p.x()[i]);
        // Fluid particles come after walls and solids, which are kept.
        let first = p.fixed_prefix();
        if !(first..p.len()).any(out) {
            return Ok(());
        }
        let n = p.len();
        let mut old_to_new = Vec::with_capacity(n);
        let mut origin = Vec::with_capacity(n);
        let mut removed = 0;
        for i in 0..n {
            if i >= first && out(i) {
                old_to_new.push(REMOVED);
                removed += 1;
            } else {
                old_to_new.push(origin.len() as u32);
                origin.push(Origin::Kept(i as u32));
            }
        }
        let map = ParticleMap { old_to_new, origin };
        ctx.particles_mut()
            .remap(&map)
            .map_err(|e| RunError::Hook {
                hook: Self::NAME.into(),
                why: e.to_string(),
            })?;
        self.removed += removed;
        Ok(())
    }

    fn save_state(&self, out: &mut Encoder) {
        out.u64(self.removed as u64);
        out.f64s(self.min.as_slice());
        out.f64s(self.max.as_slice());
    }

    /// The saved count; a run restored under another box is refused (it
    /// would not continue the run it claims to).
    fn restore_state(&mut self, from: &mut Decoder<'_>) -> Result<(), CheckpointError> {
        let removed = from.len(0)?;
        let (min, max) = (from.f64s()?, from.f64s()?);
        if min.as_slice() != self.min.as_slice() || max.as_slice() != self.max.as_slice() {
            return Err(CheckpointError::Mismatch {
                what: "the domain box",
                checkpoint: format!("[{min:?}, {max:?}]"),
                simulation: format!("[{:?}, {:?}]", self.min.as_slice(), self.max.as_slice()),
            });
        }
        self.removed = removed;
        Ok(())
    }
}
