//! The own mesh of a solid body of any geometry: the Delaunay tessellation
//! of the body's particles (through the [`Tessellator`] seam), trimmed by
//! the alpha shape of §8 and cleaned of boundary slivers.
//!
//! Box solids keep the structured mesh of [`crate::lattice::box_simplices`];
//! every other geometry (cylinders, balls, the user's particles) is meshed
//! here, once, when the simulation is built. The mesh never changes after
//! that: a solid is not remeshed (§8), its stress history lives on its
//! elements.
//!
//! ```
//! use pfem_scene::lattice::cylinder_points;
//! use pfem_scene::solid_mesh::{solid_mesh, SolidMeshParams};
//! use pfem_geometry::Delaunay3;
//! use pfem_core::Point;
//!
//! let h = 0.0075;
//! let pts = cylinder_points::<3>(&Point::<3>::zeros(), 1, 0.015, 0.15, h)?;
//! let m = solid_mesh::<3>(&pts, h, &mut Delaunay3::default(), &SolidMeshParams::default())?;
//! assert_eq!(m.simplices.len() % 4, 0);
//! assert!(m.volume > 0.0);
//! # Ok::<(), pfem_scene::SceneError>(())
//! ```

use pfem_core::{simplex_measure, Const, Dim, ParticleKind, Point, MAX_NV};
use pfem_geometry::{alpha_shape, radius_ratio, AlphaShapeParams, Tessellation, Tessellator};

use crate::SceneError;

/// Parameters of [`solid_mesh`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidMeshParams {
    /// Alpha of the alpha shape that trims the Delaunay tessellation to the
    /// body (§8; dimensionless, > 0). Default `1.3`.
    pub alpha: f64,
    /// Simplices on the mesh boundary whose normalised radius ratio
    /// ([`radius_ratio`], `1` for the regular simplex) is below this are
    /// dropped when that keeps the mesh valid (every particle still in an
    /// element, no interior hole). `0` keeps every simplex. Default `0.05`.
    pub sliver_ratio: f64,
}

impl Default for SolidMeshParams {
    fn default() -> Self {
        Self {
            alpha: 1.3,
            sliver_ratio: 0.05,
        }
    }
}

/// The mesh of one solid body, in the body's own particle numbering.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolidMesh {
    /// Flat connectivity, `D + 1` local particle indices per simplex,
    /// positively oriented.
    pub simplices: Vec<u32>,
    /// Total measure of the simplices (m³; m² in 2D).
    pub volume: f64,
    /// Slivers dropped (below [`SolidMeshParams::sliver_ratio`]).
    pub slivers_dropped: usize,
    /// Slivers kept because dropping them would have left a particle out
    /// of every element or opened a hole inside the body.
    pub slivers_kept: usize,
    /// Smallest radius ratio of the kept simplices.
    pub min_radius_ratio: f64,
}

/// Meshes a solid body's particles `points` (spacing `h`): Delaunay by
/// `tessellator`, the alpha shape with every particle treated as fluid just
/// for this call (a solid-only simplex is otherwise never a candidate),
/// then boundary slivers dropped when that keeps the mesh valid.
///
/// Errors when the tessellation fails or a particle is left out of every
/// element (the body's particles are too sparse for `alpha`).
pub fn solid_mesh<const D: usize>(
    points: &[Point<D>],
    h: f64,
    tessellator: &mut dyn Tessellator<D>,
    params: &SolidMeshParams,
) -> Result<SolidMesh, SceneError>
where
    Const<D>: Dim,
{
    match mesh_or_orphans(points, h, tessellator, params)? {
        Ok(mesh) => Ok(mesh),
        Err(orphans) => Err(orphan_error(points, orphans[0], params)),
    }
}

/// At most this fraction of a solid's particles may be left out of its
/// mesh by [`solid_mesh_pruned`]; beyond it the particles are too sparse
/// for the alpha shape, not a corner's.
pub const MAX_PRUNED_FRACTION: f64 = 0.05;

/// [`solid_mesh`], leaving out the particles that no element holds (a
/// lattice filling a sharp corner of a polygon ends in a row of particles
/// one spacing wide, which no simplex of the alpha shape joins, however
/// fine the spacing) and meshing the rest again, until every particle is
/// in an element. Returns the mesh, numbered over the kept particles, and
/// the indices in `points` of those left out (increasing). Refused as
/// [`solid_mesh`] is when more than [`MAX_PRUNED_FRACTION`] of the
/// particles would go.
pub fn solid_mesh_pruned<const D: usize>(
    points: &[Point<D>],
    h: f64,
    tessellator: &mut dyn Tessellator<D>,
    params: &SolidMeshParams,
) -> Result<(SolidMesh, Vec<usize>), SceneError>
where
    Const<D>: Dim,
{
    let mut kept: Vec<usize> = (0..points.len()).collect();
    let limit = (MAX_PRUNED_FRACTION * points.len() as f64).floor() as usize;
    loop {
        let sub: Vec<Point<D>> = kept.iter().map(|&i| points[i]).collect();
        match mesh_or_orphans(&sub, h, tessellator, params)? {
            Ok(mesh) => {
                let mut is_kept = vec![false; points.len()];
                for &i in &kept {
                    is_kept[i] = true;
                }
                let left = (0..points.len()).filter(|&i| !is_kept[i]).collect();
                return Ok((mesh, left));
            }
            Err(orphans) => {
                if points.len() - kept.len() + orphans.len() > limit {
                    return Err(orphan_error(points, kept[orphans[0]], params));
                }
                let mut out = vec![false; sub.len()];
                for &o in &orphans {
                    out[o] = true;
                }
                kept = kept
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| !out[*k])
                    .map(|(_, &i)| i)
                    .collect();
            }
        }
    }
}

fn orphan_error<const D: usize>(
    points: &[Point<D>],
    i: usize,
    params: &SolidMeshParams,
) -> SceneError
where
    Const<D>: Dim,
{
    SceneError::Mesh {
        why: format!(
            "solid mesh: its particle {} (counting from 1), at {:?}, is in no element (particles too sparse for alpha = {})",
            i + 1,
            points[i].as_slice(),
            params.alpha
        ),
    }
}

/// The mesh, or the particles in no element (increasing).
fn mesh_or_orphans<const D: usize>(
    points: &[Point<D>],
    h: f64,
    tessellator: &mut dyn Tessellator<D>,
    params: &SolidMeshParams,
) -> Result<Result<SolidMesh, Vec<usize>>, SceneError>
where
    Const<D>: Dim,
{
    let nv = D + 1;
    let err = |why: String| SceneError::Mesh { why };
    let mut tess = Tessellation::new(nv);
    tessellator
        .tessellate(points, &mut tess)
        .map_err(|e| err(format!("solid mesh: {e}")))?;
    let kinds = vec![ParticleKind::Fluid; points.len()];
    let spacing = vec![h; points.len()];
    let shape = alpha_shape(
        points,
        &kinds,
        &spacing,
        &tess,
        &AlphaShapeParams {
            alpha: params.alpha,
            // A solid's own mesh has no free surface against walls.
            drop_dry_bridges: false,
            cut_dry_bridges: false,
            up: None,
            // A solid's mesh is made once: keep it as it always was.
            min_quality_3d: pfem_geometry::MIN_SHAPE_QUALITY,
        },
    )
    .map_err(|e| err(format!("solid mesh: {e}")))?;
    let mesh = shape.mesh;
    let ns = mesh.len();
    let corners = |s: usize| {
        let mut p = [Point::<D>::zeros(); MAX_NV];
        for (a, &v) in mesh.simplex(s).iter().enumerate() {
            p[a] = points[v as usize];
        }
        p
    };
    let ratio: Vec<f64> = (0..ns)
        .map(|s| radius_ratio::<D>(&corners(s)[..nv]))
        .collect();
    // Elements per particle, to keep every particle in an element.
    let mut valence = vec![0u32; points.len()];
    for &v in &mesh.simplices {
        valence[v as usize] += 1;
    }
    let orphans: Vec<usize> = (0..points.len()).filter(|&i| valence[i] == 0).collect();
    if !orphans.is_empty() {
        return Ok(Err(orphans));
    }
    // Drop boundary slivers one at a time, worst first; a simplex is on the
    // boundary when one of its facets has no kept neighbour (NO_NEIGHBOR,
    // or SEALED: a sliver hole inside the solid counts as boundary here).
    let mut kept = vec![true; ns];
    let mut order: Vec<usize> = (0..ns)
        .filter(|&s| ratio[s] < params.sliver_ratio)
        .collect();
    order.sort_by(|&a, &b| ratio[a].total_cmp(&ratio[b]));
    let (mut dropped, mut refused) = (0, 0);
    for s in order {
        let on_boundary = mesh
            .simplex_neighbors(s)
            .iter()
            .any(|&n| n as usize >= ns || !kept[n as usize]);
        let orphans = mesh.simplex(s).iter().any(|&v| valence[v as usize] <= 1);
        if on_boundary && !orphans {
            kept[s] = false;
            for &v in mesh.simplex(s) {
                valence[v as usize] -= 1;
            }
            dropped += 1;
        } else {
            refused += 1;
        }
    }
    let mut out = SolidMesh {
        slivers_dropped: dropped,
        slivers_kept: refused,
        min_radius_ratio: f64::INFINITY,
        ..Default::default()
    };
    for s in (0..ns).filter(|&s| kept[s]) {
        out.simplices.extend_from_slice(mesh.simplex(s));
        out.volume += simplex_measure::<D>(&corners(s)[..nv]);
        out.min_radius_ratio = out.min_radius_ratio.min(ratio[s]);
    }
    Ok(Ok(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::{ball_points, box_points, cylinder_points};
    use pfem_geometry::{Delaunay2, Delaunay3};

    #[test]
    fn a_box_is_meshed_to_its_volume() {
        let (min, max) = (
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(0.1, 0.05, 0.02),
        );
        let h = 0.01;
        let pts = box_points::<3>(&min, &max, h).unwrap();
        let m = solid_mesh::<3>(&pts, h, &mut Delaunay3::default(), &Default::default()).unwrap();
        assert!((m.volume - 1e-4).abs() < 1e-12, "{}", m.volume);
        assert!(m.min_radius_ratio > 0.0);
    }

    #[test]
    fn a_cylinder_mesh_is_valid_and_close_to_its_lattice_volume() {
        let h = 0.0075;
        let (r, l) = (0.015, 0.15);
        let pts = cylinder_points::<3>(&Point::<3>::zeros(), 1, r, l, h).unwrap();
        let m = solid_mesh::<3>(&pts, h, &mut Delaunay3::default(), &Default::default()).unwrap();
        let mut used = vec![false; pts.len()];
        for &v in &m.simplices {
            used[v as usize] = true;
        }
        assert!(used.iter().all(|&u| u), "every particle in an element");
        for c in m.simplices.chunks(4) {
            let p: Vec<Point<3>> = c.iter().map(|&v| pts[v as usize]).collect();
            assert!(simplex_measure::<3>(&p) > 0.0);
        }
        // The lattice disk (13 nodes at r = 2h) is meshed to its convex
        // hull, an octagon of area 8 h²; the mesh is that prism.
        let expected = 8.0 * h * h * l;
        assert!(
            (m.volume - expected).abs() < 1e-3 * expected,
            "{} vs {expected}",
            m.volume
        );
    }

    #[test]
    fn a_disk_in_2d() {
        let h = 0.01;
        let pts = ball_points::<2>(&Point::<2>::zeros(), 0.05, h).unwrap();
        let m = solid_mesh::<2>(&pts, h, &mut Delaunay2::default(), &Default::default()).unwrap();
        let area = std::f64::consts::PI * 0.05 * 0.05;
        assert!(m.volume > 0.8 * area && m.volume <= area, "{}", m.volume);
    }
}
