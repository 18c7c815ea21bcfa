//! Per-leaf input normalization into the PCA box of the feature's control points (Carcenac §5).

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// How the PCA box is scaled into [−H/2, H/2].
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum BoxScaling {
    /// One scale for all axes: the longest box side fills [−H/2, H/2] and the shape is kept.
    /// Converges in 31–64 iterations on the torus (measured with the paper's Table 1 settings).
    #[default]
    Isotropic,
    /// Each axis scaled on its own (the paper's literal reading); slower, sometimes stalls,
    /// and impossible for planar features.
    PerAxis,
}

/// An affine map x′ = A·(x − c): rotation into the principal axes of a point set, then
/// scaling of its bounding box into [−H/2, H/2].
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Normalization {
    /// Box center c (world).
    pub center: [f64; 3],
    /// A, row-major: row i is the i-th principal axis times its scale.
    pub matrix: [[f64; 3]; 3],
}

/// Relative size below which a box side counts as zero.
const DEGENERATE: f64 = 1e-9;

impl Normalization {
    /// Fits the PCA box of `positions` and scales it into [−`box_size`/2, `box_size`/2].
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the points are coincident or collinear (no box), or planar
    /// with [`BoxScaling::PerAxis`] (a side of zero length cannot be scaled); `what` names
    /// the feature in the message.
    pub fn fit(
        positions: &[[f64; 3]],
        box_size: f64,
        scaling: BoxScaling,
        what: &str,
    ) -> Result<Self> {
        if positions.is_empty() {
            return Err(Error::invalid(format!("{what} has no control points")));
        }
        let n = positions.len() as f64;
        let mean = positions
            .iter()
            .fold(Vector3::zeros(), |acc, p| acc + Vector3::from(*p))
            / n;
        let covariance = positions.iter().fold(Matrix3::zeros(), |acc, p| {
            let d = Vector3::from(*p) - mean;
            acc + d * d.transpose()
        }) / n;
        let eigen = SymmetricEigen::new(covariance);
        let mut order = [0, 1, 2];
        order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
        let mut axes: [Vector3<f64>; 3] = order.map(|i| eigen.eigenvectors.column(i).into_owned());
        // Deterministic orientation: largest component positive, right-handed frame.
        for axis in &mut axes[..2] {
            let largest = axis
                .iter()
                .copied()
                .fold(0.0_f64, |m, c| if c.abs() > m.abs() { c } else { m });
            if largest < 0.0 {
                *axis = -*axis;
            }
        }
        axes[2] = axes[0].cross(&axes[1]);

        let mut low = [f64::INFINITY; 3];
        let mut high = [f64::NEG_INFINITY; 3];
        for p in positions {
            let d = Vector3::from(*p) - mean;
            for i in 0..3 {
                let t = axes[i].dot(&d);
                low[i] = low[i].min(t);
                high[i] = high[i].max(t);
            }
        }
        let sides: [f64; 3] = std::array::from_fn(|i| high[i] - low[i]);
        let longest = sides[0].max(sides[1]).max(sides[2]);
        let magnitude = mean.norm().max(1.0);
        // NaN spreads count as degenerate too.
        if longest.is_nan() || longest <= DEGENERATE * magnitude {
            return Err(Error::invalid(format!(
                "{what}: all {} control points coincide; a feature needs a 3-D spread",
                positions.len()
            )));
        }
        let mut sorted = sides;
        sorted.sort_by(|a, b| b.total_cmp(a));
        if sorted[1] <= DEGENERATE * longest {
            return Err(Error::invalid(format!(
                "{what}: the control points are collinear (PCA box {:.3e} × {:.3e} × {:.3e})",
                sides[0], sides[1], sides[2]
            )));
        }
        if scaling == BoxScaling::PerAxis && sorted[2] <= DEGENERATE * longest {
            return Err(Error::invalid(format!(
                "{what}: the control points are planar (PCA box {:.3e} × {:.3e} × {:.3e}), so \
                 per-axis box scaling would divide by zero; use isotropic scaling",
                sides[0], sides[1], sides[2]
            )));
        }
        let scales: [f64; 3] = match scaling {
            BoxScaling::Isotropic => [box_size / longest; 3],
            BoxScaling::PerAxis => sides.map(|s| box_size / s),
        };
        let mid: [f64; 3] = std::array::from_fn(|i| 0.5 * (low[i] + high[i]));
        let center = mean + axes[0] * mid[0] + axes[1] * mid[1] + axes[2] * mid[2];
        let matrix = std::array::from_fn(|i| (axes[i] * scales[i]).into());
        Ok(Normalization {
            center: center.into(),
            matrix,
        })
    }

    /// x′ = A·(x − c).
    pub fn apply(&self, x: [f64; 3]) -> [f64; 3] {
        let d = [
            x[0] - self.center[0],
            x[1] - self.center[1],
            x[2] - self.center[2],
        ];
        self.matrix
            .map(|row| row[0] * d[0] + row[1] * d[1] + row[2] * d[2])
    }

    /// The 12 stored parameters: c, then A row-major (core layout).
    pub fn to_params(&self) -> [f64; 12] {
        let mut out = [0.0; 12];
        out[..3].copy_from_slice(&self.center);
        for (i, row) in self.matrix.iter().enumerate() {
            out[3 + 3 * i..6 + 3 * i].copy_from_slice(row);
        }
        out
    }

    /// Reads the 12 stored parameters.
    pub fn from_params(params: &[f64]) -> Self {
        Normalization {
            center: [params[0], params[1], params[2]],
            matrix: std::array::from_fn(|i| {
                [params[3 + 3 * i], params[4 + 3 * i], params[5 + 3 * i]]
            }),
        }
    }

    /// The box's corners in world space, for a box of side `box_size` in normalized space
    /// grown by `inflate` (1.0 = exact).
    pub fn world_corners(&self, box_size: f64, inflate: f64) -> Option<[[f64; 3]; 8]> {
        let inverse = Matrix3::from_fn(|i, j| self.matrix[i][j]).try_inverse()?;
        let half = 0.5 * box_size * inflate;
        Some(std::array::from_fn(|corner| {
            let local = Vector3::new(
                if corner & 1 == 0 { -half } else { half },
                if corner & 2 == 0 { -half } else { half },
                if corner & 4 == 0 { -half } else { half },
            );
            (inverse * local + Vector3::from(self.center)).into()
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(sides: [f64; 3]) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                for k in 0..5 {
                    let t = [i, j, k].map(|v| f64::from(v) / 4.0 - 0.5);
                    // A rotated, shifted box.
                    let p = [t[0] * sides[0], t[1] * sides[1], t[2] * sides[2]];
                    let (c, s) = (0.6_f64.cos(), 0.6_f64.sin());
                    out.push([
                        c * p[0] - s * p[1] + 3.0,
                        s * p[0] + c * p[1] - 1.0,
                        p[2] + 0.5,
                    ]);
                }
            }
        }
        out
    }

    #[test]
    fn isotropic_box_fills_the_longest_side() {
        let points = grid([4.0, 2.0, 1.0]);
        let n = Normalization::fit(&points, 2.0, BoxScaling::Isotropic, "feature 0").unwrap();
        let mapped: Vec<_> = points.iter().map(|&p| n.apply(p)).collect();
        for axis in 0..3 {
            let max = mapped.iter().map(|p| p[axis].abs()).fold(0.0, f64::max);
            let expected = [1.0, 0.5, 0.25][axis];
            assert!((max - expected).abs() < 1e-9, "axis {axis}: {max}");
        }
    }

    #[test]
    fn per_axis_box_fills_every_side() {
        let points = grid([4.0, 2.0, 1.0]);
        let n = Normalization::fit(&points, 2.0, BoxScaling::PerAxis, "feature 0").unwrap();
        for axis in 0..3 {
            let max = points
                .iter()
                .map(|&p| n.apply(p)[axis].abs())
                .fold(0.0, f64::max);
            assert!((max - 1.0).abs() < 1e-9, "axis {axis}: {max}");
        }
    }

    #[test]
    fn degenerate_sets_are_named() {
        let same = vec![[1.0, 2.0, 3.0]; 10];
        let err = Normalization::fit(&same, 2.0, BoxScaling::Isotropic, "feature 4").unwrap_err();
        assert!(
            err.to_string().contains("feature 4") && err.to_string().contains("coincide"),
            "{err}"
        );
        let line: Vec<_> = (0..10)
            .map(|i| [f64::from(i), 2.0 * f64::from(i), 0.0])
            .collect();
        let err = Normalization::fit(&line, 2.0, BoxScaling::Isotropic, "feature 1").unwrap_err();
        assert!(err.to_string().contains("collinear"), "{err}");
        let plane = grid([1.0, 1.0, 0.0]);
        assert!(Normalization::fit(&plane, 2.0, BoxScaling::Isotropic, "f").is_ok());
        let err = Normalization::fit(&plane, 2.0, BoxScaling::PerAxis, "feature 2").unwrap_err();
        assert!(err.to_string().contains("planar"), "{err}");
    }

    #[test]
    fn params_round_trip() {
        let n =
            Normalization::fit(&grid([3.0, 2.0, 1.0]), 2.0, BoxScaling::Isotropic, "f").unwrap();
        assert_eq!(Normalization::from_params(&n.to_params()), n);
    }
}
