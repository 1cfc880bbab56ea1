//! A scene pays only for the effects it calls for: which stages ran, by
//! counters, for several scenes.

use pfem::prelude::*;

fn solid_only() -> Scene<2> {
    let beam = Hypoelastic::new(1000.0, 5.6e6, 0.4).unwrap();
    Scene::<2>::new("beam")
        .gravity(Vector::<2>::new(0.0, -2.0))
        .settings(RunSettings {
            end_time: 0.02,
            max_dt: 5e-3,
            output_interval: None,
            ..Default::default()
        })
        .solid(
            "beam",
            Box::new(beam),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(0.35, 0.02),
            },
            0.005,
            Some((Point::<2>::new(-1.0, -1.0), Point::<2>::new(1e-9, 1.0))),
        )
}

/// A scene of a free block over a floor, no fluid: it remeshes for
/// contact, but has no free surface to find nor fluid volume to measure
/// (the free-surface stage was counted at every remeshing until session
/// 48). Its frames' tags: `pfem-io`'s `output_vtu.rs`.
#[test]
fn a_contact_scene_without_fluid_finds_no_free_surface() {
    let h = 0.01;
    let scene = Scene::<2>::new("block")
        .gravity(Vector::<2>::new(0.0, -9.81))
        .settings(RunSettings {
            end_time: 0.01,
            max_dt: 2e-3,
            output_interval: None,
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-0.1, -h),
                max: Point::<2>::new(0.3, 0.0),
            },
            h,
            WallMotion::Fixed,
        )
        .solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, 1e7, 0.3).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 1.5 * h),
                max: Point::<2>::new(0.1, 1.5 * h + 0.05),
            },
            h,
            None,
        );
    let mut sim =
        Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default()).unwrap();
    sim.run(&mut []).unwrap();
    assert!(sim.stages().remesh && sim.stages().contact && !sim.stages().free_surface);
    assert!(sim.stats().remesh.0 > 0);
    assert_eq!(sim.stats().free_surface, (0, 0.0));
    assert_eq!(sim.fluid_volume(), 0.0);
}

#[test]
fn a_solid_only_scene_never_remeshes_nor_updates_pressure() {
    let mut sim = Simulation::new(
        solid_only(),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    sim.run(&mut []).unwrap();
    assert!(sim.steps() > 0);
    assert!(!sim.stages().remesh && !sim.stages().pressure && !sim.stages().free_surface);
    assert!(sim.stages().solid_stress && sim.stages().body_force);
    assert_eq!(sim.stats().remesh, (0, 0.0), "no time at all in remeshing");
    assert_eq!(sim.stats().free_surface, (0, 0.0));
    assert_eq!(sim.stats().pressure_updates, 0);
    assert_eq!(sim.stats().stress_updates, sim.steps());
    // The beam sags under its weight.
    let tip = sim
        .particles()
        .x()
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min);
    assert!(tip < 0.0);
}

#[test]
fn a_fluid_scene_without_gravity_assembles_no_body_force_and_has_no_solid_stage() {
    let h = 0.02;
    let scene = Scene::<2>::new("drop")
        .settings(RunSettings {
            end_time: 0.01,
            max_dt: 5e-3,
            output_interval: None,
            ..Default::default()
        })
        .fluid(
            "water",
            Box::new(Newtonian::water()),
            Geometry::Ball {
                center: Point::<2>::new(0.0, 0.0),
                radius: 0.1,
            },
            h,
        )
        .with_velocity(Vector::<2>::new(1.0, 0.0));
    let mut sim =
        Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default()).unwrap();
    sim.run(&mut []).unwrap();
    assert!(sim.stages().remesh && sim.stages().pressure);
    assert!(!sim.stages().body_force && !sim.stages().solid_stress);
    assert_eq!(sim.stats().stress_updates, 0);
    assert_eq!(sim.stats().pressure_updates, sim.steps());
    // Remeshed once at set-up and once per step after the first.
    assert_eq!(sim.stats().remesh.0, sim.steps());
    // The free-surface detection is timed at every remeshing, as a part of
    // it (the stage's timer was once never written).
    assert_eq!(sim.stats().free_surface.0, sim.stats().remesh.0);
    assert!(sim.stats().free_surface.1 > 0.0);
    assert!(sim.stats().free_surface.1 <= sim.stats().remesh.1);
    // A drop in free flight keeps its velocity.
    let mean = sim
        .particles()
        .v()
        .iter()
        .fold(Vector::<2>::zeros(), |a, v| a + v)
        / sim.particles().len() as f64;
    assert!(
        (mean.x - 1.0).abs() < 1e-6 && mean.y.abs() < 1e-6,
        "{mean:?}"
    );
}

#[test]
fn impossible_scenes_are_typed_errors_before_any_step() {
    let bad_dt = solid_only().settings(RunSettings {
        end_time: -1.0,
        ..Default::default()
    });
    assert!(matches!(
        Simulation::new(
            bad_dt,
            Box::new(Delaunay2::default()),
            StepParams::default()
        ),
        Err(pfem::SceneError::InvalidSetting {
            setting: "end_time",
            ..
        })
    ));
    let beam = Hypoelastic::new(1000.0, 5.6e6, 0.4).unwrap();
    let unsupported = Scene::<2>::new("falling beam")
        .gravity(Vector::<2>::new(0.0, -9.81))
        .solid(
            "beam",
            Box::new(beam),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(0.35, 0.02),
            },
            0.005,
            None,
        );
    assert!(matches!(
        unsupported.validate(),
        Err(pfem::SceneError::Unsupported { .. })
    ));
    let too_coarse = Scene::<2>::new("coarse").fluid(
        "water",
        Box::new(Newtonian::water()),
        Geometry::Box {
            min: Point::<2>::new(0.0, 0.0),
            max: Point::<2>::new(0.1, 0.1),
        },
        0.5,
    );
    assert!(matches!(
        too_coarse.validate(),
        Err(pfem::SceneError::SpacingLargerThanBody { .. })
    ));
    let h = 0.01;
    let overlap = Scene::<2>::new("overlap")
        .fluid(
            "a",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(0.1, 0.1),
            },
            h,
        )
        .fluid(
            "b",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<2>::new(0.05, 0.05),
                max: Point::<2>::new(0.2, 0.2),
            },
            h,
        );
    assert!(matches!(
        overlap.validate(),
        Err(pfem::SceneError::Overlap { .. })
    ));
    let wrong_kind = Scene::<2>::new("wrong").fluid(
        "rubber",
        Box::new(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap()),
        Geometry::Box {
            min: Point::<2>::new(0.0, 0.0),
            max: Point::<2>::new(0.1, 0.1),
        },
        h,
    );
    assert!(matches!(
        wrong_kind.validate(),
        Err(pfem::SceneError::MaterialKindMismatch { .. })
    ));
}

/// Rejected attempts are counted and timed apart from the accepted ones
/// (`stats.rejected`, `wall_time_s.rejected_attempts` in `summary.json`),
/// so the stage times add up to no more than the run's wall time. A coarse
/// dam break (a/8) with oversized steps (Courant 50, `max_dt` 0.05 s)
/// rejects attempts, as in `stability_fluid.rs`.
#[test]
fn rejected_attempts_are_counted_and_timed() {
    let case = pfem::cases::DamBreak {
        spacing: 0.05715 / 8.0,
        end_time: 0.1,
        ..Default::default()
    };
    let mut scene = case.scene();
    scene.settings.max_dt = 0.05;
    scene.settings.courant = 50.0;
    scene.settings.output_interval = None;
    // The stages include the set-up's first remeshing: the wall time
    // starts before it.
    let t0 = std::time::Instant::now();
    let mut sim =
        Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default()).unwrap();
    let out = StandardOutput::new(
        std::env::temp_dir().join("pfem-test-rejected"),
        false,
        vec![],
        true,
    );
    sim.run(&mut []).unwrap();
    let wall = t0.elapsed().as_secs_f64();
    assert!(sim.rejected() > 0, "the case should reject some attempts");
    assert_eq!(sim.stats().rejected.0, sim.rejected());
    assert!(sim.stats().rejected.1 > 0.0);
    let w = out.summary(&sim).wall_time_s;
    assert_eq!(w["rejected_attempts"], sim.stats().rejected.1);
    let stages: f64 = [
        "remesh",
        "assemble",
        "solve",
        "update",
        "hooks",
        "rejected_attempts",
    ]
    .iter()
    .map(|k| w[*k])
    .sum();
    assert!(stages <= wall, "stages {stages} s > wall {wall} s");
}

/// Measured by work done, not by flags: a solid-only scene builds its
/// sparsity pattern and symbolic analysis once (its mesh never changes) and
/// factorises at least once per Picard loop; every assembly covers exactly its
/// elements. A fluid scene remeshes and builds a pattern every step.
#[test]
fn work_done_follows_the_scene() {
    let mut sim = Simulation::new(
        solid_only(),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    sim.run(&mut []).unwrap();
    let w = sim.work();
    let n_el = sim.elements().len() as u64;
    println!("solid only: {w:?}, {} steps, {n_el} elements", sim.steps());
    assert_eq!(w.remeshes, 0);
    assert_eq!(w.patterns_built, 1, "the pattern is kept from step to step");
    assert_eq!(w.symbolic_analyses, 1, "so is the symbolic analysis");
    // At least one factorisation per Picard loop (a step's attempt), at
    // most one per solve: a later iterate may run on its loop's factor
    // (`BlockSolver::keep_factor_below`).
    let loops = sim.steps() + sim.stats().rejected.0;
    assert!(
        w.factorizations >= loops && w.factorizations <= sim.stats().solve.0,
        "{} factorisations, {loops} loops, {} solves",
        w.factorizations,
        sim.stats().solve.0
    );
    // Assemblies: the initial acceleration's one and one per iterate.
    assert_eq!(w.elements_assembled, n_el * (sim.stats().assemble.0 + 1));
    // A pressure stabilisation asked of a scene without fluid has no
    // pressure row to act on: the same work and the same answer. (Until
    // session 48 it split the system, and the split solve factorised
    // afresh every iterate: a symbolic analysis per solve.)
    let mut stabilised = Simulation::new(
        solid_only(),
        Box::new(Delaunay2::default()),
        StepParams {
            pressure_stabilisation: 1.0,
            ..Default::default()
        },
    )
    .unwrap();
    stabilised.run(&mut []).unwrap();
    assert_eq!(stabilised.work().symbolic_analyses, 1);
    assert_eq!(stabilised.work().factorizations, w.factorizations);
    assert_eq!(stabilised.particles().x(), sim.particles().x());

    let h = 0.05;
    let scene = Scene::<2>::new("puddle")
        .gravity(Vector::<2>::new(0.0, -9.81))
        .settings(RunSettings {
            end_time: 0.05,
            max_dt: 1e-2,
            output_interval: None,
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-0.1, -h),
                max: Point::<2>::new(0.3, 0.0),
            },
            h,
            WallMotion::Fixed,
        )
        .fluid(
            "water",
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(0.2, 0.2),
            },
            h,
        );
    let mut sim =
        Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("pfem-test-no-output-{}", std::process::id()));
    let mut out = StandardOutput::new(&dir, false, vec![], true);
    sim.run(&mut [&mut out]).unwrap();
    let w = sim.work();
    println!("fluid: {w:?}, {} steps", sim.steps());
    // The initial mesh, then one per step after the first.
    assert_eq!(w.remeshes, sim.steps());
    assert!(w.patterns_built >= sim.steps());
    // No frames and no probes asked for: none formatted, none written.
    assert!(out.history().is_empty());
    let vtu = std::fs::read_dir(&dir)
        .map(|d| {
            d.flatten()
                .filter(|e| {
                    e.path()
                        .extension()
                        .is_some_and(|x| x == "vtu" || x == "csv")
                })
                .count()
        })
        .unwrap_or(0);
    assert_eq!(vtu, 0);
    std::fs::remove_dir_all(&dir).ok();
}

/// A small clamped block at rest, no gravity: every step is `max_dt`.
fn block_at_rest(end_time: f64, max_dt: f64) -> Scene<2> {
    Scene::<2>::new("block at rest")
        .settings(RunSettings {
            end_time,
            max_dt,
            output_interval: None,
            ..Default::default()
        })
        .solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(0.02, 0.02),
            },
            0.01,
            Some((Point::<2>::new(-1.0, -1.0), Point::<2>::new(1e-9, 1.0))),
        )
}

/// Session 41 (a review of the time stepping): the clock's round-off
/// grows with the steps, and past 10⁻¹² s the run took one more step of
/// `min_dt` (10⁻⁹ s) beyond the end time: end 100 s by steps of 0.1 s
/// was 1 001 steps ending at 100.000000001 s. The last step now lands on
/// the end time.
#[test]
fn a_long_run_ends_on_its_end_time_without_a_sliver_step() {
    let mut sim = Simulation::new(
        block_at_rest(100.0, 0.1),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    sim.run(&mut []).unwrap();
    assert_eq!(sim.time(), 100.0);
    assert!(sim.dt() > 1e-3, "last step {}", sim.dt());
    assert!(sim.steps() <= 1000, "{} steps", sim.steps());
    // Called by hand past the end time, a step is the controller's, not
    // the `min_dt` the end time's cut gave (10⁻⁹ s a step: a hang).
    sim.step().unwrap();
    assert!(sim.dt() > 1e-3, "step past the end: {}", sim.dt());
    assert!(sim.time() > 100.0 + 1e-3);
}

/// Session 47 (a review of the step control): an end time off the steps'
/// grid ended with a sliver, 0.010000005 s by steps of 1 ms with one of
/// 5·10⁻⁹ s; its continuation started from it (about 55 steps to grow
/// back). The rest is taken in two halves. An end time set less than
/// `min_dt` after the clock took a step of `min_dt`, past it; and a run
/// 5·10⁻¹³ s long took no step (an absolute tolerance of 10⁻¹² s).
#[test]
fn an_end_time_off_the_steps_grid_ends_without_a_sliver() {
    let mut sim = Simulation::new(
        block_at_rest(0.010000005, 1e-3),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    sim.run(&mut []).unwrap();
    assert_eq!(sim.time(), 0.010000005);
    assert!(sim.dt() > 4e-4, "last step {}", sim.dt());
    assert!(sim.steps() <= 11, "{} steps", sim.steps());
    // Continued past it, the steps are `max_dt` again at once.
    sim.set_end_time(0.02).unwrap();
    let steps = sim.steps();
    sim.run(&mut []).unwrap();
    assert_eq!(sim.time(), 0.02);
    assert!(sim.steps() - steps <= 11, "{} steps", sim.steps() - steps);
    // An end time less than `min_dt` (10⁻⁹ s) ahead: one step onto it.
    sim.set_end_time(0.02 + 5e-10).unwrap();
    sim.run(&mut []).unwrap();
    assert_eq!(sim.time(), 0.02 + 5e-10);
    // A run shorter than 10⁻¹² s steps to its end.
    let mut short = Simulation::new(
        block_at_rest(5e-13, 1e-14),
        Box::new(Delaunay2::default()),
        StepParams {
            min_dt: 1e-16,
            ..StepParams::default()
        },
    )
    .unwrap();
    short.run(&mut []).unwrap();
    assert_eq!(short.time(), 5e-13);
    assert!(short.steps() >= 50, "{} steps", short.steps());
    // The step at its floor (`min_dt` = `max_dt`) and a rest below two of
    // them: one step of the rest, not one of `min_dt` and a sliver of
    // 5·10⁻⁷ s (the review of the change).
    let mut floor = Simulation::new(
        block_at_rest(0.0100005, 1e-3),
        Box::new(Delaunay2::default()),
        StepParams {
            min_dt: 1e-3,
            ..StepParams::default()
        },
    )
    .unwrap();
    floor.run(&mut []).unwrap();
    assert_eq!(floor.time(), 0.0100005);
    assert!(floor.dt() >= 1e-3, "last step {}", floor.dt());
    assert_eq!(floor.steps(), 10);
}

/// A restart with a later end time (the review of session 47's change):
/// the schedules' tolerance is `10⁻⁹` of the end time, and a saved next
/// row just ahead of the clock (5·10⁻⁶ s, within `10⁻⁹ × 10⁴ s`) was taken
/// for one behind it: the row due at 4 ms was skipped.
#[test]
fn a_restart_with_a_later_end_time_keeps_the_row_due() {
    let dir = std::env::temp_dir().join(format!("pfem-later-end-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let probes = || vec![Probe::<2>::new("clock", |s: &Simulation<2>| s.time())];
    let build = || {
        Simulation::new(
            block_at_rest(0.003995, 1e-3),
            Box::new(Delaunay2::default()),
            StepParams::default(),
        )
        .unwrap()
    };
    let mut a = build();
    let mut out = StandardOutput::new(&dir, false, probes(), true).checkpoint_every(Some(1.0));
    out.probe_interval = Some(0.002);
    a.run(&mut [&mut out]).unwrap();
    let ck = pfem::observe::read_checkpoint(dir.join("checkpoint.bin")).unwrap();
    let mut b = build();
    b.restore(&ck).unwrap();
    b.set_end_time(1e4).unwrap();
    b.add_hook(Box::new(pfem::hooks::StopWhen::new("two steps", |t, _| {
        t > 0.0055
    })));
    let mut out = StandardOutput::new(&dir, false, probes(), true);
    out.probe_interval = Some(0.002);
    out.resume(&ck).unwrap();
    b.run(&mut [&mut out]).unwrap();
    let rows: Vec<f64> = std::fs::read_to_string(dir.join("probes.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    let after: Vec<f64> = rows.iter().copied().filter(|&t| t > 0.003995).collect();
    // The first step past 4 ms records the row due there.
    assert!(after.first().is_some_and(|&t| t < 0.0051), "rows {rows:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Session 41: a `min_dt` above the scene's `max_dt` ran every step at
/// `min_dt`, above the ceiling, without a word; it is refused. The default
/// `min_dt` (10⁻⁹ s) goes under a finer `max_dt` instead (a scene file
/// cannot set it).
#[test]
fn a_smallest_step_above_the_largest_is_refused() {
    let mut fine = Simulation::new(
        block_at_rest(1e-8, 5e-10),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    fine.run(&mut []).unwrap();
    assert_eq!(fine.time(), 1e-8);
    assert!(fine.dt() <= 5e-10 * (1.0 + 1e-6), "{}", fine.dt());
    let params = StepParams {
        min_dt: 1e-2,
        ..StepParams::default()
    };
    let r = Simulation::new(
        block_at_rest(0.1, 1e-3),
        Box::new(Delaunay2::default()),
        params,
    );
    assert!(
        matches!(
            r,
            Err(pfem::SceneError::OutOfRange {
                setting: "min_dt",
                ..
            })
        ),
        "{r:?}"
    );
}

/// Session 41: with `velocity_floor` 0 and no body force, a body at rest
/// gave the Picard loop a change of `0/0`, read as divergence: the step
/// was halved down to `min_dt` and failed. Nothing moving is converged.
#[test]
fn a_body_at_rest_with_no_velocity_floor_steps() {
    let params = StepParams {
        velocity_floor: 0.0,
        ..StepParams::default()
    };
    let mut sim = Simulation::new(
        block_at_rest(0.01, 1e-3),
        Box::new(Delaunay2::default()),
        params,
    )
    .unwrap();
    sim.run(&mut []).unwrap();
    assert_eq!(sim.rejected(), 0);
    assert_eq!(sim.time(), 0.01);
}

/// Session 41 (a review of the library's seams): a plane-stress solid in a
/// 3D scene built from Rust ran with the plane-stress Lamé constant (a
/// third of λ at ν = 0.4), where the scene file refused it. The material
/// refuses it itself (`Material::check_dimension`).
#[test]
fn a_plane_stress_solid_in_3d_is_refused() {
    let strip = Hypoelastic::plane_stress(1100.0, 12e6, 0.4).unwrap();
    let scene = Scene::<3>::new("strip").solid(
        "strip",
        Box::new(strip),
        Geometry::Box {
            min: Point::<3>::new(0.0, 0.0, 0.0),
            max: Point::<3>::new(0.1, 0.02, 0.02),
        },
        0.01,
        Some((
            Point::<3>::new(-1.0, -1.0, -1.0),
            Point::<3>::new(1e-9, 1.0, 1.0),
        )),
    );
    let err = scene.validate().unwrap_err();
    assert!(
        matches!(err, pfem::SceneError::InvalidMaterial { .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("plane stress"), "{err}");
    // In 2D it is what it says.
    let strip = Hypoelastic::plane_stress(1100.0, 12e6, 0.4).unwrap();
    let scene = Scene::<2>::new("strip").solid(
        "strip",
        Box::new(strip),
        Geometry::Box {
            min: Point::<2>::new(0.0, 0.0),
            max: Point::<2>::new(0.1, 0.02),
        },
        0.01,
        Some((Point::<2>::new(-1.0, -1.0), Point::<2>::new(1e-9, 1.0))),
    );
    scene.validate().unwrap();
}

/// Session 41 (a review of the library's seams): per-body builder calls
/// with nothing to act on were dropped without a word: `with_velocity`
/// before any body (the water started at rest), a velocity on a wall, and
/// a velocity together with a velocity field (the field silently won).
#[test]
fn builder_calls_that_cannot_act_are_refused() {
    let water = || {
        (
            Box::new(Newtonian::water()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(0.1, 0.1),
            },
        )
    };
    let (m, g) = water();
    let early = Scene::<2>::new("early")
        .with_velocity(Vector::<2>::new(1.0, 0.0))
        .fluid("water", m, g, 0.01);
    let err = early.validate().unwrap_err();
    assert!(
        matches!(err, pfem::SceneError::Misuse { .. }) && err.to_string().contains("with_velocity"),
        "{err}"
    );
    let moving_wall = Scene::<2>::new("wall")
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(0.0, -0.01),
                max: Point::<2>::new(0.1, 0.0),
            },
            0.01,
            WallMotion::Fixed,
        )
        .with_velocity(Vector::<2>::new(1.0, 0.0));
    assert!(matches!(
        moving_wall.validate(),
        Err(pfem::SceneError::Misuse { .. })
    ));
    let (m, g) = water();
    let both = Scene::<2>::new("both")
        .fluid("water", m, g, 0.01)
        .with_velocity(Vector::<2>::new(1.0, 0.0))
        .with_velocity_field(|_| Vector::<2>::new(0.0, 1.0));
    assert!(matches!(
        both.validate(),
        Err(pfem::SceneError::Misuse { .. })
    ));
    let (m, g) = water();
    let fine = Scene::<2>::new("fine")
        .fluid("water", m, g, 0.01)
        .with_velocity(Vector::<2>::new(1.0, 0.0));
    fine.validate().unwrap();
}

/// Session 47 (a review of the step control): past an end time of about
/// 1.1·10⁶ s the smallest step is raised to `end_time · 2⁻⁵⁰`, and it was
/// among the settings a restart must repeat: a long quasi-static run
/// restarted with a later end time was refused for its `min_dt`. The
/// check compares `min_dt` as set; another `max_dt` is still refused.
#[test]
fn a_long_run_restarted_with_a_later_end_time_is_accepted() {
    let build = |end: f64, max_dt: f64| {
        Simulation::new(
            block_at_rest(end, max_dt),
            Box::new(Delaunay2::default()),
            StepParams::default(),
        )
        .unwrap()
    };
    let mut a = build(2e6, 1.0);
    for _ in 0..3 {
        a.step().unwrap();
    }
    let ck = a.checkpoint();
    let mut b = build(3e6, 1.0);
    b.restore(&ck).unwrap();
    assert_eq!(b.steps(), 3);
    b.step().unwrap();
    let err = build(2e6, 0.5).restore(&ck).unwrap_err().to_string();
    assert!(err.contains("setting"), "{err}");
}
