//! Remeshing only where the fluid can reach: the wall particles far from
//! every fluid and solid particle take no part in any element, so the
//! tessellation may leave them out (issue 18: the column on a cylinder at
//! a/20 spent 16 % of its run tessellating 22 000 wall particles, most of
//! them far from the water).
//!
//! Why leaving them out changes no element: every simplex the alpha shape
//! keeps (or counts as a sliver, a wall pocket or a contact element) has a
//! fluid or solid node and its other nodes within a few spacings of it
//! (`R ≤ α h` for an element, edges `≤ 2 α h` for a sliver, `2.2 α h` for a
//! wall pocket, [`crate::contact_elements`]' reach for contact). A simplex
//! of the Delaunay tessellation of the subset that is not one of the whole
//! set has a left-out point inside its circumsphere; if that simplex is
//! small enough to be kept, the point is within `2 α h` of one of its
//! non-wall nodes, and so it was not left out. `Delaunay3`'s exact
//! predicates and symbolic perturbation (ranked by input index:
//! [`tessellate_subset`] keeps the subset in index order) decide the same
//! way on the points they share, so only simplices the alpha shape drops
//! can differ. `Delaunay2` (spade) does not: it splits a cocircular square
//! by insertion order, so on a lattice the subset's diagonals may differ
//! from the whole set's. That is why the driver uses the subset in 3D only.
//! The order of the simplices differs, so a run with and without it agrees
//! to round-off, not bit for bit.
//!
//! One gap in that argument: slivers (and contact elements) are bounded by
//! their edges, not their circumradius, and a flat simplex's circumsphere
//! can be huge, so a sliver that holds a left-out point in its
//! circumsphere could exist in the subset's tessellation alone. Checked
//! step by step against the whole set on the 3D examples
//! (`docs/benchmarks.md`, session 23), the slivers never differed.
//!
//! The driver falls back to the whole set when the subset cannot be
//! tessellated (fewer than four points off one plane).

use pfem_core::{Const, Dim, ParticleKind, Point};

use crate::{GeometryError, Tessellation, Tessellator};

/// Largest number of grid cells [`near_matter`] uses per particle before it
/// coarsens its grid (a scene with one drop flying far from the rest).
const CELLS_PER_PARTICLE: usize = 8;

/// Writes into `out`, in increasing order, the particles a remeshing
/// needs: every particle that is not a wall, and every wall particle within
/// `reach` (m) of one. Returns `false`, with `out` empty, when that is every
/// particle (tessellate them all), when there is no fluid or solid
/// particle, or when a coordinate is not finite (the tessellator reports
/// it).
///
/// A uniform grid of cells at least `reach` wide: a wall particle is kept
/// when a non-wall particle lies in its cell or in one next to it, so every
/// wall particle within `reach` is kept, and some up to `2 √D` cells away
/// (a cell is `reach` wide unless the grid had to be coarsened to stay
/// within `CELLS_PER_PARTICLE` cells a particle: a drop far from the
/// rest). `O(N)` time and `O(N)` memory at most.
pub fn near_matter<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    reach: f64,
    out: &mut Vec<u32>,
) -> bool
where
    Const<D>: Dim,
{
    out.clear();
    let n = points.len().min(kinds.len());
    if !(reach.is_finite() && reach > 0.0) || n > u32::MAX as usize {
        return false;
    }
    let matter = |i: usize| kinds[i] != ParticleKind::Wall;
    let mut lo = [f64::INFINITY; D];
    let mut hi = [f64::NEG_INFINITY; D];
    let mut walls = 0usize;
    for (i, p) in points[..n].iter().enumerate() {
        if !p.iter().all(|x| x.is_finite()) {
            return false;
        }
        if matter(i) {
            for k in 0..D {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        } else {
            walls += 1;
        }
    }
    if walls == 0 || walls == n {
        return false;
    }
    // One cell of margin on each side: the wall particles next to the
    // matter's box. Counted in floating point, so that no extent
    // overflows an integer.
    if !(0..D).all(|k| (hi[k] - lo[k]).is_finite()) {
        return false;
    }
    let mut cell = reach;
    let dims =
        |cell: f64| -> [f64; D] { std::array::from_fn(|k| ((hi[k] - lo[k]) / cell).floor() + 3.0) };
    let cap = (CELLS_PER_PARTICLE * n + 1024) as f64;
    while dims(cell).iter().product::<f64>() > cap {
        cell *= 2.0;
    }
    let dim: [usize; D] = dims(cell).map(|d| d as usize);
    let origin: [f64; D] = std::array::from_fn(|k| lo[k] - cell);
    let index = |p: &Point<D>| -> Option<usize> {
        let mut at = 0usize;
        for k in (0..D).rev() {
            let c = ((p[k] - origin[k]) / cell).floor();
            if !(c >= 0.0 && c < dim[k] as f64) {
                return None;
            }
            at = at * dim[k] + c as usize;
        }
        Some(at)
    };
    let total = dim.iter().product::<usize>();
    let mut near = vec![false; total];
    for (i, p) in points[..n].iter().enumerate() {
        if matter(i) {
            if let Some(c) = index(p) {
                near[c] = true;
            }
        }
    }
    // Dilate by one cell along each axis in turn: the 3^D block.
    let mut stride = 1usize;
    let mut next = vec![false; total];
    for &len in dim.iter() {
        for (c, v) in next.iter_mut().enumerate() {
            let at = (c / stride) % len;
            *v = near[c] || (at > 0 && near[c - stride]) || (at + 1 < len && near[c + stride]);
        }
        std::mem::swap(&mut near, &mut next);
        stride *= len;
    }
    let mut dropped = false;
    for (i, p) in points[..n].iter().enumerate() {
        if matter(i) || index(p).is_some_and(|c| near[c]) {
            out.push(i as u32);
        } else {
            dropped = true;
        }
    }
    if !dropped {
        out.clear();
    }
    dropped
}

/// Tessellates the particles `subset` (indices into `points`, increasing)
/// with `tessellator`: the vertices of `out` are particle indices, as if
/// the whole set had been tessellated, and a particle outside `subset` is
/// in no simplex. `scratch` holds the subset's coordinates between calls.
/// Errors name particle indices too.
pub fn tessellate_subset<const D: usize>(
    tessellator: &mut dyn Tessellator<D>,
    points: &[Point<D>],
    subset: &[u32],
    scratch: &mut Vec<Point<D>>,
    out: &mut Tessellation,
) -> Result<(), GeometryError>
where
    Const<D>: Dim,
{
    if subset.windows(2).any(|w| w[0] >= w[1])
        || subset.last().is_some_and(|&i| i as usize >= points.len())
    {
        return Err(GeometryError::InvalidConnectivity {
            reason: "the subset to tessellate is not increasing particle indices",
        });
    }
    scratch.clear();
    scratch.extend(subset.iter().map(|&i| points[i as usize]));
    let particle = |i: usize| subset.get(i).map_or(i, |&p| p as usize);
    tessellator.tessellate(scratch, out).map_err(|e| match e {
        GeometryError::NonFinite { index } => GeometryError::NonFinite {
            index: particle(index),
        },
        GeometryError::NearCoincident {
            first,
            second,
            distance,
            tolerance,
        } => GeometryError::NearCoincident {
            first: particle(first),
            second: particle(second),
            distance,
            tolerance,
        },
        GeometryError::OutOfRange { index, value } => GeometryError::OutOfRange {
            index: particle(index),
            value,
        },
        GeometryError::InvalidSpacing { index, value } => GeometryError::InvalidSpacing {
            index: particle(index),
            value,
        },
        other => other,
    })?;
    // A tessellator of one's own that names a point it was not given is
    // refused as the whole set's check would (`check_tessellation`).
    if out.simplices.iter().any(|&v| v as usize >= subset.len()) {
        return Err(GeometryError::InvalidConnectivity {
            reason: "a simplex names a vertex index out of range",
        });
    }
    for v in out.simplices.iter_mut() {
        *v = subset[*v as usize];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Delaunay2, Delaunay3};
    use pfem_core::Point;

    /// A box of wall particles (spacing `h`) with fluid in one corner.
    fn tank3(h: f64) -> (Vec<Point<3>>, Vec<ParticleKind>) {
        let (mut x, mut k) = (Vec::new(), Vec::new());
        let n = 16;
        for i in 0..=n {
            for j in 0..=n {
                for l in 0..=n {
                    let on_wall = i == 0 || j == 0 || l == 0 || i == n || j == n;
                    let fluid = (1..5).contains(&i) && (1..5).contains(&j) && (1..7).contains(&l);
                    if on_wall || fluid {
                        // A little jitter off the lattice for the fluid.
                        let s = if fluid {
                            1e-3 * ((i * 7 + j * 3 + l * 5) % 11) as f64
                        } else {
                            0.0
                        };
                        x.push(Point::<3>::new(
                            i as f64 * h + s * h,
                            j as f64 * h - s * h,
                            l as f64 * h + 0.5 * s * h,
                        ));
                        k.push(if fluid {
                            ParticleKind::Fluid
                        } else {
                            ParticleKind::Wall
                        });
                    }
                }
            }
        }
        (x, k)
    }

    fn sorted_simplices(t: &Tessellation) -> Vec<Vec<u32>> {
        let mut out: Vec<Vec<u32>> = t
            .simplices
            .chunks(t.nv)
            .map(|s| {
                let mut v = s.to_vec();
                v.sort_unstable();
                v
            })
            .collect();
        out.sort();
        out
    }

    #[test]
    fn the_far_walls_are_left_out_and_the_near_ones_kept() {
        let h = 0.1;
        let (x, k) = tank3(h);
        let mut sub = Vec::new();
        assert!(near_matter(&x, &k, 3.0 * h, &mut sub));
        assert!(sub.windows(2).all(|w| w[0] < w[1]));
        for (i, p) in x.iter().enumerate() {
            let d = x
                .iter()
                .zip(&k)
                .filter(|(_, &kind)| kind != ParticleKind::Wall)
                .map(|(q, _)| (p - q).norm())
                .fold(f64::INFINITY, f64::min);
            let kept = sub.binary_search(&(i as u32)).is_ok();
            if d <= 3.0 * h {
                assert!(kept, "particle {i} at {d} from the fluid is left out");
            }
            if d > 2.0 * 3f64.sqrt() * 3.0 * h + 1e-9 {
                assert!(!kept, "particle {i} at {d} from the fluid is kept");
            }
        }
        assert!(sub.len() < x.len() / 2, "{} of {}", sub.len(), x.len());
    }

    #[test]
    fn nothing_is_left_out_without_walls_or_without_matter() {
        let (x, k) = tank3(0.1);
        let mut sub = vec![7];
        let fluid = vec![ParticleKind::Fluid; x.len()];
        assert!(!near_matter(&x, &fluid, 0.3, &mut sub));
        assert!(sub.is_empty());
        let walls = vec![ParticleKind::Wall; x.len()];
        assert!(!near_matter(&x, &walls, 0.3, &mut sub));
        assert!(!near_matter(&x, &k, f64::NAN, &mut sub));
        let mut bad = x.clone();
        bad[3].x = f64::NAN;
        assert!(!near_matter(&bad, &k, 0.3, &mut sub));
    }

    #[test]
    fn huge_extents_neither_overflow_nor_leave_a_near_wall_out() {
        let (mut x, mut k) = tank3(0.1);
        let mut sub = Vec::new();
        for far in [1e300, 1.7e308] {
            let (mut x2, mut k2) = (x.clone(), k.clone());
            x2.push(Point::<3>::new(-far, 0.0, far));
            k2.push(ParticleKind::Fluid);
            x2.push(Point::<3>::new(far, far, -far));
            k2.push(ParticleKind::Fluid);
            // Either everything (an infinite extent) or a coarse grid that
            // keeps every wall within reach of the tank's fluid.
            if near_matter(&x2, &k2, 0.3, &mut sub) {
                let mut fine = Vec::new();
                assert!(near_matter(&x, &k, 0.3, &mut fine));
                assert!(fine.iter().all(|i| sub.binary_search(i).is_ok()));
            } else {
                assert!(sub.is_empty());
            }
        }
        x.truncate(1);
        k.truncate(1);
        assert!(!near_matter(&x, &k, 0.3, &mut sub));
    }

    #[test]
    fn a_far_drop_coarsens_the_grid_but_keeps_every_near_wall() {
        let (mut x, mut k) = tank3(0.1);
        x.push(Point::<3>::new(1e6, 1e6, 1e6));
        k.push(ParticleKind::Fluid);
        let mut sub = Vec::new();
        let some_left_out = near_matter(&x, &k, 0.3, &mut sub);
        // The grid is coarse now, so most walls are kept (here all: the
        // answer is "tessellate every particle"); every wall within reach
        // of the corner's fluid still is.
        let mut fine = Vec::new();
        assert!(near_matter(
            &x[..x.len() - 1],
            &k[..k.len() - 1],
            0.3,
            &mut fine
        ));
        assert!(!some_left_out || fine.iter().all(|i| sub.binary_search(i).is_ok()));
        assert!(sub.is_empty() != some_left_out);
    }

    /// Tessellates `x` whole and without its far walls (reach `3 α h`,
    /// `α = 1.3`) and checks that the simplices with a fluid node and
    /// every edge within `2 α h` (all the alpha shape could keep or count
    /// as slivers) are the same; returns how many there are. The large
    /// simplices across the empty tank differ, as they may.
    fn same_near_the_fluid<const D: usize>(
        mut tessellator: impl Tessellator<D>,
        x: &[Point<D>],
        k: &[ParticleKind],
        h: f64,
    ) -> usize
    where
        Const<D>: Dim,
    {
        let near_fluid = |t: &Tessellation| -> Vec<Vec<u32>> {
            sorted_simplices(t)
                .into_iter()
                .filter(|s| s.iter().any(|&v| k[v as usize] == ParticleKind::Fluid))
                .filter(|s| {
                    s.iter().all(|&a| {
                        s.iter()
                            .all(|&b| (x[a as usize] - x[b as usize]).norm() <= 2.0 * 1.3 * h)
                    })
                })
                .collect()
        };
        let mut whole = Tessellation::default();
        tessellator.tessellate(x, &mut whole).unwrap();
        let mut sub = Vec::new();
        assert!(near_matter(x, k, 3.0 * 1.3 * h, &mut sub));
        let (mut part, mut scratch) = (Tessellation::default(), Vec::new());
        tessellate_subset(&mut tessellator, x, &sub, &mut scratch, &mut part).unwrap();
        assert!(part.len() < whole.len());
        let near = near_fluid(&whole);
        assert_eq!(near_fluid(&part), near);
        near.len()
    }

    /// The simplices near the fluid are those of the whole set, in 3D (own
    /// Bowyer–Watson, symbolic perturbation, lattice walls full of
    /// cospherical ties) and 2D.
    #[test]
    fn the_simplices_near_the_fluid_are_those_of_the_whole_set() {
        let h = 0.1;
        let (x, k) = tank3(h);
        let n3 = same_near_the_fluid(Delaunay3::default(), &x, &k, h);
        assert!(n3 > 500, "{n3}");

        // 2D: a square tank's walls, fluid in a corner.
        let (mut x2, mut k2) = (Vec::new(), Vec::new());
        let n = 40;
        for i in 0..=n {
            for j in 0..=n {
                let wall = i == 0 || j == 0 || i == n;
                let fluid = (1..8).contains(&i) && (1..10).contains(&j);
                if wall || fluid {
                    let s = if fluid {
                        1e-2 * ((i * 3 + j) % 7) as f64
                    } else {
                        0.0
                    };
                    x2.push(Point::<2>::new((i as f64 + s) * h, (j as f64 - s) * h));
                    k2.push(if fluid {
                        ParticleKind::Fluid
                    } else {
                        ParticleKind::Wall
                    });
                }
            }
        }
        let n2 = same_near_the_fluid(Delaunay2::default(), &x2, &k2, h);
        assert!(n2 > 100, "{n2}");
    }

    #[test]
    fn errors_name_particles_and_a_bad_subset_is_refused() {
        let (mut x, _) = tank3(0.1);
        let subset: Vec<u32> = (10..x.len() as u32).step_by(2).collect();
        x[subset[5] as usize] = x[subset[4] as usize];
        let (mut out, mut scratch) = (Tessellation::default(), Vec::new());
        let e = tessellate_subset(
            &mut Delaunay3::default(),
            &x,
            &subset,
            &mut scratch,
            &mut out,
        )
        .unwrap_err();
        match e {
            GeometryError::NearCoincident { first, second, .. } => {
                let mut pair = [first, second];
                pair.sort_unstable();
                assert_eq!(pair, [subset[4] as usize, subset[5] as usize]);
            }
            other => panic!("unexpected {other:?}"),
        }
        let e = tessellate_subset(
            &mut Delaunay3::default(),
            &x,
            &[3, 2],
            &mut scratch,
            &mut out,
        )
        .unwrap_err();
        assert!(matches!(e, GeometryError::InvalidConnectivity { .. }));
        // A tessellator of one's own naming a vertex past the subset
        // (session 44's review: an index out of bounds panic).
        #[derive(Debug, Default)]
        struct OffByOne(Delaunay3);
        impl Tessellator<3> for OffByOne {
            fn tessellate(
                &mut self,
                points: &[Point<3>],
                out: &mut Tessellation,
            ) -> Result<(), GeometryError> {
                self.0.tessellate(points, out)?;
                out.simplices[0] = points.len() as u32;
                Ok(())
            }
        }
        let subset: Vec<u32> = (0..x.len() as u32).step_by(3).collect();
        let e = tessellate_subset(
            &mut OffByOne::default(),
            &x,
            &subset,
            &mut scratch,
            &mut out,
        )
        .unwrap_err();
        assert!(
            matches!(e, GeometryError::InvalidConnectivity { .. }),
            "{e:?}"
        );
    }
}
