//! Particle management as a hook: [`ParticleManagement`], which the
//! driver installs for a scene that asks
//! (`pfem_scene::Scene::particle_management`) and a program may add
//! itself.

use pfem_core::{Const, Dim};
use pfem_geometry::ParticleManagementParams;

use super::{Hook, HookContext};
use crate::checkpoint::{CheckpointError, Decoder, Encoder};
use crate::RunError;

/// Particle management: every `every` steps, after remeshing, removes fluid
/// particles closer than a fraction of the spacing to another and inserts
/// particles into fluid elements that grew too large
/// ([`HookContext::manage_particles`]). The mesh is remade at once when
/// anything changed; the volume change is booked in the ledger under
/// [`ParticleManagement::NAME`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleManagement {
    /// Removal and insertion thresholds.
    pub params: ParticleManagementParams,
    /// Steps between two passes (≥ 1).
    pub every: u64,
    /// Particles removed so far.
    pub removed: usize,
    /// Particles inserted so far.
    pub inserted: usize,
}

impl ParticleManagement {
    /// Its name in the volume ledger.
    pub const NAME: &'static str = "particle management";

    /// Management with `params`, every `every` steps.
    pub fn new(params: ParticleManagementParams, every: u64) -> Self {
        Self {
            params,
            every: every.max(1),
            removed: 0,
            inserted: 0,
        }
    }
}

impl<const D: usize> Hook<D> for ParticleManagement
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        Self::NAME
    }

    fn start(&mut self, _ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        // `new` raises 0 to 1; a struct literal does not.
        if self.every == 0 {
            return Err(RunError::Hook {
                hook: Self::NAME.into(),
                why: "`every` is 0: it must be a number of steps, 1 or more".into(),
            });
        }
        self.params.validate().map_err(RunError::Geometry)
    }

    fn after_remesh(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        if ctx.steps() == 0 || !ctx.steps().is_multiple_of(self.every) {
            return Ok(());
        }
        let (r, i) = ctx.manage_particles(&self.params)?;
        self.removed += r;
        self.inserted += i;
        Ok(())
    }

    fn save_state(&self, out: &mut Encoder) {
        out.u64(self.removed as u64);
        out.u64(self.inserted as u64);
    }

    fn restore_state(&mut self, from: &mut Decoder<'_>) -> Result<(), CheckpointError> {
        self.removed = from.len(0)?;
        self.inserted = from.len(0)?;
        Ok(())
    }
}
