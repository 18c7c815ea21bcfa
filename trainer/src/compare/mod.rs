//! Fixed point against float: how far the core's `f32` and Q16.16 evaluations of a model are
//! from the trainer's `f64` reference, on the host and on a (simulated) target, and whether
//! the target computes exactly what the host computes.
//!
//! - [`Measured`]: what is compared at a point — Φ and ∇Φ, or a curve's or surface's
//!   position and direction;
//! - [`Deviation`]: field errors |Φ − Φ₆₄| and normal angles of one evaluation;
//! - [`Agreement`]: bit-exactness and ulp distance of two evaluations in the same scalar;
//! - [`EvaluationPoints`]: where to evaluate when the user gives no points — the model's own
//!   surface, found by Newton steps from its normalization boxes;
//! - [`CompareRow`] and [`comparison_table`]: the report `neurosurf compare` prints.

mod agreement;
mod deviation;
mod measured;
mod parameters;
mod report;
mod surface;

pub use agreement::{Agreement, ulp_distance};
pub use deviation::{Deviation, normal_angle_degrees};
pub use measured::Measured;
pub use parameters::{
    CURVE_PARAMETERS, ParameterSet, SPHERE_POINTS, SURFACE_GRID as PARAMETER_GRID, fibonacci_sphere,
};
pub use report::{CompareRow, Quantities, Side, comparison_table, comparison_table_of};
pub use surface::{
    EvaluationPoints, MIN_SURFACE_POINTS, NEWTON_STEPS, PointSource, SURFACE_SAMPLES, SURFACE_SEED,
    SURFACE_TOLERANCE, round_to_f32,
};
