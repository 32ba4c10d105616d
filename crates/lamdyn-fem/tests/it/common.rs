use faer::Mat;
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::{ModalParams, ModalSolution, Silent, solve_modes};
use lamdyn_fem::element::ShellMaterial;

/// NAFEMS FV12 material: steel plate 0.05 m thick.
pub const FV12: ShellMaterial = ShellMaterial {
    young_pa: 200e9,
    poisson: 0.3,
    density_kg_m3: 8000.0,
    thickness_m: 0.05,
};

/// The paper's plate (Table 1 thickness, Table 2 E0).
pub const ROOF: ShellMaterial = ShellMaterial {
    young_pa: 67.45e9,
    poisson: 0.22,
    density_kg_m3: 2702.0,
    thickness_m: 0.00385,
};

/// Solves and asserts the Sturm check held (every test that solves modes goes through here).
pub fn modes(asm: &Assembly, params: &ModalParams) -> ModalSolution {
    let sol = solve_modes(asm, params, &Silent).expect("modal solve");
    let sturm = sol.sturm.expect("Sturm check run");
    assert_eq!(
        sturm.count, sturm.returned,
        "Sturm count disagrees: {sturm:?}"
    );
    assert_eq!(sturm.returned, sol.modes.len());
    assert!(sol.modes.iter().all(|m| m.eigenvalue < sturm.cutoff));
    sol
}

/// Elastic frequencies (rigid modes dropped), Hz.
pub fn elastic_hz(sol: &ModalSolution) -> Vec<f64> {
    sol.modes
        .iter()
        .filter(|m| !m.rigid)
        .map(|m| m.freq_hz)
        .collect()
}

/// Dense copy of a sparse matrix.
pub fn dense(a: &faer::sparse::SparseColMat<usize, f64>) -> Mat<f64> {
    a.to_dense()
}
