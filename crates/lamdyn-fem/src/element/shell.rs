//! The continuum-based shell kernel shared by the MITC elements [Bathe 2014, §5.4]: geometry,
//! displacements, covariant and Cartesian strains, stiffness, drilling penalty and consistent
//! mass for an N-node Lagrange quadrilateral. What differs between elements, the shape functions,
//! the in-plane Gauss rule and which covariant strains are tied where, is a [`Scheme`].
//!
//! Geometry and displacements (node k: position x_k, unit director V_n^k with tangents V_1^k,
//! V_2^k, thickness a; shape functions h_k(r, s)):
//!
//! x(r,s,t) = Σ h_k x_k + (t/2) Σ a h_k V_n^k
//! u(r,s,t) = Σ h_k u_k + (t/2) Σ a h_k (−V_2^k α_k + V_1^k β_k)
//!
//! with α_k, β_k the rotations about V_1^k and V_2^k. Covariant strains
//! ε̃_ij = ½(g_i·u_,j + g_j·u_,i), g_i = ∂x/∂r_i, are evaluated directly; the scheme replaces
//! some of them by its assumed (tied) interpolation. They are turned into Cartesian strains in the
//! lamina frame (e_3 ∥ g_r × g_s) and stressed with plane stress and shear correction k = 5/6:
//! σ = C [ε_11, ε_22, γ_12, γ_23, γ_13], C = diag-blocks(E/(1−ν²)[[1, ν],[ν, 1]], G, kG, kG).
//! Integration: the scheme's Gauss rule in-plane, 2 points through the thickness (exact for the
//! linear variation of the strains through a flat shell). Mass: consistent, ρ ∫ Nᵀ N dV with
//! the same interpolation (translational and rotary inertia).
//!
//! Six global dofs per node: α = V_1·θ, β = V_2·θ. The drilling rotation θ·V_n has no stiffness
//! of its own; it is tied to the in-plane rotation of the displacement field,
//! ω_n = ½(e_2·∂u/∂x_1 − e_1·∂u/∂x_2), by the penalty ½ γ ∫ (θ·e_3 − ω_n)² dA with
//! γ = [`DRILLING_FACTOR`]·G·t [Hughes & Brezzi 1989]. A rigid rotation makes θ·e_3 = ω_n, so
//! the element keeps exactly six zero-energy modes. Every term is proportional to E at fixed ν,
//! so K(E) = (E/E0) K(E0) exactly.

use super::{ElementDefect, ElementMatrix, ShellMaterial};
use crate::vec3::{V3, add, cross, dot, inverse_columns, norm, scale, tangent_pair, unit};
use std::marker::PhantomData;

/// Shear correction factor k of the transverse shear stiffness.
pub const SHEAR_CORRECTION: f64 = 5.0 / 6.0;

/// Drilling penalty γ = DRILLING_FACTOR · G · t (N/m).
pub const DRILLING_FACTOR: f64 = 1e-3;

/// Local dofs per node: u_x, u_y, u_z, α, β.
pub const LOCAL: usize = 5;

/// Two-point Gauss rule through the thickness: (point, weight).
const THICKNESS_GAUSS: [(f64, f64); 2] = [
    (-0.577_350_269_189_625_8, 1.0),
    (0.577_350_269_189_625_8, 1.0),
];

/// A strain row over the element's local dofs, `[node][u_x, u_y, u_z, α, β]`.
pub type Row<const N: usize> = [[f64; LOCAL]; N];

/// Covariant strain rows in the order [rr, ss, rs, rt, st].
pub type CovariantRows<const N: usize> = [Row<N>; 5];

/// Σ w_i row_i.
pub fn combine<const N: usize>(terms: &[(f64, &Row<N>)]) -> Row<N> {
    let mut out = [[0.0; LOCAL]; N];
    for (w, row) in terms {
        for (o, r) in out.as_flattened_mut().iter_mut().zip(row.as_flattened()) {
            *o += w * r;
        }
    }
    out
}

/// The covariant rows of the same strain tensor in another basis: with `m[k][i]` = b_k · g^i
/// (new covariant base vectors b_k against the old contravariant g^i, m_ki = `m[k][i]`),
/// ε'_kl = Σ_ij m_ki m_lj ε_ij (ε_tt = 0: inextensible director).
pub fn change_basis<const N: usize>(
    rows: &CovariantRows<N>,
    m: &[[f64; 3]; 3],
) -> CovariantRows<N> {
    // Index of component (i, j) among the rows, with its symmetric weight.
    let index = |i: usize, j: usize| match (i.min(j), i.max(j)) {
        (0, 0) => Some(0),
        (1, 1) => Some(1),
        (0, 1) => Some(2),
        (0, 2) => Some(3),
        (1, 2) => Some(4),
        _ => None,
    };
    let targets = [(0, 0), (1, 1), (0, 1), (0, 2), (1, 2)];
    targets.map(|(k, l)| {
        let mut terms = Vec::with_capacity(9);
        for i in 0..3 {
            for j in 0..3 {
                let w = m[k][i] * m[l][j];
                if let (Some(c), true) = (index(i, j), w != 0.0) {
                    terms.push((w, &rows[c]));
                }
            }
        }
        combine(&terms)
    })
}

/// Shape functions h_k and their r and s derivatives at a point.
pub type ShapeValues<const N: usize> = ([f64; N], [f64; N], [f64; N]);

/// What makes an element of the family: interpolation, integration and tying.
pub trait Scheme<const N: usize>: Copy + std::fmt::Debug {
    /// Natural coordinates (r_k, s_k) of the nodes, in element order.
    const NODE_RS: [[f64; 2]; N];
    /// In-plane Gauss rule per direction: (point, weight).
    const GAUSS: &'static [(f64, f64)];
    /// The covariant strain rows sampled at the tying points, at one thickness coordinate.
    type Tied;
    /// Shape functions and derivatives at (r, s).
    fn shape(r: f64, s: f64) -> ShapeValues<N>;
    /// Samples what the scheme ties at thickness coordinate `t`.
    fn tie(el: &MitcShell<N, Self>, t: f64) -> Self::Tied;
    /// The assumed covariant rows at (r, s, t) from the tied samples.
    fn assumed(
        el: &MitcShell<N, Self>,
        tied: &Self::Tied,
        r: f64,
        s: f64,
        t: f64,
    ) -> CovariantRows<N>;
}

/// A shell element of `N` nodes with the tying scheme `S`: node positions (m), unit directors
/// and the thickness (m).
#[derive(Debug, Clone, Copy)]
pub struct MitcShell<const N: usize, S> {
    x: [V3; N],
    vn: [V3; N],
    v1: [V3; N],
    v2: [V3; N],
    a: f64,
    scheme: PhantomData<S>,
}

impl<const N: usize, S: Scheme<N>> MitcShell<N, S> {
    /// An element on nodes `x` (corners counter-clockwise seen from the directors' side, then
    /// the scheme's further nodes) with unit directors `directors` and thickness `thickness_m`.
    pub fn new(x: [V3; N], directors: [V3; N], thickness_m: f64) -> Self {
        let pairs = directors.map(tangent_pair);
        Self {
            x,
            vn: directors,
            v1: pairs.map(|p| p.0),
            v2: pairs.map(|p| p.1),
            a: thickness_m,
            scheme: PhantomData,
        }
    }

    /// The in-plane Gauss points with their weights (w_r w_s).
    fn gauss_points() -> impl Iterator<Item = (f64, f64, f64)> {
        S::GAUSS
            .iter()
            .flat_map(|&(r, wr)| S::GAUSS.iter().map(move |&(s, ws)| (r, s, wr * ws)))
    }

    /// Covariant base vectors g_r, g_s, g_t at a point.
    pub(super) fn base(&self, r: f64, s: f64, t: f64) -> [V3; 3] {
        let (h, hr, hs) = S::shape(r, s);
        let mut g = [[0.0; 3]; 3];
        for k in 0..N {
            let p = add(self.x[k], scale(0.5 * t * self.a, self.vn[k]));
            g[0] = add(g[0], scale(hr[k], p));
            g[1] = add(g[1], scale(hs[k], p));
            g[2] = add(g[2], scale(0.5 * self.a * h[k], self.vn[k]));
        }
        g
    }

    /// ∂u/∂r, ∂u/∂s, ∂u/∂t per local dof, `[derivative][node][local dof]`.
    fn displacement_derivatives(&self, r: f64, s: f64, t: f64) -> [[[V3; LOCAL]; N]; 3] {
        let (h, hr, hs) = S::shape(r, s);
        let mut d = [[[[0.0; 3]; LOCAL]; N]; 3];
        for k in 0..N {
            let rot_alpha = scale(-1.0, self.v2[k]);
            let rot_beta = self.v1[k];
            for (m, dh) in [hr[k], hs[k]].into_iter().enumerate() {
                for c in 0..3 {
                    d[m][k][c][c] = dh;
                }
                d[m][k][3] = scale(dh * 0.5 * t * self.a, rot_alpha);
                d[m][k][4] = scale(dh * 0.5 * t * self.a, rot_beta);
            }
            d[2][k][3] = scale(0.5 * self.a * h[k], rot_alpha);
            d[2][k][4] = scale(0.5 * self.a * h[k], rot_beta);
        }
        d
    }

    /// Covariant strain rows [rr, ss, rs, rt, st] at a point, all computed directly.
    pub(super) fn covariant_direct(&self, r: f64, s: f64, t: f64) -> CovariantRows<N> {
        let g = self.base(r, s, t);
        let d = self.displacement_derivatives(r, s, t);
        let mut e = [[[0.0; LOCAL]; N]; 5];
        for k in 0..N {
            for i in 0..LOCAL {
                let (dr, ds, dt) = (d[0][k][i], d[1][k][i], d[2][k][i]);
                e[0][k][i] = dot(g[0], dr);
                e[1][k][i] = dot(g[1], ds);
                e[2][k][i] = 0.5 * (dot(g[0], ds) + dot(g[1], dr));
                e[3][k][i] = 0.5 * (dot(g[0], dt) + dot(g[2], dr));
                e[4][k][i] = 0.5 * (dot(g[1], dt) + dot(g[2], ds));
            }
        }
        e
    }

    /// Lamina frame e_1 ∥ g_r, e_3 ∥ g_r × g_s, and `Q[a][i]` = g^i · e_a; with det J.
    fn frame(&self, r: f64, s: f64, t: f64) -> ([V3; 3], [[f64; 3]; 3], f64) {
        let g = self.base(r, s, t);
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

    /// Cartesian strain rows [ε11, ε22, γ12, γ23, γ13] from covariant rows and the frame's Q.
    fn cartesian(cov: &CovariantRows<N>, q: &[[f64; 3]; 3]) -> CovariantRows<N> {
        // Symmetric covariant tensor of rows: E[i][j]; E[2][2] = 0 (inextensible director).
        let comp = |i: usize, j: usize| -> Option<&Row<N>> {
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
        let mut b = [[[0.0; LOCAL]; N]; 5];
        for (row, (ca, cb, f)) in b.iter_mut().zip(pairs) {
            for i in 0..3 {
                for j in 0..3 {
                    let w = f * q[ca][i] * q[cb][j];
                    if let (Some(e), true) = (comp(i, j), w != 0.0) {
                        let row = row.as_flattened_mut();
                        for (x, y) in row.iter_mut().zip(e.as_flattened()) {
                            *x += w * y;
                        }
                    }
                }
            }
        }
        b
    }

    /// Checks the Jacobian at the nodes and Gauss points of the mid-surface.
    ///
    /// # Errors
    /// [`ElementDefect`] with the parametric position of the first bad point.
    pub fn check_geometry(&self) -> Result<(), ElementDefect> {
        let points = S::NODE_RS
            .iter()
            .copied()
            .chain(Self::gauss_points().map(|(r, s, _)| [r, s]));
        for at in points {
            let g = self.base(at[0], at[1], 0.0);
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

    /// The row of the map from global dofs (u, θ per node) to local dof `local` (u, α, β).
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

    /// Tᵀ A T for a symmetric local matrix A (5N × 5N, row-major), as (A T) then Tᵀ (A T) with
    /// the sparse T (one entry per translational row, three per rotational row).
    fn transform_to_global(&self, a: &[f64]) -> ElementMatrix {
        let (nl, ng) = (LOCAL * N, 6 * N);
        let mut at = vec![0.0; nl * ng];
        for i in 0..nl {
            for j in 0..nl {
                let aij = a[i * nl + j];
                for (gj, tj) in self.local_row(j) {
                    at[i * ng + gj] += aij * tj;
                }
            }
        }
        let mut out = ElementMatrix::zeros(ng);
        for i in 0..nl {
            for (gi, ti) in self.local_row(i) {
                if ti != 0.0 {
                    for (o, x) in out[gi].iter_mut().zip(&at[i * ng..(i + 1) * ng]) {
                        *o += ti * x;
                    }
                }
            }
        }
        out
    }

    /// Element stiffness over the 6N global dofs (N/m, N, N·m blocks).
    ///
    /// # Errors
    /// [`ElementDefect::Inverted`] if the Jacobian is not positive at an integration point (a
    /// shell too thick for its curvature, or a folded element).
    pub fn stiffness(&self, mat: &ShellMaterial) -> Result<ElementMatrix, ElementDefect> {
        let nl = LOCAL * N;
        let c = mat.young_pa / (1.0 - mat.poisson * mat.poisson);
        let g = mat.shear_pa();
        let moduli = [c, c, g, SHEAR_CORRECTION * g, SHEAR_CORRECTION * g];
        let mut k = vec![0.0; nl * nl];
        let tied = THICKNESS_GAUSS.map(|(t, _)| S::tie(self, t));
        for (r, s, w) in Self::gauss_points() {
            for (&(t, wt), tied) in THICKNESS_GAUSS.iter().zip(&tied) {
                let cov = S::assumed(self, tied, r, s, t);
                let (_, q, det) = self.frame(r, s, t);
                if det.is_nan() || det <= 0.0 {
                    return Err(ElementDefect::Inverted { at: [r, s] });
                }
                let b = Self::cartesian(&cov, &q);
                let b: [&[f64]; 5] = [0, 1, 2, 3, 4].map(|m| b[m].as_flattened());
                // C b: [[c, νc], [νc, c]] on the membrane pair, diagonal on the rest.
                let mut cb = vec![0.0; 5 * nl];
                for i in 0..nl {
                    cb[i] = c * b[0][i] + mat.poisson * c * b[1][i];
                    cb[nl + i] = mat.poisson * c * b[0][i] + c * b[1][i];
                    for m in 2..5 {
                        cb[m * nl + i] = moduli[m] * b[m][i];
                    }
                }
                let dv = det * w * wt;
                for i in 0..nl {
                    for j in i..nl {
                        let mut sum = 0.0;
                        for m in 0..5 {
                            sum += b[m][i] * cb[m * nl + j];
                        }
                        k[i * nl + j] += sum * dv;
                    }
                }
            }
        }
        for i in 0..nl {
            for j in 0..i {
                k[i * nl + j] = k[j * nl + i];
            }
        }
        let mut kg = self.transform_to_global(&k);
        self.add_drilling(&mut kg, DRILLING_FACTOR * g * mat.thickness_m);
        Ok(kg)
    }

    /// Adds ½ γ ∫ (θ·e_3 − ω_n)² dA over the mid-surface (the scheme's Gauss rule).
    fn add_drilling(&self, k: &mut ElementMatrix, gamma: f64) {
        let ng = 6 * N;
        for (r, s, w) in Self::gauss_points() {
            let (e, q, _) = self.frame(r, s, 0.0);
            let g = self.base(r, s, 0.0);
            let da = norm(cross(g[0], g[1])) * w;
            let d = self.displacement_derivatives(r, s, 0.0);
            // ∂u/∂x_a = Σ_i u_,i Q[a][i]; ω = ½(e2·∂u/∂x1 − e1·∂u/∂x2), over local dofs.
            let mut row = vec![0.0; ng];
            for kk in 0..N {
                for i in 0..LOCAL {
                    let du = |a: usize| {
                        add(
                            add(scale(q[a][0], d[0][kk][i]), scale(q[a][1], d[1][kk][i])),
                            scale(q[a][2], d[2][kk][i]),
                        )
                    };
                    let omega = 0.5 * (dot(e[1], du(0)) - dot(e[0], du(1)));
                    for (gi, ti) in self.local_row(LOCAL * kk + i) {
                        row[gi] -= ti * omega;
                    }
                }
            }
            let (h, _, _) = S::shape(r, s);
            for kk in 0..N {
                for c in 0..3 {
                    row[6 * kk + 3 + c] += h[kk] * e[2][c];
                }
            }
            for i in 0..ng {
                let gi = gamma * row[i] * da;
                for (kij, rj) in k[i].iter_mut().zip(&row) {
                    *kij += gi * rj;
                }
            }
        }
    }

    /// Consistent mass over the 6N global dofs (kg, kg·m, kg·m² blocks).
    pub fn mass(&self, mat: &ShellMaterial) -> ElementMatrix {
        let nl = LOCAL * N;
        let mut m = vec![0.0; nl * nl];
        for (r, s, w) in Self::gauss_points() {
            for &(t, wt) in &THICKNESS_GAUSS {
                let (h, _, _) = S::shape(r, s);
                let g = self.base(r, s, t);
                let det = dot(g[0], cross(g[1], g[2]));
                // N: 3 × 5N
                let mut n = vec![[0.0; 3]; nl];
                for k in 0..N {
                    for c in 0..3 {
                        n[LOCAL * k + c][c] = h[k];
                    }
                    n[LOCAL * k + 3] = scale(-0.5 * t * self.a * h[k], self.v2[k]);
                    n[LOCAL * k + 4] = scale(0.5 * t * self.a * h[k], self.v1[k]);
                }
                let dv = mat.density_kg_m3 * det * w * wt;
                for i in 0..nl {
                    for j in i..nl {
                        m[i * nl + j] += dot(n[i], n[j]) * dv;
                    }
                }
            }
        }
        for i in 0..nl {
            for j in 0..i {
                m[i * nl + j] = m[j * nl + i];
            }
        }
        self.transform_to_global(&m)
    }
}
