//! The laws the fit can identify, each with an unconstrained parametrization that keeps the
//! physics (positivity, t0 > μ, G∞ > G0, 0 < α < 1) for every parameter vector LM proposes.
//!
//! | law | natural parameters | unconstrained u |
//! |---|---|---|
//! | paper eq. 7 | E0, μ, t0, c | ln E0, ln μ, ln(t0 − μ), ln c |
//! | fractional Zener | G0, G∞, τ, α | ln G0, ln(G∞ − G0), ln τ, logit α |
//! | per-mode piecewise | E'_k, η_k at anchor frequencies f_k | ln E'_k, ln η_k |
//!
//! The per-mode law interpolates ln E' and ln η against ln f through the anchors with a
//! not-a-knot cubic spline ([`crate::spline`]), continued as the end tangents outside them: a
//! modulus free at each mode, with no law imposed. Linear interpolation is not enough: between
//! modes 38.7 and 58.2 Hz of the paper's plate its chord misses eq. 7's E' by 0.5 %, and a
//! constant beyond the last mode by 0.9 % two hertz later, which moves the FRF near a
//! resonance by ten percent or more. For fits, [`LawChoice::prepare`] builds the splines once
//! per parameter vector.

use crate::spline::Spline;
use lamdyn_material::law::{FractionalZener, PaperEq7Law, ViscoelasticLaw};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The law to identify.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LawChoice {
    /// Paper eq. 7.
    PaperEq7,
    /// Fractional-derivative Zener.
    FractionalZener,
    /// Free storage modulus and loss factor at each anchor frequency (Hz).
    PerMode {
        /// Anchor frequencies, Hz, increasing.
        anchors_hz: Vec<f64>,
    },
}

impl LawChoice {
    /// Parameter names with units.
    pub fn names(&self) -> Vec<String> {
        match self {
            Self::PaperEq7 => ["E0_pa", "mu_s", "t0_s", "c_pa_s"]
                .map(String::from)
                .to_vec(),
            Self::FractionalZener => ["g0_pa", "g_inf_pa", "tau_s", "alpha"]
                .map(String::from)
                .to_vec(),
            Self::PerMode { anchors_hz } => anchors_hz
                .iter()
                .flat_map(|f| {
                    [
                        format!("storage_pa@{f:.3}Hz"),
                        format!("loss_factor@{f:.3}Hz"),
                    ]
                })
                .collect(),
        }
    }

    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        match self {
            Self::PaperEq7 | Self::FractionalZener => 4,
            Self::PerMode { anchors_hz } => 2 * anchors_hz.len(),
        }
    }

    /// Natural parameters from unconstrained ones.
    pub fn natural(&self, u: &[f64]) -> Vec<f64> {
        match self {
            Self::PaperEq7 => {
                let mu = u[1].exp();
                vec![u[0].exp(), mu, mu + u[2].exp(), u[3].exp()]
            }
            Self::FractionalZener => {
                let g0 = u[0].exp();
                vec![g0, g0 + u[1].exp(), u[2].exp(), 1.0 / (1.0 + (-u[3]).exp())]
            }
            Self::PerMode { .. } => u.iter().map(|v| v.exp()).collect(),
        }
    }

    /// Unconstrained parameters from natural ones (which must satisfy the law's constraints).
    pub fn unconstrained(&self, n: &[f64]) -> Vec<f64> {
        match self {
            Self::PaperEq7 => vec![n[0].ln(), n[1].ln(), (n[2] - n[1]).ln(), n[3].ln()],
            Self::FractionalZener => vec![
                n[0].ln(),
                (n[1] - n[0]).ln(),
                n[2].ln(),
                (n[3] / (1.0 - n[3])).ln(),
            ],
            Self::PerMode { .. } => n.iter().map(|v| v.ln()).collect(),
        }
    }

    /// E*(ω) in Pa at ω (rad/s) for natural parameters `n`.
    pub fn modulus(&self, n: &[f64], omega_rad_s: f64) -> Complex64 {
        match self {
            Self::PaperEq7 => {
                let w = omega_rad_s;
                Complex64::new(n[0] * (-n[1] * w).exp(), 2.0 * n[3] * w * (-n[2] * w).exp())
            }
            Self::FractionalZener => {
                let x = omega_rad_s * n[2];
                if x <= 0.0 {
                    return Complex64::new(n[0], 0.0);
                }
                let s = Complex64::from_polar(x.powf(n[3]), n[3] * PI / 2.0);
                (n[0] + n[1] * s) / (1.0 + s)
            }
            Self::PerMode { .. } => self.prepare(n).modulus(omega_rad_s),
        }
    }

    /// The law with parameters `n`, ready for many evaluations (the per-mode splines built once).
    pub fn prepare(&self, n: &[f64]) -> PreparedLaw {
        match self {
            Self::PerMode { anchors_hz } => {
                let x: Vec<f64> = anchors_hz.iter().map(|f| f.ln()).collect();
                let storage: Vec<f64> = (0..anchors_hz.len()).map(|k| n[2 * k].ln()).collect();
                let loss: Vec<f64> = (0..anchors_hz.len()).map(|k| n[2 * k + 1].ln()).collect();
                PreparedLaw::PerMode {
                    ln_storage: Spline::new(&x, &storage),
                    ln_loss: Spline::new(&x, &loss),
                }
            }
            closed => PreparedLaw::Closed {
                law: closed.clone(),
                params: n.to_vec(),
            },
        }
    }

    /// The same law through the material crate (validated), for reports.
    pub fn as_law(&self, n: &[f64]) -> Option<Box<dyn ViscoelasticLaw>> {
        match self {
            Self::PaperEq7 => PaperEq7Law::new(n[0], n[1], n[2], n[3])
                .ok()
                .map(|l| Box::new(l) as Box<dyn ViscoelasticLaw>),
            Self::FractionalZener => FractionalZener::new(n[0], n[1], n[2], n[3])
                .ok()
                .map(|l| Box::new(l) as Box<dyn ViscoelasticLaw>),
            Self::PerMode { .. } => None,
        }
    }
}

/// A law with its parameters, for repeated evaluation ([`LawChoice::prepare`]).
#[derive(Debug, Clone)]
pub enum PreparedLaw {
    /// Eq. 7 or the fractional Zener, evaluated in closed form.
    Closed {
        /// The law.
        law: LawChoice,
        /// Its natural parameters.
        params: Vec<f64>,
    },
    /// The per-mode law's splines in ln f.
    PerMode {
        /// ln E' (Pa).
        ln_storage: Spline,
        /// ln η.
        ln_loss: Spline,
    },
}

impl PreparedLaw {
    /// E*(ω) in Pa at ω (rad/s).
    pub fn modulus(&self, omega_rad_s: f64) -> Complex64 {
        match self {
            Self::Closed { law, params } => law.modulus(params, omega_rad_s),
            Self::PerMode {
                ln_storage,
                ln_loss,
            } => {
                let x = (omega_rad_s / (2.0 * PI)).ln();
                let e = ln_storage.eval(x).exp();
                Complex64::new(e, e * ln_loss.eval(x).exp())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transforms_round_trip_and_match_the_material_laws() {
        let cases = [
            (
                LawChoice::PaperEq7,
                vec![67.45e9, 0.686e-3, 4.295e-3, 1.617e6],
            ),
            (LawChoice::FractionalZener, vec![60e9, 70e9, 1e-3, 0.4]),
            (
                LawChoice::PerMode {
                    anchors_hz: vec![16.0, 42.0],
                },
                vec![65e9, 3e-3, 63e9, 4e-3],
            ),
        ];
        for (law, n) in cases {
            let back = law.natural(&law.unconstrained(&n));
            for (a, b) in back.iter().zip(&n) {
                assert!((a / b - 1.0).abs() < 1e-14, "{law:?}");
            }
            if let Some(m) = law.as_law(&n) {
                for w in [10.0, 100.0, 500.0] {
                    let (a, b) = (law.modulus(&n, w), m.modulus(w));
                    assert!((a - b).norm() <= 1e-14 * b.norm(), "{law:?} at {w}");
                }
            }
        }
        let pm = LawChoice::PerMode {
            anchors_hz: vec![16.0, 42.0],
        };
        let n = [65e9, 3e-3, 63e9, 4e-3];
        let mid = pm.modulus(&n, 2.0 * PI * (16.0f64 * 42.0).sqrt());
        assert!(
            (mid.re / (65e9f64 * 63e9).sqrt() - 1.0).abs() < 1e-12,
            "geometric mean at the log midpoint"
        );
        // Two anchors: straight lines in ln f, continued outside.
        let below = pm.modulus(&n, 2.0 * PI * 16.0 * 16.0 / 42.0);
        assert!(
            (below.re / (65e9f64 * 65e9 / 63e9) - 1.0).abs() < 1e-12,
            "tangent line below the first anchor"
        );
    }
}
