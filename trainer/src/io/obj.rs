//! Wavefront OBJ meshes: read with the `tobj` crate (positions and faces, vertex numbering
//! kept), written by a few lines of text here (tobj has no writer).

use std::io::{BufReader, Read};
use std::path::Path;

use crate::error::{Error, Result};

use super::mesh::{Mesh, check_writable};
use super::write_atomic_with;

/// Reads the positions and faces of an OBJ file with tobj; polygons are fan-triangulated.
///
/// Statements are what tobj understands: `v x y z [w]` (a weight divides the coordinates)
/// or `v x y z r g b`; `f` with indices `v`, `v/vt`, `v//vn` or `v/vt/vn`, negative ones
/// relative to the vertices read so far; everything else (`vt`, `vn`, `o`, `g`, `s`, `usemtl`,
/// `mtllib`, comments, …) is ignored and no material file is opened. Faces with fewer than 3
/// vertices are skipped (tobj reads `l` lines as such faces). The mesh is not validated here.
///
/// The result keeps the file's vertex numbering: every `v`, in file order, used or not, so
/// indices match the file's. tobj itself would split the file at `o`/`g` statements into
/// models whose vertices are renumbered in order of first use, dropping unused ones and
/// duplicating shared ones; to avoid that the reader hides `o`/`g` statements from tobj (one
/// model) and prepends one synthetic polygon `f 1 2 … n` through all `n` vertices, which fixes
/// the numbering, and is then dropped.
/// Blanks the `/vt/vn` part of every index of a face or line statement, in place.
fn blank_attribute_indices(line: &mut [u8]) {
    let mut in_attributes = false;
    for byte in line.iter_mut() {
        if byte.is_ascii_whitespace() {
            in_attributes = false;
        } else if *byte == b'/' {
            in_attributes = true;
        }
        if in_attributes {
            *byte = b' ';
        }
    }
}

pub(crate) fn read_obj_mesh(path: &Path) -> Result<Mesh> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_obj(path, bytes)
}

fn parse_obj(path: &Path, mut bytes: Vec<u8>) -> Result<Mesh> {
    let mut vertices = 0usize;
    for line in bytes.split_mut(|&b| b == b'\n') {
        // tobj splits lines on whitespace as `str::split_whitespace` does; a line that is not
        // UTF-8 makes tobj fail below.
        let Ok(text) = std::str::from_utf8(line) else {
            continue;
        };
        let start = text.len() - text.trim_start().len();
        match text.split_whitespace().next() {
            Some("v") => vertices += 1,
            // Same length, so no copy: `o name` becomes the comment `# name`.
            Some("o" | "g") => line[start] = b'#',
            // Only positions are read: `7/3/2` becomes `7    `, so texture and normal indices
            // (which tobj mishandles when they are out of range) never reach it.
            Some("f" | "l") => blank_attribute_indices(line),
            _ => {}
        }
    }
    let mut numbering = String::with_capacity(2 + 8 * vertices);
    if vertices > 0 {
        numbering.push('f');
        for i in 1..=vertices {
            numbering.push_str(&format!(" {i}"));
        }
        numbering.push('\n');
    }
    let mut reader = BufReader::new(numbering.as_bytes().chain(&bytes[..]));
    // Keep everything as written: no triangulation (done below), points and lines included so
    // the numbering polygon is kept whatever its size.
    let options = tobj::LoadOptions::default();
    let (models, _) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| {
        let message = match e {
            tobj::LoadError::ReadError => "not UTF-8 text".to_string(),
            e => e.to_string(),
        };
        Error::format(path, format!("invalid OBJ: {message}"))
    })?;
    let [model] = &models[..] else {
        return Err(Error::format(
            path,
            format!("tobj returned {} models instead of one", models.len()),
        ));
    };
    let mesh = &model.mesh;
    // `use_f64` is on: coordinates are parsed as f64, exactly as written.
    let coordinates: &[f64] = &mesh.positions;
    let positions: Vec<[f64; 3]> = coordinates
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    debug_assert_eq!(positions.len(), vertices);
    // Empty arities mean all faces are triangles.
    let arities: Vec<usize> = if mesh.face_arities.is_empty() {
        vec![3; mesh.indices.len() / 3]
    } else {
        mesh.face_arities.iter().map(|&a| a as usize).collect()
    };
    let mut triangles = Vec::with_capacity(mesh.indices.len() / 3);
    let mut start = 0;
    for (k, &arity) in arities.iter().enumerate() {
        let face = &mesh.indices[start..start + arity];
        start += arity;
        // Face 0 is the numbering polygon; fewer than 3 vertices: a point or line.
        if (k == 0 && vertices > 0) || arity < 3 {
            continue;
        }
        for j in 1..arity - 1 {
            triangles.push([face[0], face[j], face[j + 1]]);
        }
    }
    Ok(Mesh {
        positions,
        triangles,
    })
}

/// Texture coordinates of a mesh, per triangle corner: `coordinates` are the `vt` entries,
/// `corners[t][c]` indexes the one corner `c` of triangle `t` uses. Corners may share an entry
/// or not (a seam of the parameterization needs two entries at one vertex).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TextureCoordinates {
    /// (u, v) of each `vt` line, in order.
    pub coordinates: Vec<[f64; 2]>,
    /// For each triangle of the mesh, the index into `coordinates` of each corner.
    pub corners: Vec<[u32; 3]>,
}

/// Writes `mesh` (and optional per-vertex normals) as OBJ, atomically. Coordinates are
/// printed in Rust's shortest round-trip form, so reading the file back is bit-exact.
pub(crate) fn write_obj_mesh(path: &Path, mesh: &Mesh, normals: Option<&[[f64; 3]]>) -> Result<()> {
    write_textured_obj(path, mesh, normals, None)
}

/// An OBJ mesh (vertices, optional normals, faces) with optional texture coordinates: `vt` lines after the vertices (and
/// normals), faces `v/vt` or `v/vt/vn`. Coordinates round-trip bit-exactly like the vertices.
///
/// # Errors
/// [`Error::InvalidInput`] for out-of-range vertex or texture indices, a normal count other
/// than the vertex count or a corner list other than one per triangle; I/O errors.
pub fn write_textured_obj(
    path: &Path,
    mesh: &Mesh,
    normals: Option<&[[f64; 3]]>,
    texture: Option<&TextureCoordinates>,
) -> Result<()> {
    check_writable(mesh, normals)?;
    if let Some(texture) = texture {
        check_texture(mesh, texture)?;
    }
    write_atomic_with(path, |w| {
        writeln!(
            w,
            "# neurosurf mesh: {} vertices, {} triangles",
            mesh.positions.len(),
            mesh.triangles.len()
        )?;
        for p in &mesh.positions {
            writeln!(w, "v {:?} {:?} {:?}", p[0], p[1], p[2])?;
        }
        for n in normals.unwrap_or_default() {
            writeln!(w, "vn {:?} {:?} {:?}", n[0], n[1], n[2])?;
        }
        for [u, v] in texture.map_or(&[][..], |t| &t.coordinates) {
            writeln!(w, "vt {u:?} {v:?}")?;
        }
        for (i, t) in mesh.triangles.iter().enumerate() {
            let v = t.map(|i| u64::from(i) + 1);
            let vt = texture
                .and_then(|t| t.corners.get(i))
                .map(|c| c.map(|i| u64::from(i) + 1));
            write!(w, "f")?;
            for c in 0..3 {
                match (vt, normals.is_some()) {
                    (Some(vt), true) => write!(w, " {}/{}/{}", v[c], vt[c], v[c])?,
                    (Some(vt), false) => write!(w, " {}/{}", v[c], vt[c])?,
                    (None, true) => write!(w, " {}//{}", v[c], v[c])?,
                    (None, false) => write!(w, " {}", v[c])?,
                }
            }
            writeln!(w)?;
        }
        Ok(())
    })
}

/// One corner triple per triangle, every index within the coordinates, every value finite.
fn check_texture(mesh: &Mesh, texture: &TextureCoordinates) -> Result<()> {
    if texture.corners.len() != mesh.triangles.len() {
        return Err(Error::invalid(format!(
            "{} texture corner triples for a mesh with {} triangles",
            texture.corners.len(),
            mesh.triangles.len()
        )));
    }
    let count = texture.coordinates.len();
    if let Some(i) = texture
        .corners
        .iter()
        .position(|c| c.iter().any(|&k| k as usize >= count))
    {
        return Err(Error::invalid(format!(
            "triangle {i} uses a texture coordinate beyond the {count} given"
        )));
    }
    if let Some(i) = texture
        .coordinates
        .iter()
        .position(|uv| uv.iter().any(|c| !c.is_finite()))
    {
        return Err(Error::invalid(format!(
            "texture coordinate {i} is not finite"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::mesh::tests::unit_cube;
    use crate::io::read_mesh;

    fn parse(text: &str) -> Result<Mesh> {
        parse_obj(Path::new("test.obj"), text.as_bytes().to_vec())
    }

    fn message(e: Error) -> String {
        match e {
            Error::Format { path, message } => {
                assert_eq!(path, Path::new("test.obj"));
                message
            }
            other => panic!("expected a format error, got {other:?}"),
        }
    }

    #[test]
    fn texture_and_normal_indices_out_of_range_are_ignored() {
        // Found by fuzzing: tobj overflowed on the negative texture index −10.
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-1 2/-10 3/99/-7\nf 1//5 3//-9 2\n";
        let mesh = parse(text).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 1]]);
        // Vertex indices are still checked.
        let error = message(parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/2 2 -9\n").unwrap_err());
        assert!(!error.is_empty());
    }

    #[test]
    fn reads_a_cube_written_by_hand() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cube.obj");
        // Quads with texture and normal indices, objects and groups sharing vertices,
        // materials, comments, a line and negative indices.
        let text = "\
# unit cube
mtllib cube.mtl
o cube
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 0 0 1
v 1 0 1
v 0 1 1
  v 1 1 1
vt 0 0
vn 0 0 1
g sides
usemtl none
s off
f 1/1/1 3/1/1 4/1/1 2/1/1
f 5//1 6//1 8//1 7//1
g more sides
f 1 2 6 5
usemtl other
f 3 7 8 4
l 1 8
o second
f -8 -4 -2 -6
\tg
f 2/1 4/1 8/1 6/1
";
        std::fs::write(&path, text).unwrap();
        let mesh = read_mesh(&path).unwrap();
        let cube = unit_cube();
        assert_eq!(mesh.positions, cube.positions);
        assert_eq!(mesh.triangles, cube.triangles);
    }

    #[test]
    fn keeps_numbering_exact_coordinates_and_unused_vertices() {
        let text = "v 0.1 0.2 1e-300\nv 7 7 7\nv 1 0 0\nv 0 1 0\r\nf 1 3 4\nf 4 3 1\n";
        let mesh = parse(text).unwrap();
        assert_eq!(
            mesh.positions,
            vec![
                [0.1, 0.2, 1e-300],
                [7.0; 3],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0]
            ]
        );
        assert_eq!(mesh.triangles, vec![[0, 2, 3], [3, 2, 0]]);
        // Three vertices: the numbering polygon is a triangle itself.
        let mesh = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 3 2 1\nf 1/1 2/1 3/1 1/1 2/1\n").unwrap();
        assert_eq!(
            mesh.triangles,
            vec![[2, 1, 0], [0, 1, 2], [0, 2, 0], [0, 0, 1]]
        );
        // Nothing at all.
        assert_eq!(parse("# empty\n").unwrap(), Mesh::default());
    }

    #[test]
    fn malformed_files_are_format_errors() {
        for (text, needle) in [
            ("v 0 0 0\nv 1 0 x\n", "position parse error"),
            ("v 0 0\n", "position parse error"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "out of bounds"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "out of bounds"),
            ("v 0 0 0\nf 0 1 1\n", "out of bounds"),
            ("v 0 0 0 0\n", "scaling"),
            ("v 0 0 0 1 1\n", "color"),
            ("v 0 0 0\nf 1 a 1\n", "face parse error"),
        ] {
            let e = message(parse(text).unwrap_err());
            assert!(
                e.starts_with("invalid OBJ: ") && e.contains(needle),
                "{text:?}: {e}"
            );
        }
        let e = message(parse_obj(Path::new("test.obj"), b"v 0 0 0\n\xff\n".to_vec()).unwrap_err());
        assert!(e.contains("UTF-8"), "{e}");
    }

    #[test]
    fn invalid_meshes_are_named_by_read_mesh() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.obj");
        for (text, needles) in [
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n",
                &["triangle 0", "repeats"][..],
            ),
            ("v 0 0 0\nv 1 0 0\n\nf 1 2\n", &["no triangles"]),
        ] {
            std::fs::write(&path, text).unwrap();
            let e = read_mesh(&path).unwrap_err();
            let e = match e {
                Error::Format { message, .. } => message,
                other => panic!("{other:?}"),
            };
            for needle in needles {
                assert!(e.contains(needle), "{text:?}: {e}");
            }
        }
    }

    #[test]
    fn forward_references_weights_and_colours() {
        let mesh = parse("f 1 2 3\nv 0 0 0\nv 2 0 0 2\nv 0 1 0 0.5\n").unwrap();
        assert_eq!(
            mesh.positions,
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]]
        );
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        // Six values: colours after the coordinates.
        let mesh = parse("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n").unwrap();
        assert_eq!(
            mesh.positions,
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        );
    }

    #[test]
    fn missing_file_is_an_io_error() {
        let e = read_mesh(Path::new("/nonexistent/x.obj")).unwrap_err();
        assert!(matches!(e, Error::Io { .. }), "{e}");
    }

    #[test]
    fn writes_normals_with_face_references() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("n.obj");
        let cube = unit_cube();
        let normals = vec![[0.0, 0.0, 1.0]; 8];
        crate::io::write_mesh(&path, &cube, Some(&normals)).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().filter(|l| l.starts_with("vn ")).count(), 8);
        assert!(text.contains("f 1//1 3//3 4//4"), "{text}");
        assert_eq!(read_mesh(&path).unwrap(), cube);
    }
}
