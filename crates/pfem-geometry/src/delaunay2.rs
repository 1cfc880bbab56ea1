//! The built-in 2D Delaunay tessellator, a thin layer over
//! [spade](https://docs.rs/spade) (exact predicates, `O(n log n)` bulk
//! loading) that keeps particle `i` as vertex `i`, refuses what it cannot
//! mesh with a typed error and never panics.

use pfem_core::Point;
use rayon::prelude::*;
use spade::handles::FixedFaceHandle;
use spade::{DelaunayTriangulation, Point2, Triangulation};

/// Faces per parallel work item when reading spade's mesh.
const CHUNK: usize = 4096;

use crate::{GeometryError, Tessellation, Tessellator, NO_NEIGHBOR};

/// Parameters of [`Delaunay2`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Delaunay2Params {
    /// Two particles joined by an edge and closer than
    /// `coincidence_tolerance × L` are reported as
    /// [`GeometryError::NearCoincident`], with `L` the mesh's median edge
    /// length (its typical spacing). Exact duplicates (which
    /// spade would merge) are reported with `L` the larger side of the
    /// set's bounding box. Dimensionless, `≥ 0`; `0` reports exact
    /// duplicates only. Default `1e-10`.
    ///
    /// (Until session 48 `L` was the larger side of the whole set's
    /// bounding box: one particle flung 10⁹ units away made the
    /// tolerance 0.1, and a splash's pairs "near coincident".)
    pub coincidence_tolerance: f64,
}

impl Default for Delaunay2Params {
    fn default() -> Self {
        Self {
            coincidence_tolerance: 1e-10,
        }
    }
}

impl Delaunay2Params {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), GeometryError> {
        let t = self.coincidence_tolerance;
        if !(t.is_finite() && (0.0..1.0).contains(&t)) {
            return Err(GeometryError::InvalidParameter {
                name: "coincidence_tolerance",
                value: t,
                reason: "must be finite, >= 0 and < 1",
            });
        }
        Ok(())
    }
}

/// Largest particle count [`Delaunay2`] accepts: indices are `u32` and spade
/// stores about six directed edges per vertex under `u32` handles.
pub const MAX_POINTS_2D: usize = (u32::MAX / 8) as usize;

/// 2D Delaunay tessellator backed by spade's `bulk_load_stable`.
///
/// * Particle `i` is vertex `i`; every triangle is counter-clockwise
///   (positive area); `neighbors` is read directly from spade's half-edge
///   structure (entry `k` is the triangle across the edge opposite local
///   vertex `k`).
/// * Coordinates are multiplied by one power of two before meshing so that
///   the largest magnitude is in `[0.5, 1)`. This is exact in floating point,
///   so the mesh is the Delaunay triangulation of the input itself, for any
///   magnitude (1e-300 to 1e300); only coordinates more than 2¹⁴² times
///   smaller than the largest one are flushed to zero (spade's exact
///   predicates cannot take them), a change far below any tolerance.
/// * Exact duplicates (which spade would merge silently) and particles
///   closer than [`Delaunay2Params::coincidence_tolerance`] are
///   [`GeometryError::NearCoincident`]; NaN or infinite coordinates are
///   [`GeometryError::NonFinite`]; fewer than three particles or all
///   collinear are [`GeometryError::Degenerate`].
///
/// ```
/// use pfem_core::Point;
/// use pfem_geometry::{Delaunay2, Tessellation, Tessellator};
///
/// let pts = [
///     Point::<2>::new(0.0, 0.0),
///     Point::<2>::new(1.0, 0.0),
///     Point::<2>::new(0.0, 1.0),
///     Point::<2>::new(1.0, 1.2),
/// ];
/// let mut mesh = Tessellation::default();
/// Delaunay2::default().tessellate(&pts, &mut mesh).unwrap();
/// assert_eq!(mesh.len(), 2);
/// ```
#[derive(Debug, Clone, Default)]
pub struct Delaunay2 {
    /// Parameters.
    pub params: Delaunay2Params,
}

impl Delaunay2 {
    /// A tessellator with the given parameters, validated.
    pub fn new(params: Delaunay2Params) -> Result<Self, GeometryError> {
        params.validate()?;
        Ok(Self { params })
    }
}

/// `x · 2^e`, exact unless the result underflows.
fn scale_pow2(mut x: f64, mut e: i32) -> f64 {
    while e != 0 {
        let step = e.clamp(-1000, 1000);
        x *= f64::from_bits(((1023 + step) as u64) << 52);
        e -= step;
    }
    x
}

/// Binary exponent `e` with `2^e ≤ x < 2^(e+1)` for finite `x > 0`.
fn exponent(x: f64) -> i32 {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    if biased == 0 {
        // Subnormal: 2^-1074 · mantissa.
        let m = bits & ((1u64 << 52) - 1);
        -1074 + (63 - m.leading_zeros() as i32)
    } else {
        biased - 1023
    }
}

impl Tessellator<2> for Delaunay2 {
    fn tessellate(
        &mut self,
        points: &[Point<2>],
        out: &mut Tessellation,
    ) -> Result<(), GeometryError> {
        out.nv = 3;
        out.simplices.clear();
        out.neighbors.clear();
        self.params.validate()?;
        let n = points.len();
        if n > MAX_POINTS_2D {
            return Err(GeometryError::TooManyPoints {
                count: n,
                max: MAX_POINTS_2D,
            });
        }
        if let Some(index) = points
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(GeometryError::NonFinite { index });
        }
        let degenerate = GeometryError::Degenerate { count: n, dim: 2 };
        if n < 3 {
            return Err(degenerate);
        }
        let (mut lo, mut hi) = (points[0], points[0]);
        for p in points {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let extent = (hi - lo).max();
        if extent == 0.0 {
            return Err(degenerate);
        }
        let tol = self.params.coincidence_tolerance;
        let max_abs = lo.abs().sup(&hi.abs()).max();
        // Exact power-of-two rescaling to bring max |x| into [0.5, 1).
        let e = -exponent(max_abs) - 1;
        let scaled = |x: f64| {
            let s = scale_pow2(x, e);
            if s.abs() < spade::MIN_ALLOWED_VALUE {
                0.0
            } else {
                s
            }
        };
        let input: Vec<Point2<f64>> = points
            .iter()
            .map(|p| Point2::new(scaled(p.x), scaled(p.y)))
            .collect();

        let built = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            DelaunayTriangulation::<Point2<f64>>::bulk_load_stable(input)
        }));
        let tri = match built {
            Ok(Ok(t)) => t,
            Ok(Err(err)) => {
                return Err(GeometryError::Internal {
                    message: format!("spade: {err}"),
                });
            }
            Err(panic) => {
                let message = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "spade panicked".into());
                return Err(GeometryError::Internal { message });
            }
        };

        if tri.num_vertices() != n {
            return Err(find_duplicate(
                points,
                |p| (scaled(p.x), scaled(p.y)),
                tol * extent,
            ));
        }
        let nf = tri.num_inner_faces();
        if nf == 0 {
            return Err(degenerate);
        }
        out.simplices.resize(3 * nf, 0);
        out.neighbors.resize(3 * nf, 0);
        // Face handles in index order (inner face f is simplex f - 1), then
        // the half-edge structure is read in parallel.
        let faces: Vec<_> = tri.fixed_inner_faces().collect();
        let tri = &tri;
        // Each edge's length once, in the slot of the face and local edge
        // that read it (its twin's slot holds −1).
        let mut lengths = vec![-1.0f64; 3 * nf];
        faces
            .par_chunks(CHUNK)
            .zip(out.simplices.par_chunks_mut(3 * CHUNK))
            .zip(out.neighbors.par_chunks_mut(3 * CHUNK))
            .zip(lengths.par_chunks_mut(3 * CHUNK))
            .for_each(|(((faces, simplices), neighbors), lengths)| {
                for (j, &f) in faces.iter().enumerate() {
                    let edges = tri.face(f).adjacent_edges();
                    // vertices()[k] = edges[k].from(); edge k+1 is opposite
                    // vertex k.
                    let v = [edges[0].from(), edges[1].from(), edges[2].from()]
                        .map(|h| h.fix().index());
                    for k in 0..3 {
                        simplices[3 * j + k] = v[k] as u32;
                        let across = edges[(k + 1) % 3].rev().face().fix();
                        let nb = face_to_simplex(across);
                        neighbors[3 * j + k] = nb;
                        // Edge k+1 joins vertices k+1 and k+2; each edge
                        // once (hull edges have no twin face).
                        let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
                        if a < b || nb == NO_NEIGHBOR {
                            lengths[3 * j + k] = (points[a] - points[b]).norm();
                        }
                    }
                }
            });
        // The mesh's own scale: its median edge. A particle flung far away
        // adds a few long hull edges, which do not move it (until session
        // 48 the scale was the whole set's extent: one particle 10⁹ units
        // away made a splash's pairs "near coincident").
        let mut sample: Vec<f64> = lengths.iter().copied().filter(|&l| l >= 0.0).collect();
        let mid = sample.len() / 2;
        let median = if sample.is_empty() {
            extent
        } else {
            *sample.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        drop(sample);
        let simplices = &out.simplices;
        let tolerance = tol * median;
        // The closest pair (lengths are finite: ties by index).
        let close = lengths
            .par_iter()
            .enumerate()
            .filter_map(|(slot, &d)| {
                if !(0.0..tolerance).contains(&d) {
                    return None;
                }
                let (f, k) = (slot / 3, slot % 3);
                let a = simplices[3 * f + (k + 1) % 3] as usize;
                let b = simplices[3 * f + (k + 2) % 3] as usize;
                Some((d, a.min(b), a.max(b), tolerance))
            })
            .min_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        if let Some((distance, first, second, tolerance)) = close {
            out.simplices.clear();
            out.neighbors.clear();
            return Err(GeometryError::NearCoincident {
                first,
                second,
                distance,
                tolerance,
            });
        }
        Ok(())
    }
}

/// spade's face 0 is the outer face; inner face `f` is simplex `f - 1`.
#[inline]
fn face_to_simplex(f: FixedFaceHandle<spade::handles::PossiblyOuterTag>) -> u32 {
    match f.index() {
        0 => NO_NEIGHBOR,
        i => (i - 1) as u32,
    }
}

/// Finds a pair of particles that spade merged (equal after rescaling), the
/// error path only.
fn find_duplicate(
    points: &[Point<2>],
    key: impl Fn(&Point<2>) -> (f64, f64),
    tolerance: f64,
) -> GeometryError {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        let (ka, kb) = (key(&points[a]), key(&points[b]));
        ka.partial_cmp(&kb)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(a.cmp(&b))
    });
    for w in order.windows(2) {
        if key(&points[w[0]]) == key(&points[w[1]]) {
            let (first, second) = (w[0].min(w[1]), w[0].max(w[1]));
            return GeometryError::NearCoincident {
                first,
                second,
                distance: (points[first] - points[second]).norm(),
                tolerance,
            };
        }
    }
    GeometryError::Internal {
        message: "spade dropped a vertex that has no duplicate".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use robust::{incircle, orient2d, Coord};

    fn c(p: &Point<2>) -> Coord<f64> {
        Coord { x: p.x, y: p.y }
    }

    fn mesh(points: &[Point<2>]) -> Result<Tessellation, GeometryError> {
        let mut t = Tessellation::default();
        Delaunay2::default().tessellate(points, &mut t)?;
        Ok(t)
    }

    /// Checks orientation, adjacency, vertex coverage, Euler's formula and
    /// (exactly, brute force) the empty-circumcircle property.
    fn check(points: &[Point<2>], t: &Tessellation) {
        // Robust predicates overflow beyond ~1e60: rescale exactly by a power
        // of two first, as the tessellator does.
        let max_abs = points.iter().map(|p| p.abs().max()).fold(0.0, f64::max);
        let e = -exponent(max_abs) - 1;
        let scaled: Vec<_> = points
            .iter()
            .map(|p| Point::<2>::new(scale_pow2(p.x, e), scale_pow2(p.y, e)))
            .collect();
        let points = &scaled[..];
        let n = points.len();
        let mut used = vec![false; n];
        for s in 0..t.len() {
            let v = t.simplex(s);
            let p = [
                points[v[0] as usize],
                points[v[1] as usize],
                points[v[2] as usize],
            ];
            assert!(
                orient2d(c(&p[0]), c(&p[1]), c(&p[2])) > 0.0,
                "triangle {s} not ccw"
            );
            for &i in v {
                used[i as usize] = true;
            }
            for k in 0..3 {
                let nb = t.simplex_neighbors(s)[k];
                let f = [v[(k + 1) % 3], v[(k + 2) % 3]];
                if nb == NO_NEIGHBOR {
                    continue;
                }
                let w = t.simplex(nb as usize);
                let back = t
                    .simplex_neighbors(nb as usize)
                    .iter()
                    .position(|&x| x == s as u32);
                let kb = back.expect("adjacency not symmetric");
                // Shared facet, opposite orientation.
                assert_eq!([w[(kb + 2) % 3], w[(kb + 1) % 3]], f);
            }
            if n <= 80 {
                for (j, q) in points.iter().enumerate() {
                    if !v.contains(&(j as u32)) {
                        let ic = incircle(c(&p[0]), c(&p[1]), c(&p[2]), c(q));
                        assert!(ic <= 0.0, "point {j} inside circumcircle of {s}");
                    }
                }
            }
        }
        assert!(used.iter().all(|&u| u), "a particle is not a vertex");
        let hull = t.neighbors.iter().filter(|&&x| x == NO_NEIGHBOR).count();
        assert_eq!(t.len(), 2 * n - 2 - hull, "Euler");
    }

    fn lattice(nx: usize, ny: usize, h: f64, origin: Point<2>) -> Vec<Point<2>> {
        (0..nx * ny)
            .map(|i| origin + Point::<2>::new((i % nx) as f64 * h, (i / nx) as f64 * h))
            .collect()
    }

    #[test]
    fn square_lattice_is_cocircular_everywhere() {
        let p = lattice(9, 7, 0.1, Point::<2>::zeros());
        let t = mesh(&p).unwrap();
        assert_eq!(t.len(), 2 * 8 * 6);
        check(&p, &t);
    }

    #[test]
    fn huge_and_tiny_coordinates() {
        for (scale, offset) in [
            (1e-6, 0.0),
            (1e-9, 1e6),
            (1.0, 1e6),
            (1e280, 0.0),
            (1e-300, 0.0),
        ] {
            let p: Vec<_> = lattice(6, 5, scale, Point::<2>::new(offset, -offset))
                .into_iter()
                .enumerate()
                .map(|(i, q)| q + Point::<2>::new(0.0, (i % 3) as f64 * 0.01 * scale))
                .collect();
            let t = mesh(&p).unwrap_or_else(|e| panic!("scale {scale} offset {offset}: {e}"));
            check(&p, &t);
        }
    }

    #[test]
    fn beyond_spade_limits() {
        // Above spade's 2^201 and mixed with values under its 2^-142.
        let p = [
            Point::<2>::new(1e300, 0.0),
            Point::<2>::new(0.0, 1e300),
            Point::<2>::new(-1e300, -1e300),
            Point::<2>::new(1e-200, 3e-320),
        ];
        let t = mesh(&p).unwrap();
        assert_eq!(t.len(), 3);
        check(&p, &t);
    }

    #[test]
    fn typed_errors() {
        let tri = |a: f64| {
            [
                Point::<2>::new(0.0, 0.0),
                Point::<2>::new(1.0, 0.0),
                Point::<2>::new(a, 1.0),
            ]
        };
        assert!(matches!(
            mesh(&tri(f64::NAN)),
            Err(GeometryError::NonFinite { index: 2 })
        ));
        assert!(matches!(
            mesh(&tri(f64::INFINITY)),
            Err(GeometryError::NonFinite { index: 2 })
        ));
        assert!(matches!(
            mesh(&tri(0.5)[..2]),
            Err(GeometryError::Degenerate { .. })
        ));
        assert!(matches!(mesh(&[]), Err(GeometryError::Degenerate { .. })));
        let line: Vec<_> = (0..10)
            .map(|i| Point::<2>::new(i as f64, 2.0 * i as f64))
            .collect();
        assert!(matches!(
            mesh(&line),
            Err(GeometryError::Degenerate { count: 10, dim: 2 })
        ));
        let same = [Point::<2>::new(1.0, 1.0); 5];
        assert!(matches!(mesh(&same), Err(GeometryError::Degenerate { .. })));
        let mut dup = lattice(4, 4, 1.0, Point::<2>::zeros());
        dup.push(dup[5]);
        assert_eq!(
            mesh(&dup),
            Err(GeometryError::NearCoincident {
                first: 5,
                second: 16,
                distance: 0.0,
                tolerance: 3e-10
            })
        );
        let mut near = lattice(4, 4, 1.0, Point::<2>::zeros());
        near.push(near[7] + Point::<2>::new(1e-12, 0.0));
        assert!(matches!(
            mesh(&near),
            Err(GeometryError::NearCoincident {
                first: 7,
                second: 16,
                ..
            })
        ));
        // Session 48: one particle flung 10⁹ units away (a drop with
        // nothing under it) made the tolerance 10⁻¹ (relative to the whole
        // set's extent), and a pair of the lattice 10⁻³ apart "near
        // coincident". The scale is the mesh's median edge: accepted, and
        // the near pair beside it still refused.
        let mut far = lattice(4, 4, 1.0, Point::<2>::zeros());
        far.push(far[6] + Point::<2>::new(1e-3, 0.0));
        far.push(Point::<2>::new(1.5, -1e9));
        let t = mesh(&far).unwrap();
        check(&far, &t);
        far.push(far[9] + Point::<2>::new(0.0, 1e-11));
        assert!(matches!(
            mesh(&far),
            Err(GeometryError::NearCoincident {
                first: 9,
                second: 18,
                ..
            })
        ));
        // A far drop of two particles 0.05 apart is meshed; the same
        // particle twice is not.
        let mut drop = lattice(4, 4, 1.0, Point::<2>::zeros());
        drop.push(Point::<2>::new(1.5, -1e9));
        drop.push(Point::<2>::new(1.55, -1e9));
        check(&drop, &mesh(&drop).unwrap());
        drop[17].x = 1.5;
        assert!(matches!(
            mesh(&drop),
            Err(GeometryError::NearCoincident {
                first: 16,
                second: 17,
                ..
            })
        ));
        // A cluster of three, 10⁻¹³ apart (a review of session 48: a rule
        // of each edge's nearest third vertex measured the cluster on its
        // own triangle, and accepted it).
        let mut cluster = lattice(4, 4, 1.0, Point::<2>::zeros());
        let p = Point::<2>::new(1.5, 1.5);
        cluster.extend([
            p,
            p + Point::<2>::new(1e-13, 0.0),
            p + Point::<2>::new(0.0, 1e-13),
        ]);
        assert!(matches!(
            mesh(&cluster),
            Err(GeometryError::NearCoincident { first: 16, .. })
        ));
        // Tolerance 0 accepts it, spade resolves it exactly.
        let mut t = Tessellation::default();
        let mut d = Delaunay2::new(Delaunay2Params {
            coincidence_tolerance: 0.0,
        })
        .unwrap();
        d.tessellate(&near, &mut t).unwrap();
        check(&near, &t);
        assert!(Delaunay2::new(Delaunay2Params {
            coincidence_tolerance: -1.0
        })
        .is_err());
    }

    #[test]
    fn collinear_runs_and_clusters() {
        // A collinear run with one point off the line, and a tight cluster.
        let mut p: Vec<_> = (0..30)
            .map(|i| Point::<2>::new(i as f64 * 0.1, 0.0))
            .collect();
        p.push(Point::<2>::new(1.5, 1e-3));
        for i in 0..25 {
            p.push(Point::<2>::new(
                2.0 + (i % 5) as f64 * 1e-9,
                1.0 + (i / 5) as f64 * 1e-9,
            ));
        }
        let t = mesh(&p).unwrap();
        check(&p, &t);
    }

    fn cloud(max: usize) -> impl Strategy<Value = Vec<Point<2>>> {
        prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 0..max)
            .prop_map(|v| v.into_iter().map(|(x, y)| Point::<2>::new(x, y)).collect())
    }

    /// Snapped to a coarse grid: many duplicates, collinear and cocircular
    /// subsets.
    fn grid_cloud(max: usize) -> impl Strategy<Value = Vec<Point<2>>> {
        prop::collection::vec((0i32..6, 0i32..6), 0..max).prop_map(|v| {
            v.into_iter()
                .map(|(x, y)| Point::<2>::new(x as f64, y as f64))
                .collect()
        })
    }

    /// Whether every point lies on one line (to a relative 10⁻⁹ of the
    /// cloud's extent squared; fewer than three distinct points included).
    fn collinear(p: &[Point<2>]) -> bool {
        let Some(a) = p.first() else { return true };
        // The line through `a` and the point farthest from it (a near
        // duplicate of `a` would fit any cloud).
        let Some(b) = p
            .iter()
            .max_by(|q, r| (*q - a).norm().total_cmp(&(*r - a).norm()))
        else {
            return true;
        };
        // In units of the extent: the products of coordinates of 10¹⁵⁵
        // overflow (two points were then "not collinear").
        let extent = (b - a).norm();
        if p.len() < 3 || extent == 0.0 {
            return true;
        }
        let d = (b - a) / extent;
        p.iter().all(|c| {
            let e = (c - a) / extent;
            (d.x * e.y - d.y * e.x).abs() <= 1e-9
        })
    }

    /// A tessellation that is Delaunay, or the typed error its input
    /// explains: `Degenerate` only for a collinear cloud (or fewer than
    /// three points), `NonFinite` only with a non-finite coordinate.
    /// (Until session 42 either was accepted for any cloud, so a mesher
    /// that refused everything passed.)
    fn outcome_ok(p: &[Point<2>], r: Result<Tessellation, GeometryError>) {
        match r {
            Ok(t) => check(p, &t),
            Err(GeometryError::NearCoincident { first, second, .. }) => {
                assert!(first < second && second < p.len());
            }
            Err(GeometryError::Degenerate { .. }) => {
                assert!(collinear(p), "Degenerate for a cloud that is not collinear")
            }
            Err(GeometryError::NonFinite { .. }) => {
                assert!(p.iter().any(|q| !q.iter().all(|c| c.is_finite())))
            }
            Err(e) => panic!("unexpected error {e}"),
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(96))]
        #[test]
        fn random_clouds_are_delaunay(p in cloud(70)) {
            outcome_ok(&p, mesh(&p));
        }

        #[test]
        fn grid_clouds_are_delaunay_or_typed(p in grid_cloud(50)) {
            let r = mesh(&p);
            let mut sorted: Vec<_> = p.iter().map(|q| (q.x as i32, q.y as i32)).collect();
            sorted.sort_unstable();
            let has_dup = sorted.windows(2).any(|w| w[0] == w[1]);
            if has_dup {
                prop_assert!(r.is_err());
            }
            outcome_ok(&p, r);
        }

        #[test]
        fn scaled_clouds(p in cloud(40), e in -300i32..300, off in -1e6f64..1e6) {
            let s = 10f64.powi(e);
            let q: Vec<_> = p.iter().map(|x| x * s + Point::<2>::new(off * s, 0.0)).collect();
            outcome_ok(&q, mesh(&q));
        }

        #[test]
        fn never_panics(v in prop::collection::vec((any::<f64>(), any::<f64>()), 0..20)) {
            let p: Vec<_> = v.into_iter().map(|(x, y)| Point::<2>::new(x, y)).collect();
            let _ = mesh(&p);
        }
    }
}
