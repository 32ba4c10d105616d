//! The core's law fitted to every mode at once, jointly with the inputs known only within a
//! tolerance (the faces' modulus, the thicknesses, the densities).
//!
//! Each mode k brings the core's G*_k found by an inverse with the nominal inputs (ln G'_k,
//! ln η_k), the signed sensitivities e_kj = ∂(ln G'_k, ln η_k)/∂ln θ_j of that result to each
//! input θ_j, and its own independent noise σ_k (the pole's scatter, the discretization), all
//! as relative quantities. With the inputs off nominal by δ_j = ln(θ_j/θ_j,nominal) the mode's
//! true core is, to first order,
//!
//! ln G'_true,k = ln G'_k + Σ_j e'_kj δ_j,   ln η_true,k = ln η_k + Σ_j e''_kj δ_j,
//!
//! and, where the point gives its inputs' second differences c_kj = ∂²(ln G'_k, ln η_k)/∂(ln θ_j)²
//! ([`ModePoint::second_order`]), to second order along the inputs' combined first-order shift
//! u_k = Σ_j e_kj δ_j (the sum over the inputs whose c_kj is given):
//!
//! ln x_true,k = ln x_k + Σ_j e_kj δ_j − u_k + g(u_k),  g(u) = (e^{κ_k u} − 1)/κ_k = u + ½ κ_k u² + …,
//!
//! with one curvature κ_k per mode and part fitted to the diagonal, c_kj ≈ κ_k e_kj²
//! ([`shared_curvature`]). The core found on a glass laminate is far from linear in the faces
//! (a 1 % face modulus can move a mode's G' by 11 % to first order and 4 % more to second), and
//! that nonlinearity runs along the shift the inputs make together, not input by input: on the
//! small test laminate c_kj/e_kj² is the same for the face modulus, thickness and density
//! within 10–20 % (η: 1.09–1.16 at its 103 Hz mode), and where the faces' thickness and density
//! cancel to first order their second orders cancel too. Summing the diagonal terms
//! ½ c_kj δ_j² instead (without the cross terms) put the points further from the truth than
//! the first order alone did, by up to 17 % in G' (chain coverage example, 5 seeds).
//!
//! The fit minimises over the law's parameters u and the shared δ
//!
//! S = Σ_k [(ln G'_law(f_k; u) − ln G'_k − Σ_j e'_kj δ_j)/σ'_k]² + [the same for η]
//!   + Σ_j (δ_j/s_j)²
//!
//! with the priors δ_j ~ N(0, s_j²) [Gelman et al. 2013, §14.8: a normal linear model with an
//! informative prior, here linearised in u]. One δ is shared by all modes: the law's
//! smoothness across modes then says something about the faces that no single mode can, and
//! the bands narrow where it does.
//!
//! **Scatter beyond the stated noise.** The points may scatter about the law by more than
//! their stated noise (an EMA or a model error nobody quantified): S_data/ν > 1, with ν =
//! 2K − P the data's degrees of freedom beyond the law's P parameters. That excess belongs to
//! the data, not to the priors, which are the user's statement about the inputs. So the data's
//! σ_k are scaled by a common s, s² = max(1, S_data(u(s))/ν) with S_data taken on the stated
//! σ_k and u(s) the minimum with the scaled ones, found by fixed-point iteration (a Birge ratio
//! estimated jointly with the fit; an empirical-Bayes estimate of the noise scale). Scaling
//! only the covariance afterwards, C = s²(JᵀJ)⁺, would leave the data rows their full weight
//! against the priors: under-stated noise then drags the inputs' δ (one shared shift of every
//! mode) to explain scatter that is not theirs, and the law moves with them (measured on the
//! pipeline's small plate: χ²/ν = 7.7, core thickness δ = +1.8 %, the law 1.3–2.0 % stiff
//! against points within ±1 %).
//!
//! Covariance C = (JᵀJ)⁺ of the scaled residuals at the minimum (Laplace approximation). 95 %
//! bands are ±z·sd on ln G' and ln η (log-normal, like the per-mode bands), z = 1.96 or
//! Student's t(ν) when s > 1. Each band's main source: the variance of a (linearised)
//! least-squares estimate splits exactly over the observations, var q = Σ_i (gᵀ(JᵀJ)⁺Jᵀ)_i²
//! for a quantity with gradient g; the prior rows belong to their input, a mode's data rows to
//! its noise sources in proportion to their share of s²σ_k², the rest, 1 − 1/s², to
//! "scatter about the law".
//!
//! **The pole's complex frequency.** A core found from a measured pole p holds at the complex
//! frequency ω*_k = −ip (`ModePoint::found_at_hz`), not at f_k: the free decay e^{pt} of a
//! mode feels G*(ω*), the law continued above the real axis
//! ([`ViscoelasticLaw::modulus_at_complex`]). With the pole's damping ratio ζ,
//! ln(ω*/ω_n) ≈ iζ, so the point's ln G* is off its real-axis value by about iζ d ln G*/d ln ω:
//! η by ζ (1 + η²)/η · d ln G'/d ln ω, 1–1.5 % on the demo roof (ζ 1.2–1.7 %, G' rising as
//! f^0.38), and G' by a few tenths of that. The fit therefore compares each point with the law
//! at ω*_k: the fractional Zener law exactly, the per-mode law (whose values are at the real
//! f_k) continued by the points' own log-slope S = d ln G*/d ln ω (a least-squares line of the
//! complex ln G*_k over ln f_k), ln G*(ω*_k) = ln G*(ω_k) + S ln(ω*_k/ω_k). The law, its bands
//! and [`CoreLawFit::real_frequency_points`] are on the real axis.

use crate::error::{FitError, inconsistent};
use crate::lm::{LmSettings, levenberg_marquardt};
use crate::master::{describe_direction, law_of, pseudo_inverse, t975};
use faer::Mat;
use lamdyn_material::law::ViscoelasticLaw;
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::PI;

const CONTEXT: &str = "core law fit";

/// The law fitted to the modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CoreLaw {
    /// Fractional Zener, G* = (G0 + G∞ (iωτ)^α)/(1 + (iωτ)^α): four parameters.
    FractionalZener,
    /// One free G' and η per mode (2K parameters), log-linear in frequency between the modes:
    /// the inputs stay at their priors, and each mode's band is its own.
    PerMode,
    /// Generalized Maxwell (Prony series), G* = G_e + Σ_k g_k iωτ_k/(1 + iωτ_k) [Ferry 1980,
    /// ch. 3]: causal and passive for any G_e, g_k > 0. The relaxation times are fixed
    /// ([`prony_relaxation_times`]: one per mode, 2 to 10, log-spaced from a decade below the
    /// first mode to a decade above the last) and G_e, g_k searched on their logarithms: 1 +
    /// n parameters. It follows a core whose loss factor is not the smooth arc of a fractional
    /// Zener law (a Prony series with one term per decade, as published PVB master curves
    /// are, puts bumps of several per cent in η that a fractional Zener law misses by 3–8 %).
    GeneralizedMaxwell,
}

/// The fixed relaxation times τ_k = 1/(2π f_k), s, of the [`CoreLaw::GeneralizedMaxwell`] fit
/// to modes at `log_freqs` (ln Hz, increasing): n = clamp(K, 2, 10) for K modes, f_k spaced
/// evenly in ln f from a decade below the first mode to a decade above the last. A term whose
/// relaxation frequency lies below the band acts as a spring (it joins G_e), one above it as a
/// loss growing with f, so the decade either side lets the series follow the slopes at the
/// band's ends; one term per mode keeps the law's parameters (n + 1) at most 2K − K + 1.
pub fn prony_relaxation_times(log_freqs: &[f64]) -> Vec<f64> {
    prony_relaxation_times_shifted(log_freqs, 0.0)
}

/// The relaxation times of [`prony_relaxation_times`] with every f_k moved up by `offset`
/// times their spacing in ln f (0 ≤ offset < 1: a whole spacing gives the same grid but at
/// its ends). Where the terms sit between the modes is a choice the modes do not make: on a
/// roof whose core is a Prony series with one term per decade, fits on grids a quarter of a
/// spacing apart differed by up to 1.2 % in G' and 2.1 % in η between the modes, each
/// matching the modes within their noise ([`CoreLawFit::with_alternatives`]).
pub fn prony_relaxation_times_shifted(log_freqs: &[f64], offset: f64) -> Vec<f64> {
    let n = prony_terms(log_freqs.len());
    let (first, last) = match (log_freqs.first(), log_freqs.last()) {
        (Some(&a), Some(&b)) => (a, b),
        _ => return Vec::new(),
    };
    let (lo, hi) = (first - 10f64.ln(), last + 10f64.ln());
    let step = (hi - lo) / (n - 1) as f64;
    (0..n)
        .map(|k| {
            let lf = lo + step * (k as f64 + offset);
            1.0 / (2.0 * PI * lf.exp())
        })
        .collect()
}

/// The modes' frequencies a law is fitted at (ln Hz, increasing) and, for the generalized
/// Maxwell law, where its relaxation times sit ([`prony_relaxation_times_shifted`]).
#[derive(Debug, Clone)]
struct ModeFrequencies {
    ln: Vec<f64>,
    prony_offset: f64,
}

impl ModeFrequencies {
    fn relaxation_times(&self) -> Vec<f64> {
        prony_relaxation_times_shifted(&self.ln, self.prony_offset)
    }
}

/// Terms of the [`CoreLaw::GeneralizedMaxwell`] fit to `modes` modes.
fn prony_terms(modes: usize) -> usize {
    modes.clamp(2, 10)
}

/// G* of a Prony series G_e = e^`u[0]`, g_k = e^`u[1 + k]` with relaxation times `taus`, at
/// the complex angular frequency ω (rad/s; the law continued above the real axis is the same
/// rational function).
fn prony_modulus(u: &[f64], taus: &[f64], omega: Complex64) -> Option<Complex64> {
    let i = Complex64::new(0.0, 1.0);
    let g = taus
        .iter()
        .zip(&u[1..])
        .fold(Complex64::new(u[0].exp(), 0.0), |acc, (&tau, &lg)| {
            let x = i * omega * tau;
            acc + lg.exp() * x / (1.0 + x)
        });
    g.is_finite().then_some(g)
}

impl CoreLaw {
    /// Number of parameters for `modes` modes.
    pub fn parameter_count(self, modes: usize) -> usize {
        match self {
            Self::FractionalZener => 4,
            Self::PerMode => 2 * modes,
            Self::GeneralizedMaxwell => 1 + prony_terms(modes),
        }
    }

    /// The law's name as in job files.
    pub fn name(self) -> &'static str {
        match self {
            Self::FractionalZener => "fractional_zener",
            Self::PerMode => "per_mode",
            Self::GeneralizedMaxwell => "generalized_maxwell",
        }
    }
}

/// An input known within a tolerance: its prior.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InputPrior {
    /// Its name ("face modulus", ...).
    pub name: String,
    /// Relative standard deviation s of the prior on ln θ (0.01: 1 %).
    pub rel_sd: f64,
    /// The change δ₀ = ln(θ₀/θ_nominal) at which the points and their effects were taken (0:
    /// nominal): the fit's δ is still the change from nominal, and a point moves by
    /// e_k (δ − δ₀). Set when the fit is re-linearised at the inputs a first fit found.
    pub at: f64,
}

/// One mode's core as found with the nominal inputs (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ModePoint {
    /// Frequency, Hz: where the law and the corrected point are reported.
    pub freq_hz: f64,
    /// The complex frequency ω*/2π at which `core_shear_pa` holds, Hz: −ip/2π for a core found
    /// from a pole p (imaginary part ζ f_n > 0), `freq_hz` for one found on the real axis.
    pub found_at_hz: Complex64,
    /// G* at `found_at_hz`, Pa (G' > 0, η > 0).
    pub core_shear_pa: Complex64,
    /// Per input (in the order of the priors): ∂ln G'/∂ln θ and ∂ln η/∂ln θ, signed.
    pub effects: Vec<[f64; 2]>,
    /// Per input (in the order of the priors), the second order: ∂²ln G'/∂(ln θ)² and
    /// ∂²ln η/∂(ln θ)²; empty (or zero) for first order alone. The fit reads them through one
    /// curvature along the inputs' combined shift ([`shared_curvature`], module docs).
    pub second_order: Vec<[f64; 2]>,
    /// The mode's own independent noise, per source: name and relative standard deviations of
    /// G' and η.
    pub noise: Vec<(String, [f64; 2])>,
}

impl ModePoint {
    /// Σ_j e_kj Δ_j − u_k + g(u_k) ≈ Σ_j e_kj Δ_j + ½ κ_k u_k², Δ_j = δ_j − δ₀_j, u_k =
    /// Σ_j e_kj Δ_j over the inputs with a second order, g as [`along_curve`]: how far the
    /// inputs' changes `delta` from nominal move this mode's ln G' and ln η, its point taken at
    /// the priors' `at` (module docs; κ_k from [`shared_curvature`], zero without
    /// [`ModePoint::second_order`]).
    fn input_shift(&self, delta: &[f64], priors: &[InputPrior]) -> [f64; 2] {
        let sds: Vec<f64> = priors.iter().map(|p| p.rel_sd).collect();
        let kappa = shared_curvature(&self.effects, &self.second_order, &sds);
        let part = |c: usize| {
            let (mut first, mut along) = (0.0, 0.0);
            for (j, ((e, d), p)) in self.effects.iter().zip(delta).zip(priors).enumerate() {
                let step = d - p.at;
                first += e[c] * step;
                if has_second_order(&self.second_order, j) {
                    along += e[c] * step;
                }
            }
            first - along + along_curve(kappa[c], along)
        };
        [part(0), part(1)]
    }
}

/// g(u) = (e^{κu} − 1)/κ = u + ½ κ u² + O(u³) (u where κ = 0): the inputs' combined shift u
/// to second order with curvature κ, continued monotonically. The parabola u + ½ κ u² turns
/// back at u = −1/κ, and a search that reaches there finds two input shifts for one point (on
/// the chain coverage example a seed whose 104 Hz mode the faces move by 50 % per sd went to
/// a law 22 % off).
fn along_curve(kappa: f64, u: f64) -> f64 {
    if kappa == 0.0 {
        u
    } else {
        (kappa * u).exp_m1() / kappa
    }
}

/// Whether input `j` has a measured second order (an entry not exactly zero: zero marks an
/// input whose second order was not taken, a wide prior or a failed move).
pub fn has_second_order(second_order: &[[f64; 2]], j: usize) -> bool {
    second_order.get(j).is_some_and(|c| *c != [0.0, 0.0])
}

/// The curvature κ of ln G' and ln η along the inputs' combined shift u = Σ_j e_j δ_j (module
/// docs), fitted to the inputs' second differences `second_order` c_j ≈ κ e_j² by least squares
/// on the scale of their priors `sds` s_j: with w_j = (e_j s_j)² and d_j = c_j s_j²,
/// κ = Σ_j w_j d_j / Σ_j w_j², so the inputs that move the mode most at one sd decide it. Zero
/// where no input has a second order. `effects`: e_j per input, as [`ModePoint::effects`].
pub fn shared_curvature(effects: &[[f64; 2]], second_order: &[[f64; 2]], sds: &[f64]) -> [f64; 2] {
    [0, 1].map(|c| {
        let (mut num, mut den) = (0.0, 0.0);
        for (j, (e, s)) in effects.iter().zip(sds).enumerate() {
            if !has_second_order(second_order, j) {
                continue;
            }
            let w = (e[c] * s).powi(2);
            num += w * second_order[j][c] * s * s;
            den += w * w;
        }
        if den > 0.0 { num / den } else { 0.0 }
    })
}

/// ln G' and ln η of G* = `g`.
fn log_parts(g: Complex64) -> [f64; 2] {
    [g.re.ln(), (g.im / g.re).ln()]
}

/// G* of ln G' = `v[0]`, ln η = `v[1]`.
fn from_log_parts(v: [f64; 2]) -> Complex64 {
    let storage = v[0].exp();
    Complex64::new(storage, storage * v[1].exp())
}

/// The points' log-slope S = d ln G*/d ln ω (complex): the least-squares line of ln G*_k over
/// ln f_k; 0 for a single point.
fn log_slope(points: &[ModePoint]) -> Complex64 {
    let n = points.len() as f64;
    let x: Vec<f64> = points.iter().map(|p| p.freq_hz.ln()).collect();
    let y: Vec<Complex64> = points.iter().map(|p| p.core_shear_pa.ln()).collect();
    let (xm, ym) = (x.iter().sum::<f64>() / n, y.iter().sum::<Complex64>() / n);
    let sxx: f64 = x.iter().map(|v| (v - xm).powi(2)).sum();
    if sxx <= 0.0 {
        return Complex64::new(0.0, 0.0);
    }
    x.iter()
        .zip(&y)
        .map(|(a, b)| (a - xm) * (b - ym))
        .sum::<Complex64>()
        / sxx
}

/// ln(ω*/ω) of a point: how far above (and along) the real axis its core was found.
fn log_offset(p: &ModePoint) -> Complex64 {
    (p.found_at_hz / p.freq_hz).ln()
}

/// Per point, the factor G*(f_k)/G*(ω*_k) that moves its core from the complex frequency it
/// was found at to the real `freq_hz` by the points' own log-slope (module docs): e^{−S ln(ω*/ω)}.
/// The per-mode law's continuation, and the one to use without a law.
pub fn to_real_frequency(points: &[ModePoint]) -> Vec<Complex64> {
    if points.is_empty() {
        return Vec::new();
    }
    let slope = log_slope(points);
    points
        .iter()
        .map(|p| (-slope * log_offset(p)).exp())
        .collect()
}

/// The law's value and its 95 % band at one frequency.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LawPoint {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// G', Pa.
    pub storage_pa: f64,
    /// Its 95 % band, Pa.
    pub storage_ci95: [f64; 2],
    /// η.
    pub loss_factor: f64,
    /// Its 95 % band.
    pub loss_factor_ci95: [f64; 2],
    /// The source contributing most to each band (G', η).
    pub dominant: [String; 2],
}

/// A fitted parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FittedParameter {
    /// Name with unit (`g0_pa`, ...), or an input's name: its value is then the relative change
    /// ln(θ/θ_nominal) the fit finds.
    pub name: String,
    /// Value, SI.
    pub value: f64,
    /// Standard deviation (of ln value for positive parameters, of the logit for α).
    pub sd: f64,
    /// 95 % interval.
    pub ci95: [f64; 2],
}

/// The joint fit (module docs).
#[derive(Debug, Clone, Serialize)]
pub struct CoreLawFit {
    /// The law.
    pub law: CoreLaw,
    /// The law's parameters (natural units), then one per input (relative change).
    pub parameters: Vec<FittedParameter>,
    /// Correlations of the searched parameters (ln G0, ln G∞, ln τ, logit α or the per-mode
    /// ln G', ln η; then the inputs' δ), in the order of `parameters`.
    pub correlation: Vec<Vec<f64>>,
    /// S of the data rows at the minimum, on the stated noise.
    pub chi2: f64,
    /// ν = 2K − P.
    pub dof: usize,
    /// s = √max(1, χ²/ν) at the minimum with the data's noise scaled by s (module docs): how
    /// far the scatter about the law exceeds the stated noise.
    pub scale: f64,
    /// Quantile used for the 95 % bands.
    pub z: f64,
    /// Parameter combinations the data and priors do not determine.
    pub undetermined: Vec<String>,
    /// Why this law was chosen, where a caller chose it among several ([`Self::akaike`]).
    pub selection: Option<String>,
    /// The law at each mode.
    pub at_modes: Vec<LawPoint>,
    /// Each mode's point moved from the complex frequency it was found at to its real
    /// `freq_hz` by the fitted law (module docs), with the inputs it was taken at (the priors'
    /// `at`; nominal by default), Pa: the per-mode diagnostic to set beside the law.
    pub real_frequency_points: Vec<Complex64>,
    /// Per point, the factor G*(f_k)/G*(ω*_k) that moved it from the complex frequency it was
    /// found at to the real axis (`real_frequency_points` = point × factor).
    pub real_frequency_factors: Vec<Complex64>,
    /// Each real-frequency point moved by the fitted inputs as well: G*_k e^{e_k (δ − δ₀)}, Pa.
    pub corrected_points: Vec<Complex64>,
    /// The other laws fitted to the same modes that share the band, with their Akaike
    /// weights ([`Self::with_alternatives`]; none alone). This law's own weight is the rest.
    #[serde(skip)]
    alternatives: Vec<(f64, CoreLawFit)>,
    #[serde(skip)]
    fit: Internal,
}

/// The band source of the choice between laws that fit the modes alike
/// ([`CoreLawFit::with_alternatives`]).
pub const LAW_BETWEEN_MODES: &str = "the law between the modes";

/// The band source of the part of a point's noise its stated sources do not name.
pub const NOISE_FLOOR: &str = "noise floor";

/// The band source of the points' scatter about the law beyond their stated noise.
pub const SCATTER_ABOUT_THE_LAW: &str = "scatter about the law";

/// Alternatives whose Akaike weight is below this are left out of the band
/// ([`CoreLawFit::with_alternatives`]): their share of its sd is below a thousandth of their
/// difference from the chosen law, 1e-4 of ln for a law 10 % away.
pub const LEAST_WEIGHT: f64 = 1e-3;

/// A law's own value and band at one frequency, before the alternatives.
struct OwnBand {
    /// ln G', ln η.
    value: [f64; 2],
    /// Their standard deviations.
    sd: [f64; 2],
    /// The largest source of each and its variance.
    dominant: [(String, f64); 2],
}

/// What the bands need after the fit.
#[derive(Debug, Clone)]
struct Internal {
    u: Vec<f64>,
    /// (JᵀJ)⁺ Jᵀ, p × m.
    gain: Mat<f64>,
    /// Per observation row: (source, share) pairs.
    rows: Vec<Vec<(String, f64)>>,
    log_freqs: ModeFrequencies,
}

/// ln G' and ln η of the law at `f_hz` on the searched parameters `u` (the law's part).
fn log_law(law: CoreLaw, u: &[f64], log_freqs: &ModeFrequencies, f_hz: f64) -> Option<[f64; 2]> {
    match law {
        CoreLaw::FractionalZener => {
            let g = law_of(u)?.modulus(2.0 * PI * f_hz);
            (g.re > 0.0 && g.im > 0.0).then(|| log_parts(g))
        }
        CoreLaw::GeneralizedMaxwell => {
            let taus = log_freqs.relaxation_times();
            let g = prony_modulus(u, &taus, Complex64::new(2.0 * PI * f_hz, 0.0))?;
            (g.re > 0.0 && g.im > 0.0).then(|| log_parts(g))
        }
        CoreLaw::PerMode => {
            let x = f_hz.ln();
            let log_freqs = &log_freqs.ln;
            let n = log_freqs.len();
            let k = log_freqs.partition_point(|&l| l < x).clamp(1, n.max(2) - 1);
            if n == 1 {
                return Some([u[0], u[1]]);
            }
            let t = ((x - log_freqs[k - 1]) / (log_freqs[k] - log_freqs[k - 1])).clamp(0.0, 1.0);
            let at = |c: usize| u[2 * (k - 1) + c] * (1.0 - t) + u[2 * k + c] * t;
            Some([at(0), at(1)])
        }
    }
}

/// Most fixed-point steps for the noise scale s (module docs); it settles to 1e-9 in a few.
const NOISE_SCALE_ITERATIONS: usize = 50;

/// Total relative noise of a point, floored at 1e-4 (0.01 %, below any measured pole's
/// scatter) so that a point without a noise estimate cannot pin the law.
fn noise_sd(p: &ModePoint) -> [f64; 2] {
    let part = |c: usize| {
        p.noise
            .iter()
            .map(|n| n.1[c] * n.1[c])
            .sum::<f64>()
            .sqrt()
            .max(1e-4)
    };
    [part(0), part(1)]
}

fn check(points: &[ModePoint], priors: &[InputPrior], law: CoreLaw) -> Result<(), FitError> {
    let bad = |why: String| Err(inconsistent(CONTEXT, why));
    if points.is_empty() {
        return bad("no mode with a core to fit".into());
    }
    for p in priors {
        if !p.at.is_finite() {
            return bad(format!(
                "the {} was linearised at a non-finite change {}",
                p.name, p.at
            ));
        }
        if !(p.rel_sd.is_finite() && p.rel_sd > 0.0) {
            return bad(format!(
                "the prior of the {} has standard deviation {}: it must be positive",
                p.name, p.rel_sd
            ));
        }
    }
    for (k, p) in points.iter().enumerate() {
        let g = p.core_shear_pa;
        if !([p.freq_hz, g.re, g.im]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0))
        {
            return bad(format!(
                "mode {} (f = {} Hz, G* = {g} Pa) needs a positive frequency, G' and G''",
                k + 1,
                p.freq_hz
            ));
        }
        let offset = log_offset(p);
        if !(offset.re.is_finite() && offset.im.is_finite())
            || p.found_at_hz.im < 0.0
            || offset.norm() > 0.5
        {
            return bad(format!(
                "mode {} was found at the complex frequency {} Hz: it must lie on or above the \
                 real axis, near its {} Hz (a decaying mode's −ip/2π)",
                k + 1,
                p.found_at_hz,
                p.freq_hz
            ));
        }
        if p.effects.len() != priors.len() {
            return bad(format!(
                "mode {} has {} input effects for {} priors",
                k + 1,
                p.effects.len(),
                priors.len()
            ));
        }
        let finite = p.effects.iter().flatten().all(|v| v.is_finite())
            && p.noise
                .iter()
                .all(|n| n.1.iter().all(|v| v.is_finite() && *v >= 0.0));
        if !finite {
            return bad(format!(
                "mode {} has a non-finite sensitivity or a negative or non-finite noise",
                k + 1
            ));
        }
        if k > 0 && p.freq_hz <= points[k - 1].freq_hz {
            return bad(format!(
                "the modes must come in increasing frequency: mode {} at {} Hz follows {} Hz",
                k + 1,
                p.freq_hz,
                points[k - 1].freq_hz
            ));
        }
    }
    let p = law.parameter_count(points.len());
    if p > 2 * points.len() {
        return bad(format!(
            "a {} law has {p} parameters; {} mode(s) give {} values (G' and η each): too few to \
             determine it. Identify more modes or fit per mode",
            law.name(),
            points.len(),
            2 * points.len()
        ));
    }
    Ok(())
}

/// ln G' and ln η of the law at point `p`'s complex frequency (module docs); `slope` is the
/// per-mode law's continuation.
fn log_law_at_point(
    law: CoreLaw,
    u: &[f64],
    log_freqs: &ModeFrequencies,
    p: &ModePoint,
    slope: Complex64,
) -> Option<[f64; 2]> {
    let g = match law {
        CoreLaw::FractionalZener => law_of(u)?.modulus_at_complex(2.0 * PI * p.found_at_hz),
        CoreLaw::GeneralizedMaxwell => {
            prony_modulus(u, &log_freqs.relaxation_times(), 2.0 * PI * p.found_at_hz)?
        }
        CoreLaw::PerMode => {
            from_log_parts(log_law(law, u, log_freqs, p.freq_hz)?) * (slope * log_offset(p)).exp()
        }
    };
    (g.re > 0.0 && g.im > 0.0).then(|| log_parts(g))
}

/// Residuals of the module docs; `u` = law's parameters then the inputs' δ.
fn residuals(
    law: CoreLaw,
    u: &[f64],
    points: &[ModePoint],
    sd: &[[f64; 2]],
    priors: &[InputPrior],
    log_freqs: &ModeFrequencies,
    slope: Complex64,
) -> Option<Vec<f64>> {
    let np = law.parameter_count(points.len());
    let delta = &u[np..];
    let mut r = Vec::with_capacity(2 * points.len() + priors.len());
    for (k, p) in points.iter().enumerate() {
        let m = log_law_at_point(law, &u[..np], log_freqs, p, slope)?;
        let data = log_parts(p.core_shear_pa);
        let shift = p.input_shift(delta, priors);
        for c in 0..2 {
            r.push((m[c] - data[c] - shift[c]) / sd[k][c]);
        }
    }
    r.extend(delta.iter().zip(priors).map(|(d, p)| d / p.rel_sd));
    Some(r)
}

/// Starting points of the law's parameters, best first (a grid over α and τ for the
/// fractional Zener law, G0 and G∞ from the data's range; the data themselves per mode).
fn starts(law: CoreLaw, points: &[ModePoint], log_freqs: &ModeFrequencies) -> Vec<Vec<f64>> {
    match law {
        CoreLaw::PerMode => vec![
            points
                .iter()
                .flat_map(|p| log_parts(p.core_shear_pa))
                .collect(),
        ],
        CoreLaw::FractionalZener => {
            let gs = points.iter().map(|p| p.core_shear_pa.re);
            let gmin = gs.clone().fold(f64::MAX, f64::min);
            let gmax = gs.fold(0.0, f64::max);
            let fmin = points[0].freq_hz;
            let fmax = points[points.len() - 1].freq_hz;
            let mut scored: Vec<(f64, Vec<f64>)> = Vec::new();
            for alpha in [0.2_f64, 0.35, 0.5, 0.65, 0.8] {
                for (lo, hi) in [(0.3, 30.0), (0.05, 300.0), (0.01, 3000.0)] {
                    for k in 0..13 {
                        let f = fmin * 1e-4 * (fmax * 1e8 / fmin).powf(k as f64 / 12.0);
                        let u = vec![
                            (lo * gmin).ln(),
                            (hi * gmax).ln(),
                            (1.0 / (2.0 * PI * f)).ln(),
                            (alpha / (1.0 - alpha)).ln(),
                        ];
                        let cost: f64 = points
                            .iter()
                            .map(|p| {
                                let d = log_parts(p.core_shear_pa);
                                log_law(law, &u, log_freqs, p.freq_hz).map_or(f64::INFINITY, |m| {
                                    (m[0] - d[0]).powi(2) + (m[1] - d[1]).powi(2)
                                })
                            })
                            .sum();
                        if cost.is_finite() {
                            scored.push((cost, u));
                        }
                    }
                }
            }
            scored.sort_by(|a, b| a.0.total_cmp(&b.0));
            scored.into_iter().take(6).map(|(_, u)| u).collect()
        }
        CoreLaw::GeneralizedMaxwell => prony_starts(points, &log_freqs.relaxation_times()),
    }
}

/// Starts of the Prony fit: G* is linear in (G_e, g_k), so the least-squares solution on the
/// points' G' and G'' (each row divided by |G*_k|), its negative or tiny strengths raised to
/// 1e-3 of the largest (the search is on their logarithms), and the same from a flat spectrum
/// (every g_k alike, G_e the lowest G').
fn prony_starts(points: &[ModePoint], taus: &[f64]) -> Vec<Vec<f64>> {
    let n = taus.len() + 1;
    let i = Complex64::new(0.0, 1.0);
    let mut a = Mat::<f64>::zeros(2 * points.len(), n);
    let mut b = Mat::<f64>::zeros(2 * points.len(), 1);
    for (k, p) in points.iter().enumerate() {
        let w = 1.0 / p.core_shear_pa.norm();
        let omega = 2.0 * PI * p.freq_hz;
        let column = |j: usize| {
            if j == 0 {
                Complex64::new(1.0, 0.0)
            } else {
                let x = i * omega * taus[j - 1];
                x / (1.0 + x)
            }
        };
        for j in 0..n {
            a[(2 * k, j)] = w * column(j).re;
            a[(2 * k + 1, j)] = w * column(j).im;
        }
        b[(2 * k, 0)] = w * p.core_shear_pa.re;
        b[(2 * k + 1, 0)] = w * p.core_shear_pa.im;
    }
    let gmin = points
        .iter()
        .map(|p| p.core_shear_pa.re)
        .fold(f64::MAX, f64::min);
    let gmax = points
        .iter()
        .map(|p| p.core_shear_pa.norm())
        .fold(0.0, f64::max);
    let mut out = Vec::new();
    let ata = a.transpose() * &a;
    let atb = a.transpose() * &b;
    if let Ok((inv, _)) = pseudo_inverse(&ata, CONTEXT) {
        let x = &inv * &atb;
        let largest = (0..n).map(|j| x[(j, 0)]).fold(0.0, f64::max);
        if largest > 0.0 {
            out.push((0..n).map(|j| x[(j, 0)].max(1e-3 * largest).ln()).collect());
        }
    }
    let flat = ((gmax - gmin).max(1e-3 * gmax) / (n - 1) as f64).ln();
    let mut u = vec![flat; n];
    u[0] = (0.5 * gmin).ln();
    out.push(u);
    out
}

/// Fits `law` to the modes' cores jointly with the inputs under `priors` (module docs).
///
/// # Errors
/// [`FitError::Inconsistent`] for no points, a point with a non-positive or non-finite
/// frequency or modulus, modes out of frequency order, effects that do not match the priors,
/// a prior with a non-positive standard deviation, a law with more parameters than the modes
/// give values, or a fit that finds no parameters where the law is defined.
pub fn fit_core_law(
    points: &[ModePoint],
    priors: &[InputPrior],
    law: CoreLaw,
) -> Result<CoreLawFit, FitError> {
    fit_core_law_shifted(points, priors, law, 0.0)
}

/// [`fit_core_law`] with a generalized Maxwell law's relaxation times moved by `prony_offset`
/// of their spacing ([`prony_relaxation_times_shifted`]; other laws ignore it).
///
/// # Errors
/// Those of [`fit_core_law`], and an offset outside [0, 1).
pub fn fit_core_law_shifted(
    points: &[ModePoint],
    priors: &[InputPrior],
    law: CoreLaw,
    prony_offset: f64,
) -> Result<CoreLawFit, FitError> {
    check(points, priors, law)?;
    if !(0.0..1.0).contains(&prony_offset) {
        return Err(inconsistent(
            CONTEXT,
            format!(
                "the relaxation times' offset {prony_offset} must lie in [0, 1) of their spacing"
            ),
        ));
    }
    let log_freqs = ModeFrequencies {
        ln: points.iter().map(|p| p.freq_hz.ln()).collect(),
        prony_offset: if law == CoreLaw::GeneralizedMaxwell {
            prony_offset
        } else {
            0.0
        },
    };
    let stated: Vec<[f64; 2]> = points.iter().map(noise_sd).collect();
    let slope = log_slope(points);
    let np = law.parameter_count(points.len());
    let m_data = 2 * points.len();
    let dof = m_data - np;
    let minimise = |scale: f64, starts: Vec<Vec<f64>>| {
        let sd: Vec<[f64; 2]> = stated.iter().map(|s| s.map(|v| v * scale)).collect();
        let res = |u: &[f64]| residuals(law, u, points, &sd, priors, &log_freqs, slope);
        starts
            .into_iter()
            .filter_map(|u0| levenberg_marquardt(&res, &u0, LmSettings::default()))
            .min_by(|a, b| a.cost.total_cmp(&b.cost))
    };
    let first: Vec<Vec<f64>> = starts(law, points, &log_freqs)
        .into_iter()
        .map(|mut u0| {
            u0.extend(priors.iter().map(|p| p.at));
            u0
        })
        .collect();
    let mut scale = 1.0;
    let mut best = minimise(scale, first).ok_or_else(|| {
        inconsistent(
            CONTEXT,
            format!("no start led to a {} law with G' > 0 and η > 0", law.name()),
        )
    })?;
    // S_data on the stated noise: the scaled residuals times the scale.
    let stated_chi2 =
        |r: &[f64], scale: f64| r[..m_data].iter().map(|v| (v * scale).powi(2)).sum::<f64>();
    for _ in 0..NOISE_SCALE_ITERATIONS {
        let ratio = if dof > 0 {
            stated_chi2(&best.residuals, scale) / dof as f64
        } else {
            0.0
        };
        let next = ratio.max(1.0).sqrt();
        if (next / scale - 1.0).abs() < 1e-9 {
            break;
        }
        scale = next;
        match minimise(scale, vec![best.x.clone()]) {
            Some(b) => best = b,
            None => break,
        }
    }
    let chi2 = stated_chi2(&best.residuals, scale);
    let z = if scale > 1.0 {
        t975(dof)
    } else {
        1.959_963_985
    };
    let names = parameter_names(law, points.len(), &log_freqs, priors);
    let jtj = best.jacobian.transpose() * &best.jacobian;
    let (inv, null) = pseudo_inverse(&jtj, CONTEXT)?;
    let gain = &inv * best.jacobian.transpose();
    let rows = row_sources(points, &stated, scale, priors);
    let p = best.x.len();
    let sds: Vec<f64> = (0..p).map(|i| inv[(i, i)].max(0.0).sqrt()).collect();
    let correlation = (0..p)
        .map(|i| {
            (0..p)
                .map(|j| inv[(i, j)] / (inv[(i, i)] * inv[(j, j)]).sqrt().max(f64::MIN_POSITIVE))
                .collect()
        })
        .collect();
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut parameters = natural_parameters(law, np, &best.x, &sds, z, &names);
    unbound_undetermined(&mut parameters, law, np, &null);
    let to_real: Vec<Complex64> = match law {
        CoreLaw::PerMode => to_real_frequency(points),
        CoreLaw::FractionalZener => {
            let fitted = law_of(&best.x[..np]).ok_or_else(|| {
                inconsistent(CONTEXT, "the fitted law left its domain".to_string())
            })?;
            points
                .iter()
                .map(|p| {
                    fitted.modulus(2.0 * PI * p.freq_hz)
                        / fitted.modulus_at_complex(2.0 * PI * p.found_at_hz)
                })
                .collect()
        }
        CoreLaw::GeneralizedMaxwell => {
            let taus = log_freqs.relaxation_times();
            points
                .iter()
                .map(|p| {
                    let at = |w: Complex64| prony_modulus(&best.x[..np], &taus, w);
                    match (
                        at(Complex64::new(2.0 * PI * p.freq_hz, 0.0)),
                        at(2.0 * PI * p.found_at_hz),
                    ) {
                        (Some(real), Some(found)) => Ok(real / found),
                        _ => Err(inconsistent(
                            CONTEXT,
                            "the fitted law left its domain".to_string(),
                        )),
                    }
                })
                .collect::<Result<_, _>>()?
        }
    };
    let real_frequency_points: Vec<Complex64> = points
        .iter()
        .zip(&to_real)
        .map(|(p, r)| p.core_shear_pa * r)
        .collect();
    let corrected_points = points
        .iter()
        .zip(&real_frequency_points)
        .map(|(pt, g)| {
            let shift = pt.input_shift(&best.x[np..], priors);
            let found = log_parts(*g);
            from_log_parts([found[0] + shift[0], found[1] + shift[1]])
        })
        .collect();
    let mut out = CoreLawFit {
        law,
        parameters,
        correlation,
        chi2,
        dof,
        scale,
        z,
        undetermined: null
            .iter()
            .map(|v| describe_direction(&name_refs, v))
            .collect(),
        selection: None,
        at_modes: Vec::new(),
        real_frequency_points,
        real_frequency_factors: to_real,
        corrected_points,
        alternatives: Vec::new(),
        fit: Internal {
            u: best.x,
            gain,
            rows,
            log_freqs,
        },
    };
    out.at_modes = points.iter().filter_map(|p| out.at(p.freq_hz)).collect();
    Ok(out)
}

fn parameter_names(
    law: CoreLaw,
    modes: usize,
    log_freqs: &ModeFrequencies,
    priors: &[InputPrior],
) -> Vec<String> {
    let mut names: Vec<String> = match law {
        CoreLaw::FractionalZener => ["g0_pa", "g_inf_pa", "tau_s", "alpha"]
            .map(String::from)
            .to_vec(),
        CoreLaw::PerMode => (1..=modes)
            .flat_map(|k| [format!("storage_pa_{k}"), format!("loss_factor_{k}")])
            .collect(),
        CoreLaw::GeneralizedMaxwell => std::iter::once("g_e_pa".to_string())
            .chain(
                log_freqs
                    .relaxation_times()
                    .iter()
                    .enumerate()
                    .map(|(k, tau)| format!("g{}_pa (tau {tau:.3e} s)", k + 1)),
            )
            .collect(),
    };
    names.extend(priors.iter().map(|p| p.name.clone()));
    names
}

/// Parameters in natural units: the positive ones (searched on ln) with intervals mapped back,
/// α (searched on its logit) likewise, the first `np` being the law's; the inputs' δ with
/// symmetric intervals.
fn natural_parameters(
    law: CoreLaw,
    np: usize,
    u: &[f64],
    sds: &[f64],
    z: f64,
    names: &[String],
) -> Vec<FittedParameter> {
    let logistic = |v: f64| 1.0 / (1.0 + (-v).exp());
    u.iter()
        .zip(sds)
        .zip(names)
        .enumerate()
        .map(|(i, ((&x, &sd), name))| {
            let (value, ci95) = if i >= np {
                (x, [x - z * sd, x + z * sd])
            } else if law == CoreLaw::FractionalZener && i == 3 {
                (logistic(x), [logistic(x - z * sd), logistic(x + z * sd)])
            } else {
                (x.exp(), [(x - z * sd).exp(), (x + z * sd).exp()])
            };
            FittedParameter {
                name: name.clone(),
                value,
                sd,
                ci95,
            }
        })
        .collect()
}

/// A parameter with a weight above 0.2 in a direction the data and priors do not determine
/// has no interval: its sd is infinite and its 95 % interval the whole of its domain (the
/// pseudo-inverse drops such a direction, which would otherwise read as a zero-width interval,
/// e.g. G0 of a fractional Zener law whose modes all lie far above 1/(2πτ)).
fn unbound_undetermined(
    parameters: &mut [FittedParameter],
    law: CoreLaw,
    np: usize,
    null: &[Vec<f64>],
) {
    for (i, p) in parameters.iter_mut().enumerate() {
        if !null.iter().any(|v| v[i].abs() > 0.2) {
            continue;
        }
        p.sd = f64::INFINITY;
        p.ci95 = if i >= np {
            [f64::NEG_INFINITY, f64::INFINITY]
        } else if law == CoreLaw::FractionalZener && i == 3 {
            [0.0, 1.0]
        } else {
            [0.0, f64::INFINITY]
        };
    }
}

/// Per observation row, the sources its variance belongs to with their shares: a mode's data
/// rows to its noise sources (share of s²σ², the floor's remainder to "noise floor", the
/// excess 1 − 1/s² to "scatter about the law"), a prior's row to its input.
fn row_sources(
    points: &[ModePoint],
    sd: &[[f64; 2]],
    scale: f64,
    priors: &[InputPrior],
) -> Vec<Vec<(String, f64)>> {
    let mut rows = Vec::new();
    let stated_share = 1.0 / (scale * scale);
    for (p, s) in points.iter().zip(sd) {
        for c in 0..2 {
            let total = s[c] * s[c];
            let mut shares: Vec<(String, f64)> = p
                .noise
                .iter()
                .map(|n| (n.0.clone(), stated_share * n.1[c] * n.1[c] / total))
                .collect();
            let floor = stated_share - shares.iter().map(|x| x.1).sum::<f64>();
            if floor > 1e-9 {
                shares.push((NOISE_FLOOR.into(), floor));
            }
            if 1.0 - stated_share > 1e-9 {
                shares.push((SCATTER_ABOUT_THE_LAW.into(), 1.0 - stated_share));
            }
            rows.push(shares);
        }
    }
    rows.extend(priors.iter().map(|p| vec![(p.name.clone(), 1.0)]));
    rows
}

impl CoreLawFit {
    /// Number of the law's own parameters.
    fn law_parameters(&self) -> usize {
        self.law.parameter_count(self.fit.log_freqs.ln.len())
    }

    /// ln G' and ln η of the law at `f_hz` on parameters `u`.
    fn log_at(&self, u: &[f64], f_hz: f64) -> Option<[f64; 2]> {
        log_law(
            self.law,
            &u[..self.law_parameters()],
            &self.fit.log_freqs,
            f_hz,
        )
    }

    /// The law's value and its own band at `f_hz`, without the alternatives.
    fn own_band(&self, f_hz: f64) -> Option<OwnBand> {
        let u = &self.fit.u;
        let value = self.log_at(u, f_hz)?;
        let mut sd = [0.0; 2];
        let mut dominant = [(String::new(), 0.0), (String::new(), 0.0)];
        for c in 0..2 {
            // Gradient over the searched parameters (the law's; the inputs do not enter it).
            let g: Vec<f64> = (0..u.len())
                .map(|k| {
                    if k >= self.law_parameters() {
                        return Some(0.0);
                    }
                    let h = 1e-6 * u[k].abs().max(1.0);
                    let mut up = u.clone();
                    up[k] += h;
                    let mut um = u.clone();
                    um[k] -= h;
                    Some((self.log_at(&up, f_hz)?[c] - self.log_at(&um, f_hz)?[c]) / (2.0 * h))
                })
                .collect::<Option<_>>()?;
            let mut by_source: Vec<(String, f64)> = Vec::new();
            for (i, shares) in self.fit.rows.iter().enumerate() {
                let a: f64 = (0..u.len()).map(|k| g[k] * self.fit.gain[(k, i)]).sum();
                for (name, share) in shares {
                    let v = a * a * share;
                    match by_source.iter_mut().find(|s| &s.0 == name) {
                        Some(s) => s.1 += v,
                        None => by_source.push((name.clone(), v)),
                    }
                }
            }
            sd[c] = by_source.iter().map(|s| s.1).sum::<f64>().sqrt();
            dominant[c] = by_source
                .into_iter()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or_else(|| ("-".into(), 0.0));
        }
        Some(OwnBand {
            value,
            sd,
            dominant,
        })
    }

    /// The law and its 95 % band at `f_hz` (None where the law is not defined). With
    /// alternatives ([`Self::with_alternatives`]) the band's sd is Σ_i w_i √(sd_i² + (x_i − x)²)
    /// over this law and the others, x this law's ln G' or ln η.
    pub fn at(&self, f_hz: f64) -> Option<LawPoint> {
        let own = self.own_band(f_hz)?;
        // The weights of the alternatives left out are this law's: its band stays at least its own.
        let own_weight = 1.0 - self.alternatives.iter().map(|a| a.0).sum::<f64>();
        let mut sd = own.sd.map(|v| own_weight * v);
        for (w, other) in &self.alternatives {
            let Some(o) = other.own_band(f_hz) else {
                continue;
            };
            for c in 0..2 {
                sd[c] += w * o.sd[c].hypot(o.value[c] - own.value[c]);
            }
        }
        let dominant: [String; 2] = std::array::from_fn(|c| {
            let between = sd[c] * sd[c] - own.sd[c] * own.sd[c];
            if between > own.dominant[c].1 {
                LAW_BETWEEN_MODES.to_string()
            } else {
                own.dominant[c].0.clone()
            }
        });
        let half = sd.map(|v| self.z * v);
        let storage = own.value[0].exp();
        let loss = own.value[1].exp();
        Some(LawPoint {
            freq_hz: f_hz,
            storage_pa: storage,
            storage_ci95: [storage * (-half[0]).exp(), storage * half[0].exp()],
            loss_factor: loss,
            loss_factor_ci95: [loss * (-half[1]).exp(), loss * half[1].exp()],
            dominant,
        })
    }

    /// This fit with the band widened by `others`, the other laws (or relaxation grids of a
    /// generalized Maxwell law, [`prony_relaxation_times_shifted`]) fitted to the same modes,
    /// each with its Akaike criterion ([`Self::akaike`], on the same footing as
    /// `own_criterion`, this law's). Laws that fit the modes alike can differ between them,
    /// and the modes cannot tell which is right there: the band takes that in as model
    /// selection uncertainty, with the Akaike weights w_i = e^{−Δ_i/2} / Σ_j e^{−Δ_j/2}, Δ_i =
    /// AICc_i − min AICc, and sd = Σ_i w_i √(sd_i² + (x_i − x)²) about this law's estimate x
    /// [Burnham & Anderson 2002, §4.3.2, eq. 4.9, there about the weighted mean]. At a mode
    /// every law that fits holds the point and the band hardly moves; between modes far apart
    /// it widens where the laws part. Others of weight below 1e-3 are left out; this law is
    /// the caller's choice (the lowest criterion, normally).
    pub fn with_alternatives(mut self, own_criterion: f64, others: Vec<(f64, CoreLawFit)>) -> Self {
        let best = others.iter().map(|o| o.0).fold(own_criterion, f64::min);
        let weight = |a: f64| {
            if a.is_finite() {
                (-(a - best) / 2.0).exp()
            } else {
                0.0
            }
        };
        let total = weight(own_criterion) + others.iter().map(|o| weight(o.0)).sum::<f64>();
        if !(total > 0.0 && total.is_finite()) {
            return self;
        }
        self.alternatives = others
            .into_iter()
            .map(|(a, fit)| (weight(a) / total, fit))
            .filter(|(w, _)| *w >= LEAST_WEIGHT)
            .collect();
        let freqs: Vec<f64> = self.fit.log_freqs.ln.iter().map(|l| l.exp()).collect();
        self.at_modes = freqs.iter().filter_map(|&f| self.at(f)).collect();
        self
    }

    /// The law's name, with where a generalized Maxwell law's relaxation times sit when
    /// they are moved from [`prony_relaxation_times`].
    pub fn form(&self) -> String {
        if self.fit.log_freqs.prony_offset == 0.0 {
            self.law.name().to_string()
        } else {
            format!(
                "{} (relaxation times moved by {} of their spacing)",
                self.law.name(),
                self.fit.log_freqs.prony_offset
            )
        }
    }

    /// Akaike's information criterion of the law with the small-sample correction, AICc =
    /// χ² + 2P + 2P(P + 1)/(N − P − 1) [Akaike 1974; Hurvich & Tsai 1989]: χ² of the data rows
    /// on their stated noise (the inputs' priors and their parameters are the same for every
    /// law fitted to the same points), P the law's own parameters, N = 2K the data rows
    /// (infinite when N ≤ P + 1). Of two laws fitted to the same points the one with the lower
    /// value is the better trade of fit against parameters. The correction matters here: with
    /// four modes a Prony series of four terms (P = 5 for N = 8) matched the points to χ² = 0.1
    /// and its η wandered by up to 12 % between them; plain AIC preferred it to the fractional
    /// Zener law (10.1 against 10.5), AICc does not (40.1 against 23.9).
    pub fn akaike(&self) -> f64 {
        let p = self.law_parameters() as f64;
        let n = 2.0 * self.fit.log_freqs.ln.len() as f64;
        if n <= p + 1.0 {
            return f64::INFINITY;
        }
        self.chi2 + 2.0 * p + 2.0 * p * (p + 1.0) / (n - p - 1.0)
    }

    /// The law at `n` frequencies spaced evenly in ln f from the first mode to the last.
    pub fn curve(&self, n: usize) -> Vec<LawPoint> {
        let lf = &self.fit.log_freqs.ln;
        let (a, b) = (lf[0], lf[lf.len() - 1]);
        (0..n.max(2))
            .filter_map(|k| self.at((a + (b - a) * k as f64 / (n.max(2) - 1) as f64).exp()))
            .collect()
    }

    /// G* of the fitted law at `f_hz`, Pa.
    pub fn modulus(&self, f_hz: f64) -> Option<Complex64> {
        let v = self.log_at(&self.fit.u, f_hz)?;
        let storage = v[0].exp();
        Some(Complex64::new(storage, storage * v[1].exp()))
    }

    /// The fitted relative change of each input, ln(θ/θ_nominal), with its 95 % interval.
    pub fn inputs(&self) -> &[FittedParameter] {
        &self.parameters[self.law_parameters()..]
    }

    /// A one-line description of the law's parameters.
    pub fn describe(&self) -> String {
        let law: Vec<String> = self.parameters[..self.law_parameters()]
            .iter()
            .map(|p| {
                if p.sd.is_finite() {
                    format!(
                        "{} = {:.4e} [{:.3e}, {:.3e}]",
                        p.name, p.value, p.ci95[0], p.ci95[1]
                    )
                } else {
                    format!(
                        "{} not determined (search stopped at {:.1e})",
                        p.name, p.value
                    )
                }
            })
            .collect();
        format!("{}: {}", self.law.name(), law.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::Normal;
    use lamdyn_material::law::FractionalZener;

    /// A PVB-like core over the roof's band: G' 13–23 MPa and η ≈ 0.6–0.9 at 17–64 Hz.
    fn truth() -> FractionalZener {
        FractionalZener::new(0.5e6, 400e6, 2e-5, 0.55).unwrap()
    }

    const FREQS: [f64; 5] = [17.2, 25.2, 43.7, 51.0, 64.3];

    /// The roof's sensitivities to the face modulus and the face thickness (signed, ln G' and
    /// ln η per ln θ), of the size measured on the demo roof (example roof_sensitivity).
    fn effects(k: usize) -> Vec<[f64; 2]> {
        let e = [-14.0, -61.0, -20.0, -35.0, -25.0];
        let t = [-30.0, -102.0, -22.0, -50.0, -40.0];
        vec![[e[k], 0.3 * e[k]], [t[k], -0.2 * t[k]]]
    }

    fn priors() -> Vec<InputPrior> {
        vec![
            InputPrior {
                name: "face modulus".into(),
                rel_sd: 0.01,
                at: 0.0,
            },
            InputPrior {
                name: "face thickness".into(),
                rel_sd: 0.0025,
                at: 0.0,
            },
        ]
    }

    /// The points a test on faces off nominal by `delta` gives (true = found + e δ), with
    /// relative noise `sd` drawn from `rng`.
    fn points(delta: &[f64], sd: f64, rng: &mut Normal) -> Vec<ModePoint> {
        FREQS
            .iter()
            .enumerate()
            .map(|(k, &f)| {
                let g = truth().modulus(2.0 * PI * f);
                let e = effects(k);
                let shift = |c: usize| -> f64 { e.iter().zip(delta).map(|(e, d)| e[c] * d).sum() };
                let storage = g.re * (-shift(0) + sd * rng.sample()).exp();
                let eta = g.im / g.re * (-shift(1) + sd * rng.sample()).exp();
                ModePoint {
                    freq_hz: f,
                    found_at_hz: Complex64::new(f, 0.0),
                    core_shear_pa: Complex64::new(storage, storage * eta),
                    effects: e,
                    second_order: Vec::new(),
                    noise: vec![("EMA pole".into(), [sd, sd])],
                }
            })
            .collect()
    }

    /// On nominal faces with 0.1 % noise the law between the first and the last mode is
    /// within 0.5 % of the truth in G' and η (0.1 % noise over 10 values fits 4 parameters
    /// to a few 0.1 %).
    #[test]
    fn recovers_a_fractional_zener_core() {
        let mut rng = Normal::new(7);
        let pts = points(&[0.0, 0.0], 1e-3, &mut rng);
        let fit = fit_core_law(&pts, &priors(), CoreLaw::FractionalZener).unwrap();
        for p in fit.curve(40) {
            let g = truth().modulus(2.0 * PI * p.freq_hz);
            assert!((p.storage_pa / g.re - 1.0).abs() < 5e-3, "{p:?} vs {g}");
            assert!((p.loss_factor / (g.im / g.re) - 1.0).abs() < 5e-3, "{p:?}");
        }
        assert_eq!(fit.dof, 6);
    }

    /// Points whose inputs act to second order along their combined shift (true = found +
    /// g(u) ≈ u + ½ κ u², u = Σ e δ, [`along_curve`], the faces 1.5 sd off, κ = −1 in G' and
    /// +0.5 in η: at the 25 Hz mode the second order is a third of the first at 1 sd) and give
    /// the diagonal second
    /// differences c_j = κ e_j² such a world has: the law is as close to the truth as the same
    /// test in a world linear in the inputs (0.105 % against 0.106 %) and the face modulus found
    /// lies within its interval; the same points read to first order alone put the law 4.5 %
    /// off. And [`shared_curvature`] finds κ from those differences.
    #[test]
    fn second_order_effects_are_modelled() {
        let delta = [0.015, -0.00375];
        let kappa = [-1.0, 0.5];
        let second = |k: usize| -> Vec<[f64; 2]> {
            effects(k)
                .iter()
                .map(|e| [kappa[0] * e[0] * e[0], kappa[1] * e[1] * e[1]])
                .collect()
        };
        let sds: Vec<f64> = priors().iter().map(|p| p.rel_sd).collect();
        for k in 0..FREQS.len() {
            let found = shared_curvature(&effects(k), &second(k), &sds);
            assert!((found[0] - kappa[0]).abs() < 1e-12 && (found[1] - kappa[1]).abs() < 1e-12);
        }
        let mut rng = Normal::new(11);
        let pts: Vec<ModePoint> = points(&[0.0, 0.0], 1e-3, &mut rng)
            .into_iter()
            .enumerate()
            .map(|(k, p)| {
                let q = |c: usize| -> f64 {
                    let u: f64 = p.effects.iter().zip(&delta).map(|(e, d)| e[c] * d).sum();
                    along_curve(kappa[c], u)
                };
                let g = log_parts(p.core_shear_pa);
                ModePoint {
                    core_shear_pa: from_log_parts([g[0] - q(0), g[1] - q(1)]),
                    second_order: second(k),
                    ..p
                }
            })
            .collect();
        let worst = |fit: &CoreLawFit| -> f64 {
            fit.curve(40)
                .iter()
                .map(|p| {
                    let g = truth().modulus(2.0 * PI * p.freq_hz);
                    (p.storage_pa / g.re - 1.0)
                        .abs()
                        .max((p.loss_factor / (g.im / g.re) - 1.0).abs())
                })
                .fold(0.0, f64::max)
        };
        let linear = points(&delta, 1e-3, &mut Normal::new(11));
        let linear = fit_core_law(&linear, &priors(), CoreLaw::FractionalZener).unwrap();
        let fit = fit_core_law(&pts, &priors(), CoreLaw::FractionalZener).unwrap();
        println!(
            "second order: worst {} linear {}",
            worst(&fit),
            worst(&linear)
        );
        assert!(worst(&fit) < 5e-3, "{}", worst(&fit));
        assert!((worst(&fit) - worst(&linear)).abs() < 1e-4);
        let e = &fit.inputs()[0];
        assert!(e.ci95[0] <= delta[0] && delta[0] <= e.ci95[1], "{e:?}");
        let first_only: Vec<ModePoint> = pts
            .iter()
            .map(|p| ModePoint {
                second_order: Vec::new(),
                ..p.clone()
            })
            .collect();
        let fit = fit_core_law(&first_only, &priors(), CoreLaw::FractionalZener).unwrap();
        println!("first order alone: worst {}", worst(&fit));
        assert!(worst(&fit) > 0.01, "{}", worst(&fit));
    }

    /// A per-mode law leaves the inputs at their priors, so each mode's band is the quadrature
    /// sum of its noise and its inputs' effects: 1.96 √(σ² + Σ (e s)²), in closed form.
    #[test]
    fn per_mode_law_gives_the_quadrature_band() {
        let mut rng = Normal::new(3);
        let pts = points(&[0.0, 0.0], 0.02, &mut rng);
        let fit = fit_core_law(&pts, &priors(), CoreLaw::PerMode).unwrap();
        assert_eq!(fit.dof, 0);
        for (k, p) in fit.at_modes.iter().enumerate() {
            let e = effects(k);
            for c in 0..2 {
                let var = 0.02f64.powi(2) + (e[0][c] * 0.01).powi(2) + (e[1][c] * 0.0025).powi(2);
                let want = 1.959_963_985 * var.sqrt();
                let got = if c == 0 {
                    (p.storage_ci95[1] / p.storage_pa).ln()
                } else {
                    (p.loss_factor_ci95[1] / p.loss_factor).ln()
                };
                assert!(
                    (got / want - 1.0).abs() < 1e-6,
                    "mode {k} part {c}: {got} vs {want}"
                );
            }
            let g = pts[k].core_shear_pa;
            assert!((p.storage_pa / g.re - 1.0).abs() < 1e-9);
        }
        assert!(fit.inputs()[0].value.abs() < 1e-9);
    }

    /// Coverage over 200 seeds, faces drawn from their priors and 2 % noise: the truth lies
    /// inside the joint 95 % band at ≥ 90 % of the (mode, seed) pairs in G' and in η (expected
    /// 95 %; the binomial sd over 1000 pairs is 0.7 %, the linearisation of the law costs some),
    /// and the shared inputs make the median band narrower than the per-mode one.
    #[test]
    fn joint_bands_cover_the_truth_with_faces_off_nominal() {
        let mut rng = Normal::new(11);
        let (mut inside, mut total) = ([0usize; 2], 0usize);
        let (mut joint_w, mut per_mode_w) = (Vec::new(), Vec::new());
        for _ in 0..200 {
            let delta = [0.01 * rng.sample(), 0.0025 * rng.sample()];
            let pts = points(&delta, 0.02, &mut rng);
            let fit = fit_core_law(&pts, &priors(), CoreLaw::FractionalZener).unwrap();
            let per = fit_core_law(&pts, &priors(), CoreLaw::PerMode).unwrap();
            for (p, q) in fit.at_modes.iter().zip(&per.at_modes) {
                let g = truth().modulus(2.0 * PI * p.freq_hz);
                total += 1;
                inside[0] += usize::from(p.storage_ci95[0] <= g.re && g.re <= p.storage_ci95[1]);
                let eta = g.im / g.re;
                inside[1] +=
                    usize::from(p.loss_factor_ci95[0] <= eta && eta <= p.loss_factor_ci95[1]);
                joint_w.push((p.storage_ci95[1] / p.storage_pa).ln());
                per_mode_w.push((q.storage_ci95[1] / q.storage_pa).ln());
            }
        }
        let rate = inside.map(|n| n as f64 / total as f64);
        assert!(rate[0] >= 0.9 && rate[1] >= 0.9, "coverage {rate:?}");
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (j, p) = (median(&mut joint_w), median(&mut per_mode_w));
        assert!(j < 0.8 * p, "joint {j} vs per mode {p}");
    }

    /// Points found at their poles' complex frequencies ω* = ω_n(√(1 − ζ²) + iζ), ζ = 1.5 %,
    /// without noise: the fractional Zener fit evaluates the law there and recovers it on the
    /// real axis to 1e-6 (nothing but the optimiser's tolerance separates them), and its
    /// real-frequency points equal the truth at f_k to 1e-6; the per-mode law's log-slope
    /// continuation does so to 0.1 % (the slope of ln G* varies by about 0.1 over the band, times
    /// ζ). Taken at f_k, the points themselves are more than 1 % off in η.
    #[test]
    fn points_found_at_complex_frequencies_are_moved_to_the_real_axis() {
        let zeta: f64 = 0.015;
        let pts: Vec<ModePoint> = FREQS
            .iter()
            .enumerate()
            .map(|(k, &f)| {
                let at = Complex64::new(f * (1.0 - zeta * zeta).sqrt(), f * zeta);
                ModePoint {
                    freq_hz: f,
                    found_at_hz: at,
                    core_shear_pa: truth().modulus_at_complex(2.0 * PI * at),
                    effects: effects(k),
                    second_order: Vec::new(),
                    noise: vec![("EMA pole".into(), [1e-3, 1e-3])],
                }
            })
            .collect();
        let rel =
            |a: Complex64, b: Complex64| [a.re / b.re - 1.0, (a.im / a.re) / (b.im / b.re) - 1.0];
        let off = rel(pts[2].core_shear_pa, truth().modulus(2.0 * PI * FREQS[2]));
        assert!(off[1] > 0.01, "the continuation is not negligible: {off:?}");
        let fz = fit_core_law(&pts, &priors(), CoreLaw::FractionalZener).unwrap();
        let pm = fit_core_law(&pts, &priors(), CoreLaw::PerMode).unwrap();
        for (k, &f) in FREQS.iter().enumerate() {
            let g = truth().modulus(2.0 * PI * f);
            let law = fz.modulus(f).unwrap();
            for (what, got, tol) in [
                ("law", law, 1e-6),
                ("fz point", fz.real_frequency_points[k], 1e-6),
                ("per-mode point", pm.real_frequency_points[k], 1e-3),
            ] {
                let e = rel(got, g);
                assert!(
                    e[0].abs() < tol && e[1].abs() < tol,
                    "{what} at {f} Hz: {e:?}"
                );
            }
        }
    }

    /// A G0 three orders below every mode's G' (1 kPa against 12–28 MPa) leaves no trace in
    /// the data: the fit names it undetermined and gives it the whole of (0, ∞) rather than
    /// the pseudo-inverse's zero width; the other parameters keep finite intervals.
    #[test]
    fn an_undetermined_parameter_has_no_bound() {
        let law = FractionalZener::new(1e3, 400e6, 2e-5, 0.55).unwrap();
        let pts: Vec<ModePoint> = FREQS
            .iter()
            .enumerate()
            .map(|(k, &f)| ModePoint {
                freq_hz: f,
                found_at_hz: Complex64::new(f, 0.0),
                core_shear_pa: law.modulus(2.0 * PI * f),
                effects: effects(k),
                second_order: Vec::new(),
                noise: vec![("EMA pole".into(), [1e-3, 1e-3])],
            })
            .collect();
        let fit = fit_core_law(&pts, &priors(), CoreLaw::FractionalZener).unwrap();
        assert!(
            fit.undetermined.iter().any(|u| u.contains("g0_pa")),
            "{:?}",
            fit.undetermined
        );
        assert_eq!(fit.parameters[0].ci95, [0.0, f64::INFINITY]);
        for p in &fit.parameters[1..4] {
            assert!(p.sd.is_finite() && p.ci95[1] < f64::INFINITY, "{p:?}");
        }
    }

    /// Points that scatter about the law far beyond their stated noise: the excess is the
    /// data's, so the fit scales their noise (s² = S/ν at the minimum, to 1e-6) and the inputs
    /// keep the weight of their priors; the bands name the excess as their source.
    #[test]
    fn scatter_beyond_the_stated_noise_is_the_datas() {
        let mut rng = Normal::new(5);
        let pts: Vec<ModePoint> = points(&[0.0, 0.0], 0.02, &mut rng)
            .into_iter()
            .map(|mut p| {
                p.noise = vec![("EMA pole".into(), [2e-3, 2e-3])];
                p
            })
            .collect();
        let fit = fit_core_law(&pts, &priors(), CoreLaw::FractionalZener).unwrap();
        assert!(fit.scale > 3.0, "{}", fit.scale);
        let ratio = fit.chi2 / fit.dof as f64;
        assert!((fit.scale.powi(2) / ratio - 1.0).abs() < 1e-6, "{ratio}");
        // The inputs stay within their priors' reach (|δ| < 2 s_j): the scatter is not theirs.
        for (q, p) in fit.inputs().iter().zip(priors()) {
            assert!(q.value.abs() < 2.0 * p.rel_sd, "{q:?}");
        }
        assert!(
            fit.at_modes
                .iter()
                .any(|p| p.dominant.iter().any(|d| d == SCATTER_ABOUT_THE_LAW)),
            "{:?}",
            fit.at_modes
        );
    }

    /// Points and effects taken at inputs δ₀ off nominal (`InputPrior::at`) describe the same
    /// linear model as the nominal ones: the fit finds the same inputs (from nominal) and the
    /// same law, to the optimiser's tolerance.
    #[test]
    fn the_linearisation_point_moves_nothing_in_a_linear_model() {
        let mut rng = Normal::new(9);
        let delta = [0.012, -0.003];
        let nominal = points(&delta, 0.02, &mut rng);
        let at = [0.008, -0.002];
        let moved: Vec<ModePoint> = nominal
            .iter()
            .map(|p| {
                let shift = p.input_shift(&at, &priors());
                let g = log_parts(p.core_shear_pa);
                ModePoint {
                    core_shear_pa: from_log_parts([g[0] + shift[0], g[1] + shift[1]]),
                    ..p.clone()
                }
            })
            .collect();
        let moved_priors: Vec<InputPrior> = priors()
            .into_iter()
            .zip(at)
            .map(|(p, a)| InputPrior { at: a, ..p })
            .collect();
        let a = fit_core_law(&nominal, &priors(), CoreLaw::FractionalZener).unwrap();
        let b = fit_core_law(&moved, &moved_priors, CoreLaw::FractionalZener).unwrap();
        for (x, y) in a.inputs().iter().zip(b.inputs()) {
            assert!((x.value - y.value).abs() < 1e-6, "{x:?} vs {y:?}");
        }
        for (x, y) in a.curve(10).iter().zip(b.curve(10)) {
            assert!((x.storage_pa / y.storage_pa - 1.0).abs() < 1e-6);
            assert!((x.loss_factor / y.loss_factor - 1.0).abs() < 1e-6);
        }
        for (x, y) in a.corrected_points.iter().zip(&b.corrected_points) {
            assert!((x / y - 1.0).norm() < 1e-6, "{x} vs {y}");
        }
    }

    #[test]
    fn refuses_what_cannot_be_fitted() {
        let mut rng = Normal::new(1);
        let pts = points(&[0.0, 0.0], 0.01, &mut rng);
        let e = fit_core_law(&pts[..1], &priors(), CoreLaw::FractionalZener).unwrap_err();
        assert!(e.to_string().contains("4 parameters"), "{e}");
        let mut bad = priors();
        bad[1].rel_sd = 0.0;
        let e = fit_core_law(&pts, &bad, CoreLaw::FractionalZener).unwrap_err();
        assert!(e.to_string().contains("face thickness"), "{e}");
        let mut swapped = pts.clone();
        swapped.swap(0, 1);
        let e = fit_core_law(&swapped, &priors(), CoreLaw::PerMode).unwrap_err();
        assert!(e.to_string().contains("increasing frequency"), "{e}");
        let mut short = pts.clone();
        short[2].effects.pop();
        let e = fit_core_law(&short, &priors(), CoreLaw::PerMode).unwrap_err();
        assert!(e.to_string().contains("mode 3"), "{e}");
        let mut below = pts.clone();
        below[1].found_at_hz = Complex64::new(below[1].freq_hz, -0.1);
        let e = fit_core_law(&below, &priors(), CoreLaw::PerMode).unwrap_err();
        assert!(e.to_string().contains("mode 2 was found"), "{e}");
    }

    /// A Prony core with one term per decade (τ from 100 s to 1 ns, g ∝ τ^−0.25, as published
    /// PVB master curves are written), G* at ω by the closed form, complex ω included.
    fn prony_truth(omega: Complex64) -> Complex64 {
        let i = Complex64::new(0.0, 1.0);
        (0..12).fold(Complex64::new(0.5e6, 0.0), |acc, k| {
            let tau = 10f64.powi(2 - k);
            let x = i * omega * tau;
            acc + 4e6 * tau.powf(-0.25) * x / (1.0 + x)
        })
    }

    /// Eight modes 20–200 Hz of the Prony core, each found at its pole's complex frequency
    /// (ζ = 1 %), 0.5 % stated noise, no inputs: the generalized Maxwell law follows it within
    /// 1 % in G' and η between the first mode and the last (measured 0.88 % and 0.71 %), the
    /// fractional Zener law misses by more than 2 % in G' or 3 % in η (measured 2.2 % and
    /// 4.4 %), and the small-sample Akaike criterion prefers the series; on the fractional
    /// Zener truth of the other tests it prefers the fractional Zener law. The points moved
    /// to the real axis by the series match the truth there within 0.3 %.
    #[test]
    fn generalized_maxwell_follows_a_prony_core_the_fractional_zener_misses() {
        let freqs: Vec<f64> = (0..8).map(|k| 20.0 * 10f64.powf(k as f64 / 7.0)).collect();
        let pts: Vec<ModePoint> = freqs
            .iter()
            .map(|&f| {
                let at = Complex64::new(f, 0.01 * f);
                ModePoint {
                    freq_hz: f,
                    found_at_hz: at,
                    core_shear_pa: prony_truth(2.0 * PI * at),
                    effects: Vec::new(),
                    second_order: Vec::new(),
                    noise: vec![("EMA pole".into(), [0.005, 0.005])],
                }
            })
            .collect();
        let worst = |fit: &CoreLawFit| {
            fit.curve(40).iter().fold([0.0f64; 2], |w, p| {
                let t = prony_truth(Complex64::new(2.0 * PI * p.freq_hz, 0.0));
                [
                    w[0].max((p.storage_pa / t.re - 1.0).abs()),
                    w[1].max((p.loss_factor / (t.im / t.re) - 1.0).abs()),
                ]
            })
        };
        let gm = fit_core_law(&pts, &[], CoreLaw::GeneralizedMaxwell).unwrap();
        let fz = fit_core_law(&pts, &[], CoreLaw::FractionalZener).unwrap();
        let (w_gm, w_fz) = (worst(&gm), worst(&fz));
        assert!(w_gm[0] < 0.01 && w_gm[1] < 0.01, "{w_gm:?}");
        assert!(w_fz[0] > 0.02 || w_fz[1] > 0.03, "{w_fz:?}");
        assert!(
            gm.akaike() < fz.akaike(),
            "{} vs {}",
            gm.akaike(),
            fz.akaike()
        );
        assert_eq!(gm.parameters.len(), 1 + 8);
        for (p, g) in pts.iter().zip(&gm.real_frequency_points) {
            let t = prony_truth(Complex64::new(2.0 * PI * p.freq_hz, 0.0));
            assert!((g / t - 1.0).norm() < 3e-3, "{g} vs {t}");
        }
        let pts = points(&[0.0, 0.0], 0.001, &mut Normal::new(3));
        let gm = fit_core_law(&pts, &priors(), CoreLaw::GeneralizedMaxwell).unwrap();
        let fz = fit_core_law(&pts, &priors(), CoreLaw::FractionalZener).unwrap();
        assert!(
            fz.akaike() < gm.akaike(),
            "{} vs {}",
            fz.akaike(),
            gm.akaike()
        );
    }

    /// The Prony core of the roof's independent check (one term per decade, τ from 100 s to
    /// 1 ns, strengths rising as τ^−0.37: G' 14–22 MPa, η 0.64–0.68 at 17–64 Hz), G* at ω.
    fn roof_prony_truth(omega: Complex64) -> Complex64 {
        let g = [
            3.6394e5, 8.5316e5, 2.0e6, 4.6885e6, 1.0991e7, 2.5765e7, 6.0399e7, 1.4159e8, 3.3192e8,
            7.7809e8, 1.8240e9, 4.2759e9,
        ];
        let i = Complex64::new(0.0, 1.0);
        g.iter()
            .enumerate()
            .fold(Complex64::new(0.3e6, 0.0), |acc, (k, g)| {
                let x = i * omega * 10f64.powi(2 - k as i32);
                acc + g * x / (1.0 + x)
            })
    }

    /// Five modes of the free roof (17–64 Hz) on that Prony core, with the errors and noise the
    /// chain's points had there: the generalized Maxwell law on the four grids a quarter of a
    /// spacing apart matches the modes alike (χ² 0.5–5 on 10 values), but between the modes
    /// the grids part by more than their own bands. Measured: the grids' laws lie up to 2.6 %,
    /// 1.3 %, 0.48 % and 1.9 % off the truth, and three of the four own bands miss it at 21–23 of
    /// 40 lines; with the others as alternatives ([`CoreLawFit::with_alternatives`]) every
    /// grid's band holds it at all 40 lines. The grid of the lowest criterion (the one the
    /// pipeline reports) is the closest, and its band widens at the modes by 1.16 times.
    #[test]
    fn alternatives_hold_the_law_between_the_modes() {
        // Each point off the truth as the chain's were on that roof (64 x 64 truth, face data
        // known): G' and η in per cent.
        let off: [[f64; 2]; 5] = [
            [-0.46, -0.07],
            [-0.21, -0.03],
            [-0.29, 0.17],
            [-1.09, 1.19],
            [-0.34, 0.38],
        ];
        // Their bands' sd (per cent): the 25 and 51 Hz modes are weakly determined.
        let sd: [[f64; 2]; 5] = [
            [0.36, 0.41],
            [1.7, 3.0],
            [0.6, 0.77],
            [1.6, 2.8],
            [0.56, 0.74],
        ];
        let pts: Vec<ModePoint> = [17.19, 25.21, 43.69, 50.95, 64.24]
            .iter()
            .zip(off)
            .zip(sd)
            .map(|((&f, off), sd)| {
                let at = Complex64::new(f, 0.015 * f);
                let t = log_parts(roof_prony_truth(2.0 * PI * at));
                ModePoint {
                    freq_hz: f,
                    found_at_hz: at,
                    core_shear_pa: from_log_parts([
                        t[0] + (0.01 * off[0]).ln_1p(),
                        t[1] + (0.01 * off[1]).ln_1p(),
                    ]),
                    effects: Vec::new(),
                    second_order: Vec::new(),
                    noise: vec![("EMA pole".into(), sd.map(|v| 0.01 * v))],
                }
            })
            .collect();
        let fits: Vec<CoreLawFit> = [0.0, 0.25, 0.5, 0.75]
            .iter()
            .map(|&o| fit_core_law_shifted(&pts, &[], CoreLaw::GeneralizedMaxwell, o).unwrap())
            .collect();
        // Lines whose band misses the truth, and the largest error, per fit.
        let misses = |fit: &CoreLawFit| {
            fit.curve(40).iter().fold((0, 0.0f64), |(n, w), p| {
                let t = roof_prony_truth(Complex64::new(2.0 * PI * p.freq_hz, 0.0));
                let eta = t.im / t.re;
                let inside = (p.storage_ci95[0]..=p.storage_ci95[1]).contains(&t.re)
                    && (p.loss_factor_ci95[0]..=p.loss_factor_ci95[1]).contains(&eta);
                let err = (p.storage_pa / t.re - 1.0)
                    .abs()
                    .max((p.loss_factor / eta - 1.0).abs());
                (n + usize::from(!inside), w.max(err))
            })
        };
        let alone: Vec<(usize, f64)> = fits.iter().map(misses).collect();
        assert!(alone.iter().filter(|m| m.0 > 10).count() >= 2, "{alone:?}");
        let best = (0..4)
            .min_by(|&a, &b| fits[a].akaike().total_cmp(&fits[b].akaike()))
            .unwrap();
        assert!(alone.iter().all(|m| m.1 >= alone[best].1), "{alone:?}");
        for (k, fit) in fits.iter().enumerate() {
            let others: Vec<(f64, CoreLawFit)> = fits
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != k)
                .map(|(_, f)| (f.akaike(), f.clone()))
                .collect();
            let with = fit.clone().with_alternatives(fit.akaike(), others);
            let m = misses(&with);
            let widening: f64 = with
                .at_modes
                .iter()
                .zip(&fit.at_modes)
                .map(|(a, b)| {
                    (a.storage_ci95[1] / a.storage_pa).ln()
                        / (b.storage_ci95[1] / b.storage_pa).ln()
                })
                .fold(0.0, f64::max);
            assert_eq!(m.0, 0, "grid {k}: {m:?}");
            if k == best {
                assert!(widening < 1.3, "{widening}");
            }
        }
    }
}
