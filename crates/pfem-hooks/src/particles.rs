//! Hooks that add and remove particles.

use pfem_core::{Const, Dim, ParticleKind, Point, Vector};

use pfem_driver::checkpoint::{CheckpointError, Decoder, Encoder};
use pfem_driver::hooks::{Hook, HookContext};
use pfem_driver::particles::Particle;
use pfem_driver::RunError;

/// The largest layer of particles an [`Inflow`] may place at once.
pub const MAX_LAYER: f64 = 1e7;

/// How far behind an [`Inflow`]'s face (spacings) a wall or a solid
/// across it is refused: the mesh would join it to the layers driven away
/// from it, and stretch the elements between.
pub const UPSTREAM_CLEARANCE: f64 = 3.0;

/// An inflow: fluid enters through a plane face at a prescribed velocity.
///
/// The face is the box `face` of zero thickness along the inflow direction
/// `velocity` (an axis direction), filled with a lattice of spacing `h`.
/// Each time the fluid has advanced by `h` through the face (`∫|v| dt`), a
/// new layer of particles is inserted on it (offset downstream by the
/// advance beyond `h`), so the inflow rate is `|v| × area` on average.
/// Fluid particles within `zone` metres downstream of the face move at the
/// prescribed velocity (they are the piston that pushes the fluid in) and
/// are released beyond. Insertions are booked in the ledger under
/// [`Inflow::NAME`] (they enter the fluid volume at the next remeshing).
///
/// The face needs open space behind it: a wall or a solid across it
/// within [`UPSTREAM_CLEARANCE`] spacings upstream is refused when the run
/// starts (an inlet in a tank's wall is a hole cut in the wall, the face
/// in the hole). Water behind the face is not refused, but the inflow
/// then pulls it along rather than adding to it.
#[derive(Debug, Clone)]
pub struct Inflow<const D: usize>
where
    Const<D>: Dim,
{
    body: String,
    face_min: Point<D>,
    face_max: Point<D>,
    velocity: Vector<D>,
    spacing: f64,
    zone: f64,
    axis: usize,
    advanced: f64,
    /// Particles inserted so far.
    pub inserted: usize,
    layer: Vec<Point<D>>,
    material: u16,
    body_id: u32,
}

impl<const D: usize> Inflow<D>
where
    Const<D>: Dim,
{
    /// Its name in the volume ledger.
    pub const NAME: &'static str = "inflow";

    /// Fluid of body `body` (its material) enters through the face box
    /// `[face_min, face_max]` (m; equal coordinates along the axis of
    /// `velocity`) at `velocity` (m/s), as particles of spacing `h` (m);
    /// `zone` is the
    /// depth (m) downstream of the face where particles are driven (at
    /// least `2h` is advised). A particle leaving the zone is released in
    /// every component: another hook's constraint on it (a slip plane's)
    /// is back only if that hook runs after this one, so add `SlipPlanes`
    /// after an inflow.
    pub fn new(
        body: impl Into<String>,
        face_min: Point<D>,
        face_max: Point<D>,
        velocity: Vector<D>,
        spacing: f64,
        zone: f64,
    ) -> Result<Self, RunError> {
        let bad = |why: String| RunError::Hook {
            hook: Self::NAME.into(),
            why,
        };
        if face_min
            .iter()
            .chain(face_max.iter())
            .chain(velocity.iter())
            .any(|v| !v.is_finite())
        {
            return Err(bad("the face and the velocity must be finite".into()));
        }
        let axis = (0..D)
            .find(|&k| velocity[k] != 0.0)
            .ok_or_else(|| bad("the inflow velocity is zero".into()))?;
        if (0..D).any(|k| k != axis && velocity[k] != 0.0) {
            return Err(bad(
                "the inflow velocity must be along a coordinate axis".into()
            ));
        }
        if face_min[axis] != face_max[axis] {
            return Err(bad(
                "the face must have zero thickness along the inflow".into()
            ));
        }
        if !(spacing > 0.0 && spacing.is_finite() && zone >= spacing && zone.is_finite()) {
            return Err(bad(format!(
                "spacing {spacing} must be positive and the zone {zone} at least one spacing"
            )));
        }
        if (0..D).any(|k| k != axis && face_max[k] - face_min[k] < 0.0) {
            return Err(bad("face max below min".into()));
        }
        // A face of no width across the flow (a point in 2D, a line in 3D)
        // has no area for the rate `|v| × area`, yet its lattice put a
        // line of particles through it (it was accepted: session 53's
        // review).
        if let Some(k) = (0..D).find(|&k| k != axis && face_max[k] == face_min[k]) {
            return Err(bad(format!(
                "the face has no width along axis {k} (min = max = {}): give it its extent across the flow",
                face_min[k]
            )));
        }
        // One layer of particles is placed each time the fluid advances a
        // spacing: bound it before allocating it.
        let layer_count: f64 = (0..D)
            .filter(|&k| k != axis)
            .map(|k| ((face_max[k] - face_min[k]) / spacing).floor() + 1.0)
            .product();
        if layer_count > MAX_LAYER {
            return Err(bad(format!(
                "a layer of the face would hold about {layer_count:.3e} particles, more than {MAX_LAYER:.0e} (coarsen the spacing or shrink the face)"
            )));
        }
        let mut lo = face_min;
        let mut hi = face_max;
        lo[axis] = 0.0;
        hi[axis] = 0.0;
        let layer = pfem_scene::lattice::box_points::<D>(&lo, &hi, spacing)
            .map_err(|e| bad(e.to_string()))?;
        Ok(Self {
            body: body.into(),
            face_min,
            face_max,
            velocity,
            spacing,
            zone,
            axis,
            advanced: 0.0,
            inserted: 0,
            layer,
            material: 0,
            body_id: 0,
        })
    }

    /// Distance downstream of the face (m).
    fn depth(&self, x: &Point<D>) -> f64 {
        let s = self.velocity[self.axis].signum();
        (x[self.axis] - self.face_min[self.axis]) * s
    }

    fn in_face(&self, x: &Point<D>) -> bool {
        let tol = 1e-9 * self.spacing;
        (0..D).all(|k| {
            k == self.axis || (x[k] >= self.face_min[k] - tol && x[k] <= self.face_max[k] + tol)
        })
    }
}

impl<const D: usize> Hook<D> for Inflow<D>
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        Self::NAME
    }

    fn sources_fluid(&self) -> bool {
        true
    }

    fn start(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let id = ctx.body(&self.body)?;
        let p = ctx.particles();
        let Some(i) = (0..p.len()).find(|&i| p.body()[i] == id) else {
            return Err(RunError::Hook {
                hook: Self::NAME.into(),
                why: format!("body `{}` has no particle", self.body),
            });
        };
        if p.kind()[i] != ParticleKind::Fluid {
            return Err(RunError::Hook {
                hook: Self::NAME.into(),
                why: format!("body `{}` is not a fluid", self.body),
            });
        }
        self.body_id = id;
        self.material = p.material()[i];
        // A point of the face on a wall's or a solid's row (a face drawn
        // from floor to ceiling, whose particles lie on those rows) would
        // put a fluid particle onto that row and drive it through the
        // row's particles: the Delaunay refuses them as coincident, or
        // their elements invert at every step. Such points are left out
        // (the scene's build leaves out fluid particles on another body's
        // the same way).
        let half = 0.5 * self.spacing;
        // (Where they started: a restart runs `start` again on moved
        // walls and solids, and must leave out the same points.)
        let blocked: Vec<Point<D>> = (0..p.len())
            .filter(|&j| p.kind()[j] != ParticleKind::Fluid)
            .map(|j| p.initial_positions()[j])
            .filter(|x| {
                let d = self.depth(x);
                d > -self.spacing && d < self.zone + self.spacing
            })
            .collect();
        let axis = self.axis;
        // Whether `x` lies on the lattice line (2D) or row (3D) of the
        // face point `q`, across the face: within half a spacing of it
        // sideways.
        let on_line = move |x: &Point<D>, q: &Point<D>| {
            (0..D)
                .filter(|&k| k != axis)
                .map(|k| (x[k] - q[k]).powi(2))
                .sum::<f64>()
                < half * half
        };
        self.layer
            .retain(|q| !blocked.iter().any(|x| on_line(x, q)));
        if self.layer.is_empty() {
            return Err(RunError::Hook {
                hook: Self::NAME.into(),
                why: "every point of the face lies on a wall's or a solid's row".into(),
            });
        }
        // A wall or a solid just behind the face, across it: the mesh
        // joins it to the layers the inflow drives away from it, and the
        // elements between stretch at `|v| / h` a second, which water's
        // bulk modulus turns into a tension of about `K |v| Δt / h` a step
        // (−10⁸ Pa at 0.5 m/s and h = 7 mm). A review of session 53 found
        // such runs ending `Ok` at 97–1 226 m/s, the inserted water
        // booked as no inflow at all. The face needs open space behind
        // it (a hole cut in the wall it stands in): refused within
        // `UPSTREAM_CLEARANCE` spacings, which spans the elements the
        // alpha shape keeps across a gap (α h across, the next layer one
        // spacing further). Across it means on the line of a point the
        // face keeps: a floor or a pipe's walls running along the flow lie
        // on the lines of the points left out above, and a face narrower
        // than a spacing is checked too (the review of the change found a
        // slit one spacing wide in front of a wall passed, at 67.8 m/s).
        // Exactly `UPSTREAM_CLEARANCE` spacings behind is clear, whatever
        // the round-off of the face's coordinate.
        let reach = (UPSTREAM_CLEARANCE - 1e-6) * self.spacing;
        let behind = (0..p.len()).find(|&j| {
            let x = p.initial_positions()[j];
            let d = self.depth(&x);
            p.kind()[j] != ParticleKind::Fluid
                && d < -0.5 * self.spacing
                && d > -reach
                && self.layer.iter().any(|q| on_line(&x, q))
        });
        if let Some(j) = behind {
            let name = ctx
                .body_names()
                .get(p.body()[j] as usize)
                .cloned()
                .unwrap_or_default();
            return Err(RunError::Hook {
                hook: Self::NAME.into(),
                why: format!(
                    "particle {j} of body `{name}` lies {:.3e} m behind the face, across it: an inflow needs open space behind its face (cut the wall open over the face, or keep walls and solids at least {UPSTREAM_CLEARANCE} spacings behind it)",
                    -self.depth(&p.initial_positions()[j])
                ),
            });
        }
        Ok(())
    }

    fn after_remesh(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        if ctx.steps() == 0 {
            return Ok(());
        }
        // Bound what one call inserts, as one layer is bounded: a step of
        // `max_dt` at the inflow's speed may span many spacings.
        let layers = (self.advanced / self.spacing).floor();
        let count = layers * self.layer.len() as f64;
        if count.is_nan() || count > MAX_LAYER {
            return Err(RunError::Hook {
                hook: Self::NAME.into(),
                why: format!(
                    "the fluid advanced {layers:.3e} spacings since the last insertion: {count:.3e} particles to insert at once, more than {MAX_LAYER:.0e} (lower max_dt or the inflow's speed)"
                ),
            });
        }
        while self.advanced >= self.spacing {
            self.advanced -= self.spacing;
            let off = self.advanced * self.velocity[self.axis].signum();
            for q in self.layer.clone() {
                let mut x = q;
                x[self.axis] = self.face_min[self.axis] + off;
                ctx.insert_fluid(Particle {
                    x,
                    v: self.velocity,
                    pressure: 0.0,
                    kind: ParticleKind::Fluid,
                    body: self.body_id,
                    spacing: self.spacing,
                    material: self.material,
                })?;
                self.inserted += 1;
            }
        }
        Ok(())
    }

    fn before_solve(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        let v = self.velocity;
        let zone = self.zone;
        let full = (1u8 << D) - 1;
        let mut drive = Vec::new();
        let mut release = Vec::new();
        {
            let p = ctx.particles();
            for i in 0..p.len() {
                if p.kind()[i] != ParticleKind::Fluid || p.body()[i] != self.body_id {
                    continue;
                }
                let d = self.depth(&p.x()[i]);
                if d >= -1e-9 * self.spacing && d < zone && self.in_face(&p.x()[i]) {
                    drive.push(i);
                } else if p.constraints().mask[i] == full && p.constraints().velocity[i] == v {
                    // Only what this inflow fixed (every component, at its
                    // velocity): another hook's constraints on the body's
                    // particles (a slip plane's component) stay.
                    release.push(i);
                }
            }
        }
        // Constraints and velocities only: no particle moves, so the driver
        // does not measure the fluid volume again at each attempt.
        for &i in &drive {
            ctx.constraints_mut().fix(i, v);
        }
        for &i in &drive {
            ctx.v_mut()[i] = v;
        }
        for i in release {
            ctx.constraints_mut().mask[i] = 0;
        }
        Ok(())
    }

    fn after_step(&mut self, ctx: &mut HookContext<'_, D>) -> Result<(), RunError> {
        self.advanced += self.velocity.norm() * ctx.dt();
        Ok(())
    }

    fn save_state(&self, out: &mut Encoder) {
        out.f64(self.advanced);
        out.u64(self.inserted as u64);
    }

    fn restore_state(&mut self, from: &mut Decoder<'_>) -> Result<(), CheckpointError> {
        let advanced = from.f64()?;
        // At most the step's advance since the last insertion: finite and
        // not negative (an edited value would insert without end).
        if !(advanced >= 0.0 && advanced.is_finite()) {
            return Err(CheckpointError::Corrupt(format!(
                "inflow advance {advanced} (must be finite and not negative)"
            )));
        }
        self.advanced = advanced;
        self.inserted = from.len(0)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An inflow's saved advance that is not a finite, non-negative length
    /// is refused: `1e300` less a spacing is `1e300`, and the insertion
    /// loop would never end.
    #[test]
    fn an_edited_inflow_advance_is_refused() {
        let mut inflow = Inflow::<2>::new(
            "water",
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(0.0, 0.1),
            Vector::<2>::new(1.0, 0.0),
            0.01,
            0.02,
        )
        .unwrap();
        for bad in [1e300, f64::NAN, f64::INFINITY, -0.01] {
            let mut e = Encoder::new();
            e.f64(bad);
            e.u64(0);
            let bytes = e.finish();
            let err = inflow.restore_state(&mut Decoder::new(&bytes));
            if bad == 1e300 {
                // Finite: accepted here, refused by the insertion's bound.
                assert!(err.is_ok());
            } else {
                assert!(matches!(err, Err(CheckpointError::Corrupt(_))), "{bad}");
            }
        }
        let mut e = Encoder::new();
        e.f64(0.005);
        e.u64(3);
        let bytes = e.finish();
        inflow.restore_state(&mut Decoder::new(&bytes)).unwrap();
        assert_eq!((inflow.advanced, inflow.inserted), (0.005, 3));
    }
}
