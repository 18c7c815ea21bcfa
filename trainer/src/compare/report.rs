//! The rows of a fixed-versus-float comparison and their table.

use neurosurf_core::scalar::ScalarKind;
use serde::Serialize;

use super::agreement::Agreement;
use super::deviation::Deviation;
use super::measured::Measured;
use crate::error::Result;
use crate::table::{Align, Table};

/// Where an evaluation ran.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// The core on this computer.
    Host,
    /// The core on the simulated Cortex-M4F.
    Target,
}

impl Side {
    /// `host` or `target`.
    pub const fn name(self) -> &'static str {
        match self {
            Side::Host => "host",
            Side::Target => "target",
        }
    }
}

/// One evaluation measured against the `f64` reference (and, on the target, against the
/// host's evaluation in the same scalar).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CompareRow {
    /// `"<scalar> <side>"`, e.g. `q16.16 target`.
    pub row: String,
    /// The scalar: `f32` or `q16.16`.
    pub scalar: &'static str,
    /// Where it ran.
    pub on: Side,
    /// Its deviation from the `f64` reference.
    #[serde(flatten)]
    pub deviation: Deviation,
    /// Target rows: whether every value equals the host's bit for bit.
    pub bit_exact: Option<bool>,
    /// Target rows: values (4 per point) that differ from the host's.
    pub differing_values: Option<usize>,
    /// Target rows: the largest difference from the host in the scalar's last place (`f32`
    /// ulps, or Q16.16 steps of 2⁻¹⁶).
    pub max_ulp: Option<u64>,
}

impl CompareRow {
    /// The host's evaluation in `scalar` against the `reference`.
    ///
    /// # Errors
    /// When the sample lists differ in length.
    pub fn host<T: Measured>(scalar: ScalarKind, reference: &[T], host: &[T]) -> Result<Self> {
        Ok(CompareRow {
            row: format!("{} host", scalar.name()),
            scalar: scalar.name(),
            on: Side::Host,
            deviation: Deviation::measure(reference, host)?,
            bit_exact: None,
            differing_values: None,
            max_ulp: None,
        })
    }

    /// The target's evaluation in `scalar` against the `reference` and against the `host`'s.
    ///
    /// # Errors
    /// When the sample lists differ in length.
    pub fn target<T: Measured>(
        scalar: ScalarKind,
        reference: &[T],
        target: &[T],
        host: &[T],
    ) -> Result<Self> {
        let agreement = Agreement::measure(scalar, host, target)?;
        Ok(CompareRow {
            row: format!("{} target", scalar.name()),
            scalar: scalar.name(),
            on: Side::Target,
            deviation: Deviation::measure(reference, target)?,
            bit_exact: Some(agreement.bit_exact),
            differing_values: Some(agreement.differing_values),
            max_ulp: Some(agreement.max_ulp),
        })
    }
}

/// What the columns of a comparison are called: the value's symbol (`Φ`, or `p` for a
/// position) and the direction's name (`normal`, `tangent`).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Quantities {
    /// Symbol of the value.
    pub value: &'static str,
    /// Name of the direction.
    pub direction: &'static str,
}

impl Quantities {
    /// Implicit fields: Φ and the normal −∇Φ/|∇Φ|.
    pub const FIELD: Quantities = Quantities {
        value: "Φ",
        direction: "normal",
    };
    /// Curves: the position p and the tangent.
    pub const CURVE: Quantities = Quantities {
        value: "p",
        direction: "tangent",
    };
    /// Spline surfaces: the position p and the normal.
    pub const SURFACE: Quantities = Quantities {
        value: "p",
        direction: "normal",
    };
}

/// The rows as a table: field errors in scientific notation, angles in degrees, `—` where a
/// value does not apply.
pub fn comparison_table(rows: &[CompareRow]) -> Table {
    comparison_table_of(rows, Quantities::FIELD)
}

/// [`comparison_table`] with the columns named after `quantities`.
pub fn comparison_table_of(rows: &[CompareRow], quantities: Quantities) -> Table {
    let (value, direction) = (quantities.value, quantities.direction);
    let mut table = Table::new([
        ("evaluation".to_string(), Align::Left),
        (format!("max |Δ{value}|"), Align::Right),
        (format!("RMS Δ{value}"), Align::Right),
        ("max angle".to_string(), Align::Right),
        ("median angle".to_string(), Align::Right),
        (format!("no {direction}"), Align::Right),
        ("= host bits".to_string(), Align::Right),
        ("max ulp".to_string(), Align::Right),
    ]);
    let none = || "—".to_string();
    let exp = |v: Option<f64>| v.map_or_else(none, |v| format!("{v:.3e}"));
    let degrees = |v: Option<f64>| v.map_or_else(none, |v| format!("{}°", significant(v)));
    for r in rows {
        let d = &r.deviation;
        table.push([
            r.row.clone(),
            exp(d.field_max),
            exp(d.field_rms),
            degrees(d.normal_max_degrees),
            degrees(d.normal_median_degrees),
            d.normals_skipped.to_string(),
            match (r.bit_exact, r.differing_values) {
                (Some(true), _) => "yes".to_string(),
                (Some(false), Some(n)) => format!("no ({n} values)"),
                _ => none(),
            },
            r.max_ulp.map_or_else(none, |u| u.to_string()),
        ]);
    }
    table
}

/// `v` to 3 significant digits: fixed point from 0.001 up, scientific below.
fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if v.abs() < 1e-3 {
        return format!("{v:.2e}");
    }
    let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_keep_three_significant_digits() {
        assert_eq!(significant(0.0), "0");
        assert_eq!(significant(5.6162e-5), "5.62e-5");
        assert_eq!(significant(0.0080312), "0.00803");
        assert_eq!(significant(0.5), "0.500");
        assert_eq!(significant(12.345), "12.3");
        assert_eq!(significant(180.0), "180");
    }

    #[test]
    fn rows_measure_against_the_reference_and_the_host() {
        let reference = vec![(0.0, [0.0, 0.0, 1.0]), (0.5, [1.0, 0.0, 0.0])];
        let host = vec![(0.25, [0.0, 0.0, 1.0]), (0.5, [1.0, 1.0, 0.0])];
        let mut target = host.clone();
        let host_row = CompareRow::host(ScalarKind::Q16_16, &reference, &host).unwrap();
        assert_eq!(host_row.row, "q16.16 host");
        assert_eq!(host_row.deviation.field_max, Some(0.25));
        assert_eq!(host_row.deviation.normal_max_degrees, Some(45.0));
        assert_eq!(host_row.bit_exact, None);
        let same = CompareRow::target(ScalarKind::Q16_16, &reference, &target, &host).unwrap();
        assert_eq!((same.bit_exact, same.max_ulp), (Some(true), Some(0)));
        target[1].0 += 3.0 / 65536.0;
        let off = CompareRow::target(ScalarKind::Q16_16, &reference, &target, &host).unwrap();
        assert_eq!(off.row, "q16.16 target");
        assert_eq!(
            (off.bit_exact, off.differing_values, off.max_ulp),
            (Some(false), Some(1), Some(3))
        );
        let json = serde_json::to_value(&off).unwrap();
        assert_eq!(json["bit_exact"], false);
        assert_eq!(json["on"], "target");
        assert_eq!(json["normal_max_degrees"], 45.0);

        let text = comparison_table(&[host_row, same, off]).to_text();
        assert!(text.contains("no (1 values)"), "{text}");
        assert!(text.lines().nth(1).unwrap().starts_with("q16.16 host"));
    }
}
