//! The convergence ladder on the paper's roof (glass 1.715 mm / PVB 0.42 mm / glass, 0.923 ×
//! 0.8632 m, radii 3 m and 5 m), against a truth on a finer, edge-graded mesh:
//! `roof_ladder TRUTH_N TRUTH_GRADING START_N [TOLERANCE [MAX_LEVELS [SHIFT [K_Z C_Z PATCH]]]]`,
//! SHIFT the WLF factor a_T of the core's law (1: the demo's 20 °C; 7.2: its 14 °C, c1 = 12,
//! c2 = 90 K); K_Z > 0 puts the roof on four supports at 15 % and 85 % of its plan (vertical
//! stiffness K_Z N/m each, horizontal a fifth, dashpots C_Z N s/m vertical and half that
//! horizontal, square contact patches of side PATCH m); without, it is free.
//!
//! The truth's poles: for each mode below 80 Hz, λ on the truth mesh at the core's G*(ω*) of
//! the demo's fractional Zener law at the pole's own complex frequency ω* = √λ (the complex
//! fixed point; the dashpots act there too). The ladder then starts from G* 30 % off and its
//! result is compared with G*(ω*). Prints one row per mode and the timings (docs/run.md,
//! "Convergence of the layered inverse").

#[path = "common/roof.rs"]
mod roof;

use lamdyn_layered::convergence::{LadderSettings, build_level, converge};
use lamdyn_layered::inverse::LayeredInverse;
use lamdyn_material::law::ViscoelasticLaw;
use num_complex::Complex64;
use std::f64::consts::PI;
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: &str| a.get(i).cloned().unwrap_or(d.into());
    let truth_n: usize = arg(1, "32").parse().expect("TRUTH_N");
    let truth_grading: f64 = arg(2, "0.3").parse().expect("TRUTH_GRADING");
    let start_n: usize = arg(3, "12").parse().expect("START_N");
    let settings = LadderSettings {
        tolerance: arg(4, "1e-4").parse().expect("TOLERANCE"),
        max_levels: arg(5, "5").parse().expect("MAX_LEVELS"),
        ..LadderSettings::default()
    };
    let law = roof::law();
    let shift: f64 = arg(6, "1").parse().expect("SHIFT");
    let g = |w: Complex64| law.modulus_at_complex(w * shift);
    let kz: f64 = arg(7, "0").parse().expect("K_Z");
    let cz: f64 = arg(8, "0").parse().expect("C_Z");
    let patch: f64 = arg(9, "0").parse().expect("PATCH");
    let plate = |grading: f64| {
        let mut p = roof::plate(grading);
        if kz > 0.0 {
            p.supports = roof::corner_supports(kz, cz, patch);
        }
        p
    };
    // G_ref as the chain takes it: a power of two near the core's G' mid-band.
    let g_ref = 2f64.powf(g(Complex64::new(2.0 * PI * 40.0, 0.0)).re.log2().round());
    let t = Instant::now();
    let truth =
        LayeredInverse::build(&plate(truth_grading), [truth_n; 2], g_ref, 30).expect("truth model");
    let truth_s = t.elapsed().as_secs_f64();
    let hz = |l: Complex64| l.re.sqrt() / (2.0 * PI);
    let mut poles = Vec::new();
    for rank in 0..16 {
        let mut lambda = Complex64::new((2.0 * PI * 30.0f64).powi(2), 0.0);
        for _ in 0..40 {
            lambda = truth
                .elastic_eigenvalue(g(lambda.sqrt()), rank, lambda)
                .expect("mode");
        }
        let f = hz(lambda);
        if f > 80.0 {
            break;
        }
        // The supports' rigid-body modes (the core does not move them) are no target.
        let up = truth
            .elastic_eigenvalue(g(lambda.sqrt()) * 1.01, rank, lambda)
            .expect("mode");
        if (up / lambda - 1.0).norm() > 1e-6 {
            poles.push((lambda.sqrt(), lambda));
        }
    }
    let targets: Vec<Complex64> = poles.iter().map(|p| p.1).collect();
    let starts: Vec<Complex64> = poles.iter().map(|p| g(p.0) * 1.3).collect();
    let poles: Vec<(f64, Complex64)> = poles.iter().map(|p| (p.0.re / (2.0 * PI), p.0)).collect();
    let t = Instant::now();
    let coarsest = LayeredInverse::build(&plate(0.0), [start_n; 2], g_ref, 30).expect("model");
    let coarsest_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let out = converge(
        &coarsest,
        [start_n; 2],
        &|m| build_level(&plate(0.0), m, g_ref, settings.modes),
        &targets,
        &starts,
        &settings,
        &|m| eprintln!("{m}"),
    );
    let ladder_s = t.elapsed().as_secs_f64();
    let (dofs, _) = truth.size();
    println!(
        "truth {truth_n} x {truth_n} grading {truth_grading} ({dofs} dofs, {truth_s:.1} s); \
         coarsest {start_n} x {start_n} ({coarsest_s:.1} s); ladder {ladder_s:.1} s"
    );
    let out = match out {
        Ok(o) => o,
        Err(e) => {
            println!("ladder: {e}");
            return;
        }
    };
    println!("meshes {:?} dofs {:?}", out.meshes, out.dofs);
    println!(
        "f_Hz  G'_err_%  eta_err_%  coarsest_G'_err_%  coarsest_eta_err_%  f_err_finest  eta_err_finest  residual_f  band_G'_%  band_eta_%  p  p_loss"
    );
    let eta = |x: Complex64| x.im / x.re;
    for ((f, w), m) in poles.iter().zip(&out.modes) {
        let truth = g(*w);
        match m {
            Ok(m) => println!(
                "{f:.3}  {:+.3}  {:+.3}  {:+.2}  {:+.2}  {:+.2e}  {:+.2e}  {:.1e}  {:.2}  {:.2}  {:.2}  {:.2}{}",
                100.0 * (m.core_shear_pa.re / truth.re - 1.0),
                100.0 * (eta(m.core_shear_pa) / eta(truth) - 1.0),
                100.0 * (m.coarsest_pa.re / truth.re - 1.0),
                100.0 * (eta(m.coarsest_pa) / eta(truth) - 1.0),
                m.freq_error,
                m.loss_error,
                m.residual_freq_error,
                100.0 * m.storage_band,
                100.0 * m.loss_band,
                m.order,
                m.loss_order,
                if m.asymptotic {
                    ""
                } else {
                    " (not asymptotic: p = 2)"
                }
            ),
            Err(e) => println!("{f:.3}  {e}"),
        }
    }
}
