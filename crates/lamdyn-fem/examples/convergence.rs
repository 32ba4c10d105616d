//! Prints the convergence tables of docs/fem.md: NAFEMS FV12 against its Kirchhoff reference,
//! and the paper's flat plate against its Reissner–Mindlin reference (method-notes §5), on four
//! uniform meshes and on graded ones (nodes clustered at the free edges, where a Mindlin plate has
//! a boundary layer about t/√(12k) wide).
//!
//! `cargo run --release -p lamdyn-fem --example convergence`

use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::{ModalParams, Silent, solve_modes};
use lamdyn_fem::element::ShellMaterial;
use lamdyn_fem::mesh::structured::RectangleSpec;

fn elastic(spec: RectangleSpec, mat: &ShellMaterial, n: usize) -> Vec<f64> {
    let asm = Assembly::new(&spec.build().expect("mesh"), mat, &[]).expect("assembly");
    let sol = solve_modes(&asm, &ModalParams::lowest(n + 6), &Silent).expect("modes");
    let s = sol.sturm.expect("sturm");
    assert_eq!(s.count, s.returned);
    sol.modes
        .iter()
        .filter(|m| !m.rigid)
        .map(|m| m.freq_hz)
        .collect()
}

fn table(title: &str, reference: &[f64], rows: Vec<(String, Vec<f64>)>) {
    println!("### {title}\n");
    print!("| mesh |");
    for k in 0..reference.len() {
        print!(" mode {} |", k + 7);
    }
    println!(" max error |");
    println!("|---|{}---|", "---|".repeat(reference.len()));
    print!("| reference |");
    for r in reference {
        print!(" {r} |");
    }
    println!(" |");
    for (name, f) in rows {
        print!("| {name} |");
        let mut worst: f64 = 0.0;
        for (g, r) in f.iter().zip(reference) {
            let e = g / r - 1.0;
            worst = worst.max(e.abs());
            print!(" {g:.5} ({:+.3} %) |", 100.0 * e);
        }
        println!(" {:.3} % |", 100.0 * worst);
    }
    println!();
}

fn main() {
    let fv12 = ShellMaterial {
        young_pa: 200e9,
        poisson: 0.3,
        density_kg_m3: 8000.0,
        thickness_m: 0.05,
    };
    let fv12_ref = [1.622, 2.360, 2.922, 4.190, 4.190, 7.356, 7.356, 7.668];
    let rows = [10, 20, 40, 80]
        .iter()
        .map(|&n| {
            (
                format!("{n}x{n}"),
                elastic(RectangleSpec::flat(10.0, 10.0, n, n), &fv12, 8),
            )
        })
        .collect();
    table(
        "NAFEMS FV12, free square plate 10 x 10 x 0.05 m (Kirchhoff reference, Hz)",
        &fv12_ref,
        rows,
    );

    let glass = ShellMaterial {
        young_pa: 67.45e9,
        poisson: 0.22,
        density_kg_m3: 2702.0,
        thickness_m: 0.00385,
    };
    let rm = [16.06997, 22.65761, 27.80974, 39.98957, 41.96053, 65.30584];
    let mut rows: Vec<(String, Vec<f64>)> = [10, 20, 40, 80, 160]
        .iter()
        .map(|&n| {
            (
                format!("{n}x{n}"),
                elastic(RectangleSpec::flat(0.923, 0.8632, n, n), &glass, 6),
            )
        })
        .collect();
    for n in [40, 80] {
        rows.push((
            format!("{n}x{n} graded 0.6"),
            elastic(
                RectangleSpec::flat(0.923, 0.8632, n, n).with_grading(0.6),
                &glass,
                6,
            ),
        ));
    }
    table(
        "The paper's plate taken flat, 0.923 x 0.8632 x 0.00385 m (Reissner-Mindlin reference, Hz)",
        &rm,
        rows,
    );
}
