//! MITC9: the 9-node shell element with mixed interpolation of all covariant strains
//! [Bucalem & Bathe 1993; Bathe, Lee & Hiller 2003]. Biquadratic (Lagrange) shape functions,
//! 3×3 Gauss in-plane; with a = 1/√3 and b = √(3/5) the covariant strains are tied as
//!
//! | strains | tying points | interpolation |
//! |---|---|---|
//! | ε̃_rr, ε̃_rt | r = ±a, s ∈ {−b, 0, b} | linear in r, quadratic in s |
//! | ε̃_ss, ε̃_st | r ∈ {−b, 0, b}, s = ±a | quadratic in r, linear in s |
//! | ε̃_rs | r = ±a, s = ±a | bilinear |
//!
//! which removes transverse shear locking (the shear strains of a bending field are sampled
//! where a quadratic field's parasitic terms vanish) and membrane locking of curved elements.
//!
//! The samples are tied in the covariant basis of the element's centre, g_i(0, 0, t), not each
//! tying point's own [Wisniewski & Turska 2018, MITC9i]: at a tying point
//! ε̄_kl = (g_k^c·g^i)(g_l^c·g^j) ε̃_ij, interpolated, and turned back to the local basis at the
//! integration point. On a parallelogram the bases coincide and this is the plain MITC9; on a
//! distorted element a constant strain has constant central components, so the element passes
//! the membrane and bending patch tests that plain MITC9 fails there. The rest (strains,
//! material, drilling, mass) is the shared kernel, [`super::shell`].
//!
//! Node order (Gmsh and VTK): corners (−1, −1), (1, −1), (1, 1), (−1, 1); mid-sides
//! (0, −1), (1, 0), (0, 1), (−1, 0); centre (0, 0).

use super::shell::{CovariantRows, MitcShell, Row, Scheme, ShapeValues, change_basis, combine};
use crate::vec3::{V3, dot, inverse_columns};

/// Natural coordinates (r_k, s_k) of the 9-node quadrilateral's nodes, in element order.
pub const NODE_RS_9: [[f64; 2]; 9] = [
    [-1.0, -1.0],
    [1.0, -1.0],
    [1.0, 1.0],
    [-1.0, 1.0],
    [0.0, -1.0],
    [1.0, 0.0],
    [0.0, 1.0],
    [-1.0, 0.0],
    [0.0, 0.0],
];

const GAUSS_3: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// a = 1/√3: the linear direction's tying coordinates.
const A: f64 = 0.577_350_269_189_625_8;
/// b = √(3/5): the quadratic direction's outer tying coordinates.
const B: f64 = 0.774_596_669_241_483_4;

/// Quadratic Lagrange polynomials through −1, 0, 1 at x, and their derivatives.
fn lagrange3(x: f64) -> ([f64; 3], [f64; 3]) {
    (
        [0.5 * x * (x - 1.0), 1.0 - x * x, 0.5 * x * (x + 1.0)],
        [x - 0.5, -2.0 * x, x + 0.5],
    )
}

/// Biquadratic shape functions h_k(r, s) = L_{r_k}(r) L_{s_k}(s) of the 9-node quadrilateral
/// ([`NODE_RS_9`]), L the quadratic Lagrange polynomials through −1, 0, 1; and their r and s
/// derivatives.
pub fn biquadratic_shape(r: f64, s: f64) -> ShapeValues<9> {
    let (lr, dlr) = lagrange3(r);
    let (ls, dls) = lagrange3(s);
    let index = |c: f64| (c + 1.0) as usize;
    let mut h = [0.0; 9];
    let mut hr = [0.0; 9];
    let mut hs = [0.0; 9];
    for (k, [rk, sk]) in NODE_RS_9.iter().enumerate() {
        let (i, j) = (index(*rk), index(*sk));
        h[k] = lr[i] * ls[j];
        hr[k] = dlr[i] * ls[j];
        hs[k] = lr[i] * dls[j];
    }
    (h, hr, hs)
}

/// Linear interpolation through ±a: weights of the samples at −a and +a.
fn linear_through(x: f64) -> [f64; 2] {
    [0.5 * (1.0 - x / A), 0.5 * (1.0 + x / A)]
}

/// Quadratic interpolation through −b, 0, b: weights of the three samples.
fn quadratic_through(x: f64) -> [f64; 3] {
    let b2 = B * B;
    [
        x * (x - B) / (2.0 * b2),
        1.0 - x * x / b2,
        x * (x + B) / (2.0 * b2),
    ]
}

/// The MITC9 interpolation and tying.
#[derive(Debug, Clone, Copy)]
pub struct Mitc9;

/// A MITC9 element: node positions (m), unit directors and the thickness (m).
pub type Quad9Mitc = MitcShell<9, Mitc9>;

/// The MITC9 samples at one thickness coordinate.
#[derive(Debug, Clone)]
pub struct Mitc9Tied {
    /// ε̃_rr and ε̃_rt at (∓a, {−b, 0, b}): `[component][i over r][j over s]`.
    r_family: [[[Row<9>; 3]; 2]; 2],
    /// ε̃_ss and ε̃_st at ({−b, 0, b}, ∓a): `[component][i over r][j over s]`.
    s_family: [[[Row<9>; 2]; 3]; 2],
    /// ε̃_rs at (∓a, ∓a).
    rs: [[Row<9>; 2]; 2],
    /// Contravariant base vectors of the element's centre at this thickness coordinate.
    central_contravariant: [V3; 3],
}

impl Scheme<9> for Mitc9 {
    const NODE_RS: [[f64; 2]; 9] = NODE_RS_9;
    const GAUSS: &'static [(f64, f64)] = &GAUSS_3;
    type Tied = Box<Mitc9Tied>;

    fn shape(r: f64, s: f64) -> ShapeValues<9> {
        biquadratic_shape(r, s)
    }

    fn tie(el: &Quad9Mitc, t: f64) -> Self::Tied {
        let central = el.base(0.0, 0.0, t);
        let (central_contravariant, _) = inverse_columns(central[0], central[1], central[2]);
        let direct = |r, s| {
            let g = el.base(r, s, t);
            let (gcon, _) = inverse_columns(g[0], g[1], g[2]);
            change_basis(&el.covariant_direct(r, s, t), &projections(&central, &gcon))
        };
        let zero = [[0.0; 5]; 9];
        let mut tied = Box::new(Mitc9Tied {
            r_family: [[[zero; 3]; 2]; 2],
            s_family: [[[zero; 2]; 3]; 2],
            rs: [[zero; 2]; 2],
            central_contravariant,
        });
        let lin = [-A, A];
        let quad = [-B, 0.0, B];
        for (i, &r) in lin.iter().enumerate() {
            for (j, &s) in quad.iter().enumerate() {
                let e = direct(r, s);
                tied.r_family[0][i][j] = e[0];
                tied.r_family[1][i][j] = e[3];
                let e = direct(s, r);
                tied.s_family[0][j][i] = e[1];
                tied.s_family[1][j][i] = e[4];
            }
            for (j, &s) in lin.iter().enumerate() {
                tied.rs[i][j] = direct(r, s)[2];
            }
        }
        tied
    }

    fn assumed(el: &Quad9Mitc, tied: &Self::Tied, r: f64, s: f64, t: f64) -> CovariantRows<9> {
        let (lr, ls) = (linear_through(r), linear_through(s));
        let (qr, qs) = (quadratic_through(r), quadratic_through(s));
        let central = [
            tensor(lr, qs, &tied.r_family[0]),
            tensor(qr, ls, &tied.s_family[0]),
            tensor(lr, ls, &tied.rs),
            tensor(lr, qs, &tied.r_family[1]),
            tensor(qr, ls, &tied.s_family[1]),
        ];
        let basis = projections(&el.base(r, s, t), &tied.central_contravariant);
        change_basis(&central, &basis)
    }
}

/// The tensor-product interpolation `Σ_ij w_r[i] w_s[j] samples[i][j]`.
fn tensor<const I: usize, const J: usize>(
    w_r: [f64; I],
    w_s: [f64; J],
    samples: &[[Row<9>; J]; I],
) -> Row<9> {
    let mut terms = Vec::with_capacity(I * J);
    for (wi, row) in w_r.iter().zip(samples) {
        for (wj, sample) in w_s.iter().zip(row) {
            terms.push((wi * wj, sample));
        }
    }
    combine(&terms)
}

/// `m[k][i]` = b_k · d^i.
fn projections(b: &[V3; 3], d: &[V3; 3]) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|k| [0, 1, 2].map(|i| dot(b[k], d[i])))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Partition of unity, the Kronecker property at the nodes, and derivatives that sum to
    /// zero (a constant field has no gradient).
    #[test]
    fn biquadratic_shape_functions_are_nodal_and_sum_to_one() {
        for (k, [rk, sk]) in NODE_RS_9.iter().enumerate() {
            let (h, _, _) = biquadratic_shape(*rk, *sk);
            for (m, hm) in h.iter().enumerate() {
                assert_eq!(*hm, f64::from(u8::from(m == k)), "h_{m} at node {k}");
            }
        }
        for (r, s) in [(0.3, -0.7), (-0.9, 0.1), (0.55, 0.55)] {
            let (h, hr, hs) = biquadratic_shape(r, s);
            assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            assert!(hr.iter().sum::<f64>().abs() < 1e-15);
            assert!(hs.iter().sum::<f64>().abs() < 1e-15);
            // x = Σ h_k r_k reproduces r, and its derivative is 1.
            let x: f64 = h.iter().zip(&NODE_RS_9).map(|(h, p)| h * p[0]).sum();
            let dx: f64 = hr.iter().zip(&NODE_RS_9).map(|(h, p)| h * p[0]).sum();
            assert!((x - r).abs() < 1e-15 && (dx - 1.0).abs() < 1e-15);
        }
    }

    /// The tying interpolations reproduce their samples at the tying points.
    #[test]
    fn tying_interpolations_pass_through_their_points() {
        assert_eq!(linear_through(-A), [1.0, 0.0]);
        assert!((linear_through(A)[1] - 1.0).abs() < 1e-15);
        let q = quadratic_through(B);
        assert!(q[0].abs() < 1e-15 && q[1].abs() < 1e-15 && (q[2] - 1.0).abs() < 1e-15);
        assert_eq!(quadratic_through(0.0), [0.0, 1.0, 0.0]);
    }
}
