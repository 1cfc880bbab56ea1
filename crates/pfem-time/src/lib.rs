//! Time integration of the monolithic PFEM system (Marti & Idelsohn 2007,
//! §4–§6): Bossak–Newmark (the default), the paper's trapezoidal Newmark
//! (β = ¼, γ = ½) or backward Euler in time, Picard
//! iterations on the geometry, a Courant time-step controller, and
//! rejection of steps that diverge or invert an element.
//!
//! One step ([`Integrator::try_step`]) is the paper's §6 loop:
//!
//! 1. `x⁽⁰⁾ = Xⁿ`, `V⁽⁰⁾` the velocity for which the scheme's position is `Xⁿ`;
//! 2. while not converged: assemble on `x⁽ⁱ⁾` and solve eq. 60 for
//!    `V⁽ⁱ⁺¹⁾`; move the particles, `x⁽ⁱ⁺¹⁾ = Xⁿ + Δt Vⁿ + Δt² [(½ − β) Aⁿ + β Aⁿ⁺¹]`
//!    (eq. 61 with Newmark's eq. 47; `Xⁿ + Δt (Vⁿ + V⁽ⁱ⁺¹⁾)/2` for the
//!    trapezoidal rule, `Xⁿ + Δt V⁽ⁱ⁺¹⁾` for backward Euler); `F`, `J` follow from the positions
//!    (eqs. 7–8) in the next assembly;
//! 3. converged when `‖V⁽ⁱ⁺¹⁾ − V⁽ⁱ⁾‖ ≤ tol · max(‖V⁽ⁱ⁺¹⁾‖, v_floor)`,
//!    `v_floor` at least [`BODY_FORCE_FLOOR`]` · |b| Δt` and
//!    [`ROUNDOFF_FLOOR`]` · ε L / (Δt tol)` (a change at the positions'
//!    round-off);
//!    then the fluid pressure is updated on nodes (eq. 62), the solid stress
//!    on elements (eq. 63), and the positions are accepted (eq. 64).
//!
//! [`Integrator::advance`] retries a rejected step with half the time step
//! until it succeeds or the step falls below the minimum, a typed error.

use pfem_assembly::{
    Assembler, AssemblyError, AssemblyInput, BlockSolver, Constraints, Inertia, LinearSolver,
    NodalRate, SolveError, StepMesh, VolumetricTreatment,
};
use pfem_constitutive::{History, Material, MaterialKind};
use pfem_core::{Const, Dim, Point, Vector};

/// The time scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scheme {
    /// Trapezoidal Newmark, β = ¼, γ = ½, as in the paper (§4): second
    /// order, no numerical damping. With remeshing every step it turns a
    /// dam break into spray (measured: 591 steps, 109 rejected, particles
    /// thrown to 3× the column height at a/20), hence not the default.
    Newmark,
    /// Bossak–Newmark (Wood, Bossak & Zienkiewicz 1980): the inertia is
    /// taken at `(1 − α_B) Aⁿ⁺¹ + α_B Aⁿ` with γ = ½ − α_B and
    /// β = (1 − α_B)²/4, `α_B` = [`StepParams::bossak_alpha`]. Second order,
    /// damps the highest frequencies (spectral radius at infinity
    /// `(1 + α_B)/(1 − α_B)`, 0.54 at α_B = −0.3); for violent flows,
    /// where remeshing feeds the undamped trapezoidal rule with
    /// high-frequency noise (ARCHITECTURE.md, deviation 4). The default.
    #[default]
    Bossak,
    /// Backward Euler: first order, strongly damped; for violent flows.
    BackwardEuler,
}

/// Weights of one step of a [`Scheme`]: how the inertia enters the system
/// and how velocity, acceleration and position follow from the solved
/// velocity `V = Vⁿ⁺¹` (Newmark's relations, eqs. 47–48 of the paper for
/// γ = ½, β = ¼).
///
/// ```
/// use pfem_time::{Scheme, SchemeWeights};
/// use pfem_core::{Point, Vector};
///
/// // The trapezoidal rule moves a particle by Δt (Vⁿ + Vⁿ⁺¹)/2.
/// let w = SchemeWeights::new(Scheme::Newmark, 0.0, 0.1);
/// assert_eq!(w.displacement_weight(), 0.05);
/// let (x, v, a) = (Point::<2>::zeros(), Vector::<2>::new(1.0, 0.0), Vector::<2>::zeros());
/// let target = Point::<2>::new(0.2, 0.0);
/// let v_new = w.velocity_reaching(&x, &v, &a, &target);
/// assert!((w.position(&x, &v, &a, &v_new) - target).norm() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy)]
pub struct SchemeWeights {
    dt: f64,
    gamma: f64,
    beta: f64,
    alpha_b: f64,
    euler: bool,
}

impl SchemeWeights {
    /// The weights of `scheme` (with `bossak_alpha` for [`Scheme::Bossak`])
    /// for a step of `dt` seconds.
    ///
    /// No check here: `dt` must be positive and finite and `bossak_alpha`
    /// in `[−⅓, 0]`, the ranges [`StepParams::validate`] enforces (at
    /// `α_B = ½`, `γ = 0` and the weights are infinite). The
    /// [`Integrator`] validates both before it builds them.
    pub fn new(scheme: Scheme, bossak_alpha: f64, dt: f64) -> Self {
        let (gamma, beta, alpha_b, euler) = match scheme {
            Scheme::Newmark => (0.5, 0.25, 0.0, false),
            Scheme::Bossak => {
                let a = bossak_alpha;
                (0.5 - a, 0.25 * (1.0 - a) * (1.0 - a), a, false)
            }
            Scheme::BackwardEuler => (1.0, 0.0, 0.0, true),
        };
        Self {
            dt,
            gamma,
            beta,
            alpha_b,
            euler,
        }
    }

    /// `M [(1 − α_B) Aⁿ⁺¹ + α_B Aⁿ] = c M V − M (c Vⁿ + c_a Aⁿ)`, and
    /// the displacement weight the solids' stiffness uses.
    pub fn inertia(&self) -> Inertia {
        if self.euler {
            return Inertia {
                mass_factor: 1.0 / self.dt,
                acceleration_factor: 0.0,
                displacement_weight: self.displacement_weight(),
            };
        }
        let (g, a) = (self.gamma, self.alpha_b);
        Inertia {
            mass_factor: (1.0 - a) / (g * self.dt),
            acceleration_factor: (1.0 - a) * (1.0 - g) / g - a,
            displacement_weight: self.displacement_weight(),
        }
    }

    /// `∂Xⁿ⁺¹/∂Vⁿ⁺¹` (s): `Δt` for backward Euler, `(β/γ) Δt` for the
    /// Newmark family (`Δt/2` for the trapezoidal rule). The position is
    /// affine in the solved velocity with this slope.
    pub fn displacement_weight(&self) -> f64 {
        if self.euler {
            self.dt
        } else {
            self.beta / self.gamma * self.dt
        }
    }

    /// The velocity `Vⁿ⁺¹` for which [`Self::position`] is `target`: what a
    /// prescribed motion must impose to move a particle exactly there.
    pub fn velocity_reaching<const D: usize>(
        &self,
        x_n: &Point<D>,
        v_n: &Vector<D>,
        a_n: &Vector<D>,
        target: &Point<D>,
    ) -> Vector<D>
    where
        Const<D>: Dim,
    {
        let at_zero = self.position(x_n, v_n, a_n, &Vector::<D>::zeros());
        (target - at_zero) / self.displacement_weight()
    }

    /// `Aⁿ⁺¹` from the new velocity.
    pub fn acceleration<const D: usize>(
        &self,
        v_n: &Vector<D>,
        a_n: &Vector<D>,
        v: &Vector<D>,
    ) -> Vector<D>
    where
        Const<D>: Dim,
    {
        if self.euler {
            return (v - v_n) / self.dt;
        }
        let g = self.gamma;
        (v - v_n) / (g * self.dt) - a_n * ((1.0 - g) / g)
    }

    /// `Xⁿ⁺¹ = Xⁿ + Δt Vⁿ + Δt² [(½ − β) Aⁿ + β Aⁿ⁺¹]` (eq. 61).
    pub fn position<const D: usize>(
        &self,
        x_n: &Point<D>,
        v_n: &Vector<D>,
        a_n: &Vector<D>,
        v: &Vector<D>,
    ) -> Point<D>
    where
        Const<D>: Dim,
    {
        if self.euler {
            return x_n + v * self.dt;
        }
        let dt = self.dt;
        let a = self.acceleration(v_n, a_n, v);
        x_n + v_n * dt + (a_n * (0.5 - self.beta) + a * self.beta) * (dt * dt)
    }

    /// Velocity of a particle outside every element, whose acceleration is
    /// the body force `b`.
    fn free_flight<const D: usize>(
        &self,
        v_n: &Vector<D>,
        a_n: &Vector<D>,
        b: &Vector<D>,
    ) -> Vector<D>
    where
        Const<D>: Dim,
    {
        if self.euler {
            return v_n + b * self.dt;
        }
        v_n + (a_n * (1.0 - self.gamma) + b * self.gamma) * self.dt
    }
}

/// Parameters of the Picard loop and of step rejection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParams {
    /// Time scheme.
    pub scheme: Scheme,
    /// Bossak parameter `α_B` of [`Scheme::Bossak`], in `[−⅓, 0]`
    /// (0 is trapezoidal Newmark). Default −0.3.
    pub bossak_alpha: f64,
    /// Relative velocity-change tolerance of the Picard loop. Default 1e-6.
    pub picard_tolerance: f64,
    /// Maximum Picard iterations before the step is rejected. Default 25.
    pub max_picard_iterations: usize,
    /// Also stop the Picard loop when the *estimated error* of the iterate
    /// is below [`Self::picard_tolerance`]: the loop converges linearly,
    /// so with `r = cᵢ / cᵢ₋₁` (the ratio of the last two relative
    /// changes, from the third iterate on, the first change being from an
    /// artificial start) the iterate's distance to the fixed point is
    /// about `cᵢ r / (1 − r)`. Used only while `r < ½`, where it is below
    /// the change itself, so the loop never runs longer than without it.
    /// Default false.
    pub picard_error_estimate: bool,
    /// Velocity norm (m/s, RMS per particle) below which changes are judged
    /// against this floor instead of the velocity itself. Default 1e-9.
    /// With a body force `b` the floor is never below
    /// [`BODY_FORCE_FLOOR`]` · |b| Δt`, nor ever below
    /// [`ROUNDOFF_FLOOR`]` · ε L / (Δt tol)` (a change whose displacement
    /// is the positions' round-off, `L` their largest coordinate).
    pub velocity_floor: f64,
    /// Smallest time step (s) the rejection loop may try. Default 1e-9.
    pub min_dt: f64,
    /// Treatment of the volumetric term.
    pub volumetric: VolumetricTreatment,
    /// Reuse the first iteration's factorisation in later Picard
    /// iterations: `V ← V + A₀⁻¹ (b(x⁽ⁱ⁾) − A(x⁽ⁱ⁾) V)`, which has the same
    /// fixed point as the plain Picard loop and costs triangular solves
    /// instead of factorisations; the matrix is refactorised when the
    /// correction stops shrinking by half per iteration. Default false:
    /// measured on the 2D dam break (a/20) it converged more slowly than
    /// refactorising (wall time 62 s against 34 s, 314 against 109
    /// rejected steps): the stiff volumetric term changes enough with the
    /// geometry that the frozen matrix is a poor preconditioner.
    pub reuse_factorization: bool,
    /// Pressure stabilisation factor `α` (0: off, the paper's nodal
    /// pressure): the fluid's nodal pressure solves the continuity
    /// equation with an orthogonal-subscale pressure Laplacian of
    /// intrinsic time `τ = α / (c ρ + 8 μ / h²)`
    /// (`pfem_assembly::Assembler::set_pressure_stabilisation`;
    /// ARCHITECTURE.md deviation 12). Default 0.
    pub pressure_stabilisation: f64,
    /// Slivers (ARCHITECTURE.md deviation 13), 3D: a fluid
    /// tetrahedron whose quality `measure / R³` at `tⁿ` is below this (in
    /// `[0, 0.5)`; `R` its circumradius, 0.51 for the regular tetrahedron)
    /// is integrated on its geometry at `tⁿ`, except for its volumetric
    /// terms, which follow the iterate through zero volume, so that it
    /// cannot invert the step
    /// (`pfem_assembly::Assembler::set_sliver_quality`). For callers that
    /// remesh every step, as `pfem-driver` does: the next tessellation
    /// replaces the sliver, which may end the step flat or inverted.
    /// Default [`SLIVER_QUALITY_3D`]; 0 turns it off, and with it
    /// [`StepParams::sliver_prediction`], which uses the same threshold
    /// (an inverted element then rejects the attempt, as the paper has
    /// it).
    pub sliver_quality_3d: f64,
    /// The same for 2D triangles (quality `measure / R²` in `[0, 1)`;
    /// 1.30 for the equilateral triangle, 1 for a lattice's right
    /// isosceles one). A 2D Delaunay triangulation maximises the smallest
    /// angle, but particles on a free surface can be nearly collinear,
    /// and the flow can squeeze a fair triangle flat within a step: the
    /// 2D dam break rejects 15 % of its attempts for inverted triangles.
    /// Default 0, off; [`SLIVER_QUALITY_2D`] is the measured threshold to
    /// opt in with: the 2D examples then take 11–26 % fewer steps, but
    /// the square column's surge front (`dam_break_2d --aspect 1`) falls
    /// back mid-run and its error against Martin & Moyce grows from
    /// 3.85 % to 11.57 % (`docs/benchmarks.md`, session 19).
    pub sliver_quality_2d: f64,
    /// A 3D sliver kept in shape whose quality at the start of the step is
    /// at least this carries the pressure stabilisation
    /// ([`StepParams::pressure_stabilisation`]) on that shape; flatter
    /// ones carry none, as every sliver did until session 30
    /// (`pfem_assembly::Assembler::set_sliver_stabilisation`; a value at
    /// or above [`StepParams::sliver_quality_3d`] leaves out all but the
    /// slivers foreseen ([`StepParams::sliver_prediction`]) of fair shape
    /// at `tⁿ`). Default [`SLIVER_STABILISED_3D`]. 2D slivers carry none.
    pub sliver_stabilised_3d: f64,
    /// Slivers foreseen (deviation 13): also treat as a sliver a fluid
    /// element whose quality at the step's predicted end
    /// (`xⁿ + Δt vⁿ + ½ Δt² aⁿ`) is below [`StepParams::sliver_quality_3d`]
    /// (2D: [`StepParams::sliver_quality_2d`]), so that the flow squeezing
    /// a fair element flat within the step does not invert it and reject
    /// the attempt (`pfem_assembly::Assembler::set_sliver_prediction`).
    /// Default true: measured on the column on a cylinder at a/14 (first
    /// 0.45 s), 34 rejected attempts in 260 steps without, none in 208
    /// with (`docs/benchmarks.md`, session 18); on the 2D dam break (0.4 s,
    /// with [`StepParams::sliver_quality_2d`] = 0.05), 104 in 715 steps
    /// without either rule, 30 in 589 with the start-of-step rule alone,
    /// 2 in 527 with both (session 19).
    pub sliver_prediction: bool,
    /// Start the Picard loop from the constant-acceleration prediction
    /// `V⁽⁰⁾ = Vⁿ + Δt Aⁿ` (prescribed components as prescribed),
    /// `X⁽⁰⁾` the position the scheme gives for that velocity (eq. 61:
    /// `Xⁿ + Δt Vⁿ + ½ Δt² Aⁿ` for the Newmark family, `Xⁿ + Δt Vⁿ + Δt² Aⁿ`
    /// for backward Euler; a consistent pair) instead of the start of the step
    /// (`X⁽⁰⁾ = Xⁿ` with the velocity that leaves it there), for the
    /// particles of no solid element: a solid's step is not bounded by a
    /// Courant number, and a quasi-static step of 5 s predicted a beam
    /// metres away (its Picard loop stalled). Measured (session 19,
    /// `docs/benchmarks.md`): Picard iterates per step 5.42 → 4.90 on the
    /// 2D dam break (0.4 s), 5.60 → 4.96 on the elastic gate, 5.55 → 5.28
    /// on the obstacle, 5.57 → 5.25 on the 3D water column, 5.33 → 5.20
    /// on the column on a cylinder; exact in free fall (one iterate per
    /// step). Default false: with it (and 2D slivers off) the heavy box of
    /// `tests/stability_fsi.rs` drains its water film and rests on the
    /// floor's contact, but its lowest particle comes to 0.80 h of the
    /// floor, below the test's 0.9 h, which is not yet understood.
    pub predict_first_iterate: bool,
    /// Inexact Picard iterates: the linear solve of iterate `i` is asked
    /// ([`LinearSolver::set_accuracy`]) only for the relative residual
    /// `picard_forcing · cᵢ₋₁`, with `cᵢ₋₁` the relative change of the
    /// iterate before (1 for the first), never tighter than the solver's
    /// own target. An iterate's solve need only be accurate against how
    /// far the loop still is from its fixed point, the inexact-Newton
    /// rule. An iterate whose solve was asked for less than
    /// [`Self::picard_tolerance`] and stopped above it cannot end the loop
    /// (a solver content with its guess would show no change at all); the
    /// next iterate is then asked for `picard_forcing ×` that change.
    /// Iterative solvers only: a direct solve is exact whatever it is
    /// asked. 0 turns it off.
    pub picard_forcing: f64,
    /// Aitken's relaxation of the Picard iterates (Irons–Tuck): from the
    /// second iterate on, the velocity moves by `ω_i r_i`, `r_i` the change
    /// the solve proposes, `ω_i = −ω_{i−1} (r_{i−1}·(r_i − r_{i−1}))/
    /// |r_i − r_{i−1}|²` clamped to `[0.1, 2]` (`ω = 1` at the first
    /// iterate); convergence is judged on `r_i` as without it, and the
    /// estimated-error stop ([`Self::picard_error_estimate`]) is not used
    /// with it (the ratio of changes is no longer the loop's contraction);
    /// prescribed velocities take their value. For loops
    /// that converge linearly and slowly, as a sticking frictional contact
    /// does (rate near 0.6: a 2D block at 10° with μ = 0.5 took 2 227 steps,
    /// 709 rejected, for 1 s without it and 504, 3 rejected, with it).
    /// Default false: the 2D dam break to 0.3 s took 651 steps (132
    /// rejected) with it against 539 (96) without (`docs/benchmarks.md`,
    /// session 37).
    pub picard_relaxation: bool,
}

/// Default [`StepParams::sliver_quality_3d`]: every element that inverted
/// within a step of the 3D water column had a quality `measure / R³`
/// between 10⁻³ and 0.06 at the start of the step (median 4·10⁻³).
pub const SLIVER_QUALITY_3D: f64 = 0.06;

/// Default [`StepParams::sliver_stabilised_3d`]: on the stabilised 3D
/// water column at a/20, from its impact on the far wall (0.30–0.32 s),
/// GMRES took 22–38 iterations a solve with no sliver carrying the
/// stabilisation, 10–12 with 0.01 or 0.02, 14–18 with 0.04 and 12–13 with
/// every sliver carrying it (`docs/benchmarks.md`, session 30).
pub const SLIVER_STABILISED_3D: f64 = 0.02;

/// The threshold to opt in with for [`StepParams::sliver_quality_2d`]
/// (default off): with the prediction on, the
/// 2D dam break's rejected attempts (0.4 s) were 4, 4, 2, 1 and 2 for
/// thresholds 0.01, 0.02, 0.05, 0.1 and 0.2 (104 with neither rule), in
/// 545, 531, 527, 531 and 545 steps: 0.05 takes the fewest, 4 % of the
/// equilateral triangle's quality.
pub const SLIVER_QUALITY_2D: f64 = 0.05;

/// Default [`StepParams::picard_forcing`].
pub const PICARD_FORCING: f64 = 1e-3;

/// The Picard loop's velocity floor is at least this fraction of `|b| Δt`,
/// the velocity the body force `b` gives in one step
/// ([`StepParams::velocity_floor`]). A body resting under gravity holds
/// its weight through velocities that are a cancellation of terms of
/// that size, so their changes from one iterate to the next stall at its
/// round-off: an elastic block come to rest on a floor (2D, 0.4 × 0.2 m,
/// a rounded contact onset) moved at 2.4·10⁻⁸ m/s with changes stalled at
/// 5–9·10⁻¹⁴ m/s (3–8·10⁻¹¹ `g Δt`), above 10⁻⁶ of its speed, and the
/// loop rejected every step down to `Δt` = 2·10⁻⁵ s. Against this floor
/// a change of 10⁻⁹ `g Δt` passes, 12 to 33 times the stall.
pub const BODY_FORCE_FLOOR: f64 = 1e-3;

/// The Picard loop's velocity floor is at least the change whose
/// displacement over the step is the positions' round-off, `ε L / Δt`
/// (`ε` the machine epsilon, `L` the largest coordinate of a particle),
/// divided by the Picard tolerance: a change of that size, whatever the
/// speed, is round-off and passes. A stiff solid at rest without gravity
/// (a clamped steel-like beam, `E` = 2 GPa) moved at 5·10⁻¹³ m/s (a
/// round-off initial acceleration) with changes of 4·10⁻¹⁵ to
/// 4·10⁻¹⁴ m/s from iterate to iterate, 0.006 to 0.05 of `ε L / Δt`:
/// against the default floor of 10⁻⁹ m/s the loop asked for 10⁻¹⁵ and
/// rejected 620 of 1 894 steps to 2 ms (a review in session 49). Under
/// gravity the body force's floor is the larger one for steps above
/// about `0.15 ms · √(L / 1 m)`.
pub const ROUNDOFF_FLOOR: f64 = 1.0;

impl Default for StepParams {
    fn default() -> Self {
        Self {
            scheme: Scheme::Bossak,
            bossak_alpha: -0.3,
            picard_tolerance: 1e-6,
            max_picard_iterations: 25,
            picard_error_estimate: false,
            velocity_floor: 1e-9,
            min_dt: 1e-9,
            volumetric: VolumetricTreatment::NodalAveraged,
            reuse_factorization: false,
            pressure_stabilisation: 0.0,
            sliver_quality_3d: SLIVER_QUALITY_3D,
            sliver_quality_2d: 0.0,
            sliver_stabilised_3d: SLIVER_STABILISED_3D,
            sliver_prediction: true,
            predict_first_iterate: false,
            picard_forcing: PICARD_FORCING,
            picard_relaxation: false,
        }
    }
}

/// A [`StepParams`] setting outside its range ([`StepParams::validate`]).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("the step parameter `{setting}` = {value} is outside {range}")]
pub struct InvalidStepParam {
    /// The field of [`StepParams`] (or of [`CourantController`], from its
    /// `validate`).
    pub setting: &'static str,
    /// Its value (a count as `f64`).
    pub value: f64,
    /// The accepted range.
    pub range: &'static str,
}

impl StepParams {
    /// Checks every setting against its range, naming the first that is
    /// outside it. A zero, negative or NaN tolerance, step floor or
    /// iteration limit would otherwise show only as every step failing,
    /// and a negative stabilisation would silently switch itself off.
    /// [`Integrator::try_step`] checks it on every attempt,
    /// `pfem_driver::Simulation::new` once, up front.
    pub fn validate(&self) -> Result<(), InvalidStepParam> {
        let out = |setting, value, range| {
            Err(InvalidStepParam {
                setting,
                value,
                range,
            })
        };
        for (setting, value) in [
            ("picard_tolerance", self.picard_tolerance),
            ("min_dt", self.min_dt),
            ("max_picard_iterations", self.max_picard_iterations as f64),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return out(setting, value, "(0, ∞)");
            }
        }
        for (setting, value) in [
            ("velocity_floor", self.velocity_floor),
            ("pressure_stabilisation", self.pressure_stabilisation),
        ] {
            if !(value >= 0.0 && value.is_finite()) {
                return out(setting, value, "[0, ∞)");
            }
        }
        // An iterate asked for the last change times 1 or more may return
        // its start unchanged: a zero change that cannot end the loop, and
        // then counts the next real change as growth (`pfem run` refused
        // it; the library accepted it).
        if !(0.0..1.0).contains(&self.picard_forcing) {
            return out("picard_forcing", self.picard_forcing, "[0, 1)");
        }
        if self.scheme == Scheme::Bossak && !(-1.0 / 3.0..=0.0).contains(&self.bossak_alpha) {
            return out("bossak_alpha", self.bossak_alpha, "[-1/3, 0]");
        }
        if !(0.0..0.5).contains(&self.sliver_quality_3d) {
            return out("sliver_quality_3d", self.sliver_quality_3d, "[0, 0.5)");
        }
        if !(0.0..1.0).contains(&self.sliver_quality_2d) {
            return out("sliver_quality_2d", self.sliver_quality_2d, "[0, 1)");
        }
        if !(0.0..0.5).contains(&self.sliver_stabilised_3d) {
            return out(
                "sliver_stabilised_3d",
                self.sliver_stabilised_3d,
                "[0, 0.5)",
            );
        }
        Ok(())
    }
}

/// Per-particle state: the unknowns and their history.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParticleState<const D: usize>
where
    Const<D>: Dim,
{
    /// Positions (m).
    pub x: Vec<Point<D>>,
    /// Velocities (m/s).
    pub v: Vec<Vector<D>>,
    /// Accelerations (m/s²).
    pub a: Vec<Vector<D>>,
    /// Nodal pressure (Pa, eq. 62) of every node of a fluid element, wall
    /// and solid nodes of the wetted interface included; zero at a flying
    /// particle; a solid or wall node keeps its last one while dry.
    pub pressure: Vec<f64>,
}

impl<const D: usize> ParticleState<D>
where
    Const<D>: Dim,
{
    /// Particles at rest at the given positions.
    pub fn at_rest(x: Vec<Point<D>>) -> Self {
        let n = x.len();
        Self {
            x,
            v: vec![Vector::<D>::zeros(); n],
            a: vec![Vector::<D>::zeros(); n],
            pressure: vec![0.0; n],
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there is no particle.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
}

/// Everything a step reads besides the particle state.
#[derive(Debug, Clone, Copy)]
pub struct StepInput<'a, const D: usize>
where
    Const<D>: Dim,
{
    /// The step's mesh: fluid elements and solid elements.
    pub mesh: StepMesh<'a>,
    /// The materials.
    pub materials: &'a [Box<dyn Material<D>>],
    /// Velocity constraints.
    pub constraints: &'a Constraints<D>,
    /// Body force per unit mass (m/s²), `None` when the scene has none.
    pub body_force: Option<Vector<D>>,
    /// External force on each particle (N; N per metre of depth in 2D),
    /// added to its momentum balance beside the body force (eq. 59);
    /// empty for none. A particle outside every element (a flying drop)
    /// has no mass in the system and does not feel it.
    pub external_force: &'a [Vector<D>],
}

/// Why a step failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StepError {
    /// The Picard loop did not converge.
    #[error("Picard iterations diverged or stalled at t = {time} s, dt = {dt:e} s: relative change {change:e} after {iterations} iterations")]
    PicardDiverged {
        /// Time at the start of the step (s).
        time: f64,
        /// Time step tried (s).
        dt: f64,
        /// Iterations done.
        iterations: usize,
        /// Last relative velocity change.
        change: f64,
    },
    /// An element degenerated or inverted.
    #[error("assembly failed at t = {time} s, dt = {dt:e} s: {source}")]
    Assembly {
        /// Time at the start of the step (s).
        time: f64,
        /// Time step tried (s).
        dt: f64,
        /// The assembly error.
        source: AssemblyError,
    },
    /// The linear solver failed.
    #[error("linear solve failed at t = {time} s, dt = {dt:e} s: {source}")]
    Solve {
        /// Time at the start of the step (s).
        time: f64,
        /// Time step tried (s).
        dt: f64,
        /// The solver error.
        source: SolveError,
    },
    /// A material refused the state the attempt ends in
    /// (`Material::refuses`: a contact layer closed through its gap). Nothing
    /// is written; the step is retried smaller, and counted with the
    /// inverted elements ([`Rejections::inverted`]).
    #[error("element {element} (particles {nodes:?}) at t = {time} s, dt = {dt:e} s: {why}")]
    Refused {
        /// Time at the start of the step (s).
        time: f64,
        /// Time step tried (s).
        dt: f64,
        /// The element, in the step mesh's numbering.
        element: usize,
        /// Its particles.
        nodes: Vec<u32>,
        /// The material's reason.
        why: String,
    },
    /// Halving the time step did not help before it fell below the minimum.
    #[error("time step fell below the minimum {min_dt:e} s at t = {time} s after {rejections} rejected attempts of this step (earlier steps' are in the run's count); last failure: {last}")]
    StepTooSmall {
        /// Time (s).
        time: f64,
        /// Minimum time step (s).
        min_dt: f64,
        /// Rejections in this step.
        rejections: usize,
        /// The last failure.
        last: Box<StepError>,
    },
    /// Input that cannot be stepped (bad Δt, mismatched lengths).
    #[error("invalid step input: {what}")]
    InvalidInput {
        /// What is wrong.
        what: String,
    },
    /// The converged step's state is not finite: a material's update
    /// (`Material::update_history`, `Material::update_pressure`) or the
    /// stabilised pressure increments returned a non-number. Nothing is
    /// written; the step is retried smaller (a return map that fails only
    /// at large increments), and the error is named as the last failure of
    /// a `StepTooSmall` when no step cures it.
    #[error("the step's state is not finite at t = {time} s, dt = {dt:e} s: {what}")]
    NonFinite {
        /// Time at the start of the step (s).
        time: f64,
        /// Step (s).
        dt: f64,
        /// What is not finite.
        what: String,
    },
}

impl StepError {
    /// Whether a smaller step may cure it (an inverted element, a Picard
    /// loop or a solve that did not converge, a matrix that is not finite
    /// at this step's kinematics, a material's update that returned a
    /// non-number); the others (invalid input, a mesh that names a
    /// material that does not exist, a system of the wrong shape) are
    /// returned at once.
    pub fn is_retryable(&self) -> bool {
        use pfem_assembly::{AssemblyError as A, SolveError as S};
        match self {
            StepError::InvalidInput { .. } => false,
            StepError::Assembly { source, .. } => !matches!(
                source,
                A::MeshMismatch { .. } | A::InvalidMaterial { .. } | A::MaterialPanicked { .. }
            ),
            StepError::Solve { source, .. } => !matches!(
                source,
                S::DimensionMismatch { .. }
                    | S::InvalidSystem { .. }
                    | S::NonFiniteSolution { .. }
                    | S::NoProgress { .. }
            ),
            _ => true,
        }
    }
}

/// The failed attempts of a step so far: what [`Integrator::advance`]
/// books between attempts, and what a driver that runs the attempts
/// itself ([`Integrator::try_step`], to redo its boundary conditions for
/// each step size) books the same way.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Rejections {
    /// Failed attempts.
    pub count: usize,
    /// Of them, by an inverted element, or one whose material refused its
    /// state ([`StepError::Refused`]: a contact layer closed through).
    pub inverted: usize,
    /// Of them, by a Picard loop that diverged or stalled.
    pub picard: usize,
    /// Wall-clock time they took (s).
    pub seconds: f64,
}

impl Rejections {
    /// Books the failed attempt `e` of the step of size `dt` from `time`
    /// (it took `took`): the size of the next attempt (half), or the error
    /// that ends the step (`e` itself when a smaller step cannot cure it,
    /// [`StepError::StepTooSmall`] below `min_dt`).
    pub fn reject(
        &mut self,
        e: StepError,
        time: f64,
        dt: f64,
        min_dt: f64,
        took: std::time::Duration,
    ) -> Result<f64, StepError> {
        if !e.is_retryable() {
            return Err(e);
        }
        self.seconds += took.as_secs_f64();
        match &e {
            StepError::Assembly {
                source: pfem_assembly::AssemblyError::InvertedElement { .. },
                ..
            }
            | StepError::Refused { .. } => self.inverted += 1,
            StepError::PicardDiverged { .. } => self.picard += 1,
            _ => {}
        }
        self.count += 1;
        let next = dt * 0.5;
        if next < min_dt {
            return Err(StepError::StepTooSmall {
                time,
                min_dt,
                rejections: self.count,
                last: Box::new(e),
            });
        }
        Ok(next)
    }

    /// Writes the rejections into the accepted attempt's report.
    pub fn report(&self, rep: &mut StepReport) {
        rep.rejections = self.count;
        rep.rejected_inverted = self.inverted;
        rep.rejected_picard = self.picard;
        rep.rejected_seconds = self.seconds;
    }
}

/// What a successful step reports.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepReport {
    /// Time step taken (s).
    pub dt: f64,
    /// Picard iterations of the accepted attempt.
    pub iterations: usize,
    /// Rejected attempts before it.
    pub rejections: usize,
    /// Of those, rejected because an element degenerated or inverted (or
    /// its material refused its state, [`StepError::Refused`]).
    pub rejected_inverted: usize,
    /// Of those, rejected because the Picard loop did not converge.
    pub rejected_picard: usize,
    /// Last relative velocity change.
    pub change: f64,
    /// The linear-solve residual of the accepted attempt's last solve
    /// (earlier iterates may be solved less accurately,
    /// [`StepParams::picard_forcing`]).
    pub residual: f64,
    /// Matrix factorisations (full solves) in the accepted attempt.
    pub factorizations: usize,
    /// Unknowns of the system.
    pub dofs: usize,
    /// Wall time spent assembling, the mesh's set-up for the step (its
    /// pattern) and the predictor included (s).
    pub assemble_seconds: f64,
    /// Wall time spent in linear solves (s).
    pub solve_seconds: f64,
    /// Wall time spent updating the history and state (s).
    pub update_seconds: f64,
    /// Wall time spent in the rejected attempts before this one (s): the
    /// three times above are the accepted attempt's only.
    pub rejected_seconds: f64,
    /// Nodal pressures updated by the accepted attempt (eq. 62, or the
    /// stabilised increments): the fluid nodes; 0 in a step with no fluid
    /// element.
    pub pressure_updates: usize,
    /// Solid elements whose stress was updated by the accepted attempt
    /// (eq. 63); 0 in a step with no solid element.
    pub stress_updates: usize,
}

/// The Newmark–Picard integrator: owns the assembler, the linear solver
/// and the work buffers reused from step to step.
#[derive(Debug)]
pub struct Integrator<const D: usize>
where
    Const<D>: Dim,
{
    /// Parameters.
    pub params: StepParams,
    assembler: Assembler<D>,
    solver: Box<dyn LinearSolver>,
    sol: Vec<f64>,
    res: Vec<f64>,
    delta: Vec<f64>,
    x_it: Vec<Point<D>>,
    v_it: Vec<Vector<D>>,
    rates: Vec<NodalRate>,
    /// Calls of the linear solver that solved (solves and resolves),
    /// counted here: a user's solver may report no work of its own.
    solves: u64,
}

impl<const D: usize> Integrator<D>
where
    Const<D>: Dim,
{
    /// An integrator with the default solver, [`BlockSolver`]: the split
    /// system by conjugate gradient with an exact pressure-block
    /// preconditioner (the direct solver when it cannot).
    pub fn new(params: StepParams) -> Self {
        Self::with_solver(params, Box::new(BlockSolver::default()))
    }

    /// An integrator with a given linear solver.
    pub fn with_solver(params: StepParams, solver: Box<dyn LinearSolver>) -> Self {
        Self {
            params,
            assembler: Assembler::new(params.volumetric),
            solver,
            sol: Vec::new(),
            res: Vec::new(),
            delta: Vec::new(),
            x_it: Vec::new(),
            v_it: Vec::new(),
            rates: Vec::new(),
            solves: 0,
        }
    }

    /// The linear solves this integrator asked of its solvers so far
    /// (solves and resolves that succeeded, rejected attempts included),
    /// whatever the solvers report ([`Integrator::solver_work`]).
    pub fn solves(&self) -> u64 {
        self.solves
    }

    /// The assembler (for reactions and diagnostics after a step).
    pub fn assembler(&self) -> &Assembler<D> {
        &self.assembler
    }

    /// The particles' indices changed since the last step
    /// ([`Assembler::particles_renumbered`]).
    pub fn particles_renumbered(&mut self) {
        self.assembler.particles_renumbered();
    }

    /// The linear solver's work so far ([`LinearSolver::work`]).
    pub fn solver_work(&self) -> pfem_assembly::SolverWork {
        self.solver.work()
    }

    /// The linear solver's name ([`LinearSolver::name`]).
    pub fn solver_name(&self) -> &str {
        self.solver.name()
    }

    /// The linear solver's settings ([`LinearSolver::settings`]).
    pub fn solver_settings(&self) -> String {
        self.solver.settings()
    }

    /// Sets the accelerations consistent with the state at `t₀`:
    /// `M A⁰ = F + f_int(σ⁰, V⁰)` with the lumped mass, so that Newmark's
    /// first step (eq. 48) starts from the right acceleration instead of
    /// zero. Prescribed components get zero, particles outside every
    /// element the body force.
    #[allow(clippy::needless_range_loop)] // loops index several parallel arrays
    pub fn initialize_acceleration(
        &mut self,
        state: &mut ParticleState<D>,
        history: &[History<D>],
        input: &StepInput<'_, D>,
    ) -> Result<(), StepError> {
        let n = state.len();
        let dt = 1e-12; // rate terms scale with Δt: take the limit Δt → 0
                        // The steps' own split, so that their first one keeps this pattern.
        self.configure_assembly(n, input.materials);
        self.assembler
            .prepare(n, input.mesh, input.materials)
            .map_err(|source| StepError::Assembly {
                time: 0.0,
                dt,
                source,
            })?;
        let ainput = AssemblyInput {
            x: &state.x,
            x_n: &state.x,
            v: &state.v,
            v_n: &state.v,
            a_n: &state.a,
            pressure_n: &state.pressure,
            element_history: history,
            materials: input.materials,
            constraints: input.constraints,
            body_force: input.body_force,
            dt,
            inertia: Inertia {
                mass_factor: 1.0,
                acceleration_factor: 0.0,
                displacement_weight: dt,
            },
            external_force: input.external_force,
        };
        self.assembler
            .assemble(&ainput)
            .map_err(|source| StepError::Assembly {
                time: 0.0,
                dt,
                source,
            })?;
        let mut f = vec![Vector::<D>::zeros(); n];
        self.assembler
            .internal_force(&ainput, &mut f)
            .map_err(|source| StepError::Assembly {
                time: 0.0,
                dt,
                source,
            })?;
        let b = input.body_force.unwrap_or_else(Vector::<D>::zeros);
        for p in 0..n {
            let mut a = b;
            if let Some(s) = self.assembler.system_node(p) {
                let m = self.assembler.mass()[s];
                if m > 0.0 {
                    a += f[p] / m;
                    if let Some(fe) = input.external_force.get(p) {
                        a += fe / m;
                    }
                }
            }
            for k in 0..D {
                if input.constraints.is_fixed(p, k) {
                    a[k] = 0.0;
                }
            }
            state.a[p] = a;
        }
        Ok(())
    }

    /// Advances by `dt`, halving it after each rejected attempt (Picard
    /// divergence, inverted element, failed solve) until it succeeds or
    /// falls below `params.min_dt`. On success `state` and `history` hold
    /// `t + report.dt`; on failure they are unchanged.
    pub fn advance(
        &mut self,
        time: f64,
        dt: f64,
        state: &mut ParticleState<D>,
        history: &mut [History<D>],
        input: &StepInput<'_, D>,
    ) -> Result<StepReport, StepError> {
        let mut dt = dt;
        let mut rejected = Rejections::default();
        loop {
            let t0 = std::time::Instant::now();
            match self.try_step(time, dt, state, history, input) {
                Ok(mut rep) => {
                    rejected.report(&mut rep);
                    return Ok(rep);
                }
                Err(e) => {
                    dt = rejected.reject(e, time, dt, self.params.min_dt, t0.elapsed())?;
                }
            }
        }
    }

    /// Aitken's relaxation of iterate `it` (`StepParams::picard_relaxation`):
    /// the system nodes' velocity moves by `ω r` towards the solve's `sol`,
    /// `r = sol − V`, with `ω` from this and the last change `last_r`
    /// (Irons–Tuck; `ω = 1` at the first iterate, clamped to `[0.1, 2]`).
    /// Prescribed components take the solve's value (theirs) and no part
    /// in `ω`. `r` is scratch; the two buffers swap, so a loop allocates
    /// them once.
    fn relax(
        &mut self,
        it: usize,
        constraints: &Constraints<D>,
        r: &mut Vec<f64>,
        last_r: &mut Vec<f64>,
        omega: &mut f64,
    ) {
        r.clear();
        for (s, &p) in self.assembler.particles().iter().enumerate() {
            let p = p as usize;
            for k in 0..D {
                if constraints.is_fixed(p, k) {
                    self.v_it[p][k] = self.sol[s * D + k];
                    r.push(0.0);
                } else {
                    r.push(self.sol[s * D + k] - self.v_it[p][k]);
                }
            }
        }
        *omega = if it >= 2 && last_r.len() == r.len() {
            let (mut num, mut den) = (0.0, 0.0);
            for (a, b) in r.iter().zip(last_r.iter()) {
                num += b * (a - b);
                den += (a - b) * (a - b);
            }
            if den > 0.0 && num.is_finite() {
                (-*omega * num / den).clamp(0.1, 2.0)
            } else {
                *omega
            }
        } else {
            1.0
        };
        for (s, &p) in self.assembler.particles().iter().enumerate() {
            for k in 0..D {
                self.v_it[p as usize][k] += *omega * r[s * D + k];
            }
        }
        std::mem::swap(last_r, r);
    }

    /// The split form and the pressure stabilisation of the assembly for
    /// `n` particles: split when the solver wants it or the pressure is
    /// stabilised (which needs it).
    fn configure_assembly(&mut self, n: usize, materials: &[Box<dyn Material<D>>]) {
        // (`params` is public: a treatment changed since `new` is the
        // step's, as every other setting is.)
        self.assembler.set_treatment(self.params.volumetric);
        // Without a fluid material there is no pressure row to stabilise:
        // the split system would only cost (a solid scene's direct solver
        // keeps its factor's analysis from step to step; the split one's
        // saddle solve factorised afresh every iterate, a review found).
        let fluid = materials.iter().any(|m| m.kind() == MaterialKind::Fluid);
        let stabilisation = if fluid {
            self.params.pressure_stabilisation
        } else {
            0.0
        };
        let stabilised = stabilisation > 0.0;
        self.assembler
            .set_split(stabilised || self.solver.wants_split(n * D));
        self.assembler.set_pressure_stabilisation(stabilisation);
        self.assembler.set_sliver_quality(if D == 3 {
            self.params.sliver_quality_3d
        } else {
            self.params.sliver_quality_2d
        });
        self.assembler
            .set_sliver_prediction(self.params.sliver_prediction);
        self.assembler
            .set_sliver_stabilisation((D == 3).then_some(self.params.sliver_stabilised_3d));
    }

    /// One attempt of a step of size `dt` (§6). Leaves `state` and
    /// `history` unchanged on failure.
    #[allow(clippy::needless_range_loop)] // loops index several parallel arrays
    pub fn try_step(
        &mut self,
        time: f64,
        dt: f64,
        state: &mut ParticleState<D>,
        history: &mut [History<D>],
        input: &StepInput<'_, D>,
    ) -> Result<StepReport, StepError> {
        let n = state.len();
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(StepError::InvalidInput {
                what: format!("time step {dt} is not a positive finite number"),
            });
        }
        self.params
            .validate()
            .map_err(|e| StepError::InvalidInput {
                what: e.to_string(),
            })?;
        if state.v.len() != n
            || state.a.len() != n
            || state.pressure.len() != n
            || input.constraints.mask.len() != n
            || input.constraints.velocity.len() != n
        {
            return Err(StepError::InvalidInput {
                what: "particle arrays have different lengths".into(),
            });
        }
        // A non-number in the start state or the loads is the caller's,
        // not the step's: no smaller step cures it, so it is named here
        // rather than retried down to `min_dt` (and a particle outside
        // every element, which does not iterate, would carry it silently).
        let finite = |v: &Vector<D>| v.iter().all(|c| c.is_finite());
        if let Some(p) = (0..n).find(|&p| {
            !(state.x[p].iter().all(|c| c.is_finite())
                && finite(&state.v[p])
                && finite(&state.a[p])
                && state.pressure[p].is_finite()
                && (0..D).all(|k| {
                    !input.constraints.is_fixed(p, k)
                        || input.constraints.velocity[p][k].is_finite()
                }))
        }) {
            return Err(StepError::InvalidInput {
                what: format!("particle {p}'s position, velocity, acceleration, pressure or prescribed velocity is not finite"),
            });
        }
        if !(input.external_force.is_empty() || input.external_force.len() == n) {
            return Err(StepError::InvalidInput {
                what: format!(
                    "{} external forces for {n} particles: one per particle, or none",
                    input.external_force.len()
                ),
            });
        }
        if let Some(p) = input.external_force.iter().position(|f| !finite(f)) {
            return Err(StepError::InvalidInput {
                what: format!("particle {p}'s external force is not finite"),
            });
        }
        if input.body_force.is_some_and(|b| !finite(&b)) {
            return Err(StepError::InvalidInput {
                what: "the body force is not finite".into(),
            });
        }
        if history.len() != input.mesh.element_material.len() {
            return Err(StepError::InvalidInput {
                what: "one history entry per element is required".into(),
            });
        }
        let mut rep = StepReport {
            dt,
            ..Default::default()
        };
        // The mesh's set-up (pattern, element data) and the predictor
        // count as assembly.
        let tp = std::time::Instant::now();
        self.configure_assembly(n, input.materials);
        self.assembler
            .prepare(n, input.mesh, input.materials)
            .map_err(|source| StepError::Assembly { time, dt, source })?;
        let w = SchemeWeights::new(self.params.scheme, self.params.bossak_alpha, dt);
        let inertia = w.inertia();
        self.x_it.clone_from(&state.x);
        self.v_it.clone_from(&state.v);
        // Particles outside every element fly under the body force, walls
        // follow their prescribed velocity: set once, they do not iterate.
        let b = input.body_force.unwrap_or_else(Vector::<D>::zeros);
        // The changes of a body at rest under a body force are round-off
        // of the velocity the force gives in a step (`BODY_FORCE_FLOOR`),
        // and a change that moves the particles by the round-off of their
        // positions is round-off whatever the force (`ROUNDOFF_FLOOR`).
        let extent = state
            .x
            .iter()
            .fold(0.0f64, |m, x| x.iter().fold(m, |m, c| m.max(c.abs())));
        let velocity_floor = self
            .params
            .velocity_floor
            .max(BODY_FORCE_FLOOR * b.norm() * dt)
            .max(ROUNDOFF_FLOOR * f64::EPSILON * extent / (dt * self.params.picard_tolerance));
        for p in 0..n {
            if self.assembler.system_node(p).is_none() {
                let mut v = w.free_flight(&state.v[p], &state.a[p], &b);
                for k in 0..D {
                    if input.constraints.is_fixed(p, k) {
                        v[k] = input.constraints.velocity[p][k];
                    }
                }
                self.v_it[p] = v;
            }
        }
        // The first iterate is the pair (Xⁿ, V⁽⁰⁾) with V⁽⁰⁾ the velocity for
        // which the scheme leaves a particle at Xⁿ, or, with
        // `predict_first_iterate`, the predicted pair for the particles of
        // no solid element: either way positions and velocities agree at
        // every iterate. A solid's stress follows the positions and is
        // linearised in the velocity about that pair
        // (`Kinematics::displacement_weight`). Starting from (Xⁿ, Vⁿ)
        // instead told the solid it had strained by `w D(Vⁿ)`, which a 5 s
        // quasi-static step of a moving beam could not recover from; and a
        // solid's step is not bounded by a Courant number, so a predicted
        // one lands metres away and the loop stalls (`tests/beam.rs`).
        let predict = self.params.predict_first_iterate;
        for &p in self.assembler.particles() {
            let p = p as usize;
            if predict && !self.assembler.is_solid_particle(p) {
                let mut v = state.v[p] + state.a[p] * dt;
                for k in 0..D {
                    if input.constraints.is_fixed(p, k) {
                        v[k] = input.constraints.velocity[p][k];
                    }
                }
                self.v_it[p] = v;
                self.x_it[p] = w.position(&state.x[p], &state.v[p], &state.a[p], &v);
            } else {
                self.v_it[p] =
                    w.velocity_reaching(&state.x[p], &state.v[p], &state.a[p], &state.x[p]);
            }
        }
        let dofs = self.assembler.dofs();
        rep.dofs = dofs;
        self.sol.resize(dofs, 0.0);
        let mut converged = false;
        let mut last_change = f64::INFINITY;
        let mut growth = 0;
        let mut refactor = false;
        // The last solve was asked for less than the Picard tolerance and
        // stopped above it (an inexact iterate, `picard_forcing`): its
        // change says nothing of convergence (a solver content with the
        // guess changes nothing), so it cannot end the loop.
        let mut loose = false;
        rep.assemble_seconds = tp.elapsed().as_secs_f64();
        // What the solver keeps for a loop's iterates starts here.
        self.solver.begin_loop();
        // Aitken's relaxation (`StepParams::picard_relaxation`): the last
        // proposed change and factor.
        let relax = self.params.picard_relaxation;
        let (mut r, mut last_r) = (Vec::new(), Vec::new());
        let mut omega = 1.0f64;
        for it in 1..=self.params.max_picard_iterations {
            let ta = std::time::Instant::now();
            let ainput = AssemblyInput {
                x: &self.x_it,
                x_n: &state.x,
                v: &self.v_it,
                v_n: &state.v,
                a_n: &state.a,
                pressure_n: &state.pressure,
                element_history: history,
                materials: input.materials,
                constraints: input.constraints,
                body_force: input.body_force,
                dt,
                inertia,
                external_force: input.external_force,
            };
            self.assembler
                .assemble(&ainput)
                .map_err(|source| StepError::Assembly { time, dt, source })?;
            rep.assemble_seconds += ta.elapsed().as_secs_f64();
            let ts = std::time::Instant::now();
            // Initial guess for iterative solvers: Vⁿ, then the iterate.
            let guess = if it == 1 { &state.v } else { &self.v_it };
            for (s, &p) in self.assembler.particles().iter().enumerate() {
                for k in 0..D {
                    self.sol[s * D + k] = guess[p as usize][k];
                }
            }
            // A frozen-matrix correction when the last one shrank well,
            // a fresh factorisation otherwise.
            let mut corrected = false;
            let split = self.assembler.is_split();
            if self.params.reuse_factorization && it > 1 && !refactor && !split {
                self.res.resize(dofs, 0.0);
                self.delta.resize(dofs, 0.0);
                pfem_assembly::solver::residual(
                    self.assembler.matrix(),
                    self.assembler.rhs(),
                    &self.sol,
                    &mut self.res,
                );
                if let Some(r) = self.solver.resolve(&self.res, &mut self.delta) {
                    r.map_err(|source| StepError::Solve { time, dt, source })?;
                    self.solves += 1;
                    for (x, d) in self.sol.iter_mut().zip(&self.delta) {
                        *x += d;
                    }
                    corrected = true;
                    loose = false;
                }
            }
            if !corrected {
                // Inexact Picard iterates (`StepParams::picard_forcing`).
                let forcing = self.params.picard_forcing;
                let progress = if last_change.is_finite() {
                    last_change
                } else {
                    1.0
                };
                let asked = (forcing > 0.0).then_some(forcing * progress);
                self.solver.set_accuracy(asked);
                let generation = self.assembler.generation();
                let sr = match self.assembler.split_system() {
                    Some(sys) => self.solver.solve_split(&sys, generation, &mut self.sol),
                    None => self.solver.solve(
                        self.assembler.matrix(),
                        generation,
                        self.assembler.rhs(),
                        &mut self.sol,
                    ),
                }
                .map_err(|source| StepError::Solve { time, dt, source })?;
                self.solves += 1;
                // A success that made no progress (one of the user's
                // solvers): the loop would read its zero change as
                // convergence.
                if sr.residual.is_nan() || sr.residual >= 1.0 {
                    return Err(StepError::Solve {
                        time,
                        dt,
                        source: pfem_assembly::SolveError::NoProgress {
                            solver: self.solver.name().to_string(),
                            residual: sr.residual,
                        },
                    });
                }
                rep.residual = sr.residual;
                rep.factorizations += 1;
                let tol = self.params.picard_tolerance;
                loose = asked.is_some_and(|a| a > tol) && sr.residual > tol;
            }
            rep.solve_seconds += ts.elapsed().as_secs_f64();
            // A solver that reports success with a non-number (one of the
            // user's) is named here: the loop would read it as a change of
            // NaN, a divergence, and halve the step down to `min_dt`.
            if let Some(index) = self.sol.iter().position(|v| !v.is_finite()) {
                return Err(StepError::Solve {
                    time,
                    dt,
                    source: pfem_assembly::SolveError::NonFiniteSolution {
                        solver: self.solver.name().to_string(),
                        index,
                    },
                });
            }
            // Relative change of the velocity (system nodes).
            let (mut dv2, mut v2) = (0.0, 0.0);
            for (s, &p) in self.assembler.particles().iter().enumerate() {
                let p = p as usize;
                for k in 0..D {
                    let new = self.sol[s * D + k];
                    dv2 += (new - self.v_it[p][k]).powi(2);
                    v2 += new * new;
                    if !relax {
                        self.v_it[p][k] = new;
                    }
                }
            }
            if relax {
                self.relax(it, input.constraints, &mut r, &mut last_r, &mut omega);
            }
            let ns = self.assembler.particles().len().max(1) as f64;
            let floor2 = velocity_floor.powi(2) * ns;
            // Nothing moved and nothing may (a body at rest, no body
            // force, `velocity_floor` 0): converged, not `0/0`.
            let change = if dv2 == 0.0 {
                0.0
            } else {
                (dv2 / v2.max(floor2)).sqrt()
            };
            rep.iterations = it;
            // Move the particles (eq. 61 with eq. 47).
            for p in 0..n {
                self.x_it[p] = w.position(&state.x[p], &state.v[p], &state.a[p], &self.v_it[p]);
            }
            if !change.is_finite() {
                break;
            }
            // The iterate's estimated distance to the fixed point
            // (`StepParams::picard_error_estimate`).
            let rate = change / last_change;
            // Not with the relaxation: its ratio of changes is no longer
            // the plain loop's contraction.
            let estimate = (self.params.picard_error_estimate && !relax && it >= 3 && rate < 0.5)
                .then(|| change * rate / (1.0 - rate));
            if (change <= self.params.picard_tolerance
                || estimate.is_some_and(|e| e <= self.params.picard_tolerance))
                && !loose
            {
                converged = true;
                last_change = change;
                break;
            }
            // Refactorise when the frozen-matrix correction converges slowly.
            refactor = change > 0.5 * last_change;
            if change > last_change {
                growth += 1;
                if growth >= 3 {
                    last_change = change;
                    break;
                }
            }
            last_change = change;
        }
        self.solver.set_accuracy(None);
        rep.change = last_change;
        if !converged {
            return Err(StepError::PicardDiverged {
                time,
                dt,
                iterations: rep.iterations,
                change: last_change,
            });
        }
        let tu = std::time::Instant::now();
        // The stabilised pressure increments, before anything is updated
        // (their solve may fail).
        // The last solve's `q` (same system, looser tolerance) starts it.
        let mut increments = Vec::new();
        let guess = self.solver.saddle_increment(self.assembler.generation());
        let stabilised_increments = self
            .assembler
            .stabilised_pressure_increments(&self.v_it, guess, &mut increments)
            .map_err(|source| StepError::Solve { time, dt, source })?;
        // Final geometry must stay valid; solid kinematics at the converged
        // state for the stress update (eq. 63).
        let nv = <Const<D> as Dim>::NV;
        // Element by element in parallel (a pass over every element,
        // serial until session 48: 2–5 % of a fluid step by a review's
        // estimate); the first failure in element order is the one
        // reported, as before.
        use rayon::prelude::*;
        let materials = input.materials;
        let (x_it, v_it, x_n) = (&self.x_it, &self.v_it, &state.x);
        let assembler = &self.assembler;
        // Once a material has panicked the other elements are skipped: its
        // message prints once a thread, not once an element.
        let any_panic = std::sync::atomic::AtomicBool::new(false);
        // (Only the solid elements' histories and the failures are kept,
        // in element order.)
        let n_elements = input.mesh.element_material.len();
        let outcome: Vec<(usize, Result<History<D>, StepError>)> = (0..n_elements)
            .into_par_iter()
            .with_min_len(256)
            .filter_map(|e| {
                if assembler.is_frozen(e) || any_panic.load(std::sync::atomic::Ordering::Relaxed) {
                    // A sliver on its geometry at tⁿ, or a material
                    // panicked; below, a fluid element.
                    return None;
                }
                let el = &input.mesh.elements[e * nv..(e + 1) * nv];
                let mut xs = [Point::<D>::zeros(); pfem_core::MAX_NV];
                let mut xn = [Point::<D>::zeros(); pfem_core::MAX_NV];
                let mut vs = [Vector::<D>::zeros(); pfem_core::MAX_NV];
                for a in 0..nv {
                    let p = el[a] as usize;
                    xs[a] = x_it[p];
                    xn[a] = x_n[p];
                    vs[a] = v_it[p];
                }
                let Some(st) = pfem_assembly::kernels::element_state::<D>(
                    &xs[..nv],
                    &xn[..nv],
                    &vs[..nv],
                    dt,
                    inertia.displacement_weight,
                ) else {
                    return Some((
                        e,
                        Err(StepError::Assembly {
                            time,
                            dt,
                            source: AssemblyError::InvertedElement {
                                element: e,
                                nodes: el.to_vec(),
                            },
                        }),
                    ));
                };
                let mat = &materials[input.mesh.element_material[e] as usize];
                if mat.kind() != MaterialKind::Solid {
                    return None;
                }
                // An element whose every particle is prescribed (a
                // clamped solid beside a wall) has a state no step size
                // changes: not asked.
                let held = el
                    .iter()
                    .all(|&p| input.constraints.is_fully_fixed(p as usize));
                // A user's material that panics here is an error naming
                // it, as in the assembly (`AssemblyError::MaterialPanicked`):
                // it ended the process before (session 56).
                let panicked = |call: &'static str, payload: Box<dyn std::any::Any + Send>| {
                    any_panic.store(true, std::sync::atomic::Ordering::Relaxed);
                    Err(StepError::Assembly {
                        time,
                        dt,
                        source: AssemblyError::MaterialPanicked {
                            element: e,
                            call,
                            material: input.mesh.element_material[e],
                            name: mat.name().to_string(),
                            message: pfem_assembly::error::panic_message(payload.as_ref()),
                        },
                    })
                };
                let refusal = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    (!held).then(|| mat.refuses(&st.kin, &history[e])).flatten()
                }));
                match refusal {
                    Err(payload) => return Some((e, panicked("refuses", payload))),
                    Ok(Some(why)) => {
                        return Some((
                            e,
                            Err(StepError::Refused {
                                time,
                                dt,
                                element: e,
                                nodes: el.to_vec(),
                                why,
                            }),
                        ));
                    }
                    Ok(None) => {}
                }
                let mut h = history[e];
                let updated = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    mat.update_history(&st.kin, &mut h); // eq. 63
                }));
                match updated {
                    Ok(()) => Some((e, Ok(h))),
                    Err(payload) => Some((e, panicked("update_history", payload))),
                }
            })
            .collect();
        let mut new_history: Vec<(usize, History<D>)> = Vec::with_capacity(outcome.len());
        for (e, r) in outcome {
            new_history.push((e, r?));
        }
        // A material's update or the stabilised increments may return a
        // non-number: refused before anything is written (the state, its
        // frames and checkpoints would carry it on).
        if let Some((e, _)) = new_history.iter().find(|(_, h)| !h.is_finite()) {
            return Err(StepError::NonFinite {
                time,
                dt,
                what: format!("element {e}'s stress or internal variables after `update_history`"),
            });
        }
        // Fluid pressure on nodes (eq. 62, or its stabilised form).
        let mut new_pressure: Vec<(usize, f64)> = Vec::new();
        if stabilised_increments {
            new_pressure.extend(
                increments
                    .iter()
                    .map(|&(p, dp)| (p as usize, state.pressure[p as usize] + dp)),
            );
        } else {
            self.assembler
                .nodal_volumetric_rates(&self.v_it, &mut self.rates);
            let mixed = self.assembler.mixed_fluid_shares();
            // The particle being updated, for a material's panic (below).
            let mut at = (0usize, 0u16);
            let updated = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                for r in &self.rates {
                    let p = r.particle as usize;
                    let start = mixed.partition_point(|s| s.0 < r.particle);
                    let shares = mixed[start..].iter().take_while(|s| s.0 == r.particle);
                    let weight: f64 = shares.clone().map(|s| s.2).sum();
                    let value = if weight > 0.0 {
                        // Where two fluids meet, each material's update
                        // weighted by its share, the weights of the momentum
                        // equation's `𝒦_a` (it used the first element's
                        // material alone, which that equation did not balance;
                        // session 40's review).
                        let mut sum = 0.0;
                        for &(_, m, w) in shares {
                            at = (p, m);
                            let mat = &input.materials[m as usize];
                            sum += w * mat.update_pressure(state.pressure[p], r.rate, dt);
                            // eq. 62
                        }
                        sum / weight
                    } else {
                        at = (p, r.material);
                        let mat = &input.materials[r.material as usize];
                        mat.update_pressure(state.pressure[p], r.rate, dt) // eq. 62
                    };
                    new_pressure.push((p, value));
                }
            }));
            if let Err(payload) = updated {
                let (p, m) = at;
                return Err(StepError::Assembly {
                    time,
                    dt,
                    source: AssemblyError::MaterialPanicked {
                        element: p,
                        call: "update_pressure",
                        material: m,
                        name: input.materials[m as usize].name().to_string(),
                        message: pfem_assembly::error::panic_message(payload.as_ref()),
                    },
                });
            }
        }
        if let Some(&(p, _)) = new_pressure.iter().find(|(_, v)| !v.is_finite()) {
            return Err(StepError::NonFinite {
                time,
                dt,
                what: format!("particle {p}'s pressure after `update_pressure`"),
            });
        }
        rep.stress_updates = new_history.len();
        rep.pressure_updates = new_pressure.len();
        for (e, h) in new_history {
            history[e] = h;
        }
        let mut touched = vec![false; n];
        for (p, value) in new_pressure {
            state.pressure[p] = value;
            touched[p] = true;
        }
        for p in 0..n {
            // A flying particle carries no pressure. A solid or wall
            // particle outside every fluid element keeps its last one: a
            // memory through the remeshing's flicker at the water line.
            // Reset to zero (tried in session 40), the water coming back
            // found a node at zero pressure and compressed into it: a 3D
            // stiffness-contrast case lost 1.25 % of its volume (bound
            // 1 %) and the dam-break block stopped 3.2 h short of the
            // wall. The output's pressure there is the adjacent water's
            // (`Loads::water_pressure`), zero when dry.
            //
            // A wall particle (every component prescribed) outside every
            // element keeps its last pressure too when the pressure is
            // stabilised: the stabilisation's jump reads `grad pⁿ` on each
            // element, and a tank's corner wall particle, in and out of
            // the fluid mesh as the diagonals of its square fall, came
            // back at zero: the 2D tank at rest with α = 1 moved at
            // 6.2·10⁻² √(gH) by 0.1 s (1.5·10⁻⁴ kept; session 43). The
            // paper's update is left as it was (the same tank stays at
            // rest to round-off either way; the 2D dam break's front moved
            // 1.60 → 1.84 % with walls kept, not a measured gain). A fluid
            // particle with every component prescribed (an inflow's layer
            // at its face, a held drop) flies like any other: it carries
            // no pressure (its material is a fluid's; a wall has none, or
            // the mesh gives no particle materials).
            let wall = input
                .mesh
                .node_material
                .get(p)
                .is_none_or(|&m| input.materials.get(m as usize).is_none());
            let kept_wall =
                stabilised_increments && wall && (0..D).all(|k| input.constraints.is_fixed(p, k));
            if !touched[p] && self.assembler.system_node(p).is_none() && !kept_wall {
                state.pressure[p] = 0.0;
            }
        }
        // Accelerations and positions (eqs. 47–48, 64).
        for p in 0..n {
            state.a[p] = w.acceleration(&state.v[p], &state.a[p], &self.v_it[p]);
            // A flying particle falls freely in its free components; a
            // prescribed component keeps the scheme's value (session 40:
            // a slip-plane particle flying under a tilted gravity got the
            // gravity's component across its plane, and drifted off it
            // under Bossak).
            if self.assembler.system_node(p).is_none() {
                for k in 0..D {
                    if !input.constraints.is_fixed(p, k) {
                        state.a[p][k] = b[k];
                    }
                }
            }
        }
        state.v.clone_from(&self.v_it);
        state.x.clone_from(&self.x_it);
        rep.update_seconds = tu.elapsed().as_secs_f64();
        Ok(rep)
    }
}

/// Courant time-step control: `Δt = C · h_min / v_max`, bounded above by
/// `dt_max`, by `growth ×` the previous step, and below by `dt_min`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CourantController {
    /// Courant number `C` (the fraction of the smallest element a particle
    /// may cross in one step). Default 0.5.
    pub courant: f64,
    /// Largest time step (s).
    pub dt_max: f64,
    /// Smallest time step (s).
    pub dt_min: f64,
    /// Largest growth factor from one step to the next. Default 1.25.
    pub growth: f64,
}

impl Default for CourantController {
    fn default() -> Self {
        Self {
            courant: 0.5,
            dt_max: 1e-2,
            dt_min: 1e-9,
            growth: 1.25,
        }
    }
}

impl CourantController {
    /// Checks the fields' ranges, naming the first out of range: `courant`
    /// and `dt_max` in (0, ∞), `dt_min` in (0, `dt_max`], `growth` in
    /// [1, ∞). [`CourantController::next`] assumes them (a NaN field
    /// would give a NaN step, a `dt_min` above `dt_max` steps above the
    /// ceiling, a growth below 1 steps that shrink to `dt_min` without a
    /// cause); `pfem_driver::Simulation` checks its controller once, up
    /// front.
    pub fn validate(&self) -> Result<(), InvalidStepParam> {
        let out = |setting, value, range| {
            Err(InvalidStepParam {
                setting,
                value,
                range,
            })
        };
        for (setting, value) in [("courant", self.courant), ("dt_max", self.dt_max)] {
            if !(value > 0.0 && value.is_finite()) {
                return out(setting, value, "(0, ∞)");
            }
        }
        if !(self.dt_min > 0.0 && self.dt_min <= self.dt_max) {
            return out("dt_min", self.dt_min, "(0, dt_max]");
        }
        if !(self.growth >= 1.0 && self.growth.is_finite()) {
            return out("growth", self.growth, "[1, ∞)");
        }
        Ok(())
    }

    /// The next time step from the smallest element size `h_min` (m), the
    /// largest particle speed `v_max` (m/s) and the previous step: within
    /// [`dt_min`, `dt_max`] for fields that pass
    /// [`CourantController::validate`]. A speed or size that is not a
    /// positive number (zero, NaN) sets no Courant bound, and a previous
    /// step that is not positive no growth bound: the caller checks its
    /// particles' speeds are finite.
    ///
    /// [`dt_min`]: CourantController::dt_min
    /// [`dt_max`]: CourantController::dt_max
    pub fn next(&self, h_min: f64, v_max: f64, previous: f64) -> f64 {
        let mut dt = self.dt_max;
        if v_max > 0.0 && h_min > 0.0 {
            dt = dt.min(self.courant * h_min / v_max);
        }
        if previous > 0.0 {
            dt = dt.min(previous * self.growth);
        }
        dt.max(self.dt_min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each field of a [`CourantController`] out of its range is named;
    /// the steps of a valid one stay within its bounds, whatever the
    /// speeds and sizes (zero, NaN, infinite).
    #[test]
    fn courant_controller_fields_out_of_range_are_named() {
        let d = CourantController::default();
        assert_eq!(d.validate(), Ok(()));
        for (c, name) in [
            (CourantController { courant: 0.0, ..d }, "courant"),
            (
                CourantController {
                    courant: f64::NAN,
                    ..d
                },
                "courant",
            ),
            (
                CourantController {
                    dt_max: f64::INFINITY,
                    ..d
                },
                "dt_max",
            ),
            (CourantController { dt_min: 0.0, ..d }, "dt_min"),
            (CourantController { dt_min: 0.1, ..d }, "dt_min"),
            (
                CourantController {
                    dt_min: f64::NAN,
                    ..d
                },
                "dt_min",
            ),
            (CourantController { growth: 0.9, ..d }, "growth"),
            (
                CourantController {
                    growth: f64::NAN,
                    ..d
                },
                "growth",
            ),
        ] {
            assert_eq!(c.validate().map_err(|e| e.setting), Err(name), "{c:?}");
        }
        for h in [0.0, 1e-3, f64::NAN, f64::INFINITY] {
            for v in [0.0, 1e-6, 3.0, 1e30, f64::NAN, f64::INFINITY] {
                for prev in [0.0, 1e-12, 1e-3, f64::NAN] {
                    let dt = d.next(h, v, prev);
                    assert!(
                        (d.dt_min..=d.dt_max).contains(&dt),
                        "h {h}, v {v}, previous {prev}: {dt}"
                    );
                }
            }
        }
    }

    /// Each setting outside its range is named by [`StepParams::validate`]
    /// (the integrator's attempt: `tests/closed_forms.rs`).
    #[test]
    fn step_params_outside_their_range_are_named() {
        let d = StepParams::default();
        assert_eq!(d.validate(), Ok(()));
        let bad = [
            (
                StepParams {
                    picard_tolerance: 0.0,
                    ..d
                },
                "picard_tolerance",
            ),
            (
                StepParams {
                    min_dt: f64::NAN,
                    ..d
                },
                "min_dt",
            ),
            (
                StepParams {
                    max_picard_iterations: 0,
                    ..d
                },
                "max_picard_iterations",
            ),
            (
                StepParams {
                    velocity_floor: -1.0,
                    ..d
                },
                "velocity_floor",
            ),
            (
                StepParams {
                    pressure_stabilisation: f64::INFINITY,
                    ..d
                },
                "pressure_stabilisation",
            ),
            (
                StepParams {
                    picard_forcing: -1e-3,
                    ..d
                },
                "picard_forcing",
            ),
            (
                StepParams {
                    picard_forcing: 1.0,
                    ..d
                },
                "picard_forcing",
            ),
            (
                StepParams {
                    bossak_alpha: -0.5,
                    ..d
                },
                "bossak_alpha",
            ),
            (
                StepParams {
                    sliver_quality_3d: 0.5,
                    ..d
                },
                "sliver_quality_3d",
            ),
            (
                StepParams {
                    sliver_quality_2d: f64::NAN,
                    ..d
                },
                "sliver_quality_2d",
            ),
        ];
        for (params, setting) in bad {
            assert_eq!(params.validate().map_err(|e| e.setting), Err(setting));
        }
        // Bossak's α matters only under Bossak.
        let trapezoidal = StepParams {
            scheme: Scheme::Newmark,
            bossak_alpha: 0.5,
            ..d
        };
        assert_eq!(trapezoidal.validate(), Ok(()));
    }

    /// One-degree-of-freedom oscillator `m ẍ + k x = 0` (x along the first
    /// axis, m = 1) advanced with the weights of `scheme`: the velocity
    /// solves `m (c V − c Vⁿ − c_a Aⁿ) + k X(V) = 0`, `X` linear in `V`.
    /// Returns the largest amplitude `√(x² + v²/ω²)` over the last period
    /// and the position error against `cos ωt` at the end.
    fn oscillate(scheme: Scheme, omega: f64, dt: f64, steps: usize) -> (f64, f64) {
        let k = omega * omega;
        let (mut x, mut v, mut a) = (1.0, 0.0, -k);
        let period_steps = (2.0 * std::f64::consts::PI / omega / dt).ceil() as usize;
        let mut amplitude: f64 = 0.0;
        for n in 0..steps {
            let w = SchemeWeights::new(scheme, -0.3, dt);
            let inertia = w.inertia();
            let p = |x: f64| Point::<2>::new(x, 0.0);
            let vec = |v: f64| Vector::<2>::new(v, 0.0);
            let x_of = |vel: f64| w.position(&p(x), &vec(v), &vec(a), &vec(vel)).x;
            let (x0, x1) = (x_of(0.0), x_of(1.0));
            // c V − c Vⁿ − c_a Aⁿ + k (x0 + (x1 − x0) V) = 0
            let c = inertia.mass_factor;
            let vel = (c * v + inertia.acceleration_factor * a - k * x0) / (c + k * (x1 - x0));
            let a_new = w.acceleration(&vec(v), &vec(a), &vec(vel)).x;
            x = x_of(vel);
            v = vel;
            a = a_new;
            if n + period_steps >= steps {
                amplitude = amplitude.max((x * x + v * v / k).sqrt());
            }
        }
        let t = steps as f64 * dt;
        (amplitude, (x - (omega * t).cos()).abs())
    }

    /// α_B = 0 is the trapezoidal rule: the same weights bit for bit in
    /// the inertia, and the same trajectory.
    #[test]
    fn bossak_with_zero_alpha_is_the_trapezoidal_rule() {
        let dt = 0.01;
        let n = SchemeWeights::new(Scheme::Newmark, 0.0, dt);
        let b = SchemeWeights::new(Scheme::Bossak, 0.0, dt);
        assert!((n.inertia().mass_factor - b.inertia().mass_factor).abs() < 1e-12 * 200.0);
        assert_eq!(b.inertia().acceleration_factor, 1.0);
        let (xn, vn, an) = (
            Point::<2>::new(0.3, -0.1),
            Vector::<2>::new(1.0, 2.0),
            Vector::<2>::new(-3.0, 0.5),
        );
        let v = Vector::<2>::new(0.7, 1.9);
        let trapezoid = xn + (vn + v) * (0.5 * dt);
        assert!((b.position(&xn, &vn, &an, &v) - trapezoid).norm() < 1e-15);
        assert!((n.position(&xn, &vn, &an, &v) - trapezoid).norm() < 1e-15);
    }

    /// The trapezoidal rule keeps the amplitude of an undamped oscillator
    /// (within 1e-9 over 100 periods at ωΔt = 1); Bossak with
    /// α_B = −0.3 damps a mode far above the step (ωΔt = 100) to nothing
    /// within 60 steps (spectral radius at infinity 0.54 per step) and is
    /// second order on a resolved one (error ratio ≈ 4 when Δt halves,
    /// measured at a quarter period).
    #[test]
    fn bossak_damps_high_frequencies_and_stays_second_order() {
        let (amp, _) = oscillate(Scheme::Newmark, 1.0, 1.0, 629);
        assert!((amp - 1.0).abs() < 1e-9, "trapezoidal amplitude {amp}");
        let (amp_hf, _) = oscillate(Scheme::Bossak, 100.0, 1.0, 60);
        assert!(amp_hf < 1e-10, "Bossak high-frequency amplitude {amp_hf}");
        let omega = 2.0 * std::f64::consts::PI;
        // At a quarter period, where x crosses zero, the position error is
        // the phase error itself.
        let (_, e1) = oscillate(Scheme::Bossak, omega, 0.01, 25);
        let (_, e2) = oscillate(Scheme::Bossak, omega, 0.005, 50);
        let ratio = e1 / e2;
        assert!(
            (3.5..4.5).contains(&ratio),
            "error ratio {ratio} ({e1:e} → {e2:e})"
        );
    }
}
