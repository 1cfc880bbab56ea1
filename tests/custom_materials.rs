//! Custom materials at the level of a run: what the solver hands a
//! material and asks of it (`Material::unified`'s history,
//! `Material::initial_history`), checked against closed forms.
//!
//! `cargo test --release --test suite custom_materials::`

use pfem::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

const G: f64 = 9.81;

/// The largest pressure [`PressureThickened`]'s `unified` was handed (the
/// bits of a non-negative `f64`, whose order is the numbers').
static LARGEST_SEEN: AtomicU64 = AtomicU64::new(0);

/// Water whose viscosity grows with its pressure, `μ = μ₀ + c p` (as a
/// dense suspension's or a granular flow's), writing down the largest
/// pressure its `unified` is handed in [`LARGEST_SEEN`].
#[derive(Debug)]
struct PressureThickened;

impl PressureThickened {
    const K: f64 = 2.2e9;
    const MU0: f64 = 1e-3;
    /// `c` (s): 10⁻³ Pa·s more per kPa.
    const C: f64 = 1e-6;
}

impl Material<2> for PressureThickened {
    fn name(&self) -> &str {
        "pressure_thickened"
    }
    fn kind(&self) -> MaterialKind {
        MaterialKind::Fluid
    }
    fn density(&self) -> f64 {
        1000.0
    }
    fn wave_speed(&self) -> f64 {
        (Self::K / 1000.0).sqrt()
    }
    fn unified(&self, kin: &Kinematics<2>, history: &History<2>) -> Unified<2> {
        let p = history.pressure.max(0.0);
        LARGEST_SEEN.fetch_max(p.to_bits(), Ordering::Relaxed);
        Unified::new(
            Self::MU0 + Self::C * p,
            kin.dt * Self::K,
            Tensor::<2>::identity() * -history.pressure,
            -history.pressure,
        )
    }
    fn update_history(&self, kin: &Kinematics<2>, history: &mut History<2>) {
        history.pressure -= kin.dt * Self::K * kin.volumetric_rate();
    }
    fn parameters(&self) -> Vec<f64> {
        vec![Self::K, Self::MU0, Self::C]
    }
}

/// A fluid's `unified` is handed its element's pressure at the step's
/// start (the mean of its nodes'), so that a viscosity may depend on the
/// pressure. Before session 49 it was handed 0 (`History::default()`):
/// the largest pressure seen here was 0 against `ρ g H` = 4.9 kPa at the
/// bottom. The water, its pressure hydrostatic from the start, stays at
/// rest.
#[test]
fn a_fluid_viscosity_may_depend_on_the_pressure() {
    let (h, w, depth) = (0.05, 0.5, 0.5);
    let b = |a: (f64, f64), c: (f64, f64)| Geometry::Box {
        min: Point::<2>::new(a.0, a.1),
        max: Point::<2>::new(c.0, c.1),
    };
    let end = 0.1;
    let scene = Scene::<2>::new("pressure_thickened")
        .gravity(Vector::<2>::new(0.0, -G))
        .settings(RunSettings {
            end_time: end,
            max_dt: 5e-3,
            output_interval: None,
            ..Default::default()
        })
        .wall("floor", b((-h, -h), (w + h, 0.0)), h, WallMotion::Fixed)
        .wall("left", b((-h, 0.0), (0.0, 0.7)), h, WallMotion::Fixed)
        .wall("right", b((w, 0.0), (w + h, 0.7)), h, WallMotion::Fixed)
        .fluid(
            "water",
            Box::new(PressureThickened),
            b((0.0, 0.0), (w, depth)),
            h,
        );
    let mut sim =
        Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default()).unwrap();
    let c = (G * depth).sqrt();
    let mut max_speed: f64 = 0.0;
    while sim.time() < end - 1e-12 {
        sim.step().unwrap();
        let p = sim.particles();
        for i in 0..p.len() {
            if p.kind()[i] == ParticleKind::Fluid {
                max_speed = max_speed.max(p.v()[i].norm() / c);
            }
        }
    }
    let seen = f64::from_bits(LARGEST_SEEN.load(Ordering::Relaxed));
    let head = 1000.0 * G * depth;
    println!(
        "pressure-thickened water: largest pressure seen {seen:.1} Pa against rho g H = {head:.1} Pa, \
         largest speed {max_speed:.2e} sqrt(gH)"
    );
    // The bottom elements' mean lies between the head one spacing above
    // the floor and a tenth over the floor's.
    assert!(
        seen > 1000.0 * G * (depth - h) && seen < 1.1 * head,
        "largest pressure seen {seen} Pa against {head} Pa"
    );
    assert!(max_speed <= 2e-3, "largest speed {max_speed} sqrt(gH)");
}

/// Rubber that starts in tension `σ_xx = σ₀` (a prestress, as a stretched
/// bar's or a bolt's), writing each element's initial centroid into
/// `internal[0]` (a variable the stress does not read), so that the test
/// sees where it was asked.
#[derive(Debug)]
struct Prestressed {
    rubber: Hypoelastic,
    sigma0: f64,
}

impl Material<2> for Prestressed {
    fn name(&self) -> &str {
        "prestressed"
    }
    fn kind(&self) -> MaterialKind {
        MaterialKind::Solid
    }
    fn density(&self) -> f64 {
        Material::<2>::density(&self.rubber)
    }
    fn wave_speed(&self) -> f64 {
        Material::<2>::wave_speed(&self.rubber)
    }
    fn unified(&self, kin: &Kinematics<2>, history: &History<2>) -> Unified<2> {
        self.rubber.unified(kin, history)
    }
    fn update_history(&self, kin: &Kinematics<2>, history: &mut History<2>) {
        let x = history.internal[0];
        self.rubber.update_history(kin, history);
        history.internal[0] = x;
    }
    fn internal_variables(&self) -> &[&str] {
        &["centroid_x"]
    }
    fn initial_history(&self, centroid: &Point<2>) -> History<2> {
        let mut h = History::default();
        h.stress[(0, 0)] = self.sigma0;
        h.internal[0] = centroid[0];
        h
    }
    fn parameters(&self) -> Vec<f64> {
        vec![self.sigma0]
    }
}

/// A free bar 1 m × 0.1 m (plane strain, `E` = 1 MPa, `ν` = 0.3,
/// 1000 kg/m³, no gravity) starting in tension `σ₀`.
fn prestressed_bar(sigma0: f64) -> Scene<2> {
    let rubber = Hypoelastic::new(1000.0, 1e6, 0.3).unwrap();
    Scene::<2>::new("prestressed_bar")
        .settings(RunSettings {
            end_time: 0.01,
            max_dt: 5e-4,
            output_interval: None,
            ..Default::default()
        })
        .solid(
            "bar",
            Box::new(Prestressed { rubber, sigma0 }),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(1.0, 0.1),
            },
            0.025,
            None,
        )
}

/// A solid starts from its material's `initial_history`, asked at each
/// element's centroid: the bar in tension, released, contracts from both
/// ends. An end released from a uniform stress `σ₀` moves at
/// `σ₀ / (ρ c)` behind the unloading wave, `c = √(E / ((1 − ν²) ρ))` the
/// plane-strain bar speed (33.2 m/s here): 0.030 m/s inward for
/// `σ₀` = 1 kPa. Before session 49 every solid started unstressed (no
/// way to give it a state): the bar stayed at rest.
#[test]
fn a_solid_starts_from_its_materials_initial_history() {
    let sigma0 = 1e3;
    let mut sim = Simulation::new(
        prestressed_bar(sigma0),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    )
    .unwrap();
    // Each element's state is its material's at its centroid.
    let x0 = sim.particles().initial_positions().to_vec();
    let (solid, history) = (sim.elements().solid(), sim.elements().solid_history());
    assert!(!history.is_empty());
    for (el, h) in solid.chunks_exact(3).zip(history) {
        let cx = el.iter().map(|&i| x0[i as usize][0]).sum::<f64>() / 3.0;
        assert!(
            (h.internal[0] - cx).abs() < 1e-12,
            "{} against {cx}",
            h.internal[0]
        );
        assert_eq!(h.stress[(0, 0)], sigma0);
    }
    while sim.time() < 0.01 - 1e-12 {
        sim.step().unwrap();
    }
    // The mean velocity of each end's last two columns.
    let p = sim.particles();
    let end_speed = |near: f64| {
        let (sum, n) = (0..p.len())
            .filter(|&i| (x0[i][0] - near).abs() < 0.03)
            .fold((0.0, 0), |(s, n), i| (s + p.v()[i][0], n + 1));
        sum / n as f64
    };
    let (left, right) = (end_speed(0.0), end_speed(1.0));
    let c = (1e6 / ((1.0 - 0.3f64 * 0.3) * 1000.0)).sqrt();
    let want = sigma0 / (1000.0 * c);
    println!(
        "prestressed bar after 10 ms: ends at {left:+.4} and {right:+.4} m/s against ±{want:.4} m/s"
    );
    for (v, sign) in [(left, 1.0), (right, -1.0)] {
        assert!(
            (sign * v - want).abs() < 0.25 * want,
            "an end at {v} m/s against {} m/s",
            sign * want
        );
    }
}

/// An initial history that is not finite is refused when the run is
/// built, naming the body.
#[test]
fn a_non_finite_initial_history_is_refused() {
    match Simulation::new(
        prestressed_bar(f64::NAN),
        Box::new(Delaunay2::default()),
        StepParams::default(),
    ) {
        Err(SceneError::InvalidMaterial { body, source }) => {
            assert_eq!(body, "bar");
            assert!(
                matches!(
                    source,
                    pfem::constitutive::MaterialError::NonFiniteInitialHistory
                ),
                "{source}"
            );
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
}

/// Rubber whose viscosity turns into a NaN (a user law's overflow), or,
/// with a counter, which panics in the call named.
#[derive(Debug)]
struct Poisoned(
    Hypoelastic,
    Option<(std::sync::Arc<std::sync::atomic::AtomicUsize>, &'static str)>,
);

impl Poisoned {
    /// Panics (and counts it) if `call` is the one to panic in.
    fn maybe_panic(&self, call: &str) {
        if let Some((panics, which)) = &self.1 {
            if *which == call {
                panics.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                panic!("the rubber's table ran out");
            }
        }
    }
}

impl Material<2> for Poisoned {
    fn name(&self) -> &str {
        "poisoned rubber"
    }
    fn kind(&self) -> MaterialKind {
        MaterialKind::Solid
    }
    fn density(&self) -> f64 {
        Material::<2>::density(&self.0)
    }
    fn wave_speed(&self) -> f64 {
        Material::<2>::wave_speed(&self.0)
    }
    fn unified(&self, kin: &Kinematics<2>, history: &History<2>) -> Unified<2> {
        if self.1.is_some() {
            self.maybe_panic("unified");
            return self.0.unified(kin, history);
        }
        let mut u = self.0.unified(kin, history);
        u.mu = f64::NAN;
        u
    }
    fn update_history(&self, kin: &Kinematics<2>, history: &mut History<2>) {
        self.maybe_panic("update_history");
        self.0.update_history(kin, history);
    }
    fn refuses(&self, kin: &Kinematics<2>, history: &History<2>) -> Option<String> {
        self.maybe_panic("refuses");
        self.0.refuses(kin, history)
    }
}

/// A material whose constitutive triple is not a number is named in the
/// error, not only numbered (session 54's review: "material 0 returned a
/// non-finite constitutive triple", where a negative modulus was named).
#[test]
fn a_material_returning_a_non_number_is_named() {
    let scene = Scene::<2>::new("poisoned")
        .settings(RunSettings {
            end_time: 0.01,
            max_dt: 5e-3,
            output_interval: None,
            ..Default::default()
        })
        .solid(
            "block",
            Box::new(Poisoned(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap(), None)),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(0.1, 0.05),
            },
            0.025,
            None,
        );
    let err = Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default())
        .map_err(|e| e.to_string())
        .and_then(|mut sim| sim.run(&mut []).map_err(|e| e.to_string()))
        .unwrap_err();
    assert!(
        err.contains("`poisoned rubber`") && err.contains("non-finite"),
        "{err}"
    );
}

/// A material that panics is an error naming it, returned at once, not a
/// panic of the run (session 54's review: its message printed once an
/// element, about 150 times, and the process ended). The elements after
/// the first panic are not computed: a panic a thread at most. Session
/// 56: in any of its calls, the step's update (`refuses`,
/// `update_history`, a fluid's `update_pressure`) as the assembly's
/// `unified`; a panic there ended the process.
#[test]
fn a_material_that_panics_is_an_error_naming_it() {
    for call in ["unified", "refuses", "update_history", "update_pressure"] {
        let panics = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let scene = Scene::<2>::new("panicking").settings(RunSettings {
            end_time: 0.01,
            max_dt: 5e-3,
            output_interval: None,
            ..Default::default()
        });
        let scene = if call == "update_pressure" {
            // Water on a floor, its pressure update panicking.
            scene
                .gravity(Vector::<2>::new(0.0, -9.81))
                .wall(
                    "floor",
                    Geometry::Box {
                        min: Point::<2>::new(-0.02, -0.02),
                        max: Point::<2>::new(0.22, 0.0),
                    },
                    0.01,
                    WallMotion::Fixed,
                )
                .fluid(
                    "water",
                    Box::new(PanickyWater(Newtonian::water(), panics.clone())),
                    Geometry::Box {
                        min: Point::<2>::new(0.0, 0.01),
                        max: Point::<2>::new(0.2, 0.1),
                    },
                    0.01,
                )
        } else {
            scene.solid(
                "block",
                Box::new(Poisoned(
                    Hypoelastic::new(1000.0, 1e6, 0.3).unwrap(),
                    Some((panics.clone(), call)),
                )),
                Geometry::Box {
                    min: Point::<2>::new(0.0, 0.0),
                    max: Point::<2>::new(0.2, 0.1),
                },
                0.01,
                None,
            )
        };
        let err = Simulation::new(scene, Box::new(Delaunay2::default()), StepParams::default())
            .map_err(|e| e.to_string())
            .and_then(|mut sim| sim.run(&mut []).map_err(|e| e.to_string()))
            .unwrap_err();
        let name = if call == "update_pressure" {
            "`panicky water`"
        } else {
            "`poisoned rubber`"
        };
        assert!(
            err.contains(name)
                && err.contains(&format!("panicked in `{call}`"))
                && err.contains("the rubber's table ran out"),
            "{call}: {err}"
        );
        let panics = panics.load(std::sync::atomic::Ordering::Relaxed);
        // 400 elements; one panic a worker thread at most, a few in flight.
        assert!(
            panics >= 1 && panics <= 2 * rayon::current_num_threads().max(1),
            "{call}: {panics} panics"
        );
    }
}

/// Water whose pressure update panics, counting its panics.
#[derive(Debug)]
struct PanickyWater(Newtonian, std::sync::Arc<std::sync::atomic::AtomicUsize>);

impl Material<2> for PanickyWater {
    fn name(&self) -> &str {
        "panicky water"
    }
    fn kind(&self) -> MaterialKind {
        MaterialKind::Fluid
    }
    fn density(&self) -> f64 {
        Material::<2>::density(&self.0)
    }
    fn wave_speed(&self) -> f64 {
        Material::<2>::wave_speed(&self.0)
    }
    fn unified(&self, kin: &Kinematics<2>, history: &History<2>) -> Unified<2> {
        self.0.unified(kin, history)
    }
    fn update_history(&self, kin: &Kinematics<2>, history: &mut History<2>) {
        self.0.update_history(kin, history);
    }
    fn update_pressure(&self, _p_n: f64, _volumetric_rate: f64, _dt: f64) -> f64 {
        self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        panic!("the rubber's table ran out");
    }
}
