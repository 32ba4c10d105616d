//! The model's discretization error in the fit's intervals.
//!
//! The measurement: the paper's plate (Table 1 footprint, 3.85 mm glass, free) on 24 × 24
//! MITC9 elements with 3 edge layers (within 6e-5 of the Reissner–Mindlin reference in its
//! first modes, docs/fem.md), the paper's law (Table 2), 0.25–80 Hz, a 7 × 7 × 3 sensor grid
//! and one hammer, 1 % noise. The fit's model: 16 × 16 MITC4 with 3 edge layers, whose
//! frequencies are 1e-3 to 1e-2 too high. With noise alone its 95 % intervals miss the true
//! E'(f) at the peaks; with the estimated discretization error they hold it.

use super::common::GLASS;
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::convergence::mesh_errors;
use lamdyn_fem::eigen::{ModalParams, Silent, solve_modes};
use lamdyn_fem::element::ElementOrder;
use lamdyn_fem::mesh::Mesh;
use lamdyn_fem::mesh::structured::RectangleSpec;
use lamdyn_fit::fit::{FitResult, FitSettings, LawKind, fit};
use lamdyn_fit::misfit::{MisfitKind, MisfitSpec};
use lamdyn_fit::probe::{SensorMapping, probes_with};
use lamdyn_fit::synthesis::{ModalModel, ResidualTerm};
use lamdyn_fit::synthetic::add_noise;
use lamdyn_frf::{Channel, FrfSet, Quantity};
use lamdyn_material::law::{PaperEq7Law, ViscoelasticLaw};
use std::f64::consts::PI;

fn rectangle(order: ElementOrder, n: usize) -> RectangleSpec {
    RectangleSpec::flat(0.923, 0.8632, n, n)
        .with_order(order)
        .with_edge_layers(3, 0.5 * GLASS.thickness_m)
}

fn model_of(mesh: &Mesh, modes: usize, set_channels: (&[Channel], &[Channel])) -> ModalModel {
    let asm = Assembly::new(mesh, &GLASS, &[]).unwrap();
    let sol = solve_modes(&asm, &ModalParams::lowest(modes), &Silent).unwrap();
    let probe = |c: &[Channel]| probes_with(mesh, c, 0.01, SensorMapping::Surface).unwrap();
    ModalModel::new(
        &asm,
        &sol,
        &probe(set_channels.0),
        &probe(set_channels.1),
        GLASS.young_pa,
        ResidualTerm::Static,
    )
    .unwrap()
}

fn channels() -> (Vec<Channel>, Vec<Channel>) {
    let mut sensors = Vec::new();
    for j in 0..7 {
        for i in 0..7 {
            let p = [
                -0.40 + 0.8 * i as f64 / 6.0,
                -0.37 + 0.74 * j as f64 / 6.0,
                0.0,
            ];
            for (axis, d) in [
                ("X", [1.0, 0.0, 0.0]),
                ("Y", [0.0, 1.0, 0.0]),
                ("Z", [0.0, 0.0, 1.0]),
            ] {
                sensors.push(Channel::new(format!("{i}.{j}+{axis}"), p, d).unwrap());
            }
        }
    }
    let hammer = vec![Channel::new("hammer", [0.31, 0.17, 0.0], [0.0, 0.0, -1.0]).unwrap()];
    (sensors, hammer)
}

/// Peaks whose true E'(f) lies inside the fit's 95 % interval, of all peaks.
fn covered(r: &FitResult, law: &PaperEq7Law) -> (usize, usize) {
    let inside = r
        .peaks
        .iter()
        .filter(|pk| {
            let w = 2.0 * PI * pk.freq_hz;
            let (e, _, sd) = r.modulus_uncertainty(w);
            let sd = sd.expect("the fit has a covariance").0;
            (law.modulus(w).re - e).abs() <= 1.96 * sd
        })
        .count();
    (inside, r.peaks.len())
}

#[test]
fn intervals_with_the_discretization_error_cover_the_converged_answer() {
    let law = PaperEq7Law::paper_table2();
    let (sensors, hammer) = channels();
    let truth_mesh = rectangle(ElementOrder::Quadratic, 24).build().unwrap();
    let truth = model_of(&truth_mesh, 30, (&sensors, &hammer));
    let freqs: Vec<f64> = (1..=320).map(|k| 0.25 * f64::from(k)).collect();
    let clean: FrfSet = truth
        .frf_set(
            &freqs,
            &|w| law.modulus(w),
            Quantity::Accelerance,
            sensors.clone(),
            hammer.clone(),
        )
        .unwrap();
    let measured = add_noise(&clean, 0.01, 7);

    let spec = rectangle(ElementOrder::Linear, 16);
    let coarse = spec.build().unwrap();
    let plain = model_of(&coarse, 30, (&sensors, &hammer));
    let lift = spec.surface();
    let (errors, study) = mesh_errors(&coarse, Some(&lift), &GLASS, &[], 30, &Silent).unwrap();
    assert!(study.warnings.is_empty(), "{:?}", study.warnings);
    // The coarse mesh is too stiff: its elastic modes' errors are positive, 1e-3 and more.
    assert!(errors[6..12].iter().all(|&d| d > 1e-3), "{errors:?}");
    let with_error = plain.clone().with_frequency_errors(errors).unwrap();

    let settings = FitSettings::new(LawKind::PaperEq7, MisfitSpec::new(MisfitKind::LogRms));
    let noise_only = fit(&plain, &measured, &settings).unwrap();
    let both = fit(&with_error, &measured, &settings).unwrap();
    let (a, n) = covered(&noise_only, &law);
    let (b, m) = covered(&both, &law);
    eprintln!(
        "truth inside the 95 % interval: noise only {a} of {n} peaks, with the discretization \
         error {b} of {m}"
    );
    assert!(n >= 5);
    assert!(
        a < n,
        "noise-only intervals already cover every peak: the test shows nothing"
    );
    assert_eq!(
        b, m,
        "the discretization error did not widen the intervals enough"
    );
    // The same optimum: the estimate widens the intervals, it does not move the fit.
    assert_eq!(noise_only.values(), both.values());
    assert!(noise_only.discretization_shift.is_none());
    assert!(both.discretization_shift.is_some());
}
