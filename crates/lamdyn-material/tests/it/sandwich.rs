use lamdyn_material::laminate::*;
use lamdyn_material::sandwich::*;
use lamdyn_testkit::{assert_rel, rel_err};
use num_complex::Complex64;
use proptest::prelude::*;
use std::f64::consts::PI;

fn stack(h1: f64, h2: f64, h3: f64, e3: f64) -> SandwichStack {
    let face = |h: f64, e: f64| Face {
        thickness_m: h,
        density_kg_m3: 2500.0,
        young_pa: e,
        poisson: 0.22,
        loss_factor: 0.0,
    };
    SandwichStack::new(
        face(h1, 70e9),
        CoreGeometry {
            thickness_m: h2,
            density_kg_m3: 1070.0,
            poisson: 0.49,
        },
        face(h3, e3),
        None,
    )
    .unwrap()
}

proptest! {
    #![proptest_config(lamdyn_testkit::proptest_config(256))]
    /// Mead–Markus forward at ω, then the closed-form inverse, recovers G* to 1e-10.
    #[test]
    fn forward_then_exact_inverse_round_trips(
        h1 in 5e-4f64..5e-3, h2 in 5e-5f64..3e-3, h3 in 5e-4f64..5e-3, e3 in 1e10f64..2e11,
        g in 1e4f64..1e9, eta in 0.0f64..1.5, f in 1.0f64..2000.0,
    ) {
        let s = stack(h1, h2, h3, e3);
        let g = Complex64::new(g, g * eta);
        let w = 2.0 * PI * f;
        for kin in [Kinematics::Beam, s.plate_kinematics()] {
            let mm = MeadMarkus::new(&s, kin);
            let e = mm.effective_modulus(g, w);
            let back = exact_inverse(&s, w, e, kin);
            // Far outside the sandwich regime (B within 1e-9 of a limit) the inverse is
            // ill-conditioned by construction; skip those draws.
            let b = mm.wave(g, w).stiffness;
            let span = (mm.bonded_stiffness() - mm.faces_stiffness()).norm();
            let margin = ((b - mm.faces_stiffness()).norm().min((mm.bonded_stiffness() - b).norm())) / span;
            prop_assume!(margin > 1e-4);
            let back = back.unwrap();
            prop_assert!(rel_err(back.core_shear_pa, g) < 1e-10, "{} vs {g}", back.core_shear_pa);
        }
    }

    /// The propagating root satisfies the dispersion relation D(k) k⁴ = m ω² (elastic core).
    #[test]
    fn wave_solves_the_dispersion_relation(g in 1e4f64..1e9, f in 1.0f64..5000.0) {
        let s = stack(1.7e-3, 0.4e-3, 2.1e-3, 70e9);
        let mm = MeadMarkus::new(&s, Kinematics::Beam);
        let w = 2.0 * PI * f;
        let g = Complex64::new(g, 0.0);
        let wave = mm.wave(g, w);
        prop_assert!(wave.kappa.im.abs() < 1e-12 * wave.kappa.re && wave.kappa.re > 0.0);
        let k = wave.kappa.re.sqrt();
        let d = mm.stiffness_at_wavenumber(g, k);
        prop_assert!(rel_err(d * k.powi(4), Complex64::new(s.surface_density_kg_m2() * w * w, 0.0)) < 1e-12);
    }
}

/// Limits: G → ∞ gives the bonded faces (the section's B_eq with the core's E = 0, eq. 35);
/// G → 0 gives the faces alone.
#[test]
fn mead_markus_limits() {
    let s = stack(1.715e-3, 0.42e-3, 2.5e-3, 50e9);
    let mm = MeadMarkus::new(&s, Kinematics::Beam);
    let bonded = s
        .section(Complex64::new(1.0, 0.0), Kinematics::Beam)
        .without_bending_of(1)
        .bending_stiffness();
    assert_rel("D_t (1 + Y)", mm.bonded_stiffness(), bonded, 1e-14);
    assert_rel(
        "G -> inf",
        mm.stiffness_at_wavenumber(Complex64::new(1e25, 0.0), 10.0),
        bonded,
        1e-12,
    );
    assert_rel(
        "G -> 0",
        mm.stiffness_at_wavenumber(Complex64::new(1e-20, 0.0), 10.0),
        mm.faces_stiffness(),
        1e-12,
    );
}

#[test]
fn exact_inverse_refuses_out_of_range_stiffness() {
    let s = SandwichStack::paper_roof();
    let w = 2.0 * PI * 10.0;
    let m = exact_inverse(&s, w, Complex64::new(80e9, 0.0), Kinematics::Beam)
        .unwrap_err()
        .to_string();
    assert!(m.contains("at least as stiff as the bonded faces"), "{m}");
    let m = exact_inverse(&s, w, Complex64::new(1e9, 0.0), Kinematics::Beam)
        .unwrap_err()
        .to_string();
    assert!(m.contains("no stiffer than its faces alone"), "{m}");
}
