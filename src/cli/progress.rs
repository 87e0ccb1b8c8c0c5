//! The engines' progress on stderr: notes as lines, steps as an indicatif bar (hidden when
//! stderr is not a terminal).

use gdsky::engine::Progress;
use std::time::Duration;

/// A progress bar in the style of `gdsky demo`, with the engine's notes printed above it.
pub struct Bar(indicatif::ProgressBar);

impl Bar {
    /// A bar with no length yet (an engine's `start` gives it one).
    pub fn new() -> Self {
        let bar = indicatif::ProgressBar::new(0);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{spinner} [{bar:30}] {pos}/{len} {elapsed_precise} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        Bar(bar)
    }
}

impl Progress for Bar {
    fn note(&self, text: &str) {
        self.0.suspend(|| errln!("{text}"));
    }

    fn start(&self, steps: u64) {
        self.0.set_length(steps);
        self.0.set_position(0);
        self.0.enable_steady_tick(Duration::from_millis(200));
    }

    fn message(&self, text: &str) {
        self.0.set_message(text.to_string());
    }

    fn step(&self) {
        self.0.inc(1);
    }

    fn finish(&self) {
        self.0.finish_and_clear();
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}
