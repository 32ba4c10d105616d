//! The measured FRFs as the fit sees them: the band's lines and a weight per line, channel and
//! reference.
//!
//! **Weights.** The residual of line l, sensor c, reference r is divided by
//!
//!   σ_lcr = max(e_lcr, ε · RMS_r),   e_lcr = (mean |D_l'cr|² over lines with |ln f_l' − ln f_l| ≤ h)^½,
//!
//! the curve's local level (its envelope over ±h in ln f, h = [`ENVELOPE_HALF_WIDTH`]) with a
//! floor ε = 10^(−dynamic range/20) of the reference's RMS over every curve and line. The H1
//! estimate's random error is proportional to |H| [Bendat & Piersol 2010, §9.2.4], so a
//! relative misfit is the data's own; the envelope rather than |D_l| itself keeps an
//! antiresonance (where |D| nearly vanishes and the noise is all there is) from getting a
//! weight it does not deserve, and each resonance, strong or weak, weighs by its own level,
//! so the largest peak does not dominate. The floor leaves curves that hold mostly noise (an
//! in-plane axis of a bending test) with the weight their level earns.

use crate::error::{FitError, inconsistent};
use lamdyn_frf::FrfSet;
use num_complex::Complex64;
use std::f64::consts::PI;

/// Half-width h of the envelope window in ln f (±10 %): about the half-power bandwidth of a
/// mode with 5 % damping, so a damped peak is normalised by its own level.
pub const ENVELOPE_HALF_WIDTH: f64 = 0.1;

/// The band's data, line by line.
#[derive(Debug, Clone)]
pub struct BandData {
    /// Frequencies, Hz.
    pub freqs_hz: Vec<f64>,
    /// Angular frequencies, rad/s.
    pub omegas: Vec<f64>,
    /// The measured FRF, indexed `[line][reference][sensor]`.
    pub values: Vec<Vec<Vec<Complex64>>>,
    /// 1/σ, indexed `[line][reference][sensor]` (module docs).
    pub weights: Vec<Vec<Vec<f64>>>,
    /// Sensors.
    pub n_sensors: usize,
    /// References.
    pub n_references: usize,
}

impl BandData {
    /// The lines of `set` within `band_hz` (inclusive), with the module's weights for a
    /// dynamic range of `dynamic_range_db`.
    ///
    /// # Errors
    /// [`FitError::Inconsistent`] for a band outside the data, fewer than `min_lines` lines in
    /// it, or a non-finite value there (naming the channel and the line).
    pub fn from_set(
        set: &FrfSet,
        band_hz: [f64; 2],
        dynamic_range_db: f64,
        min_lines: usize,
    ) -> Result<Self, FitError> {
        let lines: Vec<usize> = (0..set.n_lines())
            .filter(|&l| {
                let f = set.freqs_hz()[l];
                f > 0.0 && f >= band_hz[0] && f <= band_hz[1]
            })
            .collect();
        if lines.len() < min_lines {
            return Err(inconsistent(
                "FRF fit",
                format!(
                    "{} line(s) in {:.3}–{:.3} Hz, fewer than the {min_lines} the fit's parameters \
                     need",
                    lines.len(),
                    band_hz[0],
                    band_hz[1]
                ),
            ));
        }
        let (n_c, n_r) = (set.responses().len(), set.references().len());
        let mut values = vec![vec![vec![Complex64::new(0.0, 0.0); n_c]; n_r]; lines.len()];
        for r in 0..n_r {
            for c in 0..n_c {
                let curve = set.curve(c, r);
                for (k, &l) in lines.iter().enumerate() {
                    let v = curve[l];
                    if !(v.re.is_finite() && v.im.is_finite()) {
                        return Err(inconsistent(
                            "FRF fit",
                            format!(
                                "FRF {} / {} is not finite at {} Hz",
                                set.responses()[c].name,
                                set.references()[r].name,
                                set.freqs_hz()[l]
                            ),
                        ));
                    }
                    values[k][r][c] = v;
                }
            }
        }
        let freqs_hz: Vec<f64> = lines.iter().map(|&l| set.freqs_hz()[l]).collect();
        let weights = weights(&freqs_hz, &values, n_c, n_r, dynamic_range_db)?;
        Ok(Self {
            omegas: freqs_hz.iter().map(|f| 2.0 * PI * f).collect(),
            freqs_hz,
            values,
            weights,
            n_sensors: n_c,
            n_references: n_r,
        })
    }

    /// Number of lines.
    pub fn n_lines(&self) -> usize {
        self.freqs_hz.len()
    }

    /// Number of residuals (real and imaginary parts of every line, reference and sensor).
    pub fn n_residuals(&self) -> usize {
        2 * self.n_lines() * self.n_references * self.n_sensors
    }
}

/// 1/σ (module docs).
fn weights(
    freqs_hz: &[f64],
    values: &[Vec<Vec<Complex64>>],
    n_c: usize,
    n_r: usize,
    dynamic_range_db: f64,
) -> Result<Vec<Vec<Vec<f64>>>, FitError> {
    let n_l = freqs_hz.len();
    let ln_f: Vec<f64> = freqs_hz.iter().map(|f| f.ln()).collect();
    let mut out = vec![vec![vec![0.0; n_c]; n_r]; n_l];
    for r in 0..n_r {
        let total: f64 = (0..n_l)
            .flat_map(|l| values[l][r].iter().map(|v| v.norm_sqr()))
            .sum::<f64>()
            / (n_l * n_c) as f64;
        if total.is_nan() || total <= 0.0 {
            return Err(inconsistent(
                "FRF fit",
                format!("every FRF of reference {} is zero in the band", r + 1),
            ));
        }
        let floor = total.sqrt() * 10f64.powf(-dynamic_range_db / 20.0);
        for c in 0..n_c {
            // Sliding window over ln f: [lo, hi) indices of the lines within ±h.
            let (mut lo, mut hi, mut sum) = (0, 0, 0.0);
            for l in 0..n_l {
                while hi < n_l && ln_f[hi] <= ln_f[l] + ENVELOPE_HALF_WIDTH {
                    sum += values[hi][r][c].norm_sqr();
                    hi += 1;
                }
                while ln_f[lo] < ln_f[l] - ENVELOPE_HALF_WIDTH {
                    sum -= values[lo][r][c].norm_sqr();
                    lo += 1;
                }
                let envelope = (sum.max(0.0) / (hi - lo) as f64).sqrt();
                out[l][r][c] = 1.0 / envelope.max(floor);
            }
        }
    }
    Ok(out)
}
