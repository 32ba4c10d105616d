//! The 20-node serendipity hexahedron (CalculiX/Abaqus C3D20) for linear isotropic elasticity:
//! stiffness K = ∫ Bᵀ D B dV and consistent mass M = ∫ ρ Nᵀ N dV, both with 3 × 3 × 3 Gauss
//! points (full integration, as C3D20) [Zienkiewicz & Taylor, *The Finite Element Method*,
//! vol. 1, 6th ed., §8.7; Dhondt, *The Finite Element Method for Three-Dimensional
//! Thermomechanical Applications*, 2004, §6.2].
//!
//! Node order (natural coordinates ξ, η, ζ ∈ [−1, 1]): corners 1–8 as the bottom face
//! (ζ = −1) counter-clockwise then the top face; mid-edge nodes 9–12 on the bottom edges 1-2,
//! 2-3, 3-4, 4-1, 13–16 on the top edges 5-6, …, 8-5, 17–20 on the vertical edges 1-5, …, 4-8.
//! Shape functions: corner i, N = ⅛(1+ξξᵢ)(1+ηηᵢ)(1+ζζᵢ)(ξξᵢ+ηηᵢ+ζζᵢ−2); mid-edge with
//! ξᵢ = 0, N = ¼(1−ξ²)(1+ηηᵢ)(1+ζζᵢ) (and likewise for η, ζ).
//!
//! Strains in Voigt order (ε_xx, ε_yy, ε_zz, γ_xy, γ_yz, γ_zx); dofs per node (u_x, u_y, u_z),
//! element dof 3a + i for node a, direction i. Units SI.

/// Natural coordinates of the 20 nodes.
pub const NODES: [[f64; 3]; 20] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [0.0, -1.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, -1.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [-1.0, 0.0, 1.0],
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];

/// Isotropic linear elastic material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elastic {
    /// Young's modulus, Pa.
    pub young_pa: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// Density, kg/m³.
    pub density_kg_m3: f64,
}

impl Elastic {
    /// The 6 × 6 elasticity matrix D (Voigt order of the module docs, engineering shear).
    pub fn d_matrix(&self) -> [[f64; 6]; 6] {
        let (e, nu) = (self.young_pa, self.poisson);
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        let mut d = [[0.0; 6]; 6];
        for i in 0..3 {
            for j in 0..3 {
                d[i][j] = lambda + if i == j { 2.0 * mu } else { 0.0 };
            }
            d[i + 3][i + 3] = mu;
        }
        d
    }
}

/// Shape functions N and their natural derivatives dN/d(ξ, η, ζ) at a point.
pub fn shape(xi: [f64; 3]) -> ([f64; 20], [[f64; 3]; 20]) {
    let mut n = [0.0; 20];
    let mut dn = [[0.0; 3]; 20];
    for (a, c) in NODES.iter().enumerate() {
        let l = [1.0 + xi[0] * c[0], 1.0 + xi[1] * c[1], 1.0 + xi[2] * c[2]];
        if a < 8 {
            let s = xi[0] * c[0] + xi[1] * c[1] + xi[2] * c[2] - 2.0;
            n[a] = 0.125 * l[0] * l[1] * l[2] * s;
            for k in 0..3 {
                let (p, q) = ((k + 1) % 3, (k + 2) % 3);
                // d/dξ_k [l_k l_p l_q s] = c_k l_p l_q (s + l_k).
                dn[a][k] = 0.125 * c[k] * l[p] * l[q] * (s + l[k]);
            }
        } else {
            // The direction along the edge (the zero natural coordinate).
            let k = (0..3).find(|&k| c[k] == 0.0).unwrap_or(0);
            let (p, q) = ((k + 1) % 3, (k + 2) % 3);
            let bubble = 1.0 - xi[k] * xi[k];
            n[a] = 0.25 * bubble * l[p] * l[q];
            dn[a][k] = -0.5 * xi[k] * l[p] * l[q];
            dn[a][p] = 0.25 * bubble * c[p] * l[q];
            dn[a][q] = 0.25 * bubble * l[p] * c[q];
        }
    }
    (n, dn)
}

/// The 27 Gauss points (ξ, weight) of the 3 × 3 × 3 rule.
pub fn gauss27() -> Vec<([f64; 3], f64)> {
    let g = (0.6f64).sqrt();
    let pts = [(-g, 5.0 / 9.0), (0.0, 8.0 / 9.0), (g, 5.0 / 9.0)];
    let mut out = Vec::with_capacity(27);
    for &(z, wz) in &pts {
        for &(y, wy) in &pts {
            for &(x, wx) in &pts {
                out.push(([x, y, z], wx * wy * wz));
            }
        }
    }
    out
}

/// The element's stiffness and mass matrices (60 × 60, row-major) for node coordinates `x`
/// (m), or `None` if the Jacobian is not positive at a Gauss point (an inverted or degenerate
/// element).
pub fn matrices(x: &[[f64; 3]; 20], mat: &Elastic) -> Option<(Vec<f64>, Vec<f64>)> {
    let d = mat.d_matrix();
    let mut k = vec![0.0; 60 * 60];
    let mut m = vec![0.0; 60 * 60];
    for (xi, w) in gauss27() {
        let (n, dn) = shape(xi);
        let j = jacobian(&dn, x);
        let (jinv, det) = invert3(&j)?;
        if det <= 0.0 {
            return None;
        }
        // Global derivatives dN_a/dx_c = Σ_r Jinv_cr dN_a/dξ_r.
        let mut g = [[0.0; 3]; 20];
        for a in 0..20 {
            for c in 0..3 {
                g[a][c] = (0..3).map(|r| jinv[c][r] * dn[a][r]).sum();
            }
        }
        let dv = det * w;
        // B columns for node a: ε = B u.
        let b_col = |a: usize, i: usize| -> [f64; 6] {
            let [gx, gy, gz] = g[a];
            match i {
                0 => [gx, 0.0, 0.0, gy, 0.0, gz],
                1 => [0.0, gy, 0.0, gx, gz, 0.0],
                _ => [0.0, 0.0, gz, 0.0, gy, gx],
            }
        };
        let cols: Vec<[f64; 6]> = (0..60).map(|q| b_col(q / 3, q % 3)).collect();
        let db: Vec<[f64; 6]> = cols
            .iter()
            .map(|bc| {
                let mut out = [0.0; 6];
                for r in 0..6 {
                    out[r] = (0..6).map(|s| d[r][s] * bc[s]).sum();
                }
                out
            })
            .collect();
        for p in 0..60 {
            for q in p..60 {
                let v: f64 = (0..6).map(|r| cols[p][r] * db[q][r]).sum::<f64>() * dv;
                k[p * 60 + q] += v;
            }
        }
        for a in 0..20 {
            for b in a..20 {
                let v = mat.density_kg_m3 * n[a] * n[b] * dv;
                for i in 0..3 {
                    m[(3 * a + i) * 60 + 3 * b + i] += v;
                }
            }
        }
    }
    // Mirror the upper triangles.
    for p in 0..60 {
        for q in 0..p {
            k[p * 60 + q] = k[q * 60 + p];
            m[p * 60 + q] = m[q * 60 + p];
        }
    }
    Some((k, m))
}

/// The Jacobian J_rc = Σ_a dN_a/dξ_r x_a,c.
fn jacobian(dn: &[[f64; 3]; 20], x: &[[f64; 3]; 20]) -> [[f64; 3]; 3] {
    let mut j = [[0.0; 3]; 3];
    for a in 0..20 {
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += dn[a][r] * x[a][c];
            }
        }
    }
    j
}

/// Inverse and determinant of a 3 × 3 matrix (`None` if singular).
fn invert3(a: &[[f64; 3]; 3]) -> Option<([[f64; 3]; 3], f64)> {
    let c = |r: usize, s: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (s1, s2) = ((s + 1) % 3, (s + 2) % 3);
        a[r1][s1] * a[r2][s2] - a[r1][s2] * a[r2][s1]
    };
    let det = a[0][0] * c(0, 0) + a[0][1] * c(0, 1) + a[0][2] * c(0, 2);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for r in 0..3 {
        for s in 0..3 {
            // inverse = adjugate / det, adjugate = cofactorᵀ.
            inv[r][s] = c(s, r) / det;
        }
    }
    Some((inv, det))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn distorted() -> [[f64; 3]; 20] {
        // A skewed, tapered brick with curved edges (mid-edge nodes moved).
        let mut x = [[0.0; 3]; 20];
        for (a, c) in NODES.iter().enumerate() {
            let (u, v, w) = (c[0], c[1], c[2]);
            x[a] = [
                1.0 * u + 0.1 * v + 0.05 * u * v + 0.02 * (1.0 - u * u),
                0.8 * v + 0.05 * w + 0.03 * u * w,
                0.3 * w + 0.04 * u + 0.02 * (1.0 - v * v),
            ];
        }
        x
    }

    const GLASS: Elastic = Elastic {
        young_pa: 70e9,
        poisson: 0.22,
        density_kg_m3: 2500.0,
    };

    /// Σ N = 1, N_a(node b) = δ_ab, Σ dN = 0; derivatives against central differences.
    #[test]
    fn shape_functions_interpolate_and_differentiate() {
        for (b, c) in NODES.iter().enumerate() {
            let (n, _) = shape(*c);
            for a in 0..20 {
                assert!((n[a] - if a == b { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        let p = [0.3, -0.45, 0.7];
        let (n, dn) = shape(p);
        assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        for k in 0..3 {
            assert!(dn.iter().map(|d| d[k]).sum::<f64>().abs() < 1e-13);
            let h = 1e-6;
            let (mut lo, mut hi) = (p, p);
            lo[k] -= h;
            hi[k] += h;
            let (nl, nh) = (shape(lo).0, shape(hi).0);
            for a in 0..20 {
                let fd = (nh[a] - nl[a]) / (2.0 * h);
                assert!((fd - dn[a][k]).abs() < 1e-8, "node {a} dir {k}");
            }
        }
    }

    /// Six zero-energy modes (rigid body) on a distorted element, no more: K r = 0 for the
    /// three translations and three rotations, and the mass sums to ρV per direction.
    #[test]
    fn rigid_modes_and_total_mass() {
        let x = distorted();
        let (k, m) = matrices(&x, &GLASS).unwrap();
        let scale = k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for mode in 0..6 {
            let u: Vec<f64> = (0..60)
                .map(|q| {
                    let (a, i) = (q / 3, q % 3);
                    if mode < 3 {
                        if i == mode { 1.0 } else { 0.0 }
                    } else {
                        // Rotation about axis mode − 3: ω × x.
                        let mut w = [0.0; 3];
                        w[mode - 3] = 1.0;
                        let r = x[a];
                        let cross = [
                            w[1] * r[2] - w[2] * r[1],
                            w[2] * r[0] - w[0] * r[2],
                            w[0] * r[1] - w[1] * r[0],
                        ];
                        cross[i]
                    }
                })
                .collect();
            for p in 0..60 {
                let f: f64 = (0..60).map(|q| k[p * 60 + q] * u[q]).sum();
                assert!(f.abs() < 1e-9 * scale, "mode {mode}: {f}");
            }
        }
        let mat = faer::Mat::from_fn(60, 60, |p, q| k[p * 60 + q]);
        let ev = mat.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
        let zeros = ev.iter().filter(|v| v.abs() < 1e-9 * scale).count();
        assert_eq!(zeros, 6, "{ev:?}");
        // Volume by integrating det J; mass of one direction = ρV.
        let vol: f64 = gauss27()
            .iter()
            .map(|(xi, w)| invert3(&jacobian(&shape(*xi).1, &x)).unwrap().1 * w)
            .sum();
        let mx: f64 = (0..20)
            .flat_map(|a| (0..20).map(move |b| (a, b)))
            .map(|(a, b)| m[(3 * a) * 60 + 3 * b])
            .sum();
        assert!((mx / (GLASS.density_kg_m3 * vol) - 1.0).abs() < 1e-12);
    }

    /// Patch test on one element: a linear displacement field u = E x gives the constant
    /// strain's energy ½ V εᵀ D ε exactly.
    #[test]
    fn constant_strain_energy_is_exact() {
        let x = distorted();
        let (k, _) = matrices(&x, &GLASS).unwrap();
        let grad = [
            [1e-3, 2e-4, -1e-4],
            [5e-4, -3e-4, 2e-4],
            [-2e-4, 1e-4, 4e-4],
        ];
        let u: Vec<f64> = (0..60)
            .map(|q| (0..3).map(|c| grad[q % 3][c] * x[q / 3][c]).sum())
            .collect();
        let energy: f64 = 0.5
            * (0..60)
                .map(|p| u[p] * (0..60).map(|q| k[p * 60 + q] * u[q]).sum::<f64>())
                .sum::<f64>();
        let eps = [
            grad[0][0],
            grad[1][1],
            grad[2][2],
            grad[0][1] + grad[1][0],
            grad[1][2] + grad[2][1],
            grad[2][0] + grad[0][2],
        ];
        let d = GLASS.d_matrix();
        let dens: f64 = (0..6)
            .map(|r| eps[r] * (0..6).map(|s| d[r][s] * eps[s]).sum::<f64>())
            .sum::<f64>()
            * 0.5;
        let vol: f64 = gauss27()
            .iter()
            .map(|(xi, w)| invert3(&jacobian(&shape(*xi).1, &x)).unwrap().1 * w)
            .sum();
        assert!(
            (energy / (dens * vol) - 1.0).abs() < 1e-10,
            "{energy} vs {}",
            dens * vol
        );
    }
}
