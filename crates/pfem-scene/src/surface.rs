//! Bodies bounded by a closed surface: a polygon in 2D (segments) or a
//! closed triangle surface in 3D (an STL file), filled with a lattice of
//! particles at the body's spacing.
//!
//! The filling casts lattice lines along x through the surface: a node is
//! inside when it lies between an odd crossing and the next (the crossing
//! number, exact in 2D with the half-open rule, and in 3D on lines shifted
//! by a tiny fixed offset so that no line passes through an edge). A node
//! on the surface (within `10⁻⁶ h`) counts as inside, so a polygon that is
//! a rectangle on the lattice gives the same particles as the box.

use std::collections::HashMap;
use std::path::Path;

use pfem_core::{Const, Dim, Point};

/// Most grid entries the polygon crossing check stores (one per edge and
/// grid cell its box touches): 5·10⁷, 200 MB.
const MAX_CROSSING_ENTRIES: usize = 50_000_000;

/// A closed boundary: `vertices` and `facets` of `D` vertex indices each
/// (segments in 2D, triangles in 3D).
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedSurface<const D: usize>
where
    Const<D>: Dim,
{
    /// Vertices (m).
    pub vertices: Vec<Point<D>>,
    /// Facets, `D` indices into `vertices` each (flat).
    pub facets: Vec<u32>,
}

impl<const D: usize> ClosedSurface<D>
where
    Const<D>: Dim,
{
    /// The closed polygon through `points` (the last joined to the first):
    /// a boundary of segments, for `D = 2` ([`Self::check`] refuses it in
    /// 3D, where facets are triangles).
    pub fn polygon(points: Vec<Point<D>>) -> Self {
        let n = points.len() as u32;
        let facets = (0..n).flat_map(|i| [i, (i + 1) % n.max(1)]).collect();
        Self {
            vertices: points,
            facets,
        }
    }
}

/// What reading a binary STL file holds per byte of the file, an upper
/// bound (half of it for a text file; [`ClosedSurface::read_stl`] refuses
/// a file that would not fit [`crate::default_memory_budget`]).
pub const STL_BYTES_PER_BYTE: f64 = 10.0;

impl ClosedSurface<3> {
    /// Reads an STL file (ASCII or binary), scaling every coordinate by
    /// `scale` (0.001 for a file in millimetres) and then adding `offset`
    /// (m). Vertices with identical coordinates in the file are merged.
    pub fn read_stl(path: &Path, scale: f64, offset: [f64; 3]) -> Result<Self, String> {
        // A device or a pipe (`/dev/zero`) would be read without end.
        let meta = std::fs::metadata(path)
            .map_err(|e| format!("cannot open STL file {}: {e}", path.display()))?;
        if !meta.is_file() {
            return Err(format!("STL file {}: not a regular file", path.display()));
        }
        let mut file = std::fs::File::open(path)
            .map_err(|e| format!("cannot open STL file {}: {e}", path.display()))?;
        // Binary or ASCII by the file's length, not by its first word: a
        // binary file's 80-byte header may begin with "solid" (some CAD
        // programs write it), which `stl_io` reads as text and refuses.
        let binary = {
            use std::io::Read;
            let mut head = Vec::with_capacity(84);
            (&mut file)
                .take(84)
                .read_to_end(&mut head)
                .map_err(|e| format!("cannot read STL file {}: {e}", path.display()))?;
            let is_text = head
                .iter()
                .skip_while(|b| b.is_ascii_whitespace())
                .take(5)
                .map(u8::to_ascii_lowercase)
                .eq(b"solid".iter().copied());
            if head.len() == 84 {
                let count = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as u64;
                if meta.len() == 84 + 50 * count {
                    true
                } else if !is_text {
                    return Err(format!(
                        "STL file {}: not text (it does not begin with `solid`), and not binary either: its header counts {count} triangles ({} bytes) but the file has {} bytes",
                        path.display(),
                        84 + 50 * count,
                        meta.len()
                    ));
                } else {
                    false
                }
            } else {
                false
            }
        };
        // Read whole, then held as triangles, vertices, facets and the
        // surface's checks (edge maps, a crossing grid): about ten bytes
        // per byte of a binary file (50 a triangle), fewer of a text one
        // (about 250 a triangle). A sparse file of 10 GB (no disk, a header
        // counting 2·10⁸ triangles) was read into memory before any budget
        // was asked (the review of session 45).
        let need = meta.len() as f64
            * if binary {
                STL_BYTES_PER_BYTE
            } else {
                STL_BYTES_PER_BYTE / 2.0
            };
        let budget = crate::default_memory_budget();
        if need > budget {
            return Err(format!(
                "STL file {}: {} bytes would take about {need:.2e} bytes to read and check, over the memory budget of {budget:.2e}",
                path.display(),
                meta.len()
            ));
        }
        let triangles: Vec<[[f32; 3]; 3]> = if binary {
            use std::io::Read;
            let mut bytes = Vec::new();
            file.read_to_end(&mut bytes)
                .map_err(|e| format!("cannot read STL file {}: {e}", path.display()))?;
            bytes
                .chunks_exact(50)
                .map(|t| {
                    let f = |k: usize| {
                        let o = 12 + 4 * k;
                        f32::from_le_bytes([t[o], t[o + 1], t[o + 2], t[o + 3]])
                    };
                    [[f(0), f(1), f(2)], [f(3), f(4), f(5)], [f(6), f(7), f(8)]]
                })
                .collect()
        } else {
            use std::io::Seek;
            file.rewind()
                .map_err(|e| format!("cannot read STL file {}: {e}", path.display()))?;
            let mesh = stl_io::read_stl(&mut file).map_err(|e| {
                // (The parser's own words for a NaN or an infinity read
                // "expected finite f32, got NaN which is Nan".)
                let what = e.to_string();
                let hint = if what.contains("finite") {
                    " (a coordinate that is not a finite number)"
                } else {
                    ""
                };
                format!("cannot read STL file {}: {what}{hint}", path.display())
            })?;
            let mut out = Vec::with_capacity(mesh.faces.len());
            for f in &mesh.faces {
                let mut t = [[0f32; 3]; 3];
                for (a, &vi) in f.vertices.iter().enumerate() {
                    let v = mesh
                        .vertices
                        .get(vi)
                        .ok_or_else(|| format!("STL file {}: bad vertex index", path.display()))?;
                    t[a] = [v[0], v[1], v[2]];
                }
                out.push(t);
            }
            out
        };
        let mut index: HashMap<[u32; 3], u32> = HashMap::new();
        let mut vertices = Vec::new();
        let mut facets = Vec::with_capacity(3 * triangles.len());
        for t in &triangles {
            for v in t {
                // `+ 0.0` makes −0.0 and +0.0 one vertex.
                let key = [
                    (v[0] + 0.0).to_bits(),
                    (v[1] + 0.0).to_bits(),
                    (v[2] + 0.0).to_bits(),
                ];
                let id = *index.entry(key).or_insert_with(|| {
                    vertices.push(Point::<3>::new(
                        v[0] as f64 * scale + offset[0],
                        v[1] as f64 * scale + offset[1],
                        v[2] as f64 * scale + offset[2],
                    ));
                    (vertices.len() - 1) as u32
                });
                facets.push(id);
            }
            // A triangle repeating a vertex (CAD exports write some) has no
            // area and adds each of its edges once each way: dropped, it
            // changes nothing (it was refused as degenerate before session
            // 43).
            let f = &facets[facets.len() - 3..];
            if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
                facets.truncate(facets.len() - 3);
            }
        }
        Ok(Self { vertices, facets })
    }
}

impl<const D: usize> ClosedSurface<D>
where
    Const<D>: Dim,
{
    /// Lower and upper corners of the bounding box.
    pub fn bounds(&self) -> (Point<D>, Point<D>) {
        let mut lo = Point::<D>::from([f64::INFINITY; D]);
        let mut hi = Point::<D>::from([f64::NEG_INFINITY; D]);
        for v in &self.vertices {
            for k in 0..D {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        (lo, hi)
    }

    /// A triangle given twice with the same winding (an exporter's
    /// repeat), named by its corners: it leaves its three edges shared by
    /// an odd count of triangles, which [`ClosedSurface::check`] would
    /// otherwise report as a hole (a review of session 53). By its
    /// corners, not its number, since the reader drops degenerate
    /// triangles and renumbers the rest. Two parts sharing a face (the
    /// face twice, opposite windings) are closed and not named.
    fn repeated_triangle(&self) -> Option<String> {
        if D != 3 {
            return None;
        }
        let mut seen: HashMap<[u32; 3], ()> = HashMap::new();
        for f in self.facets.chunks_exact(3) {
            // The winding kept: the rotation starting at the least index.
            let r = (0..3).min_by_key(|&a| f[a]).unwrap_or(0);
            let key = [f[r], f[(r + 1) % 3], f[(r + 2) % 3]];
            if seen.insert(key, ()).is_some() {
                let corners: Vec<String> = key
                    .iter()
                    .map(|&v| {
                        let p = &self.vertices[v as usize];
                        let c: Vec<String> = p.iter().map(|c| format!("{c}")).collect();
                        format!("({})", c.join(", "))
                    })
                    .collect();
                return Some(format!(
                    "a triangle is given twice, with the same winding: {}; remove the repeat",
                    corners.join(", ")
                ));
            }
        }
        None
    }

    /// Why this is not a closed boundary, if it is not: too few facets,
    /// an index out of range, a non-finite vertex, a degenerate facet, or
    /// a boundary with holes (a vertex of a polygon, or an edge of a
    /// triangle surface, shared by an odd number of facets; a triangle
    /// given twice with one winding is named as such).
    pub fn check(&self) -> Result<(), String> {
        let n = self.vertices.len();
        if !self.facets.len().is_multiple_of(D) || self.facets.len() / D < D + 1 {
            return Err(format!(
                "a closed boundary needs at least {} {}",
                D + 1,
                if D == 2 { "vertices" } else { "triangles" }
            ));
        }
        if let Some(&i) = self.facets.iter().find(|&&i| i as usize >= n) {
            return Err(format!("facet vertex {i} out of range ({n} vertices)"));
        }
        if self
            .vertices
            .iter()
            .any(|v| v.iter().any(|c| !c.is_finite()))
        {
            return Err("a vertex is not finite".into());
        }
        let mut count: HashMap<(u32, u32), usize> = HashMap::new();
        for f in self.facets.chunks_exact(D) {
            if (0..D).any(|a| (a + 1..D).any(|b| f[a] == f[b])) {
                return Err(format!("degenerate facet {f:?} (a repeated vertex)"));
            }
            if D == 2 {
                for &v in f {
                    *count.entry((v, v)).or_default() += 1;
                }
            } else {
                for a in 0..3 {
                    let (p, q) = (f[a], f[(a + 1) % 3]);
                    *count.entry((p.min(q), p.max(q))).or_default() += 1;
                }
            }
        }
        if let Some((k, c)) = count.iter().find(|(_, c)| *c % 2 == 1) {
            if let Some(why) = self.repeated_triangle() {
                return Err(why);
            }
            return Err(if D == 2 {
                format!("the polygon is not closed at vertex {} ({c} edges)", k.0)
            } else {
                format!(
                    "the surface is not closed: the edge from {:?} to {:?} (vertices {} and {}) belongs to {c} triangle(s)",
                    self.vertices[k.0 as usize].as_slice(),
                    self.vertices[k.1 as usize].as_slice(),
                    k.0,
                    k.1
                )
            });
        }
        if D == 2 {
            // Consistently oriented (a polygon built by hand): each vertex
            // starts as many segments as it ends.
            let mut net: HashMap<u32, i64> = HashMap::new();
            for f in self.facets.chunks_exact(2) {
                *net.entry(f[0]).or_default() += 1;
                *net.entry(f[1]).or_default() -= 1;
            }
            if let Some((v, _)) = net
                .iter()
                .filter(|(_, c)| **c != 0)
                .min_by_key(|(v, _)| **v)
            {
                return Err(format!(
                    "the polygon's segments are not consistently oriented at vertex {v}"
                ));
            }
        }
        if D == 3 {
            // Consistently oriented: each edge is crossed as often one way
            // as the other. A cube with some faces reversed is closed but
            // encloses a signed volume near zero, and the memory estimate
            // (from that volume) let its fill place 10⁸ particles (session
            // 42's review).
            let mut net: HashMap<(u32, u32), i64> = HashMap::new();
            for f in self.facets.chunks_exact(3) {
                for a in 0..3 {
                    let (p, q) = (f[a], f[(a + 1) % 3]);
                    *net.entry((p.min(q), p.max(q))).or_default() += if p < q { 1 } else { -1 };
                }
            }
            if let Some((k, _)) = net
                .iter()
                .filter(|(_, c)| **c != 0)
                .min_by_key(|(k, _)| **k)
            {
                return Err(format!(
                    "the surface's triangles are not consistently oriented: the edge from {:?} to {:?} (vertices {} and {}) is crossed the same way by two of them (a face reversed?)",
                    self.vertices[k.0 as usize].as_slice(),
                    self.vertices[k.1 as usize].as_slice(),
                    k.0,
                    k.1
                ));
            }
        }
        if D == 2 {
            // A polygon that crosses itself (a bowtie) has no inside to
            // fill: two edges that share no vertex must not meet.
            let edges: Vec<&[u32]> = self.facets.chunks_exact(2).collect();
            let p = |i: u32| {
                let v = &self.vertices[i as usize];
                (v[0], v[1])
            };
            if let Some(e) = edges.iter().find(|e| p(e[0]) == p(e[1])) {
                return Err(format!(
                    "the polygon repeats a vertex: edge ({}, {}) has no length",
                    e[0], e[1]
                ));
            }
            let orient = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
                (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
            };
            // Pairs of edges near each other: a grid of about one edge a
            // cell (each edge in every cell its box touches), so a polygon
            // of 10⁵–10⁶ vertices is checked in about linear time (every
            // pair was, until session 41: 2·10¹⁰ pairs for 2·10⁵ vertices,
            // three times per run).
            let (mut lo, mut hi) = (
                (f64::INFINITY, f64::INFINITY),
                (f64::NEG_INFINITY, f64::NEG_INFINITY),
            );
            for e in &edges {
                for &v in e.iter() {
                    let q = p(v);
                    lo = (lo.0.min(q.0), lo.1.min(q.1));
                    hi = (hi.0.max(q.0), hi.1.max(q.1));
                }
            }
            let side = ((edges.len() as f64).sqrt().ceil() as usize).clamp(1, 2048);
            let size = |a: f64, b: f64| if b > a { (b - a) / side as f64 } else { 1.0 };
            let (wx, wy) = (size(lo.0, hi.0), size(lo.1, hi.1));
            let cell =
                |x: f64, w: f64, o: f64| (((x - o) / w).floor().max(0.0) as usize).min(side - 1);
            // Each edge goes into every cell its box touches: long edges
            // across the polygon (vertices listed out of order, long
            // spokes) would fill side² cells each. Counted before anything
            // is stored, and refused above 5·10⁷ entries (200 MB; a polygon
            // of 2·10⁵ shuffled vertices would have needed 4·10⁹).
            let mut entries = 0usize;
            for e in &edges {
                let (a, b) = (p(e[0]), p(e[1]));
                let (i0, i1) = (cell(a.0.min(b.0), wx, lo.0), cell(a.0.max(b.0), wx, lo.0));
                let (j0, j1) = (cell(a.1.min(b.1), wy, lo.1), cell(a.1.max(b.1), wy, lo.1));
                entries = entries.saturating_add((i1 - i0 + 1) * (j1 - j0 + 1));
            }
            if entries > MAX_CROSSING_ENTRIES {
                return Err(format!(
                    "the polygon's {} edges are too long for their number to be checked for crossings ({entries} grid entries, at most {MAX_CROSSING_ENTRIES}): are its vertices in order along the boundary?",
                    edges.len()
                ));
            }
            let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); side * side];
            for (k, e) in edges.iter().enumerate() {
                let (a, b) = (p(e[0]), p(e[1]));
                let (i0, i1) = (cell(a.0.min(b.0), wx, lo.0), cell(a.0.max(b.0), wx, lo.0));
                let (j0, j1) = (cell(a.1.min(b.1), wy, lo.1), cell(a.1.max(b.1), wy, lo.1));
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        buckets[i * side + j].push(k as u32);
                    }
                }
            }
            for bucket in &buckets {
                for (x, &ei) in bucket.iter().enumerate() {
                    for &fi in &bucket[x + 1..] {
                        let (e, f) = (edges[ei as usize], edges[fi as usize]);
                        if e.iter().any(|v| f.contains(v)) {
                            continue;
                        }
                        let (a, b, c, d) = (p(e[0]), p(e[1]), p(f[0]), p(f[1]));
                        let (o1, o2) = (orient(a, b, c), orient(a, b, d));
                        let (o3, o4) = (orient(c, d, a), orient(c, d, b));
                        if o1 * o2 <= 0.0 && o3 * o4 <= 0.0 {
                            let collinear_apart = o1 == 0.0
                                && o2 == 0.0
                                && (a.0.max(b.0) < c.0.min(d.0)
                                    || c.0.max(d.0) < a.0.min(b.0)
                                    || a.1.max(b.1) < c.1.min(d.1)
                                    || c.1.max(d.1) < a.1.min(b.1));
                            if !collinear_apart {
                                let (e, f) = if ei < fi { (e, f) } else { (f, e) };
                                return Err(format!(
                                    "the polygon crosses itself: edges ({}, {}) and ({}, {}) meet",
                                    e[0], e[1], f[0], f[1]
                                ));
                            }
                        }
                    }
                }
            }
        }
        if D == 3 {
            self.check_surface_crossings()?;
        }
        // Last: a boundary that encloses nothing (a polygon back and forth along
        // a line) would still place particles where its line meets the
        // lattice (session 42's review).
        let (lo, hi) = self.bounds();
        let extent = (0..D).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        // (As a length against the extent: no power of a far coordinate.)
        let size = self.enclosed_measure().powf(1.0 / D as f64);
        if size.is_nan() || size <= 1e-6 * extent {
            return Err(format!(
                "the boundary encloses no {} (it is flat)",
                if D == 2 { "area" } else { "volume" },
            ));
        }
        Ok(())
    }

    /// 3D: no edge of the surface pierces one of its triangles that it
    /// shares no vertex with. Two closed parts that overlap (a CAD
    /// assembly exported as separate bodies, two cubes run into each
    /// other) or a surface through itself have no inside the fill can
    /// find: it counts crossings by parity, so the overlap was left empty,
    /// a hidden cavity (session 43's review). A part wholly inside another
    /// (a cavity) crosses nothing and stays a cavity. A grid of the
    /// triangles' boxes, about one triangle a cell, as the polygon's
    /// crossing check; an edge touching a triangle's plane within 10⁻⁶ of
    /// the surface's size (two parts face to face, as an f32 file rounds
    /// them) is no crossing.
    fn check_surface_crossings(&self) -> Result<(), String> {
        let tris: Vec<&[u32]> = self.facets.chunks_exact(3).collect();
        let v = |i: u32| {
            let p = &self.vertices[i as usize];
            [p[0], p[1], p[D - 1]]
        };
        let (lo, hi) = self.bounds();
        let (lo, hi) = ([lo[0], lo[1], lo[D - 1]], [hi[0], hi[1], hi[D - 1]]);
        let side = ((tris.len() as f64).cbrt().ceil() as usize).clamp(1, 256);
        let w: [f64; 3] = std::array::from_fn(|k| {
            if hi[k] > lo[k] {
                (hi[k] - lo[k]) / side as f64
            } else {
                1.0
            }
        });
        let cell =
            |x: f64, k: usize| (((x - lo[k]) / w[k]).floor().max(0.0) as usize).min(side - 1);
        let range = |pts: &[[f64; 3]]| -> [(usize, usize); 3] {
            std::array::from_fn(|k| {
                let a = pts.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
                let b = pts.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
                (cell(a, k), cell(b, k))
            })
        };
        let count = |r: &[(usize, usize); 3]| {
            r.iter()
                .fold(1usize, |n, (a, b)| n.saturating_mul(b - a + 1))
        };
        let mut entries = 0usize;
        for t in &tris {
            entries = entries.saturating_add(count(&range(&[v(t[0]), v(t[1]), v(t[2])])));
        }
        if entries > MAX_CROSSING_ENTRIES {
            return Err(format!(
                "the surface's {} triangles are too large for their number to be checked for crossings ({entries} grid entries, at most {MAX_CROSSING_ENTRIES})",
                tris.len()
            ));
        }
        let mut buckets: HashMap<usize, Vec<u32>> = HashMap::new();
        for (k, t) in tris.iter().enumerate() {
            let r = range(&[v(t[0]), v(t[1]), v(t[2])]);
            for i in r[0].0..=r[0].1 {
                for j in r[1].0..=r[1].1 {
                    for l in r[2].0..=r[2].1 {
                        buckets
                            .entry((i * side + j) * side + l)
                            .or_default()
                            .push(k as u32);
                    }
                }
            }
        }
        let orient = |a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]| {
            let (u, w, x) = (
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
                [d[0] - a[0], d[1] - a[1], d[2] - a[2]],
            );
            u[0] * (w[1] * x[2] - w[2] * x[1]) - u[1] * (w[0] * x[2] - w[2] * x[0])
                + u[2] * (w[0] * x[1] - w[1] * x[0])
        };
        let far = (0..3)
            .map(|k| lo[k].abs().max(hi[k].abs()).max(hi[k] - lo[k]))
            .fold(0.0, f64::max);
        let tol = 1e-6 * far;
        let mut seen: std::collections::HashSet<(u32, u32)> = Default::default();
        let mut near: Vec<u32> = Vec::new();
        for t in &tris {
            for a in 0..3 {
                let (e0, e1) = (t[a].min(t[(a + 1) % 3]), t[a].max(t[(a + 1) % 3]));
                if !seen.insert((e0, e1)) {
                    continue;
                }
                let (p, q) = (v(e0), v(e1));
                let r = range(&[p, q]);
                near.clear();
                for i in r[0].0..=r[0].1 {
                    for j in r[1].0..=r[1].1 {
                        for l in r[2].0..=r[2].1 {
                            if let Some(b) = buckets.get(&((i * side + j) * side + l)) {
                                near.extend_from_slice(b);
                            }
                        }
                    }
                }
                near.sort_unstable();
                near.dedup();
                for &fi in &near {
                    let f = tris[fi as usize];
                    if f.contains(&e0) || f.contains(&e1) {
                        continue;
                    }
                    let (a, b, c) = (v(f[0]), v(f[1]), v(f[2]));
                    // Each end's distance from the triangle's plane, beyond
                    // the file's own rounding on either side (parts face
                    // to face on a tilted plane, their vertices apart, lie
                    // 10⁻⁷ of their size off each other's planes in f32).
                    let n = {
                        let (u, w) = (
                            [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                            [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
                        );
                        let cr = [
                            u[1] * w[2] - u[2] * w[1],
                            u[2] * w[0] - u[0] * w[2],
                            u[0] * w[1] - u[1] * w[0],
                        ];
                        (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt()
                    };
                    let (o1, o2) = (orient(a, b, c, p) / n, orient(a, b, c, q) / n);
                    if !((o1 < -tol && o2 > tol) || (o1 > tol && o2 < -tol)) {
                        continue;
                    }
                    let (s1, s2, s3) = (orient(p, q, a, b), orient(p, q, b, c), orient(p, q, c, a));
                    // Through the triangle, farther than `tol` from each
                    // of its edges (a crossing within it of an edge is a
                    // touch as the file rounds it: parts face to face
                    // overlap by 10⁻⁷). `s₁ / Σs` is the crossing point's
                    // barycentric weight off edge ab, whose height is
                    // `n / |b − a|`.
                    let sum = s1 + s2 + s3;
                    let len = |u: [f64; 3], w: [f64; 3]| {
                        ((w[0] - u[0]).powi(2) + (w[1] - u[1]).powi(2) + (w[2] - u[2]).powi(2))
                            .sqrt()
                    };
                    let inside = |si: f64, u: [f64; 3], w: [f64; 3]| si / sum * n / len(u, w) > tol;
                    if sum != 0.0 && inside(s1, a, b) && inside(s2, b, c) && inside(s3, c, a) {
                        return Err(format!(
                            "the surface crosses itself: edge ({e0}, {e1}) pierces triangle ({}, {}, {}) (two overlapping parts? they must be one closed surface, or apart)",
                            f[0], f[1], f[2]
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// The volume (area in 2D) enclosed, from the divergence theorem
    /// (positive whatever the orientation).
    pub fn enclosed_measure(&self) -> f64 {
        // Per connected part (facets joined through shared vertices), each
        // part's own measure taken positive: a part reversed as a whole (a
        // mirrored copy whose winding was not flipped) balances at every
        // edge and would cancel another's volume in a plain sum, and the
        // memory estimate is made from this measure (session 42's review).
        // About the box's corner, so that far coordinates do not cancel.
        let n = self.vertices.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                parent[i as usize] = parent[parent[i as usize] as usize];
                i = parent[i as usize];
            }
            i
        }
        for f in self.facets.chunks_exact(D) {
            if f.iter().any(|&v| v as usize >= n) {
                continue;
            }
            for &v in &f[1..] {
                let (a, b) = (root(&mut parent, f[0]), root(&mut parent, v));
                parent[a.max(b) as usize] = a.min(b);
            }
        }
        let (o, _) = self.bounds();
        let mut part: HashMap<u32, f64> = HashMap::new();
        for f in self.facets.chunks_exact(D) {
            if f.iter().any(|&v| v as usize >= n) {
                continue;
            }
            let v = |a: usize| self.vertices[f[a] as usize] - o;
            let s = if D == 2 {
                v(0)[0] * v(1)[1] - v(1)[0] * v(0)[1]
            } else {
                let (a, b, c) = (v(0), v(1), v(2));
                a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0])
            };
            *part.entry(root(&mut parent, f[0])).or_default() += s;
        }
        part.values().map(|s| s.abs()).sum::<f64>() / if D == 2 { 2.0 } else { 6.0 }
    }

    /// Lattice lines (along x) across the bounding box at spacing `h`:
    /// `[n_x, n_y, n_z]` intervals per axis (`n_z = 0` in 2D).
    fn lattice_size(&self, h: f64) -> ([usize; 3], Point<D>) {
        let (lo, hi) = self.bounds();
        let mut n = [0usize; 3];
        for k in 0..D {
            n[k] = ((hi[k] - lo[k]) / h + 1e-6).floor().max(0.0) as usize;
        }
        (n, lo)
    }

    /// Calls `run(first, last)` for each run of consecutive lattice lines
    /// (index `jz (n_y + 1) + jy`, `first..=last`, one run per slab) that
    /// facet `f` may cross, until `run` returns `false` (then so does this
    /// function): those within a spacing of the facet's
    /// projection across x (in 2D the segment's y-extent, in 3D the
    /// triangle's y-extent within a slab of `±h` about each line's z),
    /// with one line of margin, as the bounding box of the facet gave
    /// before session 35. The projection, not the bounding box: a thin
    /// shape along a diagonal (a needle 200 m long at a 1 cm spacing) has
    /// facets whose bounding boxes span 4·10⁸ lines but which cross 10⁵.
    fn facet_lines(
        &self,
        f: &[u32],
        h: f64,
        lo: &Point<D>,
        n: &[usize; 3],
        mut run: impl FnMut(usize, usize) -> bool,
    ) -> bool {
        let v = |a: usize| self.vertices[f[a] as usize];
        let ny = n[1] + 1;
        let span = |a: f64, b: f64, k: usize| -> (usize, usize) {
            let j0 = ((a - lo[k]) / h - 1.0).floor().max(0.0) as usize;
            let j1 = (((b - lo[k]) / h + 1.0).ceil().max(0.0) as usize).min(n[k]);
            (j0.min(n[k]), j1)
        };
        if D == 2 {
            let (a, b) = (v(0)[1], v(1)[1]);
            let (j0, j1) = span(a.min(b), a.max(b), 1);
            return run(j0, j1);
        }
        let (mut za, mut zb) = (f64::INFINITY, f64::NEG_INFINITY);
        for a in 0..D {
            za = za.min(v(a)[D - 1]);
            zb = zb.max(v(a)[D - 1]);
        }
        let (jz0, jz1) = span(za, zb, D - 1);
        for jz in jz0..=jz1 {
            let zc = lo[D - 1] + jz as f64 * h;
            let (s0, s1) = (zc - h, zc + h);
            // The triangle's y-extent within the slab: its vertices in
            // it and its edges' crossings of the slab's faces.
            let (mut ya, mut yb) = (f64::INFINITY, f64::NEG_INFINITY);
            for a in 0..D {
                let p = v(a);
                if p[D - 1] >= s0 && p[D - 1] <= s1 {
                    ya = ya.min(p[1]);
                    yb = yb.max(p[1]);
                }
                let q = v((a + 1) % D);
                for s in [s0, s1] {
                    if (p[D - 1] - s) * (q[D - 1] - s) < 0.0 {
                        let y = p[1] + (s - p[D - 1]) / (q[D - 1] - p[D - 1]) * (q[1] - p[1]);
                        ya = ya.min(y);
                        yb = yb.max(y);
                    }
                }
            }
            if ya <= yb {
                let (j0, j1) = span(ya, yb, 1);
                if !run(jz * ny + j0, jz * ny + j1) {
                    return false;
                }
            }
        }
        true
    }

    /// How many (lattice line, facet) pairs [`Self::fill`] visits at
    /// spacing `h`: its work and memory beside the particles it places
    /// (`Scene::estimate` counts 16 bytes each). Counted by runs of lines
    /// (one a facet in 2D, one a slab of lines in 3D), not stored.
    pub fn fill_work(&self, h: f64) -> f64 {
        self.fill_work_up_to(h, f64::INFINITY)
    }

    /// [`Self::fill_work`], the count stopped as soon as it exceeds `cap`
    /// (then some value above `cap` is returned): a scene's memory check
    /// needs no more, and the count's own cost, one step a slab of lines
    /// in 3D, stays within the budget it checks (at a spacing of 10⁻⁸ m a
    /// 1 m facet spans 10⁸ slabs).
    pub fn fill_work_up_to(&self, h: f64, cap: f64) -> f64 {
        if !(h > 0.0 && h.is_finite()) {
            return 0.0;
        }
        let (n, lo) = self.lattice_size(h);
        let mut count = 0.0;
        for f in self.facets.chunks_exact(D) {
            let more = self.facet_lines(f, h, &lo, &n, |a, b| {
                count += (b - a + 1) as f64;
                count <= cap
            });
            if !more {
                break;
            }
        }
        count
    }

    /// The nodes of the lattice of spacing `h` anchored at the bounding
    /// box's lower corner that lie inside the boundary or on it (module
    /// docs), ordered x fastest. The boundary must pass [`Self::check`].
    /// Its work grows with the particles it places and with
    /// [`Self::fill_work`], not with the bounding box.
    pub fn fill(&self, h: f64) -> Vec<Point<D>> {
        let (n, lo) = self.lattice_size(h);
        let tol = 1e-6 * h;
        // (line, facet) for each lattice line a facet may cross, in the
        // order of the lines, then of the facets.
        let mut pairs: Vec<(usize, u32)> = Vec::new();
        for (fi, f) in self.facets.chunks_exact(D).enumerate() {
            self.facet_lines(f, h, &lo, &n, |a, b| {
                pairs.extend((a..=b).map(|l| (l, fi as u32)));
                true
            });
        }
        pairs.sort_unstable();
        let ny = n[1] + 1;
        let shifts: &[[f64; 2]] = if D == 2 {
            &[[0.0, 0.0], [-1.0, 0.0], [1.0, 0.0]]
        } else {
            &[
                [0.0, 0.0],
                [-1.0, -1.0],
                [-1.0, 0.0],
                [-1.0, 1.0],
                [0.0, -1.0],
                [0.0, 1.0],
                [1.0, -1.0],
                [1.0, 0.0],
                [1.0, 1.0],
            ]
        };
        // Off the lattice, so that a line meets no edge of a triangle.
        let jitter = [0.731_284_9e-7 * h, 0.412_907_3e-7 * h];
        let mut out = Vec::new();
        let mut crossings = Vec::new();
        let mut intervals: Vec<(f64, f64)> = Vec::new();
        let mut candidates: Vec<usize> = Vec::new();
        for group in pairs.chunk_by(|a, b| a.0 == b.0) {
            let (jy, jz) = (group[0].0 % ny, group[0].0 / ny);
            let y = lo[1.min(D - 1)] + jy as f64 * h;
            let z = if D == 3 {
                lo[D - 1] + jz as f64 * h
            } else {
                0.0
            };
            intervals.clear();
            for s in shifts {
                let t = if D == 2 {
                    [y + s[0] * tol, 0.0]
                } else {
                    [y + s[0] * tol + jitter[0], z + s[1] * tol + jitter[1]]
                };
                crossings.clear();
                for &(_, fi) in group {
                    let f = &self.facets[fi as usize * D..fi as usize * D + D];
                    if let Some(x) = self.crossing(f, t) {
                        crossings.push(x);
                    }
                }
                crossings.sort_by(f64::total_cmp);
                for c in crossings.chunks_exact(2) {
                    intervals.push((c[0] - tol, c[1] + tol));
                }
            }
            // The nodes of the line within an interval: those near each
            // interval, each tested as every node of the line was.
            candidates.clear();
            for &(a, b) in &intervals {
                let i0 = ((a - lo[0]) / h).floor() - 1.0;
                let i1 = ((b - lo[0]) / h).ceil() + 1.0;
                let i0 = i0.max(0.0).min(n[0] as f64) as usize;
                let i1 = i1.max(0.0).min(n[0] as f64) as usize;
                candidates.extend(i0..=i1);
            }
            candidates.sort_unstable();
            candidates.dedup();
            for &i in &candidates {
                let x = lo[0] + i as f64 * h;
                if intervals.iter().any(|&(a, b)| x >= a && x <= b) {
                    let mut p = Point::<D>::zeros();
                    p[0] = x;
                    p[1] = y;
                    if D == 3 {
                        p[D - 1] = z;
                    }
                    out.push(p);
                }
            }
        }
        out
    }

    /// Where the line along x at transverse coordinates `t` crosses facet
    /// `f`, if it does.
    fn crossing(&self, f: &[u32], t: [f64; 2]) -> Option<f64> {
        let v = |a: usize| self.vertices[f[a] as usize];
        if D == 2 {
            let (a, b) = (v(0), v(1));
            // Half-open in y: a vertex shared by two edges counts once.
            if (a[1] <= t[0]) == (b[1] <= t[0]) {
                return None;
            }
            Some(a[0] + (t[0] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]))
        } else {
            let (a, b, c) = (v(0), v(1), v(2));
            let orient = |p: &Point<D>, q: &Point<D>| {
                (q[1] - p[1]) * (t[1] - p[D - 1]) - (q[D - 1] - p[D - 1]) * (t[0] - p[1])
            };
            let (wa, wb, wc) = (orient(&b, &c), orient(&c, &a), orient(&a, &b));
            let inside = (wa > 0.0 && wb > 0.0 && wc > 0.0) || (wa < 0.0 && wb < 0.0 && wc < 0.0);
            if !inside {
                return None;
            }
            let s = wa + wb + wc;
            Some((wa * a[0] + wb * b[0] + wc * c[0]) / s)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::box_points;

    fn cube(l: f64) -> ClosedSurface<3> {
        let v = |x: f64, y: f64, z: f64| Point::<3>::new(x * l, y * l, z * l);
        let vertices = vec![
            v(0., 0., 0.),
            v(1., 0., 0.),
            v(1., 1., 0.),
            v(0., 1., 0.),
            v(0., 0., 1.),
            v(1., 0., 1.),
            v(1., 1., 1.),
            v(0., 1., 1.),
        ];
        let q = |a: u32, b: u32, c: u32, d: u32| [a, b, c, a, c, d];
        let facets = [
            q(0, 3, 2, 1),
            q(4, 5, 6, 7),
            q(0, 1, 5, 4),
            q(2, 3, 7, 6),
            q(1, 2, 6, 5),
            q(0, 4, 7, 3),
        ]
        .concat();
        ClosedSurface { vertices, facets }
    }

    #[test]
    fn a_rectangle_polygon_fills_as_the_box() {
        let h = 0.1;
        let poly = ClosedSurface::polygon(vec![
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(1.0, 0.5),
            Point::<2>::new(0.0, 0.5),
        ]);
        poly.check().unwrap();
        let a = poly.fill(h);
        let b = box_points::<2>(&Point::<2>::new(0.0, 0.0), &Point::<2>::new(1.0, 0.5), h).unwrap();
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(&b) {
            assert!((p - q).norm() < 1e-12);
        }
        assert!((poly.enclosed_measure() - 0.5).abs() < 1e-12);
    }

    #[test]
    fn a_cube_surface_fills_as_the_box_and_a_triangle_by_its_area() {
        let h = 0.1;
        let c = cube(1.0);
        c.check().unwrap();
        assert!((c.enclosed_measure() - 1.0).abs() < 1e-12);
        assert_eq!(c.fill(h).len(), 11 * 11 * 11);
        // A right triangle of legs 1: nodes (i, j) with i + j <= 10.
        let tri = ClosedSurface::polygon(vec![
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(0.0, 1.0),
        ]);
        assert_eq!(tri.fill(h).len(), 66);
        // A finer lattice approaches the area.
        let n = tri.fill(0.001).len() as f64 * 1e-6;
        assert!((n - 0.5).abs() < 0.002, "{n}");
    }

    /// Every node of every line of the bounding box, every facet on every
    /// line: the fill as it was before session 35, for comparison.
    fn fill_by_every_node<const D: usize>(s: &ClosedSurface<D>, h: f64) -> Vec<Point<D>>
    where
        Const<D>: Dim,
    {
        let (n, lo) = s.lattice_size(h);
        let tol = 1e-6 * h;
        let jitter = [0.731_284_9e-7 * h, 0.412_907_3e-7 * h];
        let shifts: Vec<[f64; 2]> = if D == 2 {
            vec![[0.0, 0.0], [-1.0, 0.0], [1.0, 0.0]]
        } else {
            (-1..=1)
                .flat_map(|a| (-1..=1).map(move |b| [a as f64, b as f64]))
                .collect()
        };
        let nz = if D == 3 { n[2] + 1 } else { 1 };
        let mut out = Vec::new();
        for jz in 0..nz {
            for jy in 0..=n[1] {
                let y = lo[1] + jy as f64 * h;
                let z = if D == 3 {
                    lo[D - 1] + jz as f64 * h
                } else {
                    0.0
                };
                let mut intervals = Vec::new();
                for sh in &shifts {
                    let t = if D == 2 {
                        [y + sh[0] * tol, 0.0]
                    } else {
                        [y + sh[0] * tol + jitter[0], z + sh[1] * tol + jitter[1]]
                    };
                    let mut c: Vec<f64> = s
                        .facets
                        .chunks_exact(D)
                        .filter_map(|f| s.crossing(f, t))
                        .collect();
                    c.sort_by(f64::total_cmp);
                    intervals.extend(c.chunks_exact(2).map(|c| (c[0] - tol, c[1] + tol)));
                }
                for i in 0..=n[0] {
                    let x = lo[0] + i as f64 * h;
                    if intervals.iter().any(|&(a, b)| x >= a && x <= b) {
                        let mut p = Point::<D>::zeros();
                        p[0] = x;
                        p[1] = y;
                        if D == 3 {
                            p[D - 1] = z;
                        }
                        out.push(p);
                    }
                }
            }
        }
        out
    }

    /// The fill visits the lines near each facet's projection only, and
    /// places the same nodes in the same order as testing every node of
    /// the bounding box (a tilted octahedron, a star polygon); a needle
    /// 200 m long on a diagonal costs its facets' lines, not its bounding
    /// box's 4·10⁸ (session 35: it asked for a 9.6 GB table).
    #[test]
    fn the_fill_visits_the_facets_lines_only_and_places_every_node() {
        let (c, sn) = (0.3f64.cos(), 0.3f64.sin());
        let rot = |x: f64, y: f64, z: f64| {
            Point::<3>::new(
                c * x - sn * y + 0.51,
                sn * x + c * y + 0.49,
                0.2 * x + z + 0.5,
            )
        };
        let vertices = vec![
            rot(0.4, 0.0, 0.0),
            rot(-0.4, 0.0, 0.0),
            rot(0.0, 0.4, 0.0),
            rot(0.0, -0.4, 0.0),
            rot(0.0, 0.0, 0.4),
            rot(0.0, 0.0, -0.4),
        ];
        let facets = vec![
            0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5,
        ];
        let octa = ClosedSurface { vertices, facets };
        octa.check().unwrap();
        for h in [0.05, 0.021] {
            let a = octa.fill(h);
            assert!(a.len() > 50, "{}", a.len());
            assert_eq!(a, fill_by_every_node(&octa, h));
        }
        let star: Vec<Point<2>> = (0..10)
            .map(|k| {
                let r = if k % 2 == 0 { 1.0 } else { 0.4 };
                let t = k as f64 * std::f64::consts::PI / 5.0 + 0.1;
                Point::<2>::new(r * t.cos(), r * t.sin())
            })
            .collect();
        let star = ClosedSurface::polygon(star);
        star.check().unwrap();
        for h in [0.1, 0.013] {
            assert_eq!(star.fill(h), fill_by_every_node(&star, h));
        }
        // The needle: a thin tetrahedron along the diagonal.
        let l = 200.0;
        let needle = ClosedSurface {
            vertices: vec![
                Point::<3>::new(0.0, 0.0, 0.0),
                Point::<3>::new(l, l, l),
                Point::<3>::new(l, l + 1e-3, l),
                Point::<3>::new(l, l, l + 1e-3),
            ],
            facets: vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3],
        };
        needle.check().unwrap();
        let work = needle.fill_work(0.01);
        assert!(work < 1e6, "{work}");
        // Stopped as soon as it passes a cap, exact below it.
        let capped = needle.fill_work_up_to(0.01, 1000.0);
        assert!(capped > 1000.0 && capped < work, "{capped} of {work}");
        assert_eq!(needle.fill_work_up_to(0.01, work), work);
        // Its edge from the origin passes through the lattice's diagonal
        // nodes (on the surface: inside), 20 000 of them (the far end is
        // beyond the last whole spacing), and hardly more.
        let placed = needle.fill(0.01).len();
        assert!((20_000..21_000).contains(&placed), "{placed}");
    }

    #[test]
    fn open_and_bad_boundaries_are_refused() {
        let mut c = cube(1.0);
        c.facets.truncate(c.facets.len() - 3);
        assert!(c.check().unwrap_err().contains("not closed"));
        let mut c = cube(1.0);
        c.facets[0] = 99;
        assert!(c.check().is_err());
        // A triangle given twice with one winding is named as the repeat
        // it is, by its corners (it was "not closed"); rotated too.
        for rotate in [0, 1] {
            let mut c = cube(1.0);
            let t = [c.facets[0], c.facets[1], c.facets[2]];
            c.facets
                .extend_from_slice(&[t[rotate], t[(rotate + 1) % 3], t[(rotate + 2) % 3]]);
            let why = c.check().unwrap_err();
            assert!(
                why.starts_with("a triangle is given twice, with the same winding: (0, 0, 0)"),
                "{why}"
            );
        }
        // Reversed, it is a face shared by two parts (each edge used once
        // each way more): not named as a repeat.
        let mut c = cube(1.0);
        let t = [c.facets[0], c.facets[2], c.facets[1]];
        c.facets.extend_from_slice(&t);
        assert!(c.repeated_triangle().is_none());
        let two =
            ClosedSurface::polygon(vec![Point::<2>::new(0.0, 0.0), Point::<2>::new(1.0, 0.0)]);
        assert!(two.check().is_err());
        let mut c = cube(1.0);
        c.vertices[0][0] = f64::NAN;
        assert!(c.check().is_err());
        // Closed but with faces reversed (session 42's review): its signed
        // volume is near zero, and the memory estimate made from it let
        // the fill place 10⁸ particles.
        let mut c = cube(1.0);
        for f in c.facets[..12].chunks_exact_mut(3) {
            f.swap(1, 2);
        }
        assert!(c.check().unwrap_err().contains("not consistently oriented"));
        // Two cubes, one reversed as a whole: each is consistent, and the
        // measure is the sum of both (it cancelled to zero).
        let mut two = cube(1.0);
        let mut other = cube(1.0);
        for v in &mut other.vertices {
            v[0] += 3.0;
        }
        for f in other.facets.chunks_exact_mut(3) {
            f.swap(1, 2);
        }
        two.facets
            .extend(other.facets.iter().map(|&i| i + two.vertices.len() as u32));
        two.vertices.extend(other.vertices);
        two.check().unwrap();
        assert!((two.enclosed_measure() - 2.0).abs() < 1e-12);
        // Every face reversed is consistent (inside out is still closed).
        let mut c = cube(1.0);
        for f in c.facets.chunks_exact_mut(3) {
            f.swap(1, 2);
        }
        c.check().unwrap();
        // A polygon of many vertices out of order: refused before its
        // crossing grid is stored (its edges span the whole polygon).
        let n = 20_000u32;
        let ring: Vec<Point<2>> = (0..n)
            .map(|k| {
                // Every 7 919th vertex of a circle: a star of long chords.
                let t = 2.0 * std::f64::consts::PI * f64::from((k * 7_919) % n) / f64::from(n);
                Point::<2>::new(t.cos(), t.sin())
            })
            .collect();
        let why = ClosedSurface::polygon(ring).check().unwrap_err();
        assert!(why.contains("too long"), "{why}");
        // Back and forth along a line: no area, refused (it placed the
        // lattice nodes on the line).
        let line = ClosedSurface::polygon(vec![
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 1.0),
            Point::<2>::new(2.0, 2.0),
        ]);
        assert!(line.check().unwrap_err().contains("encloses no area"));
        // A polygon built by hand with one segment reversed.
        let mut p = ClosedSurface::polygon(vec![
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(1.0, 1.0),
            Point::<2>::new(0.0, 1.0),
        ]);
        p.facets.swap(2, 3);
        assert!(p.check().unwrap_err().contains("not consistently oriented"));
    }

    #[test]
    fn an_stl_file_round_trips() {
        let c = cube(0.5);
        let tris: Vec<stl_io::Triangle> = c
            .facets
            .chunks_exact(3)
            .map(|f| {
                let v = |a: usize| {
                    let p = c.vertices[f[a] as usize];
                    stl_io::Vector::new([p[0] as f32, p[1] as f32, p[2] as f32])
                };
                stl_io::Triangle {
                    normal: stl_io::Vector::new([0.0, 0.0, 0.0]),
                    vertices: [v(0), v(1), v(2)],
                }
            })
            .collect();
        let path = std::env::temp_dir().join(format!("pfem-cube-{}.stl", std::process::id()));
        // With a triangle repeating a vertex (no area) among them: dropped.
        let mut tris = tris;
        tris.push(stl_io::Triangle {
            normal: stl_io::Vector::new([0.0, 0.0, 0.0]),
            vertices: [
                tris[0].vertices[0],
                tris[0].vertices[0],
                tris[0].vertices[1],
            ],
        });
        let mut f = std::fs::File::create(&path).unwrap();
        stl_io::write_stl(&mut f, tris.iter()).unwrap();
        drop(f);
        let back = ClosedSurface::read_stl(&path, 2.0, [1.0, 0.0, 0.0]).unwrap();
        std::fs::remove_file(&path).ok();
        back.check().unwrap();
        assert_eq!(back.facets.len(), 36);
        assert_eq!(back.vertices.len(), 8);
        let (lo, hi) = back.bounds();
        assert_eq!(lo, Point::<3>::new(1.0, 0.0, 0.0));
        assert_eq!(hi, Point::<3>::new(2.0, 1.0, 1.0));
        assert!(ClosedSurface::read_stl(Path::new("/nonexistent.stl"), 1.0, [0.0; 3]).is_err());
    }

    /// Binary STL files as CAD programs write them (session 42's review):
    /// a header that begins with "solid" (read as text and refused), a
    /// vertex written −0.0 in one triangle and 0.0 in another (two vertices:
    /// "not closed"), and a header count that does not match the data
    /// (read short without a word).
    #[test]
    fn binary_stl_files_are_read_by_their_length() {
        let c = cube(0.5);
        let binary = |header: &[u8], count: u32, negative_zero: bool| {
            let mut b = vec![b' '; 80];
            b[..header.len()].copy_from_slice(header);
            b.extend_from_slice(&count.to_le_bytes());
            for (k, f) in c.facets.chunks_exact(3).enumerate() {
                b.extend_from_slice(&[0u8; 12]);
                for &v in f {
                    for x in c.vertices[v as usize].iter() {
                        let mut x = *x as f32;
                        if negative_zero && k == 0 && x == 0.0 {
                            x = -0.0;
                        }
                        b.extend_from_slice(&x.to_le_bytes());
                    }
                }
                b.extend_from_slice(&[0u8; 2]);
            }
            b
        };
        let read = |bytes: Vec<u8>| {
            let path = std::env::temp_dir().join(format!(
                "pfem-cube-bin-{}-{}.stl",
                std::process::id(),
                bytes.len() ^ bytes[0] as usize
            ));
            std::fs::write(&path, bytes).unwrap();
            let r = ClosedSurface::read_stl(&path, 1.0, [0.0; 3]);
            std::fs::remove_file(&path).ok();
            r
        };
        for header in [&b"solid exported by a CAD program"[..], b"binary"] {
            let s = read(binary(header, 12, true)).unwrap();
            s.check().unwrap();
            assert_eq!((s.vertices.len(), s.facets.len()), (8, 36));
        }
        let why = read(binary(b"binary", 11, false)).unwrap_err();
        assert!(why.contains("counts 11 triangles"), "{why}");
        // Cut short of its 84-byte header: refused, not a panic.
        assert!(read(binary(b"binary", 12, false)[..40].to_vec()).is_err());
        // A sparse file (no disk) larger than the memory budget allows:
        // refused before anything is read (session 45's review: a 10 GB
        // one was read whole).
        let path = std::env::temp_dir().join(format!("pfem-sparse-{}.stl", std::process::id()));
        let count = (crate::default_memory_budget() / STL_BYTES_PER_BYTE / 50.0) as u64 + 1;
        let mut f = std::fs::File::create(&path).unwrap();
        let mut head = vec![0u8; 80];
        head.extend_from_slice(&(count as u32).to_le_bytes());
        std::io::Write::write_all(&mut f, &head).unwrap();
        f.set_len(84 + 50 * count).unwrap();
        let r = ClosedSurface::read_stl(&path, 1.0, [0.0; 3]);
        std::fs::remove_file(&path).ok();
        let why = r.unwrap_err();
        assert!(why.contains("memory budget"), "{why}");
    }

    /// Session 41 (a review of hostile inputs): the crossing check took
    /// every pair of edges; a digitised profile of 2·10⁵ vertices (5 MB of
    /// scene file) took minutes, three times a run. It is checked through
    /// a grid of edges: such a circle is accepted, and the same circle
    /// with two neighbouring vertices swapped (a bowtie at one place) is
    /// refused.
    #[test]
    fn a_polygon_of_many_vertices_is_checked_for_crossings() {
        let n = 200_000;
        let circle: Vec<Point<2>> = (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                Point::<2>::new(a.cos(), a.sin())
            })
            .collect();
        ClosedSurface::polygon(circle.clone()).check().unwrap();
        let mut bowtie = circle;
        bowtie.swap(1000, 1001);
        let why = ClosedSurface::polygon(bowtie).check().unwrap_err();
        assert!(why.contains("crosses itself"), "{why}");
    }

    /// Two cubes of one surface: run into each other, refused (the fill
    /// left their overlap empty); apart, face to face, or one wholly inside
    /// the other (a cavity), accepted.
    #[test]
    fn overlapping_parts_of_a_surface_are_refused() {
        let two = |shift: [f64; 3], l2: f64| {
            let (a, b) = (cube(1.0), cube(l2));
            let mut vertices = a.vertices.clone();
            vertices.extend(
                b.vertices
                    .iter()
                    .map(|p| Point::<3>::new(p[0] + shift[0], p[1] + shift[1], p[2] + shift[2])),
            );
            let mut facets = a.facets.clone();
            facets.extend(b.facets.iter().map(|f| f + 8));
            ClosedSurface { vertices, facets }
        };
        let why = two([0.5, 0.4, 0.3], 1.0).check().unwrap_err();
        assert!(why.contains("crosses itself"), "{why}");
        let why = two([0.3, 0.2, -0.4], 1.0).check().unwrap_err();
        assert!(why.contains("crosses itself"), "{why}");
        for ok in [
            two([2.0, 0.0, 0.0], 1.0),
            two([1.0, 0.0, 0.0], 1.0),
            two([0.25, 0.25, 0.25], 0.5),
            // Face to face as an f32 file rounds them: 10⁻⁷ into each other.
            two([1.0 - 1e-7, 0.3, 0.2], 1.0),
        ] {
            ok.check().unwrap();
        }
    }
}
