//! The unified material interface (paper §3.5, eqs. 43–44).

use crate::error::MaterialError;
use pfem_core::{Const, Dim, Point, Tensor, Vector};

/// Kinematics of one element at the current Picard iterate, in the Updated
/// Lagrangian frame whose reference is the configuration at `t_n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kinematics<const D: usize> {
    /// Incremental deformation gradient `F = ∂x/∂Xⁿ` (eq. 8 with the
    /// reference at `t_n`; eq. 35 with `F⁽ⁿ⁾ = I`).
    pub f: Tensor<D>,
    /// `J = det F` (eq. 7).
    pub j: f64,
    /// Rate of deformation `D = ½ (L + Lᵀ)`, `L = grad_x V` on the current
    /// iterate (eqs. 17–18), in 1/s. In 2D, plane strain: `D_zz = 0`.
    pub d: Tensor<D>,
    /// Time step `Δt` (s).
    pub dt: f64,
    /// How the displacement over the step depends on the velocity being
    /// solved for, `∂Δu/∂Vⁿ⁺¹` (s): `Δt` for backward Euler, `(β/γ) Δt`
    /// for the Newmark family (`Δt/2` for the trapezoidal rule). A solid
    /// whose stress follows the displacement ([`Self::strain_increment`])
    /// stiffens the system by this factor, not by `Δt`; rate materials
    /// (fluids) ignore it. [`Self::new`] and [`Self::at_rest`] set it to
    /// `dt`.
    pub displacement_weight: f64,
}

impl<const D: usize> Kinematics<D>
where
    Const<D>: Dim,
{
    /// Kinematics of a body at rest: `F = I`, `J = 1`, `D = 0`.
    pub fn at_rest(dt: f64) -> Self {
        Self {
            f: Tensor::<D>::identity(),
            j: 1.0,
            d: Tensor::<D>::zeros(),
            dt,
            displacement_weight: dt,
        }
    }

    /// Kinematics from the incremental deformation gradient `F`, the rate of
    /// deformation `D` and the time step `Δt`, with `J = det F` (eq. 7).
    pub fn new(f: Tensor<D>, d: Tensor<D>, dt: f64) -> Self {
        Self {
            f,
            j: f.determinant(),
            d,
            dt,
            displacement_weight: dt,
        }
    }

    /// Left stretch of the step, `V = √(F Fᵀ)` (symmetric positive
    /// definite; `F = V R` with `R` the step's rotation), by Denman–Beavers
    /// iteration. `I` for a rigid rotation, to rounding. Returns `I` if `F`
    /// is singular (the solver rejects such steps).
    pub fn left_stretch(&self) -> Tensor<D> {
        let b = self.f * self.f.transpose();
        let (mut y, mut z) = (b, Tensor::<D>::identity());
        for _ in 0..40 {
            let (Some(yi), Some(zi)) = (y.try_inverse(), z.try_inverse()) else {
                return Tensor::<D>::identity();
            };
            let y1 = (y + zi) * 0.5;
            z = (z + yi) * 0.5;
            let done = (y1 - y).norm() <= 4.0 * f64::EPSILON * y1.norm();
            y = y1;
            if done {
                break;
            }
        }
        (y + y.transpose()) * 0.5
    }

    /// Strain increment of the step in the current configuration,
    /// `Δε = 2 (V − I)(V + I)⁻¹` with `V` the step's left stretch
    /// ([`Self::left_stretch`]): the (1,1) Padé approximant of the
    /// incremental Hencky strain `ln V`, to third order in the strain. It
    /// depends on the displacement the time scheme actually made (through
    /// `F`) and on nothing else, so it is incrementally objective at any
    /// rotation: a rigid rotation `F = R` gives `V = I` and `Δε = 0`
    /// exactly (up to rounding), however large the angle, where
    /// `Δt D(Vⁿ⁺¹)` registers `1 − cos θ` of spurious dilatation. Its
    /// linearisation in the velocity is `displacement_weight · D`. In 2D
    /// plane strain `V_zz = 1`, so `Δε_zz = 0`. Returns zeros if `V + I`
    /// is singular (it is not for `J > 0`).
    pub fn strain_increment(&self) -> Tensor<D> {
        self.strain_increment_and_convection().0
    }

    /// [`Self::strain_increment`] `Δε` together with its half-step
    /// convection `P = 2 V (V + I)⁻¹`, from one left stretch `V`: the two
    /// commute, and a solid adds its increment at the end of the step as
    /// `P (C : Δε) P` (see `Hypoelastic::stress_after`). `(0, I)` if
    /// `V + I` is singular.
    pub fn strain_increment_and_convection(&self) -> (Tensor<D>, Tensor<D>) {
        let v = self.left_stretch();
        let id = Tensor::<D>::identity();
        match (v + id).try_inverse() {
            Some(inv) => {
                let de = (v - id) * inv * 2.0;
                let pm = v * inv * 2.0;
                ((de + de.transpose()) * 0.5, (pm + pm.transpose()) * 0.5)
            }
            None => (Tensor::<D>::zeros(), id),
        }
    }

    /// Volumetric strain rate `ε_v = tr D = div V` (eq. 19), 1/s.
    pub fn volumetric_rate(&self) -> f64 {
        self.d.trace()
    }

    /// Deviatoric rate of deformation `D' = D − ⅓ (tr D) I` (eq. 20). The
    /// factor is ⅓ in 2D too: plane strain keeps the 3D deviator, whose
    /// out-of-plane component is `−⅓ tr D` (see [`Self::deviatoric_rate_zz`]).
    pub fn deviatoric_rate(&self) -> Tensor<D> {
        self.d - Tensor::<D>::identity() * (self.d.trace() / 3.0)
    }

    /// Out-of-plane component of the deviatoric rate in 2D plane strain,
    /// `D'_zz = −⅓ tr D`; zero in 3D, where there is no separate component.
    pub fn deviatoric_rate_zz(&self) -> f64 {
        if D == 2 {
            -self.d.trace() / 3.0
        } else {
            0.0
        }
    }
}

/// Most internal variables a material may keep in
/// [`History::internal`].
pub const MAX_INTERNAL: usize = 8;

/// History a material carries from step to step: state owned by the solver
/// (per element for solids, per node for fluid pressure), handed to the
/// material by reference, and moved with particles through remeshing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct History<const D: usize> {
    /// Cauchy stress `σⁿ` (Pa) of a solid; in-plane components in 2D.
    pub stress: Tensor<D>,
    /// Out-of-plane normal stress `σ_zz` (Pa) in 2D plane strain; unused
    /// (zero) in 3D.
    pub stress_zz: f64,
    /// Pressure `pⁿ` (Pa) of a fluid, positive in compression. The solver
    /// keeps a fluid's pressure on its nodes; a fluid element's
    /// [`Material::unified`] is given the mean of its nodes'.
    pub pressure: f64,
    /// A solid's internal variables at `t_n` (plastic strain, damage,
    /// viscous strains…), as many as its
    /// [`Material::internal_variables`] names, in that order; zero at the
    /// start. The solver keeps them per element, like the stress.
    pub internal: [f64; MAX_INTERNAL],
}

impl<const D: usize> Default for History<D>
where
    Const<D>: Dim,
{
    fn default() -> Self {
        Self {
            stress: Tensor::<D>::zeros(),
            stress_zz: 0.0,
            pressure: 0.0,
            internal: [0.0; MAX_INTERNAL],
        }
    }
}

impl<const D: usize> History<D>
where
    Const<D>: Dim,
{
    /// Whether every entry (stress, `σ_zz`, pressure, internal variables)
    /// is a finite number.
    pub fn is_finite(&self) -> bool {
        self.stress.iter().all(|v| v.is_finite())
            && self.stress_zz.is_finite()
            && self.pressure.is_finite()
            && self.internal.iter().all(|v| v.is_finite())
    }
}

/// The unified constitutive triple of eq. 44: with it the Cauchy stress at
/// `t_{n+1}` is `σ = σ̂⁽ⁿ⁾ + 𝒦 ε_v I + 2 μ D'` (eq. 43).
///
/// A layer ([`Self::layer`], the contact penalty) replaces `D'` by the
/// shear across its plane; every bulk material leaves it `None`. Build
/// a triple with [`Self::new`] (or [`Self::returning`]) rather than a
/// struct literal, which breaks when a field is added.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unified<const D: usize> {
    /// Effective viscosity `μ⁽ⁿ⁺¹⁾` (Pa·s, `≥ 0`, as `kappa`: the assembly
    /// refuses a negative one): `μ_f` for a fluid,
    /// `μ_h w / J` for a hypoelastic solid (`w`: the scheme's displacement
    /// weight, [`Kinematics::displacement_weight`]; `Δt` in the paper's
    /// trapezoidal rule).
    pub mu: f64,
    /// Effective volumetric coefficient `𝒦⁽ⁿ⁺¹⁾` (Pa·s): `Δt K_f` for a
    /// fluid, `(λ_h + ⅔ μ_h) w / J` for a hypoelastic solid.
    pub kappa: f64,
    /// History stress `σ̂⁽ⁿ⁾` (Pa): `−pⁿ I` for a fluid in the paper, but a
    /// fluid's pressure is nodal and added by the assembly, so a fluid's
    /// isotropic `σ̂` is not used and a deviatoric one is refused
    /// (`pfem_assembly::AssemblyError::InvalidMaterial`); for a hypoelastic
    /// solid the stress at the iterate less its linear part,
    /// `σ − (𝒦 ε_v I + 2 μ D')` ([`Self::returning`]; ARCHITECTURE.md,
    /// deviation 6), where the paper has `F σⁿ Fᵀ / J`.
    pub sigma_hat: Tensor<D>,
    /// Out-of-plane component of `σ̂⁽ⁿ⁾` in 2D plane strain (zero in 3D).
    pub sigma_hat_zz: f64,
    /// `Some` for a layer that resists only the shear across its plane
    /// ([`Layer`]): the `μ` term is then `2 μ P(D)` instead of `2 μ D'`.
    /// Not in the paper: the linearisation of the contact layer
    /// ([`crate::ContactPenalty`]), whose isotropic `2 μ D'` overstated its
    /// normal stiffness by `2 μ (1 − ⅓)` (×2.3 with `G_c = K_c`), so that
    /// the Picard iterates of a block resting on a floor converged at a
    /// linear rate near 0.6. `None` for every bulk material.
    pub layer: Option<Layer<D>>,
}

/// The plane of a layer ([`Unified::layer`]): unit normal `n` and, while
/// the layer slips, the unit slip direction `m` in the plane (zero while
/// it sticks). The layer's linear stress is `2 μ P(D)`,
/// `P(D) = (Q D n) ⊗ n + n ⊗ (Q D n)`, `Q = I − n ⊗ n − m ⊗ m`: the
/// shear across the plane, less its part along the slip, where the
/// traction is Coulomb's bound whatever the shear. No stiffness against
/// stretching along the plane; the normal stiffness is all in `𝒦`.
///
/// Both directions are taken as given: `n` must be a unit vector and `m`
/// a unit vector normal to it, or zero (a longer `n` scales the
/// stiffness). [`crate::ContactPenalty`] sets `m` only where the return
/// map slips; a frictionless layer at exactly zero trial shear sticks,
/// and its linearisation keeps `G_c` there (its true derivative is 0:
/// taking 0 made a 3D stiff block beside the walls reject 49 of 143
/// steps instead of 18 of 57, session 38).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layer<const D: usize> {
    /// Unit normal `n` of the plane.
    pub normal: Vector<D>,
    /// Unit slip direction `m` (in the plane), or zero while sticking.
    pub slip: Vector<D>,
}

impl<const D: usize> Layer<D>
where
    Const<D>: Dim,
{
    /// `Q = I − n ⊗ n − m ⊗ m`: the tangential directions that resist
    /// (exactly zero for a slipping layer in 2D, whose one tangential
    /// direction is the slip's).
    pub fn resisting(&self) -> Tensor<D> {
        if D == 2 && self.slip != Vector::<D>::zeros() {
            return Tensor::<D>::zeros();
        }
        Tensor::<D>::identity()
            - self.normal * self.normal.transpose()
            - self.slip * self.slip.transpose()
    }
}

impl<const D: usize> Unified<D>
where
    Const<D>: Dim,
{
    /// The isotropic triple `(μ, 𝒦, σ̂, σ̂_zz)` of eq. 44.
    pub fn new(mu: f64, kappa: f64, sigma_hat: Tensor<D>, sigma_hat_zz: f64) -> Self {
        Unified {
            mu,
            kappa,
            sigma_hat,
            sigma_hat_zz,
            layer: None,
        }
    }

    /// The triple of a solid whose stress at the iterate is `(σ, σ_zz)`,
    /// computed from the displacement, with effective coefficients `μ` and
    /// `𝒦`: `σ̂ = σ − (𝒦 ε_v I + 2 μ D')`, so that eq. 43 returns `σ`
    /// exactly at this iterate while the system sees the stiffness `(μ, 𝒦)`.
    /// What [`crate::Hypoelastic`] does, and any material whose stress
    /// follows the step's displacement (plasticity, damage).
    pub fn returning(
        mu: f64,
        kappa: f64,
        sigma: Tensor<D>,
        sigma_zz: f64,
        kin: &Kinematics<D>,
    ) -> Self {
        Self::new(mu, kappa, sigma, sigma_zz).returned(kin)
    }

    /// [`Self::returning`] for a layer ([`Self::layer`]):
    /// `σ̂ = σ − (𝒦 ε_v I + 2 μ P(D))`.
    pub fn returning_layer(
        mu: f64,
        kappa: f64,
        layer: Layer<D>,
        sigma: Tensor<D>,
        sigma_zz: f64,
        kin: &Kinematics<D>,
    ) -> Self {
        Unified {
            layer: Some(layer),
            ..Self::new(mu, kappa, sigma, sigma_zz)
        }
        .returned(kin)
    }

    /// `self` with `(σ̂, σ̂_zz)` taken as the stress to return at `kin`.
    fn returned(mut self, kin: &Kinematics<D>) -> Self {
        let (linear, linear_zz) = self.linear_stress(kin);
        self.sigma_hat -= linear;
        self.sigma_hat_zz = if D == 2 {
            self.sigma_hat_zz - linear_zz
        } else {
            0.0
        };
        self
    }

    /// The part of eq. 43 linear in the rate, `𝒦 ε_v I + 2 μ D'` (or
    /// `2 μ P(D)` for a [`Layer`]), in-plane and out-of-plane (2D; zero in
    /// 3D).
    pub fn linear_stress(&self, kin: &Kinematics<D>) -> (Tensor<D>, f64) {
        let ev = kin.volumetric_rate();
        let volumetric = Tensor::<D>::identity() * (self.kappa * ev);
        match self.layer {
            None => (
                volumetric + kin.deviatoric_rate() * (2.0 * self.mu),
                if D == 2 {
                    self.kappa * ev + 2.0 * self.mu * kin.deviatoric_rate_zz()
                } else {
                    0.0
                },
            ),
            Some(layer) => {
                let n = layer.normal;
                let qdn = layer.resisting() * (kin.d * n);
                let shear = qdn * n.transpose() + n * qdn.transpose();
                (
                    volumetric + shear * (2.0 * self.mu),
                    if D == 2 { self.kappa * ev } else { 0.0 },
                )
            }
        }
    }

    /// Cauchy stress of eq. 43, `σ = σ̂ + 𝒦 ε_v I + 2 μ D'` (`2 μ P(D)`
    /// for a [`Layer`]), in-plane part.
    pub fn cauchy_stress(&self, kin: &Kinematics<D>) -> Tensor<D> {
        self.sigma_hat + self.linear_stress(kin).0
    }

    /// Out-of-plane normal stress of eq. 43 in 2D plane strain (zero in 3D).
    pub fn cauchy_stress_zz(&self, kin: &Kinematics<D>) -> f64 {
        if D == 2 {
            self.sigma_hat_zz + self.linear_stress(kin).1
        } else {
            0.0
        }
    }
}

/// Whether a material behaves as a fluid (remeshed every step, pressure on
/// nodes, eq. 62) or as a solid (keeps its own mesh, stress on elements,
/// eq. 63).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MaterialKind {
    /// A fluid: history is the nodal pressure.
    Fluid,
    /// A solid: history is the element Cauchy stress.
    Solid,
}

/// A constitutive law in the unified form of eqs. 43–44: the seam where
/// users plug in their own materials.
///
/// A material is configuration (`&self`); its history ([`History`]) is state
/// owned by the solver and passed in. The trait is object safe: assembly and
/// the driver hold materials as `Box<dyn Material<D>>`.
pub trait Material<const D: usize>: Send + Sync + std::fmt::Debug
where
    Const<D>: Dim,
{
    /// A short name for messages and output.
    fn name(&self) -> &str;

    /// Fluid or solid: decides where the history lives and whether the
    /// body is remeshed.
    fn kind(&self) -> MaterialKind;

    /// Density `ρ₀` (kg/m³) in the initial configuration. A solid
    /// element's lumped mass is `ρ₀ V₀` with `V₀` its initial volume (eq.
    /// 46: `ρⁿ = ρ₀ / Jⁿ`, mass conserved); a fluid element, built anew
    /// each step, weighs `ρ₀ Vⁿ` (its density moves only by `p / K`).
    fn density(&self) -> f64;

    /// Speed of the fastest wave the material carries (m/s): `√(K/ρ)` for a
    /// fluid, `√((λ + 2μ)/ρ)` for an elastic solid (the P-wave speed). The
    /// driver reads a modulus from it: `ρ c²` is a solid's default contact
    /// penalty and a fluid's bulk modulus in the volume correction
    /// (`VolumeCorrection`); it also identifies the material in a
    /// checkpoint. A value larger than the true one stiffens contact; the
    /// time step does not follow it (the Courant bound is on the particles'
    /// speeds).
    fn wave_speed(&self) -> f64;

    /// The unified triple `(μ, 𝒦, σ̂⁽ⁿ⁾)` of eq. 44 for the kinematics of the
    /// current Picard iterate and the history at `t_n`: built by
    /// [`Unified::new`], or [`Unified::returning`] for a stress computed
    /// from the step's displacement.
    ///
    /// A solid's `history` is its element's. A fluid's pressure lives on
    /// the nodes (eq. 62), not in elements: a fluid element is given a
    /// history whose `pressure` is the mean of its nodes' pressures at
    /// `t_n` (its other entries zero), so that a fluid's `μ` or `𝒦` may
    /// depend on the pressure (explicitly: the pressure at `t_n`, not the
    /// iterate's). Its `σ̂` is not used (the nodal pressures enter the
    /// system instead) and must be isotropic.
    fn unified(&self, kin: &Kinematics<D>, history: &History<D>) -> Unified<D>;

    /// After the step has converged, advance the history from `t_n` to
    /// `t_{n+1}`: the Cauchy stress of a solid (eqs. 39–42, 63) and its
    /// internal variables. A fluid's pressure is advanced per node by
    /// [`Material::update_pressure`].
    fn update_history(&self, kin: &Kinematics<D>, history: &mut History<D>);

    /// Whether the state a converged attempt ends in is one this material
    /// cannot hold, checked for a solid's element (and a contact layer's)
    /// before [`Material::update_history`], unless every particle of the
    /// element is prescribed (no step size cures it): `Some(why)` rejects the
    /// attempt, which is retried with half the step like an inverted
    /// element and named, with `why`, as the last failure when no step
    /// down to the smallest cures it. The bundled [`crate::ContactPenalty`]
    /// refuses a layer closed through its gap; `None` (accepted) by
    /// default.
    fn refuses(&self, kin: &Kinematics<D>, history: &History<D>) -> Option<String> {
        let _ = (kin, history);
        None
    }

    /// Names of the internal variables a solid keeps in
    /// [`History::internal`] (at most [`MAX_INTERNAL`]; a scene with more is
    /// refused), written to the output by name and kept by checkpoints;
    /// none by default. A fluid keeps none (its elements are rebuilt every
    /// step): a scene refuses a fluid material that names any
    /// ([`crate::MaterialError::FluidWithInternalVariables`]).
    fn internal_variables(&self) -> &[&str] {
        &[]
    }

    /// A solid element's history at the start of a run, given the
    /// element's centroid in the initial configuration (m): a prestress
    /// (a geostatic stress growing with depth, a bolt's preload) in
    /// `stress` (and `stress_zz` in 2D), an initial plastic strain or
    /// damage in `internal`. Zero by default. Asked once per solid element
    /// when the simulation is built (a restart takes the checkpoint's
    /// instead); every entry must be finite, or the scene is refused
    /// ([`crate::MaterialError::NonFiniteInitialHistory`]). The run starts
    /// from the accelerations this stress gives with the loads: a stress
    /// they do not balance sets the body moving (no equilibrium is sought).
    /// A fluid's is not asked: its state is the nodal pressure.
    fn initial_history(&self, centroid: &Point<D>) -> History<D> {
        let _ = centroid;
        History::default()
    }

    /// Refuses a material that does not apply in this dimension `D` (a 2D
    /// assumption such as plane stress used in 3D): `Scene::validate` asks
    /// every body's material. Fine by default.
    fn check_dimension(&self) -> Result<(), MaterialError> {
        Ok(())
    }

    /// The numbers that define the material (moduli, viscosities, a yield
    /// stress…), for a checkpoint to recognise it: a restart under a
    /// material whose parameters differ is refused. None by default; a
    /// material is then recognised by its name, kind, density, wave speed
    /// and its answers to two fixed probes, which miss a parameter those
    /// probes do not reach (a yield stress above their stress).
    fn parameters(&self) -> Vec<f64> {
        Vec::new()
    }

    /// A fluid's nodal pressure at `t_{n+1}` (eq. 62) from its value `p_n`
    /// at `t_n`, the node's volumetric strain rate `ε_v` (1/s, the nodal
    /// average of eq. 19) and the step `Δt` (s). With the pressure
    /// stabilisation on (`StepParams::pressure_stabilisation` > 0) it is
    /// not called: the pressures take the stabilised solve's linear
    /// increments, built from `𝒦` (ARCHITECTURE.md, deviation 12). The default calls
    /// [`Material::update_history`] with isotropic kinematics `D = ε_v/D I`
    /// (what a fluid written against `update_history` alone expects);
    /// [`crate::Newtonian`] overrides it with eq. 26.
    fn update_pressure(&self, p_n: f64, volumetric_rate: f64, dt: f64) -> f64 {
        let kin = Kinematics {
            f: Tensor::<D>::identity(),
            j: 1.0,
            d: Tensor::<D>::identity() * (volumetric_rate / D as f64),
            dt,
            displacement_weight: dt,
        };
        let mut h = History {
            pressure: p_n,
            ..History::default()
        };
        self.update_history(&kin, &mut h);
        h.pressure
    }
}

/// The mass density of a fluid element (kg/m³): the midrange of its
/// fluid nodes' densities, `(ρ_min + ρ_max)/2`,
/// over `node_materials` (each node's material index; walls' and solids'
/// nodes, whose material is none or not a fluid's, are left out), or its
/// own material's `element_material` when no node is fluid.
///
/// Where two fluids meet, the elements between the last row of one and
/// the first row of the other have two nodes of one fluid or two of the
/// other, as the tessellation's diagonals fall. By majority they weighed
/// `ρ₁` or `ρ₂`: each interface node's lumped weight then hung on the
/// diagonals around it, no hydrostatic pressure balanced it, and the
/// rows moved in alternate columns from rest, remeshing flipping the
/// diagonals on. At the midrange every element of the band weighs
/// `(ρ₁ + ρ₂)/2`: the fluid is three layers, each of one density, and
/// the hydrostatic pressure with its kinks on the rows (the scene's
/// start) is a discrete equilibrium on any tessellation of the fluids
/// alone (an element of the band with a wall node and one fluid node
/// weighs that fluid's density). The element's viscosity and bulk modulus stay its majority material's
/// (session 43).
pub fn fluid_element_density<const D: usize>(
    materials: &[Box<dyn Material<D>>],
    node_materials: impl IntoIterator<Item = u16>,
    element_material: u16,
) -> f64
where
    Const<D>: Dim,
{
    let (lo, hi) = node_materials
        .into_iter()
        .filter_map(|m| materials.get(m as usize))
        .filter(|m| m.kind() == MaterialKind::Fluid)
        .map(|m| m.density())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
            (lo.min(r), hi.max(r))
        });
    if lo <= hi {
        if lo == hi {
            lo
        } else {
            0.5 * (lo + hi)
        }
    } else {
        materials[element_material as usize].density()
    }
}

#[cfg(test)]
mod density_tests {
    use super::*;
    use crate::{Hypoelastic, Newtonian};

    /// Water, oil, a steel solid and a wall (no material): an element of
    /// one fluid weighs that fluid's density bit for bit, one where two
    /// meet the midrange whichever of them holds more nodes, and walls'
    /// and solids' nodes count for nothing.
    #[test]
    fn a_fluid_element_weighs_the_midrange_of_its_fluids() {
        let materials: Vec<Box<dyn Material<2>>> = vec![
            Box::new(Newtonian::water()),
            Box::new(Newtonian::new(800.0, 1e-2, 1.5e9).unwrap()),
            Box::new(Hypoelastic::new(7800.0, 2e11, 0.3).unwrap()),
        ];
        let wall = u16::MAX;
        assert_eq!(fluid_element_density(&materials, [0, 0, 0], 0), 1000.0);
        assert_eq!(fluid_element_density(&materials, [0, 0, 1], 0), 900.0);
        assert_eq!(fluid_element_density(&materials, [1, 1, 0], 1), 900.0);
        assert_eq!(fluid_element_density(&materials, [1, wall, 2], 1), 800.0);
        assert_eq!(fluid_element_density(&materials, [wall, 2, 0], 0), 1000.0);
        // No fluid node (a hand-built mesh): the element's own material.
        assert_eq!(fluid_element_density(&materials, [wall, 2, 2], 1), 800.0);
    }
}
