//! Archimedes in 3D (issue 19): a free elastic block of density
//! 500 kg/m³ put in water at rest at its equilibrium draft (half its
//! height) stays there: its draft over the last half second within 2 % of
//! half its height, and the water around it meets the 3D rest bounds of
//! water at rest (issue 13: largest speed ≤ 5·10⁻³ √(gH), pressure within
//! 2 % RMS of ρ g (H − y)). The block's rows lie half a spacing off the
//! water's, as in `tests/floating.rs`. Measured (2 December 2026, 5 964
//! particles, 400 steps): draft +0.31 %, largest water speed 4.7·10⁻³
//! √(gH) over the whole run, pressure 0.36 % RMS (with a stress-free start
//! of the block: +0.28 %, 4.4·10⁻³ after the first 0.1 s, 0.29 %).
//!
//! Known gap since `402cd7d` (3 December, slivers keep their start-of-step
//! shape, ARCHITECTURE.md deviation 13), found by a bisection in session
//! 36: the water's largest speed is 5.44·10⁻³ √(gH) (bound 5·10⁻³; it
//! stays near 4.3–5.4·10⁻³ from 0.5 s on, no single event), draft
//! +0.30 %, pressure 0.35 % RMS. The same run with
//! `StepParams::sliver_quality_3d = 0` gives 4.72·10⁻³, +0.31 %, 0.36 %.
//! Exempting the slivers that touch a solid (the 2D rule, tried with a
//! temporary switch) makes it
//! 5.74·10⁻³. The test keeps the defaults and failed until session 56:
//! with a 3D contact element's gap measured to the facet itself rather
//! than its plane (`pfem_geometry::contact`), largest speed 4.44·10⁻³
//! √(gH), draft +0.32 %, pressure 0.31 % RMS: it passes, ignored for its
//! time alone.
//!
//! Where the speed is (session 37, a scratch driver printing the fastest
//! water particles): not at the surface or the walls but under the
//! block, two spacings below its bottom, where the set-up leaves a gap of
//! 1.5 spacings: the rows there rise steadily (one particle at 5·10⁻³
//! √(gH), 1 cm in 1.8 s; its neighbours at 2–4·10⁻³), with and without the
//! sliver rule (the same particle leads both runs), while the block tilts
//! by 2–3 mrad. The speed follows the block's compliance: over the first
//! 0.8 s it is 5.4·10⁻³ √(gH) with E = 10⁷ Pa, 4.7·10⁻⁴ with 10⁸ and
//! 1.9·10⁻⁴ with 10⁹. Not yet understood; the test keeps the 10⁷ Pa block.
//!
//! `cargo test --release --test suite floating_3d:: -- --ignored --nocapture`
//! (about 70 s on 2 cores).

use pfem::cases::rest_figures;
use pfem::cases3d::tank3d;
use pfem::constitutive::Hypoelastic;
use pfem::prelude::*;

const G: f64 = 9.81;

#[test]
#[ignore = "about 70 s: cargo test --release --test suite floating_3d:: -- --ignored --nocapture"]
fn a_3d_block_half_as_dense_as_water_floats_at_half_its_height() {
    let h = 0.025;
    let (length, width, depth) = (0.6, 0.4, 0.2);
    let (bw, bh) = (0.2, 0.125);
    let draft = 0.5 * bh;
    let lo = Point::<3>::new(0.5 * (length - bw), depth - draft, 0.5 * (width - bw));
    let hi = lo + Vector::<3>::new(bw, bh, bw);
    // The water: the tank's lattice less the block and one spacing round it.
    let n = |l: f64| (l / h).round() as usize;
    let mut water = Vec::new();
    for i in 0..=n(length) {
        for j in 1..=n(depth) {
            for k in 0..=n(width) {
                let p = Point::<3>::new(i as f64 * h, j as f64 * h, k as f64 * h);
                let near = (0..3).all(|d| p[d] > lo[d] - h + 1e-9 && p[d] < hi[d] + h - 1e-9);
                if !near {
                    water.push(p);
                }
            }
        }
    }
    let scene = tank3d(
        Scene::<3>::new("floating_3d"),
        length,
        width,
        1.5 * depth,
        h,
        true,
    )
    .gravity(Vector::<3>::new(0.0, -G, 0.0))
    .settings(RunSettings {
        end_time: 2.0,
        max_dt: 5e-3,
        output_interval: None,
        ..Default::default()
    })
    .fluid(
        "water",
        Box::new(Newtonian::water()),
        Geometry::Particles(water),
        h,
    )
    .solid(
        "block",
        Box::new(Hypoelastic::new(500.0, 1e7, 0.3).unwrap()),
        Geometry::Box { min: lo, max: hi },
        h,
        None,
    );
    // The defaults: dry bridges against the free block are cut at the
    // water line (`Options::cut_dry_bridges`; ARCHITECTURE.md, deviation 7).
    let mut sim =
        Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default()).unwrap();
    let block = sim.body_particles("block").unwrap();
    let water_p = sim.body_particles("water").unwrap();
    let bottom = |s: &Simulation<3>| {
        block.iter().map(|&i| s.particles().x()[i][1]).sum::<f64>() / block.len() as f64 - 0.5 * bh
    };
    // The water level far from the block: the highest water particle
    // within 0.1 m of the end walls.
    let level = |s: &Simulation<3>| {
        water_p
            .iter()
            .map(|&i| s.particles().x()[i])
            .filter(|p| p[0] < 0.1 || p[0] > length - 0.1)
            .map(|p| p[1])
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let v0 = sim.fluid_volume();
    let (mut sum, mut count) = (0.0, 0);
    let mut vmax: f64 = 0.0;
    let mut next = 0.0;
    while sim.time() < sim.end_time() - 1e-12 {
        sim.step().unwrap();
        let f = rest_figures(&sim, depth);
        vmax = vmax.max(f.max_speed);
        if sim.time() >= next {
            next += 0.25;
            println!(
                "t {:.2} bottom {:.5} level {:.5} largest speed {:.2e} √(gH)",
                sim.time(),
                bottom(&sim),
                level(&sim),
                f.max_speed
            );
        }
        if sim.time() > sim.end_time() - 0.5 {
            sum += level(&sim) - bottom(&sim);
            count += 1;
        }
    }
    let mean = sum / count as f64;
    let pressure = rest_figures(&sim, depth).pressure_rms;
    let dv = sim.fluid_volume() / v0 - 1.0;
    println!(
        "3D floating block: {} particles, {} steps ({} rejected); draft over the last 0.5 s {mean:.5} m against {draft} m ({:+.2} %); water: largest speed {vmax:.2e} √(gH), pressure {:.3} % RMS off ρ g (H − y), volume {:+.4} %",
        sim.particles().len(),
        sim.steps(),
        sim.rejected(),
        100.0 * (mean / draft - 1.0),
        100.0 * pressure,
        100.0 * dv
    );
    assert!((mean / draft - 1.0).abs() < 0.02, "draft {mean} m");
    assert!(vmax <= 5e-3, "largest speed {vmax} √(gH)");
    assert!(pressure <= 0.02, "pressure {pressure} RMS");
}

/// The water's force on a block floating at its draft (a 3D box of
/// 500 kg/m³, 8 cm, in a tank 20 cm wide; a review's scene) is its weight,
/// at every step: `Loads::pressure_force_on` counts the elements cut at a
/// free solid's water line below the line only, as the assembly does.
/// Before session 49 it counted them whole, the drifting pressures of
/// their dry nodes included: 2.51 N at the start, then 20–25 N by 0.06 s
/// while the block moved 2 µm.
#[test]
fn the_water_force_on_a_floating_block_is_its_weight() {
    let text = r#"
name = "float"
dimension = 3
gravity = [0.0, -9.81, 0.0]
spacing = 0.02
[run]
end_time = 0.1
max_dt = 5e-3
[[body]]
name = "floor"
kind = "wall"
geometry.box = { min = [-0.02, -0.02, -0.02], max = [0.22, 0.0, 0.22] }
[[body]]
name = "x0"
kind = "wall"
geometry.box = { min = [-0.02, 0.02, -0.02], max = [0.0, 0.2, 0.22] }
[[body]]
name = "x1"
kind = "wall"
geometry.box = { min = [0.2, 0.02, -0.02], max = [0.22, 0.2, 0.22] }
[[body]]
name = "z0"
kind = "wall"
geometry.box = { min = [0.02, 0.02, -0.02], max = [0.18, 0.2, 0.0] }
[[body]]
name = "z1"
kind = "wall"
geometry.box = { min = [0.02, 0.02, 0.2], max = [0.18, 0.2, 0.22] }
[[body]]
name = "block"
kind = "solid"
material.hypoelastic = { density = 500.0, young = 1e7, poisson = 0.3 }
geometry.box = { min = [0.06, 0.08, 0.06], max = [0.14, 0.16, 0.14] }
[[body]]
name = "w0"
kind = "fluid"
material.newtonian = { density = 1000.0, viscosity = 1e-3, bulk_modulus = 2.2e9 }
geometry.box = { min = [0.02, 0.02, 0.02], max = [0.18, 0.06, 0.18] }
[[body]]
name = "w1"
kind = "fluid"
material.newtonian = { density = 1000.0, viscosity = 1e-3, bulk_modulus = 2.2e9 }
geometry.box = { min = [0.02, 0.08, 0.02], max = [0.04, 0.12, 0.18] }
[[body]]
name = "w2"
kind = "fluid"
material.newtonian = { density = 1000.0, viscosity = 1e-3, bulk_modulus = 2.2e9 }
geometry.box = { min = [0.16, 0.08, 0.02], max = [0.18, 0.12, 0.18] }
[[body]]
name = "w3"
kind = "fluid"
material.newtonian = { density = 1000.0, viscosity = 1e-3, bulk_modulus = 2.2e9 }
geometry.box = { min = [0.06, 0.08, 0.02], max = [0.14, 0.12, 0.04] }
[[body]]
name = "w4"
kind = "fluid"
material.newtonian = { density = 1000.0, viscosity = 1e-3, bulk_modulus = 2.2e9 }
geometry.box = { min = [0.06, 0.08, 0.16], max = [0.14, 0.12, 0.18] }

"#;
    let scene = pfem::scene_file::SceneFile::parse(text, "float.toml")
        .and_then(|f| f.scene::<3>())
        .unwrap();
    let mut sim =
        Simulation::new(scene, Box::new(Delaunay3::default()), StepParams::default()).unwrap();
    let weight = 500.0 * G * 0.08f64.powi(3);
    let mut worst: f64 = 0.0;
    while sim.time() < 0.1 - 1e-12 {
        sim.step().unwrap();
        let f = sim.pressure_force_on("block").unwrap();
        worst = worst.max((f[1] / weight - 1.0).abs());
    }
    println!(
        "floating block: water force within {:.2} % of its weight {weight:.3} N",
        100.0 * worst
    );
    assert!(worst < 0.03, "off by {worst} of its weight");
}
