//! 3D end to end: scenes through `Simulation::<3>` with `Delaunay3`.

use pfem::geometry::Delaunay3;
use pfem::prelude::*;

const G: f64 = 9.81;

fn centroid_y(sim: &Simulation<3>, idx: &[usize]) -> f64 {
    idx.iter().map(|&i| sim.state.x[i].y).sum::<f64>() / idx.len() as f64
}

/// A 0.1 m water cube with no walls falls freely: its centroid follows
/// `y0 − g t²/2` (the fluid is stress-free, only gravity acts).
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
    let water = sim.body_particles("water");
    let y0 = centroid_y(&sim, &water);
    sim.run(&mut []).expect("runs");
    let fall = y0 - centroid_y(&sim, &water);
    let exact = 0.5 * G * sim.time * sim.time;
    let err = (fall - exact).abs() / exact;
    eprintln!(
        "free fall 3D: {} steps, fall {fall:.6e} vs {exact:.6e} ({:.3}%)",
        sim.steps,
        100.0 * err
    );
    assert!(err < 5e-3, "centroid fell {fall} m, free fall {exact} m");
}
