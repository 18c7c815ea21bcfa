//! What the core can hold, checked before training: a model that trains for minutes and then
//! is refused by `mesh`, `render`, `eval` and the microcontroller is worse than an error now.

use neurosurf_core::implicit::{DEFAULT_MODULES, MODULE_PARAMETERS, ModuleKind, ModuleLayout};

use crate::error::{Error, Result};

/// Modules and parameters of a tree over `leaves` leaves (a binary tree: `leaves − 1` nodes)
/// at hidden width `width`.
pub fn model_size(leaves: usize, width: usize) -> (usize, usize) {
    let nodes = leaves.saturating_sub(1);
    let parameters = leaves * ModuleLayout::new(ModuleKind::Leaf, width).len
        + nodes * ModuleLayout::new(ModuleKind::Node, width).len;
    (leaves + nodes, parameters)
}

/// Whether a model of `leaves` leaves at `width` fits the core's default capacity
/// ([`DEFAULT_MODULES`] modules, [`MODULE_PARAMETERS`] parameters; the rest of the core's
/// parameter capacity is the sign guards').
pub fn fits(leaves: usize, width: usize) -> bool {
    let (modules, parameters) = model_size(leaves, width);
    modules <= DEFAULT_MODULES && parameters <= MODULE_PARAMETERS
}

/// Checks that a tree of `leaves` leaves at `width` fits the core.
///
/// # Errors
/// [`Error::InvalidInput`] naming the model's size, the core's limits, and the largest
/// `--features` at this width and the largest `--width` with these features that fit.
pub fn check_capacity(leaves: usize, width: usize) -> Result<()> {
    if fits(leaves, width) {
        return Ok(());
    }
    let (modules, parameters) = model_size(leaves, width);
    let most_features = (1..leaves).rev().find(|&k| fits(k, width)).unwrap_or(0);
    let widest = (1..width).rev().find(|&w| fits(leaves, w));
    let features = if most_features > 0 {
        format!("--features {most_features} or fewer")
    } else {
        "fewer features".to_string()
    };
    let width_hint = match widest {
        Some(w) => format!(", or --width {w} or less with {leaves} features"),
        None => String::new(),
    };
    Err(Error::invalid(format!(
        "{leaves} features at width {width} make {modules} modules and {parameters} \
         parameters; the core holds at most {DEFAULT_MODULES} modules and {MODULE_PARAMETERS} \
         parameters: use {features} at width {width}{width_hint}"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_size_counts_every_module() {
        let leaf = ModuleLayout::new(ModuleKind::Leaf, 9).len;
        let node = ModuleLayout::new(ModuleKind::Node, 9).len;
        assert_eq!(model_size(1, 9), (1, leaf));
        assert_eq!(model_size(16, 9), (31, 16 * leaf + 15 * node));
    }

    #[test]
    fn the_demo_body_fits_and_the_error_names_the_way_out() {
        // The demo's 17-feature body at the default width.
        assert!(check_capacity(17, 9).is_ok());
        let message = check_capacity(24, 9).unwrap_err().to_string();
        assert!(message.contains("--features"), "{message}");
        assert!(message.contains("--width"), "{message}");
        assert!(
            message.contains(&MODULE_PARAMETERS.to_string()),
            "{message}"
        );
        // The suggested way out fits, one more feature does not.
        let most = (1..24).rev().find(|&k| fits(k, 9)).unwrap();
        assert!(check_capacity(most, 9).is_ok());
        assert!(check_capacity(most + 1, 9).is_err());
        // More leaves than modules allowed: no width rescues it.
        let message = check_capacity(DEFAULT_MODULES, 1).unwrap_err().to_string();
        assert!(message.contains("modules"), "{message}");
    }
}
