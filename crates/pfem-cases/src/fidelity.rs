//! Fidelity presets: three points on the accuracy–cost curve measured by
//! `examples/accuracy_cost.rs` (see `docs/accuracy-cost.md`).
//!
//! A preset scales a case's default particle spacing and sets the Courant
//! number and the Picard tolerance:
//!
//! ```
//! use pfem_cases::cases::DamBreak;
//! use pfem_cases::fidelity::Fidelity;
//!
//! let f = Fidelity::Draft;
//! let mut case = DamBreak::default();
//! case.spacing = f.spacing(case.spacing);
//! let mut scene = case.scene();
//! f.apply(&mut scene.settings);
//! let params = f.step_params();
//! assert_eq!(params.picard_tolerance, f.picard_tolerance());
//! ```
//!
//! The errors and times quoted on each preset are those of the 2D dam break
//! (Martin & Moyce 1952, n² = 2, a = 2.25 in, front RMS relative error for
//! T = t √(2g/a) ≤ 3 after the best time shift), measured by the full study
//! of `docs/accuracy-cost.md` (1 December 2026, 2 cores);
//! `tests/presets.rs` checks the error bounds. On the dam break the front
//! error now falls with refinement along the spacing sweep (a/10 3.12 %,
//! a/14 2.66 %, a/20 1.60 %, a/28 1.13 %; order 1.03), though the presets,
//! which also change the Courant number and tolerance, are not ordered by
//! it; refinement pays on solids (cantilever: order 1.29).

use pfem_time::StepParams;

use crate::scene::RunSettings;

/// How much accuracy to buy with time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Fidelity {
    /// Quick look: twice the default spacing, Courant 1, Picard 1e-3.
    /// Dam break (a/10): front RMS error 2.48 %, 0.5 s wall time (study);
    /// tested bound 5 %.
    Draft,
    /// The library defaults: default spacing, Courant 0.5, Picard 1e-6.
    /// Dam break (a/20): front RMS error 1.60 %, 10.1 s wall time (study);
    /// tested bound 5 %.
    #[default]
    Standard,
    /// Refined: 0.7 × the default spacing, Courant 0.5, Picard 1e-6.
    /// Dam break (a/28.6): front RMS error 1.64 %, 24.7 s wall time
    /// (study): no better than Standard on this measure (Fine's Courant
    /// and tolerance are Standard's; the spacing sweep alone reaches
    /// 1.13 % at a/28). Meant
    /// for solids, where refinement does pay (cantilever: 4.20 % at t/8,
    /// 1.74 % at t/16). Tested bound 5 %.
    Fine,
}

impl Fidelity {
    /// All presets, coarsest first.
    pub const ALL: [Fidelity; 3] = [Fidelity::Draft, Fidelity::Standard, Fidelity::Fine];

    /// Factor on a case's default particle spacing.
    pub fn spacing_factor(self) -> f64 {
        match self {
            Fidelity::Draft => 2.0,
            Fidelity::Standard => 1.0,
            Fidelity::Fine => 0.7,
        }
    }

    /// Courant number (`RunSettings::courant`).
    pub fn courant(self) -> f64 {
        match self {
            Fidelity::Draft => 1.0,
            Fidelity::Standard | Fidelity::Fine => 0.5,
        }
    }

    /// Picard tolerance (`StepParams::picard_tolerance`).
    pub fn picard_tolerance(self) -> f64 {
        match self {
            Fidelity::Draft => 1e-3,
            Fidelity::Standard | Fidelity::Fine => 1e-6,
        }
    }

    /// The spacing for a case whose default spacing is `default` (m).
    pub fn spacing(self, default: f64) -> f64 {
        default * self.spacing_factor()
    }

    /// Cells across a length scale for a case whose default is `default`
    /// cells (the spacing scaled by [`Fidelity::spacing_factor`], rounded
    /// to a whole number of cells).
    pub fn cells(self, default: usize) -> usize {
        ((default as f64 / self.spacing_factor()).round() as usize).max(1)
    }

    /// Factor on a case's time step: the Courant number over the default
    /// 0.5 (for cases whose step is set in seconds rather than by the
    /// Courant limit).
    pub fn step_factor(self) -> f64 {
        self.courant() / 0.5
    }

    /// Sets the Courant number of `settings`.
    pub fn apply(self, settings: &mut RunSettings) {
        settings.courant = self.courant();
    }

    /// The default step parameters with this preset's Picard tolerance.
    pub fn step_params(self) -> StepParams {
        StepParams {
            picard_tolerance: self.picard_tolerance(),
            ..StepParams::default()
        }
    }

    /// Lower-case name (`draft`, `standard`, `fine`).
    pub fn name(self) -> &'static str {
        match self {
            Fidelity::Draft => "draft",
            Fidelity::Standard => "standard",
            Fidelity::Fine => "fine",
        }
    }
}
