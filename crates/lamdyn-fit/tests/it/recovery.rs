//! Recovery: FRFs synthesized from a known law on the paper's plate (Table 1 size, 0.25–80 Hz at
//! 0.25 Hz, 81 points × 3 directions, 1 % complex noise) are fitted back (docs/fit.md).

use lamdyn_fit::fit::{FitResult, FitSettings, LawKind, fit};
use lamdyn_fit::misfit::{MisfitKind, MisfitSpec, Objective};
use lamdyn_fit::modes::{compare_peaks, modewise};
use lamdyn_fit::synthetic::{PaperPlateCase, SyntheticCase};
use lamdyn_material::law::{FractionalZener, PaperEq7Law, ViscoelasticLaw};
use std::f64::consts::PI;

fn case(truth: &dyn ViscoelasticLaw, seed: u64) -> SyntheticCase {
    let c = PaperPlateCase {
        seed,
        ..PaperPlateCase::default()
    }
    .build(&|w| truth.modulus(w))
    .unwrap();
    assert_eq!(
        (c.measured.responses().len(), c.measured.n_lines()),
        (243, 320)
    );
    c
}

/// E' within 0.5 % and η within 5 % of the truth at the modal frequencies; returns the largest
/// |z| = |estimate − truth|/σ over the parameters.
fn check(r: &FitResult, truth_params: &[f64], truth: &dyn ViscoelasticLaw) -> f64 {
    assert!(r.converged, "{}", r.reason);
    // The lossier fractional Zener merges close modes in the RMS curve: at least 4 peaks remain.
    assert!(r.peaks.len() >= 4, "{:?}", r.peaks);
    for pk in &r.peaks {
        let w = 2.0 * PI * pk.freq_hz;
        let (e, eta, _) = r.modulus_uncertainty(w);
        let t = truth.modulus(w);
        assert!(
            (e / t.re - 1.0).abs() < 5e-3,
            "E' at {} Hz: {e} vs {}",
            pk.freq_hz,
            t.re
        );
        assert!(
            (eta / (t.im / t.re) - 1.0).abs() < 5e-2,
            "eta at {} Hz: {eta} vs {}",
            pk.freq_hz,
            t.im / t.re
        );
    }
    r.parameters
        .iter()
        .zip(truth_params)
        .map(|(p, t)| ((p.value - t) / p.std_dev.expect("full-rank Jacobian")).abs())
        .fold(0.0, f64::max)
}

/// Five noise seeds. The four parameters of one fit are strongly correlated (t0 and c of eq. 7
/// most), so they leave their marginal intervals together and a count of parameters
/// inside is not binomial; the seeds are independent. So the test is per seed: the true
/// parameter vector inside the fit's joint 95 % region, d² = (u − u*)ᵀ C⁻¹ (u − u*) ≤ χ²₄(0.95),
/// at ≥ 4 of 5 seeds (binomial with p = 0.95: P(≤ 3 of 5) = 2.3 %, while the classical
/// covariance with the absolute RMS misfit, which covers a fifth of the parameters, fails), and
/// no marginal |z| beyond 4.
fn recovery(law: LawKind, truth: &dyn ViscoelasticLaw, truth_params: &[f64]) {
    let (mut inside, mut zmax, mut d2s) = (0, 0.0f64, Vec::new());
    for seed in 1..=5 {
        let c = case(truth, seed);
        let r = fit(
            &c.model,
            &c.measured,
            &FitSettings::new(law, MisfitSpec::new(MisfitKind::LogRms)),
        )
        .unwrap();
        let z = check(&r, truth_params, truth);
        let d2 = r.mahalanobis_squared(truth_params).expect("a covariance");
        inside += usize::from(d2 <= FitResult::CHI2_95_4_PARAMETERS);
        zmax = zmax.max(z);
        d2s.push(d2);
    }
    eprintln!("d² at seeds 1-5: {d2s:.2?}, max |z| {zmax:.2}");
    assert!(
        inside >= 4 && zmax < 4.0,
        "{inside}/5 seeds inside the joint 95 % region (d² {d2s:.2?}), max |z| {zmax}"
    );
}

#[test]
fn paper_eq7_truth_is_recovered() {
    recovery(
        LawKind::PaperEq7,
        &PaperEq7Law::paper_table2(),
        &[67.45e9, 0.686e-3, 4.295e-3, 1.617e6],
    );
}

#[test]
fn fractional_zener_truth_is_recovered() {
    recovery(
        LawKind::FractionalZener,
        &FractionalZener::new(60e9, 75e9, 3e-3, 0.5).unwrap(),
        &[60e9, 75e9, 3e-3, 0.5],
    );
}

/// The paper's own misfit (absolute RMS, eq. 10) and the complex misfit reach the same accuracy
/// in E' and η; the per-mode law and the mode-wise estimate find E' at each peak; the Table-3
/// comparison of the fitted RMS FRF matches the measured peaks.
#[test]
fn other_misfits_per_mode_law_and_table3() {
    let truth = PaperEq7Law::paper_table2();
    let c = case(&truth, 3);
    for kind in [MisfitKind::Rms, MisfitKind::Complex] {
        let r = fit(
            &c.model,
            &c.measured,
            &FitSettings::new(LawKind::PaperEq7, MisfitSpec::new(kind)),
        )
        .unwrap();
        for pk in &r.peaks {
            let w = 2.0 * PI * pk.freq_hz;
            let (e, eta, t) = (
                r.modulus(w).re,
                r.modulus(w).im / r.modulus(w).re,
                truth.modulus(w),
            );
            assert!(
                (e / t.re - 1.0).abs() < 5e-3 && (eta / (t.im / t.re) - 1.0).abs() < 5e-2,
                "{kind:?} at {} Hz",
                pk.freq_hz
            );
        }
    }
    let r = fit(
        &c.model,
        &c.measured,
        &FitSettings::new(LawKind::PerMode, MisfitSpec::new(MisfitKind::LogRms)),
    )
    .unwrap();
    for pk in &r.peaks {
        let w = 2.0 * PI * pk.freq_hz;
        assert!(
            (r.modulus(w).re / truth.modulus(w).re - 1.0).abs() < 5e-3,
            "per-mode E' at {} Hz",
            pk.freq_hz
        );
    }
    // Mode-wise: E'(f_r) = E_ref (f_exp/f_num)² is the modulus at each resonance to the
    // accuracy of the peak location: these modes (2ζf ≈ 0.05–0.3 Hz) are no wider than the
    // 0.25 Hz lines, so f_exp is known to about half a line and E' (∝ f²) to Δf/f. Where the
    // FE has a close pair (75.19 and 75.34 Hz on this nearly square plate) the RMS peak lies
    // between the two, up to half their gap g further: E' to (Δf + g)/f. The half-power
    // bandwidth is unresolved and no loss factor is claimed.
    let fe: Vec<f64> = c
        .model
        .eigenvalues()
        .iter()
        .filter(|l| **l > 1.0)
        .map(|l| l.sqrt() / (2.0 * PI))
        .collect();
    for est in modewise(&c.model, &r.peaks) {
        let t = truth.modulus(2.0 * PI * est.freq_exp_hz).re;
        let scale = est.freq_exp_hz / est.freq_num_hz;
        let gap = fe
            .iter()
            .map(|f| (f - est.freq_num_hz).abs())
            .filter(|d| *d > 0.0)
            .fold(f64::INFINITY, f64::min)
            * scale;
        let tol = (0.25 + if gap < 0.5 { gap } else { 0.0 }) / est.freq_exp_hz;
        assert!(
            (est.storage_pa / t - 1.0).abs() < tol,
            "mode-wise at {} Hz: {} vs {t}",
            est.freq_exp_hz,
            est.storage_pa
        );
        assert_eq!(
            est.loss_factor, None,
            "unresolved bandwidth at {} Hz",
            est.freq_exp_hz
        );
    }
    let objective =
        Objective::new(&c.model, &c.measured, MisfitSpec::new(MisfitKind::LogRms)).unwrap();
    let fitted = objective.model_rms(&|w| r.modulus(w));
    let table = compare_peaks(
        c.measured.freqs_hz(),
        objective.measured_rms(),
        &fitted,
        objective.lines(),
        1.5,
    );
    assert!(table.len() >= 5);
    for row in &table {
        assert!(
            row.freq_error.abs() < 1e-3 && row.amplitude_error.abs() < 0.05,
            "{row:?}"
        );
    }
}

/// The joint region's distance against its identity: parameters drawn as u + L z (L Lᵀ = C)
/// lie at d² = |z|² from the estimate, and the estimate itself at 0.
#[test]
fn mahalanobis_distance_of_drawn_parameters_is_the_deviates_norm() {
    let truth = PaperEq7Law::paper_table2();
    let c = case(&truth, 2);
    let r = fit(
        &c.model,
        &c.measured,
        &FitSettings::new(LawKind::PaperEq7, MisfitSpec::new(MisfitKind::LogRms)),
    )
    .unwrap();
    let values: Vec<f64> = r.parameters.iter().map(|p| p.value).collect();
    assert!(r.mahalanobis_squared(&values).unwrap() < 1e-12);
    for z in [[1.0, 0.0, 0.0, 0.0], [0.5, -2.0, 1.0, 3.0]] {
        let drawn = r.draw_parameters(&z).unwrap();
        let d2 = r.mahalanobis_squared(&drawn).unwrap();
        let norm2: f64 = z.iter().map(|v| v * v).sum();
        assert!((d2 / norm2 - 1.0).abs() < 1e-8, "{d2} vs {norm2}");
    }
    assert!(r.mahalanobis_squared(&values[..3]).is_none());
}
