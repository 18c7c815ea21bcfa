//! # neurosurf-trainer
//!
//! The host side of neurosurf: reads point sets and meshes, trains the models of the four
//! papers in `f64`, writes blobs that `neurosurf-core` evaluates, and evaluates them itself as
//! the `f64` reference. The `neurosurf` command (crate `neurosurf-cli`) is a thin layer over
//! this library.

pub mod blob;
pub mod caoen;
pub mod compare;
pub mod curve;
pub mod demo;
pub mod error;
pub mod evaluate;
pub mod fidelity;
pub mod geometry;
pub mod implicit;
pub mod io;
pub mod parametric;
pub mod plot;
pub mod points;
pub mod quality;
pub mod rbf;
pub mod render;
pub mod sample;
pub mod solve;
pub mod table;

pub use error::{Error, Result};
pub use points::PointSet;
