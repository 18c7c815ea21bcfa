//! What the comparison measures at one point, for every model family: a value (Φ, or a
//! position, or a Cao En network's outputs) and a direction (∇Φ, a curve's tangent, a
//! surface's normal).

use crate::evaluate::{Geometry, Sample};

/// One evaluated point, as [`super::Deviation`] and [`super::Agreement`] see it.
pub trait Measured {
    /// How far this value is from the reference's: |Φ − Φ_ref| for fields, the Euclidean
    /// distance between the positions for curves and surfaces.
    fn value_error(&self, reference: &Self) -> f64;
    /// The direction whose angle is compared: ∇Φ, dC/dt or the unit normal.
    fn direction(&self) -> [f64; 3];
    /// Every computed number, in the order the core returns them (for bit comparison).
    fn words(&self) -> impl Iterator<Item = f64>;
}

impl Measured for Sample {
    fn value_error(&self, reference: &Self) -> f64 {
        (self.0 - reference.0).abs()
    }

    fn direction(&self) -> [f64; 3] {
        self.1
    }

    fn words(&self) -> impl Iterator<Item = f64> {
        std::iter::once(self.0).chain(self.1)
    }
}

impl Measured for Geometry {
    fn value_error(&self, reference: &Self) -> f64 {
        if self.output.len() != reference.output.len() {
            return f64::NAN;
        }
        let square: f64 = self
            .output
            .iter()
            .zip(&reference.output)
            .map(|(a, b)| (a - b) * (a - b))
            .sum();
        square.sqrt()
    }

    fn direction(&self) -> [f64; 3] {
        self.direction
    }

    fn words(&self) -> impl Iterator<Item = f64> {
        self.output.iter().copied().chain(self.direction)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_and_geometry_measure_their_own_way() {
        let field: Sample = (1.0, [0.0, 0.0, 2.0]);
        assert_eq!(field.value_error(&(-0.5, [0.0; 3])), 1.5);
        assert_eq!(field.words().collect::<Vec<_>>(), [1.0, 0.0, 0.0, 2.0]);
        let point = Geometry::from((vec![3.0, 4.0, 0.0], [1.0, 0.0, 0.0]));
        assert_eq!(
            point.value_error(&Geometry::from((vec![0.0; 3], [0.0; 3]))),
            5.0
        );
        assert!(
            point
                .value_error(&Geometry::from((vec![0.0; 2], [0.0; 3])))
                .is_nan()
        );
        assert_eq!(point.direction(), [1.0, 0.0, 0.0]);
        assert_eq!(point.words().count(), 6);
    }
}
