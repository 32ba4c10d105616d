//! Per-mode discretization error estimates (Richardson over nested meshes) against independent
//! references: the estimate must cover the true error of the finest mesh.

use super::common::*;
use lamdyn_fem::convergence::{ConvergeParams, converge_modes, subdivided_dofs};
use lamdyn_fem::eigen::Silent;
use lamdyn_fem::element::ElementOrder;
use lamdyn_fem::mesh::structured::RectangleSpec;

/// The paper's plate taken flat, Reissner–Mindlin reference (method-notes §5), Hz.
const ROOF_RM_HZ: [f64; 6] = [16.06997, 22.65761, 27.80974, 39.98957, 41.96053, 65.30584];

fn flat_plate(order: ElementOrder, n: usize, layers: usize) -> lamdyn_fem::mesh::Mesh {
    RectangleSpec::flat(0.923, 0.8632, n, n)
        .with_order(order)
        .with_edge_layers(layers, 0.5 * ROOF.thickness_m)
        .build()
        .unwrap()
}

/// MITC9 with edge layers converges to 1e-4 on the first six elastic modes, and each mode's
/// estimated error covers its true error against the Reissner–Mindlin reference (which is
/// itself good to about 1e-6: its last printed digit).
#[test]
fn mitc9_estimate_covers_the_true_error_of_the_flat_plate() {
    let mesh = flat_plate(ElementOrder::Quadratic, 8, 2);
    let lift = RectangleSpec::flat(0.923, 0.8632, 8, 8).surface();
    let params = ConvergeParams::new(12, 1e-4);
    let c = converge_modes(&mesh, Some(&lift), &ROOF, &[], &params, &Silent).unwrap();
    assert!(c.converged, "{}: {:?}", c.stopped, c.modes);
    assert!(c.levels.len() >= 3);
    let elastic: Vec<_> = c.modes.iter().filter(|m| !m.rigid).collect();
    assert_eq!(elastic.len(), 6);
    for (j, (m, want)) in elastic.iter().zip(ROOF_RM_HZ).enumerate() {
        let truth = (m.freq_hz / want - 1.0).abs();
        assert!(m.error <= 1e-4, "mode {j}: estimate {:e}", m.error);
        assert!(
            truth <= m.error + 1e-6,
            "mode {j}: true error {truth:e} above the estimate {:e}",
            m.error
        );
        // The extrapolated frequency is closer to the reference than the finest mesh's.
        let extrapolated = (m.extrapolated_hz / want - 1.0).abs();
        assert!(
            extrapolated <= truth + 1e-6,
            "mode {j}: {extrapolated:e} vs {truth:e}"
        );
    }
}

/// MITC4 with edge layers: the estimate covers the true error at every level count the dof cap
/// allows, and a cap below the tolerance's needs says how far it got.
#[test]
fn mitc4_with_edge_layers_covers_the_true_error() {
    let mesh = flat_plate(ElementOrder::Linear, 12, 3);
    let lift = RectangleSpec::flat(0.923, 0.8632, 12, 12).surface();
    let mut params = ConvergeParams::new(12, 1e-5);
    params.max_dofs = 25_000;
    let c = converge_modes(&mesh, Some(&lift), &ROOF, &[], &params, &Silent).unwrap();
    assert!(!c.converged);
    assert!(c.stopped.contains("dof cap"), "{}", c.stopped);
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    let elastic: Vec<_> = c.modes.iter().filter(|m| !m.rigid).collect();
    for (j, (m, want)) in elastic.iter().zip(ROOF_RM_HZ).enumerate() {
        let truth = (m.freq_hz / want - 1.0).abs();
        assert!(
            truth <= m.error + 1e-6,
            "mode {j}: true error {truth:e} above the estimate {:e}",
            m.error
        );
    }
}

/// MITC4 on a uniform mesh never resolves the free edges' boundary layer: successive meshes
/// converge towards the Kirchhoff answer (1.6e-3 above the Reissner–Mindlin one for mode 7),
/// which no extrapolation can see. The result is not converged and says why.
#[test]
fn unresolved_free_edges_are_not_called_converged() {
    let mesh = flat_plate(ElementOrder::Linear, 10, 0);
    let lift = RectangleSpec::flat(0.923, 0.8632, 10, 10).surface();
    let mut params = ConvergeParams::new(8, 1e-2);
    params.stop_when_out_of_reach = false;
    let c = converge_modes(&mesh, Some(&lift), &ROOF, &[], &params, &Silent).unwrap();
    assert!(c.modes.iter().all(|m| m.rigid || m.error < 1e-2));
    assert!(!c.converged);
    assert!(
        c.warnings[0].contains("free edges unresolved"),
        "{:?}",
        c.warnings
    );
}

/// The same mesh with the default caps is refused before any solve: the finest mesh they allow
/// (6 × 6) still leaves the free edges unresolved, so no tolerance can be met.
#[test]
fn unresolved_free_edges_are_refused_before_any_solve() {
    let mesh = flat_plate(ElementOrder::Linear, 10, 0);
    let lift = RectangleSpec::flat(0.923, 0.8632, 10, 10).surface();
    let params = ConvergeParams::new(8, 1e-2);
    let stages = Stages::default();
    let err = converge_modes(&mesh, Some(&lift), &ROOF, &[], &params, &stages)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("cannot be met within the limits")
            && err.contains("6x6")
            && err.contains("boundary layer"),
        "{err}"
    );
    assert_eq!(stages.0.borrow().len(), 0, "solved before refusing");
}

/// A tolerance the caps cannot reach is seen after three levels, not after the expensive
/// ones: MITC4 with edge layers to 1e-6 stops at 3 × 3 saying why, and the full refinement
/// (to the 6 × 6 cap) confirms that the finest mesh misses it.
#[test]
fn an_unreachable_tolerance_stops_after_three_levels() {
    let mesh = flat_plate(ElementOrder::Linear, 12, 3);
    let lift = RectangleSpec::flat(0.923, 0.8632, 12, 12).surface();
    let params = ConvergeParams::new(8, 1e-6);
    let early = converge_modes(&mesh, Some(&lift), &ROOF, &[], &params, &Silent).unwrap();
    assert!(!early.converged);
    assert_eq!(early.levels.len(), 3, "{}", early.stopped);
    assert!(
        early.stopped.starts_with("out of reach"),
        "{}",
        early.stopped
    );
    let full = ConvergeParams {
        stop_when_out_of_reach: false,
        ..params
    };
    let full = converge_modes(&mesh, Some(&lift), &ROOF, &[], &full, &Silent).unwrap();
    assert_eq!(full.levels.len(), 6);
    let (_, worst) = full.worst().unwrap();
    assert!(worst > 1e-6, "the full refinement met {worst:e}");
}

/// The dofs counted from the topology are those of the built subdivision, for either order.
#[test]
fn subdivided_dofs_are_counted_without_building() {
    for order in [ElementOrder::Linear, ElementOrder::Quadratic] {
        let mesh = flat_plate(order, 5, 1);
        for m in 1..=4 {
            let built = mesh.subdivided(m, None).unwrap().n_dofs();
            assert_eq!(subdivided_dofs(&mesh, m), built, "{order:?} m = {m}");
        }
    }
}

/// The stages a run reported, to see whether it solved anything.
#[derive(Default)]
struct Stages(std::cell::RefCell<Vec<String>>);

impl lamdyn_fem::eigen::Progress for Stages {
    fn stage(&self, what: &str) {
        self.0.borrow_mut().push(what.to_string());
    }
}
