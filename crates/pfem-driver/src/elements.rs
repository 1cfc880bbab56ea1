//! The element set of a step: the solids' own meshes (fixed for the run)
//! and the fluid mesh the alpha shape cut this step, in one connectivity
//! array with one material and one history per element.

use pfem_assembly::StepMesh;
use pfem_constitutive::History;
use pfem_core::{simplex_measure, Const, Dim, ParticleKind, Point, Vector};
use pfem_geometry::{AlphaShape, Tessellation};

use crate::checkpoint::{fingerprint, CheckpointError, Decoder, Encoder};

/// Contact elements kept between two meshes: connectivity and histories.
pub(crate) type ContactStash<const D: usize> = (Vec<u32>, Vec<History<D>>);

/// Elements of a simulation, `D + 1` particle indices each: the solid range
/// first (each solid's own mesh, built once, carrying its stress history
/// from step to step), then the fluid range (rebuilt by every remeshing,
/// with a fresh history: a fluid's history is its nodal pressure, held by
/// the particles). The step hands the whole array to the integrator as one
/// [`StepMesh`]; nothing is copied back.
///
/// The alpha shape of the step is kept whole ([`Elements::shape`]): the
/// fluid mesh with its adjacency (free-surface facets), the closures of
/// sealed voids and the wall pockets.
#[derive(Debug, Clone, Default)]
pub struct Elements<const D: usize>
where
    Const<D>: Dim,
{
    conn: Vec<u32>,
    material: Vec<u16>,
    history: Vec<History<D>>,
    /// Each solid element's volume in the scene's initial configuration:
    /// its lumped mass is `ρ₀ V₀` (eq. 46), whatever its volume now.
    reference_volumes: Vec<f64>,
    n_solid: usize,
    n_fluid: usize,
    /// The two bodies of each contact element (master first).
    contact_bodies: Vec<(u32, u32)>,
    /// The last contact range (connectivity, histories), kept when the
    /// fluid range is replaced so that the next contact range carries the
    /// tangential tractions of elements that persist.
    stash: ContactStash<D>,
    contact_set: bool,
    shape: AlphaShape,
    close_sealed_voids: bool,
    count_wall_pockets: bool,
    /// The shape's surface cuts in element numbering, and `up`.
    cuts: Vec<(u32, u8)>,
    up: [f64; 3],
}

impl<const D: usize> Elements<D>
where
    Const<D>: Dim,
{
    /// The solid elements (`conn`, flat) with one material each, their
    /// particles' initial positions `x0` (their reference volumes), and
    /// the options for the fluid range.
    pub(crate) fn new(
        solid: Vec<u32>,
        solid_material: Vec<u16>,
        x0: &[Point<D>],
        close_sealed_voids: bool,
        count_wall_pockets: bool,
    ) -> Self {
        let n_solid = solid_material.len();
        let mut elements = Self {
            conn: solid,
            material: solid_material,
            history: vec![History::default(); n_solid],
            reference_volumes: Vec::new(),
            n_solid,
            n_fluid: 0,
            contact_bodies: Vec::new(),
            stash: (Vec::new(), Vec::new()),
            contact_set: false,
            shape: AlphaShape::default(),
            close_sealed_voids,
            count_wall_pockets,
            cuts: Vec::new(),
            up: [0.0; 3],
        };
        elements.set_reference_volumes(x0);
        elements
    }

    /// Each solid element's volume at the particles' initial positions
    /// `x0` (its mass `ρ₀ V₀`, eq. 46). A restore sets them again from the
    /// checkpoint's own initial positions, not the scene's.
    pub(crate) fn set_reference_volumes(&mut self, x0: &[Point<D>]) {
        let nv = D + 1;
        self.reference_volumes.clear();
        for el in self.conn[..self.n_solid * nv].chunks_exact(nv) {
            let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
            for (a, &i) in el.iter().enumerate() {
                p[a] = x0
                    .get(i as usize)
                    .copied()
                    .unwrap_or_else(Point::<D>::zeros);
            }
            self.reference_volumes.push(simplex_measure::<D>(&p[..nv]));
        }
    }

    /// Each solid element's initial volume (m³; m² in 2D), in the order of
    /// [`Elements::solid`]: its lumped mass is `ρ₀ V₀`.
    pub fn reference_volumes(&self) -> &[f64] {
        &self.reference_volumes
    }

    /// Replaces the fluid range with the kept simplices of `shape`, the
    /// material of each from `material_of(simplex)`; `up` is the alpha
    /// shape's (for its surface cuts).
    pub(crate) fn set_fluid(
        &mut self,
        shape: AlphaShape,
        up: Option<[f64; 3]>,
        material_of: impl Fn(&[u32]) -> u16,
    ) {
        let nv = D + 1;
        self.truncate_to_solid();
        self.conn.extend_from_slice(&shape.mesh.simplices);
        for el in shape.mesh.simplices.chunks_exact(nv) {
            self.material.push(material_of(el));
        }
        self.history.resize(self.material.len(), History::default());
        self.n_fluid = self.material.len() - self.n_solid;
        self.cuts.clear();
        if let Some(up) = up {
            let first = self.n_solid as u32;
            self.cuts.extend(
                shape
                    .surface_cuts
                    .iter()
                    .map(|&(m, mask)| (first + m, mask)),
            );
            self.up = up;
        }
        self.shape = shape;
    }

    /// Keeps only the solid range; the contact range goes to the stash
    /// first (if one was set since the last stash).
    fn truncate_to_solid(&mut self) {
        let nv = D + 1;
        if self.contact_set {
            let first = self.n_solid + self.n_fluid;
            self.stash.0.clear();
            self.stash.0.extend_from_slice(&self.conn[first * nv..]);
            self.stash.1.clear();
            self.stash.1.extend_from_slice(&self.history[first..]);
            self.contact_set = false;
        }
        self.conn.truncate(self.n_solid * nv);
        self.material.truncate(self.n_solid);
        self.history.truncate(self.n_solid);
        self.contact_bodies.clear();
        self.n_fluid = 0;
    }

    /// Appends the contact range (after the fluid range): one element per
    /// candidate with `material(nodes)`, its history's gap ratio (gap over the
    /// contact distance, [`contact_distance`]), friction
    /// (`friction(master, other)`) and normal set, and its tangential
    /// traction carried from the last contact range when the same
    /// particles were in contact there.
    pub(crate) fn set_contact(
        &mut self,
        candidates: &[pfem_geometry::ContactCandidate<D>],
        material: &dyn Fn(&[u32]) -> u16,
        body: &[u32],
        spacing: &[f64],
        friction: &dyn Fn(u32, u32) -> f64,
    ) {
        use pfem_constitutive::contact::{FRICTION, GAP_RATIO, NORMAL, TRACTION};
        let nv = D + 1;
        // The shear stress of the last contact range, `τ ⊗ n + n ⊗ τ` (the
        // same whichever body is the master), averaged at its particles:
        // a new element takes the mean of its particles' as its traction,
        // so stick keeps its memory when the tessellation flips a
        // diagonal between two lattice rows.
        let mut nodal: std::collections::HashMap<u32, (pfem_core::Tensor<D>, u32)> =
            std::collections::HashMap::new();
        for (el, h) in self.stash.0.chunks_exact(nv).zip(&self.stash.1) {
            let n = pfem_core::Vector::<D>::from_fn(|k, _| h.internal[NORMAL + k]);
            let t = pfem_core::Vector::<D>::from_fn(|k, _| h.internal[TRACTION + k]);
            let shear = t * n.transpose() + n * t.transpose();
            for &p in el {
                let e = nodal
                    .entry(p)
                    .or_insert((pfem_core::Tensor::<D>::zeros(), 0));
                e.0 += shear;
                e.1 += 1;
            }
        }
        for c in candidates {
            let el = &c.nodes[..nv];
            self.conn.extend_from_slice(el);
            self.material.push(material(el));
            let g0 = contact_distance(el, c.bodies, body, spacing);
            let mut h = History::<D>::default();
            let (mut shear, mut count) = (pfem_core::Tensor::<D>::zeros(), 0u32);
            for p in el {
                if let Some((s, k)) = nodal.get(p) {
                    shear += s / *k as f64;
                    count += 1;
                }
            }
            if count > 0 {
                let s = shear / count as f64;
                let sn = s * c.normal;
                let t = sn - c.normal * c.normal.dot(&sn);
                for k in 0..D {
                    h.internal[TRACTION + k] = t[k];
                }
            }
            h.internal[GAP_RATIO] = c.gap / g0;
            h.internal[FRICTION] = friction(c.bodies.0, c.bodies.1);
            for k in 0..D {
                h.internal[NORMAL + k] = c.normal[k];
            }
            self.history.push(h);
            self.contact_bodies.push(c.bodies);
        }
        self.contact_set = true;
    }

    /// Gives each contact element the stress its layer holds at rest,
    /// before any step moves it: the penalty of its gap ratio and its
    /// carried traction, through its material's
    /// [`pfem_constitutive::Material::update_history`] with the
    /// kinematics at rest (`F = I`, no rate: the dashpot's part is left
    /// out). Only the stress is written; the history the step reads (gap
    /// ratio, normal, traction) is left as set, so a step's results do not
    /// change. Without it a contact range re-formed without a solve (a
    /// restore, a hook's change of the particle set) read zero in
    /// `contact_force` and in the frames' `contact_pressure` until the next
    /// step (session 49's review).
    pub(crate) fn set_contact_stress_at_rest(
        &mut self,
        materials: &[Box<dyn pfem_constitutive::Material<D>>],
        dt: f64,
    ) {
        let first = self.n_solid + self.n_fluid;
        let at_rest = pfem_constitutive::Kinematics::<D>::at_rest(dt);
        for (h, &m) in self.history[first..]
            .iter_mut()
            .zip(&self.material[first..])
        {
            let Some(material) = materials.get(m as usize) else {
                continue;
            };
            let mut state = *h;
            material.update_history(&at_rest, &mut state);
            h.stress = state.stress;
            h.stress_zz = state.stress_zz;
        }
    }

    /// Takes the alpha shape out to be refilled (its buffers reused).
    pub(crate) fn take_shape(&mut self) -> AlphaShape {
        std::mem::take(&mut self.shape)
    }

    /// The whole step mesh for the integrator, and the histories it
    /// advances.
    pub(crate) fn step_mesh(&mut self) -> (StepMesh<'_>, &mut [History<D>]) {
        let closures: &[u32] = if self.close_sealed_voids {
            &self.shape.closures
        } else {
            &[]
        };
        (
            StepMesh {
                elements: &self.conn,
                element_material: &self.material,
                closures,
                surface_cuts: pfem_assembly::SurfaceCuts {
                    elements: &self.cuts,
                    up: self.up,
                },
                reference_volumes: &self.reference_volumes,
                node_material: &[],
            },
            &mut self.history,
        )
    }

    /// Every element, solid range first (flat).
    pub fn all(&self) -> &[u32] {
        &self.conn
    }

    /// Material of every element.
    pub fn materials(&self) -> &[u16] {
        &self.material
    }

    /// History of every element (solids: Cauchy stress at `t_n`).
    pub fn history(&self) -> &[History<D>] {
        &self.history
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.material.len()
    }

    /// Whether there is no element.
    pub fn is_empty(&self) -> bool {
        self.material.is_empty()
    }

    /// Number of solid elements.
    pub fn n_solid(&self) -> usize {
        self.n_solid
    }

    /// Number of fluid elements.
    pub fn n_fluid(&self) -> usize {
        self.n_fluid
    }

    /// Number of contact elements (after the fluid range).
    pub fn n_contact(&self) -> usize {
        self.material.len() - self.n_solid - self.n_fluid
    }

    /// The contact elements of the current step (flat): simplices joining
    /// a solid that takes part in contact (a free one, or any with
    /// `ContactSettings::clamped`) to a wall or another solid across a gap
    /// (`pfem_geometry::contact`).
    pub fn contact(&self) -> &[u32] {
        &self.conn[(self.n_solid + self.n_fluid) * (D + 1)..]
    }

    /// History of each contact element (its stress `−p I + τ ⊗ n + n ⊗ τ`
    /// after the step, and `pfem_constitutive::contact`'s slots).
    pub fn contact_history(&self) -> &[History<D>] {
        &self.history[self.n_solid + self.n_fluid..]
    }

    /// The nodal forces of the contact elements `e` for which `keep(e)`
    /// holds, on positions `x`: `add(e, particle, f)` with
    /// `f = −V σ ∇N` of the element's stress (its last step's, constant
    /// in the simplex) for each of its particles; a degenerate element
    /// gives none.
    pub fn contact_nodal_forces(
        &self,
        x: &[Point<D>],
        keep: impl Fn(usize) -> bool,
        mut add: impl FnMut(usize, usize, Vector<D>),
    ) {
        let nv = D + 1;
        let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
        let mut g = [Vector::<D>::zeros(); pfem_core::MAX_NV];
        for (e, (el, h)) in self
            .contact()
            .chunks_exact(nv)
            .zip(self.contact_history())
            .enumerate()
        {
            if !keep(e) {
                continue;
            }
            for k in 0..nv {
                p[k] = x[el[k] as usize];
            }
            let Some(vol) = pfem_core::shape_gradients::<D>(&p[..nv], &mut g[..nv]) else {
                continue;
            };
            for k in 0..nv {
                add(e, el[k] as usize, -(h.stress * g[k] * vol));
            }
        }
    }

    /// The two bodies of each contact element, the master (whose facet
    /// gives the normal) first.
    pub fn contact_bodies(&self) -> &[(u32, u32)] {
        &self.contact_bodies
    }

    /// The solid elements (flat).
    pub fn solid(&self) -> &[u32] {
        &self.conn[..self.n_solid * (D + 1)]
    }

    /// Material of each solid element.
    pub fn solid_material(&self) -> &[u16] {
        &self.material[..self.n_solid]
    }

    /// Stress history of each solid element.
    pub fn solid_history(&self) -> &[History<D>] {
        &self.history[..self.n_solid]
    }

    /// The fluid elements of the current step (flat).
    pub fn fluid(&self) -> &[u32] {
        &self.conn[self.n_solid * (D + 1)..(self.n_solid + self.n_fluid) * (D + 1)]
    }

    /// Material of each fluid element.
    pub fn fluid_material(&self) -> &[u16] {
        &self.material[self.n_solid..self.n_solid + self.n_fluid]
    }

    /// The fluid mesh with adjacency ([`AlphaShape::mesh`]): the same
    /// simplices as [`Elements::fluid`].
    pub fn fluid_mesh(&self) -> &Tessellation {
        &self.shape.mesh
    }

    /// The alpha shape of the current step.
    pub fn shape(&self) -> &AlphaShape {
        &self.shape
    }

    /// Closures of the sealed voids of the fluid mesh (3D; deviation 8 of
    /// `ARCHITECTURE.md`), `D + 1` particle indices each; empty when
    /// [`crate::Options::close_sealed_voids`] is off.
    pub fn closures(&self) -> &[u32] {
        if self.close_sealed_voids {
            &self.shape.closures
        } else {
            &[]
        }
    }

    /// Wall pockets of the current step (3D; deviation 9), counted in the
    /// fluid volume with [`Elements::pocket_weights`]; empty when
    /// [`crate::Options::count_wall_pockets`] is off.
    pub fn wall_pockets(&self) -> &[u32] {
        if self.count_wall_pockets {
            &self.shape.wall_pockets
        } else {
            &[]
        }
    }

    /// Weight of each wall pocket.
    pub fn pocket_weights(&self) -> &[f64] {
        if self.count_wall_pockets {
            &self.shape.pocket_weights
        } else {
            &[]
        }
    }

    /// The surface cuts of the fluid range (issue 19): each cut element's
    /// index in [`Elements::fluid`]'s order and the bit mask of its
    /// free-surface vertices, with the `up` direction of their water line
    /// (`pfem_core::below_water_line`): the assembly counts such an
    /// element's part below the line only (its volume, lumped mass and
    /// pressure rows).
    pub fn fluid_surface_cuts(
        &self,
    ) -> (impl Iterator<Item = (usize, u8)> + '_, pfem_core::Vector<D>) {
        let first = self.n_solid;
        (
            self.cuts
                .iter()
                .map(move |&(e, mask)| (e as usize - first, mask)),
            pfem_core::Vector::<D>::from_fn(|k, _| self.up[k]),
        )
    }

    /// Fluid volume at positions `x`: the measure of the fluid elements and
    /// of the weighted wall pockets (m³; m² per metre of depth in 2D).
    pub fn fluid_volume(&self, x: &[Point<D>]) -> f64 {
        let nv = D + 1;
        let measure = |el: &[u32]| {
            let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
            for (a, &i) in el.iter().enumerate() {
                p[a] = x[i as usize];
            }
            simplex_measure::<D>(&p[..nv])
        };
        let mut elements: f64 = self.fluid().chunks_exact(nv).map(measure).sum();
        // Surface cuts count their part below the water line.
        let up = pfem_core::Vector::<D>::from_fn(|k, _| self.up[k]);
        for &(e, mask) in &self.cuts {
            let el = &self.conn[e as usize * nv..(e as usize + 1) * nv];
            let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
            for (a, &i) in el.iter().enumerate() {
                p[a] = x[i as usize];
            }
            let share = pfem_core::below_water_line::<D>(&p[..nv], mask, &up).0;
            elements -= (1.0 - share) * simplex_measure::<D>(&p[..nv]);
        }
        let pockets: f64 = self
            .wall_pockets()
            .chunks_exact(nv)
            .zip(self.pocket_weights())
            .map(|(el, w)| w * measure(el))
            .sum();
        elements + pockets
    }

    /// Volume of the fluid flying as drops (m³; m² per metre in 2D): each
    /// fluid particle in no fluid element (§8's isolated particles) counts
    /// its lattice cell `hᵢ^D`, `hᵢ` its spacing, the volume it stands for
    /// in the lattice it was filled in (a square or cubic lattice of
    /// spacing `h` holds one particle per `h^D`). Without it, a drop's
    /// volume leaves the fluid's measure while it flies, and the volume
    /// correction puts it back into the remaining water (for good if the
    /// drop never lands).
    pub fn drop_volume(&self, kind: &[ParticleKind], spacing: &[f64]) -> f64 {
        let mut meshed = vec![false; kind.len()];
        for &i in self.fluid() {
            // A mesh of an older set (removed particles, not yet remeshed)
            // names indices past the end: they are not this set's.
            if let Some(m) = meshed.get_mut(i as usize) {
                *m = true;
            }
        }
        kind.iter()
            .zip(spacing)
            .zip(&meshed)
            .filter(|((&k, _), &m)| k == ParticleKind::Fluid && !m)
            .map(|((_, &h), _)| h.powi(D as i32))
            .sum()
    }

    /// Drops the fluid range after particles were removed or inserted (it
    /// indexes the old cloud); the next remeshing rebuilds it. Solid
    /// particles keep their indices under [`crate::Particles::remap`], so
    /// the solid range stays valid.
    pub(crate) fn clear_fluid(&mut self) {
        self.truncate_to_solid();
        self.cuts.clear();
        self.shape = AlphaShape::default();
    }

    /// Writes the solid range (connectivity fingerprint, materials, and
    /// each element's history) into a checkpoint section.
    pub(crate) fn encode_solid(&self, e: &mut Encoder) {
        e.u64(self.n_solid as u64);
        let conn: Vec<u8> = self.solid().iter().flat_map(|v| v.to_le_bytes()).collect();
        e.u64(fingerprint(&conn));
        for h in self.solid_history() {
            for v in h.stress.iter() {
                e.f64(*v);
            }
            e.f64(h.stress_zz);
            e.f64(h.pressure);
            for v in h.internal {
                e.f64(v);
            }
        }
    }

    /// Reads what [`Elements::encode_solid`] wrote, for the solid range,
    /// which must be the same mesh: its histories, to be put in place by
    /// [`Elements::set_solid_history`].
    pub(crate) fn decode_solid(
        &self,
        d: &mut Decoder<'_>,
    ) -> Result<Vec<History<D>>, CheckpointError> {
        let n = d.len(0)?;
        if n != self.n_solid {
            return Err(CheckpointError::Mismatch {
                what: "the number of solid elements",
                checkpoint: n.to_string(),
                simulation: self.n_solid.to_string(),
            });
        }
        let conn: Vec<u8> = self.solid().iter().flat_map(|v| v.to_le_bytes()).collect();
        let f = d.u64()?;
        if f != fingerprint(&conn) {
            return Err(CheckpointError::Mismatch {
                what: "the solid mesh (fingerprint)",
                checkpoint: format!("{f:016x}"),
                simulation: format!("{:016x}", fingerprint(&conn)),
            });
        }
        let mut history = Vec::with_capacity(n);
        for _ in 0..n {
            let mut h = History::<D>::default();
            for v in h.stress.iter_mut() {
                *v = d.f64()?;
            }
            h.stress_zz = d.f64()?;
            h.pressure = d.f64()?;
            for v in h.internal.iter_mut() {
                *v = d.f64()?;
            }
            history.push(h);
        }
        Ok(history)
    }

    /// Puts the solid range's histories ([`Elements::decode_solid`]) in place.
    pub(crate) fn set_solid_history(&mut self, history: &[History<D>]) {
        self.history[..history.len()].copy_from_slice(history);
    }

    /// Keeps the stash as the source of the next contact range (after a
    /// restore has re-formed the contact range from it for the outputs,
    /// the next step must carry from the checkpoint's range, as the
    /// uninterrupted run does).
    pub(crate) fn keep_stash(&mut self) {
        self.contact_set = false;
    }

    /// Writes the contact range (connectivity and histories): the
    /// tangential tractions that stick carries from step to step. When the
    /// next range carries from the stash (right after a restore, whose
    /// range was re-formed from it for the outputs only), the stash: a
    /// checkpoint written then, with no step between, wrote that re-formed
    /// range, its tractions averaged a second time (session 44's review).
    pub(crate) fn encode_contact(&self, e: &mut Encoder) {
        let nv = D + 1;
        let (conn, history) = if self.contact_set {
            (self.contact(), self.contact_history())
        } else {
            (&self.stash.0[..], &self.stash.1[..])
        };
        e.u64((conn.len() / nv) as u64);
        for (el, h) in conn.chunks_exact(nv).zip(history) {
            for &p in el {
                e.u64(p as u64);
            }
            for v in h.internal {
                e.f64(v);
            }
        }
    }

    /// Reads what [`Elements::encode_contact`] wrote: the stash the next
    /// contact range carries from ([`Elements::set_stash`]).
    pub(crate) fn decode_contact(
        d: &mut Decoder<'_>,
        n_particles: usize,
    ) -> Result<ContactStash<D>, CheckpointError> {
        let nv = D + 1;
        let n = d.len(8 * (nv + 8))?;
        let mut conn = Vec::with_capacity(n * nv);
        let mut hist = Vec::with_capacity(n);
        for _ in 0..n {
            for _ in 0..nv {
                let p = d.u64()?;
                if p as usize >= n_particles {
                    return Err(CheckpointError::Corrupt(format!("contact node {p}")));
                }
                conn.push(p as u32);
            }
            let mut h = History::<D>::default();
            for v in h.internal.iter_mut() {
                *v = d.f64()?;
            }
            hist.push(h);
        }
        Ok((conn, hist))
    }

    /// Drops the fluid and contact ranges and keeps `stash` (from
    /// [`Elements::decode_contact`]) as the source of the next contact
    /// range.
    pub(crate) fn set_stash(&mut self, stash: ContactStash<D>) {
        self.truncate_to_solid();
        self.stash = stash;
    }
}

/// The contact distance of a contact element between bodies `pair` (m):
/// half the sum of the two bodies' spacings (each the mean over the
/// element's particles of that body), where two bodies' outer rows sit at
/// rest, each surface half its own spacing beyond its row. The mean over
/// the element's particles, used until session 41, was another distance
/// for each element between bodies of unlike spacings: a fine block (h)
/// on a coarse floor (2h) met elements of 2h's two particles and of h's
/// two, `g₀` 1.67h and 1.33h, so no gap left them both open, and each
/// flip of the tessellation between the two kinds changed the pressure.
/// Particles of a third body are left out; one with no particle of either
/// body (not formed) takes the mean of all.
pub(crate) fn contact_distance(
    nodes: &[u32],
    pair: (u32, u32),
    body: &[u32],
    spacing: &[f64],
) -> f64 {
    let mean = |b: u32| {
        let (sum, n) = nodes
            .iter()
            .filter(|&&p| body.get(p as usize) == Some(&b))
            .fold((0.0, 0u32), |(s, n), &p| (s + spacing[p as usize], n + 1));
        (n > 0).then(|| sum / n as f64)
    };
    match (mean(pair.0), mean(pair.1)) {
        (Some(a), Some(b)) => 0.5 * (a + b),
        _ => nodes.iter().map(|&p| spacing[p as usize]).sum::<f64>() / nodes.len() as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::contact_distance;

    /// Session 41: a fine body (h) on a coarse one (2h). Every element
    /// between them has the one contact distance 1.5h, however many of
    /// its particles each body brings (the mean over the element's
    /// particles gave 1.67h and 1.33h).
    #[test]
    fn the_contact_distance_is_the_pair_s_whatever_the_element() {
        let body = [0, 0, 0, 1, 1, 1, 2];
        let spacing = [0.02, 0.02, 0.02, 0.01, 0.01, 0.01, 0.05];
        for nodes in [[0u32, 1, 3], [0, 3, 4], [0, 3, 6]] {
            let g0 = contact_distance(&nodes, (0, 1), &body, &spacing);
            assert!((g0 - 0.015).abs() < 1e-15, "{nodes:?}: {g0}");
        }
        let g0 = contact_distance(&[1, 4, 5, 2], (1, 0), &body, &spacing);
        assert!((g0 - 0.015).abs() < 1e-15);
        // No particle of one of the two: the mean of all.
        let g0 = contact_distance(&[0, 1, 6], (0, 1), &body, &spacing);
        assert!((g0 - 0.03).abs() < 1e-15);
    }
}
