//! The core laws the FRF fit identifies, on unconstrained parameters u so that every u is a
//! causal, passive law.
//!
//! - **Generalized Maxwell** (Prony series) G* = G_e + Σ_k g_k iωτ_k/(1 + iωτ_k) [Ferry 1980,
//!   ch. 3] with fixed relaxation times and u = (ln G_e, ln g_1, …): non-negative weights.
//! - **Fractional Zener** G* = G_0 + ΔG y/(1 + y), y = (iωτ)^α [Bagley & Torvik 1983] with
//!   u = (ln G_0, ln ΔG, ln τ, logit α): G_∞ = G_0 + ΔG > G_0 > 0, 0 < α < 1.

use num_complex::Complex64;
use std::f64::consts::PI;

/// A law and how it is parametrised.
#[derive(Debug, Clone, PartialEq)]
pub enum FrfLaw {
    /// Generalized Maxwell with these relaxation times, s.
    GeneralizedMaxwell {
        /// τ_k, s.
        taus: Vec<f64>,
    },
    /// Fractional Zener.
    FractionalZener,
}

/// Relaxation times per decade of the [`FrfLaw::generalized_maxwell_over`] grid: 1.5 keeps the
/// terms' loss peaks (each about 1.1 decades wide at half height) overlapping, so the series
/// follows a smooth η(f) without ripples between the terms.
pub const PRONY_TERMS_PER_DECADE: f64 = 1.5;

impl FrfLaw {
    /// A generalized Maxwell law whose relaxation frequencies 1/(2πτ_k) span a decade below
    /// `f_lo_hz` to a decade above `f_hi_hz`, [`PRONY_TERMS_PER_DECADE`] per decade (at least
    /// three): a term below the band acts as a spring, one above it as a loss growing with f,
    /// so the band's ends can follow any slope.
    pub fn generalized_maxwell_over(f_lo_hz: f64, f_hi_hz: f64) -> Self {
        let (lo, hi) = ((f_lo_hz / 10.0).ln(), (f_hi_hz * 10.0).ln());
        let decades = (hi - lo) / 10f64.ln();
        let n = ((decades * PRONY_TERMS_PER_DECADE).ceil() as usize + 1).max(3);
        let taus = (0..n)
            .map(|k| {
                let lf = lo + (hi - lo) * k as f64 / (n - 1) as f64;
                1.0 / (2.0 * PI * lf.exp())
            })
            .collect();
        Self::GeneralizedMaxwell { taus }
    }

    /// The same family on relaxation times moved by half a step of its grid (a generalized
    /// Maxwell law; `None` for the fractional Zener law, which has no grid): its fit beside this
    /// one shows what the grid's placement alone changes in the law ([`super::FrfFit::at`]).
    pub fn shifted_half_step(&self) -> Option<Self> {
        match self {
            Self::GeneralizedMaxwell { taus } if taus.len() > 1 => {
                let half = (taus[1] / taus[0]).sqrt();
                Some(Self::GeneralizedMaxwell {
                    taus: taus.iter().map(|t| t * half).collect(),
                })
            }
            _ => None,
        }
    }

    /// The step of the relaxation grid in ln f (`None` for a law without a grid).
    pub fn grid_step_ln(&self) -> Option<f64> {
        match self {
            Self::GeneralizedMaxwell { taus } if taus.len() > 1 => {
                Some((taus[1] / taus[0]).ln().abs())
            }
            _ => None,
        }
    }

    /// The law's name as in job files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::GeneralizedMaxwell { .. } => "generalized_maxwell",
            Self::FractionalZener => "fractional_zener",
        }
    }

    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        match self {
            Self::GeneralizedMaxwell { taus } => 1 + taus.len(),
            Self::FractionalZener => 4,
        }
    }

    /// Parameter names with units (natural parameters of [`Self::natural`]).
    pub fn names(&self) -> Vec<String> {
        match self {
            Self::GeneralizedMaxwell { taus } => std::iter::once("g_e_pa".to_string())
                .chain(taus.iter().map(|t| format!("g_pa(tau={t:.3e} s)")))
                .collect(),
            Self::FractionalZener => ["g0_pa", "g_inf_pa", "tau_s", "alpha"]
                .map(String::from)
                .to_vec(),
        }
    }

    /// Natural parameters (Pa, s, –) from unconstrained ones.
    pub fn natural(&self, u: &[f64]) -> Vec<f64> {
        match self {
            Self::GeneralizedMaxwell { .. } => u.iter().map(|v| v.exp()).collect(),
            Self::FractionalZener => vec![
                u[0].exp(),
                u[0].exp() + u[1].exp(),
                u[2].exp(),
                logistic(u[3]),
            ],
        }
    }

    /// G*(ω), Pa, for unconstrained parameters `u` at ω (rad/s).
    pub fn modulus(&self, u: &[f64], omega: f64) -> Complex64 {
        let i = Complex64::new(0.0, 1.0);
        match self {
            Self::GeneralizedMaxwell { taus } => taus.iter().zip(&u[1..]).fold(
                Complex64::new(u[0].exp(), 0.0),
                |acc, (&tau, &lg)| {
                    let x = i * omega * tau;
                    acc + lg.exp() * x / (1.0 + x)
                },
            ),
            Self::FractionalZener => {
                let alpha = logistic(u[3]);
                let y = (i * omega * u[2].exp()).powf(alpha);
                u[0].exp() + u[1].exp() * y / (1.0 + y)
            }
        }
    }

    /// ∂G*/∂u_k at ω, k = 0 … p − 1 (analytic).
    pub fn gradient(&self, u: &[f64], omega: f64) -> Vec<Complex64> {
        let i = Complex64::new(0.0, 1.0);
        match self {
            Self::GeneralizedMaxwell { taus } => std::iter::once(Complex64::new(u[0].exp(), 0.0))
                .chain(taus.iter().zip(&u[1..]).map(|(&tau, &lg)| {
                    let x = i * omega * tau;
                    lg.exp() * x / (1.0 + x)
                }))
                .collect(),
            Self::FractionalZener => {
                let alpha = logistic(u[3]);
                let z = i * omega * u[2].exp();
                let y = z.powf(alpha);
                let dg = u[1].exp();
                // d/dy [y/(1 + y)] = 1/(1 + y)²; dy/d ln τ = α y; dy/d logit α = y ln z α(1 − α).
                let dy = dg / ((1.0 + y) * (1.0 + y));
                vec![
                    Complex64::new(u[0].exp(), 0.0),
                    dg * y / (1.0 + y),
                    dy * alpha * y,
                    dy * y * z.ln() * alpha * (1.0 - alpha),
                ]
            }
        }
    }

    /// Parameters whose law is near G*(ω) = `target(ω)` over `omegas` (least squares on ln G'
    /// and ln η): the start of an FRF fit from another route's law or from a constant modulus.
    pub fn closest_to(
        &self,
        omegas: &[f64],
        target: &(dyn Fn(f64) -> Complex64 + Sync),
    ) -> Vec<f64> {
        let first = target(omegas[0]);
        let u0 = match self {
            Self::GeneralizedMaxwell { taus } => {
                let g = first.re.max(1.0);
                std::iter::once((0.5 * g).ln())
                    .chain(taus.iter().map(|_| (g / taus.len() as f64).ln()))
                    .collect()
            }
            Self::FractionalZener => {
                let mid = omegas[omegas.len() / 2];
                vec![
                    (0.3 * first.re.max(1.0)).ln(),
                    (3.0 * first.re.max(1.0)).ln(),
                    (1.0 / mid).ln(),
                    0.0,
                ]
            }
        };
        let residuals = |u: &[f64]| {
            let mut r = Vec::with_capacity(2 * omegas.len() + u.len());
            for &w in omegas {
                let (g, t) = (self.modulus(u, w), target(w));
                if !(g.re > 0.0 && g.im > 0.0) {
                    return None;
                }
                r.push((g.re / t.re).ln());
                r.push((g.im / g.re / (t.im / t.re)).ln());
            }
            // A weak pull to the start keeps terms the curve does not see from drifting.
            r.extend(u.iter().zip(&u0).map(|(a, b)| 1e-3 * (a - b)));
            Some(r)
        };
        crate::lm::levenberg_marquardt(&residuals, &u0, crate::lm::LmSettings::default())
            .map_or(u0.clone(), |o| o.x)
    }
}

fn logistic(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The analytic gradients match central differences for both laws.
    #[test]
    fn gradients_match_differences() {
        let laws = [
            (FrfLaw::generalized_maxwell_over(20.0, 200.0), vec![]),
            (FrfLaw::FractionalZener, vec![14.0, 18.0, -7.0, 0.3]),
        ];
        for (law, u) in laws {
            let u = if u.is_empty() {
                (0..law.n_params()).map(|k| 14.0 + 0.3 * k as f64).collect()
            } else {
                u
            };
            let w = 2.0 * PI * 60.0;
            let g = law.gradient(&u, w);
            for k in 0..u.len() {
                let h = 1e-6;
                let (mut up, mut dn) = (u.clone(), u.clone());
                up[k] += h;
                dn[k] -= h;
                let fd = (law.modulus(&up, w) - law.modulus(&dn, w)) / (2.0 * h);
                assert!(
                    (fd - g[k]).norm() <= 1e-6 * fd.norm().max(1.0),
                    "{} {k}: {fd} vs {}",
                    law.name(),
                    g[k]
                );
            }
        }
    }

    /// A law fitted to another over a band reproduces it there (a fractional Zener core through
    /// a Prony series: within 2 % in G' and η over 20–200 Hz).
    #[test]
    fn closest_to_follows_a_curve() {
        let zener = FrfLaw::FractionalZener;
        let truth = [(3e6f64).ln(), (300e6f64).ln(), (1e-4f64).ln(), 0.2];
        let target = |w: f64| zener.modulus(&truth, w);
        let omegas: Vec<f64> = (0..30)
            .map(|k| 2.0 * PI * 20.0 * 10f64.powf(k as f64 / 29.0))
            .collect();
        let gm = FrfLaw::generalized_maxwell_over(20.0, 200.0);
        let u = gm.closest_to(&omegas, &target);
        for &w in &omegas {
            let (a, b) = (gm.modulus(&u, w), target(w));
            assert!((a.re / b.re - 1.0).abs() < 0.02, "G' {} vs {}", a.re, b.re);
            assert!(((a.im / a.re) / (b.im / b.re) - 1.0).abs() < 0.02);
        }
    }
}
