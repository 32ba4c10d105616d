//! Misfit definitions: band weights scale residuals by √w; the log-RMS and RMS residuals vanish
//! on the data's own law.

use super::common::*;
use lamdyn_fit::misfit::{BandWeight, MisfitKind, MisfitSpec, Objective};
use lamdyn_fit::synthesis::ResidualTerm;
use lamdyn_fit::synthetic::triaxial_grid;
use lamdyn_frf::Quantity;
use num_complex::Complex64;

#[test]
fn weights_scale_residuals_and_own_law_fits_exactly() {
    let mesh = plate(8);
    let (asm, sol) = solve(&mesh, 14);
    let responses = triaxial_grid(&mesh, 3, 3);
    let refs = hammer(&mesh);
    let m = model(&asm, &sol, &mesh, &responses, &refs, ResidualTerm::None);
    let freqs: Vec<f64> = (1..=60).map(|k| 2.0 * k as f64).collect();
    let law = |w: f64| Complex64::new(60e9 * (1.0 - 1e-4 * w), 0.01 * 60e9);
    let data = m
        .frf_set(&freqs, &law, Quantity::Mobility, responses, refs)
        .unwrap();
    let other = |w: f64| law(w) * 1.01;
    for kind in [MisfitKind::Rms, MisfitKind::LogRms, MisfitKind::Complex] {
        let plain = Objective::new(&m, &data, MisfitSpec::new(kind)).unwrap();
        let own = plain.residuals(&law);
        let worst = own.iter().map(|r| r.abs()).fold(0.0, f64::max);
        assert!(
            worst < 1e-12,
            "{kind:?}: residual {worst} on the data's own law"
        );
        let mut spec = MisfitSpec::new(kind);
        spec.weights = vec![BandWeight {
            band_hz: [30.0, 50.0],
            weight: 4.0,
        }];
        let weighted = Objective::new(&m, &data, spec).unwrap();
        let (a, b) = (plain.residuals(&other), weighted.residuals(&other));
        let per_line = a.len() / plain.lines().len();
        for (n, (ra, rb)) in a.iter().zip(&b).enumerate() {
            let f = freqs[plain.lines()[n / per_line]];
            let factor = if (30.0..=50.0).contains(&f) { 2.0 } else { 1.0 };
            assert!(
                (rb - factor * ra).abs() <= 1e-15 * ra.abs().max(1.0),
                "{kind:?} at {f} Hz"
            );
        }
    }
}
