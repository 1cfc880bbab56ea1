//! Loads and pressures the fluid puts on bodies, measured on a
//! simulation: what probes and the VTU output read.

use pfem_core::{Const, Dim, ParticleKind, Point, Vector};
use pfem_driver::{RunError, Simulation};

/// Measurements of the fluid's action on a [`Simulation`]: the water's
/// pressure at every particle and the pressure force on a body. In the
/// prelude of `pfem`.
pub trait Loads<const D: usize>
where
    Const<D>: Dim,
{
    /// See the implementation for [`Simulation`].
    fn pressure_force_on(&self, name: &str) -> Result<Vector<D>, RunError>;
    /// See the implementation for [`Simulation`].
    fn water_pressure(&self) -> Vec<f64>;
    /// See the implementation for [`Simulation`].
    fn fluid_at(&self, at: &Point<D>) -> Option<(f64, Vector<D>)>;
    /// See the implementation for [`Simulation`].
    fn fluid_at_points(&self, at: &[Point<D>]) -> Vec<Option<(f64, Vector<D>)>> {
        at.iter().map(|q| self.fluid_at(q)).collect()
    }
    /// See the implementation for [`Simulation`].
    fn contact_force(&self, on: &str, from: &str) -> Result<ContactForce<D>, RunError>;
}

/// The contact force one body exerts on another ([`Loads::contact_force`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactForce<const D: usize>
where
    Const<D>: Dim,
{
    /// The force (N; N per metre in 2D).
    pub force: Vector<D>,
    /// Its component along the mean contact normal (pointing into the
    /// body acted on; positive when it pushes) (N; N per metre in 2D).
    pub normal: f64,
    /// The magnitude of the rest (friction) (N; N per metre in 2D).
    pub tangential: f64,
    /// Contact elements between the two bodies that carry a pressure.
    pub active: usize,
}

impl<const D: usize> Loads<D> for Simulation<D>
where
    Const<D>: Dim,
{
    /// The fluid's pressure (Pa) and velocity (m/s) at the fixed point
    /// `at`: linear interpolation of the nodal values in the fluid element
    /// that holds it (eq. 62's nodal pressure, the particles' velocities);
    /// `None` where no fluid element does (a dry point, or outside the
    /// fluid). A point probe.
    fn fluid_at(&self, at: &Point<D>) -> Option<(f64, Vector<D>)> {
        // (The elements of a set changed by hand name the old set's
        // particles: nothing is read from them, session 49.)
        if !self.is_meshed() {
            return None;
        }
        let nv = D + 1;
        let x = self.particles().x();
        let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
        let mut g = [Vector::<D>::zeros(); pfem_core::MAX_NV];
        for el in self.elements().fluid().chunks_exact(nv) {
            for a in 0..nv {
                p[a] = x[el[a] as usize];
            }
            if !in_box(&p[..nv], at) {
                continue;
            }
            if pfem_core::shape_gradients::<D>(&p[..nv], &mut g[..nv]).is_none() {
                continue;
            }
            if let Some(found) = interpolate(self, el, &p[..nv], &g[..nv], at) {
                return Some(found);
            }
        }
        None
    }

    /// [`Loads::fluid_at`] at many points in one pass over the fluid
    /// elements (the points bucketed on a grid of the largest fluid
    /// spacing, `pfem_scene::lattice::PointGrid`): each point's value is the one `fluid_at` gives it, bit for
    /// bit (the first element that holds it, in the elements' order). What
    /// a scene's point probes read each row: 900 gauges cost one pass, not
    /// 900.
    fn fluid_at_points(&self, at: &[Point<D>]) -> Vec<Option<(f64, Vector<D>)>> {
        let mut out = vec![None; at.len()];
        if !self.is_meshed() {
            return out;
        }
        let nv = D + 1;
        let (x, kind) = (self.particles().x(), self.particles().kind());
        let cell = (0..self.particles().len())
            .filter(|&i| kind[i] == ParticleKind::Fluid)
            .map(|i| self.particles().spacing()[i])
            .fold(0.0, f64::max);
        // A point that is not finite lies in no element (`fluid_at` gives
        // it `None` too): the finite ones are looked for.
        let finite: Vec<u32> = (0..at.len() as u32)
            .filter(|&i| at[i as usize].iter().all(|v| v.is_finite()))
            .collect();
        let mut left = finite.len();
        if left == 0 {
            return out;
        }
        let grid = (cell > 0.0 && cell.is_finite()).then(|| {
            let points: Vec<Point<D>> = finite.iter().map(|&i| at[i as usize]).collect();
            pfem_scene::lattice::PointGrid::new(&points, cell)
        });
        let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
        let mut g = [Vector::<D>::zeros(); pfem_core::MAX_NV];
        let mut candidates: Vec<u32> = Vec::new();
        for el in self.elements().fluid().chunks_exact(nv) {
            if left == 0 {
                break;
            }
            for a in 0..nv {
                p[a] = x[el[a] as usize];
            }
            candidates.clear();
            match &grid {
                Some(grid) => {
                    let (mut lo, mut hi) = (Point::<D>::zeros(), Point::<D>::zeros());
                    for d in 0..D {
                        lo[d] = p[..nv].iter().map(|q| q[d]).fold(f64::INFINITY, f64::min);
                        hi[d] = p[..nv]
                            .iter()
                            .map(|q| q[d])
                            .fold(f64::NEG_INFINITY, f64::max);
                    }
                    grid.for_each_in(&lo, &hi, &mut |k| {
                        let i = finite[k as usize];
                        if out[i as usize].is_none() {
                            candidates.push(i);
                        }
                    });
                }
                None => candidates.extend(finite.iter().filter(|&&i| out[i as usize].is_none())),
            }
            candidates.retain(|&i| in_box(&p[..nv], &at[i as usize]));
            if candidates.is_empty() {
                continue;
            }
            if pfem_core::shape_gradients::<D>(&p[..nv], &mut g[..nv]).is_none() {
                continue;
            }
            for &i in &candidates {
                if let Some(found) = interpolate(self, el, &p[..nv], &g[..nv], &at[i as usize]) {
                    out[i as usize] = Some(found);
                    left -= 1;
                }
            }
        }
        out
    }

    /// The force body `from` exerts on body `on` through their contact
    /// elements at the end of the last step: each element's stress `σ`
    /// (`−p I + τ ⊗ n + n ⊗ τ`, constant in the simplex) gives its particles
    /// the nodal forces `−V σ ∇N_a`, summed over the particles of `on`.
    /// The normal is the mean of the elements' normals, oriented into
    /// `on`; [`RunError::UnknownBody`] for a name no body has. Zero when
    /// the two do not touch (or the scene has no contact stage).
    fn contact_force(&self, on: &str, from: &str) -> Result<ContactForce<D>, RunError> {
        let (a, b) = (self.body_id(on)?, self.body_id(from)?);
        not_meshed(self)?;
        let body = self.particles().body();
        let mut force = Vector::<D>::zeros();
        let mut normal = Vector::<D>::zeros();
        let mut active = 0;
        let elements = self.elements();
        let (history, pairs) = (elements.contact_history(), elements.contact_bodies());
        let mut last = None;
        elements.contact_nodal_forces(
            self.particles().x(),
            // The pair's elements that push (an open one has no stress).
            |e| {
                let pair = pairs[e];
                ((pair.0 == a && pair.1 == b) || (pair.0 == b && pair.1 == a))
                    && history[e].stress.trace() < 0.0
            },
            |e, i, f| {
                if last != Some(e) {
                    last = Some(e);
                    active += 1;
                    // The element's normal points from its master into the
                    // other body: into `on` when `on` is not the master.
                    let n = Vector::<D>::from_fn(|k, _| {
                        history[e].internal[pfem_constitutive::contact::NORMAL + k]
                    });
                    normal += if pairs[e].0 == a { -n } else { n };
                }
                if body[i] == a {
                    force += f;
                }
            },
        );
        let (fn_, ft) = if normal.norm() > 0.0 {
            let n = normal / normal.norm();
            let f_n = force.dot(&n);
            (f_n, (force - n * f_n).norm())
        } else {
            (0.0, force.norm())
        };
        Ok(ContactForce {
            force,
            normal: fn_,
            tangential: ft,
            active,
        })
    }

    /// Pressure force the fluid exerts on body `name` (N, per metre of depth
    /// in 2D), or [`RunError::UnknownBody`]: at each of the body's particles
    /// `i`, the nodal pressure force `Gᵀ p` of eq. 58,
    /// `Σ_e Σ_{a∈e} p_a (∫_e W_a) grad W_i` over the fluid elements `e`
    /// holding `i`, plus the weight less the inertia of the fluid mass those
    /// elements lump on `i`, `Σ_e ρ_e (∫_e W_i) (g − aᵢ)`; `∫_e W_a` is
    /// `V_e/(D+1)`, or over the part below the water line of an element
    /// cut at a free solid's (as the assembly integrates it). The lumped mass
    /// puts part of the adjacent fluid's weight on the body's nodes, where
    /// the nodal pressure force holds it up; without the second term a
    /// block held under water at rest read its buoyancy +40 % (issue 13;
    /// `tests/water_at_rest_2d.rs` checks it to 2 %). The closures of
    /// sealed voids add their pressure force (3D; without them a 3D block
    /// read 12 N sideways and +47 % up, `tests/water_at_rest_3d.rs`).
    /// The wall pockets of deviation 9 (3D: the water in a wall corner's
    /// lattice cell that the tessellation split into wall-only simplices)
    /// add their weight less inertia and pressure force, `w (ρ (V/(D+1))
    /// (g − aᵢ) + p̄ V grad W_i)` (see `pocket_force`): the walls of a tank
    /// at rest then sum to `ρ g` times the `volume` probe, and a wall's
    /// thrust no longer jumps as round-off splits the corners' cells
    /// another way (without them the walls of a cube of water 0.2 m on a
    /// side summed to 4.9 % less than its weight, and a wall's thrust moved
    /// from 30.26 to 34.34 N as the corners' ties flipped while its mirror
    /// read 33.21 N;
    /// `water_at_rest_3d::a_3d_tank_s_walls_feel_the_weight_and_thrust_whatever_the_corners`).
    /// A body's force is its own particles': where walls meet, the
    /// particles of the corner lines carry their share of both faces to
    /// the body that holds them, and where three walls meet, a face of the
    /// corner's cell shared by all three splits `p h²/6` between two of
    /// them as its diagonal falls (1.7 % of a wall's thrust in a tank four
    /// spacings deep, 0.19 % at eight; a review). The viscous part is
    /// left out (negligible for water). The inertia is the last
    /// acceleration's, `m aⁿ⁺¹`: under Bossak's scheme the step
    /// balanced `m [(1 − α_B) aⁿ⁺¹ + α_B aⁿ]`, so a force that changes
    /// fast reads slightly off the one the step transmitted (as
    /// `pfem::cases3d::fluid_force` measures).
    fn pressure_force_on(&self, name: &str) -> Result<Vector<D>, RunError> {
        let id = self.body_id(name)?;
        not_meshed(self)?;
        let nv = D + 1;
        let (x, a, pressure) = (
            self.particles().x(),
            self.particles().a(),
            self.particles().pressure(),
        );
        let body = self.particles().body();
        let gravity = self.gravity().unwrap_or_else(Vector::<D>::zeros);
        // The elements cut at a free solid's water line count their part
        // below it, as the assembly does (before session 49 they counted
        // whole: the dry nodes' drifting pressures weighed in, and a
        // floating block read 10 times its weight, a review).
        let (cuts, up) = self.elements().fluid_surface_cuts();
        let mut cut_of = vec![0u8; self.elements().fluid().len() / nv];
        for (e, mask) in cuts {
            cut_of[e] = mask;
        }
        let mut f = Vector::<D>::zeros();
        let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
        let mut g = [Vector::<D>::zeros(); pfem_core::MAX_NV];
        for (e, el) in self.elements().fluid().chunks_exact(nv).enumerate() {
            if !el.iter().any(|&q| body[q as usize] == id) {
                continue;
            }
            for a in 0..nv {
                p[a] = x[el[a] as usize];
            }
            let Some(vol) = pfem_core::shape_gradients::<D>(&p[..nv], &mut g[..nv]) else {
                continue;
            };
            // `∫ W_a` over the element, or over its part below the line.
            let mut w = [vol / nv as f64; pfem_core::MAX_NV];
            if cut_of[e] != 0 {
                let (share, l) = pfem_core::below_water_line::<D>(&p[..nv], cut_of[e], &up);
                for a in 0..nv {
                    w[a] = vol * share * l[a];
                }
            }
            let p_w: f64 = el
                .iter()
                .zip(&w)
                .map(|(&q, w)| pressure[q as usize] * w)
                .sum();
            let rho = element_density(self, el);
            for (k, &q) in el.iter().enumerate() {
                if body[q as usize] == id {
                    f += g[k] * p_w;
                    f += (gravity - a[q as usize]) * (rho * w[k]);
                }
            }
        }
        // Closures (deviation 8): their facets carry pressure like the
        // elements' (no mass).
        for el in self.elements().closures().chunks_exact(nv) {
            if !el.iter().any(|&q| body[q as usize] == id) {
                continue;
            }
            for k in 0..nv {
                p[k] = x[el[k] as usize];
            }
            pfem_core::weighted_shape_gradients::<D>(&p[..nv], &mut g[..nv]);
            let p_sum: f64 = el.iter().map(|&q| pressure[q as usize]).sum();
            for (k, &q) in el.iter().enumerate() {
                if body[q as usize] == id {
                    f += g[k] * (p_sum / nv as f64);
                }
            }
        }
        f += pocket_force(self, id);
        Ok(f)
    }

    /// The water pressure at every particle (Pa), what the VTU output
    /// writes as `pressure`: a fluid particle's own nodal pressure; at a
    /// solid or wall particle that a fluid element touches (a wetted
    /// interface), the pressure of the adjacent water, the least-squares
    /// linear fit `p ≈ c + b·(x − xᵢ)` to the fluid particles of its fluid
    /// elements and of theirs, evaluated at the particle (their mean where
    /// they do not span a simplex); `0` elsewhere.
    ///
    /// The pressure the method itself stores on an interface particle
    /// (`state.pressure`) is the incremental nodal pressure of eq. 62 over
    /// the particle's one-sided fluid patch; it drives the interface's
    /// momentum balance, but it is not the water's pressure there when the
    /// two spacings differ (issue 13: +61 % on a plate 8 times finer than
    /// the water). The fit is exact for a hydrostatic field whatever the
    /// ratio of the spacings.
    fn water_pressure(&self) -> Vec<f64> {
        let n = self.particles().len();
        if !self.is_meshed() {
            return vec![f64::NAN; n];
        }
        let nv = D + 1;
        let mut out = vec![0.0; n];
        // Fluid elements of each particle.
        let mut elems_of: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (e, el) in self.elements().fluid().chunks_exact(nv).enumerate() {
            for &i in el {
                elems_of[i as usize].push(e as u32);
            }
        }
        let fluid_of = |e: u32, into: &mut Vec<u32>| {
            for &j in &self.elements().fluid()[e as usize * nv..(e as usize + 1) * nv] {
                if self.particles().kind()[j as usize] == ParticleKind::Fluid {
                    into.push(j);
                }
            }
        };
        // The fluid particles of an interface particle's fluid elements and
        // of theirs (two rings: one ring is often one flat layer of water,
        // which carries no gradient across it).
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut ring = Vec::new();
        for i in 0..n {
            if self.particles().kind()[i] == ParticleKind::Fluid || elems_of[i].is_empty() {
                continue;
            }
            ring.clear();
            for &e in &elems_of[i] {
                fluid_of(e, &mut ring);
            }
            ring.sort_unstable();
            ring.dedup();
            let nb = &mut neighbours[i];
            for &j in &ring {
                nb.push(j);
                for &e in &elems_of[j as usize] {
                    fluid_of(e, nb);
                }
            }
        }
        for i in 0..n {
            if self.particles().kind()[i] == ParticleKind::Fluid {
                out[i] = self.particles().pressure()[i];
                continue;
            }
            let nb = &mut neighbours[i];
            if nb.is_empty() {
                continue;
            }
            nb.sort_unstable();
            nb.dedup();
            out[i] = fit_pressure_at(self, i, nb);
        }
        out
    }
}

/// [`RunError::NotMeshed`] for a set changed since it was meshed
/// ([`Simulation::is_meshed`]): its elements name the old set's particles
/// (before session 49 reading them panicked, a review).
fn not_meshed<const D: usize>(sim: &Simulation<D>) -> Result<(), RunError>
where
    Const<D>: Dim,
{
    if sim.is_meshed() {
        Ok(())
    } else {
        Err(RunError::NotMeshed)
    }
}

/// Whether `at` lies in the bounding box of the simplex `p` (the quick
/// reject of [`Loads::fluid_at`]).
fn in_box<const D: usize>(p: &[Point<D>], at: &Point<D>) -> bool
where
    Const<D>: Dim,
{
    !(0..D).any(|k| {
        let (lo, hi) = p
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), q| {
                (l.min(q[k]), h.max(q[k]))
            });
        at[k] < lo || at[k] > hi
    })
}

/// The nodal pressure and velocity at `at` interpolated linearly in the
/// fluid element `el` (corners `p`, shape gradients `g`), or `None` when
/// `at` lies outside it (a barycentric weight below `−10⁻¹²`).
fn interpolate<const D: usize>(
    sim: &Simulation<D>,
    el: &[u32],
    p: &[Point<D>],
    g: &[Vector<D>],
    at: &Point<D>,
) -> Option<(f64, Vector<D>)>
where
    Const<D>: Dim,
{
    let nv = D + 1;
    // Barycentric weights: W_a(at) = 1/(D+1) + grad W_a · (at − centroid).
    let c = p.iter().fold(Point::<D>::zeros(), |acc, q| acc + q) / nv as f64;
    let mut w = [0.0; pfem_core::MAX_NV];
    for a in 0..nv {
        w[a] = 1.0 / nv as f64 + g[a].dot(&(at - c));
    }
    if !w[..nv].iter().all(|&wa| wa >= -1e-12) {
        return None;
    }
    let pressure = sim.particles().pressure();
    let v = sim.particles().v();
    let mut pp = 0.0;
    let mut vv = Vector::<D>::zeros();
    for a in 0..nv {
        pp += w[a] * pressure[el[a] as usize];
        vv += v[el[a] as usize] * w[a];
    }
    Some((pp, vv))
}

/// Least-squares linear fit of the fluid pressure at `nb`, evaluated at
/// particle `i` (see [`Loads::water_pressure`]).
fn fit_pressure_at<const D: usize>(sim: &Simulation<D>, i: usize, nb: &[u32]) -> f64
where
    Const<D>: Dim,
{
    let mean = nb
        .iter()
        .map(|&j| sim.particles().pressure()[j as usize])
        .sum::<f64>()
        / nb.len() as f64;
    if nb.len() < D + 1 {
        return mean;
    }
    // Normal equations in (c, b) with coordinates relative to xᵢ,
    // scaled by the particle's spacing.
    let h = sim.particles().spacing()[i].max(f64::MIN_POSITIVE);
    let m = D + 1;
    let mut a = nalgebra::DMatrix::<f64>::zeros(m, m);
    let mut r = nalgebra::DVector::<f64>::zeros(m);
    for &j in nb {
        let d = (sim.particles().x()[j as usize] - sim.particles().x()[i]) / h;
        let mut row = [1.0; 4];
        for k in 0..D {
            row[k + 1] = d[k];
        }
        let p = sim.particles().pressure()[j as usize];
        for u in 0..m {
            r[u] += row[u] * p;
            for v in 0..m {
                a[(u, v)] += row[u] * row[v];
            }
        }
    }
    // Condition check: a flat set of neighbours (all on one line or
    // plane) cannot carry a gradient across it.
    let sv = a.clone().singular_values();
    let (smax, smin) = (sv.max(), sv.min());
    if smin.is_nan() || smin <= 1e-8 * smax {
        return mean;
    }
    match a.lu().solve(&r) {
        Some(c) if c[0].is_finite() => c[0],
        _ => mean,
    }
}

/// The lumped-mass density of fluid element `el` as the assembly takes
/// it: the midrange of its fluids
/// (`pfem_constitutive::fluid_element_density`); 0 without a fluid node.
fn element_density<const D: usize>(s: &Simulation<D>, el: &[u32]) -> f64
where
    Const<D>: Dim,
{
    let (kind, material) = (s.particles().kind(), s.particles().material());
    el.iter()
        .find(|&&q| kind[q as usize] == ParticleKind::Fluid)
        .map_or(0.0, |&f| {
            pfem_constitutive::fluid_element_density(
                s.materials(),
                el.iter().map(|&q| material[q as usize]),
                material[f as usize],
            )
        })
}

/// The wall pockets' share of [`Loads::pressure_force_on`] on body `id`
/// (3D; zero without pockets on the body): each pocket's weight `w` times
/// the weight less the inertia of the water it stands for, lumped on its
/// nodes (`ρ (V/(D+1)) (g − aᵢ)`, as the elements' mass), and its pressure
/// force `p̄ V grad W_i`, `p̄` the mean of its nodes' pressures and `ρ` the
/// mean density of the fluid elements that hold them. A node outside every
/// element carries no pressure (`pfem_time`'s update sets it to zero): it
/// takes that of the held nodes carried to its height by the water's
/// weight. A pocket none of whose nodes a fluid element holds is left
/// out.
fn pocket_force<const D: usize>(s: &Simulation<D>, id: u32) -> Vector<D>
where
    Const<D>: Dim,
{
    let nv = D + 1;
    let (pockets, weights) = (s.elements().wall_pockets(), s.elements().pocket_weights());
    let (x, accel, pressure, body) = (
        s.particles().x(),
        s.particles().a(),
        s.particles().pressure(),
        s.particles().body(),
    );
    let mut f = Vector::<D>::zeros();
    if !pockets
        .chunks_exact(nv)
        .any(|el| el.iter().any(|&q| body[q as usize] == id))
    {
        return f;
    }
    // The density of a fluid element holding each pocket node (0: none).
    let mut density = vec![0.0; x.len()];
    for &q in pockets {
        density[q as usize] = f64::NAN;
    }
    for el in s.elements().fluid().chunks_exact(nv) {
        if !el.iter().any(|&q| density[q as usize] != 0.0) {
            continue;
        }
        let rho = element_density(s, el);
        if rho == 0.0 {
            continue;
        }
        for &q in el {
            if density[q as usize] != 0.0 {
                density[q as usize] = rho;
            }
        }
    }
    let gravity = s.gravity().unwrap_or_else(Vector::<D>::zeros);
    let mut p = [Point::<D>::zeros(); pfem_core::MAX_NV];
    let mut g = [Vector::<D>::zeros(); pfem_core::MAX_NV];
    for (el, &w) in pockets.chunks_exact(nv).zip(weights) {
        if !el.iter().any(|&q| body[q as usize] == id) {
            continue;
        }
        let mut held = [0usize; pfem_core::MAX_NV];
        let mut n_held = 0;
        for &q in el {
            if !density[q as usize].is_nan() {
                held[n_held] = q as usize;
                n_held += 1;
            }
        }
        let held = &held[..n_held];
        if held.is_empty() {
            continue;
        }
        for a in 0..nv {
            p[a] = x[el[a] as usize];
        }
        let Some(vol) = pfem_core::shape_gradients::<D>(&p[..nv], &mut g[..nv]) else {
            continue;
        };
        let n_held = held.len() as f64;
        let rho = held.iter().map(|&q| density[q]).sum::<f64>() / n_held;
        // A node no fluid element holds carries no pressure of its own
        // (zero after the first step): it takes its held neighbours',
        // carried to its height by the water's weight, `p_h + ρ g·(x − x_h)`
        // (the hydrostatic field exactly at rest; the stored start pressure
        // would do at the start only, and the held nodes' mean alone read a
        // tank's mirrored walls 0.15 % apart, a review).
        let p_sum: f64 = el
            .iter()
            .map(|&q| q as usize)
            .map(|q| {
                if !density[q].is_nan() {
                    return pressure[q];
                }
                held.iter()
                    .map(|&h| pressure[h] + rho * gravity.dot(&(x[q] - x[h])))
                    .sum::<f64>()
                    / n_held
            })
            .sum();
        let p_mean = p_sum / nv as f64;
        for (k, &q) in el.iter().enumerate() {
            if body[q as usize] == id {
                let q = q as usize;
                f += (g[k] * (p_mean * vol) + (gravity - accel[q]) * (rho * vol / nv as f64)) * w;
            }
        }
    }
    f
}
