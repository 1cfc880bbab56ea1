//! Spatially coherent insertion order: a biased randomised insertion order
//! (BRIO, Amenta, Choi and Rote 2003) whose rounds are sorted along a 3D
//! Hilbert curve (Skilling 2004), so that consecutive points are close and
//! the point-location walk stays short.

/// Bits per axis of the Hilbert grid.
const BITS: u32 = 12;

/// SplitMix64: a small, fast, deterministic generator.
#[derive(Debug, Clone)]
pub(super) struct SplitMix(pub u64);

impl SplitMix {
    #[inline]
    pub(super) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// Hilbert index of the grid cell `x` (each coordinate below `2^BITS`),
/// by Skilling's transpose algorithm.
fn hilbert_index(mut x: [u32; 3]) -> u64 {
    let m = 1u32 << (BITS - 1);
    // Inverse undo.
    let mut q = m;
    while q > 1 {
        let p = q - 1;
        for i in 0..3 {
            if x[i] & q != 0 {
                x[0] ^= p;
            } else {
                let t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    // Gray encode.
    x[1] ^= x[0];
    x[2] ^= x[1];
    let mut t = 0;
    let mut q = m;
    while q > 1 {
        if x[2] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    for xi in &mut x {
        *xi ^= t;
    }
    // Interleave the transposed bits, most significant first.
    let mut h = 0u64;
    for b in (0..BITS).rev() {
        for xi in &x {
            h = (h << 1) | u64::from((xi >> b) & 1);
        }
    }
    h
}

/// Writes into `order` a BRIO of `0..pts.len()`: a random permutation cut
/// into rounds of doubling size (the last round holds half the points),
/// each round sorted along a Hilbert curve. `keys` is scratch.
pub(super) fn brio(pts: &[[f64; 3]], order: &mut Vec<u32>, keys: &mut Vec<u64>, seed: u64) {
    let n = pts.len();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in pts {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let cells = ((1u32 << BITS) - 1) as f64;
    let scale: [f64; 3] = std::array::from_fn(|k| {
        let w = hi[k] - lo[k];
        if w > 0.0 && w.is_finite() {
            cells / w
        } else {
            0.0
        }
    });
    keys.clear();
    keys.extend(pts.iter().map(|p| {
        let cell: [u32; 3] = std::array::from_fn(|k| {
            // `as` saturates, and NaN (impossible here) maps to 0.
            (((p[k] - lo[k]) * scale[k]) as u32).min((1u32 << BITS) - 1)
        });
        hilbert_index(cell)
    }));
    order.clear();
    order.extend(0..n as u32);
    let mut rng = SplitMix(seed);
    for i in (1..n).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        order.swap(i, j);
    }
    let mut end = n;
    while end > 0 {
        let start = if end > 64 { end / 2 } else { 0 };
        order[start..end].sort_unstable_by_key(|&i| keys[i as usize]);
        end = start;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hilbert_is_a_bijection_on_a_small_grid_with_unit_steps() {
        // On the full grid, consecutive Hilbert indices are face neighbours.
        // Check on the 4x4x4 corner block shifted to the top bits.
        let shift = BITS - 2;
        let mut cells: Vec<(u64, [u32; 3])> = Vec::new();
        for x in 0..4u32 {
            for y in 0..4u32 {
                for z in 0..4u32 {
                    let c = [x << shift, y << shift, z << shift];
                    cells.push((hilbert_index(c), [x, y, z]));
                }
            }
        }
        cells.sort_unstable();
        cells.dedup_by_key(|c| c.0);
        assert_eq!(cells.len(), 64);
        for w in cells.windows(2) {
            let d: u32 = (0..3).map(|k| w[0].1[k].abs_diff(w[1].1[k])).sum();
            assert_eq!(d, 1, "{:?} -> {:?}", w[0], w[1]);
        }
    }

    #[test]
    fn brio_is_a_permutation() {
        let pts: Vec<[f64; 3]> = (0..1000)
            .map(|i| [i as f64, (i * 7 % 13) as f64, 0.5])
            .collect();
        let (mut order, mut keys) = (Vec::new(), Vec::new());
        brio(&pts, &mut order, &mut keys, 1);
        let mut s = order.clone();
        s.sort_unstable();
        assert!(s.iter().enumerate().all(|(i, &v)| v as usize == i));
    }
}
