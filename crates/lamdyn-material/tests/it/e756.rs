use lamdyn_material::e756::*;
use lamdyn_testkit::rel_err_f64;
use num_complex::Complex64;
use proptest::prelude::*;

/// β_n l of the clamped–free beam as tabulated in ASTM E756-05 (five decimals).
#[test]
fn clamped_free_roots_match_the_standard() {
    let table = [1.87510, 4.69409, 7.85476, 10.99554, 14.13717, 17.27876];
    for (n, want) in table.iter().enumerate() {
        let x = clamped_free_root(n + 1);
        assert!((x - want).abs() < 5e-6, "mode {}: {x} vs {want}", n + 1);
        assert!(
            (1.0 + x.cos() * x.cosh()).abs() < 1e-12 * x.cosh(),
            "mode {} residual",
            n + 1
        );
    }
    // High modes tend to (2n − 1)π/2.
    let x = clamped_free_root(20);
    assert!((x - 39.0 * std::f64::consts::PI / 2.0).abs() < 1e-12);
}

/// A steel reed by hand: f_1 = (1.87510²/(2π l²)) √(E H²/(12ρ)).
#[test]
fn uniform_beam_first_mode_by_hand() {
    let beam = UniformBeam::new(0.2, 1e-3, 7850.0).unwrap();
    let r = beam.resonance(1, 200e9, 0.0).unwrap();
    let by_hand = 1.87510f64.powi(2) / (2.0 * std::f64::consts::PI * 0.04)
        * (200e9f64 * 1e-6 / (12.0 * 7850.0)).sqrt();
    assert!(
        rel_err_f64(r.freq_hz, by_hand) < 1e-5,
        "{} vs {by_hand}",
        r.freq_hz
    );
}

proptest! {
    #![proptest_config(lamdyn_testkit::proptest_config(256))]
    #[test]
    fn uniform_beam_round_trips(l in 0.05f64..0.5, h in 5e-4f64..5e-3, e in 1e9f64..3e11, eta in 0.0f64..0.1, n in 1usize..7) {
        let beam = UniformBeam::new(l, h, 7850.0).unwrap();
        let r = beam.resonance(n, e, eta).unwrap();
        let back = beam.reduce(n, r.freq_hz, r.loss_factor).unwrap();
        prop_assert!(rel_err_f64(back.storage_pa, e) < 1e-12);
        prop_assert!((back.loss_factor - eta).abs() <= 1e-14);
    }

    /// RKU forward model → E756 sandwich reduction recovers G_1 and η_1 to 1e-10 wherever the
    /// beam can measure the core at all: a 0.1 % change of G_1 must move f²(1+iη) by more than
    /// 1e-6 (sensitivity > 1e-3). Beyond, rounding in f is amplified by 1/sensitivity; the
    /// verification example prints both regimes.
    #[test]
    fn sandwich_beam_round_trips(
        l in 0.1f64..0.3, h in 5e-4f64..3e-3, t in 0.05f64..2.0, g in 1e4f64..1e8,
        eta in 0.0f64..2.0, n in 1usize..7,
    ) {
        let beam = SandwichBeam::new(UniformBeam::new(l, h, 7850.0).unwrap(), 200e9, t * h, 1100.0).unwrap();
        let (base, s) = beam.resonances(n, g, eta).unwrap();
        prop_assume!(sensitivity(s, beam.resonances(n, g * 1.001, eta).unwrap().1) > 1e-3);
        let back = beam.reduce(n, base.freq_hz, s.freq_hz, s.loss_factor).unwrap();
        prop_assert!(rel_err_f64(back.storage_pa, g) < 1e-10, "G {} vs {g}", back.storage_pa);
        prop_assert!((back.loss_factor - eta).abs() < 1e-10 * eta.max(1e-3), "eta {} vs {eta}", back.loss_factor);
    }

    /// Oberst forward → exact complex reduction recovers E_1 and η_1 to 1e-10 (same sensitivity
    /// condition); the standard's first-order reduction is off by O(η_1²).
    #[test]
    fn oberst_beam_round_trips(
        h in 5e-4f64..3e-3, t in 0.2f64..3.0, e1 in 1e6f64..1e10, eta in 0.0f64..1.0, n in 1usize..7,
    ) {
        let beam = OberstBeam::new(UniformBeam::new(0.2, h, 7850.0).unwrap(), 200e9, t * h, 1100.0).unwrap();
        let (base, c) = beam.resonances(n, e1, eta).unwrap();
        prop_assume!(sensitivity(c, beam.resonances(n, e1 * 1.001, eta).unwrap().1) > 1e-3);
        let exact = beam.reduce_exact(n, base.freq_hz, c.freq_hz, c.loss_factor).unwrap();
        prop_assert!(rel_err_f64(exact.storage_pa, e1) < 1e-10, "E1 {} vs {e1}", exact.storage_pa);
        prop_assert!((exact.loss_factor - eta).abs() < 1e-10 * eta.max(1e-2));
        let std = beam.reduce(n, base.freq_hz, c.freq_hz, c.loss_factor).unwrap();
        prop_assert!((std.loss_factor / eta.max(1e-12) - 1.0).abs() < 0.6 * eta * eta + 1e-6, "eta {} vs {eta}", std.loss_factor);
    }
}

/// |Δλ/λ| / 1e-3 between two resonances whose material differs by 0.1 %, λ = f²(1 + iη).
fn sensitivity(a: Resonance, b: Resonance) -> f64 {
    let lam = |r: Resonance| Complex64::new(r.freq_hz.powi(2), r.freq_hz.powi(2) * r.loss_factor);
    (lam(a) - lam(b)).norm() / lam(a).norm() / 1e-3
}

#[test]
fn e756_errors_name_the_problem() {
    let beam = UniformBeam::new(0.2, 1e-3, 7850.0).unwrap();
    assert_eq!(
        beam.reduce(0, 10.0, 0.0).unwrap_err().to_string(),
        "uniform beam: mode = 0 must be 1 or more (modes are numbered from 1)"
    );
    assert_eq!(
        beam.reduce(1, -10.0, 0.0).unwrap_err().to_string(),
        "uniform beam: f_hz = -10 must be positive"
    );
    assert_eq!(
        UniformBeam::new(0.0, 1e-3, 7850.0).unwrap_err().to_string(),
        "uniform beam: length_m = 0 must be positive"
    );
    let oberst = OberstBeam::new(beam, 200e9, 1e-3, 1100.0).unwrap();
    let m = oberst.reduce(1, 30.0, 20.0, 0.01).unwrap_err().to_string();
    assert!(
        m.starts_with("Oberst reduction, mode 1: alpha = (f_c/f_n)^2 (1 + D T) = "),
        "{m}"
    );
    let sandwich = SandwichBeam::new(beam, 200e9, 1e-3, 1100.0).unwrap();
    let m = sandwich.reduce(1, 30.0, 5.0, 0.1).unwrap_err().to_string();
    assert!(m.starts_with("sandwich reduction, mode 1: A = "), "{m}");
}

/// A beam thickness in mm (1.5 for 1.5 mm) used to give G1 = 2915 MPa; now refused.
#[test]
fn e756_refuses_millimetres_and_gigapascals() {
    let e = UniformBeam::new(0.2, 1.5, 7850.0).unwrap_err().to_string();
    assert!(e.contains("thickness_m = 1.5") && e.contains("in m"), "{e}");
    let beam = UniformBeam::new(0.2, 1.5e-3, 7850.0).unwrap();
    let e = SandwichBeam::new(beam, 200.0, 1e-3, 1100.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("young_pa = 200") && e.contains("GPa"), "{e}");
    let e = OberstBeam::new(beam, 200e9, 1e-3, 1.1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("g/cm^3"), "{e}");
}
