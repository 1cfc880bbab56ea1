//! The hydrostatic start: the pressure of fluids at rest under gravity,
//! `p = p₀ + ρ g (x − x₀)·ĝ`, with `x₀` the top of the fluid column above
//! each particle and `p₀` the weight of whatever fluid rests on that top.
//!
//! Each fluid particle looks for the particle right above it (along `−ĝ`,
//! within 1.5 spacings up and 0.75 across). Its column goes on through
//! fluid of the same density and ends at its top particle, which is
//! - free (nothing above): `p₀ = 0` there, whatever the height of the
//!   other columns (a sloping or tilted surface starts at zero pressure);
//! - under a fluid of another density (oil over water): `p₀` is the upper
//!   fluid's pressure carried down across the interface, taken midway
//!   between the two particles;
//! - covered by a wall or a solid (water under a submerged obstacle, a
//!   closed box): the column takes the level of its connected fluid (same
//!   density, within 1.5 spacings), the highest of its free or loaded
//!   tops, or the fluid's highest particle if it has none.
//!
//! Walls and solids next to the fluid carry the same nodal field (eq. 62
//! puts pressure on every node of a fluid element): each takes the field
//! of its nearest fluid particle within a lattice cell's diagonal, so that a wall
//! shared by two reservoirs carries each side's own pressure; walls never
//! negative, solids linear up to a spacing above the water line (issue 19,
//! `AlphaShapeParams::cut_dry_bridges`: a solid node there is a vertex of
//! an element cut at the water line). Solids farther from any fluid
//! particle, within a spacing of a connected fluid's box, take that
//! fluid's level (a submerged solid's inside starts loaded).
//!
//! For one fluid body with a flat surface every column's top is the
//! body's highest row, and the field is `ρ g (x − x_top)·ĝ` bit for bit.
//!
//! Only fluid held up starts loaded: a connected fluid (across densities)
//! with no wall particle, and no particle of a held solid (clamped,
//! welded, or resting on a wall or a held solid), right below one of its
//! particles falls freely and starts at zero, and so do the walls and
//! solids beside it (session 50).

use pfem_core::{Const, Dim, ParticleKind, Point, Vector};

use crate::lattice::SpacingGrids;

/// The fluid particle nearest to particle `i` (a wall's or a solid's)
/// within a lattice cell's diagonal of the fluid particle's spacing, the
/// farthest a wall or solid particle of a fluid element's corner lies from
/// the fluid; the lower index of two at one distance. `fluid` holds the
/// fluid particles.
pub(crate) fn nearest_fluid<const D: usize>(
    fluid: &SpacingGrids<D>,
    x: &[Point<D>],
    spacing: &[f64],
    i: usize,
) -> Option<usize>
where
    Const<D>: Dim,
{
    let diagonal = 1.01 * (D as f64).sqrt();
    let mut near: Option<(f64, usize)> = None;
    fluid.visit(&x[i], 0.0, diagonal, x, |j| {
        let d = (x[i] - x[j]).norm();
        if d <= diagonal * spacing[j] && near.is_none_or(|(b, bj)| (d, j) < (b, bj)) {
            near = Some((d, j));
        }
    });
    near.map(|(_, j)| j)
}

/// How a column's top particle is loaded.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Top {
    /// Nothing above it.
    Free,
    /// A fluid particle of another density above it.
    Under(usize),
    /// A wall or solid particle above it.
    Covered,
}

/// The hydrostatic start pressure of every particle (Pa), 0 where it has
/// none. `density` is each fluid particle's (kg/m³; ignored elsewhere),
/// `g` the gravity (m/s², nonzero); `body` each particle's body and
/// `held` whether it is held in place (a wall's, a clamped or welded
/// solid's particle): a free solid holds the fluid on it only when it
/// rests on something held itself.
pub(crate) fn pressures<const D: usize>(
    x: &[Point<D>],
    kind: &[ParticleKind],
    spacing: &[f64],
    density: &[f64],
    g: &Vector<D>,
    body: &[u32],
    held: &[bool],
) -> Vec<f64>
where
    Const<D>: Dim,
{
    let n = x.len();
    let mut pressure = vec![0.0; n];
    let gn = g.norm();
    let fluid: Vec<usize> = (0..n).filter(|&i| kind[i] == ParticleKind::Fluid).collect();
    if fluid.is_empty() || gn.is_nan() || gn <= 0.0 {
        return pressure;
    }
    // A gravity whose norm overflows has no direction (`g / |g|` = 0):
    // its ρ g H does too, which the caller refuses.
    if gn.is_infinite() {
        return vec![f64::INFINITY; n];
    }
    let dir = g / gn;
    // Depth along gravity (grows downward).
    let depth: Vec<f64> = x.iter().map(|p| p.dot(&dir)).collect();
    // Grids by spacing class: a fine fluid beside a coarse wall costs its
    // own neighbourhood, and a coarse cover is found from a fine fluid.
    let all = SpacingGrids::new(x, spacing, |_| true);
    let fluid_grid = SpacingGrids::new(x, spacing, |i| kind[i] == ParticleKind::Fluid);
    // Highest first: a particle's neighbour above comes before it.
    let mut order = fluid.clone();
    order.sort_by(|&a, &b| depth[a].total_cmp(&depth[b]).then(a.cmp(&b)));
    // `(perp, dh)` when particle `j` lies right above particle `i`: higher
    // by more than a tenth and at most 1.5 of the larger spacing, within
    // 0.75 of it across.
    let above_of = |i: usize, j: usize| -> Option<(f64, f64)> {
        let s = spacing[i].max(spacing[j]);
        let dh = depth[i] - depth[j];
        if !(dh > 0.1 * s && dh <= 1.5 * s) {
            return None;
        }
        let d = x[i] - x[j];
        let perp = (d - dir * d.dot(&dir)).norm();
        (perp <= 0.75 * s).then_some((perp, dh))
    };
    let mut root = vec![usize::MAX; n];
    let mut top = vec![Top::Free; n];
    for &i in &order {
        let mut above: Option<(f64, f64, usize)> = None;
        all.visit(&x[i], spacing[i], 1.5, x, |j| {
            if let Some((perp, dh)) = above_of(i, j) {
                if above.is_none_or(|(bp, bh, bj)| (perp, dh, j) < (bp, bh, bj)) {
                    above = Some((perp, dh, j));
                }
            }
        });
        match above {
            None => root[i] = i,
            Some((_, _, j)) if kind[j] == ParticleKind::Fluid && density[j] == density[i] => {
                root[i] = root[j];
            }
            Some((_, _, j)) => {
                root[i] = i;
                top[i] = if kind[j] == ParticleKind::Fluid {
                    Top::Under(j)
                } else {
                    Top::Covered
                };
            }
        }
    }
    // Connected fluids of one density (`parent`), and of any density
    // (`held_by`: what holds the water up holds the oil on it, below).
    let mut parent: Vec<usize> = (0..n).collect();
    let mut held_by: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    fn join(parent: &mut [usize], i: usize, j: usize) {
        let (a, b) = (find(parent, i), find(parent, j));
        if a != b {
            parent[a.max(b)] = a.min(b);
        }
    }
    for &i in &fluid {
        fluid_grid.visit(&x[i], spacing[i], 1.5, x, |j| {
            if (x[i] - x[j]).norm() <= 1.5 * spacing[i].max(spacing[j]) {
                join(&mut held_by, i, j);
                if density[j] == density[i] {
                    join(&mut parent, i, j);
                }
            }
        });
    }
    let component: Vec<usize> = (0..n).map(|i| find(&mut parent, i)).collect();
    // Each column's (top depth, pressure there), resolved free tops first,
    // then tops under another fluid once that fluid's column is, then the
    // covered tops of a fluid once all its free and loaded tops are.
    let roots: Vec<usize> = fluid.iter().copied().filter(|&i| root[i] == i).collect();
    // Each connected fluid's highest particle (the level of one with no
    // free or loaded top: a closed, full tank).
    let mut highest: std::collections::HashMap<usize, f64> = Default::default();
    for &i in &fluid {
        let e = highest.entry(component[i]).or_insert(depth[i]);
        *e = e.min(depth[i]);
    }
    let mut value: Vec<Option<(f64, f64)>> = vec![None; n];
    for &r in &roots {
        if top[r] == Top::Free {
            value[r] = Some((depth[r], 0.0));
        }
    }
    let at = |value: &[Option<(f64, f64)>], i: usize| -> Option<f64> {
        value[root[i]].map(|(t, p0)| p0 + density[i] * gn * (depth[i] - t))
    };
    // Whether the level `(t, p0)` of a fluid of density `rho` is more
    // loaded than `(te, pe)`: the larger pressure at any one depth (one
    // density, one slope).
    let more_loaded = |rho: f64, (t, p0): (f64, f64), (te, pe): (f64, f64)| {
        p0 - rho * gn * t > pe - rho * gn * te
    };
    let mut forced = false;
    loop {
        let mut progress = false;
        for &r in &roots {
            if let (Top::Under(j), None) = (top[r], value[r]) {
                if let Some(pj) = at(&value, j) {
                    let p0 = pj + 0.5 * (density[r] + density[j]) * gn * (depth[r] - depth[j]);
                    value[r] = Some((depth[r], p0));
                    progress = true;
                }
            }
        }
        // Covered tops of fluids whose other tops are all known.
        let mut pending = std::collections::HashSet::new();
        for &r in &roots {
            if matches!(top[r], Top::Under(_)) && value[r].is_none() {
                pending.insert(component[r]);
            }
        }
        let mut level: std::collections::HashMap<usize, (f64, f64)> = Default::default();
        for &r in &roots {
            let c = component[r];
            if top[r] == Top::Covered || pending.contains(&c) {
                continue;
            }
            if let Some(v) = value[r] {
                // The most loaded of the fluid's tops.
                let e = level.entry(c).or_insert(v);
                if more_loaded(density[r], v, *e) {
                    *e = v;
                }
            }
        }
        for &r in &roots {
            let c = component[r];
            if top[r] == Top::Covered && value[r].is_none() && !pending.contains(&c) {
                let v = level
                    .get(&c)
                    .copied()
                    .unwrap_or_else(|| (highest.get(&c).copied().unwrap_or(depth[r]), 0.0));
                value[r] = Some(v);
                progress = true;
            }
        }
        if roots.iter().all(|&r| value[r].is_some()) {
            break;
        }
        if !progress {
            // A cycle of fluids each resting on the other: their loaded
            // tops start free.
            debug_assert!(!forced, "a forced pass resolves every top");
            forced = true;
            for &r in &roots {
                if matches!(top[r], Top::Under(_)) && value[r].is_none() {
                    value[r] = Some((depth[r], 0.0));
                }
            }
        }
    }
    // Fluid with nothing under it (a drop, a block of water released in
    // the air) falls freely: no pressure. A fluid connected across
    // densities (`held_by`: oil on water is held by what holds the water)
    // is held where one of its particles has a wall or
    // solid particle right below it (the mirror of the search above).
    // Until session 50 a block of water released 2 m over a floor started
    // at ρ g H: its base burst sideways at 0.06 m/s and its volume fell
    // 1.1 % in a step (a review).
    // Whether `j` lies right below `i` (the mirror of the search above).
    let right_below = |i: usize, j: usize| above_of(j, i).is_some();
    // The solid bodies held up: clamped or welded, or resting on a wall or
    // on a solid held up (a free raft 2 m over the floor holds nothing: a
    // review found the water on it started at ρ g H).
    let n_bodies = body.iter().map(|&b| b as usize + 1).max().unwrap_or(0);
    let mut body_held = vec![false; n_bodies];
    for i in 0..n {
        if kind[i] == ParticleKind::Solid && held[i] {
            body_held[body[i] as usize] = true;
        }
    }
    let support = |j: usize, body_held: &[bool]| match kind[j] {
        ParticleKind::Wall => true,
        ParticleKind::Solid => body_held[body[j] as usize],
        ParticleKind::Fluid => false,
    };
    let solids: Vec<usize> = (0..n).filter(|&i| kind[i] == ParticleKind::Solid).collect();
    loop {
        let mut more = false;
        for &i in &solids {
            if body_held[body[i] as usize] {
                continue;
            }
            let mut on = false;
            all.visit(&x[i], spacing[i], 1.5, x, |j| {
                on |= body[j] != body[i] && support(j, &body_held) && right_below(i, j);
            });
            if on {
                body_held[body[i] as usize] = true;
                more = true;
            }
        }
        if !more {
            break;
        }
    }
    let mut held = vec![false; n];
    for &i in &fluid {
        let mut below = false;
        all.visit(&x[i], spacing[i], 1.5, x, |j| {
            below |= support(j, &body_held) && right_below(i, j);
        });
        if below {
            let r = find(&mut held_by, i);
            held[r] = true;
        }
    }
    let held: Vec<bool> = (0..n).map(|i| held[find(&mut held_by, i)]).collect();
    for &i in &fluid {
        pressure[i] = if held[i] {
            at(&value, i).expect("every column resolved")
        } else {
            0.0
        };
    }
    // Walls and solids: the nearest fluid particle's field, or farther
    // (within a spacing of a connected fluid's box) that fluid's level.
    // (lowest corner, highest corner, largest spacing, level: top depth
    // and pressure there) of each connected fluid.
    type Extent<const D: usize> = (Point<D>, Point<D>, f64, f64, f64);
    let mut boxes: std::collections::HashMap<usize, Extent<D>> = Default::default();
    for &i in fluid.iter().filter(|&&i| held[i]) {
        let (t, p0) = value[root[i]].expect("every column resolved");
        let e = boxes
            .entry(component[i])
            .or_insert((x[i], x[i], spacing[i], t, p0));
        e.0 = e.0.inf(&x[i]);
        e.1 = e.1.sup(&x[i]);
        e.2 = e.2.max(spacing[i]);
        if more_loaded(density[i], (t, p0), (e.3, e.4)) {
            (e.3, e.4) = (t, p0);
        }
    }
    let mut boxes: Vec<(usize, Extent<D>)> = boxes.into_iter().collect();
    boxes.sort_by_key(|(c, _)| *c);
    let field = |i: usize, (t, p0): (f64, f64), rho: f64, h: f64| -> f64 {
        let above = depth[i] - t;
        let p = p0 + rho * gn * above;
        if kind[i] == ParticleKind::Solid && above >= -h {
            p
        } else {
            p.max(0.0)
        }
    };
    for i in 0..n {
        if kind[i] == ParticleKind::Fluid {
            continue;
        }
        if let Some(f) = nearest_fluid(&fluid_grid, x, spacing, i) {
            if held[f] {
                let v = value[root[f]].expect("every column resolved");
                pressure[i] = field(i, v, density[f], spacing[f] * 1.01);
            }
            continue;
        }
        // (Solids only: a wall's particle this far from the fluid is in
        // no fluid element; a submerged solid's inside starts loaded.)
        if kind[i] != ParticleKind::Solid {
            continue;
        }
        for (c, (lo, hi, s, t, p0)) in boxes.iter().rev() {
            let h = s * 1.01;
            if (0..D).all(|k| x[i][k] >= lo[k] - h && x[i][k] <= hi[k] + h) {
                pressure[i] = field(i, (*t, *p0), density[*c], h);
                break;
            }
        }
    }
    pressure
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = 9.81;

    /// Particles on a lattice of spacing `s` filling `[x0, x1] × [y0, y1]`
    /// (cell centres).
    fn fill(
        cloud: &mut Cloud2,
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
        s: f64,
        kind: ParticleKind,
        rho: f64,
    ) {
        let nx = ((x1 - x0) / s).round() as usize;
        let ny = ((y1 - y0) / s).round() as usize;
        for a in 0..nx {
            for b in 0..ny {
                cloud.x.push(Point::<2>::new(
                    x0 + (a as f64 + 0.5) * s,
                    y0 + (b as f64 + 0.5) * s,
                ));
                cloud.kind.push(kind);
                cloud.spacing.push(s);
                cloud.density.push(rho);
            }
        }
    }

    #[derive(Default)]
    struct Cloud2 {
        x: Vec<Point<2>>,
        kind: Vec<ParticleKind>,
        spacing: Vec<f64>,
        density: Vec<f64>,
    }

    impl Cloud2 {
        fn pressures(&self, g: Vector<2>) -> Vec<f64> {
            let n = self.x.len();
            pressures(
                &self.x,
                &self.kind,
                &self.spacing,
                &self.density,
                &g,
                &vec![0; n],
                &vec![false; n],
            )
        }
    }

    fn down() -> Vector<2> {
        Vector::<2>::new(0.0, -G)
    }

    /// One body with a flat surface: `ρ g (y_top − y)` bit for bit, and
    /// the floor's and side walls' rows the same field (never negative).
    #[test]
    fn one_flat_body_is_rho_g_depth_bit_for_bit() {
        let s = 0.1;
        let mut c = Cloud2::default();
        fill(
            &mut c,
            (0.0, 1.0),
            (0.0, 0.5),
            s,
            ParticleKind::Fluid,
            1000.0,
        );
        fill(&mut c, (-0.1, 1.1), (-0.1, 0.0), s, ParticleKind::Wall, 0.0);
        fill(&mut c, (-0.1, 0.0), (0.0, 0.8), s, ParticleKind::Wall, 0.0);
        let p = c.pressures(down());
        let top =
            c.x.iter()
                .zip(&c.kind)
                .filter(|(_, k)| **k == ParticleKind::Fluid)
                .map(|(x, _)| -x[1])
                .fold(f64::INFINITY, f64::min);
        for i in 0..c.x.len() {
            let want = 1000.0 * G * (-c.x[i][1] - top);
            let want = if c.kind[i] == ParticleKind::Wall {
                want.max(0.0)
            } else {
                want
            };
            assert_eq!(
                p[i].to_bits(),
                want.to_bits(),
                "particle {i} at {:?}",
                c.x[i]
            );
        }
    }

    /// Water (1000 kg/m³) over `0 ≤ x ≤ 0.5`, `0 ≤ y ≤ 0.4`, and oil (800)
    /// on it up to `y = 0.6`, at spacing `s`.
    fn oil_on_water(c: &mut Cloud2, s: f64) {
        fill(c, (0.0, 0.5), (0.0, 0.4), s, ParticleKind::Fluid, 1000.0);
        fill(c, (0.0, 0.5), (0.4, 0.6), s, ParticleKind::Fluid, 800.0);
    }

    /// Oil (800 kg/m³, 0.2 m) resting on water (1000, 0.4 m): the water
    /// carries the oil's weight, exactly on a lattice whose interface lies
    /// midway between two rows.
    #[test]
    fn oil_on_water_carries_its_weight() {
        let s = 0.05;
        let mut c = Cloud2::default();
        oil_on_water(&mut c, s);
        let fluid = c.x.len();
        fill(&mut c, (-0.1, 0.6), (-s, 0.0), s, ParticleKind::Wall, 0.0);
        let p = c.pressures(down());
        let top = 0.6 - 0.5 * s;
        for i in 0..fluid {
            let y = c.x[i][1];
            let want = if y > 0.4 {
                800.0 * G * (top - y)
            } else {
                800.0 * G * (top - 0.4) + 1000.0 * G * (0.4 - y)
            };
            assert!(
                (p[i] - want).abs() < 1e-9 * 1000.0 * G,
                "at {:?}: {} against {want}",
                c.x[i],
                p[i]
            );
        }
    }

    /// Water under a submerged wall (a lid with water above and around
    /// it) takes the level of the water around it, not zero under the lid.
    #[test]
    fn water_under_an_obstacle_takes_the_level_around_it() {
        let s = 0.05;
        let mut c = Cloud2::default();
        fill(
            &mut c,
            (0.0, 1.0),
            (0.0, 0.2),
            s,
            ParticleKind::Fluid,
            1000.0,
        );
        fill(
            &mut c,
            (0.0, 0.3),
            (0.2, 0.5),
            s,
            ParticleKind::Fluid,
            1000.0,
        );
        fill(
            &mut c,
            (0.7, 1.0),
            (0.2, 0.5),
            s,
            ParticleKind::Fluid,
            1000.0,
        );
        // The lid twice as coarse as the water (a coarse cover was missed
        // by a search sized by the water's spacing: the review of the
        // first version).
        fill(
            &mut c,
            (0.3, 0.7),
            (0.2, 0.3),
            2.0 * s,
            ParticleKind::Wall,
            0.0,
        );
        fill(
            &mut c,
            (0.3, 0.7),
            (0.3, 0.5),
            s,
            ParticleKind::Fluid,
            1000.0,
        );
        let p = c.pressures(down());
        let top = 0.5 - 0.5 * s;
        for i in 0..c.x.len() {
            if c.kind[i] == ParticleKind::Fluid {
                let want = 1000.0 * G * (top - c.x[i][1]);
                assert!(
                    (p[i] - want).abs() < 1e-9 * want.abs().max(1.0),
                    "at {:?}: {} against {want}",
                    c.x[i],
                    p[i]
                );
            }
        }
    }

    /// Two reservoirs at different levels on either side of one wall: each
    /// side of the wall carries its own water's pressure (it took the last
    /// body's), and each free surface starts at zero.
    #[test]
    fn a_shared_wall_carries_each_side_s_pressure() {
        let s = 0.05;
        let mut c = Cloud2::default();
        fill(
            &mut c,
            (0.0, 0.5),
            (0.0, 0.6),
            s,
            ParticleKind::Fluid,
            1000.0,
        );
        fill(
            &mut c,
            (0.6, 1.1),
            (0.0, 0.2),
            s,
            ParticleKind::Fluid,
            1000.0,
        );
        let first_wall = c.x.len();
        fill(&mut c, (0.5, 0.6), (0.0, 0.8), s, ParticleKind::Wall, 0.0);
        let floor = c.x.len();
        fill(&mut c, (-0.1, 1.2), (-s, 0.0), s, ParticleKind::Wall, 0.0);
        let p = c.pressures(down());
        for i in 0..first_wall {
            let top = if c.x[i][0] < 0.5 {
                0.6 - 0.5 * s
            } else {
                0.2 - 0.5 * s
            };
            let want = 1000.0 * G * (top - c.x[i][1]);
            assert!((p[i] - want).abs() < 1e-9 * 1000.0 * G, "at {:?}", c.x[i]);
        }
        // The wall's two columns (x = 0.525 and 0.575) each carry the
        // field of the water on their side (the right one is dry, at zero,
        // above the right water).
        for i in first_wall..floor {
            let y = c.x[i][1];
            let top = if c.x[i][0] < 0.55 {
                0.6 - 0.5 * s
            } else {
                0.2 - 0.5 * s
            };
            let want = (1000.0 * G * (top - y)).max(0.0);
            assert!(
                (p[i] - want).abs() < 1e-9 * 1000.0 * G,
                "wall at {:?}: {} against {want}",
                c.x[i],
                p[i]
            );
        }
    }

    /// Session 50 (a review): water with nothing under it falls freely and
    /// starts at zero pressure, oil resting on it too, and a wall beside it
    /// carries none; the same water on a floor carries its weight. It
    /// started at ρ g H whatever held it.
    #[test]
    fn fluid_with_nothing_under_it_starts_at_zero() {
        let s = 0.05;
        for floor_at in [0.0, -2.0] {
            let mut c = Cloud2::default();
            oil_on_water(&mut c, s);
            let fluid = c.x.len();
            // A side wall beside the water, from the floor up.
            fill(
                &mut c,
                (-0.1, 0.0),
                (floor_at, 0.8),
                s,
                ParticleKind::Wall,
                0.0,
            );
            fill(
                &mut c,
                (-0.1, 0.6),
                (floor_at - s, floor_at),
                s,
                ParticleKind::Wall,
                0.0,
            );
            let p = c.pressures(down());
            let bottom = (0..fluid)
                .min_by(|&a, &b| c.x[a][1].total_cmp(&c.x[b][1]))
                .unwrap();
            let want = 800.0 * G * (0.2 - 0.5 * s) + 1000.0 * G * (0.4 - 0.5 * s);
            if floor_at == 0.0 {
                assert!((p[bottom] - want).abs() < 1e-9 * want, "{}", p[bottom]);
                assert!(p[fluid..].iter().any(|&v| v > 0.0));
            } else {
                assert!(p.iter().all(|&v| v == 0.0), "{p:?}");
            }
        }
    }

    /// Session 50 (the day's review): water on a free solid raft that rests
    /// on nothing falls with it at zero pressure; on a clamped raft, or on a
    /// free raft resting on a floor, it carries its weight.
    #[test]
    fn water_on_a_free_raft_in_the_air_starts_at_zero() {
        let s = 0.05;
        // (held raft, raft on the floor)
        for (clamped, on_floor) in [(false, false), (true, false), (false, true)] {
            let mut c = Cloud2::default();
            fill(
                &mut c,
                (0.0, 0.5),
                (0.0, 0.3),
                s,
                ParticleKind::Fluid,
                1000.0,
            );
            let fluid = c.x.len();
            fill(&mut c, (0.0, 0.5), (-0.1, 0.0), s, ParticleKind::Solid, 0.0);
            let raft = c.x.len();
            let floor_top = if on_floor { -0.1 } else { -2.0 };
            fill(
                &mut c,
                (-0.1, 0.6),
                (floor_top - s, floor_top),
                s,
                ParticleKind::Wall,
                0.0,
            );
            let n = c.x.len();
            let body: Vec<u32> = (0..n)
                .map(|i| {
                    if i < fluid {
                        0
                    } else if i < raft {
                        1
                    } else {
                        2
                    }
                })
                .collect();
            let held: Vec<bool> = (0..n)
                .map(|i| i >= raft || (clamped && i >= fluid))
                .collect();
            let p = pressures(&c.x, &c.kind, &c.spacing, &c.density, &down(), &body, &held);
            let bottom = 1000.0 * G * (0.3 - s);
            let supported = clamped || on_floor;
            for i in 0..fluid {
                let want = if supported {
                    1000.0 * G * (0.3 - 0.5 * s - c.x[i][1])
                } else {
                    0.0
                };
                assert!(
                    (p[i] - want).abs() <= 1e-9 * bottom,
                    "clamped {clamped}, on the floor {on_floor}: {} against {want} at {:?}",
                    p[i],
                    c.x[i]
                );
            }
        }
    }

    /// A sloping surface (a step of water) and a tilted gravity start every
    /// free-surface particle at zero pressure.
    #[test]
    fn every_free_top_starts_at_zero() {
        let s = 0.05;
        let mut c = Cloud2::default();
        fill(
            &mut c,
            (0.0, 0.5),
            (0.0, 0.5),
            s,
            ParticleKind::Fluid,
            1000.0,
        );
        fill(
            &mut c,
            (0.5, 1.0),
            (0.0, 0.2),
            s,
            ParticleKind::Fluid,
            1000.0,
        );
        let fluid = c.x.len();
        fill(&mut c, (-0.1, 1.1), (-s, 0.0), s, ParticleKind::Wall, 0.0);
        let p = c.pressures(down());
        for i in 0..fluid {
            let top = if c.x[i][0] < 0.5 {
                0.5 - 0.5 * s
            } else {
                0.2 - 0.5 * s
            };
            let want = 1000.0 * G * (top - c.x[i][1]);
            assert!((p[i] - want).abs() < 1e-9 * 1000.0 * G, "at {:?}", c.x[i]);
        }
        // Gravity tilted by 30°: no particle's pressure is negative, and
        // the particles with nothing above them along g are at zero.
        let (sn, cs) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
        let g = Vector::<2>::new(G * sn, -G * cs);
        let p = c.pressures(g);
        assert!(p.iter().all(|&v| v >= 0.0));
        for i in 0..fluid {
            // Free along g: nothing above within the band (the top rows and
            // the column facing the tilt).
            let free = !(0..c.x.len()).any(|j| {
                let d = c.x[i] - c.x[j];
                let along = d.dot(&g) / G;
                let across = (d - g * (along / G)).norm();
                along > 0.1 * s && along <= 1.5 * s && across <= 0.75 * s
            });
            assert_eq!(free, p[i] == 0.0, "at {:?}: {}", c.x[i], p[i]);
        }
    }

    /// 3D: oil on water in a box with a floor: each water particle
    /// carries the oil's weight (the interface midway between the rows),
    /// the floor's particles the field below the water.
    #[test]
    fn oil_on_water_in_3d() {
        let s = 0.05;
        let (mut x, mut kind, mut spacing, mut density) = (vec![], vec![], vec![], vec![]);
        for a in 0..6 {
            for b in 0..4 {
                for c in -1..10 {
                    let (k, rho) = match c {
                        -1 => (ParticleKind::Wall, 0.0),
                        0..6 => (ParticleKind::Fluid, 1000.0),
                        _ => (ParticleKind::Fluid, 800.0),
                    };
                    x.push(Point::<3>::new(a as f64 * s, b as f64 * s, c as f64 * s));
                    kind.push(k);
                    spacing.push(s);
                    density.push(rho);
                }
            }
        }
        let n = x.len();
        let p = pressures(
            &x,
            &kind,
            &spacing,
            &density,
            &Vector::<3>::new(0.0, 0.0, -G),
            &vec![0; n],
            &vec![false; n],
        );
        let (top, interface) = (9.0 * s, 5.5 * s);
        for i in 0..x.len() {
            let z = x[i][2];
            let want = if z > interface {
                800.0 * G * (top - z)
            } else {
                800.0 * G * (top - interface) + 1000.0 * G * (interface - z)
            };
            assert!(
                (p[i] - want).abs() < 1e-9 * 1000.0 * G,
                "at {:?}: {} against {want}",
                x[i],
                p[i]
            );
        }
    }
}
