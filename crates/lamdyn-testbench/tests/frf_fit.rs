//! The core's law fitted to FRFs through the layered model (lamdyn_fit::frf_fit) on virtual
//! tests whose truth is a finer, edge-graded mesh than the identification's.

#[path = "common/glass_plate.rs"]
mod glass_plate;

use glass_plate::{bench, glass_plate, layered_plate, observed};
use lamdyn_fit::frf_fit::{FrfFit, FrfFitSettings, FrfLaw, InputPrior, fit_core_to_frfs};
use lamdyn_frf::FrfSet;
use lamdyn_layered::frf::{FrfBasis, MeasuredPoint, ObservedModel};
use lamdyn_layered::probe::SurfaceProbe;
use lamdyn_layered::reduced::DirectSolver;
use lamdyn_layered::sensitivity::Input;
use lamdyn_testbench::description::Bench;
use num_complex::Complex64;
use std::f64::consts::PI;
use std::time::Instant;

fn worst_errors(fit: &FrfFit, truth: &Bench, freqs: &[f64]) -> (f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    for &f in freqs {
        let t = truth.core_law.modulus(2.0 * PI * f);
        let p = fit.at(f);
        worst.0 = worst.0.max((p.storage_pa / t.re - 1.0).abs());
        worst.1 = worst.1.max((p.loss_factor / (t.im / t.re) - 1.0).abs());
    }
    worst
}

/// Damped, overlapping modes (modal damping 3–19 %, 20 elastic modes below 210 Hz, one
/// hammer, 42 triaxial sensors): the law from the FRFs of a finer, edge-graded mesh (24 × 18)
/// with 1 % noise, identified on an 18 × 14 mesh, within 3 % in G' and 5 % in η over 25–200
/// Hz (measured: 2.4 % and 1.9 %, the model's discretization error the main part: the
/// identification mesh at the true law is 0.4–2 % off the exact FRFs, and 12 × 9 put G' 9 %
/// low at the top of the band). The bands do not hold the discretization error yet (no mesh
/// ladder here): they are not asserted.
#[test]
fn damped_glass_plate_core_from_frfs() {
    let t0 = Instant::now();
    let truth = bench(&glass_plate([24, 18], 0.2, [7, 6], Some(40.0), 3));
    let set = truth.frfs().unwrap();
    let modal: Vec<Complex64> = truth
        .model
        .complex_eigenvalues(truth.core_scale(2.0 * PI * 80.0));
    let elastic: Vec<(f64, f64)> = modal
        .iter()
        .filter(|l| l.re > (2.0 * PI * 5.0).powi(2))
        .map(|l| (l.re.sqrt() / (2.0 * PI), 0.5 * l.im / l.re))
        .filter(|m| m.0 < 210.0)
        .collect();
    eprintln!(
        "truth {:.1?}: modes (f, zeta at 80 Hz core) {elastic:.3?}",
        t0.elapsed()
    );
    let coarse = bench(&glass_plate([18, 14], 0.0, [7, 6], None, 3));
    let g_a = coarse.assembled_modulus_pa;
    let t1 = Instant::now();
    let model = observed(&coarse, &set, &[0.5, 2.0], 30);
    eprintln!("basis {} in {:.1?}", model.basis_size(), t1.elapsed());
    // The basis against full solves of the same mesh at the true law, to the band's top
    // (measured 2.9e-5 at 25 Hz, 6.2e-4 at 80 Hz, 4.3e-3 at 150 Hz, 1.4e-2 at 205 Hz).
    let direct = DirectSolver::new(&coarse.system, &coarse.core_layers).unwrap();
    let hammer = &set.references()[0];
    let load = SurfaceProbe::locate(&coarse.mesh, hammer.point_m, hammer.direction, 1e-6, "h")
        .unwrap()
        .load(coarse.system.n_dofs);
    let dofs: Vec<usize> = (0..coarse.system.n_dofs).step_by(97).collect();
    for (f, bound) in [(25.0, 1e-4), (80.0, 2e-3), (150.0, 1e-2), (205.0, 3e-2)] {
        let w = 2.0 * PI * f;
        let s = truth.core_law.modulus(w) / g_a;
        let exact = direct.response(&load, w, s, &dofs).unwrap();
        let reduced = model
            .model()
            .response(&model.model().project_load(&load), w, s, &dofs);
        let num: f64 = exact
            .iter()
            .zip(&reduced)
            .map(|(x, y)| (x - y).norm_sqr())
            .sum();
        let den: f64 = exact.iter().map(|x| x.norm_sqr()).sum();
        let e = (num / den).sqrt();
        eprintln!("basis against the full solve at {f} Hz: {e:.2e}");
        assert!(e < bound, "{f} Hz: {e:.2e}");
    }
    let band = [20.0, 210.0];
    let law = FrfLaw::generalized_maxwell_over(band[0], band[1]);
    let t2 = Instant::now();
    let fit = fit_core_to_frfs(&model, &set, law, g_a, None, &FrfFitSettings::over(band)).unwrap();
    eprintln!("fit {:.1?}: {}", t2.elapsed(), fit.describe());
    let freqs: Vec<f64> = (0..40).map(|k| 25.0 + 175.0 * k as f64 / 39.0).collect();
    for &f in freqs.iter().step_by(6) {
        let t = truth.core_law.modulus(2.0 * PI * f);
        let p = fit.at(f);
        eprintln!(
            "{f:6.1} Hz: G' {:.4e} ({:+.2} %) [{:.3e}, {:.3e}]  eta {:.3} ({:+.2} %) [{:.3}, \
             {:.3}]",
            p.storage_pa,
            100.0 * (p.storage_pa / t.re - 1.0),
            p.storage_ci95[0],
            p.storage_ci95[1],
            p.loss_factor,
            100.0 * (p.loss_factor / (t.im / t.re) - 1.0),
            p.loss_factor_ci95[0],
            p.loss_factor_ci95[1]
        );
    }
    let (e_g, e_eta) = worst_errors(&fit, &truth, &freqs);
    eprintln!("worst G' {:.2} %, eta {:.2} %", 100.0 * e_g, 100.0 * e_eta);
    assert!(e_g < 0.03 && e_eta < 0.05);
}

/// The channels as points the model is read or driven at.
fn points(channels: &[lamdyn_frf::Channel]) -> Vec<MeasuredPoint<'_>> {
    channels
        .iter()
        .map(|c| MeasuredPoint {
            name: &c.name,
            point_m: c.point_m,
            direction: c.direction,
        })
        .collect()
}

/// A fixed xorshift sequence of standard normal draws (Box–Muller): the same on every machine.
struct Normal(u64);

impl Normal {
    fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn draw(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (2.0 * PI * b).cos()
    }
}

/// Accelerances of `model` at `freqs` with the core `core(ω)` and the inputs changed by
/// `deltas`, with complex Gaussian noise of `rel` × each curve's RMS added from `noise`.
fn noisy_accelerance(
    model: &ObservedModel,
    template: &FrfSet,
    freqs: &[f64],
    (core, g_ref): (&dyn Fn(f64) -> Complex64, f64),
    deltas: &[f64],
    (rel, noise): (f64, &mut Normal),
) -> FrfSet {
    let (n_c, n_r) = (model.n_sensors(), model.n_references());
    let mut curves = vec![Vec::with_capacity(freqs.len()); n_c * n_r];
    for &f in freqs {
        let w = 2.0 * PI * f;
        let h = model
            .receptance_with_inputs(w, core(w) / g_ref, deltas)
            .unwrap()
            .h;
        for c in 0..n_c {
            for r in 0..n_r {
                let v = h[(c, r)];
                curves[c * n_r + r].push(-w * w * Complex64::new(v.re, v.im));
            }
        }
    }
    let mut values = Vec::with_capacity(curves.len() * freqs.len());
    for curve in curves {
        let power: f64 = curve.iter().map(|v| v.norm_sqr()).sum();
        let sd = rel * (power / curve.len() as f64).sqrt() / 2f64.sqrt();
        values.extend(
            curve
                .iter()
                .map(|v| v + sd * Complex64::new(noise.draw(), noise.draw())),
        );
    }
    FrfSet::new(
        freqs.to_vec(),
        template.responses().to_vec(),
        template.references().to_vec(),
        lamdyn_frf::Quantity::Accelerance,
        values,
    )
    .unwrap()
}

/// The misfit S/s² + Σ (δ_k/sd_k)² + (ln g/s_g)² of the law `core`, the inputs `deltas` and the
/// gain `gain` to `data` on the fit's weights (`settings`) and noise scale: beside the fit's
/// own, it says how far the fitted minimum is from the truth's (the χ² the law's form or a
/// wrong basin costs).
fn misfit_at(
    (model, data, fit, settings): (&ObservedModel, &FrfSet, &FrfFit, &FrfFitSettings),
    core: &dyn Fn(f64) -> Complex64,
    deltas: &[f64],
    gain: f64,
) -> f64 {
    let band = lamdyn_fit::frf_fit::BandData::from_set(
        data,
        settings.band_hz,
        settings.dynamic_range_db,
        1,
    )
    .unwrap();
    let mut s = 0.0;
    for (l, &w) in band.omegas.iter().enumerate() {
        let h = model
            .receptance_with_inputs(w, core(w) / fit.assembled_modulus_pa, deltas)
            .unwrap()
            .h;
        for c in 0..band.n_sensors {
            let m = gain * -w * w * Complex64::new(h[(c, 0)].re, h[(c, 0)].im);
            s += (band.weights[l][0][c] * (m - band.values[l][0][c])).norm_sqr();
        }
    }
    let prior: f64 = deltas
        .iter()
        .zip(&settings.inputs)
        .map(|(d, p)| (d / p.sd).powi(2))
        .sum();
    s / fit.noise_scale.powi(2) + prior + (gain.ln() / settings.gain_prior_sd).powi(2)
}

/// Coverage of the law's 95 % band over 20 seeds on the damped glass plate (modal damping
/// 4–15 % over 20–150 Hz, overlapping modes, one hammer, 12 triaxial sensors, 1 % noise): each
/// seed draws new noise and the faces' and core's inputs from their priors (the job's default
/// tolerances: the faces' modulus 1 %, thicknesses 0.01 mm, densities 0.5 %), the inputs fitted
/// under those priors beside the law. The truth must lie inside the band at ≥ 90 % of 40
/// frequencies over the band, for G' and for η.
///
/// The data come from the identification's own mesh: this checks the band's noise, inputs and
/// law form, what the fit's covariance and the grid's spread claim. The mesh's part comes from
/// the ladder in a run (`frf_route::DiscretizationCorrection`, checked through the chain in the
/// pipeline's test `damped_modes_take_the_frf_fit`).
///
/// Measured (docs/fit.md "Coverage"): 93.9 % (G') and 92.5 % (η), mean band sd 1.9 % and
/// 1.3 %. Each seed prints the χ² of its fit less the truth's: 33–100 from the law's form (a
/// Prony core between the fit's relaxation times: η ripples about the truth identically at
/// every seed), 350–390 at seeds 8 and 11, where the fit settles with the core's thickness 5 %
/// high and G' 7.7 % high, about two thirds of their points inside the bands. About 3 s a seed
/// on 2 cores.
#[test]
fn bands_cover_the_truth_over_twenty_seeds() {
    let t0 = Instant::now();
    let small = bench(&glass_plate([4, 3], 0.0, [4, 3], None, 5));
    let template = small.frfs().unwrap();
    let plate = layered_plate();
    let priors: Vec<InputPrior> = [
        (Input::FaceModulus, 0.01),
        (Input::FaceThickness, 0.01e-3 / 3.0e-3),
        (Input::CoreThickness, 0.01e-3 / 0.76e-3),
        (Input::FaceDensity, 0.005),
        (Input::CoreDensity, 0.005),
    ]
    .map(|(input, sd)| InputPrior { input, sd })
    .to_vec();
    let inputs: Vec<Input> = priors.iter().map(|p| p.input).collect();
    let (sensors, references) = (points(template.responses()), points(template.references()));
    let g_ref = 3.0e6;
    let basis = FrfBasis {
        modes: 20,
        ratios: vec![0.5, 2.0],
        ..FrfBasis::default()
    };
    let model = ObservedModel::build(
        &plate,
        [12, 9],
        g_ref,
        &basis,
        (&sensors, &references),
        &inputs,
    )
    .unwrap();
    eprintln!("model {:.1?}: basis {}", t0.elapsed(), model.basis_size());
    let band = [20.0, 150.0];
    let freqs: Vec<f64> = (0..=65).map(|k| band[0] + 2.0 * k as f64).collect();
    let core = |w: f64| small.core_law.modulus(w);
    let settings = FrfFitSettings {
        inputs: priors.clone(),
        starts: 0,
        ..FrfFitSettings::over(band)
    };
    let law = FrfLaw::generalized_maxwell_over(band[0], band[1]);
    let probe: Vec<f64> = (0..40).map(|k| 25.0 + 125.0 * k as f64 / 39.0).collect();
    let (mut covered, mut total) = ([0usize; 2], 0usize);
    let (mut worst, mut width) = ([0.0f64; 2], [0.0f64; 2]);
    let t1 = Instant::now();
    let seeds: u64 = std::env::var("SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    let scale: f64 = std::env::var("INPUT_SCALE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1.0);
    for seed in 0..seeds {
        let mut draws = Normal::new(100 + seed);
        let truth_inputs: Vec<f64> = priors.iter().map(|p| scale * p.sd * draws.draw()).collect();
        let data = noisy_accelerance(
            &model,
            &template,
            &freqs,
            (&core, g_ref),
            &truth_inputs,
            (0.01, &mut draws),
        );
        // Started from a constant modulus (the pole route's law in a run): 3 MPa, η 1.
        let start = |_: f64| Complex64::new(g_ref, g_ref);
        let tf = Instant::now();
        let fit =
            fit_core_to_frfs(&model, &data, law.clone(), g_ref, Some(&start), &settings).unwrap();
        let fitted_law = |w: f64| fit.modulus(w / (2.0 * PI));
        let fitted_inputs: Vec<f64> = fit.inputs.iter().map(|i| i.delta).collect();
        let problem = (&model, &data, &fit, &settings);
        let gap = misfit_at(problem, &fitted_law, &fitted_inputs, fit.gains[0])
            - misfit_at(problem, &core, &truth_inputs, 1.0);
        let before = covered;
        for &f in &probe {
            let t = core(2.0 * PI * f);
            let p = fit.at(f);
            let eta = t.im / t.re;
            covered[0] += usize::from(p.storage_ci95[0] <= t.re && t.re <= p.storage_ci95[1]);
            covered[1] += usize::from(p.loss_factor_ci95[0] <= eta && eta <= p.loss_factor_ci95[1]);
            worst[0] = worst[0].max((p.storage_pa / t.re - 1.0).abs());
            worst[1] = worst[1].max((p.loss_factor / eta - 1.0).abs());
            width[0] += (p.storage_ci95[1] / p.storage_ci95[0]).ln() / 3.92;
            width[1] += (p.loss_factor_ci95[1] / p.loss_factor_ci95[0]).ln() / 3.92;
            total += 1;
        }
        eprintln!(
            "seed {seed} {:.1?}: {} work {:?}; chi2 of the fit less the truth's {gap:.1}; core \
             thickness {:+.2} % (truth {:+.2} %); inside the bands G' {}/{n}, eta {}/{n}",
            tf.elapsed(),
            fit.describe(),
            fit.work,
            100.0 * fit.inputs[2].delta,
            100.0 * truth_inputs[2],
            covered[0] - before[0],
            covered[1] - before[1],
            n = probe.len(),
        );
    }
    let rate = covered.map(|c| c as f64 / total as f64);
    eprintln!(
        "20 seeds {:.1?}: coverage G' {:.1} %, eta {:.1} %; worst error G' {:.2} %, eta {:.2} %; \
         mean band sd G' {:.2} %, eta {:.2} %",
        t1.elapsed(),
        100.0 * rate[0],
        100.0 * rate[1],
        100.0 * worst[0],
        100.0 * worst[1],
        100.0 * width[0] / total as f64,
        100.0 * width[1] / total as f64
    );
    assert!(rate[0] >= 0.9 && rate[1] >= 0.9, "{rate:?}");
}
