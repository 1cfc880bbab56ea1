//! The alpha shape of paper §8: which Delaunay simplices are fluid elements.

use pfem_core::{edge_matrix, Const, Dim, ParticleKind, Point, Vector, MAX_NV};
use rayon::prelude::*;

use crate::{GeometryError, Tessellation, NO_NEIGHBOR, SEALED};

/// Parameters of the alpha shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlphaShapeParams {
    /// A fluid-candidate simplex is kept when its circumradius
    /// `R ≤ alpha · h`, with `h` the largest spacing of its nodes (the
    /// coarser side of an interface between bodies of different spacings;
    /// ARCHITECTURE.md's deviations).
    /// Dimensionless, finite and `> 0`; PFEM codes use 1.2–1.4 (paper §8:
    /// "close to, but greater than one"). Default `1.3`.
    pub alpha: f64,
    /// Drop *dry bridges*: simplices joining a free-surface fluid particle
    /// to a wall or solid particle above the water line (see
    /// [`alpha_shape_into`]). Default `true`; `false` is the paper's plain
    /// alpha shape. Needs [`Self::up`].
    pub drop_dry_bridges: bool,
    /// With [`Self::drop_dry_bridges`]: a dry bridge against a solid, where
    /// the free surface faces up, is *cut at the water line* instead of
    /// kept or dropped whole: it stays an element, integrated only over its
    /// part below the plane normal to [`Self::up`] through its free-surface
    /// fluid nodes ([`AlphaShape::surface_cuts`]). Default `false` (the
    /// rule: drop when a wall or solid node lies more than half a spacing
    /// above and outside); for floating bodies, and then against the
    /// particles [`alpha_shape_cutting_into`] is given (the driver gives
    /// its free solids'). See `drop_dry_bridges`.
    pub cut_dry_bridges: bool,
    /// The unit vector opposite to gravity (its first `D` components are
    /// used), which says where "above the water line" is; `None` (the
    /// default) when the scene has no gravity, and no simplex is then a dry
    /// bridge. The driver sets it from the body force, again whenever a
    /// hook or a restore changes it.
    pub up: Option<[f64; 3]>,
    /// Smallest `measure / R³` of a kept tetrahedron (3D; `R` its
    /// circumradius): flatter candidates are slivers, never elements (the
    /// regular tetrahedron has 0.51, a cubic lattice's Kuhn tetrahedron
    /// 0.26). Default [`MIN_SHAPE_QUALITY`] (10⁻³): only nearly flat
    /// simplices (a tetrahedron whose smallest height is about a
    /// thousandth of its circumradius); [`MIN_ELEMENT_QUALITY_3D`] is the measured option of
    /// ARCHITECTURE.md's "options measured and left off". In 2D the sliver
    /// test is always [`MIN_SHAPE_QUALITY`].
    pub min_quality_3d: f64,
}

/// A [`AlphaShapeParams::min_quality_3d`] that removes the 3D water
/// column's rejected attempts: every element that inverted within one of
/// its steps (142 of 450 steps to 0.3 s rejected) had a quality below 0.06;
/// with those left out the run took 144 steps, none rejected, its front
/// within 1.5 %. Not the default: it changes the column-on-cylinder's
/// top displacement (50.96 against 61.15 mm with 0.4 ms steps; 47.9–66.7
/// against 59.6–64.3 mm over five step sizes).
pub const MIN_ELEMENT_QUALITY_3D: f64 = 0.06;

impl Default for AlphaShapeParams {
    fn default() -> Self {
        Self {
            alpha: 1.3,
            drop_dry_bridges: true,
            cut_dry_bridges: false,
            up: None,
            min_quality_3d: MIN_SHAPE_QUALITY,
        }
    }
}

impl AlphaShapeParams {
    /// The paper's alpha criterion with `alpha`, and the default handling
    /// of dry bridges.
    pub fn with_alpha(alpha: f64) -> Self {
        Self {
            alpha,
            ..Self::default()
        }
    }
}

impl AlphaShapeParams {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), GeometryError> {
        if !(self.alpha.is_finite() && self.alpha > 0.0) {
            return Err(GeometryError::InvalidParameter {
                name: "alpha",
                value: self.alpha,
                reason: "must be finite and > 0",
            });
        }
        if !(self.min_quality_3d.is_finite() && (0.0..0.5).contains(&self.min_quality_3d)) {
            return Err(GeometryError::InvalidParameter {
                name: "min_quality_3d",
                value: self.min_quality_3d,
                reason: "must be in [0, 0.5) (the regular tetrahedron has 0.51)",
            });
        }
        // A NaN or a zero `up` turned the dry-bridge test off unseen, a
        // long one moved it (session 35's review).
        if let Some(up) = self.up {
            let norm = up.iter().map(|c| c * c).sum::<f64>().sqrt();
            if !(up.iter().all(|c| c.is_finite()) && (norm - 1.0).abs() <= 1e-6) {
                return Err(GeometryError::InvalidParameter {
                    name: "up",
                    value: norm,
                    reason: "must be a finite unit vector (its length is the value)",
                });
            }
        }
        Ok(())
    }
}

/// Result of [`alpha_shape`]: the fluid mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AlphaShape {
    /// For each simplex of the Delaunay tessellation, whether it is kept.
    pub kept: Vec<bool>,
    /// The kept simplices, in Delaunay order, as a tessellation of the same
    /// particles. Its neighbour across a facet whose other side is not kept
    /// is [`NO_NEIGHBOR`]: those facets are the boundary (see
    /// [`classify`](crate::classify())); or [`SEALED`] when the other side
    /// is a sealed void of slivers (not boundary, see [`alpha_shape_into`]).
    pub mesh: Tessellation,
    /// `source[m]` is the Delaunay simplex that mesh simplex `m` is.
    pub source: Vec<u32>,
    /// Total measure (area in 2D, volume in 3D) of the fluid candidates:
    /// Delaunay simplices with at least one fluid node.
    pub candidate_measure: f64,
    /// Total measure of the kept simplices: the fluid volume of the mesh.
    pub kept_measure: f64,
    /// Number of dropped slivers in sealed voids (see [`alpha_shape_into`]).
    pub sealed: usize,
    /// The slivers of the sealed voids, `D + 1` particle indices each
    /// (Delaunay orientation): *closures*. They are not elements (no mass,
    /// no viscous or solid stiffness), but a sealed void is no gap in the
    /// fluid, so the pressure terms must see it closed: the area vectors of
    /// a closure's facets are finite however flat it is, and without them
    /// the kept simplices on its two sides split the same quadrilateral
    /// along different diagonals, which unbalances a hydrostatic pressure
    /// by `p h²` (see `pfem_assembly::StepMesh::closures`).
    pub closures: Vec<u32>,
    /// *Wall pockets* (3D): non-flat simplices of wall particles only, within the
    /// alpha reach, whose circumsphere passes near a fluid particle, `D + 1`
    /// particle indices each, with their weights in [`Self::pocket_weights`].
    /// They fill the lattice cells in the concave corners of the walls (a
    /// tank's floor meeting a side wall: wall nodes on two faces of the
    /// cell, fluid on the rest). Such a cell is a tie of the Delaunay
    /// criterion, which round-off splits one way or another, and the share
    /// of the cell in simplices with a fluid node swings with the split (by
    /// up to half the cell). A pocket's weight is `1 − g/δ`, `g` the
    /// distance of the nearest fluid particle of its cell from its
    /// circumsphere and `δ = R/10`: `1` in a tie, so that the cell counts
    /// whole whichever way it is split, and falling to `0` as the fluid
    /// leaves the sphere, so that the measure stays continuous. Not
    /// elements: the driver counts them in the fluid's measure only, so
    /// that its volume correction does not chase round-off.
    pub wall_pockets: Vec<u32>,
    /// Weight in `(0, 1]` of each wall pocket (see [`Self::wall_pockets`]).
    pub pocket_weights: Vec<f64>,
    /// *Surface cuts*: the kept simplices that join free-surface fluid
    /// particles to a wall or solid particle above their water line, as
    /// `(mesh simplex, mask of its free-surface fluid nodes)`. Such an
    /// element is water only below the plane normal to `up` through the
    /// mean height of those nodes ([`pfem_core::below_water_line`]); the
    /// assembly integrates it there and [`Self::kept_measure`] counts that
    /// part (see [`alpha_shape_into`], [`AlphaShapeParams::cut_dry_bridges`]).
    pub surface_cuts: Vec<(u32, u8)>,
}

impl AlphaShape {
    /// Measure of the fluid candidates that the alpha criterion dropped
    /// (the volume the alpha shape takes away from the Delaunay hull).
    pub fn deleted_measure(&self) -> f64 {
        self.candidate_measure - self.kept_measure
    }

    /// Number of kept simplices.
    pub fn len(&self) -> usize {
        self.mesh.len()
    }

    /// Whether no simplex is kept.
    pub fn is_empty(&self) -> bool {
        self.mesh.is_empty()
    }
}

/// Checks that the per-particle arrays agree and the spacings are valid.
pub(crate) fn check_particles<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    spacing: &[f64],
) -> Result<(), GeometryError>
where
    Const<D>: Dim,
{
    let n = points.len();
    if kinds.len() != n {
        return Err(GeometryError::LengthMismatch {
            what: "kinds",
            expected: n,
            found: kinds.len(),
        });
    }
    if spacing.len() != n {
        return Err(GeometryError::LengthMismatch {
            what: "spacing",
            expected: n,
            found: spacing.len(),
        });
    }
    if let Some(index) = spacing.iter().position(|h| !(h.is_finite() && *h > 0.0)) {
        return Err(GeometryError::InvalidSpacing {
            index,
            value: spacing[index],
        });
    }
    Ok(())
}

/// Checks that a tessellation has `D + 1` vertices per simplex, indices in
/// range and a neighbour array of the right length.
pub(crate) fn check_tessellation<const D: usize>(
    tess: &Tessellation,
    n_points: usize,
) -> Result<(), GeometryError>
where
    Const<D>: Dim,
{
    let nv = <Const<D> as Dim>::NV;
    if tess.nv != nv && !tess.simplices.is_empty() {
        return Err(GeometryError::InvalidConnectivity {
            reason: "nv is not D + 1",
        });
    }
    if !tess.simplices.len().is_multiple_of(nv) {
        return Err(GeometryError::InvalidConnectivity {
            reason: "connectivity length is not a multiple of D + 1",
        });
    }
    if tess.neighbors.len() != tess.simplices.len() {
        return Err(GeometryError::InvalidConnectivity {
            reason: "neighbour array length differs from connectivity length",
        });
    }
    if tess.simplices.iter().any(|&v| v as usize >= n_points) {
        return Err(GeometryError::InvalidConnectivity {
            reason: "vertex index out of range",
        });
    }
    let ns = tess.simplices.len() / nv;
    if tess
        .neighbors
        .iter()
        .any(|&t| t != NO_NEIGHBOR && t != SEALED && t as usize >= ns)
    {
        return Err(GeometryError::InvalidConnectivity {
            reason: "neighbour index out of range",
        });
    }
    Ok(())
}

/// Gathers the vertices of a simplex into a fixed-size array.
#[inline]
pub(crate) fn gather<const D: usize>(points: &[Point<D>], s: &[u32]) -> [Point<D>; MAX_NV]
where
    Const<D>: Dim,
{
    let mut p = [Point::<D>::zeros(); MAX_NV];
    for (k, &v) in s.iter().enumerate() {
        p[k] = points[v as usize];
    }
    p
}

/// Largest spacing of the nodes of a simplex: the local `h` of §8. (The
/// mean, used before, shrank the reach of the simplices joining a fine
/// solid to coarser water, so the alpha shape opened holes along the
/// interface: with a plate 8 times finer than the water, the water next
/// to it started at 68 m/s² from a hydrostatic rest; issue 13.)
#[inline]
pub(crate) fn simplex_spacing(spacing: &[f64], s: &[u32]) -> f64 {
    s.iter().map(|&v| spacing[v as usize]).fold(0.0, f64::max)
}

/// What [`decide`] makes of a Delaunay simplex.
const DROPPED: u8 = 0;
const KEPT: u8 = 1;
/// A flat fluid candidate whose edges are all within the alpha reach: not
/// an element, but not a gap in the fluid either (it may be sealed).
const SLIVER: u8 = 2;

/// Decides one simplex: `(fluid candidate measure, verdict)`.
#[inline]
fn decide<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    spacing: &[f64],
    s: &[u32],
    alpha: f64,
    quality: f64,
) -> (f64, u8)
where
    Const<D>: Dim,
{
    // Candidates: at least one fluid node (the reading notes, point 4: wall-only, solid-only
    // and solid/wall bridges are not fluid elements).
    if !s.iter().any(|&v| kinds[v as usize] == ParticleKind::Fluid) {
        return (0.0, DROPPED);
    }
    let p = gather::<D>(points, s);
    let (measure, r2) = measure_and_circumradius2::<D>(&p[..s.len()]);
    let ah = alpha * simplex_spacing(spacing, s);
    // Slivers: a simplex whose measure is a vanishing fraction of its
    // circumball's is flat (4 nearly cospherical lattice points in 3D whose
    // rounded coordinates the exact predicates see as a thin tetrahedron).
    // It would be a J ≈ 0 element that any motion inverts; it is dropped,
    // losing no measure worth counting. When its edges are short enough
    // for the alpha shape (each ≤ 2αh, the diameter of the alpha ball) it
    // is a SLIVER: fluid on both sides of it is one body.
    let r_d = if D == 2 { r2 } else { r2 * r2.sqrt() };
    let flat = measure.is_nan() || measure <= 0.0 || measure <= quality * r_d;
    if flat {
        let reach = (2.0 * ah) * (2.0 * ah);
        let short =
            (0..s.len()).all(|a| (a + 1..s.len()).all(|b| (p[a] - p[b]).norm_squared() <= reach));
        let m = if measure.is_nan() {
            0.0
        } else {
            measure.max(0.0)
        };
        return (m, if short { SLIVER } else { DROPPED });
    }
    // §8 alpha criterion: keep when the circumradius R ≤ α h.
    (measure, if r2 <= ah * ah { KEPT } else { DROPPED })
}

/// Smallest cosine between a free-surface normal and `up` for a surface
/// node to make a water line that [`drop_dry_bridges`] cuts (45°).
const WATER_LINE_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Drops the *dry bridges* among the kept simplices of `decided` and says
/// whether it dropped any: kept
/// simplices that join free-surface fluid particles to a wall or solid
/// particle lying outside the fluid, across its free surface.
///
/// Where a free surface meets a wall, the alpha shape also keeps the small
/// simplex between the last fluid particle and the wall particle above the
/// water line (in 2D the right triangle of legs `h` under the wall's next
/// particle, `R = 0.71 h`). It is not water: air lies there. Its mass,
/// lumped onto the fluid particle, has no pressure gradient to hold it
/// (its nodes all sit at the free surface's `p = 0`, and its only free
/// node's shape gradient is horizontal), so that particle accelerates
/// downwards at `g/4` from rest and the tank's water never comes to rest
/// (issue 13: corner particles sinking at 3–5 cm/s and gravity waves
/// that last; measured: with these simplices dropped, water at rest
/// remeshed every step stays at rest to 5e-15 √(gH)).
///
/// The rule: the outward normal `n_F` of the free surface at a fluid
/// particle `F` is the sum of the area-weighted outward normals of the
/// boundary facets through `F` whose nodes are all fluid. A kept simplex
/// with a wall or solid node whose fluid nodes all have such a normal (they
/// lie on the free surface) is dropped when one of its wall or solid nodes
/// `W` lies, seen from each fluid node `F`, more than half a spacing above
/// `F` (along `up`, opposite to gravity) and more than half a spacing
/// outside the free surface (`(x_W − x_F)·n̂_F > ½ h_F`): a wall rising
/// above the water line. (In 2D such a triangle has one fluid node; in 3D
/// a tetrahedron can also rest an edge or a facet of free surface against
/// the wall: with only single-fluid-node simplices dropped, the surface
/// particles along the side walls of a 3D tank at rest started at −g/5.) The
/// contact at and below the water line, a front's contact with the floor
/// ahead of it and with a wall it runs into at its own height keep their
/// simplices. (A first version without the `up` condition also dropped the
/// floor ahead of a front and delayed contacts with walls facing a front:
/// the square column's front error rose from 4.1 % to 5.9 % and the
/// obstacle's peak force from 524 to 954 N/m.)
///
/// With `cut` ([`AlphaShapeParams::cut_dry_bridges`], with the particles
/// to cut against, `None` for every solid one), a simplex with a
/// *solid* node above the water line of its free-surface fluid nodes (the
/// plane normal to `up` through their mean height) is not judged by that
/// rule but cut there: it stays, listed in the returned cuts with the mask
/// of its surface nodes, and is integrated only below the line (dropped
/// when nothing of it lies below). A floating body's particles lie
/// anywhere with respect to the water's rows, and the rule's half-spacing
/// threshold made the last surface particle beside it start at 1.8 m/s²
/// and toggle its simplex from step to step (issue 19). Walls keep the
/// rule: cutting at walls too gives the contact-line particle a weight
/// that follows its height, a spring that raised the standing wave's
/// frequency by 1 % at every resolution (measured; the rule converges to
/// linear theory at order 2.6).
#[allow(clippy::too_many_arguments)] // the alpha shape's arrays, passed through
fn drop_dry_bridges<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    spacing: &[f64],
    delaunay: &Tessellation,
    sealed: &[bool],
    up: &Vector<D>,
    cut: Option<Option<&[bool]>>,
    decided: &mut [(f64, u8)],
) -> (bool, Vec<Vector<D>>, Vec<(u32, u8, f64)>)
where
    Const<D>: Dim,
{
    let nv = <Const<D> as Dim>::NV;
    let ns = decided.len();
    let fluid = |v: u32| kinds[v as usize] == ParticleKind::Fluid;
    // Outward normals of the fluid-only boundary facets, per particle.
    let mut normal: Vec<Vector<D>> = Vec::new();
    let mut grads = [Vector::<D>::zeros(); MAX_NV];
    for s in 0..ns {
        if decided[s].1 != KEPT {
            continue;
        }
        let simplex = delaunay.simplex(s);
        if !simplex.iter().any(|&v| fluid(v)) {
            continue;
        }
        let nb = delaunay.simplex_neighbors(s);
        let mut p = [Point::<D>::zeros(); MAX_NV];
        let mut vol = f64::NAN;
        for k in 0..nv {
            let t = nb[k] as usize;
            let boundary = t >= ns || (decided[t].1 != KEPT && sealed.get(t) != Some(&true));
            if !boundary || !(0..nv).filter(|&a| a != k).all(|a| fluid(simplex[a])) {
                continue;
            }
            if vol.is_nan() {
                for a in 0..nv {
                    p[a] = points[simplex[a] as usize];
                }
                match pfem_core::shape_gradients::<D>(&p[..nv], &mut grads[..nv]) {
                    Some(v) => vol = v,
                    None => break,
                }
            }
            if normal.is_empty() {
                normal = vec![Vector::<D>::zeros(); points.len()];
            }
            // −V ∇W_k: the facet's outward normal times its measure / D.
            let share = grads[k] * (-vol);
            for a in (0..nv).filter(|&a| a != k) {
                normal[simplex[a] as usize] += share;
            }
        }
    }
    if normal.is_empty() {
        return (false, normal, Vec::new());
    }
    let mut any = false;
    let mut cuts: Vec<(u32, u8, f64)> = Vec::new();
    // The solid particles a bridge may be cut against: none without `cut`,
    // every one with `Some(None)`, those listed with `Some(Some(list))`.
    let against = |v: usize| {
        kinds[v] == ParticleKind::Solid
            && cut.is_some_and(|c| c.is_none_or(|c| c.get(v) == Some(&true)))
    };
    for s in 0..ns {
        if decided[s].1 != KEPT {
            continue;
        }
        let simplex = delaunay.simplex(s);
        // Every fluid node on the free surface (in 2D a kept triangle has a
        // single one there; in 3D a tetrahedron may rest two or three
        // surface particles against the wall above the water line).
        let mut fl = [0usize; MAX_NV];
        let mut nf = 0;
        for a in 0..nv {
            if fluid(simplex[a]) {
                fl[nf] = a;
                nf += 1;
            }
        }
        if nf == 0
            || nf == nv
            || fl[..nf]
                .iter()
                .any(|&a| normal[simplex[a] as usize] == Vector::<D>::zeros())
        {
            continue;
        }
        let mut p = [Point::<D>::zeros(); MAX_NV];
        for b in 0..nv {
            p[b] = points[simplex[b] as usize];
        }
        // Cut at the water line through its surface nodes when a solid node
        // lies above it (dropped when nothing lies below).
        let mask = fl[..nf].iter().fold(0u8, |m, &a| m | (1 << a));
        let level = fl[..nf].iter().map(|&a| p[a].dot(up)).sum::<f64>() / nf as f64;
        // A water line: every surface node's free surface faces up (a
        // front running into a body is left to the rule).
        let facing_up = fl[..nf].iter().all(|&a| {
            let n = normal[simplex[a] as usize];
            n.dot(up) >= WATER_LINE_COS * n.norm()
        });
        if cut.is_some()
            && facing_up
            && (0..nv).any(|b| against(simplex[b] as usize) && p[b].dot(up) > level)
        {
            let (frac, _) = pfem_core::below_water_line::<D>(&p[..nv], mask, up);
            if frac > 0.0 {
                cuts.push((s as u32, mask, frac));
            } else {
                decided[s].1 = DROPPED;
                any = true;
            }
            continue;
        }
        // A wall or solid node above and outside the free surface, seen
        // from each of its fluid nodes.
        let dry = (0..nv).filter(|&b| !fluid(simplex[b])).any(|b| {
            fl[..nf].iter().all(|&a| {
                let f = simplex[a] as usize;
                above_and_outside(&p[b], &p[a], &normal[f], up, spacing[f])
            })
        });
        if dry {
            decided[s].1 = DROPPED;
            any = true;
        }
    }
    (any, normal, cuts)
}

/// Marks the slivers of `decided` (what [`decide`] returned per simplex)
/// that lie in *sealed voids*: connected (through shared facets) groups of
/// slivers whose every outer facet meets a kept simplex or, when it meets
/// anything else (a dropped simplex, the hull), has no fluid node (it lies
/// on a wall or a structure). Returns the per-simplex flag and the number
/// of sealed slivers.
fn sealed_voids<const D: usize>(
    kinds: &[ParticleKind],
    delaunay: &Tessellation,
    decided: &[(f64, u8)],
) -> (Vec<bool>, usize)
where
    Const<D>: Dim,
{
    let ns = decided.len();
    let verdict = |s: usize| decided[s].1;
    let mut sealed = vec![false; ns];
    let mut seen = vec![false; ns];
    let mut group: Vec<u32> = Vec::new();
    let mut stack: Vec<u32> = Vec::new();
    let mut count = 0usize;
    for start in 0..ns {
        if verdict(start) != SLIVER || seen[start] {
            continue;
        }
        group.clear();
        stack.push(start as u32);
        seen[start] = true;
        let mut closed = true;
        while let Some(s) = stack.pop() {
            let s = s as usize;
            group.push(s as u32);
            let vs = delaunay.simplex(s);
            for (k, &t) in delaunay.simplex_neighbors(s).iter().enumerate() {
                let inside = (t as usize) < ns;
                if inside && verdict(t as usize) == SLIVER {
                    if !seen[t as usize] {
                        seen[t as usize] = true;
                        stack.push(t);
                    }
                    continue;
                }
                if inside && verdict(t as usize) == KEPT {
                    continue;
                }
                let wet = <Const<D> as Dim>::facet(k)
                    .iter()
                    .any(|&l| kinds[vs[l] as usize] == ParticleKind::Fluid);
                if wet {
                    closed = false;
                }
            }
        }
        if closed {
            count += group.len();
            for &s in &group {
                sealed[s as usize] = true;
            }
        }
    }
    (sealed, count)
}

/// Appends the wall pockets of the tessellation and their weights to `out`
/// and `weights` (see [`AlphaShape::wall_pockets`]): from each non-flat
/// wall-only simplex within the alpha reach, the simplices across shared
/// facets whose far vertex lies within `δ = R/10` of its circumsphere are
/// walked (its lattice cell), and the nearest fluid vertex found sets the
/// weight. With `dry = (up, free-surface normals)`, a fluid vertex that
/// sees a pocket vertex as a dry bridge would (above and outside it) does
/// not count: that cell is above the water line.
#[allow(clippy::too_many_arguments)]
fn wall_pockets<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    spacing: &[f64],
    delaunay: &Tessellation,
    decided: &[(f64, u8)],
    alpha: f64,
    dry: Option<(&Vector<D>, &[Vector<D>])>,
    out: &mut Vec<u32>,
    weights: &mut Vec<f64>,
) where
    Const<D>: Dim,
{
    const BAND: f64 = 0.1;
    const CELL: usize = 32;
    let nv = <Const<D> as Dim>::NV;
    let ns = decided.len();
    let wall = |v: u32| kinds[v as usize] == ParticleKind::Wall;
    let found: Vec<f64> = (0..ns)
        .into_par_iter()
        .with_min_len(2048)
        .map(|s| {
            let simplex = delaunay.simplex(s);
            if decided[s].1 != DROPPED || !simplex.iter().all(|&v| wall(v)) {
                return 0.0;
            }
            let p = gather::<D>(points, simplex);
            let (measure, r2, offset) = measure_and_circumcentre::<D>(&p[..nv]);
            let r_d = if D == 2 { r2 } else { r2 * r2.sqrt() };
            let ah = alpha * simplex_spacing(spacing, simplex);
            if !(measure > MIN_SHAPE_QUALITY * r_d && r2 <= ah * ah) {
                return 0.0;
            }
            let (centre, r) = (p[0] + offset, r2.sqrt());
            let delta = BAND * r;
            let gap = |v: u32| ((points[v as usize] - centre).norm() - r).abs();
            let mut nearest = f64::INFINITY;
            // A fluid vertex on the free surface with a pocket vertex above
            // and outside it (the dry-bridge test) does not make a pocket:
            // the cell lies above the water line.
            let dry_of = |f: u32| {
                let f = f as usize;
                let Some((up, normals)) = dry else {
                    return false;
                };
                let Some(n) = normals.get(f).filter(|n| **n != Vector::<D>::zeros()) else {
                    return false;
                };
                p[..nv]
                    .iter()
                    .any(|w| above_and_outside(w, &points[f], n, up, spacing[f]))
            };
            // Walk the cell: simplices across facets whose far vertex is on
            // the sphere.
            let mut cell = [0u32; CELL];
            let (mut len, mut head) = (1, 0);
            cell[0] = s as u32;
            while head < len {
                let t = cell[head] as usize;
                head += 1;
                let ts = delaunay.simplex(t);
                for &u in delaunay.simplex_neighbors(t) {
                    if (u as usize) >= ns || cell[..len].contains(&u) {
                        continue;
                    }
                    let Some(&apex) = delaunay
                        .simplex(u as usize)
                        .iter()
                        .find(|v| !ts.contains(v))
                    else {
                        continue;
                    };
                    let g = gap(apex);
                    if g > delta {
                        continue;
                    }
                    if kinds[apex as usize] == ParticleKind::Fluid {
                        if !dry_of(apex) {
                            nearest = nearest.min(g);
                        }
                        continue;
                    }
                    if len < CELL {
                        cell[len] = u;
                        len += 1;
                    }
                }
            }
            if nearest <= delta {
                1.0 - nearest / delta
            } else {
                0.0
            }
        })
        .collect();
    for (s, &w) in found.iter().enumerate() {
        if w > 0.0 {
            out.extend_from_slice(delaunay.simplex(s));
            weights.push(w);
        }
    }
}

/// Smallest `measure / Rᴰ` (`R` the circumradius) of a kept simplex: flatter
/// ones (slivers) are never kept by the alpha shape. The regular triangle
/// has `3√3/4 ≈ 1.3`, the regular tetrahedron `8/(9√3) ≈ 0.51`, a Kuhn
/// tetrahedron of a cubic lattice `≈ 0.26`.
pub const MIN_SHAPE_QUALITY: f64 = 1e-3;

/// The dry-bridge test of one wall or solid node `w` seen from a fluid
/// node `f` on the free surface (outward normal `n`, not normalised): `w`
/// lies more than half `f`'s spacing above `f` (along `up`) and outside
/// the free surface. Shared by [`drop_dry_bridges`] and [`wall_pockets`].
#[inline]
fn above_and_outside<const D: usize>(
    w: &Point<D>,
    f: &Point<D>,
    n: &Vector<D>,
    up: &Vector<D>,
    spacing_f: f64,
) -> bool
where
    Const<D>: Dim,
{
    let (d, reach) = (w - f, 0.5 * spacing_f);
    d.dot(up) > reach && d.dot(&n.normalize()) > reach
}

/// Signed measure and squared circumradius of a simplex (`∞` when
/// degenerate). The circumcentre offset `c` from `p[0]` solves
/// `2 Eᵀ c = (|e_k|²)_k`, `E` the edge matrix; small fixed-size inverses
/// are closed-form in nalgebra.
#[inline]
pub(crate) fn measure_and_circumradius2<const D: usize>(p: &[Point<D>]) -> (f64, f64)
where
    Const<D>: Dim,
{
    let (measure, r2, _) = measure_and_circumcentre::<D>(p);
    (measure, r2)
}

/// [`measure_and_circumradius2`] with the circumcentre's offset from
/// `p[0]` (zero when degenerate).
#[inline]
fn measure_and_circumcentre<const D: usize>(p: &[Point<D>]) -> (f64, f64, Vector<D>)
where
    Const<D>: Dim,
{
    let e = edge_matrix::<D>(p);
    let det = e.determinant();
    let measure = det * <Const<D> as Dim>::MEASURE_FACTOR;
    let none = (measure, f64::INFINITY, Vector::<D>::zeros());
    if !(det.is_finite() && det != 0.0) {
        return none;
    }
    let Some(inv) = e.transpose().try_inverse() else {
        return none;
    };
    let mut rhs = Vector::<D>::zeros();
    for k in 0..D {
        rhs[k] = e.column(k).norm_squared();
    }
    let c = inv * rhs * 0.5;
    let r2 = c.norm_squared();
    if r2.is_finite() {
        (measure, r2, c)
    } else {
        none
    }
}

/// The alpha shape of paper §8 of a Delaunay tessellation, allocating.
/// See [`alpha_shape_into`].
pub fn alpha_shape<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    spacing: &[f64],
    delaunay: &Tessellation,
    params: &AlphaShapeParams,
) -> Result<AlphaShape, GeometryError>
where
    Const<D>: Dim,
{
    let mut out = AlphaShape::default();
    alpha_shape_into(points, kinds, spacing, delaunay, params, &mut out)?;
    Ok(out)
}

/// The alpha shape of paper §8, written into `out` (allocations reused).
///
/// A Delaunay simplex is a *fluid candidate* when at least one of its nodes
/// is [`ParticleKind::Fluid`]; simplices of wall particles only, of solid
/// particles only (a solid keeps its own mesh, which the driver supplies) or
/// bridging solids and walls without a fluid node are never kept. A
/// candidate is kept when it is positively oriented, not a sliver
/// (`measure > MIN_SHAPE_QUALITY · Rᴰ`) and its circumradius
/// satisfies `R ≤ α·h` (§8), `h` the largest of its nodes' `spacing` (see
/// `simplex_spacing`).
///
/// *Sealed voids* (3D). A sliver is never an element (any motion would invert
/// it), but the hole it leaves is not a gap in the fluid: it holds no
/// volume. Slivers whose edges are all within the alpha reach (`≤ 2αh`)
/// are grouped through shared facets; a group whose every outer facet meets
/// a kept simplex, or else has no fluid node (it lies on a wall or a
/// structure), is a sealed void, and the kept simplices' facets against it
/// get the neighbour [`SEALED`] instead of [`NO_NEIGHBOR`]: they are not
/// boundary, so [`classify`](crate::classify()) does not make the particles
/// around it free-surface ones. Lattices built from different origins
/// produce such slivers by last-bit rounding (`0.04` against
/// `0.039999999999999994`) in 3D scenes. Open slivers, with a wet
/// facet on the outside, leave their kept neighbours' facets on the
/// boundary.
///
/// The per-simplex test runs in parallel (rayon); the sums are taken
/// sequentially so results are bitwise reproducible.
pub fn alpha_shape_into<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    spacing: &[f64],
    delaunay: &Tessellation,
    params: &AlphaShapeParams,
    out: &mut AlphaShape,
) -> Result<(), GeometryError>
where
    Const<D>: Dim,
{
    alpha_shape_cutting_into(points, kinds, spacing, delaunay, params, None, out)
}

/// [`alpha_shape_into`], with the solid particles a dry bridge may be cut
/// against ([`AlphaShapeParams::cut_dry_bridges`]): particle `i` when
/// `cut_against[i]` (particles past the slice's end never); `None` cuts
/// against every solid particle. The driver passes its free solids' particles:
/// a clamped structure keeps the half-spacing rule, as walls do.
#[allow(clippy::too_many_arguments)] // the alpha shape's arrays, passed through
pub fn alpha_shape_cutting_into<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    spacing: &[f64],
    delaunay: &Tessellation,
    params: &AlphaShapeParams,
    cut_against: Option<&[bool]>,
    out: &mut AlphaShape,
) -> Result<(), GeometryError>
where
    Const<D>: Dim,
{
    params.validate()?;
    check_particles(points, kinds, spacing)?;
    check_tessellation::<D>(delaunay, points.len())?;
    let nv = <Const<D> as Dim>::NV;
    let ns = delaunay.simplices.len() / nv;
    // No fluid particle (a scene of solids in contact): nothing can be
    // kept, and the passes below (per simplex, and in 3D the sealed voids'
    // and wall pockets' searches over every wall-only simplex) would find
    // nothing (session 42's review).
    if !kinds.contains(&ParticleKind::Fluid) {
        out.kept.clear();
        out.kept.resize(ns, false);
        out.source.clear();
        out.candidate_measure = 0.0;
        out.kept_measure = 0.0;
        out.sealed = 0;
        out.closures.clear();
        out.wall_pockets.clear();
        out.pocket_weights.clear();
        out.surface_cuts.clear();
        out.mesh.nv = nv;
        out.mesh.simplices.clear();
        out.mesh.neighbors.clear();
        return Ok(());
    }
    let alpha = params.alpha;
    // The sliver test: flat to round-off in 2D, below the element quality
    // in 3D (`AlphaShapeParams::min_quality_3d`).
    let quality = if D == 3 {
        params.min_quality_3d.max(MIN_SHAPE_QUALITY)
    } else {
        MIN_SHAPE_QUALITY
    };

    // Candidate measure and verdict per simplex.
    let mut decided = vec![(0.0f64, DROPPED); ns];
    delaunay
        .simplices
        .par_chunks(nv)
        .zip(decided.par_iter_mut())
        .with_min_len(2048)
        .for_each(|(s, out)| {
            *out = decide::<D>(points, kinds, spacing, s, alpha, quality);
        });
    // 3D only: a 2D square lattice makes no flat triangles, and in 2D a
    // sealed void next to a wall would break the boundary loops that
    // `classify` walks (it was tried: the square column improved, the
    // loop-count property test failed on random clouds).
    let (sealed, n_sealed) = if D == 3 {
        sealed_voids::<D>(kinds, delaunay, &decided)
    } else {
        (Vec::new(), 0)
    };

    // Dry bridges are found with the sealed voids in place (a facet
    // against a sealed void is not free surface); dropping one can open a
    // void it closed, so the voids are sealed again on the final verdicts.
    let up = params
        .up
        .filter(|_| params.drop_dry_bridges)
        .map(|u| Vector::<D>::from_fn(|k, _| u[k]));
    let (dropped, normals, cuts) = match up {
        Some(up) => drop_dry_bridges::<D>(
            points,
            kinds,
            spacing,
            delaunay,
            &sealed,
            &up,
            params.cut_dry_bridges.then_some(cut_against),
            &mut decided,
        ),
        None => (false, Vec::new(), Vec::new()),
    };
    let (sealed, n_sealed) = if dropped && D == 3 {
        sealed_voids::<D>(kinds, delaunay, &decided)
    } else {
        (sealed, n_sealed)
    };

    out.kept.clear();
    out.kept.reserve(ns);
    out.source.clear();
    out.candidate_measure = 0.0;
    out.kept_measure = 0.0;
    out.sealed = n_sealed;
    out.closures.clear();
    out.wall_pockets.clear();
    out.pocket_weights.clear();
    out.surface_cuts.clear();
    // 3D only, like the sealed voids: a 2D lattice tank at rest keeps its
    // ties (measured 1e-14 √(gH) over 5 s without pockets), and counting
    // the corner squares in 2D moved the dam break's jet at a/14 (front
    // against the experiment 1.65 % → 2.01 % RMS) for no gain.
    if D == 3 {
        wall_pockets::<D>(
            points,
            kinds,
            spacing,
            delaunay,
            &decided,
            alpha,
            up.as_ref().map(|up| (up, normals.as_slice())),
            &mut out.wall_pockets,
            &mut out.pocket_weights,
        );
    }
    // Delaunay simplex → mesh simplex (SEALED across a sealed void).
    let mut new_index = vec![NO_NEIGHBOR; ns];
    for (s, &(m, v)) in decided.iter().enumerate() {
        let keep = v == KEPT;
        out.kept.push(keep);
        out.candidate_measure += m;
        if keep {
            out.kept_measure += m;
            new_index[s] = out.source.len() as u32;
            out.source.push(s as u32);
        } else if sealed.get(s) == Some(&true) {
            new_index[s] = SEALED;
            out.closures.extend_from_slice(delaunay.simplex(s));
        }
    }
    // Cuts of simplices that stayed kept (a cut is never dropped later);
    // the kept measure counts their part below the water line.
    for &(s, mask, frac) in &cuts {
        let m = new_index[s as usize];
        if m != NO_NEIGHBOR && m != SEALED {
            out.surface_cuts.push((m, mask));
            out.kept_measure -= (1.0 - frac) * decided[s as usize].0;
        }
    }
    let mesh = &mut out.mesh;
    mesh.nv = nv;
    mesh.simplices.clear();
    mesh.neighbors.clear();
    mesh.simplices.reserve(out.source.len() * nv);
    mesh.neighbors.reserve(out.source.len() * nv);
    for &s in &out.source {
        let s = s as usize;
        mesh.simplices.extend_from_slice(delaunay.simplex(s));
        for &t in delaunay.simplex_neighbors(s) {
            mesh.neighbors.push(if (t as usize) < ns {
                new_index[t as usize]
            } else {
                NO_NEIGHBOR
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kept tetrahedron `A` with a flat sliver `B` glued to one facet;
    /// `B`'s other facets are wet and on the hull, so `B` is an open sliver:
    /// the shared facet stays boundary. (Sealed voids in a real scene:
    /// `sliver_holes_in_a_3d_tank_are_not_free_surface` in `tests/three_d.rs`.)
    #[test]
    fn an_open_sliver_leaves_the_facet_on_the_boundary() {
        let p = [
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(1.0, 0.0, 0.0),
            Point::<3>::new(0.0, 1.0, 0.0),
            Point::<3>::new(0.0, 0.0, 1.0),
            // In the plane x + y + z = 1 of the shared facet: B is flat.
            Point::<3>::new(0.7, 0.7, -0.4),
        ];
        let kinds = [ParticleKind::Fluid; 5];
        let spacing = [1.0; 5];
        let tess = Tessellation {
            nv: 4,
            simplices: vec![0, 1, 2, 3, 1, 2, 3, 4],
            neighbors: vec![1, NO_NEIGHBOR, NO_NEIGHBOR, NO_NEIGHBOR]
                .into_iter()
                .chain([NO_NEIGHBOR, NO_NEIGHBOR, NO_NEIGHBOR, 0])
                .collect(),
        };
        let params = AlphaShapeParams::default();
        let a = alpha_shape::<3>(&p, &kinds, &spacing, &tess, &params).unwrap();
        assert_eq!(a.kept, vec![true, false]);
        assert_eq!(a.sealed, 0);
        assert_eq!(a.mesh.neighbors, vec![NO_NEIGHBOR; 4]);
        // The sliver's verdict: flat, with edges inside the alpha reach.
        assert_eq!(
            decide::<3>(&p, &kinds, &spacing, &[1, 2, 3, 4], 1.3, MIN_SHAPE_QUALITY).1,
            SLIVER
        );
        // Too long an edge: merely dropped.
        let mut far = p;
        far[4] = Point::<3>::new(3.0, 3.0, -5.0);
        assert_eq!(
            decide::<3>(
                &far,
                &kinds,
                &spacing,
                &[1, 2, 3, 4],
                1.3,
                MIN_SHAPE_QUALITY
            )
            .1,
            DROPPED
        );
    }
}
