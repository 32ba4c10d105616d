//! Meshes: structured generators, validation of bad meshes, the Gmsh reader (fixtures written by
//! Gmsh itself, see testdata/gmsh/SOURCE.md), and the node locator.

use lamdyn_fem::FemError;
use lamdyn_fem::element::ElementOrder;
use lamdyn_fem::mesh::gmsh::{parse_msh, read_msh};
use lamdyn_fem::mesh::structured::{RectangleSpec, axis_coordinates};
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
        e.starts_with("rectangle: radius_x_m = 0.5 must be at least the span (1 m) in size"),
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
        "invalid mesh: elements 0 and 1 run along edge 1-4 in the same direction: their \
         orientations (normals) disagree"
    );
}

#[test]
fn gmsh_versions_2_2_and_4_1_read_the_same_mesh() {
    let a = read_msh(&fixture("plate-v22.msh"), 1.0).unwrap();
    let b = read_msh(&fixture("plate-v41.msh"), 1.0).unwrap();
    assert_eq!((a.nodes().len(), a.elements().len()), (35, 24));
    assert_eq!(a.nodes(), b.nodes());
    assert!(a.elements().eq(b.elements()));
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
    assert!(
        e.contains(
            "triangles are not supported: recombine the mesh into quadrilaterals \
             (Mesh.RecombineAll = 1)"
        ),
        "{e}"
    );
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
    // A file with no quadrilaterals was reported at "line 0".
    let lines_only = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n2 1 0 \
                      0\n$EndNodes\n$Elements\n1\n1 1 2 0 1 1 2\n$EndElements\n";
    let e = invalid(parse_msh("edges.msh", lines_only, 1.0).unwrap_err());
    assert_eq!(
        e,
        "error reading 'edges.msh': no 4-node or 9-node quadrilaterals (element types 3, 10) in \
         the file"
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
        // Binary bytes and a huge line: at most 60 characters quoted, control bytes escaped.
        (
            format!("\u{1b}[2J{}\n", "x".repeat(100_000)),
            &format!("got '\\u{{1b}}[2J{}...'", "x".repeat(56)),
        ),
        (
            text.replacen("0.3 0 0", &format!("0.3 \u{7}{} 0", "9".repeat(100_000)), 1),
            &format!("$Nodes: '\\u{{7}}{}...' is not", "9".repeat(59)),
        ),
    ];
    for (t, want) in cases {
        let e = invalid(parse_msh("x.msh", &t, 1.0).unwrap_err());
        assert!(e.contains(want), "want {want:?} in {e:?}");
        assert!(e.len() < 300 && !e.contains(['\u{1b}', '\u{7}']), "{e:?}");
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

/// The 9-node generator: (2n + 1)² nodes, exact area on the flat plate, every node of the
/// dome on the paraboloid with its exact normal, and mid-side nodes at the midpoints of the
/// corners in plan (rectangular elements in plan).
#[test]
fn structured_quadratic_plate_and_dome() {
    let m = RectangleSpec::flat(0.923, 0.8632, 9, 8)
        .with_order(ElementOrder::Quadratic)
        .build()
        .unwrap();
    assert_eq!((m.nodes().len(), m.n_elements()), (19 * 17, 72));
    assert_eq!(m.order(), ElementOrder::Quadratic);
    assert!((m.area() / (0.923 * 0.8632) - 1.0).abs() < 1e-14);
    assert_eq!(m.node_groups()["boundary"].len(), 2 * 19 + 2 * 15);
    let d = RectangleSpec::flat(1.0, 0.8, 6, 4)
        .curved(2.0, 3.0)
        .with_order(ElementOrder::Quadratic)
        .build()
        .unwrap();
    for (p, n) in d.nodes().iter().zip(d.directors()) {
        assert!((p[2] + p[0] * p[0] / 4.0 + p[1] * p[1] / 6.0).abs() < 1e-15);
        let want = [p[0] / 2.0, p[1] / 3.0, 1.0];
        let l = (want[0] * want[0] + want[1] * want[1] + 1.0).sqrt();
        assert!((0..3).all(|c| (n[c] - want[c] / l).abs() < 1e-15));
    }
    for e in 0..d.n_elements() {
        let el = d.element_nodes(e);
        for k in 0..4 {
            let (a, b, mid) = (
                d.nodes()[el[k]],
                d.nodes()[el[(k + 1) % 4]],
                d.nodes()[el[4 + k]],
            );
            assert!((mid[0] - 0.5 * (a[0] + b[0])).abs() < 1e-15);
            assert!((mid[1] - 0.5 * (a[1] + b[1])).abs() < 1e-15);
        }
    }
}

/// Edge layers: the widths grow geometrically from the given first width, the last layer
/// meets the interior's uniform width, and the side's length is kept.
#[test]
fn edge_layers_grow_geometrically_into_a_uniform_interior() {
    let x = axis_coordinates(24, 0.923, 3, 0.002).unwrap();
    assert_eq!(x.len(), 25);
    assert!((x[0] + 0.4615).abs() < 1e-15 && (x[24] - 0.4615).abs() < 1e-15);
    let w: Vec<f64> = x.windows(2).map(|p| p[1] - p[0]).collect();
    assert!((w[0] - 0.002).abs() < 1e-12, "{w:?}");
    let q = w[1] / w[0];
    assert!(q > 1.0 && (w[2] / w[1] - q).abs() < 1e-9, "{w:?}");
    let interior = w[3];
    assert!((w[2] * q / interior - 1.0).abs() < 1e-9, "{w:?}");
    assert!(w[3..21].iter().all(|h| (h / interior - 1.0).abs() < 1e-9));
    assert!((w[23] - 0.002).abs() < 1e-12);
    let e = axis_coordinates(6, 1.0, 3, 0.01).unwrap_err().to_string();
    assert!(e.starts_with("needs more than 6 elements"), "{e}");
    let e = axis_coordinates(10, 1.0, 2, 0.2).unwrap_err().to_string();
    assert!(
        e.contains("must be thinner than a uniform element (0.1 m)"),
        "{e}"
    );
    let e = invalid(
        RectangleSpec::flat(1.0, 1.0, 10, 10)
            .with_edge_layers(2, 0.2)
            .build()
            .unwrap_err(),
    );
    assert!(
        e.starts_with("rectangle: edge_layers = 2 layers from 0.2 m along x"),
        "{e}"
    );
}

/// A 9-node Gmsh file (two elements, MSH 2.2, node order as Gmsh writes it: corners, mid-sides,
/// centre) is read as a MITC9 mesh with the shared edge's mid-side node.
const TWO_QUAD9: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n15\n\
1 0 0 0\n2 1 0 0\n3 2 0 0\n4 0 1 0\n5 1 1 0\n6 2 1 0\n\
7 0.5 0 0\n8 1.5 0 0\n9 0.5 1 0\n10 1.5 1 0\n11 0 0.5 0\n12 1 0.5 0\n13 2 0.5 0\n\
14 0.5 0.5 0\n15 1.5 0.5 0\n$EndNodes\n$Elements\n2\n\
1 10 2 1 1 1 2 5 4 7 12 9 11 14\n2 10 2 1 1 2 3 6 5 8 13 10 12 15\n$EndElements\n";

#[test]
fn gmsh_nine_node_quadrilaterals_are_read() {
    let m = parse_msh("two.msh", TWO_QUAD9, 1.0).unwrap();
    assert_eq!(m.order(), ElementOrder::Quadratic);
    assert_eq!((m.nodes().len(), m.n_elements()), (15, 2));
    assert_eq!(m.element_nodes(1)[7], m.element_nodes(0)[5]);
    assert!((m.area() - 2.0).abs() < 1e-14);
}

/// Bad 9-node input: a mid-side node far off its edge's middle, neighbours that do not share
/// the mid-side node, and a file that mixes orders; elements and nodes named by the file's
/// tags, with the element's line.
#[test]
fn bad_nine_node_meshes_are_refused_with_the_node() {
    let off = TWO_QUAD9.replacen("7 0.5 0 0", "7 0.9 0 0", 1);
    let e = invalid(parse_msh("off.msh", &off, 1.0).unwrap_err());
    assert!(
        e.contains(
            "element 1 (line 24): mid-side node 7 is 4.0000e-1 m from the middle of edge \
             1-2 (1.0000e0 m long): more than a quarter of the edge"
        ),
        "{e}"
    );
    let unshared = TWO_QUAD9.replacen(
        "2 10 2 1 1 2 3 6 5 8 13 10 12 15",
        "2 10 2 1 1 2 3 6 5 8 13 10 14 15",
        1,
    );
    let e = invalid(parse_msh("unshared.msh", &unshared, 1.0).unwrap_err());
    // Elements and nodes by the file's tags and lines, not by indices from 0.
    assert!(
        e.contains(
            "elements 1 (line 24) and 2 (line 25) share edge 5-2 but not its mid-side node \
             (12 and 14)"
        ),
        "{e}"
    );
    let mixed = TWO_QUAD9
        .replacen("$Elements\n2\n", "$Elements\n3\n", 1)
        .replacen("$EndElements", "3 3 2 1 1 1 2 5 4\n$EndElements", 1);
    let e = invalid(parse_msh("mixed.msh", &mixed, 1.0).unwrap_err());
    assert!(
        e.contains("a 4-node quadrilateral after 9-node ones"),
        "{e}"
    );
    let serendipity = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 \
                       0\n$EndNodes\n$Elements\n1\n1 16 2 1 1 1 1 1 1 1 1 1 1\n$EndElements\n";
    let e = invalid(parse_msh("q8.msh", serendipity, 1.0).unwrap_err());
    assert!(e.contains("Mesh.SecondOrderIncomplete = 0"), "{e}");
}

/// A model asking for MITC9 on a file of 4-node quadrilaterals is refused with the Gmsh setting
/// that makes 9-node ones; asking for what the file holds is accepted.
#[test]
fn an_element_order_the_file_cannot_give_is_refused() {
    use lamdyn_fem::model::{MeshSpec, ModelSpec, SolverSpec};
    let spec = |element| ModelSpec {
        mesh: MeshSpec::Gmsh {
            file: "plate-v22.msh".into(),
            unit: "m".into(),
            element,
        },
        material: super::common::ROOF,
        supports: vec![],
        solver: SolverSpec::default(),
    };
    let dir = fixture("");
    let e = invalid(spec(Some(ElementOrder::Quadratic)).build(&dir).unwrap_err());
    assert!(
        e.contains(
            "'plate-v22.msh' holds 4-node quadrilaterals (MITC4); MITC9 needs 9-node ones \
             (Gmsh: Mesh.ElementOrder = 2"
        ),
        "{e}"
    );
    assert!(spec(Some(ElementOrder::Linear)).build(&dir).is_ok());
    assert!(spec(None).build(&dir).is_ok());
}

/// Node lines through a measurement grid: the paper's 9 × 9 grid with 5 cm
/// margins lies on nodes of a 40 × 40 MITC4 mesh and of a 24 × 24 MITC9 mesh with edge layers
/// (without the option the nearest nodes are up to 9 mm away); a grid too fine for the mesh and
/// a line outside the plate are refused with the field.
#[test]
fn node_lines_pass_through_a_measurement_grid() {
    let (lx, ly) = (0.923, 0.8632);
    let grid = |l: f64| -> Vec<f64> {
        (0..9)
            .map(|i| -0.5 * l + 0.05 + (l - 0.1) * i as f64 / 8.0)
            .collect()
    };
    let points: Vec<[f64; 3]> = grid(ly)
        .iter()
        .flat_map(|&y| grid(lx).into_iter().map(move |x| [x, y, 0.0]))
        .collect();
    let worst = |mesh: &lamdyn_fem::mesh::Mesh| {
        let loc = Locator::new(mesh, f64::INFINITY);
        points.iter().map(|&p| loc.nearest(p).1).fold(0.0, f64::max)
    };
    let plain = RectangleSpec::flat(lx, ly, 40, 40);
    assert!(worst(&plain.build().unwrap()) > 5e-3);
    let through = plain.with_node_lines(grid(lx), grid(ly));
    assert!(worst(&through.build().unwrap()) < 1e-12);
    let nine = RectangleSpec::flat(lx, ly, 24, 24)
        .with_order(ElementOrder::Quadratic)
        .with_edge_layers(3, 0.002)
        .with_node_lines(grid(lx), grid(ly));
    assert!(worst(&nine.build().unwrap()) < 1e-12);
    let coarse = RectangleSpec::flat(lx, ly, 6, 6).with_node_lines(grid(lx), grid(ly));
    let e = coarse.build().unwrap_err().to_string();
    assert!(
        e.contains("lines_x_m") && e.contains("use more elements"),
        "{e}"
    );
    let outside = RectangleSpec::flat(lx, ly, 40, 40).with_node_lines(vec![0.5], vec![]);
    let e = outside.build().unwrap_err().to_string();
    assert!(e.contains("lines_x_m") && e.contains("outside"), "{e}");
}
