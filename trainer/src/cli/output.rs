//! Printing a command's result: a JSON document with `--json`, human text otherwise.

use anyhow::{Context, Result};
use serde::Serialize;

/// Prints `value` as pretty JSON on stdout.
pub fn json<T: Serialize>(value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).context("cannot encode the JSON summary")?;
    println!("{text}");
    Ok(())
}
