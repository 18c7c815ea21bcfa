//! Query point lists: PLY, or whitespace-separated text.

use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};

use super::mesh::extension;
use super::ply::read_ply_positions;

/// Reads points at which to evaluate a model.
///
/// A file whose extension is `.ply` (any case), or which starts with the `ply` magic line, is
/// read as PLY: the `x y z` of its `vertex` element. Anything else is whitespace-separated
/// text: blank lines and lines whose first non-blank character is `#` are skipped, a first
/// line of column names (`x y z`, `x,y,z`) is a header, and every other line holds exactly 3
/// numbers (`x y z`) or 6 (`x y z nx ny nz`, the normal is ignored), separated by white
/// space, commas or semicolons. An empty list is not an error.
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::Format`] naming the line (text) or
/// vertex (PLY) and the offending token for unparseable lines, a wrong number of values, or
/// a coordinate that is not finite.
pub fn read_query_points(path: &Path) -> Result<Vec<[f64; 3]>> {
    if extension(path).as_deref() == Some("ply") || has_ply_magic(path)? {
        let points = read_ply_positions(path)?;
        if let Some((i, p)) = points
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
        {
            return Err(Error::format(
                path,
                format!("vertex {i} has a non-finite coordinate {p:?}"),
            ));
        }
        return Ok(points);
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_text_points(path, &bytes)
}

/// Whether the file starts with the PLY magic line.
fn has_ply_magic(path: &Path) -> Result<bool> {
    let mut head = [0u8; 4];
    let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut filled = 0;
    while filled < head.len() {
        match file.read(&mut head[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(Error::io(path, e)),
        }
    }
    Ok(&head[..filled] == b"ply\n" || &head[..filled] == b"ply\r")
}

fn parse_text_points(path: &Path, bytes: &[u8]) -> Result<Vec<[f64; 3]>> {
    let rows = parse_rows(
        path,
        bytes,
        &[3, 6],
        "3 numbers (x y z) or 6 (x y z nx ny nz)",
    )?;
    Ok(rows.iter().map(|row| first_three(row)).collect())
}

/// Most coordinates of a parameter point (a Cao En network's source dimension).
pub const MAX_PARAMETERS: usize = neurosurf_core::caoen::MAX_SOURCE_DIMENSION;

/// Reads the parameters of a parametric model, one point per line with exactly `arity`
/// numbers — 1 (t) for curves, 2 (u v) for spline surfaces, m for a Cao En network's source
/// point — in the text format of [`read_query_points`].
///
/// # Errors
/// As [`read_query_points`]; [`Error::InvalidInput`] for an arity outside 1 ..=
/// [`MAX_PARAMETERS`].
pub fn read_parameters(path: &Path, arity: usize) -> Result<Vec<Vec<f64>>> {
    let expected = match arity {
        1 => "1 number (t)".to_string(),
        2 => "2 numbers (u v)".to_string(),
        3..=MAX_PARAMETERS => format!("{arity} numbers (a source point)"),
        _ => {
            return Err(Error::invalid(format!(
                "parameters have 1 to {MAX_PARAMETERS} coordinates, not {arity}"
            )));
        }
    };
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_rows(path, &bytes, &[arity], &expected)
}

/// Reads rows of numbers with the same count on every line (1 to 64), in the text format of
/// [`read_query_points`] (blank and `#` lines skipped).
///
/// # Errors
/// As [`read_query_points`], and [`Error::Format`] naming the first line whose count differs
/// from the first row's.
pub fn read_rows(path: &Path) -> Result<Vec<Vec<f64>>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let counts: Vec<usize> = (1..=64).collect();
    let rows = parse_rows(path, &bytes, &counts, "1 to 64 numbers")?;
    let width = rows.first().map_or(0, Vec::len);
    if let Some(i) = rows.iter().position(|r| r.len() != width) {
        return Err(Error::format(
            path,
            format!(
                "row {}: {} numbers where the first row has {width}",
                i + 1,
                rows[i].len()
            ),
        ));
    }
    Ok(rows)
}

/// The first three numbers of a row, zero-padded.
fn first_three(row: &[f64]) -> [f64; 3] {
    [0, 1, 2].map(|k| row.get(k).copied().unwrap_or(0.0))
}

/// Reads scattered 2-D or 3-D points (a curve's samples): PLY (3-D), or text with 2 (x y) or
/// 3 (x y z) numbers on every line — the same count on all of them. Returns the dimension and
/// the points (z = 0 in 2-D).
///
/// # Errors
/// As [`read_query_points`], and [`Error::Format`] when lines mix 2 and 3 numbers.
pub fn read_scattered_points(path: &Path) -> Result<(usize, Vec<[f64; 3]>)> {
    if extension(path).as_deref() == Some("ply") || has_ply_magic(path)? {
        return Ok((3, read_query_points(path)?));
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let rows = parse_rows(path, &bytes, &[2, 3], "2 numbers (x y) or 3 (x y z)")?;
    let dimension = rows.first().map_or(3, Vec::len);
    if let Some(line) = rows.iter().position(|row| row.len() != dimension) {
        return Err(Error::format(
            path,
            format!(
                "point {}: {} numbers where the first point has {dimension}",
                line + 1,
                rows[line].len()
            ),
        ));
    }
    Ok((dimension, rows.iter().map(|row| first_three(row)).collect()))
}

/// Whitespace-separated rows of finite numbers: blank and `#` lines skipped, every other line
/// holds one of `counts` numbers (`expected` says which, for errors).
fn parse_rows(
    path: &Path,
    bytes: &[u8],
    counts: &[usize],
    expected: &str,
) -> Result<Vec<Vec<f64>>> {
    let mut rows = Vec::new();
    let mut first = true;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = i + 1;
        let err = |message: String| Error::format(path, format!("line {line_no}: {message}"));
        let line = std::str::from_utf8(raw).map_err(|_| err("not valid UTF-8".into()))?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        // Values are separated by white space, commas or semicolons (CSV as spreadsheets
        // write it); a first line of names only (`x y z`, `x,y,z`) is a header.
        let tokens: Vec<&str> = line
            .split(|c: char| c.is_ascii_whitespace() || c == ',' || c == ';')
            .filter(|t| !t.is_empty())
            .collect();
        if std::mem::take(&mut first) && is_header(&tokens) {
            continue;
        }
        let mut values = Vec::new();
        for &token in &tokens {
            let value: f64 = token
                .parse()
                .map_err(|_| err(format!("'{token}' is not a number")))?;
            if !value.is_finite() {
                return Err(err(format!("'{token}' is not a finite number")));
            }
            values.push(value);
        }
        if !counts.contains(&values.len()) {
            return Err(err(format!("expected {expected}, found {}", values.len())));
        }
        rows.push(values);
    }
    Ok(rows)
}

/// Whether a line's tokens are column names: none is a number, each starts with a letter.
fn is_header(tokens: &[&str]) -> bool {
    !tokens.is_empty()
        && tokens.iter().all(|t| {
            t.parse::<f64>().is_err() && t.chars().next().is_some_and(|c| c.is_alphabetic())
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_header_line_and_commas_or_semicolons_are_read() {
        let text = "x,y,z\n1,2,3\n4, 5, 6\n7;8;9\n";
        assert_eq!(
            parse(text).unwrap(),
            vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]]
        );
        assert_eq!(
            parse("# comment\nx y z nx ny nz\n1 2 3 0 0 1\n").unwrap(),
            vec![[1.0, 2.0, 3.0]]
        );
        // Only the first line may be a header; `nan` and `inf` are numbers, not names.
        let late = message(parse("1 2 3\nx y z\n").unwrap_err());
        assert!(late.contains("line 2") && late.contains("'x'"), "{late}");
        let nan = message(parse("nan 1 2\n").unwrap_err());
        assert!(nan.contains("finite"), "{nan}");
    }

    fn parse(text: &str) -> Result<Vec<[f64; 3]>> {
        parse_text_points(Path::new("q.txt"), text.as_bytes())
    }

    fn message(e: Error) -> String {
        match e {
            Error::Format { path, message } => {
                assert_eq!(path, Path::new("q.txt"));
                message
            }
            other => panic!("expected a format error, got {other:?}"),
        }
    }

    #[test]
    fn parses_three_and_six_columns_with_comments() {
        let text = "# query points\n\n  1 2 3\n\t-1.5e-3   0 +4\r\n  # indented comment\n\
                    7 8 9 0 0 1\n   \n";
        assert_eq!(
            parse(text).unwrap(),
            vec![[1.0, 2.0, 3.0], [-1.5e-3, 0.0, 4.0], [7.0, 8.0, 9.0]]
        );
        assert_eq!(parse("").unwrap(), Vec::<[f64; 3]>::new());
        assert_eq!(parse("# nothing\n").unwrap(), Vec::<[f64; 3]>::new());
    }

    #[test]
    fn errors_name_line_and_token() {
        let e = message(parse("1 2 3\n\n4 five 6\n").unwrap_err());
        assert!(e.contains("line 3") && e.contains("'five'"), "{e}");
        let e = message(parse("1 2 3\n1 2\n").unwrap_err());
        assert!(e.contains("line 2") && e.contains("found 2"), "{e}");
        let e = message(parse("# c\n1 2 3 4\n").unwrap_err());
        assert!(e.contains("line 2") && e.contains("found 4"), "{e}");
        let e = message(parse("1 2 3 4 5 6 7\n").unwrap_err());
        assert!(e.contains("line 1") && e.contains("found 7"), "{e}");
        let e = message(parse("1 2 3\n0 nan 0\n").unwrap_err());
        assert!(e.contains("line 2") && e.contains("'nan'"), "{e}");
        let e = message(parse("1,2,3\n4,5,z\n").unwrap_err());
        assert!(e.contains("line 2") && e.contains("'z'"), "{e}");
        let e = message(parse_text_points(Path::new("q.txt"), b"1 2 3\n\xff 1 2\n").unwrap_err());
        assert!(e.contains("line 2") && e.contains("UTF-8"), "{e}");
    }

    #[test]
    fn parameters_and_scattered_points_have_their_own_column_counts() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.txt");
        std::fs::write(&path, "# t\n0\n0.5\n1\n").unwrap();
        assert_eq!(
            read_parameters(&path, 1).unwrap(),
            vec![vec![0.0], vec![0.5], vec![1.0]]
        );
        let e = read_parameters(&path, 2).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("2 numbers (u v)"), "{e}");
        let e = read_parameters(&path, 4).unwrap_err().to_string();
        assert!(e.contains("4 numbers (a source point)"), "{e}");
        assert!(read_parameters(&path, 9).is_err());

        std::fs::write(&path, "1 2\n3 4\n").unwrap();
        assert_eq!(
            read_scattered_points(&path).unwrap(),
            (2, vec![[1.0, 2.0, 0.0], [3.0, 4.0, 0.0]])
        );
        std::fs::write(&path, "1 2 3\n4 5 6\n").unwrap();
        assert_eq!(read_scattered_points(&path).unwrap().0, 3);
        std::fs::write(&path, "1 2\n4 5 6\n").unwrap();
        let e = read_scattered_points(&path).unwrap_err().to_string();
        assert!(
            e.contains("point 2") && e.contains("first point has 2"),
            "{e}"
        );
        std::fs::write(&path, "1 2\n4 NaN\n").unwrap();
        let e = read_scattered_points(&path).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("NaN"), "{e}");
    }

    #[test]
    fn chooses_ply_by_extension_or_magic() {
        let dir = tempfile::tempdir().unwrap();
        let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                   property float z\nend_header\n1 2 3\n4 5 6\n";
        let expected = vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]];
        for name in ["q.ply", "q.PLY", "q.dat"] {
            let path = dir.path().join(name);
            std::fs::write(&path, ply).unwrap();
            assert_eq!(read_query_points(&path).unwrap(), expected, "{name}");
        }
        let path = dir.path().join("q.xyz");
        std::fs::write(&path, "1 2 3\n4 5 6 0 0 1\n").unwrap();
        assert_eq!(read_query_points(&path).unwrap(), expected);
        // A short text file is not mistaken for PLY.
        let path = dir.path().join("short.txt");
        std::fs::write(&path, "1 2 3").unwrap();
        assert_eq!(read_query_points(&path).unwrap(), vec![[1.0, 2.0, 3.0]]);

        let path = dir.path().join("text.ply");
        std::fs::write(&path, "1 2 3\n").unwrap();
        assert!(matches!(
            read_query_points(&path),
            Err(Error::Format { .. })
        ));
        let e = read_query_points(&dir.path().join("missing.txt")).unwrap_err();
        assert!(matches!(e, Error::Io { .. }), "{e}");
    }

    #[test]
    fn non_finite_ply_query_points_are_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("nan.ply");
        let mut bytes =
            b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\n\
                          property double y\nproperty double z\nend_header\n"
                .to_vec();
        for v in [0.0, 1.0, 2.0, 3.0, f64::INFINITY, 5.0] {
            bytes.extend(f64::to_le_bytes(v));
        }
        std::fs::write(&path, bytes).unwrap();
        let e = read_query_points(&path).unwrap_err();
        assert!(
            matches!(e, Error::Format { .. }) && e.to_string().contains("vertex 1"),
            "{e}"
        );
    }
}
