//! Structured meshes for the closed-form tests (no remeshing needed).
#![allow(dead_code)]

use pfem_core::Point;

/// Nodes of an `nx × ny` cell grid on `[x0, x0+lx] × [y0, y0+ly]`, row by row,
/// and its triangles (two per cell, alternating diagonals).
pub fn grid(x0: f64, y0: f64, lx: f64, ly: f64, nx: usize, ny: usize) -> (Vec<Point<2>>, Vec<u32>) {
    let mut pts = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            pts.push(Point::<2>::new(
                x0 + lx * i as f64 / nx as f64,
                y0 + ly * j as f64 / ny as f64,
            ));
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut tris = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                tris.extend_from_slice(&[a, b, c, a, c, d]);
            } else {
                tris.extend_from_slice(&[a, b, d, b, c, d]);
            }
        }
    }
    (pts, tris)
}

/// Nodes and tetrahedra (six per cell, Kuhn subdivision) of a box grid.
pub fn grid3(l: [f64; 3], n: [usize; 3]) -> (Vec<Point<3>>, Vec<u32>) {
    let mut pts = Vec::new();
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                pts.push(Point::<3>::new(
                    l[0] * i as f64 / n[0] as f64,
                    l[1] * j as f64 / n[1] as f64,
                    l[2] * k as f64 / n[2] as f64,
                ));
            }
        }
    }
    let id = |i: usize, j: usize, k: usize| ((k * (n[1] + 1) + j) * (n[0] + 1) + i) as u32;
    let mut tets = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let c = |b: usize| id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
                // Kuhn: paths from corner 0 to corner 7 through the 6 permutations.
                for perm in [
                    [1, 2, 4],
                    [1, 4, 2],
                    [2, 1, 4],
                    [2, 4, 1],
                    [4, 1, 2],
                    [4, 2, 1],
                ] {
                    let v0 = 0usize;
                    let v1 = v0 | perm[0];
                    let v2 = v1 | perm[1];
                    let v3 = v2 | perm[2];
                    let mut t = [c(v0), c(v1), c(v2), c(v3)];
                    let p: Vec<Point<3>> = t.iter().map(|&q| pts[q as usize]).collect();
                    if pfem_core::simplex_measure::<3>(&p) < 0.0 {
                        t.swap(2, 3);
                    }
                    tets.extend_from_slice(&t);
                }
            }
        }
    }
    (pts, tets)
}

/// A small deterministic generator (SplitMix64) giving values in `[-1, 1)`.
pub struct Jitter(u64);

impl Jitter {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// Moves every node strictly inside the box `[0, l]` by up to `amount`
/// (per component, in metres), leaving boundary nodes where they are.
pub fn perturb_interior<const D: usize>(pts: &mut [Point<D>], l: [f64; D], amount: f64, seed: u64)
where
    pfem_core::Const<D>: pfem_core::Dim,
{
    let mut rng = Jitter::new(seed);
    for p in pts.iter_mut() {
        if on_box_boundary(p, l) {
            continue;
        }
        for k in 0..D {
            p[k] += amount * rng.next();
        }
    }
}

/// Whether a point lies on the boundary of the box `[0, l]`.
pub fn on_box_boundary<const D: usize>(p: &Point<D>, l: [f64; D]) -> bool
where
    pfem_core::Const<D>: pfem_core::Dim,
{
    (0..D).any(|k| p[k] < 1e-12 * l[k] || p[k] > l[k] * (1.0 - 1e-12))
}

/// Like [`grid`] but every cell is cut along the same diagonal (from its
/// lower left to its upper right corner). Unlike the alternating pattern,
/// whose cell pairs form crossed-diagonal ("union jack") macro-elements
/// that leave linear triangles room for incompressible motion, this mesh
/// locks under an element-wise incompressibility constraint.
pub fn grid_uniform_diagonal(
    x0: f64,
    y0: f64,
    lx: f64,
    ly: f64,
    nx: usize,
    ny: usize,
) -> (Vec<Point<2>>, Vec<u32>) {
    let (pts, _) = grid(x0, y0, lx, ly, nx, ny);
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut tris = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            tris.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    (pts, tris)
}
