//! Node-block sparsity pattern of the monolithic system.
//!
//! The matrix is stored column-major (CSC) with `D` consecutive dofs per
//! node; every nonzero node pair `(i, j)` owns a dense `D × D` block. Column
//! `(j, l)` holds, for each neighbour `i` of `j` in increasing order, the rows
//! `(i, 0) … (i, D−1)`, so the value of `(i,k; j,l)` sits at
//! `col_ptr[jD + l] + (p − adj_ptr[j]) D + k` with `p` the position of `i`
//! in `adj(j)`. Block positions are found once per step, when the mesh
//! changes; Picard iterations then fill values without any search.

/// A symmetric node-level adjacency in CSR form plus the dof-level CSC
/// structure derived from it.
#[derive(Debug, Clone, Default)]
pub struct BlockPattern {
    /// Spatial dimension (dofs per node).
    pub dim: usize,
    /// CSR row pointers of the node adjacency (`n + 1` entries).
    pub adj_ptr: Vec<usize>,
    /// Sorted neighbour lists (each node is its own neighbour).
    pub adj_idx: Vec<u32>,
    /// CSC column pointers of the dof-level matrix.
    pub col_ptr: Vec<usize>,
    /// CSC row indices of the dof-level matrix.
    pub row_idx: Vec<usize>,
    /// The unsorted neighbour lists while building, kept for their
    /// allocation: a new pattern every step is then written into memory
    /// already held instead of fresh pages (about 16 entries a tetrahedron,
    /// a hundred megabytes at 289k particles in 3D).
    scratch: Vec<u32>,
}

impl BlockPattern {
    /// Builds the pattern of `n` nodes from groups of mutually coupled
    /// nodes (each element's nodes, each nodal patch), given as a flat list
    /// of groups through `groups(visit)`, which calls `visit(&[u32])` once
    /// per group. `scratch` is reused between steps.
    pub fn build(&mut self, n: usize, dim: usize, mut groups: impl FnMut(&mut dyn FnMut(&[u32]))) {
        self.dim = dim;
        // Count, then fill, then sort/dedup per node.
        let mut count = vec![0usize; n + 1];
        groups(&mut |g: &[u32]| {
            for &a in g {
                count[a as usize] += g.len();
            }
        });
        let mut ptr = vec![0usize; n + 1];
        for i in 0..n {
            ptr[i + 1] = ptr[i] + count[i];
        }
        let mut fill = ptr.clone();
        let mut idx = std::mem::take(&mut self.scratch);
        idx.clear();
        idx.resize(ptr[n], 0);
        groups(&mut |g: &[u32]| {
            for &a in g {
                let f = &mut fill[a as usize];
                idx[*f..*f + g.len()].copy_from_slice(g);
                *f += g.len();
            }
        });
        self.adj_ptr.clear();
        self.adj_ptr.push(0);
        self.adj_idx.clear();
        for i in 0..n {
            let row = &mut idx[ptr[i]..ptr[i + 1]];
            row.sort_unstable();
            let mut last = u32::MAX;
            let mut has_self = false;
            for &j in row.iter() {
                if j != last {
                    self.adj_idx.push(j);
                    has_self |= j as usize == i;
                    last = j;
                }
            }
            if !has_self {
                // An unconnected node still owns its diagonal block.
                let pos = self.adj_ptr[i]
                    + self.adj_idx[self.adj_ptr[i]..].partition_point(|&j| (j as usize) < i);
                self.adj_idx.insert(pos, i as u32);
            }
            self.adj_ptr.push(self.adj_idx.len());
        }
        self.scratch = idx;
        // Dof-level CSC.
        self.col_ptr.clear();
        self.row_idx.clear();
        self.col_ptr.push(0);
        for j in 0..n {
            let nb = &self.adj_idx[self.adj_ptr[j]..self.adj_ptr[j + 1]];
            for _l in 0..dim {
                for &i in nb {
                    for k in 0..dim {
                        self.row_idx.push(i as usize * dim + k);
                    }
                }
                self.col_ptr.push(self.row_idx.len());
            }
        }
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.adj_ptr.len().saturating_sub(1)
    }

    /// Number of dofs (matrix dimension).
    pub fn dofs(&self) -> usize {
        self.nodes() * self.dim
    }

    /// Number of stored values.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Block position `p` of node pair `(i, j)`: index into `adj_idx` of `i`
    /// within `adj(j)`. `None` if the pair is not in the pattern.
    pub fn block(&self, i: u32, j: u32) -> Option<u32> {
        let (s, e) = (self.adj_ptr[j as usize], self.adj_ptr[j as usize + 1]);
        self.adj_idx[s..e]
            .binary_search(&i)
            .ok()
            .map(|p| (s + p) as u32)
    }

    /// Value index of entry `(i,k; j,l)` from its block position `p`
    /// (see [`BlockPattern::block`]).
    #[inline]
    pub fn value_index(&self, p: u32, j: u32, k: usize, l: usize) -> usize {
        let (base, stride) = self.block_layout(p, j);
        base + l * stride + k
    }

    /// Where the block `p` of node column `j` lies in the values: entry
    /// `(k, l)` of the block is at `base + l · stride + k`
    /// ([`BlockPattern::value_index`], for a caller that writes a whole
    /// block).
    #[inline]
    pub fn block_layout(&self, p: u32, j: u32) -> (usize, usize) {
        let j = j as usize;
        let s = self.adj_ptr[j];
        let deg = self.adj_ptr[j + 1] - s;
        let d = self.dim;
        (s * d * d + (p as usize - s) * d, deg * d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_of_two_triangles_matches_a_dense_search() {
        let tris: [[u32; 3]; 2] = [[0, 1, 2], [1, 3, 2]];
        let mut p = BlockPattern::default();
        p.build(5, 2, |visit| {
            for t in &tris {
                visit(t);
            }
        });
        assert_eq!(p.dofs(), 10);
        // node 4 is unconnected but has its diagonal block
        assert!(p.block(4, 4).is_some());
        assert!(p.block(0, 3).is_none());
        for &(i, j) in &[(0u32, 1u32), (2, 3), (3, 3), (1, 0)] {
            let b = p.block(i, j).unwrap();
            for k in 0..2 {
                for l in 0..2 {
                    let vi = p.value_index(b, j, k, l);
                    let col = j as usize * 2 + l;
                    assert!(vi >= p.col_ptr[col] && vi < p.col_ptr[col + 1]);
                    assert_eq!(p.row_idx[vi], i as usize * 2 + k);
                }
            }
        }
    }
}
