//! The paper's roof as the examples model it: glass 1.715 mm / PVB 0.42 mm / glass, 0.923 ×
//! 0.8632 m, radii 3 m and 5 m, free; the demo's core law at 20 °C (fractional Zener).

use lamdyn_layered::inverse::{InverseLayer, LayeredPlate};
use lamdyn_layered::plan::Plan;
use lamdyn_layered::supports::PointSupport;
use lamdyn_material::law::FractionalZener;

/// The roof with in-plane edge grading `grading`.
pub fn plate(grading: f64) -> LayeredPlate {
    let glass = InverseLayer {
        thickness_m: 1.715e-3,
        density_kg_m3: 2500.0,
        poisson: 0.22,
        young_pa: Some(70e9),
        loss_factor: 0.0,
    };
    let pvb = InverseLayer {
        thickness_m: 0.42e-3,
        density_kg_m3: 1070.0,
        poisson: 0.49,
        young_pa: None,
        loss_factor: 0.0,
    };
    LayeredPlate {
        plan: Plan::Rectangle {
            plan_m: [0.923, 0.8632],
            radii_m: [3.0, 5.0],
            edge_grading: grading,
        },
        layers: vec![glass, pvb, glass],
        supports: Vec::new(),
        elements_per_layer: 1,
    }
}

/// The demo's core at 20 °C: G0 0.8 MPa, G∞ 1 GPa, τ 3e-7 s, α 0.4.
pub fn law() -> FractionalZener {
    FractionalZener::new(0.8e6, 1.0e9, 3e-7, 0.4).expect("law")
}

/// Four supports at 15 % and 85 % of the plan: vertical stiffness `kz` N/m each, horizontal a
/// fifth of it; dashpots `cz` N s/m vertical, half that horizontal; square contact patches of
/// side `patch` m (0: points).
#[allow(dead_code)]
pub fn corner_supports(kz: f64, cz: f64, patch: f64) -> Vec<PointSupport> {
    [[0.15, 0.15], [0.85, 0.15], [0.15, 0.85], [0.85, 0.85]]
        .map(|xy_fraction| PointSupport {
            xy_fraction,
            stiffness_n_m: [kz / 5.0, kz / 5.0, kz],
            damping_n_s_m: [cz / 2.0, cz / 2.0, cz],
            patch_m: [patch; 2],
        })
        .to_vec()
}
