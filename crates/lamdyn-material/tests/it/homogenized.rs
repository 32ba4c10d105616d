use lamdyn_material::laminate::*;
use lamdyn_material::law::{FractionalZener, ViscoelasticLaw};
use lamdyn_material::sandwich::MeadMarkus;
use lamdyn_testkit::{assert_rel, rel_err};
use num_complex::Complex64;
use proptest::prelude::*;
use std::f64::consts::PI;
use std::sync::Arc;

proptest! {
    #![proptest_config(lamdyn_testkit::proptest_config(256))]
    /// Eq. 37 inverts eq. 29 exactly: φ → κ = (√(1+φ²)+φ)² → φ.
    #[test]
    fn eq37_inverts_eq29(re in 1e-6f64..2.0, im in -0.5f64..0.5) {
        let phi = Complex64::new(re, im * re);
        let b_eq = Complex64::new(300.0, 0.0);
        let kappa = b_eq / apparent_stiffness(b_eq, phi);
        prop_assert!(rel_err(phi_from_stiffness_ratio(kappa), phi) < 1e-12);
    }

    /// Eq. 29 is the shear beam without rotary inertia: B_K k⁴ = ρ_S ω² with
    /// 1/B_K = 1/B_eq + k²/K_eq.
    #[test]
    fn eq29_is_the_shear_beam_dispersion(w in 1.0f64..1e4, k_eq in 1e3f64..1e7) {
        let (rho, b) = (10.4, Complex64::new(330.0, 0.0));
        let k_eq = Complex64::new(k_eq, 0.0);
        let bk = apparent_stiffness(b, phi(w, rho, b, k_eq));
        let k2 = w * (rho / bk).sqrt();
        prop_assert!(rel_err(1.0 / bk, 1.0 / b + k2 / k_eq) < 1e-12);
    }
}

fn roof_with(law: Arc<dyn ViscoelasticLaw>) -> LayerStack {
    SandwichStack::paper_roof().with_core_law(law).unwrap()
}

/// B_K → B_eq as ω → 0 (eq. 29 with φ → 0).
#[test]
fn apparent_stiffness_tends_to_bonded_at_low_frequency() {
    let stack = roof_with(Arc::new(FractionalZener::new(2e6, 1e9, 1e-5, 0.5).unwrap()));
    for w in [1e-3, 1e-6, 1e-9] {
        let h = stack.homogenize(w, Kinematics::Beam).unwrap();
        let gap = rel_err(h.b_k, h.b_eq);
        assert!(
            gap <= 2.0 * h.phi.norm() * 1.001,
            "omega {w}: gap {gap}, phi {}",
            h.phi
        );
    }
    let h = stack.homogenize(1e-9, Kinematics::Beam).unwrap();
    assert!(rel_err(h.b_k, h.b_eq) < 1e-9);
}

/// The paper's homogenization against exact sandwich theory (method-notes §3): while φ < 0.1 the
/// paper's B_K is within 1 % of Mead–Markus; beyond, the gap grows. Both models here make the
/// same assumptions (faces rigid in shear, core without bending: eqs. 35, 40, 41).
#[test]
fn paper_model_within_one_percent_of_mead_markus_while_phi_below_limit() {
    let stack = SandwichStack::paper_roof();
    let opts = PaperInverseOptions::default();
    let mm = MeadMarkus::new(&stack, Kinematics::Beam);
    let mut worst_inside: f64 = 0.0;
    let mut seen_beyond = false;
    for g in [1e5, 3e5, 1e6, 3e6, 1e7] {
        let g = Complex64::new(g, 0.3 * g);
        for f in [1.0, 5.0, 10.0, 20.0, 40.0, 80.0, 160.0, 320.0, 640.0] {
            let w = 2.0 * PI * f;
            let paper = paper_forward(&stack, w, g, &opts).unwrap();
            let exact = mm.wave(g, w).stiffness;
            let gap = rel_err(paper.b_k, exact);
            if paper.within_accuracy_limit() {
                worst_inside = worst_inside.max(gap);
                assert!(paper.warning().is_none());
            } else {
                seen_beyond = true;
                assert!(paper.warning().is_some());
            }
        }
    }
    assert!(
        worst_inside < 0.01,
        "worst gap inside phi < 0.1: {worst_inside}"
    );
    assert!(seen_beyond);
}

#[test]
fn warning_message_names_phi_and_frequency() {
    let w = ModelWarning::check(2.0 * PI * 80.0, Complex64::new(0.2, 0.01)).unwrap();
    let m = w.to_string();
    assert!(m.starts_with("phi = 0.200 > 0.1 at 80.00 Hz"), "{m}");
    assert!(ModelWarning::check(1.0, Complex64::new(0.05, 0.0)).is_none());
}

/// Plate kinematics: E → E/(1−ν²) in every layer, E_eff reported for a plate of ν.
#[test]
fn plate_kinematics_scale_the_bending_moduli() {
    let stack = roof_with(Arc::new(FractionalZener::sandwich_benchmark_core()));
    let nu = 0.22;
    let w = 2.0 * PI * 30.0;
    let beam = stack.section(w, Kinematics::Beam);
    let plate = stack.section(w, Kinematics::Plate { poisson: nu });
    let f = 1.0 / (1.0 - nu * nu);
    assert_rel(
        "glass",
        plate.layers()[0].young_pa,
        beam.layers()[0].young_pa * f,
        1e-15,
    );
    let h = stack
        .homogenize(w, Kinematics::Plate { poisson: nu })
        .unwrap();
    assert_rel(
        "E_eff",
        h.e_eff,
        12.0 * h.b_k / h.thickness_m.powi(3) * (1.0 - nu * nu),
        1e-15,
    );
    let bad = stack
        .homogenize(w, Kinematics::Plate { poisson: 0.7 })
        .unwrap_err()
        .to_string();
    assert_eq!(bad, "plate kinematics: poisson = 0.7 must lie in (-1, 0.5)");
}
