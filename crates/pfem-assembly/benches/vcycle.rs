//! One V-cycle of the smoothed-aggregation multigrid (`amg::Amg::apply`)
//! with the levels' matrices kept in `f64` (`lean_levels: false`) or as
//! `f32` values and `u32` indices (`lean_levels: true`, the default), on a
//! 27-point 3D Laplacian plus a mass term (the shape of the pressure Schur
//! complement: about 27 entries a row) at 32³ and 48³ nodes.
//!
//! `cargo bench -p pfem-assembly --bench vcycle`
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use pfem_assembly::amg::{Amg, AmgOptions, Csr};
use std::time::Duration;

/// `27-point Laplacian + c I` on an `n³` grid (Neumann ends).
fn laplacian27(n: usize, c: f64) -> Csr {
    let id = |i: usize, j: usize, k: usize| (k * n + j) * n + i;
    let inside = |v: i64| (0..n as i64).contains(&v);
    let mut t = Vec::with_capacity(n * n * n * 27);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let row = id(i, j, k);
                let mut diag = c;
                for dk in -1i64..=1 {
                    for dj in -1i64..=1 {
                        for di in -1i64..=1 {
                            if (di, dj, dk) == (0, 0, 0) {
                                continue;
                            }
                            let (ii, jj, kk) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                            if inside(ii) && inside(jj) && inside(kk) {
                                t.push((row, id(ii as usize, jj as usize, kk as usize), -1.0));
                                diag += 1.0;
                            }
                        }
                    }
                }
                t.push((row, row, diag));
            }
        }
    }
    Csr::from_triplets(n * n * n, n * n * n, &t)
}

fn vcycle(c: &mut Criterion) {
    let mut g = c.benchmark_group("vcycle");
    g.sample_size(20).measurement_time(Duration::from_secs(4));
    for n in [32usize, 48] {
        let a = laplacian27(n, 1e-2);
        let r: Vec<f64> = (0..a.nrows)
            .map(|i| ((i * 7919) % 1000) as f64 / 1000.0 - 0.5)
            .collect();
        let mut z = vec![0.0; a.nrows];
        for lean in [false, true] {
            let opts = AmgOptions {
                lean_levels: lean,
                ..AmgOptions::default()
            };
            let amg = Amg::new(&a, None, &opts).expect("the hierarchy");
            let name = if lean { "lean" } else { "f64" };
            g.bench_with_input(BenchmarkId::new(name, a.nrows), &n, |b, _| {
                b.iter(|| amg.apply(&r, &mut z))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, vcycle);
criterion_main!(benches);
