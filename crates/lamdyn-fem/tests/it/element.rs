//! Element invariants over the registry: symmetry, exactly six zero-energy modes on flat,
//! distorted, warped and curved geometry, rigid-body modes in the kernel, mass, linearity in E,
//! and the membrane and bending patch tests.

use super::common::*;
use faer::prelude::Solve;
use faer::{Mat, Side};
use lamdyn_fem::V3;
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::element::{ElementMatrix, Quad4Mitc, REGISTRY, ShellMaterial};
use lamdyn_fem::mesh::Mesh;

fn unit(v: V3) -> V3 {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / n, v[1] / n, v[2] / n]
}

/// Test geometries: (name, nodes, directors).
fn geometries() -> Vec<(&'static str, [V3; 4], [V3; 4])> {
    let z = [0.0, 0.0, 1.0];
    let sphere = |x: f64, y: f64| {
        let r: f64 = 2.0;
        let zz = (r * r - x * x - y * y).sqrt() - r;
        ([x, y, zz], unit([x, y, zz + r]))
    };
    let sp: Vec<(V3, V3)> = [(-0.3, -0.25), (0.35, -0.3), (0.3, 0.3), (-0.25, 0.35)]
        .iter()
        .map(|&(x, y)| sphere(x, y))
        .collect();
    // A warped quad with its directors averaged from the geometry (Mesh::new).
    let warped = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.05],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.05],
    ];
    let wm = Mesh::new(warped.to_vec(), vec![[0, 1, 2, 3]]).unwrap();
    let warped_dirs = [0, 1, 2, 3].map(|i| wm.directors()[i]);
    vec![
        (
            "unit square",
            [
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            [z; 4],
        ),
        (
            "distorted",
            [
                [0.0, 0.0, 0.0],
                [1.3, 0.2, 0.0],
                [0.9, 1.1, 0.0],
                [-0.2, 0.7, 0.0],
            ],
            [z; 4],
        ),
        (
            "rotated in space",
            [
                [0.0, 0.0, 0.0],
                [0.6, 0.8, 0.0],
                [0.6, 0.8, 1.0],
                [0.0, 0.0, 1.0],
            ],
            [[0.8, -0.6, 0.0]; 4],
        ),
        ("warped", warped, warped_dirs),
        (
            "spherical cap",
            [sp[0].0, sp[1].0, sp[2].0, sp[3].0],
            [sp[0].1, sp[1].1, sp[2].1, sp[3].1],
        ),
    ]
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
    Mat::from_fn(24, 24, |i, j| a[i][j])
}

/// The six rigid-body vectors at the nodes: translations and rotations about the centroid.
fn rigid(x: &[V3; 4]) -> Vec<[f64; 24]> {
    let c = [0, 1, 2].map(|a| x.iter().map(|p| p[a]).sum::<f64>() / 4.0);
    let mut out = Vec::new();
    for a in 0..6 {
        let mut v = [0.0; 24];
        for k in 0..4 {
            if a < 3 {
                v[6 * k + a] = 1.0;
            } else {
                let mut axis = [0.0; 3];
                axis[a - 3] = 1.0;
                let d = [x[k][0] - c[0], x[k][1] - c[1], x[k][2] - c[2]];
                let u = [
                    axis[1] * d[2] - axis[2] * d[1],
                    axis[2] * d[0] - axis[0] * d[2],
                    axis[0] * d[1] - axis[1] * d[0],
                ];
                v[6 * k..6 * k + 3].copy_from_slice(&u);
                v[6 * k + a] = 1.0;
            }
        }
        out.push(v);
    }
    out
}

#[test]
fn registry_lists_the_elements_tested_here() {
    assert_eq!(REGISTRY, &["Quad4Mitc"]);
}

#[test]
fn stiffness_and_mass_are_symmetric() {
    for (name, x, d) in geometries() {
        for mat in materials() {
            let el = Quad4Mitc::new(x, d, mat.thickness_m);
            for (what, a) in [("K", el.stiffness(&mat).unwrap()), ("M", el.mass(&mat))] {
                let scale = (0..24).map(|i| a[i][i].abs()).fold(0.0, f64::max);
                for i in 0..24 {
                    for j in 0..24 {
                        assert!(
                            (a[i][j] - a[j][i]).abs() <= 1e-13 * scale,
                            "{name} {what}[{i}][{j}]"
                        );
                    }
                }
            }
        }
    }
}

/// Exactly six eigenvalues of K vanish (to 1e-10 of the largest) on every geometry, the
/// seventh is clearly above, and the analytic rigid-body vectors lie in the kernel.
#[test]
fn exactly_six_zero_energy_modes() {
    for (name, x, d) in geometries() {
        for mat in materials() {
            let el = Quad4Mitc::new(x, d, mat.thickness_m);
            let k = el.stiffness(&mat).unwrap();
            let km = to_mat(&k);
            let ev = km.self_adjoint_eigenvalues(Side::Lower).unwrap();
            let top = ev.iter().cloned().fold(0.0, f64::max);
            let zero = ev.iter().filter(|e| e.abs() <= 1e-10 * top).count();
            assert_eq!(
                zero,
                6,
                "{name} t={}: eigenvalues {:?}",
                mat.thickness_m,
                &ev[..8]
            );
            assert!(
                ev[6] > 1e-8 * top,
                "{name} t={}: 7th eigenvalue {} too close to zero",
                mat.thickness_m,
                ev[6]
            );
            for (i, r) in rigid(&x).iter().enumerate() {
                let kr: f64 = (0..24)
                    .map(|a| (0..24).map(|b| k[a][b] * r[b]).sum::<f64>().powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!(
                    kr <= 1e-11 * top,
                    "{name}: rigid mode {i} has |K r| = {kr:e}"
                );
            }
        }
    }
}

/// ρ ∫ det J dr ds dt of the shell geometry x(r,s,t) = Σ h_k (x_k + (t/2) a V_k), by a
/// 6×6×4 Gauss rule written here (independent of the element's 2×2×2 rule).
fn volume_mass(x: &[V3; 4], d: &[V3; 4], mat: &ShellMaterial) -> f64 {
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
    let rs = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let a = mat.thickness_m;
    let mut vol = 0.0;
    for &(r, wr) in &g6 {
        for &(s, ws) in &g6 {
            for &(t, wt) in &g4 {
                let mut g = [[0.0; 3]; 3];
                for k in 0..4 {
                    let h = 0.25 * (1.0 + r * rs[k][0]) * (1.0 + s * rs[k][1]);
                    let hr = 0.25 * rs[k][0] * (1.0 + s * rs[k][1]);
                    let hs = 0.25 * rs[k][1] * (1.0 + r * rs[k][0]);
                    for c in 0..3 {
                        let p = x[k][c] + 0.5 * t * a * d[k][c];
                        g[0][c] += hr * p;
                        g[1][c] += hs * p;
                        g[2][c] += 0.5 * a * h * d[k][c];
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

/// 1ᵀ M 1 for a rigid translation is the element's mass ρ ∫ dV: exact for the bilinear geometry
/// (the 2×2×2 rule integrates the polynomial det J exactly on flat elements; on curved ones the
/// 6×6×4 reference differs only by the rule's own error).
#[test]
fn mass_of_a_rigid_translation_is_the_element_mass() {
    for (name, x, d) in geometries() {
        let mat = ROOF;
        let m = Quad4Mitc::new(x, d, mat.thickness_m).mass(&mat);
        let want = volume_mass(&x, &d, &mat);
        for a in 0..3 {
            let total: f64 = (0..4)
                .flat_map(|i| (0..4).map(move |j| (i, j)))
                .map(|(i, j)| m[6 * i + a][6 * j + a])
                .sum();
            assert!(
                (total / want - 1.0).abs() < 1e-13,
                "{name} dir {a}: {total} vs {want}"
            );
        }
    }
}

/// K is linear in E at fixed ν: K(3E) = 3 K(E) to rounding.
#[test]
fn stiffness_scales_exactly_with_young_modulus() {
    for (name, x, d) in geometries() {
        let el = Quad4Mitc::new(x, d, ROOF.thickness_m);
        let k1 = el.stiffness(&ROOF).unwrap();
        let k3 = el
            .stiffness(&ShellMaterial {
                young_pa: 3.0 * ROOF.young_pa,
                ..ROOF
            })
            .unwrap();
        let scale = (0..24).map(|i| k1[i][i].abs()).fold(0.0, f64::max);
        for i in 0..24 {
            for j in 0..24 {
                assert!(
                    (k3[i][j] - 3.0 * k1[i][j]).abs() <= 8.0 * f64::EPSILON * 3.0 * scale,
                    "{name} [{i}][{j}]"
                );
            }
        }
    }
}

/// The MacNeal–Harder patch: a 0.24 × 0.12 rectangle split into five distorted elements.
fn patch() -> Mesh {
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
    Mesh::new(nodes, elements).unwrap()
}

/// Solves K u = 0 with the boundary nodes' dofs prescribed by `field`, returns the error of
/// the interior nodes against the field.
fn patch_error(field: impl Fn(V3) -> [f64; 6], free_dofs: &[usize]) -> f64 {
    let mesh = patch();
    let mat = ShellMaterial {
        young_pa: 1e6,
        poisson: 0.25,
        density_kg_m3: 1.0,
        thickness_m: 0.001,
    };
    let asm = Assembly::new(&mesh, &mat, &[]).unwrap();
    let k = dense(&asm.stiffness);
    let exact: Vec<f64> = mesh.nodes().iter().flat_map(|p| field(*p)).collect();
    // Interior nodes 4..8: unknown in `free_dofs` components; everything else prescribed.
    let unknown: Vec<usize> = (4..8)
        .flat_map(|n| free_dofs.iter().map(move |c| 6 * n + c))
        .collect();
    let known: Vec<usize> = (0..48).filter(|d| !unknown.contains(d)).collect();
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
    let err = patch_error(field, &[0, 1, 5]);
    assert!(err < 1e-14, "membrane patch error {err:e}");
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
    let err = patch_error(field, &[2, 3, 4]);
    assert!(err < 1e-14, "bending patch error {err:e}");
}
