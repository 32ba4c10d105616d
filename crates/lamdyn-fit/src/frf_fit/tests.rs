//! The FRF fit on a small modal model with a known core: exact recovery, and its errors.

use super::*;
use faer::c64;
use lamdyn_frf::Channel;
use std::f64::consts::PI;

/// Three modes whose stiffness is k_e,k + s k_c,k (different core shares), two sensors, two
/// references: H_cr = Σ_k φ_ck φ_rk/(k_e,k + s k_c,k − ω²).
struct Modal {
    k_e: [f64; 3],
    k_c: [f64; 3],
    phi: [[f64; 3]; 2],
}

impl Modal {
    fn new() -> Self {
        let w = |f: f64| (2.0 * PI * f).powi(2);
        Self {
            k_e: [w(30.0), w(70.0), w(120.0)],
            k_c: [0.3 * w(30.0), 0.5 * w(70.0), 0.2 * w(120.0)],
            phi: [[1.0, 0.7, -0.4], [0.5, -0.9, 0.8]],
        }
    }
}

impl CoreFrfModel for Modal {
    fn n_sensors(&self) -> usize {
        2
    }
    fn n_references(&self) -> usize {
        2
    }
    fn receptance(&self, omega: f64, s: Complex64) -> Result<LineReceptance, FitError> {
        self.receptance_with_inputs(omega, s, &[])
    }
    /// One input: the modal stiffness k_e (the faces' modulus), scaled by e^δ.
    fn inputs(&self) -> Vec<Input> {
        vec![Input::FaceModulus]
    }
    fn receptance_with_inputs(
        &self,
        omega: f64,
        s: Complex64,
        deltas: &[f64],
    ) -> Result<LineReceptance, FitError> {
        let face = deltas.first().map_or(1.0, |d| d.exp());
        let mut h = Mat::<c64>::zeros(2, 2);
        let mut dh = Mat::<c64>::zeros(2, 2);
        let mut dface = Mat::<c64>::zeros(2, 2);
        for k in 0..3 {
            let z = face * self.k_e[k] + s * self.k_c[k] - omega * omega;
            for c in 0..2 {
                for r in 0..2 {
                    let a = self.phi[c][k] * self.phi[r][k] / z;
                    let d = -a * self.k_c[k] / z;
                    let e = -a * face * self.k_e[k] / z;
                    h[(c, r)] += c64::new(a.re, a.im);
                    dh[(c, r)] += c64::new(d.re, d.im);
                    dface[(c, r)] += c64::new(e.re, e.im);
                }
            }
        }
        Ok(LineReceptance {
            h,
            dh_ds: dh,
            dh_dinputs: if deltas.is_empty() {
                Vec::new()
            } else {
                vec![dface]
            },
        })
    }
}

fn channels(prefix: &str) -> Vec<Channel> {
    (0..2)
        .map(|k| {
            Channel::new(
                format!("{prefix}{k}"),
                [k as f64, 0.0, 0.0],
                [0.0, 0.0, 1.0],
            )
            .unwrap()
        })
        .collect()
}

/// Accelerance of `model` with the core `law(u)` and gains `gains` at `freqs`.
fn data(model: &Modal, law: &FrfLaw, u: &[f64], gains: [f64; 2], freqs: &[f64]) -> FrfSet {
    data_with_face(model, law, u, gains, freqs, 0.0)
}

/// [`data`] with the faces' modulus changed by e^`face`.
fn data_with_face(
    model: &Modal,
    law: &FrfLaw,
    u: &[f64],
    gains: [f64; 2],
    freqs: &[f64],
    face: f64,
) -> FrfSet {
    let mut values = Vec::new();
    for c in 0..2 {
        for r in 0..2 {
            for &f in freqs {
                let w = 2.0 * PI * f;
                let s = law.modulus(u, w) / G_A;
                let h = model.receptance_with_inputs(w, s, &[face]).unwrap().h[(c, r)];
                values.push(-w * w * gains[r] * Complex64::new(h.re, h.im));
            }
        }
    }
    FrfSet::new(
        freqs.to_vec(),
        channels("s"),
        channels("h"),
        Quantity::Accelerance,
        values,
    )
    .unwrap()
}

const G_A: f64 = 1e6;

fn zener_truth() -> Vec<f64> {
    vec![(0.4e6f64).ln(), (30e6f64).ln(), (2e-4f64).ln(), 0.4]
}

/// A Prony core on the fit's own relaxation times, G' 0.5–5 MPa and η 0.4–1 over the band.
fn prony_truth(law: &FrfLaw) -> Vec<f64> {
    (0..law.n_params())
        .map(|k| (0.3e6 * 1.8f64.powi(k as i32)).ln())
        .collect()
}

fn freqs() -> Vec<f64> {
    (0..300).map(|k| 10.0 + 0.5 * k as f64).collect()
}

/// Noise-free data of the same law family, from the grid's starts (no start curve), the modes
/// damped and overlapping: the FRFs are matched within 3e-4 relative RMS and the law over
/// 40–150 Hz and the gains' ratio come back within 1e-3 (measured: FRFs 1.55e-4, gains 4e-5,
/// the law 2e-4 at 40 Hz). The iteration stops there ("no step lowers the cost") rather than at the
/// misfit's 1e-6 floor: the Prony terms trade against each other where the FRFs hardly see
/// the core; closing that gap is open work.
#[test]
fn recovers_a_known_core_and_the_gains() {
    let model = Modal::new();
    let law = FrfLaw::generalized_maxwell_over(10.0, 160.0);
    let truth = prony_truth(&law);
    let set = data(&model, &law, &truth, [1.0, 1.07], &freqs());
    let fit = fit_core_to_frfs(
        &model,
        &set,
        law.clone(),
        G_A,
        None,
        &FrfFitSettings::over([10.0, 160.0]),
    )
    .unwrap();
    for f in [40.0, 60.0, 100.0, 150.0] {
        let (a, b) = (fit.modulus(f), law.modulus(&truth, 2.0 * PI * f));
        assert!(
            (a / b - 1.0).norm() < 1e-3,
            "{f} Hz: {a} vs {b}; {}",
            fit.describe()
        );
    }
    assert!(
        (fit.gains[1] / fit.gains[0] - 1.07).abs() < 1e-3 && fit.relative_rms < 3e-4,
        "gains {:?}; relative RMS {:.2e}; {}",
        fit.gains,
        fit.relative_rms,
        fit.describe()
    );
}

/// The faces' modulus 3 % off the model's, fitted under a 5 % prior beside the law: the
/// change comes back within 1e-3 and the law within 1e-3 (noise-free data; the prior's pull
/// is the prior row against data rows on a 1e-6 noise scale, negligible). An input the model
/// holds no derivative for is refused by name.
#[test]
fn fits_an_input_under_its_prior() {
    let model = Modal::new();
    let law = FrfLaw::generalized_maxwell_over(10.0, 160.0);
    let truth = prony_truth(&law);
    let set = data_with_face(&model, &law, &truth, [1.0, 1.0], &freqs(), 1.03f64.ln());
    let mut settings = FrfFitSettings::over([10.0, 160.0]);
    settings.inputs = vec![InputPrior {
        input: Input::FaceModulus,
        sd: 0.05,
    }];
    let fit = fit_core_to_frfs(&model, &set, law.clone(), G_A, None, &settings).unwrap();
    let face = fit.inputs[0];
    assert!(
        (face.change - 0.03).abs() < 1e-3,
        "{face:?}; {}",
        fit.describe()
    );
    assert!(face.sd < face.prior_sd, "{face:?}");
    for f in [40.0, 100.0, 150.0] {
        let (a, b) = (fit.modulus(f), law.modulus(&truth, 2.0 * PI * f));
        assert!((a / b - 1.0).norm() < 1e-3, "{f} Hz: {a} vs {b}");
    }
    settings.inputs[0].input = Input::CoreDensity;
    let e = fit_core_to_frfs(&model, &set, law, G_A, None, &settings).unwrap_err();
    assert!(e.to_string().contains("'core density'"), "{e}");
}

/// The law with the inputs held, to first order from the answer, against the law fitted again
/// with the input held (noise-free data with the faces' modulus 0.3 % off the model's; the law
/// takes the whole change up and moves 4–19 %, this model's core being a small share of its
/// modes' stiffness): the first order gets the move's size, which is what a band needs, within
/// 30 % of it over the band (measured 2026-11-29: 5–23 %, its second order).
#[test]
fn the_law_with_the_inputs_held_is_the_refit_to_first_order() {
    let model = Modal::new();
    let law = FrfLaw::FractionalZener;
    let truth = zener_truth();
    let set = data_with_face(&model, &law, &truth, [1.0, 1.0], &freqs(), 1.003f64.ln());
    let mut settings = FrfFitSettings::over([10.0, 160.0]);
    settings.inputs = vec![InputPrior {
        input: Input::FaceModulus,
        sd: 0.05,
    }];
    let fit = fit_core_to_frfs(&model, &set, law.clone(), G_A, None, &settings).unwrap();
    let curve = |w: f64| fit.modulus(w / (2.0 * PI));
    settings.inputs.clear();
    settings.starts = 0;
    let refit = fit_core_to_frfs(&model, &set, law, G_A, Some(&curve), &settings).unwrap();
    let mut largest = 0.0f64;
    for f in [15.0, 30.0, 45.0, 60.0, 80.0, 100.0, 120.0, 140.0, 160.0] {
        let (g, held) = (fit.modulus(f), fit.modulus_inputs_held(f).unwrap());
        let moved = refit.modulus(f) / g - 1.0;
        largest = largest.max(moved.norm());
        let off = (held / refit.modulus(f) - 1.0).norm();
        assert!(
            off < 0.3 * moved.norm(),
            "{f} Hz: moved {moved}, first order off by {off}"
        );
    }
    assert!(
        largest > 1e-3,
        "the input's take-up is too small to test: {largest}"
    );
    let free = fit_core_to_frfs(
        &model,
        &set,
        FrfLaw::FractionalZener,
        G_A,
        None,
        &FrfFitSettings::over([10.0, 160.0]),
    )
    .unwrap();
    assert!(free.inputs_held_step.is_none());
}

/// Every refusal names its cause: too few lines for the parameters, channel counts unlike
/// the model's, all-zero data, and a fit cut off before it settles (how far it got).
#[test]
fn refusals_name_their_cause() {
    let model = Modal::new();
    let law = FrfLaw::FractionalZener;
    let set = data(&model, &law, &zener_truth(), [1.0, 1.0], &freqs());
    let fit = |set: &FrfSet, settings: &FrfFitSettings| {
        fit_core_to_frfs(&model, set, law.clone(), G_A, None, settings)
            .unwrap_err()
            .to_string()
    };
    let few = fit(&set, &FrfFitSettings::over([10.0, 12.0]));
    assert!(
        few.contains("5 line(s)") && few.contains("fewer than the 6"),
        "{few}"
    );
    let one = set.with_responses(&[0]).unwrap();
    let counts = fit(&one, &FrfFitSettings::over([10.0, 160.0]));
    assert!(
        counts.contains("1 response(s) × 2 reference(s), the model 2 × 2"),
        "{counts}"
    );
    let zero = FrfSet::new(
        freqs(),
        channels("s"),
        channels("h"),
        Quantity::Accelerance,
        vec![Complex64::new(0.0, 0.0); 4 * freqs().len()],
    )
    .unwrap();
    let zeros = fit(&zero, &FrfFitSettings::over([10.0, 160.0]));
    assert!(zeros.contains("zero in the band"), "{zeros}");
    let mut short = FrfFitSettings::over([10.0, 160.0]);
    short.lm.max_iterations = 1;
    short.starts = 1;
    let cut = fit(&set, &short);
    assert!(
        cut.contains("did not settle in 1 iterations") && cut.contains("move together"),
        "{cut}"
    );
}

/// `set` with complex Gaussian noise of `rel` × each curve's RMS added (a fixed xorshift
/// sequence and Box–Muller: the same draws on every machine).
fn noisy(set: &FrfSet, rel: f64, seed: u64) -> FrfSet {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut uniform = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut values = Vec::new();
    for c in 0..set.responses().len() {
        for r in 0..set.references().len() {
            let curve = set.curve(c, r);
            let rms = (curve.iter().map(|v| v.norm_sqr()).sum::<f64>() / curve.len() as f64).sqrt();
            for v in curve {
                let (a, b) = (uniform(), uniform());
                let radius = (-2.0 * a.ln()).sqrt() * rel * rms / 2f64.sqrt();
                let phase = 2.0 * PI * b;
                values.push(v + Complex64::from_polar(radius, phase));
            }
        }
    }
    FrfSet::new(
        set.freqs_hz().to_vec(),
        set.responses().to_vec(),
        set.references().to_vec(),
        set.quantity(),
        values,
    )
    .unwrap()
}

/// Both laws fitted to the same noisy FRFs (1 % of each curve's RMS), the second started from
/// the first's curve alone: a fractional Zener core keeps the four-parameter law (the Prony
/// series buys no misfit its extra terms are worth), a core with two separate loss peaks, which
/// no fractional Zener law follows, keeps the Prony series.
#[test]
fn akaike_keeps_the_law_the_data_need() {
    let model = Modal::new();
    let band = [10.0, 160.0];
    let prony = FrfLaw::generalized_maxwell_over(band[0], band[1]);
    let both = |set: &FrfSet| {
        let settings = FrfFitSettings::over(band);
        let gm = fit_core_to_frfs(&model, set, prony.clone(), G_A, None, &settings).unwrap();
        let curve = |w: f64| gm.modulus(w / (2.0 * PI));
        let alone = FrfFitSettings {
            starts: 0,
            ..settings
        };
        let fz = fit_core_to_frfs(
            &model,
            set,
            FrfLaw::FractionalZener,
            G_A,
            Some(&curve),
            &alone,
        )
        .unwrap();
        let choice = compare_laws(&[&gm, &fz]).unwrap();
        eprintln!("{choice:?}\n  {}\n  {}", gm.describe(), fz.describe());
        (choice, gm, fz)
    };
    let zener = noisy(
        &data(
            &model,
            &FrfLaw::FractionalZener,
            &zener_truth(),
            [1.0, 1.0],
            &freqs(),
        ),
        0.01,
        7,
    );
    let (choice, gm, fz) = both(&zener);
    assert_eq!(
        choice.chosen,
        1,
        "{choice:?}; {}; {}",
        gm.describe(),
        fz.describe()
    );
    // Two loss peaks (the terms relaxing near 20 and 365 Hz, outside the modes at 30–120 Hz)
    // on a small equilibrium modulus: η falls from the first mode and rises again to the
    // third, a valley no fractional Zener law has.
    let mut two_peaks = vec![(0.2e6f64).ln(); prony.n_params()];
    let FrfLaw::GeneralizedMaxwell { taus } = &prony else {
        unreachable!()
    };
    for (k, tau) in taus.iter().enumerate() {
        let f = 1.0 / (2.0 * PI * tau);
        if (f / 20.0).ln().abs() < 0.4 || (f / 365.0).ln().abs() < 0.4 {
            two_peaks[1 + k] = (4e6f64).ln();
        } else {
            two_peaks[1 + k] = (0.05e6f64).ln();
        }
    }
    let peaks = noisy(
        &data(&model, &prony, &two_peaks, [1.0, 1.0], &freqs()),
        0.01,
        8,
    );
    let (choice, gm, fz) = both(&peaks);
    assert_eq!(
        choice.chosen,
        0,
        "{choice:?}; {}; {}",
        gm.describe(),
        fz.describe()
    );
    let other = FrfFit {
        residuals: gm.residuals + 2,
        ..gm.clone()
    };
    let refused = compare_laws(&[&gm, &other]).unwrap_err().to_string();
    assert!(refused.contains("different data"), "{refused}");
}

/// The bands hold where the noise does not follow the weights: noise of 2 % of each curve's RMS
/// (a floor constant along the curve, as a sensor's) against weights relative to the curve's
/// local level. Forty seeds of a fractional Zener core fitted with its own law (no error of
/// form): the truth inside the 95 % band of G' and of η at ≥ 90 % of 8 frequencies over the
/// modes (320 points: 95 % less two binomial sds is 92.6 %), and the scatter of ln G' over the
/// seeds within 25 % of the bands' mean sd.
#[test]
fn bands_hold_noise_that_does_not_follow_the_weights() {
    let model = Modal::new();
    let band = [10.0, 160.0];
    let law = FrfLaw::FractionalZener;
    let truth = zener_truth();
    let clean = data(&model, &law, &truth, [1.0, 1.0], &freqs());
    let settings = FrfFitSettings {
        starts: 0,
        ..FrfFitSettings::over(band)
    };
    let at: Vec<f64> = (0..8).map(|k| 30.0 * 4f64.powf(k as f64 / 7.0)).collect();
    let core = |w: f64| law.modulus(&truth, w);
    let (mut covered, mut total) = ([0usize; 2], 0usize);
    let mut ln_storage: Vec<Vec<f64>> = vec![Vec::new(); at.len()];
    let mut band_sd = vec![0.0; at.len()];
    let seeds = 40;
    for seed in 0..seeds {
        let set = noisy(&clean, 0.02, 100 + seed);
        let fit = fit_core_to_frfs(&model, &set, law.clone(), G_A, Some(&core), &settings).unwrap();
        for (k, &f) in at.iter().enumerate() {
            let (p, t) = (fit.at(f), core(2.0 * PI * f));
            let eta = t.im / t.re;
            covered[0] += usize::from(p.storage_ci95[0] <= t.re && t.re <= p.storage_ci95[1]);
            covered[1] += usize::from(p.loss_factor_ci95[0] <= eta && eta <= p.loss_factor_ci95[1]);
            ln_storage[k].push((p.storage_pa / t.re).ln());
            band_sd[k] += (p.storage_ci95[1] / p.storage_ci95[0]).ln() / 3.92 / seeds as f64;
            total += 1;
        }
    }
    let rate = covered.map(|c| c as f64 / total as f64);
    let ratios: Vec<f64> = ln_storage
        .iter()
        .zip(&band_sd)
        .map(|(x, sd)| {
            let mean = x.iter().sum::<f64>() / x.len() as f64;
            let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (x.len() - 1) as f64;
            var.sqrt() / sd
        })
        .collect();
    eprintln!(
        "coverage G' {:.3}, eta {:.3}; scatter / band sd of ln G' {ratios:.2?}",
        rate[0], rate[1]
    );
    assert!(rate[0] >= 0.9 && rate[1] >= 0.9, "{rate:?}");
    assert!(
        ratios.iter().all(|r| (0.8..1.25).contains(r)),
        "{ratios:.2?}"
    );
}

/// A parameter is determined by a narrow interval and information of its own: a weight driven
/// to zero has none, and the pseudo-inverse's zero variance for it is no interval.
#[test]
fn a_parameter_the_data_do_not_see_is_not_determined() {
    assert!(determined(0.1, 1.0, 1.0));
    assert!(!determined(1.2, 1.0, 1.0));
    assert!(!determined(0.0, 0.0, 1.0));
    assert!(!determined(0.0, 1e-14, 1.0));
}
