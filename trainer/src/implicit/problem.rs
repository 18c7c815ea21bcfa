//! The least-squares problem of one module: its control points' inputs and target gradients,
//! and the points that constrain only its value (off-surface and sign points).
//!
//! About 700 lines, 200 of them the tests that hold the lane-wise rows to the one-point
//! Jacobian.

use super::jacobian::{
    InputJet, InputLanes, MAX_INPUTS, TapeLanes, TrainedLayout, forward_lanes, jacobian_lanes,
    transpose_lanes,
};
use super::value_rows::{ValueTape, forward_value_lanes, value_row_lanes};
use crate::solve::{LANES, Lanes, LeastSquares, NormalEquations, cpu_has_fma};

/// Receives a group of active value rows: `(rows, residuals, point indices)`.
type RowSink<'a> = dyn FnMut(&[f64], &[f64], &[usize]) + 'a;
/// A module's training data: per control point, the module's inputs with their tangents
/// (derivatives with respect to world x), and the target gradient −s·n.
///
/// For a leaf the inputs are the normalized coordinates A(x − c) with tangents the columns of
/// A; for a node they are the last hidden layers of its (frozen) children.
#[derive(Clone, Debug, PartialEq)]
pub struct ModuleData {
    inputs: usize,
    values: Vec<f64>,
    tangents: Vec<f64>,
    targets: Vec<[f64; 3]>,
    /// Each control point's weight: its residuals and Jacobian rows are scaled by it.
    weights: Vec<f64>,
    /// Inputs of the value points (`inputs` each) and what each asks of Φ.
    point_values: Vec<f64>,
    goals: Vec<ValueGoal>,
}

/// What a value point asks of Φ: the residual `weight·(Φ − value)`. With a nonzero `hinge`
/// σ it is one-sided, counting only while σ·(Φ − value) < 0: a sign constraint that keeps Φ
/// beyond `value` on the σ side.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ValueGoal {
    /// Target of Φ.
    pub value: f64,
    /// Weight of the residual.
    pub weight: f64,
    /// 0 for a two-sided residual; +1 or −1 for a one-sided one.
    pub hinge: f64,
}

impl ValueGoal {
    /// The residual's weight at Φ = `phi`: 0 where a one-sided residual is met.
    fn active_weight(&self, phi: f64) -> f64 {
        if self.hinge != 0.0 && self.hinge * (phi - self.value) >= 0.0 {
            0.0
        } else {
            self.weight
        }
    }
}

impl ModuleData {
    /// An empty data set for a module with `inputs` inputs.
    pub fn new(inputs: usize) -> Self {
        ModuleData {
            inputs,
            values: Vec::new(),
            tangents: Vec::new(),
            targets: Vec::new(),
            weights: Vec::new(),
            point_values: Vec::new(),
            goals: Vec::new(),
        }
    }

    /// Adds one control point: input `values` (d), `tangents[k]` (d each), and the target
    /// gradient ∇Φ = −s·n.
    pub fn push(&mut self, values: &[f64], tangents: [&[f64]; 3], target_gradient: [f64; 3]) {
        self.push_weighted(values, tangents, target_gradient, 1.0);
    }

    /// [`Self::push`] for a control point whose residuals weigh `weight`.
    pub fn push_weighted(
        &mut self,
        values: &[f64],
        tangents: [&[f64]; 3],
        target_gradient: [f64; 3],
        weight: f64,
    ) {
        debug_assert_eq!(values.len(), self.inputs);
        self.values.extend_from_slice(values);
        for t in tangents {
            debug_assert_eq!(t.len(), self.inputs);
            self.tangents.extend_from_slice(t);
        }
        self.targets.push(target_gradient);
        self.weights.push(weight);
    }

    /// Adds one value point: its input `values` (d) and what it asks of Φ.
    pub fn push_value(&mut self, values: &[f64], goal: ValueGoal) {
        debug_assert_eq!(values.len(), self.inputs);
        self.point_values.extend_from_slice(values);
        self.goals.push(goal);
    }

    /// Number of control points.
    pub fn len(&self) -> usize {
        self.targets.len()
    }

    /// Number of value points.
    pub fn value_len(&self) -> usize {
        self.goals.len()
    }

    /// Whether there are no points of either kind.
    pub fn is_empty(&self) -> bool {
        self.targets.is_empty() && self.goals.is_empty()
    }

    /// Every `every`-th control point and every `every`-th value point (the first of each
    /// kind included), with their weights and goals.
    pub fn thinned(&self, every: usize) -> ModuleData {
        let every = every.max(1);
        let d = self.inputs;
        let mut thin = ModuleData::new(d);
        for i in (0..self.len()).step_by(every) {
            let input = self.input(i);
            thin.push_weighted(
                input.values,
                input.tangents,
                self.targets[i],
                self.weights[i],
            );
        }
        for j in (0..self.value_len()).step_by(every) {
            thin.push_value(&self.point_values[j * d..(j + 1) * d], self.goals[j]);
        }
        thin
    }

    /// Inputs per point.
    pub fn inputs(&self) -> usize {
        self.inputs
    }

    /// The inputs of point `i`.
    pub fn input(&self, i: usize) -> InputJet<'_> {
        let d = self.inputs;
        let values = &self.values[i * d..(i + 1) * d];
        let t = &self.tangents[i * 3 * d..(i + 1) * 3 * d];
        InputJet {
            values,
            tangents: [&t[..d], &t[d..2 * d], &t[2 * d..]],
        }
    }
}

/// Rows beyond which [`ModuleProblem`] computes its residuals and sums its normal equations on
/// two threads: a node over a few hundred control points has more (four rows per point, plus
/// its off-surface and sign points).
pub const PARALLEL_ROWS: usize = 2048;

/// A contiguous share of a problem's points and their residuals.
struct Part<'r> {
    surface_first: usize,
    surface: &'r mut [f64],
    value_first: usize,
    values: &'r mut [f64],
}

/// Residuals e = [Φ, γ(∂Φ/∂xₖ + s·nₖ)] of every control point of a module, as a
/// [`LeastSquares`] problem over the module's trained parameters.
///
/// Points go through the network [`LANES`] at a time, one per SIMD lane (with AVX2 and FMA
/// when the CPU has them), and their Jacobian rows go straight to the normal equations.
#[derive(Clone, Debug)]
pub struct ModuleProblem<'a> {
    data: &'a ModuleData,
    layout: TrainedLayout,
    gamma: f64,
    fma: bool,
}

impl<'a> ModuleProblem<'a> {
    /// The problem of fitting a width-`width` module to `data` with gradient weight `gamma`.
    pub fn new(data: &'a ModuleData, width: usize, gamma: f64) -> Self {
        ModuleProblem {
            data,
            layout: TrainedLayout::new(data.inputs(), width),
            gamma,
            fma: cpu_has_fma(),
        }
    }

    /// The trained-parameter layout.
    pub fn layout(&self) -> &TrainedLayout {
        &self.layout
    }

    fn point_residuals(&self, i: usize, tape_value: f64, gradient: [f64; 3], out: &mut [f64]) {
        let target = self.data.targets[i];
        let weight = self.data.weights[i];
        out[0] = weight * tape_value;
        for k in 0..3 {
            out[1 + k] = weight * self.gamma * (gradient[k] - target[k]);
        }
    }

    /// Loads points `first..first + count` into the lanes (the last repeated in spare lanes).
    fn gather(&self, first: usize, count: usize, lanes: &mut InputLanes) {
        let d = self.data.inputs;
        for l in 0..LANES {
            let input = self.data.input(first + l.min(count - 1));
            for c in 0..d {
                lanes.values[c][l] = input.values[c];
                for k in 0..3 {
                    lanes.tangents[k][c][l] = input.tangents[k][c];
                }
            }
        }
    }

    /// The residuals of the points in `tape` (from `first` on) into `out`.
    fn lane_residuals(&self, first: usize, tape: &TapeLanes, out: &mut [f64]) {
        for (l, point) in out.chunks_exact_mut(4).enumerate() {
            let gradient = [
                tape.gradient[0][l],
                tape.gradient[1][l],
                tape.gradient[2][l],
            ];
            self.point_residuals(first + l, tape.value[l], gradient, point);
        }
    }

    #[inline(always)]
    fn residuals_impl<const FMA: bool>(&self, params: &[f64], part: Part<'_>) {
        let mut lanes = InputLanes::ZERO;
        let mut tape = TapeLanes::ZERO;
        for (group, out) in part.surface.chunks_mut(4 * LANES).enumerate() {
            let first = part.surface_first + group * LANES;
            self.gather(first, out.len() / 4, &mut lanes);
            forward_lanes::<FMA>(&self.layout, params, &lanes, &mut tape);
            self.lane_residuals(first, &tape, out);
        }
        let mut inputs = [[0.0; LANES]; MAX_INPUTS];
        let mut tape = ValueTape::ZERO;
        for (group, out) in part.values.chunks_mut(LANES).enumerate() {
            let first = part.value_first + group * LANES;
            self.gather_values(first, out.len(), &mut inputs);
            forward_value_lanes::<FMA>(&self.layout, params, &inputs, &mut tape);
            for (l, e) in out.iter_mut().enumerate() {
                *e = self.value_residual(first + l, tape.value[l]).0;
            }
        }
    }

    /// One thread's share of the residuals.
    fn residuals_part(&self, params: &[f64], part: Part<'_>) {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
            unsafe { self.residuals_fma(params, part) };
            return;
        }
        self.residuals_impl::<false>(params, part);
    }

    /// `residuals` split into its control points' rows and its value points' rows, whole
    /// when it has at most [`PARALLEL_ROWS`] rows, else in two halves on lane-group
    /// boundaries (one per thread).
    fn parts<'r>(&self, residuals: &'r mut [f64]) -> (Part<'r>, Option<Part<'r>>) {
        let (surface, values) = residuals.split_at_mut(4 * self.data.len());
        if surface.len() + values.len() <= PARALLEL_ROWS {
            let whole = Part {
                surface_first: 0,
                surface,
                value_first: 0,
                values,
            };
            return (whole, None);
        }
        let surface_half = self.data.len().div_ceil(2 * LANES) * LANES;
        let value_half = self.data.value_len().div_ceil(2 * LANES) * LANES;
        let (surface_a, surface_b) = surface.split_at_mut(4 * surface_half);
        let (values_a, values_b) = values.split_at_mut(value_half);
        let first = Part {
            surface_first: 0,
            surface: surface_a,
            value_first: 0,
            values: values_a,
        };
        let second = Part {
            surface_first: surface_half,
            surface: surface_b,
            value_first: value_half,
            values: values_b,
        };
        (first, Some(second))
    }

    /// Loads value points `first..first + count` into lanes (the last repeated in spare lanes).
    fn gather_values(&self, first: usize, count: usize, inputs: &mut [Lanes; MAX_INPUTS]) {
        let d = self.data.inputs;
        for l in 0..LANES {
            let i = first + l.min(count - 1);
            let values = &self.data.point_values[i * d..(i + 1) * d];
            for c in 0..d {
                inputs[c][l] = values[c];
            }
        }
    }

    /// The residual of value point `i` at Φ = `phi`, and the weight its Jacobian row carries.
    fn value_residual(&self, i: usize, phi: f64) -> (f64, f64) {
        let goal = self.data.goals[i];
        let weight = goal.active_weight(phi);
        (weight * (phi - goal.value), weight)
    }

    /// The value points' residuals, and the Jacobian rows of those whose residual is active,
    /// [`LANES`] points at a time: `emit(rows, residuals, points)` receives each group's active
    /// rows (row-major with `stride`), their residuals and their point indices.
    #[inline(always)]
    fn value_rows<const FMA: bool>(
        &self,
        params: &[f64],
        first_point: usize,
        residuals: &mut [f64],
        stride: usize,
        emit: &mut RowSink<'_>,
    ) {
        let p = self.layout.len;
        let mut inputs = [[0.0; LANES]; MAX_INPUTS];
        let mut tape = ValueTape::ZERO;
        let mut lanes = vec![[0.0; LANES]; p];
        let mut rows = vec![0.0; LANES * stride];
        let mut active = [0.0; LANES];
        let mut points = [0; LANES];
        for (group, out) in residuals.chunks_mut(LANES).enumerate() {
            let first = first_point + group * LANES;
            self.gather_values(first, out.len(), &mut inputs);
            forward_value_lanes::<FMA>(&self.layout, params, &inputs, &mut tape);
            let mut count = 0;
            for (l, e) in out.iter_mut().enumerate() {
                let (residual, weight) = self.value_residual(first + l, tape.value[l]);
                *e = residual;
                if weight != 0.0 {
                    active[count] = residual;
                    points[count] = first + l;
                    if count == 0 {
                        value_row_lanes::<FMA>(&self.layout, params, &inputs, &tape, &mut lanes);
                    }
                    let row = &mut rows[count * stride..(count + 1) * stride];
                    for (r, x) in row.iter_mut().zip(&lanes) {
                        *r = weight * x[l];
                    }
                    count += 1;
                }
            }
            if count > 0 {
                emit(&rows[..count * stride], &active[..count], &points[..count]);
            }
        }
    }

    /// Residuals and the Jacobian rows of [`LANES`] points at a time: for each group, its
    /// residuals and the rows of its `count` points, row-major with `stride` (4 per point), in
    /// `block`.
    ///
    /// A loop over the groups rather than a callback, so that everything is inlined into the
    /// AVX2 build.
    #[inline(always)]
    fn jacobian_group<const FMA: bool>(
        &self,
        params: &[f64],
        first: usize,
        out: &mut [f64],
        work: &mut (InputLanes, TapeLanes, Vec<[f64; LANES]>),
        stride: usize,
        block: &mut [f64],
    ) {
        let (lanes, tape, rows) = work;
        let count = out.len() / 4;
        self.gather(first, count, lanes);
        forward_lanes::<FMA>(&self.layout, params, lanes, tape);
        self.lane_residuals(first, tape, out);
        jacobian_lanes::<FMA>(&self.layout, params, lanes, tape, self.gamma, rows, stride);
        transpose_lanes::<FMA>(rows, stride, count, block);
        let weights = &self.data.weights[first..first + count];
        for (point, &weight) in block.chunks_exact_mut(4 * stride).zip(weights) {
            if weight != 1.0 {
                point.iter_mut().for_each(|j| *j *= weight);
            }
        }
    }

    /// Scratch space of [`Self::jacobian_group`].
    fn jacobian_work(stride: usize) -> (InputLanes, TapeLanes, Vec<[f64; LANES]>) {
        (
            InputLanes::ZERO,
            TapeLanes::ZERO,
            vec![[0.0; LANES]; 4 * stride],
        )
    }

    /// Accumulates the rows of `part`'s control points and value points.
    #[inline(always)]
    fn normal_equations_impl<const FMA: bool>(
        &self,
        params: &[f64],
        part: Part<'_>,
        normal: &mut NormalEquations,
    ) {
        let stride = normal.stride();
        let mut work = Self::jacobian_work(stride);
        for (group, out) in part.surface.chunks_mut(4 * LANES).enumerate() {
            // The group's rows go straight into the accumulator's block.
            let first = part.surface_first + group * LANES;
            normal.set_cursor(4 * first);
            let (block, e) = normal.rows_mut(out.len());
            self.jacobian_group::<FMA>(params, first, out, &mut work, stride, block);
            e.copy_from_slice(out);
        }
        let value_residuals = 4 * self.data.len();
        let emit = &mut |rows: &[f64], residuals: &[f64], points: &[usize]| {
            let rows = rows.chunks_exact(stride).zip(residuals).zip(points);
            for ((row, &residual), &point) in rows {
                normal.set_cursor(value_residuals + point);
                let (block, e) = normal.rows_mut(1);
                block.copy_from_slice(row);
                e[0] = residual;
            }
        };
        self.value_rows::<FMA>(params, part.value_first, part.values, stride, emit);
    }

    /// One thread's share of the normal equations.
    fn normal_equations_part(&self, params: &[f64], part: Part<'_>, normal: &mut NormalEquations) {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
            unsafe { self.normal_equations_fma(params, part, normal) };
            return;
        }
        self.normal_equations_impl::<false>(params, part, normal);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn residuals_fma(&self, params: &[f64], part: Part<'_>) {
        self.residuals_impl::<true>(params, part);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn normal_equations_fma(&self, params: &[f64], part: Part<'_>, normal: &mut NormalEquations) {
        self.normal_equations_impl::<true>(params, part, normal);
    }
}

impl LeastSquares for ModuleProblem<'_> {
    fn parameter_count(&self) -> usize {
        self.layout.len
    }

    fn residual_count(&self) -> usize {
        4 * self.data.len() + self.data.value_len()
    }

    /// The control points' four terms each: the value points add to E_s without counting.
    fn error_terms(&self) -> usize {
        4 * self.data.len()
    }

    /// Problems of more than `PARALLEL_ROWS` rows are computed in two halves on two
    /// threads (every residual is computed alone, so the split changes no bit).
    fn residuals(&self, params: &[f64], residuals: &mut [f64]) {
        match self.parts(residuals) {
            (whole, None) => self.residuals_part(params, whole),
            (first, Some(second)) => {
                rayon::join(
                    || self.residuals_part(params, first),
                    || self.residuals_part(params, second),
                );
            }
        }
    }

    /// The rows [`Self::normal_equations`] uses (portable arithmetic).
    fn jacobian(&self, params: &[f64], residuals: &mut [f64], jacobian: &mut [f64]) {
        let p = self.layout.len;
        let stride = p.div_ceil(4) * 4;
        let mut work = Self::jacobian_work(stride);
        let mut block = vec![0.0; 4 * LANES * stride];
        let surface_rows = 4 * self.data.len();
        let (surface, values) = residuals.split_at_mut(surface_rows);
        let (surface_j, values_j) = jacobian.split_at_mut(surface_rows * p);
        let groups = surface
            .chunks_mut(4 * LANES)
            .zip(surface_j.chunks_mut(4 * LANES * p));
        for (group, (out, dst)) in groups.enumerate() {
            self.jacobian_group::<false>(params, group * LANES, out, &mut work, stride, &mut block);
            for (d, s) in dst.chunks_exact_mut(p).zip(block.chunks_exact(stride)) {
                d.copy_from_slice(&s[..p]);
            }
        }
        // Value points: inactive rows stay zero.
        values_j.fill(0.0);
        self.value_rows::<false>(params, 0, values, stride, &mut |rows, _, points| {
            for (row, &i) in rows.chunks_exact(stride).zip(points) {
                values_j[i * p..(i + 1) * p].copy_from_slice(&row[..p]);
            }
        });
    }

    /// J [`LANES`] points at a time, straight into the accumulator's block: J is never stored
    /// whole. The residuals are those of [`Self::residuals`].
    ///
    /// Problems of more than `PARALLEL_ROWS` rows are split in two halves summed on two
    /// threads (the sums are added in a fixed order, so the result does not depend on the
    /// thread count).
    fn normal_equations(
        &self,
        params: &[f64],
        residuals: &mut [f64],
        normal: &mut NormalEquations,
    ) {
        let (first, second) = match self.parts(residuals) {
            (whole, None) => {
                self.normal_equations_part(params, whole, normal);
                return;
            }
            (first, Some(second)) => (first, second),
        };
        let mut other = normal.empty_like();
        rayon::join(
            || {
                self.normal_equations_part(params, first, normal);
                normal.finish();
            },
            || {
                self.normal_equations_part(params, second, &mut other);
                other.finish();
            },
        );
        normal.add(&other);
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::implicit::jacobian::{forward, jacobian_rows};

    /// Random data and weights for a module with `d` inputs and width `n`.
    fn random_problem(d: usize, n: usize, points: usize, seed: u64) -> (ModuleData, Vec<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut data = ModuleData::new(d);
        for _ in 0..points {
            let values: Vec<f64> = (0..d).map(|_| rng.random_range(-1.5..1.5)).collect();
            let t: [Vec<f64>; 3] =
                std::array::from_fn(|_| (0..d).map(|_| rng.random_range(-2.0..2.0)).collect());
            let target = std::array::from_fn(|_| rng.random_range(-5.0..5.0));
            // Every third point weighs less, as a module's borrowed points do.
            let weight = if data.len() % 3 == 2 {
                rng.random_range(0.1..1.0)
            } else {
                1.0
            };
            data.push_weighted(&values, [&t[0], &t[1], &t[2]], target, weight);
        }
        let params = (0..TrainedLayout::new(d, n).len)
            .map(|_| rng.random_range(-0.8..0.8))
            .collect();
        (data, params)
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()))
    }

    /// The batched residuals, Jacobian and normal equations equal the per-point `forward` and
    /// `jacobian_rows` (up to rounding: lanes use their own tanh, and FMA when the CPU has it),
    /// in the portable build and, when the CPU has it, the AVX2 one.
    /// Value points: two-sided ones and one-sided ones on both sides of their margin. Their
    /// Jacobian rows match central differences of the residuals (zero where a one-sided
    /// residual is met), and the normal equations hold exactly the active rows.
    #[test]
    fn value_points_have_the_right_rows() {
        for (d, n, seed) in [(3, 9, 5), (21, 9, 6), (3, 4, 7)] {
            let (mut data, params) = random_problem(d, n, 6, seed);
            let mut rng = ChaCha8Rng::seed_from_u64(seed + 100);
            for k in 0..11 {
                let values: Vec<f64> = (0..d).map(|_| rng.random_range(-1.5..1.5)).collect();
                let hinge = [0.0, 1.0, -1.0][k % 3];
                let goal = ValueGoal {
                    value: rng.random_range(-0.5..0.5),
                    weight: rng.random_range(0.5..2.0),
                    hinge,
                };
                data.push_value(&values, goal);
            }
            for fma in [false, cpu_has_fma()] {
                let mut problem = ModuleProblem::new(&data, n, 0.3);
                problem.fma = fma;
                let (m, p) = (problem.residual_count(), problem.parameter_count());
                let mut e = vec![0.0; m];
                let mut j = vec![0.0; m * p];
                problem.jacobian(&params, &mut e, &mut j);
                let first = 4 * data.len();
                let mut plus = vec![0.0; m];
                let mut minus = vec![0.0; m];
                let h = 1e-6;
                let mut inactive = 0;
                for t in 0..p {
                    let mut shifted = params.clone();
                    shifted[t] += h;
                    problem.residuals(&shifted, &mut plus);
                    shifted[t] -= 2.0 * h;
                    problem.residuals(&shifted, &mut minus);
                    for r in first..m {
                        let numeric = (plus[r] - minus[r]) / (2.0 * h);
                        let analytic = j[r * p + t];
                        // A one-sided residual that is met is 0 on both sides (away from its kink).
                        assert!(
                            (numeric - analytic).abs() <= 1e-6 * (1.0 + numeric.abs()),
                            "d {d} row {r} param {t}: {numeric} vs {analytic}"
                        );
                    }
                }
                for r in first..m {
                    if j[r * p..(r + 1) * p].iter().all(|&x| x == 0.0) {
                        inactive += 1;
                        assert_eq!(e[r], 0.0);
                    }
                }
                assert!(inactive > 0 && inactive < m - first, "{inactive}");
                let mut normal = NormalEquations::new(p);
                let mut e2 = vec![0.0; m];
                problem.normal_equations(&params, &mut e2, &mut normal);
                normal.finish();
                assert!(e.iter().zip(&e2).all(|(a, b)| close(*a, *b)));
                let mut reference = NormalEquations::new(p);
                reference.add_jacobian(&j, &e);
                reference.finish();
                for r in 0..p {
                    assert!(close(normal.gradient(r), reference.gradient(r)));
                    for c in r..p {
                        assert!(close(normal.gram(r, c), reference.gram(r, c)), "{r} {c}");
                    }
                }
            }
        }
    }

    /// A problem large enough to be summed on two threads gives the sums of its whole J.
    #[test]
    fn split_normal_equations_match_the_whole_jacobian() {
        let (mut data, params) = random_problem(3, 9, 1100, 8);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for k in 0..301 {
            let values: Vec<f64> = (0..3).map(|_| rng.random_range(-1.5..1.5)).collect();
            let goal = ValueGoal {
                value: 0.1,
                weight: 1.0,
                hinge: [0.0, 1.0, -1.0][k % 3],
            };
            data.push_value(&values, goal);
        }
        let problem = ModuleProblem::new(&data, 9, 0.05);
        let (m, p) = (problem.residual_count(), problem.parameter_count());
        assert!(m > PARALLEL_ROWS);
        let mut e = vec![0.0; m];
        let mut j = vec![0.0; m * p];
        problem.jacobian(&params, &mut e, &mut j);
        let mut reference = NormalEquations::new(p);
        reference.add_jacobian(&j, &e);
        reference.finish();
        let mut normal = NormalEquations::new(p).keeping_rows();
        let mut e2 = vec![0.0; m];
        problem.normal_equations(&params, &mut e2, &mut normal);
        normal.finish();
        assert!(e.iter().zip(&e2).all(|(a, b)| close(*a, *b)));
        for r in 0..p {
            assert!(close(normal.gradient(r), reference.gradient(r)));
            for c in r..p {
                let (a, b) = (normal.gram(r, c), reference.gram(r, c));
                assert!((a - b).abs() <= 1e-10 * (1.0 + a.abs()), "{r} {c}: {a} {b}");
            }
        }
        // The kept rows, from both halves and the value points, each carry its residual's
        // index: Jᵀq for q_i = i + J_i·v is that of the whole J (f32 rows: to 10⁻⁵).
        let kept = normal.kept_rows().expect("kept rows");
        assert!(kept.is_complete());
        let v: Vec<f64> = (0..p).map(|k| (k as f64 * 0.37).sin()).collect();
        let mut got = vec![0.0; p];
        kept.transpose_along(&v, |i, along| 1e-3 * i as f64 + along, &mut got);
        let mut expected = vec![0.0; p];
        for (i, row) in j.chunks_exact(p).enumerate() {
            let along: f64 = row.iter().zip(&v).map(|(a, b)| a * b).sum();
            for (x, &a) in expected.iter_mut().zip(row) {
                *x += (1e-3 * i as f64 + along) * a;
            }
        }
        let scale = expected.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (a, b) in got.iter().zip(&expected) {
            assert!((a - b).abs() <= 1e-5 * scale, "{a} vs {b} (of {scale})");
        }
    }

    /// A thinned data set keeps every k-th point of each kind, with its weight and goal.
    #[test]
    fn thinned_data_keeps_every_kth_point() {
        let (mut data, params) = random_problem(3, 9, 10, 12);
        for k in 0..7 {
            let goal = ValueGoal {
                value: 0.1 * f64::from(k),
                weight: 1.0,
                hinge: 0.0,
            };
            data.push_value(&[f64::from(k), 0.0, 0.0], goal);
        }
        let thin = data.thinned(4);
        assert_eq!((thin.len(), thin.value_len()), (3, 2));
        for (t, i) in [0, 4, 8].into_iter().enumerate() {
            assert_eq!(thin.input(t).values, data.input(i).values);
            assert_eq!(thin.input(t).tangents, data.input(i).tangents);
            assert_eq!(
                (thin.targets[t], thin.weights[t]),
                (data.targets[i], data.weights[i])
            );
        }
        assert_eq!(thin.goals, [data.goals[0], data.goals[4]]);
        assert_eq!(thin.point_values, [0.0, 0.0, 0.0, 4.0, 0.0, 0.0]);
        // Its residuals are the kept points' residuals of the whole set.
        let problem = ModuleProblem::new(&data, 9, 0.05);
        let mut whole = vec![0.0; problem.residual_count()];
        problem.residuals(&params, &mut whole);
        let thin_problem = ModuleProblem::new(&thin, 9, 0.05);
        let mut part = vec![0.0; thin_problem.residual_count()];
        thin_problem.residuals(&params, &mut part);
        assert_eq!(part[4..8], whole[16..20]);
        assert_eq!(part[12], whole[40]);
        assert_eq!(part[13], whole[44]);
    }

    #[test]
    fn lanes_match_the_per_point_sweeps() {
        for (d, n, points, seed) in [(3, 9, 13, 1), (3, 1, 4, 2), (3, 16, 9, 3), (18, 9, 7, 4)] {
            let (data, params) = random_problem(d, n, points, seed);
            for fma in [false, cpu_has_fma()] {
                let mut problem = ModuleProblem::new(&data, n, 0.37);
                problem.fma = fma;
                check_against_per_point(&problem, &params);
            }
        }
    }

    fn check_against_per_point(problem: &ModuleProblem<'_>, params: &[f64]) {
        let (data, layout) = (problem.data, problem.layout);
        let (p, points, what) = (
            layout.len,
            data.len(),
            format!("{layout:?} {}", problem.fma),
        );
        let mut expected_e = vec![0.0; 4 * points];
        let mut expected_j = vec![0.0; 4 * points * p];
        for i in 0..points {
            let tape = forward(&layout, params, &data.input(i));
            problem.point_residuals(i, tape.value, tape.gradient, &mut expected_e[4 * i..]);
            let rows = &mut expected_j[4 * i * p..4 * (i + 1) * p];
            jacobian_rows(&layout, params, &data.input(i), &tape, problem.gamma, rows);
            rows.iter_mut().for_each(|j| *j *= data.weights[i]);
        }
        let all_close = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(a, b)| close(*a, *b));
        let mut e = vec![0.0; 4 * points];
        problem.residuals(params, &mut e);
        assert!(all_close(&e, &expected_e), "{what}");
        let mut j = vec![0.0; 4 * points * p];
        e.fill(0.0);
        problem.jacobian(params, &mut e, &mut j);
        assert!(all_close(&e, &expected_e), "{what}");
        assert!(all_close(&j, &expected_j), "{what}");

        let mut normal = NormalEquations::new(p);
        e.fill(0.0);
        problem.normal_equations(params, &mut e, &mut normal);
        normal.finish();
        assert!(all_close(&e, &expected_e), "{what}");
        let mut reference = NormalEquations::new(p);
        reference.add_jacobian(&expected_j, &expected_e);
        reference.finish();
        for r in 0..p {
            assert!(close(normal.gradient(r), reference.gradient(r)), "{what}");
            for c in r..p {
                assert!(
                    close(normal.gram(r, c), reference.gram(r, c)),
                    "{what} {r} {c}"
                );
            }
        }
    }
}
