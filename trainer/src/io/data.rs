//! Where the public test meshes are: the repository's `data/` folder (see its README for each
//! mesh's source and terms), or the folder the `NEUROSURF_DATA` environment variable names.

use std::path::PathBuf;

use crate::error::{Error, Result};

/// Environment variable that overrides the test-mesh folder.
pub const DATA_VARIABLE: &str = "NEUROSURF_DATA";

/// The test-mesh folder: `$NEUROSURF_DATA` if set, else the repository's `data/`.
pub fn data_dir() -> PathBuf {
    match std::env::var_os(DATA_VARIABLE) {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../data"),
    }
}

/// The path of test mesh `name` (e.g. `spot.obj`).
///
/// # Errors
/// [`Error::InvalidInput`] saying where it looked and how to point elsewhere, when the file is
/// not there.
pub fn data_file(name: &str) -> Result<PathBuf> {
    let path = data_dir().join(name);
    if path.is_file() {
        return Ok(path);
    }
    Err(Error::invalid(format!(
        "test mesh {name} not found at {}: the repository ships it in data/; \
         set {DATA_VARIABLE}=DIR to use another folder",
        path.display()
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_mesh_names_where_it_looked_and_the_variable() {
        let e = data_file("no-such-mesh.obj").unwrap_err().to_string();
        assert!(
            e.contains("no-such-mesh.obj") && e.contains(DATA_VARIABLE),
            "{e}"
        );
    }
}
