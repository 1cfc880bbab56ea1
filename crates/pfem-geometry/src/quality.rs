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
        Self {
            degenerate_threshold: 1e-3,
        }
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
    /// [`QualityParams::degenerate_threshold`] (zero measure included when
    /// the threshold is above 0),
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
    let mut rep = QualityReport {
        min: 1.0,
        mean: 1.0,
        ..Default::default()
    };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Delaunay2, Tessellator};

    #[test]
    fn radius_ratio_of_reference_simplices() {
        let s3 = 3f64.sqrt();
        let eq = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(2.0, 0.0),
            Point::<2>::new(1.0, s3),
        ];
        assert!((radius_ratio::<2>(&eq) - 1.0).abs() < 1e-12);
        let right = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(0.0, 1.0),
        ];
        // r = (2 - √2)/2, R = √2/2: q = 2 r / R = 2(√2 - 1).
        assert!((radius_ratio::<2>(&right) - 2.0 * (2f64.sqrt() - 1.0)).abs() < 1e-12);
        let inverted = [right[0], right[2], right[1]];
        assert!((radius_ratio::<2>(&inverted) + radius_ratio::<2>(&right)).abs() < 1e-15);
        let flat = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(3.0, 0.0),
        ];
        assert_eq!(radius_ratio::<2>(&flat), 0.0);
        let needle = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(0.5, 1e-6),
        ];
        assert!(radius_ratio::<2>(&needle) < 1e-5);

        let tet = [
            Point::<3>::new(1.0, 1.0, 1.0),
            Point::<3>::new(1.0, -1.0, -1.0),
            Point::<3>::new(-1.0, 1.0, -1.0),
            Point::<3>::new(-1.0, -1.0, 1.0),
        ];
        let q = radius_ratio::<3>(&tet);
        assert!((q.abs() - 1.0).abs() < 1e-12, "{q}");
        let corner = [
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(1.0, 0.0, 0.0),
            Point::<3>::new(0.0, 1.0, 0.0),
            Point::<3>::new(0.0, 0.0, 1.0),
        ];
        let q = radius_ratio::<3>(&corner);
        assert!(q > 0.0 && q < 1.0);
        let sliver = [
            corner[0],
            corner[1],
            corner[2],
            Point::<3>::new(1.0, 1.0, 1e-9),
        ];
        assert!(radius_ratio::<3>(&sliver).abs() < 1e-6);
    }

    #[test]
    fn mesh_quality_flags_degenerate_and_inverted() {
        let p = vec![
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(0.0, 1.0),
            Point::<2>::new(1.0, 1.0),
            Point::<2>::new(2.0, 0.0),
            Point::<2>::new(3.0, 1e-9),
        ];
        let mut t = Tessellation::new(3);
        t.simplices = vec![0, 1, 2, 1, 3, 2, 0, 2, 1, 1, 4, 5];
        t.neighbors = vec![crate::NO_NEIGHBOR; 12];
        let r = mesh_quality::<2>(&p, &t, &QualityParams::default()).unwrap();
        assert_eq!(r.inverted, vec![2]);
        assert_eq!(r.degenerate, vec![3]);
        assert_eq!(r.worst, Some(2));
        assert!(r.min < 0.0);

        let grid: Vec<_> = (0..100)
            .map(|i| Point::<2>::new((i % 10) as f64, (i / 10) as f64))
            .collect();
        let mut t = Tessellation::default();
        Delaunay2::default().tessellate(&grid, &mut t).unwrap();
        let r = mesh_quality::<2>(&grid, &t, &QualityParams::default()).unwrap();
        assert!(r.inverted.is_empty() && r.degenerate.is_empty());
        assert!((r.min - 2.0 * (2f64.sqrt() - 1.0)).abs() < 1e-12);
        assert!(QualityParams {
            degenerate_threshold: 1.5
        }
        .validate()
        .is_err());
    }
}
