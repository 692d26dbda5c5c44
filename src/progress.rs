//! Progress bars for long runs: drawn on stderr when it is a terminal, hidden otherwise (CI, pipes).

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// A bar of `len` steps labelled `what`, redrawn every 0.5 s; hidden when stderr is not a terminal.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template(
            "{msg:>24} [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})",
        )
        .expect("the template is valid")
        .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    // Redraw twice a second, so that the elapsed time moves while a long step (one optimized set,
    // one sampler at the largest N) runs.
    bar.enable_steady_tick(std::time::Duration::from_millis(500));
    bar
}
