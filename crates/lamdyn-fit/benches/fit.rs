//! The fit of the recovery case (paper's plate, 24 × 24 MITC4, 24 modes + residual, 243
//! channels, 320 lines) after the eigen solve, and one misfit evaluation by modal synthesis and
//! by direct sparse LU solves (the paper's route). The side-by-side ratio, extrapolated to a whole
//! fit, is printed by `cargo run --release -p lamdyn-fit --example fit_vs_direct`. The same
//! evaluation on the plate resting on four foam blocks (the supports couple the modes: one
//! dense solve per line, `lamdyn_fit::supports`).
//!
//! `cargo bench -p lamdyn-fit --bench fit`

use criterion::{Criterion, criterion_group, criterion_main};
use lamdyn_fem::eigen::{ModalParams, Silent, solve_modes};
use lamdyn_fit::direct::DirectSolver;
use lamdyn_fit::fit::{FitSettings, LawKind, fit};
use lamdyn_fit::misfit::{MisfitKind, MisfitSpec, Objective};
use lamdyn_fit::supports::GroundedSupport;
use lamdyn_fit::synthesis::{ModalModel, ResidualTerm};
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
    let supported = supported_model(&case);
    let objective = Objective::new(
        &supported,
        &case.measured,
        MisfitSpec::new(MisfitKind::LogRms),
    )
    .expect("objective");
    group.bench_function("supported/one_log_rms_evaluation", |b| {
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

/// The case's plate on four foam blocks near its corners
/// ([`lamdyn_fit::synthetic::corner_foam_blocks`]).
fn supported_model(case: &lamdyn_fit::synthetic::SyntheticCase) -> ModalModel {
    let blocks = lamdyn_fit::synthetic::corner_foam_blocks();
    let supports = GroundedSupport::on_plan(&case.mesh, &blocks).expect("supports");
    let modes = case.model.eigenvalues().len();
    let sol = solve_modes(&case.assembly, &ModalParams::lowest(modes), &Silent).expect("modes");
    ModalModel::supported(
        &case.assembly,
        &sol,
        &case.response_probes,
        &case.reference_probes,
        case.material.young_pa,
        ResidualTerm::Static,
        &supports,
    )
    .expect("supported model")
}

criterion_group!(benches, bench);
criterion_main!(benches);
