//! The surface network's training kernels, each against a baseline measured in the same run:
//! the packed forward pass (four points per pass, the lanes of `solve::lanes`) against the
//! reference `SurfaceNetwork::forward_normalized` and against the `exp` calls alone; and the
//! 10 000-point LLE matrix: its assembly, compression and shifted Cholesky factorization.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench parametric_kernels`.

use std::hint::black_box;
use std::time::Instant;

use neurosurf_trainer::parametric::{
    Activation, LaneRecord, PackedNetwork, SurfaceNetwork, SymmetricMatrix, check_points,
    embedding_matrix, nearest_neighbors, reconstruction_weights,
};

/// Median seconds of `runs` runs of `f`.
fn median_seconds(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}

fn forward_pass() {
    let mut network = SurfaceNetwork::zeros(
        &[12, 12],
        Activation::TanSig,
        [0.0; 2],
        [1.0; 2],
        [0.0; 3],
        1.0,
    )
    .expect("network");
    let values: Vec<f64> = (0..network.parameter_count())
        .map(|i| ((i * 37 % 101) as f64 - 50.0) / 60.0)
        .collect();
    network.set_parameters(&values).expect("parameters");
    let inputs: Vec<[f64; 2]> = (0..100_000)
        .map(|k| [(k as f64 * 0.37).sin(), (k as f64 * 0.71).cos()])
        .collect();
    let targets = vec![[0.0; 3]; inputs.len()];
    let indices: Vec<usize> = (0..inputs.len()).collect();
    let per_point = |seconds: f64| seconds * 1e9 / inputs.len() as f64;
    let reference = per_point(median_seconds(5, || {
        let sum: f64 = inputs
            .iter()
            .map(|&x| {
                network
                    .forward_normalized(x)
                    .iter()
                    .map(|y| y * y)
                    .sum::<f64>()
            })
            .sum();
        black_box(sum);
    }));
    let packed = PackedNetwork::new(&network);
    let mut record = LaneRecord::default();
    let fast = per_point(median_seconds(5, || {
        black_box(packed.squared_error_sum(&inputs, &targets, &indices, &mut record));
    }));
    let exps = per_point(median_seconds(5, || {
        let sum: f64 = inputs
            .iter()
            .map(|x| (0..24).map(|k| (x[0] * k as f64).exp()).sum::<f64>())
            .sum();
        black_box(sum);
    }));
    println!("| 2 × 12 tan-sig network, per point (median of 5) | ns | ÷ reference |");
    println!("|---|---:|---:|");
    println!("| reference forward pass (baseline) | {reference:.0} | 1.00 |");
    println!(
        "| packed, four points per pass | {fast:.0} | {:.2} |",
        fast / reference
    );
    println!(
        "| its 24 `exp` calls alone | {exps:.0} | {:.2} |",
        exps / reference
    );
}

fn lle_matrix() {
    let points: Vec<[f64; 3]> = (0..10_000)
        .map(|k| {
            let (u, v) = ((k % 100) as f64 / 99.0, (k / 100) as f64 / 99.0);
            [u, v, 0.1 * (6.0 * u).sin() * (4.0 * v).cos()]
        })
        .collect();
    let diagonal = check_points(&points, 11).expect("points");
    let neighbors = nearest_neighbors(&points, 10, diagonal).expect("neighbours");
    let weights = reconstruction_weights(&points, &neighbors, 1e-3).expect("weights");
    let mut m = SymmetricMatrix::new(0);
    let assemble = median_seconds(5, || m = embedding_matrix(&neighbors, &weights));
    let compressed = m.compress().expect("compressed");
    let compress = median_seconds(5, || {
        black_box(m.compress().expect("compressed"));
    });
    let shifted = compressed.with_diagonal_added(1e-9).expect("shifted");
    let factor = median_seconds(5, || {
        black_box(shifted.cholesky().expect("positive definite"));
    });
    println!();
    println!("| 10 000-point LLE matrix, k = 10 (median of 5) | ms | ÷ assembly |");
    println!("|---|---:|---:|");
    println!(
        "| triplets, `embedding_matrix` (baseline) | {:.1} | 1.00 |",
        assemble * 1e3
    );
    println!(
        "| compress | {:.1} | {:.2} |",
        compress * 1e3,
        compress / assemble
    );
    println!(
        "| Cholesky of M + σI | {:.1} | {:.2} |",
        factor * 1e3,
        factor / assemble
    );
}

fn main() {
    forward_pass();
    lle_matrix();
}
