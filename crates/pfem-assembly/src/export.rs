//! The library's own systems in Matrix Market form, to compare solvers
//! outside it (CHOLMOD, PETSc, SciPy) on exactly what a step solves.

use std::io::Write;
use std::path::PathBuf;

use faer::sparse::SparseColMatRef;

use crate::solver::{LinearSolver, SolveReport, SolverWork, SplitSystem};
use crate::SolveError;

/// Writes `a` as a Matrix Market `coordinate real general` file (1-based
/// indices, every stored entry).
pub fn write_matrix_market(
    w: &mut impl Write,
    a: SparseColMatRef<'_, usize, f64>,
) -> std::io::Result<()> {
    let nnz = a.compute_nnz();
    writeln!(w, "%%MatrixMarket matrix coordinate real general")?;
    writeln!(
        w,
        "% written by pfem (the monolithic system of one Picard iterate)"
    )?;
    writeln!(w, "{} {} {}", a.nrows(), a.ncols(), nnz)?;
    for j in 0..a.ncols() {
        for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            writeln!(w, "{} {} {:.17e}", i + 1, j + 1, v)?;
        }
    }
    Ok(())
}

/// Writes a right-hand side as a Matrix Market `array real general` file.
pub fn write_vector_market(w: &mut impl Write, b: &[f64]) -> std::io::Result<()> {
    writeln!(w, "%%MatrixMarket matrix array real general")?;
    writeln!(w, "{} 1", b.len())?;
    for v in b {
        writeln!(w, "{v:.17e}")?;
    }
    Ok(())
}

/// A [`LinearSolver`] that writes the whole matrix and the right-hand side
/// of its `n`-th solve (0 the first) to `<stem>.mtx` and `<stem>_rhs.mtx`,
/// then hands every solve to the solver it wraps. A split system is
/// written whole (`A_v + Cᵀ C`).
#[derive(Debug)]
pub struct MatrixExport {
    inner: Box<dyn LinearSolver>,
    stem: PathBuf,
    at: usize,
    seen: usize,
    error: Option<String>,
}

impl MatrixExport {
    /// Wraps `inner`; writes solve number `at` to `stem` (`.mtx` added).
    pub fn new(inner: Box<dyn LinearSolver>, stem: impl Into<PathBuf>, at: usize) -> Self {
        Self {
            inner,
            stem: stem.into(),
            at,
            seen: 0,
            error: None,
        }
    }

    /// Whether the system was written, and the I/O error if writing failed.
    pub fn written(&self) -> Result<bool, String> {
        match &self.error {
            Some(e) => Err(e.clone()),
            None => Ok(self.seen > self.at),
        }
    }

    fn write(&mut self, a: SparseColMatRef<'_, usize, f64>, b: &[f64]) {
        let go = || -> std::io::Result<()> {
            // `STEM.mtx` and `STEM_rhs.mtx`, the stem kept whole (a dot in
            // it is no extension to replace: `sys.t5` wrote `sys.mtx`).
            // (A stem given with its `.mtx` is taken without it.)
            let stem = match self.stem.to_str().and_then(|s| s.strip_suffix(".mtx")) {
                Some(s) => std::path::PathBuf::from(s),
                None => self.stem.clone(),
            };
            let mut matrix = stem.clone().into_os_string();
            matrix.push(".mtx");
            let mut f = std::io::BufWriter::new(std::fs::File::create(matrix)?);
            write_matrix_market(&mut f, a)?;
            f.flush()?;
            let mut stem = stem.into_os_string();
            stem.push("_rhs.mtx");
            let mut f = std::io::BufWriter::new(std::fs::File::create(stem)?);
            write_vector_market(&mut f, b)?;
            f.flush()
        };
        if let Err(e) = go() {
            self.error = Some(e.to_string());
        }
    }
}

impl LinearSolver for MatrixExport {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn settings(&self) -> String {
        self.inner.settings()
    }

    fn solve(
        &mut self,
        a: SparseColMatRef<'_, usize, f64>,
        generation: u64,
        b: &[f64],
        x: &mut [f64],
    ) -> Result<SolveReport, SolveError> {
        if self.seen == self.at {
            self.write(a, b);
        }
        self.seen += 1;
        self.inner.solve(a, generation, b, x)
    }

    fn resolve(&mut self, b: &[f64], x: &mut [f64]) -> Option<Result<(), SolveError>> {
        self.inner.resolve(b, x)
    }

    fn work(&self) -> SolverWork {
        self.inner.work()
    }

    fn set_accuracy(&mut self, relative_residual: Option<f64>) {
        self.inner.set_accuracy(relative_residual);
    }

    fn begin_loop(&mut self) {
        self.inner.begin_loop();
    }

    fn saddle_increment(&self, generation: u64) -> Option<&[f64]> {
        self.inner.saddle_increment(generation)
    }

    fn wants_split(&self, dofs: usize) -> bool {
        self.inner.wants_split(dofs)
    }

    fn solve_split(
        &mut self,
        sys: &SplitSystem<'_>,
        generation: u64,
        x: &mut [f64],
    ) -> Result<SolveReport, SolveError> {
        sys.check("matrix export", x)?;
        if self.seen == self.at {
            if sys.stabilisation.is_some() {
                let (k, b) = crate::block::saddle_system(sys)?;
                self.write(k.as_ref(), &b);
            } else {
                let a = sys.to_matrix()?;
                self.write(a.as_ref(), sys.rhs);
            }
        }
        self.seen += 1;
        self.inner.solve_split(sys, generation, x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};

    /// The two files are `STEM.mtx` and `STEM_rhs.mtx` with the stem kept
    /// whole: a stem with a dot (`sys.t5`) wrote `sys.mtx` before session
    /// 42 (and `sys.t5_rhs.mtx`).
    #[test]
    fn a_stem_with_a_dot_names_both_files() {
        let dir = std::env::temp_dir().join(format!("pfem-export-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(
            2,
            2,
            &[Triplet::new(0, 0, 2.0), Triplet::new(1, 1, 3.0)],
        )
        .unwrap();
        let mut x = vec![0.0; 2];
        let mut e = MatrixExport::new(
            Box::new(crate::DirectSolver::default()),
            dir.join("sys.t5"),
            0,
        );
        e.solve(a.as_ref(), 0, &[1.0, 1.0], &mut x).unwrap();
        assert_eq!(e.written(), Ok(true));
        assert!(dir.join("sys.t5.mtx").is_file());
        assert!(dir.join("sys.t5_rhs.mtx").is_file());
        assert!(!dir.join("sys.mtx").exists());
        let mut e = MatrixExport::new(
            Box::new(crate::DirectSolver::default()),
            dir.join("m.mtx"),
            0,
        );
        e.solve(a.as_ref(), 0, &[1.0, 1.0], &mut x).unwrap();
        assert!(dir.join("m.mtx").is_file() && dir.join("m_rhs.mtx").is_file());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_matrix_reads_back_from_its_matrix_market_text() {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(
            3,
            3,
            &[
                Triplet::new(0, 0, 4.0),
                Triplet::new(2, 0, -1.5),
                Triplet::new(1, 1, 1e-300),
                Triplet::new(0, 2, -1.5),
                Triplet::new(2, 2, 0.1),
            ],
        )
        .unwrap();
        let mut buf = Vec::new();
        write_matrix_market(&mut buf, a.as_ref()).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let mut lines = text.lines().filter(|l| !l.starts_with('%'));
        assert_eq!(lines.next(), Some("3 3 5"));
        let mut back = [[0.0f64; 3]; 3];
        for l in lines {
            let f: Vec<&str> = l.split_whitespace().collect();
            let (i, j): (usize, usize) = (f[0].parse().unwrap(), f[1].parse().unwrap());
            back[i - 1][j - 1] = f[2].parse().unwrap();
        }
        assert_eq!(back[0][0], 4.0);
        assert_eq!(back[2][0], -1.5);
        assert_eq!(back[0][2], -1.5);
        assert_eq!(back[1][1], 1e-300);
        assert_eq!(back[2][2], 0.1);
    }
}
