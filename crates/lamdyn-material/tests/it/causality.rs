use lamdyn_material::causality::*;
use lamdyn_material::law::*;
use lamdyn_testkit::log_grid;
use num_complex::Complex64;
use std::f64::consts::FRAC_PI_2;

fn sample(law: &dyn ViscoelasticLaw, omega: &[f64]) -> Vec<Complex64> {
    omega.iter().map(|w| law.modulus(*w)).collect()
}

#[test]
fn causal_laws_pass_everywhere() {
    let omega = log_grid(1e-2, 1e12, 141); // 10 points per decade
    let laws: Vec<Box<dyn ViscoelasticLaw>> = vec![
        Box::new(FractionalZener::sandwich_benchmark_core()),
        Box::new(FractionalZener::new(2e6, 5e8, 1e-4, 0.35).unwrap()),
        Box::new(
            GeneralizedMaxwell::new(
                1e6,
                (0..12)
                    .map(|k| PronyTerm {
                        g_pa: 3e7,
                        tau_s: 10f64.powi(-k),
                    })
                    .collect(),
            )
            .unwrap(),
        ),
    ];
    for law in &laws {
        let report = kramers_kronig_check(
            &omega,
            &sample(law.as_ref(), &omega),
            CausalityParams::default(),
        )
        .unwrap();
        let bad: Vec<_> = report.violations().collect();
        assert!(bad.is_empty(), "{}: {:?}", law.describe(), bad.first());
        let min_ratio = report
            .lines
            .iter()
            .filter_map(|l| l.ratio)
            .fold(f64::INFINITY, f64::min);
        assert!(
            min_ratio >= 2.0 / std::f64::consts::PI * 0.99,
            "{}: min ratio {min_ratio}",
            law.describe()
        );
    }
}

/// A constant-Q (power-law) material G* = (iω)^n is exactly causal and has
/// r = tan(nπ/2)/(nπ/2); the second-order slope on 20 points per decade is good to ~n²h²/6.
#[test]
fn power_law_ratio_is_tan_n_pi_over_2_over_n_pi_over_2() {
    let n = 0.3;
    let omega = log_grid(1.0, 1e4, 81);
    let modulus: Vec<Complex64> = omega
        .iter()
        .map(|w| Complex64::from_polar(w.powf(n), n * FRAC_PI_2))
        .collect();
    let report = kramers_kronig_check(&omega, &modulus, CausalityParams::default()).unwrap();
    let want = (n * FRAC_PI_2).tan() / (n * FRAC_PI_2);
    for l in &report.lines[1..report.lines.len() - 1] {
        let r = l.ratio.unwrap();
        assert!((r / want - 1.0).abs() < 1e-3, "ratio {r} vs {want}");
        assert!(l.verdict.is_consistent());
    }
}

#[test]
fn paper_eq7_storage_falls() {
    let omega = log_grid(10.0, 600.0, 30);
    let law = PaperEq7Law::paper_table2();
    let report =
        kramers_kronig_check(&omega, &sample(&law, &omega), CausalityParams::default()).unwrap();
    assert!(
        report
            .lines
            .iter()
            .all(|l| l.verdict == CausalityVerdict::StorageFalls)
    );
}

/// The paper's quoted core: G' rising from 4.5 to 13.8 MPa over the band with a loss factor of
/// 0.05–0.065. A power-law rise of exponent n needs η ≈ tan(nπ/2) ≈ 1.6 here.
#[test]
fn paper_quoted_core_has_too_little_loss() {
    let f: Vec<f64> = (0..17).map(|i| 16.0 + 4.0 * i as f64).collect(); // 16..80 Hz
    let omega: Vec<f64> = f.iter().map(|f| 2.0 * std::f64::consts::PI * f).collect();
    let n = (13.8f64 / 4.5).ln() / 5f64.ln();
    let modulus: Vec<Complex64> = f
        .iter()
        .map(|f| {
            let g = 4.5e6 * (f / 16.0).powf(n);
            Complex64::new(g, 0.06 * g)
        })
        .collect();
    let report = kramers_kronig_check(&omega, &modulus, CausalityParams::default()).unwrap();
    assert!(
        report
            .lines
            .iter()
            .all(|l| l.verdict == CausalityVerdict::TooLittleLoss)
    );
    assert!(report.lines.iter().all(|l| l.ratio.unwrap() < 0.1));
}

#[test]
fn negative_loss_is_flagged() {
    let omega = [1.0, 2.0, 3.0];
    let modulus = [
        Complex64::new(1.0, 0.1),
        Complex64::new(1.0, -0.1),
        Complex64::new(1.0, 0.1),
    ];
    let report = kramers_kronig_check(&omega, &modulus, CausalityParams::default()).unwrap();
    assert_eq!(report.lines[1].verdict, CausalityVerdict::NegativeLoss);
    assert!(!report.is_causal());
}

#[test]
fn bad_data_is_refused_with_the_index() {
    let ok = [Complex64::new(1.0, 0.1); 3];
    let p = CausalityParams::default();
    let e = kramers_kronig_check(&[1.0, 3.0, 2.0], &ok, p)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "Kramers-Kronig check: frequencies must increase: [1] = 3 then [2] = 2"
    );
    let e = kramers_kronig_check(&[1.0, f64::NAN, 2.0], &ok, p)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "Kramers-Kronig check: frequency [1] = NaN is not a positive number"
    );
    let e = kramers_kronig_check(&[1.0, 2.0], &ok[..2], p)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "Kramers-Kronig check: needs at least 3 frequencies, got 2"
    );
    let e = kramers_kronig_check(&[1.0, 2.0, 3.0], &ok[..2], p)
        .unwrap_err()
        .to_string();
    assert_eq!(e, "Kramers-Kronig check: 3 frequencies but 2 moduli");
    let nan = [ok[0], Complex64::new(f64::NAN, 0.0), ok[0]];
    let e = kramers_kronig_check(&[1.0, 2.0, 3.0], &nan, p)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("Kramers-Kronig check: modulus [1] ="), "{e}");
}
