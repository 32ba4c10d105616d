//! Progress on stderr: a spinner with the current stage, drawn only on a terminal (indicatif
//! hides it when stderr is redirected, so tests and pipes see nothing).

use lamdyn_fem::eigen::Progress;

/// A spinner that shows the elapsed time and the stage or Lanczos convergence.
pub struct Spinner(indicatif::ProgressBar);

impl Spinner {
    /// A spinner on stderr.
    pub fn new() -> Self {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.set_style(
            indicatif::ProgressStyle::with_template("{spinner} [{elapsed}] {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        );
        Self(bar)
    }

    /// Removes the spinner.
    pub fn finish(&self) {
        self.0.finish_and_clear();
    }
}

impl Default for Spinner {
    fn default() -> Self {
        Self::new()
    }
}

impl Progress for Spinner {
    fn stage(&self, name: &str) {
        self.0.set_message(name.to_string());
        self.0.tick();
    }
    fn converged(&self, converged: usize, wanted: usize) {
        self.0
            .set_message(format!("Lanczos: {converged}/{wanted} modes converged"));
        self.0.tick();
    }
}
