use lamdyn_material::laminate::*;
use lamdyn_material::sandwich::*;
use lamdyn_testkit::rel_err;
use num_complex::Complex64;
use proptest::prelude::*;

proptest! {
    #![proptest_config(lamdyn_testkit::proptest_config(256))]
    /// RKU with E_2 → 0 is Mead–Markus at the same wavenumber.
    #[test]
    fn rku_without_core_extension_is_mead_markus(
        h1 in 5e-4f64..5e-3, h2 in 5e-5f64..3e-3, h3 in 5e-4f64..5e-3,
        e1 in 1e10f64..2e11, e3 in 1e10f64..2e11, g in 1e3f64..1e9, eta in 0.0f64..1.5, k in 0.1f64..200.0,
    ) {
        let face = |h: f64, e: f64| Face { thickness_m: h, density_kg_m3: 2500.0, young_pa: e, poisson: 0.3, loss_factor: 0.0 };
        let s = SandwichStack::new(face(h1, e1), CoreGeometry { thickness_m: h2, density_kg_m3: 1000.0, poisson: 0.49 }, face(h3, e3), None).unwrap();
        let g = Complex64::new(g, g * eta);
        let rku = RkuBeam { h1_m: h1, e1_pa: e1.into(), h2_m: h2, e2_pa: 0.0.into(), h3_m: h3, e3_pa: e3.into() };
        let mm = MeadMarkus::new(&s, Kinematics::Beam).stiffness_at_wavenumber(g, k);
        prop_assert!(rel_err(rku.flexural_rigidity(g, k), mm) < 1e-12);
    }

    /// RKU with g → ∞ is the perfectly bonded three-layer stack (eqs. 14–18), core included.
    #[test]
    fn rku_with_infinite_shear_is_the_bonded_stack(
        h in prop::array::uniform3(1e-4f64..5e-3),
        e in prop::array::uniform3(1e6f64..2e11),
        eta2 in 0.0f64..1.0,
    ) {
        let e2 = Complex64::new(e[1], e[1] * eta2);
        let rku = RkuBeam { h1_m: h[0], e1_pa: e[0].into(), h2_m: h[1], e2_pa: e2, h3_m: h[2], e3_pa: e[2].into() };
        let one = Complex64::new(1.0, 0.0);
        let bonded = Section::new([(h[0], e[0].into(), one), (h[1], e2, one), (h[2], e[2].into(), one)], 1.0).bending_stiffness();
        // The slip terms decay as 1/g; at g = 1e15 they are below 1e-12 of EI.
        let ei = rku.flexural_rigidity_at_shear_parameter(Complex64::new(1e15, 0.0));
        prop_assert!(rel_err(ei, bonded) < 1e-11, "{ei} vs {bonded}");
    }
}

/// RKU (E_2 = 0) and Mead–Markus against an independent symbolic energy derivation
/// (`testdata/rku/derive.py`, values to 17 digits).
#[test]
fn rku_and_mead_markus_match_the_energy_derivation() {
    let text = include_str!("../../testdata/rku/values.json");
    let doc: serde_json::Value = serde_json::from_str(text).unwrap();
    for case in doc["cases"].as_array().unwrap() {
        let x = |k: &str| case[k].as_f64().unwrap();
        let (h1, h2, h3) = (x("h1_m"), x("h2_m"), x("h3_m"));
        let g = Complex64::new(x("g2_pa"), 0.0);
        let want = Complex64::new(x("flexural_rigidity_n_m"), 0.0);
        let rku = RkuBeam {
            h1_m: h1,
            e1_pa: x("e1_pa").into(),
            h2_m: h2,
            e2_pa: 0.0.into(),
            h3_m: h3,
            e3_pa: x("e3_pa").into(),
        };
        assert!(
            rel_err(rku.flexural_rigidity(g, x("k_rad_m")), want) < 1e-13,
            "RKU {case}"
        );
        let face = |h: f64, e: f64| Face {
            thickness_m: h,
            density_kg_m3: 2500.0,
            young_pa: e,
            poisson: 0.3,
            loss_factor: 0.0,
        };
        let s = SandwichStack::new(
            face(h1, x("e1_pa")),
            CoreGeometry {
                thickness_m: h2,
                density_kg_m3: 1000.0,
                poisson: 0.49,
            },
            face(h3, x("e3_pa")),
            None,
        )
        .unwrap();
        let mm = MeadMarkus::new(&s, Kinematics::Beam).stiffness_at_wavenumber(g, x("k_rad_m"));
        assert!(rel_err(mm, want) < 1e-13, "Mead-Markus {case}");
    }
}
