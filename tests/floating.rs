//! Archimedes (issue 19): a free elastic block of density 500 kg/m³ put in
//! water at rest at its equilibrium draft (half its height) stays there:
//! its draft over the last half second within 2 % of half its height, and
//! the water around it meets the rest bounds of water at rest (issue 13:
//! largest speed ≤ 2·10⁻³ √(gH), RMS ≤ 5·10⁻⁴ √(gH), pressure within 1 %
//! RMS of ρ g (H − y), volume within 0.1 %).
//! Floating bodies need `Options::cut_dry_bridges` (on by default; it cuts
//! against free solids only; ARCHITECTURE.md, deviation 7).
//! `cargo test --release --test suite floating:: -- --nocapture` (20 s)

use pfem::cases::rest_figures;
use pfem::constitutive::Hypoelastic;
use pfem::prelude::*;

const G: f64 = 9.81;

/// The block starts as a rigid body under its net load
/// (`Options::free_solids_start_rigid`, the default): the rest bounds hold
/// from the first step. Started stress-free instead, its interior fell at
/// `g` for a step and shook the water next to it to 2.9·10⁻³ √(gH) within
/// 0.015 s, whatever its stiffness (E = 10⁹ Pa: the same).
/// The block's rows of particles lie half a spacing off the water's (its
/// draft is 2.5 spacings), so the last surface particle beside it meets
/// the block between two of its particles. Without surface cuts
/// (`Options::cut_dry_bridges = false`) the simplex joining them
/// is kept or dropped whole: that particle starts at 1.8 m/s² towards the
/// block, the water never comes to rest (largest speed 0.12 m/s) and the
/// block sinks and rolls (mean draft over 1.5–2 s +5.4 %;
/// `without_surface_cuts_the_water_beside_the_block_never_rests`).
/// Measured with the cuts (2 December 2026): draft +0.00 %, largest speed
/// 1.8·10⁻⁴ √(gH) (in the first steps), RMS 2.7·10⁻⁵ √(gH), pressure
/// 0.000 % RMS.
#[test]
fn a_block_half_as_dense_as_water_floats_at_half_its_height() {
    let f = float(true, 5.0);
    assert!(
        (f.draft_error).abs() < 0.02,
        "draft {:+.3} %",
        100.0 * f.draft_error
    );
    assert!(f.vmax <= 2e-3, "largest speed {} √(gH)", f.vmax);
    assert!(f.rms <= 5e-4, "RMS speed {} √(gH)", f.rms);
    assert!(f.pressure <= 0.01, "pressure {} RMS", f.pressure);
    assert!(f.volume.abs() <= 1e-3, "volume {}", f.volume);
}

/// The control: without surface cuts the water
/// beside the block never comes to rest (largest speed measured 6.9·10⁻²
/// √(gH) over 2 s, 35 times the bound) and the block sinks (mean draft over
/// 1.5–2 s +5.4 %; +16 % and a roll with the stress-free start).
#[test]
fn without_surface_cuts_the_water_beside_the_block_never_rests() {
    let f = float(false, 2.0);
    assert!(f.vmax > 1e-2, "largest speed {} √(gH)", f.vmax);
}

/// What [`float`] measured.
struct Figures {
    /// Mean draft over the last 0.5 s against half the block's height,
    /// relative.
    draft_error: f64,
    /// Largest and RMS water speed over the run (√(gH)).
    vmax: f64,
    rms: f64,
    /// Pressure error, RMS relative, at the end.
    pressure: f64,
    /// Fluid volume change, relative.
    volume: f64,
}

/// The floating block with or without surface cuts, run to `end_time`.
fn float(cut: bool, end_time: f64) -> Figures {
    let h = 0.02;
    let (width, depth) = (1.0, 0.3);
    let (bw, bh) = (0.2, 0.1);
    let x0 = 0.5 * (width - bw);
    let draft = 0.5 * bh;
    let bottom = depth - draft;
    // The water around the block: a U-shaped polygon one spacing off it.
    let water = Geometry::polygon(vec![
        Point::<2>::new(0.0, 0.0),
        Point::<2>::new(width, 0.0),
        Point::<2>::new(width, depth),
        Point::<2>::new(x0 + bw + h, depth),
        Point::<2>::new(x0 + bw + h, bottom - h),
        Point::<2>::new(x0 - h, bottom - h),
        Point::<2>::new(x0 - h, depth),
        Point::<2>::new(0.0, depth),
    ]);
    let scene = Scene::<2>::new("floating")
        .gravity(Vector::<2>::new(0.0, -G))
        .settings(RunSettings {
            end_time,
            max_dt: 5e-3,
            output_interval: None,
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-h, -h),
                max: Point::<2>::new(width + h, -h),
            },
            h,
            WallMotion::Fixed,
        )
        .wall(
            "left",
            Geometry::Box {
                min: Point::<2>::new(-h, 0.0),
                max: Point::<2>::new(-h, 0.5),
            },
            h,
            WallMotion::Fixed,
        )
        .wall(
            "right",
            Geometry::Box {
                min: Point::<2>::new(width + h, 0.0),
                max: Point::<2>::new(width + h, 0.5),
            },
            h,
            WallMotion::Fixed,
        )
        .fluid("water", Box::new(Newtonian::water()), water, h)
        .solid(
            "block",
            Box::new(Hypoelastic::new(500.0, 1e7, 0.3).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(x0, bottom),
                max: Point::<2>::new(x0 + bw, bottom + bh),
            },
            h,
            None,
        );
    let mut sim = Simulation::with_options(
        scene,
        Box::new(Delaunay2::default()),
        StepParams::default(),
        // Dry bridges against free solids cut at the water line (the
        // default; ARCHITECTURE.md, deviation 7) or kept or dropped whole.
        Options {
            cut_dry_bridges: cut,
            ..Options::default()
        },
    )
    .unwrap();
    let block = sim.body_particles("block").unwrap();
    let water_p = sim.body_particles("water").unwrap();
    // The bottom of the block: its centroid less half its height (a
    // rolling block's lowest particle is not its draft).
    let lowest = |s: &Simulation<2>| {
        block.iter().map(|&i| s.particles().x()[i][1]).sum::<f64>() / block.len() as f64 - 0.5 * bh
    };
    // The water level far from the block: the highest water particle
    // within 0.2 m of the side walls.
    let level = |s: &Simulation<2>| {
        let far: Vec<f64> = water_p
            .iter()
            .map(|&i| s.particles().x()[i])
            .filter(|p| p[0] < 0.2 || p[0] > width - 0.2)
            .map(|p| p[1])
            .collect();
        far.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    };
    let (mut sum, mut n) = (0.0, 0);
    let (mut vmax, mut rms): (f64, f64) = (0.0, 0.0);
    let v0 = sim.fluid_volume();
    let mut next = 0.0;
    let bw_n = (bw / h).round() as usize + 1; // bottom row: the first particles
    let a0 = block
        .iter()
        .map(|&i| sim.particles().a()[i][1])
        .sum::<f64>()
        / block.len() as f64;
    // Unweighted: a stress-free start pushes the bottom row up and lets
    // the interior fall; the rigid start gives every particle the same.
    println!("mean initial vertical acceleration of the block's particles {a0:.3e} m/s²");
    while sim.time() < sim.end_time() - 1e-12 {
        sim.step().unwrap();
        let f = rest_figures(&sim, depth);
        vmax = vmax.max(f.max_speed);
        rms = rms.max(f.rms_speed);
        if sim.time() >= next {
            next += 0.5;
            let vy = block
                .iter()
                .map(|&i| sim.particles().v()[i][1])
                .sum::<f64>()
                / block.len() as f64;
            let ys: Vec<f64> = block.iter().map(|&i| sim.particles().x()[i][1]).collect();
            let roll = (ys[bw_n - 1] - ys[0]) / bw;
            println!(
                "t {:.2} bottom {:.4} level {:.4} vy {vy:.3e} roll {roll:.3e}",
                sim.time(),
                lowest(&sim),
                level(&sim)
            );
        }
        if sim.time() > sim.end_time() - 0.5 {
            sum += level(&sim) - lowest(&sim);
            n += 1;
        }
    }
    let mean = sum / n as f64;
    let pressure = rest_figures(&sim, depth).pressure_rms;
    let dv = sim.fluid_volume() / v0 - 1.0;
    println!(
        "floating block (surface cuts {cut}): {} steps ({} rejected); draft over the last 0.5 s {mean:.5} m against {draft} m ({:+.2} %); water: largest speed {vmax:.2e} √(gH), RMS {rms:.2e} √(gH), pressure {:.3} % RMS off ρ g (H − y), volume {:+.4} %",
        sim.steps(),
        sim.rejected(),
        100.0 * (mean / draft - 1.0),
        100.0 * pressure,
        100.0 * dv
    );
    Figures {
        draft_error: mean / draft - 1.0,
        vmax,
        rms,
        pressure,
        volume: dv,
    }
}
