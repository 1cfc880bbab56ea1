//! Scenes: the bodies of a simulation (fluids, solids, walls), their
//! materials, geometry and particle spacing, the body forces and the run
//! settings. Built with [`Scene::new`] and its builder methods, validated by
//! [`Scene::validate`] before any step runs.

use pfem_constitutive::{Material, MaterialKind};
use pfem_core::{Const, Dim, ParticleKind, Point, Vector};

use crate::SceneError;

/// Where a body's particles are.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry<const D: usize>
where
    Const<D>: Dim,
{
    /// An axis-aligned box (rectangle in 2D) filled with a lattice of
    /// spacing `h` whose nodes include the box's corners.
    Box {
        /// Lower corner (m).
        min: Point<D>,
        /// Upper corner (m).
        max: Point<D>,
    },
    /// A disk (2D) or ball (3D): the lattice nodes inside it.
    Ball {
        /// Centre (m).
        center: Point<D>,
        /// Radius (m).
        radius: f64,
    },
    /// A right circular cylinder (3D only) standing on `base` (the centre
    /// of its bottom disk) along coordinate axis `axis` (0, 1 or 2): the
    /// disks of lattice nodes inside `radius`, one every spacing from
    /// `base` to `base + height` along the axis. In 2D it is rejected by
    /// [`Scene::validate`] (use a box).
    Cylinder {
        /// Centre of the bottom disk (m).
        base: Point<D>,
        /// Coordinate axis of the cylinder (0, 1 or 2).
        axis: usize,
        /// Radius (m).
        radius: f64,
        /// Height along the axis (m).
        height: f64,
    },
    /// The user's own particles (m).
    Particles(Vec<Point<D>>),
}

impl<const D: usize> Geometry<D>
where
    Const<D>: Dim,
{
    /// Lower and upper corners of the bounding box.
    pub fn bounds(&self) -> (Point<D>, Point<D>) {
        match self {
            Geometry::Box { min, max } => (*min, *max),
            Geometry::Ball { center, radius } => (
                center - Vector::<D>::repeat(*radius),
                center + Vector::<D>::repeat(*radius),
            ),
            Geometry::Cylinder {
                base,
                axis,
                radius,
                height,
            } => {
                let mut lo = base - Vector::<D>::repeat(*radius);
                let mut hi = base + Vector::<D>::repeat(*radius);
                if *axis < D {
                    lo[*axis] = base[*axis];
                    hi[*axis] = base[*axis] + height;
                }
                (lo, hi)
            }
            Geometry::Particles(p) => {
                let mut lo = Point::<D>::repeat(f64::INFINITY);
                let mut hi = Point::<D>::repeat(f64::NEG_INFINITY);
                for q in p {
                    lo = lo.inf(q);
                    hi = hi.sup(q);
                }
                (lo, hi)
            }
        }
    }
}

/// Prescribed motion of a wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WallMotion<const D: usize>
where
    Const<D>: Dim,
{
    /// At rest.
    Fixed,
    /// Moving at a constant velocity (m/s).
    Velocity(Vector<D>),
}

/// Where a solid is clamped (its velocity held at zero).
#[derive(Clone)]
pub enum Clamp<const D: usize>
where
    Const<D>: Dim,
{
    /// The solid's particles inside this box (lower and upper corners, m;
    /// a tolerance of 10⁻¹² m).
    Box(Point<D>, Point<D>),
    /// The solid's particles at whose initial position the predicate holds.
    Where(std::sync::Arc<dyn Fn(&Point<D>) -> bool + Send + Sync>),
}

impl<const D: usize> Clamp<D>
where
    Const<D>: Dim,
{
    /// Whether the particle at `p` is clamped.
    pub fn holds(&self, p: &Point<D>) -> bool {
        match self {
            Clamp::Box(lo, hi) => (0..D).all(|k| p[k] >= lo[k] - 1e-12 && p[k] <= hi[k] + 1e-12),
            Clamp::Where(f) => f(p),
        }
    }
}

impl<const D: usize> std::fmt::Debug for Clamp<D>
where
    Const<D>: Dim,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Clamp::Box(lo, hi) => write!(f, "Clamp::Box({:?}, {:?})", lo.as_slice(), hi.as_slice()),
            Clamp::Where(_) => write!(f, "Clamp::Where(..)"),
        }
    }
}

/// A function of a particle's coordinates (m).
pub type FieldFn<T> = dyn Fn(&[f64]) -> T + Send + Sync;

/// A field over a body's particles at `t = 0`: a function of the
/// particle's position.
#[derive(Clone)]
pub struct InitialField<T>(pub std::sync::Arc<FieldFn<T>>);

impl<T> std::fmt::Debug for InitialField<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "InitialField(..)")
    }
}

/// A body of a scene.
#[derive(Debug)]
pub struct Body<const D: usize>
where
    Const<D>: Dim,
{
    /// Name used in messages and output.
    pub name: String,
    /// Fluid, solid or wall.
    pub kind: ParticleKind,
    /// Material (none for a wall).
    pub material: Option<Box<dyn Material<D>>>,
    /// Where its particles are.
    pub geometry: Geometry<D>,
    /// Particle spacing `h` (m).
    pub spacing: f64,
    /// Initial velocity (m/s), uniform; see also [`Body::velocity_field`].
    pub velocity: Vector<D>,
    /// Initial velocity per particle (m/s) from its position (its
    /// coordinates as a slice), replacing [`Body::velocity`] where set.
    pub velocity_field: Option<InitialField<Vector<D>>>,
    /// Initial pressure per particle (Pa) from its position, replacing the
    /// hydrostatic start of a fluid where set.
    pub pressure_field: Option<InitialField<f64>>,
    /// Wall motion (walls only).
    pub motion: WallMotion<D>,
    /// Solids only: where the solid is clamped (any number of clamps).
    pub clamps: Vec<Clamp<D>>,
}

/// Run settings of a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSettings {
    /// End time (s).
    pub end_time: f64,
    /// Largest time step (s).
    pub max_dt: f64,
    /// Courant number bounding `Δt ≤ C h_min / v_max`.
    pub courant: f64,
    /// Interval between outputs (s); `None` for no VTU output.
    pub output_interval: Option<f64>,
    /// Alpha of the alpha shape (§8).
    pub alpha: f64,
}

impl Default for RunSettings {
    fn default() -> Self {
        Self {
            end_time: 1.0,
            max_dt: 1e-3,
            courant: 0.5,
            output_interval: Some(0.02),
            alpha: 1.3,
        }
    }
}

/// A scene: bodies, body force and run settings.
#[derive(Debug)]
pub struct Scene<const D: usize>
where
    Const<D>: Dim,
{
    /// Scene name (file names, summary).
    pub name: String,
    /// The bodies.
    pub bodies: Vec<Body<D>>,
    /// Body force per unit mass (m/s²), `None` for none.
    pub gravity: Option<Vector<D>>,
    /// Run settings.
    pub settings: RunSettings,
}

impl<const D: usize> Scene<D>
where
    Const<D>: Dim,
{
    /// An empty scene.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            bodies: Vec::new(),
            gravity: None,
            settings: RunSettings::default(),
        }
    }

    /// Sets the gravity (m/s²).
    pub fn gravity(mut self, g: Vector<D>) -> Self {
        self.gravity = Some(g);
        self
    }

    /// Sets the run settings.
    pub fn settings(mut self, settings: RunSettings) -> Self {
        self.settings = settings;
        self
    }

    /// Adds a fluid body.
    pub fn fluid(
        mut self,
        name: &str,
        material: Box<dyn Material<D>>,
        geometry: Geometry<D>,
        spacing: f64,
    ) -> Self {
        self.bodies.push(Body {
            name: name.into(),
            kind: ParticleKind::Fluid,
            material: Some(material),
            geometry,
            spacing,
            velocity: Vector::<D>::zeros(),
            velocity_field: None,
            pressure_field: None,
            motion: WallMotion::Fixed,
            clamps: Vec::new(),
        });
        self
    }

    /// Adds a solid body, clamped where `clamp` (a box) says; more clamps
    /// with [`Scene::clamp_box`] and [`Scene::clamp_where`]. A solid may
    /// touch a wall: where one of its particles falls within a quarter
    /// spacing of a wall particle, the wall particle is dropped and the
    /// solid particle is welded to the wall (it moves with it).
    pub fn solid(
        mut self,
        name: &str,
        material: Box<dyn Material<D>>,
        geometry: Geometry<D>,
        spacing: f64,
        clamp: Option<(Point<D>, Point<D>)>,
    ) -> Self {
        self.bodies.push(Body {
            name: name.into(),
            kind: ParticleKind::Solid,
            material: Some(material),
            geometry,
            spacing,
            velocity: Vector::<D>::zeros(),
            velocity_field: None,
            pressure_field: None,
            motion: WallMotion::Fixed,
            clamps: clamp
                .map(|(lo, hi)| Clamp::Box(lo, hi))
                .into_iter()
                .collect(),
        });
        self
    }

    /// Adds a wall.
    pub fn wall(
        mut self,
        name: &str,
        geometry: Geometry<D>,
        spacing: f64,
        motion: WallMotion<D>,
    ) -> Self {
        self.bodies.push(Body {
            name: name.into(),
            kind: ParticleKind::Wall,
            material: None,
            geometry,
            spacing,
            velocity: Vector::<D>::zeros(),
            velocity_field: None,
            pressure_field: None,
            motion,
            clamps: Vec::new(),
        });
        self
    }

    /// Sets the initial velocity of the last body added.
    pub fn with_velocity(mut self, v: Vector<D>) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.velocity = v;
        }
        self
    }

    /// Sets the initial velocity of each particle of the last body added
    /// from its position: `f(x)` with `x` the particle's coordinates (m).
    /// The initial accelerations are computed from it.
    pub fn with_velocity_field(
        mut self,
        f: impl Fn(&[f64]) -> Vector<D> + Send + Sync + 'static,
    ) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.velocity_field = Some(InitialField(std::sync::Arc::new(f)));
        }
        self
    }

    /// Sets the initial pressure (Pa) of each particle of the last body
    /// added (a fluid) from its position, instead of the hydrostatic start.
    pub fn with_pressure_field(
        mut self,
        f: impl Fn(&[f64]) -> f64 + Send + Sync + 'static,
    ) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.pressure_field = Some(InitialField(std::sync::Arc::new(f)));
        }
        self
    }

    /// Clamps the particles of the last body added (a solid) inside the box
    /// `[min, max]`, besides its other clamps.
    pub fn clamp_box(mut self, min: Point<D>, max: Point<D>) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.clamps.push(Clamp::Box(min, max));
        }
        self
    }

    /// Clamps the particles of the last body added (a solid) whose initial
    /// position satisfies `f`, besides its other clamps.
    pub fn clamp_where(mut self, f: impl Fn(&Point<D>) -> bool + Send + Sync + 'static) -> Self {
        if let Some(b) = self.bodies.last_mut() {
            b.clamps.push(Clamp::Where(std::sync::Arc::new(f)));
        }
        self
    }

    /// Checks the scene before any step runs: positive finite spacing no
    /// larger than its body, materials where needed and of the right kind,
    /// valid run settings, cylinders in 3D only, solids supported, fluids not overlapping other
    /// bodies' interiors.
    pub fn validate(&self) -> Result<(), SceneError> {
        let s = &self.settings;
        for (what, v) in [
            ("end_time", s.end_time),
            ("max_dt", s.max_dt),
            ("courant", s.courant),
            ("alpha", s.alpha),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(SceneError::InvalidSetting {
                    setting: what,
                    value: v,
                });
            }
        }
        if let Some(dt) = s.output_interval {
            if !(dt > 0.0 && dt.is_finite()) {
                return Err(SceneError::InvalidSetting {
                    setting: "output_interval",
                    value: dt,
                });
            }
        }
        if let Some(g) = self.gravity {
            if g.iter().any(|v| !v.is_finite()) {
                return Err(SceneError::InvalidSetting {
                    setting: "gravity",
                    value: f64::NAN,
                });
            }
        }
        if self.bodies.is_empty() {
            return Err(SceneError::Empty);
        }
        for b in &self.bodies {
            if !(b.spacing > 0.0 && b.spacing.is_finite()) {
                return Err(SceneError::InvalidSpacing {
                    body: b.name.clone(),
                    spacing: b.spacing,
                });
            }
            let (lo, hi) = b.geometry.bounds();
            if lo.iter().chain(hi.iter()).any(|v| !v.is_finite()) {
                return Err(SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: "non-finite or empty geometry".into(),
                });
            }
            let extent = (hi - lo).max();
            if let Geometry::Ball { radius, .. } = b.geometry {
                if radius.is_nan() || radius <= 0.0 {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: "radius must be positive".into(),
                    });
                }
            }
            if let Geometry::Cylinder {
                axis,
                radius,
                height,
                ..
            } = b.geometry
            {
                let why = if D != 3 {
                    Some("a cylinder is a 3D geometry (use a box in 2D)")
                } else if axis >= D {
                    Some("cylinder axis must be 0, 1 or 2")
                } else if !(radius > 0.0 && height > 0.0) {
                    Some("cylinder radius and height must be positive")
                } else {
                    None
                };
                if let Some(why) = why {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: why.into(),
                    });
                }
            }
            if !matches!(b.geometry, Geometry::Particles(_)) && b.spacing > extent + 1e-12 {
                return Err(SceneError::SpacingLargerThanBody {
                    body: b.name.clone(),
                    spacing: b.spacing,
                    extent,
                });
            }
            if let Geometry::Box { min, max } = &b.geometry {
                if (0..D).any(|k| max[k] < min[k]) {
                    return Err(SceneError::InvalidGeometry {
                        body: b.name.clone(),
                        why: "box max below min".into(),
                    });
                }
            }
            match (b.kind, &b.material) {
                (ParticleKind::Wall, _) => {}
                (_, None) => {
                    return Err(SceneError::MissingMaterial {
                        body: b.name.clone(),
                    })
                }
                (ParticleKind::Fluid, Some(m)) if m.kind() != MaterialKind::Fluid => {
                    return Err(SceneError::MaterialKindMismatch {
                        body: b.name.clone(),
                    })
                }
                (ParticleKind::Solid, Some(m)) if m.kind() != MaterialKind::Solid => {
                    return Err(SceneError::MaterialKindMismatch {
                        body: b.name.clone(),
                    })
                }
                _ => {}
            }
            if b.kind == ParticleKind::Solid {
                // Boxes keep a structured mesh; any other geometry is meshed
                // by `solid_mesh` (Delaunay of its particles + alpha shape).
                let touches_wall = self.bodies.iter().any(|w| {
                    w.kind == ParticleKind::Wall
                        && boxes_touch(&b.geometry, &w.geometry, b.spacing.min(w.spacing))
                });
                let supported = !b.clamps.is_empty() || touches_wall || self.gravity.is_none();
                let floating = self.bodies.iter().any(|o| o.kind == ParticleKind::Fluid);
                if !supported && !floating {
                    return Err(SceneError::Unsupported {
                        body: b.name.clone(),
                    });
                }
            }
        }
        // Overlap: a box body's interior (shrunk by half a spacing) must not
        // contain another body's box interior.
        for (i, a) in self.bodies.iter().enumerate() {
            for b in self.bodies.iter().skip(i + 1) {
                if let (Geometry::Box { min: a0, max: a1 }, Geometry::Box { min: b0, max: b1 }) =
                    (&a.geometry, &b.geometry)
                {
                    let m = 0.5 * a.spacing.min(b.spacing);
                    let overlap = (0..D).all(|k| a0[k] + m < b1[k] - m && b0[k] + m < a1[k] - m);
                    if overlap {
                        return Err(SceneError::Overlap {
                            first: a.name.clone(),
                            second: b.name.clone(),
                        });
                    }
                }
            }
        }
        // Clamps and fields on bodies of the wrong kind.
        for b in &self.bodies {
            if !b.clamps.is_empty() && b.kind != ParticleKind::Solid {
                return Err(SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: "only a solid can be clamped".into(),
                });
            }
            if b.pressure_field.is_some() && b.kind != ParticleKind::Fluid {
                return Err(SceneError::InvalidGeometry {
                    body: b.name.clone(),
                    why: "only a fluid has an initial pressure field".into(),
                });
            }
        }
        let mut names: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
        names.sort_unstable();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(SceneError::InvalidGeometry {
                body: w[0].to_string(),
                why: "two bodies have this name".into(),
            });
        }
        Ok(())
    }
}

/// Whether the bounding boxes of two geometries touch (within `tol`).
fn boxes_touch<const D: usize>(a: &Geometry<D>, b: &Geometry<D>, tol: f64) -> bool
where
    Const<D>: Dim,
{
    let (a0, a1) = a.bounds();
    let (b0, b1) = b.bounds();
    (0..D).all(|k| a0[k] <= b1[k] + tol && b0[k] <= a1[k] + tol)
}
