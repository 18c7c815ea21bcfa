//! Progress bars for training (hidden when stderr is not a terminal or output is JSON).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use neurosurf_trainer::implicit::Progress;

/// A spinner counting a training's finished modules; the message shows the latest module's
/// iteration and error.
pub fn training_bar(prefix: &str, quiet: bool) -> ProgressBar {
    let target = if quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(None, target);
    if let Ok(style) =
        ProgressStyle::with_template("{spinner} {prefix}: {pos} modules trained, {msg} [{elapsed}]")
    {
        bar.set_style(style);
    }
    bar.set_prefix(prefix.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

/// Updates `bar` from one training event.
pub fn update(bar: &ProgressBar, event: Progress) {
    match event {
        Progress::Started { module, points } => {
            bar.set_message(format!("module {module}: {points} points"));
        }
        Progress::Iteration {
            module,
            iteration,
            error,
        } => bar.set_message(format!(
            "module {module}: iteration {iteration}, E {error:.2e}"
        )),
        Progress::Finished { .. } => bar.inc(1),
    }
}

/// A bar counting finished pieces of work (image tiles, mesh blocks), hidden when `quiet`.
/// Its length is set by the first [`ProgressBar::set_length`] call from the work's callback.
pub fn work_bar(prefix: &str, unit: &str, quiet: bool) -> ProgressBar {
    let target = if quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(Some(0), target);
    let template = format!("{{prefix}} [{{bar:30}}] {{pos}}/{{len}} {unit} [{{elapsed}}]");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style);
    }
    bar.set_prefix(prefix.to_string());
    bar
}
