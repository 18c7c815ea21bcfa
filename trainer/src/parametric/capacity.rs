//! What the core can hold, checked before embedding or fitting: the topology search may pick
//! any network up to `max_layers` layers of `max_neurons` neurons, so the largest of them
//! must load in the core.

use neurosurf_core::parametric::{DEFAULT_PARAMETERS, MAX_HIDDEN_LAYERS, MAX_NEURONS};

use crate::error::{Error, Result};

/// Words of the largest network the search may build: `layers` hidden layers of `neurons`.
pub fn largest_parameter_count(layers: usize, neurons: usize) -> usize {
    let neurons = u8::try_from(neurons).unwrap_or(u8::MAX);
    neurosurf_core::parametric::parameter_count(&vec![neurons; layers])
}

/// Checks that every network of at most `max_layers` hidden layers of at most `max_neurons`
/// neurons loads in the core ([`MAX_HIDDEN_LAYERS`], [`MAX_NEURONS`], [`DEFAULT_PARAMETERS`]).
///
/// # Errors
/// [`Error::InvalidInput`] naming the option, its value, the core's limit and the largest
/// value that fits.
pub fn check_capacity(max_layers: usize, max_neurons: usize) -> Result<()> {
    if !(1..=MAX_HIDDEN_LAYERS).contains(&max_layers) {
        return Err(Error::invalid(format!(
            "--max-layers {max_layers}: the core evaluates 1 to {MAX_HIDDEN_LAYERS} hidden layers"
        )));
    }
    if !(1..=MAX_NEURONS).contains(&max_neurons) {
        return Err(Error::invalid(format!(
            "--max-neurons {max_neurons}: the core evaluates 1 to {MAX_NEURONS} neurons per layer"
        )));
    }
    let count = largest_parameter_count(max_layers, max_neurons);
    if count <= DEFAULT_PARAMETERS {
        return Ok(());
    }
    let fits = |layers: usize, neurons: usize| {
        largest_parameter_count(layers, neurons) <= DEFAULT_PARAMETERS
    };
    let neurons = (1..max_neurons).rev().find(|&n| fits(max_layers, n));
    let layers = (1..max_layers).rev().find(|&l| fits(l, max_neurons));
    let mut ways = Vec::new();
    if let Some(n) = neurons {
        ways.push(format!(
            "--max-neurons {n} or fewer with --max-layers {max_layers}"
        ));
    }
    if let Some(l) = layers {
        ways.push(format!(
            "--max-layers {l} or fewer with --max-neurons {max_neurons}"
        ));
    }
    Err(Error::invalid(format!(
        "--max-layers {max_layers} with --max-neurons {max_neurons} allow networks of \
         {count} parameters; the core holds at most {DEFAULT_PARAMETERS}: use {}",
        ways.join(", or ")
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_fit_and_the_error_names_sizes_that_do() {
        check_capacity(2, 12).unwrap();
        let error = check_capacity(4, 32).unwrap_err().to_string();
        assert!(error.contains("3371") && error.contains("1280"), "{error}");
        let neurons = (1..32)
            .rev()
            .find(|&n| largest_parameter_count(4, n) <= 1280);
        let n = neurons.unwrap();
        assert!(
            error.contains(&format!("--max-neurons {n} or fewer")),
            "{error}"
        );
        check_capacity(4, n).unwrap();
        assert!(check_capacity(4, n + 1).is_err());
        assert!(
            check_capacity(0, 4)
                .unwrap_err()
                .to_string()
                .contains("--max-layers 0")
        );
        assert!(
            check_capacity(1, 33)
                .unwrap_err()
                .to_string()
                .contains("--max-neurons 33")
        );
    }
}
