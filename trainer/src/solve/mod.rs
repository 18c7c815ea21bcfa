//! The numerical machinery every trainer shares: Levenberg–Marquardt ([`lm`]), its normal
//! equations and damped Cholesky solve ([`normal_equations`]), and the four-lane `f64` kernels
//! they and the networks' Jacobians are written in ([`lanes`]). The implicit modules and the
//! Yumer & Kara surface networks both train through it.

pub mod kept_rows;
pub mod lanes;
pub mod lm;
pub mod normal_equations;

pub use kept_rows::KeptRows;
pub use lanes::{LANES, Lanes, cpu_has_fma, madd, tanh_lanes};
pub use lm::{DecayScale, LeastSquares, LmOptions, LmReport, StopReason, levenberg_marquardt};
pub use normal_equations::{DampedSystem, NormalEquations};
