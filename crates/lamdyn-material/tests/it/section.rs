use lamdyn_material::laminate::Section;
use lamdyn_testkit::{assert_rel, rel_err};
use num_complex::Complex64;
use proptest::prelude::*;

fn c(re: f64, im: f64) -> Complex64 {
    Complex64::new(re, im)
}

/// Stacks of identical material (any thicknesses) are one homogeneous layer.
fn identical_layers(thicknesses: &[f64], e: Complex64, g: Complex64) -> Section {
    Section::new(thicknesses.iter().map(|h| (*h, e, g)), 1.0)
}

proptest! {
    #![proptest_config(lamdyn_testkit::proptest_config(256))]
    /// K_eq = (5/6) G h for any stack of identical layers, symmetric or not (eq. 23).
    #[test]
    fn identical_layers_give_five_sixths_g_h(
        hs in prop::collection::vec(1e-4f64..5e-3, 1..7),
        e in 1e6f64..1e11, nu in 0.0f64..0.49, eta in 0.0f64..0.5,
    ) {
        let ec = c(e, e * eta);
        let g = ec / (2.0 * (1.0 + nu));
        let s = identical_layers(&hs, ec, g);
        let h: f64 = hs.iter().sum();
        let want = 5.0 / 6.0 * g * h;
        prop_assert!(rel_err(s.shear_stiffness(), want) < 1e-12);
        prop_assert!(rel_err(s.bending_stiffness(), ec * h.powi(3) / 12.0) < 1e-12);
        prop_assert!(rel_err(s.neutral_plane_m(), c(h / 2.0, 0.0)) < 1e-13);
        if hs.len() == 3 {
            let k: Complex64 = s.paper_three_layer_compliances().unwrap().iter().sum();
            prop_assert!(rel_err(1.0 / k, want) < 1e-12, "eqs. 25-27: {} vs {}", 1.0 / k, want);
        }
    }

    /// Eqs. 25–27 of the paper, written out literally, are the Jourawski compliances of each
    /// layer for any three-layer section, complex moduli included.
    #[test]
    fn paper_eqs_25_to_27_equal_the_jourawski_integral(
        h in prop::array::uniform3(1e-4f64..4e-3),
        e in prop::array::uniform3(1e5f64..1e11),
        eta in prop::array::uniform3(0.0f64..1.0),
        nu in prop::array::uniform3(0.0f64..0.49),
    ) {
        let layers: Vec<_> = (0..3).map(|i| {
            let ec = c(e[i], e[i] * eta[i]);
            (h[i], ec, ec / (2.0 * (1.0 + nu[i])))
        }).collect();
        let s = Section::new(layers, 1.0);
        let paper = s.paper_three_layer_compliances().unwrap();
        let jour = s.shear_compliances();
        let total: Complex64 = jour.iter().sum();
        for i in 0..3 {
            // Compare each layer's share of the total (a layer's own share can be tiny).
            prop_assert!((paper[i] - jour[i]).norm() < 1e-12 * total.norm(), "layer {i}: {} vs {}", paper[i], jour[i]);
        }
    }
}

/// Eq. 35 is eq. 14 with the core's bending neglected, for a symmetric stack.
#[test]
fn eq35_is_eq14_without_the_core() {
    let (hg, ha, eg) = (1.715e-3, 0.42e-3, 70e9);
    let s = Section::new(
        [
            (hg, c(eg, 0.0), c(1.0, 0.0)),
            (ha, c(3e7, 0.0), c(1e7, 0.0)),
            (hg, c(eg, 0.0), c(1.0, 0.0)),
        ],
        1.0,
    );
    let eq35 = 2.0 * eg * hg * (hg * hg / 12.0 + (hg + ha).powi(2) / 4.0);
    assert_rel(
        "eq. 35",
        s.without_bending_of(1).bending_stiffness(),
        c(eq35, 0.0),
        1e-15,
    );
    assert_rel("eq. 42", s.neutral_plane_m(), c(hg + ha / 2.0, 0.0), 1e-15);
}

/// Two bonded layers against the closed form used by the Oberst beam:
/// EI = (E H³/12)(1 + 4MT + 6MT² + 4MT³ + M²T⁴)/(1 + MT).
#[test]
fn two_layers_match_the_oberst_closed_form() {
    let (h, t, e) = (2e-3, 0.7, 200e9);
    let m = c(0.01, 0.004);
    let s = Section::new(
        [(h, c(e, 0.0), c(1.0, 0.0)), (t * h, m * e, c(1.0, 0.0))],
        1.0,
    );
    let ratio =
        (1.0 + m * (4.0 * t + 6.0 * t * t + 4.0 * t.powi(3)) + m * m * t.powi(4)) / (1.0 + m * t);
    assert_rel(
        "two layers",
        s.bending_stiffness(),
        e * h.powi(3) / 12.0 * ratio,
        1e-14,
    );
}
