//! Element quality: the normalised radius ratio, and detection of
//! degenerate and inverted simplices, for any dimension.

use pfem_core::{circumsphere, simplex_measure, Const, Dim, Point};
use rayon::prelude::*;

use crate::alpha::{check_tessellation, gather};
use crate::{GeometryError, Tessellation};

/// Measure of a facet (`D` vertices in `D`-space): edge length in 2D,
/// triangle area in 3D, from the Gram determinant of its edge vectors.
#[inline]
fn facet_measure<const D: usize>(q: &[Point<D>]) -> f64
where
    Const<D>: Dim,
{
    let u = q[1] - q[0];
    if D == 2 {
        u.norm()
    } else {
        let w = q[2] - q[0];
        let (uu, ww, uw) = (u.dot(&u), w.dot(&w), u.dot(&w));
        0.5 * (uu * ww - uw * uw).max(0.0).sqrt()
    }
}

/// Normalised radius ratio `q = D · r / R` of a simplex (`r` inradius, `R`
/// circumradius): `1` for the regular simplex, `→ 0` as it degenerates,
/// **negative** when the simplex is inverted (negative signed measure), `0`
/// when its measure is zero or not finite.
///
/// `r = D · |V| / S` with `S` the total facet measure.
///
/// ```
/// use pfem_core::Point;
/// use pfem_geometry::radius_ratio;
/// let s3 = 3f64.sqrt();
/// let eq = [Point::<2>::new(0.0, 0.0), Point::<2>::new(1.0, 0.0), Point::<2>::new(0.5, s3 / 2.0)];
/// assert!((radius_ratio::<2>(&eq) - 1.0).abs() < 1e-12);
/// ```
pub fn radius_ratio<const D: usize>(p: &[Point<D>]) -> f64
where
    Const<D>: Dim,
{
    let nv = <Const<D> as Dim>::NV;
    let v = simplex_measure::<D>(&p[..nv]);
    if !v.is_finite() || v == 0.0 {
        return 0.0;
    }
    let mut s = 0.0;
    let mut q = [Point::<D>::zeros(); 3];
    for k in 0..nv {
        for (o, &l) in q.iter_mut().zip(<Const<D> as Dim>::facet(k)) {
            *o = p[l];
        }
        s += facet_measure::<D>(&q[..D]);
    }
    let Some((_, r_circ)) = circumsphere::<D>(&p[..nv]) else {
        return 0.0;
    };
    let r_in = D as f64 * v.abs() / s;
    let q = D as f64 * r_in / r_circ;
    if !q.is_finite() {
        return 0.0;
    }
    q.min(1.0).copysign(v)
}

/// Parameters of [`mesh_quality`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QualityParams {
    /// A simplex whose `|radius_ratio|` is below this is *degenerate*
    /// (a sliver or needle). Dimensionless in `[0, 1)`. Default `1e-3`.
    pub degenerate_threshold: f64,
}

impl Default for QualityParams {
    fn default() -> Self {
        Self { degenerate_threshold: 1e-3 }
    }
}

impl QualityParams {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), GeometryError> {
        let t = self.degenerate_threshold;
        if !(t.is_finite() && (0.0..1.0).contains(&t)) {
            return Err(GeometryError::InvalidParameter {
                name: "degenerate_threshold",
                value: t,
                reason: "must be in [0, 1)",
            });
        }
        Ok(())
    }
}

/// Summary of the quality of a mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct QualityReport {
    /// Radius ratio of every simplex (see [`radius_ratio`]).
    pub quality: Vec<f64>,
    /// Smallest quality (negative if a simplex is inverted); `1` if empty.
    pub min: f64,
    /// Mean quality; `1` if empty.
    pub mean: f64,
    /// Simplex of smallest quality.
    pub worst: Option<u32>,
    /// Simplices with negative signed measure, ascending.
    pub inverted: Vec<u32>,
    /// Positively oriented simplices with quality below
    /// [`QualityParams::degenerate_threshold`] (zero measure included),
    /// ascending.
    pub degenerate: Vec<u32>,
}

/// Quality of every simplex of `mesh` (parallel), with degenerate and
/// inverted simplices listed.
pub fn mesh_quality<const D: usize>(
    points: &[Point<D>],
    mesh: &Tessellation,
    params: &QualityParams,
) -> Result<QualityReport, GeometryError>
where
    Const<D>: Dim,
{
    params.validate()?;
    check_tessellation::<D>(mesh, points.len())?;
    let nv = <Const<D> as Dim>::NV;
    let quality: Vec<f64> = mesh
        .simplices
        .par_chunks(nv)
        .with_min_len(2048)
        .map(|s| radius_ratio::<D>(&gather::<D>(points, s)[..nv]))
        .collect();
    let mut rep = QualityReport { min: 1.0, mean: 1.0, ..Default::default() };
    let mut sum = 0.0;
    for (s, &q) in quality.iter().enumerate() {
        sum += q;
        if q < rep.min || rep.worst.is_none() {
            rep.min = q;
            rep.worst = Some(s as u32);
        }
        if q < 0.0 {
            rep.inverted.push(s as u32);
        } else if q < params.degenerate_threshold {
            rep.degenerate.push(s as u32);
        }
    }
    if !quality.is_empty() {
        rep.mean = sum / quality.len() as f64;
    }
    rep.quality = quality;
    Ok(rep)
}
