//! The trainer's file readers on any bytes: the first byte picks the reader (PLY oriented
//! points, PLY and OBJ meshes, text and PLY query points, text parameters, rows and scattered
//! points, PNG pictures), the rest is the file. Every reader must return a value or an error
//! that names the file; a panic, an abort or a hang is the failure.

use std::io::Write;
use std::path::{Path, PathBuf};

use neurosurf_trainer::io;

/// A reader, its value dropped.
type Reader = fn(&Path) -> Result<(), neurosurf_trainer::Error>;

/// The readers, with the extension each is given its file under.
const READERS: [(&str, Reader); 9] = [
    ("ply", |p| io::read_points(p).map(drop)),
    ("ply", |p| io::read_mesh(p).map(drop)),
    ("obj", |p| io::read_mesh(p).map(drop)),
    ("txt", |p| io::read_query_points(p).map(drop)),
    ("ply", |p| io::read_query_points(p).map(drop)),
    ("txt", |p| io::read_parameters(p, 2).map(drop)),
    ("txt", |p| io::read_rows(p).map(drop)),
    ("txt", |p| io::read_scattered_points(p).map(drop)),
    ("png", |p| io::read_picture(p).map(drop)),
];

/// How many readers [`read`] picks from.
pub const READER_COUNT: usize = READERS.len();

thread_local! {
    static FOLDER: tempfile::TempDir = tempfile::tempdir().expect("a temporary folder");
}

/// The reader `data[0]` picks: `data[0] % READER_COUNT`.
pub fn reader_of(data: &[u8]) -> Option<usize> {
    data.first()
        .map(|&selector| usize::from(selector) % READER_COUNT)
}

/// Writes `data[1..]` to a file and reads it with reader `data[0] % READER_COUNT`; returns the
/// error's message, if any.
///
/// # Panics
/// When an error does not name the file (or a reader panics).
pub fn read(data: &[u8]) -> Option<String> {
    let (&selector, file) = data.split_first()?;
    read_with(usize::from(selector) % READER_COUNT, file)
}

/// Writes `file` and reads it with reader `index` (below [`READER_COUNT`]); as [`read`].
///
/// # Panics
/// As [`read`], and for an index past the readers.
pub fn read_with(index: usize, file: &[u8]) -> Option<String> {
    let selector = index;
    let (extension, reader) = READERS[index];
    let path = FOLDER.with(|folder| folder.path().join(format!("input.{extension}")));
    write(&path, file);
    let error = reader(&path).err()?.to_string();
    assert!(
        error.contains("input."),
        "reader {selector}: the error does not name the file: {error}"
    );
    Some(error)
}

fn write(path: &PathBuf, bytes: &[u8]) {
    let mut file = std::fs::File::create(path).expect("the fuzz input file");
    file.write_all(bytes).expect("the fuzz input written");
}
