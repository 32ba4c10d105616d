//! The shell model with grounded supports against the full sparse solve and the full
//! eigensolution of the supported part.

use super::common::*;
use lamdyn_fem::assembly::{Assembly, NodeSpring};
use lamdyn_fem::eigen::{ModalParams, ModalSolution, Silent, solve_modes};
use lamdyn_fem::element::ShellMaterial;
use lamdyn_fem::mesh::Mesh;
use lamdyn_fit::direct::DirectSolver;
use lamdyn_fit::fit::pole_moduli;
use lamdyn_fit::probe::Probe;
use lamdyn_fit::supports::GroundedSupport;
use lamdyn_fit::synthesis::{ModalModel, ResidualTerm};
use lamdyn_fit::synthetic::{corner_foam_blocks, triaxial_grid};
use lamdyn_material::law::{PaperEq7Law, ViscoelasticLaw};
use num_complex::Complex64;
use std::f64::consts::PI;

/// A flat plate of the paper's glass on `n` × `n` elements, its lowest `modes` free modes,
/// `grid` × `grid` triaxial responses and the hammer.
struct Case {
    mesh: Mesh,
    asm: Assembly,
    sol: ModalSolution,
    responses: Vec<Probe>,
    references: Vec<Probe>,
}

impl Case {
    fn new(n: usize, modes: usize, grid: usize) -> Self {
        let mesh = plate(n);
        let (asm, sol) = solve(&mesh, modes);
        let responses = probes_of(&mesh, &triaxial_grid(&mesh, grid, grid));
        let references = probes_of(&mesh, &hammer(&mesh));
        Self {
            mesh,
            asm,
            sol,
            responses,
            references,
        }
    }

    /// The modal model (residual term included) on `supports` (none: free).
    fn model(&self, supports: &[GroundedSupport]) -> ModalModel {
        let (asm, sol, young) = (&self.asm, &self.sol, GLASS.young_pa);
        let (pr, pf) = (&self.responses, &self.references);
        ModalModel::supported(asm, sol, pr, pf, young, ResidualTerm::Static, supports).unwrap()
    }
}

/// Largest relative Frobenius error over 50 lines, 1.6–80 Hz (eq. 7 modulus).
fn worst_error(model: &ModalModel, direct: &[Vec<Complex64>]) -> f64 {
    let law = PaperEq7Law::paper_table2();
    (1..=50)
        .zip(direct)
        .map(|(k, d)| {
            let w = 2.0 * PI * 1.6 * k as f64;
            let h = model.receptance(w, law.modulus(w) / GLASS.young_pa);
            let num: f64 = h.iter().zip(d).map(|(a, b)| (a - b).norm_sqr()).sum();
            let den: f64 = d.iter().map(|b| b.norm_sqr()).sum();
            (num / den).sqrt()
        })
        .fold(0.0, f64::max)
}

/// The supported synthesis (30 free modes, residual term, supports coupling the modes) against
/// faer's sparse LU of the supported part at every line: within the free synthesis's own
/// bound (1e-3, `synthesis_matches_direct_solves`); the free synthesis of the same part is
/// far off (printed).
#[test]
fn supported_synthesis_matches_direct_solves() {
    let case = Case::new(20, 30, 9);
    let supports = GroundedSupport::on_plan(&case.mesh, &corner_foam_blocks()).unwrap();
    let law = PaperEq7Law::paper_table2();
    let direct_solver = DirectSolver::new(&case.asm)
        .unwrap()
        .with_supports(&supports)
        .unwrap();
    let (pr, pf) = (&case.responses, &case.references);
    let direct: Vec<Vec<Complex64>> = (1..=50)
        .map(|k| {
            let w = 2.0 * PI * 1.6 * k as f64;
            let s = law.modulus(w) / GLASS.young_pa;
            direct_solver.receptance(w, s, pr, pf).unwrap()
        })
        .collect();
    let (e_supported, e_free) = (
        worst_error(&case.model(&supports), &direct),
        worst_error(&case.model(&[]), &direct),
    );
    eprintln!(
        "supported plate, 50 lines 1.6-80 Hz: supported synthesis {e_supported:.2e}, free \
         synthesis {e_free:.2e}"
    );
    assert!(e_supported < 1e-3, "supported synthesis: {e_supported:e}");
    assert!(e_free > 100.0 * e_supported, "free: {e_free:e}");
}

/// The fast RMS evaluator equals the RMS of the supported model's FRFs.
#[test]
fn supported_rms_evaluator_equals_rms_of_the_frfs() {
    let case = Case::new(12, 20, 5);
    let supports = GroundedSupport::on_plan(&case.mesh, &corner_foam_blocks()).unwrap();
    assert_rms_evaluator_exact(&case.model(&supports));
}

/// A patch support placed on the plan keeps its totals: under a rigid translation along each
/// axis the placed springs and dashpots sum to the support's k and c.
#[test]
fn a_patch_on_the_plan_keeps_its_totals() {
    let mesh = plate(12);
    let blocks = corner_foam_blocks();
    let supports = GroundedSupport::on_plan(&mesh, &blocks[..1]).unwrap();
    for axis in 0..3 {
        let along = |d: usize| if d % 6 == axis { 1.0 } else { 0.0 };
        let (k, c) = supports.iter().fold((0.0, 0.0), |(k, c), s| {
            let u = s.probe.dot(along);
            (k + s.stiffness_n_m * u * u, c + s.damping_n_s_m * u * u)
        });
        let want = (blocks[0].stiffness_n_m[axis], blocks[0].damping_n_s_m[axis]);
        assert!((k - want.0).abs() <= 1e-9 * want.0, "axis {axis}: k {k}");
        assert!(
            (c - want.1).abs() <= 1e-9 * want.1.max(1.0),
            "axis {axis}: c {c}"
        );
    }
}

/// The moduli of the supported part's poles: the full sparse eigensolution of the part at
/// E = 0.8 E_ref on node springs (Lanczos on K + K_s, M, independent of the modal basis)
/// gives undamped poles; `pole_moduli` on the 40-mode model with the same springs recovers
/// 0.8 E_ref at every isolated pole below half the basis' top, the springs' rocking mode
/// included. The Ritz basis' truncation grows towards its top (measured: 1e-9 at 7–21 Hz,
/// 1.4e-5 at 106 Hz, 1.2e-4 at 160 Hz, half the basis' top); the bound 2e-4 is 0.01 % in
/// frequency. The free model's estimate is far off (printed).
#[test]
fn pole_moduli_recover_the_supported_parts_modulus() {
    let case = Case::new(16, 40, 5);
    let corners: Vec<NodeSpring> = case.mesh.node_groups()["corners"]
        .iter()
        .map(|&node| NodeSpring {
            node,
            translational_n_per_m: [0.0, 0.0, 3e4],
            rotational_nm_per_rad: [0.0; 3],
        })
        .collect();
    let softer = ShellMaterial {
        young_pa: 0.8 * GLASS.young_pa,
        ..GLASS
    };
    let supported_asm = Assembly::new(&case.mesh, &softer, &corners).unwrap();
    let exact = solve_modes(&supported_asm, &ModalParams::lowest(24), &Silent).unwrap();
    let springs: Vec<GroundedSupport> = corners
        .iter()
        .flat_map(GroundedSupport::from_node_spring)
        .collect();
    let (free, supported) = (case.model(&[]), case.model(&springs));
    let sol = &case.sol;
    assert_eq!(
        supported.eigenvalues().len(),
        sol.modes.len() + 4,
        "one shape per spring"
    );
    // The poles above the free in-plane rigid-body modes and below half the basis' top (as a
    // run keeps its band), each at least 5 % from the next (a close pair is a question of
    // matching, not of the supported root).
    let top = sol.modes.last().unwrap().eigenvalue;
    let half_top = 0.5 * (0.8 * top).sqrt() / (2.0 * PI);
    let hz: Vec<f64> = exact
        .modes
        .iter()
        .map(|m| m.eigenvalue.max(0.0).sqrt() / (2.0 * PI))
        .collect();
    let isolated = |k: usize| {
        let near = |j: usize| (hz[j] / hz[k]).ln().abs() < 0.05;
        !(k > 0 && near(k - 1) || k + 1 < hz.len() && near(k + 1))
    };
    let poles: Vec<(f64, f64)> = (0..hz.len())
        .filter(|&k| hz[k] > 1.0 && hz[k] < half_top && isolated(k))
        .map(|k| (hz[k], 0.0))
        .collect();
    assert!(poles.len() >= 5, "{} isolated poles", poles.len());
    let off = |moduli: Vec<Complex64>| {
        moduli
            .iter()
            .map(|e| (e.re / softer.young_pa - 1.0).abs() + e.im.abs() / softer.young_pa)
            .fold(0.0, f64::max)
    };
    let (e_supported, e_free) = (
        off(pole_moduli(&supported, &poles)),
        off(pole_moduli(&free, &poles)),
    );
    eprintln!(
        "pole moduli at {} supported poles: supported model {e_supported:.2e}, free model \
         {e_free:.2e}",
        poles.len()
    );
    assert!(e_supported < 2e-4, "supported: {e_supported:e}");
    assert!(e_free > 10.0 * e_supported, "free: {e_free:e}");
}

/// A supported model's cache (format version 2) reads back bit for bit; a free model's stays
/// version 1.
#[test]
fn a_supported_cache_round_trips_exactly() {
    let case = Case::new(8, 16, 3);
    let supports = GroundedSupport::on_plan(&case.mesh, &corner_foam_blocks()).unwrap();
    let m = case.model(&supports);
    let bytes = m.to_cache_bytes();
    assert!(bytes.starts_with(b"lamdyn modal model v2\n"));
    let back = ModalModel::from_cache_bytes(&bytes).unwrap();
    assert!(back.has_supports());
    let (w, s) = (2.0 * PI * 23.0, Complex64::new(0.9, 0.05));
    assert_eq!(back.receptance(w, s), m.receptance(w, s));
    assert!(ModalModel::from_cache_bytes(&bytes[..bytes.len() - 8]).is_err());
    let free = case.model(&[]).to_cache_bytes();
    assert!(free.starts_with(b"lamdyn modal model v1\n"));
}
