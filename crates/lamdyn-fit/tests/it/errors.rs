//! Inconsistent inputs give clear errors.

use super::common::*;
use lamdyn_fem::assembly::{Assembly, NodeSpring};
use lamdyn_fit::fit::{FitSettings, LawKind, fit};
use lamdyn_fit::misfit::{BandWeight, MisfitKind, MisfitSpec};
use lamdyn_fit::probe::probes;
use lamdyn_fit::synthesis::{ModalModel, ResidualTerm};
use lamdyn_fit::synthetic::triaxial_grid;
use lamdyn_frf::{Channel, FrfSet, Quantity};
use num_complex::Complex64;

#[test]
fn inconsistent_inputs() {
    let mesh = plate(8);
    let (asm, sol) = solve(&mesh, 12);
    let responses = triaxial_grid(&mesh, 3, 3);
    let refs = hammer(&mesh);
    // A sensor off the mesh.
    let off = vec![Channel::new("far", [2.0, 0.0, 0.0], [0.0, 0.0, 1.0]).unwrap()];
    let e = probes(&mesh, &off, 1e-3).unwrap_err().to_string();
    assert!(
        e.starts_with("channel 'far': point at (2, 0, 0) m: 1.5385e0 m from the mid-surface"),
        "{e}"
    );
    assert!(e.ends_with("(sensor off the mesh?)"), "{e}");
    // Supports: the basis must be the free part's, the supports given beside it.
    let sprung = Assembly::new(
        &mesh,
        &GLASS,
        &[NodeSpring {
            node: 0,
            translational_n_per_m: [0.0, 0.0, 1e3],
            rotational_nm_per_rad: [0.0; 3],
        }],
    )
    .unwrap();
    let e = ModalModel::new(
        &sprung,
        &sol,
        &probes_of(&mesh, &responses),
        &probes_of(&mesh, &refs),
        GLASS.young_pa,
        ResidualTerm::None,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("modal synthesis: the assembly has 1 support springs"),
        "{e}"
    );
    let m = model(&asm, &sol, &mesh, &responses, &refs, ResidualTerm::None);
    // Measured data with another channel count.
    let freqs = vec![10.0, 20.0, 30.0];
    let one = FrfSet::new(
        freqs.clone(),
        responses[..2].to_vec(),
        refs.clone(),
        Quantity::Accelerance,
        vec![Complex64::new(1.0, 0.0); 6],
    )
    .unwrap();
    let e = fit(
        &m,
        &one,
        &FitSettings::new(LawKind::PaperEq7, MisfitSpec::new(MisfitKind::Rms)),
    )
    .unwrap_err()
    .to_string();
    assert_eq!(
        e,
        "misfit: the model has 27 responses x 1 references, the measurement 2 x 1"
    );
    // Fewer lines than parameters.
    let few = FrfSet::new(
        freqs,
        responses.clone(),
        refs.clone(),
        Quantity::Accelerance,
        vec![Complex64::new(1.0, 0.0); 81],
    )
    .unwrap();
    let e = fit(
        &m,
        &few,
        &FitSettings::new(LawKind::PaperEq7, MisfitSpec::new(MisfitKind::Rms)),
    )
    .unwrap_err()
    .to_string();
    assert_eq!(
        e,
        "fit: 3 residuals for 4 parameters: widen the band or use more lines"
    );
    // Flat data: no peak to start from.
    let flat_freqs: Vec<f64> = (1..=20).map(|k| k as f64).collect();
    let flat = FrfSet::new(
        flat_freqs,
        responses.clone(),
        refs.clone(),
        Quantity::Accelerance,
        vec![Complex64::new(1.0, 0.0); 540],
    )
    .unwrap();
    let e = fit(
        &m,
        &flat,
        &FitSettings::new(LawKind::PaperEq7, MisfitSpec::new(MisfitKind::LogRms)),
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("fit: no resonance peak in the band"), "{e}");
    // Weights must be positive.
    let mut spec = MisfitSpec::new(MisfitKind::Rms);
    spec.weights = vec![BandWeight {
        band_hz: [1.0, 5.0],
        weight: 0.0,
    }];
    let e = fit(&m, &flat, &FitSettings::new(LawKind::PaperEq7, spec))
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "misfit: weights[0].weight = 0 must be positive and finite (use exclude_hz to leave a band \
         out)"
    );
    // NaN and non-increasing axes are refused by the set itself.
    let e = FrfSet::new(
        vec![1.0, 2.0],
        responses[..1].to_vec(),
        refs.clone(),
        Quantity::Receptance,
        vec![Complex64::new(f64::NAN, 0.0), Complex64::new(0.0, 0.0)],
    )
    .unwrap_err()
    .to_string();
    assert_eq!(e, "FRF set: value of response '1+X' at 1 Hz is not finite");
    let e = FrfSet::new(
        vec![2.0, 1.0],
        responses[..1].to_vec(),
        refs.clone(),
        Quantity::Receptance,
        vec![Complex64::new(0.0, 0.0); 2],
    )
    .unwrap_err()
    .to_string();
    assert_eq!(
        e,
        "FRF set: frequencies must increase: [0] = 2 Hz then [1] = 1 Hz"
    );
    // An empty band.
    let mut spec = MisfitSpec::new(MisfitKind::Rms);
    spec.band_hz = Some([100.0, 200.0]);
    let e = fit(&m, &few, &FitSettings::new(LawKind::PaperEq7, spec))
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "misfit: no frequency line lies in [100, 200] Hz outside the excluded bands"
    );
}
