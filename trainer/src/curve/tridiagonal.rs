//! Solvers for the (1, 4, 1) systems of cubic B-spline interpolation: the Thomas algorithm
//! and its cyclic variant (Sherman–Morrison). Both are O(n) and, the matrix being strictly
//! diagonally dominant (4 > 1 + 1), need no pivoting and lose at most a few ulp per unknown.

/// Solves `a·x_{i−1} + b·x_i + c·x_{i+1} = rhs_i` (i = 0..n, no wrap: x_{−1} = x_n = 0) for
/// three right-hand sides at once. `b` must dominate (`|b| > |a| + |c|`).
pub(crate) fn solve_tridiagonal(a: f64, b: f64, c: f64, rhs: &[[f64; 3]]) -> Vec<[f64; 3]> {
    thomas_general(a, &vec![b; rhs.len()], c, rhs)
}

/// Solves the cyclic system `a·x_{i−1} + b·x_i + c·x_{i+1} = rhs_i` with indices mod n
/// (n ≥ 3). Sherman–Morrison: one tridiagonal solve for the right-hand sides and one for the
/// correction vector.
pub(crate) fn solve_cyclic(a: f64, b: f64, c: f64, rhs: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = rhs.len();
    // A = T + w·vᵀ with the corners a (top right: row 0, column n−1) and c (bottom left).
    // Choose γ = −b; w = (γ, 0, …, 0, c), v = (1, 0, …, 0, a/γ).
    let gamma = -b;
    // The modified tridiagonal: b₀ − γ, b_{n−1} − a·c/γ. Solve with a general diagonal.
    let mut diagonal = vec![b; n];
    diagonal[0] = b - gamma;
    diagonal[n - 1] = b - a * c / gamma;
    let y = thomas_general(a, &diagonal, c, rhs);
    let mut w = vec![[0.0; 3]; n];
    w[0] = [gamma; 3];
    w[n - 1] = [c; 3];
    let z = thomas_general(a, &diagonal, c, &w);
    let v_last = a / gamma;
    let mut x = y.clone();
    for k in 0..3 {
        let numerator = y[0][k] + v_last * y[n - 1][k];
        let denominator = 1.0 + z[0][k] + v_last * z[n - 1][k];
        let factor = numerator / denominator;
        for i in 0..n {
            x[i][k] = y[i][k] - factor * z[i][k];
        }
    }
    x
}

/// Thomas algorithm with constant off-diagonals and a per-row diagonal.
fn thomas_general(a: f64, diagonal: &[f64], c: f64, rhs: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = rhs.len();
    let mut c_prime = vec![0.0; n];
    let mut x = rhs.to_vec();
    if n == 0 {
        return x;
    }
    c_prime[0] = c / diagonal[0];
    x[0] = x[0].map(|v| v / diagonal[0]);
    for i in 1..n {
        let denominator = diagonal[i] - a * c_prime[i - 1];
        c_prime[i] = c / denominator;
        let previous = x[i - 1];
        for k in 0..3 {
            x[i][k] = (x[i][k] - a * previous[k]) / denominator;
        }
    }
    for i in (0..n - 1).rev() {
        let following = x[i + 1];
        for k in 0..3 {
            x[i][k] -= c_prime[i] * following[k];
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(a: f64, b: f64, c: f64, x: &[[f64; 3]], cyclic: bool) -> Vec<[f64; 3]> {
        let n = x.len();
        (0..n)
            .map(|i| {
                [0, 1, 2].map(|k| {
                    let left = if i > 0 {
                        x[i - 1][k]
                    } else if cyclic {
                        x[n - 1][k]
                    } else {
                        0.0
                    };
                    let right = if i + 1 < n {
                        x[i + 1][k]
                    } else if cyclic {
                        x[0][k]
                    } else {
                        0.0
                    };
                    a * left + b * x[i][k] + c * right
                })
            })
            .collect()
    }

    #[test]
    fn both_solvers_invert_their_systems() {
        for n in [1, 2, 3, 4, 7, 50] {
            let rhs: Vec<[f64; 3]> = (0..n)
                .map(|i| [i as f64, (i * i) as f64 * 0.1 - 3.0, (i as f64).sin()])
                .collect();
            let x = solve_tridiagonal(1.0, 4.0, 1.0, &rhs);
            let back = apply(1.0, 4.0, 1.0, &x, false);
            for (r, b) in rhs.iter().zip(&back) {
                for k in 0..3 {
                    assert!((r[k] - b[k]).abs() < 1e-12, "n = {n}: {r:?} vs {b:?}");
                }
            }
            if n >= 3 {
                let x = solve_cyclic(1.0, 4.0, 1.0, &rhs);
                let back = apply(1.0, 4.0, 1.0, &x, true);
                for (r, b) in rhs.iter().zip(&back) {
                    for k in 0..3 {
                        assert!(
                            (r[k] - b[k]).abs() < 1e-12,
                            "cyclic n = {n}: {r:?} vs {b:?}"
                        );
                    }
                }
            }
        }
    }
}
