//! MITC4: the 4-node shell element with mixed-interpolated transverse shear strains
//! [Dvorkin & Bathe 1984; Bathe 2014, §5.4], the paper's element.
//!
//! Bilinear shape functions, 2×2 Gauss in-plane. The in-plane covariant strains are computed
//! directly; the transverse shear strains are tied (Dvorkin–Bathe):
//!
//! ε̃_rt = ½(1+s) ε̃_rt|_A + ½(1−s) ε̃_rt|_C,  A = (0, 1), C = (0, −1)
//! ε̃_st = ½(1+r) ε̃_st|_D + ½(1−r) ε̃_st|_B,  D = (1, 0), B = (−1, 0)
//!
//! The rest (strains, material, drilling, mass) is the shared kernel, [`super::shell`].

use super::shell::{CovariantRows, MitcShell, Scheme, ShapeValues, combine};

/// Natural coordinates (r_k, s_k) of the 4-node quadrilateral's nodes, in element order.
pub const NODE_RS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

const GAUSS_2: [(f64, f64); 2] = [
    (-0.577_350_269_189_625_8, 1.0),
    (0.577_350_269_189_625_8, 1.0),
];

/// Bilinear shape functions h_k = ¼(1 + r r_k)(1 + s s_k) of the 4-node quadrilateral (nodes
/// at (r_k, s_k) = (−1, −1), (1, −1), (1, 1), (−1, 1)) and their r and s derivatives.
pub fn bilinear_shape(r: f64, s: f64) -> ShapeValues<4> {
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

/// The MITC4 interpolation and tying.
#[derive(Debug, Clone, Copy)]
pub struct Mitc4;

/// A MITC4 element: node positions (m), unit directors and the thickness (m).
pub type Quad4Mitc = MitcShell<4, Mitc4>;

impl Scheme<4> for Mitc4 {
    const NODE_RS: [[f64; 2]; 4] = NODE_RS;
    const GAUSS: &'static [(f64, f64)] = &GAUSS_2;
    /// ε̃_rt at A, C and ε̃_st at D, B.
    type Tied = [super::shell::Row<4>; 4];

    fn shape(r: f64, s: f64) -> ShapeValues<4> {
        bilinear_shape(r, s)
    }

    fn tie(el: &Quad4Mitc, t: f64) -> Self::Tied {
        let direct = |r, s| el.covariant_direct(r, s, t);
        [
            direct(0.0, 1.0)[3],
            direct(0.0, -1.0)[3],
            direct(1.0, 0.0)[4],
            direct(-1.0, 0.0)[4],
        ]
    }

    fn assumed(el: &Quad4Mitc, tied: &Self::Tied, r: f64, s: f64, t: f64) -> CovariantRows<4> {
        let mut e = el.covariant_direct(r, s, t);
        let [a, c, d, b] = tied;
        e[3] = combine(&[(0.5 * (1.0 + s), a), (0.5 * (1.0 - s), c)]);
        e[4] = combine(&[(0.5 * (1.0 + r), d), (0.5 * (1.0 - r), b)]);
        e
    }
}
