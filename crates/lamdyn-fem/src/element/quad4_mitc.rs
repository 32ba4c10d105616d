//! MITC4: the 4-node shell element with mixed-interpolated transverse shear strains
//! [Dvorkin & Bathe 1984; Bathe 2014, §5.4].
//!
//! Geometry and displacements of the continuum-based shell (node k: position x_k, unit
//! director V_n^k with tangents V_1^k, V_2^k, thickness a; bilinear h_k(r, s)):
//!
//! x(r,s,t) = Σ h_k x_k + (t/2) Σ a h_k V_n^k
//! u(r,s,t) = Σ h_k u_k + (t/2) Σ a h_k (−V_2^k α_k + V_1^k β_k)
//!
//! with α_k, β_k the rotations about V_1^k and V_2^k. Covariant strains
//! ε̃_ij = ½(g_i·u_,j + g_j·u_,i), g_i = ∂x/∂r_i, are computed directly for rr, ss, rs; the
//! transverse shear strains are tied (Dvorkin–Bathe):
//!
//! ε̃_rt = ½(1+s) ε̃_rt|_A + ½(1−s) ε̃_rt|_C,  A = (0, 1), C = (0, −1)
//! ε̃_st = ½(1+r) ε̃_st|_D + ½(1−r) ε̃_st|_B,  D = (1, 0), B = (−1, 0)
//!
//! They are turned into Cartesian strains in the lamina frame (e_3 ∥ g_r × g_s) and stressed
//! with plane stress and shear correction k = 5/6:
//! σ = C [ε_11, ε_22, γ_12, γ_23, γ_13], C = diag-blocks(E/(1−ν²)[[1, ν],[ν, 1]], G, kG, kG).
//! Integration: 2×2 Gauss in-plane, 2 points through the thickness. Mass: consistent,
//! ρ ∫ Nᵀ N dV with the same interpolation (translational and rotary inertia).
//!
//! Six global dofs per node: α = V_1·θ, β = V_2·θ. The drilling rotation θ·V_n has no stiffness
//! of its own; it is tied to the in-plane rotation of the displacement field,
//! ω_n = ½(e_2·∂u/∂x_1 − e_1·∂u/∂x_2), by the penalty ½ γ ∫ (θ·e_3 − ω_n)² dA with
//! γ = [`DRILLING_FACTOR`]·G·t [Hughes & Brezzi 1989]. A rigid rotation makes θ·e_3 = ω_n, so the
//! element keeps exactly six zero-energy modes. Every term is proportional to E at fixed ν,
//! so K(E) = (E/E0) K(E0) exactly.

use super::{ElementDefect, ElementMatrix, ShellMaterial};
use crate::vec3::{V3, add, cross, dot, inverse_columns, norm, scale, tangent_pair, unit};

/// Shear correction factor k of the transverse shear stiffness.
pub const SHEAR_CORRECTION: f64 = 5.0 / 6.0;

/// Drilling penalty γ = DRILLING_FACTOR · G · t (N/m).
pub const DRILLING_FACTOR: f64 = 1e-3;

const GAUSS: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];
/// Natural coordinates (r_k, s_k) of the 4-node quadrilateral's nodes, in element order.
pub const NODE_RS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// Bilinear shape functions h_k = ¼(1 + r r_k)(1 + s s_k) of the 4-node quadrilateral (nodes
/// at (r_k, s_k) = (−1, −1), (1, −1), (1, 1), (−1, 1)) and their r and s derivatives.
pub fn bilinear_shape(r: f64, s: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let mut h = [0.0; 4];
    let mut hr = [0.0; 4];
    let mut hs = [0.0; 4];
    for k in 0..4 {
        let [rk, sk] = NODE_RS[k];
        h[k] = 0.25 * (1.0 + r * rk) * (1.0 + s * sk);
        hr[k] = 0.25 * rk * (1.0 + s * sk);
        hs[k] = 0.25 * sk * (1.0 + r * rk);
    }
    (h, hr, hs)
}

/// Local dofs per node: u_x, u_y, u_z, α, β.
const LOCAL: usize = 5;

/// A MITC4 element: node positions (m), unit directors and the thickness (m).
#[derive(Debug, Clone, Copy)]
pub struct Quad4Mitc {
    x: [V3; 4],
    vn: [V3; 4],
    v1: [V3; 4],
    v2: [V3; 4],
    a: f64,
}

/// Covariant base vectors at a point.
struct Base {
    g: [V3; 3],
}

/// Rows over the 20 local dofs.
type Row = [f64; 20];

impl Quad4Mitc {
    /// An element on nodes `x` (counter-clockwise seen from the directors' side) with unit
    /// directors `directors` and thickness `thickness_m`.
    pub fn new(x: [V3; 4], directors: [V3; 4], thickness_m: f64) -> Self {
        let mut v1 = [[0.0; 3]; 4];
        let mut v2 = [[0.0; 3]; 4];
        for k in 0..4 {
            (v1[k], v2[k]) = tangent_pair(directors[k]);
        }
        Self {
            x,
            vn: directors,
            v1,
            v2,
            a: thickness_m,
        }
    }

    fn shape(r: f64, s: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
        bilinear_shape(r, s)
    }

    fn base(&self, r: f64, s: f64, t: f64) -> Base {
        let (h, hr, hs) = Self::shape(r, s);
        let mut g = [[0.0; 3]; 3];
        for k in 0..4 {
            let p = add(self.x[k], scale(0.5 * t * self.a, self.vn[k]));
            g[0] = add(g[0], scale(hr[k], p));
            g[1] = add(g[1], scale(hs[k], p));
            g[2] = add(g[2], scale(0.5 * self.a * h[k], self.vn[k]));
        }
        Base { g }
    }

    /// ∂u/∂r, ∂u/∂s, ∂u/∂t per local dof.
    fn displacement_derivatives(&self, r: f64, s: f64, t: f64) -> [[V3; 20]; 3] {
        let (h, hr, hs) = Self::shape(r, s);
        let mut d = [[[0.0; 3]; 20]; 3];
        for k in 0..4 {
            let rot_alpha = scale(-1.0, self.v2[k]);
            let rot_beta = self.v1[k];
            for (m, dh) in [hr[k], hs[k]].into_iter().enumerate() {
                for c in 0..3 {
                    d[m][LOCAL * k + c][c] = dh;
                }
                d[m][LOCAL * k + 3] = scale(dh * 0.5 * t * self.a, rot_alpha);
                d[m][LOCAL * k + 4] = scale(dh * 0.5 * t * self.a, rot_beta);
            }
            d[2][LOCAL * k + 3] = scale(0.5 * self.a * h[k], rot_alpha);
            d[2][LOCAL * k + 4] = scale(0.5 * self.a * h[k], rot_beta);
        }
        d
    }

    /// Covariant strain rows [rr, ss, rs, rt, st] at a point, all computed directly.
    fn covariant_direct(&self, r: f64, s: f64, t: f64) -> [Row; 5] {
        let Base { g } = self.base(r, s, t);
        let d = self.displacement_derivatives(r, s, t);
        let mut e = [[0.0; 20]; 5];
        for i in 0..20 {
            e[0][i] = dot(g[0], d[0][i]);
            e[1][i] = dot(g[1], d[1][i]);
            e[2][i] = 0.5 * (dot(g[0], d[1][i]) + dot(g[1], d[0][i]));
            e[3][i] = 0.5 * (dot(g[0], d[2][i]) + dot(g[2], d[0][i]));
            e[4][i] = 0.5 * (dot(g[1], d[2][i]) + dot(g[2], d[1][i]));
        }
        e
    }

    /// The tying-point shear rows at thickness coordinate t: (ε̃_rt at A, C; ε̃_st at D, B).
    fn tying_rows(&self, t: f64) -> [Row; 4] {
        [
            self.covariant_direct(0.0, 1.0, t)[3],
            self.covariant_direct(0.0, -1.0, t)[3],
            self.covariant_direct(1.0, 0.0, t)[4],
            self.covariant_direct(-1.0, 0.0, t)[4],
        ]
    }

    /// Covariant strain rows with the MITC4 tying of the transverse shear strains.
    fn covariant_mitc(&self, r: f64, s: f64, t: f64, tying: &[Row; 4]) -> [Row; 5] {
        let mut e = self.covariant_direct(r, s, t);
        let [a, c, d, b] = tying;
        for i in 0..20 {
            e[3][i] = 0.5 * (1.0 + s) * a[i] + 0.5 * (1.0 - s) * c[i];
            e[4][i] = 0.5 * (1.0 + r) * d[i] + 0.5 * (1.0 - r) * b[i];
        }
        e
    }

    /// Lamina frame e_1 ∥ g_r, e_3 ∥ g_r × g_s, and `Q[a][i]` = g^i · e_a; with det J.
    fn frame(&self, r: f64, s: f64, t: f64) -> ([V3; 3], [[f64; 3]; 3], f64) {
        let Base { g } = self.base(r, s, t);
        let e3 = unit(cross(g[0], g[1]));
        let e1 = unit(g[0]);
        let e2 = cross(e3, e1);
        let (gcon, det) = inverse_columns(g[0], g[1], g[2]);
        let e = [e1, e2, e3];
        let mut q = [[0.0; 3]; 3];
        for a in 0..3 {
            for i in 0..3 {
                q[a][i] = dot(gcon[i], e[a]);
            }
        }
        (e, q, det)
    }

    /// Cartesian strain rows [ε11, ε22, γ12, γ23, γ13] and det J at a point.
    fn cartesian_b(&self, r: f64, s: f64, t: f64, tying: &[Row; 4]) -> ([Row; 5], f64) {
        let cov = self.covariant_mitc(r, s, t, tying);
        let (_, q, det) = self.frame(r, s, t);
        // Symmetric covariant tensor of rows: E[i][j]; E[2][2] = 0 (inextensible director).
        let comp = |i: usize, j: usize| -> Option<&Row> {
            match (i.min(j), i.max(j)) {
                (0, 0) => Some(&cov[0]),
                (1, 1) => Some(&cov[1]),
                (0, 1) => Some(&cov[2]),
                (0, 2) => Some(&cov[3]),
                (1, 2) => Some(&cov[4]),
                _ => None,
            }
        };
        let pairs: [(usize, usize, f64); 5] = [
            (0, 0, 1.0),
            (1, 1, 1.0),
            (0, 1, 2.0),
            (1, 2, 2.0),
            (0, 2, 2.0),
        ];
        let mut b = [[0.0; 20]; 5];
        for (row, (ca, cb, f)) in b.iter_mut().zip(pairs) {
            for i in 0..3 {
                for j in 0..3 {
                    let w = f * q[ca][i] * q[cb][j];
                    if let (Some(e), true) = (comp(i, j), w != 0.0) {
                        for (x, y) in row.iter_mut().zip(e) {
                            *x += w * y;
                        }
                    }
                }
            }
        }
        (b, det)
    }

    /// Checks the Jacobian at the Gauss points and corners of the mid-surface.
    ///
    /// # Errors
    /// [`ElementDefect`] with the parametric position of the first bad point.
    pub fn check_geometry(&self) -> Result<(), ElementDefect> {
        let points = NODE_RS.iter().copied().chain(
            GAUSS
                .iter()
                .flat_map(|&r| GAUSS.iter().map(move |&s| [r, s])),
        );
        for at in points {
            let Base { g } = self.base(at[0], at[1], 0.0);
            let area = norm(cross(g[0], g[1]));
            if area.is_nan() || area <= 1e-10 * norm(g[0]) * norm(g[1]) {
                return Err(ElementDefect::Degenerate { at });
            }
            if dot(cross(g[0], g[1]), g[2]) <= 0.0 {
                return Err(ElementDefect::Inverted { at });
            }
        }
        Ok(())
    }

    /// The 20 × 24 map from global dofs (u, θ per node) to local ones (u, α, β).
    fn local_row(&self, local: usize) -> [(usize, f64); 3] {
        let (k, d) = (local / LOCAL, local % LOCAL);
        match d {
            0..=2 => [(6 * k + d, 1.0), (6 * k + d, 0.0), (6 * k + d, 0.0)],
            3 => [
                (6 * k + 3, self.v1[k][0]),
                (6 * k + 4, self.v1[k][1]),
                (6 * k + 5, self.v1[k][2]),
            ],
            _ => [
                (6 * k + 3, self.v2[k][0]),
                (6 * k + 4, self.v2[k][1]),
                (6 * k + 5, self.v2[k][2]),
            ],
        }
    }

    /// Tᵀ A T for a symmetric 20 × 20 local matrix A, as (A T) then Tᵀ (A T) with the sparse T
    /// (one entry per translational row, three per rotational row).
    fn transform_to_global(&self, a: &[[f64; 20]; 20]) -> ElementMatrix {
        let mut at = [[0.0; 24]; 20];
        for i in 0..20 {
            for j in 0..20 {
                let aij = a[i][j];
                for (gj, tj) in self.local_row(j) {
                    at[i][gj] += aij * tj;
                }
            }
        }
        let mut out = [[0.0; 24]; 24];
        for i in 0..20 {
            for (gi, ti) in self.local_row(i) {
                if ti != 0.0 {
                    for g in 0..24 {
                        out[gi][g] += ti * at[i][g];
                    }
                }
            }
        }
        out
    }

    /// Element stiffness over the 24 global dofs (N/m, N, N·m blocks).
    ///
    /// # Errors
    /// [`ElementDefect::Inverted`] if the Jacobian is not positive at an integration point (a
    /// shell too thick for its curvature, or a folded element).
    pub fn stiffness(&self, mat: &ShellMaterial) -> Result<ElementMatrix, ElementDefect> {
        let c = mat.young_pa / (1.0 - mat.poisson * mat.poisson);
        let g = mat.shear_pa();
        let moduli = [c, c, g, SHEAR_CORRECTION * g, SHEAR_CORRECTION * g];
        let mut k = [[0.0; 20]; 20];
        let tying = GAUSS.map(|t| self.tying_rows(t));
        for &r in &GAUSS {
            for &s in &GAUSS {
                for (&t, tying) in GAUSS.iter().zip(&tying) {
                    let (b, det) = self.cartesian_b(r, s, t, tying);
                    if det.is_nan() || det <= 0.0 {
                        return Err(ElementDefect::Inverted { at: [r, s] });
                    }
                    // C = [[c, νc, 0..], [νc, c, ..], G, kG, kG]
                    let mut cb = b;
                    for i in 0..20 {
                        cb[0][i] = c * b[0][i] + mat.poisson * c * b[1][i];
                        cb[1][i] = mat.poisson * c * b[0][i] + c * b[1][i];
                        for m in 2..5 {
                            cb[m][i] = moduli[m] * b[m][i];
                        }
                    }
                    for i in 0..20 {
                        for j in i..20 {
                            let mut sum = 0.0;
                            for m in 0..5 {
                                sum += b[m][i] * cb[m][j];
                            }
                            k[i][j] += sum * det;
                        }
                    }
                }
            }
        }
        for i in 0..20 {
            for j in 0..i {
                k[i][j] = k[j][i];
            }
        }
        let mut kg = self.transform_to_global(&k);
        self.add_drilling(&mut kg, DRILLING_FACTOR * g * mat.thickness_m);
        Ok(kg)
    }

    /// Adds ½ γ ∫ (θ·e_3 − ω_n)² dA over the mid-surface (2×2 Gauss).
    fn add_drilling(&self, k: &mut ElementMatrix, gamma: f64) {
        for &r in &GAUSS {
            for &s in &GAUSS {
                let (e, q, _) = self.frame(r, s, 0.0);
                let Base { g } = self.base(r, s, 0.0);
                let da = norm(cross(g[0], g[1]));
                let d = self.displacement_derivatives(r, s, 0.0);
                // ∂u/∂x_a = Σ_i u_,i Q[a][i]; ω = ½(e2·∂u/∂x1 − e1·∂u/∂x2), over local dofs.
                let mut omega = [0.0; 20];
                for (i, w) in omega.iter_mut().enumerate() {
                    let du = |a: usize| {
                        add(
                            add(scale(q[a][0], d[0][i]), scale(q[a][1], d[1][i])),
                            scale(q[a][2], d[2][i]),
                        )
                    };
                    *w = 0.5 * (dot(e[1], du(0)) - dot(e[0], du(1)));
                }
                let (h, _, _) = Self::shape(r, s);
                let mut row = [0.0; 24];
                for (i, w) in omega.iter().enumerate() {
                    for (gi, ti) in self.local_row(i) {
                        row[gi] -= ti * w;
                    }
                }
                for kk in 0..4 {
                    for c in 0..3 {
                        row[6 * kk + 3 + c] += h[kk] * e[2][c];
                    }
                }
                for i in 0..24 {
                    for j in 0..24 {
                        k[i][j] += gamma * row[i] * row[j] * da;
                    }
                }
            }
        }
    }

    /// Consistent mass over the 24 global dofs (kg, kg·m, kg·m² blocks).
    pub fn mass(&self, mat: &ShellMaterial) -> ElementMatrix {
        let mut m = [[0.0; 20]; 20];
        for &r in &GAUSS {
            for &s in &GAUSS {
                for &t in &GAUSS {
                    let (h, _, _) = Self::shape(r, s);
                    let Base { g } = self.base(r, s, t);
                    let det = dot(g[0], cross(g[1], g[2]));
                    // N: 3 × 20
                    let mut n = [[0.0; 3]; 20];
                    for k in 0..4 {
                        for c in 0..3 {
                            n[LOCAL * k + c][c] = h[k];
                        }
                        n[LOCAL * k + 3] = scale(-0.5 * t * self.a * h[k], self.v2[k]);
                        n[LOCAL * k + 4] = scale(0.5 * t * self.a * h[k], self.v1[k]);
                    }
                    for i in 0..20 {
                        for j in i..20 {
                            m[i][j] += mat.density_kg_m3 * dot(n[i], n[j]) * det;
                        }
                    }
                }
            }
        }
        for i in 0..20 {
            for j in 0..i {
                m[i][j] = m[j][i];
            }
        }
        self.transform_to_global(&m)
    }
}
