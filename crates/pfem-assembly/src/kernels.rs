//! Element kernels for linear simplices (triangles in 2D, tetrahedra in 3D),
//! one code path for both dimensions.
//!
//! Everything is evaluated on the current Picard iterate `x⁽ⁱ⁾` (spatial
//! gradients, current measure), which is the Updated Lagrangian form of the
//! paper's integrals over `Ωₙ` with `F`, `J` of the iterate: for a linear
//! simplex `∫_Ωₙ Grad Wᵢ F⁻¹ … J dVₙ = ∫_Ω grad Wᵢ … dv`.

use pfem_constitutive::{History, Kinematics, Material, MaterialKind, Unified};
use pfem_core::{edge_matrix, shape_gradients, Const, Dim, Point, Tensor, Vector, MAX_NV};

/// Largest local matrix dimension (`NV · D` = 12 for a tetrahedron).
pub const MAX_LOCAL: usize = MAX_NV * 3;

/// Geometry and kinematics of one element at the current iterate.
#[derive(Debug, Clone, Copy)]
pub struct ElementState<const D: usize> {
    /// Gradients of the shape functions on the current iterate, `grad Wₐ`.
    pub grads: [Vector<D>; MAX_NV],
    /// Measure (area/volume) on the current iterate (m² per m, or m³).
    pub volume: f64,
    /// Measure at `t_n`, the Updated Lagrangian reference.
    pub volume_n: f64,
    /// Kinematics handed to the material.
    pub kin: Kinematics<D>,
}

/// Shape quality `measure / R^D` of a simplex (`R` its circumradius):
/// 0.51 for the regular tetrahedron, 1.30 for the equilateral triangle,
/// 0 when flat or degenerate. The measure the alpha shape tests slivers
/// with.
pub fn shape_quality<const D: usize>(x: &[Point<D>]) -> f64
where
    Const<D>: Dim,
{
    let nv = <Const<D> as Dim>::NV;
    let m = pfem_core::simplex_measure::<D>(&x[..nv]);
    match pfem_core::circumsphere::<D>(&x[..nv]) {
        Some((_, r)) if m.is_finite() && m > 0.0 && r > 0.0 => m / r.powi(D as i32),
        _ => 0.0,
    }
}

/// Computes the element's gradients, measures and kinematics: the
/// incremental deformation gradient `F = ∂x/∂Xⁿ` (eq. 8, Updated Lagrangian
/// reference `t_n`), `J = det F` (eq. 7) and `D = sym grad_x V` (eqs. 17–18).
///
/// Returns `None` when the element is degenerate at `t_n` or at the iterate,
/// or inverted (`J ≤ 0`): the time step must then be rejected.
pub fn element_state<const D: usize>(
    x: &[Point<D>],
    x_n: &[Point<D>],
    v: &[Vector<D>],
    dt: f64,
    displacement_weight: f64,
) -> Option<ElementState<D>>
where
    Const<D>: Dim,
{
    let nv = <Const<D> as Dim>::NV;
    let mut grads = [Vector::<D>::zeros(); MAX_NV];
    let volume = shape_gradients::<D>(&x[..nv], &mut grads[..nv])?;
    let e_n = edge_matrix::<D>(&x_n[..nv]);
    let det_n = e_n.determinant();
    let volume_n = det_n * <Const<D> as Dim>::MEASURE_FACTOR;
    if volume <= 0.0 || volume_n <= 0.0 {
        return None;
    }
    let f = edge_matrix::<D>(&x[..nv]) * e_n.try_inverse()?; // eq. 8
    let j = f.determinant(); // eq. 7
    if j.is_nan() || j <= 0.0 {
        return None;
    }
    let mut l = Tensor::<D>::zeros(); // eq. 18: L = grad V
    for a in 0..nv {
        l += v[a] * grads[a].transpose();
    }
    let d = (l + l.transpose()) * 0.5; // eq. 17
    Some(ElementState {
        grads,
        volume,
        volume_n,
        kin: Kinematics {
            f,
            j,
            d,
            dt,
            displacement_weight,
        },
    })
}

/// Whether the volumetric term `𝒦 ε_v` of an element is integrated on the
/// element (the paper's literal form) or through nodal averaged volumetric
/// strain (`Gᵀ M̂⁻¹ G`, the default for fluids; see NOTES point 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum VolumetricTreatment {
    /// Nodal averaged volumetric strain for fluids, element-wise for
    /// solids: free of volumetric locking with real water.
    #[default]
    NodalAveraged,
    /// The paper's eq. 57 integrated element by element for every material.
    /// Locks on linear simplices with a real bulk modulus; kept to show it.
    ElementWise,
}

/// Local stiffness (eq. 57) of one element, `(NV·D)²` entries, row-major
/// with local dof `a·D + k`:
///
/// `K[(a,k),(b,l)] = V [ μ (gₐ·g_b δ_kl + gₐ[l] g_b[k]) + (κ − ⅔μ) gₐ[k] g_b[l] ]`
///
/// With `include_volumetric = false` the `κ` part is left out (it is then
/// assembled nodally).
pub fn element_stiffness<const D: usize>(
    st: &ElementState<D>,
    u: &Unified<D>,
    include_volumetric: bool,
    out: &mut [f64],
) where
    Const<D>: Dim,
{
    let nv = <Const<D> as Dim>::NV;
    let n = nv * D;
    let mu = u.mu;
    let lam = if include_volumetric { u.kappa } else { 0.0 } - 2.0 / 3.0 * mu;
    let vol = st.volume;
    for a in 0..nv {
        let ga = &st.grads[a];
        for b in 0..nv {
            let gb = &st.grads[b];
            let dot = ga.dot(gb);
            for k in 0..D {
                for l in 0..D {
                    let mut kv = mu * ga[l] * gb[k] + lam * ga[k] * gb[l];
                    if k == l {
                        kv += mu * dot;
                    }
                    out[(a * D + k) * n + b * D + l] = vol * kv;
                }
            }
        }
    }
}

/// Internal force of the history stress, `−∫ grad Wₐ · σ̂⁽ⁿ⁾ dv` (the
/// `−D σ̂⁽ⁿ⁾` term of eq. 55 with eq. 58), added into `out[a·D + k]`.
pub fn element_history_force<const D: usize>(
    st: &ElementState<D>,
    sigma_hat: &Tensor<D>,
    out: &mut [f64],
) where
    Const<D>: Dim,
{
    let nv = <Const<D> as Dim>::NV;
    for a in 0..nv {
        let f = sigma_hat * st.grads[a] * (-st.volume);
        for k in 0..D {
            out[a * D + k] += f[k];
        }
    }
}

/// The unified triple of an element's material at its current kinematics
/// (eq. 44). Fluids ignore the history passed here: their pressure history
/// is nodal and enters through [`element_history_force`]'s nodal analogue.
pub fn element_unified<const D: usize>(
    material: &dyn Material<D>,
    st: &ElementState<D>,
    history: &History<D>,
) -> Unified<D>
where
    Const<D>: Dim,
{
    material.unified(&st.kin, history)
}

/// Whether a material's volumetric term is assembled on the element under
/// `treatment`.
pub fn volumetric_on_element(kind: MaterialKind, treatment: VolumetricTreatment) -> bool {
    match treatment {
        VolumetricTreatment::ElementWise => true,
        VolumetricTreatment::NodalAveraged => kind == MaterialKind::Solid,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn kinematics_of_a_uniform_stretch() {
        let x_n = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(0.0, 1.0),
        ];
        let x = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.1, 0.0),
            Point::<2>::new(0.0, 1.0),
        ];
        let v = [
            Vector::<2>::zeros(),
            Vector::<2>::new(0.2, 0.0),
            Vector::<2>::zeros(),
        ];
        let st = element_state::<2>(&x, &x_n, &v, 0.5, 0.5).unwrap();
        assert_relative_eq!(st.kin.j, 1.1, epsilon = 1e-14);
        assert_relative_eq!(st.kin.f[(0, 0)], 1.1, epsilon = 1e-14);
        assert_relative_eq!(st.kin.d[(0, 0)], 0.2 / 1.1, epsilon = 1e-14);
        assert_relative_eq!(st.volume, 0.55, epsilon = 1e-14);
        assert_relative_eq!(st.volume_n, 0.5, epsilon = 1e-14);
        // Inverted iterate is refused.
        let xi = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(0.0, 1.0),
            Point::<2>::new(1.0, 0.0),
        ];
        assert!(element_state::<2>(&xi, &x_n, &v, 0.5, 0.5).is_none());
    }

    #[test]
    fn stiffness_is_symmetric_and_annihilates_rigid_translation_3d() {
        let x = [
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(1.0, 0.1, 0.0),
            Point::<3>::new(0.2, 1.0, 0.1),
            Point::<3>::new(0.1, 0.2, 1.0),
        ];
        let v = [Vector::<3>::zeros(); 4];
        let st = element_state::<3>(&x, &x, &v, 1.0, 1.0).unwrap();
        let u = Unified {
            mu: 2.0,
            kappa: 7.0,
            sigma_hat: Tensor::<3>::zeros(),
            sigma_hat_zz: 0.0,
        };
        let mut k = [0.0; 144];
        element_stiffness::<3>(&st, &u, true, &mut k);
        for i in 0..12 {
            for j in 0..12 {
                assert_relative_eq!(k[i * 12 + j], k[j * 12 + i], epsilon = 1e-12);
            }
            // a uniform velocity has no rate of deformation
            for c in 0..3 {
                let s: f64 = (0..4).map(|b| k[i * 12 + b * 3 + c]).sum();
                assert!(s.abs() < 1e-12);
            }
        }
    }
}
