//! The material of contact elements (`pfem_geometry::contact`): a penalty
//! layer between two bodies that resists the closing of the gap and,
//! with friction, the sliding across it up to Coulomb's limit.
//!
//! A contact element is a simplex spanning the gap between two bodies. Its
//! gap at the start of the step `gⁿ` over the contact distance `g₀` (where
//! particles of two bodies at rest sit: half the sum of their spacings,
//! set by the driver) is `rⁿ`; the gap at
//! the iterate follows the element's volume, `g/g₀ = J rⁿ`. The normal
//! pressure is the penalty
//!
//! `p = K_c s_δ(1 − g/g₀)`, `s_δ(x) = 0` for `x ≤ 0`, `x²/(2δ)` for
//! `0 < x < δ`, `x − δ/2` beyond: the penalty's kink at the contact
//! distance rounded over the first `δ` of the closure, so that `p` and its
//! slope are continuous and both vanish at `g = g₀`
//! ([`ContactPenalty::onset`] `δ`; `δ = 0` is the plain `max(0, x)`).
//!
//! and the tangential traction `τ` is elastic with stiffness `G_c` on the
//! shear strain of the layer, `τⁿ⁺¹ = τⁿ + G_c γ`, `γ = 2 (Δε n − (n·Δε n) n)`,
//! returned to the Coulomb cone `|τ| ≤ μ p` (stick inside, slip on it). The
//! stress is `σ = −p I + τ ⊗ n + n ⊗ τ`. A dashpot on the gap's rate
//! ([`ContactPenalty::damping`], grown in over the first [`DASHPOT_RAMP`]
//! of the onset) damps the contact's unresolved chatter. The element's
//! [`History::internal`] holds `[rⁿ, μ, nⁿ (3), τⁿ (3)]`; the driver sets
//! the first five when it forms the element, and `τ` is carried while the
//! same particles stay in contact (stick has memory).

use pfem_core::{Const, Dim, Tensor, Vector};

use crate::material::{History, Kinematics, Layer, Material, MaterialKind, Unified};

/// Slot of `gⁿ/g₀` in [`History::internal`].
pub const GAP_RATIO: usize = 0;
/// Slot of the friction coefficient.
pub const FRICTION: usize = 1;
/// First slot of the normal (3 slots).
pub const NORMAL: usize = 2;
/// First slot of the tangential traction (3 slots).
pub const TRACTION: usize = 5;

/// The dashpot ([`ContactPenalty::damping`]) grows in linearly over this
/// fraction of the rounded onset: at closure `x = 1 − g/g₀` its strength
/// is `min(1, x/(0.1 δ))` of the full (full at once with the kink).
/// Bodies at rest sit at `x` ≈ 10⁻⁴–10⁻³ (`δ` = 10⁻²), where it is
/// from a tenth to full strength and damps their ringing; a ramp over the
/// whole onset (a hundredth to a tenth there) left a 2D block at 20°
/// creeping 1.8 mm in 1 s against 0.03 mm.
pub const DASHPOT_RAMP: f64 = 0.1;

/// A contact layer whose gap an attempted step closes to this fraction of
/// its contact distance or less (`J rⁿ ≤ CLOSED_GAP`) has been pushed
/// through: its penalty is far too soft for the load, and the next
/// remeshing could not form it again (the driver leaves out contact
/// simplices flatter than the same fraction of a spacing), so the solid
/// would pass through the wall unseen. [`ContactPenalty`] refuses such a
/// state ([`Material::refuses`]): the step is retried smaller, and the run
/// fails with the bodies named when no step cures it.
pub const CLOSED_GAP: f64 = 0.05;

/// The penalty material of contact elements (module docs). Massless.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPenalty {
    /// Normal penalty `K_c` (Pa): the slope of the pressure against the
    /// gap's closure `1 − g/g₀` beyond the rounded onset (a gap closed
    /// entirely: `K_c (1 − δ/2)`).
    pub normal_stiffness: f64,
    /// Tangential stiffness `G_c` (Pa) of the layer while it sticks.
    pub shear_stiffness: f64,
    /// Normal damping `c` (dimensionless): while the gap is closed a
    /// dashpot adds `p_v = −c Δt K_c tr D` (`tr D` the rate of the
    /// layer's volume, `ġ/g`; grown in over the first [`DASHPOT_RAMP`] of
    /// the onset, and the pressure never below zero), so that a contact mode of frequency `ω`
    /// has the damping ratio `c ω Δt / 2`: strong on the contact's
    /// chatter that the step does not resolve (`ω Δt ≫ 1`), weak on
    /// motions it does (a bounce over many steps). 0 for none.
    pub damping: f64,
    /// Width `δ` of the penalty's rounded onset, as a fraction of the
    /// contact distance (dimensionless, `[0, ½]`): the pressure starts at
    /// `g = g₀` with zero slope, which grows linearly to `K_c` at
    /// `g = (1 − δ) g₀` (module docs). Bodies at rest sit within `σ/K_c`
    /// of `g₀`, the penalty's kink with `δ = 0`: any ringing then switched
    /// the layer's stiffness between 0 and `K_c` from one Picard iterate
    /// to the next. 0 for the kink.
    pub onset: f64,
}

/// What a contact element carries at an iterate.
struct State<const D: usize>
where
    Const<D>: Dim,
{
    sigma: Tensor<D>,
    pressure: f64,
    normal: Vector<D>,
    traction: Vector<D>,
    /// Stiffness factors of the linearisation: (shear, volumetric).
    tangent: (f64, f64),
    /// Unit slip direction while slipping, zero while sticking.
    slip: Vector<D>,
}

impl ContactPenalty {
    /// A penalty of normal stiffness `K_c` and shear stiffness `G_c` (Pa),
    /// damping `c` and rounded onset `δ` (the fields' docs); a struct
    /// literal breaks when a field is added.
    pub fn new(normal_stiffness: f64, shear_stiffness: f64, damping: f64, onset: f64) -> Self {
        Self {
            normal_stiffness,
            shear_stiffness,
            damping,
            onset,
        }
    }

    fn state<const D: usize>(&self, kin: &Kinematics<D>, h: &History<D>) -> State<D>
    where
        Const<D>: Dim,
    {
        let zero = State {
            sigma: Tensor::<D>::zeros(),
            pressure: 0.0,
            normal: Vector::<D>::zeros(),
            traction: Vector::<D>::zeros(),
            tangent: (0.0, 0.0),
            slip: Vector::<D>::zeros(),
        };
        let ratio = h.internal[GAP_RATIO];
        if ratio <= 0.0 {
            return zero;
        }
        let r = kin.j * ratio;
        // The normal, convected by the step: n ∝ F⁻ᵀ nⁿ.
        let nn = Vector::<D>::from_fn(|k, _| h.internal[NORMAL + k]);
        let n = match kin.f.try_inverse() {
            Some(fi) => fi.transpose() * nn,
            None => nn,
        };
        let n = if n.norm() > 0.0 { n / n.norm() } else { n };
        let (p_elastic, slope) = self.rounded(1.0 - r);
        if p_elastic <= 0.0 || n.norm() == 0.0 {
            return State { normal: n, ..zero };
        }
        // The dashpot grows in over the first tenth of the onset
        // (`DASHPOT_RAMP`; at once with the kink): at full strength from
        // `g₀` on, its `c |tr D|` switched on from nothing as a closing gap
        // passed `g₀`, a jump in the pressure, and the Picard iterates of a
        // 3D post clamped one spacing from the side walls alternated
        // between two states (session 38).
        //
        // The ramp's own derivative, `−c_full tr D φ'(x) r w` (x falls by
        // `r w` per unit rate), is in the linearisation: left out, a
        // cantilever landing on a floor had 68 of 417 steps rejected
        // (2-cycles); with it, 10 of 315. While the pressure is positive
        // the whole tangent is too (the term is bounded by half the
        // penalty's slope there); the `max(0, ·)` below only guards a
        // negative damping. (`x > 0` here: the penalty pushes.)
        let x = 1.0 - r;
        let rate = kin.volumetric_rate();
        let w = kin.displacement_weight;
        let c_full = self.damping * kin.dt * self.normal_stiffness;
        let ramp = DASHPOT_RAMP * self.onset.max(0.0);
        let (c, ramp_slope) = if ramp > 0.0 && x < ramp {
            (c_full * (x / ramp), -c_full * rate / ramp * r * w)
        } else {
            (c_full, 0.0)
        };
        // (A non-finite rate gives a non-finite pressure, which the
        // assembly refuses with the element named; `max(0, ·)` used to
        // turn a NaN into 0.)
        let p = p_elastic - c * rate;
        if p <= 0.0 {
            // The dashpot holds the layer open faster than the penalty
            // closes it: no pressure, and no stiffness either (the
            // derivative of `max(0, ·)` there). Until session 38 the
            // linearisation kept `K_c s' r w + c` here, which the
            // pressure does not have: a 3D stiff block resting beside
            // the walls took 57 steps (18 rejected by Picard, the iterates
            // converging linearly at 0.75) for 0.02 s, against 14 (2).
            return State { normal: n, ..zero };
        }
        let de = kin.strain_increment();
        let den = de * n;
        let gamma = (den - n * n.dot(&den)) * 2.0;
        let old = Vector::<D>::from_fn(|k, _| h.internal[TRACTION + k]);
        let old = old - n * n.dot(&old);
        let trial = old + gamma * self.shear_stiffness;
        let cap = h.internal[FRICTION].max(0.0) * p;
        // Return to the Coulomb cone. While slipping along `m` the
        // traction's derivative by the shear is 0 along `m` and the secant
        // `G_c |τ|/|τ_trial|` across it: the layer's linearisation
        // (`Unified::layer`, the `Layer`'s slip direction) takes both, and
        // in 2D, with one tangential direction, it has none. The cap's
        // dependence on the volume change (`μ p'`) and the normal's
        // turning with the shear are left out. Before session 38 the
        // linearisation was isotropic (`2 μ D'`, one scalar for every
        // shear, which overstated the normal stiffness ×2.3); the elastic
        // tangent `G_c` while slipping was tried then: a
        // frictionless block resting on a floor took 2 471 steps (798
        // rejected by Picard) for 0.5 s against 250 (none).
        let zero_slip = Vector::<D>::zeros();
        let tn = trial.norm();
        let (traction, shear_factor, slip) = if tn > cap {
            (trial * (cap / tn), cap / tn, trial / tn)
        } else {
            (trial, 1.0, zero_slip)
        };
        let sigma =
            Tensor::<D>::identity() * (-p) + traction * n.transpose() + n * traction.transpose();
        State {
            sigma,
            pressure: p,
            normal: n,
            traction,
            slip,
            tangent: (
                self.shear_stiffness * w * shear_factor,
                (self.normal_stiffness * slope * r * w + c + ramp_slope).max(0.0),
            ),
        }
    }

    /// The elastic normal pressure `K_c s_δ(x)` of a closure `x = 1 − g/g₀`
    /// and the slope `s_δ'(x)` (module docs).
    fn rounded(&self, x: f64) -> (f64, f64) {
        // A public struct: a negative or NaN width is the kink.
        let d = self.onset.max(0.0);
        if x <= 0.0 {
            (0.0, 0.0)
        } else if x >= d {
            (self.normal_stiffness * (x - 0.5 * d), 1.0)
        } else {
            (self.normal_stiffness * x * x / (2.0 * d), x / d)
        }
    }

    /// The normal pressure of a contact element at the end of its last
    /// step (Pa), from its history (its stress trace).
    pub fn pressure<const D: usize>(h: &History<D>) -> f64
    where
        Const<D>: Dim,
    {
        -h.stress.trace() / D as f64
    }
}

impl<const D: usize> Material<D> for ContactPenalty
where
    Const<D>: Dim,
{
    fn name(&self) -> &str {
        "contact penalty"
    }

    fn kind(&self) -> MaterialKind {
        MaterialKind::Solid
    }

    /// Massless: the layer adds no inertia.
    fn density(&self) -> f64 {
        0.0
    }

    /// No wave of its own (massless); the bodies' waves bound the step.
    fn wave_speed(&self) -> f64 {
        0.0
    }

    fn unified(&self, kin: &Kinematics<D>, history: &History<D>) -> Unified<D> {
        let s = self.state(kin, history);
        let zz = if D == 2 { -s.pressure } else { 0.0 };
        // The layer resists the shear across its plane alone: its
        // linearisation is `2 G_c P(D)`, not the isotropic `2 G_c D'`
        // ([`Unified::layer`]).
        if s.normal.norm() > 0.0 {
            let layer = Layer {
                normal: s.normal,
                slip: s.slip,
            };
            Unified::returning_layer(s.tangent.0, s.tangent.1, layer, s.sigma, zz, kin)
        } else {
            Unified::returning(s.tangent.0, s.tangent.1, s.sigma, zz, kin)
        }
    }

    /// A layer the step closes across [`CLOSED_GAP`] of its contact
    /// distance. One formed below it (a fine body on a coarse one: the
    /// driver forms down to 5 % of the element's mean spacing, which is
    /// below 5 % of the pair's contact distance) is refused only when a
    /// step halves it (`J < ½`): any closure at all could not be cured by
    /// a smaller step, whose `J` only nears 1 from below.
    fn refuses(&self, kin: &Kinematics<D>, history: &History<D>) -> Option<String> {
        let ratio = history.internal[GAP_RATIO];
        if ratio <= 0.0 {
            return None;
        }
        let r = kin.j * ratio;
        let closed = if ratio > CLOSED_GAP {
            r <= CLOSED_GAP
        } else {
            kin.j < 0.5
        };
        closed.then(|| {
            if ratio > CLOSED_GAP {
                format!(
                    "the contact layer closed to {:.2} % of its contact distance in one step (from {:.2} %): its penalty K_c = {:e} Pa is too soft for the load; raise the contact stiffness",
                    100.0 * r,
                    100.0 * ratio,
                    self.normal_stiffness
                )
            } else {
                // Closed before the step began: a smaller step cannot open
                // it, nor can a stiffer penalty alone (the message said
                // "closed … in one step (from 5.00 %) … too soft", which
                // no stiffness cured: session 54's review).
                format!(
                    "the contact layer was closed to {:.2} % of its contact distance when the step began, and closed to {:.2} % (the bodies met inside it between two remeshings, too fast for the steps: lower max_dt; its penalty is K_c = {:e} Pa)",
                    100.0 * ratio,
                    100.0 * r,
                    self.normal_stiffness
                )
            }
        })
    }

    fn update_history(&self, kin: &Kinematics<D>, history: &mut History<D>) {
        let s = self.state(kin, history);
        history.stress = s.sigma;
        history.stress_zz = if D == 2 { -s.pressure } else { 0.0 };
        for k in 0..D {
            history.internal[NORMAL + k] = s.normal[k];
            history.internal[TRACTION + k] = s.traction[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kin(f: Tensor<2>) -> Kinematics<2> {
        let mut k = Kinematics::<2>::at_rest(1e-3);
        k.f = f;
        k.j = f.determinant();
        k.displacement_weight = 1e-3;
        k
    }

    fn penalty() -> ContactPenalty {
        ContactPenalty {
            normal_stiffness: 1e6,
            shear_stiffness: 1e6,
            damping: 0.0,
            onset: 0.0,
        }
    }

    #[test]
    fn the_rounded_onset_is_continuous_with_its_slope() {
        let d = 0.01;
        let m = ContactPenalty {
            onset: d,
            ..penalty()
        };
        let k = m.normal_stiffness;
        // Continuous, with a continuous slope, at both ends of the band.
        for x0 in [0.0, d] {
            let (below, s_below) = m.rounded(x0 - 1e-12);
            let (above, s_above) = m.rounded(x0 + 1e-12);
            assert!(
                (below - above).abs() < 1e-5 * k * d,
                "{x0}: {below} {above}"
            );
            assert!(
                (s_below - s_above).abs() < 1e-8,
                "{x0}: {s_below} {s_above}"
            );
        }
        // The slope is the pressure's derivative inside the band.
        for x in [0.1 * d, 0.5 * d, 0.9 * d, 2.0 * d] {
            let e = 1e-7 * d;
            let fd = (m.rounded(x + e).0 - m.rounded(x - e).0) / (2.0 * e);
            assert!((fd / k - m.rounded(x).1).abs() < 1e-6, "{x}");
        }
        // At the contact distance nothing pushes, as with the kink: bodies
        // set one spacing apart start unloaded.
        assert_eq!(m.rounded(0.0), (0.0, 0.0));
        assert_eq!(m.rounded(-0.5 * d), (0.0, 0.0));
        // A negative or NaN width (the struct is public) is the kink: no
        // pressure while the gap is open.
        for bad in [-d, f64::NAN] {
            let b = ContactPenalty {
                onset: bad,
                ..penalty()
            };
            assert_eq!(b.rounded(-0.25 * d), (0.0, 0.0));
            assert_eq!(b.rounded(0.05), penalty().rounded(0.05));
        }
        // Half-way through the band: K_c δ/8, half the stiffness.
        assert!((m.rounded(0.5 * d).0 - 0.125 * d * k).abs() < 1e-9 * k);
        assert_eq!(m.rounded(0.5 * d).1, 0.5);
        // Beyond the band, the plain penalty less K_c δ/2.
        let (p, slope) = m.rounded(0.05);
        assert!((p - k * (0.05 - 0.5 * d)).abs() < 1e-9 * k && slope == 1.0);
        // Through the element: closed by 0.5 δ, the layer is stiff where
        // the kink's is too; closed by 0.01 δ, it is nearly free where the
        // kink's already has all of `K_c`.
        let h = layer(1.0, 0.0);
        for (closed, ratio) in [(0.5 * d, 0.5), (0.01 * d, 0.01)] {
            let f = Tensor::<2>::new(1.0, 0.0, 0.0, 1.0 - closed);
            let rounded = m.state(&kin(f), &h);
            let kink = penalty().state(&kin(f), &h);
            assert!(rounded.pressure > 0.0);
            let r = rounded.tangent.1 / kink.tangent.1;
            assert!((r - ratio).abs() < 1e-6, "{closed}: {r}");
        }
    }

    fn layer(ratio: f64, mu: f64) -> History<2> {
        let mut h = History::<2>::default();
        h.internal[GAP_RATIO] = ratio;
        h.internal[FRICTION] = mu;
        h.internal[NORMAL + 1] = 1.0; // n = +y
        h
    }

    /// Session 45: a layer a step closes to 5 % of its contact distance
    /// is refused (the next remeshing would drop it, and its solid would
    /// pass through); one formed that close is refused only when a step
    /// closes it further, and an opening or unchanged layer never.
    #[test]
    fn a_layer_closed_through_its_gap_is_refused() {
        let m = penalty();
        let squeeze = |j: f64| kin(Tensor::<2>::new(1.0, 0.0, 0.0, j));
        let refuses = |ratio: f64, j: f64| {
            <ContactPenalty as Material<2>>::refuses(&m, &squeeze(j), &layer(ratio, 0.0))
        };
        // From the contact distance to 4 % of it in one step.
        let why = refuses(1.0, 0.04).expect("closed through");
        assert!(why.contains("raise the contact stiffness"), "{why}");
        // To 6 %: held.
        assert!(refuses(1.0, 0.06).is_none());
        // Formed at 4.5 % (a fine body on a coarse one): held as it is,
        // opening or settling (a smaller step would not cure a closure of
        // any size: its J nears 1 from below), refused when halved.
        assert!(refuses(0.045, 1.0).is_none());
        assert!(refuses(0.045, 1.1).is_none());
        assert!(refuses(0.045, 1.0 - 1e-12).is_none());
        assert!(refuses(0.045, 0.9).is_none());
        assert!(refuses(0.045, 0.4).is_some());
        // No layer (ratio 0): nothing to refuse.
        assert!(refuses(0.0, 0.01).is_none());
    }

    #[test]
    fn the_gap_closing_gives_the_penalty_pressure_and_opening_none() {
        let m = penalty();
        // Compressed by 1 % along n: p = K (1 − 0.99).
        let h = layer(1.0, 0.0);
        let s = m.state(&kin(Tensor::<2>::new(1.0, 0.0, 0.0, 0.99)), &h);
        assert!((s.pressure - 1e4).abs() < 1e-6, "{}", s.pressure);
        assert!((s.sigma[(1, 1)] + 1e4).abs() < 1e-6);
        // Opened: nothing.
        let s = m.state(&kin(Tensor::<2>::new(1.0, 0.0, 0.0, 1.01)), &h);
        assert_eq!(s.pressure, 0.0);
        assert_eq!(s.sigma, Tensor::<2>::zeros());
    }

    #[test]
    fn shear_sticks_below_coulomb_and_slips_on_it() {
        let m = penalty();
        // p = 1e4 Pa; a shear F_xy = 1e-3 gives τ ≈ G γ = 1e3 Pa < μ p.
        let h = layer(1.0, 0.5);
        let f = Tensor::<2>::new(1.0, 1e-3, 0.0, 0.99);
        let s = m.state(&kin(f), &h);
        assert!(s.traction.norm() < 0.5 * s.pressure);
        assert!(s.traction.norm() > 0.0);
        // Sticking, the linearisation's shear stiffness is the layer's.
        assert_eq!(s.tangent.0, m.shear_stiffness * 1e-3);
        // A shear ten times larger reaches the cone: |τ| = μ p.
        let f = Tensor::<2>::new(1.0, 2e-2, 0.0, 0.99);
        let s = m.state(&kin(f), &h);
        assert!((s.traction.norm() - 0.5 * s.pressure).abs() < 1e-6 * s.pressure);
        // Slipping in 2D: the traction does not change along the one
        // tangential direction, and neither does the linearisation's
        // stress: a shear rate gives none.
        let u = Material::<2>::unified(&m, &kin(f), &h);
        let mut shear = kin(f);
        shear.d = Tensor::<2>::new(0.0, 1.0, 1.0, 0.0);
        assert!(u.linear_stress(&shear).0.norm() < 1e-12 * m.shear_stiffness);
        // Sticking, it does: 2 μ on the shear.
        let f = Tensor::<2>::new(1.0, 1e-3, 0.0, 0.99);
        let u = Material::<2>::unified(&m, &kin(f), &h);
        let s2 = u.linear_stress(&shear).0;
        assert!((s2[(0, 1)] - 2.0 * m.shear_stiffness * 1e-3).abs() < 1e-9);
        // Nor does it resist a stretch along the plane or (beyond the
        // volumetric part) across it.
        let mut stretch = kin(f);
        stretch.d = Tensor::<2>::new(1.0, 0.0, 0.0, -1.0);
        assert!(u.linear_stress(&stretch).0.norm() < 1e-12 * m.shear_stiffness);
        // Without friction no traction.
        let s = m.state(&kin(f), &layer(1.0, 0.0));
        assert_eq!(s.traction.norm(), 0.0);
    }

    #[test]
    fn slipping_in_3d_resists_only_across_the_slip() {
        let m = penalty();
        let mut h = History::<3>::default();
        h.internal[GAP_RATIO] = 1.0;
        h.internal[FRICTION] = 0.5;
        h.internal[NORMAL + 1] = 1.0;
        let mut k = Kinematics::<3>::at_rest(1e-3);
        k.f = Tensor::<3>::new(1.0, 2e-2, 0.0, 0.0, 0.99, 0.0, 0.0, 0.0, 1.0);
        k.j = k.f.determinant();
        k.displacement_weight = 1e-3;
        let s = m.state(&k, &h);
        let trial = m.shear_stiffness * 2.0 * k.strain_increment()[(0, 1)];
        // It slips: on the cone, well inside the trial.
        assert!((s.traction.norm() - 0.5 * s.pressure).abs() < 1e-6 * s.pressure);
        assert!(trial.abs() > 2.0 * s.traction.norm());
        let secant = m.shear_stiffness * 1e-3 * s.traction.norm() / trial.abs();
        assert!(
            (s.tangent.0 / secant - 1.0).abs() < 1e-9,
            "{} {secant}",
            s.tangent.0
        );
        // The slip is along x (n = y): a shear rate along it meets no
        // stiffness, one across it (z) the secant.
        let u = Material::<3>::unified(&m, &k, &h);
        let mut along = k;
        along.d = Tensor::<3>::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert!(u.linear_stress(&along).0.norm() < 1e-12 * m.shear_stiffness);
        let mut across = k;
        across.d = Tensor::<3>::new(0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0);
        let sa = u.linear_stress(&across).0;
        assert!((sa[(1, 2)] / (2.0 * s.tangent.0) - 1.0).abs() < 1e-9);
    }

    /// The layer's triple returns its stress exactly at the iterate, in
    /// 2D (with `σ_zz = −p`) and 3D, sticking and slipping.
    #[test]
    fn the_layer_returns_its_stress_at_the_iterate() {
        let m = ContactPenalty {
            damping: 0.1,
            onset: 0.01,
            ..penalty()
        };
        for f in [
            Tensor::<2>::new(1.0, 1e-3, 0.0, 0.99),
            Tensor::<2>::new(1.0, 2e-2, 0.0, 0.99),
        ] {
            let mut k = kin(f);
            k.d = Tensor::<2>::new(0.3, 0.7, 0.7, -0.2);
            let h = layer(1.0, 0.5);
            let s = m.state(&k, &h);
            let u = Material::<2>::unified(&m, &k, &h);
            assert!(u.layer.is_some());
            assert!((u.cauchy_stress(&k) - s.sigma).norm() <= 1e-9 * s.sigma.norm());
            assert!((u.cauchy_stress_zz(&k) + s.pressure).abs() <= 1e-9 * s.pressure);
        }
        let mut h = History::<3>::default();
        h.internal[GAP_RATIO] = 1.0;
        h.internal[FRICTION] = 0.5;
        h.internal[NORMAL + 1] = 1.0;
        for shear in [1e-3, 2e-2] {
            let mut k = Kinematics::<3>::at_rest(1e-3);
            k.f = Tensor::<3>::new(1.0, shear, 0.0, 0.0, 0.99, 0.0, 0.0, 3e-3, 1.0);
            k.j = k.f.determinant();
            k.displacement_weight = 1e-3;
            k.d = Tensor::<3>::new(0.3, 0.7, 0.1, 0.7, -0.2, 0.4, 0.1, 0.4, 0.5);
            let s = m.state(&k, &h);
            let u = Material::<3>::unified(&m, &k, &h);
            assert!(s.pressure > 0.0 && u.layer.is_some());
            assert!((u.cauchy_stress(&k) - s.sigma).norm() <= 1e-9 * s.sigma.norm());
        }
    }

    /// Where the dashpot holds the layer open (the gap closed, but opening
    /// fast enough that `K_c s(x) − c Δt K_c tr D ≤ 0`) there is no
    /// pressure and no stiffness: the linearisation is the clamp's zero
    /// derivative. Bug fixed (session 38): it kept `K_c s' r w + c`.
    #[test]
    fn a_layer_held_open_by_its_dashpot_has_no_stiffness() {
        let m = ContactPenalty {
            damping: 0.1,
            ..penalty()
        };
        let h = layer(1.0, 0.5);
        let f = Tensor::<2>::new(1.0, 0.0, 0.0, 0.99);
        // Closing (or still): pressure and stiffness.
        let mut k = kin(f);
        k.d = Tensor::<2>::new(0.0, 0.0, 0.0, -1.0);
        let s = m.state(&k, &h);
        assert!(s.pressure > 0.0 && s.tangent.1 > 0.0);
        // Opening at 10⁴ s⁻¹: the dashpot's 0.1 × 10⁻³ s × 10⁶ Pa × 10⁴ s⁻¹
        // = 10⁶ Pa outweighs the penalty's 10⁴ Pa.
        k.d = Tensor::<2>::new(0.0, 0.0, 0.0, 1e4);
        let s = m.state(&k, &h);
        assert_eq!(s.pressure, 0.0);
        assert_eq!(s.tangent, (0.0, 0.0));
        assert_eq!(s.sigma, Tensor::<2>::zeros());
        let u = Material::<2>::unified(&m, &k, &h);
        assert_eq!((u.mu, u.kappa), (0.0, 0.0));
    }

    /// The dashpot grows in over the first tenth of the onset: a gap
    /// closing past `g₀` meets a pressure that starts from zero, not the
    /// dashpot's full `c |tr D|` at once. Bug fixed (session 38): that
    /// jump made the Picard iterates of a 3D post clamped beside the walls
    /// alternate between two states.
    #[test]
    fn the_dashpot_grows_in_without_a_jump() {
        let m = ContactPenalty {
            damping: 0.1,
            onset: 0.01,
            ..penalty()
        };
        let h = layer(1.0, 0.0);
        // Closing at 1 s⁻¹: the full dashpot is 0.1 × 10⁻³ s × 10⁶ Pa = 100 Pa.
        let at = |x: f64| {
            let mut k = kin(Tensor::<2>::new(1.0, 0.0, 0.0, 1.0 - x));
            k.d = Tensor::<2>::new(0.0, 0.0, 0.0, -1.0);
            m.state(&k, &h).pressure
        };
        let elastic = |x: f64| m.rounded(x).0;
        assert!(at(1e-7) < 0.02, "{}", at(1e-7));
        assert!((at(5e-4) - elastic(5e-4) - 50.0).abs() < 1e-6);
        assert!((at(2e-3) - elastic(2e-3) - 100.0).abs() < 1e-6);
        // With the kink it is there at once.
        let kink = ContactPenalty { onset: 0.0, ..m };
        let mut k = kin(Tensor::<2>::new(1.0, 0.0, 0.0, 1.0 - 1e-7));
        k.d = Tensor::<2>::new(0.0, 0.0, 0.0, -1.0);
        assert!((kink.state(&k, &h).pressure - 100.1).abs() < 1e-6);
        // So is a negative or NaN onset (the struct is public).
        for bad in [-0.01, f64::NAN] {
            let b = ContactPenalty { onset: bad, ..m };
            assert!((b.state(&k, &h).pressure - 100.1).abs() < 1e-6);
        }
        // Continuous where the ramp ends (x = 0.1 δ = 10⁻³).
        let (below, above) = (at(1e-3 - 1e-12), at(1e-3 + 1e-12));
        assert!((below - above).abs() < 1e-6, "{below} {above}");
    }

    /// In the dashpot's ramp the pressure's derivative by the volume's
    /// rate is the linearisation's `𝒦`, the ramp's own slope included:
    /// kinematics made consistent (`F = I + w L`, `D = sym L`) and
    /// differenced along a volumetric `L`. Bug fixed (session 38): the
    /// ramp's slope was left out, and a cantilever landing on a floor had
    /// 68 of 417 steps rejected by Picard (10 of 315 with it).
    #[test]
    fn the_linearisation_follows_the_pressure_through_the_dashpot_ramp() {
        let m = ContactPenalty {
            damping: 0.1,
            onset: 0.01,
            ..penalty()
        };
        // A displacement weight other than the step (the trapezoidal rule's
        // Δt/2), so that the one cannot stand for the other.
        let w = 5e-4;
        // The gap ratio puts the layer at x ≈ 5·10⁻⁴, halfway up the ramp.
        let h = layer(1.0 - 5e-4, 0.0);
        let state = |l: Tensor<2>| {
            let mut k = Kinematics::<2>::at_rest(1e-3);
            k.f = Tensor::<2>::identity() + l * w;
            k.j = k.f.determinant();
            k.d = (l + l.transpose()) * 0.5;
            k.displacement_weight = w;
            m.state(&k, &h)
        };
        for rate in [-0.2, -0.1, 0.02] {
            let l = Tensor::<2>::new(0.0, 0.0, 0.0, rate);
            let s = state(l);
            assert!(s.pressure > 0.0);
            let e = 1e-6;
            let dl = Tensor::<2>::identity() * (0.5 * e);
            let fd = -(state(l + dl).pressure - state(l - dl).pressure) / (2.0 * e);
            assert!(
                (fd - s.tangent.1).abs() <= 1e-3 * fd.abs(),
                "rate {rate}: {fd} against {}",
                s.tangent.1
            );
        }
    }
}
