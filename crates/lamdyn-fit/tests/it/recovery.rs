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

/// E' within 0.5 % and η within 5 % of the truth at the modal frequencies; returns how many
/// true parameters lie inside their 95 % intervals and the largest |z| = |estimate − truth|/σ.
fn check(r: &FitResult, truth_params: &[f64], truth: &dyn ViscoelasticLaw) -> (usize, f64) {
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
        .fold((0, 0.0f64), |(n, z), (p, t)| {
            let (ci, sd) = (
                p.ci95.expect("full-rank Jacobian"),
                p.std_dev.expect("full-rank Jacobian"),
            );
            (
                n + usize::from(ci[0] <= *t && *t <= ci[1]),
                z.max(((p.value - t) / sd).abs()),
            )
        })
}

/// Five noise seeds, four parameters each: a calibrated 95 % interval misses the truth in one
/// case in twenty, so all 20 inside is not to be expected; at least 17 of 20 are required
/// (binomial with p = 0.95: P(≤ 16) = 1.6 %, while the classical covariance with the absolute
/// RMS misfit, which covers 40 %, would fail), and no |z| beyond 4.
fn recovery(law: LawKind, truth: &dyn ViscoelasticLaw, truth_params: &[f64]) {
    let (mut inside, mut zmax) = (0, 0.0f64);
    for seed in 1..=5 {
        let c = case(truth, seed);
        let r = fit(
            &c.model,
            &c.measured,
            &FitSettings::new(law, MisfitSpec::new(MisfitKind::LogRms)),
        )
        .unwrap();
        let (n, z) = check(&r, truth_params, truth);
        inside += n;
        zmax = zmax.max(z);
    }
    assert!(
        inside >= 17 && zmax < 4.0,
        "{inside}/20 inside the 95 % intervals, max |z| {zmax}"
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
