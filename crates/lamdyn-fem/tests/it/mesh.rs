//! Meshes: structured generators, validation of bad meshes, the Gmsh reader (fixtures written by
//! Gmsh itself, see testdata/gmsh/SOURCE.md), and the node locator.

use lamdyn_fem::FemError;
use lamdyn_fem::mesh::gmsh::{parse_msh, read_msh};
use lamdyn_fem::mesh::structured::RectangleSpec;
use lamdyn_fem::mesh::{Locator, Mesh};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("testdata/gmsh")
        .join(name)
}

fn invalid(e: FemError) -> String {
    e.to_string()
}

#[test]
fn structured_plate_and_shell() {
    let m = RectangleSpec::flat(0.923, 0.8632, 9, 8).build().unwrap();
    assert_eq!(
        (m.nodes().len(), m.elements().len(), m.n_dofs()),
        (90, 72, 540)
    );
    assert!((m.area() / (0.923 * 0.8632) - 1.0).abs() < 1e-14);
    assert_eq!(m.node_groups()["corners"].len(), 4);
    assert_eq!(m.node_groups()["boundary"].len(), 2 * 10 + 2 * 7);
    let s = RectangleSpec::flat(1.0, 0.8, 10, 8)
        .curved(2.0, 3.0)
        .build()
        .unwrap();
    for (p, d) in s.nodes().iter().zip(s.directors()) {
        // z = −x²/(2R_x) − y²/(2R_y), normal ∝ (x/R_x, y/R_y, 1)
        assert!((p[2] + p[0] * p[0] / 4.0 + p[1] * p[1] / 6.0).abs() < 1e-15);
        let n = [p[0] / 2.0, p[1] / 3.0, 1.0];
        let l = (n[0] * n[0] + n[1] * n[1] + 1.0).sqrt();
        assert!((0..3).all(|c| (d[c] - n[c] / l).abs() < 1e-15));
    }
    let g = RectangleSpec::flat(1.0, 1.0, 10, 10)
        .with_grading(0.5)
        .build()
        .unwrap();
    let x1 = g.nodes()[1][0] - g.nodes()[0][0];
    let x5 = g.nodes()[6][0] - g.nodes()[5][0];
    assert!(
        x1 < 0.7 * x5,
        "grading clusters nodes at the edges: {x1} vs {x5}"
    );
}

#[test]
fn structured_parameters_are_checked() {
    let e = invalid(RectangleSpec::flat(0.0, 1.0, 4, 4).build().unwrap_err());
    assert_eq!(e, "rectangle: length_x_m = 0 must be positive");
    let e = invalid(RectangleSpec::flat(1.0, 1.0, 0, 4).build().unwrap_err());
    assert_eq!(e, "rectangle: elements_x = 0 must lie in 1..=2000");
    let e = invalid(
        RectangleSpec::flat(1.0, 1.0, 4, 4)
            .curved(0.5, 2.0)
            .build()
            .unwrap_err(),
    );
    assert!(
        e.starts_with("rectangle: radius_x_m = 0.5 must be positive and at least the span (1 m)"),
        "{e}"
    );
    let e = invalid(
        RectangleSpec::flat(1.0, 1.0, 4, 4)
            .with_grading(1.0)
            .build()
            .unwrap_err(),
    );
    assert_eq!(e, "rectangle: grading = 1 must lie in [0, 1)");
}

#[test]
fn bad_meshes_name_the_node_or_element() {
    let square = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut nan = square.clone();
    nan[2][1] = f64::NAN;
    assert_eq!(
        invalid(Mesh::new(nan, vec![[0, 1, 2, 3]]).unwrap_err()),
        "invalid mesh: node 2 has a non-finite coordinate [1.0, NaN, 0.0]"
    );
    assert_eq!(
        invalid(Mesh::new(square.clone(), vec![[0, 1, 2, 7]]).unwrap_err()),
        "invalid mesh: element 0 refers to node 7, but there are 4 nodes"
    );
    assert_eq!(
        invalid(Mesh::new(square.clone(), vec![[0, 1, 1, 3]]).unwrap_err()),
        "invalid mesh: element 0 (nodes [0, 1, 1, 3]) repeats node 1: degenerate"
    );
    let mut extra = square.clone();
    extra.push([5.0, 5.0, 0.0]);
    assert_eq!(
        invalid(Mesh::new(extra, vec![[0, 1, 2, 3]]).unwrap_err()),
        "invalid mesh: node 4 is not used by any element (a free node makes the stiffness singular)"
    );
    let collinear = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [3.0, 0.0, 0.0],
    ];
    let e = invalid(
        Mesh::with_directors(collinear, vec![[0.0, 0.0, 1.0]; 4], vec![[0, 1, 2, 3]]).unwrap_err(),
    );
    assert!(
        e.starts_with("invalid mesh: element 0 (nodes [0, 1, 2, 3]) is degenerate"),
        "{e}"
    );
    // A bow-tie: nodes out of order fold the element.
    let bow = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let e = invalid(
        Mesh::with_directors(bow, vec![[0.0, 0.0, 1.0]; 4], vec![[0, 1, 2, 3]]).unwrap_err(),
    );
    assert!(
        e.starts_with("invalid mesh: element 0 (nodes [0, 1, 2, 3]) is inverted"),
        "{e}"
    );
    // Directors against the element's normal.
    let e = invalid(
        Mesh::with_directors(
            square.clone(),
            vec![[0.0, 0.0, -1.0]; 4],
            vec![[0, 1, 2, 3]],
        )
        .unwrap_err(),
    );
    assert!(e.contains("is inverted"), "{e}");
    // Two neighbours of opposite orientation.
    let two = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [2.0, 1.0, 0.0],
    ];
    let e = invalid(Mesh::new(two, vec![[0, 1, 4, 3], [1, 4, 5, 2]]).unwrap_err());
    assert_eq!(
        e,
        "invalid mesh: elements 0 and 1 run along edge 1-4 in the same direction: their orientations (normals) disagree"
    );
}

#[test]
fn gmsh_versions_2_2_and_4_1_read_the_same_mesh() {
    let a = read_msh(&fixture("plate-v22.msh"), 1.0).unwrap();
    let b = read_msh(&fixture("plate-v41.msh"), 1.0).unwrap();
    assert_eq!((a.nodes().len(), a.elements().len()), (35, 24));
    assert_eq!(a.nodes(), b.nodes());
    assert_eq!(a.elements(), b.elements());
    assert!((a.area() - 0.06).abs() < 1e-14);
    for m in [&a, &b] {
        assert_eq!(m.element_groups()["plate"].len(), 24);
        assert_eq!(m.node_groups()["long edges"].len(), 14);
        assert_eq!(m.node_groups()["corner"].len(), 1);
        assert!(
            m.directors()
                .iter()
                .all(|d| (d[2].abs() - 1.0).abs() < 1e-15)
        );
    }
    let mm = read_msh(&fixture("plate-v41.msh"), 1e-3).unwrap();
    assert!(
        (mm.area() - 0.06e-6).abs() < 1e-18,
        "scale applies to coordinates"
    );
}

#[test]
fn gmsh_curved_quads_have_radial_directors() {
    let m = read_msh(&fixture("dome-v41.msh"), 1.0).unwrap();
    assert!(m.elements().len() > 10);
    for (p, d) in m.nodes().iter().zip(m.directors()) {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let cos = (p[0] * d[0] + p[1] * d[1] + p[2] * d[2]).abs() / r;
        assert!(
            (r - 1.0).abs() < 1e-9 && cos > 0.99,
            "node {p:?} director {d:?}"
        );
    }
}

#[test]
fn gmsh_errors_name_file_and_line() {
    let e = invalid(read_msh(&fixture("triangles-v41.msh"), 1.0).unwrap_err());
    assert!(e.contains("triangles are not supported: recombine the mesh into quadrilaterals (Mesh.RecombineAll = 1)"), "{e}");
    assert!(
        e.starts_with("error reading '") && e.contains("triangles-v41.msh' line "),
        "{e}"
    );
    let e = invalid(read_msh(&fixture("binary-v41.msh"), 1.0).unwrap_err());
    assert!(
        e.ends_with("line 2: binary MSH files are not supported: save as ASCII (Mesh.Binary = 0)"),
        "{e}"
    );
    let e = invalid(read_msh(&fixture("missing.msh"), 1.0).unwrap_err());
    assert!(e.contains("missing.msh': No such file"), "{e}");
    // Issue 19.9: a file with no quadrilaterals was reported at "line 0".
    let lines_only = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n2 1 0 0\n$EndNodes\n$Elements\n1\n1 1 2 0 1 1 2\n$EndElements\n";
    let e = invalid(parse_msh("edges.msh", lines_only, 1.0).unwrap_err());
    assert_eq!(
        e,
        "error reading 'edges.msh': no 4-node quadrilaterals (element type 3) in the file"
    );
    let text = std::fs::read_to_string(fixture("plate-v22.msh")).unwrap();
    let cases = [
        (
            text.replacen("0.3 0 0", "0.3 zero 0", 1),
            "line 13: $Nodes: 'zero' is not a valid number",
        ),
        (
            text.lines().take(20).collect::<Vec<_>>().join("\n"),
            "unexpected end of file",
        ),
        (
            text.replacen("$Nodes\n35", "$Nodes\n34", 1),
            "expected $EndNodes, got '35 ",
        ),
        (
            text.replacen("2.2 0 8", "3.0 0 8", 1),
            "line 2: MSH version 3.0 is not supported",
        ),
        (
            "hello world\n".to_string(),
            "line 1: expected a section such as $Nodes, got 'hello world'",
        ),
        (String::new(), "no $MeshFormat section: not a Gmsh MSH file"),
    ];
    for (t, want) in cases {
        let e = invalid(parse_msh("x.msh", &t, 1.0).unwrap_err());
        assert!(e.contains(want), "want {want:?} in {e:?}");
    }
    let unknown_node = text.replacen("3 3 2 1 1 1 11 16 8", "3 3 2 1 1 1 11 16 99", 1);
    if unknown_node != text {
        let e = invalid(parse_msh("x.msh", &unknown_node, 1.0).unwrap_err());
        assert!(
            e.contains("refers to node tag 99, which is not in $Nodes"),
            "{e}"
        );
    }
}

#[test]
fn locator_maps_points_to_nearest_nodes() {
    let m = RectangleSpec::flat(0.923, 0.8632, 40, 40)
        .curved(4.0, 6.0)
        .build()
        .unwrap();
    let loc = Locator::new(&m, 1e-3);
    // Every node finds itself; a point just off a node finds it.
    for (i, p) in m.nodes().iter().enumerate().step_by(37) {
        assert_eq!(loc.nearest(*p).0, i);
        let q = [p[0] + 2e-4, p[1] - 1e-4, p[2]];
        assert_eq!(loc.locate_all(&[q]).unwrap(), vec![i]);
    }
    // Brute force agrees on arbitrary points.
    for k in 0..50 {
        let q = [-0.46 + 0.0187 * k as f64, 0.43 - 0.017 * k as f64, -0.01];
        let brute = (0..m.nodes().len())
            .min_by(|&a, &b| {
                let d = |n: usize| {
                    (0..3)
                        .map(|c| (m.nodes()[n][c] - q[c]).powi(2))
                        .sum::<f64>()
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        assert_eq!(loc.nearest(q).0, brute, "point {q:?}");
    }
    let e = loc.locate_all(&[[0.0, 0.0, 0.5]]).unwrap_err().to_string();
    assert!(
        e.starts_with("point 0 at (0, 0, 0.5) m: nearest node")
            && e.ends_with("beyond the tolerance of 1.0000e-3 m"),
        "{e}"
    );
    let e = loc
        .locate_all(&[[0.0, f64::NAN, 0.0]])
        .unwrap_err()
        .to_string();
    assert_eq!(e, "point 0 at (0, NaN, 0) m: not a finite point");
}
