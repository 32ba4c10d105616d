use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::{ModalParams, ModalSolution, Silent, solve_modes};
use lamdyn_fem::element::ShellMaterial;
use lamdyn_fem::mesh::Mesh;
use lamdyn_fem::mesh::structured::RectangleSpec;
use lamdyn_fit::probe::{Probe, probes};
use lamdyn_fit::synthesis::{ModalModel, ResidualTerm};
use lamdyn_frf::Channel;

/// The paper's plate (Table 1 footprint and thickness) at E_ref = 67.45 GPa.
pub const GLASS: ShellMaterial = ShellMaterial {
    young_pa: 67.45e9,
    poisson: 0.22,
    density_kg_m3: 2702.0,
    thickness_m: 0.00385,
};

pub fn plate(n: usize) -> Mesh {
    RectangleSpec::flat(0.923, 0.8632, n, n).build().unwrap()
}

pub fn solve(mesh: &Mesh, modes: usize) -> (Assembly, ModalSolution) {
    let asm = Assembly::new(mesh, &GLASS, &[]).unwrap();
    let sol = solve_modes(&asm, &ModalParams::lowest(modes), &Silent).unwrap();
    (asm, sol)
}

/// The hammer: +Z... at a point off the symmetry lines (so that every mode is excited).
pub fn hammer(mesh: &Mesh) -> Vec<Channel> {
    let p = mesh.nodes().iter().min_by(|a, b| {
        let d = |q: &[f64; 3]| (q[0] - 0.31).powi(2) + (q[1] - 0.17).powi(2);
        d(a).total_cmp(&d(b))
    });
    vec![Channel::new("hammer", *p.unwrap(), [0.0, 0.0, -1.0]).unwrap()]
}

pub fn probes_of(mesh: &Mesh, channels: &[Channel]) -> Vec<Probe> {
    probes(mesh, channels, 1e-6).unwrap()
}

pub fn model(
    asm: &Assembly,
    sol: &ModalSolution,
    mesh: &Mesh,
    responses: &[Channel],
    refs: &[Channel],
    residual: ResidualTerm,
) -> ModalModel {
    ModalModel::new(
        asm,
        sol,
        &probes_of(mesh, responses),
        &probes_of(mesh, refs),
        GLASS.young_pa,
        residual,
    )
    .unwrap()
}

/// The fast RMS evaluator of `m` for reference 0 equals the RMS of its receptances over the
/// responses, to rounding, at lines below, among and above the modes.
pub fn assert_rms_evaluator_exact(m: &ModalModel) {
    let ev = m.rms_evaluator(0);
    for f in [3.0, 16.0, 41.0, 120.0] {
        let w = 2.0 * std::f64::consts::PI * f;
        let s = num_complex::Complex64::new(0.97, 0.004);
        let h = m.receptance(w, s);
        let direct = (h.iter().map(|v| v.norm_sqr()).sum::<f64>() / h.len() as f64).sqrt();
        assert!((ev.rms(w, s) / direct - 1.0).abs() < 1e-12, "{f} Hz");
    }
}
