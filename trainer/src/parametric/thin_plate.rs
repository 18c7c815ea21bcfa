//! The radial-basis baseline of §7.1: a thin-plate spline from the plane to D values,
//! f(x) = Σⱼ wⱼ φ(|x − cⱼ|) + a + b·x₀ + c·x₁ with φ(r) = r² ln r, one set of weights per output.
//!
//! With one centre per input point the spline interpolates: the augmented system
//! [Φ P; Pᵀ 0] is solved directly (a 10⁻¹⁰ relative ridge on Φ keeps it regular); past a
//! size it interpolates an even subsample. With grid centres it is a least-squares fit with a
//! 10⁻⁸ relative ridge.

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};

/// A fitted thin-plate spline ℝ² → ℝᴰ.
#[derive(Clone, Debug)]
pub(crate) struct ThinPlate<const D: usize> {
    centers: Vec<[f64; 2]>,
    /// One weight vector per centre, then the constant, x₀ and x₁ terms.
    weights: Vec<[f64; D]>,
}

/// Where the centres go.
#[derive(Copy, Clone, Debug)]
pub(crate) enum Centers {
    /// g × g over the inputs' bounding box (a least-squares fit).
    Grid(usize),
    /// One centre per input point, interpolating; beyond this many inputs, an even subsample
    /// of them (every ⌈n / most⌉-th in input order), interpolated.
    Points(usize),
}

fn phi(r2: f64) -> f64 {
    if r2 > 0.0 { 0.5 * r2 * r2.ln() } else { 0.0 }
}

fn distance_squared(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

impl<const D: usize> ThinPlate<D> {
    /// Fits `outputs[i]` at `inputs[i]`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for different lengths, fewer than 3 inputs, or a singular system
    /// (collinear inputs).
    pub(crate) fn fit(inputs: &[[f64; 2]], outputs: &[[f64; D]], centers: Centers) -> Result<Self> {
        if inputs.len() != outputs.len() || inputs.len() < 3 {
            return Err(Error::invalid(format!(
                "a thin-plate spline needs at least 3 inputs with one output each, got {} and {}",
                inputs.len(),
                outputs.len()
            )));
        }
        match centers {
            Centers::Grid(g) => {
                let centers = grid_centers(inputs, g);
                let weights = Self::least_squares(inputs, outputs, &centers)?;
                Ok(ThinPlate { centers, weights })
            }
            Centers::Points(most) => {
                // Beyond `most` inputs, the spline interpolates an even subsample: a dense
                // least-squares system over every input would grow with inputs × centres.
                let step = inputs.len().div_ceil(most.max(1)).max(1);
                let centers: Vec<[f64; 2]> = inputs.iter().step_by(step).copied().collect();
                let values: Vec<[f64; D]> = outputs.iter().step_by(step).copied().collect();
                let weights = Self::interpolate(&centers, &values)?;
                Ok(ThinPlate { centers, weights })
            }
        }
    }

    /// Basis j at x: the radial terms, then 1, x₀, x₁.
    fn basis(centers: &[[f64; 2]], x: [f64; 2], j: usize) -> f64 {
        match j.checked_sub(centers.len()) {
            None => phi(distance_squared(x, centers[j])),
            Some(0) => 1.0,
            Some(1) => x[0],
            Some(_) => x[1],
        }
    }

    fn interpolate(inputs: &[[f64; 2]], outputs: &[[f64; D]]) -> Result<Vec<[f64; D]>> {
        let n = inputs.len();
        let m = n + 3;
        let mut a = DMatrix::from_fn(m, m, |i, j| {
            if i < n {
                Self::basis(inputs, inputs[i], j)
            } else if j < n {
                Self::basis(inputs, inputs[j], i)
            } else {
                0.0
            }
        });
        let scale = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .fold(0.0_f64, |s, (i, j)| s.max(a[(i, j)].abs()))
            .max(f64::MIN_POSITIVE);
        for k in 0..n {
            a[(k, k)] += 1e-10 * scale;
        }
        let lu = a.lu();
        Self::solve_columns(
            m,
            m,
            |rhs| lu.solve(rhs),
            |i, d| {
                if i < n { outputs[i][d] } else { 0.0 }
            },
        )
    }

    fn least_squares(
        inputs: &[[f64; 2]],
        outputs: &[[f64; D]],
        centers: &[[f64; 2]],
    ) -> Result<Vec<[f64; D]>> {
        let m = centers.len() + 3;
        let a = DMatrix::from_fn(inputs.len(), m, |i, j| Self::basis(centers, inputs[i], j));
        let mut normal = a.transpose() * &a;
        let scale = normal.diagonal().max();
        for k in 0..m {
            normal[(k, k)] += 1e-8 * scale;
        }
        let lu = normal.lu();
        let at = a.transpose();
        Self::solve_columns(
            inputs.len(),
            m,
            |rhs| lu.solve(&(&at * rhs)),
            |i, d| outputs[i][d],
        )
    }

    /// Solves once per output coordinate d, with the right-hand side `value(i, d)` for
    /// i < `rows`; `solve` returns the `unknowns` weights.
    fn solve_columns(
        rows: usize,
        unknowns: usize,
        solve: impl Fn(&DVector<f64>) -> Option<DVector<f64>>,
        value: impl Fn(usize, usize) -> f64,
    ) -> Result<Vec<[f64; D]>> {
        let mut weights = vec![[0.0; D]; unknowns];
        for d in 0..D {
            let rhs = DVector::from_fn(rows, |i, _| value(i, d));
            let w = solve(&rhs)
                .filter(|w| w.len() == unknowns && w.iter().all(|v| v.is_finite()))
                .ok_or_else(|| {
                    Error::invalid("the thin-plate system is singular: the inputs lie on a line")
                })?;
            for (k, v) in w.iter().enumerate() {
                weights[k][d] = *v;
            }
        }
        Ok(weights)
    }

    /// The spline at `x`.
    pub(crate) fn value(&self, x: [f64; 2]) -> [f64; D] {
        let mut out = [0.0; D];
        for (j, w) in self.weights.iter().enumerate() {
            let b = Self::basis(&self.centers, x, j);
            for d in 0..D {
                out[d] += w[d] * b;
            }
        }
        out
    }

    /// Number of radial centres.
    pub(crate) fn center_count(&self) -> usize {
        self.centers.len()
    }
}

/// `g × g` points over the bounding box of `inputs`.
fn grid_centers(inputs: &[[f64; 2]], g: usize) -> Vec<[f64; 2]> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in inputs {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let g = g.max(1);
    let d = (g - 1).max(1) as f64;
    (0..g * g)
        .map(|k| {
            let (i, j) = ((k % g) as f64, (k / g) as f64);
            [
                lo[0] + (hi[0] - lo[0]) * i / d,
                lo[1] + (hi[1] - lo[1]) * j / d,
            ]
        })
        .collect()
}
