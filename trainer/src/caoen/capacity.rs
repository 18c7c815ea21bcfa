//! What the core holds of a Cao En network, checked before anything is fitted.

use neurosurf_core::caoen::DEFAULT_KEY_POINTS;

use crate::error::{Error, Result};

/// Refuses more key points than the core (and the firmware) hold, before a fit spends its
/// time on them. `what` names where the count comes from (an option, or a file).
///
/// # Errors
/// [`Error::InvalidInput`] naming the count, the limit and `what` to change.
pub fn check_key_count(keys: usize, what: &str) -> Result<()> {
    if keys > DEFAULT_KEY_POINTS {
        return Err(Error::invalid(format!(
            "{what}: {keys} key points, but the core holds at most {DEFAULT_KEY_POINTS}; give \
             {DEFAULT_KEY_POINTS} or fewer"
        )));
    }
    Ok(())
}
