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

/// The part of a simplex where a linear height `s` is not positive: its
/// share of the simplex's measure and the barycentric coordinates of its
/// centroid. `s[a]` is the height of vertex `a` (`NV` entries, `D` 2 or 3).
/// Since the shape functions are linear, `∫_part W_a = frac · V · λ_a`,
/// which is all a linear element integrated over the part needs (issue 19:
/// the cut of a dry bridge at the water line). The whole simplex gives
/// `(1, 1/NV …)`, none of it `(0, 1/NV …)`; the share is continuous in `s`.
pub fn part_below<const D: usize>(s: &[f64]) -> (f64, [f64; MAX_NV])
where
    Const<D>: Dim,
{
    let nv = D + 1;
    let uniform = {
        let mut u = [0.0; MAX_NV];
        u[..nv].iter_mut().for_each(|v| *v = 1.0 / nv as f64);
        u
    };
    let above: usize = s[..nv].iter().filter(|&&v| v > 0.0).count();
    if above == 0 {
        return (1.0, uniform);
    }
    if above == nv {
        return (0.0, uniform);
    }
    // Vertices and edge crossings in barycentric coordinates.
    let vertex = |a: usize| {
        let mut l = [0.0; MAX_NV];
        l[a] = 1.0;
        l
    };
    let crossing = |a: usize, b: usize| {
        // The point of edge a–b where s = 0 (s[a] and s[b] of opposite sides).
        let t = s[a] / (s[a] - s[b]);
        let mut l = [0.0; MAX_NV];
        l[a] = 1.0 - t;
        l[b] = t;
        l
    };
    // Measure (relative to the simplex) and first moment of a sub-simplex
    // given by the barycentric coordinates of its vertices.
    let sub = |v: &[[f64; MAX_NV]]| {
        // The nv × nv determinant, padded with the identity to 4 × 4.
        let m = nalgebra::Matrix4::<f64>::from_fn(|i, j| {
            if i < nv && j < nv {
                v[j][i]
            } else if i == j {
                1.0
            } else {
                0.0
            }
        });
        let frac = m.determinant().abs();
        let mut c = [0.0; MAX_NV];
        for l in v {
            for a in 0..nv {
                c[a] += l[a] * frac / nv as f64;
            }
        }
        (frac, c)
    };
    let (mut up, mut down) = ([0usize; MAX_NV], [0usize; MAX_NV]);
    let (mut nu, mut nd) = (0, 0);
    for a in 0..nv {
        if s[a] > 0.0 {
            up[nu] = a;
            nu += 1;
        } else {
            down[nd] = a;
            nd += 1;
        }
    }
    let mut parts = [[0.0; MAX_NV]; MAX_NV];
    let (frac, moment) = if nd == 1 {
        // A corner at the one vertex below.
        let b = down[0];
        parts[0] = vertex(b);
        for (k, &a) in up[..nu].iter().enumerate() {
            parts[k + 1] = crossing(b, a);
        }
        sub(&parts[..nv])
    } else if nu == 1 {
        // The whole less the corner at the one vertex above.
        let a = up[0];
        parts[0] = vertex(a);
        for (k, &b) in down[..nd].iter().enumerate() {
            parts[k + 1] = crossing(a, b);
        }
        let (fc, mc) = sub(&parts[..nv]);
        let mut m = uniform;
        for k in 0..nv {
            m[k] -= mc[k];
        }
        (1.0 - fc, m)
    } else {
        // 3D, two above and two below: a prism with the triangles
        // (b0, c00, c01) and (b1, c10, c11), split into three tetrahedra.
        let (b0, b1, a0, a1) = (down[0], down[1], up[0], up[1]);
        let t0 = [vertex(b0), crossing(b0, a0), crossing(b0, a1)];
        let t1 = [vertex(b1), crossing(b1, a0), crossing(b1, a1)];
        let mut frac = 0.0;
        let mut m = [0.0; MAX_NV];
        for tet in [
            [t0[0], t0[1], t0[2], t1[0]],
            [t0[1], t0[2], t1[0], t1[1]],
            [t0[2], t1[0], t1[1], t1[2]],
        ] {
            let (f, c) = sub(&tet);
            frac += f;
            for k in 0..nv {
                m[k] += c[k];
            }
        }
        (frac, m)
    };
    if frac <= 0.0 {
        return (0.0, uniform);
    }
    let mut l = [0.0; MAX_NV];
    for k in 0..nv {
        l[k] = moment[k] / frac;
    }
    (frac.min(1.0), l)
}

/// The share of a simplex below its *water line* and the barycentric
/// coordinates of that part's centroid ([`part_below`]): the water line is
/// the plane normal to `up` through the mean height of the vertices in
/// `surface` (a bit mask of local vertices: the free-surface fluid nodes of
/// a simplex that joins them to a wall or a solid; issue 19). `p` holds the
/// simplex's `D + 1` vertices.
pub fn below_water_line<const D: usize>(
    p: &[Point<D>],
    surface: u8,
    up: &Vector<D>,
) -> (f64, [f64; MAX_NV])
where
    Const<D>: Dim,
{
    let nv = D + 1;
    let (mut level, mut n) = (0.0, 0);
    for (a, x) in p[..nv].iter().enumerate() {
        if surface & (1 << a) != 0 {
            level += x.dot(up);
            n += 1;
        }
    }
    let mut s = [0.0; MAX_NV];
    if n > 0 {
        level /= n as f64;
        for (a, x) in p[..nv].iter().enumerate() {
            s[a] = x.dot(up) - level;
        }
    }
    part_below::<D>(&s[..nv])
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

    /// The part below a plane, against a fine sampling of the simplex in
    /// barycentric coordinates: share and centroid, every case of the cut.
    fn check_part_below<const D: usize>(s: &[f64])
    where
        Const<D>: Dim,
    {
        let nv = D + 1;
        let (frac, l) = part_below::<D>(s);
        let n = if D == 2 { 600 } else { 120 };
        let (mut count, mut total) = (0usize, 0usize);
        let mut c = [0.0; MAX_NV];
        // Points at the centres of a regular subdivision of the simplex.
        let mut idx = vec![0usize; D];
        loop {
            let sum: usize = idx.iter().sum();
            if sum < n {
                let mut lam = [0.0; MAX_NV];
                for k in 0..D {
                    lam[k + 1] = (idx[k] as f64 + 1.0 / nv as f64) / n as f64;
                }
                lam[0] = 1.0 - lam[1..nv].iter().sum::<f64>();
                if lam[0] > 0.0 {
                    total += 1;
                    let h: f64 = (0..nv).map(|a| lam[a] * s[a]).sum();
                    if h <= 0.0 {
                        count += 1;
                        for a in 0..nv {
                            c[a] += lam[a];
                        }
                    }
                }
            }
            let mut k = 0;
            loop {
                idx[k] += 1;
                if idx[k] < n {
                    break;
                }
                idx[k] = 0;
                k += 1;
                if k == D {
                    break;
                }
            }
            if k == D {
                break;
            }
        }
        let sampled = count as f64 / total as f64;
        assert!(
            (frac - sampled).abs() < 1e-2,
            "{s:?}: {frac} against {sampled}"
        );
        if count > 0 {
            for a in 0..nv {
                assert!((l[a] - c[a] / count as f64).abs() < 2e-2, "{s:?}: λ {l:?}");
            }
        }
        let sum: f64 = l[..nv].iter().sum();
        assert_relative_eq!(sum, 1.0, epsilon = 1e-12);
        // The two sides make the whole.
        let flip: Vec<f64> = s[..nv].iter().map(|v| -v).collect();
        let (other, lo) = part_below::<D>(&flip);
        if (0..nv).all(|a| s[a] != 0.0) {
            assert_relative_eq!(frac + other, 1.0, epsilon = 1e-12);
            for a in 0..nv {
                let whole = frac * l[a] + other * lo[a];
                assert_relative_eq!(whole, 1.0 / nv as f64, epsilon = 1e-12);
            }
        }
    }

    #[test]
    fn the_part_below_a_plane_matches_a_sampling_in_every_case() {
        for s in [
            [-1.0, -2.0, -0.5],
            [1.0, 2.0, 0.5],
            [0.3, -0.7, -0.2],
            [0.3, 0.7, -0.2],
            [1.0, -1.0, 0.0],
        ] {
            check_part_below::<2>(&s);
        }
        for s in [
            [-1.0, -2.0, -0.5, -0.1],
            [0.4, -0.7, -0.2, -0.9],
            [0.4, 0.7, -0.2, -0.9],
            [0.4, 0.7, 0.2, -0.9],
            [-0.3, 0.5, -0.8, 0.6],
            [0.5, -0.5, 0.5, -0.5],
        ] {
            check_part_below::<3>(&s);
        }
        // Continuous as a vertex crosses the plane.
        let (a, _) = part_below::<2>(&[1e-12, -1.0, -1.0]);
        assert_relative_eq!(a, 1.0, epsilon = 1e-9);
        let (b, _) = part_below::<3>(&[1.0, 1.0, 1.0, -1e-12]);
        assert!(b < 1e-9);
    }

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
