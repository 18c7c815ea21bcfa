//! Files in and out: PLY (ascii and binary, via `ply-rs-bw`), OBJ (read via `tobj`), binary STL
//! (written), whitespace point lists, PNG pictures (read); atomic writes.
//!
//! Readers name the file, and where known the line, element, vertex or property, in every
//! [`Error::Format`]; writers go through [`write_atomic_with`] so a failed write never leaves
//! a partial file.
//!
//! [`Error::Format`]: crate::Error::Format

mod atomic;
mod data;
mod mesh;
mod obj;
mod picture;
mod ply;
mod stl;
mod text;

pub use atomic::{check_output, write_atomic, write_atomic_with};
pub use data::{DATA_VARIABLE, data_dir, data_file};
pub use mesh::{
    EdgeReport, Mesh, MeshOrPoints, read_mesh, read_mesh_or_points, read_obj_vertices, write_mesh,
};
pub use obj::{TextureCoordinates, write_textured_obj};
pub use picture::read_picture;
pub use ply::{PlyEncoding, read_points, write_mesh_ply, write_points_ply};
pub use text::{
    MAX_PARAMETERS, read_parameters, read_query_points, read_rows, read_scattered_points,
};
