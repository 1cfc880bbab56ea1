//! Exact integer evaluation of the `orient3d` and `insphere` determinants,
//! the fast exact stage for the degenerate (zero or nearly zero) cases that
//! PFEM's lattices produce by the thousand.
//!
//! When the coordinates of the points of a predicate are all integer
//! multiples of one power of two spanning at most 60 bits, they become
//! `i64`, and the determinants are evaluated in 384-bit two's-complement
//! arithmetic, which holds them with room to spare (|insphere| < 2^312).
//! Otherwise the caller falls back to Shewchuk's adaptive expansions.

/// A 384-bit two's-complement integer with wrapping arithmetic: exact for
/// values below 2^383 in magnitude.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct I384([u64; 6]);

impl I384 {
    #[inline]
    fn from_i128(v: i128) -> Self {
        let ext = if v < 0 { u64::MAX } else { 0 };
        I384([v as u64, (v >> 64) as u64, ext, ext, ext, ext])
    }

    #[inline]
    fn add(self, o: Self) -> Self {
        let mut r = [0u64; 6];
        let mut carry = false;
        for i in 0..6 {
            let (s1, c1) = self.0[i].overflowing_add(o.0[i]);
            let (s2, c2) = s1.overflowing_add(carry as u64);
            r[i] = s2;
            carry = c1 || c2;
        }
        I384(r)
    }

    #[inline]
    fn neg(self) -> Self {
        let mut r = self.0.map(|x| !x);
        for x in &mut r {
            let (s, c) = x.overflowing_add(1);
            *x = s;
            if !c {
                break;
            }
        }
        I384(r)
    }

    #[inline]
    fn sub(self, o: Self) -> Self {
        self.add(o.neg())
    }

    /// Product modulo 2^384 (exact when the true product fits).
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut r = [0u64; 6];
        for i in 0..6 {
            if self.0[i] == 0 {
                continue;
            }
            let mut carry = 0u128;
            for j in 0..6 - i {
                let t = u128::from(r[i + j]) + u128::from(self.0[i]) * u128::from(o.0[j]) + carry;
                r[i + j] = t as u64;
                carry = t >> 64;
            }
        }
        I384(r)
    }

    #[inline]
    fn signum(self) -> i32 {
        if self.0.iter().all(|&x| x == 0) {
            0
        } else if self.0[5] >> 63 == 1 {
            -1
        } else {
            1
        }
    }
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

#[inline]
fn det3(a: [i64; 3], b: [i64; 3], c: [i64; 3]) -> I384 {
    let m = |x: i64, y: i64, z: i64, w: i64| {
        i128::from(x) * i128::from(y) - i128::from(z) * i128::from(w)
    };
    let m0 = I384::from_i128(m(b[1], c[2], b[2], c[1]));
    let m1 = I384::from_i128(m(b[0], c[2], b[2], c[0]));
    let m2 = I384::from_i128(m(b[0], c[1], b[1], c[0]));
    let a0 = I384::from_i128(a[0].into());
    let a1 = I384::from_i128(a[1].into());
    let a2 = I384::from_i128(a[2].into());
    a0.mul(m0).sub(a1.mul(m1)).add(a2.mul(m2))
}

#[inline]
fn diff(a: [i64; 3], b: [i64; 3]) -> [i64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Exact sign of `det[b − a, c − a, d − a]`, or `None` when the
/// coordinates span too many binary orders of magnitude.
pub(super) fn orient3d(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3], d: &[f64; 3]) -> Option<i32> {
    let [a, b, c, d] = to_integers([a, b, c, d])?;
    Some(det3(diff(b, a), diff(c, a), diff(d, a)).signum())
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
    let (a, b, c, d) = (diff(a, e), diff(b, e), diff(c, e), diff(d, e));
    let lift = |p: [i64; 3]| {
        I384::from_i128(
            p.iter()
                .map(|&x| i128::from(x) * i128::from(x))
                .sum::<i128>(),
        )
    };
    // Laplace expansion along the lifted column.
    let det = lift(d)
        .mul(det3(a, b, c))
        .sub(lift(c).mul(det3(a, b, d)))
        .add(lift(b).mul(det3(a, c, d)))
        .sub(lift(a).mul(det3(b, c, d)));
    Some(det.signum())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wide_arithmetic() {
        let x = I384::from_i128(-(1i128 << 100));
        let y = I384::from_i128(1i128 << 120);
        let p = x.mul(y).mul(y); // -2^340
        assert_eq!(p.signum(), -1);
        assert_eq!(p.add(p.neg()).signum(), 0);
        assert_eq!(p.neg().signum(), 1);
        assert_eq!(
            I384::from_i128(3).sub(I384::from_i128(5)),
            I384::from_i128(-2)
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
