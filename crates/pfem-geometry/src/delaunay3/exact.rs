//! Exact integer evaluation of the `orient3d` and `insphere` determinants,
//! the fast exact stage for the degenerate (zero or nearly zero) cases that
//! PFEM's lattices produce by the thousand.
//!
//! When the coordinates of the points of a predicate are all integer
//! multiples of one power of two spanning at most 60 bits, they become
//! `i64`, and the determinants are evaluated exactly in fixed-width integer
//! arithmetic of up to 384 bits (|insphere| < 2^313).
//! Otherwise the caller falls back to Shewchuk's adaptive expansions.

/// Schoolbook product of two magnitudes, truncated to `C` limbs (exact
/// when `C ≥ A + B` or the product fits).
#[inline(always)]
fn mul_mag<const A: usize, const B: usize, const C: usize>(a: [u64; A], b: [u64; B]) -> [u64; C] {
    let mut r = [0u64; C];
    for (i, &ai) in a.iter().enumerate() {
        if ai == 0 {
            continue;
        }
        let mut carry = 0u128;
        for (j, &bj) in b.iter().enumerate() {
            if i + j >= C {
                break;
            }
            let t = u128::from(r[i + j]) + u128::from(ai) * u128::from(bj) + carry;
            r[i + j] = t as u64;
            carry = t >> 64;
        }
        if i + B < C {
            r[i + B] = carry as u64;
        }
    }
    r
}

/// A signed magnitude, widened to `N` limbs of two's complement.
#[inline(always)]
fn twos<const M: usize, const N: usize>(neg: bool, mag: [u64; M]) -> [u64; N] {
    let mut r = [0u64; N];
    r[..M].copy_from_slice(&mag);
    if neg {
        let mut carry = true;
        for x in &mut r {
            let (s, c) = (!*x).overflowing_add(carry as u64);
            *x = s;
            carry = c;
        }
    }
    r
}

/// Wrapping sum of two's-complement numbers.
#[inline(always)]
fn add<const N: usize>(a: [u64; N], b: [u64; N]) -> [u64; N] {
    let mut r = [0u64; N];
    let mut carry = false;
    for ((ri, &x), &y) in r.iter_mut().zip(&a).zip(&b) {
        let (s1, c1) = x.overflowing_add(y);
        let (s2, c2) = s1.overflowing_add(carry as u64);
        *ri = s2;
        carry = c1 || c2;
    }
    r
}

/// Sign and magnitude of a two's-complement number.
#[inline(always)]
fn split<const N: usize>(a: [u64; N]) -> (bool, [u64; N]) {
    let neg = a[N - 1] >> 63 == 1;
    (neg, if neg { twos(true, a) } else { a })
}

#[inline(always)]
fn signum<const N: usize>(a: [u64; N]) -> i32 {
    if a.iter().all(|&x| x == 0) {
        0
    } else if a[N - 1] >> 63 == 1 {
        -1
    } else {
        1
    }
}

#[inline(always)]
fn limbs(x: u128) -> [u64; 2] {
    [x as u64, (x >> 64) as u64]
}

/// `x = m · 2^e` with `m` odd (or zero).
#[inline]
fn decompose(x: f64) -> (i64, i32) {
    let bits = x.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    let frac = (bits & ((1u64 << 52) - 1)) as i64;
    let (mut m, mut e) = if exp == 0 {
        (frac, -1074)
    } else {
        (frac | (1i64 << 52), exp - 1075)
    };
    if m == 0 {
        return (0, 0);
    }
    let tz = m.trailing_zeros();
    m >>= tz;
    e += tz as i32;
    if x < 0.0 {
        m = -m;
    }
    (m, e)
}

/// The coordinates of `N` points as integers in a common unit 2^k, if
/// they all fit in 60 bits.
#[inline]
fn to_integers<const N: usize>(p: [&[f64; 3]; N]) -> Option<[[i64; 3]; N]> {
    let mut d = [[(0i64, 0i32); 3]; N];
    let mut kmin = i32::MAX;
    for (di, pi) in d.iter_mut().zip(p) {
        for (dk, &x) in di.iter_mut().zip(pi) {
            *dk = decompose(x);
            if dk.0 != 0 {
                kmin = kmin.min(dk.1);
            }
        }
    }
    let mut out = [[0i64; 3]; N];
    for (oi, di) in out.iter_mut().zip(&d) {
        for (o, &(m, e)) in oi.iter_mut().zip(di) {
            if m == 0 {
                continue;
            }
            let shift = (e - kmin) as u32;
            let bits = 64 - m.unsigned_abs().leading_zeros();
            if bits + shift > 60 {
                return None;
            }
            *o = m << shift;
        }
    }
    Some(out)
}

/// `det[a; b; c]` for entries below 2^61 in magnitude: below 2^187, as
/// 256-bit two's complement.
#[inline]
fn det3(a: [i64; 3], b: [i64; 3], c: [i64; 3]) -> [u64; 4] {
    let m = |x: i64, y: i64, z: i64, w: i64| {
        i128::from(x) * i128::from(y) - i128::from(z) * i128::from(w)
    };
    let minors = [
        m(b[1], c[2], b[2], c[1]),
        -m(b[0], c[2], b[2], c[0]),
        m(b[0], c[1], b[1], c[0]),
    ];
    let mut det = [0u64; 4];
    for (&ai, &mi) in a.iter().zip(&minors) {
        let neg = (ai < 0) != (mi < 0);
        let p: [u64; 3] = mul_mag([ai.unsigned_abs()], limbs(mi.unsigned_abs()));
        det = add(det, twos(neg, p));
    }
    det
}

#[inline]
fn diff(a: [i64; 3], b: [i64; 3]) -> [i64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Exact sign of `det[b − a, c − a, d − a]`, or `None` when the
/// coordinates span too many binary orders of magnitude.
pub(super) fn orient3d(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3], d: &[f64; 3]) -> Option<i32> {
    let [a, b, c, d] = to_integers([a, b, c, d])?;
    Some(signum(det3(diff(b, a), diff(c, a), diff(d, a))))
}

/// Exact sign of Shewchuk's in-sphere determinant (rows `p − e`,
/// `|p − e|²` for `p = a, b, c, d`), or `None` as for [`orient3d`].
pub(super) fn insphere_det(
    a: &[f64; 3],
    b: &[f64; 3],
    c: &[f64; 3],
    d: &[f64; 3],
    e: &[f64; 3],
) -> Option<i32> {
    let [a, b, c, d, e] = to_integers([a, b, c, d, e])?;
    Some(insphere_det_int(a, b, c, d, e))
}

/// Converts all points to integers in one common unit 2^k, if every
/// coordinate then fits in 60 bits; `out` is left empty otherwise.
pub(super) fn to_integers_all(pts: &[[f64; 3]], out: &mut Vec<[i64; 3]>) {
    out.clear();
    let kmin = pts
        .iter()
        .flatten()
        .map(|&x| decompose(x))
        .filter(|d| d.0 != 0)
        .map(|d| d.1)
        .min()
        .unwrap_or(0);
    for p in pts {
        let mut q = [0i64; 3];
        for (qk, &x) in q.iter_mut().zip(p) {
            let (m, e) = decompose(x);
            if m == 0 {
                continue;
            }
            let shift = (e - kmin) as u32;
            if 64 - m.unsigned_abs().leading_zeros() + shift > 60 {
                out.clear();
                return;
            }
            *qk = m << shift;
        }
        out.push(q);
    }
}

/// Exact sign of `det[b − a, c − a, d − a]` for integer coordinates below
/// 2^60 in magnitude.
#[inline]
pub(super) fn orient3d_int(a: [i64; 3], b: [i64; 3], c: [i64; 3], d: [i64; 3]) -> i32 {
    signum(det3(diff(b, a), diff(c, a), diff(d, a)))
}

/// Exact sign of Shewchuk's in-sphere determinant for integer coordinates
/// below 2^60 in magnitude.
pub(super) fn insphere_det_int(
    a: [i64; 3],
    b: [i64; 3],
    c: [i64; 3],
    d: [i64; 3],
    e: [i64; 3],
) -> i32 {
    let (a, b, c, d) = (diff(a, e), diff(b, e), diff(c, e), diff(d, e));
    let lift = |p: [i64; 3]| {
        p.iter()
            .map(|&x| (i128::from(x) * i128::from(x)) as u128)
            .sum::<u128>()
    };
    // Laplace expansion along the lifted column; |terms| < 2^124 · 2^187.
    let terms = [
        (lift(d), det3(a, b, c), false),
        (lift(c), det3(a, b, d), true),
        (lift(b), det3(a, c, d), false),
        (lift(a), det3(b, c, d), true),
    ];
    let mut det = [0u64; 6];
    for (l, m, minus) in terms {
        let (neg, mag) = split(m);
        let mag3 = [mag[0], mag[1], mag[2]];
        let p: [u64; 5] = mul_mag(limbs(l), mag3);
        det = add(det, twos(neg != minus, p));
    }
    signum(det)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wide_arithmetic() {
        let x: [u64; 6] = twos(true, mul_mag::<2, 2, 4>(limbs(1 << 100), limbs(1 << 120)));
        assert_eq!(signum(x), -1);
        assert_eq!(
            signum(add(
                x,
                twos(false, mul_mag::<2, 2, 4>(limbs(1 << 120), limbs(1 << 100)))
            )),
            0
        );
        assert_eq!(split(x).1[3], 1 << (220 - 192));
        assert_eq!(
            add::<2>(twos(false, [3]), twos(true, [5])),
            twos::<1, 2>(true, [2])
        );
    }

    #[test]
    fn agrees_with_adaptive_expansions() {
        let mut s = 11u64;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Lattice-like values, sometimes exactly cospherical.
            ((s >> 40) % 7) as f64 * 0.01
        };
        let c3 = |p: &[f64; 3]| robust::Coord3D {
            x: p[0],
            y: p[1],
            z: p[2],
        };
        let sg = |x: f64| (x > 0.0) as i32 - (x < 0.0) as i32;
        for _ in 0..2000 {
            let p: [[f64; 3]; 5] = std::array::from_fn(|_| [next(), next(), next()]);
            let o = orient3d(&p[0], &p[1], &p[2], &p[3]).unwrap();
            assert_eq!(
                o,
                -sg(robust::orient3d(c3(&p[0]), c3(&p[1]), c3(&p[2]), c3(&p[3])))
            );
            let i = insphere_det(&p[0], &p[1], &p[2], &p[3], &p[4]).unwrap();
            let r = robust::insphere(c3(&p[0]), c3(&p[1]), c3(&p[2]), c3(&p[3]), c3(&p[4]));
            assert_eq!(i, sg(r));
        }
        assert_eq!(
            orient3d(&[1e-30, 0.0, 0.0], &[1.0; 3], &[0.5; 3], &[0.0; 3]),
            None
        );
    }
}
