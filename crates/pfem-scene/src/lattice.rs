//! Lattices of particles filling simple shapes, and the structured simplex
//! mesh of a box lattice (the own mesh of a solid body).

use pfem_core::{simplex_measure, Const, Dim, ParticleKind, Point, Vector};

use crate::SceneError;

/// Refuses a lattice that cannot be filled: a spacing that is not a
/// positive finite number, a bound, radius or height that is not finite
/// (or a radius or height below zero), or about `count` points that would
/// not fit [`crate::default_memory_budget`] (a spacing mistyped as 10⁻⁹ m
/// would fill until the allocator aborted the process).
fn check_lattice<const D: usize>(
    h: f64,
    lengths: &[(&'static str, f64)],
    count: f64,
) -> Result<(), SceneError>
where
    Const<D>: Dim,
{
    if !(h.is_finite() && h > 0.0) {
        return Err(SceneError::InvalidSetting {
            setting: "lattice spacing",
            value: h,
        });
    }
    for &(setting, value) in lengths {
        if !value.is_finite() {
            return Err(SceneError::NonFinite { setting });
        }
        if value < 0.0 {
            return Err(SceneError::InvalidSetting { setting, value });
        }
    }
    let bytes = count * std::mem::size_of::<Point<D>>() as f64;
    let budget = crate::default_memory_budget();
    if bytes.is_nan() || bytes > budget {
        return Err(SceneError::TooLarge {
            particles: count,
            bytes,
            budget,
            largest: String::new(),
        });
    }
    Ok(())
}

/// The extents of the box `[min, max]` along each axis, checked.
fn box_extents<const D: usize>(min: &Point<D>, max: &Point<D>) -> Result<(), SceneError>
where
    Const<D>: Dim,
{
    if (0..D).any(|k| !(min[k].is_finite() && max[k].is_finite())) {
        return Err(SceneError::NonFinite {
            setting: "lattice box bounds",
        });
    }
    // A corner past the other (one point at `min` came out).
    if let Some(k) = (0..D).find(|&k| min[k] > max[k]) {
        return Err(SceneError::OutOfRange {
            setting: "lattice box extent (max − min)",
            value: max[k] - min[k],
            range: "[0, ∞): the box's max below its min",
        });
    }
    Ok(())
}

fn counts<const D: usize>(min: &Point<D>, max: &Point<D>, h: f64) -> [usize; 3]
where
    Const<D>: Dim,
{
    // A box of zero extent along an axis (a wall one particle thick) has
    // one node along it, not two at the same place.
    let mut n = [0usize; 3];
    for k in 0..D {
        let extent = max[k] - min[k];
        n[k] = if extent > 0.0 {
            (extent / h).round().max(1.0) as usize
        } else {
            0
        };
    }
    n
}

/// Lattice nodes of the box `[min, max]` at spacing close to `h` (the
/// spacing along each axis is adjusted so the corners are nodes), ordered
/// x fastest. Refused ([`SceneError`]): a spacing that is not a positive
/// finite number, a bound that is not finite, a max below its min, or more
/// points than the memory budget holds.
///
/// ```
/// use pfem_core::Point;
/// use pfem_scene::lattice::box_points;
///
/// let p = box_points::<2>(&Point::<2>::new(0.0, 0.0), &Point::<2>::new(1.0, 0.5), 0.25)?;
/// assert_eq!(p.len(), 5 * 3);
/// assert!(box_points::<2>(&Point::<2>::new(0.0, 0.0), &Point::<2>::new(1.0, 0.5), 0.0).is_err());
/// # Ok::<(), pfem_scene::SceneError>(())
/// ```
pub fn box_points<const D: usize>(
    min: &Point<D>,
    max: &Point<D>,
    h: f64,
) -> Result<Vec<Point<D>>, SceneError>
where
    Const<D>: Dim,
{
    box_extents::<D>(min, max)?;
    let count: f64 = (0..D)
        .map(|k| ((max[k] - min[k]).max(0.0) / h).round() + 1.0)
        .product();
    check_lattice::<D>(h, &[], count)?;
    let n = counts::<D>(min, max, h);
    let mut out = Vec::new();
    let nz = if D == 3 { n[2] + 1 } else { 1 };
    for k in 0..nz {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                let idx = [i, j, k];
                let mut p = Point::<D>::zeros();
                for d in 0..D {
                    p[d] = if n[d] == 0 {
                        min[d]
                    } else {
                        min[d] + (max[d] - min[d]) * idx[d] as f64 / n[d] as f64
                    };
                }
                out.push(p);
            }
        }
    }
    Ok(out)
}

/// Simplices (triangles, or six Kuhn tetrahedra per cell) of the lattice
/// of [`box_points`], positively oriented, indices into its output.
/// Refused as [`box_points`] refuses its lattice, and when the node
/// indices would not fit `u32`.
pub fn box_simplices<const D: usize>(
    min: &Point<D>,
    max: &Point<D>,
    h: f64,
) -> Result<Vec<u32>, SceneError>
where
    Const<D>: Dim,
{
    let pts = box_points::<D>(min, max, h)?;
    // The connectivity: D! simplices of D + 1 indices per cell, about
    // (D + 1)! indices per point.
    let indices = pts.len() as f64 * if D == 3 { 24.0 } else { 6.0 };
    let budget = crate::default_memory_budget();
    if indices * 4.0 > budget {
        return Err(SceneError::TooLarge {
            particles: pts.len() as f64,
            bytes: indices * 4.0,
            budget,
            largest: String::new(),
        });
    }
    if pts.len() > u32::MAX as usize {
        return Err(SceneError::TooLarge {
            particles: pts.len() as f64,
            bytes: (pts.len() * std::mem::size_of::<Point<D>>()) as f64,
            budget: (u32::MAX as usize * std::mem::size_of::<Point<D>>()) as f64,
            largest: String::new(),
        });
    }
    let n = counts::<D>(min, max, h);
    let id = |i: usize, j: usize, k: usize| ((k * (n[1] + 1) + j) * (n[0] + 1) + i) as u32;
    let mut out = Vec::new();
    if D == 2 {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let (a, b, c, d) = (
                    id(i, j, 0),
                    id(i + 1, j, 0),
                    id(i + 1, j + 1, 0),
                    id(i, j + 1, 0),
                );
                if (i + j) % 2 == 0 {
                    out.extend_from_slice(&[a, b, c, a, c, d]);
                } else {
                    out.extend_from_slice(&[a, b, d, b, c, d]);
                }
            }
        }
    } else {
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let c = |b: usize| id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
                    for perm in [
                        [1, 2, 4],
                        [1, 4, 2],
                        [2, 1, 4],
                        [2, 4, 1],
                        [4, 1, 2],
                        [4, 2, 1],
                    ] {
                        let v1 = perm[0];
                        let v2 = v1 | perm[1];
                        let v3 = v2 | perm[2];
                        let mut t = [c(0), c(v1), c(v2), c(v3)];
                        let p: Vec<Point<D>> = t.iter().map(|&q| pts[q as usize]).collect();
                        if simplex_measure::<D>(&p) < 0.0 {
                            t.swap(2, 3);
                        }
                        out.extend_from_slice(&t);
                    }
                }
            }
        }
    }
    Ok(out)
}

/// The centre's coordinates, checked finite.
fn finite_center<const D: usize>(center: &Point<D>) -> Result<(), SceneError>
where
    Const<D>: Dim,
{
    if !center.iter().all(|c| c.is_finite()) {
        return Err(SceneError::NonFinite {
            setting: "lattice centre",
        });
    }
    Ok(())
}

/// Lattice nodes (spacing `h`, centred on `center`) inside the ball.
/// Refused ([`SceneError`]): a spacing that is not a positive finite
/// number, a centre or radius that is not finite, a negative radius, or
/// more points than the memory budget holds.
pub fn ball_points<const D: usize>(
    center: &Point<D>,
    radius: f64,
    h: f64,
) -> Result<Vec<Point<D>>, SceneError>
where
    Const<D>: Dim,
{
    finite_center::<D>(center)?;
    check_lattice::<D>(
        h,
        &[("lattice radius", radius)],
        (2.0 * (radius / h).floor() + 1.0).powi(D as i32),
    )?;
    let m = (radius / h).floor() as i64;
    let mut out = Vec::new();
    let range = -m..=m;
    let zr = if D == 3 { -m..=m } else { 0..=0 };
    for k in zr {
        for j in range.clone() {
            for i in range.clone() {
                let idx = [i, j, k];
                let mut p = *center;
                for d in 0..D {
                    p[d] += idx[d] as f64 * h;
                }
                if (p - center).norm() <= radius + 1e-9 * h {
                    out.push(p);
                }
            }
        }
    }
    Ok(out)
}

/// A disk (2D) or ball (3D) sampled on concentric rings or shells, from
/// the surface inwards, about `h` apart radially (`radius / round(radius /
/// h)`) and about `h` apart along each (rings: equal angles, every other
/// ring turned by half a step; shells: Fibonacci points), plus the centre.
/// Its surface is round at the particle scale, unlike a lattice's, whose
/// lowest particle stands alone a spacing below a flat disk of the next
/// layer: a solid ball from a lattice met a floor with that one particle
/// and its elements round it were crushed (issue 19). [`crate::Scene::build`]
/// uses it for the balls of solids and walls; fluids take the lattice
/// ([`ball_points`]), which the remeshing forgets anyway. Refused as
/// [`ball_points`] refuses its ball, and for a radius of zero (its rings
/// would all sit on the centre).
pub fn shell_points<const D: usize>(
    center: &Point<D>,
    radius: f64,
    h: f64,
) -> Result<Vec<Point<D>>, SceneError>
where
    Const<D>: Dim,
{
    use std::f64::consts::PI;
    finite_center::<D>(center)?;
    // A ball of no radius has no shell: its rings would all sit on the
    // centre.
    if radius == 0.0 {
        return Err(SceneError::InvalidSetting {
            setting: "lattice radius",
            value: radius,
        });
    }
    // About the ball's volume over `h^D`, each ring or shell at least 3
    // or 4 points.
    let shells_f = (radius / h).round().max(1.0);
    let per_shell = if D == 2 {
        (2.0 * PI * radius / h).round().max(3.0)
    } else {
        (4.0 * PI * radius * radius / (h * h)).round().max(4.0)
    };
    check_lattice::<D>(h, &[("lattice radius", radius)], 1.0 + shells_f * per_shell)?;
    let shells = shells_f as usize;
    let dr = radius / shells as f64;
    let golden = PI * (3.0 - 5f64.sqrt());
    let mut out = vec![*center];
    for k in 0..shells {
        let rk = radius - k as f64 * dr;
        if D == 2 {
            let n = (2.0 * PI * rk / h).round().max(3.0) as usize;
            let turn = if k % 2 == 1 { 0.5 } else { 0.0 };
            for i in 0..n {
                let phi = 2.0 * PI * (i as f64 + turn) / n as f64;
                let mut p = *center;
                p[0] += rk * phi.cos();
                p[1] += rk * phi.sin();
                out.push(p);
            }
        } else {
            let n = (4.0 * PI * rk * rk / (h * h)).round().max(4.0) as usize;
            for i in 0..n {
                let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let s = (1.0 - y * y).sqrt();
                let phi = golden * i as f64 + k as f64;
                let mut p = *center;
                p[0] += rk * s * phi.cos();
                p[1] += rk * y;
                p[D - 1] += rk * s * phi.sin();
                out.push(p);
            }
        }
    }
    Ok(out)
}

/// Lattice nodes of a cylinder along coordinate `axis` (3D): disks of
/// lattice nodes (spacing `h`, centred on the axis) within `radius`, at
/// `base + k · height / n` along the axis, `k = 0..=n`, `n = round(height / h)`
/// (the ends are nodes). In 2D the "disk" is the segment across the axis,
/// so the cylinder is a rectangle. Refused ([`SceneError`]): a spacing
/// that is not a positive finite number, a base, radius or height that is
/// not finite, a negative radius, a height that is not positive, an axis
/// the dimension has not (`axis ≥ D`), or more points than the memory
/// budget holds.
pub fn cylinder_points<const D: usize>(
    base: &Point<D>,
    axis: usize,
    radius: f64,
    height: f64,
    h: f64,
) -> Result<Vec<Point<D>>, SceneError>
where
    Const<D>: Dim,
{
    finite_center::<D>(base)?;
    if axis >= D {
        return Err(SceneError::OutOfRange {
            setting: "lattice cylinder axis",
            value: axis as f64,
            range: "the coordinates: 0, 1 (2D), 2 (3D)",
        });
    }
    // A cylinder of no height would stack two identical disks.
    if height == 0.0 {
        return Err(SceneError::InvalidSetting {
            setting: "lattice height",
            value: height,
        });
    }
    check_lattice::<D>(
        h,
        &[("lattice radius", radius), ("lattice height", height)],
        ((height / h).round().max(1.0) + 1.0)
            * (2.0 * (radius / h).floor() + 1.0).powi(D as i32 - 1),
    )?;
    let n = (height / h).round().max(1.0) as usize;
    let m = (radius / h).floor() as i64;
    let across: Vec<usize> = (0..D).filter(|&k| k != axis).collect();
    let (ra, rb) = (-m..=m, if D == 3 { -m..=m } else { 0..=0 });
    let mut out = Vec::new();
    for k in 0..=n {
        for j in rb.clone() {
            for i in ra.clone() {
                let off = [i as f64 * h, j as f64 * h];
                if (off[0] * off[0] + off[1] * off[1]).sqrt() > radius + 1e-9 * h {
                    continue;
                }
                let mut p = *base;
                p[axis] += height * k as f64 / n as f64;
                for (c, &d) in across.iter().enumerate() {
                    p[d] += off[c];
                }
                out.push(p);
            }
        }
    }
    Ok(out)
}

/// A hash grid over particle positions, for coincidence queries: one or
/// more levels of cells `cell · 2ˡ`, each recording every point, so that a
/// query within a tolerance far larger than the finest cell (a coarse
/// body's quarter spacing next to a fine one) looks at a few cells of a
/// coarser level instead of `(tol/cell)^D` of the finest.
#[derive(Debug, Clone)]
pub struct HashGrid<const D: usize> {
    levels: Vec<(f64, Cells)>,
}

/// One level of a [`HashGrid`]: the points recorded in each cell.
type Cells = std::collections::HashMap<[i64; 3], Vec<usize>>;

/// The most levels [`HashGrid::with_tolerances`] builds (cells up to `2⁶³`
/// times the finest).
pub const MAX_LEVELS: usize = 64;

impl<const D: usize> HashGrid<D>
where
    Const<D>: Dim,
{
    /// An empty grid of cell size `cell` (m), one level.
    pub fn new(cell: f64) -> Self {
        Self {
            levels: vec![(cell, Cells::new())],
        }
    }

    /// An empty grid of finest cell `cell` (m) with the coarser levels
    /// `cell · 2ˡ` that queries within `tolerances` (m) use, one for each
    /// (the first no smaller than it), and no others: each query then
    /// visits `3^D` cells, and each point is recorded once per level used
    /// (at most [`MAX_LEVELS`] levels).
    pub fn with_tolerances(cell: f64, tolerances: &[f64]) -> Self {
        let mut g = Self::new(cell);
        let mut cells: Vec<f64> = tolerances
            .iter()
            .filter(|&&t| t > cell && t.is_finite())
            .map(|&t| {
                let l = (t / cell).log2().ceil().min((MAX_LEVELS - 1) as f64);
                cell * 2f64.powi(l as i32)
            })
            .collect();
        cells.sort_by(f64::total_cmp);
        cells.dedup();
        g.levels
            .extend(cells.into_iter().map(|c| (c, Cells::new())));
        g
    }

    fn key(cell: f64, p: &Point<D>) -> [i64; 3] {
        let mut k = [0i64; 3];
        for d in 0..D {
            k[d] = (p[d] / cell).floor() as i64;
        }
        k
    }

    /// Records point `index` at `p`.
    pub fn insert(&mut self, p: &Point<D>, index: usize) {
        for (cell, map) in &mut self.levels {
            let k = Self::key(*cell, p);
            map.entry(k).or_default().push(index);
        }
    }

    /// Whether a recorded point lies within `tol` of `p`.
    pub fn near(&self, p: &Point<D>, tol: f64, points: &[Point<D>]) -> bool {
        self.find(p, tol, points).is_some()
    }

    /// Calls `f` with every recorded point within `tol` of `p` (in the
    /// grid's order), from the same cells as [`HashGrid::find`].
    pub fn visit(&self, p: &Point<D>, tol: f64, points: &[Point<D>], mut f: impl FnMut(usize)) {
        let (cell, map) = self
            .levels
            .iter()
            .find(|(c, _)| *c >= tol)
            .unwrap_or_else(|| self.levels.last().expect("a grid has a level"));
        let k = Self::key(*cell, p);
        let r = ((tol / cell).ceil() as i64).max(1);
        let zr = if D == 3 { -r..=r } else { 0..=0 };
        for dz in zr {
            for dy in -r..=r {
                for dx in -r..=r {
                    let kk = [k[0] + dx, k[1] + dy, k[2] + dz];
                    if let Some(v) = map.get(&kk) {
                        for &i in v {
                            if (points[i] - p).norm() <= tol {
                                f(i);
                            }
                        }
                    }
                }
            }
        }
    }

    /// The nearest recorded point within `tol` of `p`, if any. Searches
    /// every cell `tol` can reach on the finest level whose cell is no
    /// smaller than `tol` (or the coarsest level).
    pub fn find(&self, p: &Point<D>, tol: f64, points: &[Point<D>]) -> Option<usize> {
        let mut best: Option<(f64, usize)> = None;
        self.visit(p, tol, points, |i| {
            let d = (points[i] - p).norm();
            if d < tol && best.is_none_or(|(b, _)| d < b) {
                best = Some((d, i));
            }
        });
        best.map(|(_, i)| i)
    }
}

/// Hash grids of points by spacing class (spacings within a factor of 2
/// share one, its cell 1.5 times the class's largest): a query within a
/// multiple of the larger spacing of a pair visits each class's grid at
/// that class's own radius, so fine particles beside coarse ones cost
/// their own neighbourhood, not the coarse one's (a grid sized by the
/// largest spacing scanned `(s_max/s_min)^D` fine particles a cell).
#[derive(Debug, Clone)]
pub struct SpacingGrids<const D: usize> {
    /// (largest spacing of the class, its grid, its points).
    classes: Vec<(f64, HashGrid<D>, Vec<usize>)>,
}

impl<const D: usize> SpacingGrids<D>
where
    Const<D>: Dim,
{
    /// The points `i` with `keep(i)`, by the class of `spacing[i]` (finite
    /// and positive spacings only).
    pub fn new(points: &[Point<D>], spacing: &[f64], keep: impl Fn(usize) -> bool) -> Self {
        let mut classes: Vec<(i32, f64, HashGrid<D>, Vec<usize>)> = Vec::new();
        for (i, p) in points.iter().enumerate() {
            let s = spacing[i];
            if !(keep(i) && s > 0.0 && s.is_finite()) {
                continue;
            }
            let k = s.log2().floor() as i32;
            let c = match classes.iter().position(|c| c.0 == k) {
                Some(c) => c,
                None => {
                    let top = 2f64.powi(k + 1);
                    classes.push((k, top, HashGrid::new(1.5 * top), Vec::new()));
                    classes.len() - 1
                }
            };
            classes[c].2.insert(p, i);
            classes[c].3.push(i);
        }
        Self {
            classes: classes
                .into_iter()
                .map(|(_, top, g, members)| (top, g, members))
                .collect(),
        }
    }

    /// Calls `f` with every recorded point within `factor` times the
    /// larger of `s` and its class's largest spacing from `p` (a superset
    /// of the points within `factor · max(s, sⱼ)`; the caller checks its
    /// own pair radius).
    pub fn visit(
        &self,
        p: &Point<D>,
        s: f64,
        factor: f64,
        points: &[Point<D>],
        mut f: impl FnMut(usize),
    ) {
        for (top, grid, members) in &self.classes {
            let r = factor * s.max(*top);
            // A query far coarser than the class (a wall at 0.1 m beside
            // a body at 10⁻⁹ m) would visit more cells than the class has
            // points: its points one by one instead.
            let side = 2.0 * (r / (1.5 * top)).ceil() + 1.0;
            if side.powi(D as i32) > members.len() as f64 {
                for &j in members {
                    if (points[j] - p).norm() <= r {
                        f(j);
                    }
                }
            } else {
                grid.visit(p, r, points, &mut f);
            }
        }
    }
}

/// The first fluid particle with particles of one other body on both
/// sides of it along every axis and every face diagonal (within 1.5
/// spacings along the direction, 0.75 across it, the larger spacing of the
/// pair), and that body: a fluid drawn inside another body off its
/// lattice. `None` when there is none. Particles beside a body, along a
/// sloping face of it, or in a concave corner of it are on one side of
/// some direction: a face diagonal leaves the corner and the slope (the
/// axes alone refused a water particle in the corner of a U-shaped wall
/// and on a 45° boundary whose lattices were off each other's; session
/// 43's review).
pub fn fluid_inside_another_body<const D: usize>(
    x: &[Point<D>],
    kind: &[ParticleKind],
    body: &[u32],
    spacing: &[f64],
) -> Option<(usize, u32)>
where
    Const<D>: Dim,
{
    let grids = SpacingGrids::new(x, spacing, |_| true);
    // The axes and the face diagonals.
    let mut dirs: Vec<Vector<D>> = Vec::new();
    for a in 0..D {
        let mut u = Vector::<D>::zeros();
        u[a] = 1.0;
        dirs.push(u);
        for b in a + 1..D {
            for sign in [1.0, -1.0] {
                let mut u = Vector::<D>::zeros();
                u[a] = std::f64::consts::FRAC_1_SQRT_2;
                u[b] = sign * std::f64::consts::FRAC_1_SQRT_2;
                dirs.push(u);
            }
        }
    }
    // Per other body near a particle: (below, above) along each direction
    // (at most 3 axes and 6 face diagonals: no allocation a particle).
    let mut sides: Vec<(u32, [[bool; 2]; 9])> = Vec::new();
    for i in 0..x.len() {
        if kind[i] != ParticleKind::Fluid || !(spacing[i] > 0.0 && spacing[i].is_finite()) {
            continue;
        }
        sides.clear();
        grids.visit(&x[i], spacing[i], 1.5, x, |j| {
            if body[j] == body[i] {
                return;
            }
            let s = spacing[i].max(spacing[j]);
            let d = x[j] - x[i];
            if d.norm() > 1.5 * s {
                return;
            }
            let k = match sides.iter().position(|(b, _)| *b == body[j]) {
                Some(k) => k,
                None => {
                    sides.push((body[j], [[false; 2]; 9]));
                    sides.len() - 1
                }
            };
            for (u, side) in dirs.iter().zip(sides[k].1.iter_mut()) {
                let along = d.dot(u);
                if (d - u * along).norm() <= 0.75 * s {
                    if along < -0.25 * s {
                        side[0] = true;
                    } else if along > 0.25 * s {
                        side[1] = true;
                    }
                }
            }
        });
        if let Some((b, _)) = sides
            .iter()
            .find(|(_, f)| f[..dirs.len()].iter().all(|side| side[0] && side[1]))
        {
            return Some((i, *b));
        }
    }
    None
}

/// Points bucketed on a grid of cell width `h`, to find the points in a
/// box without testing every point (a solid's clamps, the fluid inside a
/// wall's box, the point probes' elements in `pfem_io`).
#[derive(Debug, Clone)]
pub struct PointGrid {
    h: f64,
    cells: std::collections::HashMap<[i64; 3], Vec<u32>>,
    /// The range of occupied cells.
    min: [i64; 3],
    max: [i64; 3],
}

impl PointGrid {
    fn key<const D: usize>(&self, q: &Point<D>) -> [i64; 3]
    where
        Const<D>: Dim,
    {
        // `as` saturates: a corner far beyond the points keys to the edge.
        let mut k = [0i64; 3];
        for d in 0..D {
            k[d] = (q[d] / self.h).floor() as i64;
        }
        k
    }

    /// The grid of `points` (finite), cell width `h` (positive, finite).
    pub fn new<const D: usize>(points: &[Point<D>], h: f64) -> Self
    where
        Const<D>: Dim,
    {
        let mut g = Self {
            h,
            cells: std::collections::HashMap::new(),
            min: [i64::MAX; 3],
            max: [i64::MIN; 3],
        };
        for (i, q) in points.iter().enumerate() {
            let k = g.key(q);
            for d in 0..D {
                g.min[d] = g.min[d].min(k[d]);
                g.max[d] = g.max[d].max(k[d]);
            }
            g.cells.entry(k).or_default().push(i as u32);
        }
        g
    }

    /// Calls `f` with every point of the cells the box `lo`–`hi` covers (a
    /// superset of the points in it: `floor` keeps the order, so a point in
    /// the box is in a covered cell), and returns the cells visited: those
    /// the box covers, or the occupied ones when they are fewer.
    pub fn for_each_in<const D: usize>(
        &self,
        lo: &Point<D>,
        hi: &Point<D>,
        f: &mut impl FnMut(u32),
    ) -> u64
    where
        Const<D>: Dim,
    {
        let (klo, khi) = (self.key(lo), self.key(hi));
        let (mut a, mut b) = ([0i64; 3], [0i64; 3]);
        let mut cells: u64 = 1;
        for d in 0..D {
            a[d] = klo[d].max(self.min[d]);
            b[d] = khi[d].min(self.max[d]);
            let n = if b[d] >= a[d] {
                (b[d] as i128 - a[d] as i128 + 1).min(u64::MAX as i128) as u64
            } else {
                0
            };
            cells = cells.saturating_mul(n);
        }
        if cells == 0 {
            return 0;
        }
        if cells <= self.cells.len() as u64 {
            let mut k = a;
            'cells: loop {
                if let Some(list) = self.cells.get(&k) {
                    list.iter().for_each(|&i| f(i));
                }
                for d in 0..D {
                    if k[d] < b[d] {
                        k[d] += 1;
                        continue 'cells;
                    }
                    k[d] = a[d];
                }
                break;
            }
            cells
        } else {
            for (k, list) in &self.cells {
                if (0..D).all(|d| a[d] <= k[d] && k[d] <= b[d]) {
                    list.iter().for_each(|&i| f(i));
                }
            }
            self.cells.len() as u64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid for a fine and a coarse tolerance holds two levels, and a
    /// coarse query finds the nearest point within its tolerance (a fine
    /// body's point, or none) as a one-level grid would.
    #[test]
    fn a_grid_keeps_one_level_per_tolerance_and_finds_the_same_points() {
        let fine = 1e-3;
        let pts: Vec<Point<2>> = (0..50)
            .map(|i| Point::<2>::new(i as f64 * fine, 0.0))
            .collect();
        let mut levels = HashGrid::<2>::with_tolerances(fine, &[0.25 * fine, 0.025, 0.025]);
        let mut flat = HashGrid::<2>::new(fine);
        for (i, p) in pts.iter().enumerate() {
            levels.insert(p, i);
            flat.insert(p, i);
        }
        assert_eq!(levels.levels.len(), 2);
        for q in [
            Point::<2>::new(0.0101, 0.001),
            Point::<2>::new(0.2, 0.0),
            Point::<2>::new(-0.02, 0.0),
        ] {
            for tol in [0.25 * fine, 0.025] {
                assert_eq!(levels.find(&q, tol, &pts), flat.find(&q, tol, &pts));
            }
        }
        assert_eq!(
            levels.find(&Point::<2>::new(0.0101, 0.001), 0.025, &pts),
            Some(10)
        );
    }

    /// Session 44's review: the public helpers filled whatever a spacing
    /// of zero or 10⁻⁹ gave (no end, or the allocator's abort). Each is
    /// refused with a typed error before anything is allocated.
    #[test]
    fn lattices_refuse_spacings_and_sizes_they_cannot_fill() {
        let (lo, hi) = (
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(1.0, 1.0, 1.0),
        );
        let c = Point::<3>::new(0.0, 0.0, 0.0);
        for h in [0.0, -0.1, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                box_points::<3>(&lo, &hi, h),
                Err(SceneError::InvalidSetting { .. })
            ));
            assert!(box_simplices::<3>(&lo, &hi, h).is_err());
            assert!(ball_points::<3>(&c, 1.0, h).is_err());
            assert!(shell_points::<3>(&c, 1.0, h).is_err());
            assert!(cylinder_points::<3>(&c, 1, 1.0, 1.0, h).is_err());
        }
        // 10²⁷ points.
        assert!(matches!(
            box_points::<3>(&lo, &hi, 1e-9),
            Err(SceneError::TooLarge { .. })
        ));
        assert!(matches!(
            ball_points::<3>(&c, 1.0, 1e-9),
            Err(SceneError::TooLarge { .. })
        ));
        assert!(matches!(
            shell_points::<3>(&c, 1.0, 1e-9),
            Err(SceneError::TooLarge { .. })
        ));
        assert!(matches!(
            cylinder_points::<3>(&c, 1, 1.0, 1.0, 1e-9),
            Err(SceneError::TooLarge { .. })
        ));
        // Bounds, radii and heights that are not numbers, or negative.
        let nan = Point::<3>::new(f64::NAN, 0.0, 0.0);
        assert!(matches!(
            box_points::<3>(&nan, &hi, 0.1),
            Err(SceneError::NonFinite { .. })
        ));
        assert!(ball_points::<3>(&nan, 1.0, 0.1).is_err());
        assert!(ball_points::<3>(&c, f64::INFINITY, 0.1).is_err());
        assert!(shell_points::<3>(&c, -1.0, 0.1).is_err());
        assert!(cylinder_points::<3>(&c, 1, 1.0, f64::NAN, 0.1).is_err());
        assert!(cylinder_points::<3>(&c, 1, 1.0, -1.0, 0.1).is_err());
        // A box turned inside out, a shell of no radius, a cylinder of no
        // height or along an axis the dimension has not (the review of
        // the change: one point, rings on the centre, two identical
        // disks, an axis silently clamped).
        assert!(box_points::<3>(&hi, &lo, 0.1).is_err());
        assert!(box_simplices::<3>(&hi, &lo, 0.1).is_err());
        assert!(shell_points::<3>(&c, 0.0, 0.1).is_err());
        assert!(cylinder_points::<3>(&c, 1, 1.0, 0.0, 0.1).is_err());
        assert!(cylinder_points::<3>(&c, 3, 1.0, 1.0, 0.1).is_err());
        assert!(cylinder_points::<2>(&Point::<2>::zeros(), 2, 1.0, 1.0, 0.1).is_err());
        // A fine lattice still fills.
        assert_eq!(box_points::<3>(&lo, &hi, 0.1).unwrap().len(), 11 * 11 * 11);
        assert!(!shell_points::<2>(&Point::<2>::zeros(), 0.1, 0.01)
            .unwrap()
            .is_empty());
    }

    #[test]
    fn box_mesh_covers_the_box() {
        let min = Point::<2>::new(0.0, 0.0);
        let max = Point::<2>::new(0.35, 0.02);
        let p = box_points::<2>(&min, &max, 0.005).unwrap();
        let t = box_simplices::<2>(&min, &max, 0.005).unwrap();
        let area: f64 = t
            .chunks(3)
            .map(|c| simplex_measure::<2>(&[p[c[0] as usize], p[c[1] as usize], p[c[2] as usize]]))
            .sum();
        assert!((area - 0.35 * 0.02).abs() < 1e-12);
        let min3 = Point::<3>::new(0.0, 0.0, 0.0);
        let max3 = Point::<3>::new(1.0, 0.5, 0.25);
        let p = box_points::<3>(&min3, &max3, 0.25).unwrap();
        let t = box_simplices::<3>(&min3, &max3, 0.25).unwrap();
        let vol: f64 = t
            .chunks(4)
            .map(|c| {
                let q: Vec<Point<3>> = c.iter().map(|&i| p[i as usize]).collect();
                let v = simplex_measure::<3>(&q);
                assert!(v > 0.0);
                v
            })
            .sum();
        assert!((vol - 0.125).abs() < 1e-12);
    }

    /// The rings and shells lie on the surface and inside, about a spacing
    /// apart: nearest neighbours between 0.6 h and 1.4 h, and the ball's
    /// lowest particles are many, not one below a flat layer.
    #[test]
    fn shells_are_round_and_about_a_spacing_apart() {
        fn check<const D: usize>(r: f64, h: f64)
        where
            Const<D>: Dim,
        {
            let c = Point::<D>::from_element(0.3);
            let p = shell_points::<D>(&c, r, h).unwrap();
            for (i, a) in p.iter().enumerate() {
                assert!((a - c).norm() <= r * (1.0 + 1e-12));
                let nearest = p
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .map(|(_, b)| (a - b).norm())
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest > 0.6 * h && nearest < 1.4 * h, "{D}D: {nearest}");
            }
            // Within a tenth of a spacing of the lowest point, several
            // particles (a lattice ball with r = 8 h has one, its next
            // layer a spacing higher).
            let low = p.iter().map(|q| q[1]).fold(f64::INFINITY, f64::min);
            assert!((low - (c[1] - r)).abs() < 0.1 * h);
            let near = p.iter().filter(|q| q[1] < low + 0.1 * h).count();
            assert!(near >= 3, "{D}D: {near} particles at the bottom");
            // The count is about the ball's measure over h^D (the outer
            // shell holds a whole layer's particles for half a layer's
            // measure: 3D r = 8 h +27 %).
            let measure = if D == 2 {
                std::f64::consts::PI * r * r
            } else {
                4.0 / 3.0 * std::f64::consts::PI * r * r * r
            };
            let ratio = p.len() as f64 * h.powi(D as i32) / measure;
            assert!((0.8..1.35).contains(&ratio), "{D}D: {ratio}");
        }
        check::<2>(0.1, 0.01);
        check::<2>(0.105, 0.01);
        check::<3>(0.05, 0.00625);
        check::<3>(0.047, 0.00625);
    }

    #[test]
    fn cylinder_lattice_is_inside_and_has_its_ends() {
        let base = Point::<3>::new(0.3, 0.0, 0.07);
        let p = cylinder_points::<3>(&base, 1, 0.015, 0.15, 0.0075).unwrap();
        // 13 nodes per disk (r = 2 h), 21 disks.
        assert_eq!(p.len(), 13 * 21);
        for q in &p {
            let r = ((q.x - base.x).powi(2) + (q.z - base.z).powi(2)).sqrt();
            assert!(r <= 0.015 + 1e-12 && q.y >= -1e-12 && q.y <= 0.15 + 1e-12);
        }
        assert!(p.iter().any(|q| (q.y - 0.15).abs() < 1e-12));
    }
}
