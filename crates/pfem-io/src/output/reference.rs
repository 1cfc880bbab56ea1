//! Published measurements the validation cases compare to, embedded in the
//! library so that examples and tests need no path. The same files are in
//! `data/validation/` with a README; the `#` lines of each text name the
//! source and the dimensionless groups. Parse with
//! [`parse_reference_csv`](super::parse_reference_csv):
//!
//! ```
//! use pfem_io::output::{parse_reference_csv, reference};
//!
//! let front = parse_reference_csv(reference::MARTIN_MOYCE_N2_2_A2_25IN_FRONT)?;
//! assert_eq!(front[0], (0.832, 1.217)); // (T = t·√(2g/a), Z = x/a)
//! # Ok::<(), pfem_io::output::ParseError>(())
//! ```
//!
//! The experiments released the water by lifting a gate; simulations
//! usually lag them by a short time shift, which a comparison may fit once
//! and must then report.

/// Martin & Moyce (1952), dam break with a column `a` wide and `2a` high
/// (n² = 2), `a` = 2.25 in: surge front `Z = x/a` against `T = t·√(2g/a)`.
pub const MARTIN_MOYCE_N2_2_A2_25IN_FRONT: &str =
    include_str!("../../../../data/validation/martin_moyce_1952_n2_2_a2.25in_front.csv");

/// Martin & Moyce (1952), n² = 2 as above with `a` = 1.125 in: surge front
/// `Z = x/a` against `T = t·√(2g/a)`.
pub const MARTIN_MOYCE_N2_2_A1_125IN_FRONT: &str =
    include_str!("../../../../data/validation/martin_moyce_1952_n2_2_a1.125in_front.csv");

/// Martin & Moyce (1952), square column (height = width = `H`, n² = 1):
/// surge front `Z = x/H` against `T = t·√(g/H)`.
pub const MARTIN_MOYCE_N2_1_FRONT: &str =
    include_str!("../../../../data/validation/martin_moyce_1952_n2_1_front.csv");

/// Martin & Moyce (1952), square column: residual height at the back wall
/// `h/H` against `t·√(g/H)`.
pub const MARTIN_MOYCE_N2_1_HEIGHT: &str =
    include_str!("../../../../data/validation/martin_moyce_1952_n2_1_height.csv");

/// Antoci, Gallati & Sibilla (2007), elastic gate: horizontal displacement
/// of the free end (m) against time (s). The first point is a digitisation
/// offset of about −0.3 mm.
pub const ANTOCI_2007_GATE_UX: &str =
    include_str!("../../../../data/validation/antoci_2007_gate_experiment_ux.csv");

/// Antoci, Gallati & Sibilla (2007), elastic gate: vertical displacement of
/// the free end (m, upward positive) against time (s).
pub const ANTOCI_2007_GATE_UY: &str =
    include_str!("../../../../data/validation/antoci_2007_gate_experiment_uy.csv");

#[cfg(test)]
mod tests {
    use super::super::parse_reference_csv;
    use super::*;

    #[test]
    fn all_embedded_tables_parse() {
        for text in [
            MARTIN_MOYCE_N2_2_A2_25IN_FRONT,
            MARTIN_MOYCE_N2_2_A1_125IN_FRONT,
            MARTIN_MOYCE_N2_1_FRONT,
            MARTIN_MOYCE_N2_1_HEIGHT,
            ANTOCI_2007_GATE_UX,
            ANTOCI_2007_GATE_UY,
        ] {
            assert!(text.starts_with('#'), "source line kept");
            let rows = parse_reference_csv(text).unwrap();
            assert!(rows.len() >= 9);
            assert!(rows.windows(2).all(|w| w[0].0 < w[1].0), "time increases");
        }
    }
}
