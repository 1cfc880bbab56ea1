//! The particle set: every per-particle array of a simulation in one place,
//! with one way to change their number ([`Particles::remap`]).

use pfem_assembly::Constraints;
use pfem_core::{Const, Dim, ParticleKind, Point, Vector};
use pfem_geometry::{Origin, ParticleMap};
use pfem_time::ParticleState;

use crate::checkpoint::{CheckpointError, Decoder, Encoder};

pub use pfem_scene::{Particle, NO_MATERIAL};

/// Every per-particle array of a simulation: state (positions, velocities,
/// accelerations, pressure), kind, body, spacing, material, initial
/// position and velocity constraints, all of one length.
///
/// Order: the constructor places walls first, then solids, then fluids, and
/// particles come and go only among fluids ([`Particles::remap`] refuses
/// anything else), so a wall or solid particle keeps its index for the
/// whole run and a probe may hold it; fluid indices change when particles
/// are removed or inserted ([`Particles::generation`] counts the changes).
#[derive(Debug, Clone, Default)]
pub struct Particles<const D: usize>
where
    Const<D>: Dim,
{
    state: ParticleState<D>,
    kind: Vec<ParticleKind>,
    body: Vec<u32>,
    spacing: Vec<f64>,
    material: Vec<u16>,
    x0: Vec<Point<D>>,
    constraints: Constraints<D>,
    generation: u64,
}

/// Why [`Particles::remap`] refused a map.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RemapError {
    /// The map was made for another number of particles.
    #[error("the particle map is for {map} particles, the set has {set}")]
    Length {
        /// Particles the map expects.
        map: usize,
        /// Particles in the set.
        set: usize,
    },
    /// The map removes or moves a wall or solid particle.
    #[error(
        "particle {0} is a wall or solid particle: only fluid particles may be removed or inserted"
    )]
    NotFluid(usize),
    /// The map's new particles do not match its old ones: a kept particle
    /// that is not an old one or not where `old_to_new` puts it, kept
    /// particles out of their old order, a kept old particle missing from
    /// the new ones, or an inserted particle whose parents are not old
    /// particles or whose weights are not each finite and ≥ 0, summing to
    /// 1.
    #[error("the particle map is inconsistent at new particle {index}: {why}")]
    Inconsistent {
        /// The new particle (the map's length when one is missing).
        index: usize,
        /// What does not fit.
        why: &'static str,
    },
}

/// What keeps `p` from being a fluid particle of a simulation with these
/// materials and bodies (`fixed_body[b]`: body `b` is a wall's or
/// solid's), if anything: the one check of [`Particles::push`]ed particles
/// at the next mesh and of `HookContext::insert_fluid`.
pub(crate) fn fluid_particle_fault<const D: usize>(
    p: &Particle<D>,
    materials: &[Box<dyn pfem_constitutive::Material<D>>],
    body_names: &[String],
    fixed_body: &[bool],
) -> Option<String>
where
    Const<D>: Dim,
{
    if p.kind != ParticleKind::Fluid {
        return Some("not a fluid particle".into());
    }
    let m = p.material as usize;
    match materials.get(m) {
        None => return Some(format!("no material {m}")),
        Some(law) if law.kind() != pfem_constitutive::MaterialKind::Fluid => {
            return Some(format!("a fluid particle of material {m}, not a fluid's"))
        }
        Some(_) => {}
    }
    let b = p.body as usize;
    match fixed_body.get(b) {
        None => return Some(format!("body {b} past the scene's {}", body_names.len())),
        Some(true) => {
            let name = body_names.get(b).map_or("?", String::as_str);
            return Some(format!(
                "a fluid particle in body {b} (`{name}`), a wall's or solid's"
            ));
        }
        Some(false) => {}
    }
    if !(p.spacing > 0.0 && p.spacing.is_finite()) {
        return Some(format!("spacing {} m", p.spacing));
    }
    if !(p.pressure.is_finite() && p.x.iter().chain(p.v.iter()).all(|c| c.is_finite())) {
        return Some("a non-finite position, velocity or pressure".into());
    }
    None
}

impl<const D: usize> Particles<D>
where
    Const<D>: Dim,
{
    /// Particle `i` as a [`Particle`] (its state, kind, body, spacing and
    /// material).
    pub fn get(&self, i: usize) -> Particle<D> {
        Particle {
            x: self.state.x[i],
            v: self.state.v[i],
            pressure: self.state.pressure[i],
            kind: self.kind[i],
            body: self.body[i],
            spacing: self.spacing[i],
            material: self.material[i],
        }
    }

    /// Which bodies are walls' or solids': those of the walls-and-solids
    /// prefix (a fluid particle may not join one), `n_bodies` long.
    pub(crate) fn fixed_bodies(&self, n_bodies: usize) -> Vec<bool> {
        let mut fixed = vec![false; n_bodies];
        for &b in &self.body[..self.fixed_prefix()] {
            if let Some(f) = fixed.get_mut(b as usize) {
                *f = true;
            }
        }
        fixed
    }

    /// An empty set (to which only fluid particles can be pushed: a set
    /// with walls and solids comes from a scene, [`Particles::from_cloud`]).
    pub fn new() -> Self {
        Self::default()
    }

    /// The particle set of a built scene ([`pfem_scene::Scene::build`]),
    /// with its prescribed velocities as constraints.
    pub fn from_cloud(cloud: pfem_scene::Cloud<D>) -> Self {
        let n = cloud.len();
        let mut constraints = Constraints::free(n);
        for (i, f) in cloud.fixed.iter().enumerate() {
            if let Some(v) = f {
                constraints.fix(i, *v);
            }
        }
        Self {
            x0: cloud.x.clone(),
            state: ParticleState {
                x: cloud.x,
                v: cloud.v,
                a: vec![Vector::<D>::zeros(); n],
                pressure: cloud.pressure,
            },
            kind: cloud.kind,
            body: cloud.body,
            spacing: cloud.spacing,
            material: cloud.material,
            constraints,
            generation: 0,
        }
    }

    /// Appends a fluid particle, free of constraints, acceleration zero
    /// (set it with [`Particles::a_mut`] when it is not: a flying
    /// particle's is the body force, and the time scheme starts from it);
    /// its initial position is `p.x`. Returns its index.
    ///
    /// Only fluid particles may be appended: walls and solids come from the
    /// scene and keep their indices for the whole run (they come first, and
    /// a probe, a load or a solid's element may hold their indices), so a
    /// wall or solid particle is refused with [`RemapError::NotFluid`] (its
    /// would-be index) and the set is left as it was. The rest of the
    /// particle (its material, body, spacing, finite values) is checked
    /// against the simulation when the next step meshes the changed set
    /// (`RunError::InvalidParticle`).
    pub fn push(&mut self, p: Particle<D>) -> Result<usize, RemapError> {
        if p.kind != ParticleKind::Fluid {
            return Err(RemapError::NotFluid(self.len()));
        }
        self.state.x.push(p.x);
        self.state.v.push(p.v);
        self.state.a.push(Vector::<D>::zeros());
        self.state.pressure.push(p.pressure);
        self.kind.push(p.kind);
        self.body.push(p.body);
        self.spacing.push(p.spacing);
        self.material.push(p.material);
        self.x0.push(p.x);
        self.constraints.mask.push(0);
        self.constraints.velocity.push(Vector::<D>::zeros());
        self.generation += 1;
        Ok(self.state.x.len() - 1)
    }

    /// How many particles come before the first fluid one: the walls and
    /// solids, whose indices no change of the set moves (`remap` refuses
    /// to, and insertions are fluid).
    pub fn fixed_prefix(&self) -> usize {
        self.kind
            .iter()
            .take_while(|&&k| k != ParticleKind::Fluid)
            .count()
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.state.x.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.state.x.is_empty()
    }

    /// Positions (m).
    pub fn x(&self) -> &[Point<D>] {
        &self.state.x
    }

    /// Velocities (m/s).
    pub fn v(&self) -> &[Vector<D>] {
        &self.state.v
    }

    /// Accelerations (m/s²).
    pub fn a(&self) -> &[Vector<D>] {
        &self.state.a
    }

    /// Nodal pressure the method stores (Pa, eq. 62); see
    /// `pfem_io::Loads::water_pressure` for the water's pressure on
    /// interfaces.
    pub fn pressure(&self) -> &[f64] {
        &self.state.pressure
    }

    /// Kind of each particle.
    pub fn kind(&self) -> &[ParticleKind] {
        &self.kind
    }

    /// Body index of each particle.
    pub fn body(&self) -> &[u32] {
        &self.body
    }

    /// Spacing of each particle (m).
    pub fn spacing(&self) -> &[f64] {
        &self.spacing
    }

    /// Material index of each particle ([`NO_MATERIAL`] for walls).
    pub fn material(&self) -> &[u16] {
        &self.material
    }

    /// Position of each particle when it entered the simulation (m).
    pub fn initial_positions(&self) -> &[Point<D>] {
        &self.x0
    }

    /// Velocity constraints (walls, clamps, slip planes, prescribed motion).
    pub fn constraints(&self) -> &Constraints<D> {
        &self.constraints
    }

    /// The state the time integrator advances.
    pub fn state(&self) -> &ParticleState<D> {
        &self.state
    }

    /// The first particle with a non-finite position, velocity,
    /// acceleration, pressure or prescribed velocity, and which.
    pub(crate) fn non_finite(&self) -> Option<(usize, &'static str)> {
        let vector = |v: &Vector<D>| v.iter().all(|c| c.is_finite());
        let (s, c) = (&self.state, &self.constraints);
        // (Constraints of another length are the step's to refuse.)
        (0..self.len()).find_map(|i| {
            let what = if !s.x[i].iter().all(|c| c.is_finite()) {
                "position"
            } else if !vector(&s.v[i]) {
                "velocity"
            } else if !vector(&s.a[i]) {
                "acceleration"
            } else if !s.pressure[i].is_finite() {
                "pressure"
            } else if (0..D).any(|k| {
                let fixed = c.mask.get(i).is_some_and(|m| m & (1 << k) != 0);
                fixed && !c.velocity.get(i).is_none_or(|v| v[k].is_finite())
            }) {
                "prescribed velocity"
            } else {
                return None;
            };
            Some((i, what))
        })
    }

    /// How many times particles were added or removed.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Mutable positions (m): moving a particle by hand takes effect at the
    /// next remeshing.
    pub fn x_mut(&mut self) -> &mut [Point<D>] {
        &mut self.state.x
    }

    /// Mutable velocities (m/s).
    pub fn v_mut(&mut self) -> &mut [Vector<D>] {
        &mut self.state.v
    }

    /// Mutable accelerations (m/s²).
    pub fn a_mut(&mut self) -> &mut [Vector<D>] {
        &mut self.state.a
    }

    /// Mutable pressures (Pa).
    pub fn pressure_mut(&mut self) -> &mut [f64] {
        &mut self.state.pressure
    }

    /// Mutable constraints.
    pub fn constraints_mut(&mut self) -> &mut Constraints<D> {
        &mut self.constraints
    }

    /// Mutable state, the constraints and each particle's material together
    /// (the integrator reads them all).
    pub(crate) fn state_and_constraints(
        &mut self,
    ) -> (&mut ParticleState<D>, &Constraints<D>, &[u16]) {
        (&mut self.state, &self.constraints, &self.material)
    }

    /// Mutable state.
    pub(crate) fn state_mut(&mut self) -> &mut ParticleState<D> {
        &mut self.state
    }

    /// Carries every array to a new cloud described by `map`
    /// ([`pfem_geometry::manage_particles`]): kept particles keep their
    /// values, inserted ones get the barycentric interpolation of their
    /// parents' position, velocity, acceleration, pressure and spacing
    /// (each weighted as the position), the body and material of the first
    /// parent of the parents' majority fluid,
    /// no constraint, and their own position as initial position. Only
    /// fluid particles may be removed or inserted, and kept particles must
    /// keep their order (so wall and solid indices do not move).
    pub fn remap(&mut self, map: &ParticleMap) -> Result<(), RemapError> {
        let n = self.len();
        if map.old_to_new.len() != n {
            return Err(RemapError::Length {
                map: map.old_to_new.len(),
                set: n,
            });
        }
        for (i, &k) in self.kind.iter().enumerate() {
            if k != ParticleKind::Fluid && map.old_to_new[i] as usize != i {
                return Err(RemapError::NotFluid(i));
            }
        }
        // The new particles against the old (a map built by hand; session
        // 35's review: a kept index past the set panicked, an empty
        // `origin` removed every particle).
        let mut kept = 0usize;
        let mut last_kept: Option<u32> = None;
        for (j, o) in map.origin.iter().enumerate() {
            let bad = |why| Err(RemapError::Inconsistent { index: j, why });
            match o {
                Origin::Kept(i) => {
                    if *i as usize >= n || map.old_to_new[*i as usize] as usize != j {
                        return bad("a kept particle is not the old one `old_to_new` puts here");
                    }
                    // (Session 48's review: the order was documented, not
                    // checked.)
                    if last_kept.is_some_and(|l| *i <= l) {
                        return bad("the kept particles are not in their old order");
                    }
                    last_kept = Some(*i);
                    kept += 1;
                }
                Origin::Inserted { nodes, weights } => {
                    if nodes.is_empty()
                        || nodes.len() != weights.len()
                        || nodes.iter().any(|&q| q as usize >= n)
                        || weights.iter().any(|w| !(w.is_finite() && *w >= 0.0))
                        || (weights.iter().sum::<f64>() - 1.0).abs() > 1e-9
                    {
                        return bad("an inserted particle's parents or weights are not valid (old particles, as many weights, each ≥ 0, summing to 1)");
                    }
                }
            }
        }
        let staying = map
            .old_to_new
            .iter()
            .filter(|&&k| k != pfem_geometry::REMOVED)
            .count();
        if kept != staying {
            return Err(RemapError::Inconsistent {
                index: map.origin.len(),
                why: "an old particle `old_to_new` keeps is not among the new ones",
            });
        }
        // The first parent of the parents' majority fluid (an inserted
        // particle where two fluids meet took the first fluid parent in
        // the tessellation's order, whichever fluid it was: session 43's
        // review).
        let fluid_parent = |nodes: &[u32]| {
            let m = crate::simulation::majority_fluid_material(nodes, &self.kind, &self.material);
            nodes
                .iter()
                .copied()
                .find(|&q| {
                    self.kind[q as usize] == ParticleKind::Fluid && self.material[q as usize] == m
                })
                .unwrap_or(nodes[0]) as usize
        };
        let x = map.apply_with(&self.state.x, |nodes, w| {
            let mut acc = Point::<D>::zeros();
            for (&q, &wq) in nodes.iter().zip(w) {
                acc += self.state.x[q as usize] * wq;
            }
            acc
        });
        let v = map.apply(&self.state.v);
        let a = map.apply(&self.state.a);
        let pressure = map.apply(&self.state.pressure);
        let spacing = map.apply(&self.spacing);
        let kind = map.apply_with(&self.kind, |_, _| ParticleKind::Fluid);
        let body = map.apply_with(&self.body, |nodes, _| self.body[fluid_parent(nodes)]);
        let material = map.apply_with(&self.material, |nodes, _| {
            self.material[fluid_parent(nodes)]
        });
        let mask = map.apply_with(&self.constraints.mask, |_, _| 0);
        let cv = map.apply_with(&self.constraints.velocity, |_, _| Vector::<D>::zeros());
        let mut x0 = Vec::with_capacity(map.len());
        for (j, o) in map.origin.iter().enumerate() {
            x0.push(match o {
                Origin::Kept(i) => self.x0[*i as usize],
                Origin::Inserted { .. } => x[j],
            });
        }
        self.state = ParticleState { x, v, a, pressure };
        self.kind = kind;
        self.body = body;
        self.material = material;
        self.spacing = spacing;
        self.x0 = x0;
        self.constraints = Constraints { mask, velocity: cv };
        self.generation += 1;
        Ok(())
    }
}

impl<const D: usize> Particles<D>
where
    Const<D>: Dim,
{
    /// Writes every array into a checkpoint section.
    pub(crate) fn encode(&self, e: &mut Encoder) {
        let n = self.len();
        e.u64(n as u64);
        e.u64(self.generation);
        for i in 0..n {
            for k in 0..D {
                e.f64(self.state.x[i][k]);
            }
            for k in 0..D {
                e.f64(self.state.v[i][k]);
            }
            for k in 0..D {
                e.f64(self.state.a[i][k]);
            }
            e.f64(self.state.pressure[i]);
            e.u64(match self.kind[i] {
                ParticleKind::Fluid => 0,
                ParticleKind::Solid => 1,
                ParticleKind::Wall => 2,
            });
            e.u64(self.body[i] as u64);
            e.f64(self.spacing[i]);
            e.u64(self.material[i] as u64);
            for k in 0..D {
                e.f64(self.x0[i][k]);
            }
            e.u64(self.constraints.mask[i] as u64);
            for k in 0..D {
                e.f64(self.constraints.velocity[i][k]);
            }
        }
    }

    /// Reads what [`Particles::encode`] wrote.
    pub(crate) fn decode(d: &mut Decoder<'_>) -> Result<Self, CheckpointError> {
        let per = 8 * (5 * D + 6);
        let n = d.len(per)?;
        let generation = d.u64()?;
        let mut p = Self {
            generation,
            ..Self::default()
        };
        let vec = |d: &mut Decoder<'_>| -> Result<Vector<D>, CheckpointError> {
            let mut v = Vector::<D>::zeros();
            for k in 0..D {
                v[k] = d.f64()?;
            }
            Ok(v)
        };
        let small = |v: u64, max: u64, what: &str| {
            if v <= max {
                Ok(v)
            } else {
                Err(CheckpointError::Corrupt(format!("{what} {v} out of range")))
            }
        };
        for _ in 0..n {
            p.state.x.push(Point::from(vec(d)?));
            p.state.v.push(vec(d)?);
            p.state.a.push(vec(d)?);
            p.state.pressure.push(d.f64()?);
            p.kind.push(match d.u64()? {
                0 => ParticleKind::Fluid,
                1 => ParticleKind::Solid,
                2 => ParticleKind::Wall,
                k => return Err(CheckpointError::Corrupt(format!("particle kind {k}"))),
            });
            p.body
                .push(small(d.u64()?, u32::MAX as u64, "body")? as u32);
            p.spacing.push(d.f64()?);
            p.material
                .push(small(d.u64()?, u16::MAX as u64, "material")? as u16);
            p.x0.push(Point::from(vec(d)?));
            p.constraints
                .mask
                .push(small(d.u64()?, (1 << D) - 1, "constraint mask")? as u8);
            p.constraints.velocity.push(vec(d)?);
        }
        Ok(p)
    }
}
