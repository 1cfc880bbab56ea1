//! Slivers keep their start-of-step shape (`Assembler::set_sliver_quality`,
//! ARCHITECTURE.md deviation 13): a nearly flat fluid tetrahedron whose
//! iterate passes through zero volume is assembled on its geometry at `tⁿ`
//! instead of failing the assembly, except for its volumetric terms, which
//! follow the iterate through the inversion, so that the nodal volumetric
//! strain rate of a uniform expansion stays exact; a well-shaped element
//! follows the iterate, unless its motion at `tⁿ` predicts it flat or
//! inverted at the step's end (`Assembler::set_sliver_prediction`).

use pfem_assembly::{
    Assembler, AssemblyError, AssemblyInput, Constraints, Inertia, StepMesh, VolumetricTreatment,
};
use pfem_constitutive::{History, Hypoelastic, Material, Newtonian};
use pfem_core::{Const, Dim, Point, Vector};

/// Node 2 lifts the square 0-1-2-3 by `EPS`: tetrahedron 0 (0, 1, 3, 2)
/// is a sliver (quality about 0.005); tetrahedra 1 (0, 3, 1, 4) below and
/// 2 (1, 2, 3, 5) above are well shaped.
const EPS: f64 = 0.02;

fn start() -> Vec<Point<3>> {
    vec![
        Point::<3>::new(0.0, 0.0, 0.0),
        Point::<3>::new(1.0, 0.0, 0.0),
        Point::<3>::new(1.0, 1.0, EPS),
        Point::<3>::new(0.0, 1.0, 0.0),
        Point::<3>::new(0.3, 0.3, -0.9),
        Point::<3>::new(0.7, 0.7, 0.9),
    ]
}

const TETS: [u32; 12] = [0, 1, 3, 2, 0, 3, 1, 4, 1, 2, 3, 5];

/// Assembles at the iterate `x` (start `xⁿ` = [`start`]) with the sliver
/// threshold `q`, at rest at `tⁿ`.
fn assemble(x: &[Point<3>], q: f64) -> (Assembler<3>, Result<(), AssemblyError>) {
    assemble_moving(x, q, false, &vec![Vector::<3>::zeros(); x.len()])
}

/// [`assemble`] with the velocities `v_n` at `tⁿ` and the sliver
/// prediction on or off.
fn assemble_moving(
    x: &[Point<3>],
    q: f64,
    predict: bool,
    v_n: &[Vector<3>],
) -> (Assembler<3>, Result<(), AssemblyError>) {
    let materials: Vec<Box<dyn Material<3>>> = vec![Box::new(Newtonian::water())];
    let mesh = Mesh {
        xn: &start(),
        elements: &TETS,
        element_material: &[0, 0, 0],
        materials: &materials,
    };
    assemble_mesh(&mesh, x, q, predict, v_n)
}

/// A step's mesh at `tⁿ`: positions, connectivity, materials.
struct Mesh<'a, const D: usize>
where
    Const<D>: Dim,
{
    xn: &'a [Point<D>],
    elements: &'a [u32],
    element_material: &'a [u16],
    materials: &'a [Box<dyn Material<D>>],
}

/// Assembles `mesh` at the iterate `x` (the velocity that takes `xⁿ`
/// there in `Δt` = 1 ms) with the sliver threshold `q`, the prediction on
/// or off, and the velocities `v_n` at `tⁿ`.
fn assemble_mesh<const D: usize>(
    mesh: &Mesh<'_, D>,
    x: &[Point<D>],
    q: f64,
    predict: bool,
    v_n: &[Vector<D>],
) -> (Assembler<D>, Result<(), AssemblyError>)
where
    Const<D>: Dim,
{
    assemble_configured(mesh, x, q, predict, v_n, |_| {})
}

/// [`assemble_mesh`] with the assembler further set by `configure`
/// before its first `prepare`.
fn assemble_configured<const D: usize>(
    mesh: &Mesh<'_, D>,
    x: &[Point<D>],
    q: f64,
    predict: bool,
    v_n: &[Vector<D>],
    configure: impl Fn(&mut Assembler<D>),
) -> (Assembler<D>, Result<(), AssemblyError>)
where
    Const<D>: Dim,
{
    let n = mesh.xn.len();
    let dt = 1e-3;
    let mut asm = Assembler::<D>::new(VolumetricTreatment::NodalAveraged);
    asm.set_sliver_quality(q);
    asm.set_sliver_prediction(predict);
    configure(&mut asm);
    asm.prepare(
        n,
        StepMesh {
            elements: mesh.elements,
            element_material: mesh.element_material,
            closures: &[],
            surface_cuts: Default::default(),
            reference_volumes: &[],
            node_material: &[],
        },
        mesh.materials,
    )
    .unwrap();
    let v: Vec<Vector<D>> = x.iter().zip(mesh.xn).map(|(a, b)| (a - b) / dt).collect();
    let mut g = Vector::<D>::zeros();
    g[D - 1] = -9.81;
    let r = asm
        .assemble(&AssemblyInput {
            x,
            x_n: mesh.xn,
            v: &v,
            v_n,
            a_n: &vec![Vector::<D>::zeros(); n],
            pressure_n: &vec![0.0; n],
            element_history: &vec![History::default(); mesh.element_material.len()],
            materials: mesh.materials,
            constraints: &Constraints::<D>::free(n),
            body_force: Some(g),
            dt,
            inertia: Inertia {
                mass_factor: 2.0 / dt,
                acceleration_factor: 1.0,
                displacement_weight: 0.5 * dt,
            },
            external_force: &[],
        })
        .map(|_| ());
    (asm, r)
}

#[test]
fn a_sliver_that_inverts_within_the_step_keeps_its_start_shape() {
    let quality = |t: &[u32]| {
        pfem_assembly::kernels::shape_quality::<3>(
            &t.iter().map(|&i| start()[i as usize]).collect::<Vec<_>>(),
        )
    };
    let q = quality(&TETS[..4]);
    assert!(q > 0.0 && q < 0.01, "sliver quality {q}");
    for t in TETS[4..].chunks(4) {
        assert!(quality(t) > 0.1, "{t:?}: quality {}", quality(t));
    }
    // The iterate pushes node 2 through the plane of 0, 1, 3 and moves
    // node 4 a little.
    let mut x = start();
    x[2].z = -EPS;
    x[4].z -= 0.01;
    // Without the threshold the sliver inverts the assembly.
    let (_, off) = assemble(&x, 0.0);
    assert!(matches!(
        off,
        Err(AssemblyError::InvertedElement { element: 0, .. })
    ));
    // With it, only the sliver keeps its start shape.
    let (asm, on) = assemble(&x, 0.06);
    on.unwrap();
    assert!(asm.is_frozen(0) && !asm.is_frozen(1) && !asm.is_frozen(2));
    // Its volumetric terms are the iterate's: a uniform expansion
    // `v = x` has the nodal volumetric strain rate 3 at every node, node 2
    // (whose patch holds the inverted sliver) included.
    let mut rates = Vec::new();
    let v: Vec<Vector<3>> = x.clone();
    asm.nodal_volumetric_rates(&v, &mut rates);
    assert_eq!(rates.len(), 6);
    for r in &rates {
        assert!(
            (r.rate - 3.0).abs() < 1e-12,
            "node {}: {}",
            r.particle,
            r.rate
        );
    }
}

/// A well-shaped tetrahedron that the motion at `tⁿ` flattens within the
/// step (issue 18, item 3: the rejected attempts of the column on a
/// cylinder at a/14 were such elements, quality 0.06–0.18 at `tⁿ`): with
/// the prediction it is treated as a sliver from the step's first
/// assembly, and the iterate that inverts it no longer fails the
/// assembly.
#[test]
fn a_tetrahedron_foreseen_flat_keeps_its_start_shape() {
    let quality = pfem_assembly::kernels::shape_quality::<3>(
        &TETS[8..]
            .iter()
            .map(|&i| start()[i as usize])
            .collect::<Vec<_>>(),
    );
    assert!(quality > 0.1, "tetrahedron 2: quality {quality}");
    // Node 5, the apex of tetrahedron 2, falls through the plane of 1, 2,
    // 3 within the step: predicted at z = -0.1 at its end, and the iterate
    // puts it there.
    let dt = 1e-3;
    let mut v_n = vec![Vector::<3>::zeros(); 6];
    v_n[5].z = -1.0 / dt;
    let mut x = start();
    x[5].z = -0.1;
    let (_, off) = assemble_moving(&x, 0.06, false, &v_n);
    assert!(matches!(
        off,
        Err(AssemblyError::InvertedElement { element: 2, .. })
    ));
    let (asm, on) = assemble_moving(&x, 0.06, true, &v_n);
    on.unwrap();
    // The sliver 0 as before, and tetrahedron 2 foreseen; 1 follows the
    // iterate.
    assert!(asm.is_frozen(0) && !asm.is_frozen(1) && asm.is_frozen(2));
    // Nothing moving at tⁿ: the prediction adds nothing.
    let (asm, _) = assemble_moving(&start(), 0.06, true, &[Vector::<3>::zeros(); 6]);
    assert!(asm.is_frozen(0) && !asm.is_frozen(1) && !asm.is_frozen(2));
}

/// A sliver kept in shape carries the pressure stabilisation on its
/// shape at `tⁿ` when that shape is fair
/// (`Assembler::set_sliver_stabilisation`, issue 18, session 30): with
/// `Some(0.02)` tetrahedron 2, foreseen flat but of quality above 0.1 at
/// `tⁿ`, does; the sliver 0, flat at `tⁿ` (quality 0.005), never does; with
/// `None` neither does. Tetrahedron 1, which follows the iterate, carries
/// it either way.
#[test]
fn a_sliver_of_fair_start_shape_carries_the_stabilisation() {
    use std::collections::HashMap;
    let dt = 1e-3;
    let mut v_n = vec![Vector::<3>::zeros(); 6];
    v_n[5].z = -1.0 / dt;
    // The first iterate, at the start: node 5's nodal measure (tetrahedron
    // 2's alone) is positive, so its row of `L̃` can be.
    let x = start();
    let materials: Vec<Box<dyn Material<3>>> = vec![Box::new(Newtonian::water())];
    let xn = start();
    let mesh = Mesh {
        xn: &xn,
        elements: &TETS,
        element_material: &[0, 0, 0],
        materials: &materials,
    };
    // The entries of `L̃`, by the particles of their row and column.
    let couplings = |from: Option<f64>| -> HashMap<(u32, u32), f64> {
        let (asm, r) = assemble_configured(&mesh, &x, 0.06, true, &v_n, |a| {
            a.set_split(true);
            a.set_pressure_stabilisation(1.0);
            a.set_sliver_stabilisation(from);
        });
        r.unwrap();
        assert!(asm.is_frozen(0) && !asm.is_frozen(1) && asm.is_frozen(2));
        let sys = asm.split_system().unwrap();
        let st = sys.stabilisation.unwrap();
        let ids = st.row_ids.unwrap();
        let mut out = HashMap::new();
        for i in 0..ids.len() {
            for k in st.l_ptr[i]..st.l_ptr[i + 1] {
                out.insert((ids[i], ids[st.l_idx[k]]), st.l_val[k]);
            }
        }
        out
    };
    let none = couplings(None);
    let fair = couplings(Some(0.02));
    let at = |m: &HashMap<(u32, u32), f64>, a, b| m.get(&(a, b)).copied().unwrap_or(0.0);
    // Node 5 belongs to tetrahedron 2 alone.
    for b in 0..6 {
        assert_eq!(at(&none, 5, b), 0.0, "(5, {b}) without");
    }
    assert!(at(&fair, 5, 5) > 0.0, "(5, 5) with: {}", at(&fair, 5, 5));
    assert!(at(&fair, 1, 5) != 0.0);
    // The edge 0-2 belongs to the sliver 0 alone.
    assert_eq!(at(&none, 0, 2), 0.0);
    assert_eq!(at(&fair, 0, 2), 0.0);
    // Node 4 belongs to tetrahedron 1 alone.
    let (a, b) = (at(&none, 4, 4), at(&fair, 4, 4));
    assert!(a > 0.0 && (a - b).abs() <= 1e-12 * a, "{a} against {b}");
    // A threshold above its quality at `tⁿ` leaves tetrahedron 2 out again.
    assert_eq!(at(&couplings(Some(0.45)), 5, 5), 0.0);
}

/// Two triangles on the edge 1-2: triangle 0 (0, 1, 2) well shaped,
/// triangle 1 (1, 3, 2) nearly flat (node 3 a hundredth of the edge off
/// it, quality about 0.04).
fn start_2d() -> Vec<Point<2>> {
    vec![
        Point::<2>::new(0.0, 0.0),
        Point::<2>::new(1.0, 0.0),
        Point::<2>::new(0.0, 1.0),
        Point::<2>::new(0.5 + 0.01, 0.5 + 0.01),
    ]
}

const TRIS: [u32; 6] = [0, 1, 2, 1, 3, 2];

/// The 2D analogue of [`assemble_moving`] (start [`start_2d`]).
fn assemble_2d(
    x: &[Point<2>],
    q: f64,
    predict: bool,
    v_n: &[Vector<2>],
) -> (Assembler<2>, Result<(), AssemblyError>) {
    let materials: Vec<Box<dyn Material<2>>> = vec![Box::new(Newtonian::water())];
    let mesh = Mesh {
        xn: &start_2d(),
        elements: &TRIS,
        element_material: &[0, 0],
        materials: &materials,
    };
    assemble_mesh(&mesh, x, q, predict, v_n)
}

/// Deviation 13 in 2D (session 19): the 2D dam break rejected 15 % of its
/// attempts for inverted triangles. A flat triangle whose iterate inverts
/// keeps its start shape; a fair one that the motion at `tⁿ` pushes
/// through its opposite edge is foreseen.
#[test]
fn a_triangle_flat_or_foreseen_flat_keeps_its_start_shape() {
    let q = |t: &[u32]| {
        pfem_assembly::kernels::shape_quality::<2>(
            &t.iter()
                .map(|&i| start_2d()[i as usize])
                .collect::<Vec<_>>(),
        )
    };
    assert!(q(&TRIS[..3]) > 0.9, "triangle 0: {}", q(&TRIS[..3]));
    assert!(q(&TRIS[3..]) < 0.05, "triangle 1: {}", q(&TRIS[3..]));
    // Node 3 crosses the edge 1-2 (triangle 1 inverts): failed without the
    // rule, kept in shape with it.
    let mut x = start_2d();
    x[3] = Point::<2>::new(0.49, 0.49);
    let still = vec![Vector::<2>::zeros(); 4];
    let (_, off) = assemble_2d(&x, 0.0, false, &still);
    assert!(matches!(
        off,
        Err(AssemblyError::InvertedElement { element: 1, .. })
    ));
    let (asm, on) = assemble_2d(&x, 0.05, false, &still);
    on.unwrap();
    assert!(!asm.is_frozen(0) && asm.is_frozen(1));
    // Node 0 moving at tⁿ towards the far side of edge 1-2: triangle 0,
    // fair at tⁿ, is foreseen inverted and kept in shape too.
    let dt = 1e-3;
    let mut v_n = still.clone();
    v_n[0] = Vector::<2>::new(0.8, 0.8) / dt;
    let mut x = start_2d();
    x[0] = Point::<2>::new(0.8, 0.8);
    let (_, off) = assemble_2d(&x, 0.05, false, &v_n);
    assert!(matches!(
        off,
        Err(AssemblyError::InvertedElement { element: 0, .. })
    ));
    let (asm, on) = assemble_2d(&x, 0.05, true, &v_n);
    on.unwrap();
    assert!(asm.is_frozen(0) && asm.is_frozen(1));
}

/// A flat fluid triangle with a particle of a solid element is not kept in
/// shape: a film of water between two bodies must be squeezed out, which
/// needs its flattened elements to reject the step (the heavy box of
/// `tests/stability_fsi.rs` stopped on its film otherwise).
#[test]
fn a_flat_triangle_touching_a_solid_is_not_kept_in_shape() {
    // Triangles 0 and 1 as in `start_2d`, and a solid triangle 2 (3, 4, 5)
    // beyond node 3.
    let mut xn = start_2d();
    xn.push(Point::<2>::new(1.5, 1.0));
    xn.push(Point::<2>::new(1.0, 1.5));
    let elements: [u32; 9] = [0, 1, 2, 1, 3, 2, 3, 4, 5];
    let n = xn.len();
    let materials: Vec<Box<dyn Material<2>>> = vec![
        Box::new(Newtonian::water()),
        Box::new(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap()),
    ];
    let assemble = |solid: bool| {
        // Node 3 crosses the edge 1-2 (triangle 1 inverts), dragging the
        // third triangle along.
        let mut x = xn.clone();
        for p in [3, 4, 5] {
            x[p] -= Vector::<2>::new(0.02, 0.02);
        }
        let mesh = Mesh {
            xn: &xn,
            elements: &elements,
            element_material: &[0, 0, if solid { 1 } else { 0 }],
            materials: &materials,
        };
        assemble_mesh(&mesh, &x, 0.05, false, &vec![Vector::<2>::zeros(); n])
    };
    // All fluid: triangle 1 is kept in shape and the assembly succeeds.
    let (asm, r) = assemble(false);
    r.unwrap();
    assert!(asm.is_frozen(1));
    // Node 3 in a solid element: triangle 1 follows the iterate and
    // inverts.
    let (asm, r) = assemble(true);
    assert!(!asm.is_frozen(1));
    assert!(matches!(
        r,
        Err(AssemblyError::InvertedElement { element: 1, .. })
    ));
}
