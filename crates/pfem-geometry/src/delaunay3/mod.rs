//! Incremental 3D Delaunay tetrahedralisation with exact predicates and
//! symbolic perturbation, written for PFEM's per-step remeshing.
//!
//! The algorithm is the Bowyer–Watson cavity insertion (Bowyer 1981,
//! Watson 1981) over a tessellation closed by an *infinite vertex*, the
//! scheme of CGAL and Geogram described by Boissonnat, Devillers, Pion,
//! Teillaud and Yvinec (2002):
//!
//! 1. points are inserted in a biased randomised order whose rounds follow
//!    a Hilbert curve (BRIO, Amenta, Choi and Rote 2003);
//! 2. each point is located by a visibility walk from the last created
//!    tetrahedron, with exact `orient3d` (Devillers, Pion and Teillaud 2002);
//! 3. the tetrahedra whose circumsphere contains the point (its *cavity*,
//!    found by a breadth-first search from the located tetrahedron) are
//!    replaced by the star of the point on the cavity boundary.
//! 4. the tetrahedra are written along the Hilbert curve of their first
//!    vertex on it, so that consecutive ones are near: a caller numbering
//!    nodes by first appearance (the assembly) numbers neighbours close
//!    together, which made the 3D assembly a third faster at 98k particles
//!    (`docs/benchmarks.md`, session 29).
//!
//! Every in-sphere tie (cospherical points: every cube of a lattice) is
//! broken by the symbolic perturbation of [`predicates`], so the result is
//! the unique Delaunay tessellation of the perturbed points, independent of
//! the insertion order, and each tetrahedron has positive volume.
//!
//! ```
//! use pfem_core::Point;
//! use pfem_geometry::{Delaunay3, Tessellation, Tessellator};
//!
//! // The eight corners of a unit cube and its centre.
//! let mut pts: Vec<Point<3>> = (0..8)
//!     .map(|i| Point::<3>::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
//!     .collect();
//! pts.push(Point::<3>::new(0.5, 0.5, 0.5));
//! let mut mesher = Delaunay3::default();
//! let mut mesh = Tessellation::new(4);
//! mesher.tessellate(&pts, &mut mesh)?;
//! // Each of the 6 faces is split in two and coned to the centre.
//! assert_eq!(mesh.len(), 12);
//! let volume: f64 = (0..mesh.len())
//!     .map(|s| {
//!         let p: Vec<Point<3>> = mesh.simplex(s).iter().map(|&v| pts[v as usize]).collect();
//!         pfem_core::simplex_measure::<3>(&p)
//!     })
//!     .sum();
//! assert!((volume - 1.0).abs() < 1e-12);
//! # Ok::<(), pfem_geometry::GeometryError>(())
//! ```

mod exact;
mod order;
pub mod predicates;

use pfem_core::Point;

use crate::{GeometryError, Tessellation, Tessellator, NO_NEIGHBOR};
use predicates::{collinear, hull_conflict_sos, insphere_sos, orient3d};

/// The infinite vertex, at local index 3 of every infinite tetrahedron.
const INF: u32 = u32::MAX;
/// Marks a free tetrahedron slot (in its vertex 0).
const DEAD: u32 = u32::MAX - 1;
/// Local vertex indices of the facet opposite vertex `k`
/// (`<Const<3> as Dim>::facet(k)`).
const FACET: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// Largest number of points [`Delaunay3`] accepts: neighbour references
/// pack a tetrahedron index and a local facet into a `u32`, and a
/// tessellation of `n` points has about `6.7 n` tetrahedra.
pub const MAX_POINTS: usize = 1 << 27;

/// A facet of the cavity boundary and the new tetrahedron built on it.
#[derive(Debug, Clone, Copy)]
struct BoundaryFacet {
    /// Vertices of the new tetrahedron (the cavity tetrahedron with its
    /// vertex `f` replaced by the new point).
    v: [u32; 4],
    /// Local index of the new point.
    f: u32,
    /// Packed reference (`tet << 2 | facet`) to the outside neighbour.
    nb: u32,
}

/// An entry of the edge table that links the new tetrahedra to each other.
#[derive(Debug, Clone, Copy, Default)]
struct EdgeSlot {
    key: u64,
    val: u32,
    gen: u32,
}

/// A tetrahedron slot.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(32))]
struct Tet {
    /// Vertices; `INF` at index 3 for infinite tetrahedra, `DEAD` at
    /// index 0 for free slots.
    v: [u32; 4],
    /// Neighbours, packed `tet << 2 | local facet of the neighbour`.
    n: [u32; 4],
}

/// Where a point falls.
enum Located {
    /// In conflict with this tetrahedron.
    Tet(u32),
    /// Exactly on this vertex.
    Duplicate(u32),
    /// No tetrahedron found (only on predicate failure).
    Lost,
}

/// The 3D Delaunay tessellator: incremental Bowyer–Watson insertion with
/// exact, symbolically perturbed predicates (see the [module docs](self)).
///
/// Keep one per simulation and call [`Tessellator::tessellate`] every
/// step: its work arrays are reused, so a step allocates nothing once the
/// particle count has settled.
///
/// Errors: [`GeometryError::NonFinite`] for a NaN or infinite coordinate,
/// [`GeometryError::Degenerate`] when fewer than four points are affinely
/// independent, [`GeometryError::NearCoincident`] for two points at the
/// same position (or closer than [`Delaunay3::min_distance`]),
/// [`GeometryError::TooManyPoints`] above [`MAX_POINTS`], and
/// [`GeometryError::Internal`] if the predicates were defeated by
/// underflow (coordinates spanning hundreds of orders of magnitude).
#[derive(Clone, Default)]
pub struct Delaunay3 {
    /// Two points closer than this (m) are reported as
    /// [`GeometryError::NearCoincident`]; `0` (the default) reports exact
    /// duplicates only.
    pub min_distance: f64,
    ws: Workspace,
}

impl std::fmt::Debug for Delaunay3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Delaunay3")
            .field("min_distance", &self.min_distance)
            .field("tetrahedra", &self.ws.tets.len())
            .finish_non_exhaustive()
    }
}

/// Work arrays, reused from call to call.
#[derive(Clone, Default)]
struct Workspace {
    /// Coordinates in insertion order (internal vertex `k` is input point
    /// `rank[k]`), rescaled by a power of two.
    pts: Vec<[f64; 3]>,
    /// Input index of each internal vertex: the insertion order, and the
    /// rank of the symbolic perturbation.
    rank: Vec<u32>,
    /// The same coordinates as exact integers in a common unit, when
    /// they fit in 60 bits (lattices do), else empty.
    ints: Vec<[i64; 3]>,
    /// Coordinates in input order (scratch).
    input: Vec<[f64; 3]>,
    /// Hilbert keys (scratch of the ordering).
    keys: Vec<u64>,
    /// The live tetrahedra by output order: (key, slot) (scratch of
    /// `write`).
    live: Vec<(u64, u32)>,
    /// Tetrahedron slots: vertices and neighbours together, one memory
    /// access per tetrahedron.
    tets: Vec<Tet>,
    /// Per-slot stamp: `stamp` in the current cavity, `stamp + 1` tested
    /// and not in conflict.
    mark: Vec<u32>,
    stamp: u32,
    /// Free slots.
    free: Vec<u32>,
    /// Cavity tetrahedra and search stack.
    cavity: Vec<u32>,
    stack: Vec<u32>,
    /// Cavity boundary.
    boundary: Vec<BoundaryFacet>,
    /// Open-addressing edge table with generation stamps.
    edges: Vec<EdgeSlot>,
    edge_gen: u32,
    /// A live tetrahedron near the last inserted point.
    last: u32,
    rng: u64,
}

impl Delaunay3 {
    /// A tessellator reporting exact duplicates only.
    pub fn new() -> Self {
        Self::default()
    }

    /// A tessellator reporting points closer than `min_distance` (m).
    pub fn with_min_distance(min_distance: f64) -> Self {
        Self {
            min_distance,
            ..Self::default()
        }
    }
}

impl Tessellator<3> for Delaunay3 {
    fn tessellate(
        &mut self,
        points: &[Point<3>],
        out: &mut Tessellation,
    ) -> Result<(), GeometryError> {
        out.nv = 4;
        out.simplices.clear();
        out.neighbors.clear();
        if !(self.min_distance >= 0.0 && self.min_distance.is_finite()) {
            return Err(GeometryError::InvalidParameter {
                name: "min_distance",
                value: self.min_distance,
                reason: "must be finite and non-negative",
            });
        }
        let ws = &mut self.ws;
        ws.load(points)?;
        // Power-of-two rescaling is exact, so distances scale back exactly.
        let scale = ws.rescale();
        exact::to_integers_all(&ws.pts, &mut ws.ints);
        let n = points.len();
        let Some(first) = ws.initial_tetrahedron() else {
            return Err(GeometryError::Degenerate { count: n, dim: 3 });
        };
        let tol = self.min_distance * scale;
        // Each insertion checks its point against the cavity's vertices;
        // the first tetrahedron's own pairs are checked here (they were
        // not: two of its corners 10⁻² apart passed a 10⁻¹ check).
        if tol > 0.0 {
            for a in 0..4 {
                for b in a + 1..4 {
                    let (p, q) = (ws.pts[first[a] as usize], ws.pts[first[b] as usize]);
                    let d = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
                    if d < tol {
                        return Err(near_coincident(&ws.rank, first[a], first[b], d, tol, scale));
                    }
                }
            }
        }
        for p in 0..n as u32 {
            if first.contains(&p) {
                continue;
            }
            ws.insert(p, tol, scale)?;
        }
        ws.write(out);
        Ok(())
    }
}

/// [`GeometryError::NearCoincident`] for the workspace's points `a` and `b`
/// (input order through `rank`), at the rescaled distance `d` and
/// tolerance `tol` (scaled back by `scale`).
fn near_coincident(rank: &[u32], a: u32, b: u32, d: f64, tol: f64, scale: f64) -> GeometryError {
    let (v, w) = (rank[a as usize], rank[b as usize]);
    GeometryError::NearCoincident {
        first: v.min(w) as usize,
        second: v.max(w) as usize,
        distance: d / scale,
        tolerance: tol / scale,
    }
}

#[inline(always)]
fn pack(t: u32, f: usize) -> u32 {
    (t << 2) | f as u32
}

impl Workspace {
    /// Copies and checks the points, and computes the insertion order.
    fn load(&mut self, points: &[Point<3>]) -> Result<(), GeometryError> {
        let n = points.len();
        if n > MAX_POINTS {
            return Err(GeometryError::TooManyPoints {
                count: n,
                max: MAX_POINTS,
            });
        }
        self.input.clear();
        for (index, p) in points.iter().enumerate() {
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                return Err(GeometryError::NonFinite { index });
            }
            self.input.push([p.x, p.y, p.z]);
        }
        order::brio(
            &self.input,
            &mut self.rank,
            &mut self.keys,
            0x5EED_DE1A_0A1E_2024,
        );
        // Store the points in insertion order: neighbours in the walk and
        // the cavity are then close in memory too.
        self.pts.clear();
        self.pts
            .extend(self.rank.iter().map(|&i| self.input[i as usize]));
        Ok(())
    }

    /// Scales the coordinates by a power of two (exact) so that the largest
    /// magnitude is near one, away from overflow in the predicates.
    /// Returns the factor.
    fn rescale(&mut self) -> f64 {
        let m = self
            .pts
            .iter()
            .flat_map(|p| p.iter())
            .fold(0.0f64, |m, &x| m.max(x.abs()));
        if m == 0.0 {
            return 1.0;
        }
        let e = m.log2().round().clamp(-1000.0, 1000.0) as i32;
        if e.abs() < 64 {
            return 1.0; // no risk of overflow or underflow
        }
        let s = 2f64.powi(-e);
        for p in &mut self.pts {
            for x in p.iter_mut() {
                *x *= s;
            }
        }
        s
    }

    /// Finds four affinely independent points, earliest in the insertion
    /// order, and builds the first tetrahedron and its four infinite
    /// neighbours. `None` when the set is flat.
    fn initial_tetrahedron(&mut self) -> Option<[u32; 4]> {
        let pts = &self.pts;
        let p = |i: u32| &pts[i as usize];
        let mut ids = 0..pts.len() as u32;
        let a = ids.next()?;
        let b = ids.clone().find(|&i| p(i) != p(a))?;
        let c = ids.clone().find(|&i| !collinear(p(a), p(b), p(i)))?;
        let d = ids.find(|&i| orient3d(p(a), p(b), p(c), p(i)) != 0)?;
        let t = if orient3d(p(a), p(b), p(c), p(d)) > 0 {
            [a, b, c, d]
        } else {
            [b, a, c, d]
        };

        self.tets.clear();
        self.mark.clear();
        self.free.clear();
        self.stamp = 0;
        self.edge_gen = 0;
        for e in &mut self.edges {
            e.gen = 0;
        }
        self.rng = 0x2545_F491_4F6C_DD1D;
        self.tets.push(Tet { v: t, n: [0; 4] });
        for (k, fk) in FACET.iter().enumerate() {
            // Infinite tet over facet k, its finite facet (opposite INF at
            // local 3) glued to facet k of tet 0.
            self.tets.push(Tet {
                v: [t[fk[0]], t[fk[1]], t[fk[2]], INF],
                n: [0; 4],
            });
            self.tets[0].n[k] = pack(k as u32 + 1, 3);
            self.tets[k + 1].n[3] = pack(0, k);
        }
        // Glue the infinite tets to each other across their faces through
        // INF: face j (j < 3) of an infinite tet holds the two finite
        // vertices other than j; match them by vertex pair.
        for s in 1..5u32 {
            for j in 0..3 {
                let v = self.tets[s as usize].v;
                let (x, y) = other_two(v, j);
                'search: for r in 1..5u32 {
                    if r == s {
                        continue;
                    }
                    let w = self.tets[r as usize].v;
                    for i in 0..3 {
                        let (u, z) = other_two(w, i);
                        if (u == x && z == y) || (u == y && z == x) {
                            self.tets[s as usize].n[j] = pack(r, i);
                            break 'search;
                        }
                    }
                }
            }
        }
        self.mark.resize(self.tets.len(), 0);
        self.last = 0;
        Some(t)
    }

    #[inline]
    fn next_rand(&mut self) -> u32 {
        // xorshift64
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.rng = x;
        (x >> 32) as u32
    }

    /// Visibility walk from the last created tetrahedron.
    fn locate(&mut self, pi: u32) -> Located {
        let mut r = self.next_rand();
        let pts = &self.pts;
        let p = &pts[pi as usize];
        let mut t = self.last;
        if self.tets[t as usize].v[3] == INF {
            t = self.tets[t as usize].n[3] >> 2;
        }
        let mut prev = u32::MAX;
        let limit = 1000 + self.tets.len();
        for _ in 0..limit {
            let Tet { v, n: tn } = self.tets[t as usize];
            let q = v.map(|i| &pts[i as usize]);
            let mut next = u32::MAX;
            r = r.rotate_left(2);
            for k in 0..4 {
                let f = (r as usize + k) & 3;
                let nb = tn[f] >> 2;
                if nb == prev {
                    continue;
                }
                let mut w = q;
                w[f] = p;
                if orient3d(w[0], w[1], w[2], w[3]) < 0 {
                    next = nb;
                    break;
                }
            }
            if next == u32::MAX {
                // p is in the closed tetrahedron t.
                if let Some(&dup) = v.iter().find(|&&i| &pts[i as usize] == p) {
                    return Located::Duplicate(dup);
                }
                return Located::Tet(t);
            }
            prev = t;
            t = next;
            if self.tets[t as usize].v[3] == INF {
                return Located::Tet(t);
            }
        }
        self.locate_brute_force(pi)
    }

    /// Exhaustive location, the fallback of a walk that did not terminate.
    #[cold]
    fn locate_brute_force(&self, pi: u32) -> Located {
        let pts = &self.pts;
        let p = &pts[pi as usize];
        for (t, Tet { v, .. }) in self.tets.iter().enumerate() {
            if v[0] == DEAD {
                continue;
            }
            if v[3] == INF {
                let q = v.map(|i| if i == INF { p } else { &pts[i as usize] });
                if orient3d(q[0], q[1], q[2], p) > 0 {
                    return Located::Tet(t as u32);
                }
                continue;
            }
            let q = v.map(|i| &pts[i as usize]);
            let inside = (0..4).all(|f| {
                let mut w = q;
                w[f] = p;
                orient3d(w[0], w[1], w[2], w[3]) >= 0
            });
            if inside {
                if let Some(&dup) = v.iter().find(|&&i| &pts[i as usize] == p) {
                    return Located::Duplicate(dup);
                }
                return Located::Tet(t as u32);
            }
        }
        Located::Lost
    }

    /// Inserts point `pi`: locate, dig the cavity, fill it with the star.
    fn insert(&mut self, pi: u32, tol: f64, scale: f64) -> Result<(), GeometryError> {
        let seed = match self.locate(pi) {
            Located::Tet(t) => t,
            Located::Duplicate(v) => {
                return Err(near_coincident(&self.rank, v, pi, 0.0, tol, scale));
            }
            Located::Lost => {
                let i = self.rank[pi as usize];
                return Err(GeometryError::Internal {
                    message: format!("point {i} could not be located (predicate underflow?)"),
                });
            }
        };
        self.stamp += 2;
        let s_in = self.stamp;
        let s_out = s_in + 1;
        self.cavity.clear();
        self.stack.clear();
        self.boundary.clear();
        self.mark[seed as usize] = s_in;
        self.cavity.push(seed);
        self.stack.push(seed);
        let pts = &self.pts;
        let rank = &self.rank;
        let ints = &self.ints;
        while let Some(t) = self.stack.pop() {
            let Tet { v: tv, n: tn } = self.tets[t as usize];
            for (f, &nb) in tn.iter().enumerate() {
                let n = (nb >> 2) as usize;
                let m = self.mark[n];
                if m == s_in {
                    continue;
                }
                if m != s_out {
                    let v = self.tets[n].v;
                    let conflict = if v[3] == INF {
                        hull_conflict_sos(pts, rank, [v[0], v[1], v[2]], pi)
                    } else {
                        insphere_sos(pts, ints, rank, v, pi)
                    };
                    if conflict {
                        self.mark[n] = s_in;
                        self.cavity.push(n as u32);
                        self.stack.push(n as u32);
                        continue;
                    }
                    self.mark[n] = s_out;
                }
                let mut v = tv;
                v[f] = pi;
                self.boundary.push(BoundaryFacet { v, f: f as u32, nb });
            }
        }

        // Near-coincidence: the nearest neighbour of p is a Delaunay
        // neighbour, hence a vertex of the cavity boundary.
        if tol > 0.0 {
            let p = pts[pi as usize];
            let mut best = (f64::INFINITY, 0u32);
            for b in &self.boundary {
                for &u in &b.v {
                    if u != pi && u != INF {
                        let q = pts[u as usize];
                        let d2 = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>();
                        if d2 < best.0 {
                            best = (d2, u);
                        }
                    }
                }
            }
            let d = best.0.sqrt();
            if d < tol {
                return Err(near_coincident(rank, best.1, pi, d, tol, scale));
            }
        }

        self.fill_cavity()
    }

    /// Replaces the cavity by one new tetrahedron per boundary facet and
    /// links them: to the outside through the facet, to each other through
    /// the edge table.
    fn fill_cavity(&mut self) -> Result<(), GeometryError> {
        let nb_count = self.boundary.len();
        let size = (nb_count * 8).next_power_of_two().max(64);
        if self.edges.len() < size {
            self.edges.clear();
            self.edges.resize(size, EdgeSlot::default());
            self.edge_gen = 0;
        }
        self.edge_gen += 1;
        let gen = self.edge_gen;
        let mask = self.edges.len() - 1;
        let shift = 64 - mask.count_ones();
        let mut links = 0usize;
        for i in 0..nb_count {
            let b = self.boundary[i];
            let t = if i < self.cavity.len() {
                self.cavity[i]
            } else if let Some(t) = self.free.pop() {
                t
            } else {
                // A slot index is packed with its face in 32 bits (`pack`,
                // `t << 2`): 2³⁰ slots at most.
                if self.tets.len() >= 1 << 30 {
                    return Err(GeometryError::TooManyPoints {
                        count: self.pts.len(),
                        max: MAX_POINTS,
                    });
                }
                self.tets.push(Tet::default());
                self.mark.push(0);
                (self.tets.len() - 1) as u32
            };
            let f = b.f as usize;
            self.tets[t as usize].v = b.v;
            self.mark[t as usize] = 0;
            self.tets[t as usize].n[f] = b.nb;
            self.tets[(b.nb >> 2) as usize].n[(b.nb & 3) as usize] = pack(t, f);
            for j in 0..4 {
                if j == f {
                    continue;
                }
                let (x, y) = other_two_of(b.v, f, j);
                let key = (u64::from(x.min(y)) << 32) | u64::from(x.max(y));
                let mut h = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize;
                loop {
                    let e = &mut self.edges[h];
                    if e.gen != gen {
                        *e = EdgeSlot {
                            key,
                            val: pack(t, j),
                            gen,
                        };
                        break;
                    }
                    if e.key == key {
                        let other = e.val;
                        e.key = u64::MAX; // consumed: each edge is shared twice
                        self.tets[t as usize].n[j] = other;
                        self.tets[(other >> 2) as usize].n[(other & 3) as usize] = pack(t, j);
                        links += 1;
                        break;
                    }
                    h = (h + 1) & mask;
                }
            }
        }
        // Fewer boundary facets than cavity tets cannot happen for a
        // star-shaped cavity (B = 2C + 2); free the rest anyway.
        for i in nb_count..self.cavity.len() {
            let t = self.cavity[i];
            self.tets[t as usize].v[0] = DEAD;
            self.free.push(t);
        }
        if 2 * links != 3 * nb_count {
            return Err(GeometryError::Internal {
                message: "cavity not star-shaped (predicate underflow?)".to_string(),
            });
        }
        self.last = self.cavity.first().copied().unwrap_or(0);
        Ok(())
    }

    /// Writes the finite tetrahedra and their adjacency.
    fn write(&mut self, out: &mut Tessellation) {
        // The live tetrahedra along the Hilbert curve of their first
        // vertex on it (then by slot): slots are reused in the order of
        // insertion, which scatters neighbours over the whole output, and
        // a caller that numbers nodes by first appearance (the assembly)
        // would scatter them too.
        let (rank, keys, live) = (&self.rank, &self.keys, &mut self.live);
        live.clear();
        live.extend(
            self.tets
                .iter()
                .enumerate()
                .filter(|(_, Tet { v, .. })| v[0] != DEAD && v[3] != INF)
                .map(|(t, Tet { v, .. })| {
                    let key = v.iter().map(|&i| keys[rank[i as usize] as usize]).min();
                    (key.unwrap_or(0), t as u32)
                }),
        );
        live.sort_unstable();
        let live = &self.live;
        // Reuse `mark` as the slot -> output index map.
        self.mark.iter_mut().for_each(|m| *m = u32::MAX);
        for (k, &(_, t)) in live.iter().enumerate() {
            self.mark[t as usize] = k as u32;
        }
        let count = live.len();
        out.simplices.reserve(4 * count);
        out.neighbors.reserve(4 * count);
        for &(_, t) in live {
            let Tet { v, n } = &self.tets[t as usize];
            out.simplices
                .extend(v.iter().map(|&i| self.rank[i as usize]));
            for &nb in n {
                let m = self.mark[(nb >> 2) as usize];
                out.neighbors
                    .push(if m == u32::MAX { NO_NEIGHBOR } else { m });
            }
        }
    }
}

/// The two vertices of `v` other than local indices `j` and 3 (for the
/// faces through the infinite vertex of an infinite tet).
#[inline]
fn other_two(v: [u32; 4], j: usize) -> (u32, u32) {
    other_two_of(v, 3, j)
}

/// The two vertices of `v` other than local indices `a` and `b`.
#[inline(always)]
fn other_two_of(v: [u32; 4], a: usize, b: usize) -> (u32, u32) {
    let mut r = [0u32; 2];
    let mut k = 0;
    for (i, &x) in v.iter().enumerate() {
        if i != a && i != b {
            r[k] = x;
            k += 1;
        }
    }
    (r[0], r[1])
}
