//! Contact and free solids (issue 19): elastic blocks resting on a floor and
//! on each other, a block on an inclined floor with Coulomb friction
//! (sticking below the friction angle, sliding at g (sin θ − μ cos θ) above
//! it), an elastic disk bouncing on a floor.
//!
//! The incline is the floor under gravity tilted by θ (the same problem in
//! the floor's frame). The 3D block rests too (session 37: the contact
//! penalty's rounded onset, see its docs).
//! `cargo test --release --test suite contact:: -- --nocapture`

use pfem::constitutive::{ContactPenalty, Hypoelastic};
use pfem::prelude::*;

const G: f64 = 9.81;

/// A floor 2 m long (top row at y = 0) and a free elastic block
/// `w × t` one spacing above it, under gravity tilted by `theta` (rad)
/// towards +x, with friction `mu` between block and floor.
fn block_on_floor(h: f64, w: f64, t: f64, theta: f64, mu: f64, young: f64) -> Scene<2> {
    Scene::<2>::new("block")
        .gravity(Vector::<2>::new(G * theta.sin(), -G * theta.cos()))
        .settings(RunSettings {
            end_time: 1.0,
            max_dt: 2e-3,
            output_interval: None,
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-0.5, -h),
                max: Point::<2>::new(1.5, 0.0),
            },
            h,
            WallMotion::Fixed,
        )
        .solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, young, 0.3).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(0.0, h),
                max: Point::<2>::new(w, h + t),
            },
            h,
            None,
        )
        .friction("block", "floor", mu)
}

fn sim(scene: Scene<2>) -> Simulation<2> {
    Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default()).unwrap()
}

/// Mean of a body's particle positions.
fn centroid(sim: &Simulation<2>, body: &str) -> Point<2> {
    let idx = sim.body_particles(body).unwrap();
    let mut c = Point::<2>::zeros();
    for &i in &idx {
        c += sim.particles().x()[i];
    }
    c / idx.len() as f64
}

/// Lowest particle of a body (m).
fn lowest(sim: &Simulation<2>, body: &str) -> f64 {
    sim.body_particles(body)
        .unwrap()
        .iter()
        .map(|&i| sim.particles().x()[i][1])
        .fold(f64::INFINITY, f64::min)
}

/// A floor two rows deep (top row at y = 0, spacing `h`) and a free steel
/// block (E = 2·10¹¹ Pa, 0.1 m wide) from `bottom` to `top`.
fn steel_over_floor(name: &str, settings: RunSettings, h: f64, bottom: f64, top: f64) -> Scene<2> {
    Scene::<2>::new(name)
        .gravity(Vector::<2>::new(0.0, -G))
        .settings(settings)
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-0.1, -2.0 * h),
                max: Point::<2>::new(0.2, 0.0),
            },
            h,
            WallMotion::Fixed,
        )
        .solid(
            "steel",
            Box::new(Hypoelastic::new(STEEL.0, STEEL.1, STEEL.2).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(0.0, bottom),
                max: Point::<2>::new(0.1, top),
            },
            h,
            None,
        )
}

/// Steel: density (kg/m³), Young's modulus (Pa), Poisson's ratio.
const STEEL: (f64, f64, f64) = (7800.0, 2e11, 0.3);

/// Session 50 (a review): a soft block (E = 10⁴ Pa) resting on a free
/// steel block (E = 2·10¹¹ Pa) that rests on the floor. Each contact
/// element took the stiffest penalty among its bodies, the steel's P-wave
/// modulus, 2·10⁷ times the soft block's own: its elements inverted at
/// t = 0.20 s (`StepTooSmall` after 238 Picard rejections), where on a
/// wall it rests with none. The softer solid's penalty: no step rejected,
/// and the soft block sits on the steel.
#[test]
fn a_soft_block_rests_on_a_free_steel_block() {
    let h = 0.01;
    let settings = RunSettings {
        end_time: 0.5,
        max_dt: 2e-3,
        output_interval: None,
        ..Default::default()
    };
    let scene = steel_over_floor("stack_mixed", settings, h, h, 0.1).solid(
        "soft",
        Box::new(Hypoelastic::new(1000.0, 1e4, 0.3).unwrap()),
        Geometry::Box {
            min: Point::<2>::new(0.0, 0.1 + h),
            max: Point::<2>::new(0.1, 0.2),
        },
        h,
        None,
    );
    let mut s = sim(scene);
    let result = s.run(&mut []);
    let soft_low = lowest(&s, "soft");
    let steel_top = s
        .body_particles("steel")
        .unwrap()
        .iter()
        .map(|&i| s.particles().x()[i][1])
        .fold(f64::NEG_INFINITY, f64::max);
    println!(
        "soft on steel: {:?} at t = {:.3} s, {} steps ({} rejected), soft block's lowest particle {:.3} h above the steel's top",
        result.as_ref().err(),
        s.time(),
        s.steps(),
        s.rejected(),
        (soft_low - steel_top) / h
    );
    result.unwrap();
    assert!(s.rejected() * 20 <= s.steps(), "{} rejected", s.rejected());
    assert!(soft_low - steel_top > 0.5 * h);
}

/// Session 50 (session 49's review): a restored simulation reads the
/// contact force its checkpoint's run did. The contact range is formed
/// anew by the restore without a solve, and its elements read zero until
/// the next step; a block sticking on a 20° incline (μ = 0.5) now reads
/// its weight's normal and tangential parts from the restore on.
#[test]
fn a_restored_simulation_reads_the_contact_force_of_its_checkpoint() {
    let (h, theta) = (0.02, 20f64.to_radians());
    let scene = || block_on_floor(h, 0.4, 0.2, theta, 0.5, 1e7);
    let mut s = sim(scene());
    s.set_end_time(0.3).unwrap();
    s.run(&mut []).unwrap();
    let before = s.contact_force("block", "floor").unwrap();
    let weight = 1000.0 * 0.4 * 0.2 * G;
    let mut restored = sim(scene());
    restored.restore(&s.checkpoint()).unwrap();
    let after = restored.contact_force("block", "floor").unwrap();
    println!(
        "sticking block: normal {:.2} / {:.2} N/m, tangential {:.2} / {:.2} N/m (weight's {:.2} / {:.2}), {} / {} active elements, before / after the restore",
        before.normal,
        after.normal,
        before.tangential,
        after.tangential,
        weight * theta.cos(),
        weight * theta.sin(),
        before.active,
        after.active
    );
    for (f, what) in [(before, "before"), (after, "after")] {
        assert!(
            (f.normal / (weight * theta.cos()) - 1.0).abs() < 0.02,
            "{what}: normal {}",
            f.normal
        );
        assert!(
            (f.tangential / (weight * theta.sin()) - 1.0).abs() < 0.05,
            "{what}: tangential {}",
            f.tangential
        );
    }
    // The frames' contact pressure too: some element pushes.
    let first = restored.elements().len() - restored.elements().n_contact();
    assert!(restored.elements().history()[first..]
        .iter()
        .any(|h| ContactPenalty::pressure(h) > 0.0));
}

#[test]
fn a_free_block_rests_on_the_floor_without_sinking_through_it() {
    let h = 0.02;
    let mut s = sim(block_on_floor(h, 0.4, 0.2, 0.0, 0.0, 1e7));
    assert!(s.stages().contact, "the scene has contact");
    s.set_end_time(0.5).unwrap();
    let mut worst: f64 = f64::INFINITY;
    while s.time() < s.end_time() - 1e-12 {
        s.step().unwrap();
        worst = worst.min(lowest(&s, "block"));
    }
    let v = s
        .body_particles("block")
        .unwrap()
        .iter()
        .map(|&i| s.particles().v()[i].norm())
        .fold(0.0, f64::max);
    let penetration = (h - worst) / h;
    println!(
        "block on floor: {} steps ({} rejected), deepest penetration {:.2e} spacing, largest speed at the end {v:.2e} m/s, {} contact elements",
        s.steps(),
        s.rejected(),
        penetration,
        s.elements().n_contact()
    );
    // The floor carries the block's weight, 1000 × 0.4 × 0.2 × g.
    let f = s.contact_force("block", "floor").unwrap();
    let weight = 1000.0 * 0.4 * 0.2 * G;
    println!(
        "contact force on the block: normal {:.2} N/m (weight {weight:.2}), tangential {:.2e}, {} active elements",
        f.normal, f.tangential, f.active
    );
    assert!(
        (f.normal / weight - 1.0).abs() < 0.01,
        "{} vs {weight}",
        f.normal
    );
    assert!(f.tangential < 1e-3 * weight);
    assert!(s.contact_force("block", "nobody").is_err());
    assert!(penetration < 0.05, "penetration {penetration} of a spacing");
    assert!(v < 0.02, "still moving at {v} m/s");
    assert!(s.elements().n_contact() > 0);
    // Come to rest (2.4·10⁻⁸ m/s at 0.45 s), its velocity's changes from
    // one Picard iterate to the next stall at round-off; judged against
    // the velocity alone, every step from 0.452 s was rejected down to
    // Δt = 2·10⁻⁵ s (1 995 steps, 575 rejected; `pfem_time::BODY_FORCE_FLOOR`).
    assert!(s.rejected() <= 2, "{} rejected steps", s.rejected());
}

/// The 0.2 × 0.1 m block on the floor tilted by `theta_deg` with friction
/// `mu`, run for 1 s with `params`: how far its centroid moved (m, printed
/// with the run's cost) and the simulation.
fn creep(theta_deg: f64, mu: f64, params: StepParams) -> (f64, Simulation<2>) {
    let scene = block_on_floor(0.02, 0.2, 0.1, theta_deg.to_radians(), mu, 1e7);
    let relaxed = params.picard_relaxation;
    let mut s = Simulation::new(scene, Box::new(Delaunay2::default()), params).unwrap();
    let x0 = centroid(&s, "block")[0];
    s.run(&mut []).unwrap();
    let dx = centroid(&s, "block")[0] - x0;
    println!(
        "{}θ = {theta_deg}°, tan θ = {:.3} < μ = {mu}: moved {dx:.2e} m in 1 s, {} steps ({} rejected), {} Picard iterates",
        if relaxed { "relaxed, " } else { "" },
        theta_deg.to_radians().tan(),
        s.steps(),
        s.rejected(),
        s.stats().assemble.0
    );
    (dx, s)
}

/// A sticking block's 1 s costs few steps and few rejected ones (the
/// layer's own linearisation, session 38).
fn assert_sticks_cheaply(s: &Simulation<2>) {
    assert!(s.rejected() <= 20, "{} rejected steps", s.rejected());
    assert!(s.steps() <= 600, "{} steps", s.steps());
}

/// Below the friction angle the block sticks; above it, it slides with
/// the acceleration g (sin θ − μ cos θ).
#[test]
fn friction_holds_below_the_friction_angle_and_lets_go_above_it() {
    let (h, mu) = (0.02, 0.5);
    for theta_deg in [10.0f64, 15.0] {
        let (dx, _) = creep(theta_deg, mu, StepParams::default());
        assert!(dx.abs() < 1e-3 * 0.2, "θ = {theta_deg}°: slid {dx} m");
    }
    for theta_deg in [35.0f64, 45.0] {
        let theta = theta_deg.to_radians();
        let mut s = sim(block_on_floor(h, 0.2, 0.1, theta, mu, 1e7));
        s.set_end_time(0.4).unwrap();
        let mut series = Vec::new();
        let (mut ft, mut fnorm) = (0.0, 0.0);
        while s.time() < s.end_time() - 1e-12 {
            s.step().unwrap();
            if s.time() > 0.1 {
                series.push((s.time(), centroid(&s, "block")[0]));
                let f = s.contact_force("block", "floor").unwrap();
                ft += f.tangential * s.dt();
                fnorm += f.normal * s.dt();
            }
        }
        // Least-squares x = a + b t + c t²/2.
        let a = fit_acceleration(&series);
        // Sliding: the friction impulse is μ times the normal impulse.
        println!(
            "θ = {theta_deg}°: friction / normal impulse = {:.4} (μ = {mu})",
            ft / fnorm
        );
        assert!((ft / fnorm / mu - 1.0).abs() < 0.01, "{}", ft / fnorm);
        let expect = G * (theta.sin() - mu * theta.cos());
        println!(
            "θ = {theta_deg}°: acceleration {a:.4} m/s² against g (sin θ − μ cos θ) = {expect:.4} ({:+.2} %)",
            100.0 * (a / expect - 1.0)
        );
        assert!(
            (a / expect - 1.0).abs() < 0.03,
            "θ = {theta_deg}°: {a} vs {expect}"
        );
    }
}

/// Nearer the friction angle (20° with μ = 0.5: tan θ = 0.73 μ) the block
/// still sticks. With the penalty's kink (`onset = 0`) it crept 2.9 mm in
/// 1 s (15 times the bound), rocking on the layer whose stiffness
/// switched on and off; with the rounded onset (session 37), 0.11 mm,
/// and with the consistent (zero) slip tangent in 2D, 0.02 mm. Picard
/// then still rejected a third of its steps (557 of 1 748), converging
/// linearly near 0.6: the layer's linearisation was isotropic. With its
/// own (`Unified::layer`, session 38) it took 507 steps, 4 rejected, and
/// crept 0.013 mm; with the contact dashpot grown in over the onset (the
/// same session), 517 steps, 9 rejected, 0.032 mm. About 1 s.
#[test]
fn friction_holds_near_the_friction_angle() {
    let (mu, theta_deg) = (0.5, 20.0f64);
    let (dx, s) = creep(theta_deg, mu, StepParams::default());
    assert!(dx.abs() < 1e-3 * 0.2, "θ = {theta_deg}°: slid {dx} m");
    // The layer's linearisation resists only the shear across it
    // (`Unified::layer`, session 38): 517 steps, 9 rejected. With the
    // isotropic `2 G_c D'` before it, 1 748 steps, 557 rejected by Picard.
    assert_sticks_cheaply(&s);
}

/// The same block with Aitken's relaxation of the Picard iterates
/// (`StepParams::picard_relaxation`, opt-in, session 37): it sticks as
/// well (8.7·10⁻⁶ m in 1 s, 500 steps, none rejected, 1 559 Picard
/// iterates against 1 847 without). Session 37 brought it in when the
/// layer's isotropic linearisation made the iterates converge linearly
/// at a rate near 0.6 (557 of 1 748 steps rejected without it, 6 of 507
/// with it); the layer's own linearisation (session 38) has since cured
/// that cause. About 1 s.
#[test]
fn aitken_relaxation_makes_a_sticking_block_cheap() {
    let params = StepParams {
        picard_relaxation: true,
        ..StepParams::default()
    };
    let (dx, s) = creep(20.0, 0.5, params);
    assert!(dx.abs() < 1e-3 * 0.2, "slid {dx} m");
    // Without it: 517 steps, 9 rejected (the test above).
    assert_sticks_cheaply(&s);
}

fn fit_acceleration(series: &[(f64, f64)]) -> f64 {
    // Least squares for x = a + b t + c t²/2: normal equations, Cramer.
    let mut m = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    for &(t, x) in series {
        let b = [1.0, t, 0.5 * t * t];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += b[i] * b[j];
            }
            r[i] += b[i] * x;
        }
    }
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let mut m2 = m;
    for i in 0..3 {
        m2[i][2] = r[i];
    }
    det(&m2) / det(&m)
}

#[test]
fn two_blocks_stacked_on_a_floor_stay_apart() {
    let h = 0.02;
    let scene = block_on_floor(h, 0.4, 0.1, 0.0, 0.0, 1e7).solid(
        "top",
        Box::new(Hypoelastic::new(1000.0, 1e7, 0.3).unwrap()),
        Geometry::Box {
            min: Point::<2>::new(0.1, 0.1 + 2.0 * h),
            max: Point::<2>::new(0.3, 0.2 + 2.0 * h),
        },
        h,
        None,
    );
    let mut s = sim(scene);
    s.set_end_time(0.3).unwrap();
    let mut gap_top: f64 = f64::INFINITY;
    let mut gap_floor: f64 = f64::INFINITY;
    while s.time() < s.end_time() - 1e-12 {
        s.step().unwrap();
        let top_low = lowest(&s, "top");
        let block_high = s
            .body_particles("block")
            .unwrap()
            .iter()
            .map(|&i| s.particles().x()[i][1])
            .fold(f64::NEG_INFINITY, f64::max);
        gap_top = gap_top.min(top_low - block_high);
        gap_floor = gap_floor.min(lowest(&s, "block"));
    }
    println!(
        "stacked: {} steps, smallest gaps {:.4} h (top on block), {:.4} h (block on floor)",
        s.steps(),
        gap_top / h,
        gap_floor / h
    );
    assert!(gap_top > 0.95 * h && gap_floor > 0.95 * h);
    assert!(s
        .particles()
        .x()
        .iter()
        .all(|p| p.iter().all(|v| v.is_finite())));
}

/// Kinetic and elastic energy of a body (J per metre): lumped masses from
/// its solid elements, plane-strain strain energy from their stress.
fn energy(sim: &Simulation<2>, rho: f64, young: f64, nu: f64) -> (f64, f64) {
    let x = sim.particles().x();
    let v = sim.particles().v();
    let el = sim.elements();
    let mass = crate::stability_support::solid_masses(sim, rho);
    let mut strain = 0.0;
    for (e, h) in el.solid().chunks_exact(3).zip(el.solid_history()) {
        let p = [x[e[0] as usize], x[e[1] as usize], x[e[2] as usize]];
        let area = pfem::core::simplex_measure::<2>(&p);
        let (sx, sy, sz, t) = (
            h.stress[(0, 0)],
            h.stress[(1, 1)],
            h.stress_zz,
            h.stress[(0, 1)],
        );
        strain += area
            * (sx * sx + sy * sy + sz * sz - 2.0 * nu * (sx * sy + sy * sz + sz * sx)
                + 2.0 * (1.0 + nu) * t * t)
            / (2.0 * young);
    }
    let kinetic = (0..x.len())
        .map(|i| 0.5 * mass[i] * v[i].norm_squared())
        .sum::<f64>();
    (kinetic, strain)
}

/// An elastic disk thrown at a floor at 1 m/s (no gravity, no friction,
/// the undamped trapezoidal rule, a contact stiffness ten times the disk's
/// P-wave modulus and no contact dashpot) bounces back without passing
/// through it and keeps its energy. The disk (`Geometry::Ball` for a
/// solid) is sampled on rings: measured 1.7 % of the gap closed, energy
/// +0.18 % (1.2 % and +0.28 % before the rounded onset, session 37), in
/// contact for 19.8 ms (with the default dashpot 1.1 % and +0.23 %). As a lattice it met the floor with one particle: it needed the
/// dashpot (2.5 %, +0.2 %; without, the chatter inverted an element), and
/// at the default stiffness (the disk's modulus) it closed 23 % of the
/// gap, against 9.4 % on rings. (Ten times the default on the resting block of the first test took
/// 17 184 steps, 5 507 rejected by Picard, against 250.)
#[test]
fn an_elastic_disk_bounces_off_a_floor_and_keeps_its_energy() {
    let (h, r, rho, young, nu) = (0.01, 0.1, 1000.0, 1e6, 0.3);
    let scene = Scene::<2>::new("disk")
        .settings(RunSettings {
            end_time: 0.06,
            max_dt: 2e-4,
            output_interval: None,
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-0.2, -h),
                max: Point::<2>::new(0.2, 0.0),
            },
            h,
            WallMotion::Fixed,
        )
        .solid(
            "disk",
            Box::new(Hypoelastic::new(rho, young, nu).unwrap()),
            Geometry::Ball {
                center: Point::<2>::new(0.0, r + 2.0 * h),
                radius: r,
            },
            h,
            None,
        )
        .with_velocity(Vector::<2>::new(0.0, -1.0))
        // Ten times the default (the disk's P-wave modulus 1.35 MPa).
        .contact_stiffness(1.35e7)
        .contact_damping(0.0);
    let params = StepParams {
        scheme: Scheme::Newmark,
        ..StepParams::default()
    };
    let mut s = Simulation::new(scene, Box::new(Delaunay2::default()), params).unwrap();
    let (k0, e0) = energy(&s, rho, young, nu);
    let mut deepest: f64 = f64::INFINITY;
    let (mut t_on, mut t_off) = (None, None);
    while s.time() < s.end_time() - 1e-12 {
        s.step().unwrap();
        deepest = deepest.min(lowest(&s, "disk"));
        let pushing = s.contact_force("disk", "floor").unwrap().normal > 0.0;
        if pushing && t_on.is_none() {
            t_on = Some(s.time());
        }
        if !pushing && t_on.is_some() && t_off.is_none() {
            t_off = Some(s.time());
        }
    }
    let (k1, e1) = energy(&s, rho, young, nu);
    let vy = {
        let idx = s.body_particles("disk").unwrap();
        idx.iter().map(|&i| s.particles().v()[i][1]).sum::<f64>() / idx.len() as f64
    };
    let total0 = k0 + e0;
    let total1 = k1 + e1;
    println!(
        "disk: {} steps ({} rejected); contact from {:?} to {:?} s; deepest point {:.3} h above the floor's top row; \
         energy {total0:.4} -> {total1:.4} J/m ({:+.2} %; elastic {e1:.4}); rebound velocity {vy:.3} m/s",
        s.steps(),
        s.rejected(),
        t_on,
        t_off,
        deepest / h,
        100.0 * (total1 / total0 - 1.0)
    );
    assert!(t_off.is_some(), "the disk did not leave the floor");
    assert!(vy > 0.0, "no rebound");
    assert!(deepest > 0.95 * h, "penetrated to {deepest} m");
    assert!((total1 / total0 - 1.0).abs() < 0.05, "{total0} -> {total1}");
}

/// A block dropped from above a floor lands on it. Until session 41 the
/// scene's validation refused it ("no support"): a free solid under
/// gravity had to start touching a wall, though contact catches it as
/// well from above. It falls freely to the contact distance (one spacing
/// above the floor's top row), comes back up, and never sinks through.
#[test]
fn a_block_dropped_onto_a_floor_lands_on_it() {
    let (h, drop) = (0.01, 0.03);
    let scene_with = |g: Vector<2>| {
        Scene::<2>::new("drop")
            .gravity(g)
            .wall(
                "floor",
                Geometry::Box {
                    min: Point::<2>::new(-0.1, -h),
                    max: Point::<2>::new(0.2, 0.0),
                },
                h,
                WallMotion::Fixed,
            )
            .solid(
                "block",
                Box::new(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap()),
                Geometry::Box {
                    min: Point::<2>::new(0.0, h + drop),
                    max: Point::<2>::new(0.1, h + drop + 0.05),
                },
                h,
                None,
            )
    };
    let scene = scene_with(Vector::<2>::new(0.0, -G)).settings(RunSettings {
        end_time: 0.25,
        max_dt: 2e-3,
        output_interval: None,
        ..Default::default()
    });
    scene.validate().expect("a solid above a floor lands on it");
    // Under a ceiling alone it has nothing to land on.
    let hanging = Scene::<2>::new("ceiling")
        .gravity(Vector::<2>::new(0.0, -G))
        .wall(
            "ceiling",
            Geometry::Box {
                min: Point::<2>::new(-0.1, 0.2),
                max: Point::<2>::new(0.2, 0.2 + h),
            },
            h,
            WallMotion::Fixed,
        )
        .solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(0.0, h + drop),
                max: Point::<2>::new(0.1, h + drop + 0.05),
            },
            h,
            None,
        );
    assert!(matches!(
        hanging.validate(),
        Err(pfem::SceneError::Unsupported { .. })
    ));
    // Gravity tilted past 45° still lands it on the floor below and
    // ahead of it; zero gravity needs no support.
    let mut tilted = scene_with(Vector::<2>::new(0.8 * G, -0.6 * G));
    assert!(tilted.validate().is_ok());
    tilted.gravity = Some(Vector::<2>::zeros());
    assert!(tilted.validate().is_ok());
    let mut s = sim(scene);
    assert!(s.stages().contact);
    let block = s.body_particles("block").unwrap();
    let mean_vy = |s: &Simulation<2>| {
        block.iter().map(|&i| s.particles().v()[i][1]).sum::<f64>() / block.len() as f64
    };
    // Free fall to the contact distance: t = sqrt(2 drop / g).
    let t_land = (2.0 * drop / G).sqrt();
    let (mut worst, mut impact_v, mut rebound_v): (f64, f64, f64) = (f64::INFINITY, 0.0, 0.0);
    while s.time() < s.end_time() - 1e-12 {
        s.step().unwrap();
        worst = worst.min(lowest(&s, "block"));
        let vy = mean_vy(&s);
        impact_v = impact_v.min(vy);
        rebound_v = rebound_v.max(vy);
        if s.time() < 0.9 * t_land {
            // In free fall: v = −g t to the scheme's round-off.
            assert!((vy + G * s.time()).abs() < 1e-6 * G, "{vy} at {}", s.time());
        }
    }
    println!(
        "dropped block: {} steps ({} rejected), impact {impact_v:.3} m/s (free fall {:.3}), rebound {rebound_v:.3} m/s, lowest point {:.3} h above the floor's top row",
        s.steps(),
        s.rejected(),
        -(2.0 * G * drop).sqrt(),
        worst / h
    );
    assert!(worst > 0.8 * h, "sank to {worst} m");
    assert!(
        impact_v < -0.9 * (2.0 * G * drop).sqrt(),
        "impact {impact_v}"
    );
    assert!(
        rebound_v > 0.2 * (2.0 * G * drop).sqrt(),
        "no rebound: {rebound_v}"
    );
}

/// A steel block (E = 2·10¹¹ Pa) dropped onto a floor at the default
/// step (`max_dt` 5 ms) never rises above where it started, and its
/// energy (kinetic, potential and strain) never grows past its start by
/// more than 1 % of what the drop gives it. Session 51 (a review): the
/// stiff contact layer stopped the block within one step, and the
/// scheme carried the impact's end-of-step acceleration into the next,
/// where the layer had let go: dropped 1 cm it rose here to 2.87 times
/// its drop, its energy up by 1.87 times the drop's
/// (`Simulation::forget_impacts` now leaves the impact's acceleration
/// out: 0.41 times, no gain; 5 cm: 0.140). Dropped 45 cm (3 m/s, half a
/// spacing a step) it went from beyond the contact elements' reach to
/// inside its contact distance within one step, and the element formed
/// late pushed it out: 1.64 times its drop (the step is now bounded by
/// the bodies' approach, `Simulation::approach_time`: 0.096 times). Each
/// figure "before" is this test with that one part taken out; the
/// review's scene (a floor of one row less) rose 5.85 and 5.26 times
/// dropped 5 and 45 cm with neither.
#[test]
fn a_stiff_block_dropped_onto_a_floor_never_rises_above_its_start() {
    let h = 0.01;
    let (rho, young, nu) = STEEL;
    // (The last with a step bound far above the fall's time: the first
    // step from rest, which has no velocity to bound it by, took the block
    // 4 spacings down to 9.5 % of its contact distance with no element to
    // stop it, and it rose to 6 times its drop; the bodies' accelerations
    // bound it now: session 54's review.)
    for (drop, max_dt, rho, young) in [
        (0.01, 5e-3, rho, young),
        (0.05, 5e-3, rho, young),
        (0.45, 5e-3, rho, young),
        (0.04, 0.1, 1000.0, 1e9),
    ] {
        let settings = RunSettings {
            end_time: 4.0 * (2.0 * drop / G).sqrt(),
            max_dt,
            output_interval: None,
            ..Default::default()
        };
        let mut scene = steel_over_floor("steel drop", settings, h, h + drop, h + drop + 0.09);
        scene.bodies[1].material = Some(Box::new(Hypoelastic::new(rho, young, nu).unwrap()));
        let mut s = sim(scene);
        let mass = crate::stability_support::solid_masses(&s, rho);
        let total = |s: &Simulation<2>| {
            let (kinetic, strain) = energy(s, rho, young, nu);
            let potential: f64 = (0..mass.len())
                .map(|i| mass[i] * G * s.particles().x()[i][1])
                .sum();
            kinetic + strain + potential
        };
        let m: f64 = mass.iter().sum();
        let (e0, y0) = (total(&s), lowest(&s, "steel"));
        let (mut highest_after, mut landed, mut gain): (f64, bool, f64) =
            (f64::NEG_INFINITY, false, f64::NEG_INFINITY);
        while s.time() < s.end_time() - 1e-12 {
            s.step().unwrap();
            let y = lowest(&s, "steel");
            landed |= y < y0 - 0.9 * drop;
            if landed {
                highest_after = highest_after.max(y);
            }
            gain = gain.max(total(&s) - e0);
        }
        println!(
            "block (E = {young:e} Pa) dropped {drop} m (max_dt {max_dt} s): {} steps ({} rejected); highest after landing {:.3} of the drop above the floor's contact distance; largest energy gain {:.4} of the drop's",
            s.steps(),
            s.rejected(),
            (highest_after - h) / drop,
            gain / (m * G * drop)
        );
        assert!(landed, "the block never landed");
        assert!(
            highest_after < y0,
            "dropped {drop} m it rose to {:.2} times its drop",
            (highest_after - h) / drop
        );
        assert!(
            gain < 0.01 * m * G * drop,
            "dropped {drop} m its energy grew by {:.3} of the drop's",
            gain / (m * G * drop)
        );
    }
}

/// A steel block set by the scene just inside its contact distance of the
/// floor (at 99 % of it, which the scene accepts) stays on the floor: the
/// penalty of the layer its placement closed entered the first
/// accelerations, and the scheme carried it into the first step's
/// velocity, throwing the block off the floor at 57 m/s (session 54's
/// review: 16.8 m up in 0.3 s). Before the first step the accelerations
/// leave the contact layers out now, and the first step's solve lets the
/// layer push the block out of its closure (10⁻⁴ m).
#[test]
fn a_stiff_block_set_just_inside_its_contact_distance_stays_on_the_floor() {
    let h = 0.01;
    for young in [1e9, STEEL.1] {
        let settings = RunSettings {
            end_time: 0.1,
            max_dt: 2e-3,
            output_interval: None,
            ..Default::default()
        };
        let bottom = 0.99 * h;
        let mut scene = steel_over_floor("set inside", settings, h, bottom, bottom + 0.09);
        scene.bodies[1].material =
            Some(Box::new(Hypoelastic::new(STEEL.0, young, STEEL.2).unwrap()));
        let mut s = sim(scene);
        let mut highest = f64::NEG_INFINITY;
        while s.time() < s.end_time() - 1e-12 {
            s.step().unwrap();
            highest = highest.max(lowest(&s, "steel"));
        }
        println!(
            "E = {young:e} Pa set at 0.99 h: highest {:.3e} m above its start",
            highest - bottom
        );
        // Out of the closure (h/100), and not thrown: within a tenth of a
        // spacing of its start.
        assert!(
            highest - bottom < 0.1 * h,
            "E = {young:e}: rose {:.3e} m",
            highest - bottom
        );
        assert!(
            (lowest(&s, "steel") - h).abs() < 0.02 * h,
            "{}",
            lowest(&s, "steel")
        );
    }
}

/// A block of spacing 0.01 m (the box `lo`–`hi`) over a floor of spacing
/// 0.02 m whose top row is at `y = 0`, under gravity, to `end_time`.
fn fine_block_on_coarse_floor(lo: Point<2>, hi: Point<2>, end_time: f64) -> Scene<2> {
    let hf = 0.02;
    Scene::<2>::new("fine on coarse")
        .gravity(Vector::<2>::new(0.0, -G))
        .settings(RunSettings {
            end_time,
            max_dt: 2e-3,
            output_interval: None,
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-0.2, -hf),
                max: Point::<2>::new(0.4, 0.0),
            },
            hf,
            WallMotion::Fixed,
        )
        .solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, 1e7, 0.3).unwrap()),
            Geometry::Box { min: lo, max: hi },
            0.01,
            None,
        )
}

/// A fine block (spacing h) on a coarse floor (2h), its bottom row the
/// pair's contact distance 1.5h above the floor's top row: it rests. Until
/// session 41 each contact element took the mean spacing of its own
/// particles as its contact distance (1.67h with two floor particles,
/// 1.33h with two block particles), so the block started under pressure
/// in one kind and open in the other.
#[test]
fn a_fine_block_rests_on_a_coarse_floor() {
    let (h, hf) = (0.01, 0.02);
    let (w, t) = (0.2, 0.05);
    let y = 0.5 * (h + hf);
    let scene = fine_block_on_coarse_floor(Point::<2>::new(0.0, y), Point::<2>::new(w, y + t), 0.3);
    let mut s = sim(scene);
    let y0 = lowest(&s, "block");
    let weight = 1000.0 * w * t * G;
    let (mut top, mut impulse, mut span) = (y0, 0.0, 0.0);
    while s.time() < s.end_time() - 1e-12 {
        s.step().unwrap();
        top = top.max(lowest(&s, "block"));
        if s.time() > 0.2 {
            impulse += s.contact_force("block", "floor").unwrap().normal * s.dt();
            span += s.dt();
        }
    }
    let f = impulse / span;
    let v = s
        .body_particles("block")
        .unwrap()
        .iter()
        .map(|&i| s.particles().v()[i].norm())
        .fold(0.0, f64::max);
    println!(
        "fine block on a coarse floor: {} steps ({} rejected), rose {:.2e} m above its start, floor force {f:.3} N/m (weight {weight:.3}), largest speed at the end {v:.2e} m/s",
        s.steps(),
        s.rejected(),
        top - y0
    );
    assert!(top - y0 < 0.01 * h, "launched: rose {} m", top - y0);
    assert!((f / weight - 1.0).abs() < 0.02, "{f} vs {weight}");
    assert!(v < 0.02, "still moving at {v} m/s");
}

/// Bodies in contact that start closer than their contact distance are
/// refused with the pair named (session 44's review): the block one of
/// its own spacings over the floor twice as coarse started at 67 % of the
/// contact distance, under a third of the penalty's modulus, and a block
/// standing on the floor's row with its lattice offset by a quarter of
/// the floor's spacing at 33 %. Both were built and kicked at the first step. At the contact
/// distance the same block is built (`a_fine_block_rests_on_a_coarse_floor`).
#[test]
fn bodies_in_contact_closer_than_their_contact_distance_are_refused() {
    let (h, hf) = (0.01, 0.02);
    let block = |lo, hi| fine_block_on_coarse_floor(lo, hi, 0.01);
    for (lo, hi) in [
        (Point::<2>::new(0.0, h), Point::<2>::new(0.2, h + 0.05)),
        (Point::<2>::new(0.005, 0.0), Point::<2>::new(0.205, 0.05)),
    ] {
        let err = Simulation::new(
            block(lo, hi),
            Box::new(Delaunay2::default()),
            StepParams::default(),
        )
        .map(|_| ())
        .unwrap_err();
        assert!(
            err.to_string().contains("contact distance") && err.to_string().contains("floor"),
            "{lo}: {err}"
        );
        println!("{err}");
    }
    let y = 0.5 * (h + hf);
    assert!(Simulation::new(
        block(Point::<2>::new(0.0, y), Point::<2>::new(0.2, y + 0.05)),
        Box::new(Delaunay2::default()),
        StepParams::default()
    )
    .is_ok());
    // Session 47: the widest onset (½) accepted the first block, half its
    // contact distance in (67 %), under a tenth of the penalty's modulus
    // (`K_c x²/2δ`, `x` = 0.33). The starting pressure is bounded by the
    // default onset's (`K_c δ₀/2`): at ½, 92.9 % is the least accepted.
    let wide = |lo, hi| {
        Simulation::new(
            block(lo, hi).contact_onset(0.5),
            Box::new(Delaunay2::default()),
            StepParams::default(),
        )
        .map(|_| ())
    };
    let err = wide(Point::<2>::new(0.0, h), Point::<2>::new(0.2, h + 0.05)).unwrap_err();
    assert!(err.to_string().contains("92.9 %"), "{err}");
    assert!(wide(Point::<2>::new(0.0, y), Point::<2>::new(0.2, y + 0.05)).is_ok());
    // Session 48: the accepted block moved by hand down to the first
    // block's place before the first step was meshed there (session 47)
    // but not checked again: it started under the penalty and was kicked.
    // The first step refuses it, naming a particle of the block; moved by
    // hand to another accepted place, it runs.
    for (dy, refused) in [(y - h, true), (-0.002, false)] {
        let mut s = Simulation::new(
            block(Point::<2>::new(0.0, y), Point::<2>::new(0.2, y + 0.05)),
            Box::new(Delaunay2::default()),
            StepParams::default(),
        )
        .unwrap();
        let ids = s.body_particles("block").unwrap();
        for &i in &ids {
            s.particles_mut().x_mut()[i].y -= dy;
        }
        // (Refused again at a second try: the positions were meshed by
        // the first, which found nothing moved since.)
        for _ in 0..2 {
            let r = s.step();
            match r {
                Err(RunError::InvalidParticle { particle, why }) if refused => {
                    assert!(ids.contains(&particle), "{particle}: {why}");
                    assert!(
                        why.contains("moved by hand") && why.contains("contact distance"),
                        "{why}"
                    );
                }
                r => assert_eq!(r.is_ok(), !refused, "{dy}: {r:?}"),
            }
        }
    }
}

/// 3D: a free elastic block resting on a floor (contact elements of three
/// nodes against one, and two against two) sinks no deeper than a small
/// fraction of the spacing, and the floor carries its weight.
///
/// History: on 2 December 2026 Picard rejected 158 of 564 steps and the
/// block still rang at 0.3 s (the floor's force read 171–192 N); session
/// 36's contact slivers and corners (`pfem_geometry::contact`) left 26 of
/// 189 steps rejected and the mean floor force over 0.2–0.3 s −4.4 % off.
/// The cause was the penalty's kink: the block rests `σ/K_c` ≈ 1.5·10⁻⁴
/// of the gap inside the contact distance, so its ringing switched the
/// layer's stiffness between 0 and `K_c` from one Picard iterate to the
/// next. With the rounded onset (`ContactSettings::onset`, 10⁻², session
/// 37) it takes 150 steps, none rejected, the mean floor force is −0.04 %
/// off the weight (−0.12 % with the dashpot grown in, session 38), and it
/// closes 5.4·10⁻³ of the gap; with `onset = 0`
/// it is again 189 (26) and −4.4 % (asserted below). About 3 s.
#[test]
fn a_free_block_rests_on_a_floor_in_3d() {
    let h = 0.05;
    let weight = 1000.0 * 0.3 * 0.2 * 0.3 * G;
    // (rejected steps, mean floor force over 0.2–0.3 s, deepest point).
    let run = |onset: f64| {
        let scene = block_on_floor_3d(
            "block3d",
            Vector::<3>::new(0.0, -G, 0.0),
            0.3,
            h,
            [
                Point::<3>::new(-0.2, -h, -0.2),
                Point::<3>::new(0.5, 0.0, 0.5),
            ],
            [
                Point::<3>::new(0.0, h, 0.0),
                Point::<3>::new(0.3, h + 0.2, 0.3),
            ],
        )
        .contact_onset(onset);
        let mut s =
            Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default()).unwrap();
        assert!(s.stages().contact);
        let block = s.body_particles("block").unwrap();
        let mut worst: f64 = f64::INFINITY;
        // The floor's force averaged over the last 0.1 s (impulse / time).
        let (mut impulse, mut span) = (0.0, 0.0);
        while s.time() < s.end_time() - 1e-12 {
            s.step().unwrap();
            for &i in &block {
                worst = worst.min(s.particles().x()[i][1]);
            }
            if s.time() > 0.2 {
                impulse += s.contact_force("block", "floor").unwrap().normal * s.dt();
                span += s.dt();
            }
        }
        let f = impulse / span;
        println!(
            "3D block on floor, onset {onset}: {} steps ({} rejected), {} contact elements, deepest penetration {:.2e} spacing, floor force over 0.2-0.3 s {f:.2} N (weight {weight:.2}, {:+.2} %)",
            s.steps(),
            s.rejected(),
            s.elements().n_contact(),
            (h - worst) / h,
            100.0 * (f / weight - 1.0)
        );
        (s.rejected(), f, worst)
    };
    let (rejected, f, worst) = run(pfem::scene::CONTACT_ONSET);
    assert!((h - worst) / h < 0.05);
    assert!((f / weight - 1.0).abs() < 0.01, "{f} vs {weight}");
    assert!(rejected <= 5, "{rejected} rejected steps");
    // The kink: the same block rings and Picard rejects its steps.
    let (rejected, f, _) = run(0.0);
    assert!(
        rejected > 5 || (f / weight - 1.0).abs() > 0.01,
        "with the kink: {rejected} rejected, {f} N"
    );
}

/// A cantilever clamped at its left end, too soft to carry its own weight
/// (Euler–Bernoulli's tip deflection 0.57 m), over a floor 0.03 m below
/// it. With `contact_clamped(on)`.
fn sagging_cantilever(on: bool) -> Scene<2> {
    let h = 0.01;
    Scene::<2>::new("sagging_cantilever")
        .gravity(Vector::<2>::new(0.0, -G))
        .settings(RunSettings {
            end_time: 0.6,
            max_dt: 2e-3,
            output_interval: None,
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-0.1, -h),
                max: Point::<2>::new(0.6, 0.0),
            },
            h,
            WallMotion::Fixed,
        )
        .solid(
            "beam",
            Box::new(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.03),
                max: Point::<2>::new(0.5, 0.07),
            },
            h,
            Some((Point::<2>::new(-1.0, -1.0), Point::<2>::new(0.005, 1.0))),
        )
        .contact_clamped(on)
}

/// A clamped solid takes part in contact when the scene asks for it
/// (`Scene::contact_clamped`): the sagging cantilever comes to rest on the
/// floor (its lowest particle stays above half a spacing, the floor
/// carries a force) instead of passing through it, as it does without.
#[test]
fn a_clamped_cantilever_rests_on_the_floor_when_asked() {
    let h = 0.01;
    for on in [false, true] {
        let mut sim = sim(sagging_cantilever(on));
        assert_eq!(sim.stages().contact, on);
        let beam = sim.body_particles("beam").unwrap();
        let mut lowest = f64::INFINITY;
        let mut force: f64 = 0.0;
        while sim.time() < sim.end_time() - 1e-12 {
            sim.step().unwrap();
            for &i in &beam {
                let p = sim.particles().x()[i];
                assert!(p.iter().all(|v| v.is_finite()));
                lowest = lowest.min(p[1]);
            }
            if on {
                force = force.max(sim.contact_force("beam", "floor").unwrap().normal);
            }
        }
        println!(
            "contact for clamped solids {on}: {} steps ({} rejected), lowest particle {:.3} h, largest floor force {force:.1} N/m (beam weight {:.1} N/m)",
            sim.steps(),
            sim.rejected(),
            lowest / h,
            1000.0 * 0.5 * 0.04 * G
        );
        if on {
            assert!(lowest > 0.5 * h, "into the floor: {} h", lowest / h);
            assert!(force > 0.0, "the floor carried nothing");
        } else {
            assert!(
                lowest < 0.0,
                "without contact it passes through: {} h",
                lowest / h
            );
        }
    }
}

/// Each contact element takes the penalty of the softest solid among its
/// own bodies (a wall brings none): a soft block (E = 1e4 Pa) and a stiff
/// one (E = 1e8 Pa) on one floor meet it through two contact materials
/// (one per penalty), the soft block's elements all through one, the
/// stiff block's through the other; before session 36 every element took
/// the stiff one's. An element joining two solids takes the softer's
/// (the stiffer's until session 50, when a soft block on a free steel
/// block inverted: `a_soft_block_rests_on_a_free_steel_block`).
#[test]
fn each_contact_takes_the_penalty_of_its_own_softest_solid() {
    let h = 0.02;
    let scene = block_on_floor(h, 0.1, 0.1, 0.0, 0.0, 1e4).solid(
        "stiff",
        Box::new(Hypoelastic::new(1000.0, 1e8, 0.3).unwrap()),
        Geometry::Box {
            min: Point::<2>::new(0.5, h),
            max: Point::<2>::new(0.6, h + 0.1),
        },
        h,
        None,
    );
    let sim = sim(scene);
    let n_scene_materials = 2;
    assert_eq!(sim.materials().len(), n_scene_materials + 2);
    let range = sim.elements().len() - sim.elements().n_contact();
    let body = sim.particles().body();
    let stiff = body[sim.body_particles("stiff").unwrap()[0]];
    let (mut soft_m, mut stiff_m) = (Vec::new(), Vec::new());
    for (el, &m) in sim
        .elements()
        .contact()
        .chunks_exact(3)
        .zip(&sim.elements().materials()[range..])
    {
        assert!((n_scene_materials..sim.materials().len()).contains(&(m as usize)));
        if el.iter().any(|&p| body[p as usize] == stiff) {
            stiff_m.push(m);
        } else {
            soft_m.push(m);
        }
    }
    assert!(!soft_m.is_empty() && !stiff_m.is_empty());
    assert!(soft_m.iter().all(|&m| m == soft_m[0]));
    assert!(stiff_m.iter().all(|&m| m == stiff_m[0]));
    assert_ne!(soft_m[0], stiff_m[0]);
    // Each penalty is its block's P-wave modulus ρ c².
    for (m, block) in [(soft_m[0], "block"), (stiff_m[0], "stiff")] {
        let p = sim.body_particles(block).unwrap()[0];
        let solid = &sim.materials()[sim.particles().material()[p] as usize];
        let k = solid.density() * solid.wave_speed() * solid.wave_speed();
        let penalty = format!("{:?}", sim.materials()[m as usize]);
        assert!(
            penalty.contains(&format!("normal_stiffness: {k:?}")),
            "{block}: {penalty} against {k}"
        );
    }
}

/// The sagging cantilever's landing on the floor through contact gains
/// no energy and inverts nothing (the hard cases' checks,
/// `stability_support.rs`). Measured (5 December 2026): 459 steps (85
/// rejected), energy never above its start; 315 (10) in session 38.
#[test]
fn a_clamped_cantilever_lands_without_gaining_energy() {
    let o = crate::stability_support::run_checked(sagging_cantilever(true), StepParams::default());
    o.report("sagging cantilever on the floor");
    o.assert_completed();
    o.assert_stable(0.0);
    // Bug fixed (session 38): the contact dashpot's ramp over the onset
    // left its own derivative out of the linearisation, and the landing's
    // Picard iterates alternated between two states: 68 of 417 steps
    // rejected. With it, 10 of 315.
    assert!(
        o.rejected <= 25,
        "{} of {} steps rejected",
        o.rejected,
        o.steps
    );
}

/// A user's solid whose P-wave modulus `ρ c²` (the default contact
/// penalty) overflows, though its density and wave speed are finite, is
/// refused when a scene with contact is built, not left to give its
/// contact elements no usable material (review of session 36).
#[test]
fn a_solid_whose_penalty_is_not_finite_is_refused() {
    use pfem::constitutive::{History, Kinematics, Material, MaterialKind, Unified};
    #[derive(Debug)]
    struct Infinite(Hypoelastic);
    impl Material<2> for Infinite {
        fn name(&self) -> &str {
            "infinite"
        }
        fn kind(&self) -> MaterialKind {
            MaterialKind::Solid
        }
        fn density(&self) -> f64 {
            1e300
        }
        fn wave_speed(&self) -> f64 {
            1e5
        }
        fn unified(&self, kin: &Kinematics<2>, history: &History<2>) -> Unified<2> {
            Material::<2>::unified(&self.0, kin, history)
        }
        fn update_history(&self, kin: &Kinematics<2>, history: &mut History<2>) {
            Material::<2>::update_history(&self.0, kin, history)
        }
    }
    let h = 0.02;
    let scene = block_on_floor(h, 0.1, 0.1, 0.0, 0.0, 1e6).solid(
        "infinite",
        Box::new(Infinite(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap())),
        Geometry::Box {
            min: Point::<2>::new(0.5, h),
            max: Point::<2>::new(0.6, h + 0.1),
        },
        h,
        None,
    );
    let err =
        Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default()).unwrap_err();
    assert!(
        matches!(
            err,
            pfem::SceneError::InvalidSetting {
                setting: "contact_stiffness",
                ..
            }
        ),
        "{err}"
    );
}

/// A block sticking on a 20° slope (μ = 0.5), to 0.3 s.
fn sticking_block() -> Simulation<2> {
    let mut scene = block_on_floor(0.02, 0.2, 0.1, 20f64.to_radians(), 0.5, 1e7);
    scene.settings.end_time = 0.3;
    sim(scene)
}

/// Renumbers nothing, yet changes the set's generation (the mesh is
/// remade).
fn identity_remap(p: &mut pfem::particles::Particles<2>) {
    let n = p.len() as u32;
    let map = pfem::geometry::ParticleMap {
        old_to_new: (0..n).collect(),
        origin: (0..n).map(pfem::geometry::Origin::Kept).collect(),
    };
    p.remap(&map).unwrap();
}

/// Session 41 (a review of contact across the remeshing): a hook that
/// changes the particle set after the remeshing has the mesh remade, and
/// the contact range just formed, never solved, went to the stash: the
/// next range averaged the carried tractions a second time, and stick's
/// memory faded at every such step. A hook that renumbers nothing (an
/// identity remap, which still remakes the mesh) now leaves the run as it
/// was, bit for bit: a block sticking on a 20° slope (μ = 0.5).
///
/// Session 44's review: the same after the step (an `after_step` hook
/// that renumbers), by hand between steps, and by a hook started mid-run
/// (each remeshing came before the step's own, which stashed the range
/// formed for it: averaged a second time).
#[test]
fn a_remesh_by_a_hook_leaves_stick_s_memory_alone() {
    let renumber = |ctx: &mut HookContext<'_, 2>| {
        identity_remap(ctx.particles_mut());
        Ok(())
    };
    let run = |remap: Option<bool>| {
        let mut s = sticking_block();
        let hook = pfem::hooks::FnHook::new("renumber");
        match remap {
            Some(false) => s.add_hook(Box::new(hook.after_remesh(renumber))),
            Some(true) => s.add_hook(Box::new(hook.after_step(renumber))),
            None => {}
        }
        s.run(&mut []).unwrap();
        (s.particles().x().to_vec(), s.steps(), s.work().remeshes)
    };
    let (plain, n, remeshes) = run(None);
    for late_start in [false, true] {
        let mut s = sticking_block();
        while s.time() < s.end_time() - 1e-12 {
            s.step().unwrap();
            if !late_start {
                identity_remap(s.particles_mut());
            } else if s.steps() == 20 {
                let hook = pfem::hooks::FnHook::new("late renumber").start(renumber);
                s.add_hook(Box::new(hook));
            }
        }
        assert_eq!(s.steps(), n);
        assert_eq!(
            s.particles().x(),
            plain.as_slice(),
            "renumbered by hand ({}) or at a late start ({late_start})",
            !late_start
        );
    }
    for after_step in [false, true] {
        let (renumbered, m, more) = run(Some(after_step));
        assert_eq!(n, m);
        // The hook's renumbering did remesh: once more each step.
        assert_eq!(more, remeshes + n, "remeshes {remeshes} and {more}");
        let moved = plain
            .iter()
            .zip(&renumbered)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        assert_eq!(
            moved, 0.0,
            "the run renumbered after the step ({after_step}) moved by {moved:e} m"
        );
    }
}

/// A contact penalty far too soft for its load is an error naming the
/// bodies, not a solid passing through a wall. The 0.4 × 0.2 m block
/// presses on the floor with 1 962 Pa; a penalty of 500 Pa cannot hold
/// it at any closure. Before session 45 the layer closed below 5 % of its
/// gap, the next remeshing left it out (a sliver) and the block fell
/// through the floor with the run `Ok`. Now every step that closes it
/// through is retried smaller, and the run fails with
/// `RunError::ContactClosed`; with the default penalty the same block
/// rests (`a_free_block_rests_on_the_floor_without_sinking_through_it`).
#[test]
fn a_contact_far_too_soft_for_its_load_is_an_error_not_a_pass_through() {
    let h = 0.02;
    let scene = block_on_floor(h, 0.4, 0.2, 0.0, 0.0, 1e7).contact_stiffness(500.0);
    let mut s = sim(scene);
    s.set_end_time(0.5).unwrap();
    let e = loop {
        match s.step() {
            Ok(_) if s.time() < s.end_time() - 1e-12 => {
                assert!(
                    lowest(&s, "block") > -h,
                    "the block passed through the floor at t = {} s",
                    s.time()
                );
            }
            Ok(_) => panic!("the run ended with the block at {} m", lowest(&s, "block")),
            Err(e) => break e,
        }
    };
    eprintln!("{e}");
    match &e {
        RunError::ContactClosed {
            master, other, why, ..
        } => {
            let mut pair = [master.as_str(), other.as_str()];
            pair.sort();
            assert_eq!(pair, ["block", "floor"]);
            assert!(why.contains("raise the contact stiffness"), "{why}");
        }
        other => panic!("expected ContactClosed, got {other}"),
    }
}

/// Session 47 (a review of contact): friction between a clamped solid and
/// a wall was accepted and never acted (a clamped solid takes no part in
/// contact unless `contact_clamped`); it is refused, and accepted with
/// `contact_clamped`.
#[test]
fn friction_that_could_never_act_is_refused() {
    let (h, hf) = (0.01, 0.02);
    let y = 0.5 * (h + hf);
    let scene = || {
        Scene::<2>::new("clamped beam")
            .gravity(Vector::<2>::new(0.0, -G))
            .wall(
                "floor",
                Geometry::Box {
                    min: Point::<2>::new(-0.2, -hf),
                    max: Point::<2>::new(0.4, 0.0),
                },
                hf,
                WallMotion::Fixed,
            )
            .solid(
                "beam",
                Box::new(Hypoelastic::new(1000.0, 1e7, 0.3).unwrap()),
                Geometry::Box {
                    min: Point::<2>::new(0.0, y),
                    max: Point::<2>::new(0.2, y + 0.02),
                },
                h,
                Some((Point::<2>::new(-1.0, -1.0), Point::<2>::new(0.001, 1.0))),
            )
            .friction("beam", "floor", 0.3)
    };
    let err = scene().validate().unwrap_err().to_string();
    assert!(err.contains("neither body takes part in contact"), "{err}");
    assert!(scene().contact_clamped(true).validate().is_ok());
}

/// A known gap, asserted as it stands (session 47's review of contact):
/// 3D has no corner rule, so a free block one spacing from the floor and
/// the side wall of one wall body (a tank drawn as one surface) meets a
/// tetrahedron across the concave corner, edge against edge at `h/√2`,
/// and starts at 70.7 % of its contact distance: refused, with the way
/// out. The same walls as two bodies build and run (the three-body rule
/// measures the nearest pair).
#[test]
fn a_block_in_the_corner_of_one_wall_body_in_3d_is_refused_with_the_way_out() {
    let h = 0.05;
    let lattice = |is: std::ops::RangeInclusive<i32>, js: std::ops::RangeInclusive<i32>| {
        let mut p = Vec::new();
        for i in is.clone() {
            for j in js.clone() {
                for k in -2..=6 {
                    p.push(Point::<3>::new(i as f64 * h, j as f64 * h, k as f64 * h));
                }
            }
        }
        p
    };
    // The floor (two layers) and the side wall at x ≤ 0 (two layers).
    let floor = lattice(0..=8, -1..=0);
    let side = lattice(-1..=0, 1..=6);
    let build = |one_body: bool| {
        let mut scene = Scene::<3>::new("corner")
            .gravity(Vector::<3>::new(0.0, -G, 0.0))
            .settings(RunSettings {
                end_time: 0.01,
                max_dt: 2e-3,
                output_interval: None,
                ..Default::default()
            });
        scene = if one_body {
            let all = floor.iter().chain(&side).copied().collect();
            scene.wall("tank", Geometry::Particles(all), h, WallMotion::Fixed)
        } else {
            scene
                .wall(
                    "floor",
                    Geometry::Particles(floor.clone()),
                    h,
                    WallMotion::Fixed,
                )
                .wall(
                    "side",
                    Geometry::Particles(side.clone()),
                    h,
                    WallMotion::Fixed,
                )
        };
        let scene = scene.solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, 1e7, 0.3).unwrap()),
            Geometry::Box {
                min: Point::<3>::new(h, h, 0.0),
                max: Point::<3>::new(h + 0.15, h + 0.1, 0.15),
            },
            h,
            None,
        );
        Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default())
    };
    let err = build(true).map(|_| ()).unwrap_err().to_string();
    assert!(
        err.contains("70.7 %") && err.contains("separate bodies"),
        "{err}"
    );
    let mut two = build(false).unwrap();
    assert!(two.elements().n_contact() > 0);
    two.run(&mut []).unwrap();
}

/// 3D Coulomb friction on a slope (a review in session 49): a free block
/// (0.1 m cube, `E` = 10⁷ Pa) on a floor under gravity tilted 35° along
/// `z`, `μ` = 0.5, should slide at `g (sin θ − μ cos θ)` = 1.609 m/s²:
/// 32.2 mm in 0.2 s, straight down the slope. It slides 33.03 mm
/// (+2.6 %), 0.04 mm sideways, lifting 0.002 mm (session 56, the contact
/// reach 1.8 h in 3D). A known gap until then: with a reach of 1.6 h it
/// slid 35.1 mm (+9 %), drifting 2.0 mm sideways and lifting 1.3 mm
/// (33.96, 1.55 and 0.30 mm with the gap measured to the facet itself,
/// session 56's first change) (the 2D block is exact,
/// `friction_holds_below_the_friction_angle_and_lets_go_above_it`; without
/// friction the 3D block is exact).
///
/// The cause (a read-only analysis, session 49): the contact range
/// kept a third of the layer between two aligned lattices, since the
/// reach cut every tetrahedron with a cell's diagonal across the gap
/// (√3 h > 1.6 h; 2D's longest is √2 h), the third kept changed as the
/// block slid, and friction rocked it. Measuring the cross-body edges by
/// their part along the facets (tried in session 49) gave 33.1 mm and
/// 0.014 mm sideways, but the Hertz ball's approaching surface then formed
/// long elements that inverted (`hertz_3d`'s bounce failed at 12.6 ms,
/// also with the longer edges admitted only near the contact distance):
/// not kept.
#[test]
fn a_block_slides_straight_down_a_slope_with_friction_in_3d() {
    let (h, theta, mu): (f64, f64, f64) = (0.02, 35f64.to_radians(), 0.5);
    let scene = block_on_floor_3d(
        "slope3d",
        Vector::<3>::new(0.0, -G * theta.cos(), G * theta.sin()),
        0.2,
        h,
        [
            Point::<3>::new(-0.06, -h, -0.1),
            Point::<3>::new(0.16, 0.0, 0.5),
        ],
        [
            Point::<3>::new(0.0, h, 0.0),
            Point::<3>::new(0.1, h + 0.1, 0.1),
        ],
    )
    .friction("block", "floor", mu);
    let mut s =
        Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default()).unwrap();
    let block = s.body_particles("block").unwrap();
    let mean = |s: &Simulation<3>| {
        block
            .iter()
            .map(|&i| s.particles().x()[i] - s.initial_position(i))
            .fold(Vector::<3>::zeros(), |a, d| a + d)
            / block.len() as f64
    };
    let mut lift: f64 = 0.0;
    while s.time() < s.end_time() - 1e-12 {
        s.step().unwrap();
        lift = lift.max(mean(&s)[1]);
    }
    let u = mean(&s);
    let want = 0.5 * G * (theta.sin() - mu * theta.cos()) * 0.2 * 0.2;
    println!(
        "3D block on a slope, mu {mu}: slid {:.2} mm against {:.2} mm, sideways {:.3} mm, lifted at most {:.3} mm",
        1e3 * u[2],
        1e3 * want,
        1e3 * u[0],
        1e3 * lift
    );
    assert!((u[2] / want - 1.0).abs() < 0.05, "slid {} m", u[2]);
    assert!(u[0].abs() < 1e-4, "sideways {} m", u[0]);
    assert!(lift < 1e-4, "lifted {lift} m");
}

/// An elastic cube (0.1 m, `E` = 10⁷ Pa, h = 0.02 m) dropped flat from
/// 5 cm onto a frictionless floor in 3D bounces, settles flat and comes
/// to rest within 1 s. Until session 56 it gained energy at its second
/// impact (+13.7 % at a quarter of the step), tilted up to 14.7° and still
/// rocked at 0.36 m/s after 1 s: a contact tetrahedron's gap was the
/// height over its master facet's plane (or between its edges' lines), so
/// elements formed already closed at each remeshing, and the reach
/// (1.6 spacings) left out every tetrahedron holding a cell's diagonal.
/// Measured since: 503 steps (2 rejected), its energy never above the
/// start's, tilt 0.00°, largest speed 2.8·10⁻³ m/s at 1 s. About 6 s.
#[test]
fn a_cube_dropped_flat_comes_to_rest_flat_in_3d() {
    let h = 0.02;
    let scene = block_on_floor_3d(
        "drop3d",
        Vector::<3>::new(0.0, -G, 0.0),
        1.0,
        h,
        [
            Point::<3>::new(0.0, -h, 0.0),
            Point::<3>::new(0.3, 0.0, 0.3),
        ],
        [
            Point::<3>::new(0.1, 0.07, 0.1),
            Point::<3>::new(0.2, 0.17, 0.2),
        ],
    );
    let mut s =
        Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default()).unwrap();
    let block = s.body_particles("block").unwrap();
    // Energy per unit mass (the particles' plain mean: a lattice block's
    // lumped masses are near equal) and the tilt of the line joining the
    // block's bottom and top centres.
    let energy = |s: &Simulation<3>| {
        block
            .iter()
            .map(|&i| G * s.particles().x()[i].y + 0.5 * s.particles().v()[i].norm_squared())
            .sum::<f64>()
            / block.len() as f64
    };
    let e0 = energy(&s);
    let (y_lo, y_hi) = (0.07 + 1e-9, 0.17 - 1e-9);
    let mut most = e0;
    while s.time() < s.end_time() - 1e-12 {
        s.step().unwrap();
        most = most.max(energy(&s));
    }
    // The centre of the block's top or bottom row, as it started.
    let centre = |top: bool| {
        let pts: Vec<Point<3>> = block
            .iter()
            .filter(|&&i| {
                let y = s.initial_position(i).y;
                if top {
                    y >= y_hi
                } else {
                    y <= y_lo
                }
            })
            .map(|&i| s.particles().x()[i])
            .collect();
        pts.iter().fold(Point::<3>::zeros(), |a, p| a + p) / pts.len() as f64
    };
    let axis = centre(true) - centre(false);
    let tilt = (axis.y / axis.norm()).acos().to_degrees();
    let fastest = block
        .iter()
        .map(|&i| s.particles().v()[i].norm())
        .fold(0.0, f64::max);
    println!(
        "cube dropped flat: {} steps ({} rejected); energy at most {:+.3} % of the start's, tilt {tilt:.2}°, largest speed at 1 s {fastest:.2e} m/s",
        s.steps(),
        s.rejected(),
        100.0 * (most / e0 - 1.0)
    );
    assert!(most <= e0 * (1.0 + 1e-3), "energy rose to {most} from {e0}");
    assert!(tilt < 1.0, "tilted {tilt}°");
    assert!(fastest < 0.01, "still moving at {fastest} m/s");
}

/// A 3D scene of a wall box `floor` and a free elastic block `block`
/// (1000 kg/m³, `E` = 10⁷ Pa, ν = 0.3), both of spacing `h`, under
/// `gravity`, run to `end_time` with steps of at most 2 ms.
fn block_on_floor_3d(
    name: &str,
    gravity: Vector<3>,
    end_time: f64,
    h: f64,
    floor: [Point<3>; 2],
    block: [Point<3>; 2],
) -> Scene<3> {
    Scene::<3>::new(name)
        .gravity(gravity)
        .settings(RunSettings {
            end_time,
            max_dt: 2e-3,
            output_interval: None,
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: floor[0],
                max: floor[1],
            },
            h,
            WallMotion::Fixed,
        )
        .solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, 1e7, 0.3).unwrap()),
            Geometry::Box {
                min: block[0],
                max: block[1],
            },
            h,
            None,
        )
}
