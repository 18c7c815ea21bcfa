//! Cao En batches against point-by-point evaluation on the host, in the same run: positions
//! and positions with normals, f32 and Q16.16, for networks of 26 and 104 keys, at sphere
//! points in mesh order (each point beside the previous one, as `caoen mesh` and the depth
//! buffer ask) and the same points in a scattered order.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench caoen_batch`; `-- --out FILE` also writes
//! the table as Markdown.

use std::hint::black_box;
use std::time::Instant;

use neurosurf_core::caoen::{Blending, CaoEnModel, Domain};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
use neurosurf_trainer::caoen::{fit_shape, from_key_points, order_for_groups, to_blob};
use neurosurf_trainer::compare::fibonacci_sphere;

/// Median seconds of `runs` runs of `a` and of `b`, run in turn so that both see the same
/// machine.
fn median_pair(runs: usize, mut a: impl FnMut(), mut b: impl FnMut()) -> (f64, f64) {
    let timed = |f: &mut dyn FnMut()| {
        let start = Instant::now();
        f();
        start.elapsed().as_secs_f64()
    };
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        ta.push(timed(&mut a));
        tb.push(timed(&mut b));
    }
    let median = |mut t: Vec<f64>| {
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    };
    (median(ta), median(tb))
}

/// A sphere network with `n` Fibonacci keys on a bent ellipsoid; compact blending is
/// normalized, with caps reaching about three key spacings.
fn network(n: usize, blending: Blending) -> Vec<u8> {
    let keys = fibonacci_sphere(n);
    let targets: Vec<Vec<f64>> = keys
        .iter()
        .map(|k| vec![1.3 * k[0], 0.8 * k[1] + 0.25 * k[0] * k[0], 0.6 * k[2]])
        .collect();
    let (q, normalized) = match blending {
        Blending::Compact => (n as f64 / 12.0, true),
        Blending::Power => (2.0, false),
        _ => (if n > 30 { 12.0 } else { 4.0 }, false),
    };
    let built =
        from_key_points(Domain::Sphere, blending, normalized, &keys, &targets, q).expect("network");
    let fitted = order_for_groups(&fit_shape(&built, &keys, &targets).expect("fit"));
    to_blob(&fitted, ScalarKind::F32, &[]).expect("blob")
}

/// A latitude–longitude grid of the sphere, row by row: consecutive points are neighbours.
fn mesh_order(rows: usize, columns: usize) -> Vec<[f64; 3]> {
    let mut points = Vec::with_capacity(rows * columns);
    for i in 0..rows {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / rows as f64;
        let r = (1.0 - z * z).sqrt();
        for j in 0..columns {
            let a = std::f64::consts::TAU * j as f64 / columns as f64;
            points.push([r * a.cos(), r * a.sin(), z]);
        }
    }
    points
}

/// The same points, visited with a stride coprime to their count.
fn scattered(points: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = points.len();
    (0..n).map(|i| points[(i * 7919) % n]).collect()
}

struct Timing {
    single: f64,
    batch: f64,
}

/// Median seconds of the points `x` through `single`, one by one, and through `batch`.
fn single_and_batch<X, T: Copy + Default, E: std::fmt::Debug>(
    x: &[X],
    single: impl Fn(&X) -> T,
    batch: impl Fn(&[X], &mut [T]) -> Result<(), E>,
) -> (f64, f64) {
    let out = std::cell::RefCell::new(vec![T::default(); x.len()]);
    median_pair(
        31,
        || {
            for (x, out) in x.iter().zip(out.borrow_mut().iter_mut()) {
                *out = single(black_box(x));
            }
            black_box(&out);
        },
        || {
            batch(black_box(x), &mut out.borrow_mut()).expect("lengths");
            black_box(&out);
        },
    )
}

fn time<S: Scalar>(blob: &[u8], points: &[[f64; 3]], normals: bool) -> Timing {
    let model: CaoEnModel<S> = CaoEnModel::from_blob(blob).expect("the core loads the blob");
    let x: Vec<[S; 3]> = points
        .iter()
        .map(|p| p.map(|c| S::from_f32_saturating(c as f32)))
        .collect();
    let (single, batch) = if normals {
        single_and_batch(
            &x,
            |x| model.eval_normal(x),
            |x, out| model.eval_normal_batch(x, out),
        )
    } else {
        single_and_batch(
            &x,
            |x| model.eval::<3, 3>(x),
            |x, out| model.eval_batch(x, out),
        )
    };
    let per_point = 1e9 / x.len() as f64;
    Timing {
        single: single * per_point,
        batch: batch * per_point,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1));
    let grid = mesh_order(48, 96);
    let orders = [
        ("mesh order", grid.clone()),
        ("scattered", scattered(&grid)),
    ];
    let mut table = String::from(
        "| network | points | op | scalar | single ns/point | batch ns/point | batch ÷ single |\n\
         |---|---|---|---|---:|---:|---:|\n",
    );
    for (n, blending, name) in [
        (26, Blending::Exponential, "26 keys, exponential"),
        (104, Blending::Exponential, "104 keys, exponential"),
        (104, Blending::Power, "104 keys, power q = 2"),
        (26, Blending::Compact, "26 keys, compact normalized"),
        (104, Blending::Compact, "104 keys, compact normalized"),
    ] {
        let blob = network(n, blending);
        for (order, points) in &orders {
            for (op, normals) in [("position", false), ("position+normal", true)] {
                for scalar in [ScalarKind::F32, ScalarKind::Q16_16] {
                    let t = match scalar {
                        ScalarKind::F32 => time::<f32>(&blob, points, normals),
                        _ => time::<Q16>(&blob, points, normals),
                    };
                    let line = format!(
                        "| {name} | {order} | {op} | {} | {:.0} | {:.0} | {:.2} |\n",
                        scalar.name(),
                        t.single,
                        t.batch,
                        t.batch / t.single
                    );
                    print!("{line}");
                    table.push_str(&line);
                }
            }
        }
    }
    if let Some(path) = out {
        let text = format!(
            "# Cao En batches on the host\n\nWritten by `cargo bench -p neurosurf-trainer --bench \
             caoen_batch -- --out {path}`: nanoseconds per point, the median of 31 runs each, taken in turn, over \
             4 608 sphere points, batch and point by point in the same run. Mesh order: a \
             latitude–longitude grid row by row; scattered: the same points with a stride of \
             7 919.\n\n{table}"
        );
        // Relative to the workspace, where the command is typed (cargo runs benches in the
        // package's directory).
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(path);
        std::fs::write(&file, text).expect("write --out");
        eprintln!("wrote {}", file.display());
    }
}
