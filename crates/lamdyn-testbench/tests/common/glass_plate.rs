//! The damped glass plate of `tests/frf_fit.rs` and `benches/frf_fit.rs`: its description and
//! the identification's observed model (included by both with `#[path]`).

use lamdyn_frf::FrfSet;
use lamdyn_layered::frf::ObservedModel;
use lamdyn_layered::probe::SurfaceProbe;
use lamdyn_layered::reduced::ReducedModel;
use lamdyn_testbench::description::{Bench, Description};
use std::f64::consts::PI;

/// A free laminated-glass plate, 1.2 × 0.9 m, glass 3 mm / acoustic-PVB-like core 0.76 mm /
/// glass 3 mm, `grid` triaxial sensors and one hammer; the core a Prony series with G' 1.6–6 MPa
/// and η 0.9–1.3 over 20–200 Hz.
pub fn glass_plate(
    elements: [usize; 2],
    grading: f64,
    grid: [usize; 2],
    snr_db: Option<f64>,
    seed: u64,
) -> String {
    let noise = snr_db.map_or(String::new(), |s| format!("frf_snr_db = {s}\n"));
    format!(
        r#"
[plate]
length_m = 1.2
width_m = 0.9

[mesh]
elements = [{}, {}]
edge_grading = {grading}
through_thickness = [1, 1, 1]

[[layers]]
name = "glass"
thickness_m = 3.0e-3
density_kg_m3 = 2500.0
poisson = 0.23
young_pa = 70e9

[[layers]]
name = "acoustic PVB"
thickness_m = 0.76e-3
density_kg_m3 = 1070.0
poisson = 0.49
shear_law = {{ kind = "generalized_maxwell", g_e_pa = 0.2e6, terms = [{{ g_pa = 0.5e6, tau_s = 1e-1 }}, {{ g_pa = 2.0e6, tau_s = 1e-2 }}, {{ g_pa = 8.0e6, tau_s = 1e-3 }}, {{ g_pa = 32e6, tau_s = 1e-4 }}, {{ g_pa = 128e6, tau_s = 1e-5 }}] }}

[[layers]]
name = "glass"
thickness_m = 3.0e-3
density_kg_m3 = 2500.0
poisson = 0.23
young_pa = 70e9

[test]
grid = [{}, {}]
hammer_xy_fraction = [0.31, 0.27]
step_hz = 0.5
max_hz = 220.0
seed = {seed}
{noise}
[basis]
modes = 40
reference_hz = [20.0, 200.0]
"#,
        elements[0], elements[1], grid[0], grid[1]
    )
}

/// The bench of a description's `text`.
pub fn bench(text: &str) -> Bench {
    Description::parse("glass plate", text)
        .unwrap()
        .build(&mut |_| {})
        .unwrap()
}

/// The identification's model: `coarse`'s mesh read at the measured channels' points and
/// driven at the reference, on a basis of `modes` modes at `ratios` × G_a.
pub fn observed(coarse: &Bench, set: &FrfSet, ratios: &[f64], modes: usize) -> ObservedModel {
    let locate = |c: &lamdyn_frf::Channel| {
        SurfaceProbe::locate(&coarse.mesh, c.point_m, c.direction, 1e-6, &c.name).unwrap()
    };
    let sensors: Vec<SurfaceProbe> = set.responses().iter().map(locate).collect();
    let references: Vec<SurfaceProbe> = set.references().iter().map(locate).collect();
    let loads: Vec<Vec<f64>> = references
        .iter()
        .map(|r| r.load(coarse.system.n_dofs))
        .collect();
    let shift = -(2.0 * PI).powi(2);
    let model = ReducedModel::with_orders(
        &coarse.system,
        &coarse.core_layers,
        ratios,
        modes,
        &loads,
        shift,
        2,
    )
    .unwrap();
    ObservedModel::new(model, &sensors, &references).unwrap()
}

/// The glass plate of [`glass_plate`] as the layered route models it (no supports, one element
/// per layer through the thickness), for [`lamdyn_layered::frf::ObservedModel::build`].
#[allow(dead_code)] // used by the test, not the bench
pub fn layered_plate() -> lamdyn_layered::inverse::LayeredPlate {
    use lamdyn_layered::inverse::{InverseLayer, LayeredPlate};
    use lamdyn_layered::plan::Plan;
    let glass = InverseLayer {
        thickness_m: 3.0e-3,
        density_kg_m3: 2500.0,
        poisson: 0.23,
        young_pa: Some(70e9),
        loss_factor: 0.0,
    };
    let core = InverseLayer {
        thickness_m: 0.76e-3,
        density_kg_m3: 1070.0,
        poisson: 0.49,
        young_pa: None,
        loss_factor: 0.0,
    };
    LayeredPlate {
        plan: Plan::Rectangle {
            plan_m: [1.2, 0.9],
            radii_m: [f64::INFINITY; 2],
            edge_grading: 0.0,
        },
        layers: vec![glass, core, glass],
        supports: Vec::new(),
        elements_per_layer: 1,
    }
}
