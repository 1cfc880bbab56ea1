//! A one-line progress display on stderr.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

#[cfg(feature = "progress")]
use indicatif::{ProgressBar, ProgressStyle};

/// Without the `progress` feature (indicatif), a plain line redrawn in
/// place with a carriage return.
#[cfg(not(feature = "progress"))]
#[derive(Debug)]
struct ProgressBar;

#[cfg(not(feature = "progress"))]
impl ProgressBar {
    fn set_position(&self, _: u64) {}
    fn set_message(&self, msg: String) {
        use std::io::Write;
        let mut e = std::io::stderr();
        let _ = write!(e, "\r{msg}    ");
        let _ = e.flush();
    }
    fn println(&self, line: &str) {
        crate::errln!("\r{line}");
    }
    fn finish_with_message(&self, msg: String) {
        crate::errln!("\r{msg}    ");
    }
}

#[cfg(feature = "progress")]
fn new_bar() -> ProgressBar {
    let style =
        ProgressStyle::with_template("{elapsed_precise} [{bar:30.cyan/blue}] {msg}  ETA {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
    ProgressBar::new(TICKS).with_style(style)
}

#[cfg(not(feature = "progress"))]
fn new_bar() -> ProgressBar {
    ProgressBar
}

/// Bar resolution: positions per run.
const TICKS: u64 = 10_000;
/// Shortest interval between two redraws of the message.
const REDRAW: Duration = Duration::from_millis(100);
/// Interval between two plain progress lines when stderr is not a terminal
/// (a log file, a batch job).
pub const LOG_EVERY: Duration = Duration::from_secs(30);

/// Shows simulated time / end time, the time step and the estimated time
/// left on stderr, as a bar that redraws in place.
///
/// When stderr is not a terminal (a log file, a batch job, CI) it prints a
/// plain line every [`LOG_EVERY`] of wall time instead; nothing when
/// `quiet` is set. Drivers can call it unconditionally:
///
/// ```
/// use pfem_io::output::Progress;
///
/// let mut progress = Progress::new(1.0, true);
/// let (mut t, dt) = (0.0, 0.25);
/// while t < 1.0 {
///     t += dt;
///     progress.update(t, dt);
/// }
/// progress.finish();
/// ```
#[derive(Debug)]
pub struct Progress {
    bar: Option<ProgressBar>,
    end_time: f64,
    quiet: bool,
    last_message: Option<Instant>,
    /// Latest `(t, dt)`, shown by [`finish`](Self::finish).
    latest: (f64, f64),
    /// Without a bar and not quiet: the start, the last line printed and
    /// the interval between lines.
    log: Option<(Instant, Instant, Duration)>,
}

impl Progress {
    /// A progress display for a run that ends at simulated time `end_time`
    /// (s): a bar on a terminal, a line every [`LOG_EVERY`] otherwise,
    /// nothing when `quiet`.
    pub fn new(end_time: f64, quiet: bool) -> Self {
        let mut p = Self::log_every(end_time, quiet, LOG_EVERY);
        if p.log.is_some() && std::io::stderr().is_terminal() {
            p.log = None;
            p.bar = Some(new_bar());
        }
        p
    }

    /// Plain progress lines every `interval` of wall time (none when
    /// `quiet`), whatever stderr is.
    pub fn log_every(end_time: f64, quiet: bool, interval: Duration) -> Self {
        let now = Instant::now();
        Self {
            bar: None,
            end_time,
            quiet,
            last_message: None,
            latest: (0.0, 0.0),
            log: (!quiet).then_some((now, now, interval)),
        }
    }

    /// Whether a bar is drawn.
    pub fn is_enabled(&self) -> bool {
        self.bar.is_some()
    }

    /// Whether plain progress lines are printed (stderr not a terminal).
    pub fn is_logging(&self) -> bool {
        self.log.is_some()
    }

    /// Reports that the simulation reached time `t` (s) with a last step of
    /// `dt` (s). Cheap enough to call every step: the text is redrawn at
    /// most ten times a second.
    pub fn update(&mut self, t: f64, dt: f64) {
        if let Some((start, last, every)) = self.log {
            let now = Instant::now();
            if now.duration_since(last) >= every {
                self.log = Some((start, now, every));
                let done = 100.0 * self.position(t) as f64 / TICKS as f64;
                crate::errln!(
                    "[{:.0} s] {} ({done:.1} %)",
                    now.duration_since(start).as_secs_f64(),
                    self.message(t, dt)
                );
            }
            return;
        }
        let Some(bar) = &self.bar else { return };
        self.latest = (t, dt);
        bar.set_position(self.position(t));
        let now = Instant::now();
        if self
            .last_message
            .is_none_or(|last| now.duration_since(last) >= REDRAW)
        {
            self.last_message = Some(now);
            bar.set_message(self.message(t, dt));
        }
    }

    fn message(&self, t: f64, dt: f64) -> String {
        format!("t = {t:.4} / {:.4} s  Δt = {dt:.2e} s", self.end_time)
    }

    /// Prints a line to stderr: above the bar when it is shown, as a plain
    /// line when stderr is not a terminal, not at all when `quiet`.
    pub fn println(&self, line: &str) {
        match &self.bar {
            Some(bar) => bar.println(line),
            None if !self.quiet => crate::errln!("{line}"),
            None => {}
        }
    }

    /// Leaves the bar in its final state on the terminal.
    pub fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            let (t, dt) = self.latest;
            bar.finish_with_message(self.message(t, dt));
        }
    }

    fn position(&self, t: f64) -> u64 {
        let fraction = if self.end_time > 0.0 {
            (t / self.end_time).clamp(0.0, 1.0)
        } else {
            1.0
        };
        if fraction.is_nan() {
            0
        } else {
            (fraction * TICKS as f64).round() as u64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_a_terminal_lines_are_logged_unless_quiet() {
        let mut p = Progress::log_every(1.0, false, Duration::ZERO);
        assert!(p.is_logging() && !p.is_enabled());
        p.update(0.5, 0.01);
        assert!(p.log.unwrap().1 > p.log.unwrap().0, "a line was due");
        let p = Progress::log_every(1.0, true, Duration::ZERO);
        assert!(!p.is_logging());
        // In a test, stderr is not a terminal: lines every LOG_EVERY.
        if !std::io::stderr().is_terminal() {
            assert!(Progress::new(1.0, false).is_logging());
            assert!(!Progress::new(1.0, true).is_logging());
        }
    }

    #[test]
    fn quiet_is_disabled_and_positions_clamp() {
        let mut p = Progress::new(2.0, true);
        assert!(!p.is_enabled());
        assert_eq!(p.position(1.0), TICKS / 2);
        assert_eq!(p.position(5.0), TICKS);
        assert_eq!(p.position(-1.0), 0);
        assert_eq!(p.position(f64::NAN), 0);
        p.update(1.0, 0.1);
        p.finish();
    }
}
