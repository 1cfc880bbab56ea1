//! Shared foundations of the pfem crates: the dimension abstraction that lets
//! one code path serve 2D and 3D, and the small particle types every layer
//! speaks.
//!
//! Every numeric item in pfem is generic over `const D: usize` with the bound
//! `Const<D>: Dim`, which holds exactly for `D = 2` and `D = 3`:
//!
//! ```
//! use pfem_core::{Const, Dim, Point, simplex_measure};
//!
//! fn area_or_volume<const D: usize>(p: &[Point<D>]) -> f64
//! where
//!     Const<D>: Dim,
//! {
//!     simplex_measure::<D>(p)
//! }
//!
//! let tri = [Point::<2>::new(0.0, 0.0), Point::<2>::new(1.0, 0.0), Point::<2>::new(0.0, 1.0)];
//! assert_eq!(area_or_volume(&tri), 0.5);
//! ```
//!
//! Units throughout pfem are SI: metres, seconds, kilograms, pascals.

pub use nalgebra::Const;
use nalgebra::{SMatrix, SVector};

/// A position in `D`-dimensional space (m).
pub type Point<const D: usize> = SVector<f64, D>;
/// A vector (velocity, acceleration, force…) in `D` dimensions.
pub type Vector<const D: usize> = SVector<f64, D>;
/// A second-order tensor (stress, deformation gradient…) in `D` dimensions.
pub type Tensor<const D: usize> = SMatrix<f64, D, D>;

mod sealed {
    pub trait Sealed {}
    impl Sealed for nalgebra::Const<2> {}
    impl Sealed for nalgebra::Const<3> {}
}

/// The spatial dimension, implemented for `Const<2>` and `Const<3>` only.
///
/// In 2D, pfem works in **plane strain**: the out-of-plane strain rate is
/// zero, the out-of-plane stress is carried by the materials where it
/// matters, and "volume" means area per metre of depth.
pub trait Dim:
    sealed::Sealed
    + nalgebra::DimName
    + nalgebra::ToTypenum
    + nalgebra::DimMin<Self, Output = Self>
    + Copy
    + Send
    + Sync
    + std::fmt::Debug
    + 'static
{
    /// Spatial dimension.
    const D: usize;
    /// Vertices of a simplex (triangle in 2D, tetrahedron in 3D): `D + 1`.
    const NV: usize;
    /// Vertices of a simplex facet (edge in 2D, triangle in 3D): `D`.
    const NF: usize;
    /// `1 / D!`: the measure of a simplex is this factor times the
    /// determinant of its edge matrix.
    const MEASURE_FACTOR: f64;
    /// Short name for messages and file names: `"2d"` or `"3d"`.
    const NAME: &'static str;
    /// Local vertex indices of facet `i` of a simplex, the facet opposite
    /// vertex `i`, ordered so that its outward normal follows the usual
    /// orientation convention for a positively oriented simplex.
    fn facet(i: usize) -> &'static [usize];
}

impl Dim for Const<2> {
    const D: usize = 2;
    const NV: usize = 3;
    const NF: usize = 2;
    const MEASURE_FACTOR: f64 = 0.5;
    const NAME: &'static str = "2d";
    fn facet(i: usize) -> &'static [usize] {
        const F: [[usize; 2]; 3] = [[1, 2], [2, 0], [0, 1]];
        &F[i]
    }
}

impl Dim for Const<3> {
    const D: usize = 3;
    const NV: usize = 4;
    const NF: usize = 3;
    const MEASURE_FACTOR: f64 = 1.0 / 6.0;
    const NAME: &'static str = "3d";
    fn facet(i: usize) -> &'static [usize] {
        const F: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];
        &F[i]
    }
}

/// Largest number of vertices of a simplex over all supported dimensions;
/// fixed-size local arrays use it and look at the first `NV` entries.
pub const MAX_NV: usize = 4;

/// Edge matrix of a simplex: column `k` is `p[k + 1] - p[0]`.
#[inline]
pub fn edge_matrix<const D: usize>(p: &[Point<D>]) -> Tensor<D>
where
    Const<D>: Dim,
{
    let mut e = Tensor::<D>::zeros();
    for k in 0..D {
        e.set_column(k, &(p[k + 1] - p[0]));
    }
    e
}

/// Signed measure (area in 2D, volume in 3D) of the simplex with vertices
/// `p[0..=D]`; positive for a positively oriented simplex.
#[inline]
pub fn simplex_measure<const D: usize>(p: &[Point<D>]) -> f64
where
    Const<D>: Dim,
{
    edge_matrix::<D>(p).determinant() * <Const<D> as Dim>::MEASURE_FACTOR
}

/// Gradients of the linear shape functions of a simplex, written into
/// `grads[0..=D]`, and its signed measure. Returns `None` when the simplex is
/// degenerate (measure not finite or zero).
///
/// `grad W_k = row k-1 of E^{-1}` for `k ≥ 1` and `grad W_0 = -Σ grad W_k`,
/// with `E` the [`edge_matrix`].
#[inline]
pub fn shape_gradients<const D: usize>(p: &[Point<D>], grads: &mut [Vector<D>]) -> Option<f64>
where
    Const<D>: Dim,
{
    let e = edge_matrix::<D>(p);
    let det = e.determinant();
    if !det.is_finite() || det == 0.0 {
        return None;
    }
    let inv = e.try_inverse()?;
    let mut g0 = Vector::<D>::zeros();
    for k in 0..D {
        let g = inv.row(k).transpose();
        g0 -= g;
        grads[k + 1] = g;
    }
    grads[0] = g0;
    Some(det * <Const<D> as Dim>::MEASURE_FACTOR)
}

/// Measure-weighted shape-function gradients `V grad Wₐ` of a simplex and
/// its signed measure `V`, defined for every simplex, flat or inverted
/// included: `V grad W_{k+1}` is `MEASURE_FACTOR` times row `k` of the
/// adjugate of the edge matrix (cross products of the other edges in 3D,
/// the rotated other edge in 2D), and `V grad W₀ = −Σ_k V grad W_{k+1}`.
/// For a non-degenerate simplex it equals `V` times [`shape_gradients`].
/// `D` is 2 or 3.
pub fn weighted_shape_gradients<const D: usize>(p: &[Point<D>], out: &mut [Vector<D>]) -> f64
where
    Const<D>: Dim,
{
    let e = edge_matrix::<D>(p);
    let f = <Const<D> as Dim>::MEASURE_FACTOR;
    let mut g0 = Vector::<D>::zeros();
    for k in 0..D {
        let mut g = Vector::<D>::zeros();
        if D == 2 {
            let o = e.column(1 - k);
            let s = if k == 0 { 1.0 } else { -1.0 };
            g[0] = s * o[1] * f;
            g[1] = -s * o[0] * f;
        } else {
            let (a, b) = (e.column((k + 1) % 3), e.column((k + 2) % 3));
            g[0] = (a[1] * b[2] - a[2] * b[1]) * f;
            g[1] = (a[2] * b[0] - a[0] * b[2]) * f;
            g[2] = (a[0] * b[1] - a[1] * b[0]) * f;
        }
        g0 -= g;
        out[k + 1] = g;
    }
    out[0] = g0;
    e.determinant() * f
}

/// Circumcentre and circumradius of a simplex, `None` if degenerate.
pub fn circumsphere<const D: usize>(p: &[Point<D>]) -> Option<(Point<D>, f64)>
where
    Const<D>: Dim,
{
    // Solve 2 Eᵀ c = (|e_k|²)_k for the centre offset c from p[0].
    let e = edge_matrix::<D>(p);
    let mut rhs = Vector::<D>::zeros();
    for k in 0..D {
        rhs[k] = e.column(k).norm_squared();
    }
    let c = (e.transpose() * 2.0).lu().solve(&rhs)?;
    if !c.iter().all(|x| x.is_finite()) {
        return None;
    }
    Some((p[0] + c, c.norm()))
}

/// What a particle is made of. Fluid and solid particles move with the
/// solution; wall particles carry a prescribed velocity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParticleKind {
    /// A particle of a fluid body (remeshed every step).
    Fluid,
    /// A particle of a deformable solid body (keeps its own mesh).
    Solid,
    /// A particle of a rigid wall with prescribed motion.
    Wall,
}

/// Index of a body (a fluid, a solid or a wall) in a scene.
pub type BodyId = u32;

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn gradients_sum_to_zero_and_reproduce_linear_fields_3d() {
        let p = [
            Point::<3>::new(0.1, 0.0, 0.0),
            Point::<3>::new(1.0, 0.2, 0.0),
            Point::<3>::new(0.0, 1.0, 0.3),
            Point::<3>::new(0.2, 0.1, 1.0),
        ];
        let mut g = [Vector::<3>::zeros(); 4];
        let vol = shape_gradients::<3>(&p, &mut g).unwrap();
        assert!(vol > 0.0);
        let a = Vector::<3>::new(1.5, -2.0, 0.7);
        // f(x) = a·x has gradient a: Σ f(p_k) grad W_k = a.
        let mut grad = Vector::<3>::zeros();
        for k in 0..4 {
            grad += g[k] * a.dot(&p[k]);
        }
        assert_relative_eq!(grad, a, epsilon = 1e-12);
    }

    #[test]
    fn weighted_gradients_are_measure_times_gradients() {
        let p3 = [
            Point::<3>::new(0.1, 0.0, 0.0),
            Point::<3>::new(1.0, 0.2, 0.0),
            Point::<3>::new(0.0, 1.0, 0.3),
            Point::<3>::new(0.2, 0.1, 1.0),
        ];
        let (mut g, mut w) = ([Vector::<3>::zeros(); 4], [Vector::<3>::zeros(); 4]);
        let v = shape_gradients::<3>(&p3, &mut g).unwrap();
        assert_relative_eq!(
            weighted_shape_gradients::<3>(&p3, &mut w),
            v,
            epsilon = 1e-15
        );
        for k in 0..4 {
            assert_relative_eq!(w[k], g[k] * v, epsilon = 1e-14);
        }
        // Inverted (two vertices swapped): the measure changes sign, and so
        // does V grad W (the gradients themselves are unchanged).
        let q3 = [p3[1], p3[0], p3[2], p3[3]];
        assert_relative_eq!(
            weighted_shape_gradients::<3>(&q3, &mut w),
            -v,
            epsilon = 1e-15
        );
        assert_relative_eq!(w[0], g[1] * -v, epsilon = 1e-14);
        let p2 = [
            Point::<2>::new(0.1, 0.0),
            Point::<2>::new(1.0, 0.2),
            Point::<2>::new(0.3, 0.9),
        ];
        let (mut g, mut w) = ([Vector::<2>::zeros(); 3], [Vector::<2>::zeros(); 3]);
        let v = shape_gradients::<2>(&p2, &mut g).unwrap();
        assert_relative_eq!(
            weighted_shape_gradients::<2>(&p2, &mut w),
            v,
            epsilon = 1e-15
        );
        for k in 0..3 {
            assert_relative_eq!(w[k], g[k] * v, epsilon = 1e-14);
        }
    }

    #[test]
    fn circumsphere_of_right_triangle() {
        let p = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(2.0, 0.0),
            Point::<2>::new(0.0, 2.0),
        ];
        let (c, r) = circumsphere::<2>(&p).unwrap();
        assert_relative_eq!(c, Point::<2>::new(1.0, 1.0), epsilon = 1e-14);
        assert_relative_eq!(r, 2f64.sqrt(), epsilon = 1e-14);
        let flat = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(2.0, 0.0),
        ];
        assert!(circumsphere::<2>(&flat).is_none());
        let mut g = [Vector::<2>::zeros(); 3];
        assert!(shape_gradients::<2>(&flat, &mut g).is_none());
        // The weighted gradients stay defined on it: V = 0, finite V grad W.
        let v = weighted_shape_gradients::<2>(&flat, &mut g);
        assert_eq!(v, 0.0);
        assert!(g[..3].iter().all(|w| w.iter().all(|c| c.is_finite())));
    }

    #[test]
    fn facets_are_opposite_their_vertex() {
        for i in 0..3 {
            assert!(!<Const<2> as Dim>::facet(i).contains(&i));
        }
        for i in 0..4 {
            assert!(!<Const<3> as Dim>::facet(i).contains(&i));
        }
    }
}
