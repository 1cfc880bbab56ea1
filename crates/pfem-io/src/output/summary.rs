//! The end-of-run summary, `summary.json`.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{write_atomic, OutputError};

/// Figures that describe one run, written as `summary.json` by
/// [`write_summary`]. Maps are ordered by key so that two runs diff cleanly.
///
/// ```
/// use pfem_io::output::RunSummary;
///
/// let mut s = RunSummary { scene: "dam_break_2d".into(), particles: 1200, ..Default::default() };
/// s.wall_time_s.insert("remesh".into(), 1.5);
/// s.volume_change_by_cause.insert("alpha_shape".into(), -2.0e-6);
/// s.extra.insert("front_rmse".into(), 0.04.into());
/// let json = serde_json::to_value(&s).unwrap();
/// assert_eq!(json["wall_time_s"]["remesh"], 1.5);
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Scene name.
    pub scene: String,
    /// Spatial dimension (2 or 3).
    pub dimension: usize,
    /// Number of particles when the summary was written (the run's end;
    /// particles may come and go during it).
    pub particles: usize,
    /// Accepted time steps.
    pub steps: u64,
    /// Time steps rejected and retried (non-convergence, inverted
    /// elements…).
    pub rejected_steps: u64,
    /// Simulated time reached (s).
    #[serde(deserialize_with = "nan_from_null")]
    pub simulated_time: f64,
    /// Wall-clock time per stage (stage name → s), e.g. `"remesh"`,
    /// `"assemble"`, `"solve"`, `"update"`, `"hooks"`, `"output"`,
    /// `"total"`.
    #[serde(deserialize_with = "nans_from_nulls")]
    pub wall_time_s: BTreeMap<String, f64>,
    /// Fluid volume at the start (m³; m² per metre of depth in 2D).
    #[serde(deserialize_with = "nan_from_null")]
    pub fluid_volume_initial: f64,
    /// Fluid volume at the end (same unit).
    #[serde(deserialize_with = "nan_from_null")]
    pub fluid_volume_final: f64,
    /// The volume the run should end with (same unit): the initial one
    /// plus what sources (inflows, outflows) added or removed,
    /// `Simulation::volume().sources`. `None` in a summary written before
    /// it was recorded.
    #[serde(default)]
    pub fluid_volume_intended: Option<f64>,
    /// Volume gained (+) or lost (−) by cause (cause → the unit of
    /// [`RunSummary::fluid_volume_initial`]: m³; m² per metre of depth in
    /// 2D): `"remeshing"`, `"solution"` and each hook's name (e.g.
    /// `"volume correction"`).
    #[serde(deserialize_with = "nans_from_nulls")]
    pub volume_change_by_cause: BTreeMap<String, f64>,
    /// Any further figures (errors against references, fitted time shifts,
    /// solver statistics…).
    pub extra: BTreeMap<String, serde_json::Value>,
}

impl RunSummary {
    /// Relative error of the fluid volume, `(final − intended) /
    /// max(initial, intended)`: against the initial volume plus what
    /// sources added or removed ([`RunSummary::fluid_volume_intended`];
    /// the initial volume where that is not recorded), so that an
    /// inflow's water, or an outflow's loss, is not counted as an error.
    /// NaN when both volumes are zero.
    pub fn relative_volume_change(&self) -> f64 {
        let intended = self
            .fluid_volume_intended
            .filter(|v| v.is_finite())
            .unwrap_or(self.fluid_volume_initial);
        let scale = self.fluid_volume_initial.max(intended);
        if scale == 0.0 {
            f64::NAN
        } else {
            (self.fluid_volume_final - intended) / scale
        }
    }
}

/// A number written as `null` (NaN or ±∞, which JSON cannot express) is
/// read back as NaN.
fn nan_from_null<'de, De: serde::Deserializer<'de>>(d: De) -> Result<f64, De::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// [`nan_from_null`] for each value of a map.
fn nans_from_nulls<'de, De: serde::Deserializer<'de>>(
    d: De,
) -> Result<BTreeMap<String, f64>, De::Error> {
    Ok(BTreeMap::<String, Option<f64>>::deserialize(d)?
        .into_iter()
        .map(|(k, v)| (k, v.unwrap_or(f64::NAN)))
        .collect())
}

/// Writes `summary` to `path` as pretty-printed JSON, atomically. Non-finite
/// numbers (NaN, ±∞), which JSON cannot express, are written as `null`, and
/// read back as NaN.
pub fn write_summary(path: impl AsRef<Path>, summary: &RunSummary) -> Result<(), OutputError> {
    let path = path.as_ref();
    let mut bytes = serde_json::to_vec_pretty(summary).map_err(|source| OutputError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}
