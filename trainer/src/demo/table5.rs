//! Carcenac's Table 5 on this machine: the torus (R = 1, r = 0.4) learned from a number of
//! control points by one network module (Levenberg–Marquardt, Table 1 settings) and by the
//! multiquadric RBF baseline (its defaults: c = 0.0078·D, which is Carcenac's c² = 10⁻³ on this
//! torus, and off-surface points on both sides at 1 % of D); training times, iterations, and
//! the fidelity of both on 2000 held-out points of the true torus. The `table5` bench and the
//! demo tour both measure it here.

use std::time::Instant;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::fidelity::{Fidelity, median};
use crate::implicit::{self, FitRequest, ImplicitOptions, Outcome};
use crate::points::PointSet;
use crate::rbf::{self, RbfOptions};
use crate::sample::{Shape, sample_shape};

/// The torus of Table 5.
pub const TABLE5_TORUS: Shape = Shape::Torus {
    major: 1.0,
    minor: 0.4,
};
/// Its diameter D, which distances are a percentage of.
pub const TABLE5_DIAMETER: f64 = 2.8;
/// Held-out points of the true torus the fidelity is measured on.
pub const TABLE5_HELD_OUT: usize = 2000;
/// Seed of the held-out points (distinct from every training seed used).
const HELD_OUT_SEED: u64 = 999;

/// One row of the paper's Table 5 (C on a 1.7 GHz Pentium IV).
#[derive(Copy, Clone, Debug, PartialEq, Serialize)]
pub struct PaperTable5Row {
    /// Control points.
    pub points: usize,
    /// LM iterations of the network.
    pub iterations: usize,
    /// Network training time, seconds.
    pub network_seconds: f64,
    /// RBF training time, seconds.
    pub rbf_seconds: f64,
}

/// The paper's Table 5.
pub const PAPER_TABLE5: [PaperTable5Row; 5] = [
    paper_row(48, 73, 2.5, 0.0018),
    paper_row(96, 61, 3.6, 0.027),
    paper_row(160, 67, 6.2, 0.18),
    paper_row(336, 58, 10.9, 1.88),
    paper_row(576, 59, 17.8, 8.3),
];

const fn paper_row(
    points: usize,
    iterations: usize,
    network_seconds: f64,
    rbf_seconds: f64,
) -> PaperTable5Row {
    PaperTable5Row {
        points,
        iterations,
        network_seconds,
        rbf_seconds,
    }
}

/// The point counts of the paper's rows.
pub fn paper_points() -> Vec<usize> {
    PAPER_TABLE5.iter().map(|r| r.points).collect()
}

/// One point count measured here: medians over the seeds.
#[derive(Clone, Debug, Serialize)]
pub struct Table5Row {
    /// Control points.
    pub points: usize,
    /// Seeds of the samples and weights (the medians are over these).
    pub seeds: Vec<u64>,
    /// LM iterations of the network on all its points.
    pub iterations: f64,
    /// LM iterations of its coarse start, on every 4th point (and every 16th, …): each costs
    /// about that share of a full iteration.
    pub coarse_iterations: f64,
    /// Network training time, seconds (one thread).
    pub network_seconds: f64,
    /// RBF training time, seconds.
    pub rbf_seconds: f64,
    /// Network: median distance to the true torus, % of D.
    pub network_distance_percent: f64,
    /// Network: median normal error, degrees.
    pub network_angle_degrees: f64,
    /// RBF: median distance to the true torus, % of D.
    pub rbf_distance_percent: f64,
    /// RBF: median normal error, degrees.
    pub rbf_angle_degrees: f64,
    /// How the network's trainings ended, the worst over the seeds.
    pub outcome: Outcome,
    /// The paper's row for this point count, if it has one.
    pub paper: Option<PaperTable5Row>,
}

impl Table5Row {
    /// The paper's value formatted by `f`, in parentheses after a space; empty when the paper
    /// has no row for this count.
    pub fn beside_paper(&self, f: impl Fn(&PaperTable5Row) -> String) -> String {
        self.paper
            .as_ref()
            .map_or_else(String::new, |p| format!(" ({})", f(p)))
    }
}

/// The held-out points of the true torus every row is measured on.
///
/// # Errors
/// None expected (the torus sampler only fails on a zero count).
pub fn table5_held_out() -> Result<PointSet> {
    sample_shape(&TABLE5_TORUS, TABLE5_HELD_OUT, HELD_OUT_SEED)
}

/// Measures every count in `points` for every seed in `seeds`, training on one thread (the
/// torus is one leaf module; the paper's machine had one core).
///
/// # Errors
/// [`Error::InvalidInput`] for no seed, a count the RBF cannot fit, or no thread to run on.
pub fn table5(points: &[usize], seeds: &[u64]) -> Result<Vec<Table5Row>> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| Error::invalid(format!("no thread for Table 5: {e}")))?;
    let held_out = table5_held_out()?;
    pool.install(|| {
        points
            .iter()
            .map(|&n| table5_row(n, seeds, &held_out))
            .collect()
    })
}

/// Measures one count of control points over `seeds` on the current thread pool.
///
/// # Errors
/// [`Error::InvalidInput`] for no seed or a count the RBF cannot fit.
pub fn table5_row(points: usize, seeds: &[u64], held_out: &PointSet) -> Result<Table5Row> {
    if seeds.is_empty() {
        return Err(Error::invalid("Table 5 needs at least one seed"));
    }
    let mut iterations = Vec::new();
    let mut coarse = Vec::new();
    let mut times = [Vec::new(), Vec::new()];
    let mut fidelity: [[Vec<f64>; 2]; 2] = Default::default();
    let mut outcome = Outcome::Converged;
    let mut record = |which: usize, f: Option<Fidelity>| -> Result<()> {
        let f = f.ok_or_else(|| Error::invalid("no held-out point to measure Table 5 on"))?;
        fidelity[which][0].push(f.median_distance_percent);
        fidelity[which][1].push(f.median_angle_degrees);
        Ok(())
    };
    for &seed in seeds {
        let sample = sample_shape(&TABLE5_TORUS, points, seed)?;
        // The paper's procedure alone: no off-surface or sign points, no sign guards (none of
        // them is in the paper).
        let options = ImplicitOptions {
            seed,
            ..ImplicitOptions::paper()
        };
        let start = Instant::now();
        let request = FitRequest {
            unguarded: true,
            ..FitRequest::default()
        };
        let trained = implicit::fit(sample.clone(), &request, &options, &|_| {})?;
        times[0].push(start.elapsed().as_secs_f64());
        let modules = &trained.summary.modules;
        outcome = outcome.worst(trained.summary.outcome());
        iterations.push(modules.iter().map(|m| m.lm.iterations as f64).sum());
        coarse.push(modules.iter().map(|m| m.coarse_iterations as f64).sum());
        record(
            0,
            Fidelity::measure(held_out, TABLE5_DIAMETER, |p| trained.network.eval(p)),
        )?;

        let start = Instant::now();
        let (model, _) = rbf::fit(&sample, &RbfOptions::default())?;
        times[1].push(start.elapsed().as_secs_f64());
        record(
            1,
            Fidelity::measure(held_out, TABLE5_DIAMETER, |p| model.field_gradient(p)),
        )?;
    }
    let [[net_d, net_a], [rbf_d, rbf_a]] = &mut fidelity;
    let [net_t, rbf_t] = &mut times;
    Ok(Table5Row {
        points,
        seeds: seeds.to_vec(),
        iterations: median(&mut iterations),
        coarse_iterations: median(&mut coarse),
        network_seconds: median(net_t),
        rbf_seconds: median(rbf_t),
        network_distance_percent: median(net_d),
        network_angle_degrees: median(net_a),
        rbf_distance_percent: median(rbf_d),
        rbf_angle_degrees: median(rbf_a),
        outcome,
        paper: PAPER_TABLE5.iter().find(|r| r.points == points).copied(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_measures_both_models_beside_the_papers_numbers() {
        let rows = table5(&[48], &[1]).unwrap();
        let row = &rows[0];
        assert_eq!(row.points, 48);
        assert_eq!(row.paper, Some(PAPER_TABLE5[0]));
        assert!(row.outcome.settled(), "{row:?}");
        assert!(row.iterations >= 1.0, "{row:?}");
        assert!(
            row.network_seconds > 0.0 && row.rbf_seconds > 0.0,
            "{row:?}"
        );
        // The paper's point: from 48 points the network is much closer to the torus than the
        // RBF (here about 4× in distance).
        assert!(row.network_distance_percent < 0.2, "{row:?}");
        assert!(
            row.network_distance_percent < row.rbf_distance_percent,
            "{row:?}"
        );
        assert!(row.network_angle_degrees < row.rbf_angle_degrees, "{row:?}");
    }

    #[test]
    fn counts_outside_the_paper_have_no_paper_row_and_no_seed_is_refused() {
        let held_out = table5_held_out().unwrap();
        let row = table5_row(64, &[2], &held_out).unwrap();
        assert_eq!(row.paper, None);
        assert_eq!(row.seeds, [2]);
        assert!(table5_row(48, &[], &held_out).is_err());
    }
}
