//! Outputs: MAC and VTK files.

use lamdyn_fem::mesh::structured::RectangleSpec;
use lamdyn_fem::output::{mac, mac_matrix, write_vtu};

#[test]
fn mac_identities() {
    let a = [1.0, 2.0, -1.0];
    assert!((mac(&a, &a) - 1.0).abs() < 1e-15);
    assert!(
        (mac(&a, &[-2.0, -4.0, 2.0]) - 1.0).abs() < 1e-15,
        "MAC ignores scale and sign"
    );
    assert_eq!(mac(&[1.0, 0.0], &[0.0, 1.0]), 0.0);
    let m = mac_matrix(&[a.to_vec(), vec![0.0, 1.0, 2.0]], &[a.to_vec()]);
    assert_eq!(m.len(), 2);
    assert!((m[1][0] - 0.0).abs() < 1e-15);
}

#[test]
fn vtu_file_lists_points_cells_and_modes() {
    let mesh = RectangleSpec::flat(1.0, 1.0, 3, 2).build().unwrap();
    let dir = lamdyn_testkit::TempDir::new("fem-vtu");
    let path = dir.join("m.vtu");
    let shape: Vec<f64> = (0..mesh.n_dofs()).map(|i| i as f64).collect();
    write_vtu(&path, &mesh, &[12.5], &[shape]).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("NumberOfPoints=\"12\" NumberOfCells=\"6\""));
    assert!(text.contains("Name=\"mode_01\"") && text.contains("Name=\"rotation_01\""));
    assert!(text.contains("1.250000000e1"));
    assert!(
        text.contains("Name=\"types\" format=\"ascii\">\n9 9 9 9 9 9"),
        "six VTK_QUAD cells"
    );
    let bad = dir.join("no/such/dir/m.vtu");
    let e = write_vtu(&bad, &mesh, &[], &[]).unwrap_err().to_string();
    assert!(e.starts_with("cannot write '"), "{e}");
}
