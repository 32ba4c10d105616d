//! The simulated impact test on the curved roof laminate with a viscoelastic core.

use lamdyn_layered::mesh::HexMesh;
use lamdyn_layered::reduced::ReducedModel;
use lamdyn_layered::system::LayeredSystem;
use lamdyn_material::law::{FractionalZener, ViscoelasticLaw};
use lamdyn_testbench::cases::{ELASTIC_CORE, ccx_check_laminate};
use lamdyn_testbench::impact::{ImpactTest, hammer_load, simulate, surface_frame};
use std::f64::consts::PI;

struct Bench {
    mesh: HexMesh,
    model: ReducedModel,
    law: FractionalZener,
    g_a: f64,
}

/// 8 × 8 curved laminate, fractional Zener core, basis for a hammer at `hammers`.
fn bench(hammers: &[[f64; 2]]) -> (Bench, Vec<ImpactTest>) {
    let (spec, materials) = ccx_check_laminate(8, 8, 3.0, 5.0);
    let mesh = spec.build().unwrap();
    let sys = LayeredSystem::assemble(&mesh, &materials).unwrap();
    let law = FractionalZener::new(0.3e6, 300e6, 1e-4, 0.55).unwrap();
    let g_a = ELASTIC_CORE.young_pa / (2.0 * (1.0 + ELASTIC_CORE.poisson));
    let tests: Vec<ImpactTest> = hammers
        .iter()
        .map(|h| ImpactTest {
            step_hz: 0.5,
            ..ImpactTest::grid(&mesh, 5, 5, *h)
        })
        .collect();
    // Loads of every hammer position in the basis.
    let loads: Vec<Vec<f64>> = tests
        .iter()
        .map(|t| hammer_load(&mesh, t).unwrap())
        .collect();
    let ratios = [1.0, 80.0].map(|f: f64| law.modulus(2.0 * PI * f).norm() / g_a);
    let model = ReducedModel::new(&sys, &[1], &ratios, 30, &loads, -(2.0 * PI).powi(2)).unwrap();
    (
        Bench {
            mesh,
            model,
            law,
            g_a,
        },
        tests,
    )
}

#[test]
fn frames_reciprocity_and_bad_sensors() {
    // The hammer at the first sensor's point and at the centre.
    let (b, tests) = bench(&[[0.1, 0.1], [0.5, 0.5]]);
    let scale = |w: f64| b.law.modulus(w) / b.g_a;
    let (t0, t1) = (&tests[0], &tests[1]);
    assert_eq!(
        t0.sensors[0], t0.hammer,
        "the first sensor sits under the first hammer"
    );
    let a = simulate(&b.mesh, &b.model, &scale, t0).unwrap();
    let c = simulate(&b.mesh, &b.model, &scale, t1).unwrap();
    assert_eq!(a.responses().len(), 75);
    // Reciprocity: normal response at the centre sensor (index 12) to a hit at sensor 0 equals
    // the normal response at sensor 0 to a hit at the centre (the hammer hits along −n and the
    // sensor reads +n: both FRFs carry the same sign).
    let centre = 3 * 12 + 2;
    assert_eq!(t0.sensors[12], t1.hammer);
    let (h01, h10) = (a.curve(centre, 0), c.curve(2, 0));
    let freqs = a.freqs_hz();
    // Measured: ~1e-7 above 5 Hz; 1.3e-4 at 0.5 Hz, where the six rigid-body modes dominate and
    // round-off in their (nearly zero) stiffness is magnified by 1/ω².
    for ((x, y), f) in h01.iter().zip(h10).zip(freqs) {
        let tol = if *f >= 5.0 { 1e-5 } else { 1e-3 };
        assert!((x - y).norm() <= tol * x.norm(), "{f} Hz: {x} vs {y}");
    }
    // Frames are orthonormal and right-handed.
    let n = [0.1, -0.2, 0.97f64];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let f = surface_frame([n[0] / l, n[1] / l, n[2] / l]);
    for i in 0..3 {
        for j in 0..3 {
            let d: f64 = (0..3).map(|k| f[i][k] * f[j][k]).sum();
            assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
        }
    }
    // A sensor 1 cm above the surface.
    let mut bad = t0.clone();
    bad.sensors[3][2] += 0.01;
    let e = simulate(&b.mesh, &b.model, &scale, &bad)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sensor S1.4") && e.contains("from the top surface"),
        "{e}"
    );
}

/// The chain's first stage on simulated data: lamdyn-ema identifies the roof's modes from the
/// 75 noisy FRFs (40 dB) and the regenerated FRFs correlate with them.
#[test]
fn ema_identifies_the_simulated_roof() {
    let (b, tests) = bench(&[[0.3, 0.35]]);
    let scale = |w: f64| b.law.modulus(w) / b.g_a;
    let test = ImpactTest {
        snr_db: Some(40.0),
        ..tests[0].clone()
    };
    let set = simulate(&b.mesh, &b.model, &scale, &test).unwrap();
    let r = lamdyn_ema::identify::identify(
        &set,
        &lamdyn_ema::identify::EmaSettings {
            band_hz: Some([5.0, 80.0]),
            ..Default::default()
        },
    )
    .unwrap();
    let fracs: Vec<f64> = r.correlation.clone();
    let good = fracs.iter().filter(|c| **c > 0.95).count();
    eprintln!(
        "{} modes: {:?} Hz; FRAC > 0.95 on {good} of {} curves (min {:.3})",
        r.modes.len(),
        r.modes
            .iter()
            .map(|m| (m.freq_hz * 100.0).round() / 100.0)
            .collect::<Vec<_>>(),
        fracs.len(),
        fracs.iter().copied().fold(1.0, f64::min)
    );
    assert!(r.modes.len() >= 3);
    assert!(good * 10 >= fracs.len() * 9, "{fracs:?}");
}
