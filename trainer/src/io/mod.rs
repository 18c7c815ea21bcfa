//! Files in and out: PLY (ascii and binary), OBJ, whitespace point lists; atomic writes.

mod atomic;

pub use atomic::{write_atomic, write_atomic_with};
