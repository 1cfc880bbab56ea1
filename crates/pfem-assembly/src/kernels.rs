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
/// strain (`Gᵀ M̂⁻¹ G`, the default for fluids; ARCHITECTURE.md, deviation 1).
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
///
/// A layer ([`Unified::layer`]: normal `n`, resisting tangential
/// directions `Q`, the contact penalty) has `2 μ P(ε)` in place of
/// `2 μ ε'`:
///
/// `K[(a,k),(b,l)] = V [ μ S + κ gₐ[k] g_b[l] ]`,
/// `S = Q_kl aₙ bₙ + (Q g_b)[k] n_l aₙ + n_k (Q gₐ)[l] bₙ + n_k n_l gₐ·Q g_b`,
/// `aₙ = gₐ·n`, `bₙ = g_b·n`.
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
    let vol = st.volume;
    if let Some(layer) = u.layer {
        let kappa = if include_volumetric { u.kappa } else { 0.0 };
        let nrm = layer.normal;
        let q = layer.resisting();
        for a in 0..nv {
            let ga = &st.grads[a];
            let an = ga.dot(&nrm);
            let qa = q * ga;
            for b in 0..nv {
                let gb = &st.grads[b];
                let bn = gb.dot(&nrm);
                let qb = q * gb;
                let aqb = ga.dot(&qb);
                for k in 0..D {
                    for l in 0..D {
                        let shear = q[(k, l)] * an * bn
                            + qb[k] * nrm[l] * an
                            + nrm[k] * qa[l] * bn
                            + nrm[k] * nrm[l] * aqb;
                        out[(a * D + k) * n + b * D + l] =
                            vol * (mu * shear + kappa * ga[k] * gb[l]);
                    }
                }
            }
        }
        return;
    }
    let lam = if include_volumetric { u.kappa } else { 0.0 } - 2.0 / 3.0 * mu;
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
/// (eq. 44). A fluid's `σ̂` is not used: its pressure history is nodal and
/// enters through [`element_history_force`]'s nodal analogue (the
/// assembly hands a fluid element its nodes' mean pressure, which its `μ`
/// or `𝒦` may read).
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
    use pfem_constitutive::Layer;

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

    /// A tetrahedron of no symmetry.
    fn skewed_tetrahedron() -> [Point<3>; 4] {
        [
            Point::<3>::new(0.0, 0.0, 0.0),
            Point::<3>::new(1.0, 0.1, 0.0),
            Point::<3>::new(0.2, 1.0, 0.1),
            Point::<3>::new(0.1, 0.2, 1.0),
        ]
    }

    #[test]
    fn stiffness_is_symmetric_and_annihilates_rigid_translation_3d() {
        let x = skewed_tetrahedron();
        let v = [Vector::<3>::zeros(); 4];
        let st = element_state::<3>(&x, &x, &v, 1.0, 1.0).unwrap();
        let u = Unified::new(2.0, 7.0, Tensor::<3>::zeros(), 0.0);
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

    /// `K v` is the force `V σ_lin gₐ` of the linear stress
    /// (`Unified::linear_stress`) at the rate the velocities `v` give.
    fn stiffness_is_the_linear_stress<const D: usize>(
        x: &[Point<D>],
        v: &[Vector<D>],
        u: &Unified<D>,
    ) where
        Const<D>: Dim,
    {
        let nv = <Const<D> as Dim>::NV;
        let n = nv * D;
        let st = element_state::<D>(x, x, v, 1.0, 1.0).unwrap();
        let mut k = vec![0.0; n * n];
        element_stiffness::<D>(&st, u, true, &mut k);
        let sigma = u.linear_stress(&st.kin).0;
        let scale = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for a in 0..nv {
            let f = sigma * st.grads[a] * st.volume;
            for kk in 0..D {
                let kv: f64 = (0..nv)
                    .flat_map(|b| (0..D).map(move |l| (b, l)))
                    .map(|(b, l)| k[(a * D + kk) * n + b * D + l] * v[b][l])
                    .sum();
                assert!(
                    (kv - f[kk]).abs() <= 1e-12 * scale,
                    "{a} {kk}: {kv} {}",
                    f[kk]
                );
            }
        }
        for i in 0..n {
            for j in 0..n {
                assert!((k[i * n + j] - k[j * n + i]).abs() <= 1e-12 * scale);
            }
        }
    }

    #[test]
    fn a_layer_resists_only_the_shear_across_its_plane() {
        let x2 = [
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 0.1),
            Point::<2>::new(0.2, 0.9),
        ];
        let v2 = [
            Vector::<2>::new(0.3, -0.2),
            Vector::<2>::new(-0.1, 0.4),
            Vector::<2>::new(0.5, 0.05),
        ];
        let n2 = Vector::<2>::new(0.6, 0.8);
        let layer2 = Unified {
            layer: Some(Layer {
                normal: n2,
                slip: Vector::<2>::zeros(),
            }),
            ..Unified::new(2.0, 7.0, Tensor::<2>::zeros(), 0.0)
        };
        stiffness_is_the_linear_stress::<2>(&x2, &v2, &layer2);
        stiffness_is_the_linear_stress::<2>(
            &x2,
            &v2,
            &Unified::new(2.0, 7.0, Tensor::<2>::zeros(), 0.0),
        );
        let x3 = skewed_tetrahedron();
        let v3 = [
            Vector::<3>::new(0.3, -0.2, 0.1),
            Vector::<3>::new(-0.1, 0.4, 0.0),
            Vector::<3>::new(0.5, 0.05, -0.3),
            Vector::<3>::new(0.0, 0.2, 0.7),
        ];
        let n3 = Vector::<3>::new(2.0, -1.0, 2.0) / 3.0;
        let t = Vector::<3>::new(1.0, 2.0, 0.0) / 5f64.sqrt();
        let layer3 = Unified {
            layer: Some(Layer {
                normal: n3,
                slip: Vector::<3>::zeros(),
            }),
            ..Unified::new(2.0, 0.0, Tensor::<3>::zeros(), 0.0)
        };
        stiffness_is_the_linear_stress::<3>(&x3, &v3, &layer3);
        // Slipping along m = n × t: only the shear along t resists.
        let m = n3.cross(&t).normalize();
        let slipping = Unified {
            layer: Some(Layer {
                normal: n3,
                slip: m,
            }),
            ..Unified::new(2.0, 7.0, Tensor::<3>::zeros(), 0.0)
        };
        stiffness_is_the_linear_stress::<3>(&x3, &v3, &slipping);
        let mut kin = pfem_constitutive::Kinematics::<3>::at_rest(1.0);
        kin.d = (m * n3.transpose() + n3 * m.transpose()) * 0.5;
        assert!(slipping.linear_stress(&kin).0.norm() < 1e-14);
        kin.d = (t * n3.transpose() + n3 * t.transpose()) * 0.5;
        let s = slipping.linear_stress(&kin).0;
        assert!((t.dot(&(s * n3)) - 2.0).abs() < 1e-14);
        // Its stress: shear across the plane only. A stretch along the
        // plane (t ⊥ n) and a normal stretch give nothing with 𝒦 = 0; a
        // shear t–n gives 2 μ γ on (t, n).
        let mut kin = pfem_constitutive::Kinematics::<3>::at_rest(1.0);
        for d in [t * t.transpose(), n3 * n3.transpose()] {
            kin.d = d;
            assert!(layer3.linear_stress(&kin).0.norm() < 1e-14);
        }
        kin.d = (t * n3.transpose() + n3 * t.transpose()) * 0.5;
        let s = layer3.linear_stress(&kin).0;
        assert!((t.dot(&(s * n3)) - 2.0).abs() < 1e-14);
        assert!(t.dot(&(s * t)).abs() < 1e-14 && n3.dot(&(s * n3)).abs() < 1e-14);
    }
}
