//! The same scene gives bit-identical results with 1, 2 and 3 threads (issue
//! 17): every parallel loop of a step writes disjoint entries or reduces in
//! a fixed order.
//! `cargo test --release --test suite determinism::`

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

/// The stabilised multigrid path (GMRES, the block preconditioner, the
/// multigrid set-up, the parallel assembly's parts) on a system above the
/// size where its vector operations and products run in parallel (20 000
/// rows): 23k particles, three steps.
#[test]
fn the_multigrid_path_gives_identical_results_on_one_and_two_threads() {
    let run = |threads: usize| -> Run {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut c = DamBreak::default();
            c.spacing = c.width / 100.0;
            let params = StepParams {
                pressure_stabilisation: 1.0,
                ..StepParams::default()
            };
            let mut sim =
                Simulation::new(c.scene(), Box::new(Delaunay2::default()), params).unwrap();
            let mut solver = pfem::assembly::BlockSolver::default();
            solver.pressure = pfem::assembly::PressureSolve::Multigrid;
            sim.set_solver(Box::new(solver));
            assert!(sim.particles().len() > 22_000, "{}", sim.particles().len());
            while sim.steps() < 3 {
                sim.step().unwrap();
            }
            assert!(sim.work().solver_iterations > 0, "the multigrid path ran");
            let p = sim.particles();
            (
                p.x().to_vec(),
                p.v().to_vec(),
                p.pressure().to_vec(),
                sim.steps(),
            )
        })
    };
    same("multigrid dam break", &run(1), &run(2), 2);
}

fn compare(name: &str, scene: fn() -> Scene<2>) {
    let one = run(1, scene);
    // Three threads as well: each part of the assembly owns a range of
    // nodes, and a middle part owns neither end.
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
