//! Side by side: the whole fit of the recovery case by modal synthesis, against the direct
//! route of the paper (a sparse LU solve of (−ω²M + s(ω)K0) x = f per line and per trial),
//! timed for a few misfit evaluations and extrapolated to the fit's evaluation count.
//!
//! `cargo run --release -p lamdyn-fit --example fit_vs_direct -- [repeats]`
//!
//! Prints a markdown table (docs/fit.md) and the machine's core count.

use lamdyn_fit::direct::DirectSolver;
use lamdyn_fit::fit::{FitSettings, LawKind, fit};
use lamdyn_fit::misfit::{MisfitKind, MisfitSpec};
use lamdyn_fit::synthetic::PaperPlateCase;
use lamdyn_frf::Quantity;
use lamdyn_material::law::{PaperEq7Law, ViscoelasticLaw};
use num_complex::Complex64;
use std::f64::consts::PI;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let truth = PaperEq7Law::paper_table2();
    let case = PaperPlateCase::default()
        .build(&|w| truth.modulus(w))
        .expect("case");
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "paper plate 24 x 24 MITC4, {} modes + residual, {} channels, {} lines; {cores} cores",
        case.model.eigenvalues().len(),
        case.measured.responses().len(),
        case.measured.n_lines()
    );
    println!(
        "model (eigen solve, projections, residual terms): {:.3} s\n",
        case.model_seconds
    );
    // One direct evaluation: receptances at every line, then the log-RMS residuals.
    let direct = DirectSolver::new(&case.assembly).expect("direct");
    let freqs = case.measured.freqs_hz().to_vec();
    let rms_exp = case.measured.rms(0);
    let direct_eval = || {
        let t = Instant::now();
        let lines = direct
            .receptance_lines(
                &freqs,
                &|w| truth.modulus(w),
                case.material.young_pa,
                &case.response_probes,
                &case.reference_probes,
            )
            .expect("direct");
        let cost: f64 = lines
            .iter()
            .zip(&freqs)
            .zip(&rms_exp)
            .map(|((h, f), e)| {
                let q = Quantity::Accelerance.from_receptance(2.0 * PI * f).norm();
                let rms =
                    (h.iter().map(Complex64::norm_sqr).sum::<f64>() / h.len() as f64).sqrt() * q;
                (e.ln() - rms.ln()).powi(2)
            })
            .sum();
        assert!(cost.is_finite());
        t.elapsed().as_secs_f64()
    };
    let per_eval = median((0..3).map(|_| direct_eval()).collect());
    println!(
        "direct: {} lines, {} dofs, sparse complex LU per line in parallel: {per_eval:.2} s per \
         evaluation\n",
        freqs.len(),
        case.assembly.n_dofs()
    );
    println!(
        "| fit | modal: whole fit, median of {repeats} | evaluations | direct: one evaluation, \
         median of 3 | direct: extrapolated fit | ratio |"
    );
    println!("|---|---|---|---|---|---|");
    for (name, law, kind) in [
        ("eq7, log-RMS", LawKind::PaperEq7, MisfitKind::LogRms),
        (
            "eq7, RMS (paper eq. 10)",
            LawKind::PaperEq7,
            MisfitKind::Rms,
        ),
        (
            "fractional Zener, log-RMS",
            LawKind::FractionalZener,
            MisfitKind::LogRms,
        ),
    ] {
        let settings = FitSettings::new(law, MisfitSpec::new(kind));
        let runs: Vec<(f64, usize)> = (0..repeats)
            .map(|_| {
                let r = fit(&case.model, &case.measured, &settings).expect("fit");
                (r.seconds, r.evaluations)
            })
            .collect();
        let evals = runs[0].1;
        let t = median(runs.iter().map(|r| r.0).collect());
        let extrapolated = per_eval * evals as f64;
        println!(
            "| {name} | {t:.3} s | {evals} | {per_eval:.3} s | {extrapolated:.1} s | {:.0}x |",
            extrapolated / t
        );
    }
}
