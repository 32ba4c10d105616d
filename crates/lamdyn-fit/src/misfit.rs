//! Misfit between measured and computed FRFs.
//!
//! | kind | residual per line k (and channel i) |
//! |---|---|
//! | `rms` (paper eqs. 2, 10) | (rms_exp(ω_k) − rms_num(ω_k)) / max_k rms_exp |
//! | `log_rms` | ln rms_exp(ω_k) − ln rms_num(ω_k) |
//! | `complex` | (H_exp,i(ω_k) − H_num,i(ω_k)) / max(|H_exp,i(ω_k)|, 10⁻³‖H_exp,i‖), real and imaginary parts |
//!
//! rms is the RMS of the magnitudes over all responses for one reference (eq. 2 read as in
//! method-notes §1). The paper minimises the absolute difference of eq. 10; its square summed
//! over lines is what Levenberg–Marquardt minimises. `log_rms` weighs every line equally in
//! relative terms (peaks and valleys alike), which matches noise proportional to the signal and
//! gives calibrated intervals (docs/fit.md); `complex` also uses the phases, each value relative
//! to its own magnitude (floored at 10⁻³ of the channel's RMS so that anti-resonances do not
//! dominate). Lines are those in
//! `band_hz` minus `exclude_hz` (e.g. the supports' resonances, paper Fig. 2). Optional band
//! weights w multiply the squared residuals of their lines (each residual is scaled by √w);
//! lines in several weighted bands take the product.

use crate::error::{FitError, inconsistent};
use crate::synthesis::{ModalModel, RmsEvaluator};
use lamdyn_frf::FrfSet;
use num_complex::Complex64;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The residual definition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MisfitKind {
    /// Paper eqs. 2 and 10: RMS magnitudes, absolute difference.
    Rms,
    /// RMS magnitudes, log difference.
    LogRms,
    /// Complex FRFs per channel.
    Complex,
}

/// Which lines and how they are compared.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MisfitSpec {
    /// The residual definition.
    pub kind: MisfitKind,
    /// Band [f_lo, f_hi] in Hz (default: all lines above 0 Hz).
    #[serde(default)]
    pub band_hz: Option<[f64; 2]>,
    /// Bands to leave out, Hz.
    #[serde(default)]
    pub exclude_hz: Vec<[f64; 2]>,
    /// Index of the reference (excitation) compared.
    #[serde(default)]
    pub reference: usize,
    /// Weights of the squared residuals in frequency bands (default 1 everywhere).
    #[serde(default)]
    pub weights: Vec<BandWeight>,
}

/// A weight on the squared residuals of the lines in a band.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BandWeight {
    /// Band [f_lo, f_hi], Hz.
    pub band_hz: [f64; 2],
    /// Weight, positive (leave a band out with `exclude_hz` instead of a zero weight).
    pub weight: f64,
}

impl MisfitSpec {
    /// A spec of `kind` over all lines, first reference.
    pub fn new(kind: MisfitKind) -> Self {
        Self {
            kind,
            band_hz: None,
            exclude_hz: vec![],
            reference: 0,
            weights: vec![],
        }
    }

    /// Indices of the lines used.
    ///
    /// # Errors
    /// [`FitError::Inconsistent`] for a band that is empty, reversed or not finite.
    pub fn lines(&self, freqs_hz: &[f64]) -> Result<Vec<usize>, FitError> {
        let ctx = "misfit";
        let [lo, hi] = self.band_hz.unwrap_or([f64::MIN_POSITIVE, f64::INFINITY]);
        if lo.is_nan() || hi.is_nan() || hi <= lo {
            return Err(inconsistent(
                ctx,
                format!("band_hz = [{lo}, {hi}] must be increasing"),
            ));
        }
        for b in &self.exclude_hz {
            if !(b[0].is_finite() && b[1].is_finite() && b[1] > b[0]) {
                return Err(inconsistent(
                    ctx,
                    format!(
                        "exclude_hz band [{}, {}] must be increasing and finite",
                        b[0], b[1]
                    ),
                ));
            }
        }
        let lines: Vec<usize> = (0..freqs_hz.len())
            .filter(|&k| {
                let f = freqs_hz[k];
                f > 0.0
                    && f >= lo
                    && f <= hi
                    && !self.exclude_hz.iter().any(|b| f >= b[0] && f <= b[1])
            })
            .collect();
        if lines.is_empty() {
            return Err(inconsistent(
                ctx,
                format!("no frequency line lies in [{lo}, {hi}] Hz outside the excluded bands"),
            ));
        }
        Ok(lines)
    }

    /// √w for each of `lines` (the product of the weights of the bands holding the line).
    ///
    /// # Errors
    /// [`FitError::Inconsistent`] for a weight that is not positive and finite or a band that
    /// is not increasing.
    pub fn sqrt_weights(&self, freqs_hz: &[f64], lines: &[usize]) -> Result<Vec<f64>, FitError> {
        for (k, w) in self.weights.iter().enumerate() {
            let [lo, hi] = w.band_hz;
            if !(lo.is_finite() && hi.is_finite() && hi > lo) {
                return Err(inconsistent(
                    "misfit",
                    format!("weights[{k}].band_hz = [{lo}, {hi}] must be increasing and finite"),
                ));
            }
            if !(w.weight.is_finite() && w.weight > 0.0) {
                return Err(inconsistent(
                    "misfit",
                    format!(
                        "weights[{k}].weight = {} must be positive and finite (use exclude_hz to \
                         leave a band out)",
                        w.weight
                    ),
                ));
            }
        }
        Ok(lines
            .iter()
            .map(|&k| {
                let f = freqs_hz[k];
                self.weights
                    .iter()
                    .filter(|w| f >= w.band_hz[0] && f <= w.band_hz[1])
                    .map(|w| w.weight)
                    .product::<f64>()
                    .sqrt()
            })
            .collect())
    }
}

/// The misfit of one measured set against one modal model.
pub struct Objective<'a> {
    spec: MisfitSpec,
    model: &'a ModalModel,
    measured: &'a FrfSet,
    lines: Vec<usize>,
    evaluator: RmsEvaluator,
    rms_exp: Vec<f64>,
    scale: f64,
    channel_norm: Vec<f64>,
    sqrt_w: Vec<f64>,
}

impl<'a> Objective<'a> {
    /// Prepares the misfit.
    ///
    /// # Errors
    /// [`FitError::Inconsistent`] when the model's channels do not match the measured set's, the
    /// reference does not exist, or no line is left.
    pub fn new(
        model: &'a ModalModel,
        measured: &'a FrfSet,
        spec: MisfitSpec,
    ) -> Result<Self, FitError> {
        let (nr, nf) = model.shape();
        if measured.responses().len() != nr || measured.references().len() != nf {
            return Err(inconsistent(
                "misfit",
                format!(
                    "the model has {nr} responses x {nf} references, the measurement {} x {}",
                    measured.responses().len(),
                    measured.references().len()
                ),
            ));
        }
        if spec.reference >= nf {
            return Err(inconsistent(
                "misfit",
                format!(
                    "reference = {} but there are {nf} references",
                    spec.reference
                ),
            ));
        }
        let lines = spec.lines(measured.freqs_hz())?;
        let sqrt_w = spec.sqrt_weights(measured.freqs_hz(), &lines)?;
        let rms_exp = measured.rms(spec.reference);
        if let Some(&k) = lines.iter().find(|&&k| rms_exp[k] <= 0.0) {
            return Err(inconsistent(
                "misfit",
                format!(
                    "the measured RMS FRF is zero at {} Hz",
                    measured.freqs_hz()[k]
                ),
            ));
        }
        let scale = lines.iter().map(|&k| rms_exp[k]).fold(0.0, f64::max);
        let channel_norm = (0..nr)
            .map(|i| {
                let c = measured.curve(i, spec.reference);
                (lines.iter().map(|&k| c[k].norm_sqr()).sum::<f64>() / lines.len() as f64)
                    .sqrt()
                    .max(f64::MIN_POSITIVE)
            })
            .collect();
        Ok(Self {
            evaluator: model.rms_evaluator(spec.reference),
            spec,
            model,
            measured,
            lines,
            rms_exp,
            scale,
            channel_norm,
            sqrt_w,
        })
    }

    /// The same misfit against another model of the same channels (e.g.
    /// [`ModalModel::corrected`]).
    pub fn with_model<'b>(&self, model: &'b ModalModel) -> Objective<'b>
    where
        'a: 'b,
    {
        Objective {
            spec: self.spec.clone(),
            model,
            measured: self.measured,
            lines: self.lines.clone(),
            evaluator: model.rms_evaluator(self.spec.reference),
            rms_exp: self.rms_exp.clone(),
            scale: self.scale,
            channel_norm: self.channel_norm.clone(),
            sqrt_w: self.sqrt_w.clone(),
        }
    }

    /// The model.
    pub fn model(&self) -> &ModalModel {
        self.model
    }

    /// The lines used.
    pub fn lines(&self) -> &[usize] {
        &self.lines
    }

    /// Number of residuals.
    pub fn n_residuals(&self) -> usize {
        match self.spec.kind {
            MisfitKind::Complex => 2 * self.lines.len() * self.model.shape().0,
            _ => self.lines.len(),
        }
    }

    /// The measured RMS FRF on every line.
    pub fn measured_rms(&self) -> &[f64] {
        &self.rms_exp
    }

    /// The computed RMS FRF (measured quantity) on every line for the modulus law `modulus`.
    pub fn model_rms(&self, modulus: &(dyn Fn(f64) -> Complex64 + Sync)) -> Vec<f64> {
        let q = self.measured.quantity();
        let e_ref = self.model.e_ref_pa();
        self.measured
            .freqs_hz()
            .iter()
            .map(|f| {
                let w = 2.0 * PI * f;
                if w == 0.0 {
                    return 0.0;
                }
                self.evaluator.rms(w, modulus(w) / e_ref) * q.from_receptance(w).norm()
            })
            .collect()
    }

    /// Residuals for the modulus law `modulus` (Pa, of ω in rad/s).
    pub fn residuals(&self, modulus: &(dyn Fn(f64) -> Complex64 + Sync)) -> Vec<f64> {
        let q = self.measured.quantity();
        let e_ref = self.model.e_ref_pa();
        let freqs = self.measured.freqs_hz();
        match self.spec.kind {
            MisfitKind::Rms | MisfitKind::LogRms => self
                .lines
                .iter()
                .zip(&self.sqrt_w)
                .map(|(&k, sw)| {
                    let w = 2.0 * PI * freqs[k];
                    let num =
                        self.evaluator.rms(w, modulus(w) / e_ref) * q.from_receptance(w).norm();
                    sw * match self.spec.kind {
                        MisfitKind::Rms => (self.rms_exp[k] - num) / self.scale,
                        _ => self.rms_exp[k].ln() - num.max(f64::MIN_POSITIVE).ln(),
                    }
                })
                .collect(),
            MisfitKind::Complex => {
                let (nr, nf) = self.model.shape();
                let j = self.spec.reference;
                let per_line: Vec<Vec<f64>> = self
                    .lines
                    .par_iter()
                    .zip(&self.sqrt_w)
                    .map(|(&k, sw)| {
                        let w = 2.0 * PI * freqs[k];
                        let h = self.model.receptance(w, modulus(w) / e_ref);
                        let qf = q.from_receptance(w);
                        (0..nr)
                            .flat_map(|i| {
                                let exp = self.measured.curve(i, j)[k];
                                let d = sw * (exp - h[i * nf + j] * qf)
                                    / exp.norm().max(1e-3 * self.channel_norm[i]);
                                [d.re, d.im]
                            })
                            .collect()
                    })
                    .collect();
                per_line.concat()
            }
        }
    }
}
