//! The simulation loop: remesh → assemble → solve (Picard) → update →
//! observe, with only the stages a scene calls for.

use std::time::Instant;

use pfem_assembly::{Constraints, StepMesh};
use pfem_constitutive::{History, Material, MaterialKind};
use pfem_core::{simplex_measure, Const, Dim, ParticleKind, Point, Vector};
use pfem_geometry::{alpha_shape, classify, AlphaShapeParams, NodeTag, Tessellation, Tessellator};
use pfem_time::{CourantController, Integrator, ParticleState, StepInput, StepParams};

use crate::lattice;
use crate::scene::{Geometry, Scene, WallMotion};
use crate::{RunError, SceneError};

/// The stages a step runs, derived from the scene: a scene pays only for
/// the effects it has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stages {
    /// Delaunay remeshing and alpha shape every step (scenes with a fluid).
    pub remesh: bool,
    /// Nodal pressure update, eq. 62 (scenes with a fluid).
    pub pressure: bool,
    /// Solid stress update, eq. 63 (scenes with a solid).
    pub solid_stress: bool,
    /// Body-force assembly (scenes with gravity).
    pub body_force: bool,
    /// Flying-particle handling: particles outside every element fly
    /// ballistically (scenes with a fluid that has a free surface).
    pub free_surface: bool,
}

/// Wall time and call count of each stage.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageStats {
    /// Remeshing: calls and seconds.
    pub remesh: (u64, f64),
    /// Free-surface detection and its `p = 0` condition: calls and seconds.
    pub free_surface: (u64, f64),
    /// Assembly: calls (steps) and seconds.
    pub assemble: (u64, f64),
    /// Linear solves: calls (steps) and seconds.
    pub solve: (u64, f64),
    /// History and state update: calls and seconds.
    pub update: (u64, f64),
    /// Observers (output): calls and seconds.
    pub observe: (u64, f64),
    /// Volume correction (see [`Simulation::volume_correction`]): calls
    /// and seconds.
    pub volume_correction: (u64, f64),
    /// Rejected step attempts (inverted element, Picard divergence, failed
    /// solve): count and seconds. `assemble`, `solve` and `update` count
    /// accepted attempts only.
    pub rejected: (u64, f64),
    /// Pressure updates (eq. 62) done.
    pub pressure_updates: u64,
    /// Solid stress updates (eq. 63) done.
    pub stress_updates: u64,
}

/// Something called after every accepted step (outputs, probes, checks).
/// Every method has a do-nothing default; `()` observes nothing.
pub trait Observer<const D: usize>
where
    Const<D>: Dim,
{
    /// Called once before the first step.
    fn start(&mut self, _sim: &Simulation<D>) -> Result<(), RunError> {
        Ok(())
    }
    /// Called after every accepted step.
    fn step(&mut self, _sim: &Simulation<D>) -> Result<(), RunError> {
        Ok(())
    }
    /// Called once after the last step.
    fn finish(&mut self, _sim: &Simulation<D>) -> Result<(), RunError> {
        Ok(())
    }
}

impl<const D: usize> Observer<D> for () where Const<D>: Dim {}

/// Fluid volume changes by cause (m³, m² per metre in 2D).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VolumeLedger {
    /// Fluid volume at the start.
    pub initial: f64,
    /// Change by remeshing (Delaunay + alpha shape deletions/creations).
    pub remeshing: f64,
    /// Change during the solution (quasi-incompressibility, flow).
    pub solution: f64,
    /// Change by the volume correction (see
    /// [`Simulation::volume_correction`]); zero when it is off.
    pub correction: f64,
}

/// A running simulation.
pub struct Simulation<const D: usize>
where
    Const<D>: Dim,
{
    /// Scene name.
    pub name: String,
    /// Particle state: positions, velocities, accelerations, pressure.
    pub state: ParticleState<D>,
    /// Kind of each particle.
    pub kind: Vec<ParticleKind>,
    /// Body of each particle.
    pub body: Vec<u32>,
    /// Spacing carried by each particle (m).
    pub spacing: Vec<f64>,
    /// Material of each particle (`u16::MAX` for walls).
    pub material_of: Vec<u16>,
    /// The materials.
    pub materials: Vec<Box<dyn Material<D>>>,
    /// Body names.
    pub body_names: Vec<String>,
    /// Velocity constraints (walls, clamps).
    pub constraints: Constraints<D>,
    /// Fluid elements of the current step (flat).
    pub fluid_elements: Vec<u32>,
    /// Closures of the current step: the flat simplices filling sealed voids
    /// of the fluid mesh (3D), `D + 1` particle indices each; the pressure
    /// terms see the fluid closed across them
    /// ([`pfem_assembly::StepMesh::closures`]). Empty when
    /// [`Simulation::close_sealed_voids`] is off.
    pub fluid_closures: Vec<u32>,
    /// Wall pockets of the current step
    /// ([`pfem_geometry::AlphaShape::wall_pockets`]): lattice cells in the
    /// concave corners of the walls, counted whole in
    /// [`Simulation::fluid_volume`] whichever way round-off splits them. Not
    /// elements.
    pub wall_pockets: Vec<u32>,
    /// Weight of each wall pocket in the fluid volume.
    pub pocket_weights: Vec<f64>,
    /// Count the wall pockets in the fluid volume (default true; deviation 9
    /// of `ARCHITECTURE.md`).
    pub count_wall_pockets: bool,
    /// Close the sealed voids of the fluid mesh for the pressure terms
    /// (default true; deviation 8 of `ARCHITECTURE.md`). Measured on 3D
    /// water at rest (0.5 × 0.25 × 0.5 m, h = H/10): without closures the
    /// first layer of water above the floor starts at 14 m/s² along the
    /// floor from rest (the kept tetrahedra on the two sides of each flat
    /// lattice sliver split one quadrilateral along different diagonals, so a
    /// hydrostatic pressure no longer balances).
    pub close_sealed_voids: bool,
    /// The alpha-shape fluid mesh of the current step, with adjacency.
    pub fluid_mesh: Tessellation,
    /// Material of each fluid element.
    pub fluid_material: Vec<u16>,
    /// Solid elements, each solid's own mesh (flat).
    pub solid_elements: Vec<u32>,
    /// Material of each solid element.
    pub solid_material: Vec<u16>,
    /// Cauchy stress history of each solid element.
    pub solid_history: Vec<History<D>>,
    /// Stages this scene runs.
    pub stages: Stages,
    /// Stage timings and counters.
    pub stats: StageStats,
    /// Simulated time (s).
    pub time: f64,
    /// Last time step (s).
    pub dt: f64,
    /// Accepted steps.
    pub steps: u64,
    /// Rejected attempts.
    pub rejected: u64,
    /// Rejected attempts by cause: (inverted element, Picard divergence).
    pub rejected_by_cause: (u64, u64),
    /// Volume ledger.
    pub volume: VolumeLedger,
    /// Body force (m/s²).
    pub gravity: Option<Vector<D>>,
    /// End time (s).
    pub end_time: f64,
    /// Output interval (s).
    pub output_interval: Option<f64>,
    /// Time-step controller.
    pub controller: CourantController,
    /// Alpha-shape parameters.
    pub alpha: AlphaShapeParams,
    /// Impose `p = 0` on free-surface nodes after each remeshing. Default
    /// false: measured on the 2D dam break (a/20) it lowered the front error
    /// (4.8% → 2.7%) but doubled the volume loss (−2.7% → −7.3%), and it did
    /// not stop the energy growth of the violent-splash case.
    pub free_surface_pressure_zero: bool,
    /// Volume correction: the fraction `β ∈ [0, 1]` of the fluid's volume
    /// error that each step restores. Default 1; 0 turns it off.
    ///
    /// Remeshing changes the measure of the fluid mesh (the alpha shape
    /// joins particles to walls as the fluid spreads, drops stretched
    /// boundary elements, closes and opens pockets), while the fluid's mass
    /// is fixed. After each remeshing the driver moves the free-surface
    /// fluid particles (not those of elements touching a solid, never walls
    /// or constrained components) by the minimum-norm displacement
    /// `uᵢ = −β e mᵢ / Σ|m|²` that restores `β e` to first order, `e` the
    /// volume error against the start (net of the elastic compression
    /// `Σ V p / K`, so a soft fluid keeps its physical compression) and `mᵢ`
    /// the particle's share of the free surface's area-weighted outward
    /// normals; each move is capped at 20 % of the smallest spacing and
    /// undone where it would halve an element. Velocities, pressures and
    /// accelerations are untouched: the correction is geometric and adds
    /// no momentum. Its effect is booked as `volume.correction`.
    pub volume_correction: f64,
    /// Elastic compression `Σ V p / K` of the fluid mesh at the start (m³).
    compression0: f64,
    x0: Vec<Point<D>>,
    /// Fluid volume of the current mesh at the current positions.
    volume_now: f64,
    tessellator: Box<dyn Tessellator<D>>,
    integrator: Integrator<D>,
    tess: Tessellation,
    elements: Vec<u32>,
    element_material: Vec<u16>,
    history: Vec<History<D>>,
}

impl<const D: usize> std::fmt::Debug for Simulation<D>
where
    Const<D>: Dim,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("name", &self.name)
            .field("particles", &self.state.len())
            .field("time", &self.time)
            .field("steps", &self.steps)
            .finish_non_exhaustive()
    }
}

impl<const D: usize> Simulation<D>
where
    Const<D>: Dim,
{
    /// Builds the particles, solid meshes and constraints of a validated
    /// scene. `tessellator` remeshes the fluid each step; `params` sets the
    /// time scheme and Picard loop.
    pub fn new(
        scene: Scene<D>,
        mut tessellator: Box<dyn Tessellator<D>>,
        params: StepParams,
    ) -> Result<Self, SceneError> {
        scene.validate()?;
        let Scene {
            name,
            bodies,
            gravity,
            settings,
        } = scene;
        let mut x: Vec<Point<D>> = Vec::new();
        let mut v: Vec<Vector<D>> = Vec::new();
        let mut kind = Vec::new();
        let mut body = Vec::new();
        let mut spacing = Vec::new();
        let mut material_of = Vec::new();
        let mut materials: Vec<Box<dyn Material<D>>> = Vec::new();
        let mut body_names = Vec::new();
        let mut solid_elements = Vec::new();
        let mut solid_material = Vec::new();
        let mut fixed: Vec<(usize, Vector<D>)> = Vec::new();
        // Walls and solids first: fluid lattice nodes that coincide with
        // them are dropped, the wall or solid particle takes their place.
        let mut order: Vec<usize> = (0..bodies.len()).collect();
        order.sort_by_key(|&i| match bodies[i].kind {
            ParticleKind::Wall => 0,
            ParticleKind::Solid => 1,
            ParticleKind::Fluid => 2,
        });
        let mut bodies: Vec<Option<crate::scene::Body<D>>> = bodies.into_iter().map(Some).collect();
        let cell = bodies
            .iter()
            .flatten()
            .map(|b| b.spacing)
            .fold(f64::INFINITY, f64::min);
        let mut grid = lattice::HashGrid::<D>::new(cell);
        for bi in order {
            let b = bodies[bi].take().expect("each body once");
            let id = body_names.len() as u32;
            body_names.push(b.name.clone());
            let pts = match &b.geometry {
                Geometry::Box { min, max } => lattice::box_points::<D>(min, max, b.spacing),
                Geometry::Ball { center, radius } => {
                    lattice::ball_points::<D>(center, *radius, b.spacing)
                }
                Geometry::Cylinder {
                    base,
                    axis,
                    radius,
                    height,
                } => lattice::cylinder_points::<D>(base, *axis, *radius, *height, b.spacing),
                Geometry::Particles(p) => p.clone(),
            };
            let mat = match b.material {
                Some(m) => {
                    materials.push(m);
                    (materials.len() - 1) as u16
                }
                None => u16::MAX,
            };
            let tol = 0.25 * b.spacing;
            let mut local_index = vec![u32::MAX; pts.len()];
            for (li, p) in pts.iter().enumerate() {
                // A wall or fluid particle that falls on an earlier body's
                // particle is dropped: that particle takes its place.
                if b.kind != ParticleKind::Solid && grid.near(p, tol, &x) {
                    continue;
                }
                // A solid keeps every particle (its own mesh uses them all):
                // one that falls on another particle is an error, not a merge.
                if b.kind == ParticleKind::Solid && grid.near(p, tol, &x) {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: format!(
                            "particle at {:?} lies within a quarter spacing ({tol:e} m) of another particle",
                            p.as_slice()
                        ),
                    });
                }
                local_index[li] = x.len() as u32;
                grid.insert(p, x.len());
                x.push(*p);
                kind.push(b.kind);
                body.push(id);
                spacing.push(b.spacing);
                material_of.push(mat);
                let vel = match (b.kind, b.motion) {
                    (ParticleKind::Wall, WallMotion::Velocity(w)) => w,
                    (ParticleKind::Wall, WallMotion::Fixed) => Vector::<D>::zeros(),
                    _ => b.velocity,
                };
                v.push(vel);
                let clamped = b.clamp.is_some_and(|(lo, hi)| {
                    (0..D).all(|k| p[k] >= lo[k] - 1e-12 && p[k] <= hi[k] + 1e-12)
                });
                if b.kind == ParticleKind::Wall || clamped {
                    fixed.push((
                        x.len() - 1,
                        if clamped { Vector::<D>::zeros() } else { vel },
                    ));
                }
            }
            if b.kind == ParticleKind::Solid {
                // Boxes: structured mesh; any other geometry: Delaunay of
                // its own particles trimmed by the alpha shape.
                let conn = match &b.geometry {
                    Geometry::Box { min, max } => lattice::box_simplices::<D>(min, max, b.spacing),
                    _ => {
                        let params = crate::solid_mesh::SolidMeshParams {
                            alpha: settings.alpha,
                            ..Default::default()
                        };
                        crate::solid_mesh::solid_mesh::<D>(
                            &pts,
                            b.spacing,
                            tessellator.as_mut(),
                            &params,
                        )
                        .map_err(|e| SceneError::InvalidGeometry {
                            body: b.name.clone(),
                            why: e.to_string(),
                        })?
                        .simplices
                    }
                };
                for &q in &conn {
                    solid_elements.push(local_index[q as usize]);
                }
                solid_material.extend(std::iter::repeat_n(mat, conn.len() / (D + 1)));
            }
        }
        if x.is_empty() {
            return Err(SceneError::Empty);
        }
        let n = x.len();
        let mut constraints = Constraints::<D>::free(n);
        for (i, vel) in fixed {
            constraints.fix(i, vel);
        }
        let mut state = ParticleState::at_rest(x);
        state.v = v;
        // Hydrostatic initial pressure in fluids at rest under gravity:
        // p = ρ g·(x_top − x) with x_top the body's highest particle along g.
        if let Some(g) = gravity {
            let gn = g.norm();
            if gn > 0.0 {
                let dir = g / gn;
                for (bi, _) in body_names.iter().enumerate() {
                    let idx: Vec<usize> = (0..n)
                        .filter(|&i| body[i] == bi as u32 && kind[i] == ParticleKind::Fluid)
                        .collect();
                    if idx.is_empty() {
                        continue;
                    }
                    let top = idx
                        .iter()
                        .map(|&i| state.x[i].dot(&dir))
                        .fold(f64::INFINITY, f64::min);
                    let rho = materials[material_of[idx[0]] as usize].density();
                    for &i in &idx {
                        state.pressure[i] = rho * gn * (state.x[i].dot(&dir) - top);
                    }
                    // Wall and solid particles bounding the fluid carry the
                    // same hydrostatic nodal pressure (eq. 62 puts pressure
                    // on every node of a fluid element).
                    let (lo, hi) = idx.iter().fold(
                        (
                            Point::<D>::repeat(f64::INFINITY),
                            Point::<D>::repeat(f64::NEG_INFINITY),
                        ),
                        |(lo, hi), &i| (lo.inf(&state.x[i]), hi.sup(&state.x[i])),
                    );
                    let h = spacing[idx[0]] * 1.01;
                    for i in 0..n {
                        let inside = (0..D)
                            .all(|k| state.x[i][k] >= lo[k] - h && state.x[i][k] <= hi[k] + h);
                        if kind[i] != ParticleKind::Fluid && inside {
                            state.pressure[i] = (rho * gn * (state.x[i].dot(&dir) - top)).max(0.0);
                        }
                    }
                }
            }
        }
        let has_fluid = kind.contains(&ParticleKind::Fluid);
        let has_solid = kind.contains(&ParticleKind::Solid);
        let stages = Stages {
            remesh: has_fluid,
            pressure: has_fluid,
            solid_stress: has_solid,
            body_force: gravity.is_some_and(|g| g.norm() > 0.0),
            free_surface: has_fluid,
        };
        let controller = CourantController {
            courant: settings.courant,
            dt_max: settings.max_dt,
            dt_min: params.min_dt,
            growth: 1.25,
        };
        let n_solid = solid_material.len();
        let mut sim = Self {
            name,
            state,
            kind,
            body,
            spacing,
            material_of,
            materials,
            body_names,
            constraints,
            fluid_elements: Vec::new(),
            fluid_closures: Vec::new(),
            wall_pockets: Vec::new(),
            pocket_weights: Vec::new(),
            count_wall_pockets: true,
            close_sealed_voids: true,
            fluid_mesh: Tessellation::default(),
            fluid_material: Vec::new(),
            solid_elements,
            solid_material,
            solid_history: vec![History::default(); n_solid],
            stages,
            stats: StageStats::default(),
            time: 0.0,
            dt: settings.max_dt,
            steps: 0,
            rejected: 0,
            rejected_by_cause: (0, 0),
            volume: VolumeLedger::default(),
            gravity: if stages.body_force { gravity } else { None },
            end_time: settings.end_time,
            output_interval: settings.output_interval,
            controller,
            alpha: AlphaShapeParams {
                // Above the water line is against gravity (dry bridges).
                up: gravity.filter(|g| g.norm() > 0.0).map(|g| {
                    let u = -g / g.norm();
                    [u[0], u[1], if D == 3 { u[D - 1] } else { 0.0 }]
                }),
                ..AlphaShapeParams::with_alpha(settings.alpha)
            },
            free_surface_pressure_zero: false,
            volume_correction: 1.0,
            compression0: 0.0,
            x0: Vec::new(),
            volume_now: 0.0,
            tessellator,
            integrator: Integrator::new(params),
            tess: Tessellation::default(),
            elements: Vec::new(),
            element_material: Vec::new(),
            history: Vec::new(),
        };
        sim.x0.clone_from(&sim.state.x);
        sim.remesh()
            .map_err(|e| SceneError::Mesh { why: e.to_string() })?;
        sim.volume.initial = sim.fluid_volume();
        sim.volume_now = sim.volume.initial;
        sim.compression0 = sim.fluid_compression();
        sim.assemble_mesh();
        let input = StepInput {
            mesh: StepMesh {
                elements: &sim.elements,
                element_material: &sim.element_material,
                closures: &sim.fluid_closures,
            },
            materials: &sim.materials,
            constraints: &sim.constraints,
            body_force: sim.gravity,
        };
        sim.integrator
            .initialize_acceleration(&mut sim.state, &sim.history, &input)
            .map_err(|e| SceneError::Mesh { why: e.to_string() })?;
        Ok(sim)
    }

    /// Fluid volume: the measure of the current fluid elements and of the
    /// wall pockets ([`Simulation::wall_pockets`]) (m³; m² per metre of depth
    /// in 2D).
    pub fn fluid_volume(&self) -> f64 {
        let nv = D + 1;
        let elements: f64 = self
            .fluid_elements
            .chunks_exact(nv)
            .map(|el| simplex_measure::<D>(&self.gather(el)[..nv]))
            .sum();
        let pockets: f64 = self
            .wall_pockets
            .chunks_exact(nv)
            .zip(&self.pocket_weights)
            .map(|(el, w)| w * simplex_measure::<D>(&self.gather(el)[..nv]))
            .sum();
        elements + pockets
    }

    /// Elastic compression of the fluid mesh, `Σ_e V_e p̄_e / K_e` (m³;
    /// `p̄_e` the mean nodal pressure of element `e`, `K_e = ρc²` of its
    /// fluid).
    fn fluid_compression(&self) -> f64 {
        let nv = D + 1;
        let mut c = 0.0;
        for (el, &m) in self
            .fluid_elements
            .chunks_exact(nv)
            .zip(&self.fluid_material)
        {
            let Some(mat) = self.materials.get(m as usize) else {
                continue;
            };
            let k = mat.density() * mat.wave_speed().powi(2);
            if !(k.is_finite() && k > 0.0) {
                continue;
            }
            let pm = el
                .iter()
                .map(|&i| self.state.pressure[i as usize])
                .sum::<f64>()
                / nv as f64;
            c += simplex_measure::<D>(&self.gather(el)[..nv]) * pm / k;
        }
        c
    }

    /// The volume correction of [`Simulation::volume_correction`]: moves
    /// the fluid particles of the free surface along their outward normals.
    fn correct_volume(&mut self) -> Result<(), RunError> {
        let beta = self.volume_correction;
        if !(0.0..=1.0).contains(&beta) {
            return Err(RunError::InvalidSetting {
                name: "volume_correction",
                value: beta,
                reason: "must be in [0, 1]",
            });
        }
        if beta == 0.0 || !self.stages.free_surface || self.volume_now <= 0.0 {
            return Ok(());
        }
        let t0 = Instant::now();
        let e = (self.volume_now + self.fluid_compression())
            - (self.volume.initial + self.compression0);
        if !e.is_finite() || e == 0.0 {
            return Ok(());
        }
        let nv = D + 1;
        let n = self.state.len();
        // Particles that may move: fluid, not touching a solid (moving them
        // squeezes the fluid against a structure that answers: the thin
        // plate of the hard cases gained 7.8 % energy with backward Euler).
        let mut movable: Vec<bool> = self
            .kind
            .iter()
            .map(|&k| k == ParticleKind::Fluid)
            .collect();
        for el in self.fluid_elements.chunks_exact(nv) {
            if el
                .iter()
                .any(|&i| self.kind[i as usize] == ParticleKind::Solid)
            {
                for &i in el {
                    movable[i as usize] = false;
                }
            }
        }
        // Area-weighted outward normal of the free surface at each movable
        // particle: the facet opposite vertex k of element e has outward
        // normal × measure −D Vₑ ∇W_k, shared equally by its D nodes. Only
        // facets with a fluid node are free surface (all-wall or all-solid
        // facets lie on a wall or a structure).
        let mut normal = vec![Vector::<D>::zeros(); n];
        let mut grads = [Vector::<D>::zeros(); pfem_core::MAX_NV];
        let mesh = &self.fluid_mesh;
        for (el, nb) in mesh
            .simplices
            .chunks_exact(nv)
            .zip(mesh.neighbors.chunks_exact(nv))
        {
            if !nb.contains(&pfem_geometry::NO_NEIGHBOR) {
                continue;
            }
            let p = self.gather(el);
            let Some(vol) = pfem_core::shape_gradients::<D>(&p[..nv], &mut grads[..nv]) else {
                continue;
            };
            for k in (0..nv).filter(|&k| nb[k] == pfem_geometry::NO_NEIGHBOR) {
                let facet = (0..nv).filter(|&a| a != k);
                if !facet
                    .clone()
                    .any(|a| self.kind[el[a] as usize] == ParticleKind::Fluid)
                {
                    continue;
                }
                let share = grads[k] * (-vol);
                for a in facet {
                    let i = el[a] as usize;
                    if movable[i] {
                        normal[i] += share;
                    }
                }
            }
        }
        // Constrained components (slip planes, clamps) do not move.
        for (i, m) in normal.iter_mut().enumerate() {
            for k in 0..D {
                if self.constraints.is_fixed(i, k) {
                    m[k] = 0.0;
                }
            }
        }
        // Minimum-norm move restoring β e to first order:
        // uᵢ = −β e mᵢ / Σ|m|², so Σ mᵢ·uᵢ = −β e; each move capped.
        let m2: f64 = normal.iter().map(|m| m.norm_squared()).sum();
        if !(m2.is_finite() && m2 > 0.0) {
            return Ok(());
        }
        let h_min = (0..n)
            .filter(|&i| self.kind[i] == ParticleKind::Fluid)
            .map(|i| self.spacing[i])
            .fold(f64::INFINITY, f64::min);
        // 5 % of a spacing could not follow single remeshings that change
        // a coarse (a/10) thin layer's volume by 4 %; 20 % keeps every hard
        // case of `tests/stability_*.rs` within 1 %.
        let cap = 0.2 * h_min;
        let s = beta * e / m2;
        let old: Vec<Point<D>> = self.state.x.clone();
        for (x, m) in self.state.x.iter_mut().zip(&normal) {
            let u = m * (-s);
            let len = u.norm();
            *x += if len > cap { u * (cap / len) } else { u };
        }
        // A move that would flatten an element (measure below half its
        // value) is undone for that element's nodes, until none is left.
        loop {
            let mut undone = false;
            for el in self.fluid_elements.chunks_exact(nv) {
                if !el
                    .iter()
                    .any(|&i| self.state.x[i as usize] != old[i as usize])
                {
                    continue;
                }
                let p1 = self.gather(el);
                let mut p0 = [Point::<D>::zeros(); pfem_core::MAX_NV];
                for a in 0..nv {
                    p0[a] = old[el[a] as usize];
                }
                if simplex_measure::<D>(&p1[..nv]) < 0.5 * simplex_measure::<D>(&p0[..nv]) {
                    for &i in el {
                        self.state.x[i as usize] = old[i as usize];
                    }
                    undone = true;
                }
            }
            if !undone {
                break;
            }
        }
        let after = self.fluid_volume();
        self.volume.correction += after - self.volume_now;
        self.volume_now = after;
        self.stats.volume_correction.0 += 1;
        self.stats.volume_correction.1 += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// Positions of the vertices of a simplex.
    fn gather(&self, el: &[u32]) -> [Point<D>; pfem_core::MAX_NV] {
        let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
        for (a, &i) in el.iter().enumerate() {
            p[a] = self.state.x[i as usize];
        }
        p
    }

    /// Regenerates the fluid mesh: Delaunay of all particles, alpha shape
    /// (§8), one fluid material per element from its fluid nodes.
    fn remesh(&mut self) -> Result<(), RunError> {
        if !self.stages.remesh {
            return Ok(());
        }
        let t0 = Instant::now();
        self.tessellator
            .tessellate(&self.state.x, &mut self.tess)
            .map_err(RunError::Geometry)?;
        let shape = alpha_shape(
            &self.state.x,
            &self.kind,
            &self.spacing,
            &self.tess,
            &self.alpha,
        )
        .map_err(RunError::Geometry)?;
        self.fluid_elements.clear();
        self.fluid_material.clear();
        let nv = D + 1;
        for el in shape.mesh.simplices.chunks_exact(nv) {
            let m = el
                .iter()
                .find(|&&p| self.kind[p as usize] == ParticleKind::Fluid)
                .map(|&p| self.material_of[p as usize])
                .unwrap_or(u16::MAX);
            self.fluid_elements.extend_from_slice(el);
            self.fluid_material.push(m);
        }
        self.fluid_mesh = shape.mesh;
        self.wall_pockets.clear();
        self.pocket_weights.clear();
        if self.count_wall_pockets {
            self.wall_pockets.extend_from_slice(&shape.wall_pockets);
            self.pocket_weights.extend_from_slice(&shape.pocket_weights);
        }
        self.fluid_closures.clear();
        if self.close_sealed_voids {
            self.fluid_closures.extend_from_slice(&shape.closures);
        }
        self.stats.remesh.0 += 1;
        self.stats.remesh.1 += t0.elapsed().as_secs_f64();
        if self.stages.free_surface && self.free_surface_pressure_zero {
            // Free-surface condition p = 0 on the nodes the alpha shape puts
            // on the free surface (§8): pressure stored at a node that the
            // new mesh exposes would otherwise push on neighbours with no
            // compression left to justify it.
            let t1 = Instant::now();
            let cls = classify(&self.state.x, &self.kind, &self.fluid_mesh, None)
                .map_err(RunError::Geometry)?;
            for (i, tag) in cls.tags.iter().enumerate() {
                if matches!(tag, NodeTag::FreeSurface | NodeTag::Isolated) {
                    self.state.pressure[i] = 0.0;
                }
            }
            self.stats.free_surface.0 += 1;
            self.stats.free_surface.1 += t1.elapsed().as_secs_f64();
        }
        Ok(())
    }

    fn assemble_mesh(&mut self) {
        self.elements.clear();
        self.elements.extend_from_slice(&self.fluid_elements);
        self.elements.extend_from_slice(&self.solid_elements);
        self.element_material.clear();
        self.element_material
            .extend_from_slice(&self.fluid_material);
        self.element_material
            .extend_from_slice(&self.solid_material);
        self.history.clear();
        self.history
            .resize(self.fluid_material.len(), History::default());
        self.history.extend_from_slice(&self.solid_history);
    }

    /// Smallest element size `h_min` used by the Courant controller: the
    /// smallest particle spacing.
    pub fn h_min(&self) -> f64 {
        self.spacing.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Shortest time a particle needs to cross its own spacing,
    /// `min_i h_i / |v_i|` (s); infinite when nothing moves. Wall particles
    /// are skipped.
    pub fn crossing_time(&self) -> f64 {
        (0..self.state.len())
            .filter(|&i| self.kind[i] != ParticleKind::Wall)
            .map(|i| self.spacing[i] / self.state.v[i].norm())
            .fold(f64::INFINITY, f64::min)
    }

    /// Largest particle speed (m/s).
    pub fn v_max(&self) -> f64 {
        self.state.v.iter().map(|v| v.norm()).fold(0.0, f64::max)
    }

    /// One accepted step: remesh (if the scene has a fluid), then the
    /// Newmark–Picard step with rejection and retry.
    ///
    /// The step runs on a worker of rayon's global pool (the calling thread
    /// waits), so that the parallel loops inside it (meshing, element
    /// kernels) are entered from inside the pool. Called from outside the
    /// pool, every parallel loop would hand its work over and back, and the
    /// pool's idle workers would compete for the cores with the calling
    /// thread's serial work: measured on the 2-core reference machine, the
    /// 2D gate to 0.05 s took 11.6–12.5 s that way against 6.1–7.1 s inside
    /// the pool (same session, same build).
    pub fn step(&mut self) -> Result<(), RunError> {
        rayon::scope(|_| self.step_in_pool())
    }

    fn step_in_pool(&mut self) -> Result<(), RunError> {
        // The fluid volume at the end of the last step is `volume_now`; it is
        // measured once after remeshing and once after the solution.
        if self.steps > 0 {
            self.remesh()?;
            let after = self.fluid_volume();
            self.volume.remeshing += after - self.volume_now;
            self.volume_now = after;
        }
        self.correct_volume()?;
        self.assemble_mesh();
        // Courant bound per particle, on its own spacing: Δt ≤ C min_i h_i/|v_i|,
        // passed to the controller as (h, v) = (min_i h_i/|v_i|, 1).
        let crossing = self.crossing_time();
        let mut dt = if crossing.is_finite() {
            self.controller.next(crossing, 1.0, self.dt)
        } else {
            self.controller.next(0.0, 0.0, self.dt)
        };
        if self.time + dt > self.end_time {
            dt = (self.end_time - self.time).max(self.controller.dt_min);
        }
        let input = StepInput {
            mesh: StepMesh {
                elements: &self.elements,
                element_material: &self.element_material,
                closures: &self.fluid_closures,
            },
            materials: &self.materials,
            constraints: &self.constraints,
            body_force: self.gravity,
        };
        let rep =
            self.integrator
                .advance(self.time, dt, &mut self.state, &mut self.history, &input)?;
        let nf = self.fluid_material.len();
        self.solid_history.copy_from_slice(&self.history[nf..]);
        self.time += rep.dt;
        self.dt = rep.dt;
        self.steps += 1;
        self.rejected += rep.rejections as u64;
        self.rejected_by_cause.0 += rep.rejected_inverted as u64;
        self.rejected_by_cause.1 += rep.rejected_picard as u64;
        self.stats.assemble.0 += rep.iterations as u64;
        self.stats.assemble.1 += rep.assemble_seconds;
        self.stats.solve.0 += rep.iterations as u64;
        self.stats.solve.1 += rep.solve_seconds;
        self.stats.update.0 += 1;
        self.stats.update.1 += rep.update_seconds;
        self.stats.rejected.0 += rep.rejections as u64;
        self.stats.rejected.1 += rep.rejected_seconds;
        if self.stages.pressure {
            self.stats.pressure_updates += 1;
        }
        if self.stages.solid_stress {
            self.stats.stress_updates += 1;
        }
        let end = self.fluid_volume();
        self.volume.solution += end - self.volume_now;
        self.volume_now = end;
        if let Some(i) = self
            .state
            .x
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite()))
        {
            return Err(RunError::NonFinite {
                time: self.time,
                particle: i,
            });
        }
        Ok(())
    }

    /// Runs to the end time, calling the observers after every step.
    pub fn run(&mut self, observers: &mut [&mut dyn Observer<D>]) -> Result<(), RunError> {
        for o in observers.iter_mut() {
            o.start(self)?;
        }
        while self.time < self.end_time - 1e-12 {
            self.step()?;
            let t0 = Instant::now();
            for o in observers.iter_mut() {
                o.step(self)?;
            }
            self.stats.observe.0 += 1;
            self.stats.observe.1 += t0.elapsed().as_secs_f64();
        }
        for o in observers.iter_mut() {
            o.finish(self)?;
        }
        Ok(())
    }

    /// Replaces the linear solver (default: [`pfem_assembly::DirectSolver`], sparse Cholesky with an LU fallback).
    pub fn set_solver(&mut self, solver: Box<dyn pfem_assembly::LinearSolver>) {
        let params = self.integrator.params;
        self.integrator = Integrator::with_solver(params, solver);
    }

    /// Position of particle `i` at `t = 0` (m).
    pub fn initial_position(&self, i: usize) -> Point<D> {
        self.x0[i]
    }

    /// Pressure force the fluid exerts on body `name` (N, per metre of depth
    /// in 2D): at each of the body's particles `i`, the nodal pressure force
    /// `Gᵀ p` of eq. 58, `Σ_e Σ_{a∈e} p_a (V_e/(D+1)) grad W_i` over the
    /// fluid elements `e` holding `i`, plus the weight less the inertia of
    /// the fluid mass those elements lump on `i`, `Σ_e ρ_e V_e/(D+1) (g − aᵢ)`.
    /// The lumped mass puts part of the adjacent fluid's weight on the
    /// body's nodes, where the nodal pressure force holds it up; without
    /// the second term a block held under water at rest read its buoyancy
    /// +40 % (issue 13; `tests/water_at_rest_2d.rs` now checks it to 2 %).
    /// The closures of sealed voids add their pressure force (3D; without
    /// them a 3D block read 12 N sideways and +47 % up,
    /// `tests/water_at_rest_3d.rs`).
    /// The viscous part is left out (negligible for water).
    pub fn pressure_force_on(&self, name: &str) -> Vector<D> {
        let Some(id) = self.body_names.iter().position(|b| b == name) else {
            return Vector::<D>::zeros();
        };
        let nv = D + 1;
        let gravity = self.gravity.unwrap_or_else(Vector::<D>::zeros);
        let mut f = Vector::<D>::zeros();
        let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
        let mut g = [Vector::<D>::zeros(); pfem_core::MAX_NV];
        for el in self.fluid_elements.chunks_exact(nv) {
            if !el.iter().any(|&q| self.body[q as usize] == id as u32) {
                continue;
            }
            for a in 0..nv {
                p[a] = self.state.x[el[a] as usize];
            }
            let Some(vol) = pfem_core::shape_gradients::<D>(&p[..nv], &mut g[..nv]) else {
                continue;
            };
            let p_sum: f64 = el.iter().map(|&q| self.state.pressure[q as usize]).sum();
            let rho = el
                .iter()
                .find(|&&q| self.kind[q as usize] == ParticleKind::Fluid)
                .map(|&q| self.materials[self.material_of[q as usize] as usize].density())
                .unwrap_or(0.0);
            for (a, &q) in el.iter().enumerate() {
                if self.body[q as usize] == id as u32 {
                    f += g[a] * (p_sum * vol / nv as f64);
                    let m = rho * vol / nv as f64;
                    f += (gravity - self.state.a[q as usize]) * m;
                }
            }
        }
        // Closures (deviation 8): their facets carry pressure like the
        // elements' (no mass).
        for el in self.fluid_closures.chunks_exact(nv) {
            if !el.iter().any(|&q| self.body[q as usize] == id as u32) {
                continue;
            }
            for a in 0..nv {
                p[a] = self.state.x[el[a] as usize];
            }
            pfem_core::weighted_shape_gradients::<D>(&p[..nv], &mut g[..nv]);
            let p_sum: f64 = el.iter().map(|&q| self.state.pressure[q as usize]).sum();
            for (a, &q) in el.iter().enumerate() {
                if self.body[q as usize] == id as u32 {
                    f += g[a] * (p_sum / nv as f64);
                }
            }
        }
        f
    }

    /// Particles of body `name`.
    pub fn body_particles(&self, name: &str) -> Vec<usize> {
        match self.body_names.iter().position(|b| b == name) {
            Some(id) => (0..self.state.len())
                .filter(|&i| self.body[i] == id as u32)
                .collect(),
            None => Vec::new(),
        }
    }

    /// The water pressure at every particle (Pa), what the VTU output
    /// writes as `pressure`: a fluid particle's own nodal pressure; at a
    /// solid or wall particle that a fluid element touches (a wetted
    /// interface), the pressure of the adjacent water, the least-squares
    /// linear fit `p ≈ c + b·(x − xᵢ)` to the fluid particles of its fluid
    /// elements and of theirs, evaluated at the particle (their mean where
    /// they do not span a simplex); `0` elsewhere.
    ///
    /// The pressure the method itself stores on an interface particle
    /// (`state.pressure`) is the incremental nodal pressure of eq. 62 over
    /// the particle's one-sided fluid patch; it drives the interface's
    /// momentum balance, but it is not the water's pressure there when the
    /// two spacings differ (issue 13: +61 % on a plate 8 times finer than
    /// the water). The fit is exact for a hydrostatic field whatever the
    /// ratio of the spacings.
    pub fn water_pressure(&self) -> Vec<f64> {
        let n = self.state.len();
        let nv = D + 1;
        let mut out = vec![0.0; n];
        // Fluid elements of each particle.
        let mut elems_of: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (e, el) in self.fluid_elements.chunks_exact(nv).enumerate() {
            for &i in el {
                elems_of[i as usize].push(e as u32);
            }
        }
        let fluid_of = |e: u32, into: &mut Vec<u32>| {
            for &j in &self.fluid_elements[e as usize * nv..(e as usize + 1) * nv] {
                if self.kind[j as usize] == ParticleKind::Fluid {
                    into.push(j);
                }
            }
        };
        // The fluid particles of an interface particle's fluid elements and
        // of theirs (two rings: one ring is often one flat layer of water,
        // which carries no gradient across it).
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut ring = Vec::new();
        for i in 0..n {
            if self.kind[i] == ParticleKind::Fluid || elems_of[i].is_empty() {
                continue;
            }
            ring.clear();
            for &e in &elems_of[i] {
                fluid_of(e, &mut ring);
            }
            ring.sort_unstable();
            ring.dedup();
            let nb = &mut neighbours[i];
            for &j in &ring {
                nb.push(j);
                for &e in &elems_of[j as usize] {
                    fluid_of(e, nb);
                }
            }
        }
        for i in 0..n {
            if self.kind[i] == ParticleKind::Fluid {
                out[i] = self.state.pressure[i];
                continue;
            }
            let nb = &mut neighbours[i];
            if nb.is_empty() {
                continue;
            }
            nb.sort_unstable();
            nb.dedup();
            out[i] = self.fit_pressure_at(i, nb);
        }
        out
    }

    /// Least-squares linear fit of the fluid pressure at `nb`, evaluated at
    /// particle `i` (see [`Simulation::water_pressure`]).
    fn fit_pressure_at(&self, i: usize, nb: &[u32]) -> f64 {
        let mean = nb
            .iter()
            .map(|&j| self.state.pressure[j as usize])
            .sum::<f64>()
            / nb.len() as f64;
        if nb.len() < D + 1 {
            return mean;
        }
        // Normal equations in (c, b) with coordinates relative to xᵢ,
        // scaled by the particle's spacing.
        let h = self.spacing[i].max(f64::MIN_POSITIVE);
        let m = D + 1;
        let mut a = nalgebra::DMatrix::<f64>::zeros(m, m);
        let mut r = nalgebra::DVector::<f64>::zeros(m);
        for &j in nb {
            let d = (self.state.x[j as usize] - self.state.x[i]) / h;
            let mut row = [1.0; 4];
            for k in 0..D {
                row[k + 1] = d[k];
            }
            let p = self.state.pressure[j as usize];
            for u in 0..m {
                r[u] += row[u] * p;
                for v in 0..m {
                    a[(u, v)] += row[u] * row[v];
                }
            }
        }
        // Condition check: a flat set of neighbours (all on one line or
        // plane) cannot carry a gradient across it.
        let sv = a.clone().singular_values();
        let (smax, smin) = (sv.max(), sv.min());
        if smin.is_nan() || smin <= 1e-8 * smax {
            return mean;
        }
        match a.lu().solve(&r) {
            Some(c) if c[0].is_finite() => c[0],
            _ => mean,
        }
    }

    /// Particles of fluid bodies that are in at least one fluid element.
    pub fn meshed_fluid_particles(&self) -> Vec<bool> {
        let mut m = vec![false; self.state.len()];
        for &p in &self.fluid_elements {
            if self.kind[p as usize] == ParticleKind::Fluid {
                m[p as usize] = true;
            }
        }
        m
    }

    /// Whether materials of this simulation include a solid.
    pub fn has_solid(&self) -> bool {
        self.materials
            .iter()
            .any(|m| m.kind() == MaterialKind::Solid)
    }
}
