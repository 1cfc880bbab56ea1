//! Incremental objectivity of the solid stress update through the whole
//! integrator (issue 14, acceptance 1): a prestressed solid block spun
//! rigidly about its centre by 0.5 rad per step, with every time scheme,
//! keeps its volume and rotates its stress with it, to 1e-8 relative, and
//! comes back to its stress after a full turn; a block under uniform
//! stretch rotated by 90° (in one step and in three) carries its stress
//! round with it.
//!
//! Every node's velocity is prescribed to the value for which the scheme's
//! position update (`SchemeWeights::velocity_reaching`) lands it exactly on
//! the rotated position, so the motion is the same for every scheme while
//! the velocities (and the paper's `Δt D(Vⁿ⁺¹)`) differ. Before the fix the
//! stress came from `Δt D(Vⁿ⁺¹)`: under backward Euler the velocity
//! `(R − I) X / Δt` has `sym grad V = (1 − cos θ) I / Δt`, a spurious
//! dilatation of 12 % of a strain per 0.5 rad step.

use crate::common;

use pfem_assembly::{Constraints, StepMesh};
use pfem_constitutive::{History, Hypoelastic, Material};
use pfem_core::{simplex_measure, Const, Dim, Point, Tensor, Vector};
use pfem_time::{Integrator, ParticleState, Scheme, SchemeWeights, StepInput, StepParams};

const SCHEMES: [Scheme; 3] = [Scheme::Newmark, Scheme::Bossak, Scheme::BackwardEuler];

/// Rotation by `theta` about z in 2D, about the unit axis (1, 2, 3)/√14 in 3D.
fn rotation<const D: usize>(theta: f64) -> Tensor<D>
where
    Const<D>: Dim,
{
    let (s, c) = theta.sin_cos();
    let mut r = Tensor::<D>::identity();
    if D == 2 {
        r[(0, 0)] = c;
        r[(0, 1)] = -s;
        r[(1, 0)] = s;
        r[(1, 1)] = c;
    } else {
        let n = [1.0, 2.0, 3.0].map(|x: f64| x / 14f64.sqrt());
        let mut k = Tensor::<D>::zeros();
        k[(0, 1)] = -n[2];
        k[(0, 2)] = n[1];
        k[(1, 0)] = n[2];
        k[(1, 2)] = -n[0];
        k[(2, 0)] = -n[1];
        k[(2, 1)] = n[0];
        r += k * s + k * k * (1.0 - c);
    }
    r
}

/// A unit block of solid elements with every node's velocity prescribed.
struct Block<const D: usize>
where
    Const<D>: Dim,
{
    state: ParticleState<D>,
    elements: Vec<u32>,
    material_of: Vec<u16>,
    history: Vec<History<D>>,
    materials: Vec<Box<dyn Material<D>>>,
    integrator: Integrator<D>,
    scheme: Scheme,
    time: f64,
}

impl<const D: usize> Block<D>
where
    Const<D>: Dim,
{
    fn new(x: Vec<Point<D>>, elements: Vec<u32>, scheme: Scheme) -> Self {
        let ne = elements.len() / (D + 1);
        Self {
            state: ParticleState::at_rest(x),
            elements,
            material_of: vec![0; ne],
            history: vec![History::default(); ne],
            materials: vec![Box::new(Hypoelastic::new(1000.0, 1.0e6, 0.3).unwrap())],
            integrator: Integrator::new(StepParams {
                scheme,
                ..Default::default()
            }),
            scheme,
            time: 0.0,
        }
    }

    fn centre(&self) -> Point<D> {
        let n = self.state.len() as f64;
        self.state
            .x
            .iter()
            .fold(Point::<D>::zeros(), |s, p| s + p / n)
    }

    /// One step that moves every node to `map(x)`.
    fn step_to(&mut self, map: impl Fn(&Point<D>) -> Point<D>) {
        let dt = 0.01;
        let w = SchemeWeights::new(self.scheme, -0.3, dt);
        let n = self.state.len();
        let mut constraints = Constraints::<D>::free(n);
        for p in 0..n {
            let s = &self.state;
            let v = w.velocity_reaching(&s.x[p], &s.v[p], &s.a[p], &map(&s.x[p]));
            constraints.fix(p, v);
        }
        let input = StepInput {
            mesh: StepMesh {
                elements: &self.elements,
                element_material: &self.material_of,
                closures: &[],
                surface_cuts: Default::default(),
                reference_volumes: &[],
                node_material: &[],
            },
            materials: &self.materials,
            constraints: &constraints,
            body_force: None,
            external_force: &[],
        };
        let rep = self
            .integrator
            .try_step(self.time, dt, &mut self.state, &mut self.history, &input)
            .unwrap_or_else(|e| panic!("{:?}: {e}", self.scheme));
        self.time += rep.dt;
    }

    /// Rotates the block rigidly about its centre by `theta`.
    fn rotate(&mut self, theta: f64) {
        let c = self.centre();
        let r = rotation::<D>(theta);
        self.step_to(|x| c + r * (x - c));
    }

    fn volume(&self) -> f64 {
        let nv = D + 1;
        self.elements
            .chunks(nv)
            .map(|el| {
                let p: Vec<Point<D>> = el.iter().map(|&i| self.state.x[i as usize]).collect();
                simplex_measure::<D>(&p)
            })
            .sum()
    }

    /// Largest deviation of any element's stress (and σ_zz) from `expected`,
    /// relative to its norm.
    fn stress_error(&self, expected: &Tensor<D>, expected_zz: f64) -> f64 {
        let scale = expected.norm() + expected_zz.abs();
        self.history
            .iter()
            .map(|h| ((h.stress - expected).norm() + (h.stress_zz - expected_zz).abs()) / scale)
            .fold(0.0, f64::max)
    }
}

fn block<const D: usize>(scheme: Scheme) -> Block<D>
where
    Const<D>: Dim,
{
    if D == 2 {
        let (x, e) = common::grid(0.0, 0.0, 1.0, 1.0, 4, 4);
        let x = x.iter().map(|p| Point::<D>::from_fn(|i, _| p[i])).collect();
        Block::new(x, e, scheme)
    } else {
        let (x, e) = common::grid3([1.0, 1.0, 1.0], [3, 3, 3]);
        let x = x.iter().map(|p| Point::<D>::from_fn(|i, _| p[i])).collect();
        Block::new(x, e, scheme)
    }
}

/// Stretches the block uniformly (1 %, −0.5 %, 0.2 %) about its centre and
/// returns the stress it then carries, checked uniform over the elements.
fn prestress<const D: usize>(b: &mut Block<D>) -> (Tensor<D>, f64)
where
    Const<D>: Dim,
{
    let c = b.centre();
    let stretch = [1.01, 0.995, 1.002];
    b.step_to(|x| c + Vector::<D>::from_fn(|i, _| stretch[i] * (x[i] - c[i])));
    let (s0, szz0) = (b.history[0].stress, b.history[0].stress_zz);
    assert!(s0.norm() > 1e3, "the stretch left no stress: {s0}");
    let spread = b.stress_error(&s0, szz0);
    assert!(
        spread < 1e-12,
        "stress not uniform after the stretch: {spread:e}"
    );
    (s0, szz0)
}

fn spin<const D: usize>()
where
    Const<D>: Dim,
{
    for scheme in SCHEMES {
        let mut b = block::<D>(scheme);
        let (s0, szz0) = prestress(&mut b);
        let v0 = b.volume();
        // 0.5 rad per step for 12 steps, then the rest of the turn.
        let mut angle = 0.0;
        let mut worst_stress: f64 = 0.0;
        let mut worst_volume: f64 = 0.0;
        let turn = 2.0 * std::f64::consts::PI;
        while angle < turn - 1e-12 {
            let step = (turn - angle).min(0.5);
            b.rotate(step);
            angle += step;
            let r = rotation::<D>(angle);
            worst_stress = worst_stress.max(b.stress_error(&(r * s0 * r.transpose()), szz0));
            worst_volume = worst_volume.max((b.volume() / v0 - 1.0).abs());
        }
        let after_turn = b.stress_error(&s0, szz0);
        println!(
            "{D}D {scheme:?}: after a full turn in 0.5 rad steps: stress off by {after_turn:.1e}, \
             largest along the way {worst_stress:.1e}, volume off by {worst_volume:.1e}"
        );
        assert!(
            after_turn < 1e-8,
            "{scheme:?}: stress after a turn off by {after_turn:e}"
        );
        assert!(
            worst_stress < 1e-8,
            "{scheme:?}: rotated stress off by {worst_stress:e}"
        );
        assert!(
            worst_volume < 1e-8,
            "{scheme:?}: volume off by {worst_volume:e}"
        );
    }
}

#[test]
fn spinning_block_keeps_volume_and_stress_2d() {
    spin::<2>();
}

#[test]
fn spinning_block_keeps_volume_and_stress_3d() {
    spin::<3>();
}

fn stretched_quarter_turn<const D: usize>()
where
    Const<D>: Dim,
{
    let quarter = std::f64::consts::FRAC_PI_2;
    for scheme in SCHEMES {
        for steps in [1, 3] {
            let mut b = block::<D>(scheme);
            let (s0, szz0) = prestress(&mut b);
            for _ in 0..steps {
                b.rotate(quarter / steps as f64);
            }
            let r = rotation::<D>(quarter);
            let err = b.stress_error(&(r * s0 * r.transpose()), szz0);
            println!("{D}D {scheme:?}: stretched block turned 90° in {steps} step(s): stress off by {err:.1e}");
            assert!(err < 1e-8, "{scheme:?}, {steps} steps: {err:e}");
        }
    }
}

#[test]
fn stretched_block_turned_a_quarter_carries_its_stress_2d() {
    stretched_quarter_turn::<2>();
}

#[test]
fn stretched_block_turned_a_quarter_carries_its_stress_3d() {
    stretched_quarter_turn::<3>();
}
