//! The recovery study of docs/fit.md: FRFs synthesized from a known law on the paper's plate
//! (0.25–80 Hz at 0.25 Hz, 81 points × 3 directions, 1 % complex noise) are fitted back.
//!
//! ```text
//! cargo run --release -p lamdyn-fit --example recovery -- one [eq7|zener|per_mode] [rms|log_rms|complex] [seed]
//! cargo run --release -p lamdyn-fit --example recovery -- study [seeds]
//! ```
//!
//! RECOVERY_MESH=mitc4 runs either on 24 × 24 MITC4 instead of the case's default mesh.
//! `one` prints a single fit in detail (per_mode fits the per-mode law to eq. 7 data; set
//! RECOVERY_RESIDUALS=1 to list the lines with large residuals); `study` prints the markdown
//! table of docs/fit.md: for each truth law, misfit and covariance estimator, over seeds 1..=seeds,
//! how many true parameters fall inside the 95 % intervals, at how many seeds the true parameter
//! vector lies inside the joint 95 % confidence region (d² ≤ χ²₄(0.95)), the largest
//! |z| = |estimate − truth|/σ, and the largest errors of E' and η at the measured peaks.

use lamdyn_fit::fit::{Covariance, FitResult, FitSettings, LawKind, fit};
use lamdyn_fit::misfit::{MisfitKind, MisfitSpec, Objective};
use lamdyn_fit::modes::modewise;
use lamdyn_fit::synthetic::{PaperPlateCase, SyntheticCase};
use lamdyn_material::law::{FractionalZener, PaperEq7Law, ViscoelasticLaw};
use std::f64::consts::PI;

fn truth(law: &str) -> (Box<dyn ViscoelasticLaw>, Vec<f64>) {
    match law {
        "zener" => (
            Box::new(FractionalZener::new(60e9, 75e9, 3e-3, 0.5).unwrap()),
            vec![60e9, 75e9, 3e-3, 0.5],
        ),
        _ => (
            Box::new(PaperEq7Law::paper_table2()),
            vec![67.45e9, 0.686e-3, 4.295e-3, 1.617e6],
        ),
    }
}

fn kind(name: &str) -> MisfitKind {
    match name {
        "log_rms" => MisfitKind::LogRms,
        "complex" => MisfitKind::Complex,
        _ => MisfitKind::Rms,
    }
}

fn law_kind(name: &str) -> LawKind {
    match name {
        "zener" => LawKind::FractionalZener,
        "per_mode" => LawKind::PerMode,
        _ => LawKind::PaperEq7,
    }
}

/// The case's mesh: the default (12 × 12 MITC9 with 2 edge layers), or with
/// RECOVERY_MESH=mitc4 the 24 × 24 MITC4 mesh of the same dofs the study used before.
fn build(law: &str, seed: u64) -> SyntheticCase {
    let (t, _) = truth(law);
    let mut case = PaperPlateCase {
        seed,
        ..PaperPlateCase::default()
    };
    if std::env::var("RECOVERY_MESH").is_ok_and(|m| m == "mitc4") {
        case.elements = 24;
        case.element = lamdyn_fem::element::ElementOrder::Linear;
        case.edge_layers = 0;
    }
    case.build(&|w| t.modulus(w)).unwrap()
}

/// Largest relative errors of E' and η at the peaks.
fn peak_errors(r: &FitResult, t: &dyn ViscoelasticLaw) -> (f64, f64) {
    r.peaks.iter().fold((0.0f64, 0.0f64), |(a, b), pk| {
        let w = 2.0 * PI * pk.freq_hz;
        let (e, tt) = (r.modulus(w), t.modulus(w));
        (
            a.max((e.re / tt.re - 1.0).abs()),
            b.max((e.im / e.re / (tt.im / tt.re) - 1.0).abs()),
        )
    })
}

fn one(law: &str, misfit: &str, seed: u64) {
    let c = build(if law == "per_mode" { "eq7" } else { law }, seed);
    let (t, truth_params) = truth(law);
    let settings = FitSettings::new(law_kind(law), MisfitSpec::new(kind(misfit)));
    let r = fit(&c.model, &c.measured, &settings).unwrap();
    println!(
        "model {:.2} s, fit {:.3} s, {} evaluations, reason: {}",
        c.model_seconds, r.seconds, r.evaluations, r.reason
    );
    if law != "per_mode" {
        for (p, tv) in r.parameters.iter().zip(&truth_params) {
            let sd = p.std_dev.unwrap_or(f64::NAN);
            println!(
                "{:10} {:14.6e} ± {:10.3e}  truth {:12.6e}  z {:+.2}",
                p.name,
                p.value,
                sd,
                tv,
                (p.value - tv) / sd
            );
        }
    }
    let objective = Objective::new(&c.model, &c.measured, settings.misfit.clone()).unwrap();
    let at_truth: f64 = objective
        .residuals(&|w| t.modulus(w))
        .iter()
        .map(|v| v * v)
        .sum();
    println!(
        "cost at the truth {at_truth:.4e}, at the optimum {:.4e}",
        r.cost
    );
    if std::env::var_os("RECOVERY_RESIDUALS").is_some() {
        let rr = objective.residuals(&|w| r.modulus(w));
        for (k, v) in objective
            .lines()
            .iter()
            .zip(&rr)
            .filter(|(_, v)| v.abs() > 0.03)
        {
            println!("  residual {:7.2} Hz {v:+.3}", c.measured.freqs_hz()[*k]);
        }
    }
    for s in &r.starts {
        println!(
            "  start {:?} -> cost {:.4e} after {} iterations (converged {})",
            s.start, s.cost, s.iterations, s.converged
        );
    }
    for est in modewise(&c.model, &r.peaks) {
        let tv = t.modulus(2.0 * PI * est.freq_exp_hz).re;
        println!(
            "  mode-wise {:7.3} Hz (FE {:7.3} Hz at E_ref): E' err {:+.2e}",
            est.freq_exp_hz,
            est.freq_num_hz,
            est.storage_pa / tv - 1.0
        );
    }
    for pk in &r.peaks {
        let w = 2.0 * PI * pk.freq_hz;
        let (e, eta, sd) = r.modulus_uncertainty(w);
        let et = t.modulus(w);
        let (se, sn) = sd.map_or((f64::NAN, f64::NAN), |s| (s.0 / e, s.1 / eta));
        println!(
            "  f {:7.3} Hz  E' err {:+.2e} (sd {se:.1e})  eta err {:+.2e} (sd {sn:.1e})",
            pk.freq_hz,
            e / et.re - 1.0,
            eta / (et.im / et.re) - 1.0
        );
    }
}

fn study(seeds: u64) {
    println!(
        "| truth and law | misfit | covariance | inside 95 % CI | seeds inside the joint 95 % \
         region | max abs z | max E' error at peaks | max eta error at peaks | fit time, median |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for law in ["eq7", "zener"] {
        let cases: Vec<SyntheticCase> = (1..=seeds).map(|s| build(law, s)).collect();
        let (t, truth_params) = truth(law);
        for (misfit, cov) in ["rms", "log_rms", "complex"]
            .into_iter()
            .flat_map(|m| [(m, Covariance::RobustHc3), (m, Covariance::Classical)])
        {
            let (mut inside, mut total, mut zmax, mut emax, mut nmax) =
                (0, 0, 0.0f64, 0.0f64, 0.0f64);
            let mut joint = 0;
            let mut times = Vec::new();
            for c in &cases {
                let mut settings = FitSettings::new(law_kind(law), MisfitSpec::new(kind(misfit)));
                settings.covariance = cov;
                let r = fit(&c.model, &c.measured, &settings).unwrap();
                joint += usize::from(
                    r.mahalanobis_squared(&truth_params)
                        .is_some_and(|d2| d2 <= FitResult::CHI2_95_4_PARAMETERS),
                );
                for (p, tv) in r.parameters.iter().zip(&truth_params) {
                    total += 1;
                    if let (Some(ci), Some(sd)) = (p.ci95, p.std_dev) {
                        inside += usize::from(ci[0] <= *tv && *tv <= ci[1]);
                        zmax = zmax.max(((p.value - tv) / sd).abs());
                    }
                }
                let (e, n) = peak_errors(&r, t.as_ref());
                emax = emax.max(e);
                nmax = nmax.max(n);
                times.push(r.seconds);
            }
            times.sort_by(f64::total_cmp);
            println!(
                "| {law} | {misfit} | {cov:?} | {inside}/{total} | {joint}/{} | {zmax:.2} | {:.2e} \
                 | {:.2e} | {:.3} s |",
                cases.len(),
                emax,
                nmax,
                times[times.len() / 2]
            );
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match args.get(1).map(String::as_str) {
        Some("study") => study(args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10)),
        _ => one(
            args.get(2).map_or("eq7", String::as_str),
            args.get(3).map_or("log_rms", String::as_str),
            args.get(4).and_then(|s| s.parse().ok()).unwrap_or(1),
        ),
    }
}
