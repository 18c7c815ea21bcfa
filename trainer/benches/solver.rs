//! The training solver's kernels on this machine: one Levenberg–Marquardt iteration of the
//! N = 9 torus leaf at Carcenac's largest Table 5 size (576 points), piece by piece —
//! residuals, the Jacobian, JᵀJ and Jᵀe fused with the Jacobian (what training runs) against
//! JᵀJ from a stored Jacobian, and the damped Cholesky solve — and the normal equations of a
//! large dense problem (2 304 × 136) in f64 and f32.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench solver`. Times are the fastest of many runs
//! (the machine is shared); ratios are against the fused normal equations of the same run.

use std::hint::black_box;
use std::time::Instant;

use neurosurf_trainer::demo::TABLE5_TORUS;
use neurosurf_trainer::implicit::{BoxScaling, ModuleData, ModuleProblem, Normalization};
use neurosurf_trainer::sample::sample_shape;
use neurosurf_trainer::solve::{DampedSystem, LeastSquares, NormalEquations};

/// Fastest of `reps` runs of `f`, in milliseconds.
fn best_ms(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let points = sample_shape(&TABLE5_TORUS, 576, 1).expect("torus");
    let norm = Normalization::fit(&points.positions, 2.0, BoxScaling::Isotropic, "torus")
        .expect("normalization");
    let columns: [[f64; 3]; 3] = std::array::from_fn(|k| norm.matrix.map(|r| r[k]));
    let mut data = ModuleData::new(3);
    for (x, n) in points.positions.iter().zip(&points.normals) {
        let target = n.map(|n| -5.0 * n);
        data.push(
            &norm.apply(*x),
            [&columns[0], &columns[1], &columns[2]],
            target,
        );
    }
    let problem = ModuleProblem::new(&data, 9, 0.05);
    let (p, ns) = (problem.parameter_count(), problem.residual_count());
    let params: Vec<f64> = (0..p)
        .map(|i| ((i * 37 % 17) as f64 - 8.0) / 16.0)
        .collect();
    let mut e = vec![0.0; ns];
    let mut j = vec![0.0; ns * p];
    let mut sums = NormalEquations::new(p);

    let residuals = best_ms(200, || problem.residuals(black_box(&params), &mut e));
    let jacobian = best_ms(100, || problem.jacobian(black_box(&params), &mut e, &mut j));
    let fused = best_ms(100, || {
        sums.clear();
        problem.normal_equations(black_box(&params), &mut e, &mut sums);
        sums.finish();
    });
    problem.jacobian(&params, &mut e, &mut j);
    let stored = best_ms(100, || {
        sums.clear();
        sums.add_jacobian(black_box(&j), &e);
        sums.finish();
    });
    let mut system = DampedSystem::new(p);
    for i in 0..p {
        let row = system.lhs_row_mut(i);
        // Row i from the diagonal on: entry k is A[i][i + k].
        for (k, value) in row.iter_mut().enumerate() {
            *value = sums.gram(i, i + k) / ns as f64;
        }
    }
    for (i, b) in system.rhs_mut().iter_mut().enumerate() {
        *b = -sums.gradient(i) / ns as f64;
    }
    assert!(system.solve(1e-3).is_some(), "A + μI is positive definite");
    let solve = best_ms(2000, || {
        black_box(system.solve(black_box(1e-3)));
    });

    println!(
        "one LM iteration of the N = 9 torus leaf, 576 points ({ns} residuals, {p} parameters)"
    );
    println!();
    println!("| step | ms | ÷ fused J + JᵀJ |");
    println!("|---|---:|---:|");
    for (step, ms) in [
        ("residuals", residuals),
        ("Jacobian (stored)", jacobian),
        ("J + JᵀJ + Jᵀe fused (training)", fused),
        ("JᵀJ + Jᵀe from the stored J", stored),
        ("(A + μI)Δ = b, Cholesky", solve),
    ] {
        println!("| {step} | {ms:.3} | {:.2} |", ms / fused);
    }

    let (rows, cols) = (2304, 136);
    let big: Vec<f64> = (0..rows * cols)
        .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
        .collect();
    let r: Vec<f64> = (0..rows).map(|i| (i % 5) as f64 - 2.0).collect();
    let mut double = NormalEquations::new(cols);
    let f64_ms = best_ms(100, || {
        double.clear();
        double.add_jacobian(black_box(&big), &r);
        double.finish();
    });
    let mut single = NormalEquations::single_precision(cols);
    let f32_ms = best_ms(100, || {
        single.clear();
        single.add_jacobian(black_box(&big), &r);
        single.finish();
    });
    let fmas = (rows * cols * (cols + 1) / 2) as f64;
    println!();
    println!("JᵀJ of a {rows} × {cols} Jacobian (lower triangle, {fmas:.2e} multiply–adds)");
    println!();
    println!("| sums in | ms | GFMA/s | ÷ f64 |");
    println!("|---|---:|---:|---:|");
    for (what, ms) in [("f64", f64_ms), ("f32", f32_ms)] {
        println!(
            "| {what} | {ms:.3} | {:.2} | {:.2} |",
            fmas / ms * 1e-6,
            ms / f64_ms
        );
    }
}
