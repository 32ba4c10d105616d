//! Element invariants over the registry: symmetry, exactly six zero-energy modes on flat,
//! distorted, warped and curved geometry, rigid-body modes in the kernel, mass, linearity in E,
//! and the membrane and bending patch tests.

use super::common::*;
use faer::prelude::Solve;
use faer::{Mat, Side};
use lamdyn_fem::V3;
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::element::{
    ElementMatrix, ElementOrder, Quad4Mitc, Quad9Mitc, REGISTRY, ShellElement, ShellMaterial,
};
use lamdyn_fem::mesh::Mesh;

fn unit(v: V3) -> V3 {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / n, v[1] / n, v[2] / n]
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The element orders under test, with the registry's names.
const ORDERS: [(ElementOrder, &str); 2] = [
    (ElementOrder::Linear, "Quad4Mitc"),
    (ElementOrder::Quadratic, "Quad9Mitc"),
];

/// A test geometry: the mid-surface point and director at natural coordinates (r, s).
type Surface = Box<dyn Fn(f64, f64) -> (V3, V3)>;

/// Bilinear map of four corners (counter-clockwise from (−1, −1)).
fn bilinear(c: [V3; 4], r: f64, s: f64) -> V3 {
    let h = [
        0.25 * (1.0 - r) * (1.0 - s),
        0.25 * (1.0 + r) * (1.0 - s),
        0.25 * (1.0 + r) * (1.0 + s),
        0.25 * (1.0 - r) * (1.0 + s),
    ];
    [0, 1, 2].map(|a| (0..4).map(|k| h[k] * c[k][a]).sum())
}

/// The normal g_r × g_s of a map, by central differences (directors of the warped quad).
fn normal_of(f: impl Fn(f64, f64) -> V3, r: f64, s: f64) -> V3 {
    let e = 1e-6;
    let d = |a: V3, b: V3| [0, 1, 2].map(|i| (a[i] - b[i]) / (2.0 * e));
    unit(cross(
        d(f(r + e, s), f(r - e, s)),
        d(f(r, s + e), f(r, s - e)),
    ))
}

/// Test geometries: flat, distorted (curved in-plane edges where the element has mid-side
/// nodes), rotated in space, warped, and a spherical cap.
fn geometries() -> Vec<(&'static str, Surface)> {
    let z = [0.0, 0.0, 1.0];
    let square = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let distorted = [
        [0.0, 0.0, 0.0],
        [1.3, 0.2, 0.0],
        [0.9, 1.1, 0.0],
        [-0.2, 0.7, 0.0],
    ];
    let rotated = [
        [0.0, 0.0, 0.0],
        [0.6, 0.8, 0.0],
        [0.6, 0.8, 1.0],
        [0.0, 0.0, 1.0],
    ];
    let warped = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.05],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.05],
    ];
    let cap = [
        [-0.3, -0.25, 0.0],
        [0.35, -0.3, 0.0],
        [0.3, 0.3, 0.0],
        [-0.25, 0.35, 0.0],
    ];
    let sphere = |p: V3| {
        let r: f64 = 2.0;
        let zz = (r * r - p[0] * p[0] - p[1] * p[1]).sqrt() - r;
        ([p[0], p[1], zz], unit([p[0], p[1], zz + r]))
    };
    vec![
        (
            "unit square",
            Box::new(move |r, s| (bilinear(square, r, s), z)),
        ),
        (
            "distorted",
            Box::new(move |r, s| {
                // Zero at the corners: the 4-node element sees the straight-edged quad.
                let bump = [
                    0.08 * (1.0 - r * r) * (1.0 + s),
                    0.06 * (1.0 - s * s) * (1.0 - r),
                    0.0,
                ];
                let p = bilinear(distorted, r, s);
                ([p[0] + bump[0], p[1] + bump[1], 0.0], z)
            }),
        ),
        (
            "rotated in space",
            Box::new(move |r, s| (bilinear(rotated, r, s), [0.8, -0.6, 0.0])),
        ),
        (
            "warped",
            Box::new(move |r, s| {
                let f = |r, s| bilinear(warped, r, s);
                (f(r, s), normal_of(f, r, s))
            }),
        ),
        (
            "spherical cap",
            Box::new(move |r, s| sphere(bilinear(cap, r, s))),
        ),
    ]
}

/// The nodes and directors of an element of `order` on a surface.
fn nodes_of(order: ElementOrder, surface: &Surface) -> (Vec<V3>, Vec<V3>) {
    order
        .node_rs()
        .iter()
        .map(|rs| surface(rs[0], rs[1]))
        .unzip()
}

fn element(order: ElementOrder, x: &[V3], d: &[V3], t: f64) -> ShellElement {
    match order {
        ElementOrder::Linear => ShellElement::Quad4(Quad4Mitc::new(
            std::array::from_fn(|k| x[k]),
            std::array::from_fn(|k| d[k]),
            t,
        )),
        ElementOrder::Quadratic => ShellElement::Quad9(Quad9Mitc::new(
            std::array::from_fn(|k| x[k]),
            std::array::from_fn(|k| d[k]),
            t,
        )),
    }
}

/// Every (order, geometry name, nodes, directors) case.
fn cases() -> Vec<(ElementOrder, &'static str, Vec<V3>, Vec<V3>)> {
    let mut out = Vec::new();
    for (order, _) in ORDERS {
        for (name, surface) in geometries() {
            let (x, d) = nodes_of(order, &surface);
            out.push((order, name, x, d));
        }
    }
    out
}

fn materials() -> Vec<ShellMaterial> {
    vec![
        ROOF,
        ShellMaterial {
            thickness_m: 0.1,
            ..FV12
        },
        ShellMaterial {
            thickness_m: 1e-3,
            ..FV12
        },
    ]
}

fn to_mat(a: &ElementMatrix) -> Mat<f64> {
    Mat::from_fn(a.size(), a.size(), |i, j| a[i][j])
}

/// The six rigid-body vectors at the nodes: translations and rotations about the centroid.
fn rigid(x: &[V3]) -> Vec<Vec<f64>> {
    let n = x.len();
    let c = [0, 1, 2].map(|a| x.iter().map(|p| p[a]).sum::<f64>() / n as f64);
    let mut out = Vec::new();
    for a in 0..6 {
        let mut v = vec![0.0; 6 * n];
        for k in 0..n {
            if a < 3 {
                v[6 * k + a] = 1.0;
            } else {
                let mut axis = [0.0; 3];
                axis[a - 3] = 1.0;
                let d = [x[k][0] - c[0], x[k][1] - c[1], x[k][2] - c[2]];
                v[6 * k..6 * k + 3].copy_from_slice(&cross(axis, d));
                v[6 * k + a] = 1.0;
            }
        }
        out.push(v);
    }
    out
}

#[test]
fn registry_lists_the_elements_tested_here() {
    assert_eq!(REGISTRY, ORDERS.map(|o| o.1));
}

#[test]
fn stiffness_and_mass_are_symmetric() {
    for (order, name, x, d) in cases() {
        for mat in materials() {
            let el = element(order, &x, &d, mat.thickness_m);
            for (what, a) in [("K", el.stiffness(&mat).unwrap()), ("M", el.mass(&mat))] {
                let n = a.size();
                let scale = (0..n).map(|i| a[i][i].abs()).fold(0.0, f64::max);
                for i in 0..n {
                    for j in 0..n {
                        assert!(
                            (a[i][j] - a[j][i]).abs() <= 1e-13 * scale,
                            "{order:?} {name} {what}[{i}][{j}]"
                        );
                    }
                }
            }
        }
    }
}

/// Exactly six eigenvalues of K vanish (to 1e-10 of the largest; rigid modes sit at rounding,
/// about 1e-16 of it) on every geometry, the seventh is clearly above (1e-9 of the largest: a
/// thin bending mode of a 1 mm plate 1 m across is about 6e-9 of the membrane stiffness on the
/// 9-node element), and the analytic rigid-body vectors lie in the kernel.
#[test]
fn exactly_six_zero_energy_modes() {
    for (order, name, x, d) in cases() {
        for mat in materials() {
            let el = element(order, &x, &d, mat.thickness_m);
            let k = el.stiffness(&mat).unwrap();
            let n = k.size();
            let km = to_mat(&k);
            let ev = km.self_adjoint_eigenvalues(Side::Lower).unwrap();
            let top = ev.iter().cloned().fold(0.0, f64::max);
            let zero = ev.iter().filter(|e| e.abs() <= 1e-10 * top).count();
            assert_eq!(
                zero,
                6,
                "{order:?} {name} t={}: eigenvalues {:?}",
                mat.thickness_m,
                &ev[..8]
            );
            assert!(
                ev[6] > 1e-9 * top,
                "{order:?} {name} t={}: 7th eigenvalue {} too close to zero",
                mat.thickness_m,
                ev[6]
            );
            for (i, r) in rigid(&x).iter().enumerate() {
                let kr: f64 = (0..n)
                    .map(|a| (0..n).map(|b| k[a][b] * r[b]).sum::<f64>().powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!(
                    kr <= 1e-11 * top,
                    "{order:?} {name}: rigid mode {i} has |K r| = {kr:e}"
                );
            }
        }
    }
}

/// ρ ∫ det J dr ds dt of the shell geometry x(r,s,t) = Σ h_k (x_k + (t/2) a V_k), by a
/// 6×6×4 Gauss rule written here (independent of the element's own rule).
fn volume_mass(order: ElementOrder, x: &[V3], d: &[V3], mat: &ShellMaterial) -> f64 {
    let g6 = [
        (-0.932_469_514_203_152, 0.171_324_492_379_170),
        (-0.661_209_386_466_265, 0.360_761_573_048_139),
        (-0.238_619_186_083_197, 0.467_913_934_572_691),
        (0.238_619_186_083_197, 0.467_913_934_572_691),
        (0.661_209_386_466_265, 0.360_761_573_048_139),
        (0.932_469_514_203_152, 0.171_324_492_379_170),
    ];
    let g4 = [
        (-0.861_136_311_594_053, 0.347_854_845_137_454),
        (-0.339_981_043_584_856, 0.652_145_154_862_546),
        (0.339_981_043_584_856, 0.652_145_154_862_546),
        (0.861_136_311_594_053, 0.347_854_845_137_454),
    ];
    let a = mat.thickness_m;
    let mut vol = 0.0;
    for &(r, wr) in &g6 {
        for &(s, ws) in &g6 {
            let (h, hr, hs) = order.shape(r, s);
            for &(t, wt) in &g4 {
                let mut g = [[0.0; 3]; 3];
                for k in 0..x.len() {
                    for c in 0..3 {
                        let p = x[k][c] + 0.5 * t * a * d[k][c];
                        g[0][c] += hr[k] * p;
                        g[1][c] += hs[k] * p;
                        g[2][c] += 0.5 * a * h[k] * d[k][c];
                    }
                }
                let det = g[0][0] * (g[1][1] * g[2][2] - g[1][2] * g[2][1])
                    - g[0][1] * (g[1][0] * g[2][2] - g[1][2] * g[2][0])
                    + g[0][2] * (g[1][0] * g[2][1] - g[1][1] * g[2][0]);
                vol += det * wr * ws * wt;
            }
        }
    }
    mat.density_kg_m3 * vol
}

/// 1ᵀ M 1 for a rigid translation is the element's mass ρ ∫ dV: exact on flat elements (the
/// element's rule integrates the polynomial det J exactly); on curved ones the 6×6×4 reference
/// differs only by the rule's own error.
#[test]
fn mass_of_a_rigid_translation_is_the_element_mass() {
    for (order, name, x, d) in cases() {
        let mat = ROOF;
        let m = element(order, &x, &d, mat.thickness_m).mass(&mat);
        let want = volume_mass(order, &x, &d, &mat);
        let n = x.len();
        for a in 0..3 {
            let total: f64 = (0..n)
                .flat_map(|i| (0..n).map(move |j| (i, j)))
                .map(|(i, j)| m[6 * i + a][6 * j + a])
                .sum();
            assert!(
                (total / want - 1.0).abs() < 1e-13,
                "{order:?} {name} dir {a}: {total} vs {want}"
            );
        }
    }
}

/// K is linear in E at fixed ν: K(3E) = 3 K(E) to rounding.
#[test]
fn stiffness_scales_exactly_with_young_modulus() {
    for (order, name, x, d) in cases() {
        let el = element(order, &x, &d, ROOF.thickness_m);
        let k1 = el.stiffness(&ROOF).unwrap();
        let k3 = el
            .stiffness(&ShellMaterial {
                young_pa: 3.0 * ROOF.young_pa,
                ..ROOF
            })
            .unwrap();
        let n = k1.size();
        let scale = (0..n).map(|i| k1[i][i].abs()).fold(0.0, f64::max);
        for i in 0..n {
            for j in 0..n {
                assert!(
                    (k3[i][j] - 3.0 * k1[i][j]).abs() <= 8.0 * f64::EPSILON * 3.0 * scale,
                    "{order:?} {name} [{i}][{j}]"
                );
            }
        }
    }
}

/// A 9-node mesh from a 4-node one: mid-side nodes at the edges' midpoints (shared between
/// neighbours), centre nodes at the bilinear centres.
fn to_quadratic(mut nodes: Vec<V3>, elements: &[[usize; 4]]) -> Mesh {
    let mut mids = std::collections::HashMap::new();
    let mut out = Vec::new();
    for el in elements {
        let mut q = [0; 9];
        q[..4].copy_from_slice(el);
        for k in 0..4 {
            let (a, b) = (el[k], el[(k + 1) % 4]);
            q[4 + k] = *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
                nodes.push([0, 1, 2].map(|c| 0.5 * (nodes[a][c] + nodes[b][c])));
                nodes.len() - 1
            });
        }
        nodes.push([0, 1, 2].map(|c| el.iter().map(|&n| nodes[n][c]).sum::<f64>() / 4.0));
        q[8] = nodes.len() - 1;
        out.push(q);
    }
    Mesh::quadratic(nodes, None, out).unwrap()
}

/// The MacNeal–Harder patch: a 0.24 × 0.12 rectangle split into five distorted elements.
fn patch(order: ElementOrder) -> Mesh {
    let nodes = vec![
        [0.0, 0.0, 0.0],
        [0.24, 0.0, 0.0],
        [0.24, 0.12, 0.0],
        [0.0, 0.12, 0.0],
        [0.04, 0.02, 0.0],
        [0.18, 0.03, 0.0],
        [0.16, 0.08, 0.0],
        [0.08, 0.08, 0.0],
    ];
    let elements = vec![
        [0, 1, 5, 4],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [3, 0, 4, 7],
        [4, 5, 6, 7],
    ];
    match order {
        ElementOrder::Linear => Mesh::new(nodes, elements).unwrap(),
        ElementOrder::Quadratic => to_quadratic(nodes, &elements),
    }
}

/// Solves K u = 0 with the boundary nodes' dofs prescribed by `field`, returns the error of
/// the interior nodes against the field.
fn patch_error(order: ElementOrder, field: impl Fn(V3) -> [f64; 6], free_dofs: &[usize]) -> f64 {
    let mesh = patch(order);
    let mat = ShellMaterial {
        young_pa: 1e6,
        poisson: 0.25,
        density_kg_m3: 1.0,
        thickness_m: 0.001,
    };
    let asm = Assembly::new(&mesh, &mat, &[]).unwrap();
    let k = dense(&asm.stiffness);
    let exact: Vec<f64> = mesh.nodes().iter().flat_map(|p| field(*p)).collect();
    // Interior nodes: unknown in `free_dofs` components; everything else prescribed.
    let on_boundary = |p: &V3| {
        p[0].abs() < 1e-12
            || (p[0] - 0.24).abs() < 1e-12
            || p[1].abs() < 1e-12
            || (p[1] - 0.12).abs() < 1e-12
    };
    let unknown: Vec<usize> = (0..mesh.nodes().len())
        .filter(|&n| !on_boundary(&mesh.nodes()[n]))
        .flat_map(|n| free_dofs.iter().map(move |c| 6 * n + c))
        .collect();
    let known: Vec<usize> = (0..mesh.n_dofs())
        .filter(|d| !unknown.contains(d))
        .collect();
    let kuu = Mat::from_fn(unknown.len(), unknown.len(), |i, j| {
        k[(unknown[i], unknown[j])]
    });
    let rhs = Mat::from_fn(unknown.len(), 1, |i, _| {
        -known
            .iter()
            .map(|&j| k[(unknown[i], j)] * exact[j])
            .sum::<f64>()
    });
    let u = kuu
        .llt(Side::Lower)
        .expect("interior block is positive definite")
        .solve(&rhs);
    unknown
        .iter()
        .enumerate()
        .map(|(i, &d)| (u[(i, 0)] - exact[d]).abs())
        .fold(0.0, f64::max)
}

/// Membrane patch test: a linear in-plane field is reproduced exactly (drilling rotation equal
/// to the field's in-plane rotation).
#[test]
fn membrane_patch_test() {
    let field = |p: V3| {
        let (x, y) = (p[0], p[1]);
        let u = 1e-3 * (x + y / 2.0);
        let v = 1e-3 * (y + x / 2.0);
        // ω = ½(∂v/∂x − ∂u/∂y) = 0 for this symmetric gradient
        [u, v, 0.0, 0.0, 0.0, 0.0]
    };
    for (order, _) in ORDERS {
        let err = patch_error(order, field, &[0, 1, 5]);
        assert!(err < 1e-14, "{order:?}: membrane patch error {err:e}");
    }
}

/// Bending patch test: constant curvatures w = κ(x² + xy + y²)/2 with rotations equal to the
/// slopes (θ_x = ∂w/∂y, θ_y = −∂w/∂x) are reproduced exactly.
#[test]
fn bending_patch_test() {
    let k = 1e-3;
    let field = |p: V3| {
        let (x, y) = (p[0], p[1]);
        let w = 0.5 * k * (x * x + x * y + y * y);
        [
            0.0,
            0.0,
            w,
            0.5 * k * (x + 2.0 * y),
            -0.5 * k * (2.0 * x + y),
            0.0,
        ]
    };
    for (order, _) in ORDERS {
        let err = patch_error(order, field, &[2, 3, 4]);
        assert!(err < 1e-14, "{order:?}: bending patch error {err:e}");
    }
}
