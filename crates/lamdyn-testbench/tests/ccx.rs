//! The layered C3D20 model against CalculiX 2.20 C3D20 on the same meshes: the reference
//! frequencies in tools/calculix/hex20_results.json were written by
//! tools/calculix/compare_hex20.py (which runs `ccx` on the deck it writes from this model).

use lamdyn_layered::system::LayeredSystem;
use lamdyn_testbench::cases::ccx_check_laminate;
use std::f64::consts::PI;

/// First ten elastic free-free frequencies within 1e-5 of CalculiX (ccx prints 7 significant
/// digits, so agreement is bounded near 1e-7) on the flat and the doubly curved laminate.
#[test]
fn ccx_c3d20_frequencies() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tools/calculix/hex20_results.json"
    );
    let cases: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    for case in cases.as_array().unwrap() {
        let radius = |k: &str| case[k].as_str().unwrap().parse::<f64>().unwrap();
        let (spec, materials) = ccx_check_laminate(
            case["nx"].as_u64().unwrap() as usize,
            case["ny"].as_u64().unwrap() as usize,
            radius("radius_x_m"),
            radius("radius_y_m"),
        );
        let sys = LayeredSystem::assemble(&spec.build().unwrap(), &materials).unwrap();
        let (lambda, _) = sys.modes(&[1.0; 3], 16, -(2.0 * PI).powi(2)).unwrap();
        let reference: Vec<f64> = case["ccx_elastic_hz"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(reference.len(), 10);
        for (k, (l, r)) in lambda[6..].iter().zip(&reference).enumerate() {
            let f = l.sqrt() / (2.0 * PI);
            assert!(
                (f / r - 1.0).abs() < 1e-5,
                "{}: mode {}: {f} Hz vs ccx {r} Hz",
                case["case"],
                k + 7
            );
        }
        // Six rigid-body modes (round-off leaves them at a small fraction of a hertz).
        let rigid: Vec<f64> = lambda[..6]
            .iter()
            .map(|l| l.abs().sqrt() / (2.0 * PI))
            .collect();
        assert!(rigid.iter().all(|f| *f < 1e-3 * reference[0]), "{rigid:?}");
    }
}
