//! Curves and spline surfaces as IGES 5.3 entities, the exchange form most CAD systems read.
//!
//! A curve becomes a rational B-spline curve (entity 126, form 0) on clamped knots
//! ([`clamped`]), so that it starts at its first control point and ends at its last over the
//! parameter range [0, 1] of [`BSplineCurve::point`]; a surface becomes a rational B-spline
//! surface (entity 128, form 0) on the uniform knots of [`export_surface`] with the parameter
//! range [0, 1]² of [`BSplineSurface::point`]. Every weight is 1 (the polynomial flag is set),
//! a closed curve or a tube is flagged closed, and a 2-D curve is flagged planar in z = 0.
//!
//! The file has the five fixed-column sections of the standard (Start, Global, Directory
//! Entry, Parameter Data, Terminate), in millimetres. Accuracy: reals are written with 17
//! significant digits, so de Boor's algorithm on the knots and control points read back
//! reproduces the model to within f64 rounding.

use crate::error::Result;

use super::export::{clamped, export_curve, export_surface};
use super::spline::{BSplineCurve, BSplineSurface};

/// Columns of a line that hold data in the Start, Global and Directory sections.
const DATA_COLUMNS: usize = 72;
/// Columns of a Parameter Data line that hold parameters (then a pointer to the entry).
const PARAMETER_COLUMNS: usize = 64;

/// One entity: its type number and its parameters, already formatted.
struct Entity {
    kind: u32,
    parameters: Vec<String>,
}

/// `curves` and `surfaces` as one IGES file, in that order.
///
/// # Errors
/// [`crate::Error::InvalidInput`] when a curve or a surface is not valid.
pub fn iges(curves: &[BSplineCurve], surfaces: &[BSplineSurface]) -> Result<Vec<u8>> {
    let mut entities = Vec::with_capacity(curves.len() + surfaces.len());
    for curve in curves {
        entities.push(curve_entity(curve)?);
    }
    for surface in surfaces {
        entities.push(surface_entity(surface)?);
    }
    let largest = curves
        .iter()
        .flat_map(|c| c.control.iter())
        .chain(surfaces.iter().flat_map(|s| s.control.iter()))
        .flatten()
        .fold(0.0, |m: f64, c| m.max(c.abs()));
    Ok(write(&entities, largest).into_bytes())
}

/// A real with a decimal point and 17 significant digits, as IGES wants it.
fn real(x: f64) -> String {
    format!("{x:.16E}")
}

/// Entity 126 for `curve`, on clamped knots.
fn curve_entity(curve: &BSplineCurve) -> Result<Entity> {
    let export = clamped(&export_curve(curve)?);
    let count = export.control_points.len();
    let planar = export.dimension == 2;
    let mut p = vec![
        "126".to_string(),
        (count - 1).to_string(),
        export.degree.to_string(),
        u8::from(planar).to_string(),
        u8::from(export.closed).to_string(),
        "1".into(),
        "0".into(),
    ];
    p.extend(export.knots.iter().map(|&k| real(k)));
    p.extend((0..count).map(|_| real(1.0)));
    for c in &export.control_points {
        p.extend((0..3).map(|k| real(c.get(k).copied().unwrap_or(0.0))));
    }
    p.extend(export.domain.map(real));
    p.extend([0.0, 0.0, if planar { 1.0 } else { 0.0 }].map(real));
    Ok(Entity {
        kind: 126,
        parameters: p,
    })
}

/// Entity 128 for `surface`, on its uniform knots.
fn surface_entity(surface: &BSplineSurface) -> Result<Entity> {
    let export = export_surface(surface)?;
    let mut p = vec![
        "128".to_string(),
        (export.count_u - 1).to_string(),
        (export.count_v - 1).to_string(),
        export.degree_u.to_string(),
        export.degree_v.to_string(),
        u8::from(export.closed_u).to_string(),
        u8::from(export.closed_v).to_string(),
        "1".into(),
        "0".into(),
        "0".into(),
    ];
    p.extend(export.knots_u.iter().map(|&k| real(k)));
    p.extend(export.knots_v.iter().map(|&k| real(k)));
    p.extend((0..export.control_points.len()).map(|_| real(1.0)));
    for c in &export.control_points {
        p.extend(c.map(real));
    }
    for range in export.domain {
        p.extend(range.map(real));
    }
    Ok(Entity {
        kind: 128,
        parameters: p,
    })
}

/// A Hollerith string: `nH` and the text.
fn hollerith(text: &str) -> String {
    format!("{}H{text}", text.len())
}

/// `text`'s 72 data columns, the section letter and the line number.
fn line(text: &str, section: char, number: usize) -> String {
    format!("{text:<DATA_COLUMNS$}{section}{number:>7}\n")
}

/// Tokens packed into lines of at most `width` columns, each token followed by `,` (the
/// last by `;`), never split across lines.
fn pack(tokens: &[String], width: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for (i, token) in tokens.iter().enumerate() {
        let delimiter = if i + 1 == tokens.len() { ';' } else { ',' };
        let piece = format!("{token}{delimiter}");
        let current = lines.last_mut().expect("one line");
        if !current.is_empty() && current.len() + piece.len() > width {
            lines.push(piece);
        } else {
            current.push_str(&piece);
        }
    }
    lines
}

/// The date and time now (UTC) as IGES writes it, `YYYYMMDD.HHNNSS`.
fn now() -> String {
    let seconds = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, time) = ((seconds / 86_400) as i64, seconds % 86_400);
    // Days since 1970-01-01 to the civil date (Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let day_of_era = z - era * 146_097;
    let year_of_era =
        (day_of_era - day_of_era / 1_460 + day_of_era / 36_524 - day_of_era / 146_096) / 365;
    let day_of_year = day_of_era - (365 * year_of_era + year_of_era / 4 - year_of_era / 100);
    let shifted_month = (5 * day_of_year + 2) / 153;
    let day = day_of_year - (153 * shifted_month + 2) / 5 + 1;
    let month = if shifted_month < 10 {
        shifted_month + 3
    } else {
        shifted_month - 9
    };
    let year = year_of_era + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}{month:02}{day:02}.{:02}{:02}{:02}",
        time / 3_600,
        time / 60 % 60,
        time % 60
    )
}

/// The five sections around `entities`; `largest` is the largest coordinate magnitude.
fn write(entities: &[Entity], largest: f64) -> String {
    let mut out = String::new();
    let start = ["neurosurf: B-spline curves and surfaces fitted to scattered points."];
    for (i, text) in start.iter().enumerate() {
        out.push_str(&line(text, 'S', i + 1));
    }
    let global = [
        "1H,".to_string(),
        "1H;".into(),
        hollerith("neurosurf"),
        hollerith("neurosurf.igs"),
        hollerith("neurosurf"),
        hollerith(env!("CARGO_PKG_VERSION")),
        "32".into(),
        "38".into(),
        "6".into(),
        "308".into(),
        "15".into(),
        hollerith("neurosurf"),
        real(1.0),
        "2".into(),
        hollerith("MM"),
        "1".into(),
        real(1.0),
        hollerith(&now()),
        real(1e-9),
        real(largest),
        hollerith(""),
        hollerith(""),
        "11".into(),
        "0".into(),
    ];
    let global_lines = pack(&global, DATA_COLUMNS);
    for (i, text) in global_lines.iter().enumerate() {
        out.push_str(&line(text, 'G', i + 1));
    }
    // Parameter lines first, to know where each entity's start.
    let mut parameter_lines = Vec::new();
    let mut directory = Vec::new();
    for (e, entity) in entities.iter().enumerate() {
        let entry = 2 * e + 1;
        let lines = pack(&entity.parameters, PARAMETER_COLUMNS);
        let first = parameter_lines.len() + 1;
        for text in &lines {
            parameter_lines.push(format!("{text:<PARAMETER_COLUMNS$} {entry:>7}"));
        }
        let field = |x: String| format!("{x:>8}");
        let first_line: String = [
            entity.kind.to_string(),
            first.to_string(),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "00000000".into(),
        ]
        .into_iter()
        .map(field)
        .collect();
        let second_line: String = [
            entity.kind.to_string(),
            "0".into(),
            "0".into(),
            lines.len().to_string(),
            "0".into(),
            String::new(),
            String::new(),
            String::new(),
            "0".into(),
        ]
        .into_iter()
        .map(field)
        .collect();
        directory.push(first_line);
        directory.push(second_line);
    }
    for (i, text) in directory.iter().enumerate() {
        out.push_str(&line(text, 'D', i + 1));
    }
    for (i, text) in parameter_lines.iter().enumerate() {
        out.push_str(&line(text, 'P', i + 1));
    }
    let counts = format!(
        "S{:>7}G{:>7}D{:>7}P{:>7}",
        start.len(),
        global_lines.len(),
        directory.len(),
        parameter_lines.len()
    );
    out.push_str(&line(&counts, 'T', 1));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::tests::de_boor;

    /// The parameters of each entity in `file`, read back from its Parameter Data lines.
    fn read_entities(file: &str) -> Vec<Vec<f64>> {
        let mut entities: Vec<(usize, String)> = Vec::new();
        for l in file.lines() {
            assert_eq!(l.len(), 80, "{l:?}");
            if l.as_bytes()[72] != b'P' {
                continue;
            }
            let entry: usize = l[65..72].trim().parse().unwrap();
            match entities.last_mut() {
                Some((e, text)) if *e == entry => text.push_str(&l[..64]),
                _ => entities.push((entry, l[..64].to_string())),
            }
        }
        entities
            .into_iter()
            .map(|(_, text)| {
                text.trim()
                    .trim_end_matches(';')
                    .split(',')
                    .map(|t| t.trim().replace('D', "E").parse().unwrap())
                    .collect()
            })
            .collect()
    }

    fn curve(degree: usize, closed: bool, dimension: usize) -> BSplineCurve {
        let control: Vec<[f64; 3]> = (0..9)
            .map(|i| {
                let a = i as f64 * 0.7;
                let z = if dimension == 3 { 0.3 * a } else { 0.0 };
                [a.cos() * (1.0 + 0.1 * i as f64), a.sin(), z]
            })
            .collect();
        BSplineCurve {
            dimension,
            closed,
            degree,
            control,
        }
    }

    /// Read back, the knots and control points give `point` to 1e-12 through de Boor's
    /// algorithm, for degrees 2, 3 and 5, open and closed, 2-D and 3-D curves; a surface (a
    /// tube, closed around u) likewise; every line is 80 columns and the Terminate line counts
    /// the sections.
    #[test]
    fn curves_and_surfaces_read_back_to_their_points() {
        let curves: Vec<BSplineCurve> = [(2, false, 2), (3, true, 2), (5, false, 3), (3, true, 3)]
            .into_iter()
            .map(|(d, c, n)| curve(d, c, n))
            .collect();
        let control: Vec<[f64; 3]> = (0..6 * 5)
            .map(|k| {
                let (i, j) = (k % 6, k / 6);
                let a = std::f64::consts::TAU * i as f64 / 6.0;
                [(1.0 + 0.1 * j as f64) * a.cos(), a.sin(), j as f64 * 0.5]
            })
            .collect();
        let surface = BSplineSurface {
            closed_u: true,
            closed_v: false,
            degree_u: 3,
            degree_v: 2,
            count_u: 6,
            count_v: 5,
            control,
        };
        let file =
            String::from_utf8(iges(&curves, std::slice::from_ref(&surface)).unwrap()).unwrap();
        assert!(file.contains(&format!("15H{}", &now()[..8])), "the date");
        let last = file.lines().last().unwrap();
        let count = |section: u8| file.lines().filter(|l| l.as_bytes()[72] == section).count();
        let expected = format!(
            "S{:>7}G{:>7}D{:>7}P{:>7}",
            count(b'S'),
            count(b'G'),
            count(b'D'),
            count(b'P')
        );
        assert!(
            last.starts_with(&expected) && last.ends_with("T      1"),
            "{last}"
        );
        assert_eq!(count(b'D'), 10);
        let entities = read_entities(&file);
        assert_eq!(entities.len(), 5);
        for (c, p) in curves.iter().zip(&entities) {
            assert_eq!(p[0], 126.0);
            let (k, m) = (p[1] as usize, p[2] as usize);
            assert_eq!(p[4], f64::from(u8::from(c.closed)));
            let knots = &p[7..7 + k + m + 2];
            let points_at = 7 + k + m + 2 + k + 1;
            let control: Vec<Vec<f64>> = (0..=k)
                .map(|i| p[points_at + 3 * i..points_at + 3 * i + 3].to_vec())
                .collect();
            for step in 0..=50 {
                let t = step as f64 / 50.0;
                let read = de_boor(knots, &control, m, t);
                let point = c.point(t);
                for axis in 0..3 {
                    assert!((read[axis] - point[axis]).abs() < 1e-12, "{c:?} at {t}");
                }
            }
        }
        let p = &entities[4];
        assert_eq!(
            p[..10],
            [128.0, 8.0, 4.0, 3.0, 2.0, 1.0, 0.0, 1.0, 0.0, 0.0]
        );
        let (ku, kv) = (p[1] as usize, p[2] as usize);
        let knots_u = &p[10..10 + ku + 3 + 2];
        let knots_v = &p[10 + ku + 5..10 + ku + 5 + kv + 2 + 2];
        let points_at = 10 + ku + 5 + kv + 4 + (ku + 1) * (kv + 1);
        for (u, v) in [(0.0, 0.0), (0.3, 0.7), (0.99, 0.5), (1.0, 1.0)] {
            // Along u in each row, then along v.
            let rows: Vec<Vec<f64>> = (0..=kv)
                .map(|j| {
                    let row: Vec<Vec<f64>> = (0..=ku)
                        .map(|i| {
                            let at = points_at + 3 * (j * (ku + 1) + i);
                            p[at..at + 3].to_vec()
                        })
                        .collect();
                    de_boor(knots_u, &row, 3, u)
                })
                .collect();
            let read = de_boor(knots_v, &rows, 2, v);
            let point = surface.point(u, v);
            for axis in 0..3 {
                assert!((read[axis] - point[axis]).abs() < 1e-12, "({u}, {v})");
            }
        }
    }
}
