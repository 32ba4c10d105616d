//! The paper's roof as the examples model it: glass 1.715 mm / PVB 0.42 mm / glass, 0.923 ×
//! 0.8632 m, radii 3 m and 5 m, free; the demo's core law at 20 °C (fractional Zener).

use lamdyn_layered::inverse::{InverseLayer, LayeredPlate};
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
        plan_m: [0.923, 0.8632],
        radii_m: [3.0, 5.0],
        edge_grading: grading,
        layers: vec![glass, pvb, glass],
        supports: Vec::new(),
    }
}

/// The demo's core at 20 °C: G0 0.8 MPa, G∞ 1 GPa, τ 3e-7 s, α 0.4.
pub fn law() -> FractionalZener {
    FractionalZener::new(0.8e6, 1.0e9, 3e-7, 0.4).expect("law")
}
