//! Prescribed rigid motions of walls in time ([`crate::WallMotion::Law`]).

use pfem_core::{Const, Dim, Point, Vector};

use crate::SceneError;

/// A prescribed rigid motion: where a point that was at `x0` at `t = 0` is
/// at time `t`, and its velocity. Laws must be continuous in time and give
/// the velocity that is the derivative of the position. A law's `Debug`
/// text is its fingerprint in a checkpoint (a restart under a law that
/// prints otherwise is refused): print its parameters, not addresses.
pub trait MotionLaw<const D: usize>: Send + Sync + std::fmt::Debug
where
    Const<D>: Dim,
{
    /// Position at `t` of the point that was at `x0` at `t = 0` (m).
    fn position(&self, x0: &Point<D>, t: f64) -> Point<D>;
    /// Its velocity (m/s).
    fn velocity(&self, x0: &Point<D>, t: f64) -> Vector<D>;
    /// Its acceleration (m/s²), `None` (the default) where the law cannot
    /// tell: the wall's particles then carry the time scheme's value, which
    /// starts at zero and, under the trapezoidal rule, alternates about the
    /// true one for the whole run. The pressure force on a moving wall
    /// reads it (the inertia of the water it carries).
    fn acceleration(&self, x0: &Point<D>, t: f64) -> Option<Vector<D>> {
        let _ = (x0, t);
        None
    }
    /// Why the law cannot be followed (a parameter out of its range), or
    /// `Ok`: [`crate::Scene::validate`] refuses a wall with a law that
    /// fails it, naming the body. Default `Ok`.
    fn check(&self) -> Result<(), String> {
        Ok(())
    }
    /// The first time after `t` (beyond round-off) at which the velocity
    /// jumps (a table's row), if any; `None` (the default) for a law whose
    /// velocity is continuous. The driver ends a step there, so that no
    /// step straddles a kink: a step across one prescribed the next
    /// segment's velocity for the whole step, and the wall was then put
    /// back on its path by up to `Δt |Δv| / 2` after it (a quarter of a
    /// 1 cm spacing for a table's stop from 0.5 m/s at 1 ms steps).
    fn next_kink(&self, t: f64) -> Option<f64> {
        let _ = t;
        None
    }
    /// The velocity arriving at `t`: where the velocity jumps at `t` (a
    /// kink), its left limit, the one a step ending at `t` prescribes
    /// ([`MotionLaw::velocity`] is the right one, the velocity leaving
    /// `t`). Default [`MotionLaw::velocity`]. A law that gives kinks
    /// ([`MotionLaw::next_kink`]) gives this too: the default would
    /// prescribe the velocity leaving the kink for the step that ends on
    /// it.
    fn velocity_arriving(&self, x0: &Point<D>, t: f64) -> Vector<D> {
        self.velocity(x0, t)
    }
    /// An upper bound of the speed (m/s) of any point that starts in the
    /// box `[min, max]`, at any time; `None` (the default) where the law
    /// cannot tell. `Scene::validate` bounds the steps a run needs with it,
    /// as it does a constant wall velocity.
    fn max_speed(&self, min: &Point<D>, max: &Point<D>) -> Option<f64> {
        let _ = (min, max);
        None
    }
}

/// An upper bound of `|r(t) ω cos(ωt) + r'(t) sin(ωt)|` for the ramp `r`
/// over `ramp` seconds and `ω = 2π / period`: `r' ≤ π/2 / ramp` and, within
/// the ramp, `|sin ωt| ≤ ω t ≤ ω ramp`, so the second term is at most
/// `π/2 min(1/ramp, ω)` (the bound `π/2 / ramp` alone refused runs with a
/// ramp of a few microseconds as needing too many steps).
fn oscillation_rate(period: f64, ramp: f64) -> f64 {
    let w = (2.0 * std::f64::consts::PI / period).abs();
    w + if ramp > 0.0 {
        0.5 * std::f64::consts::PI * (1.0 / ramp).min(w)
    } else {
        0.0
    }
}

/// A sinusoidal translation `d(t) = A sin(2π t / T)`: a piston or flap
/// wave-maker's stroke.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoidal<const D: usize>
where
    Const<D>: Dim,
{
    /// Amplitude `A` (m), a vector: the stroke's direction and half-length.
    pub amplitude: Vector<D>,
    /// Period `T` (s).
    pub period: f64,
    /// Duration of a ramp of the amplitude from 0 (s); 0 for none. A ramp
    /// over a period or two spares the fluid the start-up jerk. The ramp
    /// is the half cosine `(1 − cos(π t / ramp)) / 2`: the wall's velocity
    /// is continuous at both of its ends whatever its length, and its
    /// acceleration too when the ramp is a multiple of half the period (a
    /// linear ramp, before session 43, ended with a jump of
    /// `A sin(2π ramp / T) / ramp` in velocity unless the ramp was such a
    /// multiple, and with a jump in acceleration always).
    pub ramp: f64,
}

impl<const D: usize> Sinusoidal<D>
where
    Const<D>: Dim,
{
    fn factor(&self, t: f64) -> (f64, f64) {
        ramp_factor(self.ramp, t)
    }
}

/// A half-cosine ramp from 0 to 1 over `ramp` seconds (none when 0),
/// `r = (1 − cos(π t / ramp)) / 2`, whose rate vanishes at both ends, and
/// that rate: `(r(t), r'(t))`. (A quintic `6s⁵ − 15s⁴ + 10s³`, whose
/// second derivative vanishes too, was tried: steeper in its middle, it
/// set the paddle test's tank sloshing at 0.893 s against the paddle's
/// 0.8 s; 0.803 s with this one.)
fn ramp_factor(ramp: f64, t: f64) -> (f64, f64) {
    let (r, dr, _) = ramp_derivatives(ramp, t);
    (r, dr)
}

/// `(r, r', r'')` of [`ramp_factor`]'s ramp at `t`.
fn ramp_derivatives(ramp: f64, t: f64) -> (f64, f64, f64) {
    // (A ramp so short that its square underflows is none.)
    if ramp * ramp > 0.0 && t < ramp {
        let (pi, s) = (std::f64::consts::PI, (t / ramp).max(0.0));
        (
            0.5 * (1.0 - (pi * s).cos()),
            0.5 * pi * (pi * s).sin() / ramp,
            0.5 * pi * pi * (pi * s).cos() / (ramp * ramp),
        )
    } else {
        (1.0, 0.0, 0.0)
    }
}

/// The second derivative of `r(t) sin(ω t)` (`ω = 2π / period`, `r` the
/// ramp): `r'' sin(ω t) + 2 r' ω cos(ω t) − r ω² sin(ω t)`.
fn oscillation_acceleration(period: f64, ramp: f64, t: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI / period;
    let (r, dr, ddr) = ramp_derivatives(ramp, t);
    ddr * (w * t).sin() + 2.0 * dr * w * (w * t).cos() - r * w * w * (w * t).sin()
}

impl<const D: usize> MotionLaw<D> for Sinusoidal<D>
where
    Const<D>: Dim,
{
    /// Its fields are public: a period that is not positive and finite,
    /// a ramp that is negative or not finite, or an amplitude that is not
    /// finite is refused here (a zero period gave NaN at `t = 0`, a
    /// negative one a negative speed bound).
    fn check(&self) -> Result<(), String> {
        if !(self.period > 0.0 && self.period.is_finite()) {
            return Err(format!(
                "the period {} s must be positive and finite",
                self.period
            ));
        }
        if !(self.ramp >= 0.0 && self.ramp.is_finite()) {
            return Err(format!(
                "the ramp {} s must be non-negative and finite",
                self.ramp
            ));
        }
        if self.amplitude.iter().any(|c| !c.is_finite()) {
            return Err("the amplitude must be finite".into());
        }
        Ok(())
    }
    fn position(&self, x0: &Point<D>, t: f64) -> Point<D> {
        let w = 2.0 * std::f64::consts::PI / self.period;
        let (r, _) = self.factor(t);
        x0 + self.amplitude * (r * (w * t).sin())
    }
    fn velocity(&self, _x0: &Point<D>, t: f64) -> Vector<D> {
        let w = 2.0 * std::f64::consts::PI / self.period;
        let (r, dr) = self.factor(t);
        self.amplitude * (r * w * (w * t).cos() + dr * (w * t).sin())
    }
    fn acceleration(&self, _x0: &Point<D>, t: f64) -> Option<Vector<D>> {
        Some(self.amplitude * oscillation_acceleration(self.period, self.ramp, t))
    }
    fn max_speed(&self, _min: &Point<D>, _max: &Point<D>) -> Option<f64> {
        Some(self.amplitude.norm() * oscillation_rate(self.period, self.ramp))
    }
}

/// A translation interpolated linearly in a table of `(t, displacement)`
/// rows (times increasing, the first at 0 with zero displacement); constant
/// after the last row.
#[derive(Debug, Clone, PartialEq)]
pub struct PiecewiseLinear<const D: usize>
where
    Const<D>: Dim,
{
    rows: Vec<(f64, Vector<D>)>,
    /// The rows' times where the velocity changes (beyond round-off), the
    /// last row's too unless the table ends at rest: [`MotionLaw::next_kink`].
    kinks: Vec<f64>,
}

impl<const D: usize> PiecewiseLinear<D>
where
    Const<D>: Dim,
{
    /// A table law; its rows must start at `t = 0` with zero displacement,
    /// with finite, strictly increasing times and finite displacements.
    pub fn new(rows: Vec<(f64, Vector<D>)>) -> Result<Self, SceneError> {
        let bad = |why: &str| SceneError::InvalidMotion {
            law: "a piecewise-linear motion",
            why: why.into(),
        };
        let Some(first) = rows.first() else {
            return Err(bad("the table is empty"));
        };
        if first.0 != 0.0 || first.1.norm() != 0.0 {
            return Err(bad("the first row must be t = 0 with zero displacement"));
        }
        if rows
            .iter()
            .any(|(t, d)| !t.is_finite() || d.iter().any(|c| !c.is_finite()))
        {
            return Err(bad("non-finite time or displacement"));
        }
        if rows.windows(2).any(|w| w[1].0 <= w[0].0) {
            return Err(bad("times must increase strictly"));
        }
        // The velocity of each segment, and zero after the last row.
        let slopes: Vec<Vector<D>> = rows
            .windows(2)
            .map(|w| (w[1].1 - w[0].1) / (w[1].0 - w[0].0))
            .chain(std::iter::once(Vector::<D>::zeros()))
            .collect();
        let kinks = (1..rows.len())
            .filter(|&j| {
                let (before, after) = (slopes[j - 1], slopes[j]);
                (after - before).norm() > 1e-9 * before.norm().max(after.norm())
            })
            .map(|j| rows[j].0)
            .collect();
        Ok(Self { rows, kinks })
    }

    /// Times within this of a row are at it (a step that lands on a row
    /// ends within round-off of it).
    fn tolerance(t: f64) -> f64 {
        8.0 * f64::EPSILON * t.abs() + f64::MIN_POSITIVE
    }

    /// Displacement and velocity at `t`: the velocity leaving `t` (at a
    /// row, the next segment's), or arriving at it (`arriving`: the last
    /// segment's).
    fn at(&self, t: f64, arriving: bool) -> (Vector<D>, Vector<D>) {
        let tol = Self::tolerance(t);
        let k = if arriving {
            self.rows.partition_point(|r| r.0 < t - tol)
        } else {
            self.rows.partition_point(|r| r.0 <= t + tol)
        };
        if k == 0 {
            return (Vector::<D>::zeros(), Vector::<D>::zeros());
        }
        if k == self.rows.len() {
            return (self.rows[k - 1].1, Vector::<D>::zeros());
        }
        let (t0, d0) = self.rows[k - 1];
        let (t1, d1) = self.rows[k];
        let s = (t - t0) / (t1 - t0);
        (d0 + (d1 - d0) * s, (d1 - d0) / (t1 - t0))
    }
}

impl<const D: usize> MotionLaw<D> for PiecewiseLinear<D>
where
    Const<D>: Dim,
{
    fn position(&self, x0: &Point<D>, t: f64) -> Point<D> {
        x0 + self.at(t, false).0
    }
    fn velocity(&self, _x0: &Point<D>, t: f64) -> Vector<D> {
        self.at(t, false).1
    }
    fn velocity_arriving(&self, _x0: &Point<D>, t: f64) -> Vector<D> {
        self.at(t, true).1
    }
    /// The rows where the velocity changes (to zero after the last, unless
    /// the table ends at rest); a row on a straight line is none.
    fn next_kink(&self, t: f64) -> Option<f64> {
        let tol = Self::tolerance(t);
        let k = self.kinks.partition_point(|&k| k <= t + tol);
        self.kinks.get(k).copied()
    }
    /// Zero: the velocity is constant between rows (the jumps at the rows
    /// are not accelerations a step can carry).
    fn acceleration(&self, _x0: &Point<D>, _t: f64) -> Option<Vector<D>> {
        Some(Vector::<D>::zeros())
    }
    fn max_speed(&self, _min: &Point<D>, _max: &Point<D>) -> Option<f64> {
        Some(
            self.rows
                .windows(2)
                .map(|w| (w[1].1 - w[0].1).norm() / (w[1].0 - w[0].0))
                .fold(0.0, f64::max),
        )
    }
}

/// A rigid rotation about `center` (and, in 3D, the unit `axis` through
/// it): the angle `θ(t) = ω t + A r(t) sin(2π t / T)` (rad), a steady spin
/// at `rate` ω plus an oscillation of amplitude `A` (a flap wave-maker's
/// stroke, hinged at `center`), its amplitude ramped from 0 over `ramp`
/// as in [`Sinusoidal`]. Positive angles turn x towards y in 2D, and
/// counter-clockwise about `axis` in 3D.
///
/// ```
/// use pfem_core::{Point, Vector};
/// use pfem_scene::motion::{MotionLaw, Rotation};
/// let spin = Rotation::<2>::new(Point::<2>::zeros(), None, std::f64::consts::PI, 0.0, 1.0, 0.0)?;
/// let p = spin.position(&Point::<2>::new(1.0, 0.0), 0.5); // a quarter turn
/// assert!((p - Point::<2>::new(0.0, 1.0)).norm() < 1e-12);
/// let v = spin.velocity(&Point::<2>::new(1.0, 0.0), 0.0);
/// assert!((v - Vector::<2>::new(0.0, std::f64::consts::PI)).norm() < 1e-12);
/// # Ok::<(), pfem_scene::SceneError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rotation<const D: usize>
where
    Const<D>: Dim,
{
    center: Point<D>,
    axis: [f64; 3],
    rate: f64,
    amplitude: f64,
    period: f64,
    ramp: f64,
}

impl<const D: usize> Rotation<D>
where
    Const<D>: Dim,
{
    /// A rotation about `center`; `axis` is required in 3D (normalised
    /// here) and ignored in 2D; `rate` ω (rad/s), `amplitude` A (rad),
    /// `period` T (s, positive when A is not 0) and `ramp` (s, ≥ 0).
    pub fn new(
        center: Point<D>,
        axis: Option<[f64; 3]>,
        rate: f64,
        amplitude: f64,
        period: f64,
        ramp: f64,
    ) -> Result<Self, SceneError> {
        let bad = |why: String| SceneError::InvalidMotion {
            law: "a rotation",
            why,
        };
        let finite = center.iter().all(|c| c.is_finite())
            && rate.is_finite()
            && amplitude.is_finite()
            && ramp.is_finite()
            && ramp >= 0.0;
        if !finite {
            return Err(bad(
                "center, rate, amplitude and ramp must be finite, ramp ≥ 0".into(),
            ));
        }
        if amplitude != 0.0 && !(period.is_finite() && period > 0.0) {
            return Err(bad(format!("period {period} must be positive")));
        }
        let axis = if D == 3 {
            let a = axis.ok_or_else(|| bad("a 3D rotation needs an axis".into()))?;
            // Scaled by its largest component first: an axis of 10²⁰⁰
            // (or 10⁻²⁰⁰) overflowed (underflowed) when squared.
            let m = a.iter().fold(0.0, |m: f64, c| m.max(c.abs()));
            if !(m.is_finite() && m > 0.0) {
                return Err(bad("the axis must be a non-zero finite vector".into()));
            }
            let b = [a[0] / m, a[1] / m, a[2] / m];
            let n = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
            [b[0] / n, b[1] / n, b[2] / n]
        } else {
            [0.0, 0.0, 1.0]
        };
        Ok(Self {
            center,
            axis,
            rate,
            amplitude,
            period,
            ramp,
        })
    }

    /// The angle θ(t) (rad) and its rate θ'(t) (rad/s).
    pub fn angle(&self, t: f64) -> (f64, f64) {
        let mut th = self.rate * t;
        let mut dth = self.rate;
        if self.amplitude != 0.0 {
            let w = 2.0 * std::f64::consts::PI / self.period;
            let (r, dr) = ramp_factor(self.ramp, t);
            th += self.amplitude * r * (w * t).sin();
            dth += self.amplitude * (r * w * (w * t).cos() + dr * (w * t).sin());
        }
        (th, dth)
    }

    /// `k × r` for the axis `k` (in 2D, `(-r_y, r_x)`).
    fn cross(&self, r: &Vector<D>) -> Vector<D> {
        let mut out = Vector::<D>::zeros();
        if D == 2 {
            out[0] = -r[1];
            out[1] = r[0];
        } else {
            let k = self.axis;
            out[0] = k[1] * r[2] - k[2] * r[1];
            out[1] = k[2] * r[0] - k[0] * r[2];
            out[2] = k[0] * r[1] - k[1] * r[0];
        }
        out
    }
}

impl<const D: usize> MotionLaw<D> for Rotation<D>
where
    Const<D>: Dim,
{
    fn position(&self, x0: &Point<D>, t: f64) -> Point<D> {
        // Rodrigues: r' = r cos θ + (k × r) sin θ + k (k·r)(1 − cos θ).
        let (th, _) = self.angle(t);
        let r = x0 - self.center;
        let kr: f64 = if D == 3 {
            (0..3).map(|i| self.axis[i] * r[i]).sum()
        } else {
            0.0
        };
        let mut k = Vector::<D>::zeros();
        if D == 3 {
            for i in 0..3 {
                k[i] = self.axis[i];
            }
        }
        self.center + r * th.cos() + self.cross(&r) * th.sin() + k * (kr * (1.0 - th.cos()))
    }
    fn velocity(&self, x0: &Point<D>, t: f64) -> Vector<D> {
        let (_, dth) = self.angle(t);
        let r = self.position(x0, t) - self.center;
        self.cross(&r) * dth
    }
    /// `θ'' k × r + θ'² k × (k × r)`: the angular acceleration's part and
    /// the centripetal one.
    fn acceleration(&self, x0: &Point<D>, t: f64) -> Option<Vector<D>> {
        let (_, dth) = self.angle(t);
        let ddth = if self.amplitude != 0.0 {
            self.amplitude * oscillation_acceleration(self.period, self.ramp, t)
        } else {
            0.0
        };
        let r = self.position(x0, t) - self.center;
        let kr = self.cross(&r);
        Some(kr * ddth + self.cross(&kr) * (dth * dth))
    }
    fn max_speed(&self, min: &Point<D>, max: &Point<D>) -> Option<f64> {
        // The farthest corner of the box from the centre bounds every
        // point's distance from the axis.
        let radius = (0..D)
            .map(|k| {
                let d = (min[k] - self.center[k])
                    .abs()
                    .max((max[k] - self.center[k]).abs());
                d * d
            })
            .sum::<f64>()
            .sqrt();
        let rate = self.rate.abs()
            + if self.amplitude != 0.0 {
                self.amplitude.abs() * oscillation_rate(self.period, self.ramp)
            } else {
                0.0
            };
        Some(rate * radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Velocity is the time derivative of position, and distances to the
    /// centre are kept.
    fn check<const D: usize>(law: &Rotation<D>, x0: Point<D>)
    where
        Const<D>: Dim,
    {
        for &t in &[0.0, 0.13, 0.5, 0.77, 1.9] {
            let dt = 1e-6;
            let fd = (law.position(&x0, t + dt) - law.position(&x0, (t - dt).max(0.0)))
                / (t + dt - (t - dt).max(0.0));
            let v = law.velocity(&x0, t);
            assert!(
                (fd - v).norm() < 1e-5 * (1.0 + v.norm()),
                "t = {t}: {fd} vs {v}"
            );
            let r0 = (x0 - law.center).norm();
            let r = (law.position(&x0, t) - law.center).norm();
            assert!((r - r0).abs() < 1e-12);
            check_acceleration(law, x0, t);
        }
    }

    /// The acceleration is the time derivative of the velocity (session
    /// 40: laws give it, so a moving wall carries its own).
    fn check_acceleration<const D: usize>(law: &dyn MotionLaw<D>, x0: Point<D>, t: f64)
    where
        Const<D>: Dim,
    {
        let dt = 1e-6;
        let fd = (law.velocity(&x0, t + dt) - law.velocity(&x0, (t - dt).max(0.0)))
            / (t + dt - (t - dt).max(0.0));
        let a = law
            .acceleration(&x0, t)
            .expect("the law gives its acceleration");
        assert!(
            (fd - a).norm() < 1e-4 * (1.0 + a.norm()),
            "t = {t}: {fd} vs {a}"
        );
    }

    #[test]
    fn sinusoidal_and_table_laws_give_their_acceleration() {
        let piston = Sinusoidal::<2> {
            amplitude: Vector::<2>::new(0.05, 0.01),
            period: 0.8,
            ramp: 0.4,
        };
        let table = PiecewiseLinear::<2>::new(vec![
            (0.0, Vector::<2>::zeros()),
            (1.0, Vector::<2>::new(0.1, 0.0)),
            (3.0, Vector::<2>::new(0.1, 0.2)),
        ])
        .unwrap();
        for &t in &[0.0, 0.13, 0.5, 0.77, 1.9] {
            check_acceleration(&piston, Point::<2>::new(0.1, 0.3), t);
            check_acceleration(&table, Point::<2>::new(0.1, 0.3), t);
        }
    }

    /// A ramp of any length ends without a jump in velocity (the linear
    /// ramp, before session 43, jumped by `A sin(2π ramp / T) / ramp`:
    /// 0.059 m/s here), one of half a period without a jump in
    /// acceleration either, and the speed stays within `max_speed`.
    #[test]
    fn a_ramp_of_any_length_ends_smoothly() {
        let x0 = Point::<2>::new(0.0, 0.0);
        let e = 1e-9;
        for (ramp, smooth_acceleration) in [(0.3, false), (0.4, true)] {
            let piston = Sinusoidal::<2> {
                amplitude: Vector::<2>::new(0.05, 0.0),
                period: 0.8,
                ramp,
            };
            let (v0, v1) = (
                piston.velocity(&x0, ramp - e),
                piston.velocity(&x0, ramp + e),
            );
            assert!((v1 - v0).norm() < 1e-6, "{v0} then {v1}");
            let a0 = piston.acceleration(&x0, ramp - e).unwrap();
            let a1 = piston.acceleration(&x0, ramp + e).unwrap();
            assert_eq!(
                (a1 - a0).norm() < 1e-5,
                smooth_acceleration,
                "{a0} then {a1}"
            );
            let bound = piston.max_speed(&x0, &x0).unwrap();
            for k in 0..=1000 {
                let t = k as f64 * 1e-3;
                let v = piston.velocity(&x0, t).norm();
                assert!(v <= bound, "t = {t}: {v} above {bound}");
                // The velocity is the position's derivative through the ramp.
                let fd = (piston.position(&x0, t + 1e-7) - piston.position(&x0, t)) / 1e-7;
                assert!((fd - piston.velocity(&x0, t)).norm() < 1e-5, "t = {t}");
                if (t - ramp).abs() > 1e-5 {
                    check_acceleration(&piston, x0, t.max(2e-6));
                }
            }
        }
        // The bound holds, yet stays within `1 + π/2` of the true speed's
        // bound `A ω`, for a ramp of a microsecond (it was π/2/ramp above it: 1.6·10⁶ m/s
        // here, and a run was refused as needing too many steps).
        let piston = Sinusoidal::<2> {
            amplitude: Vector::<2>::new(0.05, 0.0),
            period: 0.8,
            ramp: 1e-6,
        };
        let bound = piston.max_speed(&x0, &x0).unwrap();
        let w = 2.0 * std::f64::consts::PI / 0.8;
        assert!(
            bound <= (1.0 + 0.5 * std::f64::consts::PI) * 0.05 * w * (1.0 + 1e-12),
            "{bound}"
        );
        for k in 0..=2000 {
            let t = k as f64 * 1e-9;
            let v = piston.velocity(&x0, t).norm();
            assert!(v <= bound, "t = {t}: {v} above {bound}");
        }
    }

    #[test]
    fn rotations_are_rigid_and_their_velocity_is_the_derivative() {
        let flap =
            Rotation::<2>::new(Point::<2>::new(0.1, -0.2), None, 0.3, 0.2, 0.8, 0.4).unwrap();
        check(&flap, Point::<2>::new(0.1, 0.3));
        let spin = Rotation::<3>::new(
            Point::<3>::new(0.0, 1.0, 0.0),
            Some([1.0, 1.0, 0.0]),
            2.0,
            0.1,
            1.0,
            0.0,
        )
        .unwrap();
        check(&spin, Point::<3>::new(0.5, -0.2, 0.7));
        // A point on the axis does not move.
        let on = Point::<3>::new(1.0, 2.0, 0.0);
        assert!((spin.position(&on, 0.7) - on).norm() < 1e-12);
        // A 3D rotation needs an axis; an oscillation needs a period.
        assert!(Rotation::<3>::new(Point::<3>::zeros(), None, 1.0, 0.0, 0.0, 0.0).is_err());
        // An axis of any finite, non-zero size is the same axis.
        for scale in [1e-200, 1.0, 1e200] {
            let r = Rotation::<3>::new(
                Point::<3>::new(0.0, 1.0, 0.0),
                Some([scale, scale, 0.0]),
                2.0,
                0.1,
                1.0,
                0.0,
            )
            .unwrap();
            assert_eq!(r, spin, "axis scaled by {scale}");
        }
        assert!(
            Rotation::<3>::new(Point::<3>::zeros(), Some([0.0; 3]), 1.0, 0.0, 0.0, 0.0).is_err()
        );
        assert!(Rotation::<2>::new(Point::<2>::zeros(), None, 0.0, 0.1, 0.0, 0.0).is_err());
    }
}
