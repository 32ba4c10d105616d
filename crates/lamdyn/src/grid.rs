//! Frequency grids given on the command line (Hz).

use anyhow::{Result, bail};

/// The largest number of frequency lines a grid may have.
const MAX_LINES: usize = 1_000_000;

/// A list of frequencies in Hz, strictly increasing and positive.
pub fn build(list: Option<&[f64]>, min_hz: f64, max_hz: f64, step_hz: f64) -> Result<Vec<f64>> {
    if let Some(list) = list {
        for (i, f) in list.iter().enumerate() {
            if *f <= 0.0 {
                bail!("--freq-hz: frequency [{i}] = {f} must be positive");
            }
            if i > 0 && *f <= list[i - 1] {
                bail!(
                    "--freq-hz: frequencies must increase, got {} then {f}",
                    list[i - 1]
                );
            }
        }
        if list.is_empty() {
            bail!("--freq-hz: give at least one frequency");
        }
        return Ok(list.to_vec());
    }
    if min_hz <= 0.0 {
        bail!("--f-min-hz = {min_hz} must be positive (the inverses are undefined at 0 Hz)");
    }
    if max_hz < min_hz {
        bail!("--f-max-hz = {max_hz} must not be below --f-min-hz = {min_hz}");
    }
    if step_hz <= 0.0 {
        bail!("--f-step-hz = {step_hz} must be positive");
    }
    let count = ((max_hz - min_hz) / step_hz + 1e-9).floor() + 1.0;
    if count > MAX_LINES as f64 {
        bail!(
            "the grid {min_hz}..{max_hz} Hz by {step_hz} Hz has {count} lines; at most {MAX_LINES}"
        );
    }
    Ok((0..count as usize)
        .map(|i| min_hz + step_hz * i as f64)
        .collect())
}
