//! Bare spade `bulk_load_stable` against the full 2D pipeline (Delaunay2 +
//! alpha shape + classification) on uniform random particles:
//! `cargo bench -p pfem-geometry --bench pipeline`. Figures and machine are
//! recorded in `docs/benchmarks.md`.
#![allow(missing_docs)] // criterion_group! generates an undocumented fn

use std::time::Duration;

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use pfem_core::{ParticleKind, Point};
use pfem_geometry::{
    alpha_shape_into, classify_into, AlphaShape, AlphaShapeParams, Classification, Delaunay2,
    Tessellation, Tessellator,
};
use spade::{DelaunayTriangulation, Point2, Triangulation};

/// Deterministic uniform points in the unit square (SplitMix64).
fn random_points(n: usize) -> Vec<Point<2>> {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n).map(|_| Point::<2>::new(next(), next())).collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("geometry2d");
    for &n in &[10_000usize, 100_000, 1_000_000] {
        let pts = random_points(n);
        let kinds = vec![ParticleKind::Fluid; n];
        let h = 1.0 / (n as f64).sqrt();
        let spacing = vec![h; n];
        g.sample_size(if n >= 1_000_000 { 10 } else { 20 });
        g.warm_up_time(Duration::from_secs(1));
        g.measurement_time(Duration::from_secs(if n >= 1_000_000 { 12 } else { 4 }));
        g.bench_with_input(
            BenchmarkId::new("spade_bulk_load_stable", n),
            &pts,
            |b, pts| {
                b.iter(|| {
                    let v: Vec<Point2<f64>> = pts.iter().map(|p| Point2::new(p.x, p.y)).collect();
                    let t = DelaunayTriangulation::<Point2<f64>>::bulk_load_stable(v).unwrap();
                    black_box(t.num_inner_faces())
                })
            },
        );
        let mut tess = Tessellation::default();
        let mut alpha = AlphaShape::default();
        let mut cls = Classification::default();
        let params = AlphaShapeParams::default();
        g.bench_with_input(
            BenchmarkId::new("delaunay_alpha_classify", n),
            &pts,
            |b, pts| {
                b.iter(|| {
                    Delaunay2::default().tessellate(pts, &mut tess).unwrap();
                    alpha_shape_into(pts, &kinds, &spacing, &tess, &params, &mut alpha).unwrap();
                    classify_into(pts, &kinds, &alpha.mesh, None, &mut cls).unwrap();
                    black_box(cls.boundary_facets.len())
                })
            },
        );
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
