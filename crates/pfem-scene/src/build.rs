//! From a scene to its initial particles: lattices filled body by body,
//! near-coincident particles merged or refused, solids meshed, clamps and
//! welds, initial velocity and pressure fields. The driver turns the
//! result into its particle set.

use pfem_constitutive::Material;
use pfem_core::{Const, Dim, ParticleKind, Point, Vector};
use pfem_geometry::Tessellator;

use crate::lattice;
use crate::scene::{Geometry, RunSettings, Scene, WallMotion};
use crate::SceneError;

/// Material index of a particle without a material (walls).
pub const NO_MATERIAL: u16 = u16::MAX;

/// One particle's data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle<const D: usize>
where
    Const<D>: Dim,
{
    /// Position (m).
    pub x: Point<D>,
    /// Velocity (m/s).
    pub v: Vector<D>,
    /// Pressure (Pa).
    pub pressure: f64,
    /// Fluid, solid or wall.
    pub kind: ParticleKind,
    /// Body index.
    pub body: u32,
    /// Spacing (m).
    pub spacing: f64,
    /// Material index ([`NO_MATERIAL`] for walls).
    pub material: u16,
}

/// The initial particles of a scene, structure of arrays.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Cloud<const D: usize>
where
    Const<D>: Dim,
{
    /// Positions (m).
    pub x: Vec<Point<D>>,
    /// Velocities (m/s).
    pub v: Vec<Vector<D>>,
    /// Pressures (Pa).
    pub pressure: Vec<f64>,
    /// Kinds.
    pub kind: Vec<ParticleKind>,
    /// Body indices (the scene's order).
    pub body: Vec<u32>,
    /// Spacings (m).
    pub spacing: Vec<f64>,
    /// Material indices ([`NO_MATERIAL`] for walls).
    pub material: Vec<u16>,
    /// Prescribed velocity of walls, clamped and welded particles.
    pub fixed: Vec<Option<Vector<D>>>,
}

impl<const D: usize> Cloud<D>
where
    Const<D>: Dim,
{
    /// The largest `|vᵢ| / hᵢ` over the particles that are not walls
    /// (1/s): the Courant bound asks for steps of at most `C` over it.
    pub fn crossing_rate(&self) -> f64 {
        (0..self.x.len())
            .filter(|&i| self.kind[i] != ParticleKind::Wall)
            .map(|i| self.v[i].norm() / self.spacing[i])
            .fold(0.0, f64::max)
    }

    fn push(&mut self, p: Particle<D>) -> usize {
        self.x.push(p.x);
        self.v.push(p.v);
        self.pressure.push(p.pressure);
        self.kind.push(p.kind);
        self.body.push(p.body);
        self.spacing.push(p.spacing);
        self.material.push(p.material);
        self.fixed.push(None);
        self.x.len() - 1
    }
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }
    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
    /// Whether a solid here has something to touch through contact: a
    /// wall, or a second solid body.
    pub fn solid_can_touch(&self) -> bool {
        let mut first_solid: Option<u32> = None;
        for (k, &b) in self.kind.iter().zip(&self.body) {
            match k {
                ParticleKind::Wall => return true,
                ParticleKind::Solid => match first_solid {
                    None => first_solid = Some(b),
                    Some(f) if f != b => return true,
                    Some(_) => {}
                },
                ParticleKind::Fluid => {}
            }
        }
        false
    }
    fn x(&self) -> &[Point<D>] {
        &self.x
    }
    fn kind(&self) -> &[ParticleKind] {
        &self.kind
    }
    fn body(&self) -> &[u32] {
        &self.body
    }
    fn spacing(&self) -> &[f64] {
        &self.spacing
    }
    fn material(&self) -> &[u16] {
        &self.material
    }
}

/// A scene made into particles, ready for the driver.
#[derive(Debug)]
pub struct Built<const D: usize>
where
    Const<D>: Dim,
{
    /// Scene name.
    pub name: String,
    /// The particles: walls first, then solids, then fluids.
    pub particles: Cloud<D>,
    /// The materials, by index.
    pub materials: Vec<Box<dyn Material<D>>>,
    /// Body names, in the scene's order (the particles' body indices).
    pub body_names: Vec<String>,
    /// Solid elements (each solid's own mesh), `D + 1` particle indices
    /// each.
    pub solid_elements: Vec<u32>,
    /// Material of each solid element.
    pub solid_material: Vec<u16>,
    /// Body force per unit mass (m/s²).
    pub gravity: Option<Vector<D>>,
    /// Run settings.
    pub settings: RunSettings,
    /// Particles of a body that fell within a quarter spacing of an earlier
    /// body's particle: dropped (a fluid on a wall, two walls) or welded (a
    /// solid's on a wall's, which it replaces); of its own (a repeated
    /// point, dropped); and a solid's lattice fill's that no element of its
    /// mesh holds (left out). Reported by `pfem check`.
    pub merges: Vec<Merge>,
    /// Walls moving along a law of time, by name.
    #[allow(clippy::type_complexity)]
    pub laws: Vec<(String, std::sync::Arc<dyn crate::motion::MotionLaw<D>>)>,
    /// Forces on solids in time ([`crate::Scene::force`]).
    pub forces: Vec<crate::AppliedLoad<D>>,
    /// Per body: a free solid (no clamp, not welded to a wall).
    pub free_solids: Vec<bool>,
    /// Solid particles welded to a wall (they replaced a wall particle and
    /// take its velocity): (particle, the wall's body index). A hook that
    /// moves that wall would leave them where they started
    /// (`PrescribedMotion` refuses it, as the scene refuses a motion law).
    pub welds: Vec<(u32, u32)>,
    /// Per body: takes part in contact (the free solids, and every solid
    /// with [`crate::ContactSettings::clamped`]).
    pub in_contact: Vec<bool>,
    /// Friction coefficients by pair of body indices.
    pub friction: Vec<(u32, u32, f64)>,
    /// Per body: the normal penalty stiffness of contact it brings (Pa):
    /// for a solid body, the scene's [`crate::ContactSettings::stiffness`]
    /// if given, else its P-wave modulus `ρ c²`; 0 for walls and fluids. A
    /// contact element takes the largest among its particles' bodies.
    pub contact_stiffness: Vec<f64>,
    /// Normal damping of contact (steps).
    pub contact_damping: f64,
    /// Width of the contact penalty's rounded onset (fraction of the
    /// contact distance).
    pub contact_onset: f64,
    /// The domain box ([`Scene::domain`]).
    pub domain: Option<(Point<D>, Point<D>)>,
    /// Particle management ([`Scene::particle_management`]).
    pub particle_management: Option<(pfem_geometry::ParticleManagementParams, u64)>,
}

/// What [`Scene::build`] did to one body's particles that fell on another
/// body's.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Merge {
    /// The body.
    pub body: String,
    /// Its particles dropped because another body's particle is there.
    pub dropped: usize,
    /// Its particles dropped because one of its own is there (a
    /// `Geometry::Particles` list that repeats a point): they are not
    /// counted in `dropped`.
    pub duplicates: usize,
    /// Its particles (a solid's lattice fill) that no element of its own
    /// mesh held, left out: the row one spacing wide at a sharp corner
    /// (`solid_mesh::solid_mesh_pruned`).
    pub unmeshed: usize,
    /// Its particles (a solid's) that fell on a wall's particle and replaced
    /// it: the solid is welded to the wall at those points.
    pub welded: usize,
}

impl<const D: usize> Scene<D>
where
    Const<D>: Dim,
{
    /// Validates the scene and makes its particles: lattices filled body by
    /// body (walls, then solids, then fluids: a wall or fluid particle
    /// within a quarter spacing of an earlier body's particle is dropped;
    /// a solid particle on a wall's replaces it and is welded there (moves
    /// with the wall); a solid particle on another solid's is an error); solid meshes (boxes
    /// structured, other shapes by `tessellator` and the alpha shape);
    /// clamps; initial velocity fields; hydrostatic pressure in fluids
    /// under gravity, or the bodies' pressure fields. Refused as
    /// [`SceneError::TooLarge`] when its estimate exceeds
    /// [`crate::default_memory_budget`] (80 % of the machine's memory):
    /// a mistyped spacing would otherwise abort the process on allocation
    /// ([`Scene::build_within`] takes another budget).
    pub fn build(self, tessellator: &mut dyn Tessellator<D>) -> Result<Built<D>, SceneError> {
        self.build_within(crate::default_memory_budget(), tessellator)
    }

    /// [`Scene::build`] within a memory budget of `budget` bytes
    /// ([`Scene::validate_within`]; `f64::INFINITY`: no limit).
    pub fn build_within(
        self,
        budget: f64,
        tessellator: &mut dyn Tessellator<D>,
    ) -> Result<Built<D>, SceneError> {
        self.validate_within(budget)?;
        let scene = self;
        let Scene {
            name,
            bodies,
            gravity,
            settings,
            contact,
            pressure_stabilisation: _,
            misuse: _,
            forces,
            domain,
            particle_management,
        } = scene;
        let mut free_solids = vec![false; bodies.len()];
        let mut particles = Cloud::<D>::default();
        let mut materials: Vec<Box<dyn Material<D>>> = Vec::new();
        let mut body_names = vec![String::new(); bodies.len()];
        let mut solid_elements = Vec::new();
        let mut solid_material = Vec::new();
        // (particle, prescribed velocity): walls, clamps, welds.
        let mut fixed: Vec<(usize, Vector<D>)> = Vec::new();
        // Walls first, then solids, then fluids: a wall or fluid particle
        // that falls on an earlier body's particle is dropped, a solid
        // particle that falls on a wall's replaces it and is welded there,
        // and fluid particles come last so that particles come and go among
        // them only (the driver's `Particles`).
        let mut order: Vec<usize> = (0..bodies.len()).collect();
        order.sort_by_key(|&i| match bodies[i].kind {
            ParticleKind::Wall => 0,
            ParticleKind::Solid => 1,
            ParticleKind::Fluid => 2,
        });
        // Wall particles replaced by a solid's (removed after placement).
        let mut replaced: Vec<usize> = Vec::new();
        // (solid particle, wall body) of each weld, renumbered with them.
        let mut weld_walls: Vec<(usize, u32)> = Vec::new();
        let mut is_replaced = std::collections::HashSet::new();
        // The walls that are boxes, for the fluid-inside-a-wall check
        // after placement: (body, interior shrunk by half its spacing).
        let wall_boxes: Vec<(usize, Point<D>, Point<D>)> = bodies
            .iter()
            .enumerate()
            .filter(|(_, b)| b.kind == ParticleKind::Wall)
            .filter_map(|(i, b)| match &b.geometry {
                Geometry::Box { min, max } => {
                    let m = 0.5 * b.spacing;
                    Some((i, min.map(|v| v + m), max.map(|v| v - m)))
                }
                _ => None,
            })
            .collect();
        let mut bodies: Vec<Option<crate::scene::Body<D>>> = bodies.into_iter().map(Some).collect();
        let cell = bodies
            .iter()
            .flatten()
            .map(|b| b.spacing)
            .fold(f64::INFINITY, f64::min);
        // A level of the grid for each body's coincidence tolerance (a
        // quarter spacing, below): a scene of very different spacings
        // (10⁻⁹ m beside 0.1 m) would otherwise have each coarse particle
        // look at (10⁸/4)^D cells of the fine spacing.
        let tolerances: Vec<f64> = bodies.iter().flatten().map(|b| 0.25 * b.spacing).collect();
        let mut grid = lattice::HashGrid::<D>::with_tolerances(cell, &tolerances);
        let mut merges: Vec<Merge> = Vec::new();
        let mut laws = Vec::new();
        let mut pressure_fields = Vec::new();
        let solid_mesh_params = crate::solid_mesh::SolidMeshParams {
            alpha: settings.alpha,
            ..Default::default()
        };
        // Body ids follow the scene's order.
        for bi in order {
            let b = bodies[bi].take().expect("each body once");
            let id = bi as u32;
            body_names[bi] = b.name.clone();
            let pts = match &b.geometry {
                Geometry::Box { min, max } => lattice::box_points::<D>(min, max, b.spacing)?,
                // Solids and walls round at the particle scale (contact);
                // fluids on the lattice.
                Geometry::Ball { center, radius } if b.kind != ParticleKind::Fluid => {
                    lattice::shell_points::<D>(center, *radius, b.spacing)?
                }
                Geometry::Ball { center, radius } => {
                    lattice::ball_points::<D>(center, *radius, b.spacing)?
                }
                Geometry::Cylinder {
                    base,
                    axis,
                    radius,
                    height,
                } => lattice::cylinder_points::<D>(base, *axis, *radius, *height, b.spacing)?,
                Geometry::Particles(p) => p.clone(),
                Geometry::Surface(surface) => surface.fill(b.spacing),
            };
            // A solid of any shape but a box: its own mesh, made before its
            // particles are placed. A lattice fill's particles that no
            // element holds (the row one spacing wide that ends a sharp
            // corner, whatever the spacing) are left out, counted in
            // `Merge::unmeshed`: until session 50 a tapered cantilever or
            // a triangle was refused, the message blaming alpha (a
            // review). A user's own particles are meshed as given, once
            // placed (below: a repeated one is refused by name first).
            let mut unmeshed = 0usize;
            let mesh_error = |e: SceneError| SceneError::InvalidGeometry {
                body: b.name.clone(),
                why: e.to_string(),
            };
            let (pts, solid_conn) = match (&b.kind, &b.geometry) {
                (ParticleKind::Solid, Geometry::Box { min, max }) => {
                    let conn = lattice::box_simplices::<D>(min, max, b.spacing)?;
                    (pts, Some(conn))
                }
                (ParticleKind::Solid, Geometry::Particles(_)) => (pts, None),
                // (No particle: refused below as an empty geometry.)
                (ParticleKind::Solid, _) if !pts.is_empty() => {
                    let (m, left) = crate::solid_mesh::solid_mesh_pruned::<D>(
                        &pts,
                        b.spacing,
                        tessellator,
                        &solid_mesh_params,
                    )
                    .map_err(mesh_error)?;
                    unmeshed = left.len();
                    // (`left` increases.)
                    let kept = pts
                        .into_iter()
                        .enumerate()
                        .filter(|(i, _)| left.binary_search(i).is_err())
                        .map(|(_, p)| p)
                        .collect();
                    (kept, Some(m.simplices))
                }
                _ => (pts, None),
            };
            let mat = match b.material {
                Some(m) => {
                    materials.push(m);
                    (materials.len() - 1) as u16
                }
                None => NO_MATERIAL,
            };
            if let (ParticleKind::Wall, WallMotion::Law(law)) = (b.kind, &b.motion) {
                laws.push((b.name.clone(), law.clone()));
            }
            let wall_velocity = match &b.motion {
                WallMotion::Velocity(w) => *w,
                WallMotion::Fixed => Vector::<D>::zeros(),
                WallMotion::Law(_) => Vector::<D>::zeros(),
            };
            let tol = 0.25 * b.spacing;
            let mut local_index = vec![u32::MAX; pts.len()];
            let mut welded = 0usize;
            let mut dropped = 0usize;
            let mut duplicates = 0usize;
            let first = particles.len();
            // The body's particles welded to a wall (not clamped: the weld
            // prescribes their velocity).
            let mut welds: Vec<usize> = Vec::new();
            for (li, p) in pts.iter().enumerate() {
                let mut weld: Option<(Vector<D>, u32)> = None;
                if let Some(j) = grid.find(p, tol, particles.x()) {
                    match (b.kind, particles.kind()[j]) {
                        // A wall driven by a motion law moves only its own
                        // particles (`PrescribedMotion`): a solid particle
                        // welded to it would stay where it started while
                        // the wall moves through the solid (session 42's
                        // review). Refused.
                        (ParticleKind::Solid, ParticleKind::Wall)
                            if laws
                                .iter()
                                .any(|(n, _)| *n == body_names[particles.body()[j] as usize]) =>
                        {
                            return Err(SceneError::InvalidGeometry {
                                body: b.name.clone(),
                                why: format!(
                                    "particle at {:?} lies on a particle of wall `{}`, which moves by a motion law: a solid cannot be welded to a moving wall (it would stay where it started); leave a spacing between them, or clamp the solid",
                                    p.as_slice(),
                                    body_names[particles.body()[j] as usize]
                                ),
                            });
                        }
                        // A solid particle on a wall's replaces it and is
                        // welded to the wall: it moves with the wall.
                        (ParticleKind::Solid, ParticleKind::Wall) if is_replaced.insert(j) => {
                            replaced.push(j);
                            weld = Some((particles.v[j], particles.body()[j]));
                            welded += 1;
                        }
                        // A solid keeps every particle it places (its own
                        // mesh uses them all; a lattice fill's that no
                        // element holds were left out above): one that
                        // falls on another solid's particle is an error,
                        // not a merge.
                        (ParticleKind::Solid, _) => {
                            return Err(SceneError::InvalidGeometry {
                                body: b.name.clone(),
                                why: if particles.body()[j] == id {
                                    format!(
                                        "particle at {:?} lies within a quarter spacing ({tol:e} m) of another of its own particles, at {:?}",
                                        p.as_slice(),
                                        particles.x()[j].as_slice()
                                    )
                                } else {
                                    format!(
                                        "particle at {:?} lies within a quarter spacing ({tol:e} m) of a particle of body `{}`",
                                        p.as_slice(),
                                        body_names[particles.body()[j] as usize]
                                    )
                                },
                            });
                        }
                        // (Its own particle there: a repeated point of
                        // its list, counted apart; session 49's review
                        // found it reported as an earlier body's.)
                        _ if particles.body()[j] == id => {
                            duplicates += 1;
                            continue;
                        }
                        _ => {
                            dropped += 1;
                            continue;
                        }
                    }
                }
                let v = match (b.kind, &b.velocity_field) {
                    (ParticleKind::Wall, _) => wall_velocity,
                    (_, Some(f)) => (f.0)(p.as_slice()),
                    _ => b.velocity,
                };
                if v.iter().any(|c| !c.is_finite()) {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: format!("non-finite initial velocity at {:?}", p.as_slice()),
                    });
                }
                let i = particles.push(Particle {
                    x: *p,
                    v,
                    pressure: 0.0,
                    kind: b.kind,
                    body: id,
                    spacing: b.spacing,
                    material: mat,
                });
                local_index[li] = i as u32;
                grid.insert(p, i);
                if b.kind == ParticleKind::Wall {
                    fixed.push((i, wall_velocity));
                } else if let Some((w, wall)) = weld {
                    fixed.push((i, w));
                    welds.push(i);
                    weld_walls.push((i, wall));
                }
            }
            // A body that places no particle, or a clamp that holds none of
            // its body's, is a mistake in the scene (an empty geometry, a
            // body inside another, a clamp box beside its solid): refused,
            // not run as if it were not there.
            if particles.len() == first && welded == 0 {
                return Err(SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: if dropped > 0 {
                        format!("all of its {dropped} particles fall on earlier bodies' particles")
                    } else {
                        "its geometry places no particle (empty or flat)".into()
                    },
                });
            }
            if !b.clamps.is_empty() {
                let (held, holds_any) = clamped(&particles.x()[first..], &b.clamps, b.spacing)
                    .map_err(|why| SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why,
                    })?;
                if let Some(k) = holds_any.iter().position(|&any| !any) {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: format!(
                            "clamp {} ({}) holds none of its particles{}",
                            k + 1,
                            match &b.clamps[k] {
                                crate::scene::Clamp::Box(lo, hi) =>
                                    format!("box {:?} to {:?}", lo.as_slice(), hi.as_slice()),
                                crate::scene::Clamp::Where(_) => "a predicate".into(),
                            },
                            // (A clamp at a sharp tip held only the row its
                            // mesh left out: session 50's review.)
                            if unmeshed > 0 {
                                format!(" ({unmeshed} of its particles, at a corner or a part thinner than a spacing, were left out of its mesh: clamp it over a wider part)")
                            } else {
                                String::new()
                            }
                        ),
                    });
                }
                let mut welded = vec![false; held.len()];
                for &i in &welds {
                    welded[i - first] = true;
                }
                for (k, _) in held.iter().enumerate().filter(|(k, &h)| h && !welded[*k]) {
                    fixed.push((first + k, Vector::<D>::zeros()));
                }
            }
            if let Some(f) = b.pressure_field.clone() {
                pressure_fields.push((first..particles.len(), f));
            }
            // A solid's mesh (above; a user's particles here): boxes
            // structured, any other geometry the Delaunay tessellation of
            // its own particles trimmed by the alpha shape.
            let solid_conn = match solid_conn {
                None if b.kind == ParticleKind::Solid && !pts.is_empty() => Some(
                    crate::solid_mesh::solid_mesh::<D>(
                        &pts,
                        b.spacing,
                        tessellator,
                        &solid_mesh_params,
                    )
                    .map_err(mesh_error)?
                    .simplices,
                ),
                conn => conn,
            };
            if let Some(conn) = solid_conn {
                for &q in &conn {
                    solid_elements.push(local_index[q as usize]);
                }
                solid_material.extend(std::iter::repeat_n(mat, conn.len() / (D + 1)));
            }
            if b.kind == ParticleKind::Solid && b.clamps.is_empty() && welded == 0 {
                free_solids[bi] = true;
            }
            if dropped > 0 || duplicates > 0 || welded > 0 || unmeshed > 0 {
                merges.push(Merge {
                    body: b.name.clone(),
                    dropped,
                    duplicates,
                    unmeshed,
                    welded,
                });
            }
        }
        // Remove the wall particles that solids replaced, renumbering the
        // solid elements, the constraints and the fluids' ranges (all
        // replaced particles are walls, placed before every solid and fluid).
        if !replaced.is_empty() {
            replaced.sort_unstable();
            let n = particles.len();
            let mut new_index = vec![u32::MAX; n];
            let mut next = 0u32;
            let mut r = replaced.iter().peekable();
            for (i, slot) in new_index.iter_mut().enumerate() {
                if r.peek() == Some(&&i) {
                    r.next();
                    continue;
                }
                *slot = next;
                next += 1;
            }
            let keep = |i: &usize| new_index[*i] != u32::MAX;
            let c = std::mem::take(&mut particles);
            for i in (0..n).filter(keep) {
                particles.push(Particle {
                    x: c.x[i],
                    v: c.v[i],
                    pressure: c.pressure[i],
                    kind: c.kind[i],
                    body: c.body[i],
                    spacing: c.spacing[i],
                    material: c.material[i],
                });
            }
            for q in &mut solid_elements {
                *q = new_index[*q as usize];
            }
            fixed.retain(|(i, _)| keep(i));
            for (i, _) in &mut fixed {
                *i = new_index[*i] as usize;
            }
            for (i, _) in &mut weld_walls {
                *i = new_index[*i] as usize;
            }
            let shift = replaced.len();
            for (range, _) in &mut pressure_fields {
                *range = range.start - shift..range.end - shift;
            }
        }
        if particles.is_empty() {
            return Err(SceneError::Empty);
        }
        let n = particles.len();
        for (i, vel) in fixed {
            particles.fixed[i] = Some(vel);
            // A clamped or welded particle starts at its prescribed
            // velocity, whatever its body's initial velocity (before, it
            // started at the body's and was displaced by it in the first
            // step: a clamped beam given 1 m/s moved its clamp 0.94 mm, a
            // review in session 49).
            particles.v[i] = vel;
        }
        // A fluid particle inside a wall's box (deeper than half the wall's
        // spacing): only boxes against boxes are refused before placement,
        // and placement drops a fluid particle only on another particle, so
        // a polygon, ball or STL fluid drawn into a wall kept the particles
        // between the wall's lattice rows (session 42's review).
        // The first fluid particle inside a box, with the first box that
        // holds it, found on a grid of the fluid particles (each against
        // every box took F·W tests: 3·10¹¹ for 30 000 walls).
        if !wall_boxes.is_empty() {
            let fluid: Vec<usize> = (0..n)
                .filter(|&i| particles.kind()[i] == ParticleKind::Fluid)
                .collect();
            let at: Vec<Point<D>> = fluid.iter().map(|&i| particles.x()[i]).collect();
            let h = fluid
                .iter()
                .map(|&i| particles.spacing()[i])
                .fold(f64::INFINITY, f64::min);
            let mut hit: Option<(usize, usize)> = None;
            let inside = |x: &Point<D>, lo: &Point<D>, hi: &Point<D>| {
                (0..D).all(|d| x[d] > lo[d] && x[d] < hi[d])
            };
            if wall_boxes.len() <= FEW_BOXES {
                hit = fluid.iter().zip(&at).find_map(|(&i, x)| {
                    wall_boxes
                        .iter()
                        .position(|(_, lo, hi)| inside(x, lo, hi))
                        .map(|k| (i, k))
                });
            } else if !fluid.is_empty() {
                let grid = crate::lattice::PointGrid::new(&at, h);
                for (k, (_, lo, hi)) in wall_boxes.iter().enumerate() {
                    grid.for_each_in(lo, hi, &mut |q| {
                        let (i, x) = (fluid[q as usize], at[q as usize]);
                        if inside(&x, lo, hi) && hit.is_none_or(|(first, _)| i < first) {
                            hit = Some((i, k));
                        }
                    });
                }
            }
            if let Some((i, k)) = hit {
                return Err(SceneError::Overlap {
                    first: body_names[wall_boxes[k].0].clone(),
                    second: body_names[particles.body()[i] as usize].clone(),
                });
            }
        }
        // A fluid particle inside another body, whatever its shape: another
        // body's particles on both sides of it along every axis and face
        // diagonal (`lattice::fluid_inside_another_body`). A fluid drawn
        // into another fluid, a solid or a polygon or STL wall off their
        // lattice kept its particles between theirs (0.7 spacing apart,
        // none merged): a drop of oil in water weighed the midrange of the
        // two, a ball of solid was full of water (session 43's review).
        // Bodies side by side or along a sloping face, a fluid in a gap
        // between two bodies, along a plate or in a concave corner are on
        // one side of some direction.
        if let Some(i) = crate::lattice::fluid_inside_another_body(
            particles.x(),
            particles.kind(),
            particles.body(),
            particles.spacing(),
        ) {
            let (inside, of) = i;
            return Err(SceneError::Overlap {
                first: body_names[of as usize].clone(),
                second: body_names[particles.body()[inside] as usize].clone(),
            });
        }
        // A solid under gravity needs a clamp, a weld, a fluid to rest in,
        // or something to rest on through contact (a wall, another solid).
        let has_fluid = particles.kind().contains(&ParticleKind::Fluid);
        if gravity.is_some_and(|g| g.norm() > 0.0) && !has_fluid && !particles.solid_can_touch() {
            for (bi, name) in body_names.iter().enumerate() {
                let ids: Vec<usize> = (0..n)
                    .filter(|&i| {
                        particles.body()[i] == bi as u32
                            && particles.kind()[i] == ParticleKind::Solid
                    })
                    .collect();
                if !ids.is_empty() && !ids.iter().any(|&i| particles.fixed[i].is_some()) {
                    return Err(SceneError::Unsupported { body: name.clone() });
                }
            }
        }
        // Hydrostatic initial pressure in fluids at rest under gravity,
        // each column from its own top, loaded by the fluids resting on it
        // (`crate::hydrostatic`).
        if let Some(g) = gravity {
            let density: Vec<f64> = (0..n)
                .map(|i| match particles.kind()[i] {
                    ParticleKind::Fluid => materials[particles.material()[i] as usize].density(),
                    _ => 0.0,
                })
                .collect();
            let held: Vec<bool> = particles.fixed.iter().map(Option::is_some).collect();
            particles.pressure = crate::hydrostatic::pressures(
                particles.x(),
                particles.kind(),
                particles.spacing(),
                &density,
                &g,
                particles.body(),
                &held,
            );
        }
        // A gravity finite but so large that ρ g H overflows (or its norm
        // does) leaves the hydrostatic start without numbers.
        if particles.pressure.iter().any(|p| !p.is_finite()) {
            return Err(SceneError::NonFinite {
                setting: "the hydrostatic start pressure (gravity too large)",
            });
        }
        // Initial pressure fields replace the hydrostatic start.
        for (range, f) in &pressure_fields {
            for i in range.clone() {
                let p = (f.0)(particles.x()[i].as_slice());
                if !p.is_finite() {
                    return Err(SceneError::InvalidSetting {
                        setting: "pressure field",
                        value: p,
                    });
                }
                particles.pressure[i] = p;
            }
        }
        // The walls and solids next to such a fluid carry its field too
        // (eq. 62 puts the pressure on every node of a fluid element), at
        // their own positions: each whose nearest fluid particle within a
        // lattice cell's diagonal (the hydrostatic start's rule) has a
        // field. Before session 49 they kept the hydrostatic start (or 0
        // without gravity): a uniform 10⁵ Pa moved water at rest in a
        // closed box at 1 cm/s (a review).
        if !pressure_fields.is_empty() {
            let (x, kind, spacing) = (particles.x(), particles.kind(), particles.spacing());
            let fluid =
                crate::lattice::SpacingGrids::new(x, spacing, |i| kind[i] == ParticleKind::Fluid);
            let mut set = Vec::new();
            for i in (0..x.len()).filter(|&i| kind[i] != ParticleKind::Fluid) {
                let near = crate::hydrostatic::nearest_fluid(&fluid, x, spacing, i);
                let field = near.and_then(|j| {
                    pressure_fields
                        .iter()
                        .find(|(range, _)| range.contains(&j))
                        .map(|(_, f)| f)
                });
                if let Some(f) = field {
                    let p = (f.0)(x[i].as_slice());
                    if !p.is_finite() {
                        return Err(SceneError::InvalidSetting {
                            setting: "pressure field",
                            value: p,
                        });
                    }
                    set.push((i, p));
                }
            }
            for (i, p) in set {
                particles.pressure[i] = p;
            }
        }
        // The Courant bound on the placed particles' initial speeds, each
        // on its own spacing: `Scene::validate` bounds a body's uniform
        // `velocity`; a `velocity_field` is known only here.
        let rate = particles.crossing_rate();
        let courant_steps = settings.end_time * rate / settings.courant;
        if courant_steps > crate::scene::MAX_STEPS {
            return Err(SceneError::CannotFinish {
                what: "steps at the Courant limit of the placed particles' initial speeds".into(),
                count: courant_steps,
                limit: crate::scene::MAX_STEPS,
            });
        }
        // Contact: a contact element's default penalty is the smallest
        // P-wave modulus ρ c² among its particles' solids (the driver).
        let mut contact_stiffness = vec![0.0; bodies.len()];
        let mut in_contact = free_solids.clone();
        for ((&b, &m), k) in particles
            .body
            .iter()
            .zip(&particles.material)
            .zip(&particles.kind)
        {
            if *k == ParticleKind::Solid {
                let m = &materials[m as usize];
                contact_stiffness[b as usize] = contact
                    .stiffness
                    .unwrap_or(m.density() * m.wave_speed() * m.wave_speed());
                in_contact[b as usize] |= contact.clamped;
            }
        }
        // A solid in contact needs a penalty a contact element can use
        // (ρ c² can overflow, or vanish, for absurd but finite constants).
        for (b, &k) in contact_stiffness.iter().enumerate() {
            if in_contact[b] && !(k.is_finite() && k > 0.0) {
                return Err(SceneError::InvalidSetting {
                    setting: "contact_stiffness",
                    value: k,
                });
            }
        }
        let friction = contact
            .friction
            .iter()
            .filter_map(|(a, b, mu)| {
                let ia = body_names.iter().position(|n| n == a)? as u32;
                let ib = body_names.iter().position(|n| n == b)? as u32;
                Some((ia, ib, *mu))
            })
            .collect();
        // An applied force acts on its body's free particles inside its
        // region: one that holds none is refused here, where `check` sees
        // it (before session 49 only the run's hook found it, and a force
        // on clamped particles was accepted and lost).
        for load in &forces {
            let Some(id) = body_names.iter().position(|n| *n == load.body) else {
                continue; // (`validate` refused it.)
            };
            let free = (0..particles.len()).any(|i| {
                particles.body()[i] as usize == id
                    && particles.fixed[i].is_none()
                    && load.covers(&particles.x()[i])
            });
            if !free {
                return Err(SceneError::InvalidGeometry {
                    body: load.body.clone(),
                    why: "an applied force's region holds none of its free particles (clamped and welded ones do not move: a force on them would be lost)".into(),
                });
            }
        }
        Ok(Built {
            free_solids,
            welds: weld_walls.into_iter().map(|(i, w)| (i as u32, w)).collect(),
            in_contact,
            friction,
            contact_stiffness,
            contact_damping: contact.damping,
            contact_onset: contact.onset,
            name,
            particles,
            materials,
            body_names,
            solid_elements,
            solid_material,
            gravity,
            settings,
            merges,
            laws,
            forces,
            domain,
            particle_management,
        })
    }
}

/// Up to this many boxes are tested against every particle; more find
/// their particles on a [`crate::lattice::PointGrid`].
const FEW_BOXES: usize = 8;

/// The most grid cells the clamp boxes of one body may visit together
/// ([`clamped`]): some seconds of work. Beyond it the scene is refused
/// (boxes that overlap by the thousand: merge them).
const CLAMP_CELL_VISITS: u64 = 200_000_000;

/// Which of `points` (one body's particles, spacing `h`) the clamps hold,
/// and whether each clamp holds any: what [`crate::scene::Clamp::holds`]
/// answers for each pair, found for the boxes on a grid of the body's
/// spacing. Tested pair by pair it took `P · C` tests: 10¹¹ for 10⁶ clamps
/// on 10⁵ particles (the review of session 45). A predicate
/// (`Clamp::Where`) is asked of every particle. `Err` names the work when
/// the boxes would visit more than [`CLAMP_CELL_VISITS`] cells.
pub(crate) fn clamped<const D: usize>(
    points: &[Point<D>],
    clamps: &[crate::scene::Clamp<D>],
    h: f64,
) -> Result<(Vec<bool>, Vec<bool>), String>
where
    Const<D>: Dim,
{
    use crate::scene::Clamp;
    let mut held = vec![false; points.len()];
    let mut holds_any = vec![false; clamps.len()];
    // A few boxes are cheaper tested against every particle than a grid
    // is to build.
    let grid = (clamps
        .iter()
        .filter(|c| matches!(c, Clamp::Box(..)))
        .count()
        > FEW_BOXES)
        .then(|| crate::lattice::PointGrid::new(points, h));
    let mut visits: u64 = 0;
    for (c, clamp) in clamps.iter().enumerate() {
        let mut test = |i: u32| {
            if clamp.holds(&points[i as usize]) {
                held[i as usize] = true;
                holds_any[c] = true;
            }
        };
        match (clamp, &grid) {
            (Clamp::Box(lo, hi), Some(grid)) => {
                // The box widened by `holds`' tolerance.
                visits = visits.saturating_add(grid.for_each_in(
                    &lo.map(|v| v - 1e-12),
                    &hi.map(|v| v + 1e-12),
                    &mut test,
                ));
                if visits > CLAMP_CELL_VISITS {
                    return Err(format!(
                        "its {} clamps over {} particles would visit more than {CLAMP_CELL_VISITS} cells to find what they hold: merge the boxes that overlap",
                        clamps.len(),
                        points.len()
                    ));
                }
            }
            _ => (0..points.len() as u32).for_each(test),
        }
    }
    Ok((held, holds_any))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Clamp;

    /// Session 50 (a review): a solid polygon with a sharp corner builds,
    /// the row of particles one spacing wide at its tip left out of its
    /// mesh (and counted); a user's own particles are meshed as given, so
    /// the same particles as a list are refused. Before, the wedge was
    /// refused ("particles too sparse for alpha"), at any spacing.
    #[test]
    fn a_solid_with_a_sharp_corner_builds_without_its_tip_row() {
        use pfem_constitutive::Hypoelastic;
        use pfem_geometry::Delaunay2;
        let p = |x: f64, y: f64| Point::<2>::new(x, y);
        let wedge = || Geometry::polygon(vec![p(0.0, 0.0), p(0.3, 0.0), p(0.3, 0.1)]);
        let solid = || Box::new(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap());
        for h in [0.01, 0.0025] {
            let built = Scene::<2>::new("wedge")
                .solid("wedge", solid(), wedge(), h, None)
                .build(&mut Delaunay2::default())
                .unwrap();
            let m = &built.merges[0];
            let placed = built.particles.len();
            assert!(
                m.unmeshed > 0 && m.unmeshed * 20 <= placed + m.unmeshed,
                "{h}: {} of {placed}",
                m.unmeshed
            );
            // Every particle placed is in an element.
            let mut used = vec![false; placed];
            for &v in &built.solid_elements {
                used[v as usize] = true;
            }
            assert!(used.iter().all(|&u| u), "{h}");
        }
        let Geometry::Surface(surface) = wedge() else {
            unreachable!("a polygon is a surface")
        };
        let points = surface.fill(0.01);
        let err = Scene::<2>::new("wedge")
            .solid("wedge", solid(), Geometry::Particles(points), 0.01, None)
            .build(&mut Delaunay2::default())
            .unwrap_err()
            .to_string();
        assert!(err.contains("in no element"), "{err}");
    }

    /// Session 50 (session 49's review): a point repeated in a body's own
    /// list is counted apart from those that fall on an earlier body's
    /// (it was reported as an earlier body's), and a solid's is refused as
    /// its own.
    #[test]
    fn a_bodys_repeated_point_is_told_apart_from_an_earlier_bodys() {
        use pfem_constitutive::{Hypoelastic, Newtonian};
        use pfem_geometry::Delaunay2;
        let h = 0.1;
        let p = |x: f64, y: f64| Point::<2>::new(x, y);
        let floor = Geometry::Box {
            min: p(-0.5, -h),
            max: p(1.5, 0.0),
        };
        // Two points on the floor's top row, one repeated, two free.
        let points = vec![
            p(0.0, 0.0),
            p(0.5, 0.0),
            p(0.2, 0.5),
            p(0.2, 0.5),
            p(0.4, 0.5),
        ];
        let water = || Box::new(Newtonian::new(1000.0, 1e-3, 2.2e9).unwrap());
        let built = Scene::<2>::new("dup")
            .wall("floor", floor.clone(), h, WallMotion::Fixed)
            .fluid("drops", water(), Geometry::Particles(points.clone()), h)
            .build(&mut Delaunay2::default())
            .unwrap();
        let m = &built.merges[0];
        assert_eq!(
            (m.body.as_str(), m.dropped, m.duplicates, m.welded),
            ("drops", 2, 1, 0)
        );
        let err = Scene::<2>::new("dup")
            .wall("floor", floor, h, WallMotion::Fixed)
            .solid(
                "beads",
                Box::new(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap()),
                Geometry::Particles(points[2..].to_vec()),
                h,
                None,
            )
            .build(&mut Delaunay2::default())
            .unwrap_err()
            .to_string();
        assert!(err.contains("another of its own particles"), "{err}");
    }

    /// A fixed-seed generator in [0, 1).
    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    fn brute<const D: usize>(points: &[Point<D>], clamps: &[Clamp<D>]) -> (Vec<bool>, Vec<bool>)
    where
        Const<D>: Dim,
    {
        (
            points
                .iter()
                .map(|p| clamps.iter().any(|c| c.holds(p)))
                .collect(),
            clamps
                .iter()
                .map(|c| points.iter().any(|p| c.holds(p)))
                .collect(),
        )
    }

    fn same_as_brute<const D: usize>(seed: u64)
    where
        Const<D>: Dim,
    {
        let mut s = seed;
        let h = 0.1;
        // A lattice of 10^D particles, and clamps of every kind: small
        // boxes, boxes on a particle exactly (lo == hi), boxes beyond the
        // body, a box over everything, an inverted box, a predicate.
        let n = 10usize;
        let points: Vec<Point<D>> = (0..n.pow(D as u32))
            .map(|mut i| {
                Point::<D>::from_fn(|_, _| {
                    let c = (i % n) as f64 * h;
                    i /= n;
                    c
                })
            })
            .collect();
        let mut clamps: Vec<Clamp<D>> = Vec::new();
        for _ in 0..40 {
            let lo = Point::<D>::from_fn(|_, _| -0.3 + 1.5 * lcg(&mut s));
            let hi = lo.map(|v| v + 0.15 * lcg(&mut s));
            clamps.push(Clamp::Box(lo, hi));
        }
        for k in [0, 17, 999 % points.len()] {
            clamps.push(Clamp::Box(points[k], points[k]));
            // Within the tolerance of `holds`, and just outside it.
            clamps.push(Clamp::Box(
                points[k].map(|v| v + 5e-13),
                points[k].map(|v| v + 0.05),
            ));
            clamps.push(Clamp::Box(
                points[k].map(|v| v + 1e-9),
                points[k].map(|v| v + 1e-9),
            ));
        }
        clamps.push(Clamp::Box(Point::<D>::repeat(5.0), Point::<D>::repeat(6.0)));
        // Without the box over everything, some particles are held and
        // some not.
        let part = clamped(&points, &clamps, h).unwrap();
        assert_eq!(part, brute(&points, &clamps), "{D}D, seed {seed}");
        assert!(part.0.iter().any(|&a| a) && part.0.iter().any(|&a| !a));
        clamps.push(Clamp::Box(
            Point::<D>::repeat(-1e300),
            Point::<D>::repeat(1e300),
        ));
        clamps.push(Clamp::Box(Point::<D>::repeat(0.5), Point::<D>::repeat(0.4)));
        clamps.push(Clamp::Where(std::sync::Arc::new(|p: &Point<D>| {
            p[0] > 0.75
        })));
        let got = clamped(&points, &clamps, h).unwrap();
        assert_eq!(got, brute(&points, &clamps), "{D}D, seed {seed}");
        // Both answers are asked: clamps that hold particles, and ones
        // that hold none.
        let holding = got.1.iter().filter(|&&a| a).count();
        assert!(
            holding > 10 && holding < clamps.len(),
            "{holding} of {}",
            clamps.len()
        );
    }

    /// The grid finds what testing every clamp against every particle
    /// finds, in 2D and 3D.
    #[test]
    fn clamps_found_on_the_grid_hold_what_each_pair_says() {
        for seed in 1..4 {
            same_as_brute::<2>(seed);
            same_as_brute::<3>(seed);
        }
    }

    /// 10⁵ small clamps on 10⁴ particles are found in linear time; 10⁵
    /// boxes each over the whole body (10⁹ cell visits) are refused, not
    /// worked through.
    #[test]
    fn many_clamps_are_found_fast_and_overlapping_multitudes_refused() {
        let h = 0.01;
        let points: Vec<Point<2>> = (0..10_000)
            .map(|i| Point::<2>::new((i % 100) as f64 * h, (i / 100) as f64 * h))
            .collect();
        let small: Vec<Clamp<2>> = (0..100_000)
            .map(|k| {
                let p = points[k % points.len()];
                Clamp::Box(p, p.map(|v| v + 0.5 * h))
            })
            .collect();
        let t = std::time::Instant::now();
        let (held, any) = clamped(&points, &small, h).unwrap();
        println!("10^5 clamps on 10^4 particles: {:?}", t.elapsed());
        assert!(held.iter().all(|&x| x) && any.iter().all(|&x| x));
        let whole: Vec<Clamp<2>> = (0..100_000)
            .map(|k| {
                Clamp::Box(
                    Point::<2>::new(-1.0 - k as f64 * 1e-9, -1.0),
                    Point::<2>::new(2.0, 2.0),
                )
            })
            .collect();
        let err = clamped(&points, &whole, h).unwrap_err();
        assert!(err.contains("merge the boxes"), "{err}");
    }
}
