//! The firmware's defmt log, decoded with `defmt-decoder` from the ELF's tables.

use std::path::Path;

use defmt_decoder::{DecodeError, Table};

use crate::SimError;

/// The defmt table of a firmware ELF: its `bytes`, read from `elf`.
///
/// # Errors
/// [`SimError::Elf`] when the ELF has no (readable) defmt table.
pub fn table(elf: &Path, bytes: &[u8]) -> Result<Table, SimError> {
    let bad = |reason: String| SimError::Elf {
        path: elf.to_path_buf(),
        reason,
    };
    Table::parse(bytes)
        .map_err(|e| bad(format!("defmt table: {e}")))?
        .ok_or_else(|| bad("no defmt table".into()))
}

/// Decodes the defmt frames in `bytes` (the semihosting output of one run) into lines like
/// `INFO  evaluated 64 points`. Undecodable bytes end the log with a note, never an error:
/// the log is diagnostics, the result file is the answer.
pub fn decode(table: &Table, bytes: &[u8]) -> Vec<String> {
    let mut decoder = table.new_stream_decoder();
    decoder.received(bytes);
    let mut lines = Vec::new();
    loop {
        match decoder.decode() {
            Ok(frame) => {
                let level = frame
                    .level()
                    .map_or_else(|| "PRINT".to_string(), |l| l.as_str().to_uppercase());
                lines.push(format!("{level:<5} {}", frame.display_message()));
            }
            Err(DecodeError::UnexpectedEof) => break,
            Err(DecodeError::Malformed) => {
                lines.push("(undecodable log bytes follow)".to_string());
                break;
            }
        }
    }
    lines
}
