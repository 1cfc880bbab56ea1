//! 3D Delaunay tessellation speed: `cargo bench -p pfem-geometry --bench delaunay3`.
//! Figures and machine are recorded in `docs/benchmarks.md`.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use pfem_core::Point;
use pfem_geometry::{Delaunay3, Tessellation, Tessellator};

/// Uniform points in the unit cube from a fixed-seed SplitMix64.
fn random_points(n: usize, seed: u64) -> Vec<Point<3>> {
    let mut s = seed;
    let mut next = move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| Point::<3>::new(next(), next(), next()))
        .collect()
}

/// A `k × k × k` cubic lattice of spacing `h` (every cube cospherical).
fn lattice(k: usize, h: f64) -> Vec<Point<3>> {
    let mut pts = Vec::with_capacity(k * k * k);
    for i in 0..k {
        for j in 0..k {
            for l in 0..k {
                pts.push(Point::<3>::new(i as f64 * h, j as f64 * h, l as f64 * h));
            }
        }
    }
    pts
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("delaunay3");
    group.sample_size(10);
    let cases = [
        ("random", 10_000, random_points(10_000, 1)),
        ("random", 100_000, random_points(100_000, 2)),
        ("lattice", 27_000, lattice(30, 0.01)),
    ];
    for (name, n, pts) in &cases {
        let mut mesher = Delaunay3::default();
        let mut out = Tessellation::new(4);
        group.bench_with_input(BenchmarkId::new(*name, n), pts, |b, pts| {
            b.iter(|| mesher.tessellate(pts, &mut out).expect("tessellation"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
