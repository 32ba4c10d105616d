//! Each mode's residues from the lines around its own pole: the mode shapes.
//!
//! **Why.** The residues of the whole band's fit ([`crate::lsfd`]) share the band with a real
//! lower and upper residual. Damped modes above and below the band, and modes the diagram did
//! not find, do not fit those two terms, and their misfit goes into the residues of the poles
//! that are there, differently on each curve: the shapes of real modes turn complex. On a
//! simply supported plate at ζ = 8 %, noise-free, with the exact poles, the band's fit gives
//! its first mode an MPC well below one, which the verdict then reads as one pole over a
//! cluster (docs/ema.md, method step 5, has the measurements). A mode's residues are decided
//! where its term is large, near its pole, and there the rest of the band is smooth.
//!
//! **The fit.** Within ±[`HALF_WIDTHS`] half-power half-widths of pole λ_r (ζ_r f_r each, at
//! least [`MIN_HALF_WINDOW_LINES`] lines), every curve is fitted by least squares with
//!
//!   (iω)^k [A/(iω − λ) + A*/(iω − λ*)]
//!
//! for the pole and for each pole whose half-power band reaches the window (the terms of the
//! band's fit, k = 0, 1, 2 for receptance, mobility, accelerance), and a complex quadratic in
//! frequency for everything else. A_r is the mode's residue on that curve, in the units of the
//! band's fit, so shapes, their scaling through a driving point and the participation factors
//! are made from it as from those. The band's fit still gives the regenerated FRFs.

use crate::band::line_spacing;
use crate::lscf::{pole_damping, pole_freq_hz};
use crate::projection::LineBasis;
use crate::quality::Measured;
use faer::Mat;
use faer::linalg::solvers::SolveLstsq;
use lamdyn_frf::Quantity;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The window's half-width in half-power half-widths ζf of the pole.
pub const HALF_WIDTHS: f64 = 2.0;

/// The window's least half-width, in lines (a pole narrower than a line is still fitted over
/// enough lines for its terms and the quadratic).
pub const MIN_HALF_WINDOW_LINES: f64 = 20.0;

/// The residues of every pole of `poles` (rad/s) over the curves of `data` (values of
/// `quantity`; module docs), `residues[r][o]`; None for a pole with too few lines in its window
/// or a fit that is not finite (the band's residues stand then).
pub fn local_residues(
    poles: &[Complex64],
    quantity: Quantity,
    data: Measured,
) -> Vec<Option<Vec<Complex64>>> {
    let spacing = line_spacing(data.freqs_hz, data.lines);
    (0..poles.len())
        .map(|r| residues_near(poles, r, quantity, data, spacing))
        .collect()
}

/// The lines around one pole that its local fits use (module docs; the second-shape test's
/// too): within ±[`HALF_WIDTHS`] ζf of f = |λ|/2π, at least [`MIN_HALF_WINDOW_LINES`] lines.
pub(crate) struct PoleWindow {
    /// The pole's frequency |λ|/2π, Hz.
    pub(crate) center_hz: f64,
    /// The half-width, Hz.
    pub(crate) half_hz: f64,
    /// The lines of the data within it.
    pub(crate) lines: Vec<usize>,
}

/// The half-width of the window of `pole` (Hz) on lines `spacing` Hz apart: [`HALF_WIDTHS`]
/// half-power half-widths ζf, at least [`MIN_HALF_WINDOW_LINES`] lines.
pub(crate) fn half_width_hz(pole: Complex64, spacing: f64) -> f64 {
    (HALF_WIDTHS * pole_damping(pole) * pole_freq_hz(pole)).max(MIN_HALF_WINDOW_LINES * spacing)
}

impl PoleWindow {
    /// The window of `pole` on `data` (lines `spacing` Hz apart); None for a pole whose damping
    /// is not positive and finite.
    pub(crate) fn of(pole: Complex64, data: Measured, spacing: f64) -> Option<Self> {
        let (center_hz, z) = (pole_freq_hz(pole), pole_damping(pole));
        if !(z.is_finite() && z > 0.0) {
            return None;
        }
        let half_hz = half_width_hz(pole, spacing);
        let lines = data
            .lines
            .iter()
            .copied()
            .filter(|&i| (data.freqs_hz[i] - center_hz).abs() <= half_hz)
            .collect();
        Some(Self {
            center_hz,
            half_hz,
            lines,
        })
    }

    /// The poles other than `poles[k]` (the window's own) whose half-power band, half-widths
    /// doubled for the tails (±2ζf), reaches the window.
    pub(crate) fn poles_reaching(&self, poles: &[Complex64], k: usize) -> Vec<Complex64> {
        poles
            .iter()
            .enumerate()
            .filter(|&(j, &p)| {
                let reach = self.half_hz + 2.0 * pole_damping(p) * pole_freq_hz(p);
                j != k && (pole_freq_hz(p) - self.center_hz).abs() <= reach
            })
            .map(|(_, p)| *p)
            .collect()
    }
}

/// The residues of pole `r` over every curve (module docs); `spacing` the lines' spacing, Hz.
fn residues_near(
    poles: &[Complex64],
    r: usize,
    quantity: Quantity,
    data: Measured,
    spacing: f64,
) -> Option<Vec<Complex64>> {
    let window = PoleWindow::of(poles[r], data, spacing)?;
    let mut local = vec![poles[r]];
    local.extend(window.poles_reaching(poles, r));
    let mut a = local_basis(&local, quantity, data.freqs_hz, &window);
    if a.nrows() < 2 * a.ncols() {
        return None;
    }
    let norms: Vec<f64> = (0..a.ncols())
        .map(|c| a.col(c).norm_l2().max(f64::MIN_POSITIVE))
        .collect();
    for (c, n) in norms.iter().enumerate() {
        a.col_mut(c).iter_mut().for_each(|x| *x /= *n);
    }
    let y = Mat::from_fn(a.nrows(), data.curves.len(), |row, o| {
        let h = data.curves[o][window.lines[row / 2]];
        if row % 2 == 0 { h.re } else { h.im }
    });
    let x = a.qr().solve_lstsq(&y);
    let residues: Vec<Complex64> = (0..data.curves.len())
        .map(|o| Complex64::new(x[(0, o)] / norms[0], x[(1, o)] / norms[1]))
        .collect();
    residues
        .iter()
        .all(|a| a.re.is_finite() && a.im.is_finite())
        .then_some(residues)
}

/// The local basis on `window` as real rows (re, im per line): the two columns of each of
/// `poles` (the band's fit's: (iω)^k [1/(iω − λ) + 1/(iω − λ*)] and
/// (iω)^k i[1/(iω − λ) − 1/(iω − λ*)]), the first pole's first, then 1, x, x² and i, ix, ix²,
/// x = (f − centre)/half-width.
fn local_basis(
    poles: &[Complex64],
    quantity: Quantity,
    freqs_hz: &[f64],
    window: &PoleWindow,
) -> Mat<f64> {
    let columns = 2 * poles.len() + 6;
    let mut a = Mat::zeros(2 * window.lines.len(), columns);
    for (i, &k) in window.lines.iter().enumerate() {
        let line = LineBasis::new(poles, quantity, 2.0 * PI * freqs_hz[k]);
        let mut values: Vec<Complex64> = line
            .fractions
            .iter()
            .flat_map(|&(t, tc)| {
                [
                    line.factor * (t + tc),
                    line.factor * Complex64::i() * (t - tc),
                ]
            })
            .collect();
        let x = (freqs_hz[k] - window.center_hz) / window.half_hz;
        for power in [1.0, x, x * x] {
            values.push(Complex64::new(power, 0.0));
            values.push(Complex64::new(0.0, power));
        }
        for (c, v) in values.iter().enumerate() {
            a[(2 * i, c)] = v.re;
            a[(2 * i + 1, c)] = v.im;
        }
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_frfs::{accelerances, pole};

    #[test]
    fn a_damped_mode_beside_modes_outside_the_band_keeps_its_real_shape() {
        // Modes at 8 %: one in the band 20-60 Hz next to its lower edge, four above it.
        let freqs: Vec<f64> = (1..=2000).map(|k| 0.1 * f64::from(k)).collect();
        let modes = vec![
            (25.0, 0.08, vec![1.0, 0.8, -0.5, 0.3]),
            (70.0, 0.08, vec![1.0, -0.9, 0.7, 0.6]),
            (85.0, 0.08, vec![0.5, 0.4, 1.0, -1.0]),
            (110.0, 0.08, vec![0.7, -0.2, -1.0, 0.9]),
            (140.0, 0.08, vec![0.3, 1.0, 0.6, -0.4]),
        ];
        let curves = accelerances(&freqs, &modes);
        let refs: Vec<&[Complex64]> = curves.iter().map(|c| c.as_slice()).collect();
        let lines = crate::band::positive_lines(&freqs, [20.0, 60.0]);
        let data = Measured {
            freqs_hz: &freqs,
            curves: &refs,
            lines: &lines,
        };
        let local = local_residues(&[pole(25.0, 0.08)], Quantity::Accelerance, data);
        let residues = local[0].as_ref().expect("a fit");
        let truth = |o: usize| {
            modes[0].2[o] * modes[0].2[0] / Complex64::new(0.0, 2.0 * pole(25.0, 0.08).im)
        };
        for (o, a) in residues.iter().enumerate() {
            assert!(
                (a - truth(o)).norm() < 2e-3 * truth(0).norm(),
                "curve {o}: {a}"
            );
        }
        assert!(crate::shapes::mpc(residues) > 0.9999);
        // The band's fit, its real residuals standing in for the modes above: complex.
        let poles = [pole(25.0, 0.08)];
        let band = crate::lsfd::lsfd(&freqs, &refs, Quantity::Accelerance, &poles, [20.0, 60.0]);
        let band_mpc = crate::shapes::mpc(&band.expect("a fit").shape(0, None));
        assert!(band_mpc < 0.99, "the band's fit's MPC {band_mpc}");
    }
}
