//! The training schedule shared by the chain and the grid map: the paper's linearly
//! decreasing learning rate and a Gaussian neighbourhood whose radius shrinks geometrically.

/// Learning rate and neighbourhood radius as functions of the presentation counter t ∈ [0, T).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Schedule {
    /// T: presentations in total.
    pub total: usize,
    /// η₀.
    pub initial_rate: f64,
    /// σ₀ in neurons (distance along the chain or grid).
    pub initial_radius: f64,
    /// σ at t = T, in neurons.
    pub final_radius: f64,
}

impl Schedule {
    /// The paper's learning rate η(t) = η₀ (1 − t/T).
    pub(crate) fn rate(&self, t: usize) -> f64 {
        self.initial_rate * (1.0 - t as f64 / self.total as f64)
    }

    /// σ(t) = σ₀ (σ_T / σ₀)^{t/T}: from the initial to the final radius geometrically.
    pub(crate) fn radius(&self, t: usize) -> f64 {
        let x = t as f64 / self.total as f64;
        self.initial_radius * (self.final_radius / self.initial_radius).powf(x)
    }
}

/// Gaussian neighbourhood weights h(d) = exp(−d² / 2σ²) for d = 0..=⌈3σ⌉ (beyond 3σ the
/// weight is below 1.2 %, and is dropped), at most `limit + 1` entries.
pub(crate) fn gaussian_table(radius: f64, limit: usize, table: &mut Vec<f64>) {
    let reach = ((3.0 * radius).ceil() as usize).min(limit);
    let scale = -0.5 / (radius * radius);
    table.clear();
    table.extend((0..=reach).map(|d| ((d * d) as f64 * scale).exp()));
}

/// How many presentations share one neighbourhood table: the radius is recomputed this
/// often (at most ~1000 times per training run).
pub(crate) fn radius_block(total: usize) -> usize {
    (total / 1000).max(1)
}

/// Checks the settings every map schedule shares: `epochs` ≥ 1, the learning rate in (0, 1]
/// and every named value in `positive` finite and > 0; `what` names the map in the message
/// ("Kohonen option initial_rate must lie in (0, 1], got 1.5").
///
/// # Errors
/// [`crate::error::Error::InvalidInput`] naming the offending setting.
pub(crate) fn check_settings(
    what: &str,
    epochs: usize,
    initial_rate: f64,
    positive: &[(&str, f64)],
) -> crate::error::Result<()> {
    use crate::error::Error;
    if epochs == 0 {
        return Err(Error::invalid(format!(
            "{what} option epochs must be at least 1"
        )));
    }
    if !(initial_rate > 0.0 && initial_rate <= 1.0) {
        return Err(Error::invalid(format!(
            "{what} option initial_rate must lie in (0, 1], got {initial_rate}"
        )));
    }
    for &(name, value) in positive {
        if !(value.is_finite() && value > 0.0) {
            return Err(Error::invalid(format!(
                "{what} option {name} must be finite and positive, got {value}"
            )));
        }
    }
    Ok(())
}
