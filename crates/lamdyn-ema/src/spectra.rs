//! FRFs from impact-test time data: H1, H2, Hv and coherence, averaged over hits, with the
//! force and exponential windows of hammer testing.
//!
//! Per hit, the record starts `pretrigger` samples before the first sample whose |force|
//! reaches `trigger` × the hit's peak. The force is kept inside a force window of `force_window_s`
//! after that start (zero outside, a half-cosine taper over its last 10 %); force and responses
//! are multiplied by the exponential window w(t) = e^{−t/τ}, t from the record start. With
//! X = FFT(force), Y = FFT(response) summed over hits:
//!
//!   H1 = Σ Y X* / Σ |X|²,  H2 = Σ |Y|² / Σ X Y*,  Hv = √(H1 H2) (phase of H1),
//!   γ² = |Σ Y X*|² / (Σ|X|² Σ|Y|²) = H1/H2.
//!
//! **Window damping.** Multiplying a free decay by e^{−t/τ} adds 1/τ to every pole's decay
//! rate: identified poles satisfy Re λ_id = Re λ − 1/τ. [`correct_exponential_window`] adds
//! 1/τ back; for a mode of natural frequency ω_n the damping ratio drops by 1/(τ ω_n)
//! [Fladung & Rost 1997]. (Windowing the force too keeps input and output consistent, so the
//! correction is exact for the transfer function.)
//!
//! **Checks.** Hits are numbered from 1 in messages. A double hit: after the force first falls
//! below 10 % of the peak after the peak, it rises again
//! above `double_hit` × the peak. An overload: three or more consecutive samples at the record's
//! largest absolute value (a clipped converter), in force or response.

use crate::error::{EmaError, invalid};
use num_complex::Complex64;
use realfft::RealFftPlanner;
use serde::Serialize;

/// One hit: force and responses sampled at `rate_hz`, same length.
#[derive(Debug, Clone, PartialEq)]
pub struct Hit {
    /// Force, N.
    pub force: Vec<f64>,
    /// Responses (any unit), one vector per channel.
    pub responses: Vec<Vec<f64>>,
}

/// Settings of [`estimate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectraSettings {
    /// Sampling rate, Hz.
    pub rate_hz: f64,
    /// Trigger level as a fraction of the hit's peak force.
    pub trigger: f64,
    /// Samples kept before the trigger.
    pub pretrigger: usize,
    /// Record length after the start, samples (the FFT length); 0: the longest record every
    /// hit holds.
    pub length: usize,
    /// Force window length, s.
    pub force_window_s: f64,
    /// Exponential window time constant τ, s (`None`: no exponential window).
    pub exp_tau_s: Option<f64>,
    /// Second-hit threshold as a fraction of the peak force.
    pub double_hit: f64,
}

/// FRF estimates of one response channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimates {
    /// H1 per line.
    pub h1: Vec<Complex64>,
    /// H2 per line.
    pub h2: Vec<Complex64>,
    /// Hv per line.
    pub hv: Vec<Complex64>,
    /// Coherence per line.
    pub coherence: Vec<f64>,
}

/// The FRFs of all response channels and what was noticed in the hits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spectra {
    /// Frequencies, Hz (0 to Nyquist, `length`/2 + 1 lines).
    pub freqs_hz: Vec<f64>,
    /// Per response channel.
    pub channels: Vec<Estimates>,
    /// Warnings (double hits, overloads), naming the hit and channel.
    pub warnings: Vec<String>,
}

/// The warning for spectra averaged over one `what` (hit, segment): |S_yx|² = S_xx S_yy
/// there, whatever the noise.
pub(crate) fn one_average(what: &str) -> String {
    format!(
        "one {what} averaged: the coherence is 1 by definition and says nothing of the noise \
         (average several {what}s)"
    )
}

pub(crate) fn clipped(x: &[f64]) -> bool {
    let m = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if m == 0.0 {
        return false;
    }
    let mut run = 0;
    for v in x {
        run = if v.abs() == m { run + 1 } else { 0 };
        if run >= 3 {
            return true;
        }
    }
    false
}

/// Whether the force rises above `threshold` × its peak after first falling below 10 % of the
/// peak *after* the peak (module docs; a trigger sample on the rising flank below 10 % is not
/// a fall).
fn double_hit(f: &[f64], threshold: f64) -> bool {
    let (at, peak) =
        f.iter().enumerate().fold(
            (0, 0.0f64),
            |(i, m), (k, v)| if v.abs() > m { (k, v.abs()) } else { (i, m) },
        );
    let Some(fall) = f[at..].iter().position(|v| v.abs() < 0.1 * peak) else {
        return false;
    };
    f[at + fall..].iter().any(|v| v.abs() > threshold * peak)
}

/// A hit or record (`noun` number `k`, from 1) against the first one's `n_resp` responses:
/// the same channel count, every channel as long as the force, every sample finite.
pub(crate) fn check_shape(hit: &Hit, noun: &str, k: usize, n_resp: usize) -> Result<(), EmaError> {
    let n = hit.force.len();
    if hit.responses.len() != n_resp {
        return Err(invalid(
            "time data",
            format!(
                "{noun} {k} has {} response channels, {noun} 1 has {n_resp}",
                hit.responses.len()
            ),
        ));
    }
    if let Some(c) = hit.responses.iter().position(|r| r.len() != n) {
        return Err(invalid(
            "time data",
            format!(
                "{noun} {k}: response {c} has {} samples, the force {n}",
                hit.responses[c].len()
            ),
        ));
    }
    if hit
        .force
        .iter()
        .chain(hit.responses.iter().flatten())
        .any(|v| !v.is_finite())
    {
        return Err(invalid(
            "time data",
            format!("{noun} {k} holds a sample that is not finite"),
        ));
    }
    Ok(())
}

/// The first sample whose |force| reaches `trigger` × the peak.
fn trigger_index(force: &[f64], trigger: f64) -> usize {
    let peak = force.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    force
        .iter()
        .position(|v| v.abs() >= trigger * peak)
        .unwrap_or(0)
}

/// The record's first sample: `pretrigger` samples before the trigger (module docs).
fn record_start(force: &[f64], s: &SpectraSettings) -> usize {
    trigger_index(force, s.trigger).saturating_sub(s.pretrigger)
}

/// H1, H2, Hv and coherence from `hits` (module docs).
///
/// # Errors
/// [`EmaError::Invalid`] for no hit, channels of different lengths or counts, non-finite
/// samples, a zero force, a record longer than the data, or non-physical settings.
pub fn estimate(hits: &[Hit], s: &SpectraSettings) -> Result<Spectra, EmaError> {
    if hits.is_empty() {
        return Err(invalid("time data", "no hit".into()));
    }
    let length = match s.length {
        0 => hits
            .iter()
            .map(|h| h.force.len().saturating_sub(record_start(&h.force, s)))
            .min()
            .unwrap_or(0),
        n => n,
    };
    check_settings(s, length)?;
    let n_resp = hits[0].responses.len();
    let nl = length / 2 + 1;
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(length);
    let (mut sxx, mut syx, mut syy) = (
        vec![0.0; nl],
        vec![vec![Complex64::new(0.0, 0.0); nl]; n_resp],
        vec![vec![0.0; nl]; n_resp],
    );
    let mut warnings = Vec::new();
    let mut spectrum = fft.make_output_vec();
    for (h, hit) in hits.iter().enumerate() {
        let hn = h + 1;
        check_shape(hit, "hit", hn, n_resp)?;
        let n = hit.force.len();
        let peak = hit.force.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if peak == 0.0 {
            return Err(invalid("time data", format!("hit {hn}: the force is zero")));
        }
        let trig = trigger_index(&hit.force, s.trigger);
        let start = trig.saturating_sub(s.pretrigger);
        if start + length > n {
            return Err(invalid(
                "time data",
                format!(
                    "hit {hn}: {n} samples, but the record needs {} from sample {start}",
                    length
                ),
            ));
        }
        warnings.extend(hit_warnings(hit, hn, s.double_hit));
        let win: Vec<f64> = (0..length)
            .map(|k| {
                s.exp_tau_s
                    .map_or(1.0, |tau| (-(k as f64) / (s.rate_hz * tau)).exp())
            })
            .collect();
        let mut x = force_record(&hit.force[start..start + length], &win, s);
        fft.process(&mut x, &mut spectrum)
            .map_err(|e| invalid("FFT", e.to_string()))?;
        let xs = spectrum.clone();
        for k in 0..nl {
            sxx[k] += xs[k].norm_sqr();
        }
        for (c, r) in hit.responses.iter().enumerate() {
            let mut y: Vec<f64> = (0..length).map(|k| r[start + k] * win[k]).collect();
            fft.process(&mut y, &mut spectrum)
                .map_err(|e| invalid("FFT", e.to_string()))?;
            for k in 0..nl {
                syx[c][k] += spectrum[k] * xs[k].conj();
                syy[c][k] += spectrum[k].norm_sqr();
            }
        }
    }
    let freqs_hz = (0..nl)
        .map(|k| k as f64 * s.rate_hz / length as f64)
        .collect();
    if hits.len() == 1 {
        warnings.push(one_average("hit"));
    }
    Ok(from_sums(freqs_hz, &sxx, &syx, &syy, warnings))
}

/// Refuses non-physical settings for records of `length` samples.
fn check_settings(s: &SpectraSettings, length: usize) -> Result<(), EmaError> {
    if !(s.rate_hz.is_finite()
        && s.rate_hz > 0.0
        && length >= 4
        && s.force_window_s > 0.0
        && (0.0..1.0).contains(&s.trigger))
    {
        return Err(invalid(
            "settings",
            format!(
                "rate {} Hz, length {}, force window {} s, trigger {}: rate and window must be \
                 positive, length at least 4, trigger in [0, 1)",
                s.rate_hz, length, s.force_window_s, s.trigger
            ),
        ));
    }
    if let Some(t) = s.exp_tau_s {
        if !(t.is_finite() && t > 0.0) {
            return Err(invalid(
                "settings",
                format!("exponential window tau = {t} s must be positive"),
            ));
        }
    }
    Ok(())
}

/// A hit's double hit (the force above `double_hit` of its peak after the first impact) and
/// its clipped channels, one line each, the hit numbered `hn`.
fn hit_warnings(hit: &Hit, hn: usize, double_hit_level: f64) -> Vec<String> {
    let mut warnings = Vec::new();
    if double_hit(&hit.force, double_hit_level) {
        warnings.push(format!(
            "hit {hn}: double hit (the force rises above {:.0} % of its peak \
             after the first impact)",
            100.0 * double_hit_level
        ));
    }
    if clipped(&hit.force) {
        warnings.push(format!("hit {hn}: force overload (clipped samples)"));
    }
    for (c, r) in hit.responses.iter().enumerate() {
        if clipped(r) {
            warnings.push(format!("hit {hn}: response {c} overload (clipped samples)"));
        }
    }
    warnings
}

/// The force's record (`force`, from its start) under the force window (flat over
/// `s.force_window_s`, a cosine taper over its last tenth, zero after) and the exponential
/// window `win`.
fn force_record(force: &[f64], win: &[f64], s: &SpectraSettings) -> Vec<f64> {
    let fw = (s.force_window_s * s.rate_hz).round() as usize;
    let taper = (fw / 10).max(1);
    (0..force.len())
        .map(|k| {
            let w = if k >= fw {
                0.0
            } else if k + taper > fw {
                0.5 * (1.0 + (std::f64::consts::PI * (k + taper - fw) as f64 / taper as f64).cos())
            } else {
                1.0
            };
            force[k] * w * win[k]
        })
        .collect()
}

/// H1, H2, Hv and coherence of every response from the summed auto- and cross-spectra
/// Σ|X|², Σ Y X*, Σ|Y|² (module docs; the scaling of the sums cancels).
pub(crate) fn from_sums(
    freqs_hz: Vec<f64>,
    sxx: &[f64],
    syx: &[Vec<Complex64>],
    syy: &[Vec<f64>],
    warnings: Vec<String>,
) -> Spectra {
    let nl = sxx.len();
    let channels = (0..syx.len())
        .map(|c| {
            let h1: Vec<Complex64> = (0..nl)
                .map(|k| syx[c][k] / sxx[k].max(f64::MIN_POSITIVE))
                .collect();
            let h2: Vec<Complex64> = (0..nl).map(|k| syy[c][k] / syx[c][k].conj()).collect();
            let coherence: Vec<f64> = (0..nl)
                .map(|k| syx[c][k].norm_sqr() / (sxx[k] * syy[c][k]).max(f64::MIN_POSITIVE))
                .collect();
            let hv = h1
                .iter()
                .zip(&h2)
                .map(|(a, b)| Complex64::from_polar((a.norm() * b.norm()).sqrt(), a.arg()))
                .collect();
            Estimates {
                h1,
                h2,
                hv,
                coherence,
            }
        })
        .collect();
    Spectra {
        freqs_hz,
        channels,
        warnings,
    }
}

/// Removes the exponential window's damping from a pole: Re λ + 1/τ (module docs).
pub fn correct_exponential_window(pole: Complex64, tau_s: f64) -> Complex64 {
    Complex64::new(pole.re + 1.0 / tau_s, pole.im)
}
