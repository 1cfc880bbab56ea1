//! faer's sparse Cholesky, the factorisation behind `DirectSolver`, on a
//! system exported as Matrix Market (`solver_scaling --export`): times the
//! analysis (ordering and symbolic factorisation), the numeric
//! factorisation and one solve, best of `--repeat` runs, and prints the
//! factor's size, in the format of `tools/cholmod_factor.c`, so that the
//! two stand side by side on the same matrix (issue 18;
//! `tools/cholmod_side_by_side.sh` runs both).
//!
//! ```text
//! cargo run --release --example factor_mtx -- STEM.mtx [--rhs STEM_rhs.mtx] [--repeat 3] [--threads 1]
//! ```

use std::time::Instant;

use faer::col::ColMut;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Par, Side};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

fn main() {
    if let Err(e) = run() {
        pfem::errln!("error: {e}");
        std::process::exit(1);
    }
}

/// A Matrix Market `coordinate real general|symmetric` file (both
/// triangles on return).
fn read_matrix(path: &str) -> Res<SparseColMat<usize, f64>> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut lines = text.lines();
    let header = lines.next().ok_or("empty file")?.to_lowercase();
    if !header.starts_with("%%matrixmarket matrix coordinate real") {
        return Err(format!("{path}: not a coordinate real Matrix Market file").into());
    }
    let symmetric = header.contains("symmetric");
    let mut lines = lines.filter(|l| !l.starts_with('%') && !l.trim().is_empty());
    let size: Vec<usize> = lines
        .next()
        .ok_or("no size line")?
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let [n, m, nnz] = size[..] else {
        return Err("bad size line".into());
    };
    let mut t = Vec::with_capacity(if symmetric { 2 * nnz } else { nnz });
    for l in lines {
        let mut w = l.split_whitespace();
        let (i, j, v): (usize, usize, f64) = (
            w.next().ok_or("short line")?.parse()?,
            w.next().ok_or("short line")?.parse()?,
            w.next().ok_or("short line")?.parse()?,
        );
        if i == 0 || j == 0 || i > n || j > m {
            return Err(format!("{path}: entry ({i}, {j}) outside {n} × {m}").into());
        }
        t.push(Triplet::new(i - 1, j - 1, v));
        if symmetric && i != j {
            t.push(Triplet::new(j - 1, i - 1, v));
        }
    }
    Ok(SparseColMat::try_new_from_triplets(n, m, &t).map_err(|e| format!("{e:?}"))?)
}

/// A Matrix Market `array real general` vector.
fn read_vector(path: &str) -> Res<Vec<f64>> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut lines = text
        .lines()
        .filter(|l| !l.starts_with('%') && !l.trim().is_empty());
    lines.next().ok_or("no size line")?;
    Ok(lines.map(|l| l.trim().parse()).collect::<Result<_, _>>()?)
}

fn run() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let opt = |name: &str| {
        args.iter()
            .position(|a| a == &format!("--{name}"))
            .and_then(|i| args.get(i + 1).cloned())
    };
    let path = args
        .first()
        .filter(|a| !a.starts_with("--"))
        .ok_or("usage: factor_mtx STEM.mtx [--rhs STEM_rhs.mtx] [--repeat 3] [--threads 1]")?;
    let repeat: usize = opt("repeat").map(|s| s.parse()).transpose()?.unwrap_or(3);
    let threads: usize = opt("threads").map(|s| s.parse()).transpose()?.unwrap_or(1);
    let par = if threads > 1 {
        Par::rayon(threads)
    } else {
        Par::Seq
    };
    let a = read_matrix(path)?;
    let n = a.nrows();
    let b = match opt("rhs") {
        Some(p) => read_vector(&p)?,
        None => vec![1.0; n],
    };
    if b.len() != n {
        return Err(format!("right-hand side has {} entries, matrix {n} rows", b.len()).into());
    }
    let (mut t_an, mut t_fa, mut t_so) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let mut x = b.clone();
    let mut nnz_l = 0;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        let sym = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .map_err(|e| format!("{e:?}"))?;
        t_an = t_an.min(t.elapsed().as_secs_f64());
        nnz_l = sym.len_val();
        let t = Instant::now();
        let mut l = vec![0.0; sym.len_val()];
        let mut mem =
            MemBuffer::try_new(sym.factorize_numeric_llt_scratch::<f64>(par, Default::default()))?;
        sym.factorize_numeric_llt::<f64>(
            &mut l,
            a.as_ref(),
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|e| format!("{e:?}"))?;
        t_fa = t_fa.min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        x.copy_from_slice(&b);
        let mut mem = MemBuffer::try_new(sym.solve_in_place_scratch::<f64>(1, par))?;
        LltRef::new(&sym, &l).solve_in_place_with_conj(
            Conj::No,
            ColMut::from_slice_mut(&mut x).as_mat_mut(),
            par,
            MemStack::new(&mut mem),
        );
        t_so = t_so.min(t.elapsed().as_secs_f64());
    }
    let residual = pfem::assembly::solver::relative_residual(a.as_ref(), &b, &x);
    pfem::outln!(
        "faer(threads {threads}) n {n} nnz(A) {} nnz(L) {nnz_l} analyse {t_an:.4} s factorise {t_fa:.4} s solve {t_so:.4} s residual {residual:.2e}",
        a.compute_nnz()
    );
    Ok(())
}
