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
