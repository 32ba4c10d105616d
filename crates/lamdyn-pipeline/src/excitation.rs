//! How the structure was excited ([`ExcitationKind`], as the job and `--excitation` name it)
//! and the FRF estimator's settings it implies ([`Excitation`]): hammer hits, or Welch
//! averaging of continuous excitation.

use crate::bail;
use crate::error::Result;

/// How the structure was excited, by name (`--excitation`, `measurement.excitation`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExcitationKind {
    /// Hammer hits: trigger, force window, exponential window.
    #[default]
    Impact,
    /// Random noise (Hann window, overlapping segments by default).
    Random,
    /// Burst random: each burst dies out inside its segment.
    Burst,
    /// Periodic chirp or multisine: whole periods in a segment.
    Periodic,
    /// Swept sine starting and ending inside the record.
    Sweep,
}

impl Excitation {
    /// The estimator settings of an excitation kind: Welch with `window` (default Hann for
    /// random noise, rectangular for the others), `segment_s` and `overlap` (default 0.5 with a
    /// tapered window, 0 with the rectangular one) over every record; impact takes none of
    /// them.
    ///
    /// # Errors
    /// Welch settings given for impact, an overlap outside [0, 1), a non-positive segment.
    pub fn new(
        kind: ExcitationKind,
        window: Option<lamdyn_ema::welch::Window>,
        segment_s: Option<f64>,
        overlap: Option<f64>,
        band_hz: Option<[f64; 2]>,
    ) -> Result<Self> {
        use lamdyn_ema::welch::Window;
        if kind == ExcitationKind::Impact {
            if window.is_some() || segment_s.is_some() || overlap.is_some() {
                bail!(
                    "window, segment and overlap are for continuous excitation (random, burst, \
                     periodic, sweep), not impact"
                );
            }
            return Ok(Self::Impact);
        }
        let window = window.unwrap_or(if kind == ExcitationKind::Random {
            Window::Hann
        } else {
            Window::Rectangular
        });
        let overlap = overlap.unwrap_or(if window == Window::Rectangular {
            0.0
        } else {
            0.5
        });
        if !(0.0..1.0).contains(&overlap) {
            bail!("overlap {overlap} must be a fraction of a segment in [0, 1)");
        }
        if let Some(s) = segment_s.filter(|s| !(s.is_finite() && *s > 0.0)) {
            bail!("segment {s} s must be a positive time");
        }
        Ok(Self::Continuous(ContinuousOptions {
            window,
            segment_s,
            overlap,
            band_hz,
        }))
    }
}

/// How the structure was excited.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Excitation {
    /// Hammer hits, one per file.
    Impact,
    /// Random, burst random, periodic chirp or swept sine: each file a record, Welch-averaged.
    Continuous(ContinuousOptions),
}

/// Welch settings in seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContinuousOptions {
    /// The window.
    pub window: lamdyn_ema::welch::Window,
    /// Segment length, s (None: each record whole with the rectangular window; else the power
    /// of two of samples nearest 1/8 of the shortest record).
    pub segment_s: Option<f64>,
    /// Overlap of consecutive segments, fraction of a segment in [0, 1).
    pub overlap: f64,
    /// Band where the force must carry energy, Hz.
    pub band_hz: Option<[f64; 2]>,
}
