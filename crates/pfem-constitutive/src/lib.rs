//! Constitutive laws for pfem (Marti & Idelsohn 2007, §3).
//!
//! Every material answers one question of the solver, in the unified form of
//! eqs. 43–44: for the kinematics of the current Picard iterate
//! ([`Kinematics`]: `F`, `J`, `D`, `Δt`, `∂Δu/∂V`) and the history at `t_n`
//! ([`History`]: pressure or stress), what are
//!
//! - the effective viscosity `μ` (Pa·s),
//! - the effective volumetric coefficient `𝒦` (Pa·s), and
//! - the history stress `σ̂⁽ⁿ⁾` (Pa),
//!
//! so that the Cauchy stress at `t_{n+1}` is
//! `σ = σ̂⁽ⁿ⁾ + 𝒦 ε_v I + 2 μ D'` (eq. 43), with `ε_v = tr D` (eq. 19) and
//! `D' = D − ⅓ ε_v I` (eq. 20); a contact layer ([`ContactPenalty`]) has
//! `2 μ P(D)`, the shear across its plane, in place of `2 μ D'`
//! ([`Unified::layer`]). That triple is a [`Unified`]; the trait is
//! [`Material`], object safe, held by the solver as `Box<dyn Material<D>>`.
//! After the step converges the solver calls [`Material::update_history`]
//! once per solid element (eq. 63) and [`Material::update_pressure`] once
//! per fluid node (eq. 62).
//!
//! | law | `μ` | `𝒦` | `σ̂⁽ⁿ⁾` |
//! |---|---|---|---|
//! | [`Newtonian`] fluid (eqs. 16–27) | `μ_f` | `Δt K_f` | `−pⁿ I` |
//! | [`Hypoelastic`] solid (eqs. 28–42) | `μ_h w / J` | `(λ_h + ⅔ μ_h) w / J` | `F σⁿ Fᵀ / J` + `P (C : Δε) P / det P` − `(𝒦 ε_v I + 2 μ D')` |
//! | [`ContactPenalty`] layer (not in the paper) | `G_c w` sticking, its secant across the slip slipping | `K_c s_δ' r w` + dashpot | `σ` of the layer − `(𝒦 ε_v I + 2 μ P(D))` |
//!
//! For the solid, `w = ∂Δu/∂V` ([`Kinematics::displacement_weight`]: `Δt`
//! for backward Euler, `(β/γ) Δt` for the Newmark family: about 0.53 `Δt`
//! for Bossak at α_B = −0.3, the default, `Δt/2` for the trapezoidal rule), `Δε` the
//! objective strain increment of the step's displacement
//! ([`Kinematics::strain_increment`]) and `P` its half-step convection: the stress at the iterate follows the
//! displacement the time scheme made, and `σ̂` is that stress less its part
//! the system treats as linear in the velocity, so that eq. 43 returns it
//! exactly at every Picard iterate (see [`Hypoelastic`]).
//!
//! Materials are immutable configuration, validated at construction
//! ([`MaterialError`]); their history is state the solver owns. One
//! implementation serves 2D (plane strain, with the out-of-plane stress
//! carried in [`History::stress_zz`]) and 3D.
//!
//! # Example
//!
//! ```
//! use pfem_constitutive::{History, Hypoelastic, Kinematics, Material, Newtonian, Tensor};
//!
//! // The solver holds materials as trait objects.
//! let materials: Vec<Box<dyn Material<2>>> = vec![
//!     Box::new(Newtonian::water()),
//!     Box::new(Hypoelastic::new(1100.0, 12.0e6, 0.4)?),
//! ];
//!
//! // Kinematics of one element: a small simple shear over Δt = 1 ms.
//! let dt = 1e-3;
//! let gamma_dot = 2.0; // 1/s
//! let f = Tensor::<2>::new(1.0, gamma_dot * dt, 0.0, 1.0);
//! let d = Tensor::<2>::new(0.0, 0.5 * gamma_dot, 0.5 * gamma_dot, 0.0);
//! let kin = Kinematics::new(f, d, dt);
//!
//! for m in &materials {
//!     let mut history = History::default();
//!     let u = m.unified(&kin, &history); // eq. 44, once per Picard iterate
//!     let sigma = u.cauchy_stress(&kin); // eq. 43
//!     // Shear stress τ = 2 μ D'_xy = μ γ̇ for both laws (the solid's follows
//!     // the displacement F, equal to Δt D up to (γ̇ Δt)²).
//!     assert!((sigma[(0, 1)] - u.mu * gamma_dot).abs() <= 1e-5 * sigma[(0, 1)].abs());
//!     m.update_history(&kin, &mut history); // eqs. 62–63, once converged
//! }
//!
//! // Water's shear stress is μ_f γ̇ = 2 mPa.
//! let water = &materials[0];
//! let tau = water.unified(&kin, &History::default()).cauchy_stress(&kin)[(0, 1)];
//! assert!((tau - 2.0e-3).abs() < 1e-15);
//! # Ok::<(), pfem_constitutive::MaterialError>(())
//! ```
//!
//! # Writing your own material
//!
//! Implement [`Material`] for a configuration type: return the triple of
//! eq. 44 from [`Material::unified`] and advance the history in
//! [`Material::update_history`]. A fluid keeps its history in
//! [`History::pressure`] and is updated per node with an isotropic `D`, so
//! its `update_history` must use only `tr D`; a solid keeps
//! [`History::stress`] (and `stress_zz` in 2D) per element. The
//! crate's `tests/custom_material.rs` writes a regularised Bingham fluid
//! this way.

pub mod contact;
pub mod error;
pub mod hypoelastic;
pub mod material;
pub mod newtonian;

pub use contact::ContactPenalty;
pub use error::{MaterialError, Parameter};
pub use hypoelastic::Hypoelastic;
pub use material::*;
pub use newtonian::Newtonian;
pub use pfem_core::{Const, Dim, Tensor};
