//! Progress on stderr for long work: a spinner with the elapsed time and the current stage on a
//! terminal, plain lines elsewhere (a pipe, a log file, CI), so that no step of more than about
//! a second runs silently.
//!
//! Both forms may be updated from any thread (the Monte Carlo reports from rayon workers). They
//! never wait for a lock the main thread could hold while it waits for those workers: the
//! spinner draws through indicatif's own stderr handle, the plain lines through `eprintln!`,
//! each taking stderr's lock only for its own line, and the binary never locks stderr for
//! longer (see `main.rs`).
//!
//! A step that reports nothing for [`HEARTBEAT`] gets a line of its own ("still: ...") from a
//! small timer thread, so a pipe never stays silent while a long factorization runs.
//!
//! Plain lines are throttled: a new step is printed at once, updates that differ from the last
//! line only in their numbers (Lanczos convergence, Monte Carlo counts, the mode being
//! matched) at most every [`PLAIN_INTERVAL`]. `LAMDYN_PROGRESS=off`
//! silences both forms, `=lines` forces plain lines, `=spinner` forces the spinner.

use lamdyn_pipeline::Reporter;
use std::io::IsTerminal;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

/// Shortest time between two plain lines of the same step.
pub const PLAIN_INTERVAL: Duration = Duration::from_secs(2);

/// Silence after which the plain-line form repeats the current step.
pub const HEARTBEAT: Duration = Duration::from_secs(5);

/// How progress is shown.
enum Mode {
    /// An indicatif spinner (stderr is a terminal).
    Spinner(indicatif::ProgressBar),
    /// Plain lines on stderr, with the heartbeat thread.
    Lines(Arc<Lines>),
    /// Nothing.
    Off,
}

/// The plain-line form: what it printed, and the condition that wakes the heartbeat.
struct Lines {
    state: Mutex<LineState>,
    wake: Condvar,
}

/// What the plain-line form has printed.
struct LineState {
    start: Instant,
    last_print: Option<Instant>,
    last_step: String,
    last_message: String,
    finished: bool,
}

impl Lines {
    fn print(s: &mut LineState, now: Instant, message: &str) {
        eprintln!(
            "lamdyn: [{:7.1} s] {message}",
            now.duration_since(s.start).as_secs_f64()
        );
        s.last_print = Some(now);
    }

    /// Repeats the current step after [`HEARTBEAT`] of silence, until finished.
    fn heartbeat(self: Arc<Self>) {
        let Ok(mut s) = self.state.lock() else { return };
        while !s.finished {
            let wait = match s.last_print {
                Some(t) => HEARTBEAT.saturating_sub(t.elapsed()),
                None => HEARTBEAT,
            };
            if wait.is_zero() {
                if !s.last_message.is_empty() {
                    let m = format!("still: {}", s.last_message);
                    Self::print(&mut s, Instant::now(), &m);
                } else {
                    s.last_print = Some(Instant::now());
                }
                continue;
            }
            s = match self.wake.wait_timeout(s, wait) {
                Ok((s, _)) => s,
                Err(_) => return,
            };
        }
    }
}

/// Progress of a command on stderr (module docs).
pub struct Spinner(Mode);

impl Spinner {
    /// A spinner on a terminal, plain lines otherwise (`LAMDYN_PROGRESS` overrides).
    pub fn new() -> Self {
        let choice = std::env::var("LAMDYN_PROGRESS").unwrap_or_default();
        match choice.as_str() {
            "off" | "0" | "none" => Self(Mode::Off),
            "lines" => Self::lines(),
            "spinner" => Self::terminal(),
            _ if std::io::stderr().is_terminal() => Self::terminal(),
            _ => Self::lines(),
        }
    }

    fn terminal() -> Self {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.set_style(
            indicatif::ProgressStyle::with_template("{spinner} [{elapsed}] {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        );
        bar.enable_steady_tick(Duration::from_millis(120));
        Self(Mode::Spinner(bar))
    }

    fn lines() -> Self {
        let lines = Arc::new(Lines {
            state: Mutex::new(LineState {
                start: Instant::now(),
                last_print: None,
                last_step: String::new(),
                last_message: String::new(),
                finished: false,
            }),
            wake: Condvar::new(),
        });
        let beat = Arc::clone(&lines);
        // Without the thread the lines still work, only without the heartbeat.
        let _ = std::thread::Builder::new()
            .name("lamdyn-progress".into())
            .spawn(move || beat.heartbeat());
        Self(Mode::Lines(lines))
    }

    /// Shows `message`: at once on the spinner; as a line when it starts a new step or
    /// [`PLAIN_INTERVAL`] has passed since the last line.
    pub fn message(&self, message: &str) {
        match &self.0 {
            Mode::Spinner(bar) => bar.set_message(message.to_string()),
            Mode::Lines(lines) => {
                let Ok(mut s) = lines.state.lock() else {
                    return;
                };
                let step = step_of(message);
                let now = Instant::now();
                let due = s
                    .last_print
                    .is_none_or(|t| now.duration_since(t) >= PLAIN_INTERVAL);
                if step != s.last_step || due {
                    Lines::print(&mut s, now, message);
                    s.last_step = step;
                }
                s.last_message = message.to_string();
            }
            Mode::Off => {}
        }
    }

    /// Removes the spinner; stops the heartbeat.
    pub fn finish(&self) {
        match &self.0 {
            Mode::Spinner(bar) => bar.finish_and_clear(),
            Mode::Lines(lines) => {
                if let Ok(mut s) = lines.state.lock() {
                    s.finished = true;
                }
                lines.wake.notify_all();
            }
            Mode::Off => {}
        }
    }
}

/// The step a progress message belongs to: the message without its numbers ("Lanczos: 3/20
/// modes converged" and "Lanczos: 4/20 modes converged" are one step).
fn step_of(message: &str) -> String {
    message
        .chars()
        .filter(|c| !(c.is_ascii_digit() || *c == '.'))
        .collect()
}

impl Default for Spinner {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        self.finish();
    }
}

impl Reporter for Spinner {
    fn stage(&self, name: &str) {
        self.message(name);
    }
    fn converged(&self, converged: usize, wanted: usize) {
        self.message(&format!("Lanczos: {converged}/{wanted} modes converged"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_is_the_message_without_its_numbers() {
        assert_eq!(step_of("Lanczos: 3/20"), step_of("Lanczos: 14/20"));
        assert_ne!(
            step_of("stage 'virtual test': mesh"),
            step_of("stage 'virtual test': assembly")
        );
    }

    /// Updates from many threads at once neither block nor panic in any form.
    #[test]
    fn updates_from_worker_threads_return() {
        use rayon::prelude::*;
        for s in [Spinner::lines(), Spinner(Mode::Off)] {
            (0..200)
                .into_par_iter()
                .for_each(|k| s.message(&format!("stage 'x': {k}/200")));
            s.finish();
        }
    }
}
