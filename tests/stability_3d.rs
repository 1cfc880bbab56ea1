//! The hard cases of `stability_fluid.rs` and `stability_fsi.rs` in 3D,
//! through the same code path: real water at Courant 1, a violent splash,
//! steps far beyond the stable limit, a stiffness contrast (E = 1e9 Pa and
//! E = 1e4 Pa posts in water; the 2D case's 1e3 Pa is a known gap in 3D,
//! below), free solids 10× heavier and 10× lighter than water, and a thin
//! plate (1:20) hit by a wave. Coarse (1 100 to 5 300 particles) so
//! that the suite stays short (about 25 s on 2 cores); release mode:
//! `cargo test --release --test suite stability_3d::`.
//!
//! Checks as in 2D (`stability_support.rs`): the run reaches its end time
//! with no error, no NaN, no inverted fluid or solid element after
//! a step (but the slivers kept in their start-of-step shape), the kinetic
//! and gravitational potential energy of the non-wall particles never above
//! the initial total + `ENERGY_TOL`; the fluid volume deviates by at most
//! `VOLUME_STEP_TOL` (5 %) after any step and (but the oversized steps,
//! as in 2D) changes by at most `VOLUME_CHANGE_TOL` (1 %) over the run.

use crate::stability_support::*;
use pfem::cases3d::tank3d;
use pfem::core::Point;
use pfem::prelude::*;

/// Energy growth allowed over the initial total: 5 %, as in 2D.
const ENERGY_TOL: f64 = 0.05;

/// Gravity (0, −9.81, 0): `y` up, as in every 3D case of the library.
fn g3() -> Vector<3> {
    Vector::<3>::new(0.0, -9.81, 0.0)
}

/// A box geometry.
fn cuboid(min: [f64; 3], max: [f64; 3]) -> Geometry<3> {
    Geometry::Box {
        min: Point::<3>::from(min),
        max: Point::<3>::from(max),
    }
}

/// A clamp that holds a post's bottom row (`y ≤ y_top`) whatever its `x`
/// and `z`.
fn base_clamp(y_top: f64) -> Option<(Point<3>, Point<3>)> {
    Some((
        Point::<3>::new(-10.0, -10.0, -10.0),
        Point::<3>::new(10.0, y_top + 1e-9, 10.0),
    ))
}

/// A column of water 0.1 m × 0.1 m (`x`, `z`) and `height` tall released at
/// the back of a tank `length` long and 0.1 m wide.
fn column(name: &str, length: f64, height: f64, h: f64, end_time: f64, max_dt: f64) -> Scene<3> {
    let s = Scene::<3>::new(name)
        .gravity(g3())
        .settings(settings(end_time, max_dt, 0.5));
    tank3d(s, length, 0.1, height + 0.2, h, true).fluid(
        "water",
        Box::new(Newtonian::water()),
        cuboid([0.0, 0.0, 0.0], [0.1, height, 0.1]),
        h,
    )
}

/// Water with its real bulk modulus at Courant 1 (a particle may cross a
/// whole element a step): a 0.1 m cube collapsing in a 0.3 m tank.
/// Measured (5 December 2026, `max_dt` 5 ms): 30 steps (0 rejected),
/// volume within 2.21 % at every step, +0.19 % at the end; session 48
/// (20 ms): 10 steps (1 rejected), 3.27 %, +0.10 %, Courant number 1.00.
#[test]
fn real_bulk_modulus_at_courant_one_3d() {
    // (`max_dt` 20 ms: at 5 ms every step was the ceiling's, a Courant
    // number of about 0.35; session 48's review. Measured: 1.00.)
    let mut scene = column("courant_one_3d", 0.3, 0.1, 0.02, 0.15, 0.02);
    scene.settings.courant = 1.0;
    let o = run_checked_3d(scene, StepParams::default());
    o.report("3D bulk modulus, C = 1");
    assert!(
        o.watch.courant_max > 0.9,
        "the largest Courant number taken was {:.2}",
        o.watch.courant_max
    );
    o.assert_stable(ENERGY_TOL);
    o.assert_volume_change(VOLUME_CHANGE_TOL);
    o.assert_volume(VOLUME_STEP_TOL);
}

/// A column 0.1 m × 0.25 m × 0.1 m released into a 0.25 m tank: it hits
/// the far wall, runs up, and sheets of particles detach and fall back.
/// Besides the common checks, the water runs up the far wall above the
/// level it settles to (0.1 m). Measured (5 December 2026, 2 376
/// particles): 250 steps (0 rejected), energy at most +0.03 %, fastest
/// particle 2.66 m/s, run-up 0.118 m (coarse: six particles across the
/// column), volume within 1.77 % at every step, 10 s.
#[test]
fn violent_splash_stays_bounded_3d() {
    let scene = column("splash_3d", 0.25, 0.25, 0.02, 0.5, 2e-3);
    let mut sim =
        Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default()).unwrap();
    let mut run_up: f64 = 0.0;
    let mut track = Track::<3>(Box::new(|s: &Simulation<3>| {
        for (p, k) in s.particles().x().iter().zip(s.particles().kind()) {
            if *k == pfem::core::ParticleKind::Fluid && p[0] > 0.2 {
                run_up = run_up.max(p[1]);
            }
        }
    }));
    let o = run_sim_with(&mut sim, 0.5, Some(&mut track));
    drop(track);
    o.report("3D splash");
    eprintln!("run-up on the far wall: {run_up:.3} m");
    assert!(
        run_up > 0.1,
        "the water did not run up the far wall: {run_up} m"
    );
    o.assert_stable(ENERGY_TOL);
    // Twice the free fall from the column's top, 2 √(2 g 0.25 m).
    o.assert_speed(free_fall_bound(0.25));
    o.assert_volume_change(VOLUME_CHANGE_TOL);
    o.assert_volume(VOLUME_STEP_TOL);
}

/// Near-degenerate elements that reach the solver in 3D: a 0.1 m cube of
/// water as a lattice of spacing 0.02 m with every particle moved by up to
/// 0.2 h in each coordinate and a companion 0.3 h from every fifth (above
/// the h/4 that `Simulation::new` merges), released in a 0.3 m tank for
/// 0.15 s: the first meshes hold tetrahedra far flatter than a lattice's
/// (asserted: the least kept quality `V/R³` below a tenth of a regular
/// one's). Besides the common checks, no particle faster than twice the
/// free fall from the column's top (session 48's review: no near-degenerate
/// mesh reached the 3D solver in this suite).
#[test]
fn jittered_particles_run_3d() {
    let h = 0.02;
    let mut pts = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            for k in 0..5 {
                let n = pts.len();
                let p = Point::<3>::new(
                    (i as f64 + 0.5) * h + 0.2 * h * jitter(n, 0),
                    (j as f64 + 0.5) * h + 0.2 * h * jitter(n, 1),
                    (k as f64 + 0.5) * h + 0.2 * h * jitter(n, 2),
                );
                pts.push(p);
                if n % 5 == 0 {
                    let d = Vector::<3>::new(jitter(n, 3), jitter(n, 4), jitter(n, 5));
                    pts.push(p + d.normalize() * (0.3 * h));
                }
            }
        }
    }
    let s = Scene::<3>::new("jittered_3d")
        .gravity(g3())
        .settings(settings(0.15, 2e-3, 0.5));
    let scene = tank3d(s, 0.3, 0.1, 0.3, h, true).fluid(
        "water",
        Box::new(Newtonian::water()),
        Geometry::Particles(pts.clone()),
        h,
    );
    let mut sim = Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default())
        .expect("scene builds");
    assert_eq!(fluid_count(&sim), pts.len());
    // The least `V/R³` of the kept fluid tetrahedra, against a regular
    // one's (0.513).
    let x = sim.particles().x();
    let worst = sim
        .elements()
        .fluid()
        .chunks_exact(4)
        .map(|e| {
            let p: Vec<Point<3>> = e.iter().map(|&i| x[i as usize]).collect();
            pfem::assembly::kernels::shape_quality::<3>(&p)
        })
        .fold(f64::INFINITY, f64::min);
    eprintln!("jittered 3D: least tetrahedron quality {worst:.4}");
    assert!(worst < 0.05, "{worst}");
    let o = run_sim(&mut sim, 0.15);
    o.report("3D jittered");
    o.assert_stable(ENERGY_TOL);
    o.assert_volume_change(VOLUME_CHANGE_TOL);
    o.assert_volume(VOLUME_STEP_TOL);
    // (The column's top: 0.1 m and a jitter, 0.12 m with a margin.)
    o.assert_speed(free_fall_bound(0.12));
}

/// Steps far beyond the stable limit (`max_dt` = 0.05 s, Courant 50): the
/// integrator must reject them, halve, and still reach the end time.
/// Measured (5 December 2026, to 0.12 s): 4 steps, 1 rejected, energy at
/// most +0.11 %, volume within 3.15 % at every step. Since session 47 a
/// rest shorter than two steps is taken in two halves (0.12 s became
/// 0.05 + 0.035 + 0.035 s, none rejected), so the run goes to 0.15 s, three
/// steps of `max_dt`: 5 steps, 1 rejected, +0.11 %, 3.15 %. Exempt from
/// the 1 % over the run, as in 2D: a few steps leave the volume
/// correction no time (+1.73 % at the end of the 0.12 s run).
#[test]
fn oversized_steps_are_rejected_halved_and_recovered_3d() {
    let mut scene = column("oversized_3d", 0.3, 0.1, 0.025, 0.15, 0.05);
    scene.settings.courant = 50.0;
    let mut sim = Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default())
        .expect("scene builds");
    let o = run_sim(&mut sim, 0.15);
    o.report("3D oversized steps");
    assert!(sim.rejected() > 0, "no step was rejected");
    assert!(o.result.is_ok(), "did not recover: {:?}", o.result);
    o.assert_stable(ENERGY_TOL);
    o.assert_volume(VOLUME_STEP_TOL);
    // Large steps were taken, not only halved ones (measured: 50 ms, a
    // particle crossing 0.87 of its spacing).
    assert!(
        o.watch.dt_max >= 0.01 && o.watch.courant_max > 0.5,
        "largest step {:.2e} s, largest Courant number {:.2}",
        o.watch.dt_max,
        o.watch.courant_max
    );
}

/// A 0.1 m cube of water released in a 0.4 m tank onto two posts
/// 0.04 m × 0.08 m × 0.06 m clamped at their base: E = 1e9 Pa at
/// x = 0.2 m and `soft` at x = 0.3 m (ρ g H of the post's own weight is
/// about 800 Pa).
fn stiffness_contrast_3d(soft: f64) -> Scene<3> {
    let h = 0.02;
    let s = Scene::<3>::new("stiffness_contrast_3d")
        .gravity(g3())
        .settings(settings(0.3, 2e-3, 0.5));
    let post = |s: Scene<3>, name: &str, x: f64, e: f64| {
        let m = Hypoelastic::new(1000.0, e, 0.3).expect("valid solid");
        s.solid(
            name,
            Box::new(m),
            cuboid([x, h, 0.02], [x + 0.04, h + 0.08, 0.08]),
            h,
            base_clamp(h),
        )
    };
    let s = tank3d(s, 0.4, 0.1, 0.3, h, true);
    let s = post(s, "stiff", 0.2, 1e9);
    let s = post(s, "soft", 0.3, soft);
    s.fluid(
        "water",
        Box::new(Newtonian::water()),
        cuboid([0.0, 0.0, 0.0], [0.1, 0.1, 0.1]),
        h,
    )
}

/// Stiffness contrast with a soft post of E = 1e4 Pa (about 13 times the
/// stress of its own weight): the wave bends both posts and the run
/// reaches its end. Measured (5 December 2026, 2 208 particles): 150 steps
/// (0 rejected), energy never above its start, volume within 1.74 % at
/// every step and −0.00 % at the end, 3 s.
#[test]
fn stiffness_contrast_in_water_3d() {
    let o = run_checked_3d(stiffness_contrast_3d(1e4), StepParams::default());
    o.report("3D stiffness contrast");
    o.assert_stable(ENERGY_TOL);
    o.assert_volume_change(VOLUME_CHANGE_TOL);
    o.assert_volume(VOLUME_STEP_TOL);
}

/// The 2D case's soft post (E = 1e3 Pa, softer than its own weight) in 3D:
/// known gap. The wave crushes the post from t ≈ 0.125 s: one of its
/// tetrahedra flattens faster than any step can follow (its measure falls
/// from 2·10⁻² h³ to 7·10⁻⁹ h³ over 24 halvings) and the run stops with
/// `StepTooSmall` at t = 0.127 s naming the inverted element, while the post, spread
/// sideways, has particles inside the tank's side wall (`z` = −0.015 m
/// against the wall's face at 0): by default a clamped solid takes no
/// part in contact (ARCHITECTURE.md, deviation 11). With
/// `Scene::contact_clamped(true)` it does, but this case is not cured:
/// with the penalty of the time, the stiffest solid's P-wave modulus
/// (1.35·10⁹ Pa), the floor crushed the post at t = 0.024 s; with each
/// contact element's own bodies' (1.35·10³ Pa for this post, session 36)
/// the energy rose 62 % within the first 3 ms as the sagging post met the
/// floor, 176 of 537 attempts were rejected, and the run stopped at
/// t = 0.134 s the same way; in session 38 (the layer's own
/// linearisation, the dashpot grown in over the onset) the energy rose
/// 32.6 %, 24 of 82 attempts were rejected, and the run stopped at
/// t = 0.137 s the same way. With E = 3e3 Pa and no contact the run ends
/// but the fluid volume strays 5.91 % for a step (bound 5 %).
/// `cargo test --release --test suite stability_3d::a_post_softer -- --ignored --nocapture`
#[test]
#[ignore = "known gap: the wave crushes a 3D post softer than its own weight (typed error at t = 0.127 s)"]
fn a_post_softer_than_its_weight_survives_the_wave_3d() {
    let o = run_checked_3d(stiffness_contrast_3d(1e3), StepParams::default());
    o.report("3D stiffness contrast, E = 1e3 Pa");
    o.assert_stable(ENERGY_TOL);
    o.assert_volume(VOLUME_STEP_TOL);
}

/// Two free 0.04 m cubes (E = 1e6 Pa) released 0.02 m above the surface of
/// a 0.4 m × 0.1 m × 0.1 m pool: ρ = 10 000 kg/m³ (sinks) and
/// ρ = 100 kg/m³ (floats).
fn density_ratio_3d() -> Scene<3> {
    let h = 0.02;
    let s = Scene::<3>::new("density_ratio_3d")
        .gravity(g3())
        .settings(settings(0.3, 2e-3, 0.5));
    let s = tank3d(s, 0.4, 0.1, 0.3, h, true);
    let heavy = Hypoelastic::new(10_000.0, 1e6, 0.3).expect("valid solid");
    let light = Hypoelastic::new(100.0, 1e6, 0.3).expect("valid solid");
    s.solid(
        "heavy",
        Box::new(heavy),
        cuboid([0.08, 0.12, 0.03], [0.12, 0.16, 0.07]),
        h,
        None,
    )
    .solid(
        "light",
        Box::new(light),
        cuboid([0.28, 0.12, 0.03], [0.32, 0.16, 0.07]),
        h,
        None,
    )
    .fluid(
        "water",
        Box::new(Newtonian::water()),
        cuboid([0.0, 0.0, 0.0], [0.4, 0.1, 0.1]),
        h,
    )
}

/// Density ratio: besides the common checks, the heavy cube sinks (its
/// centre below 0.08 m at the end) without passing into the floor (its
/// lowest particle above 0.9 h), and the light one stays afloat (its
/// centre never below the water surface). Measured (5 December 2026,
/// 2 422 particles): 150 steps (0 rejected); the heavy cube rests with its
/// lowest particle 1.47 h above the floor, on a film of water one particle
/// thick as in 2D (`stability_fsi.rs`); the light one's centre never below
/// 0.1235 m; fluid volume within 4.26 % at every step, +0.91 % at the end;
/// 5 s. The volume at the end is not held to 1 % here: it is chaotic
/// (session 50). Scaling the solids' stress increment by 1 ± 10⁻⁴ … 10⁻³
/// (a scratch build) gave, at the end, +0.00, +0.00, +0.44, +0.68 (none),
/// +0.98, +1.46 and +3.45 % (1 − 10⁻⁴, 1 + 10⁻⁴, 1 − 3·10⁻⁴, 1, 1 + 2·10⁻⁴,
/// 1 + 5·10⁻⁴, 1 + 10⁻³), and at most 1.64–4.14 % for a step; the
/// corrected solid update of session 50 (an `O(e²)` change) ends at +1.78 %
/// (3.48 % for a step). A fluid particle next to a free solid is not
/// moved by the volume correction, so the water the remeshing adds
/// around the cubes stays (a block dropped into coarse 3D water gains
/// 14 %, `docs/robustness.md`). The 1 % is
/// `density_ratio_keeps_its_fluid_volume_3d` (ignored, a known gap).
#[test]
fn density_ratio_free_solids_in_water_3d() {
    let h = 0.02;
    let mut sim = Simulation::new(
        density_ratio_3d(),
        Box::new(Delaunay3::default()),
        StepParams::default(),
    )
    .expect("scene builds");
    assert!(sim.stages().contact);
    let heavy = sim.body_particles("heavy").unwrap();
    let light = sim.body_particles("light").unwrap();
    let mean_y = |s: &Simulation<3>, set: &[usize]| {
        set.iter().map(|&i| s.particles().x()[i][1]).sum::<f64>() / set.len() as f64
    };
    let (mut lowest, mut heavy_end, mut light_low, mut light_end) =
        (f64::INFINITY, 0.0, f64::INFINITY, 0.0);
    let mut track = Track::<3>(Box::new(|s: &Simulation<3>| {
        for &i in &heavy {
            lowest = lowest.min(s.particles().x()[i][1]);
        }
        heavy_end = mean_y(s, &heavy);
        light_end = mean_y(s, &light);
        light_low = light_low.min(light_end);
    }));
    let o = run_sim_with(&mut sim, 0.3, Some(&mut track));
    drop(track);
    o.report("3D density ratio");
    eprintln!(
        "heavy: lowest particle {:.3} h above the floor, centre at {heavy_end:.4} m at the end; light: centre at {light_end:.4} m at the end, lowest {light_low:.4} m (water surface 0.1 m)",
        lowest / h
    );
    assert!(lowest > 0.9 * h, "into the floor: {} h", lowest / h);
    assert!(
        heavy_end < 0.08,
        "the heavy cube did not sink: {heavy_end} m"
    );
    assert!(
        light_low > 0.1,
        "the light cube sank: centre at {light_low} m"
    );
    o.assert_stable(ENERGY_TOL);
    o.assert_volume(VOLUME_STEP_TOL);
}

/// The density-ratio case keeps its fluid volume within 1 % over the run:
/// a known gap, chaotic (+0.00 to +3.45 % under perturbations of 10⁻⁴ …
/// 10⁻³ of the solids' stress, +1.78 % as it stands; see
/// `density_ratio_free_solids_in_water_3d`).
/// `cargo test --release --test suite stability_3d::density_ratio_keeps -- --ignored --nocapture`
#[test]
#[ignore = "known gap: the 3D density ratio's fluid volume ends +1.78 % (bound 1 %), chaotic: +0.00 to +3.45 % under 1e-4..1e-3 perturbations"]
fn density_ratio_keeps_its_fluid_volume_3d() {
    let mut sim = Simulation::new(
        density_ratio_3d(),
        Box::new(Delaunay3::default()),
        StepParams::default(),
    )
    .expect("scene builds");
    let o = run_sim(&mut sim, 0.3);
    o.report("3D density ratio");
    o.assert_volume_change(VOLUME_CHANGE_TOL);
}

/// A plate 0.1 m high, 0.06 m wide and 0.005 m thick (1:20, one cell
/// through the thickness at its spacing, E = 1e6 Pa, ρ = 1100 kg/m³)
/// clamped at its base at x = 0.15 m, hit by the wave of a 0.08 m column
/// (fluid spacing 0.01 m).
fn thin_plate_3d() -> Scene<3> {
    let hf = 0.01;
    let hp = 0.005;
    let s = Scene::<3>::new("thin_plate_3d")
        .gravity(g3())
        .settings(settings(0.25, 1e-3, 0.5));
    let s = tank3d(s, 0.3, 0.1, 0.2, hf, true);
    let plate = Hypoelastic::new(1100.0, 1e6, 0.4).expect("valid solid");
    s.solid(
        "plate",
        Box::new(plate),
        cuboid([0.15, hf, 0.02], [0.15 + hp, hf + 0.1, 0.08]),
        hp,
        base_clamp(hf),
    )
    .fluid(
        "water",
        Box::new(Newtonian::water()),
        cuboid([0.0, 0.0, 0.0], [0.08, 0.08, 0.1]),
        hf,
    )
}

/// Thin plate: besides the common checks, the wave bends it (its top moves
/// more than 2 mm along `x`). Measured (5 December 2026): 250 steps (0
/// rejected), top displaced 11.1 mm at most, energy at most +0.03 %,
/// volume within 0.22 % at every step, 19 s.
#[test]
fn thin_plate_hit_by_a_wave_3d() {
    let mut sim = Simulation::new(
        thin_plate_3d(),
        Box::new(Delaunay3::default()),
        StepParams::default(),
    )
    .expect("scene builds");
    let plate = sim.body_particles("plate").unwrap();
    let top_y = plate
        .iter()
        .map(|&i| sim.particles().x()[i][1])
        .fold(f64::NEG_INFINITY, f64::max);
    let top: Vec<usize> = plate
        .iter()
        .copied()
        .filter(|&i| sim.particles().x()[i][1] > top_y - 1e-9)
        .collect();
    let x0: f64 = top.iter().map(|&i| sim.particles().x()[i][0]).sum::<f64>() / top.len() as f64;
    let mut largest: f64 = 0.0;
    let mut track = Track::<3>(Box::new(|s: &Simulation<3>| {
        let x = top.iter().map(|&i| s.particles().x()[i][0]).sum::<f64>() / top.len() as f64;
        largest = largest.max(x - x0);
    }));
    let o = run_sim_with(&mut sim, 0.25, Some(&mut track));
    drop(track);
    o.report("3D thin plate");
    eprintln!(
        "plate top: largest displacement along x {:.2} mm",
        1e3 * largest
    );
    assert!(
        largest > 2e-3,
        "the wave did not bend the plate: {largest} m"
    );
    o.assert_stable(ENERGY_TOL);
    o.assert_volume_change(VOLUME_CHANGE_TOL);
    o.assert_volume(VOLUME_STEP_TOL);
}

/// Contact for clamped solids (`Scene::contact_clamped`) in 3D: the
/// stiffness contrast under the wave runs as it does without it, 150
/// steps, none rejected, no energy gained (asserted: energy at most +5 %, at most 5 rejected),
/// while the posts press on the side walls through up to 172 contact
/// elements (0.51 N at most).
///
/// History (the setting was refused in 3D until session 38, measured in
/// temporary builds). Session 36: a stiff post (E = 1e9 Pa) clamped on
/// the floor alone in the tank took 66 197 steps (21 315 rejected) for
/// 0.1 s 1.5 spacings from the side walls, a case not reproduced since.
/// Session 37, with the penalty's rounded onset: this scene took 744
/// steps (220 rejected by Picard). Session 38: the layer's own
/// linearisation, 258 (50); the dashpot's clamp without stiffness, 242
/// (43), the rejected attempts 2-cycles of the iterates; with damping 0,
/// 150 (0). The cause: the dashpot's `c |tr D|` switched on at full
/// strength as a closing gap passed the contact distance, a jump in the
/// pressure. It now grows in over the first tenth of the onset
/// (`pfem_constitutive::contact::DASHPOT_RAMP`): 150 (0). About 10 s.
#[test]
fn contact_for_clamped_solids_in_3d() {
    let s = stiffness_contrast_3d(1e4).contact_clamped(true);
    let end = s.settings.end_time;
    let mut sim =
        Simulation::new(s, Box::new(Delaunay3::default()), StepParams::default()).unwrap();
    assert!(sim.stages().contact);
    // The posts stand one spacing from the side walls and press on them
    // through contact elements (measured: up to 172 elements, 0.51 N).
    let mut most = 0;
    let mut largest: f64 = 0.0;
    let mut track = Track(Box::new(|sim: &Simulation<3>| {
        most = most.max(sim.elements().n_contact());
        for post in ["stiff", "soft"] {
            for wall in ["floor", "side_wall_0", "side_wall_1"] {
                if let Ok(f) = sim.contact_force(post, wall) {
                    largest = largest.max(f.normal.abs());
                }
            }
        }
    }));
    let o = run_sim_with(&mut sim, end, Some(&mut track));
    drop(track);
    println!("clamped contact: up to {most} contact elements, largest wall force {largest:.3e} N");
    assert!(most > 0 && largest > 0.05, "{most} elements, {largest} N");
    o.report("3D stiffness contrast, clamped contact");
    o.assert_stable(ENERGY_TOL);
    o.assert_volume_change(VOLUME_CHANGE_TOL);
    o.assert_volume(VOLUME_STEP_TOL);
    assert!(
        o.rejected <= 5,
        "{} of {} steps rejected",
        o.rejected,
        o.steps
    );
}

/// A stiff free block (E = 1e9 Pa) standing on the floor one spacing from
/// both side walls stays at rest: no energy gained, no particle kicked.
/// Bug fixed (session 36): flat contact tetrahedra (a row of the block
/// over a row of the floor) measured their gap along the arbitrary common
/// normal of two nearly parallel edges, and corner tetrahedra of three
/// bodies along a plane across the corner; elements started at 0.68 of
/// their gap, under pressure, and a particle left at 169 m/s within
/// 0.1 ms (energy ×4 000). Now (measured): energy never above its start
/// (asserted), fastest particle 1.6 mm/s (asserted below 1 cm/s).
#[test]
fn a_stiff_free_block_beside_the_side_walls_stays_at_rest_3d() {
    let h = 0.02;
    let s = Scene::<3>::new("block_beside_walls")
        .gravity(g3())
        .settings(settings(0.02, 2e-3, 0.5));
    let s = tank3d(s, 0.4, 0.1, 0.3, h, true).solid(
        "block",
        Box::new(Hypoelastic::new(1000.0, 1e9, 0.3).expect("valid solid")),
        cuboid([0.3, h, 0.02], [0.34, h + 0.08, 0.08]),
        h,
        None,
    );
    let o = run_checked_3d(s, StepParams::default());
    o.report("3D stiff block beside the side walls");
    eprintln!(
        "energy growth {:e}, fastest particle {:e} m/s",
        o.watch.energy_growth(),
        o.watch.v_max.0
    );
    o.assert_stable(0.0);
    assert!(o.watch.v_max.0 < 1e-2, "kicked: {} m/s", o.watch.v_max.0);
    // Bug fixed (session 38): where the contact dashpot clamped an
    // element's pressure to zero, its linearisation kept the penalty's and
    // the dashpot's stiffness; the iterates converged linearly at 0.75 and
    // 18 of 57 steps were rejected. Now 2 of 14 (0 of 10 once the
    // dashpot's ramp and its slope came in, the same session).
    assert!(
        o.rejected <= 5,
        "{} of {} steps rejected",
        o.rejected,
        o.steps
    );
}
