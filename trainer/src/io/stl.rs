//! Binary STL output: an 80-byte header, the triangle count, then per triangle its unit
//! normal, three vertices (little-endian `f32`) and a zero attribute word.
//!
//! STL stores no shared vertices and no vertex normals; the facet normal is the triangle's
//! geometric normal (zero for a degenerate triangle), consistent with the counter-clockwise
//! winding seen from outside. Coordinates are rounded to `f32`, as the format requires.

use std::path::Path;

use crate::error::{Error, Result};
use crate::geometry::vector::{cross, norm, sub};

use super::mesh::{Mesh, check_writable};
use super::write_atomic_with;

/// Writes `mesh` as binary STL to `path`, atomically.
///
/// # Errors
/// [`Error::InvalidInput`] for indices out of range or more than `u32::MAX` triangles;
/// [`Error::Io`] when writing fails.
pub(crate) fn write_stl_mesh(path: &Path, mesh: &Mesh) -> Result<()> {
    check_writable(mesh, None)?;
    let count = u32::try_from(mesh.triangles.len())
        .map_err(|_| Error::invalid("too many triangles for STL (more than 2³² − 1)"))?;
    write_atomic_with(path, |w| {
        let mut header = [0_u8; 80];
        let text = b"neurosurf binary STL";
        header[..text.len()].copy_from_slice(text);
        w.write_all(&header)?;
        w.write_all(&count.to_le_bytes())?;
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let n = cross(sub(b, a), sub(c, a));
            let length = norm(n);
            let n = if length > 0.0 {
                n.map(|x| x / length)
            } else {
                [0.0; 3]
            };
            for p in [n, a, b, c] {
                for x in p {
                    w.write_all(&(x as f32).to_le_bytes())?;
                }
            }
            w.write_all(&[0, 0])?;
        }
        Ok(())
    })
}
