//! Property tests of the 3D Delaunay tessellator: every input ends in a
//! valid Delaunay tetrahedralisation of its convex hull or a typed error.

use pfem_core::{simplex_measure, Point};
use pfem_geometry::delaunay3::predicates::{insphere, orient3d};
use pfem_geometry::{Delaunay3, GeometryError, Tessellation, Tessellator, NO_NEIGHBOR};
use proptest::prelude::*;
use std::collections::{HashMap, HashSet};

const FACET: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

fn a(p: &Point<3>) -> [f64; 3] {
    [p.x, p.y, p.z]
}

fn tess(pts: &[Point<3>]) -> Result<Tessellation, GeometryError> {
    let mut out = Tessellation::new(4);
    Delaunay3::default().tessellate(pts, &mut out)?;
    Ok(out)
}

/// Checks everything that makes `t` the Delaunay tessellation of the
/// convex hull of `pts` (all distinct); returns the total volume.
fn check_delaunay(pts: &[Point<3>], t: &Tessellation) -> f64 {
    let p: Vec<[f64; 3]> = pts.iter().map(a).collect();
    assert_eq!(t.nv, 4);
    assert_eq!(t.simplices.len(), t.neighbors.len());
    let nt = t.len();
    assert!(nt > 0);
    let mut volume = 0.0;
    let mut used = vec![false; pts.len()];
    let mut edges = HashSet::new();
    let mut faces = HashSet::new();
    let mut hull_faces = 0usize;
    let mut hull_edges = HashSet::new();
    let mut hull_vertices = HashSet::new();
    for s in 0..nt {
        let v = t.simplex(s);
        let q: Vec<&[f64; 3]> = v.iter().map(|&i| &p[i as usize]).collect();
        // Positively oriented, exactly and in floating point.
        assert_eq!(
            orient3d(q[0], q[1], q[2], q[3]),
            1,
            "tet {s} {v:?} not positive"
        );
        let tp: Vec<Point<3>> = v.iter().map(|&i| pts[i as usize]).collect();
        let vol = simplex_measure::<3>(&tp);
        assert!(vol > 0.0);
        volume += vol;
        // Empty circumsphere, exactly.
        for (i, r) in p.iter().enumerate() {
            assert!(
                insphere(q[0], q[1], q[2], q[3], r) <= 0,
                "point {i} strictly inside the circumsphere of tet {s} {v:?}"
            );
        }
        for &i in v {
            used[i as usize] = true;
        }
        for x in 0..4 {
            for y in x + 1..4 {
                edges.insert((v[x].min(v[y]), v[x].max(v[y])));
            }
            let mut f = [v[FACET[x][0]], v[FACET[x][1]], v[FACET[x][2]]];
            f.sort_unstable();
            faces.insert(f);
        }
        // Neighbour symmetry, across the facet opposite local vertex k.
        for (k, fk) in FACET.iter().enumerate() {
            let nb = t.simplex_neighbors(s)[k];
            let mut f: Vec<u32> = fk.iter().map(|&j| v[j]).collect();
            if nb == NO_NEIGHBOR {
                hull_faces += 1;
                // Convex hull facet: no point beyond it.
                let fq: Vec<&[f64; 3]> = f.iter().map(|&i| &p[i as usize]).collect();
                for r in &p {
                    assert!(
                        orient3d(fq[0], fq[1], fq[2], r) <= 0,
                        "hull not convex at tet {s}"
                    );
                }
                for x in 0..3 {
                    let (u, w) = (f[x], f[(x + 1) % 3]);
                    hull_edges.insert((u.min(w), u.max(w)));
                    hull_vertices.insert(u);
                }
                continue;
            }
            let nb = nb as usize;
            assert!(nb < nt);
            let back = t
                .simplex_neighbors(nb)
                .iter()
                .position(|&x| x as usize == s);
            let kb = back.expect("neighbour relation not symmetric");
            let w = t.simplex(nb);
            let mut g: Vec<u32> = FACET[kb].iter().map(|&j| w[j]).collect();
            f.sort_unstable();
            g.sort_unstable();
            assert_eq!(f, g, "tets {s} and {nb} do not share the facet they claim");
        }
    }
    // Every point is a vertex of the Delaunay tessellation.
    assert!(
        used.iter().all(|&u| u),
        "a point is missing from the tessellation"
    );
    // Euler characteristic of a 3-ball and of its boundary sphere.
    let euler = pts.len() as i64 - edges.len() as i64 + faces.len() as i64 - nt as i64;
    assert_eq!(euler, 1, "V - E + F - T");
    let euler_b = hull_vertices.len() as i64 - hull_edges.len() as i64 + hull_faces as i64;
    assert_eq!(euler_b, 2, "boundary V - E + F");
    volume
}

/// Volume of the convex hull of points in general position, by brute force.
fn hull_volume_brute_force(pts: &[Point<3>]) -> f64 {
    let p: Vec<[f64; 3]> = pts.iter().map(a).collect();
    let n = p.len();
    let c = pts.iter().fold(Point::<3>::zeros(), |s, q| s + q) / n as f64;
    let mut vol = 0.0;
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let s: Vec<i32> = (0..n)
                    .filter(|&l| l != i && l != j && l != k)
                    .map(|l| orient3d(&p[i], &p[j], &p[k], &p[l]))
                    .collect();
                if s.iter().all(|&x| x > 0) || s.iter().all(|&x| x < 0) {
                    vol += simplex_measure::<3>(&[pts[i], pts[j], pts[k], c]).abs();
                }
            }
        }
    }
    vol
}

fn lattice(k: [usize; 3], h: f64, origin: [f64; 3]) -> Vec<Point<3>> {
    let mut pts = Vec::new();
    for i in 0..k[0] {
        for j in 0..k[1] {
            for l in 0..k[2] {
                pts.push(Point::<3>::new(
                    origin[0] + i as f64 * h,
                    origin[1] + j as f64 * h,
                    origin[2] + l as f64 * h,
                ));
            }
        }
    }
    pts
}

/// Whether all points are coplanar (exactly).
fn flat(pts: &[Point<3>]) -> bool {
    let p: Vec<[f64; 3]> = pts.iter().map(a).collect();
    for i in 0..p.len() {
        for j in 0..p.len() {
            for k in 0..p.len() {
                if p.iter().any(|r| orient3d(&p[i], &p[j], &p[k], r) != 0) {
                    return false;
                }
            }
        }
    }
    true
}

fn has_duplicate(pts: &[Point<3>]) -> bool {
    let mut seen = HashSet::new();
    !pts.iter()
        .all(|p| seen.insert([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]))
}

fn cloud(n: std::ops::Range<usize>, lo: f64, hi: f64) -> impl Strategy<Value = Vec<Point<3>>> {
    prop::collection::vec((lo..hi, lo..hi, lo..hi), n).prop_map(|v| {
        v.into_iter()
            .map(|(x, y, z)| Point::<3>::new(x, y, z))
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_clouds_are_delaunay_and_fill_the_hull(pts in cloud(5..30, -1.0, 1.0)) {
        let t = tess(&pts).unwrap();
        let vol = check_delaunay(&pts, &t);
        let hull = hull_volume_brute_force(&pts);
        prop_assert!((vol - hull).abs() <= 1e-9 * hull, "{vol} vs hull {hull}");
    }

    #[test]
    fn lattices_fill_their_box_exactly(
        kx in 2usize..7, ky in 2usize..7, kz in 2usize..7,
        e in -20i32..20, ox in -3.0f64..3.0, oy in -3.0f64..3.0,
    ) {
        let h = 2f64.powi(e);
        let pts = lattice([kx, ky, kz], h, [ox * h, oy * h, 0.0]);
        let t = tess(&pts).unwrap();
        let vol = check_delaunay(&pts, &t);
        let boxv = (kx - 1) as f64 * (ky - 1) as f64 * (kz - 1) as f64 * h * h * h;
        prop_assert!((vol - boxv).abs() <= 1e-12 * boxv, "{vol} vs box {boxv}");
    }

    /// Small integer grids: duplicates, collinear and coplanar runs and
    /// cospherical sets everywhere. The outcome is fully determined.
    #[test]
    fn integer_grids_end_in_a_tessellation_or_a_typed_error(
        raw in prop::collection::vec((0i32..3, 0i32..3, 0i32..3), 0..24)
    ) {
        let pts: Vec<Point<3>> =
            raw.iter().map(|&(x, y, z)| Point::<3>::new(x as f64, y as f64, z as f64)).collect();
        match tess(&pts) {
            Ok(t) => {
                prop_assert!(!has_duplicate(&pts));
                check_delaunay(&pts, &t);
            }
            Err(GeometryError::Degenerate { count, dim }) => {
                prop_assert_eq!((count, dim), (pts.len(), 3));
                prop_assert!(pts.len() < 4 || flat(&pts));
            }
            Err(GeometryError::NearCoincident { first, second, distance, .. }) => {
                prop_assert!(first < second);
                prop_assert_eq!(pts[first], pts[second]);
                prop_assert_eq!(distance, 0.0);
                prop_assert!(!flat(&pts));
            }
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }

    #[test]
    fn coplanar_runs_plus_one_apex(
        raw in prop::collection::vec((0i32..6, 0i32..6), 3..30), apex in (0i32..6, 0i32..6, 1i32..3),
        tilt in 0i32..5,
    ) {
        // Quarter slopes keep the plane exact in floating point.
        let tilt = f64::from(tilt) / 4.0;
        let mut pts: Vec<Point<3>> = raw.iter()
            .map(|&(x, y)| Point::<3>::new(x as f64, y as f64, tilt * x as f64))
            .collect();
        let mut seen = HashSet::new();
        pts.retain(|p| seen.insert([p.x.to_bits(), p.y.to_bits()]));
        let flat_result = matches!(tess(&pts), Err(GeometryError::Degenerate { .. }));
        prop_assert!(flat_result);
        pts.push(Point::<3>::new(apex.0 as f64, apex.1 as f64, tilt * apex.0 as f64 + apex.2 as f64));
        let collinear = flat(&pts);
        match tess(&pts) {
            Ok(t) => { check_delaunay(&pts, &t); }
            Err(GeometryError::Degenerate { .. }) => prop_assert!(collinear),
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }

    #[test]
    fn exact_duplicates_are_reported(pts in cloud(5..40, -1.0, 1.0), i in 0usize..40, j in 0usize..40) {
        let mut pts = pts;
        let (i, j) = (i % pts.len(), j % pts.len());
        prop_assume!(i != j);
        pts[j] = pts[i];
        match tess(&pts) {
            Err(GeometryError::NearCoincident { first, second, distance, .. }) => {
                prop_assert_eq!((first, second), (i.min(j), i.max(j)));
                prop_assert_eq!(distance, 0.0);
            }
            other => prop_assert!(false, "expected NearCoincident, got {other:?}"),
        }
    }

    #[test]
    fn tessellation_does_not_depend_on_input_order(pts in cloud(5..60, 0.0, 1.0), seed in 0u64..1000) {
        let n = pts.len();
        let mut perm: Vec<usize> = (0..n).collect();
        let mut s = seed;
        for i in (1..n).rev() {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            perm.swap(i, (s >> 33) as usize % (i + 1));
        }
        let shuffled: Vec<Point<3>> = perm.iter().map(|&i| pts[i]).collect();
        let canon = |t: &Tessellation, map: &dyn Fn(u32) -> u32| {
            let mut v: Vec<[u32; 4]> = (0..t.len()).map(|s| {
                let mut q: [u32; 4] = std::array::from_fn(|k| map(t.simplex(s)[k]));
                q.sort_unstable();
                q
            }).collect();
            v.sort_unstable();
            v
        };
        let t1 = tess(&pts).unwrap();
        let t2 = tess(&shuffled).unwrap();
        prop_assert_eq!(canon(&t1, &|i| i), canon(&t2, &|i| perm[i as usize] as u32));
    }

    #[test]
    fn far_and_tiny_coordinates(pts in cloud(5..30, 0.0, 1.0), far in prop::bool::ANY) {
        let (scale, shift) = if far { (1.0, 1e6) } else { (1e-6, 0.0) };
        let pts: Vec<Point<3>> = pts.iter().map(|p| p * scale + Point::<3>::repeat(shift)).collect();
        match tess(&pts) {
            Ok(t) => { check_delaunay(&pts, &t); }
            Err(GeometryError::NearCoincident { .. }) => prop_assert!(has_duplicate(&pts)),
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }
}

#[test]
fn small_and_flat_inputs_are_degenerate() {
    for n in 0..4 {
        let pts: Vec<Point<3>> = (0..n)
            .map(|i| Point::<3>::new(i as f64, (i * i) as f64, 0.5))
            .collect();
        assert_eq!(
            tess(&pts),
            Err(GeometryError::Degenerate { count: n, dim: 3 })
        );
    }
    let line: Vec<Point<3>> = (0..50)
        .map(|i| Point::<3>::new(i as f64, 2.0 * i as f64, -(i as f64)))
        .collect();
    assert!(matches!(
        tess(&line),
        Err(GeometryError::Degenerate { count: 50, dim: 3 })
    ));
    let same = vec![Point::<3>::new(1.0, 2.0, 3.0); 10];
    assert!(matches!(tess(&same), Err(GeometryError::Degenerate { .. })));
}

#[test]
fn non_finite_coordinates_are_reported() {
    let mut pts = lattice([3, 3, 3], 1.0, [0.0; 3]);
    pts[7].y = f64::NAN;
    assert_eq!(tess(&pts), Err(GeometryError::NonFinite { index: 7 }));
    pts[7].y = 0.5;
    pts[3].z = f64::NEG_INFINITY;
    assert_eq!(tess(&pts), Err(GeometryError::NonFinite { index: 3 }));
}

#[test]
fn near_coincident_points_are_reported_with_a_tolerance() {
    let mut pts = lattice([4, 4, 4], 1.0, [0.0; 3]);
    pts.push(Point::<3>::new(1.0 + 1e-9, 2.0, 2.0));
    let mut out = Tessellation::new(4);
    // Default: only exact duplicates are errors.
    Delaunay3::default().tessellate(&pts, &mut out).unwrap();
    check_delaunay(&pts, &out);
    let err = Delaunay3::with_min_distance(1e-6)
        .tessellate(&pts, &mut out)
        .unwrap_err();
    match err {
        GeometryError::NearCoincident {
            first,
            second,
            distance,
            tolerance,
        } => {
            // Lattice point (1, 2, 2) is number 16 + 2 * 4 + 2.
            assert_eq!((first, second), (26, 64));
            assert!((distance - 1e-9).abs() < 1e-12);
            assert_eq!(tolerance, 1e-6);
        }
        e => panic!("unexpected {e}"),
    }
}

/// The first tetrahedron's own corners are checked too (session 40's
/// review: four points, two of them 10⁻² apart, passed a 10⁻¹ tolerance,
/// since only inserted points were compared with their cavity).
#[test]
fn near_coincident_corners_of_the_first_tetrahedron_are_reported() {
    let pts = [
        Point::<3>::new(0.0, 0.0, 0.0),
        Point::<3>::new(0.01, 0.0, 0.0),
        Point::<3>::new(0.0, 1.0, 0.0),
        Point::<3>::new(0.0, 0.0, 1.0),
    ];
    let mut out = Tessellation::new(4);
    Delaunay3::default().tessellate(&pts, &mut out).unwrap();
    match Delaunay3::with_min_distance(0.1).tessellate(&pts, &mut out) {
        Err(GeometryError::NearCoincident {
            first,
            second,
            distance,
            ..
        }) => {
            assert_eq!((first, second), (0, 1));
            assert!((distance - 0.01).abs() < 1e-15, "{distance}");
        }
        other => panic!("expected NearCoincident, got {other:?}"),
    }
}

#[test]
fn huge_and_mixed_magnitudes_never_panic() {
    // The checker's predicates would overflow at 2^500: check the
    // tessellation on the points scaled back (exactly) by 2^-500.
    let big = 2f64.powi(500);
    let mut pts = lattice([3, 3, 3], big, [0.0; 3]);
    let unit = lattice([3, 3, 3], 1.0, [0.0; 3]);
    let t = tess(&pts).unwrap();
    assert!((check_delaunay(&unit, &t) - 8.0).abs() < 1e-12);
    pts.push(Point::<3>::new(1e-300, 2e-300, 0.5 * big));
    // Either a tessellation or a typed error, never a panic.
    if let Ok(t) = tess(&pts) {
        assert!(!t.is_empty());
    }
}

#[test]
fn random_points_make_about_six_and_a_half_tets_each() {
    let n = 4000;
    let mut s = 7u64;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let pts: Vec<Point<3>> = (0..n)
        .map(|_| Point::<3>::new(next(), next(), next()))
        .collect();
    let t = tess(&pts).unwrap();
    let ratio = t.len() as f64 / n as f64;
    // 6.77 n in the limit; the hull lowers it for a few thousand points.
    assert!((5.8..6.8).contains(&ratio), "{ratio}");
    let vol: f64 = (0..t.len())
        .map(|s| {
            simplex_measure::<3>(
                &t.simplex(s)
                    .iter()
                    .map(|&i| pts[i as usize])
                    .collect::<Vec<_>>(),
            )
        })
        .sum();
    assert!(vol > 0.95 && vol < 1.0, "{vol}");
    // Neighbour symmetry on the large mesh.
    let mut across = HashMap::new();
    for s in 0..t.len() {
        for k in 0..4 {
            let nb = t.simplex_neighbors(s)[k];
            if nb != NO_NEIGHBOR {
                across.insert((s as u32, nb), ());
                assert!(t.simplex_neighbors(nb as usize).contains(&(s as u32)));
            }
        }
    }
    assert!(!across.is_empty());
}

#[test]
fn reusing_the_tessellator_gives_the_same_result() {
    let pts = lattice([5, 4, 3], 0.1, [1.0, 2.0, 3.0]);
    let mut mesher = Delaunay3::default();
    let mut a = Tessellation::new(4);
    let mut b = Tessellation::new(4);
    mesher.tessellate(&pts, &mut a).unwrap();
    mesher.tessellate(&pts[..20], &mut b).unwrap();
    mesher.tessellate(&pts, &mut b).unwrap();
    assert_eq!(a, b);
}

#[test]
fn lattices_far_from_the_origin() {
    for k in [3, 4, 5, 6, 8] {
        for shift in [1e6, 1e3, 12345.678] {
            let pts: Vec<Point<3>> = lattice([k, k, k], 0.01, [0.0; 3])
                .iter()
                .map(|p| p.map(|x| x + shift))
                .collect();
            let t = tess(&pts).unwrap();
            check_delaunay(&pts, &t);
        }
    }
}
