//! Prescribed rigid motions of walls in time ([`crate::WallMotion::Law`]).

use pfem_core::{Const, Dim, Point, Vector};

use crate::SceneError;

/// A prescribed rigid motion: where a point that was at `x0` at `t = 0` is
/// at time `t`, and its velocity. Laws must be continuous in time and give
/// the velocity that is the derivative of the position.
pub trait MotionLaw<const D: usize>: Send + Sync + std::fmt::Debug
where
    Const<D>: Dim,
{
    /// Position at `t` of the point that was at `x0` at `t = 0` (m).
    fn position(&self, x0: &Point<D>, t: f64) -> Point<D>;
    /// Its velocity (m/s).
    fn velocity(&self, x0: &Point<D>, t: f64) -> Vector<D>;
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
    /// Duration of a linear ramp of the amplitude from 0 (s); 0 for none.
    /// A ramp over a period or two spares the fluid the start-up jerk.
    pub ramp: f64,
}

impl<const D: usize> Sinusoidal<D>
where
    Const<D>: Dim,
{
    fn factor(&self, t: f64) -> (f64, f64) {
        if self.ramp > 0.0 && t < self.ramp {
            (t / self.ramp, 1.0 / self.ramp)
        } else {
            (1.0, 0.0)
        }
    }
}

impl<const D: usize> MotionLaw<D> for Sinusoidal<D>
where
    Const<D>: Dim,
{
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
}

impl<const D: usize> PiecewiseLinear<D>
where
    Const<D>: Dim,
{
    /// A table law; its rows must start at `t = 0` with zero displacement,
    /// with finite, strictly increasing times and finite displacements.
    pub fn new(rows: Vec<(f64, Vector<D>)>) -> Result<Self, SceneError> {
        let bad = |why: &str| SceneError::InvalidGeometry {
            body: "piecewise-linear motion".into(),
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
        Ok(Self { rows })
    }

    fn at(&self, t: f64) -> (Vector<D>, Vector<D>) {
        let k = self.rows.partition_point(|r| r.0 <= t);
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
        x0 + self.at(t).0
    }
    fn velocity(&self, _x0: &Point<D>, t: f64) -> Vector<D> {
        self.at(t).1
    }
}
