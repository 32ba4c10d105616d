//! Named bench cases shared by the examples, tests and cross-check scripts.

use lamdyn_layered::hex20::Elastic;
use lamdyn_layered::mesh::{LayerMesh, LayeredPlateSpec};

/// Glass: E = 70 GPa, ν = 0.22, ρ = 2500 kg/m³.
pub const GLASS: Elastic = Elastic {
    young_pa: 70e9,
    poisson: 0.22,
    density_kg_m3: 2500.0,
};

/// An elastic PVB-like core: G = 2 MPa (E = 2G(1 + ν) = 5.96 MPa), ν = 0.49, ρ = 1070 kg/m³.
pub const ELASTIC_CORE: Elastic = Elastic {
    young_pa: 5.96e6,
    poisson: 0.49,
    density_kg_m3: 1070.0,
};

/// The CalculiX cross-check laminate (tools/calculix/compare_hex20.py): glass 2.1 mm / elastic
/// core 0.76 mm / glass 2.1 mm, one hexahedron per layer through the thickness, on the paper's
/// roof footprint 0.923 × 0.8632 m with `nx` × `ny` elements and radii `rx`, `ry` (m, infinite
/// for flat). Returns the mesh description and the layer materials, bottom to top.
pub fn ccx_check_laminate(
    nx: usize,
    ny: usize,
    rx: f64,
    ry: f64,
) -> (LayeredPlateSpec, [Elastic; 3]) {
    let layer = |t: f64| LayerMesh {
        thickness_m: t,
        elements: 1,
    };
    (
        LayeredPlateSpec {
            length_m: 0.923,
            width_m: 0.8632,
            nx,
            ny,
            radius_x_m: rx,
            radius_y_m: ry,
            edge_grading: 0.0,
            layers: vec![layer(0.0021), layer(0.00076), layer(0.0021)],
        },
        [GLASS, ELASTIC_CORE, GLASS],
    )
}
