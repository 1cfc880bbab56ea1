//! 3D end to end: scenes through `Simulation::<3>` with `Delaunay3`.

use pfem::prelude::*;

const G: f64 = 9.81;

fn centroid_y(sim: &Simulation<3>, idx: &[usize]) -> f64 {
    idx.iter().map(|&i| sim.particles().x()[i].y).sum::<f64>() / idx.len() as f64
}

/// A 0.1 m water cube with no walls falls freely: its centroid follows
/// `y0 − g t²/2`. The exact solution is stress-free, so the hydrostatic
/// pressure the scene starts with is zeroed (and the initial acceleration
/// set to `g`).
#[test]
fn free_fall_of_a_water_block() {
    let h = 0.025;
    let t_end = 0.1;
    let scene = Scene::<3>::new("free_fall_3d")
        .gravity(Vector::<3>::new(0.0, -G, 0.0))
        .settings(RunSettings {
            end_time: t_end,
            max_dt: 5e-3,
            output_interval: None,
            ..Default::default()
        })
        .fluid(
            "water",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<3>::new(0.0, 0.0, 0.0),
                max: Point::<3>::new(0.1, 0.1, 0.1),
            },
            h,
        );
    let mut sim = Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default())
        .expect("3D scene builds");
    for i in 0..sim.particles().len() {
        sim.particles_mut().pressure_mut()[i] = 0.0;
        sim.particles_mut().a_mut()[i] = Vector::<3>::new(0.0, -G, 0.0);
    }
    let water = sim.body_particles("water").unwrap();
    let y0 = centroid_y(&sim, &water);
    sim.run(&mut []).expect("runs");
    let fall = y0 - centroid_y(&sim, &water);
    let exact = 0.5 * G * sim.time() * sim.time();
    let err = (fall - exact).abs() / exact;
    eprintln!(
        "free fall 3D: {} steps, fall {fall:.6e} vs {exact:.6e} (relative error {err:e})",
        sim.steps(),
    );
    // The scheme is exact for a constant acceleration, and a block with no
    // pressure falls rigidly (the bound was 5·10⁻³ until session 42).
    assert!(err < 1e-9, "centroid fell {fall} m, free fall {exact} m");
}

/// A tiny 3D column collapse (§9.1 geometry, h = a/5, two spacings deep)
/// runs to its end time with finite state and its front moving forward.
#[test]
fn tiny_column_collapse_runs_to_its_end() {
    use pfem::cases3d::WaterColumn3d;
    let case = WaterColumn3d {
        spacing: 0.146 / 5.0,
        depth: 4.0 * 0.146 / 5.0,
        end_time: 0.15,
        ..Default::default()
    };
    let mut sim = Simulation::new(
        case.scene(),
        Box::new(Delaunay3::default()),
        StepParams::default(),
    )
    .expect("3D scene builds");
    let v0 = sim.fluid_volume();
    sim.run(&mut []).expect("runs to the end");
    assert!(sim.time() >= case.end_time - 1e-12);
    assert!(sim
        .particles()
        .x()
        .iter()
        .all(|p| p.iter().all(|v| v.is_finite())));
    assert!(sim
        .particles()
        .v()
        .iter()
        .all(|v| v.iter().all(|c| c.is_finite())));
    let front = pfem::cases3d::front_x(&sim);
    let dv = sim.fluid_volume() / v0 - 1.0;
    eprintln!(
        "tiny collapse: {} steps ({} rejected), front {front:.3} m, volume {:+.2}%",
        sim.steps(),
        sim.rejected(),
        100.0 * dv
    );
    assert!(front > case.width + 0.02, "front at {front} m");
}

/// A cylinder solid: its own mesh (Delaunay + alpha shape) covers every
/// particle, the bottom disk is clamped, a few steps run.
#[test]
fn clamped_cylinder_in_water_builds_and_steps() {
    use pfem::cases3d::{ColumnOnCylinder3d, WaterColumn3d};
    let case = ColumnOnCylinder3d {
        column: WaterColumn3d {
            spacing: 0.146 / 5.0,
            depth: 2.0 * 0.146 / 5.0,
            end_time: 0.01,
            ..Default::default()
        },
        cylinder_x: 0.3,
        ..Default::default()
    };
    let mut sim = Simulation::new(
        case.scene().expect("valid cylinder"),
        Box::new(Delaunay3::default()),
        StepParams::default(),
    )
    .expect("builds");
    let cyl = sim.body_particles("cylinder").unwrap();
    let mut used = vec![false; sim.particles().len()];
    for &p in sim.elements().solid() {
        used[p as usize] = true;
    }
    assert!(
        cyl.iter().all(|&i| used[i]),
        "every cylinder particle in a solid element"
    );
    let clamped = cyl
        .iter()
        .filter(|&&i| sim.particles().constraints().is_fully_fixed(i))
        .count();
    assert_eq!(clamped, 13, "the bottom disk (13 particles at r = 2 h)");
    sim.run(&mut []).expect("runs");
    assert!(sim
        .particles()
        .x()
        .iter()
        .all(|p| p.iter().all(|v| v.is_finite())));
}

/// A cylinder is a 3D geometry: a 2D scene with one is rejected by a typed
/// error.
#[test]
fn a_cylinder_in_2d_is_rejected() {
    let scene = Scene::<2>::new("c2").fluid(
        "water",
        Box::new(Newtonian::water()),
        Geometry::Cylinder {
            base: Point::<2>::new(0.0, 0.0),
            axis: 1,
            radius: 0.1,
            height: 0.2,
        },
        0.02,
    );
    assert!(matches!(
        scene.validate(),
        Err(pfem::SceneError::InvalidGeometry { .. })
    ));
}

/// Runs the 2D dam break (Martin & Moyce, n² = 2) and the same case as a
/// 3D slab one spacing deep with slip side planes, at the same spacing
/// (`a / divisions`), and returns the RMS difference of their fronts (m),
/// the column width, and the RMS of the relative difference
/// `(x₃ − x₂)/x₂`.
fn dam_break_2d_vs_slab(end_time: f64, divisions: f64) -> (f64, f64, f64) {
    use pfem::cases::DamBreak;
    use pfem::cases3d::{slip_sides, thin_dam_break};
    let mut case = DamBreak::default();
    case.spacing = case.width / divisions;
    case.end_time = end_time;
    let mut s2 = Simulation::new(
        case.scene(),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    let mut front2 = Vec::new();
    while s2.time() < case.end_time - 1e-12 {
        s2.step().unwrap();
        front2.push((s2.time(), pfem::cases::front_x(&s2)));
    }
    let mut s3 = Simulation::new(
        thin_dam_break(&case),
        Box::new(Delaunay3::default()),
        StepParams::default(),
    )
    .unwrap();
    slip_sides(&mut s3);
    let mut front3 = Vec::new();
    while s3.time() < case.end_time - 1e-12 {
        s3.step().unwrap();
        front3.push((s3.time(), pfem::cases3d::front_x(&s3)));
    }
    let mut worst: f64 = 0.0;
    let mut sq = 0.0;
    let mut rel = 0.0;
    for &(t, x3) in &front3 {
        let x2 = pfem::cases::interpolate(&front2, t);
        worst = worst.max((x3 - x2).abs());
        sq += (x3 - x2).powi(2);
        rel += ((x3 - x2) / x2).powi(2);
    }
    let rms = (sq / front3.len() as f64).sqrt();
    let rel = (rel / front3.len() as f64).sqrt();
    eprintln!(
        "dam break a/{divisions}: 2D {} steps, 3D slab {} steps ({} rejected); fronts at the end 2D {:.4} m, 3D {:.4} m; largest difference {:.4} m ({:.1}% of a), RMS {:.4} m ({:.1}% of a)",
        s2.steps(), s3.steps(), s3.rejected(),
        front2.last().unwrap().1, front3.last().unwrap().1, worst, 100.0 * worst / case.width, rms, 100.0 * rms / case.width
    );
    eprintln!("relative RMS difference of the fronts: {:.2}%", 100.0 * rel);
    (rms, case.width, rel)
}

/// T = t √(2g/a) at which the quasi-2D comparisons end.
const QUASI_2D_T: f64 = 3.2;

/// Quasi-2D check of 3D against 2D (issue 6: within 5 %) at the 2D
/// example's default resolution (a/20): the dam break as a slab one
/// spacing deep with slip side planes follows the 2D front to
/// T = t √(2g/a) = 3.2, RMS of the relative front difference below 5 %.
/// Measured 2.02 % (the same with slivers foreseen; 2.76 % before
/// ARCHITECTURE.md deviation 13;
/// docs/benchmarks.md); about 20 s in release on 2 cores (about 100 s
/// before deviation 13, when it was an ignored test).
#[test]
fn quasi_2d_dam_break_follows_the_2d_front() {
    let (_, _, rel) = dam_break_2d_vs_slab(QUASI_2D_T / (2.0 * G / 0.05715f64).sqrt(), 20.0);
    assert!(rel < 0.05, "fronts differ by {:.2}% (RMS)", 100.0 * rel);
}

/// The same check at a/14 in the default suite (about 35 s in release),
/// same 5 % bound: measured 4.52 % in session 18 (4.39 % before slivers
/// were foreseen, ARCHITECTURE.md deviation 13; an earlier session
/// measured 1.38 %). At a/10 the comparison gives 5.10 %:
/// there the 2D front itself advances in jumps (0.132, 0.178, 0.220,
/// 0.221 m at T = 2.0, 2.4, 2.8, 3.2), too coarse to compare with.
#[test]
fn quasi_2d_dam_break_follows_the_2d_front_at_a_14() {
    let (_, _, rel) = dam_break_2d_vs_slab(QUASI_2D_T / (2.0 * G / 0.05715f64).sqrt(), 14.0);
    assert!(rel < 0.05, "fronts differ by {:.2}% (RMS)", 100.0 * rel);
}

/// Water (a 0.2 m cube, h = 0.02 m) at rest in a closed tank with no-slip
/// side walls, to 0.3 s. (Water at rest itself is `tests/water_at_rest_3d.rs`.)
fn rest_tank() -> Simulation<3> {
    use pfem::cases3d::tank3d;
    let (a, h) = (0.2, 0.02);
    let scene = Scene::<3>::new("rest3d")
        .gravity(Vector::<3>::new(0.0, -G, 0.0))
        .settings(RunSettings {
            end_time: 0.3,
            max_dt: 5e-3,
            courant: 0.5,
            output_interval: None,
            alpha: 1.3,
        });
    let scene = tank3d(scene, a, a, 1.2 * a, h, true).fluid(
        "water",
        Box::new(Newtonian::water()),
        Geometry::Box {
            min: Point::<3>::new(0.0, 0.0, 0.0),
            max: Point::<3>::new(a, a, a),
        },
        h,
    );
    Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default()).unwrap()
}

/// The walls and the water of the tank are lattices generated from
/// different origins, so the same grid point can be `0.04` in one and
/// `0.039999999999999994` in the other; the last-bit differences make flat
/// slivers of cospherical lattice cubes, which the alpha shape drops as
/// elements. The holes they leave are sealed voids, not free surface: only
/// the top layer of the water is free surface. (Before sealing, hundreds of
/// interior particles were tagged free surface and the volume correction
/// moved nearly all of them.)
#[test]
fn sliver_holes_in_a_3d_tank_are_not_free_surface() {
    use pfem::geometry::{alpha_shape, classify, AlphaShapeParams, NodeTag, Tessellation};
    let sim = rest_tank();
    let mut t = Tessellation::default();
    Delaunay3::default()
        .tessellate(sim.particles().x(), &mut t)
        .unwrap();
    let shape = alpha_shape(
        sim.particles().x(),
        sim.particles().kind(),
        sim.particles().spacing(),
        &t,
        &AlphaShapeParams::default(),
    )
    .unwrap();
    let cls = classify(
        sim.particles().x(),
        sim.particles().kind(),
        &shape.mesh,
        None,
    )
    .unwrap();
    let below_top = (0..sim.particles().len())
        .filter(|&i| cls.tags[i] == NodeTag::FreeSurface && sim.particles().x()[i].y < 0.19)
        .count();
    assert_eq!(
        below_top, 0,
        "{below_top} particles below the top layer tagged free surface ({} slivers sealed)",
        shape.sealed
    );
    assert!(shape.sealed > 0, "the lattices no longer make slivers");
}

/// The 3D water column's first 0.15 s take few rejected attempts (issue
/// 18, item 3) by default: poor tetrahedra keep their start-of-step shape
/// through the step (`StepParams::sliver_quality_3d`, ARCHITECTURE.md
/// deviation 13) instead of inverting in it. With that off the same run
/// rejects a large share of its steps; leaving the poor tetrahedra out of
/// the mesh (`Options::min_quality_3d`, "options measured and left off")
/// also avoids the rejections. The front is the same within 3 %.
#[test]
fn poor_tetrahedra_do_not_reject_attempts_of_the_3d_water_column() {
    let run = |sliver_quality: f64, min_quality_3d: f64| {
        let case = pfem::cases3d::WaterColumn3d {
            side_walls: false,
            end_time: 0.15,
            ..Default::default()
        };
        let options = Options {
            min_quality_3d,
            ..Options::default()
        };
        let params = StepParams {
            sliver_quality_3d: sliver_quality,
            ..StepParams::default()
        };
        let mut sim = Simulation::with_options(
            case.scene(),
            Box::new(Delaunay3::default()),
            params,
            options,
        )
        .unwrap();
        pfem::cases3d::slip_sides(&mut sim);
        sim.run(&mut []).unwrap();
        (sim.steps(), sim.rejected(), pfem::cases3d::front_x(&sim))
    };
    let round_off = pfem::geometry::MIN_SHAPE_QUALITY;
    let (steps, rejected, front) = run(pfem::time::SLIVER_QUALITY_3D, round_off);
    let (steps0, rejected0, front0) = run(0.0, round_off);
    let (steps1, rejected1, front1) = run(0.0, pfem::geometry::MIN_ELEMENT_QUALITY_3D);
    println!(
        "3D water column to 0.15 s: default: {steps} steps, {rejected} rejected, front {front:.4} m; \
         slivers not kept in shape: {steps0} steps, {rejected0} rejected, front {front0:.4} m; \
         left out instead: {steps1} steps, {rejected1} rejected, front {front1:.4} m"
    );
    for (r, s) in [(rejected, steps), (rejected1, steps1)] {
        assert!(r as f64 <= 0.05 * s as f64, "{r} of {s} steps rejected");
    }
    assert!(rejected0 as f64 > 0.05 * steps0 as f64);
    for f in [front0, front1] {
        assert!((front / f - 1.0).abs() < 0.03, "{front} vs {f}");
    }
    // The options are checked.
    let bad_floor = Options {
        min_quality_3d: 0.6,
        ..Options::default()
    };
    let bad_sliver = StepParams {
        sliver_quality_3d: 0.5,
        ..StepParams::default()
    };
    for (params, options) in [
        (StepParams::default(), bad_floor),
        (bad_sliver, Options::default()),
    ] {
        let scene = pfem::cases3d::WaterColumn3d::default().scene();
        assert!(
            Simulation::with_options(scene, Box::new(Delaunay3::default()), params, options)
                .is_err()
        );
    }
}

/// The remeshing leaves out the walls far from the water and the cylinder
/// (`Options::tessellate_far_walls`, default false): the fluid elements,
/// the sealed slivers and the wall pockets are the same as when every wall
/// is tessellated, step after step, and the particles move alike (to
/// round-off: the elements come in another order).
#[test]
fn leaving_out_the_far_walls_changes_no_element() {
    use pfem::cases3d::{ColumnOnCylinder3d, WaterColumn3d};
    let case = ColumnOnCylinder3d {
        column: WaterColumn3d {
            spacing: 0.146 / 5.0,
            end_time: 0.01,
            ..Default::default()
        },
        ..Default::default()
    };
    let sim = |tessellate_far_walls: bool| {
        Simulation::with_options(
            case.scene().expect("valid cylinder"),
            Box::new(Delaunay3::default()),
            StepParams::default(),
            Options {
                tessellate_far_walls,
                ..Options::default()
            },
        )
        .expect("builds")
    };
    let (mut near, mut all) = (sim(false), sim(true));
    let mut kept = Vec::new();
    assert!(
        pfem::geometry::near_matter(
            near.particles().x(),
            near.particles().kind(),
            3.0 * 1.3 * 0.146 / 5.0,
            &mut kept
        ),
        "the scene has far walls"
    );
    println!(
        "tessellated {} of {} particles",
        kept.len(),
        near.particles().len()
    );
    let canon = |v: &[u32]| {
        let mut o: Vec<Vec<u32>> = v
            .chunks(4)
            .map(|c| {
                let mut c = c.to_vec();
                c.sort_unstable();
                c
            })
            .collect();
        o.sort();
        o
    };
    for step in 0..6 {
        let (a, b) = (near.elements().shape(), all.elements().shape());
        assert!(!a.mesh.is_empty());
        assert_eq!(
            canon(&a.mesh.simplices),
            canon(&b.mesh.simplices),
            "step {step}"
        );
        assert_eq!(canon(&a.closures), canon(&b.closures), "step {step}");
        assert_eq!(
            canon(&a.wall_pockets),
            canon(&b.wall_pockets),
            "step {step}"
        );
        assert!((a.kept_measure - b.kept_measure).abs() <= 1e-12 * b.kept_measure);
        near.step().expect("steps");
        all.step().expect("steps");
    }
    let scale = all
        .particles()
        .v()
        .iter()
        .fold(0.0f64, |m, v| m.max(v.norm()));
    let gap = near
        .particles()
        .v()
        .iter()
        .zip(all.particles().v())
        .fold(0.0f64, |m, (p, q)| m.max((p - q).norm()));
    println!("largest velocity difference {gap:.3e} of {scale:.3e} m/s");
    assert!(gap <= 1e-6 * scale, "{gap:e} of {scale:e}");
}

/// A cantilever of square section in 3D, clamped at `x = 0`, under its
/// weight: Timoshenko's static tip deflection (E, shear factor 5/6), the
/// same closed form as the 2D `pfem::exact::Cantilever` in plane stress.
struct Cantilever3d {
    length: f64,
    side: f64,
    cells: usize,
}

impl Cantilever3d {
    const DENSITY: f64 = 1000.0;
    const YOUNG: f64 = 5.6e6;
    const POISSON: f64 = 0.3;
    const GRAVITY: f64 = 2.0;

    /// The beam for Timoshenko's closed forms (`pfem::exact::BeamSection`,
    /// shared with the 2D case): square section, bending modulus `E`.
    fn section(&self) -> pfem::exact::BeamSection {
        let t = self.side;
        pfem::exact::BeamSection {
            length: self.length,
            area: t * t,
            second_moment: t.powi(4) / 12.0,
            bending_modulus: Self::YOUNG,
            shear_modulus: Self::YOUNG / (2.0 * (1.0 + Self::POISSON)),
            density: Self::DENSITY,
        }
    }

    fn exact(&self) -> f64 {
        let t = self.side;
        self.section()
            .tip_deflection(Self::DENSITY * Self::GRAVITY * t * t)
    }

    fn omega(&self) -> f64 {
        self.section().first_frequency()
    }

    /// Quasi-static run (backward Euler, steps of 5 s to 40 s, as the 2D
    /// case): the tip's mid-section deflection (m, positive down) and the
    /// particle count.
    fn run(&self) -> (f64, usize) {
        let params = StepParams {
            scheme: pfem::time::Scheme::BackwardEuler,
            ..Default::default()
        };
        let (series, n) = self.series(40.0, 5.0, params);
        (-series.last().unwrap().1, n)
    }

    /// Free vibration with the default scheme: gravity switched on at
    /// `t = 0`, 1.5 periods of 40 steps each; the frequency from the
    /// zero crossings of the tip's deflection about the mean of its
    /// extremes (`pfem::exact::frequency_about_mean`, as the 2D case).
    fn frequency(&self) -> f64 {
        let period = 2.0 * std::f64::consts::PI / self.omega();
        let (series, _) = self.series(1.5 * period, period / 40.0, StepParams::default());
        pfem::exact::frequency_about_mean(&series)
    }

    /// The tip's vertical displacement after every step, and the particle
    /// count.
    fn series(&self, end_time: f64, max_dt: f64, params: StepParams) -> (Vec<(f64, f64)>, usize) {
        let h = self.side / self.cells as f64;
        let m = pfem::constitutive::Hypoelastic::new(Self::DENSITY, Self::YOUNG, Self::POISSON)
            .unwrap();
        let scene = Scene::<3>::new("cantilever_3d")
            .gravity(Vector::<3>::new(0.0, -Self::GRAVITY, 0.0))
            .settings(RunSettings {
                end_time,
                max_dt,
                output_interval: None,
                ..Default::default()
            })
            .solid(
                "beam",
                Box::new(m),
                Geometry::Box {
                    min: Point::<3>::new(0.0, 0.0, 0.0),
                    max: Point::<3>::new(self.length, self.side, self.side),
                },
                h,
                Some((
                    Point::<3>::new(-1.0, -1.0, -1.0),
                    Point::<3>::new(1e-9, 1.0, 1.0),
                )),
            );
        let mut sim = Simulation::new(scene, Box::new(Delaunay3::default()), params).unwrap();
        assert!(!sim.stages().remesh, "a solid-only scene does not remesh");
        let target = Point::<3>::new(self.length, 0.5 * self.side, 0.5 * self.side);
        let tip = (0..sim.particles().len())
            .min_by(|&a, &b| {
                (sim.initial_position(a) - target)
                    .norm()
                    .total_cmp(&(sim.initial_position(b) - target).norm())
            })
            .unwrap();
        let y0 = sim.initial_position(tip)[1];
        let mut series = Vec::new();
        while sim.time() < sim.end_time() - 1e-12 {
            sim.step().unwrap();
            series.push((sim.time(), sim.particles().x()[tip][1] - y0));
        }
        (series, sim.particles().len())
    }
}

/// The 3D solid against closed forms: the static tip deflection of a
/// cantilever under its weight, and its first bending frequency, converge
/// to Timoshenko's as the spacing falls (linear tetrahedra lock in
/// bending, so the coarse beams are stiff), each at an observed order of
/// at least 0.9, as the 2D cantilever's (`tests/convergence.rs`; the
/// frequency at 2 and 4 cells only, to keep the suite short). Measured (5
/// December 2026): deflection error 49.7 / 21.3 / 7.1 % at 2 / 4 / 8
/// cells through the side (324 / 1 775 / 11 421 particles), order 1.41;
/// frequency error 37.7 / 12.1 % at 2 / 4 cells, order 1.64, as the
/// stiffness the deflection shows predicts (ω ∝ δ^(−1/2): 41 % and
/// 12.7 %); about 8 s.
#[test]
fn cantilever_3d_static_deflection_and_frequency_converge() {
    let mut points = Vec::new();
    let mut freq = Vec::new();
    for cells in [2, 4, 8] {
        let case = Cantilever3d {
            length: 0.35,
            side: 0.02,
            cells,
        };
        let t0 = std::time::Instant::now();
        let (d, n) = case.run();
        let error = (d / case.exact() - 1.0).abs();
        eprintln!(
            "3D cantilever, {cells} cells through the side ({n} particles): tip {:.3} mm against {:.3} mm, error {:.2} %, {:.1} s",
            1e3 * d,
            1e3 * case.exact(),
            100.0 * error,
            t0.elapsed().as_secs_f64()
        );
        points.push((case.side / cells as f64, error));
        if cells <= 4 {
            let t0 = std::time::Instant::now();
            let w = case.frequency();
            let error = (w / case.omega() - 1.0).abs();
            eprintln!(
                "3D cantilever, {cells} cells: ω = {w:.3} rad/s against {:.3}, error {:.2} %, {:.1} s",
                case.omega(),
                100.0 * error,
                t0.elapsed().as_secs_f64()
            );
            freq.push((case.side / cells as f64, error));
        }
    }
    for (name, pts) in [("deflection", &points), ("frequency", &freq)] {
        let order = pfem::exact::observed_order(pts);
        eprintln!("{name}: observed order {order:.2}");
        for w in pts.windows(2) {
            assert!(w[1].1 < w[0].1, "{name}: the error does not fall: {pts:?}");
        }
        assert!(order >= 0.9, "{name}: observed order {order}");
    }
}
