//! Parallel sparse assembly of the monolithic system, eqs. 55–59.
//!
//! The system solved for the velocity `V` at the Picard iterate is eq. 55
//! divided by `Δt`:
//!
//! `(c M + K) V = c M Vⁿ + c_a M Aⁿ − D σ̂⁽ⁿ⁾ + F`
//!
//! with the time scheme's weights `(c, c_a)` ([`Inertia`]): `(2/Δt, 1)` for
//! the trapezoidal Newmark (β = ¼, γ = ½; the paper prints `M Aⁿ/Δt` in
//! eq. 49, dimensional consistency and Newmark's eq. 48 give `M Aⁿ`),
//! Bossak's weights (`pfem-time`), `(1/Δt, 0)` for backward Euler. `M` is
//! the lumped mass per node, each element's `ρ₀ V₀ / (D + 1)` where the
//! mesh gives its reference volume (a solid's, eq. 46,
//! [`StepMesh::reference_volumes`]), else `ρ Vₑⁿ / (D + 1)`.
//!
//! Fluids carry their pressure on nodes (eq. 62). The volumetric term of a
//! fluid is assembled as `Gᵀ M̂⁻¹ 𝒦 G` with the lumped `M̂` of eq. 56 and
//! `G_aj = ∫ W_a grad W_j` (nodal averaged volumetric strain, the default
//! [`VolumetricTreatment::NodalAveraged`]) or element by element as printed
//! in eq. 57 ([`VolumetricTreatment::ElementWise`]). The fluid history force
//! `−D σ̂⁽ⁿ⁾` with `σ̂ = −pⁿ I` is `Gᵀ pⁿ` in both cases.

use pfem_constitutive::{fluid_element_density, History, Material, MaterialKind, Unified};
use pfem_core::{
    below_water_line, weighted_shape_gradients, Const, Dim, Point, Tensor, Vector, MAX_NV,
};
use rayon::prelude::*;

use crate::kernels::{
    element_history_force, element_state, element_stiffness, volumetric_on_element, ElementState,
    VolumetricTreatment, MAX_LOCAL,
};
use crate::pattern::BlockPattern;
use crate::solver::SplitSystem;
use crate::AssemblyError;

const NONE: u32 = u32::MAX;

/// Velocity constraints, per particle and component: wall particles
/// (prescribed velocity, fixed or moving), slip walls (one component),
/// clamped solid nodes (zero velocity).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Constraints<const D: usize>
where
    Const<D>: Dim,
{
    /// Bit `k` set: component `k` of the particle's velocity is prescribed.
    pub mask: Vec<u8>,
    /// Prescribed velocity (m/s); only the masked components are used.
    pub velocity: Vec<Vector<D>>,
}

impl<const D: usize> Constraints<D>
where
    Const<D>: Dim,
{
    /// No constraint on any of `n` particles.
    pub fn free(n: usize) -> Self {
        Self {
            mask: vec![0; n],
            velocity: vec![Vector::<D>::zeros(); n],
        }
    }

    /// Prescribes the whole velocity of particle `i`.
    pub fn fix(&mut self, i: usize, velocity: Vector<D>) {
        self.mask[i] = (1u8 << D) - 1;
        self.velocity[i] = velocity;
    }

    /// Prescribes component `k` of the velocity of particle `i` (a slip
    /// wall normal to axis `k`).
    ///
    /// # Panics
    ///
    /// When `i` is not a particle of the constraints or `k` is not an axis
    /// (`k ≥ D`).
    pub fn fix_component(&mut self, i: usize, k: usize, value: f64) {
        assert!(k < D, "fix_component: axis {k} of a {D}D velocity");
        self.mask[i] |= 1 << k;
        self.velocity[i][k] = value;
    }

    /// Whether component `k` of particle `i` is prescribed.
    #[inline]
    pub fn is_fixed(&self, i: usize, k: usize) -> bool {
        self.mask[i] & (1 << k) != 0
    }

    /// Whether every component of particle `i` is prescribed.
    #[inline]
    pub fn is_fully_fixed(&self, i: usize) -> bool {
        self.mask[i] == (1u8 << D) - 1
    }
}

/// Time-integration weights of the inertia term, set by the time scheme.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertia {
    /// Factor `c` of `c M` on the left and `c M Vⁿ` on the right (1/s).
    pub mass_factor: f64,
    /// Factor `c_a` of `c_a M Aⁿ` on the right (dimensionless): 1 for
    /// trapezoidal Newmark, 0 for backward Euler, between for Bossak.
    pub acceleration_factor: f64,
    /// How the step's displacement depends on the solved velocity,
    /// `∂Δu/∂Vⁿ⁺¹` (s): `Δt` for backward Euler, `(β/γ) Δt` for the
    /// Newmark family. Handed to the materials as
    /// [`pfem_constitutive::Kinematics::displacement_weight`].
    pub displacement_weight: f64,
}

/// The mesh of one step: all elements (fluid from the tessellation, solid
/// from each solid's own mesh) with their material index. `Default` is the
/// empty mesh: build one as `StepMesh { elements, element_material,
/// ..Default::default() }`.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepMesh<'a> {
    /// Flat connectivity, `D + 1` particle indices per element.
    pub elements: &'a [u32],
    /// Material index (into the materials slice) of each element.
    pub element_material: &'a [u16],
    /// *Closures*: flat simplices (`D + 1` particle indices each) that fill
    /// sealed voids of the fluid mesh (`pfem_geometry::AlphaShape::closures`).
    /// They carry no mass and no viscous or solid stiffness, and are never
    /// checked for inversion; they enter only the nodal pressure terms
    /// (their measure-weighted gradients `V grad W`, finite however flat the
    /// simplex, in the rows `G` of eq. 58 and in `M̂` of eq. 56), so that the
    /// pressure sees the fluid closed across the void. A closure whose nodes
    /// are not all nodes of elements is ignored. Empty in 2D and when the
    /// driver turns closing off.
    pub closures: &'a [u32],
    /// Fluid elements integrated only below their water line (issue 19;
    /// `pfem_geometry::AlphaShape::surface_cuts`). Empty by default.
    pub surface_cuts: SurfaceCuts<'a>,
    /// Reference volume `V₀` (m³; m² in 2D) of the first elements, one
    /// each (a prefix: the solids' elements, which keep their nodes for
    /// the whole run): an element's lumped mass is `ρ₀ V₀` whatever its
    /// volume at `t_n`, since `ρⁿ = ρ₀ / Jⁿ` (eq. 46). The elements after
    /// the prefix (a fluid's, built anew each step, whose density moves
    /// only by `p / K`) weigh `ρ Vⁿ`. Empty by default: every element
    /// weighs `ρ Vⁿ`, so a solid's mass drifted with its volume strain.
    pub reference_volumes: &'a [f64],
    /// Material index of each particle (the elements' indexing), or empty.
    /// Where fluids of different densities meet (oil on water), a fluid
    /// element takes its nodes' majority material for its viscosity and
    /// bulk modulus, but its mass density is
    /// [`pfem_constitutive::fluid_element_density`]'s,
    /// the same for every element of the band between the two fluids'
    /// rows whichever diagonals the tessellation drew. Empty: every
    /// element weighs its material's density.
    pub node_material: &'a [u16],
}

/// Fluid elements that join free-surface particles to a solid
/// above their water line: each is integrated only over its part below the
/// plane normal to `up` through the mean height of its free-surface nodes
/// (`pfem_core::below_water_line`), taken at `xⁿ` so that the part is
/// material within the step. Its mass, viscous
/// stiffness, nodal volume `M̂` and pressure rows `G` (eqs. 56, 58) are the
/// integrals of the element's own linear shape functions over that part,
/// so a hydrostatic pressure balances its weight wherever the wall's nodes
/// lie with respect to the water line.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SurfaceCuts<'a> {
    /// `(element, mask of its free-surface nodes)`, the element indexing
    /// [`StepMesh::elements`], bit `a` for local node `a`.
    pub elements: &'a [(u32, u8)],
    /// The unit vector opposite to gravity (first `D` components used).
    pub up: [f64; 3],
}

/// What the assembly reads at a Picard iterate.
#[derive(Debug, Clone, Copy)]
pub struct AssemblyInput<'a, const D: usize>
where
    Const<D>: Dim,
{
    /// Positions of the iterate `x⁽ⁱ⁾`, per particle.
    pub x: &'a [Point<D>],
    /// Positions at `t_n`, the Updated Lagrangian reference.
    pub x_n: &'a [Point<D>],
    /// Velocity of the iterate `V⁽ⁱ⁾` (for rate-dependent materials).
    pub v: &'a [Vector<D>],
    /// Velocity at `t_n`.
    pub v_n: &'a [Vector<D>],
    /// Acceleration at `t_n`.
    pub a_n: &'a [Vector<D>],
    /// Nodal pressure at `t_n` (Pa); read for nodes of fluid elements.
    pub pressure_n: &'a [f64],
    /// Per element history at `t_n` (solid stress). A fluid element's
    /// entry is not read: its material's `unified` is handed a history
    /// whose `pressure` is the mean of its nodes' `pressure_n` (a fluid's
    /// history is nodal, eq. 62), the rest zero.
    pub element_history: &'a [History<D>],
    /// The materials, indexed by [`StepMesh::element_material`].
    pub materials: &'a [Box<dyn Material<D>>],
    /// Velocity constraints.
    pub constraints: &'a Constraints<D>,
    /// Body force per unit mass (m/s²), `None` when the scene has none.
    pub body_force: Option<Vector<D>>,
    /// External force on each particle (N; N per metre of depth in 2D),
    /// added at its node beside the lumped body force (eq. 59); empty for
    /// none, else one per particle.
    pub external_force: &'a [Vector<D>],
    /// Time step (s).
    pub dt: f64,
    /// Inertia weights of the time scheme.
    pub inertia: Inertia,
}

/// The 3D stabilised pressure increments, `(I + L̃) q = C V − o`, are
/// found by multigrid-preconditioned CG from this many rows, by the sparse
/// factor below (the 3D stabilised system's `block::MULTIGRID_FROM` until
/// session 53, which lowered that one alone).
const INCREMENT_MULTIGRID_FROM: usize = 2_000;

/// A multigrid hierarchy of the stabilised increments' `I + L̃` with what
/// carrying it to the next pattern needs ([`Assembler`]'s `inc_amg`).
struct IncrementHierarchy {
    amg: crate::amg::Amg,
    /// The particle of each row it was last used for.
    ids: Vec<u32>,
    /// Patterns it has been carried over (`u32::MAX`: no more).
    age: u32,
    /// CG iterations of its first solve.
    fresh_iterations: usize,
    /// [`increment_scale`] of the matrix it was built on.
    scale: f64,
}

impl std::fmt::Debug for IncrementHierarchy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("IncrementHierarchy")
            .field("rows", &self.ids.len())
            .field("age", &self.age)
            .field("fresh_iterations", &self.fresh_iterations)
            .finish_non_exhaustive()
    }
}

impl IncrementHierarchy {
    /// The hierarchy on the new matrix `il` whose rows belong to the
    /// particles `ids` (`Amg::with_finest`), under the block solver's
    /// rules (`BlockSolver::carry_steps`): at most
    /// [`crate::block::CARRY_STEPS`] patterns in a row, no more than one
    /// row in twenty new, the scale of `L̃` within a factor 4 of the
    /// hierarchy's (the coarse levels rescaled to it).
    fn carry(self, il: &crate::amg::Csr, ids: &[u32]) -> Option<IncrementHierarchy> {
        if self.age >= crate::block::CARRY_STEPS || self.ids.is_empty() {
            return None;
        }
        let scale = increment_scale(il);
        let drift = crate::block::SCALE_DRIFT;
        if !(scale <= self.scale * drift && scale * drift >= self.scale) {
            return None;
        }
        let rho = scale / self.scale;
        let from = crate::block::rows_from(&self.ids, ids)?;
        Some(IncrementHierarchy {
            amg: self.amg.with_finest(il, &from, rho)?,
            ids: Vec::new(),
            age: self.age + 1,
            fresh_iterations: self.fresh_iterations,
            scale: self.scale,
        })
    }
}

/// The mean diagonal of `L̃` in `I + L̃`: the scale of the pressure
/// Laplacian against the identity, which the time step sets.
fn increment_scale(il: &crate::amg::Csr) -> f64 {
    let sum: f64 = il.diagonal().iter().map(|d| d - 1.0).sum();
    sum / il.nrows.max(1) as f64
}
/// What is wrong with an element at the iterate (the assembly's first
/// failure in element order).
#[derive(Debug, Clone)]
enum Bad {
    /// Degenerate or inverted: a smaller step may cure it.
    Inverted,
    /// Its material returned a non-number.
    NonFinite,
    /// Its material returned what no step size cures.
    Invalid(&'static str),
    /// Its material panicked (the message).
    Panicked(String),
}

/// Whether `σ̂` (with its out-of-plane `σ̂_zz` in 2D) is isotropic, to a
/// relative 10⁻¹², the sum of its diagonal's three terms rounded.
fn isotropic<const D: usize>(sigma_hat: &Tensor<D>, zz: f64) -> bool
where
    Const<D>: Dim,
{
    let scale = sigma_hat.amax().max(zz.abs());
    if scale == 0.0 {
        return true;
    }
    let tr = sigma_hat.trace() + if D == 2 { zz } else { 0.0 };
    let mean = tr / 3.0;
    let tol = 1e-12 * scale;
    (0..D).all(|i| {
        (0..D).all(|j| {
            let dev = sigma_hat[(i, j)] - if i == j { mean } else { 0.0 };
            dev.abs() <= tol
        })
    }) && (D == 3 || (zz - mean).abs() <= tol)
}

/// Relative residual at which that CG stops; the sparse factor it replaces
/// reaches about 10⁻¹⁴.
const INCREMENT_TOLERANCE: f64 = 1e-12;
/// Iteration limit of that CG (then the factor is used).
const INCREMENT_MAX_ITERATIONS: usize = 200;

/// Assembles the monolithic system on one step's mesh. The pattern and all
/// index maps are built once per step by [`Assembler::prepare`]; each Picard
/// iteration then refills the values with [`Assembler::assemble`].
#[derive(Debug, Default)]
pub struct Assembler<const D: usize>
where
    Const<D>: Dim,
{
    /// How the volumetric term is integrated
    /// ([`Assembler::set_treatment`]).
    treatment: VolumetricTreatment,
    n_particles: usize,
    n_elements: usize,
    /// particle → system node (NONE if in no element).
    sys_of: Vec<u32>,
    /// system node → particle.
    particle_of: Vec<u32>,
    /// Element connectivity in system node numbers.
    elem_sys: Vec<u32>,
    elem_material: Vec<u16>,
    /// Each element's mass density (kg/m³): its material's, or for a
    /// fluid element with `StepMesh::node_material`,
    /// [`pfem_constitutive::fluid_element_density`].
    elem_density: Vec<f64>,
    /// Whether each element is a fluid element (pressure on nodes).
    elem_fluid: Vec<bool>,
    /// Whether each element's volumetric term is assembled on it.
    elem_vol: Vec<bool>,
    pattern: BlockPattern,
    generation: u64,
    /// The mesh of the last `prepare` (elements, materials, closures,
    /// particle count), to keep the pattern when it has not changed.
    last_mesh: (Vec<u32>, Vec<u16>, Vec<u32>, usize),
    work: AssemblerWork,
    /// NV² block positions per element, row node a, column node b.
    elem_blocks: Vec<u32>,
    /// Nodal patches: for each system node a in a fluid element, the
    /// system nodes of its fluid elements.
    patch_ptr: Vec<usize>,
    patch_nodes: Vec<u32>,
    /// NV² slots per element: slot of node b in patch(a).
    elem_slots: Vec<u32>,
    /// P_a² block positions per patch, row i, column j.
    patch_block_ptr: Vec<usize>,
    /// Block position of each system node's diagonal block.
    diag_block: Vec<u32>,
    patch_blocks: Vec<u32>,
    /// Fluid material of each patch node (first fluid element seen).
    node_fluid_material: Vec<u16>,
    /// Whether each patch node touches fluid elements of two materials or
    /// more, and whether any does.
    node_mixed: Vec<bool>,
    any_mixed: bool,
    /// At such nodes, filled by [`Assembler::mixed_fluid_shares`]:
    /// (particle, material, its share of `M̂_a`), by particle.
    mixed_shares: Vec<(u32, u16, f64)>,
    /// Closure connectivity in system node numbers (see
    /// [`StepMesh::closures`]) and NV² patch slots per closure.
    clo_sys: Vec<u32>,
    clo_slots: Vec<u32>,
    /// Per closure: `V grad W` of its nodes and `V`, at the iterate.
    clo_w: Vec<[Vector<D>; MAX_NV]>,
    clo_vol: Vec<f64>,
    /// Surface cuts ([`StepMesh::surface_cuts`]): per element its cut
    /// (NONE when whole), the cuts, `up`, and per cut the share below the
    /// water line with its centroid's barycentric coordinates at `t_n`.
    cut_of: Vec<u32>,
    cuts: Vec<(u32, u8)>,
    cut_up: [f64; 3],
    cut_share: Vec<(f64, [f64; MAX_NV])>,
    /// [`StepMesh::reference_volumes`] of the step.
    ref_vol: Vec<f64>,
    // Per-iteration values.
    values: Vec<f64>,
    rhs: Vec<f64>,
    mass: Vec<f64>,
    vol_hat: Vec<f64>,
    kappa_hat: Vec<f64>,
    w: Vec<Vector<D>>,
    states: Vec<ElementState<D>>,
    unified: Vec<Unified<D>>,
    /// The elements with a node in each part of the parallel scatter, in
    /// order (`part_elems[part_ptr[k]..part_ptr[k + 1]]`), for the
    /// pattern generation and node ranges in `part_key`.
    part_ptr: Vec<usize>,
    part_elems: Vec<u32>,
    part_key: (u64, Vec<usize>),
    /// Whether the nodal volumetric term is kept apart as `Cᵀ C`
    /// ([`Assembler::set_split`]).
    split: bool,
    /// Split form: the rows of `C` (one per system node with a nodal
    /// patch), CSR over dofs; row `r` belongs to system node
    /// `c_node[r]`; node `a`'s row is `c_row[a]` (NONE without a patch).
    c_node: Vec<u32>,
    /// The particle of each row of `C` (`particle_of[c_node[r]]`): the
    /// rows' identities across patterns
    /// ([`crate::solver::Stabilisation::row_ids`]).
    c_particle: Vec<u32>,
    /// Whether `c_particle` names the same particles as the last pattern's
    /// rows did (false on the first pattern after
    /// [`Assembler::particles_renumbered`]).
    ids_valid: bool,
    /// [`Assembler::particles_renumbered`] was called since the last
    /// [`Assembler::prepare`].
    renumbered: bool,
    /// The last [`Assembler::prepare`] failed: nothing is assembled until
    /// one succeeds.
    failed_prepare: bool,
    c_row: Vec<u32>,
    c_ptr: Vec<usize>,
    c_idx: Vec<usize>,
    c_val: Vec<f64>,
    /// System node coordinates of the last assembly, `D` per node.
    coords: Vec<f64>,
    /// Pressure stabilisation factor `α` of `τ` (0: off;
    /// [`Assembler::set_pressure_stabilisation`]).
    stabilisation: f64,
    /// Quality below which a fluid element is integrated on its geometry
    /// at `tⁿ` ([`Assembler::set_sliver_quality`]; 0: never).
    sliver_quality: f64,
    /// Also integrate on its geometry at `tⁿ` a fluid element whose
    /// quality at the step's predicted end is below `sliver_quality`
    /// ([`Assembler::set_sliver_prediction`]).
    sliver_prediction: bool,
    /// A sliver kept in shape whose quality at `tⁿ` is at least this
    /// carries the pressure stabilisation on that shape; `None`: no sliver
    /// does ([`Assembler::set_sliver_stabilisation`]).
    sliver_stabilised_from: Option<f64>,
    /// Per element: integrated on its geometry at `tⁿ`, decided at the
    /// step's first assembly (`prepare`, `set_sliver_quality` and
    /// `set_sliver_prediction` clear it), and then its signed measure and `V grad W` at the iterate,
    /// which its volumetric terms use.
    frozen: Vec<bool>,
    frozen_w: Vec<(f64, [Vector<D>; MAX_NV])>,
    /// Per element, decided with `frozen`: kept in shape and carrying no
    /// pressure stabilisation ([`Assembler::set_sliver_stabilisation`]).
    frozen_bare: Vec<bool>,
    /// Per element, decided with `frozen`: a fluid element's mean nodal
    /// pressure at `tⁿ`, which its material's `unified` is handed (the
    /// same at every iterate of a step: found once, not at each).
    mean_pressure: Vec<f64>,
    /// Per particle: a node of a solid element of the mesh
    /// ([`Assembler::is_solid_particle`]).
    in_solid: Vec<bool>,
    /// Stabilised split form: `L̃` (CSR over the rows of `C`, laid out as
    /// the nodal patches, so that an element's `elem_slots` index its
    /// values; built with the pattern), the offset `o` of the second row,
    /// the fixed velocities' part `c₀` of `C V`.
    l_ptr: Vec<usize>,
    l_idx: Vec<usize>,
    l_val: Vec<f64>,
    c_offset: Vec<f64>,
    c_fixed: Vec<f64>,
    /// Scratch of the stabilisation: nodal projection of `grad pⁿ` and its
    /// weights.
    stab_pi: Vec<Vector<D>>,
    stab_weight: Vec<f64>,
    /// Scratch of the stabilisation: per element `τ V`, `grad pⁿ` and `V`
    /// (kept for its allocation: tens of megabytes at 10⁶ elements,
    /// written at every Picard iterate).
    stab_per: Vec<Option<(f64, Vector<D>, f64)>>,
    /// Scratch of the nodal patches' unsorted lists (kept for its
    /// allocation: about 16 entries a tetrahedron, every step).
    patch_scratch: Vec<u32>,
    /// The factor of `I + L̃` ([`Assembler::stabilised_pressure_increments`]).
    l_factor: crate::block::QuasiDefinite,
    /// 3D: the multigrid hierarchy of the last `I + L̃` (CG for the
    /// stabilised increments), carried over to the next pattern as the
    /// block solver carries its own (`BlockSolver::carry_steps`): the
    /// hierarchy, its rows' particles, the patterns it has been carried
    /// over, and the most CG iterations it took when new.
    inc_amg: Option<IncrementHierarchy>,
}

/// Work an [`Assembler`] has done.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AssemblerWork {
    /// Calls of [`Assembler::prepare`].
    pub prepares: u64,
    /// Sparsity patterns built (a prepare on an unchanged mesh keeps the
    /// last one).
    pub patterns_built: u64,
    /// Elements assembled, summed over [`Assembler::assemble`] calls.
    pub elements_assembled: u64,
}

/// Figures of one assembly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AssemblyInfo {
    /// Unknowns of the system.
    pub dofs: usize,
    /// Stored nonzeros.
    pub nnz: usize,
}

impl<const D: usize> Assembler<D>
where
    Const<D>: Dim,
{
    /// A new assembler using `treatment` for the volumetric term.
    pub fn new(treatment: VolumetricTreatment) -> Self {
        Self {
            treatment,
            ..Default::default()
        }
    }

    /// How the volumetric term is integrated.
    pub fn treatment(&self) -> VolumetricTreatment {
        self.treatment
    }

    /// Integrates the volumetric term by `treatment` from the next
    /// [`Assembler::prepare`] on (which builds its pattern anew if it
    /// changed: each element's volumetric term is chosen there).
    pub fn set_treatment(&mut self, treatment: VolumetricTreatment) {
        if treatment != self.treatment {
            self.treatment = treatment;
            self.last_mesh.3 = usize::MAX;
        }
    }

    /// The work done so far.
    pub fn work(&self) -> AssemblerWork {
        self.work
    }

    /// Keeps the nodal volumetric term (eq. 56, `Gᵀ M̂⁻¹ 𝒦 G`) out of the
    /// matrix and apart as `Cᵀ C`, `C = (𝒦/M̂)^{1/2} G` with one row per
    /// fluid node ([`Assembler::split_system`]), for solvers that treat it
    /// as a second field ([`crate::LinearSolver::wants_split`]). The matrix
    /// then holds only the element couplings, so its pattern is the mesh's
    /// and not its neighbours' neighbours'. Takes effect at the next
    /// [`Assembler::prepare`].
    pub fn set_split(&mut self, on: bool) {
        if on != self.split {
            self.split = on;
            self.last_mesh.3 = usize::MAX;
        }
    }

    /// Slivers (ARCHITECTURE.md deviation 13): a fluid element whose
    /// quality `measure / R^D` at `tⁿ` (`R` its circumradius; 0.51 for the
    /// regular tetrahedron, 1.30 for the equilateral triangle) is below
    /// `q` is integrated on its geometry at `tⁿ` (`F = I`, its gradients,
    /// measure and unified triple there) instead of the iterate's, so that
    /// a motion flattening it through zero (which a nearly flat
    /// tetrahedron's tiny height makes likely) cannot invert the
    /// assembly. Its volumetric terms (its rows of `G` and its share of
    /// `M̂`, eq. 56) stay the iterate's, from `V grad W` and the signed `V`,
    /// which are finite through zero volume (as for closures): the nodal
    /// volumetric strain rate stays exact for affine motions (the patch
    /// test) and the water's stiffness sees the volume it conserves. The
    /// next remeshing replaces the element. In 2D an element with a
    /// particle of a solid element is never kept in shape: a film of water
    /// between two bodies must be squeezed out, which needs its flattened
    /// elements to reject the step (a heavy box in water stopped on its
    /// film with them kept, `tests/stability_fsi.rs`). Not in 3D, whose
    /// contact tests pass without it and where it cost the column on a
    /// cylinder at a/14 29 rejected attempts in 486 steps against 4 in 437
    /// (ARCHITECTURE.md deviation 13). `0` (or not finite) turns it off.
    /// Takes effect at the next [`Assembler::assemble`].
    pub fn set_sliver_quality(&mut self, q: f64) {
        let q = if q.is_finite() && q > 0.0 { q } else { 0.0 };
        if q != self.sliver_quality {
            self.sliver_quality = q;
            self.frozen.clear();
        }
    }

    /// Slivers foreseen (ARCHITECTURE.md deviation 13): with `on`, a fluid
    /// element is also treated as a sliver ([`Assembler::set_sliver_quality`])
    /// when its quality at the step's predicted end, the particles moved
    /// to `xⁿ + Δt vⁿ + ½ Δt² aⁿ`, is below the sliver quality (an
    /// element predicted to invert has quality 0). Those are the elements
    /// that otherwise invert within the step and reject it: a tetrahedron
    /// of fair shape at `tⁿ` that the flow squeezes flat. Decided, as the
    /// slivers are, at the step's first assembly. Default off here;
    /// `pfem_time::StepParams::sliver_prediction` turns it on.
    pub fn set_sliver_prediction(&mut self, on: bool) {
        if on != self.sliver_prediction {
            self.sliver_prediction = on;
            self.frozen.clear();
        }
    }

    /// Which slivers kept in shape ([`Assembler::set_sliver_quality`])
    /// carry the pressure stabilisation
    /// ([`Assembler::set_pressure_stabilisation`]): with `Some(q)`, those
    /// whose quality at `tⁿ` is at least `q`, on their shape at `tⁿ`
    /// (where they are integrated; the term still vanishes for a linear
    /// pressure); the flatter ones carry none, nor does any with `None`
    /// (the default). A sliver foreseen to flatten within the step
    /// ([`Assembler::set_sliver_prediction`]) is often of fair shape at
    /// `tⁿ`; left without the term, the regions a violent flow deforms
    /// lose it, and the pressure multigrid with them: on the stabilised
    /// 3D water column at a/20 after its impact on the wall, GMRES took
    /// 22–38 iterations a solve with none carrying it, 10–12 with `0.02`
    /// (`docs/benchmarks.md`, session 30). `pfem_time::StepParams::sliver_stabilised_3d`
    /// sets it in 3D. A `q` that is not a number is `None`. Takes effect
    /// at the next [`Assembler::assemble`].
    pub fn set_sliver_stabilisation(&mut self, q: Option<f64>) {
        let q = q.filter(|q| !q.is_nan());
        if q != self.sliver_stabilised_from {
            self.sliver_stabilised_from = q;
            self.frozen.clear();
        }
    }

    /// Whether element `e` was integrated on its geometry at `tⁿ` in the
    /// last assembly ([`Assembler::set_sliver_quality`]).
    pub fn is_frozen(&self, e: usize) -> bool {
        self.frozen.get(e).copied().unwrap_or(false)
    }

    /// Whether particle `p` is a node of a solid element of the mesh of
    /// the last [`Assembler::prepare`].
    pub fn is_solid_particle(&self, p: usize) -> bool {
        self.in_solid.get(p).copied().unwrap_or(false)
    }

    /// Whether the nodal volumetric term is kept apart.
    pub fn is_split(&self) -> bool {
        self.split
    }

    /// Pressure stabilisation (ARCHITECTURE.md deviation 12): with
    /// `alpha > 0` the nodal pressure of the fluid solves the stabilised
    /// continuity equation
    ///
    /// `(M̂/𝒦) Δp + τ L Δp = −G V − τ (L pⁿ − P π)`,
    ///
    /// `L_ab = Σₑ τₑ ∫ ∇W_a·∇W_b` over the fluid elements with the
    /// intrinsic time `τₑ = α / (c ρ + 8 μ / hₑ²)` (`c` the scheme's mass
    /// factor, about `2/Δt`; `hₑ = (D! Vₑ)^{1/D}`), and `π` the lumped nodal
    /// projection of `grad pⁿ`, so that the term vanishes for a pressure
    /// linear in space (hydrostatics) and the scheme stays consistent (an
    /// orthogonal-subscale, time-lagged projection). A sliver kept in
    /// shape ([`Assembler::set_sliver_quality`]) is left out of `L` and `π`
    /// unless [`Assembler::set_sliver_stabilisation`] keeps it:
    /// on a nearly flat tetrahedron `∫ ∇W_a·∇W_b` grows as the inverse of
    /// its height with couplings of the wrong sign, which stalled the
    /// pressure multigrid of a running 3D flow. The system is then
    /// the saddle-point form of [`SplitSystem::stabilisation`]; it needs the
    /// split assembly, which this turns on. `0` (the default) is the paper's
    /// `Δp = −(𝒦/M̂) G V`. Takes effect at the next [`Assembler::prepare`].
    pub fn set_pressure_stabilisation(&mut self, alpha: f64) {
        let alpha = if alpha.is_finite() && alpha > 0.0 {
            alpha
        } else {
            0.0
        };
        if alpha != self.stabilisation {
            self.stabilisation = alpha;
            if alpha > 0.0 {
                self.set_split(true);
            }
            self.last_mesh.3 = usize::MAX;
        }
    }

    /// The particles' indices changed since the last step (particles
    /// removed or inserted, a restored checkpoint): the next pattern's rows
    /// name no particles ([`crate::solver::Stabilisation::row_ids`] is
    /// `None`), so that no solver carries a preconditioner across the
    /// renumbering, and the stabilised increments' carried hierarchy is
    /// dropped. `pfem-driver` calls it whenever its particle set's
    /// generation changed.
    pub fn particles_renumbered(&mut self) {
        self.renumbered = true;
        self.inc_amg = None;
    }

    /// Whether the pressure is stabilised (and so the assembly split).
    pub fn is_stabilised(&self) -> bool {
        self.split && self.stabilisation > 0.0
    }

    /// The last assembled system in split form, `(A_v + Cᵀ C) V = f`, or
    /// `None` when the assembler is not split ([`Assembler::set_split`]).
    pub fn split_system(&self) -> Option<SplitSystem<'_>> {
        if !self.split {
            return None;
        }
        Some(SplitSystem {
            a_v: self.matrix(),
            c_ptr: &self.c_ptr,
            c_idx: &self.c_idx,
            c_val: &self.c_val,
            block_size: D,
            coords: &self.coords,
            rhs: &self.rhs,
            stabilisation: self
                .is_stabilised()
                .then_some(crate::solver::Stabilisation {
                    l_ptr: &self.l_ptr,
                    l_idx: &self.l_idx,
                    l_val: &self.l_val,
                    offset: &self.c_offset,
                    row_ids: self.ids_valid.then_some(&self.c_particle[..]),
                }),
        })
    }

    /// Builds the pattern and index maps for the mesh of a step; keeps them
    /// (and the pattern's [`Assembler::generation`], so a direct solver
    /// keeps its symbolic analysis) when the mesh is the one of the last
    /// call, as in a scene without a fluid, which never remeshes.
    pub fn prepare(
        &mut self,
        n_particles: usize,
        mesh: StepMesh<'_>,
        materials: &[Box<dyn Material<D>>],
    ) -> Result<(), AssemblyError> {
        self.work.prepares += 1;
        // Checked before anything changes (the last mesh stays usable).
        let ne = mesh.elements.len() / <Const<D> as Dim>::NV;
        let refs = mesh.reference_volumes;
        if refs.len() > ne {
            return Err(AssemblyError::MeshMismatch {
                what: "more reference volumes than elements",
            });
        }
        if refs.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(AssemblyError::MeshMismatch {
                what: "a reference volume that is not a positive number",
            });
        }
        if !mesh.node_material.is_empty() && mesh.node_material.len() != n_particles {
            return Err(AssemblyError::MeshMismatch {
                what: "node materials and particles have different lengths",
            });
        }
        let renumbered = std::mem::take(&mut self.renumbered);
        if renumbered {
            self.ids_valid = false;
        }
        // Which elements are slivers depends on `xⁿ` (and, foreseen, on
        // `vⁿ`, `aⁿ` and `Δt`): decided again at the first assembly of
        // this attempt.
        self.frozen.clear();
        if let Err(e) = self.set_cuts(
            mesh.elements.len() / <Const<D> as Dim>::NV,
            mesh.surface_cuts,
        ) {
            // The cut tables are half written: nothing is assembled until
            // a `prepare` succeeds, and the next builds anew.
            self.failed_prepare = true;
            self.last_mesh.3 = usize::MAX;
            return Err(e);
        }
        self.ref_vol.clear();
        self.ref_vol.extend_from_slice(mesh.reference_volumes);
        let (ref le, ref lm, ref lc, ln) = self.last_mesh;
        if self.work.patterns_built > 0
            && ln == n_particles
            && le.as_slice() == mesh.elements
            && lm.as_slice() == mesh.element_material
            && lc.as_slice() == mesh.closures
            && mesh
                .element_material
                .iter()
                .all(|&m| (m as usize) < materials.len())
        {
            // (The particles' materials may have changed.)
            self.set_densities(&mesh, materials);
            self.failed_prepare = false;
            return Ok(());
        }
        // Forget the last mesh first: a failed build must not be reused.
        self.last_mesh.3 = usize::MAX;
        // The last assembly's element states belong to the last mesh: an
        // internal force asked before the next assembly is refused
        // (session 42's review: it returned the old mesh's states on the
        // new connectivity).
        self.states.clear();
        self.unified.clear();
        if let Err(e) = self.prepare_new(n_particles, mesh, materials) {
            // Nothing half-built may be assembled (session 35's review: it
            // indexed the half-built maps; session 42's: an empty input
            // then met the last pattern and panicked): every assembly is
            // refused until a `prepare` succeeds.
            self.n_particles = 0;
            self.n_elements = 0;
            self.particle_of.clear();
            self.failed_prepare = true;
            return Err(e);
        }
        self.failed_prepare = false;
        self.ids_valid = !renumbered;
        self.work.patterns_built += 1;
        let last = &mut self.last_mesh;
        last.0.clear();
        last.0.extend_from_slice(mesh.elements);
        last.1.clear();
        last.1.extend_from_slice(mesh.element_material);
        last.2.clear();
        last.2.extend_from_slice(mesh.closures);
        last.3 = n_particles;
        Ok(())
    }

    /// Each element's mass density: its material's, a fluid element's
    /// from its nodes' fluids where the mesh gives the particles'
    /// materials ([`pfem_constitutive::fluid_element_density`]).
    fn set_densities(&mut self, mesh: &StepMesh<'_>, materials: &[Box<dyn Material<D>>]) {
        let nv = <Const<D> as Dim>::NV;
        self.elem_density.clear();
        self.elem_density.extend(
            mesh.element_material
                .iter()
                .zip(mesh.elements.chunks_exact(nv))
                .map(|(&m, el)| {
                    let mat = &materials[m as usize];
                    if mat.kind() == MaterialKind::Fluid && !mesh.node_material.is_empty() {
                        fluid_element_density(
                            materials,
                            el.iter().map(|&p| mesh.node_material[p as usize]),
                            m,
                        )
                    } else {
                        mat.density()
                    }
                }),
        );
    }

    /// Records the surface cuts of a step's mesh.
    fn set_cuts(&mut self, ne: usize, cuts: SurfaceCuts<'_>) -> Result<(), AssemblyError> {
        self.cut_of.clear();
        self.cuts.clear();
        self.cut_share.clear();
        if cuts.elements.is_empty() {
            return Ok(());
        }
        self.cut_of.resize(ne, NONE);
        for (k, &(e, mask)) in cuts.elements.iter().enumerate() {
            if e as usize >= ne || mask == 0 || mask >> <Const<D> as Dim>::NV != 0 {
                return Err(AssemblyError::MeshMismatch {
                    what: "a surface cut names no element or no node of it",
                });
            }
            self.cut_of[e as usize] = k as u32;
        }
        self.cuts.extend_from_slice(cuts.elements);
        self.cut_up = cuts.up;
        Ok(())
    }

    /// The share of element `e` that is integrated (1 unless cut).
    #[inline]
    fn share(&self, e: usize) -> f64 {
        cut_part(&self.cut_of, &self.cut_share, e).map_or(1.0, |(share, _)| share)
    }

    fn prepare_new(
        &mut self,
        n_particles: usize,
        mesh: StepMesh<'_>,
        materials: &[Box<dyn Material<D>>],
    ) -> Result<(), AssemblyError> {
        let nv = <Const<D> as Dim>::NV;
        if !mesh.elements.len().is_multiple_of(nv)
            || mesh.elements.len() / nv != mesh.element_material.len()
        {
            return Err(AssemblyError::MeshMismatch {
                what: "element connectivity and element materials have different lengths",
            });
        }
        let ne = mesh.element_material.len();
        self.n_particles = n_particles;
        self.n_elements = ne;
        // System nodes.
        self.sys_of.clear();
        self.sys_of.resize(n_particles, NONE);
        self.particle_of.clear();
        for &p in mesh.elements {
            let p = p as usize;
            if p >= n_particles {
                return Err(AssemblyError::MeshMismatch {
                    what: "element refers to a particle that does not exist",
                });
            }
            if self.sys_of[p] == NONE {
                self.sys_of[p] = self.particle_of.len() as u32;
                self.particle_of.push(p as u32);
            }
        }
        let ns = self.particle_of.len();
        if !mesh.closures.len().is_multiple_of(nv) {
            return Err(AssemblyError::MeshMismatch {
                what: "closure connectivity is not a whole number of simplices",
            });
        }
        // Closures count only where all their nodes are element nodes.
        self.clo_sys.clear();
        for c in mesh.closures.chunks_exact(nv) {
            if c.iter()
                .all(|&p| (p as usize) < n_particles && self.sys_of[p as usize] != NONE)
            {
                self.clo_sys
                    .extend(c.iter().map(|&p| self.sys_of[p as usize]));
            }
        }
        self.elem_sys.clear();
        self.elem_sys
            .extend(mesh.elements.iter().map(|&p| self.sys_of[p as usize]));
        self.elem_material.clear();
        self.elem_material.extend_from_slice(mesh.element_material);
        self.elem_fluid.clear();
        self.elem_vol.clear();
        self.in_solid.clear();
        self.in_solid.resize(n_particles, false);
        for (&m, el) in mesh
            .element_material
            .iter()
            .zip(mesh.elements.chunks_exact(nv))
        {
            let mat = materials
                .get(m as usize)
                .ok_or(AssemblyError::MeshMismatch {
                    what: "element refers to a material that does not exist",
                })?;
            let kind = mat.kind();
            self.elem_fluid.push(kind == MaterialKind::Fluid);
            if kind == MaterialKind::Solid {
                for &p in el {
                    self.in_solid[p as usize] = true;
                }
            }
            self.elem_vol
                .push(volumetric_on_element(kind, self.treatment));
        }
        self.set_densities(&mesh, materials);
        // Nodal patches of fluid elements.
        let mut count = vec![0usize; ns + 1];
        for e in 0..ne {
            if self.elem_fluid[e] {
                for &a in &self.elem_sys[e * nv..(e + 1) * nv] {
                    count[a as usize] += nv;
                }
            }
        }
        for c in self.clo_sys.chunks_exact(nv) {
            for &a in c {
                count[a as usize] += nv;
            }
        }
        let mut ptr = vec![0usize; ns + 1];
        for a in 0..ns {
            ptr[a + 1] = ptr[a] + count[a];
        }
        let mut fill = ptr.clone();
        let mut raw = std::mem::take(&mut self.patch_scratch);
        raw.clear();
        raw.resize(ptr[ns], 0);
        self.node_fluid_material.clear();
        self.node_fluid_material.resize(ns, u16::MAX);
        self.node_mixed.clear();
        self.node_mixed.resize(ns, false);
        self.any_mixed = false;
        for e in 0..ne {
            if self.elem_fluid[e] {
                let el = &self.elem_sys[e * nv..(e + 1) * nv];
                for &a in el {
                    let a = a as usize;
                    raw[fill[a]..fill[a] + nv].copy_from_slice(el);
                    fill[a] += nv;
                    if self.node_fluid_material[a] == u16::MAX {
                        self.node_fluid_material[a] = self.elem_material[e];
                    } else if self.node_fluid_material[a] != self.elem_material[e] {
                        self.node_mixed[a] = true;
                        self.any_mixed = true;
                    }
                }
            }
        }
        for c in self.clo_sys.chunks_exact(nv) {
            for &a in c {
                let a = a as usize;
                raw[fill[a]..fill[a] + nv].copy_from_slice(c);
                fill[a] += nv;
            }
        }
        self.patch_ptr.clear();
        self.patch_ptr.push(0);
        self.patch_nodes.clear();
        for a in 0..ns {
            let row = &mut raw[ptr[a]..ptr[a + 1]];
            row.sort_unstable();
            let start = self.patch_nodes.len();
            for &j in row.iter() {
                if self.patch_nodes.len() == start || *self.patch_nodes.last().unwrap() != j {
                    self.patch_nodes.push(j);
                }
            }
            self.patch_ptr.push(self.patch_nodes.len());
        }
        self.patch_scratch = raw;
        // Pattern: element couplings, plus patch × patch for the nodal
        // volumetric term and the pressure coupling.
        let (elem_sys, patch_ptr, patch_nodes) =
            (&self.elem_sys, &self.patch_ptr, &self.patch_nodes);
        let split = self.split;
        self.pattern.build(ns, D, |visit| {
            for el in elem_sys.chunks_exact(nv) {
                visit(el);
            }
            if split {
                return;
            }
            for a in 0..ns {
                let p = &patch_nodes[patch_ptr[a]..patch_ptr[a + 1]];
                if !p.is_empty() {
                    visit(p);
                }
            }
        });
        self.generation += 1;
        // Block positions and patch slots are stored as `u32` (half the
        // memory of the element tables): past 2³² they would wrap into
        // other entries without a word (about 6·10⁷ nodes in 3D with the
        // unsplit pattern). Refused instead (session 42's review).
        if self.pattern.adj_idx.len() >= NONE as usize || self.patch_nodes.len() >= NONE as usize {
            return Err(AssemblyError::MeshMismatch {
                what: "the system has 2³² node-pair blocks or more, past what the assembly's 32-bit tables index",
            });
        }
        // Block positions.
        self.elem_blocks.clear();
        self.elem_slots.clear();
        for e in 0..ne {
            let el = &self.elem_sys[e * nv..(e + 1) * nv];
            for &a in el {
                for &b in el {
                    self.elem_blocks
                        .push(self.pattern.block(a, b).expect("element pair in pattern"));
                    let slot = if self.elem_fluid[e] {
                        let p = &self.patch_nodes
                            [self.patch_ptr[a as usize]..self.patch_ptr[a as usize + 1]];
                        (self.patch_ptr[a as usize]
                            + p.binary_search(&b).expect("patch holds element"))
                            as u32
                    } else {
                        NONE
                    };
                    self.elem_slots.push(slot);
                }
            }
        }
        self.clo_slots.clear();
        for c in self.clo_sys.chunks_exact(nv) {
            for &a in c {
                let p =
                    &self.patch_nodes[self.patch_ptr[a as usize]..self.patch_ptr[a as usize + 1]];
                for &b in c {
                    self.clo_slots.push(
                        (self.patch_ptr[a as usize]
                            + p.binary_search(&b).expect("patch holds closure"))
                            as u32,
                    );
                }
            }
        }
        self.patch_block_ptr.clear();
        self.patch_block_ptr.push(0);
        self.patch_blocks.clear();
        self.c_node.clear();
        self.c_particle.clear();
        self.c_row.clear();
        self.c_ptr.clear();
        self.c_idx.clear();
        if self.split {
            // Rows of `C`: a node's patch, D dofs per patch node.
            self.c_row.resize(ns, NONE);
            self.c_ptr.push(0);
            for a in 0..ns {
                let p = &self.patch_nodes[self.patch_ptr[a]..self.patch_ptr[a + 1]];
                if p.is_empty() {
                    continue;
                }
                self.c_row[a] = self.c_node.len() as u32;
                self.c_node.push(a as u32);
                self.c_particle.push(self.particle_of[a]);
                for &i in p {
                    self.c_idx.extend((0..D).map(|k| i as usize * D + k));
                }
                self.c_ptr.push(self.c_idx.len());
            }
            self.c_val.resize(self.c_idx.len(), 0.0);
            let m = self.c_node.len();
            self.c_fixed.clear();
            self.c_fixed.resize(m, 0.0);
            self.c_offset.clear();
            self.c_offset.resize(m, 0.0);
            // `L̃` couples a node to its patch: the patches' layout, with
            // the rows of `C` for columns (a patch node always has one).
            self.l_ptr.clear();
            self.l_ptr
                .extend(self.c_node.iter().map(|&a| self.patch_ptr[a as usize]));
            self.l_ptr.push(self.patch_ptr[ns]);
            self.l_idx.clear();
            self.l_idx.extend(
                self.patch_nodes
                    .iter()
                    .map(|&b| self.c_row[b as usize] as usize),
            );
            self.l_val.clear();
            self.l_val.resize(self.l_idx.len(), 0.0);
        }
        for a in 0..ns {
            if self.split {
                self.patch_block_ptr.push(0);
                continue;
            }
            let p = &self.patch_nodes[self.patch_ptr[a]..self.patch_ptr[a + 1]];
            for &i in p {
                for &j in p {
                    self.patch_blocks
                        .push(self.pattern.block(i, j).expect("patch pair in pattern"));
                }
            }
            self.patch_block_ptr.push(self.patch_blocks.len());
        }
        self.diag_block.clear();
        self.diag_block
            .extend((0..ns as u32).map(|a| self.pattern.block(a, a).expect("diagonal block")));
        self.values.resize(self.pattern.nnz(), 0.0);
        self.rhs.resize(self.pattern.dofs(), 0.0);
        Ok(())
    }

    /// Fills the matrix and right-hand side at the iterate described by
    /// `input` (eqs. 55–59 with the corrections stated in the module docs).
    pub fn assemble(
        &mut self,
        input: &AssemblyInput<'_, D>,
    ) -> Result<AssemblyInfo, AssemblyError> {
        if self.failed_prepare {
            return Err(AssemblyError::MeshMismatch {
                what: "the last prepare failed: prepare a mesh before assembling",
            });
        }
        let nv = <Const<D> as Dim>::NV;
        let ne = self.n_elements;
        let n_local = nv * D;
        let n = self.n_particles;
        if [input.x, input.x_n].iter().any(|a| a.len() != n)
            || [input.v, input.v_n, input.a_n].iter().any(|a| a.len() != n)
            || input.pressure_n.len() != n
            || input.element_history.len() != ne
        {
            return Err(AssemblyError::MeshMismatch {
                what: "assembly input does not match the prepared mesh",
            });
        }
        // The constraints index every particle, the materials every
        // element's material (a `Constraints::default()`, or a shorter
        // material list than the mesh's, panicked in the scatter).
        if input.constraints.mask.len() != n || input.constraints.velocity.len() != n {
            return Err(AssemblyError::MeshMismatch {
                what: "the constraints do not have one entry per particle",
            });
        }
        if self.elem_material[..ne.min(self.elem_material.len())]
            .iter()
            .any(|&m| m as usize >= input.materials.len())
        {
            return Err(AssemblyError::MeshMismatch {
                what: "an element's material index is beyond the materials given",
            });
        }
        self.work.elements_assembled += ne as u64;
        // 1. Element states and unified triples, in parallel.
        let elem_sys = &self.elem_sys;
        let particle_of = &self.particle_of;
        let mut states = std::mem::take(&mut self.states);
        let mut unified = std::mem::take(&mut self.unified);
        states.resize(ne, dummy_state());
        unified.resize(ne, Unified::new(0.0, 0.0, Tensor::<D>::zeros(), 0.0));
        let mut frozen = std::mem::take(&mut self.frozen);
        let decide = frozen.len() != ne;
        frozen.resize(ne, false);
        let mut frozen_w = std::mem::take(&mut self.frozen_w);
        frozen_w.resize(ne, (0.0, [Vector::<D>::zeros(); MAX_NV]));
        let mut frozen_bare = std::mem::take(&mut self.frozen_bare);
        frozen_bare.resize(ne, false);
        // The fluid elements' mean pressures at `tⁿ`, at the step's first
        // assembly (read at every iterate: 10 % of a 3D assembly when each
        // iterate gathered them again).
        if decide {
            let (elem_sys, particle_of) = (&self.elem_sys, &self.particle_of);
            let elem_fluid = &self.elem_fluid;
            let mut mean = std::mem::take(&mut self.mean_pressure);
            mean.clear();
            mean.par_extend((0..ne).into_par_iter().map(|e| {
                if elem_fluid[e] {
                    elem_sys[e * nv..(e + 1) * nv]
                        .iter()
                        .map(|&k| input.pressure_n[particle_of[k as usize] as usize])
                        .sum::<f64>()
                        / nv as f64
                } else {
                    0.0
                }
            }));
            self.mean_pressure = mean;
        }
        let mean_pressure = &self.mean_pressure;
        let (elem_fluid, sliver_quality) = (&self.elem_fluid, self.sliver_quality);
        let stabilised_from = self.sliver_stabilised_from;
        let predict = self.sliver_prediction;
        // 2D: an element touching a particle of a solid element is never
        // kept in shape, so that a film of water between two bodies can be
        // squeezed out (the step is rejected and halved instead).
        let in_solid = &self.in_solid;
        let touches_solid = |parts: &[usize]| D == 2 && parts.iter().any(|&p| in_solid[p]);
        let panicked = std::sync::atomic::AtomicBool::new(false);
        let bad = states
            .par_iter_mut()
            .zip(unified.par_iter_mut())
            .zip(
                frozen
                    .par_iter_mut()
                    .zip(frozen_w.par_iter_mut())
                    .zip(frozen_bare.par_iter_mut()),
            )
            .enumerate()
            // (A fluid element's history, one a thread, its pressure set
            // for each: not made anew for every element.)
            .map_init(History::<D>::default, |fluid_h, (e, ((st, un), ((fr, fw), bare)))| {
                // After a material's panic the rest is not computed (each
                // would print its panic too); the error is the first's.
                if panicked.load(std::sync::atomic::Ordering::Relaxed) {
                    return None;
                }
                let mut x = [Point::<D>::zeros(); MAX_NV];
                let mut xn = [Point::<D>::zeros(); MAX_NV];
                let mut v = [Vector::<D>::zeros(); MAX_NV];
                let mut parts = [0usize; MAX_NV];
                for a in 0..nv {
                    let p = particle_of[elem_sys[e * nv + a] as usize] as usize;
                    parts[a] = p;
                    x[a] = input.x[p];
                    xn[a] = input.x_n[p];
                    v[a] = input.v[p];
                }
                if decide {
                    let candidate =
                        sliver_quality > 0.0 && elem_fluid[e] && !touches_solid(&parts[..nv]);
                    // Its quality at `tⁿ` (only a candidate's is needed).
                    let qn = if candidate {
                        crate::kernels::shape_quality::<D>(&xn[..nv])
                    } else {
                        f64::INFINITY
                    };
                    *fr = candidate
                        && (qn < sliver_quality
                            || (predict && {
                                // The constant-acceleration prediction of
                                // the step's end (deviation 13).
                                let (dt, mut xp) = (input.dt, xn);
                                for (xp, &p) in xp.iter_mut().zip(&parts[..nv]) {
                                    *xp = *xp + input.v_n[p] * dt + input.a_n[p] * (0.5 * dt * dt);
                                }
                                crate::kernels::shape_quality::<D>(&xp[..nv]) < sliver_quality
                            }));
                    // Flat at `tⁿ`, it carries no pressure stabilisation.
                    *bare = *fr && stabilised_from.is_none_or(|q| qn < q);
                }
                if *fr {
                    // Its volumetric terms at the iterate (finite through
                    // inversion), the rest at `tⁿ`.
                    fw.0 = weighted_shape_gradients::<D>(&x[..nv], &mut fw.1[..nv]);
                    x = xn;
                }
                match element_state::<D>(
                    &x[..nv],
                    &xn[..nv],
                    &v[..nv],
                    input.dt,
                    input.inertia.displacement_weight,
                ) {
                    Some(s) => {
                        *st = s;
                        let mat = &input.materials[self.elem_material[e] as usize];
                        let called = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                            if elem_fluid[e] {
                                // A fluid's history is its nodal pressure
                                // (eq. 62): the element is given its nodes'
                                // mean at `tⁿ`, so that a fluid's `μ` or `𝒦`
                                // may depend on it (a pressure-dependent
                                // viscosity). Before, it was given 0.
                                fluid_h.pressure = mean_pressure[e];
                                mat.unified(&s.kin, fluid_h)
                            } else {
                                mat.unified(&s.kin, &input.element_history[e])
                            }
                        }));
                        *un = match called {
                            Ok(u) => u,
                            Err(payload) => {
                                panicked.store(true, std::sync::atomic::Ordering::Relaxed);
                                let message = crate::error::panic_message(payload.as_ref());
                                return Some((e, Bad::Panicked(message)));
                            }
                        };
                        if !(un.mu.is_finite()
                            && un.kappa.is_finite()
                            && un.sigma_hat_zz.is_finite()
                            && un.sigma_hat.iter().all(|v| v.is_finite()))
                        {
                            Some((e, Bad::NonFinite))
                        } else if un.mu < 0.0 || un.kappa < 0.0 {
                            // (Negative, the system is indefinite: a solver
                            // or the Picard loop failed at every step size,
                            // naming no material; a negative 𝒦 made the
                            // split form's square root a NaN.)
                            Some((e, Bad::Invalid("a negative μ or 𝒦 (they are the unified form's viscosity and volumetric coefficient, eq. 44, ≥ 0)")))
                        } else if elem_fluid[e] && !isotropic(&un.sigma_hat, un.sigma_hat_zz) {
                            // A fluid's stress beyond `2μD' + 𝒦 ε_v` is its
                            // nodal pressure: a deviatoric `σ̂` (a yield
                            // stress written there) was ignored without a
                            // word (a review, session 48).
                            Some((e, Bad::Invalid("a fluid's σ̂ with a deviatoric part, which the assembly would ignore (a fluid's stress is 2μD' + 𝒦 ε_v I and its nodal pressure: put a yield stress or other shear stress into μ, as an effective viscosity)")))
                        } else {
                            None
                        }
                    }
                    None => Some((e, Bad::Inverted)),
                }
            })
            // The first bad element, whatever the threads did: the error (and
            // the rejection cause a checkpoint keeps) is the same every run.
            .find_first(|r| r.is_some())
            .flatten();
        self.states = states;
        self.unified = unified;
        self.frozen = frozen;
        self.frozen_w = frozen_w;
        self.frozen_bare = frozen_bare;
        // The cut parts at `xⁿ`, once per step (`prepare` clears them):
        // material within the step (the affine map of each element keeps
        // shares and barycentric centroids).
        let up = Vector::<D>::from_fn(|k, _| self.cut_up[k]);
        for &(e, mask) in self.cuts.iter().skip(self.cut_share.len()) {
            let mut xn = [Point::<D>::zeros(); MAX_NV];
            for a in 0..nv {
                let p = self.particle_of[self.elem_sys[e as usize * nv + a] as usize] as usize;
                xn[a] = input.x_n[p];
            }
            self.cut_share
                .push(below_water_line::<D>(&xn[..nv], mask, &up));
        }
        if let Some((e, bad)) = bad {
            let nodes = (0..nv)
                .map(|a| self.particle_of[self.elem_sys[e * nv + a] as usize])
                .collect();
            let material = self.elem_material[e];
            return Err(match bad {
                Bad::Inverted => AssemblyError::InvertedElement { element: e, nodes },
                Bad::NonFinite => AssemblyError::NonFiniteMaterial {
                    element: e,
                    material,
                    name: input.materials[material as usize].name().to_string(),
                },
                Bad::Invalid(why) => AssemblyError::InvalidMaterial {
                    element: e,
                    material,
                    name: input.materials[material as usize].name().to_string(),
                    why,
                },
                Bad::Panicked(message) => AssemblyError::MaterialPanicked {
                    element: e,
                    call: "unified",
                    material,
                    name: input.materials[material as usize].name().to_string(),
                    message,
                },
            });
        }
        self.values.iter_mut().for_each(|v| *v = 0.0);
        self.rhs.iter_mut().for_each(|v| *v = 0.0);
        let ns = self.particle_of.len();
        self.mass.clear();
        self.mass.resize(ns, 0.0);
        // 2. Element stiffness and solid history force, in parallel: each
        // part owns a range of nodes (the columns of `values`, the rows of
        // `rhs` and `mass` that belong to them) and visits, in order, the
        // elements with a node in it, computing each element's matrix and
        // scattering its own entries. Each entry sums its terms in the
        // order of a serial pass, for any number of parts; an element with
        // nodes in two parts is computed by both.
        let node_parts = node_parts(&self.pattern.adj_ptr, rayon::current_num_threads());
        self.part_elements(&node_parts);
        let parts = scatter_parts::<D>(
            &node_parts,
            &self.pattern.adj_ptr,
            &mut self.values,
            &mut self.rhs,
            &mut self.mass,
        );
        let (states, unified) = (&self.states, &self.unified);
        let (elem_vol, elem_fluid) = (&self.elem_vol, &self.elem_fluid);
        let (elem_sys, elem_blocks) = (&self.elem_sys, &self.elem_blocks);
        let elem_density = &self.elem_density;
        let ref_vol = &self.ref_vol;
        let (cut_of, cut_share) = (&self.cut_of, &self.cut_share);
        let (pattern, particle_of) = (&self.pattern, &self.particle_of);
        let constraints = input.constraints;
        let (part_ptr, part_elems) = (&self.part_ptr, &self.part_elems);
        parts.into_par_iter().enumerate().for_each(|(pi_, part)| {
            let ScatterPart {
                nodes,
                value0,
                values,
                rhs,
                mass,
            } = part;
            let own = |n: u32| nodes.contains(&(n as usize));
            let mut buf = [0.0; MAX_LOCAL * MAX_LOCAL + MAX_LOCAL];
            for &e in &part_elems[part_ptr[pi_]..part_ptr[pi_ + 1]] {
                let e = e as usize;
                let (k, f) = buf[..n_local * n_local + n_local].split_at_mut(n_local * n_local);
                element_stiffness::<D>(&states[e], &unified[e], elem_vol[e], k);
                if let Some((share, _)) = cut_part(cut_of, cut_share, e) {
                    k.iter_mut().for_each(|v| *v *= share);
                }
                f.iter_mut().for_each(|v| *v = 0.0);
                if !elem_fluid[e] {
                    element_history_force::<D>(&states[e], &unified[e].sigma_hat, f);
                }
                let (k, f) = (&*k, &*f);
                let el = &elem_sys[e * nv..(e + 1) * nv];
                let rho = elem_density[e];
                // Lumped mass `ρ₀ V₀` (eq. 46) where the element has a
                // reference, else `ρ Vⁿ`.
                let weight = rho * ref_vol.get(e).copied().unwrap_or(states[e].volume_n);
                for a in 0..nv {
                    let i = el[a];
                    let own_i = own(i);
                    let pi = particle_of[i as usize] as usize;
                    let ri = (i as usize).wrapping_sub(nodes.start);
                    if own_i {
                        // Lumped: ∫ ρ W_a over the element (or its cut part).
                        mass[ri] += shape_integral::<D>(cut_of, cut_share, e, a, weight);
                        for kk in 0..D {
                            if !constraints.is_fixed(pi, kk) {
                                rhs[ri * D + kk] += f[a * D + kk];
                            }
                        }
                    }
                    for b in 0..nv {
                        let j = el[b];
                        let own_j = own(j);
                        if !own_i && !own_j {
                            continue;
                        }
                        let p = elem_blocks[e * nv * nv + a * nv + b];
                        let pj = particle_of[j as usize] as usize;
                        // The block's place in this part's values (entry
                        // `(kk, l)` at `base + l · stride + kk`).
                        let (base, stride) = if own_j {
                            let (base, stride) = pattern.block_layout(p, j);
                            (base - value0, stride)
                        } else {
                            (0, 0)
                        };
                        for kk in 0..D {
                            if constraints.is_fixed(pi, kk) {
                                continue;
                            }
                            for l in 0..D {
                                let val = k[(a * D + kk) * n_local + b * D + l];
                                if constraints.is_fixed(pj, l) {
                                    if own_i {
                                        rhs[ri * D + kk] -= val * constraints.velocity[pj][l];
                                    }
                                } else if own_j {
                                    values[base + l * stride + kk] += val;
                                }
                            }
                        }
                    }
                }
            }
        });
        if self.split {
            self.coords.clear();
            for &p in &self.particle_of {
                self.coords.extend(input.x[p as usize].iter());
            }
        }
        // 3. Nodal volumetric term and fluid pressure force (eqs. 56, 58),
        // closures included.
        let nc = self.clo_sys.len() / nv;
        self.clo_w.resize(nc, [Vector::<D>::zeros(); MAX_NV]);
        self.clo_vol.resize(nc, 0.0);
        for c in 0..nc {
            let mut x = [Point::<D>::zeros(); MAX_NV];
            for a in 0..nv {
                x[a] = input.x[self.particle_of[self.clo_sys[c * nv + a] as usize] as usize];
            }
            self.clo_vol[c] = weighted_shape_gradients::<D>(&x[..nv], &mut self.clo_w[c]);
        }
        self.nodal_gradients();
        let mut sink = Sink {
            pattern: &self.pattern,
            particle_of: &self.particle_of,
            constraints: input.constraints,
            values: &mut self.values,
            rhs: &mut self.rhs,
        };
        for a in 0..ns {
            let (s, e) = (self.patch_ptr[a], self.patch_ptr[a + 1]);
            if s == e {
                continue;
            }
            let p_a = input.pressure_n[self.particle_of[a] as usize];
            // Gᵀ pⁿ: force on node i is p_a w_{a,i}.
            for slot in s..e {
                let i = self.patch_nodes[slot];
                for k in 0..D {
                    let f = p_a * self.w[slot][k];
                    sink.rhs(i, k, f);
                }
            }
            if self.split {
                // Row of `C`: (𝒦/M̂)^{1/2} w on free dofs; prescribed dofs'
                // share of `Cᵀ C` moves to the right-hand side.
                let r = self.c_row[a] as usize;
                let row = &mut self.c_val[self.c_ptr[r]..self.c_ptr[r + 1]];
                let nodal =
                    self.treatment == VolumetricTreatment::NodalAveraged && self.vol_hat[a] > 0.0;
                let c = if nodal {
                    self.kappa_hat[a] / self.vol_hat[a]
                } else {
                    0.0
                };
                let sc = c.sqrt();
                let mut fixed = 0.0;
                for (ii, si) in (s..e).enumerate() {
                    let pi = self.particle_of[self.patch_nodes[si] as usize] as usize;
                    for k in 0..D {
                        if input.constraints.is_fixed(pi, k) {
                            fixed += self.w[si][k] * input.constraints.velocity[pi][k];
                            row[ii * D + k] = 0.0;
                        } else {
                            row[ii * D + k] = sc * self.w[si][k];
                        }
                    }
                }
                if self.stabilisation > 0.0 {
                    // Kept apart: it goes through `(I + L̃)⁻¹` (the offset).
                    self.c_fixed[r] = sc * fixed;
                    continue;
                }
                if fixed != 0.0 {
                    for si in s..e {
                        let i = self.patch_nodes[si];
                        for k in 0..D {
                            sink.rhs(i, k, -c * self.w[si][k] * fixed);
                        }
                    }
                }
                continue;
            }
            if self.treatment == VolumetricTreatment::NodalAveraged && self.vol_hat[a] > 0.0 {
                let c = self.kappa_hat[a] / self.vol_hat[a];
                let np = e - s;
                let bp = self.patch_block_ptr[a];
                for (ii, si) in (s..e).enumerate() {
                    let wi = self.w[si];
                    let i = self.patch_nodes[si];
                    for (jj, sj) in (s..e).enumerate() {
                        let wj = self.w[sj];
                        let j = self.patch_nodes[sj];
                        let p = self.patch_blocks[bp + ii * np + jj];
                        for k in 0..D {
                            for l in 0..D {
                                sink.entry(p, i, k, j, l, c * wi[k] * wj[l]);
                            }
                        }
                    }
                }
            }
        }
        // 4. Inertia and body force on each system node, then (5.) the
        // prescribed dofs: identity rows, value on the right. Node by node
        // in parallel parts: node `a`'s terms go to its own column and row.
        let cm = input.inertia.mass_factor;
        let ca = input.inertia.acceleration_factor;
        let parts = scatter_parts::<D>(
            &node_parts,
            &self.pattern.adj_ptr,
            &mut self.values,
            &mut self.rhs,
            &mut self.mass,
        );
        let (pattern, particle_of, diag_block) =
            (&self.pattern, &self.particle_of, &self.diag_block);
        let constraints = input.constraints;
        parts.into_par_iter().for_each(|part| {
            let ScatterPart {
                nodes,
                value0,
                values,
                rhs,
                mass,
            } = part;
            for a in nodes.clone() {
                let ra = a - nodes.start;
                let part = particle_of[a] as usize;
                let m = mass[ra];
                let mut f = input.v_n[part] * (cm * m);
                if ca != 0.0 {
                    f += input.a_n[part] * (ca * m);
                }
                if let Some(b) = input.body_force {
                    f += b * m; // eq. 59, lumped
                }
                if let Some(fe) = input.external_force.get(part) {
                    f += fe; // a nodal force (eq. 59's boundary term)
                }
                let p = diag_block[a];
                for k in 0..D {
                    if !constraints.is_fixed(part, k) {
                        rhs[ra * D + k] += f[k];
                        values[pattern.value_index(p, a as u32, k, k) - value0] += cm * m;
                    }
                }
                if constraints.mask[part] != 0 {
                    for k in 0..D {
                        if constraints.is_fixed(part, k) {
                            values[pattern.value_index(p, a as u32, k, k) - value0] = 1.0;
                            rhs[ra * D + k] = constraints.velocity[part][k];
                        }
                    }
                }
            }
        });
        if self.is_stabilised() {
            self.stabilise(input)?;
        }
        if let Some(i) = first_non_finite(&self.rhs) {
            return Err(AssemblyError::NonFiniteSystem { dof: i });
        }
        let c_val = if self.split { &self.c_val[..] } else { &[] };
        if let Some(entry) = first_non_finite(&self.values)
            .or_else(|| first_non_finite(c_val).map(|i| i + self.values.len()))
        {
            return Err(AssemblyError::NonFiniteMatrix { entry });
        }
        Ok(AssemblyInfo {
            dofs: self.pattern.dofs(),
            nnz: self.pattern.nnz(),
        })
    }

    /// The elements with a node in each of the node ranges `node_parts`
    /// (ascending), kept while the pattern and the ranges stay.
    fn part_elements(&mut self, node_parts: &[usize]) {
        if self.part_key.0 == self.generation
            && self.part_key.1 == node_parts
            && self.part_ptr.len() == node_parts.len()
        {
            return;
        }
        let nv = <Const<D> as Dim>::NV;
        let elem_sys = &self.elem_sys;
        let lists: Vec<Vec<u32>> = node_parts
            .par_windows(2)
            .map(|w| {
                let nodes = w[0]..w[1];
                (0..self.n_elements)
                    .filter(|&e| {
                        elem_sys[e * nv..(e + 1) * nv]
                            .iter()
                            .any(|&n| nodes.contains(&(n as usize)))
                    })
                    .map(|e| e as u32)
                    .collect()
            })
            .collect();
        self.part_ptr.clear();
        self.part_ptr.push(0);
        self.part_elems.clear();
        for l in &lists {
            self.part_elems.extend_from_slice(l);
            self.part_ptr.push(self.part_elems.len());
        }
        self.part_key = (self.generation, node_parts.to_vec());
    }

    /// The stabilisation of the split form at the iterate (see
    /// [`Assembler::set_pressure_stabilisation`]): `L̃ = S τ L S` and the
    /// offset `o = −(c₀ + S τ (L pⁿ − P π))`, `S = (𝒦/M̂)^{1/2}`, over the
    /// fluid elements (a cut one by its part's measure; closures and
    /// slivers kept in shape carry none).
    fn stabilise(&mut self, input: &AssemblyInput<'_, D>) -> Result<(), AssemblyError> {
        let nv = <Const<D> as Dim>::NV;
        let ns = self.particle_of.len();
        let mut fact = 1.0;
        for k in 2..=D {
            fact *= k as f64;
        }
        let scale: Vec<f64> = (0..ns)
            .into_par_iter()
            .map(|a| self.nodal_scale(a))
            .collect();
        // Where fluids of different densities meet (oil on water) the
        // hydrostatic pressure has a kink at each interface row, and the
        // projected jump of `∇pⁿ` did not vanish there: at α = 1 the
        // resting oil moved at 7·10⁻² √(gH). Each element's gradient is
        // taken less `(ρ_e − ρ_ref) g`, the part of the weight the first
        // fluid's density does not give it: zero for one fluid (the
        // gradient bit for bit), and a jump that vanishes on any
        // hydrostatic field of layered fluids (session 43).
        let rho_ref = (0..self.n_elements)
            .find(|&e| self.elem_fluid[e])
            .map_or(0.0, |e| self.elem_density[e]);
        let gravity = input.body_force.unwrap_or_else(Vector::<D>::zeros);
        // Per fluid element: τ V, grad pⁿ and the element's measure V (None
        // for an element that carries none), in parallel.
        let mut per = std::mem::take(&mut self.stab_per);
        per.clear();
        per.par_extend((0..self.n_elements).into_par_iter().map(|e| {
            if !self.elem_fluid[e] {
                return None;
            }
            let st = &self.states[e];
            let vol = st.volume * self.share(e);
            if vol <= 0.0 {
                return None;
            }
            // A sliver kept in shape (deviation 13) whose shape at `tⁿ`
            // is flat carries none: on a nearly flat tetrahedron
            // `τ V ∇W_a·∇W_b` grows as the inverse of its height, with
            // couplings of the wrong sign (positive off-diagonals up to
            // 2.6 times the diagonal in the running 3D column), which
            // stalled the pressure multigrid (43–50 CG iterations on
            // `Ŝ + L̃` against 10). Left out of `L`, of `π` and of the
            // offset alike, the term still vanishes for a linear
            // pressure. One of fair shape at `tⁿ` (foreseen to flatten,
            // or just below the sliver quality) carries it on that
            // shape ([`Assembler::set_sliver_stabilisation`]).
            if self.frozen_bare.get(e).copied().unwrap_or(false) {
                return None;
            }
            // (The element's mass density: the midrange where two fluids
            // meet, as its lumped mass.)
            let h2 = (fact * st.volume).powf(2.0 / D as f64);
            let tau = self.stabilisation
                / (input.inertia.mass_factor * self.elem_density[e]
                    + 8.0 * self.unified[e].mu / h2);
            let mut gp = Vector::<D>::zeros();
            for a in 0..nv {
                let part = self.particle_of[self.elem_sys[e * nv + a] as usize] as usize;
                gp += st.grads[a] * input.pressure_n[part];
            }
            let extra = self.elem_density[e] - rho_ref;
            if extra != 0.0 {
                gp -= gravity * extra;
            }
            Some((tau * vol, gp, vol))
        }));
        // The nodal projection π, then `L̃` into the pattern's slots and
        // `S τ (L pⁿ − P π)` per row: node by node in the parts of the
        // scatter, each part visiting its elements in order (each entry
        // sums its terms in the order of a serial pass).
        let mut pi = std::mem::take(&mut self.stab_pi);
        let mut weight = std::mem::take(&mut self.stab_weight);
        pi.clear();
        pi.resize(ns, Vector::<D>::zeros());
        weight.clear();
        weight.resize(ns, 0.0);
        let bounds = self.part_key.1.clone();
        let (part_ptr, part_elems) = (&self.part_ptr, &self.part_elems);
        let elem_sys = &self.elem_sys;
        let elements = |k: usize| &part_elems[part_ptr[k]..part_ptr[k + 1]];
        split_mut(&mut pi, &bounds)
            .into_par_iter()
            .zip(split_mut(&mut weight, &bounds))
            .enumerate()
            .for_each(|(k, (pi, weight))| {
                let n0 = bounds[k];
                for &e in elements(k) {
                    let e = e as usize;
                    let Some((_, gp, vol)) = per[e] else { continue };
                    for &na in &elem_sys[e * nv..(e + 1) * nv] {
                        let Some(r) = (na as usize).checked_sub(n0).filter(|&r| r < pi.len())
                        else {
                            continue;
                        };
                        pi[r] += gp * (vol / nv as f64);
                        weight[r] += vol / nv as f64;
                    }
                }
                for (p, w) in pi.iter_mut().zip(weight.iter()) {
                    if *w > 0.0 {
                        *p /= *w;
                    }
                }
            });
        let patch_bounds: Vec<usize> = bounds.iter().map(|&n| self.patch_ptr[n]).collect();
        let row_bounds: Vec<usize> = bounds
            .iter()
            .map(|&n| self.c_node.partition_point(|&a| (a as usize) < n))
            .collect();
        let (states, elem_slots, c_row) = (&self.states, &self.elem_slots, &self.c_row);
        let pi_ref = &pi;
        split_mut(&mut self.l_val, &patch_bounds)
            .into_par_iter()
            .zip(split_mut(&mut self.c_offset, &row_bounds))
            .enumerate()
            .for_each(|(k, (l_val, c_offset))| {
                let (n0, n1) = (bounds[k], bounds[k + 1]);
                let (s0, r0) = (patch_bounds[k], row_bounds[k]);
                l_val.iter_mut().for_each(|v| *v = 0.0);
                c_offset.iter_mut().for_each(|v| *v = 0.0);
                for &e in elements(k) {
                    let e = e as usize;
                    let Some((tv, gp, _)) = per[e] else { continue };
                    let st = &states[e];
                    let el = &elem_sys[e * nv..(e + 1) * nv];
                    let mut pbar = Vector::<D>::zeros();
                    for &a in el {
                        pbar += pi_ref[a as usize];
                    }
                    pbar /= nv as f64;
                    let jump = gp - pbar;
                    for a in 0..nv {
                        let na = el[a] as usize;
                        if na < n0 || na >= n1 {
                            continue;
                        }
                        let sa = scale[na];
                        c_offset[c_row[na] as usize - r0] += sa * tv * st.grads[a].dot(&jump);
                        for b in 0..nv {
                            let slot = elem_slots[e * nv * nv + a * nv + b] as usize;
                            l_val[slot - s0] +=
                                sa * scale[el[b] as usize] * tv * st.grads[a].dot(&st.grads[b]);
                        }
                    }
                }
            });
        self.stab_pi = pi;
        self.stab_weight = weight;
        self.stab_per = per;
        // o = −(c₀ + r).
        for (o, c0) in self.c_offset.iter_mut().zip(&self.c_fixed) {
            *o = -(c0 + *o);
        }
        if let Some(entry) = self
            .l_val
            .iter()
            .chain(&self.c_offset)
            .position(|v| !v.is_finite())
        {
            return Err(AssemblyError::NonFiniteMatrix { entry });
        }
        Ok(())
    }

    /// `(𝒦/M̂)^{1/2}` of system node `a` (the scale of its row of `C`; 0
    /// without the nodal volumetric term).
    fn nodal_scale(&self, a: usize) -> f64 {
        if self.treatment == VolumetricTreatment::NodalAveraged && self.vol_hat[a] > 0.0 {
            (self.kappa_hat[a] / self.vol_hat[a]).sqrt()
        } else {
            0.0
        }
    }

    /// The stabilised pressure increment `Δp_a = −S_a q_a`,
    /// `q = (I + L̃)⁻¹ (C V − o)`, at every node with a pressure row, for the
    /// velocity `v` (indexed by particle) on the geometry of the last
    /// assembly: `(particle, Δp)` pairs in `out`. `Ok(false)` (and `out`
    /// empty) when the pressure is not stabilised
    /// ([`Assembler::nodal_volumetric_rates`] then gives eq. 62). `guess`,
    /// when it has one value per pressure row, starts the iterative solve
    /// (the last saddle-point solve's `q`,
    /// [`crate::LinearSolver::saddle_increment`]); the answer is the same
    /// to the solve's tolerance with or without it.
    pub fn stabilised_pressure_increments(
        &mut self,
        v: &[Vector<D>],
        guess: Option<&[f64]>,
        out: &mut Vec<(u32, f64)>,
    ) -> Result<bool, crate::SolveError> {
        out.clear();
        if !self.is_stabilised() {
            return Ok(false);
        }
        if v.len() < self.n_particles {
            return Err(crate::SolveError::invalid(
                "stabilised pressure increments",
                "the velocities do not cover the prepared particles",
            ));
        }
        let m = self.c_node.len();
        let mut q = vec![0.0; m];
        for (r, qr) in q.iter_mut().enumerate() {
            let mut cv = 0.0;
            for p in self.c_ptr[r]..self.c_ptr[r + 1] {
                let dof = self.c_idx[p];
                let part = self.particle_of[dof / D] as usize;
                cv += self.c_val[p] * v[part][dof % D];
            }
            *qr = cv - self.c_offset[r];
        }
        // I + L̃ on `L̃`'s pattern (every row holds its diagonal).
        let mut val = self.l_val.clone();
        for r in 0..m {
            for p in self.l_ptr[r]..self.l_ptr[r + 1] {
                if self.l_idx[p] == r {
                    val[p] += 1.0;
                }
            }
        }
        let il = crate::amg::Csr {
            nrows: m,
            ncols: m,
            ptr: self.l_ptr.clone(),
            idx: self.l_idx.clone(),
            val,
        };
        let fail = |detail: String| crate::SolveError::Factorization {
            solver: "pressure stabilisation",
            detail,
        };
        // In 3D from `INCREMENT_MULTIGRID_FROM` rows, CG with one V-cycle of
        // smoothed aggregation per iteration: the sparse factor of `I + L̃`,
        // a pressure Laplacian, fills as N² in 3D (at 98k particles it took
        // most of the 2.9 s per step outside the stage timers, session 21).
        // Otherwise, or should CG not reach the factor's accuracy, the
        // factor (in 2D it was the faster at 100k particles: 0.25 against
        // 0.5 s per step).
        let mut solved = false;
        if D == 3 && m >= INCREMENT_MULTIGRID_FROM {
            // The last pattern's hierarchy first, then a new one.
            let carried = self
                .inc_amg
                .take()
                .and_then(|h| h.carry(&il, &self.c_particle));
            let fresh = || {
                let opts = crate::amg::AmgOptions {
                    rescalable: true,
                    ..Default::default()
                };
                crate::amg::Amg::new(&il, None, &opts)
                    .ok()
                    .map(|amg| IncrementHierarchy {
                        amg,
                        ids: Vec::new(),
                        age: 0,
                        fresh_iterations: 0,
                        scale: increment_scale(&il),
                    })
            };
            let mut next = carried.or_else(fresh);
            while let Some(mut h) = next.take() {
                let mut x = match guess {
                    Some(g) if g.len() == m && g.iter().all(|v| v.is_finite()) => g.to_vec(),
                    _ => vec![0.0; m],
                };
                let (iterations, residual) = crate::amg::pcg(
                    &il,
                    &q,
                    &mut x,
                    &|r: &[f64], z: &mut [f64]| h.amg.apply(r, z),
                    INCREMENT_TOLERANCE,
                    INCREMENT_MAX_ITERATIONS,
                );
                let carried = h.age > 0;
                if residual <= INCREMENT_TOLERANCE * 10.0 {
                    q = x;
                    solved = true;
                    if !carried {
                        h.fresh_iterations = iterations;
                    } else if iterations > (h.fresh_iterations * 3 / 2).max(h.fresh_iterations + 3)
                    {
                        h.age = u32::MAX;
                    }
                    h.ids.clear();
                    h.ids.extend_from_slice(&self.c_particle);
                    self.inc_amg = Some(h);
                } else if carried {
                    next = fresh();
                }
            }
        }
        if !solved {
            let mut work = crate::solver::SolverWork::default();
            self.l_factor
                .factorise(&il, None, &mut work)
                .map_err(fail)?;
            self.l_factor.solve_in_place(&mut q).map_err(fail)?;
        }
        for (r, qr) in q.iter().enumerate() {
            let part = self.particle_of[self.c_node[r] as usize];
            out.push((part, -self.nodal_scale(self.c_node[r] as usize) * qr));
        }
        Ok(true)
    }

    /// Nodal weights `w_{a,j} = Σ_{e∋a,j} Vₑ/(D+1) grad W_j` (the rows of
    /// `G` of eq. 58 without `𝒦`), lumped `M̂_a` (eq. 56) and the
    /// volume-weighted nodal `𝒦_a`.
    fn nodal_gradients(&mut self) {
        let nv = <Const<D> as Dim>::NV;
        let ns = self.particle_of.len();
        self.w.clear();
        self.w.resize(self.patch_nodes.len(), Vector::<D>::zeros());
        self.vol_hat.clear();
        self.vol_hat.resize(ns, 0.0);
        self.kappa_hat.clear();
        self.kappa_hat.resize(ns, 0.0);
        // Node by node in the parts of the scatter, each part visiting its
        // elements in order (each sum in the order of a serial pass).
        let bounds = self.part_key.1.clone();
        let patch_bounds: Vec<usize> = bounds.iter().map(|&n| self.patch_ptr[n]).collect();
        let (part_ptr, part_elems) = (&self.part_ptr, &self.part_elems);
        let (elem_sys, elem_slots, elem_fluid) =
            (&self.elem_sys, &self.elem_slots, &self.elem_fluid);
        let (states, unified, frozen_w) = (&self.states, &self.unified, &self.frozen_w);
        let (frozen_of, cut_of, cut_share) = (&self.frozen, &self.cut_of, &self.cut_share);
        split_mut(&mut self.w, &patch_bounds)
            .into_par_iter()
            .zip(split_mut(&mut self.vol_hat, &bounds))
            .zip(split_mut(&mut self.kappa_hat, &bounds))
            .enumerate()
            .for_each(|(k, ((w, vol_hat), kappa_hat))| {
                let (n0, n1, s0) = (bounds[k], bounds[k + 1], patch_bounds[k]);
                for &e in &part_elems[part_ptr[k]..part_ptr[k + 1]] {
                    let e = e as usize;
                    if !elem_fluid[e] {
                        continue;
                    }
                    let st = &states[e];
                    let frozen = frozen_of.get(e).copied().unwrap_or(false);
                    for a in 0..nv {
                        let na = elem_sys[e * nv + a] as usize;
                        if na < n0 || na >= n1 {
                            continue;
                        }
                        // A sliver kept in shape (deviation 13): `V grad W`
                        // and the signed `V` of the iterate, as for
                        // closures.
                        let (wv, frac) = if frozen {
                            let frac = shape_integral::<D>(cut_of, cut_share, e, a, 1.0);
                            (frac * frozen_w[e].0, frac)
                        } else {
                            let wv = shape_integral::<D>(cut_of, cut_share, e, a, st.volume);
                            (wv, 0.0)
                        };
                        vol_hat[na - n0] += wv;
                        kappa_hat[na - n0] += wv * unified[e].kappa;
                        for b in 0..nv {
                            let slot = elem_slots[e * nv * nv + a * nv + b] as usize;
                            w[slot - s0] += if frozen {
                                frozen_w[e].1[b] * frac
                            } else {
                                st.grads[b] * wv
                            };
                        }
                    }
                }
                for (kh, v) in kappa_hat.iter_mut().zip(vol_hat.iter()) {
                    if *v > 0.0 {
                        *kh /= *v;
                    }
                }
            });
        // Closures: `V grad W` directly (finite when V → 0); no 𝒦 weight (𝒦_a is
        // the mean over the elements).
        for c in 0..self.clo_sys.len() / nv {
            let wv = self.clo_vol[c] / nv as f64;
            for a in 0..nv {
                let na = self.clo_sys[c * nv + a] as usize;
                self.vol_hat[na] += wv;
                for b in 0..nv {
                    let slot = self.clo_slots[c * nv * nv + a * nv + b] as usize;
                    self.w[slot] += self.clo_w[c][b] / nv as f64;
                }
            }
        }
    }

    /// At each node where fluid elements of two materials or more meet:
    /// (particle, material, that material's share of the node's weight),
    /// sorted by particle then material; the shares of a node sum to its
    /// `M̂_a` less its closures' (an inverted sliver kept in shape counts
    /// zero). The same weights as the volume-weighted
    /// `𝒦_a` of the momentum equation, so that a pressure update weighted
    /// by them (`pfem_time`) is the one that equation balanced. Empty when
    /// the mesh has one fluid material. Uses the geometry of the last
    /// assembly.
    pub fn mixed_fluid_shares(&mut self) -> &[(u32, u16, f64)] {
        let nv = <Const<D> as Dim>::NV;
        // Each material's share of the node's weights, the weights of
        // `𝒦_a` in `nodal_gradients` (serial: such nodes are an
        // interface's; once a step, not once an iterate). A frozen
        // sliver's signed weight is taken at zero when negative (an
        // inverted one): a share is a weight of an average.
        self.mixed_shares.clear();
        // (Nothing before the mesh's first assembly: the shares read its
        // element states.)
        if self.any_mixed && !self.failed_prepare && self.states.len() >= self.n_elements {
            for e in 0..self.n_elements {
                if !self.elem_fluid[e] {
                    continue;
                }
                let frozen = self.frozen.get(e).copied().unwrap_or(false);
                for a in 0..nv {
                    let na = self.elem_sys[e * nv + a] as usize;
                    if !self.node_mixed[na] {
                        continue;
                    }
                    let wv = if frozen {
                        shape_integral::<D>(&self.cut_of, &self.cut_share, e, a, 1.0)
                            * self.frozen_w[e].0
                    } else {
                        shape_integral::<D>(
                            &self.cut_of,
                            &self.cut_share,
                            e,
                            a,
                            self.states[e].volume,
                        )
                    };
                    self.mixed_shares.push((
                        self.particle_of[na],
                        self.elem_material[e],
                        wv.max(0.0),
                    ));
                }
            }
            // A stable sort, then each (particle, material) summed in
            // element order.
            self.mixed_shares.sort_by_key(|s| (s.0, s.1));
            self.mixed_shares.dedup_by(|later, kept| {
                let same = later.0 == kept.0 && later.1 == kept.1;
                if same {
                    kept.2 += later.2;
                }
                same
            });
        }
        &self.mixed_shares
    }

    /// The assembled matrix as a faer sparse view.
    pub fn matrix(&self) -> faer::sparse::SparseColMatRef<'_, usize, f64> {
        let n = self.pattern.dofs();
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(
            n,
            n,
            &self.pattern.col_ptr,
            None,
            &self.pattern.row_idx,
        );
        faer::sparse::SparseColMatRef::new(sym, &self.values)
    }

    /// The assembled right-hand side.
    pub fn rhs(&self) -> &[f64] {
        &self.rhs
    }

    /// Changes whenever [`Assembler::prepare`] builds a new pattern, so that
    /// solvers can reuse a symbolic factorisation while it stays the same.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Number of unknowns.
    pub fn dofs(&self) -> usize {
        self.pattern.dofs()
    }

    /// Particle of each system node.
    pub fn particles(&self) -> &[u32] {
        &self.particle_of
    }

    /// System node of particle `p`, `None` if it is in no element.
    pub fn system_node(&self, p: usize) -> Option<usize> {
        match self.sys_of.get(p) {
            Some(&s) if s != NONE => Some(s as usize),
            _ => None,
        }
    }

    /// Lumped nodal mass of each system node (kg, per metre in 2D).
    pub fn mass(&self) -> &[f64] {
        &self.mass
    }

    /// Element states of the last assembly.
    pub fn element_states(&self) -> &[ElementState<D>] {
        &self.states
    }

    /// Whether element `e` is a fluid element.
    pub fn is_fluid_element(&self, e: usize) -> bool {
        self.elem_fluid[e]
    }

    /// Material of element `e`.
    pub fn element_material(&self, e: usize) -> u16 {
        self.elem_material[e]
    }

    /// Nodal averaged volumetric strain rate `ε_{v,a} = (G V)_a / M̂_a`
    /// (eq. 56 without `𝒦`) at every system node of a fluid element, with
    /// the fluid material of the node and its `M̂_a`; uses the geometry of
    /// the last assembly. `v` is indexed by particle.
    pub fn nodal_volumetric_rates(&self, v: &[Vector<D>], out: &mut Vec<NodalRate>) {
        out.clear();
        // A velocity array that does not cover the prepared particles has
        // no rates (session 35's review: it indexed past its end).
        if v.len() < self.n_particles {
            return;
        }
        for a in 0..self.particle_of.len() {
            let (s, e) = (self.patch_ptr[a], self.patch_ptr[a + 1]);
            if s == e || self.vol_hat[a] <= 0.0 {
                continue;
            }
            let mut div = 0.0;
            for slot in s..e {
                div += self.w[slot]
                    .dot(&v[self.particle_of[self.patch_nodes[slot] as usize] as usize]);
            }
            out.push(NodalRate {
                particle: self.particle_of[a],
                material: self.node_fluid_material[a],
                volume: self.vol_hat[a],
                rate: div / self.vol_hat[a],
            });
        }
    }

    /// Force the assembled system's element and nodal terms exert on each
    /// particle for a given velocity field, excluding inertia and body force:
    /// `−(K V − fσ̂)`, written per particle. Used for reactions on walls.
    ///
    /// Errors: [`AssemblyError::MeshMismatch`] when `input`'s velocities
    /// and pressures or `out` do not cover the prepared particles, or when
    /// no assembly has run since the last [`Assembler::prepare`] (the
    /// element states are the assembly's).
    pub fn internal_force(
        &self,
        input: &AssemblyInput<'_, D>,
        out: &mut [Vector<D>],
    ) -> Result<(), AssemblyError> {
        let nv = <Const<D> as Dim>::NV;
        let n = self.n_particles;
        if input.v.len() < n || input.pressure_n.len() < n || out.len() < n {
            return Err(AssemblyError::MeshMismatch {
                what: "the velocities, pressures or forces do not cover the prepared particles",
            });
        }
        if self.failed_prepare
            || self.states.len() < self.n_elements
            || self.unified.len() < self.n_elements
        {
            return Err(AssemblyError::MeshMismatch {
                what: "no assembly since the mesh was prepared",
            });
        }
        out.iter_mut().for_each(|f| *f = Vector::<D>::zeros());
        let mut k = [0.0; MAX_LOCAL * MAX_LOCAL];
        let n_local = nv * D;
        for e in 0..self.n_elements {
            let st = &self.states[e];
            let un = &self.unified[e];
            element_stiffness::<D>(st, un, self.elem_vol[e], &mut k[..n_local * n_local]);
            let share = self.share(e);
            if share != 1.0 {
                k[..n_local * n_local].iter_mut().for_each(|v| *v *= share);
            }
            let mut f = [0.0; MAX_LOCAL];
            if !self.elem_fluid[e] {
                element_history_force::<D>(st, &un.sigma_hat, &mut f[..n_local]);
            }
            let el = &self.elem_sys[e * nv..(e + 1) * nv];
            for a in 0..nv {
                let pa = self.particle_of[el[a] as usize] as usize;
                for kk in 0..D {
                    let mut s = f[a * D + kk];
                    for b in 0..nv {
                        let pb = self.particle_of[el[b] as usize] as usize;
                        for l in 0..D {
                            s -= k[(a * D + kk) * n_local + b * D + l] * input.v[pb][l];
                        }
                    }
                    out[pa][kk] += s;
                }
            }
        }
        for a in 0..self.particle_of.len() {
            let (s, e) = (self.patch_ptr[a], self.patch_ptr[a + 1]);
            if s == e {
                continue;
            }
            // Nodal pressure at n+1 would be pⁿ − 𝒦 ε_v: force p w.
            let pa = self.particle_of[a] as usize;
            let mut p = input.pressure_n[pa];
            if self.treatment == VolumetricTreatment::NodalAveraged && self.vol_hat[a] > 0.0 {
                let mut div = 0.0;
                for slot in s..e {
                    div += self.w[slot]
                        .dot(&input.v[self.particle_of[self.patch_nodes[slot] as usize] as usize]);
                }
                p -= self.kappa_hat[a] * div / self.vol_hat[a];
            }
            for slot in s..e {
                let i = self.particle_of[self.patch_nodes[slot] as usize] as usize;
                out[i] += self.w[slot] * p;
            }
        }
        Ok(())
    }
}

/// The cut part of element `e` (share, barycentric centroid), if it is cut.
#[inline]
fn cut_part(
    cut_of: &[u32],
    cut_share: &[(f64, [f64; MAX_NV])],
    e: usize,
) -> Option<(f64, [f64; MAX_NV])> {
    match cut_of.get(e) {
        Some(&c) if c != NONE => cut_share.get(c as usize).copied(),
        _ => None,
    }
}

/// `∫ W_a` over element `e` (or its cut part) of measure `volume`.
#[inline]
fn shape_integral<const D: usize>(
    cut_of: &[u32],
    cut_share: &[(f64, [f64; MAX_NV])],
    e: usize,
    a: usize,
    volume: f64,
) -> f64
where
    Const<D>: Dim,
{
    match cut_part(cut_of, cut_share, e) {
        Some((share, l)) => volume * share * l[a],
        None => volume / <Const<D> as Dim>::NV as f64,
    }
}

/// What one part of the parallel scatter of element matrices owns: its
/// nodes' columns of the matrix values (`values[0]` is entry `value0`),
/// and their rows of the right-hand side and of the lumped mass.
struct ScatterPart<'s> {
    nodes: std::ops::Range<usize>,
    value0: usize,
    values: &'s mut [f64],
    rhs: &'s mut [f64],
    mass: &'s mut [f64],
}

/// The node ranges `node_parts` as [`ScatterPart`]s: each with its columns
/// of `values` (`adj_ptr`, the node adjacency's row pointers), its rows of
/// `rhs` and its entries of `mass`.
fn scatter_parts<'s, const D: usize>(
    node_parts: &[usize],
    adj_ptr: &[usize],
    values: &'s mut [f64],
    rhs: &'s mut [f64],
    mass: &'s mut [f64],
) -> Vec<ScatterPart<'s>> {
    let cols = |n: usize| adj_ptr[n] * D * D;
    let mut parts = Vec::with_capacity(node_parts.len());
    let (mut values, mut rhs, mut mass) = (values, rhs, mass);
    for w in node_parts.windows(2) {
        let (n0, n1) = (w[0], w[1]);
        let (v, vr) = values.split_at_mut(cols(n1) - cols(n0));
        let (r, rr) = rhs.split_at_mut((n1 - n0) * D);
        let (m, mr) = mass.split_at_mut(n1 - n0);
        (values, rhs, mass) = (vr, rr, mr);
        parts.push(ScatterPart {
            nodes: n0..n1,
            value0: cols(n0),
            values: v,
            rhs: r,
            mass: m,
        });
    }
    parts
}

/// The first entry of `v` that is not finite: chunks in parallel.
fn first_non_finite(v: &[f64]) -> Option<usize> {
    const CH: usize = 8192;
    let c = v
        .par_chunks(CH)
        .position_first(|c| c.iter().any(|x| !x.is_finite()))?;
    let base = c * CH;
    v[base..]
        .iter()
        .position(|x| !x.is_finite())
        .map(|i| base + i)
}

/// `v` cut at the ascending `bounds` (from 0 to `v.len()`): one slice per
/// consecutive pair.
fn split_mut<'s, T>(v: &'s mut [T], bounds: &[usize]) -> Vec<&'s mut [T]> {
    let mut out = Vec::with_capacity(bounds.len().saturating_sub(1));
    let mut rest = v;
    for w in bounds.windows(2) {
        let (head, tail) = rest.split_at_mut(w[1] - w[0]);
        out.push(head);
        rest = tail;
    }
    out
}

/// Boundaries of `parts` node ranges with about equal numbers of matrix
/// entries (`adj_ptr`, the node adjacency's row pointers), from 0 to the
/// node count.
fn node_parts(adj_ptr: &[usize], parts: usize) -> Vec<usize> {
    let n = adj_ptr.len().saturating_sub(1);
    let total = adj_ptr.last().copied().unwrap_or(0);
    let parts = parts.clamp(1, n.max(1));
    let mut out = vec![0];
    for t in 1..parts {
        let b = adj_ptr.partition_point(|&v| v < total * t / parts).min(n);
        if b > out[out.len() - 1] {
            out.push(b);
        }
    }
    if out[out.len() - 1] < n || out.len() == 1 {
        out.push(n);
    }
    out
}

/// Where assembled entries go: applies the velocity constraints (identity
/// rows for prescribed dofs, their columns moved to the right-hand side so
/// the system stays symmetric). The element scatter applies the same
/// rules part by part ([`ScatterPart`]).
struct Sink<'s, const D: usize>
where
    Const<D>: Dim,
{
    pattern: &'s BlockPattern,
    particle_of: &'s [u32],
    constraints: &'s Constraints<D>,
    values: &'s mut [f64],
    rhs: &'s mut [f64],
}

impl<const D: usize> Sink<'_, D>
where
    Const<D>: Dim,
{
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn entry(&mut self, p: u32, i: u32, k: usize, j: u32, l: usize, val: f64) {
        let pi = self.particle_of[i as usize] as usize;
        if self.constraints.is_fixed(pi, k) {
            return;
        }
        let pj = self.particle_of[j as usize] as usize;
        if self.constraints.is_fixed(pj, l) {
            self.rhs[i as usize * D + k] -= val * self.constraints.velocity[pj][l];
            return;
        }
        let idx = self.pattern.value_index(p, j, k, l);
        self.values[idx] += val;
    }

    #[inline]
    fn rhs(&mut self, i: u32, k: usize, val: f64) {
        let pi = self.particle_of[i as usize] as usize;
        if !self.constraints.is_fixed(pi, k) {
            self.rhs[i as usize * D + k] += val;
        }
    }
}

/// Nodal volumetric rate of a fluid node, see
/// [`Assembler::nodal_volumetric_rates`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodalRate {
    /// Particle index.
    pub particle: u32,
    /// Fluid material of the node: its first fluid element's (where two
    /// fluids meet, [`Assembler::mixed_fluid_shares`] gives each one's
    /// share).
    pub material: u16,
    /// Lumped nodal measure `M̂_a` (eq. 56).
    pub volume: f64,
    /// `ε_{v,a}` (1/s).
    pub rate: f64,
}

fn dummy_state<const D: usize>() -> ElementState<D>
where
    Const<D>: Dim,
{
    ElementState {
        grads: [Vector::<D>::zeros(); MAX_NV],
        volume: 0.0,
        volume_n: 0.0,
        kin: pfem_constitutive::Kinematics::at_rest(0.0),
    }
}
