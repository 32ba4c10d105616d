//! The fit of the recovery case (paper's plate, 24 × 24 MITC4, 24 modes + residual, 243
//! channels, 320 lines) after the eigen solve, and one misfit evaluation by modal synthesis and
//! by direct sparse LU solves (the paper's route). The side-by-side ratio, extrapolated to a whole
//! fit, is printed by `cargo run --release -p lamdyn-fit --example fit_vs_direct`.
//!
//! `cargo bench -p lamdyn-fit --bench fit`

use criterion::{Criterion, criterion_group, criterion_main};
use lamdyn_fit::direct::DirectSolver;
use lamdyn_fit::fit::{FitSettings, LawKind, fit};
use lamdyn_fit::misfit::{MisfitKind, MisfitSpec, Objective};
use lamdyn_fit::synthetic::PaperPlateCase;
use lamdyn_material::law::{PaperEq7Law, ViscoelasticLaw};
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let truth = PaperEq7Law::paper_table2();
    let case = PaperPlateCase::default()
        .build(&|w| truth.modulus(w))
        .expect("case");
    let mut group = c.benchmark_group("fit");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for (name, law, kind) in [
        (
            "modal/fit_eq7_log_rms",
            LawKind::PaperEq7,
            MisfitKind::LogRms,
        ),
        ("modal/fit_eq7_rms", LawKind::PaperEq7, MisfitKind::Rms),
        (
            "modal/fit_eq7_complex",
            LawKind::PaperEq7,
            MisfitKind::Complex,
        ),
        (
            "modal/fit_zener_log_rms",
            LawKind::FractionalZener,
            MisfitKind::LogRms,
        ),
    ] {
        let settings = FitSettings::new(law, MisfitSpec::new(kind));
        group.bench_function(name, |b| {
            b.iter(|| fit(&case.model, &case.measured, &settings).expect("fit"))
        });
    }
    let objective = Objective::new(
        &case.model,
        &case.measured,
        MisfitSpec::new(MisfitKind::LogRms),
    )
    .expect("objective");
    group.bench_function("modal/one_log_rms_evaluation", |b| {
        b.iter(|| objective.residuals(&|w| truth.modulus(w)))
    });
    let direct = DirectSolver::new(&case.assembly).expect("direct");
    let freqs = case.measured.freqs_hz().to_vec();
    group.bench_function("direct/one_evaluation_320_lines", |b| {
        b.iter(|| {
            direct
                .receptance_lines(
                    &freqs,
                    &|w| truth.modulus(w),
                    case.material.young_pa,
                    &case.response_probes,
                    &case.reference_probes,
                )
                .expect("direct")
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
