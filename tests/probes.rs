//! Point probes measured together: `Loads::fluid_at_points` gives every
//! point what `Loads::fluid_at` gives it alone, bit for bit.

use pfem::cases::DamBreak;
use pfem::cases3d::WaterColumn3d;
use pfem::prelude::*;

/// The points a check asks about: every particle's position (each a
/// corner shared by several elements, where the first element in order
/// decides), the midpoints of consecutive particles, points outside the
/// water, far away, and not finite.
fn points_of<const D: usize>(sim: &Simulation<D>) -> Vec<Point<D>>
where
    Const<D>: Dim,
{
    let x = sim.particles().x();
    let mut at: Vec<Point<D>> = x.to_vec();
    at.extend(x.windows(2).map(|w| (w[0] + w[1]) / 2.0));
    at.extend(x.windows(3).map(|w| (w[0] + w[1] * 2.0 + w[2]) / 4.0));
    at.push(Point::<D>::repeat(-1.0));
    at.push(Point::<D>::repeat(1e300));
    at.push(Point::<D>::repeat(f64::NAN));
    at.push(Point::<D>::repeat(f64::INFINITY));
    at
}

fn same_as_alone<const D: usize>(sim: &Simulation<D>, at: &[Point<D>]) -> usize
where
    Const<D>: Dim,
{
    let together = sim.fluid_at_points(at);
    assert_eq!(together.len(), at.len());
    let mut inside = 0;
    for (k, (q, got)) in at.iter().zip(&together).enumerate() {
        let alone = sim.fluid_at(q);
        let bits = |v: Option<(f64, Vector<D>)>| {
            v.map(|(p, u)| {
                let mut b = vec![p.to_bits()];
                b.extend(u.iter().map(|c| c.to_bits()));
                b
            })
        };
        assert_eq!(
            bits(*got),
            bits(alone),
            "point {k} at {:?}: together {got:?}, alone {alone:?}",
            q.as_slice()
        );
        inside += usize::from(alone.is_some());
    }
    inside
}

#[test]
fn points_measured_together_read_what_each_reads_alone() {
    let mut c = DamBreak::default();
    c.spacing = c.width / 10.0;
    let mut sim = Simulation::new(
        c.scene(),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    for _ in 0..6 {
        sim.step().unwrap();
    }
    let at = points_of(&sim);
    // Few points take the walk over the buckets, many the cells' lookup.
    // (The last particles are fluid: walls and solids come first.)
    let n = sim.particles().len();
    let few = same_as_alone(&sim, &at[n - 3..n]);
    let inside = same_as_alone(&sim, &at);
    println!(
        "2D: {few} of 3, {inside} of {} points inside the water",
        at.len()
    );
    assert_eq!(few, 3);
    assert!(inside > 200, "only {inside} points found water");

    let mut c = WaterColumn3d::default();
    c.spacing = c.width / 6.0;
    let mut sim = Simulation::new(
        c.scene(),
        Box::new(Delaunay3::default()),
        StepParams::default(),
    )
    .unwrap();
    for _ in 0..3 {
        sim.step().unwrap();
    }
    let at = points_of(&sim);
    let inside = same_as_alone(&sim, &at);
    println!("3D: {inside} of {} points inside the water", at.len());
    assert!(inside > 100, "only {inside} points found water");
}

/// A run whose probe rows would not fit its memory budget is refused when
/// its outputs start, not hours later: 3 columns every step (at most 5 ms)
/// over 10⁴ s are at least 2·10⁶ rows, 144 MB, against a budget of 100 MB
/// (900 gauges in 3D over 10⁶ steps held 29 GB). With a row a second it
/// runs.
#[test]
fn probe_rows_beyond_the_memory_budget_are_refused_at_the_start() {
    let mut c = DamBreak::default();
    c.spacing = c.width / 10.0;
    let options = Options {
        memory_budget: 1e8,
        ..Options::default()
    };
    let mut sim = Simulation::with_options(
        c.scene(),
        Box::new(Delaunay2::default()),
        StepParams::default(),
        options,
    )
    .unwrap();
    sim.set_end_time(1e4).unwrap();
    let probes = || c.probes();
    let dir = std::env::temp_dir().join(format!("pfem-probe-rows-{}", std::process::id()));
    let mut out = StandardOutput::new(&dir, false, probes(), true).overwrite(true);
    let err = sim.run(&mut [&mut out]).unwrap_err().to_string();
    assert!(
        err.contains("probe_interval")
            && err.contains("keep_rows(false)")
            && err.contains("memory budget"),
        "{err}"
    );
    assert_eq!(sim.steps(), 0);
    // Rows not kept in memory (written to probes.csv only): the same run
    // starts (stopped after its first step), its rows written, none held.
    let mut out = StandardOutput::new(&dir, false, probes(), true)
        .overwrite(true)
        .keep_rows(false);
    sim.add_hook(Box::new(pfem::hooks::StopWhen::new("a step", |t, _| {
        t > 0.0
    })));
    sim.run(&mut [&mut out]).unwrap();
    assert!(sim.steps() > 0 && sim.time() < 1.0);
    assert!(out.history().is_empty());
    let csv = std::fs::read_to_string(dir.join("probes.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 1 + sim.steps() as usize, "{csv}");
    let mut out = StandardOutput::new(&dir, false, probes(), true).overwrite(true);
    out.probe_interval = Some(1.0);
    sim.set_end_time(sim.time() + 0.004).unwrap();
    sim.run(&mut [&mut out]).unwrap();
    assert!(sim.steps() > 0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `height_at_wall` reads the main body's largest `y` within the band of
/// `x = 0`, whatever its sign, and NaN with no water there. Before
/// session 49 it folded from 0 (water wholly below `y = 0` read 0, as did
/// no water at the wall) and took every particle with `x ≤ band`.
#[test]
fn the_height_at_the_wall_is_read_below_zero_and_nan_without_water() {
    let h = 0.025;
    let boxed = |x0: f64, y0: f64, x1: f64, y1: f64| Geometry::Box {
        min: Point::<2>::new(x0, y0),
        max: Point::<2>::new(x1, y1),
    };
    let tank = |x0: f64| {
        Scene::<2>::new("low")
            .gravity(Vector::<2>::new(0.0, -9.81))
            .wall(
                "floor",
                boxed(-0.1, -1.0 - h, 0.6, -1.0),
                h,
                WallMotion::Fixed,
            )
            .wall("back", boxed(-0.1, -1.0, 0.0, -0.5), h, WallMotion::Fixed)
            .fluid(
                "water",
                Box::new(Newtonian::water()),
                boxed(x0, -1.0, x0 + 0.2, -0.75),
                h,
            )
    };
    let at_wall = Simulation::new(
        tank(0.0),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    let height = pfem::cases::height_at_wall(&at_wall, 1.5 * h);
    // The top row of the water, at y = −0.75.
    assert!((height + 0.75).abs() < 1e-9, "height {height}");
    let away = Simulation::new(
        tank(0.3),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    let height = pfem::cases::height_at_wall(&away, 1.5 * h);
    assert!(height.is_nan(), "height {height} with no water at the wall");
}
