//! Each converged mode's 95 % band ([`band`], a [`LayeredBand`]), from four kinds of source
//! ([`crate::band::BandSource`]):
//! - the inputs known within a tolerance (`[uncertainty]`: the faces' modulus, the thicknesses,
//!   the densities, and on supports their stiffness and damping), each through its sensitivity
//!   dG*/d ln θ on the coarsest model at the converged G*
//!   ([`lamdyn_layered::sensitivity`]), to first order: a sensitivity of −20 turns a 1 % face
//!   modulus into 20 % of G', so the bands of a stiff-core laminate are wide and, at tens of
//!   per cent, only roughly normal;
//! - those inputs beyond first order ([`second_order`]): the core found is not linear in the
//!   faces, and the joint law fit, which shares one first-order shift of the inputs among all
//!   modes, must not take a mode's first-order point for more than it is;
//! - the pole's scatter ([`super::pole_scatter`](mod@super::pole_scatter)) through dG* = δλ/(∂λ/∂G);
//! - the discretization: the ladder's residual band, read as a 95 % half-width, and what one
//!   element per layer through the thickness leaves against two
//!   ([`BandSource::ThroughThickness`]: per mode, the G* change the coarsest mesh with two
//!   elements per layer finds at the same pole, |ln G*₂ − ln G*₁| to first order through the
//!   mode's sensitivity, as one standard deviation; the ladder refines in plane only).

use super::pole_scatter::PoleScatter;
use super::setup::input_rel_sd;
use crate::band::{BandSource, CoarsePole, InputEffect, LayeredBand, StorageAndLoss, half_width};
use crate::job::UncertaintyOptions;
use lamdyn_layered::LayeredError;
use lamdyn_layered::convergence::ConvergedMode;
use lamdyn_layered::inverse::{LayeredInverse, LayeredPlate};
use lamdyn_layered::sensitivity::{Input, ModeSensitivity, log_parts, relative_parts};
use num_complex::Complex64;
use rayon::prelude::*;

/// Each input's prior and the coarsest model moved by ±1 sd of each input with a prior below
/// `wide_prior` ([`LawTuning::wide_prior`](super::tuning::LawTuning::wide_prior)), built once for
/// every mode's band ([`band`], [`second_order`]): neither depends on the mode.
pub struct MovedBySd {
    /// Per input: its prior's relative sd ([`input_rel_sd`]) and the models at +1 sd and
    /// −1 sd (none for a wide or zero prior, or a move that failed).
    models: Vec<(Input, f64, Option<[LayeredInverse; 2]>)>,
}

impl MovedBySd {
    /// The moves of `coarsest` by the priors of `plate`'s inputs in `priors`.
    pub fn build(
        coarsest: &LayeredInverse,
        plate: &LayeredPlate,
        priors: &UncertaintyOptions,
        wide_prior: f64,
    ) -> Self {
        let models = coarsest
            .inputs()
            .into_par_iter()
            .map(|input| {
                let sd = input_rel_sd(input, plate, priors);
                let moved = (sd > 0.0 && sd < wide_prior)
                    .then(|| {
                        let at = |sign: f64| coarsest.with_inputs_moved(&[(input, sign * sd)]).ok();
                        Some([at(1.0)?, at(-1.0)?])
                    })
                    .flatten();
                (input, sd, moved)
            })
            .collect();
        Self { models }
    }

    /// The models at ±1 sd of `input`, if it has them.
    fn of(&self, input: Input) -> Option<&[LayeredInverse; 2]> {
        self.models
            .iter()
            .find(|(i, _, _)| *i == input)
            .and_then(|(_, _, m)| m.as_ref())
    }

    /// The relative sd of the prior on `input` (0 for an input the model has no derivative for).
    fn rel_sd(&self, input: Input) -> f64 {
        self.models
            .iter()
            .find(|(i, _, _)| *i == input)
            .map_or(0.0, |(_, sd, _)| *sd)
    }
}

/// The band of one converged mode (module docs).
pub fn band(
    (coarsest, thick): (&LayeredInverse, Option<&LayeredInverse>),
    moved: &MovedBySd,
    mode: &ConvergedMode,
    target: Complex64,
    scatter: PoleScatter,
    supports_at: [f64; 2],
) -> std::result::Result<LayeredBand, LayeredError> {
    // At the converged G*, about the coarsest model's own eigenvalue there: the ladder
    // corrects that model by a factor per mode, and its relative sensitivities there agree
    // with a 21 x 21 mesh's within 6 % on the demo roof (at its own, coarse solution they fall
    // 5-40 % short; example roof_sensitivity).
    let rank = mode.rank;
    let g0 = mode.core_shear_pa;
    // The coarsest model's pole at G*, the dashpots at its own frequency: what its inverse
    // maps back to G* (the moved models' inverses below start from it).
    let at = coarsest
        .pole_eigenvalue(g0, rank, target)
        .ok_or_else(|| LayeredError::Solver(format!("mode {} lost", rank + 1)))?;
    let sens: ModeSensitivity = coarsest.sensitivity(g0, rank, at)?;
    // A change of the measured eigenvalue acts through the corrected model λ_∞ = (λ_∞/λ_c) λ_c.
    let to_model = at / target;
    let inputs: Vec<InputEffect> = sens
        .inputs
        .iter()
        .map(|e| InputEffect {
            input: e.input,
            rel_sd: moved.rel_sd(e.input),
            effect: StorageAndLoss::from_array(log_parts(e.dg_dln, g0)),
        })
        .collect();
    let inputs_at = sens
        .inputs
        .iter()
        .map(|e| match e.input {
            Input::SupportStiffness => supports_at[0],
            Input::SupportDamping => supports_at[1],
            _ => 0.0,
        })
        .collect();
    let mut sources: Vec<(BandSource, StorageAndLoss)> = inputs
        .iter()
        .map(|i| {
            let sd = i.rel_sd;
            (BandSource::Input(i.input), i.effect.map(|x| (x * sd).abs()))
        })
        .collect();
    // λ = ω²(1 + iη), η = 2ζ: δλ = 2λ δf/f from the frequency, i Re λ 2δζ from the damping.
    let f = target.re.sqrt() / (2.0 * std::f64::consts::PI);
    let pole_source = |[sd_f, sd_zeta]: [f64; 2]| {
        let from_f = relative_parts(
            sens.dg_for_eigenvalue(to_model * target * (2.0 * sd_f / f)),
            g0,
        );
        let from_zeta = relative_parts(
            sens.dg_for_eigenvalue(to_model * Complex64::new(0.0, 2.0 * target.re * sd_zeta)),
            g0,
        );
        StorageAndLoss::new(from_f[0].hypot(from_zeta[0]), from_f[1].hypot(from_zeta[1]))
    };
    if let Some(sd) = scatter.noise {
        sources.push((BandSource::EmaPole, pole_source(sd)));
    }
    if let Some(sd) = scatter.hits {
        sources.push((BandSource::HitsLeftOut, pole_source(sd)));
    }
    if let Some(l) = thick.and_then(|t| through_thickness_eigenvalue(t, g0, rank, at)) {
        // The one-element model is stiffer by λ₁ − λ₂: the G* a measured pole finds on it is
        // off by the dG that change of eigenvalue maps to.
        let dg = sens.dg_for_eigenvalue(at - l);
        sources.push((
            BandSource::ThroughThickness,
            StorageAndLoss::from_array(log_parts(dg, g0).map(f64::abs)),
        ));
    }
    let curvature = second_order(moved, &sens, &inputs, at, g0);
    let second_order: Vec<StorageAndLoss> = curvature
        .iter()
        .map(|c| StorageAndLoss::from_array(c.second))
        .collect();
    let [modelled, beyond] = second_order_sd(&inputs, &curvature);
    sources.push((
        BandSource::InputsBeyondFirstOrder,
        StorageAndLoss::from_array(modelled),
    ));
    sources.push((
        BandSource::InputsBeyondSecondOrder,
        StorageAndLoss::from_array(beyond),
    ));
    sources.push((
        BandSource::Discretization,
        StorageAndLoss::new(mode.storage_band / 1.96, mode.loss_band / 1.96),
    ));
    Ok(LayeredBand {
        half_width: half_width(&sources),
        sources,
        inputs,
        second_order,
        inputs_at,
        found_at_hz: target.sqrt() / (2.0 * std::f64::consts::PI),
        found_pa: g0,
        coarse: CoarsePole {
            rank,
            eigenvalue: at,
        },
    })
}

/// The eigenvalue at `g` of the mode of `thick` nearest `at` among elastic ranks `rank` − 1 ..=
/// `rank` + 1 (two elements through a layer can swap a close pair's order), within 1 % of
/// it; `None` otherwise.
fn through_thickness_eigenvalue(
    thick: &LayeredInverse,
    g: Complex64,
    rank: usize,
    at: Complex64,
) -> Option<Complex64> {
    (rank.saturating_sub(1)..=rank + 1)
        .filter_map(|r| thick.pole_eigenvalue(g, r, at))
        .min_by(|a, b| (a - at).norm().total_cmp(&(b - at).norm()))
        .filter(|l| (l - at).norm() <= 0.01 * at.norm())
}

/// The second order of the inputs' effect on a mode's core, per input: ∂²ln x/∂(ln θ_j)² for x = G'
/// and η (the "inputs beyond first order" of [`LayeredBand`]). Each input j with a prior s_j below
/// the wide prior (the wide ones are re-linearised by [`super::law::fit_law`] instead) is moved by
/// ±s_j on the coarsest model (once for all modes, [`MovedBySd`]) and the mode's coarse eigenvalue
/// inverted there: the second difference d_j = ln x₊ + ln x₋ − 2 ln x₀ gives d_j/s_j². On a glass
/// laminate the core found is far from linear in the faces: on the small test laminate a 1 % face
/// modulus moves G' at its 103 Hz mode by −10.9 % to first order with a second difference of −3.8 %
/// (η: −26.7 % and +8.0 %), and with the faces drawn from their priors the first-order points
/// missed the truth by up to 2.5 % in G' where their other sources said 0.4 %. The joint law fit
/// models this term through one curvature along the inputs' combined shift
/// ([`lamdyn_fit::joint::shared_curvature`]: the differences of the face inputs are one curvature
/// times their e_j², and summed input by input without the cross terms they moved the points
/// further from the truth than the first order alone); the per-mode band takes its root mean square
/// over the priors ([`second_order_sd`]) as a source. An input whose moved inversion fails gets
/// zero.
fn second_order(
    moved: &MovedBySd,
    sens: &ModeSensitivity,
    inputs: &[InputEffect],
    at: Complex64,
    g0: Complex64,
) -> Vec<InputCurvature> {
    let log = |x: Complex64| [x.re.ln(), (x.im / x.re).ln()];
    let c = log(g0);
    sens.inputs
        .iter()
        .zip(inputs)
        .map(|(e, i)| {
            let (sd, first) = (i.rel_sd, i.effect.to_array());
            let Some([up, down]) = moved.of(e.input) else {
                return InputCurvature::default();
            };
            let found = |m: &LayeredInverse| -> Option<[f64; 2]> {
                let g = m.invert(at, g0).ok()?.core_shear_pa;
                (g.re > 0.0 && g.im > 0.0).then(|| log(g))
            };
            match (found(up), found(down)) {
                (Some(p), Some(m)) => InputCurvature {
                    second: [0, 1].map(|k| (p[k] + m[k] - 2.0 * c[k]) / (sd * sd)),
                    third_at_sd: [0, 1].map(|k| 0.5 * (p[k] - m[k]) - first[k] * sd),
                },
                _ => InputCurvature::default(),
            }
        })
        .collect()
}

/// One input's effect on a mode's core beyond first order, from its ±1 sd moves
/// ([`second_order`]); zero where it was not taken.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct InputCurvature {
    /// ∂²ln x/∂(ln θ)² for x = G', η: the second difference over s².
    second: [f64; 2],
    /// The odd part the first order leaves at 1 sd, ½(ln x₊ − ln x₋) − e s: the third-order
    /// term x⁽³⁾ s³/6 (and the first order's own error).
    third_at_sd: [f64; 2],
}

/// The standard deviations (G', η) of what the inputs do beyond first order under their
/// priors, δ_j ~ N(0, s_j²), as two sources:
/// - **modelled** by the joint law fit: ½ κ u² with u = Σ_j e_j δ_j, σ_u² = Σ_j (e_j s_j)² over
///   the inputs with a second order and κ the curvature along u
///   ([`lamdyn_fit::joint::shared_curvature`]); its root mean square is (√3/2)|κ| σ_u²;
/// - **not modelled**, the point's own noise in that fit: what the one curvature leaves of each
///   input's second difference, (√3/2)|c_j − κ e_j²| s_j², and its third order at 1 sd t_j
///   ([`InputCurvature::third_at_sd`]: t_j z³ with z ~ N(0, 1), root mean square √15 |t_j|),
///   in quadrature. A mode whose core is far from quadratic in the inputs (a mode the faces
///   move by tens of per cent per sd) so weighs less in the law, instead of pulling the
///   shared inputs by a slope that holds only near nominal.
fn second_order_sd(inputs: &[InputEffect], curvature: &[InputCurvature]) -> [[f64; 2]; 2] {
    let effects: Vec<[f64; 2]> = inputs.iter().map(|i| i.effect.to_array()).collect();
    let sds: Vec<f64> = inputs.iter().map(|i| i.rel_sd).collect();
    let second: Vec<[f64; 2]> = curvature.iter().map(|c| c.second).collect();
    let kappa = lamdyn_fit::joint::shared_curvature(&effects, &second, &sds);
    let parts = [0, 1].map(|k| {
        let (mut var_u, mut rest) = (0.0, 0.0);
        for (j, ((e, s), c)) in effects.iter().zip(&sds).zip(curvature).enumerate() {
            if !lamdyn_fit::joint::has_second_order(&second, j) {
                continue;
            }
            var_u += (e[k] * s).powi(2);
            rest += 0.75 * ((c.second[k] - kappa[k] * e[k] * e[k]) * s * s).powi(2)
                + THIRD_ORDER_MOMENT * c.third_at_sd[k].powi(2);
        }
        [(0.75 * (kappa[k] * var_u).powi(2)).sqrt(), rest.sqrt()]
    });
    [[parts[0][0], parts[1][0]], [parts[0][1], parts[1][1]]]
}

/// E(z⁶) = 15 for z ~ N(0, 1): the mean square of the third-order remainder t z³ at δ = z s
/// ([`second_order_sd`]). An odd part that is the first order's own error instead (t z) would
/// have mean square t², so this is the conservative reading of the two; on the in-band foam
/// roof 1 instead of 15 left the bands within 1 % of their width (the remainder that matters
/// there is the curvature's, not the odd part's).
const THIRD_ORDER_MOMENT: f64 = 15.0;
