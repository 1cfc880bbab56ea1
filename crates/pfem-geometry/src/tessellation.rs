//! The tessellation seam: what the driver calls to turn particles into
//! simplices, so that the built-in 2D and 3D Delaunay tessellators and a
//! user's own mesher plug in the same way.

use pfem_core::{Const, Dim, Point};

use crate::GeometryError;

/// Sentinel in [`Tessellation::neighbors`] for a facet on the convex hull.
pub const NO_NEIGHBOR: u32 = u32::MAX;

/// Sentinel in the neighbours of an alpha-shape mesh
/// ([`AlphaShape::mesh`](crate::AlphaShape::mesh)) for a facet against a
/// *sealed void*: flat slivers that the alpha shape drops from the mesh but
/// that the fluid encloses (see [`alpha_shape_into`](crate::alpha_shape_into)).
/// There is no simplex across such a facet, yet it is not boundary.
pub const SEALED: u32 = u32::MAX - 1;

/// A simplicial tessellation of a point set. Vertex `i` of the tessellation
/// is point `i` of the input: no point is reordered or dropped.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Tessellation {
    /// Vertices per simplex (`D + 1`).
    pub nv: usize,
    /// Connectivity, flat, `nv` point indices per simplex, each simplex
    /// positively oriented (positive signed measure).
    pub simplices: Vec<u32>,
    /// Adjacency, flat, `nv` entries per simplex: entry `k` of simplex `s`
    /// is the simplex across the facet opposite local vertex `k`
    /// (`Dim::facet(k)`), or [`NO_NEIGHBOR`] on the convex hull (in an
    /// alpha-shape mesh also [`SEALED`]).
    pub neighbors: Vec<u32>,
}

impl Tessellation {
    /// An empty tessellation with `nv` vertices per simplex.
    pub fn new(nv: usize) -> Self {
        Self {
            nv,
            simplices: Vec::new(),
            neighbors: Vec::new(),
        }
    }

    /// Number of simplices.
    pub fn len(&self) -> usize {
        self.simplices.len().checked_div(self.nv).unwrap_or(0)
    }

    /// Whether there is no simplex.
    pub fn is_empty(&self) -> bool {
        self.simplices.is_empty()
    }

    /// Vertex indices of simplex `s`.
    pub fn simplex(&self, s: usize) -> &[u32] {
        &self.simplices[s * self.nv..(s + 1) * self.nv]
    }

    /// Neighbours of simplex `s` (see [`Tessellation::neighbors`]).
    pub fn simplex_neighbors(&self, s: usize) -> &[u32] {
        &self.neighbors[s * self.nv..(s + 1) * self.nv]
    }
}

/// Turns a point set into a [`Tessellation`]. Object safe: the driver holds
/// a `Box<dyn Tessellator<D>>`.
///
/// Implementations must keep point `i` as vertex `i`, must never panic on
/// any input (duplicates, collinear or cospherical points, huge or tiny
/// coordinates, non-finite values) and report what they cannot mesh as a
/// typed [`GeometryError`].
pub trait Tessellator<const D: usize>: Send + Sync + std::fmt::Debug
where
    Const<D>: Dim,
{
    /// Tessellates `points` into `out`, reusing its allocations.
    fn tessellate(
        &mut self,
        points: &[Point<D>],
        out: &mut Tessellation,
    ) -> Result<(), GeometryError>;
}

/// [`Tessellator::tessellate`], with a set that has no simplex (fewer than
/// `D + 1` points, or all on one line in 2D or one plane in 3D) given as
/// an empty tessellation instead of [`GeometryError::Degenerate`]: no mesh,
/// so every fluid particle of it flies (§8's isolated particles). Other
/// errors are returned.
pub fn tessellate_or_empty<const D: usize>(
    tessellator: &mut dyn Tessellator<D>,
    points: &[Point<D>],
    out: &mut Tessellation,
) -> Result<(), GeometryError>
where
    Const<D>: Dim,
{
    match tessellator.tessellate(points, out) {
        Err(GeometryError::Degenerate { .. }) => {
            out.nv = D + 1;
            out.simplices.clear();
            out.neighbors.clear();
            Ok(())
        }
        r => r,
    }
}
