//! The FRF fit's identification stage (lamdyn_fit::frf_fit) at the size of issue 44's target:
//! 81 channels (27 triaxial sensors) × 401 lines (20–220 Hz at 0.5 Hz), one hammer, the free
//! damped glass plate of `tests/frf_fit.rs` (glass 3 / acoustic PVB 0.76 / glass 3 mm, modal
//! damping 3–19 %), truth on 24 × 18 graded, 1 % noise, identified on an 18 × 14 model.
//!
//! Prints, for 1 and 2 rayon threads: the basis's build, one sweep of the model over the lines
//! (one LU of the reduced dynamic stiffness per line: what an evaluation of the residuals and
//! the Jacobian costs, independent of the full model's dofs once the basis is built), the
//! whole fit with its evaluations and iterations, the time per evaluation and per iteration,
//! and whether the two fits are the same bits.
//!
//! `cargo bench -p lamdyn-testbench --bench frf_fit`

#[path = "../tests/common/glass_plate.rs"]
mod glass_plate;

use glass_plate::{bench, glass_plate, observed};
use lamdyn_fit::frf_fit::{FrfFit, FrfFitSettings, FrfLaw, fit_core_to_frfs};
use std::f64::consts::PI;
use std::time::Instant;

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    let truth = bench(&glass_plate([24, 18], 0.2, [9, 3], Some(40.0), 3));
    let set = truth.frfs().expect("FRFs");
    let band = [20.0, 220.0];
    let lines = set
        .freqs_hz()
        .iter()
        .filter(|f| (band[0]..=band[1]).contains(*f))
        .count();
    let coarse = bench(&glass_plate([18, 14], 0.0, [9, 3], None, 3));
    let g_a = coarse.assembled_modulus_pa;
    let mut fits: Vec<FrfFit> = Vec::new();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let t = Instant::now();
            let model = observed(&coarse, &set, &[0.5, 2.0], 30);
            let build_s = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let omegas: Vec<f64> = set
                .freqs_hz()
                .iter()
                .filter(|f| (band[0]..=band[1]).contains(*f))
                .map(|f| 2.0 * PI * f)
                .collect();
            use rayon::prelude::*;
            let s = truth.core_law.modulus(2.0 * PI * 80.0) / g_a;
            let ok = omegas
                .par_iter()
                .map(|&w| model.receptance(w, s).is_ok())
                .filter(|&b| b)
                .count();
            let sweep_s = t.elapsed().as_secs_f64();
            let law = FrfLaw::generalized_maxwell_over(band[0], band[1]);
            let t = Instant::now();
            let fit = fit_core_to_frfs(&model, &set, law, g_a, None, &FrfFitSettings::over(band))
                .expect("fit");
            let fit_s = t.elapsed().as_secs_f64();
            println!(
                "{threads} thread(s): {} channels x {lines} lines, basis {} vectors built in \
                 {build_s:.2} s; one sweep ({ok} LUs) {sweep_s:.3} s; fit {fit_s:.1} s: {} \
                 iterations ({:.2} s each), {} evaluations ({:.3} s each) over all starts and \
                 passes; {}",
                set.responses().len(),
                model.basis_size(),
                fit.work[0],
                fit_s / fit.work[0].max(1) as f64,
                fit.work[1],
                fit_s / fit.work[1].max(1) as f64,
                fit.describe()
            );
            fits.push(fit);
        });
    }
    let same = fits[0]
        .u
        .iter()
        .zip(&fits[1].u)
        .all(|(a, b)| a.to_bits() == b.to_bits())
        && fits[0].gains[0].to_bits() == fits[1].gains[0].to_bits();
    println!("same bits on 1 and 2 threads: {same}");
    for f in [25.0, 80.0, 150.0, 200.0] {
        let t = truth.core_law.modulus(2.0 * PI * f);
        let p = fits[1].at(f);
        println!(
            "{f:5.0} Hz: G' {:+.2} %, eta {:+.2} %",
            100.0 * (p.storage_pa / t.re - 1.0),
            100.0 * (p.loss_factor / (t.im / t.re) - 1.0)
        );
    }
}
