//! Exact geometric predicates for the 3D Delaunay tessellator, with the
//! symbolic perturbation (simulation of simplicity) that resolves every
//! cospherical and coplanar tie deterministically.
//!
//! The sign conventions follow [`pfem_core::simplex_measure`]: a tetrahedron
//! `(a, b, c, d)` is positively oriented when `det[b − a, c − a, d − a] > 0`.
//! The determinants are evaluated with Shewchuk's adaptive-precision
//! arithmetic (the `robust` crate), so every sign returned here is exact for
//! finite inputs whose products neither overflow nor underflow.
//!
//! The perturbation is the one of Edelsbrunner and Mücke (1990), §5 and
//! Devillers and Teillaud (2011): the lifted coordinate `|p_i|²` of point `i`
//! is raised by `ε^(N − i)`, so the point with the largest index is the most
//! perturbed. With it, the Delaunay tessellation is unique for any point set
//! without duplicates, and independent of the insertion order.

use robust::Coord3D;

use super::exact;

#[inline(always)]
fn c3(p: &[f64; 3]) -> Coord3D<f64> {
    Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

#[inline(always)]
fn sign(x: f64) -> i32 {
    (x > 0.0) as i32 - (x < 0.0) as i32
}

/// Exact sign of `det[b − a, c − a, d − a]`: `+1` when `(a, b, c, d)` is
/// positively oriented (positive signed volume), `−1` when negatively,
/// `0` when the four points are coplanar.
#[inline]
pub fn orient3d(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3], d: &[f64; 3]) -> i32 {
    let (bx, by, bz) = (b[0] - a[0], b[1] - a[1], b[2] - a[2]);
    let (cx, cy, cz) = (c[0] - a[0], c[1] - a[1], c[2] - a[2]);
    let (dx, dy, dz) = (d[0] - a[0], d[1] - a[1], d[2] - a[2]);
    let det = bz * (cx * dy - dx * cy) + cz * (dx * by - bx * dy) + dz * (bx * cy - cx * by);
    // Semi-static filter: Shewchuk's bound (7 + 56ε)ε · permanent with the
    // permanent bounded by 6 mx my mz (ε = 2^-53), rounded up.
    let mx = bx.abs().max(cx.abs()).max(dx.abs());
    let my = by.abs().max(cy.abs()).max(dy.abs());
    let mz = bz.abs().max(cz.abs()).max(dz.abs());
    let eps = 5.2e-15 * (mx * my * mz);
    if mx == 0.0 || my == 0.0 || mz == 0.0 {
        return 0; // the four points share a coordinate plane
    }
    if mx.min(my).min(mz) > 1e-90 && mx.max(my).max(mz) < 1e90 {
        if det > eps {
            return 1;
        }
        if det < -eps {
            return -1;
        }
    }
    orient3d_exact(a, b, c, d)
}

#[cold]
#[inline(never)]
fn orient3d_exact(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3], d: &[f64; 3]) -> i32 {
    if let Some(s) = exact::orient3d(a, b, c, d) {
        return s;
    }
    // Shewchuk's orient3d is det[a − d, b − d, c − d] = −det[b − a, c − a, d − a].
    -sign(robust::orient3d(c3(a), c3(b), c3(c), c3(d)))
}

/// Exact in-sphere test: `+1` when `e` lies strictly inside the sphere
/// through `a, b, c, d`, `−1` strictly outside, `0` on it, provided
/// `(a, b, c, d)` is positively oriented (the sign flips otherwise).
#[inline]
pub fn insphere(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3], d: &[f64; 3], e: &[f64; 3]) -> i32 {
    match insphere_filter(a, b, c, d, e) {
        Some(s) => s,
        None => insphere_exact(a, b, c, d, e),
    }
}

/// The floating-point stage of [`insphere`]: its sign when certain.
#[inline(always)]
fn insphere_filter(
    a: &[f64; 3],
    b: &[f64; 3],
    c: &[f64; 3],
    d: &[f64; 3],
    e: &[f64; 3],
) -> Option<i32> {
    let (ax, ay, az) = (a[0] - e[0], a[1] - e[1], a[2] - e[2]);
    let (bx, by, bz) = (b[0] - e[0], b[1] - e[1], b[2] - e[2]);
    let (cx, cy, cz) = (c[0] - e[0], c[1] - e[1], c[2] - e[2]);
    let (dx, dy, dz) = (d[0] - e[0], d[1] - e[1], d[2] - e[2]);
    let ab = ax * by - bx * ay;
    let bc = bx * cy - cx * by;
    let cd = cx * dy - dx * cy;
    let da = dx * ay - ax * dy;
    let ac = ax * cy - cx * ay;
    let bd = bx * dy - dx * by;
    let abc = az * bc - bz * ac + cz * ab;
    let bcd = bz * cd - cz * bd + dz * bc;
    let cda = cz * da + dz * ac + az * cd;
    let dab = dz * ab + az * bd + bz * da;
    let alift = ax * ax + ay * ay + az * az;
    let blift = bx * bx + by * by + bz * bz;
    let clift = cx * cx + cy * cy + cz * cz;
    let dlift = dx * dx + dy * dy + dz * dz;
    // Shewchuk's determinant, positive inside for *his* orientation,
    // which is ours negated.
    let det = (dlift * abc - clift * dab) + (blift * cda - alift * bcd);
    // Semi-static filter: (16 + 224ε)ε · permanent, the permanent bounded
    // by 72 M² mx my mz with M = max(mx, my, mz), rounded up.
    let mx = ax.abs().max(bx.abs()).max(cx.abs()).max(dx.abs());
    let my = ay.abs().max(by.abs()).max(cy.abs()).max(dy.abs());
    let mz = az.abs().max(bz.abs()).max(cz.abs()).max(dz.abs());
    let big = mx.max(my).max(mz);
    let eps = 1.3e-13 * (mx * my * mz) * (big * big);
    if mx.min(my).min(mz) > 1e-55 && big < 1e55 {
        if det > eps {
            return Some(-1);
        }
        if det < -eps {
            return Some(1);
        }
    }
    None
}

#[cold]
#[inline(never)]
fn insphere_exact(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3], d: &[f64; 3], e: &[f64; 3]) -> i32 {
    if let Some(s) = exact::insphere_det(a, b, c, d, e) {
        return -s;
    }
    -sign(robust::insphere(c3(a), c3(b), c3(c), c3(d), c3(e)))
}

/// Exact orientation of three points in the `(i, j)` coordinate plane.
#[inline]
fn orient2d_proj(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3], i: usize, j: usize) -> i32 {
    let pa = robust::Coord { x: a[i], y: a[j] };
    let pb = robust::Coord { x: b[i], y: b[j] };
    let pc = robust::Coord { x: c[i], y: c[j] };
    sign(robust::orient2d(pa, pb, pc))
}

/// Whether three points are exactly collinear (or coincident).
pub fn collinear(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3]) -> bool {
    orient2d_proj(a, b, c, 0, 1) == 0
        && orient2d_proj(a, b, c, 1, 2) == 0
        && orient2d_proj(a, b, c, 2, 0) == 0
}

/// The coordinate plane `(i, j)` onto which the non-collinear triangle
/// `a, b, c` projects without degenerating, and its orientation there.
fn projection_plane(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3]) -> (usize, usize, i32) {
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        let o = orient2d_proj(a, b, c, i, j);
        if o != 0 {
            return (i, j, o);
        }
    }
    (0, 1, 0)
}

/// In-sphere test with symbolic perturbation, for point indices: `true`
/// when point `e` is in conflict with (strictly inside the perturbed
/// circumsphere of) the positively oriented tetrahedron `t`. Never ties.
/// `pts` holds the coordinates, `rank` the perturbation rank of each point
/// (distinct; the point of largest rank is the most perturbed).
///
/// `ints`, when not empty, holds the same points as exact integers (see
/// [`exact`]), a faster exact stage than the adaptive expansions.
#[inline]
pub(super) fn insphere_sos(
    pts: &[[f64; 3]],
    ints: &[[i64; 3]],
    rank: &[u32],
    t: [u32; 4],
    e: u32,
) -> bool {
    let p = |i: u32| &pts[i as usize];
    let s = match insphere_filter(p(t[0]), p(t[1]), p(t[2]), p(t[3]), p(e)) {
        Some(s) => s,
        None => insphere_exact_ids(pts, ints, t, e),
    };
    if s != 0 {
        return s > 0;
    }
    insphere_tie(pts, ints, rank, t, e)
}

/// Exact stage of [`insphere_sos`].
#[cold]
#[inline(never)]
fn insphere_exact_ids(pts: &[[f64; 3]], ints: &[[i64; 3]], t: [u32; 4], e: u32) -> i32 {
    if ints.is_empty() {
        let p = |i: u32| &pts[i as usize];
        insphere_exact(p(t[0]), p(t[1]), p(t[2]), p(t[3]), p(e))
    } else {
        let q = |i: u32| ints[i as usize];
        -exact::insphere_det_int(q(t[0]), q(t[1]), q(t[2]), q(t[3]), q(e))
    }
}

/// Symbolic perturbation of a cospherical in-sphere test.
#[cold]
#[inline(never)]
fn insphere_tie(pts: &[[f64; 3]], ints: &[[i64; 3]], rank: &[u32], t: [u32; 4], e: u32) -> bool {
    let p = |i: u32| &pts[i as usize];
    // Cospherical: the leading terms of the perturbed determinant decide,
    // from the most perturbed point (largest rank) down (Devillers and
    // Teillaud 2011, §3.1; two terms suffice for a non-flat tetrahedron).
    let ids = [t[0], t[1], t[2], t[3], e];
    let by_rank = |skip: u32| {
        ids.iter()
            .copied()
            .filter(|&i| i != skip)
            .max_by_key(|&i| rank[i as usize])
            .unwrap_or(e)
    };
    let first = by_rank(u32::MAX);
    for top in [first, by_rank(first)] {
        if top == e {
            return false;
        }
        // Orientation of `t` with the top vertex replaced by `e`.
        let mut q = t;
        for v in q.iter_mut() {
            if *v == top {
                *v = e;
            }
        }
        let o = if ints.is_empty() {
            orient3d(p(q[0]), p(q[1]), p(q[2]), p(q[3]))
        } else {
            let r = |i: u32| ints[i as usize];
            exact::orient3d_int(r(q[0]), r(q[1]), r(q[2]), r(q[3]))
        };
        if o != 0 {
            return o > 0;
        }
    }
    false
}

/// Conflict test of point `e` against the infinite tetrahedron over the
/// hull facet `f` (positively oriented towards the outside: a point beyond
/// the hull has positive orientation with it). Coplanar points are decided
/// by the perturbed in-circle test within the facet's plane, which is the
/// restriction of [`insphere_sos`] to that plane, so both tests agree.
pub(super) fn hull_conflict_sos(pts: &[[f64; 3]], rank: &[u32], f: [u32; 3], e: u32) -> bool {
    let p = |i: u32| &pts[i as usize];
    let (a, b, c, q) = (p(f[0]), p(f[1]), p(f[2]), p(e));
    let o = orient3d(a, b, c, q);
    if o != 0 {
        return o > 0;
    }
    let (i, j, local) = projection_plane(a, b, c);
    if local == 0 {
        return false; // flat facet: cannot happen in a valid tessellation
    }
    // In-circle within the plane: the sphere through a, b, c and any point
    // off the plane cuts the plane in the circumcircle of a, b, c.
    let k = 3 - i - j;
    let mut off = *a;
    off[k] += a[k].abs().max(1.0);
    let side = orient3d(a, b, c, &off);
    let s = insphere(a, b, c, &off, q) * side;
    if s != 0 {
        return s > 0;
    }
    let mut ids = [f[0], f[1], f[2], e];
    ids.sort_unstable_by_key(|&i| std::cmp::Reverse(rank[i as usize]));
    for &top in &ids[..3] {
        if top == e {
            return false;
        }
        let mut r = f;
        for v in r.iter_mut() {
            if *v == top {
                *v = e;
            }
        }
        let o = orient2d_proj(p(r[0]), p(r[1]), p(r[2]), i, j);
        if o != 0 {
            return o * local > 0;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conventions_match_simplex_measure() {
        let a = [0.0, 0.0, 0.0];
        let b = [1.0, 0.0, 0.0];
        let c = [0.0, 1.0, 0.0];
        let d = [0.0, 0.0, 1.0];
        let pts = [a, b, c, d].map(pfem_core::Point::<3>::from);
        assert!(pfem_core::simplex_measure::<3>(&pts) > 0.0);
        assert_eq!(orient3d(&a, &b, &c, &d), 1);
        assert_eq!(orient3d(&b, &a, &c, &d), -1);
        assert_eq!(orient3d(&a, &b, &c, &[1.0, 1.0, 0.0]), 0);
        assert_eq!(insphere(&a, &b, &c, &d, &[0.25, 0.25, 0.25]), 1);
        assert_eq!(insphere(&a, &b, &c, &d, &[2.0, 2.0, 2.0]), -1);
        assert_eq!(insphere(&a, &b, &c, &d, &[1.0, 1.0, 1.0]), 0);
    }

    #[test]
    fn filtered_predicates_agree_with_adaptive_expansions() {
        let mut s = 5u64;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let sg = |x: f64| (x > 0.0) as i32 - (x < 0.0) as i32;
        for round in 0..3000 {
            // Plain random, near-degenerate (a tiny offset from a lattice,
            // cospherical), and lattice points far from the origin.
            let mut p: [[f64; 3]; 5] = std::array::from_fn(|_| [next(), next(), next()]);
            if round % 3 == 1 {
                for q in &mut p {
                    for x in q.iter_mut() {
                        *x = (*x * 3.0).floor() * 0.1 + (next() - 0.5) * 1e-17;
                    }
                }
            } else if round % 3 == 2 {
                for q in &mut p {
                    for x in q.iter_mut() {
                        *x = 1e6 + (*x * 3.0).floor() * 0.25;
                    }
                }
            }
            let o = orient3d(&p[0], &p[1], &p[2], &p[3]);
            let r = -sg(robust::orient3d(c3(&p[0]), c3(&p[1]), c3(&p[2]), c3(&p[3])));
            assert_eq!(o, r, "{p:?}");
            let i = insphere(&p[0], &p[1], &p[2], &p[3], &p[4]);
            let r = -sg(robust::insphere(
                c3(&p[0]),
                c3(&p[1]),
                c3(&p[2]),
                c3(&p[3]),
                c3(&p[4]),
            ));
            assert_eq!(i, r, "{p:?}");
        }
    }
}
