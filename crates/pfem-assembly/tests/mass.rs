//! A solid element's lumped mass is `ρ₀ V₀` (eq. 46: `ρⁿ = ρ₀ / Jⁿ`),
//! whatever its volume at `tⁿ`, when the mesh gives its reference volume
//! (`StepMesh::reference_volumes`, which the driver fills for every solid
//! element); a fluid element's is `ρ Vⁿ`. Before, every element weighed
//! `ρ Vⁿ`, so a solid's mass drifted with its volume strain (session 40's
//! review against the paper).

use pfem_assembly::{
    Assembler, AssemblyError, AssemblyInput, Constraints, Inertia, StepMesh, VolumetricTreatment,
};
use pfem_constitutive::{History, Hypoelastic, Material, Newtonian};
use pfem_core::{Point, Vector};

/// The trapezoidal rule's inertia weights for a step `dt`.
fn trapezoidal(dt: f64) -> Inertia {
    Inertia {
        mass_factor: 2.0 / dt,
        acceleration_factor: 1.0,
        displacement_weight: 0.5 * dt,
    }
}

/// Two solid triangles (the unit square, material 0) and a fluid one
/// above them (material 1), stretched by 10 % along x at `tⁿ`: the
/// solid's area is 1.1 against 1 at the start.
fn assemble(reference_volumes: &[f64]) -> (Assembler<2>, Result<(), AssemblyError>) {
    let x0 = [
        Point::<2>::new(0.0, 0.0),
        Point::<2>::new(1.0, 0.0),
        Point::<2>::new(1.0, 1.0),
        Point::<2>::new(0.0, 1.0),
        Point::<2>::new(0.5, 1.5),
    ];
    let x: Vec<Point<2>> = x0.iter().map(|p| Point::<2>::new(1.1 * p.x, p.y)).collect();
    let elements = [0, 1, 2, 0, 2, 3, 3, 2, 4];
    let element_material = [0, 0, 1];
    let materials: Vec<Box<dyn Material<2>>> = vec![
        Box::new(Hypoelastic::new(2500.0, 1e6, 0.3).unwrap()),
        Box::new(Newtonian::water()),
    ];
    let n = x.len();
    let dt = 1e-3;
    let mut asm = Assembler::<2>::new(VolumetricTreatment::NodalAveraged);
    let prepared = asm.prepare(
        n,
        StepMesh {
            elements: &elements,
            element_material: &element_material,
            reference_volumes,
            ..Default::default()
        },
        &materials,
    );
    if let Err(e) = prepared {
        return (asm, Err(e));
    }
    let zeros = vec![Vector::<2>::zeros(); n];
    let r = asm
        .assemble(&AssemblyInput {
            x: &x,
            x_n: &x,
            v: &zeros,
            v_n: &zeros,
            a_n: &zeros,
            pressure_n: &vec![0.0; n],
            element_history: &vec![History::default(); 3],
            materials: &materials,
            constraints: &Constraints::<2>::free(n),
            body_force: None,
            dt,
            inertia: trapezoidal(dt),
            external_force: &[],
        })
        .map(|_| ());
    (asm, r)
}

#[test]
fn a_solid_element_weighs_its_reference_volume() {
    let fluid = 1000.0 * 0.5 * 1.1 * 0.5; // ρ Vⁿ of the fluid triangle
    let (asm, r) = assemble(&[0.5, 0.5]);
    r.unwrap();
    let total: f64 = asm.mass().iter().sum();
    let want = 2500.0 * 1.0 + fluid;
    assert!((total - want).abs() < 1e-9 * want, "{total} against {want}");
    // Without references every element weighs its volume at tⁿ: the
    // solid 10 % heavier.
    let (asm, r) = assemble(&[]);
    r.unwrap();
    let total: f64 = asm.mass().iter().sum();
    let stretched = 2500.0 * 1.1 + fluid;
    assert!((total - stretched).abs() < 1e-9 * stretched, "{total}");
}

#[test]
fn bad_reference_volumes_are_refused() {
    for bad in [
        &[0.5, -0.5][..],
        &[0.5, f64::NAN],
        &[0.5, 0.0],
        &[0.5, 0.5, 0.5, 0.5],
    ] {
        let (_, r) = assemble(bad);
        assert!(
            matches!(r, Err(AssemblyError::MeshMismatch { .. })),
            "{bad:?}: {r:?}"
        );
    }
}

/// After a `prepare` that fails, every assembly is refused until one
/// succeeds, an empty input too (session 42's review: the empty input met
/// the last pattern and panicked); and the internal force of a newly
/// prepared mesh is refused until it is assembled (it returned the last
/// mesh's element states on the new connectivity).
#[test]
fn a_failed_or_unassembled_prepare_is_refused_not_misread() {
    let (mut asm, r) = assemble(&[0.5, 0.5]);
    r.unwrap();
    let materials: Vec<Box<dyn Material<2>>> = vec![
        Box::new(Hypoelastic::new(2500.0, 1e6, 0.3).unwrap()),
        Box::new(Newtonian::water()),
    ];
    let mesh = |elements: &'static [u32], element_material: &'static [u16]| StepMesh {
        elements,
        element_material,
        ..Default::default()
    };
    // A particle past the set: refused, and so is an empty assembly.
    assert!(asm.prepare(5, mesh(&[0, 1, 9], &[1]), &materials).is_err());
    let dt = 1e-3;
    let empty = AssemblyInput::<2> {
        x: &[],
        x_n: &[],
        v: &[],
        v_n: &[],
        a_n: &[],
        pressure_n: &[],
        element_history: &[],
        materials: &materials,
        constraints: &Constraints::<2>::free(0),
        body_force: None,
        dt,
        inertia: trapezoidal(dt),
        external_force: &[],
    };
    assert!(matches!(
        asm.assemble(&empty),
        Err(AssemblyError::MeshMismatch { .. })
    ));
    // Nor an internal force of nothing (it returned Ok with zero forces).
    assert!(matches!(
        asm.internal_force(&empty, &mut []),
        Err(AssemblyError::MeshMismatch { .. })
    ));
    // A good mesh of one fluid triangle, prepared and not assembled: no
    // internal force.
    asm.prepare(5, mesh(&[3, 2, 4], &[1]), &materials).unwrap();
    let zeros = vec![Vector::<2>::zeros(); 5];
    let p = vec![0.0; 5];
    let input = AssemblyInput::<2> {
        x: &[Point::<2>::new(0.0, 0.0); 5],
        v: &zeros,
        pressure_n: &p,
        ..empty
    };
    let mut f = vec![Vector::<2>::zeros(); 5];
    assert!(matches!(
        asm.internal_force(&input, &mut f),
        Err(AssemblyError::MeshMismatch { .. })
    ));
}
