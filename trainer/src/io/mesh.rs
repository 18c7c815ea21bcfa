//! Triangle meshes: the in-memory type and format dispatch by file extension.

use std::collections::HashMap;
use std::path::Path;

use crate::error::{Error, Result};

use super::{obj, ply, stl};

/// An indexed triangle mesh. Triangles wind counter-clockwise seen from outside, so
/// `(b - a) × (c - a)` points outward.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Checks the mesh is usable: at least one vertex and one triangle, finite coordinates,
    /// every index in range and no triangle repeating a vertex index.
    ///
    /// Triangles whose three distinct vertices are collinear or coincide (zero area) are
    /// accepted; samplers skip them.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the first offending vertex or triangle.
    pub fn validated(self) -> Result<Mesh> {
        if self.positions.is_empty() {
            return Err(Error::invalid("the mesh has no vertices"));
        }
        if self.triangles.is_empty() {
            return Err(Error::invalid("the mesh has no triangles"));
        }
        if let Some((i, p)) = self
            .positions
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
        {
            return Err(Error::invalid(format!(
                "vertex {i} has a non-finite coordinate {p:?}"
            )));
        }
        let n = self.positions.len();
        for (i, t) in self.triangles.iter().enumerate() {
            if let Some(&bad) = t.iter().find(|&&v| v as usize >= n) {
                return Err(Error::invalid(format!(
                    "triangle {i} references vertex {bad} but the mesh has {n} vertices"
                )));
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(Error::invalid(format!(
                    "triangle {i} repeats a vertex index: {t:?}"
                )));
            }
        }
        Ok(self)
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// How the triangles meet along their edges: whether the mesh is closed and consistently
    /// wound, and its Euler characteristic.
    pub fn edge_report(&self) -> EdgeReport {
        // Per undirected edge: how many triangles use it, and the sum of +1 for each use
        // from the lower index to the higher and −1 for the other way.
        let mut edges: HashMap<(u32, u32), (usize, i64)> = HashMap::new();
        let mut used = vec![false; self.positions.len()];
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let entry = edges.entry((a.min(b), a.max(b))).or_default();
                entry.0 += 1;
                entry.1 += if a < b { 1 } else { -1 };
                if let Some(u) = used.get_mut(a as usize) {
                    *u = true;
                }
            }
        }
        let vertices = used.iter().filter(|&&u| u).count() as i64;
        EdgeReport {
            edges: edges.len(),
            not_shared_by_two: edges.values().filter(|e| e.0 != 2).count(),
            same_way: edges.values().filter(|e| e.0 == 2 && e.1 != 0).count(),
            euler_characteristic: vertices - edges.len() as i64 + self.triangles.len() as i64,
        }
    }
}

/// How the triangles of a [`Mesh`] meet along their edges ([`Mesh::edge_report`]).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct EdgeReport {
    /// Distinct undirected edges.
    pub edges: usize,
    /// Edges not shared by exactly two triangles: open (one) or non-manifold (three or more).
    pub not_shared_by_two: usize,
    /// Edges shared by two triangles that run along it the same way (inconsistent winding).
    pub same_way: usize,
    /// V − E + F, counting the vertices the triangles use: 2 for a closed surface of genus 0,
    /// 0 for a torus.
    pub euler_characteristic: i64,
}

impl EdgeReport {
    /// Watertight and consistently wound: every edge shared by exactly two triangles, once
    /// in each direction.
    pub fn is_closed(&self) -> bool {
        self.not_shared_by_two == 0 && self.same_way == 0
    }
}

/// The lower-cased extension of `path`, if any.
pub(crate) fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// Reads a triangle mesh from a Wavefront `.obj` or a `.ply` file (chosen by extension) and
/// validates it.
///
/// OBJ (parsed by `tobj`): `v` and `f` statements (`f` indices may be `v`, `v/vt`, `v//vn` or
/// `v/vt/vn`, negative indices count back from the last vertex); polygons are
/// fan-triangulated, faces with fewer than 3 vertices skipped; other statements are ignored;
/// every vertex is kept, in file order, so indices match the file's. PLY (parsed by
/// `ply-rs-bw`, ascii or binary): a `vertex` element with `x y z` and a `face` element with a
/// `vertex_indices` (or `vertex_index`) list of any integer type; polygons are
/// fan-triangulated.
///
/// # Errors
/// [`Error::Io`] when the file cannot be read, [`Error::Format`] for malformed content (naming
/// the line where the parser reports one: PLY ascii yes, OBJ no) or an invalid mesh (see
/// [`Mesh::validated`]), [`Error::InvalidInput`] for an unsupported extension.
pub fn read_mesh(path: &Path) -> Result<Mesh> {
    let mesh = match extension(path).as_deref() {
        Some("obj") => obj::read_obj_mesh(path)?,
        Some("ply") => ply::read_ply_mesh(path)?,
        _ => {
            return Err(Error::invalid(format!(
                "{}: unsupported mesh format (expected .obj or .ply)",
                path.display()
            )));
        }
    };
    mesh.validated().map_err(|e| match e {
        Error::InvalidInput(message) => Error::format(path, message),
        other => other,
    })
}

/// What a surface file holds.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshOrPoints {
    /// Triangles.
    Mesh(Mesh),
    /// Points only: an OBJ without faces, a PLY without a `face` element, or text rows.
    Points(Vec<[f64; 3]>),
}

/// A mesh when the file has faces, its points when it has none: OBJ and PLY files by their
/// extension (any case), text rows of x y z otherwise.
///
/// # Errors
/// As [`read_mesh`] for a file with faces (a bad face is an error, not a reason to read the
/// points alone), as [`read_query_points`](super::read_query_points) for the points.
pub fn read_mesh_or_points(path: &Path) -> Result<MeshOrPoints> {
    match extension(path).as_deref() {
        Some("obj") => {
            let raw = obj::read_obj_mesh(path)?;
            if raw.triangles.is_empty() {
                return read_obj_vertices(path).map(MeshOrPoints::Points);
            }
            read_mesh(path).map(MeshOrPoints::Mesh)
        }
        Some("ply") => match ply::read_ply_mesh(path) {
            Ok(mesh) if mesh.triangles.is_empty() => Ok(MeshOrPoints::Points(mesh.positions)),
            Ok(_) => read_mesh(path).map(MeshOrPoints::Mesh),
            Err(e) if e.to_string().contains(ply::NO_FACE_ELEMENT) => {
                super::read_query_points(path).map(MeshOrPoints::Points)
            }
            Err(e) => Err(e),
        },
        _ => super::read_query_points(path).map(MeshOrPoints::Points),
    }
}

/// The vertices of an OBJ file, with or without faces: a point cloud written as OBJ.
///
/// # Errors
/// [`Error::Io`] when the file cannot be read, [`Error::Format`] for malformed content or a
/// file without vertices, [`Error::InvalidInput`] for another extension than `.obj`.
pub fn read_obj_vertices(path: &Path) -> Result<Vec<[f64; 3]>> {
    if extension(path).as_deref() != Some("obj") {
        return Err(Error::invalid(format!(
            "{}: OBJ vertices are read from .obj files only",
            path.display()
        )));
    }
    let positions = obj::read_obj_mesh(path)?.positions;
    if positions.is_empty() {
        return Err(Error::format(path, "the file has no vertices"));
    }
    Ok(positions)
}

/// Writes `mesh` to `path` atomically, as Wavefront OBJ, binary little-endian PLY or binary
/// STL depending on the extension (`.obj`, `.ply` or `.stl`). When `normals` is given (one per
/// vertex) it is written too (`vn` lines, or `nx ny nz` vertex properties; STL stores facet
/// normals only).
///
/// Use [`ply::write_mesh_ply`](super::write_mesh_ply) to choose the PLY encoding.
///
/// # Errors
/// [`Error::InvalidInput`] for an unsupported extension, a normal count that differs from
/// the vertex count, or indices out of range; [`Error::Io`] when writing fails.
pub fn write_mesh(path: &Path, mesh: &Mesh, normals: Option<&[[f64; 3]]>) -> Result<()> {
    match extension(path).as_deref() {
        Some("obj") => obj::write_obj_mesh(path, mesh, normals),
        Some("ply") => {
            ply::write_mesh_ply(path, mesh, normals, ply::PlyEncoding::BinaryLittleEndian)
        }
        Some("stl") => {
            check_writable(mesh, normals)?;
            stl::write_stl_mesh(path, mesh)
        }
        _ => Err(Error::invalid(format!(
            "{}: unsupported mesh format (expected .obj, .ply or .stl)",
            path.display()
        ))),
    }
}

/// Checks what a mesh writer needs: indices in range, one normal per vertex.
pub(crate) fn check_writable(mesh: &Mesh, normals: Option<&[[f64; 3]]>) -> Result<()> {
    let n = mesh.positions.len();
    if let Some(normals) = normals
        && normals.len() != n
    {
        return Err(Error::invalid(format!(
            "{} normals for a mesh with {n} vertices",
            normals.len()
        )));
    }
    if let Some((i, t)) = mesh
        .triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
    {
        return Err(Error::invalid(format!(
            "triangle {i} {t:?} references a vertex beyond the {n} vertices"
        )));
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn a_file_is_a_mesh_when_it_has_faces_and_points_when_it_has_none() {
        let dir = tempfile::tempdir().unwrap();
        let file = |name: &str, text: &str| {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            read_mesh_or_points(&path)
        };
        let points = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        assert!(matches!(file("a.obj", points), Ok(MeshOrPoints::Points(p)) if p.len() == 3));
        assert!(matches!(file("B.OBJ", points), Ok(MeshOrPoints::Points(p)) if p.len() == 3));
        let triangle = format!("{points}f 1 2 3\n");
        assert!(
            matches!(file("c.obj", &triangle), Ok(MeshOrPoints::Mesh(m)) if m.triangles.len() == 1)
        );
        // A bad face is the mesh's error, not a reason to take the points alone.
        let e = file("d.obj", &format!("{points}f 1 1 2\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("repeats a vertex"), "{e}");
        let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                   property float z\nend_header\n0 0 0\n1 2 3\n";
        assert!(matches!(file("e.ply", ply), Ok(MeshOrPoints::Points(p)) if p.len() == 2));
        assert!(
            matches!(file("f.xyz", "0 0 0\n1 1 1\n"), Ok(MeshOrPoints::Points(p)) if p.len() == 2)
        );
    }

    #[test]
    fn obj_vertices_are_read_with_or_without_faces() {
        let dir = tempfile::tempdir().unwrap();
        let cloud = dir.path().join("cloud.obj");
        std::fs::write(&cloud, "# points\nv 0 0 0\nv 1 0 0\nv 0 1 2.5\n").unwrap();
        let points = read_obj_vertices(&cloud).unwrap();
        assert_eq!(points, vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 2.5]]);
        assert!(read_mesh(&cloud).is_err());
        let empty = dir.path().join("empty.obj");
        std::fs::write(&empty, "# nothing\n").unwrap();
        let e = read_obj_vertices(&empty).unwrap_err().to_string();
        assert!(e.contains("no vertices"), "{e}");
        let e = read_obj_vertices(&dir.path().join("cloud.ply"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(".obj files only"), "{e}");
    }

    /// The unit cube `[0, 1]³` with outward (counter-clockwise) triangles.
    pub(crate) fn unit_cube() -> Mesh {
        let positions = (0..8)
            .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
            .collect();
        // Quads listed counter-clockwise seen from outside, each split into two triangles.
        let quads: [[u32; 4]; 6] = [
            [0, 2, 3, 1], // z = 0, normal -z
            [4, 5, 7, 6], // z = 1, normal +z
            [0, 1, 5, 4], // y = 0, normal -y
            [2, 6, 7, 3], // y = 1, normal +y
            [0, 4, 6, 2], // x = 0, normal -x
            [1, 3, 7, 5], // x = 1, normal +x
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Mesh {
            positions,
            triangles,
        }
    }

    #[test]
    fn cube_winding_is_outward() {
        let m = unit_cube();
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let centroid = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0 - 0.5);
            let dot: f64 = (0..3).map(|k| n[k] * centroid[k]).sum();
            assert!(dot > 0.0, "{t:?}");
        }
    }

    #[test]
    fn edge_report_tells_closed_open_flipped_and_non_manifold_meshes() {
        let cube = unit_cube();
        let closed = cube.edge_report();
        assert_eq!(closed.edges, 18);
        assert_eq!(closed.euler_characteristic, 2);
        assert!(closed.is_closed(), "{closed:?}");

        let mut open = cube.clone();
        open.triangles.pop();
        let report = open.edge_report();
        assert_eq!((report.not_shared_by_two, report.same_way), (3, 0));
        assert!(!report.is_closed());

        let mut flipped = cube.clone();
        flipped.triangles[0].swap(1, 2);
        let report = flipped.edge_report();
        assert_eq!((report.not_shared_by_two, report.same_way), (0, 3));
        assert!(!report.is_closed());

        let mut fin = cube;
        fin.positions.push([0.5, 0.5, 0.5]);
        fin.triangles.push([0, 2, 8]);
        let report = fin.edge_report();
        // Edge 0–2 is now used three times; the fin's two new edges once each.
        assert_eq!(report.not_shared_by_two, 3);
        assert!(!report.is_closed());
    }

    #[test]
    fn validation_rejects_bad_meshes() {
        assert!(unit_cube().validated().is_ok());
        let empty = Mesh::default().validated().unwrap_err();
        assert!(empty.to_string().contains("no vertices"), "{empty}");
        let mut m = unit_cube();
        m.triangles.clear();
        assert!(
            m.validated()
                .unwrap_err()
                .to_string()
                .contains("no triangles")
        );
        let mut m = unit_cube();
        m.positions[3][1] = f64::NAN;
        assert!(m.validated().unwrap_err().to_string().contains("vertex 3"));
        let mut m = unit_cube();
        m.triangles[5] = [0, 1, 8];
        let e = m.validated().unwrap_err().to_string();
        assert!(e.contains("triangle 5") && e.contains("vertex 8"), "{e}");
        let mut m = unit_cube();
        m.triangles[2] = [4, 1, 4];
        let e = m.validated().unwrap_err().to_string();
        assert!(e.contains("triangle 2") && e.contains("repeats"), "{e}");
    }

    #[test]
    fn unknown_extensions_are_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mesh.gltf");
        let e = write_mesh(&path, &unit_cube(), None).unwrap_err();
        assert!(matches!(e, Error::InvalidInput(_)), "{e}");
        assert!(!path.exists());
        let e = read_mesh(&path).unwrap_err();
        assert!(matches!(e, Error::InvalidInput(_)), "{e}");
    }

    #[test]
    fn mismatched_normals_are_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let normals = vec![[0.0, 0.0, 1.0]; 3];
        for name in ["m.obj", "m.ply"] {
            let path = dir.path().join(name);
            let e = write_mesh(&path, &unit_cube(), Some(&normals)).unwrap_err();
            assert!(e.to_string().contains("3 normals"), "{e}");
            assert!(!path.exists());
        }
    }

    fn round_trip(name: &str, normals: bool) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        let mut mesh = unit_cube();
        // Coordinates that need every bit of a double.
        for (i, p) in mesh.positions.iter_mut().enumerate() {
            p[0] += 0.1 * i as f64 + 1e-17;
            p[2] *= std::f64::consts::PI;
            p[1] -= 1.0 / 3.0;
        }
        let n: Vec<[f64; 3]> = (0..8)
            .map(|i| {
                let s = (i as f64 + 1.0).sqrt().recip();
                [s, -s, 0.0]
            })
            .collect();
        write_mesh(&path, &mesh, normals.then_some(&n[..])).unwrap();
        let back = read_mesh(&path).unwrap();
        assert_eq!(back, mesh, "{name}");
    }

    #[test]
    fn obj_round_trip_is_exact() {
        round_trip("cube.obj", false);
        round_trip("cube-normals.OBJ", true);
    }

    #[test]
    fn ply_round_trip_is_exact() {
        round_trip("cube.ply", false);
        round_trip("cube-normals.PLY", true);
    }

    #[test]
    fn shared_test_models_load() {
        // Counts from data/README.md.
        for (name, vertices, faces) in [
            ("spot.obj", 2930, 5856),
            ("woody.obj", 694, 1267),
            ("teapot.obj", 3644, 6320),
            ("fandisk.obj", 6475, 12946),
            ("stanford-bunny.obj", 35947, 69451),
        ] {
            let path = crate::io::data_file(name).unwrap_or_else(|e| panic!("{e}"));
            let mesh = read_mesh(&path).unwrap();
            assert_eq!(mesh.vertex_count(), vertices, "{name}");
            assert_eq!(mesh.triangle_count(), faces, "{name}");
            let (lo, hi) = mesh.positions.iter().fold(
                ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
                |(lo, hi), p| {
                    (
                        [0, 1, 2].map(|k| lo[k].min(p[k])),
                        [0, 1, 2].map(|k| hi[k].max(p[k])),
                    )
                },
            );
            let flat = (0..3).filter(|&k| hi[k] == lo[k]).count();
            // woody.obj is a flat, triangulated outline in the plane z = 0.
            assert_eq!(
                flat,
                usize::from(name == "woody.obj"),
                "{name}: {lo:?} {hi:?}"
            );
        }
    }
}
