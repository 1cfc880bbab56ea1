//! Boundary classification of the fluid mesh (paper §8): boundary facets
//! and nodes, node tags, isolated particles, connected components and, in
//! 2D, boundary loops.

use pfem_core::{simplex_measure, Const, Dim, ParticleKind, Point, MAX_NV};

use rayon::prelude::*;

use crate::alpha::{check_tessellation, gather};
use crate::{GeometryError, Tessellation, NO_NEIGHBOR};

/// What a particle is in the fluid mesh. The rules, from what the node
/// touches:
///
/// | particle kind | in a kept simplex? | on a boundary facet? | tag |
/// |---|---|---|---|
/// | fluid | no | – | [`Isolated`](NodeTag::Isolated) |
/// | fluid | yes | no | [`Interior`](NodeTag::Interior) |
/// | fluid | yes | yes | [`FreeSurface`](NodeTag::FreeSurface) |
/// | wall | yes | any | [`Wall`](NodeTag::Wall) |
/// | solid | yes | any | [`Interface`](NodeTag::Interface) |
/// | wall or solid | no | – | [`Dry`](NodeTag::Dry) |
///
/// A fluid node on the boundary is always on a free-surface facet (every
/// facet with a fluid node is one, see [`FacetKind`]), including at a
/// contact line where the free surface meets a wall or a solid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum NodeTag {
    /// Fluid particle inside the fluid: on no boundary facet.
    Interior,
    /// Fluid particle on the free surface (pressure boundary condition).
    FreeSurface,
    /// Wall particle in contact with the fluid.
    Wall,
    /// Solid particle in contact with the fluid: the fluid–solid interface.
    Interface,
    /// Fluid particle in no kept simplex: a flying drop of one particle.
    Isolated,
    /// Wall or solid particle touching no fluid element.
    Dry,
}

/// What a boundary facet of the fluid mesh lies against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum FacetKind {
    /// At least one node is fluid: free surface.
    FreeSurface,
    /// Only wall nodes: the fluid lies on a wall.
    Wall,
    /// No fluid node and at least one solid node: the fluid lies on a solid.
    Interface,
}

/// A facet of exactly one kept simplex.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoundaryFacet {
    /// The kept simplex (index in [`AlphaShape::mesh`](crate::AlphaShape::mesh)).
    pub simplex: u32,
    /// Local facet index: the facet opposite local vertex `facet`
    /// (`Dim::facet`), with outward orientation.
    pub facet: u8,
    /// What it lies against.
    pub kind: FacetKind,
}

/// A connected component of the kept simplices (simplices joined through
/// shared facets; two simplices sharing only a vertex are not joined).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Component {
    /// Number of simplices.
    pub simplices: u32,
    /// Total measure (area in 2D, volume in 3D).
    pub measure: f64,
}

/// Result of [`classify`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Classification {
    /// Tag of every particle (see [`NodeTag`] for the rules).
    pub tags: Vec<NodeTag>,
    /// Facets of exactly one kept simplex, in simplex order.
    pub boundary_facets: Vec<BoundaryFacet>,
    /// Particles on at least one boundary facet, ascending.
    pub boundary_nodes: Vec<u32>,
    /// Fluid particles in no kept simplex, ascending.
    pub isolated: Vec<u32>,
    /// Component of each kept simplex (index into `components`); components
    /// are numbered in order of their first simplex.
    pub component: Vec<u32>,
    /// The connected components: a detached drop of several particles is a
    /// component of its own.
    pub components: Vec<Component>,
    /// Number of closed boundary loops (2D only; `None` in 3D). A simply
    /// connected blob has one, an annulus two.
    pub boundary_loops: Option<usize>,
    /// With solid elements given: all-solid boundary facets of the fluid
    /// mesh that are not a facet of any solid element (the fluid mesh cuts
    /// across a solid body). Always 0 without solid elements.
    pub unmatched_interface_facets: usize,
}

impl Classification {
    /// Vertex indices of a boundary facet, in outward orientation.
    pub fn facet_nodes<const D: usize>(
        &self,
        mesh: &Tessellation,
        f: &BoundaryFacet,
    ) -> [u32; MAX_NV]
    where
        Const<D>: Dim,
    {
        let s = mesh.simplex(f.simplex as usize);
        let mut out = [u32::MAX; MAX_NV];
        for (o, &l) in out
            .iter_mut()
            .zip(<Const<D> as Dim>::facet(f.facet as usize))
        {
            *o = s[l];
        }
        out
    }
}

/// Sorted facet key (unused entries `u32::MAX`).
fn facet_key<const D: usize>(s: &[u32], k: usize) -> [u32; MAX_NV]
where
    Const<D>: Dim,
{
    let mut key = [u32::MAX; MAX_NV];
    for (o, &l) in key.iter_mut().zip(<Const<D> as Dim>::facet(k)) {
        *o = s[l];
    }
    key[..D].sort_unstable();
    key
}

/// Classifies the fluid mesh (paper §8: "the boundary surface is defined by
/// all the polyhedral surfaces … belonging to just one polyhedron").
///
/// `mesh` is the kept tessellation ([`AlphaShape::mesh`](crate::AlphaShape::mesh)),
/// whose neighbour array marks with [`NO_NEIGHBOR`] every facet that belongs
/// to one kept simplex only: those are the boundary facets (no hashing).
///
/// `solid_elements` is the optional flat connectivity (`D + 1` particle
/// indices per element) of the solid bodies' own meshes. Facet kinds and
/// node tags follow from particle kinds alone (a boundary facet with no
/// fluid node lies on a wall or a solid); the solid elements are used to
/// check the fluid–solid interface: an all-solid boundary facet that is no
/// facet of a solid element is counted in
/// [`Classification::unmatched_interface_facets`] (the fluid mesh overlaps a
/// solid). Matching sorts the solid facets once (`O(m log m)`).
pub fn classify<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    mesh: &Tessellation,
    solid_elements: Option<&[u32]>,
) -> Result<Classification, GeometryError>
where
    Const<D>: Dim,
{
    let mut out = Classification::default();
    classify_into(points, kinds, mesh, solid_elements, &mut out)?;
    Ok(out)
}

/// [`classify`] writing into `out`, reusing its allocations.
pub fn classify_into<const D: usize>(
    points: &[Point<D>],
    kinds: &[ParticleKind],
    mesh: &Tessellation,
    solid_elements: Option<&[u32]>,
    out: &mut Classification,
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
    check_tessellation::<D>(mesh, n)?;
    let nv = <Const<D> as Dim>::NV;
    let ns = mesh.simplices.len() / nv;

    // Solid facets, sorted, for interface matching.
    let solid_facets = match solid_elements {
        None => None,
        Some(el) => {
            if el.len() % nv != 0 {
                return Err(GeometryError::InvalidConnectivity {
                    reason: "solid connectivity length is not a multiple of D + 1",
                });
            }
            if el.iter().any(|&v| v as usize >= n) {
                return Err(GeometryError::InvalidConnectivity {
                    reason: "solid vertex index out of range",
                });
            }
            let mut keys: Vec<[u32; MAX_NV]> = Vec::with_capacity(el.len());
            for s in el.chunks_exact(nv) {
                for k in 0..nv {
                    keys.push(facet_key::<D>(s, k));
                }
            }
            keys.sort_unstable();
            Some(keys)
        }
    };

    // Node flags: bit 0 in a kept simplex, bit 1 on a boundary facet.
    let mut flags = vec![0u8; n];
    out.boundary_facets.clear();
    out.unmatched_interface_facets = 0;
    for (s, (vs, nb)) in mesh
        .simplices
        .chunks_exact(nv)
        .zip(mesh.neighbors.chunks_exact(nv))
        .enumerate()
    {
        for &v in vs {
            flags[v as usize] |= 1;
        }
        for (k, &t) in nb.iter().enumerate() {
            if t != NO_NEIGHBOR {
                continue;
            }
            let (mut fluid, mut solid, mut wall) = (false, false, false);
            for &l in <Const<D> as Dim>::facet(k) {
                let v = vs[l] as usize;
                flags[v] |= 2;
                match kinds[v] {
                    ParticleKind::Fluid => fluid = true,
                    ParticleKind::Solid => solid = true,
                    ParticleKind::Wall => wall = true,
                }
            }
            let kind = if fluid {
                FacetKind::FreeSurface
            } else if solid {
                if let (Some(keys), false) = (&solid_facets, wall) {
                    if keys.binary_search(&facet_key::<D>(vs, k)).is_err() {
                        out.unmatched_interface_facets += 1;
                    }
                }
                FacetKind::Interface
            } else {
                FacetKind::Wall
            };
            out.boundary_facets.push(BoundaryFacet {
                simplex: s as u32,
                facet: k as u8,
                kind,
            });
        }
    }

    out.tags.clear();
    out.boundary_nodes.clear();
    out.isolated.clear();
    out.tags.reserve(n);
    for (i, (&f, &kind)) in flags.iter().zip(kinds).enumerate() {
        let tag = match (kind, f & 1 != 0, f & 2 != 0) {
            (ParticleKind::Fluid, false, _) => NodeTag::Isolated,
            (ParticleKind::Fluid, true, false) => NodeTag::Interior,
            (ParticleKind::Fluid, true, true) => NodeTag::FreeSurface,
            (ParticleKind::Wall, true, _) => NodeTag::Wall,
            (ParticleKind::Solid, true, _) => NodeTag::Interface,
            (_, false, _) => NodeTag::Dry,
        };
        if tag == NodeTag::Isolated {
            out.isolated.push(i as u32);
        }
        if f & 2 != 0 {
            out.boundary_nodes.push(i as u32);
        }
        out.tags.push(tag);
    }

    connected_components::<D>(points, mesh, &mut out.component, &mut out.components);
    out.boundary_loops = if D == 2 {
        Some(count_boundary_loops_2d(mesh, ns))
    } else {
        None
    };
    Ok(())
}

/// Union–find root with path halving.
#[inline]
fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let p = parent[parent[x as usize] as usize];
        parent[x as usize] = p;
        x = p;
    }
    x
}

/// Connected components of the simplices of `mesh` through shared facets.
fn connected_components<const D: usize>(
    points: &[Point<D>],
    mesh: &Tessellation,
    component: &mut Vec<u32>,
    components: &mut Vec<Component>,
) where
    Const<D>: Dim,
{
    let nv = <Const<D> as Dim>::NV;
    let ns = mesh.simplices.len() / nv;
    let mut parent: Vec<u32> = (0..ns as u32).collect();
    for (s, nb) in mesh.neighbors.chunks_exact(nv).enumerate() {
        for &t in nb {
            // NO_NEIGHBOR and SEALED are both ≥ ns: no simplex to join.
            if (t as usize) < ns && (t as usize) > s {
                let (a, b) = (find(&mut parent, s as u32), find(&mut parent, t));
                if a != b {
                    let (lo, hi) = (a.min(b), a.max(b));
                    parent[hi as usize] = lo;
                }
            }
        }
    }
    component.clear();
    component.reserve(ns);
    components.clear();
    // Roots are the smallest simplex of their set, so labels in order of
    // first simplex come out of one forward pass.
    let measures: Vec<f64> = mesh
        .simplices
        .par_chunks(nv)
        .with_min_len(4096)
        .map(|s| simplex_measure::<D>(&gather::<D>(points, s)[..nv]))
        .collect();
    let mut label = vec![u32::MAX; ns];
    for (s, &measure) in measures.iter().enumerate() {
        let r = find(&mut parent, s as u32) as usize;
        if label[r] == u32::MAX {
            label[r] = components.len() as u32;
            components.push(Component {
                simplices: 0,
                measure: 0.0,
            });
        }
        let c = label[r];
        component.push(c);
        let c = &mut components[c as usize];
        c.simplices += 1;
        c.measure += measure;
    }
}

/// Number of closed boundary loops of a 2D mesh: each boundary edge
/// `a → b` (counter-clockwise around its triangle) is followed by the next
/// boundary edge leaving `b`, found by turning around `b` through the kept
/// triangles; the successor map is a permutation whose cycles are the loops
/// (pinch vertices shared by two loops are handled correctly).
fn count_boundary_loops_2d(mesh: &Tessellation, ns: usize) -> usize {
    // Boundary edge id of (simplex, local facet), or u32::MAX.
    let mut id = vec![u32::MAX; 3 * ns];
    let mut edges: Vec<(u32, u8)> = Vec::new();
    for (i, &t) in mesh.neighbors.iter().enumerate() {
        if t == NO_NEIGHBOR {
            id[i] = edges.len() as u32;
            edges.push(((i / 3) as u32, (i % 3) as u8));
        }
    }
    let m = edges.len();
    let mut next = vec![u32::MAX; m];
    for (e, &(s, k)) in edges.iter().enumerate() {
        // Facet k of a ccw triangle runs from local k+1 to local k+2.
        let (mut s, k) = (s as usize, k as usize);
        let b = mesh.simplices[3 * s + (k + 2) % 3];
        // Edge leaving b in s: from local j=(k+2)%3 to j+1, opposite j+2.
        let mut f = (k + 1) % 3;
        let mut guard = 0usize;
        loop {
            let t = mesh.neighbors[3 * s + f];
            if t == NO_NEIGHBOR {
                next[e] = id[3 * s + f];
                break;
            }
            if t as usize >= ns {
                break; // a sealed void: the walk cannot cross it
            }
            s = t as usize;
            let Some(jb) = (0..3).find(|&j| mesh.simplices[3 * s + j] == b) else {
                break; // inconsistent mesh: leave unlinked
            };
            f = (jb + 2) % 3;
            guard += 1;
            if guard > ns {
                break;
            }
        }
    }
    // Count cycles of the successor map.
    let mut seen = vec![false; m];
    let mut loops = 0;
    for start in 0..m {
        if seen[start] {
            continue;
        }
        loops += 1;
        let mut e = start;
        while e != u32::MAX as usize && !seen[e] {
            seen[e] = true;
            e = next[e] as usize;
        }
    }
    loops
}
