//! Refined poles held to their columns in the stabilization diagram.
//!
//! The refinement ([`crate::lsfd::refined_poles`]) starts from the diagram's poles and may move
//! a pole out of its column ([`SelectedPole::holds`]): noise, or a damped mode outside the band
//! for which the refinement borrows a pole, pulls it away. Such a pole is *lost*: the diagram's
//! pole is put back in its place, with a warning. So is each refined pole whose diagram pole's
//! half-power band overlaps that of a lost one: it was fitted beside a pole standing elsewhere
//! and may have taken over that pole's mode. Both estimators that refine
//! ([`crate::identify::PoleEstimator`]) start from the poles put back: the check of
//! [`crate::context`] tries the others, the refined estimator takes them (the cases measured
//! are in docs/ema.md, "Refinement, its check, and residues").

use crate::lscf::{half_power_bands_overlap, pole_damping, pole_freq_hz};
use crate::stabilization::{SelectedPole, StabilityCriteria};
use num_complex::Complex64;

/// The refined poles `refined` (index-aligned with `selected`) with each that left its column in
/// the diagram ([`SelectedPole::holds`]) replaced by the diagram's pole, and so each whose
/// diagram pole's half-power band overlaps that of a pole that left (it was fitted beside a pole
/// standing elsewhere and may have taken over that pole's mode: [`beside_a_lost_pole`]); with
/// one warning per pole that left.
pub(crate) fn in_their_columns(
    refined: &[Complex64],
    selected: &[SelectedPole],
    c: &StabilityCriteria,
) -> (Vec<Complex64>, Vec<String>) {
    let left = left_their_columns(refined, selected, c);
    let diagram: Vec<Complex64> = selected.iter().map(|p| p.pole).collect();
    let put_back = beside_a_lost_pole(&diagram, &left);
    let poles = (0..refined.len())
        .map(|r| if put_back[r] { diagram[r] } else { refined[r] })
        .collect();
    let warnings = (0..refined.len())
        .filter(|&r| left[r])
        .map(|r| {
            format!(
                "{}: the diagram's pole is kept, and so is that of each pole whose half-power \
                 band overlaps its own",
                out_of_column(&selected[r], refined[r])
            )
        })
        .collect();
    (poles, warnings)
}

/// "the refinement moved the pole at … to …, out of its column in the diagram (…)": the start of
/// a warning about the refined pole `p` of the column `col` it left.
fn out_of_column(col: &SelectedPole, p: Complex64) -> String {
    format!(
        "the refinement moved the pole at {:.3} Hz (zeta {:.3} %) to {:.3} Hz (zeta {:.3} %), out \
         of its column in the diagram ({:.3}-{:.3} Hz, zeta {:.3}-{:.3} %)",
        col.freq_hz,
        100.0 * col.damping,
        pole_freq_hz(p),
        100.0 * pole_damping(p),
        col.freq_range_hz[0],
        col.freq_range_hz[1],
        100.0 * col.damping_range[0],
        100.0 * col.damping_range[1],
    )
}

/// The refined poles `refined` (index-aligned with `selected`), each clamped into its column in
/// the diagram ([`SelectedPole::clamp`]): a pole that left is moved back to the column's edge
/// where it crossed it, in f and ζ; a pole the column holds is returned as it is. This is the
/// refinement's estimate limited to where the diagram supports this mode, and so a bounded
/// measure of how far the data pull the pole from the diagram's (`identify`'s widened
/// standard deviation).
pub(crate) fn clamped_to_their_columns(
    refined: &[Complex64],
    selected: &[SelectedPole],
    c: &StabilityCriteria,
) -> Vec<Complex64> {
    refined
        .iter()
        .zip(selected)
        .map(|(&p, col)| {
            let (f, z) = col.clamp(pole_freq_hz(p), pole_damping(p), c);
            pole_of(f, z)
        })
        .collect()
}

/// The pole λ = ω(−ζ + i√(1 − ζ²)), ω = 2πf, of frequency f (Hz, |λ|/2π) and damping ratio ζ
/// (−Re λ/|λ|); ζ is taken within [0, 1].
fn pole_of(freq_hz: f64, damping: f64) -> Complex64 {
    let w = 2.0 * std::f64::consts::PI * freq_hz;
    let z = damping.clamp(0.0, 1.0);
    Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
}

/// For each refined pole (index-aligned with `selected`), whether it left its column in the
/// diagram ([`SelectedPole::holds`]).
fn left_their_columns(
    refined: &[Complex64],
    selected: &[SelectedPole],
    c: &StabilityCriteria,
) -> Vec<bool> {
    refined
        .iter()
        .zip(selected)
        .map(|(&p, col)| !col.holds(pole_freq_hz(p), pole_damping(p), c))
        .collect()
}

/// For each diagram pole, whether the refinement lost it (`lost`: it left its column) or lost
/// a pole whose half-power band overlaps its own ([`half_power_bands_overlap`]; module docs).
fn beside_a_lost_pole(diagram: &[Complex64], lost: &[bool]) -> Vec<bool> {
    (0..diagram.len())
        .map(|r| {
            (0..diagram.len())
                .any(|j| lost[j] && (j == r || half_power_bands_overlap(diagram[r], diagram[j])))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Only the lost pole and the poles whose half-power bands overlap its own are marked.
    #[test]
    fn poles_beside_a_lost_pole_are_marked() {
        let pole = |f: f64| Complex64::new(-0.08 * 2.0 * PI * f, 2.0 * PI * f);
        let diagram = [pole(25.6), pole(102.5), pole(105.6), pole(152.5)];
        let lost = [false, false, true, false];
        assert_eq!(
            beside_a_lost_pole(&diagram, &lost),
            vec![false, true, true, false]
        );
        assert_eq!(beside_a_lost_pole(&diagram, &[false; 4]), vec![false; 4]);
    }

    /// A refined pole inside its column comes back as it is (to rounding); one that ran away
    /// comes back on its column's edge, with the frequency and damping that `pole_of` was
    /// given.
    #[test]
    fn refined_poles_are_clamped_into_their_columns() {
        let c = StabilityCriteria::default();
        let col = |f: f64, z: f64| SelectedPole {
            pole: pole_of(f, z),
            freq_hz: f,
            damping: z,
            count: 10,
            spread_hz: 0.1,
            freq_range_hz: [f - 0.05, f + 0.05],
            damping_range: [z - 0.001, z + 0.001],
            pick: crate::stabilization::Pick::Auto,
        };
        let selected = [col(25.6, 0.15), col(75.0, 0.011)];
        let inside = pole_of(25.7, 0.16);
        let runaway = pole_of(1.1e8, 0.0);
        let out = clamped_to_their_columns(&[inside, runaway], &selected, &c);
        assert!(
            (out[0] - inside).norm() < 1e-9 * inside.norm(),
            "{:?}",
            out[0]
        );
        let (f, z) = (pole_freq_hz(out[1]), pole_damping(out[1]));
        assert!(
            (f - 75.80).abs() < 1e-9 && (z - 0.0045).abs() < 1e-12,
            "{f} {z}"
        );
        assert!((pole_freq_hz(pole_of(40.0, 0.2)) - 40.0).abs() < 1e-12);
        assert!((pole_damping(pole_of(40.0, 0.2)) - 0.2).abs() < 1e-12);
    }
}
