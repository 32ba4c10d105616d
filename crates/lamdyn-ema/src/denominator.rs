//! The denominator of the LSCF model the diagram's poles were read from, kept for the pole
//! refinement and its check: its roots in the Ω = e^{−iωΔt} domain ([`crate::lscf`]), and the
//! real partial-fraction columns of those held fixed.
//!
//! The model of order n is H_o(Ω) = B_o(Ω) A(Ω)⁻¹ with real coefficients. Its partial fractions
//!
//!   H_o(Ω) = d_o + Σ_r c_o,r / (Ω − x_r),   x_r the roots of det A, c_o,r̄ = c̄_o,r,
//!
//! span the functions the numerators B_o can make; with the roots fixed they are linear in the
//! residues: one real column per real root, two per conjugate pair (g₁ = 1/(Ω−x) + 1/(Ω−x̄),
//! g₂ = i[1/(Ω−x) − 1/(Ω−x̄)]), real and imaginary part of every line as two rows.

use faer::Mat;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The denominator of the LSCF model the physical poles were read from.
#[derive(Debug, Clone, PartialEq)]
pub struct LscfContext {
    /// The model's sampling interval Δt ([`crate::lscf::sample_interval`]), s.
    pub dt: f64,
    /// Every root x of its denominator, in the Ω domain ([`crate::lscf::OrderPoles::roots`]).
    pub roots: Vec<Complex64>,
}

/// One root held fixed: one real column, or two for a conjugate pair.
#[derive(Debug, Clone, Copy)]
pub(crate) enum FixedRoot {
    /// A real root: one column 1/(Ω − x).
    Real(f64),
    /// One root x of a conjugate pair (x, x̄): the two columns of [`pair_columns`].
    Pair(Complex64),
}

impl LscfContext {
    /// The roots held fixed beside `poles` (rad/s): one of each conjugate pair and the real
    /// roots, less the root nearest each pole (its own root at this order) where one lies
    /// within three half-power half-widths or 1 % of |λ|.
    pub(crate) fn fixed_roots(&self, poles: &[Complex64]) -> Vec<FixedRoot> {
        let pairs: Vec<Complex64> = self
            .roots
            .iter()
            .copied()
            .filter(|&x| !is_real(x) && x.im < 0.0)
            .collect();
        let pairs = without_own(pairs, poles, |x| self.pole(x));
        let reals = self
            .roots
            .iter()
            .filter(|&&x| is_real(x))
            .map(|x| FixedRoot::Real(x.re));
        pairs
            .into_iter()
            .map(FixedRoot::Pair)
            .chain(reals)
            .collect()
    }

    /// The roots that stand for what lies below `band_hz`: the positive real roots (at 0 Hz)
    /// and the conjugate pairs whose pole's damped frequency lies below the band (one root of
    /// each pair). The computational roots inside the band, with which a damped pole would
    /// compete, are not among them, nor the negative real roots, where the model gathers the
    /// modes above the band at its upper edge (1/(2Δt)): a damped mode just above the band is a
    /// poor fit to them, and the refinement holds pseudo-modes there instead
    /// ([`crate::band::pseudo_modes_above`]).
    pub(crate) fn roots_below(&self, band_hz: [f64; 2]) -> Vec<Complex64> {
        self.roots
            .iter()
            .copied()
            .filter(|&x| {
                (is_real(x) && x.re > 0.0)
                    || (x.im < 0.0 && !is_real(x) && self.pole(x).im / (2.0 * PI) < band_hz[0])
            })
            .collect()
    }

    /// Whether the refinement of `pole` (rad/s) holds the roots `below` ([`Self::roots_below`]):
    /// not where one of their poles lies within three half-power half-widths (or 1 % of |λ|) of
    /// `pole`, since a damped pole next to the band's edge trades with them (measured in
    /// docs/ema.md, "Damped poles").
    pub(crate) fn holds_below_beside(&self, below: &[Complex64], pole: Complex64) -> bool {
        !below.iter().any(|x| {
            let q = self.pole(*x);
            within_reach(pole, Complex64::new(q.re, q.im.abs()))
        })
    }

    /// The columns of the roots `held` on `lines` (indices into `freqs_hz`), as real rows (re,
    /// im of each line) scaled to unit norm: one per real root, two per conjugate pair (one
    /// root of each pair given). No direct term: the refinement's residual terms hold the
    /// constant.
    pub(crate) fn held_root_columns(
        &self,
        freqs_hz: &[f64],
        lines: &[usize],
        held: &[Complex64],
    ) -> Mat<f64> {
        let held: Vec<FixedRoot> = held
            .iter()
            .map(|&x| {
                if is_real(x) {
                    FixedRoot::Real(x.re)
                } else {
                    FixedRoot::Pair(x)
                }
            })
            .collect();
        let omega = self.omega(freqs_hz, lines);
        scaled_real_matrix(&root_columns(&omega, &held), 2 * lines.len())
    }

    /// Ω = e^{−iωΔt} of each of `lines` (indices into `freqs_hz`).
    pub(crate) fn omega(&self, freqs_hz: &[f64], lines: &[usize]) -> Vec<Complex64> {
        lines
            .iter()
            .map(|&k| Complex64::from_polar(1.0, -2.0 * PI * freqs_hz[k] * self.dt))
            .collect()
    }

    /// The pole λ = −ln(x)/Δt of root x.
    pub(crate) fn pole(&self, x: Complex64) -> Complex64 {
        -x.ln() / self.dt
    }

    /// The root x = e^{−λΔt} of pole λ.
    pub(crate) fn root(&self, p: Complex64) -> Complex64 {
        (-p * self.dt).exp()
    }
}

/// `rest` less each of `poles`' own (rad/s): in turn, each pole takes the one of `rest` whose
/// pole (`pole_of`) lies nearest it, where that lies within its reach ([`within_reach`]).
pub(crate) fn without_own<T: Copy>(
    mut rest: Vec<T>,
    poles: &[Complex64],
    pole_of: impl Fn(T) -> Complex64,
) -> Vec<T> {
    for &p in poles {
        let own = rest
            .iter()
            .enumerate()
            .map(|(k, &x)| (k, (pole_of(x) - p).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, _)) = own.filter(|&(k, _)| within_reach(p, pole_of(rest[k]))) {
            rest.swap_remove(k);
        }
    }
    rest
}

/// Whether `q` lies within the reach of pole `p` (both rad/s): three half-power half-widths of
/// `p`, or 1 % of |p| for a lightly damped one.
fn within_reach(p: Complex64, q: Complex64) -> bool {
    (q - p).norm() <= 3.0 * (-p.re).max(0.01 * p.norm())
}

/// The partial-fraction columns of `roots` over the lines Ω (module docs), complex: one per
/// real root, two per conjugate pair ([`pair_columns`]).
pub(crate) fn root_columns(omega: &[Complex64], roots: &[FixedRoot]) -> Vec<Vec<Complex64>> {
    let mut cols = Vec::with_capacity(2 * roots.len());
    for root in roots {
        match *root {
            FixedRoot::Real(x) => cols.push(omega.iter().map(|w| 1.0 / (w - x)).collect()),
            FixedRoot::Pair(x) => {
                let (g1, g2) = pair_columns(omega, x);
                cols.push(g1);
                cols.push(g2);
            }
        }
    }
    cols
}

/// Whether root `x` is real (its imaginary part within rounding of its modulus).
pub(crate) fn is_real(x: Complex64) -> bool {
    x.im.abs() <= 1e-12 * x.norm().max(1e-300)
}

/// The two real-coefficient columns of the conjugate pair (x, x̄) over the lines Ω (module
/// docs).
pub(crate) fn pair_columns(omega: &[Complex64], x: Complex64) -> (Vec<Complex64>, Vec<Complex64>) {
    omega
        .iter()
        .map(|w| {
            let (a, b) = (1.0 / (w - x), 1.0 / (w - x.conj()));
            (a + b, Complex64::i() * (a - b))
        })
        .unzip()
}

/// The complex columns as a real matrix (real and imaginary part of each line in turn), each
/// column scaled to unit norm (for the QR's conditioning; the span is what counts).
pub(crate) fn scaled_real_matrix(cols: &[Vec<Complex64>], rows: usize) -> Mat<f64> {
    let norms: Vec<f64> = cols
        .iter()
        .map(|c| {
            c.iter()
                .map(|v| v.norm_sqr())
                .sum::<f64>()
                .sqrt()
                .max(f64::MIN_POSITIVE)
        })
        .collect();
    let mut m = Mat::<f64>::zeros(rows, cols.len());
    for (c, (col, norm)) in cols.iter().zip(&norms).enumerate() {
        let scale = 1.0 / norm;
        let out = m.col_as_slice_mut(c);
        for (pair, v) in out.chunks_exact_mut(2).zip(col) {
            pair[0] = v.re * scale;
            pair[1] = v.im * scale;
        }
    }
    m
}
