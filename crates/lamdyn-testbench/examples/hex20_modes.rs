//! Lowest free-free modes of a three-layer laminate meshed with C3D20 hexahedra, printed as
//! JSON (nodes, elements, layer of each element, frequencies in Hz) for
//! tools/calculix/compare_hex20.py:
//! `hex20_modes NX NY RX_M RY_M MODES` (radii `inf` for flat).
//!
//! The laminate is `lamdyn_testbench::cases::ccx_check_laminate`.

use lamdyn_layered::system::LayeredSystem;
use lamdyn_testbench::cases::ccx_check_laminate;
use std::f64::consts::PI;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let num = |i: usize| -> f64 { a[i].parse().expect("a number") };
    let (nx, ny, rx, ry, count) = (
        num(1) as usize,
        num(2) as usize,
        num(3),
        num(4),
        num(5) as usize,
    );
    let (spec, materials) = ccx_check_laminate(nx, ny, rx, ry);
    let mesh = spec.build().expect("mesh");
    let t = std::time::Instant::now();
    let sys = LayeredSystem::assemble(&mesh, &materials).expect("assembly");
    // Six rigid modes at 0: shift below them.
    let shift = -(2.0 * PI * 1.0f64).powi(2);
    let (lambda, _) = sys.modes(&[1.0; 3], count, shift).expect("modes");
    let seconds = t.elapsed().as_secs_f64();
    let freqs: Vec<String> = lambda
        .iter()
        .map(|l| format!("{:.12e}", l.max(0.0).sqrt() / (2.0 * PI)))
        .collect();
    let nodes: Vec<String> = mesh
        .nodes
        .iter()
        .map(|p| format!("[{:.17e},{:.17e},{:.17e}]", p[0], p[1], p[2]))
        .collect();
    let elems: Vec<String> = mesh.elements.iter().map(|e| format!("{:?}", e)).collect();
    println!(
        "{{\"dofs\":{},\"seconds\":{seconds},\"freqs_hz\":[{}],\"layer\":{:?},\"nodes\":[{}],\"elements\":[{}]}}",
        sys.n_dofs,
        freqs.join(","),
        mesh.layer,
        nodes.join(","),
        elems.join(",")
    );
}
