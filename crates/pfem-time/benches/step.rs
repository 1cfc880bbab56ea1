//! Assembly and solve of one Picard iteration on a structured 2D water
//! tank (real bulk modulus, hydrostatic pressure, trapezoidal-Newmark inertia
//! weights; the scheme changes only two scalars of the system) at 10k
//! and 100k particles: assembly alone, and assembly plus one solve with
//! sparse LU, sparse Cholesky and PCG (IC(0)), and the default path: the
//! split system (`Assembler::set_split`) and `BlockSolver`.
//!
//! `cargo bench -p pfem-time --bench step`
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use pfem_assembly::{
    Assembler, AssemblyInput, BlockSolver, ConjugateGradient, Constraints, Inertia, LinearSolver,
    SparseCholesky, SparseLu, StepMesh, VolumetricTreatment,
};
use pfem_constitutive::{History, Material, Newtonian};
use pfem_core::{Point, Vector};
use std::time::Duration;

struct Tank {
    x: Vec<Point<2>>,
    v: Vec<Vector<2>>,
    a: Vec<Vector<2>>,
    p: Vec<f64>,
    tris: Vec<u32>,
    mat: Vec<u16>,
    history: Vec<History<2>>,
    constraints: Constraints<2>,
    materials: Vec<Box<dyn Material<2>>>,
}

/// A water column on an `n × n` cell grid (`(n+1)²` particles), wall
/// particles on the bottom and sides.
fn tank(n: usize) -> Tank {
    let h = 1.0;
    let mut x = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            x.push(Point::<2>::new(
                h * i as f64 / n as f64,
                h * j as f64 / n as f64,
            ));
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                tris.extend_from_slice(&[a, b, c, a, c, d]);
            } else {
                tris.extend_from_slice(&[a, b, d, b, c, d]);
            }
        }
    }
    let np = x.len();
    let mut constraints = Constraints::<2>::free(np);
    for (i, q) in x.iter().enumerate() {
        if q.y < 1e-9 || q.x < 1e-9 || q.x > h - 1e-9 {
            constraints.fix(i, Vector::<2>::zeros());
        }
    }
    let p = x.iter().map(|q| 1000.0 * 9.81 * (h - q.y)).collect();
    let ne = tris.len() / 3;
    Tank {
        v: vec![Vector::<2>::zeros(); np],
        a: vec![Vector::<2>::zeros(); np],
        p,
        x,
        tris,
        mat: vec![0; ne],
        history: vec![History::default(); ne],
        constraints,
        materials: vec![Box::new(Newtonian::water())],
    }
}

fn input(t: &Tank) -> AssemblyInput<'_, 2> {
    let dt = 1e-3;
    AssemblyInput {
        x: &t.x,
        x_n: &t.x,
        v: &t.v,
        v_n: &t.v,
        a_n: &t.a,
        pressure_n: &t.p,
        element_history: &t.history,
        materials: &t.materials,
        constraints: &t.constraints,
        body_force: Some(Vector::<2>::new(0.0, -9.81)),
        dt,
        inertia: Inertia {
            mass_factor: 2.0 / dt,
            acceleration_factor: 1.0,
            displacement_weight: 0.5 * dt,
        },
        external_force: &[],
    }
}

/// An assembler prepared for the tank's mesh; `split` keeps the nodal
/// volumetric term apart (`Assembler::set_split`).
fn prepared(t: &Tank, split: bool) -> Assembler<2> {
    let mut asm = Assembler::<2>::new(VolumetricTreatment::NodalAveraged);
    asm.set_split(split);
    asm.prepare(
        t.x.len(),
        StepMesh {
            elements: &t.tris,
            element_material: &t.mat,
            closures: &[],
            surface_cuts: Default::default(),
            reference_volumes: &[],
            node_material: &[],
        },
        &t.materials,
    )
    .unwrap();
    asm
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("assembly_and_solve");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for (label, n) in [("10k", 99usize), ("100k", 315)] {
        let t = tank(n);
        let inp = input(&t);
        let mut asm = prepared(&t, false);
        let info = asm.assemble(&inp).unwrap();
        eprintln!(
            "{label}: {} particles, {} elements, {} dofs, {} nonzeros",
            t.x.len(),
            t.tris.len() / 3,
            info.dofs,
            info.nnz
        );
        g.bench_function(BenchmarkId::new("assemble", label), |b| {
            b.iter(|| asm.assemble(&inp).unwrap())
        });
        let solvers: Vec<Box<dyn LinearSolver>> = vec![
            Box::new(SparseLu::default()),
            Box::new(SparseCholesky::default()),
            Box::new(ConjugateGradient::default()),
        ];
        for mut s in solvers {
            let name = s.name().replace(' ', "_");
            let mut x = vec![0.0; asm.dofs()];
            // One check outside the timing: does this solver handle it?
            match s.solve(asm.matrix(), asm.generation(), asm.rhs(), &mut x) {
                Ok(r) => eprintln!(
                    "{label} {}: residual {:.1e}, {} iterations",
                    s.name(),
                    r.residual,
                    r.iterations
                ),
                Err(e) => {
                    eprintln!("{label} {}: failed: {e}", s.name());
                    continue;
                }
            }
            g.bench_function(BenchmarkId::new(format!("assemble+{name}"), label), |b| {
                b.iter(|| {
                    asm.assemble(&inp).unwrap();
                    x.iter_mut().for_each(|v| *v = 0.0);
                    s.solve(asm.matrix(), asm.generation(), asm.rhs(), &mut x)
                        .unwrap()
                })
            });
        }
        // The default path: the split system and BlockSolver.
        let mut split = prepared(&t, true);
        split.assemble(&inp).unwrap();
        let mut s = BlockSolver::default();
        let mut x = vec![0.0; split.dofs()];
        let gen = split.generation();
        let sys = split.split_system().unwrap();
        let r = s.solve_split(&sys, gen, &mut x).unwrap();
        eprintln!(
            "{label} {}: residual {:.1e}, {} iterations, split matrix {} nonzeros",
            s.name(),
            r.residual,
            r.iterations,
            sys.a_v.compute_nnz()
        );
        g.bench_function(BenchmarkId::new("assemble_split+block", label), |b| {
            b.iter(|| {
                split.assemble(&inp).unwrap();
                x.iter_mut().for_each(|v| *v = 0.0);
                let sys = split.split_system().unwrap();
                s.solve_split(&sys, gen, &mut x).unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
