//! Cantilever under self-weight (Turek & Hron 2006, CSM2 and CSM3 without
//! the fluid): `L = 0.35 m`, thickness `t = 0.02 m`, `ρ = 1000 kg/m³`,
//! `E = 5.6 MPa`, `ν = 0.4`, `g = 2 m/s²`, clamped at `x = 0`, plane
//! strain, hypoelastic solid on linear triangles.
//!
//! References: CSM2's published tip deflection −16.97 mm; the
//! Euler–Bernoulli plane-strain estimate `q L⁴ / (8 E' I)` with
//! `E' = E / (1 − ν²)`, `q = ρ g t`, `I = t³/12`: 16.88 mm; the first
//! bending frequency `f₁ = (1.8751² / 2π) √(E' I / (ρ A L⁴))` = 2.153 Hz.

use crate::common;

use pfem_assembly::{Constraints, StepMesh, VolumetricTreatment};
use pfem_constitutive::{History, Hypoelastic, Material};
use pfem_core::{Point, Vector};
use pfem_time::{Integrator, ParticleState, Scheme, SchemeWeights, StepInput, StepParams};

const L: f64 = 0.35;
const T: f64 = 0.02;
const RHO: f64 = 1000.0;
const E: f64 = 5.6e6;
const NU: f64 = 0.4;
const G: f64 = 2.0;
const CSM2_TIP: f64 = -16.97e-3;
/// CSM2's horizontal tip displacement (m).
const CSM2_TIP_X: f64 = -0.469e-3;

fn e_prime() -> f64 {
    E / (1.0 - NU * NU)
}

fn euler_bernoulli_tip() -> f64 {
    let q = RHO * G * T;
    let i = T.powi(3) / 12.0;
    -q * L.powi(4) / (8.0 * e_prime() * i)
}

fn euler_bernoulli_frequency() -> f64 {
    let i = T.powi(3) / 12.0;
    let a = T;
    1.8751f64.powi(2) / (2.0 * std::f64::consts::PI)
        * (e_prime() * i / (RHO * a * L.powi(4))).sqrt()
}

/// The beam with `ny` cells through the thickness and square cells.
struct Beam {
    state: ParticleState<2>,
    tris: Vec<u32>,
    constraints: Constraints<2>,
    /// Particle at the middle of the free end (Turek–Hron point A).
    tip: usize,
}

fn beam(ny: usize) -> Beam {
    let nx = (ny as f64 * L / T).round() as usize;
    let (pts, tris) = common::grid(0.0, 0.0, L, T, nx, ny);
    let mut constraints = Constraints::<2>::free(pts.len());
    for (i, p) in pts.iter().enumerate() {
        if p.x < 1e-12 {
            constraints.fix(i, Vector::<2>::zeros()); // clamped
        }
    }
    let tip = pts
        .iter()
        .position(|p| p.x > L - 1e-12 && (p.y - 0.5 * T).abs() < 1e-12)
        .expect("ny even");
    Beam {
        state: ParticleState::at_rest(pts),
        tris,
        constraints,
        tip,
    }
}

/// Runs `steps` steps of size `dt`; calls `each(t, state)` after each.
fn run(
    b: &mut Beam,
    scheme: Scheme,
    dt: f64,
    steps: usize,
    each: impl FnMut(f64, &ParticleState<2>),
) {
    let mut sim = Sim::new(b, E, scheme);
    sim.run(dt, steps, |_| G, each);
}

/// A beam with its stress history, integrator and clock, so that a run can
/// change the load or the scheme on the way.
struct Sim<'b> {
    b: &'b mut Beam,
    materials: Vec<Box<dyn Material<2>>>,
    mat: Vec<u16>,
    history: Vec<History<2>>,
    integ: Integrator<2>,
    t: f64,
    initialised: bool,
}

impl<'b> Sim<'b> {
    /// Continues from a state and stress history reached earlier.
    fn resume(
        b: &'b mut Beam,
        young: f64,
        scheme: Scheme,
        from: &(ParticleState<2>, Vec<History<2>>),
    ) -> Self {
        b.state = from.0.clone();
        let mut sim = Self::new(b, young, scheme);
        sim.history = from.1.clone();
        sim.initialised = true;
        sim
    }

    fn new(b: &'b mut Beam, young: f64, scheme: Scheme) -> Self {
        let ne = b.tris.len() / 3;
        let params = StepParams {
            scheme,
            volumetric: VolumetricTreatment::NodalAveraged,
            ..Default::default()
        };
        Self {
            b,
            materials: vec![Box::new(Hypoelastic::new(RHO, young, NU).unwrap())],
            mat: vec![0u16; ne],
            history: vec![History::<2>::default(); ne],
            integ: Integrator::<2>::new(params),
            t: 0.0,
            initialised: false,
        }
    }

    /// `steps` steps of `dt` under gravity `g(t)` (m/s², downwards, taken
    /// at the end of each step); `each(t, state)` after each.
    fn run(
        &mut self,
        dt: f64,
        steps: usize,
        g: impl Fn(f64) -> f64,
        mut each: impl FnMut(f64, &ParticleState<2>),
    ) {
        for _ in 0..steps {
            let input = StepInput {
                mesh: StepMesh {
                    elements: &self.b.tris,
                    element_material: &self.mat,
                    closures: &[],
                    surface_cuts: Default::default(),
                    reference_volumes: &[],
                    node_material: &[],
                },
                materials: &self.materials,
                constraints: &self.b.constraints,
                body_force: Some(Vector::<2>::new(0.0, -g(self.t + dt))),
                external_force: &[],
            };
            if !self.initialised {
                let at_start = StepInput {
                    body_force: Some(Vector::<2>::new(0.0, -g(self.t))),
                    external_force: &[],
                    ..input
                };
                self.integ
                    .initialize_acceleration(&mut self.b.state, &self.history, &at_start)
                    .unwrap();
                self.initialised = true;
            }
            let rep =
                match self
                    .integ
                    .try_step(self.t, dt, &mut self.b.state, &mut self.history, &input)
                {
                    Ok(r) => r,
                    Err(e) => panic!("{e}"),
                };
            self.t += rep.dt;
            each(self.t, &self.b.state);
        }
    }

    /// Backward Euler steps of 5 s (each a static solve on the updated
    /// geometry) under gravity `g` until the tip moves less than 1e-10 m in
    /// a step; returns the tip displacement `(ux, uy)`.
    fn settle(&mut self, g: f64, x0: Point<2>) -> (f64, f64) {
        self.integ.params.scheme = Scheme::BackwardEuler;
        let tip = self.b.tip;
        for _ in 0..40 {
            let before = self.b.state.x[tip];
            self.run(5.0, 1, |_| g, |_, _| {});
            if (self.b.state.x[tip] - before).norm() < 1e-10 {
                break;
            }
        }
        let u = self.b.state.x[tip] - x0;
        (u.x, u.y)
    }
}

/// Quasi-static tip deflection (m) by backward Euler with steps far longer
/// than the beam's period: each step is then a static solve on the
/// updated geometry, and the inertia left over decays by `1/(ω Δt)²`.
fn static_tip(ny: usize) -> (f64, f64, f64) {
    let mut b = beam(ny);
    let x0: Point<2> = b.state.x[b.tip];
    let tip = b.tip;
    let mut last = (0.0, 0.0, 0.0);
    run(&mut b, Scheme::BackwardEuler, 5.0, 8, |_, s| {
        last = (s.x[tip].y - x0.y, last.0, s.x[tip].x - x0.x);
    });
    // (deflection, change over the last step, horizontal displacement)
    (last.0, last.0 - last.1, last.2)
}

/// Also the regression test of the direct solvers' acceptance check: at
/// `ny = 32` sparse LU's `‖r‖/‖b‖` was 2.3e-8 (1.3e-8 at equilibrium after
/// refinement), above its 1e-8 limit, and every step was rejected; the
/// solvers now refine and accept by backward error.
///
/// Measured tip deflection (mm): ny = 2: 11.10, 4: 14.75, 8: 16.14,
/// 16: 16.55, 32: 16.66 (−1.8 % from CSM2) before the objective strain
/// increment; now 11.14, 14.83, 16.26, 16.68, 16.79 (−1.1 %), and the
/// horizontal displacement at ny = 32 is −0.458 mm (−2.2 %).
#[test]
fn cantilever_under_self_weight_matches_csm2() {
    let eb = euler_bernoulli_tip();
    println!(
        "Euler-Bernoulli plane strain: {:.3} mm; CSM2: {:.3} mm",
        eb * 1e3,
        CSM2_TIP * 1e3
    );
    let mut results = Vec::new();
    for ny in [2, 4, 8, 16, 32] {
        let (tip, change, ux) = static_tip(ny);
        println!(
            "ny = {ny:2} ({} x {} cells): tip {:.3} mm ({:+.2}% vs CSM2), ux {:.3} mm ({:+.1}%), last-step change {:.1e} mm",
            (ny as f64 * L / T).round(),
            ny,
            tip * 1e3,
            (tip / CSM2_TIP - 1.0) * 100.0,
            ux * 1e3,
            (ux / CSM2_TIP_X - 1.0) * 100.0,
            change * 1e3
        );
        results.push((tip, ux));
    }
    let (finest, finest_x) = *results.last().unwrap();
    assert!(
        ((finest - CSM2_TIP) / CSM2_TIP).abs() < 0.02,
        "tip {finest} m"
    );
    // The horizontal displacement is the shortening that the bending
    // rotation makes, second order in the deflection: a step that mistook
    // rotation for strain (issue 14) put it at −0.853 mm, +82 %.
    assert!(
        ((finest_x - CSM2_TIP_X) / CSM2_TIP_X).abs() < 0.05,
        "tip ux {} mm against CSM2's {} mm",
        finest_x * 1e3,
        CSM2_TIP_X * 1e3
    );
}

/// First-mode period from the zero crossings of the tip's vertical
/// velocity, released from rest under gravity (Newmark).
fn vibration_frequency(ny: usize, periods: f64, steps_per_period: f64) -> (f64, usize) {
    let f_eb = euler_bernoulli_frequency();
    let dt = 1.0 / (f_eb * steps_per_period);
    let steps = (periods * steps_per_period).ceil() as usize;
    let mut b = beam(ny);
    let tip = b.tip;
    let mut crossings = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    run(&mut b, Scheme::Newmark, dt, steps, |t, s| {
        let v = s.v[tip].y;
        if let Some((t0, v0)) = prev {
            if v0 != 0.0 && v0.signum() != v.signum() {
                crossings.push(t0 + (t - t0) * v0 / (v0 - v));
            }
        }
        prev = Some((t, v));
    });
    let k = crossings.len();
    assert!(k >= 3, "only {k} zero crossings");
    let period = 2.0 * (crossings[k - 1] - crossings[0]) / (k - 1) as f64;
    (1.0 / period, k)
}

/// Measured: ny = 8, 60 steps per period: 2.2016 Hz (+2.24 %; 2.1907 Hz,
/// +1.73 %, while the stress update still damped the higher modes that
/// shift the velocity's zero crossings);
/// ny = 16, 80 steps per period: 2.1641 Hz (+0.50 %, 50 s, too slow for
/// the suite). The excess follows the too-stiff bending of coarse linear
/// triangles seen in the static test.
#[test]
fn free_vibration_at_the_euler_bernoulli_frequency() {
    let f_eb = euler_bernoulli_frequency();
    let (f, k) = vibration_frequency(8, 3.2, 60.0);
    println!(
        "ny = 8: f = {f:.4} Hz from {k} zero crossings; Euler-Bernoulli {f_eb:.4} Hz ({:+.2}%)",
        (f / f_eb - 1.0) * 100.0
    );
    assert!(
        (f / f_eb - 1.0).abs() < 0.03,
        "f = {f} Hz against {f_eb} Hz"
    );
}

/// Turek & Hron's CSM1/CSM3 solid: `E = 1.4 MPa` (μ = 0.5 MPa, ν = 0.4),
/// whose tip under `g = 2 m/s²` goes (−7.187, −66.10) mm.
const E_CSM1: f64 = 1.4e6;
const CSM1_TIP: (f64, f64) = (-7.187e-3, -66.10e-3);

/// Issue 14, acceptance 2: a hypoelastic solid must not remember how it was
/// loaded. The CSM1 beam loaded suddenly (backward Euler steps of 5 s, each
/// a static solve, the first of them from the straight beam to nearly the
/// final 66 mm) and loaded by a 5 s ramp of gravity (500 steps of 10 ms)
/// settle to the same tip displacement, both components within 0.5 %.
///
/// Measured: sudden (−6.613, −63.441) mm, ramped (−6.613, −63.435) mm,
/// −0.007 % and +0.010 %. Before the objective strain increment the sudden
/// load mistook the step's rotation for strain: the centre line came out about 1 % short,
/// the deflection 5 % short and the horizontal displacement 40 % off.
#[test]
fn sudden_and_ramped_loads_reach_the_same_state() {
    let ny = 8;
    let mut sudden = beam(ny);
    let x0 = sudden.state.x[sudden.tip];
    let (sx, sy) = Sim::new(&mut sudden, E_CSM1, Scheme::BackwardEuler).settle(G, x0);
    let mut ramped = beam(ny);
    let (rx, ry) = {
        let mut sim = Sim::new(&mut ramped, E_CSM1, Scheme::BackwardEuler);
        sim.run(0.01, 500, |t| G * (t / 5.0).min(1.0), |_, _| {});
        sim.settle(G, x0)
    };
    let (dx, dy) = (sx / rx - 1.0, sy / ry - 1.0);
    println!(
        "ny = {ny}: sudden ({:.3}, {:.3}) mm, ramped ({:.3}, {:.3}) mm: differ by {:+.3} %, {:+.3} %; \
         CSM1 ({:.3}, {:.3}) mm",
        sx * 1e3,
        sy * 1e3,
        rx * 1e3,
        ry * 1e3,
        dx * 100.0,
        dy * 100.0,
        CSM1_TIP.0 * 1e3,
        CSM1_TIP.1 * 1e3
    );
    assert!(dx.abs() < 0.005, "ux: sudden {sx} m, ramped {rx} m");
    assert!(dy.abs() < 0.005, "uy: sudden {sy} m, ramped {ry} m");
}

/// The CSM2 beam (ny = 4) released from rest under gravity and run for
/// five periods with Bossak at 20 steps per period, which removes the
/// higher bending modes (ω Δt ≥ 2, spectral radius ≤ 0.75 per step) and
/// leaves a first-mode vibration about the static state, of about the
/// static deflection in amplitude (17 mm): the start of the free-vibration
/// tests. Returns the state and stresses, and the tip's static height.
fn first_mode_start() -> ((ParticleState<2>, Vec<History<2>>), f64) {
    let ny = 4;
    let mut b = beam(ny);
    let tip = b.tip;
    let x0 = b.state.x[tip];
    let dt = 1.0 / (euler_bernoulli_frequency() * 20.0);
    let start = {
        let mut sim = Sim::new(&mut b, E, Scheme::Bossak);
        sim.run(dt, 100, |_| G, |_, _| {});
        (sim.b.state.clone(), sim.history.clone())
    };
    let mut s = beam(ny);
    let (_, uy) = Sim::new(&mut s, E, Scheme::BackwardEuler).settle(G, x0);
    (start, x0.y + uy)
}

/// What a free-vibration run records after every step.
#[derive(Default)]
struct Record {
    t: Vec<f64>,
    tip_y: Vec<f64>,
    tip_vy: Vec<f64>,
    /// Kinetic + elastic (complementary, plane strain) + gravity potential (J/m).
    energy: Vec<f64>,
    kinetic: Vec<f64>,
}

/// Runs `periods` first-mode periods (Euler–Bernoulli estimate) at
/// `per_period` steps each with `scheme`, from `start`.
fn vibrate(
    start: &(ParticleState<2>, Vec<History<2>>),
    scheme: Scheme,
    per_period: f64,
    periods: f64,
) -> Record {
    let mut b = beam(4);
    // Lumped masses of the initial mesh: ρ V / 3 per triangle node.
    let mut mass = vec![0.0; b.state.len()];
    for t in b.tris.chunks(3) {
        let p: Vec<Point<2>> = t.iter().map(|&i| b.state.x[i as usize]).collect();
        let v = pfem_core::simplex_measure::<2>(&p);
        for &i in t {
            mass[i as usize] += RHO * v / 3.0;
        }
    }
    let tip = b.tip;
    let tris = b.tris.clone();
    let f = euler_bernoulli_frequency();
    let dt = 1.0 / (f * per_period);
    let steps = (periods * per_period).round() as usize;
    let mut sim = Sim::resume(&mut b, E, scheme, start);
    let mut rec = Record::default();
    for _ in 0..steps {
        sim.run(dt, 1, |_| G, |_, _| {});
        let s = &sim.b.state;
        let kinetic: f64 = (0..s.len())
            .map(|i| 0.5 * mass[i] * s.v[i].norm_squared())
            .sum();
        let potential: f64 = (0..s.len()).map(|i| mass[i] * G * s.x[i].y).sum();
        let mut elastic = 0.0;
        for (e, t) in tris.chunks(3).enumerate() {
            let p: Vec<Point<2>> = t.iter().map(|&i| s.x[i as usize]).collect();
            let v = pfem_core::simplex_measure::<2>(&p);
            let h = &sim.history[e];
            let (sx, sy, sxy, sz) = (
                h.stress[(0, 0)],
                h.stress[(1, 1)],
                h.stress[(0, 1)],
                h.stress_zz,
            );
            let ss = sx * sx + sy * sy + sz * sz + 2.0 * sxy * sxy;
            let tr = sx + sy + sz;
            elastic += v * ((1.0 + NU) * ss - NU * tr * tr) / (2.0 * E);
        }
        rec.t.push(sim.t);
        rec.tip_y.push(s.x[tip].y);
        rec.tip_vy.push(s.v[tip].y);
        rec.energy.push(kinetic + elastic + potential);
        rec.kinetic.push(kinetic);
    }
    rec
}

/// Period from the upward zero crossings of the tip's vertical velocity.
fn period(rec: &Record) -> f64 {
    let mut up = Vec::new();
    for k in 1..rec.t.len() {
        let (v0, v1) = (rec.tip_vy[k - 1], rec.tip_vy[k]);
        if v0 < 0.0 && v1 >= 0.0 {
            let (t0, t1) = (rec.t[k - 1], rec.t[k]);
            up.push(t0 + (t1 - t0) * v0 / (v0 - v1));
        }
    }
    assert!(up.len() >= 3, "only {} crossings", up.len());
    (up[up.len() - 1] - up[0]) / (up.len() - 1) as f64
}

/// Fractional amplitude lost per period: a least-squares fit of
/// `ln √((y − y_eq)² + (v/ω)²)` against time.
fn loss_per_period(t: &[f64], y: &[f64], vy: &[f64], y_eq: f64, period: f64) -> f64 {
    let omega = 2.0 * std::f64::consts::PI / period;
    let la: Vec<f64> = y
        .iter()
        .zip(vy)
        .map(|(y, v)| 0.5 * ((y - y_eq).powi(2) + (v / omega).powi(2)).ln())
        .collect();
    let n = t.len() as f64;
    let (mt, ml) = (t.iter().sum::<f64>() / n, la.iter().sum::<f64>() / n);
    let num: f64 = t.iter().zip(&la).map(|(t, l)| (t - mt) * (l - ml)).sum();
    let den: f64 = t.iter().map(|t| (t - mt).powi(2)).sum();
    1.0 - (num / den * period).exp()
}

/// The same measure on the scheme's own single-degree-of-freedom
/// oscillator `ẍ + ω² x = 0` at the same `ω Δt`: what the scheme is
/// designed to lose per period.
fn designed_loss(scheme: Scheme, period: f64, dt: f64, periods: f64) -> f64 {
    let omega = 2.0 * std::f64::consts::PI / period;
    let k = omega * omega;
    let w = SchemeWeights::new(scheme, -0.3, dt);
    let inertia = w.inertia();
    let (mut x, mut v, mut a) = (1.0, 0.0, -k);
    let (mut ts, mut xs, mut vs) = (Vec::new(), Vec::new(), Vec::new());
    let steps = (periods * period / dt).round() as usize;
    let p = |x: f64| Point::<2>::new(x, 0.0);
    let vec = |v: f64| Vector::<2>::new(v, 0.0);
    for n in 1..=steps {
        let x0 = w.position(&p(x), &vec(v), &vec(a), &vec(0.0)).x;
        let c = inertia.mass_factor;
        let vel =
            (c * v + inertia.acceleration_factor * a - k * x0) / (c + k * w.displacement_weight());
        a = w.acceleration(&vec(v), &vec(a), &vec(vel)).x;
        x = x0 + w.displacement_weight() * vel;
        v = vel;
        ts.push(n as f64 * dt);
        xs.push(x);
        vs.push(v);
    }
    loss_per_period(&ts, &xs, &vs, 0.0, period)
}

/// Issue 14, acceptance 3: the trapezoidal rule adds no damping to the
/// solid. Free first-mode vibration of the CSM2 beam over 20 periods at 40
/// and at 160 steps per period: amplitude lost per period ≤ 0.05 % and the
/// total energy (kinetic + elastic + gravity) constant to 0.1 % of the
/// vibration's energy, at both. Before the fix the stress increment was
/// `Δt D(Vⁿ⁺¹)`, a backward-Euler increment: damping ratio `ω Δt / 4`,
/// 10 % of the amplitude per period at 40 steps.
///
/// Measured: amplitude −0.0003 / −0.0002 % per period (a gain) at 40 / 160
/// steps per period; energy range 0.0132 / 0.0127 % of the vibration's
/// energy, a floor of this geometrically nonlinear hypoelastic beam that
/// no longer depends on the step. (With the strain increment added at the
/// end of the step, unconvected, the range was 0.23 / 0.063 %, first order
/// in Δt.)
#[test]
fn trapezoidal_rule_keeps_the_beams_amplitude_and_energy() {
    let (start, y_eq) = first_mode_start();
    for spp in [40.0, 160.0] {
        let rec = vibrate(&start, Scheme::Newmark, spp, 20.0);
        let p = period(&rec);
        let loss = loss_per_period(&rec.t, &rec.tip_y, &rec.tip_vy, y_eq, p);
        let (emin, emax) = rec
            .energy
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &e| {
                (a.min(e), b.max(e))
            });
        let scale = rec.kinetic.iter().cloned().fold(0.0, f64::max);
        let range = (emax - emin) / scale;
        println!(
            "trapezoidal, {spp} steps per period, 20 periods: period {p:.5} s, amplitude lost {:+.4} % per period, \
             energy range {:.4} % of the vibration's energy",
            loss * 100.0,
            range * 100.0
        );
        assert!(
            loss.abs() <= 5e-4,
            "{spp} steps per period: amplitude lost {loss:e} per period"
        );
        assert!(
            range <= 1e-3,
            "{spp} steps per period: energy varies by {range:e} of the vibration's"
        );
    }
}

/// Issue 14, acceptance 3: the trapezoidal rule's period error falls at
/// second order. Period at 20, 40 and 80 steps per period over 10
/// periods; the observed order `log₂((P₂₀ − P₄₀)/(P₄₀ − P₈₀))` is 2 ± 0.2
/// (the rule's own period error is `(ω Δt)²/12` to leading order).
#[test]
fn trapezoidal_period_error_is_second_order() {
    let (start, _) = first_mode_start();
    let p: Vec<f64> = [20.0, 40.0, 80.0]
        .iter()
        .map(|&n| period(&vibrate(&start, Scheme::Newmark, n, 10.0)))
        .collect();
    let order = ((p[0] - p[1]) / (p[1] - p[2])).log2();
    println!(
        "trapezoidal periods at 20/40/80 steps per period: {:.6} / {:.6} / {:.6} s, observed order {order:.3}",
        p[0], p[1], p[2]
    );
    assert!((order - 2.0).abs() <= 0.2, "observed order {order}");
}

/// Issue 14, acceptance 3: Bossak (α_B = −0.3) damps the beam exactly as
/// it damps its own oscillator at the same `ω Δt`: at 10 steps per period
/// over 20 periods, the loss per period within 10 % of the designed one.
#[test]
fn bossak_damps_the_beam_as_designed() {
    let (start, y_eq) = first_mode_start();
    let per_period = 10.0;
    let rec = vibrate(&start, Scheme::Bossak, per_period, 20.0);
    let p = period(&rec);
    let loss = loss_per_period(&rec.t, &rec.tip_y, &rec.tip_vy, y_eq, p);
    let dt = 1.0 / (euler_bernoulli_frequency() * per_period);
    // The oscillator at the beam's own (semi-discrete) frequency: the
    // trapezoidal rule's period at 80 steps per period, corrected by its
    // (ω Δt)²/12 lengthening.
    let p80 = period(&vibrate(&start, Scheme::Newmark, 80.0, 10.0));
    let dt80 = 1.0 / (euler_bernoulli_frequency() * 80.0);
    let p_exact = p80 / (1.0 + (2.0 * std::f64::consts::PI * dt80 / p80).powi(2) / 12.0);
    let designed = designed_loss(Scheme::Bossak, p_exact, dt, 20.0);
    println!(
        "Bossak, ω Δt = {:.3}: beam loses {:.3} % per period, its oscillator {:.3} % ({:+.1} %)",
        2.0 * std::f64::consts::PI * dt / p_exact,
        loss * 100.0,
        designed * 100.0,
        (loss / designed - 1.0) * 100.0
    );
    assert!(
        (loss / designed - 1.0).abs() <= 0.1,
        "loss {loss} against {designed}"
    );
}
