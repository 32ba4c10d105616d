//! Prints the convergence tables of docs/fem.md: NAFEMS FV12 against its Kirchhoff reference,
//! the paper's flat plate against its Reissner–Mindlin reference (method-notes §5), and the
//! paper-sized dome (radii 3 m and 5 m) against a reference extrapolated from the finest MITC9
//! meshes; MITC4 and MITC9, uniform, graded and with geometric edge layers (the free edges of a
//! Mindlin plate have a boundary layer about t/√(12k) wide). Each row gives the dofs and the
//! wall time of assembly and solve on this machine: accuracy per second.
//!
//! `cargo run --release -p lamdyn-fem --example convergence`

use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::{ModalParams, Silent, solve_modes};
use lamdyn_fem::element::{ElementOrder, ShellMaterial};
use lamdyn_fem::mesh::structured::RectangleSpec;
use std::time::Instant;

/// The first `n` elastic frequencies (Hz), with "dofs, seconds" of the model.
fn elastic(spec: RectangleSpec, mat: &ShellMaterial, n: usize) -> (Vec<f64>, String) {
    let start = Instant::now();
    let asm = Assembly::new(&spec.build().expect("mesh"), mat, &[]).expect("assembly");
    let sol = solve_modes(&asm, &ModalParams::lowest(n + 6), &Silent).expect("modes");
    let s = sol.sturm.expect("sturm");
    assert_eq!(s.count, s.returned);
    let f = sol
        .modes
        .iter()
        .filter(|m| !m.rigid)
        .map(|m| m.freq_hz)
        .take(n)
        .collect();
    let cost = format!("{} | {:.2}", asm.n_dofs(), start.elapsed().as_secs_f64());
    (f, cost)
}

fn table(title: &str, reference: &[f64], rows: Vec<(String, (Vec<f64>, String))>) {
    println!("### {title}\n");
    print!("| mesh | dofs | s |");
    for k in 0..reference.len() {
        print!(" mode {} |", k + 7);
    }
    println!(" max error |");
    println!("|---|---|---|{}---|", "---|".repeat(reference.len()));
    print!("| reference | | |");
    for r in reference {
        print!(" {r:.5} |");
    }
    println!(" |");
    for (name, (f, cost)) in rows {
        print!("| {name} | {cost} |");
        let mut worst: f64 = 0.0;
        for (g, r) in f.iter().zip(reference) {
            let e = g / r - 1.0;
            worst = worst.max(e.abs());
            print!(" {:+.1e} |", e);
        }
        println!(" {worst:.1e} |");
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
    let mut rows: Vec<(String, (Vec<f64>, String))> = [10, 20, 40, 80]
        .iter()
        .map(|&n| {
            (
                format!("{n}x{n}"),
                elastic(RectangleSpec::flat(10.0, 10.0, n, n), &fv12, 8),
            )
        })
        .collect();
    for n in [5, 10, 20] {
        rows.push((
            format!("{n}x{n} MITC9"),
            elastic(
                RectangleSpec::flat(10.0, 10.0, n, n).with_order(ElementOrder::Quadratic),
                &fv12,
                8,
            ),
        ));
    }
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
    let mut rows: Vec<(String, (Vec<f64>, String))> = [10, 20, 40, 80, 160]
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
    let mitc9 = |spec: RectangleSpec| spec.with_order(ElementOrder::Quadratic);
    let layers = |spec: RectangleSpec, n: usize| spec.with_edge_layers(n, glass.thickness_m / 2.0);
    for n in [40, 80] {
        rows.push((
            format!("{n}x{n} MITC4, 3 edge layers from t/2"),
            elastic(
                layers(RectangleSpec::flat(0.923, 0.8632, n, n), 3),
                &glass,
                6,
            ),
        ));
    }
    for n in [6, 12, 24, 48] {
        rows.push((
            format!("{n}x{n} MITC9"),
            elastic(mitc9(RectangleSpec::flat(0.923, 0.8632, n, n)), &glass, 6),
        ));
    }
    for (n, l) in [(8, 2), (12, 2), (16, 3), (24, 3)] {
        rows.push((
            format!("{n}x{n} MITC9, {l} edge layers from t/2"),
            elastic(
                layers(mitc9(RectangleSpec::flat(0.923, 0.8632, n, n)), l),
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

    // The dome: reference by Richardson extrapolation of the three finest layered MITC9 meshes.
    let dome = |n: usize| RectangleSpec::flat(0.923, 0.8632, n, n).curved(3.0, 5.0);
    let modes = 12;
    let fine: Vec<(usize, Vec<f64>)> = [24, 36, 48]
        .iter()
        .map(|&n| (n, elastic(layers(mitc9(dome(n)), 4), &glass, modes).0))
        .collect();
    let (reference, order) = richardson(&fine);
    println!(
        "Dome reference: Richardson extrapolation of MITC9 with 4 edge layers at 24, 36 and 48 \
         elements per side; observed order p = {order:.2} (median over modes); the 48 x 48 mesh \
         differs from it by at most {:.1e}.\n",
        fine[2]
            .1
            .iter()
            .zip(&reference)
            .map(|(f, r)| (f / r - 1.0).abs())
            .fold(0.0, f64::max)
    );
    let mut rows = Vec::new();
    for n in [20, 40, 80, 160] {
        rows.push((format!("{n}x{n} MITC4"), elastic(dome(n), &glass, modes)));
    }
    for n in [40, 80] {
        rows.push((
            format!("{n}x{n} MITC4, 3 edge layers from t/2"),
            elastic(layers(dome(n), 3), &glass, modes),
        ));
    }
    for n in [8, 12, 16, 24] {
        rows.push((
            format!("{n}x{n} MITC9"),
            elastic(mitc9(dome(n)), &glass, modes),
        ));
    }
    for (n, l) in [(8, 2), (12, 2), (16, 3), (20, 3), (24, 4)] {
        rows.push((
            format!("{n}x{n} MITC9, {l} edge layers from t/2"),
            elastic(layers(mitc9(dome(n)), l), &glass, modes),
        ));
    }
    table(
        "The paper-sized dome, 0.923 x 0.8632 x 0.00385 m, radii 3 m and 5 m (extrapolated \
         reference, Hz)",
        &reference,
        rows,
    );
}

/// Richardson extrapolation per mode from three meshes of n₁ < n₂ < n₃ elements per side
/// (h ∝ 1/n) with the observed order, not capped
/// ([`lamdyn_fem::convergence::richardson`]). Returns the extrapolated values and the median p.
fn richardson(meshes: &[(usize, Vec<f64>)]) -> (Vec<f64>, f64) {
    let h: Vec<f64> = meshes.iter().map(|(n, _)| 1.0 / *n as f64).collect();
    let mut orders = Vec::new();
    let extrapolated = (0..meshes[2].1.len())
        .map(|k| {
            let f: Vec<f64> = meshes.iter().map(|(_, f)| f[k]).collect();
            let e = lamdyn_fem::convergence::richardson(&h, &f, f64::INFINITY);
            orders.push(e.order.unwrap_or(f64::NAN));
            e.extrapolated_hz
        })
        .collect();
    orders.sort_by(f64::total_cmp);
    (extrapolated, orders[orders.len() / 2])
}
