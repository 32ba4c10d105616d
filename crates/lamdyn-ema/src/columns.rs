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

/// Why the diagram's pole was put back in place of a refined pole ([`in_their_columns`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PutBack {
    /// The refined pole left its column in the diagram.
    LeftItsColumn,
    /// Its diagram pole's half-power band overlaps that of a pole that left its column.
    BesideALostPole,
}

/// The refined poles held to their columns ([`in_their_columns`]), index-aligned with the
/// selection.
pub(crate) struct HeldPoles {
    /// The refined pole, or the diagram's where it was put back.
    pub poles: Vec<Complex64>,
    /// Why each pole was put back; None where the refined pole stays.
    pub put_back: Vec<Option<PutBack>>,
    /// One line per pole that left its column.
    pub warnings: Vec<String>,
}

/// The refined poles `refined` (index-aligned with `selected`) with each that left its column in
/// the diagram ([`SelectedPole::holds`]) replaced by the diagram's pole, and so each whose
/// diagram pole's half-power band overlaps that of a pole that left (it was fitted beside a pole
/// standing elsewhere and may have taken over that pole's mode: [`beside_a_lost_pole`]); with
/// one warning per pole that left.
pub(crate) fn in_their_columns(
    refined: &[Complex64],
    selected: &[SelectedPole],
    c: &StabilityCriteria,
) -> HeldPoles {
    let left = left_their_columns(refined, selected, c);
    let diagram: Vec<Complex64> = selected.iter().map(|p| p.pole).collect();
    let put_back: Vec<Option<PutBack>> = beside_a_lost_pole(&diagram, &left)
        .into_iter()
        .zip(&left)
        .map(|(beside, &gone)| match (gone, beside) {
            (true, _) => Some(PutBack::LeftItsColumn),
            (false, true) => Some(PutBack::BesideALostPole),
            (false, false) => None,
        })
        .collect();
    let poles = (0..refined.len())
        .map(|r| match put_back[r] {
            Some(_) => diagram[r],
            None => refined[r],
        })
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
    HeldPoles {
        poles,
        put_back,
        warnings,
    }
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

/// The order of a joint fit's poles `fitted` (the selection's, index-aligned with `selected`,
/// then modes held beside them) in which each selected pole that left its column is exchanged
/// for a held mode that lies in it (the one nearest the diagram's pole, if several). The fit's
/// modes are a set: which of two it calls the selected one follows their starts, and a mode
/// held from a start beside a selected pole may end in that pole's column while the selected
/// one ends elsewhere (in another mode of the pair).
pub(crate) fn exchanged_into_columns(
    fitted: &[Complex64],
    selected: &[SelectedPole],
    c: &StabilityCriteria,
) -> Vec<usize> {
    let mut order: Vec<usize> = (0..fitted.len()).collect();
    let n = selected.len();
    for (r, col) in selected.iter().enumerate() {
        let holds = |k: usize| col.holds(pole_freq_hz(fitted[k]), pole_damping(fitted[k]), c);
        if holds(order[r]) {
            continue;
        }
        let nearest = (n..fitted.len())
            .filter(|&j| holds(order[j]))
            .min_by(|&a, &b| {
                let d = |j: usize| (fitted[order[j]] - col.pole).norm();
                d(a).total_cmp(&d(b))
            });
        if let Some(j) = nearest {
            order.swap(r, j);
        }
    }
    order
}

/// For each refined pole (index-aligned with `selected`), whether it left its column in the
/// diagram ([`SelectedPole::holds`]).
pub(crate) fn left_their_columns(
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
    use crate::stabilization::Pick;
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

    /// A selected pole that left its column trades places with the held mode in it, the
    /// nearest of two; one that stayed, and a lost one with no held mode in its column, keep
    /// their places.
    #[test]
    fn a_held_mode_in_a_lost_poles_column_takes_its_place() {
        let pole = |f: f64, z: f64| Complex64::new(-z * 2.0 * PI * f, 2.0 * PI * f);
        let column = |f: f64, z: f64| SelectedPole {
            pole: pole(f, z),
            freq_hz: f,
            damping: z,
            count: 10,
            spread_hz: 0.0,
            freq_range_hz: [f - 0.2, f + 0.2],
            damping_range: [0.9 * z, 1.1 * z],
            pick: Pick::default(),
        };
        let selected = [
            column(100.0, 0.05),
            column(180.0, 0.05),
            column(140.0, 0.05),
        ];
        let c = StabilityCriteria::default();
        let fitted = [
            pole(100.1, 0.05),
            pole(170.0, 0.10), // left its column, towards a neighbour
            pole(150.0, 0.05), // left too; no held mode in its column
            pole(180.3, 0.052),
            pole(179.95, 0.05),
            pole(60.0, 0.02),
        ];
        assert_eq!(
            exchanged_into_columns(&fitted, &selected, &c),
            vec![0, 4, 2, 3, 1, 5]
        );
    }
}
