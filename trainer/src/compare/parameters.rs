//! Where to compare a parametric model when the user gives no points: its whole parameter
//! domain, covered evenly and deterministically.

use neurosurf_core::caoen::Domain;

use crate::evaluate::LoadedModel;

/// Parameters t on a uniform grid of [0, 1] for a curve.
pub const CURVE_PARAMETERS: usize = 1001;
/// Grid points per side of [0, 1]² for a spline surface, and per angle on a Cao En torus.
pub const SURFACE_GRID: usize = 33;
/// Source points on a Cao En sphere or hypersphere.
pub const SPHERE_POINTS: usize = 1000;

/// Parameters covering a parametric model's domain, and how they were chosen (for reports).
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterSet {
    /// The parameter points (t; u v; or a source point).
    pub points: Vec<Vec<f64>>,
    /// In words, e.g. "1001 uniform parameters t".
    pub description: String,
}

impl ParameterSet {
    /// The default set for `model`: uniform t for curves, a grid of [0, 1]² for spline
    /// surfaces, a grid of the parameter box a surface network was trained on, and
    /// for Cao En networks a Fibonacci sphere (m = 3), a θ × φ grid (torus) or quasi-random
    /// unit vectors (hyperspheres). `None` for field models.
    pub fn covering(model: &LoadedModel) -> Option<ParameterSet> {
        let step = 1.0 / (SURFACE_GRID - 1) as f64;
        match model {
            LoadedModel::Curve { .. } => Some(ParameterSet {
                points: (0..CURVE_PARAMETERS)
                    .map(|i| vec![i as f64 / (CURVE_PARAMETERS - 1) as f64])
                    .collect(),
                description: format!("{CURVE_PARAMETERS} uniform parameters t"),
            }),
            LoadedModel::SplineSurface { .. } => Some(ParameterSet {
                points: grid(|u, v| vec![u * step, v * step]),
                description: format!("a {SURFACE_GRID} × {SURFACE_GRID} grid of (u, v)"),
            }),
            LoadedModel::SurfaceNetwork { decoded, .. } => {
                let net = &decoded.network;
                let corner = |a: usize, t: f64| {
                    net.input_center[a] + net.input_scale[a] * (2.0 * t * step - 1.0)
                };
                Some(ParameterSet {
                    points: grid(|i, j| vec![corner(0, i), corner(1, j)]),
                    description: format!(
                        "a {SURFACE_GRID} × {SURFACE_GRID} grid of the trained (u, v) box"
                    ),
                })
            }
            LoadedModel::CaoEn { decoded, .. } => {
                let m = decoded.network.source_dimension();
                let torus = decoded.network.domain == Domain::Torus.code();
                let turn = std::f64::consts::TAU / SURFACE_GRID as f64;
                Some(if torus {
                    ParameterSet {
                        points: grid(|i, j| {
                            let (a, b) = (i * turn, j * turn);
                            vec![a.cos(), a.sin(), b.cos(), b.sin()]
                        }),
                        description: format!(
                            "a {SURFACE_GRID} × {SURFACE_GRID} grid of torus angles (θ, φ)"
                        ),
                    }
                } else if m == 3 {
                    ParameterSet {
                        points: fibonacci_sphere(SPHERE_POINTS),
                        description: format!("{SPHERE_POINTS} points spread over the sphere"),
                    }
                } else {
                    ParameterSet {
                        points: hypersphere(SPHERE_POINTS, m),
                        description: format!(
                            "{SPHERE_POINTS} quasi-random points of the {m}-D unit sphere"
                        ),
                    }
                })
            }
            _ => None,
        }
    }
}

/// `f(i, j)` over the SURFACE_GRID² grid, i fastest.
fn grid(f: impl Fn(f64, f64) -> Vec<f64>) -> Vec<Vec<f64>> {
    (0..SURFACE_GRID * SURFACE_GRID)
        .map(|k| f((k % SURFACE_GRID) as f64, (k / SURFACE_GRID) as f64))
        .collect()
}

/// n nearly evenly spread unit vectors (the golden-angle spiral).
pub fn fibonacci_sphere(n: usize) -> Vec<Vec<f64>> {
    let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let a = golden * i as f64;
            vec![r * a.cos(), r * a.sin(), z]
        })
        .collect()
}

/// n unit vectors of ℝᵐ from a fixed low-discrepancy sequence pushed through the Gaussian
/// quantile (Box–Muller on Halton coordinates), so the same m always gives the same points.
fn hypersphere(n: usize, m: usize) -> Vec<Vec<f64>> {
    // Two distinct bases per coordinate, for up to 8 coordinates.
    const PRIMES: [usize; 16] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53];
    let halton = |mut i: usize, base: usize| {
        let (mut f, mut r) = (1.0, 0.0);
        while i > 0 {
            f /= base as f64;
            r += f * (i % base) as f64;
            i /= base;
        }
        r
    };
    (1..=n)
        .map(|i| {
            let mut v: Vec<f64> = (0..m)
                .map(|k| {
                    let u1 = halton(i, PRIMES[(2 * k) % 16]).max(1e-12);
                    let u2 = halton(i, PRIMES[(2 * k + 1) % 16]);
                    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
                })
                .collect();
            let length = v.iter().map(|c| c * c).sum::<f64>().sqrt().max(1e-300);
            v.iter_mut().for_each(|c| *c /= length);
            v
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_points_are_unit_and_spread() {
        let points = fibonacci_sphere(500);
        for p in &points {
            let length = p.iter().map(|c| c * c).sum::<f64>().sqrt();
            assert!((length - 1.0).abs() < 1e-12);
        }
        let mean_z: f64 = points.iter().map(|p| p[2]).sum::<f64>() / 500.0;
        assert!(mean_z.abs() < 1e-12, "{mean_z}");
        let wide = hypersphere(200, 5);
        assert_eq!(wide.len(), 200);
        for p in &wide {
            let length = p.iter().map(|c| c * c).sum::<f64>().sqrt();
            assert!((length - 1.0).abs() < 1e-12 && p.len() == 5);
        }
        assert_eq!(hypersphere(10, 5), hypersphere(10, 5));
        // Every coordinate varies on its own: no two coordinates coincide over the set.
        let eight = hypersphere(200, 8);
        for a in 0..8 {
            for b in a + 1..8 {
                let same = eight.iter().filter(|p| (p[a] - p[b]).abs() < 1e-12).count();
                assert!(same < 5, "coordinates {a} and {b} coincide {same} times");
            }
        }
    }
}
