//! Printing a command's result: a JSON document with `--json`, human text otherwise.

use anyhow::{Context, Result};
use neurosurf_core::scalar::ScalarKind;
use serde::Serialize;

/// Prints `value` as pretty JSON on stdout.
pub fn json<T: Serialize>(value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).context("cannot encode the JSON summary")?;
    println!("{text}");
    Ok(())
}

/// The scalar a blob stores its numbers in: `f32` or `q16.16` (blobs hold no `f64`).
pub fn blob_scalar(precision: neurosurf_trainer::evaluate::Precision) -> Result<ScalarKind> {
    use neurosurf_trainer::evaluate::Precision;
    match precision {
        Precision::F32 => Ok(ScalarKind::F32),
        Precision::Q16 => Ok(ScalarKind::Q16_16),
        Precision::F64 => anyhow::bail!("blobs store f32 or q16.16 numbers, not f64"),
    }
}

/// Says what a fitting command wrote: the blob (its size and scalar), then any extra file.
pub fn wrote_blob(
    path: &std::path::Path,
    bytes: usize,
    scalar: ScalarKind,
    extra: Option<&std::path::Path>,
) {
    println!(
        "wrote {} ({bytes} bytes, {})",
        path.display(),
        scalar.name()
    );
    if let Some(extra) = extra {
        println!("wrote {}", extra.display());
    }
}

/// Parses `N` comma-separated values (`800,600`) for an option such as `--size`.
pub fn comma_list<T: std::str::FromStr, const N: usize>(text: &str) -> Result<[T; N], String> {
    let values: Vec<T> = text
        .split(',')
        .map(|v| {
            v.trim()
                .parse()
                .map_err(|_| format!("'{}' is not a valid value", v.trim()))
        })
        .collect::<Result<_, _>>()?;
    let count = values.len();
    values
        .try_into()
        .map_err(|_| format!("expected {N} comma-separated values, got {count}"))
}

#[cfg(test)]
mod tests {
    use super::comma_list;

    #[test]
    fn comma_lists_have_their_exact_length() {
        assert_eq!(comma_list::<u32, 2>("800, 600"), Ok([800, 600]));
        assert_eq!(comma_list::<f64, 3>("1,0.5,2"), Ok([1.0, 0.5, 2.0]));
        assert!(comma_list::<u32, 2>("800").unwrap_err().contains("got 1"));
        assert!(comma_list::<u32, 2>("8,x").unwrap_err().contains("'x'"));
    }
}
