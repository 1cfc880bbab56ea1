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
//! The errors and times quoted on each preset were measured by the full
//! study of `docs/accuracy-cost.md` (6 December 2026, 2 cores) on every
//! case with a reference: circular Couette flow (velocity RMS), the first
//! sloshing mode (frequency), the CSM2 cantilever (static deflection, first
//! frequency) and the 2D dam break (front against a run at a/45, and
//! against Martin & Moyce 1952, T ≤ 2.5 after the best time shift);
//! `tests/presets.rs` holds each preset to them (+25 %). Along the study's
//! knobs, refining the spacing is the one that keeps buying accuracy on
//! every case (the time step pays until its error falls below the
//! spacing's: on the standing wave, T/40 instead of T/20 at 20 cells cuts
//! the error 3× for 1.5× the time, T/80 only 6 % more); the Picard
//! tolerance changes no error on the exact cases (1e-3 saves 0–23 % of
//! the time, single short runs) and little on the dam break. The times
//! below are `Simulation::run`'s, summed over the five cases. Standard keeps the
//! library's defaults (1e-6), with which the hard cases of the stability
//! suite were verified.

use pfem_time::StepParams;

use crate::scene::RunSettings;

/// How much accuracy to buy with time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Fidelity {
    /// Quick look: twice the default spacing, Courant 0.5, Picard 1e-3.
    /// Couette 2.3 %, standing wave 3.8 %, cantilever static 34 % and
    /// frequency 22 % (two linear triangles through the thickness lock in
    /// bending), dam break (a/10) 9.1 % against a/45 and 2.0 % against the
    /// experiment; its runs of the study take about 0.3 s together.
    Draft,
    /// The library defaults: default spacing, Courant 0.5, Picard 1e-6.
    /// Couette 0.33 % (0.8 s), standing wave 0.65 % (0.07 s), cantilever
    /// static 11.5 % and frequency 5.9 %, dam break (a/20) 1.9 % against
    /// a/45 and 1.8 % against the experiment; about 2.5 s together.
    #[default]
    Standard,
    /// Refined: 0.7 × the default spacing, Courant 0.5, Picard 1e-6.
    /// Couette 0.19 % (1.1 s), standing wave 0.27 % (0.2 s), cantilever
    /// static 5.6 % and frequency 2.6 %, dam break (a/29) 1.2 % against
    /// a/45 and 1.1 % against the experiment; about 6.1 s together: about
    /// 3.0× Standard's time on the dam break for 0.62 of its difference to
    /// a/45 (a biased measure, `docs/accuracy-cost.md`: 0.74 to 0.86 of
    /// Standard's error with the orders its four points also fit).
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

    /// Courant number (`RunSettings::courant`): the default 0.5 for every
    /// preset. On the dam break the study found Courant 1 (Draft's before)
    /// a poor trade: at a/16 it rejected 11 of 84 steps and saved 1 % of
    /// the time (11 % on 2 December) for a front 9 % further from a/45.
    pub fn courant(self) -> f64 {
        0.5
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
