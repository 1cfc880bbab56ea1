//! Times each phase of the 2D pipeline on random particles.
use std::time::Instant;

use pfem_core::{ParticleKind, Point};
use pfem_geometry::{
    alpha_shape_into, classify_into, AlphaShape, AlphaShapeParams, Classification, Delaunay2,
    Tessellation, Tessellator,
};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000);
    let mut s = 1u64;
    let mut next = || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let pts: Vec<Point<2>> = (0..n).map(|_| Point::<2>::new(next(), next())).collect();
    let kinds = vec![ParticleKind::Fluid; n];
    let spacing = vec![1.0 / (n as f64).sqrt(); n];
    let (mut t, mut a, mut c) = (
        Tessellation::default(),
        AlphaShape::default(),
        Classification::default(),
    );
    for _ in 0..5 {
        let t0 = Instant::now();
        let v: Vec<spade::Point2<f64>> = pts.iter().map(|p| spade::Point2::new(p.x, p.y)).collect();
        let _tri = spade::DelaunayTriangulation::<spade::Point2<f64>>::bulk_load_stable(v).unwrap();
        let t1 = Instant::now();
        Delaunay2::default().tessellate(&pts, &mut t).unwrap();
        let t2 = Instant::now();
        alpha_shape_into(
            &pts,
            &kinds,
            &spacing,
            &t,
            &AlphaShapeParams::default(),
            &mut a,
        )
        .unwrap();
        let t3 = Instant::now();
        classify_into(&pts, &kinds, &a.mesh, None, &mut c).unwrap();
        let t4 = Instant::now();
        println!(
            "spade {:.1} ms, delaunay2 {:.1} ms, alpha {:.1} ms, classify {:.1} ms",
            (t1 - t0).as_secs_f64() * 1e3,
            (t2 - t1).as_secs_f64() * 1e3,
            (t3 - t2).as_secs_f64() * 1e3,
            (t4 - t3).as_secs_f64() * 1e3
        );
    }
}
