//! FRFs from continuous excitation (random, burst random, periodic chirp, swept sine): Welch's
//! averaged spectra [Welch 1967; Bendat & Piersol 2010, §9.2] over segments of every record.
//!
//! Each record (a run: force and responses at one rate) is cut into segments of `segment`
//! samples starting every `segment − overlap` samples (the segments that fit whole; scipy's
//! `noverlap`); each segment has its mean removed (`detrend`, scipy's default `'constant'`) and is
//! multiplied by the window w; with X = FFT(w·x), Y = FFT(w·y) summed over every segment of every
//! record,
//!
//!   H1 = Σ Y X* / Σ|X|²,  H2 = Σ|Y|² / Σ X Y*,  Hv = √(H1 H2) (phase of H1),  γ² = H1/H2,
//!
//! the window's scaling cancelling in each ratio: H1 equals scipy's `csd(x, y) / welch(x)` with
//! the same window, `nperseg`, `noverlap` and detrend.
//!
//! **Windows.** Hann (random excitation: leakage of a non-periodic signal), flat-top (SRS's five
//! terms, for amplitudes of periodic signals), rectangular (periodic signals with a whole number
//! of periods in the segment, or a burst or a sweep that starts and ends inside it: no leakage
//! then, and the best resolution).
//!
//! **Checks.** Non-finite samples, channels of different lengths, a segment longer than a record,
//! and whole-record segments on records of different lengths are errors (naming the record).
//! Warnings: a clipped channel (three equal samples at the record's peak: an overloaded
//! converter); a force whose autospectrum falls 40 dB below its 90th percentile inside the band
//! (no energy there: H1 is noise; a shaker's force drops 20–30 dB at the structure's
//! resonances, which is not flagged); with the rectangular window, a response still ringing at the
//! segment's end (the RMS of its last 5 % above 10 % of the segment's: leakage).

use crate::error::{EmaError, invalid};
use crate::spectra::{Hit, Spectra, check_shape, clipped, from_sums};
use num_complex::Complex64;
use realfft::RealFftPlanner;
use std::f64::consts::PI;

/// The window applied to each segment (in job files `hann`, `flattop`, `rect`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Window {
    /// Periodic Hann, 0.5 − 0.5 cos(2πk/N) (scipy `'hann'`, `sym=False`).
    Hann,
    /// Periodic flat-top, five cosine terms (scipy `'flattop'`, `sym=False`).
    #[serde(rename = "flattop", alias = "flat_top")]
    FlatTop,
    /// No window.
    #[serde(rename = "rect", alias = "rectangular")]
    Rectangular,
}

impl Window {
    /// The window's N values.
    pub fn values(self, n: usize) -> Vec<f64> {
        let c = |k: usize, j: f64| (2.0 * PI * j * k as f64 / n as f64).cos();
        (0..n)
            .map(|k| match self {
                Self::Hann => 0.5 - 0.5 * c(k, 1.0),
                Self::FlatTop => {
                    0.215_578_95 - 0.416_631_58 * c(k, 1.0) + 0.277_263_158 * c(k, 2.0)
                        - 0.083_578_947 * c(k, 3.0)
                        + 0.006_947_368 * c(k, 4.0)
                }
                Self::Rectangular => 1.0,
            })
            .collect()
    }
}

/// Settings of [`welch`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WelchSettings {
    /// Sampling rate, Hz.
    pub rate_hz: f64,
    /// Segment length, samples (the FFT length); 0: each record whole (then every record must
    /// have the same length).
    pub segment: usize,
    /// Samples shared by consecutive segments (< `segment`).
    pub overlap: usize,
    /// The window.
    pub window: Window,
    /// Remove each segment's mean before the window.
    pub detrend: bool,
    /// Band where the force must carry energy, Hz (None: every line above 0 Hz).
    pub band_hz: Option<[f64; 2]>,
}

/// Start indices of the segments of a record of `n` samples.
fn starts(n: usize, segment: usize, overlap: usize) -> Vec<usize> {
    let step = segment - overlap;
    (0..)
        .map(|k| k * step)
        .take_while(|s| s + segment <= n)
        .collect()
}

fn check_records(records: &[Hit], s: &WelchSettings) -> Result<usize, EmaError> {
    if records.is_empty() {
        return Err(invalid("time data", "no record".into()));
    }
    if !(s.rate_hz.is_finite() && s.rate_hz > 0.0) {
        return Err(invalid(
            "settings",
            format!("rate {} Hz must be positive", s.rate_hz),
        ));
    }
    let n_resp = records[0].responses.len();
    for (r, rec) in records.iter().enumerate() {
        check_shape(rec, "record", r + 1, n_resp)?;
    }
    let first = records[0].force.len();
    let segment = if s.segment == 0 {
        if let Some(r) = records.iter().position(|x| x.force.len() != first) {
            return Err(invalid(
                "time data",
                format!(
                    "record {} holds {} samples, record 1 {first}: with each record whole as the \
                     segment their lines would differ; give a segment length",
                    r + 1,
                    records[r].force.len()
                ),
            ));
        }
        first
    } else {
        s.segment
    };
    if segment < 8 {
        return Err(invalid(
            "settings",
            format!("segment of {segment} samples: at least 8 needed"),
        ));
    }
    if s.overlap >= segment {
        return Err(invalid(
            "settings",
            format!(
                "overlap of {} samples must be shorter than the segment ({segment})",
                s.overlap
            ),
        ));
    }
    if let Some((r, rec)) = records
        .iter()
        .enumerate()
        .find(|(_, x)| x.force.len() < segment)
    {
        return Err(invalid(
            "time data",
            format!(
                "the segment ({segment} samples, {:.4} s) is longer than record {} ({} samples, \
                 {:.4} s)",
                segment as f64 / s.rate_hz,
                r + 1,
                rec.force.len(),
                rec.force.len() as f64 / s.rate_hz
            ),
        ));
    }
    Ok(segment)
}

/// Ranges (Hz) in the band where the force's autospectrum is 40 dB below its 90th percentile
/// there (module docs).
fn weak_force(sxx: &[f64], freqs: &[f64], band: [f64; 2]) -> Vec<[f64; 2]> {
    let idx = crate::band::positive_lines(freqs, band);
    if idx.is_empty() {
        return Vec::new();
    }
    let mut v: Vec<f64> = idx.iter().map(|&k| sxx[k]).collect();
    v.sort_by(f64::total_cmp);
    let level = 1e-4 * v[(9 * v.len()) / 10];
    let mut ranges: Vec<[f64; 2]> = Vec::new();
    let mut prev: Option<usize> = None;
    for &k in &idx {
        if sxx[k] < level {
            match (ranges.last_mut(), prev) {
                (Some(r), Some(p)) if p + 1 == k => r[1] = freqs[k],
                _ => ranges.push([freqs[k], freqs[k]]),
            }
            prev = Some(k);
        }
    }
    ranges
}

/// H1, H2, Hv and coherence of continuous excitation by Welch averaging (module docs).
///
/// # Errors
/// [`EmaError::Invalid`] naming the record: none given, channels of different counts or
/// lengths, non-finite samples, a segment longer than a record or shorter than 8 samples, an
/// overlap not shorter than the segment, whole-record segments on records of different
/// lengths, a force with no energy at all.
pub fn welch(records: &[Hit], s: &WelchSettings) -> Result<Spectra, EmaError> {
    let segment = check_records(records, s)?;
    let overlap = if s.segment == 0 { 0 } else { s.overlap };
    let n_resp = records[0].responses.len();
    let nl = segment / 2 + 1;
    let win = s.window.values(segment);
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(segment);
    let (mut sxx, mut syx, mut syy) = (
        vec![0.0; nl],
        vec![vec![Complex64::new(0.0, 0.0); nl]; n_resp],
        vec![vec![0.0; nl]; n_resp],
    );
    let mut warnings = Vec::new();
    let mut spectrum = fft.make_output_vec();
    let mut buf = vec![0.0; segment];
    let mut ringing = Vec::new();
    let spectrum_of = |x: &[f64], buf: &mut Vec<f64>, out: &mut Vec<Complex64>| {
        let mean = if s.detrend {
            x.iter().sum::<f64>() / x.len() as f64
        } else {
            0.0
        };
        for k in 0..segment {
            buf[k] = (x[k] - mean) * win[k];
        }
        fft.process(buf, out)
            .map_err(|e| invalid("FFT", e.to_string()))
    };
    for (r, rec) in records.iter().enumerate() {
        let rn = r + 1;
        warnings.extend(overloads(rec, rn));
        for start in starts(rec.force.len(), segment, overlap) {
            spectrum_of(&rec.force[start..start + segment], &mut buf, &mut spectrum)?;
            let xs = spectrum.clone();
            for k in 0..nl {
                sxx[k] += xs[k].norm_sqr();
            }
            for (c, y) in rec.responses.iter().enumerate() {
                let seg = &y[start..start + segment];
                if s.window == Window::Rectangular && tail_ratio(seg) > 0.1 {
                    ringing.push((rn, c));
                }
                spectrum_of(seg, &mut buf, &mut spectrum)?;
                for k in 0..nl {
                    syx[c][k] += spectrum[k] * xs[k].conj();
                    syy[c][k] += spectrum[k].norm_sqr();
                }
            }
        }
    }
    if sxx.iter().skip(1).all(|v| *v == 0.0) {
        return Err(invalid(
            "time data",
            "the force carries no energy (zero or constant in every record)".into(),
        ));
    }
    let averaged: usize = records
        .iter()
        .map(|rec| starts(rec.force.len(), segment, overlap).len())
        .sum();
    if averaged == 1 {
        warnings.push(crate::spectra::one_average("segment"));
    }
    let freqs_hz: Vec<f64> = (0..nl)
        .map(|k| k as f64 * s.rate_hz / segment as f64)
        .collect();
    let band = s.band_hz.unwrap_or([freqs_hz[1], freqs_hz[nl - 1]]);
    warnings.extend(weak_force_warning(&sxx, &freqs_hz, band));
    if !ringing.is_empty() {
        warnings.push(format!(
            "leakage: with the rectangular window {} segment(s) end while the response still rings \
             (record {}, response {} first): use a Hann window, longer segments, or a burst that \
             stops earlier",
            ringing.len(),
            ringing[0].0,
            ringing[0].1
        ));
    }
    Ok(from_sums(freqs_hz, &sxx, &syx, &syy, warnings))
}

/// A record's clipped channels (numbered `rn`), one line each.
fn overloads(rec: &Hit, rn: usize) -> Vec<String> {
    let mut warnings = Vec::new();
    if clipped(&rec.force) {
        warnings.push(format!(
            "record {rn}: force overload (clipped samples at its peak)"
        ));
    }
    for (c, y) in rec.responses.iter().enumerate() {
        if clipped(y) {
            warnings.push(format!(
                "record {rn}: response {c} overload (clipped samples at its peak)"
            ));
        }
    }
    warnings
}

/// A warning naming the bands where the force's autospectrum `sxx` has no energy
/// ([`weak_force`]), if there are any in `band`.
fn weak_force_warning(sxx: &[f64], freqs_hz: &[f64], band: [f64; 2]) -> Option<String> {
    let weak = weak_force(sxx, freqs_hz, band);
    if weak.is_empty() {
        return None;
    }
    let list: Vec<String> = weak
        .iter()
        .take(6)
        .map(|r| format!("{:.1}-{:.1} Hz", r[0], r[1]))
        .collect();
    Some(format!(
        "the force has no energy (autospectrum 40 dB below its level in the band) at {}{}: H1 \
         there is noise; excite that band or leave it out",
        list.join(", "),
        if weak.len() > 6 { ", ..." } else { "" }
    ))
}

/// RMS of a segment's last 5 % over the whole segment's RMS (after its mean).
fn tail_ratio(x: &[f64]) -> f64 {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let rms =
        |v: &[f64]| (v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
    let tail = (x.len() / 20).max(1);
    let all = rms(x);
    if all == 0.0 {
        0.0
    } else {
        rms(&x[x.len() - tail..]) / all
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A single-dof system driven by white noise through its sampled impulse response h
    /// (returned: the discrete system's exact transfer is h's DTFT).
    fn sdof_records(n: usize, records: usize) -> (Vec<Hit>, f64, Vec<f64>) {
        let (rate, fn_hz, zeta): (f64, f64, f64) = (1024.0, 60.0, 0.02);
        let wn = 2.0 * PI * fn_hz;
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        let dt = 1.0 / rate;
        let h: Vec<f64> = (0..2048)
            .map(|k| {
                let t = k as f64 * dt;
                (-zeta * wn * t).exp() * (wd * t).sin() / wd * dt
            })
            .collect();
        let mut state = 7u64;
        let mut noise = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let hits = (0..records)
            .map(|_| {
                let f: Vec<f64> = (0..n + h.len()).map(|_| noise()).collect();
                let y: Vec<f64> = (h.len()..n + h.len())
                    .map(|k| (0..h.len()).map(|j| h[j] * f[k - j]).sum())
                    .collect();
                Hit {
                    force: f[h.len()..].to_vec(),
                    responses: vec![y],
                }
            })
            .collect();
        (hits, rate, h)
    }

    /// Σ h_k e^{−iωk/rate}: the discrete system's transfer at `f` Hz.
    fn dtft(h: &[f64], f: f64, rate: f64) -> Complex64 {
        h.iter()
            .enumerate()
            .map(|(k, v)| v * Complex64::from_polar(1.0, -2.0 * PI * f * k as f64 / rate))
            .sum()
    }

    #[test]
    fn windows_match_their_definitions() {
        let h = Window::Hann.values(8);
        assert!((h[0]).abs() < 1e-15 && (h[4] - 1.0).abs() < 1e-15);
        // Flat-top: peak 1 at the centre (the SRS coefficients sum to 1.000000001).
        let f = Window::FlatTop.values(64);
        assert!((f[32] - 1.0).abs() < 1e-8, "{}", f[32]);
        assert!(Window::Rectangular.values(5).iter().all(|v| *v == 1.0));
    }

    #[test]
    fn h1_of_a_noise_driven_oscillator_is_its_receptance() {
        let (recs, rate, h) = sdof_records(16384, 2);
        let s = WelchSettings {
            rate_hz: rate,
            segment: 1024,
            overlap: 512,
            window: Window::Hann,
            detrend: true,
            band_hz: None,
        };
        let sp = welch(&recs, &s).unwrap();
        // Away from the 60 Hz peak (there the 1 Hz lines of a Hann window smear a 2.4 Hz
        // half-power band by a few %), H1 is the system's transfer: no output noise, so only
        // the segments' leakage of the 2 s impulse response remains (under 3 %).
        for f in [20.0, 40.0, 100.0, 200.0] {
            let k = (f * 1024.0 / rate) as usize;
            let exact = dtft(&h, sp.freqs_hz[k], rate);
            let got = sp.channels[0].h1[k];
            assert!(
                (got / exact - 1.0).norm() < 0.03,
                "{f} Hz: {got} vs {exact}"
            );
            assert!(sp.channels[0].coherence[k] > 0.95);
        }
        assert!(sp.warnings.is_empty(), "{:?}", sp.warnings);
    }

    #[test]
    fn bad_records_are_refused_with_the_record_named() {
        let (mut recs, rate, _) = sdof_records(4096, 2);
        let s = WelchSettings {
            rate_hz: rate,
            segment: 0,
            overlap: 0,
            window: Window::Rectangular,
            detrend: true,
            band_hz: None,
        };
        let long = WelchSettings { segment: 8192, ..s };
        let e = welch(&recs, &long).unwrap_err().to_string();
        assert!(e.contains("longer than record 1"), "{e}");
        recs[1].force.truncate(4000);
        recs[1].responses[0].truncate(4000);
        let e = welch(&recs, &s).unwrap_err().to_string();
        assert!(e.contains("record 2 holds 4000 samples"), "{e}");
        recs[1].responses[0].truncate(3000);
        let e = welch(&recs, &s).unwrap_err().to_string();
        assert!(e.contains("record 2: response 0 has 3000"), "{e}");
    }

    #[test]
    fn clipping_and_ringing_are_warned() {
        let (mut recs, rate, _) = sdof_records(4096, 1);
        // Clip the response at 80 % of its peak.
        let peak = recs[0].responses[0]
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        for v in &mut recs[0].responses[0] {
            *v = v.clamp(-0.8 * peak, 0.8 * peak);
        }
        let s = WelchSettings {
            rate_hz: rate,
            segment: 512,
            overlap: 0,
            window: Window::Rectangular,
            detrend: true,
            band_hz: None,
        };
        let w = welch(&recs, &s).unwrap().warnings.join("\n");
        assert!(w.contains("response 0 overload"), "{w}");
        assert!(w.contains("leakage"), "{w}");
    }

    #[test]
    fn a_force_without_energy_in_part_of_the_band_is_warned() {
        let (mut recs, rate, _) = sdof_records(8192, 1);
        // A multisine over 10-150 Hz (0.5 Hz steps, phases from a fixed LCG) as the force.
        let mut phase = 1u64;
        let lines: Vec<(f64, f64)> = (20..=300)
            .map(|j| {
                phase = phase.wrapping_mul(6364136223846793005).wrapping_add(1);
                (
                    0.5 * j as f64,
                    (phase >> 11) as f64 / (1u64 << 53) as f64 * 2.0 * PI,
                )
            })
            .collect();
        for (k, v) in recs[0].force.iter_mut().enumerate() {
            let t = k as f64 / rate;
            *v = lines
                .iter()
                .map(|(f, p)| (2.0 * PI * f * t + p).sin())
                .sum();
        }
        let s = WelchSettings {
            rate_hz: rate,
            segment: 1024,
            overlap: 512,
            window: Window::Hann,
            detrend: true,
            band_hz: Some([10.0, 300.0]),
        };
        let w = welch(&recs, &s).unwrap().warnings.join("\n");
        assert!(w.contains("in the band) at 153.0-300.0 Hz"), "{w}");
        assert!(!w.contains("leakage"), "{w}");
    }
}
