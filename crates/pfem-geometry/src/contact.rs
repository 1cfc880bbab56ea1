//! Contact elements: the simplices of the particles' Delaunay tessellation
//! that join two bodies with no fluid between them (the contact-domain idea
//! of the PFEM solid-mechanics codes). The tessellation finds the contact:
//! where a solid that takes part in contact (a free one; also a clamped
//! one when the scene asks) comes within reach of a wall or
//! another solid, the simplices spanning the gap become interface
//! elements, and the driver
//! gives them a penalty material that resists the closing of the gap
//! (`pfem_constitutive::ContactPenalty`).
//!
//! Each element has a *master* facet (the nodes of one body) and the rest
//! (the other body): its gap is the height of the simplex over the master
//! facet (2D: the lone node's distance to the master edge's line; 3D,
//! three nodes on one body: the lone node's distance to their triangle,
//! the triangle itself where the node stands beside it; two and two: the
//! distance between the two edges as segments), its normal the master facet's, pointing from
//! the master body towards the other. In 3D a tetrahedron whose smallest
//! height is below `min_gap` spacings is no contact element. A simplex
//! where three or more bodies meet (2D or 3D) takes the gap and normal of
//! its nearest pair of particles of different bodies, one of a body in
//! contact.

use pfem_core::{Const, Dim, ParticleKind, Point, Vector};

use crate::{GeometryError, Tessellation};

/// One contact element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactCandidate<const D: usize>
where
    Const<D>: Dim,
{
    /// The simplex's particles (`D + 1`; the rest unused), as in the
    /// tessellation.
    pub nodes: [u32; 4],
    /// Gap across the element (m), positive.
    pub gap: f64,
    /// Unit normal from the master body towards the other.
    pub normal: Vector<D>,
    /// The two bodies, master first.
    pub bodies: (u32, u32),
}

/// The contact elements of `delaunay`: simplices with no fluid node, with
/// nodes of at least two bodies of which at least one takes part in
/// contact (`in_contact[body]`: the free solids, and the clamped ones
/// when the scene asks), every edge shorter than `reach` times the
/// mean spacing of its nodes, and a gap above `min_gap` times that
/// spacing (no slivers; in 3D also a smallest height above it). Where
/// three or more bodies meet (2D or 3D), the gap, normal and `bodies` are those
/// of the nearest pair of particles of different bodies, one of a body in
/// contact. In tessellation order.
///
/// Errors, before anything is written: [`GeometryError::LengthMismatch`]
/// when `kinds`, `spacing` or `bodies` does not have one entry per point,
/// [`GeometryError::InvalidSpacing`] for a spacing that is not a positive
/// number, and [`GeometryError::InvalidConnectivity`] for a tessellation
/// that is not one of `D + 1` in-range vertices per simplex.
#[allow(clippy::too_many_arguments)]
pub fn contact_elements<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    bodies: &[u32],
    spacing: &[f64],
    in_contact: &[bool],
    delaunay: &Tessellation,
    reach: f64,
    min_gap: f64,
    out: &mut Vec<ContactCandidate<D>>,
) -> Result<(), GeometryError>
where
    Const<D>: Dim,
{
    out.clear();
    crate::alpha::check_particles(points, kinds, spacing)?;
    if bodies.len() != points.len() {
        return Err(GeometryError::LengthMismatch {
            what: "bodies",
            expected: points.len(),
            found: bodies.len(),
        });
    }
    crate::alpha::check_tessellation::<D>(delaunay, points.len())?;
    let nv = D + 1;
    for s in delaunay.simplices.chunks_exact(nv) {
        if s.iter().any(|&p| kinds[p as usize] == ParticleKind::Fluid)
            || !s.iter().any(|&p| kinds[p as usize] == ParticleKind::Solid)
        {
            continue;
        }
        // Bodies and their node counts.
        let mut group: [(u32, usize); 4] = [(u32::MAX, 0); 4];
        let mut ng = 0;
        for &p in s {
            let b = bodies[p as usize];
            match group[..ng].iter_mut().find(|g| g.0 == b) {
                Some(g) => g.1 += 1,
                None => {
                    group[ng] = (b, 1);
                    ng += 1;
                }
            }
        }
        if ng < 2
            || !group[..ng]
                .iter()
                .any(|g| in_contact.get(g.0 as usize).copied().unwrap_or(false))
        {
            continue;
        }
        let h = s.iter().map(|&p| spacing[p as usize]).sum::<f64>() / nv as f64;
        let x = |a: usize| points[s[a] as usize];
        let too_long = (0..nv).any(|a| (a + 1..nv).any(|b| (x(a) - x(b)).norm() > reach * h));
        if too_long {
            continue;
        }
        // 3D: a tetrahedron whose smallest height is below `min_gap`
        // spacings is a sliver, whatever gap its bodies' planes or edges
        // measure. Four nearly coplanar particles of two bodies (a row of
        // a block over a row of the floor, both along `z`) make two
        // nearly parallel opposite edges, whose common normal the
        // edge-against-edge gap takes in any direction: such an element
        // started at 0.68 of its gap, under pressure, and a block resting
        // one spacing from a side wall was kicked to 169 m/s (session 36).
        if D == 3 && smallest_height_3d::<D>(&x) <= min_gap * h {
            continue;
        }
        // Master: the body with most nodes (the first such).
        group[..ng].sort_by_key(|g| std::cmp::Reverse(g.1));
        let (mut master, mut other) = (group[0].0, group[1].0);
        let on = |a: usize| bodies[s[a] as usize] == master;
        // Three or more bodies (2D: one node each): the nearest pair. A
        // plane or edge through the master's node and another body's node
        // mixes two bodies; in 2D it put a solid resting one spacing from
        // a floor and a side wall under penalty at rest (gap 0.71 h, a
        // diagonal normal; session 40's review).
        let body = |a: usize| bodies[s[a] as usize];
        let takes_part = |a: usize| in_contact.get(body(a) as usize).copied().unwrap_or(false);
        let found = if ng >= 3 {
            nearest_pair::<D>(&x, &body, &takes_part, master).map(|(gap, n, pair)| {
                (master, other) = pair;
                (gap, n)
            })
        } else {
            // Two bodies: the master facet's height, unless (2D) the edge
            // cuts across a concave corner of one body (a floor and a side
            // wall of one polygon): then it lies nearer than any particle
            // of that body, and the nearest pair measures the gap
            // (`CORNER_RATIO`; session 41's review).
            gap_and_normal::<D>(&x, &on, group[0].1).map(|(gap, n)| {
                if D != 2 {
                    return (gap, n);
                }
                match nearest_pair::<D>(&x, &body, &takes_part, master) {
                    Some((d, nd, pair)) if gap < CORNER_RATIO * d => {
                        (master, other) = pair;
                        (d, nd)
                    }
                    _ => (gap, n),
                }
            })
        };
        let Some((gap, normal)) = found else {
            continue;
        };
        if gap <= min_gap * h {
            continue;
        }
        let mut nodes = [0u32; 4];
        nodes[..nv].copy_from_slice(s);
        out.push(ContactCandidate {
            nodes,
            gap,
            normal,
            bodies: (master, other),
        });
    }
    Ok(())
}

/// 2D: below this ratio of a two-body triangle's edge height to its
/// nearest pair of particles of the two bodies, the master edge cuts
/// across a concave corner of the master body and the nearest pair gives
/// the gap. Across a corner of a lattice the ratio is `1/√2` (a solid one
/// spacing from a floor and a side wall of one body: the edge's height
/// 0.71 h, a diagonal normal, the solid under penalty at rest); over a
/// flat row it is at least `g/√(g² + s²)`, `s` the largest offset of the
/// other body's particle from the master's nearest (half the master's
/// spacing): 0.89 between offset rows at the contact distance, 0.83 for a
/// row on one of twice its spacing, 0.78 at four times, and 0.79 with 10 %
/// of the gap closed. Not in 3D: there a flat contact reaches 0.71 too
/// (the central tetrahedron of a cube cell split in five, edge against
/// edge, whose nearest pair is a face diagonal), so the 3D corner of one
/// body is left as the facet measures it (session 41's review).
const CORNER_RATIO: f64 = 0.75;

/// Gap, normal and bodies of a tetrahedron where three or four bodies meet
/// (a solid in the corner of two walls): the shortest distance between two
/// of its particles of different bodies, one of them of a body in contact
/// (`takes_part`), along that pair, from the `master` body's particle if
/// the pair has one (else from the body in contact's), and the pair's
/// bodies in that order. A plane through the master's nodes, or an edge
/// against an edge of two other bodies, puts the corner's diagonal nearer
/// than either body really is: a free block standing one spacing from a
/// floor and a side wall then started under a penalty pressure at rest,
/// and a particle left at 169 m/s (session 36). Between lattices one
/// spacing apart this gap is the spacing, so the element starts open, as
/// the two-body ones do.
fn nearest_pair<const D: usize>(
    x: &dyn Fn(usize) -> Point<D>,
    body: &dyn Fn(usize) -> u32,
    takes_part: &dyn Fn(usize) -> bool,
    master: u32,
) -> Option<(f64, Vector<D>, (u32, u32))>
where
    Const<D>: Dim,
{
    let nv = D + 1;
    let mut best: Option<(f64, usize, usize)> = None;
    for a in 0..nv {
        for b in a + 1..nv {
            if body(a) == body(b) || !(takes_part(a) || takes_part(b)) {
                continue;
            }
            let len = (x(b) - x(a)).norm();
            if best.as_ref().is_none_or(|q| len < q.0) {
                best = Some((len, a, b));
            }
        }
    }
    let (gap, a, b) = best?;
    // From the master's particle, or else from the body in contact's.
    let (from, to) = if body(b) == master || (body(a) != master && takes_part(b) && !takes_part(a))
    {
        (b, a)
    } else {
        (a, b)
    };
    (gap.is_finite() && gap > 0.0).then(|| (gap, (x(to) - x(from)) / gap, (body(from), body(to))))
}

/// The smallest height of a tetrahedron (`3 V` over its largest face);
/// 0 when flat.
fn smallest_height_3d<const D: usize>(x: &dyn Fn(usize) -> Point<D>) -> f64
where
    Const<D>: Dim,
{
    let (a, b, c) = (x(1) - x(0), x(2) - x(0), x(3) - x(0));
    let six_v = cross3::<D>(&a, &b).dot(&c).abs();
    let twice_largest = (0..4)
        .map(|skip| {
            let f: Vec<usize> = (0..4).filter(|&k| k != skip).collect();
            cross3::<D>(&(x(f[1]) - x(f[0])), &(x(f[2]) - x(f[0]))).norm()
        })
        .fold(0.0, f64::max);
    if twice_largest > 0.0 {
        six_v / twice_largest
    } else {
        0.0
    }
}

/// Gap and master normal of a simplex of two bodies whose nodes `a` with
/// `on(a)` are the master body's (`m` of them): a triangle 2 + 1 in 2D, a
/// tetrahedron 3 + 1 or 2 + 2 in 3D (three or more bodies:
/// [`nearest_pair`]).
fn gap_and_normal<const D: usize>(
    x: &dyn Fn(usize) -> Point<D>,
    on: &dyn Fn(usize) -> bool,
    m: usize,
) -> Option<(f64, Vector<D>)>
where
    Const<D>: Dim,
{
    let nv = D + 1;
    let mine: Vec<usize> = (0..nv).filter(|&a| on(a)).collect();
    let theirs: Vec<usize> = (0..nv).filter(|&a| !on(a)).collect();
    let c_other = theirs.iter().map(|&a| x(a)).sum::<Vector<D>>() / theirs.len() as f64;
    let orient = |n: Vector<D>, base: Point<D>| {
        let n = n / n.norm();
        if n.dot(&(c_other - base)) < 0.0 {
            -n
        } else {
            n
        }
    };
    let n = if D == 2 {
        // 2D: the master edge (two bodies split a triangle 2 + 1).
        if m != 2 {
            return None;
        }
        let (p, q) = (x(mine[0]), x(mine[1]));
        let e = q - p;
        let mut n = Vector::<D>::zeros();
        n[0] = -e[1];
        n[1] = e[0];
        if n.norm() == 0.0 {
            return None;
        }
        orient(n, p)
    } else if m == 3 {
        let (p, q, r) = (x(mine[0]), x(mine[1]), x(mine[2]));
        let n = cross3::<D>(&(q - p), &(r - p));
        if n.norm() == 0.0 {
            return None;
        }
        orient(n, p)
    } else if m == 2 && theirs.len() == 2 {
        // Edge against edge: the common normal.
        let e1 = x(mine[1]) - x(mine[0]);
        let e2 = x(theirs[1]) - x(theirs[0]);
        let n = cross3::<D>(&e1, &e2);
        if n.norm() == 0.0 {
            return None;
        }
        orient(n, x(mine[0]))
    } else {
        // Three or more bodies: `nearest_pair` measures those, and two
        // bodies split a tetrahedron 3 + 1 or 2 + 2.
        return None;
    };
    // The gap: the largest distance of a non-master node from the master's
    // plane through its first node (for edge-edge, the edges' distance).
    let base = x(mine[0]);
    let gap = theirs
        .iter()
        .map(|&a| (x(a) - base).dot(&n))
        .fold(f64::NEG_INFINITY, f64::max);
    // 3D: the distance to the master's facet itself, not to its plane or
    // line: from the lone node to the nearest point of the master's
    // triangle (3 + 1), between the two edges as segments (2 + 2). Where
    // the lone node stands beside the triangle, or the edges' lines meet
    // beyond their ends (nearly parallel edges), the plane or line passes
    // nearer than the body does: a tessellation of a curved or tilted
    // solid formed such elements already closed, each remeshing stored
    // penalty energy that no motion had put in, and a ball R = 4 h thrown
    // at a floor left with ×1.13 of its kinetic and strain energy
    // (`tests/hertz_3d.rs`; ×1.02 measured so). Where the nearest points
    // fall inside both, the two measures agree.
    let gap = if D == 3 && m == 3 {
        gap.max(point_triangle::<D>(
            x(theirs[0]),
            x(mine[0]),
            x(mine[1]),
            x(mine[2]),
        ))
    } else if D == 3 {
        gap.max(segment_segment::<D>(
            x(mine[0]),
            x(mine[1]),
            x(theirs[0]),
            x(theirs[1]),
        ))
    } else {
        gap
    };
    (gap.is_finite() && gap > 0.0).then_some((gap, n))
}

/// Distance from `p` to the triangle `a b c` (closest point clamped to it).
fn point_triangle<const D: usize>(p: Point<D>, a: Point<D>, b: Point<D>, c: Point<D>) -> f64
where
    Const<D>: Dim,
{
    let n = cross3::<D>(&(b - a), &(c - a));
    let nn = n.norm_squared();
    if nn > 0.0 {
        // Projection inside the triangle: the plane's distance.
        let q = p - n * ((p - a).dot(&n) / nn);
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|(u, v)| cross3::<D>(&(*v - *u), &(q - *u)).dot(&n) >= 0.0);
        if inside {
            return (p - q).norm();
        }
    }
    segment_point::<D>(p, a, b)
        .min(segment_point::<D>(p, b, c))
        .min(segment_point::<D>(p, c, a))
}

fn segment_point<const D: usize>(p: Point<D>, a: Point<D>, b: Point<D>) -> f64
where
    Const<D>: Dim,
{
    let e = b - a;
    let ee = e.norm_squared();
    let t = if ee > 0.0 {
        ((p - a).dot(&e) / ee).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + e * t)).norm()
}

/// Distance between the segments `p0 p1` and `q0 q1`.
fn segment_segment<const D: usize>(p0: Point<D>, p1: Point<D>, q0: Point<D>, q1: Point<D>) -> f64
where
    Const<D>: Dim,
{
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let (a, e, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    let (b, c) = (d1.dot(&d2), d1.dot(&r));
    let den = a * e - b * b;
    let mut best = segment_point::<D>(p0, q0, q1)
        .min(segment_point::<D>(p1, q0, q1))
        .min(segment_point::<D>(q0, p0, p1))
        .min(segment_point::<D>(q1, p0, p1));
    if den > 1e-12 * a * e {
        let s = (b * f - c * e) / den;
        let t = (a * f - b * c) / den;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            best = best.min(((p0 + d1 * s) - (q0 + d2 * t)).norm());
        }
    }
    best
}

fn cross3<const D: usize>(a: &Vector<D>, b: &Vector<D>) -> Vector<D>
where
    Const<D>: Dim,
{
    let mut c = Vector::<D>::zeros();
    if D == 3 {
        c[0] = a[1] * b[2] - a[2] * b[1];
        c[1] = a[2] * b[0] - a[0] * b[2];
        c[2] = a[0] * b[1] - a[1] * b[0];
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Delaunay2, Tessellator};

    /// A solid row one spacing above a wall row: the triangles between them
    /// are contact elements with gap h and normal +y from the wall, or −y
    /// from the solid.
    #[test]
    fn a_row_above_a_row_makes_contact_elements_of_gap_h() {
        let h = 0.1;
        let mut x = Vec::new();
        let mut kinds = Vec::new();
        let mut bodies = Vec::new();
        for i in 0..6 {
            x.push(Point::<2>::new(i as f64 * h, 0.0));
            kinds.push(ParticleKind::Wall);
            bodies.push(0);
        }
        for i in 0..6 {
            x.push(Point::<2>::new(i as f64 * h + 0.013, h));
            kinds.push(ParticleKind::Solid);
            bodies.push(1);
        }
        let spacing = vec![h; x.len()];
        let mut t = Tessellation::default();
        Delaunay2::default().tessellate(&x, &mut t).unwrap();
        let mut out = Vec::new();
        contact_elements(
            &x,
            &kinds,
            &bodies,
            &spacing,
            &[false, true],
            &t,
            1.6,
            0.05,
            &mut out,
        )
        .unwrap();
        assert!(out.len() >= 9, "{}", out.len());
        for c in &out {
            assert!((c.gap - h).abs() < 1e-12, "gap {}", c.gap);
            let sign = if c.bodies.0 == 0 { 1.0 } else { -1.0 };
            assert!((c.normal - Vector::<2>::new(0.0, sign)).norm() < 1e-12);
        }
        // Nobody in contact: nothing.
        contact_elements(
            &x,
            &kinds,
            &bodies,
            &spacing,
            &[false, false],
            &t,
            1.6,
            0.05,
            &mut out,
        )
        .unwrap();
        assert!(out.is_empty());
        // Arrays of other lengths, or a tessellation of other points, are
        // errors, not panics (session 35's review).
        let short = &bodies[..bodies.len() - 1];
        let err = contact_elements(
            &x,
            &kinds,
            short,
            &spacing,
            &[true, true],
            &t,
            1.6,
            0.05,
            &mut out,
        );
        assert!(
            matches!(
                err,
                Err(GeometryError::LengthMismatch { what: "bodies", .. })
            ),
            "{err:?}"
        );
        let err = contact_elements(
            &x[..3],
            &kinds[..3],
            &bodies[..3],
            &spacing[..3],
            &[true, true],
            &t,
            1.6,
            0.05,
            &mut out,
        );
        assert!(
            matches!(err, Err(GeometryError::InvalidConnectivity { .. })),
            "{err:?}"
        );
    }

    /// Every particle a wall's but those of body `solid`.
    fn kinds_of(bodies: &[u32], solid: u32) -> Vec<ParticleKind> {
        bodies
            .iter()
            .map(|&b| {
                if b == solid {
                    ParticleKind::Solid
                } else {
                    ParticleKind::Wall
                }
            })
            .collect()
    }

    /// 2D: a solid resting one spacing from a floor and from a side wall,
    /// each a body of its own. The corner triangle {floor, solid, side
    /// wall} has the gap of its nearest pair (the spacing), from the
    /// solid's neighbour along the pair, never the mixed floor–wall edge's
    /// (0.71 h, a diagonal normal: the solid started under penalty at
    /// rest). Every element starts open at the spacing.
    #[test]
    fn a_solid_in_a_corner_of_two_walls_starts_open_2d() {
        let mut x = Vec::new();
        let mut bodies = Vec::new();
        for i in 0..4 {
            x.push(Point::<2>::new(i as f64, 0.0)); // floor, body 0
            bodies.push(0);
        }
        for j in 1..4 {
            x.push(Point::<2>::new(0.0, j as f64)); // side wall, body 1
            bodies.push(1);
        }
        for i in 1..3 {
            for j in 1..3 {
                x.push(Point::<2>::new(i as f64, j as f64)); // solid, body 2
                bodies.push(2);
            }
        }
        // Both diagonals of the corner square: the lattice's tie may go
        // either way. Triangle {floor (1,0), solid (1,1), side (0,1)} with
        // the corner (0,0), and the other split.
        for corner in [[0u32, 7, 4, 0, 1, 7], [0, 1, 4, 1, 7, 4]] {
            let out = tris_2d(&x, &bodies, &corner);
            assert!(!out.is_empty(), "{corner:?}");
            for c in &out {
                assert!((c.gap - 1.0).abs() < 1e-12, "{corner:?}: gap {}", c.gap);
                // Along a lattice axis, between the solid and a wall.
                assert!(
                    (c.normal.x.abs() - 1.0).abs() < 1e-12
                        || (c.normal.y.abs() - 1.0).abs() < 1e-12,
                    "{corner:?}: normal {:?}",
                    c.normal
                );
                assert!(c.bodies.0 == 2 || c.bodies.1 == 2, "{:?}", c.bodies);
            }
        }
    }

    /// Session 41's review: the floor and the side wall are one body (a
    /// tank of one polygon). The triangle {floor (1,0), solid (1,1), side
    /// (0,1)} is then a two-body simplex whose master edge, floor to side,
    /// cuts the corner: gap 0.71 h with a diagonal normal (the solid under
    /// penalty at rest). It takes its nearest pair's: the spacing, along
    /// an axis. A row over a row offset by half a spacing keeps its facet's
    /// gap (the spacing, vertical).
    #[test]
    fn a_solid_in_a_corner_of_one_wall_body_starts_open_2d() {
        let mut x = Vec::new();
        let mut bodies = Vec::new();
        for i in 0..4 {
            x.push(Point::<2>::new(i as f64, 0.0)); // floor, body 0
            bodies.push(0);
        }
        for j in 1..4 {
            x.push(Point::<2>::new(0.0, j as f64)); // side wall, body 0 too
            bodies.push(0);
        }
        for i in 1..3 {
            for j in 1..3 {
                x.push(Point::<2>::new(i as f64, j as f64)); // solid, body 2
                bodies.push(2);
            }
        }
        let out = tris_2d(&x, &bodies, &[1, 7, 4]);
        assert_eq!(out.len(), 1);
        let c = &out[0];
        assert!((c.gap - 1.0).abs() < 1e-12, "gap {}", c.gap);
        assert!(
            (c.normal.x.abs() - 1.0).abs() < 1e-12 || (c.normal.y.abs() - 1.0).abs() < 1e-12,
            "normal {:?}",
            c.normal
        );
        // A flat floor and a solid row offset by half a spacing, one
        // spacing up: the floor's edge, gap 1, normal +y.
        let x = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(0.5, 1.0),
        ];
        let out = tris_2d(&x, &[0, 0, 2], &[0, 1, 2]);
        assert_eq!(out.len(), 1);
        assert!((out[0].gap - 1.0).abs() < 1e-12 && (out[0].normal.y - 1.0).abs() < 1e-12);
    }

    /// Contact elements of 2D triangles (`tris`, three indices each) of the
    /// given bodies (body 2 a solid in contact; 0 and 1 walls).
    fn tris_2d(x: &[Point<2>], bodies: &[u32], tris: &[u32]) -> Vec<ContactCandidate<2>> {
        let tess = Tessellation {
            nv: 3,
            simplices: tris.to_vec(),
            neighbors: vec![crate::NO_NEIGHBOR; tris.len()],
        };
        let mut out = Vec::new();
        contact_elements::<2>(
            x,
            &kinds_of(bodies, 2),
            bodies,
            &vec![1.0; x.len()],
            &[false, false, true],
            &tess,
            1.6,
            0.05,
            &mut out,
        )
        .unwrap();
        out
    }

    /// Contact elements of single 3D tetrahedra, each of the given bodies
    /// (body 1 takes part in contact; 0 and 2 are walls).
    fn tets_3d(x: &[Point<3>], bodies: &[u32], tets: &[[u32; 4]]) -> Vec<ContactCandidate<3>> {
        let kinds = kinds_of(bodies, 1);
        let tess = Tessellation {
            nv: 4,
            simplices: tets.iter().flatten().copied().collect(),
            neighbors: vec![crate::NO_NEIGHBOR; 4 * tets.len()],
        };
        let mut out = Vec::new();
        contact_elements::<3>(
            x,
            &kinds,
            bodies,
            &vec![1.0; x.len()],
            &[false, true, false],
            &tess,
            1.6,
            0.05,
            &mut out,
        )
        .unwrap();
        out
    }

    /// 3D, session 41's review: the central tetrahedron of a cube cell
    /// split in five between a floor's top row and a block's bottom row,
    /// edge against edge, has the gap of the spacing along the vertical,
    /// though its nearest pair is a face diagonal (a 2D-style corner rule
    /// had opened it at 1.41 h with a 45° normal).
    #[test]
    fn the_central_tetrahedron_of_a_flat_contact_keeps_its_gap_3d() {
        let x = [
            Point::<3>::new(1.0, 0.0, 0.0),
            Point::<3>::new(0.0, 1.0, 0.0),
            Point::<3>::new(0.0, 0.0, 1.0),
            Point::<3>::new(1.0, 1.0, 1.0),
        ];
        let out = tets_3d(&x, &[0, 0, 1, 1], &[[0, 1, 2, 3]]);
        assert_eq!(out.len(), 1);
        assert!((out[0].gap - 1.0).abs() < 1e-12, "gap {}", out[0].gap);
        assert!(
            (out[0].normal.z.abs() - 1.0).abs() < 1e-12,
            "{:?}",
            out[0].normal
        );
    }

    /// 3D, session 56: the gap is the distance to the master's facet, not
    /// to its plane or line. A solid particle 0.8 spacings above a floor
    /// triangle's plane but beside the triangle (its nearest point on
    /// the hypotenuse, 0.98 spacings away) is not 0.8 from the floor's facet;
    /// a solid edge slanting across a floor edge (their lines pass 0.36
    /// spacings apart, beyond the edges' ends) is as far as the segments'
    /// nearest points, 0.61. The plane's and the lines' measures
    /// formed such elements already closed, and a ball left a floor with
    /// ×1.13 of its energy (`tests/hertz_3d.rs`).
    #[test]
    fn the_gap_is_the_distance_to_the_facet_not_its_plane_3d() {
        // 3 + 1: floor triangle (0,0,0) (1,0,0) (0,1,0); the solid
        // particle above (0.9, 0.9, 0.8), beside the triangle's hypotenuse.
        let x = [
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(1.0, 0.0, 0.0),
            Point::<3>::new(0.0, 1.0, 0.0),
            Point::<3>::new(0.9, 0.9, 0.8),
        ];
        let out = tets_3d(&x, &[0, 0, 0, 1], &[[0, 1, 2, 3]]);
        assert_eq!(out.len(), 1);
        let beside = (0.4f64.powi(2) * 2.0 + 0.64).sqrt();
        assert!((out[0].gap - beside).abs() < 1e-12, "gap {}", out[0].gap);
        assert!((out[0].normal.z - 1.0).abs() < 1e-12);
        // Above the triangle the plane's height: (0.2, 0.2, 0.8).
        let x = [x[0], x[1], x[2], Point::<3>::new(0.2, 0.2, 0.8)];
        let out = tets_3d(&x, &[0, 0, 0, 1], &[[0, 1, 2, 3]]);
        assert!((out[0].gap - 0.8).abs() < 1e-12, "gap {}", out[0].gap);
        // 2 + 2: a floor edge along x and a solid edge from (0.1, 0.3, 1)
        // to (1.1, 0, 0.6): their lines' common normal is tilted 53° from
        // the floor's and short.
        let x = [
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(1.0, 0.0, 0.0),
            Point::<3>::new(0.1, 0.3, 1.0),
            Point::<3>::new(1.1, 0.0, 0.6),
        ];
        let out = tets_3d(&x, &[0, 0, 1, 1], &[[0, 1, 2, 3]]);
        assert_eq!(out.len(), 1);
        let (p0, p1, q0, q1) = (x[0], x[1], x[2], x[3]);
        let lines = {
            let n = (p1 - p0).cross(&(q1 - q0));
            (q0 - p0).dot(&n).abs() / n.norm()
        };
        let segments = segment_segment::<3>(p0, p1, q0, q1);
        assert!(lines < 0.4 && segments > 0.6, "{lines} {segments}");
        assert!((out[0].gap - segments).abs() < 1e-12, "gap {}", out[0].gap);
    }

    /// 3D: four nearly coplanar particles, a row of a solid one spacing
    /// over a row of a wall, make no contact element (their two opposite
    /// edges are nearly parallel, so the edge-against-edge gap would take
    /// any direction), while a fair tetrahedron between the same rows
    /// does, with the gap of the spacing. Session 36: the flat one started
    /// at 0.68 of its gap and kicked a resting block.
    #[test]
    fn a_flat_tetrahedron_between_two_rows_is_no_contact_element_3d() {
        let x = [
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(0.0, 0.0, 1.0),
            Point::<3>::new(1e-9, 1.0, 0.0),
            Point::<3>::new(-1e-9, 1.0, 1.0),
            Point::<3>::new(1.0, 0.0, 0.0),
        ];
        let bodies = [0, 0, 1, 1, 0];
        assert!(tets_3d(&x, &bodies, &[[0, 1, 2, 3]]).is_empty());
        let fair = tets_3d(&x, &bodies, &[[0, 4, 1, 2]]);
        assert_eq!(fair.len(), 1);
        assert!((fair[0].gap - 1.0).abs() < 1e-6, "{}", fair[0].gap);
    }

    /// 3D: a corner tetrahedron of three bodies (a solid's edge one
    /// spacing from a floor node and from a side wall node) has the gap of
    /// its nearest pair, the spacing: it starts open, as the two-body
    /// elements between the same lattices do.
    #[test]
    fn a_corner_of_three_bodies_has_the_gap_of_its_nearest_pair_3d() {
        let x = [
            Point::<3>::new(0.0, 1.0, 1.0),
            Point::<3>::new(1.0, 1.0, 1.0),
            Point::<3>::new(0.0, 0.0, 1.0),
            Point::<3>::new(0.0, 1.0, 0.0),
        ];
        let bodies = [1, 1, 0, 2];
        let c = tets_3d(&x, &bodies, &[[0, 1, 2, 3]]);
        assert_eq!(c.len(), 1);
        assert!((c[0].gap - 1.0).abs() < 1e-12, "{}", c[0].gap);
        assert!((c[0].normal.norm() - 1.0).abs() < 1e-12);
        assert_eq!(c[0].bodies.0, 1);
        // The master a wall (two floor nodes): the pair is still the
        // solid's, never the floor against the side wall, which cannot
        // close; the bodies name the solid.
        // (The floor–wall pair comes first and is as near: it must not be
        // taken.)
        let x = [
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(1.0, 0.0, 0.0),
            Point::<3>::new(0.0, 0.0, 1.0),
            Point::<3>::new(0.0, 1.0, 0.0),
        ];
        let bodies = [0, 0, 2, 1];
        let c = tets_3d(&x, &bodies, &[[0, 1, 2, 3]]);
        assert_eq!(c.len(), 1);
        assert!((c[0].gap - 1.0).abs() < 1e-12, "{}", c[0].gap);
        assert_eq!(c[0].bodies, (0, 1));
        assert!((c[0].normal - Vector::<3>::new(0.0, 1.0, 0.0)).norm() < 1e-12);
    }
}
