//! The same scene gives bit-identical results with 1, 2 and 3 threads (issue
//! 17): every parallel loop of a step writes disjoint entries or reduces in
//! a fixed order.
//! `cargo test --release --test determinism`

use pfem::cases::{DamBreak, ElasticGate};
use pfem::prelude::*;

/// Final positions, velocities and pressures of `scene` run in a pool of
/// `threads` workers.
fn run(threads: usize, scene: impl Fn() -> Scene<2> + Send + Sync) -> Run {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut sim = Simulation::new(
            scene(),
            Box::new(Delaunay2::default()),
            StepParams::default(),
        )
        .unwrap();
        sim.run(&mut []).unwrap();
        let p = sim.particles();
        (
            p.x().to_vec(),
            p.v().to_vec(),
            p.pressure().to_vec(),
            sim.steps(),
        )
    })
}

fn dam_break() -> Scene<2> {
    DamBreak {
        spacing: 0.05715 / 10.0,
        end_time: 0.05,
        ..Default::default()
    }
    .scene()
}

fn gate() -> Scene<2> {
    ElasticGate {
        end_time: 0.01,
        ..Default::default()
    }
    .scene()
    .unwrap()
}

#[test]
fn one_two_and_three_threads_give_identical_results() {
    compare("dam break", dam_break);
    compare("elastic gate", gate);
}

fn compare(name: &str, scene: fn() -> Scene<2>) {
    let one = run(1, scene);
    // Three threads as well: the assembly scatters element matrices in
    // one part per thread, and a middle part owns neither end.
    for threads in [2, 3] {
        same(name, &one, &run(threads, scene), threads);
    }
}

type Run = (Vec<Point<2>>, Vec<Vector<2>>, Vec<f64>, u64);

fn same(name: &str, one: &Run, two: &Run, threads: usize) {
    println!(
        "{name}: {} steps with 1 thread, {} with {threads}",
        one.3, two.3
    );
    assert_eq!(one.3, two.3, "step counts differ");
    assert_eq!(one.0.len(), two.0.len());
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for i in 0..one.0.len() {
        assert_eq!(
            bits(one.0[i].as_slice()),
            bits(two.0[i].as_slice()),
            "position {i}"
        );
        assert_eq!(
            bits(one.1[i].as_slice()),
            bits(two.1[i].as_slice()),
            "velocity {i}"
        );
    }
    assert_eq!(bits(&one.2), bits(&two.2), "pressures");
}
