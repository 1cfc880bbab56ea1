//! Patch tests of the Newmark–Picard step on irregular meshes, 2D and 3D,
//! fluid (real water) and hypoelastic solid.
//!
//! Boundary particles move with the linear velocity field `v = L x₀`, every
//! particle starts with it, `A⁰ = 0` and there is no body force. The exact
//! motion is affine, `x = x₀ + t L x₀`: the rate of deformation and the
//! deformation gradient are uniform, so is the stress, and a uniform stress
//! exerts no net force on interior particles. The discrete step must keep
//! `V = L x₀` on interior particles to round-off and keep every element's
//! stress (solid) and every node's pressure (fluid) uniform.

use crate::common;

use pfem_assembly::{Constraints, StepMesh, VolumetricTreatment};
use pfem_constitutive::{History, Hypoelastic, Material, MaterialKind, Newtonian};
use pfem_core::{Const, Dim, Point, Tensor, Vector};
use pfem_time::{Integrator, ParticleState, Scheme, StepInput, StepParams};

/// Figures of one patch test run.
#[derive(Debug)]
struct PatchResult {
    /// Largest `|V − L x₀|` over interior particles, relative to the largest `|L x₀|`.
    velocity: f64,
    /// Largest deviation of an element stress from the first element's,
    /// relative to its norm (solid; 0 for a fluid).
    stress: f64,
    /// Largest deviation of a nodal pressure from the mean, relative to
    /// the mean (fluid; 0 for a solid).
    pressure: f64,
    /// Size of the stress or pressure reached (Pa), to show it is not trivial.
    scale: f64,
}

#[allow(clippy::too_many_arguments)]
fn run_patch<const D: usize>(
    mut pts: Vec<Point<D>>,
    elems: Vec<u32>,
    l_box: [f64; D],
    grad: Tensor<D>,
    material: Box<dyn Material<D>>,
    treatment: VolumetricTreatment,
    scheme: Scheme,
    dt: f64,
    steps: usize,
) -> PatchResult
where
    Const<D>: Dim,
{
    let h = l_box[0] / 6.0;
    common::perturb_interior(&mut pts, l_box, 0.25 * h, 7);
    let nv = D + 1;
    for el in elems.chunks(nv) {
        let p: Vec<Point<D>> = el.iter().map(|&q| pts[q as usize]).collect();
        assert!(
            pfem_core::simplex_measure::<D>(&p) > 0.0,
            "perturbation inverted an element"
        );
    }
    let kind = material.kind();
    let materials = vec![material];
    let ne = elems.len() / nv;
    let mat = vec![0u16; ne];
    let mut history = vec![History::<D>::default(); ne];
    let n = pts.len();
    let exact: Vec<Vector<D>> = pts.iter().map(|p| grad * p).collect();
    let mut constraints = Constraints::<D>::free(n);
    let mut interior = vec![false; n];
    for (i, p) in pts.iter().enumerate() {
        if common::on_box_boundary(p, l_box) {
            constraints.fix(i, exact[i]);
        } else {
            interior[i] = true;
        }
    }
    assert!(interior.iter().filter(|&&b| b).count() > 10);
    let mut state = ParticleState::at_rest(pts);
    state.v.clone_from(&exact);
    let params = StepParams {
        volumetric: treatment,
        scheme,
        ..Default::default()
    };
    let mut integ = Integrator::<D>::new(params);
    let input = StepInput {
        mesh: StepMesh {
            elements: &elems,
            element_material: &mat,
            closures: &[],
            surface_cuts: Default::default(),
            reference_volumes: &[],
            node_material: &[],
        },
        materials: &materials,
        constraints: &constraints,
        body_force: None,
        external_force: &[],
    };
    let mut t = 0.0;
    for _ in 0..steps {
        let rep = integ
            .advance(t, dt, &mut state, &mut history, &input)
            .unwrap();
        assert_eq!(rep.rejections, 0, "{rep:?}");
        t += rep.dt;
    }
    let vscale = exact.iter().fold(0.0f64, |m, v| m.max(v.norm()));
    let velocity = (0..n)
        .filter(|&i| interior[i])
        .map(|i| (state.v[i] - exact[i]).norm())
        .fold(0.0f64, f64::max)
        / vscale;
    let (mut stress, mut pressure) = (0.0, 0.0);
    let scale;
    match kind {
        MaterialKind::Solid => {
            let s0 = history[0].stress;
            let z0 = history[0].stress_zz;
            scale = s0.norm();
            for hst in &history {
                let d = (hst.stress - s0).norm() + (hst.stress_zz - z0).abs();
                stress = f64::max(stress, d / scale);
            }
        }
        MaterialKind::Fluid => {
            let mean = state.pressure.iter().sum::<f64>() / n as f64;
            scale = mean.abs();
            for p in &state.pressure {
                pressure = f64::max(pressure, (p - mean).abs() / scale);
            }
        }
    }
    PatchResult {
        velocity,
        stress,
        pressure,
        scale,
    }
}

fn grad2() -> Tensor<2> {
    // Volumetric part tr L = 1.5e-2 1/s, shear and spin.
    Tensor::<2>::new(1.0e-2, 0.4e-2, -0.3e-2, 0.5e-2)
}

fn grad3() -> Tensor<3> {
    Tensor::<3>::new(
        1.0e-2, 0.4e-2, -0.2e-2, //
        -0.3e-2, 0.5e-2, 0.1e-2, //
        0.2e-2, -0.1e-2, -0.3e-2,
    )
}

fn mesh2() -> (Vec<Point<2>>, Vec<u32>, [f64; 2]) {
    let (pts, tris) = common::grid(0.0, 0.0, 0.3, 0.3, 6, 6);
    (pts, tris, [0.3, 0.3])
}

fn mesh3() -> (Vec<Point<3>>, Vec<u32>, [f64; 3]) {
    let (pts, tets) = common::grid3([0.3, 0.3, 0.3], [6, 6, 6]);
    (pts, tets, [0.3, 0.3, 0.3])
}

fn rubber() -> Hypoelastic {
    Hypoelastic::new(1100.0, 1.2e7, 0.4).unwrap()
}

/// Relative tolerance of the patch tests.
///
/// For water the floor is round-off in the pressure force `Gᵀ p`: on an
/// interior node the uniform pressure's contributions cancel only to
/// `ε p h^{D−1}`, and the divergence-free modes that take this residual are
/// held by inertia alone (`2 M / Δt`), so the velocity error is about
/// `ε p Δt / (ρ h)`, growing with the pressure reached. The runs keep the
/// pressure near 1 MPa (measured: 2D ≈ 1e-11, 3D ≈ 2e-11 relative); at
/// 10 MPa the same round-off reaches 4–6e-10.
const TOL: f64 = 1e-10;

fn check(name: &str, r: &PatchResult) {
    println!(
        "{name}: velocity {:.2e}, stress {:.2e}, pressure {:.2e} (scale {:.3e} Pa)",
        r.velocity, r.stress, r.pressure, r.scale
    );
    assert!(r.scale > 0.0, "{name}: nothing happened");
    assert!(
        r.velocity < TOL,
        "{name}: interior velocity error {:e}",
        r.velocity
    );
    assert!(r.stress < TOL, "{name}: stress not uniform {:e}", r.stress);
    assert!(
        r.pressure < TOL,
        "{name}: pressure not uniform {:e}",
        r.pressure
    );
}

#[test]
fn patch_2d_water() {
    let (p, e, l) = mesh2();
    for treatment in [
        VolumetricTreatment::NodalAveraged,
        VolumetricTreatment::ElementWise,
    ] {
        let r = run_patch::<2>(
            p.clone(),
            e.clone(),
            l,
            grad2(),
            Box::new(Newtonian::water()),
            treatment,
            Scheme::Newmark,
            0.005,
            8,
        );
        check(&format!("2D water {treatment:?}"), &r);
    }
}

#[test]
fn patch_2d_hypoelastic() {
    let (p, e, l) = mesh2();
    for scheme in [Scheme::Newmark, Scheme::BackwardEuler] {
        let r = run_patch::<2>(
            p.clone(),
            e.clone(),
            l,
            grad2(),
            Box::new(rubber()),
            VolumetricTreatment::NodalAveraged,
            scheme,
            0.01,
            8,
        );
        check(&format!("2D hypoelastic {scheme:?}"), &r);
    }
}

#[test]
fn patch_3d_water() {
    let (p, e, l) = mesh3();
    let r = run_patch::<3>(
        p,
        e,
        l,
        grad3(),
        Box::new(Newtonian::water()),
        VolumetricTreatment::NodalAveraged,
        Scheme::Newmark,
        0.005,
        8,
    );
    check("3D water", &r);
}

#[test]
fn patch_3d_hypoelastic() {
    let (p, e, l) = mesh3();
    let r = run_patch::<3>(
        p,
        e,
        l,
        grad3(),
        Box::new(rubber()),
        VolumetricTreatment::NodalAveraged,
        Scheme::Newmark,
        0.01,
        6,
    );
    check("3D hypoelastic", &r);
}

/// Pressures after two steps of water from a velocity that is not affine
/// (the two volumetric treatments then differ), the integrator built with
/// `built` and its `params.volumetric` set to `set` before the first step.
fn water_pressures(built: VolumetricTreatment, set: VolumetricTreatment) -> Vec<f64> {
    let (mut pts, elems, l) = mesh2();
    common::perturb_interior(&mut pts, l, 0.25 * l[0] / 6.0, 7);
    let n = pts.len();
    let materials: Vec<Box<dyn Material<2>>> = vec![Box::new(Newtonian::water())];
    let mat = vec![0u16; elems.len() / 3];
    let mut history = vec![History::<2>::default(); mat.len()];
    let mut constraints = Constraints::<2>::free(n);
    for (i, p) in pts.iter().enumerate() {
        if common::on_box_boundary(p, l) {
            constraints.fix(i, Vector::<2>::zeros());
        }
    }
    let mut state = ParticleState::at_rest(pts.clone());
    for (v, p) in state.v.iter_mut().zip(&pts) {
        *v = Vector::<2>::new((3.0 * p.y).sin(), (2.0 * p.x).cos() - 1.0) * 1e-3;
    }
    let mut integ = Integrator::<2>::new(StepParams {
        volumetric: built,
        ..Default::default()
    });
    integ.params.volumetric = set;
    let input = StepInput {
        mesh: StepMesh {
            elements: &elems,
            element_material: &mat,
            closures: &[],
            surface_cuts: Default::default(),
            reference_volumes: &[],
            node_material: &[],
        },
        materials: &materials,
        constraints: &constraints,
        body_force: None,
        external_force: &[],
    };
    let mut t = 0.0;
    for _ in 0..2 {
        t += integ
            .advance(t, 1e-3, &mut state, &mut history, &input)
            .unwrap()
            .dt;
    }
    state.pressure
}

#[test]
fn a_volumetric_treatment_set_after_new_is_the_steps() {
    use VolumetricTreatment::{ElementWise, NodalAveraged};
    let bits = |p: Vec<f64>| p.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let nodal = water_pressures(NodalAveraged, NodalAveraged);
    let element = water_pressures(ElementWise, ElementWise);
    assert_ne!(bits(nodal.clone()), bits(element.clone()));
    assert_eq!(
        bits(water_pressures(NodalAveraged, ElementWise)),
        bits(element)
    );
    assert_eq!(
        bits(water_pressures(ElementWise, NodalAveraged)),
        bits(nodal)
    );
}
