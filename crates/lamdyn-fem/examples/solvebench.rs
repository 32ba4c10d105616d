use faer::sparse::SparseColMatRef;
use faer::{Mat, Par};
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::factor::FactorPlan;
use lamdyn_fem::element::ShellMaterial;
use lamdyn_fem::mesh::structured::RectangleSpec;
use std::time::Instant;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(160);
    let mesh = RectangleSpec::flat(0.923, 0.8632, n, n).build().unwrap();
    let mat = ShellMaterial {
        young_pa: 67.45e9,
        poisson: 0.22,
        density_kg_m3: 2702.0,
        thickness_m: 0.00385,
    };
    let t = Instant::now();
    let asm = Assembly::new(&mesh, &mat, &[]).unwrap();
    println!("assembly {:.3} s", t.elapsed().as_secs_f64());
    println!(
        "M nnz {} K nnz {}",
        asm.mass.val().len(),
        asm.stiffness.val().len()
    );
    for cols in [1, 8] {
        let x = Mat::from_fn(asm.n_dofs(), cols, |i, j| ((i * 7 + j) % 13) as f64);
        let mut y = Mat::zeros(asm.n_dofs(), cols);
        let t = Instant::now();
        for _ in 0..10 {
            lamdyn_fem::sparse::symmetric_matmul(asm.mass.as_ref(), x.as_ref(), y.as_mut());
        }
        println!(
            "M x {cols} cols: {:.1} ms",
            t.elapsed().as_secs_f64() * 100.0
        );
    }
    for par in [Par::Seq] {
        let plan = FactorPlan::new(&asm.pattern).unwrap();
        let shifted = asm.shifted_values(asm.stiffness.val(), -1e4);
        let t = Instant::now();
        let f = plan
            .llt(
                SparseColMatRef::new(asm.stiffness.symbolic(), &shifted),
                -1e4,
                16,
            )
            .unwrap();
        println!(
            "{par:?} llt {:.3}s nnz {}",
            t.elapsed().as_secs_f64(),
            plan.factor_nnz()
        );
        for cols in [1, 2, 4, 8, 16] {
            let mut x = Mat::from_fn(asm.n_dofs(), cols, |i, j| ((i * 7 + j) % 13) as f64);
            let t = Instant::now();
            for _ in 0..3 {
                f.solve_in_place(x.as_mut());
            }
            println!(
                "  solve {cols:2} cols: {:.1} ms/solve, {:.1} ms/col",
                t.elapsed().as_secs_f64() * 1e3 / 3.0,
                t.elapsed().as_secs_f64() * 1e3 / 3.0 / cols as f64
            );
        }
    }
}
