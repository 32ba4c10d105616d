//! Stabilization diagram and automatic selection of physical poles.
//!
//! **Classification.** A pole at order n is compared with the nearest pole (in frequency) of
//! the previous order: *stable in frequency* if |Δf|/f ≤ `freq_tol` (default 1 %), *stable in
//! damping* as well if |Δζ|/ζ ≤ `damping_tol` (default 5 %) (the criteria of sdypy-EMA), and
//! *stable in vector* as well if the two poles' mode vectors (from the LSCF numerators) have
//! 1 − MAC ≤ `vector_tol` (default 2 %, the usual commercial default). A pole counts as
//! *stable* when it passes every criterion the diagram has data for (the vector one only when
//! mode vectors were computed).
//!
//! **Automatic selection.** Stable poles are clustered across orders into columns by frequency
//! (a pole joins the nearest column whose median frequency is within `freq_tol`), a column
//! holding at most one pole per order: two stable poles of one order are two modes however
//! close (a pair 0.14 % apart with different shapes comes out as two; before, every pole within
//! `freq_tol` of a column joined it and the pair was one mode). A column holding stable poles at
//! no fewer than `min_fraction` of the orders above its first appearance is a physical mode,
//! represented by its pole at the median frequency (spurious poles of over-modelled noise
//! wander and do not build long columns).
//!
//! **Peaks of the CMIF.** A peak of the first CMIF that no selected pole explains, or of the
//! second that fewer than two explain (a close pair that several references see), is a mode
//! the criteria missed where the diagram holds it, stable in frequency but not in damping or
//! vector (measured data): the columns of frequency-stable poles near it that pass the same
//! order rule are added ([`rescue_cmif_peaks`]).
//!
//! **Selection near given frequencies.** For each given frequency, the stable pole nearest to
//! it at the highest order where one exists within `window_hz`.

use crate::lscf::{OrderPoles, pole_damping, pole_freq_hz};
use crate::shapes::mac;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// Stability of a pole in the diagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Stability {
    /// No matching pole at the previous order.
    New,
    /// Frequency within tolerance.
    Frequency,
    /// Frequency and damping within tolerance.
    FrequencyDamping,
    /// Frequency, damping and mode vector within tolerance.
    FrequencyDampingVector,
}

/// A pole in the diagram.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DiagramPole {
    /// Model order.
    pub order: usize,
    /// Pole λ, rad/s.
    pub pole: Complex64,
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Damping ratio.
    pub damping: f64,
    /// Stability against the previous order.
    pub stability: Stability,
    /// MAC of its mode vector with the matched pole's of the previous order (when both have
    /// mode vectors).
    pub vector_mac: Option<f64>,
}

impl DiagramPole {
    /// Passes every criterion the diagram has data for (module docs).
    pub fn is_stable(&self) -> bool {
        match self.stability {
            Stability::FrequencyDampingVector => true,
            Stability::FrequencyDamping => self.vector_mac.is_none(),
            _ => false,
        }
    }
}

/// Tolerances of the diagram and of the selection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilityCriteria {
    /// Relative frequency tolerance.
    pub freq_tol: f64,
    /// Relative damping tolerance.
    pub damping_tol: f64,
    /// Mode-vector tolerance on 1 − MAC.
    pub vector_tol: f64,
    /// Fraction of the orders above a cluster's first one that must hold a stable pole.
    pub min_fraction: f64,
}

impl Default for StabilityCriteria {
    fn default() -> Self {
        Self {
            freq_tol: 0.01,
            damping_tol: 0.05,
            vector_tol: 0.02,
            min_fraction: 0.5,
        }
    }
}

/// The poles of the diagram's highest order that are stable in frequency and damping (rad/s).
pub(crate) fn top_order_stable(diagram: &[DiagramPole]) -> Vec<Complex64> {
    let top = diagram.iter().map(|p| p.order).max().unwrap_or(0);
    diagram
        .iter()
        .filter(|p| p.order == top)
        .filter(|p| {
            matches!(
                p.stability,
                Stability::FrequencyDamping | Stability::FrequencyDampingVector
            )
        })
        .map(|p| p.pole)
        .collect()
}

/// Classifies every pole of `orders` (increasing order).
pub fn diagram(orders: &[OrderPoles], c: &StabilityCriteria) -> Vec<DiagramPole> {
    let mut out = Vec::new();
    let mut previous: Option<&OrderPoles> = None;
    for op in orders {
        for (r, &p) in op.poles.iter().enumerate() {
            let (f, z) = (pole_freq_hz(p), pole_damping(p));
            let near = previous.and_then(|prev| {
                (0..prev.poles.len()).min_by(|&a, &b| {
                    (pole_freq_hz(prev.poles[a]) - f)
                        .abs()
                        .total_cmp(&(pole_freq_hz(prev.poles[b]) - f).abs())
                })
            });
            let (mut stability, mut vector_mac) = (Stability::New, None);
            if let (Some(prev), Some(q)) = (previous, near) {
                let qp = prev.poles[q];
                if (pole_freq_hz(qp) - f).abs() <= c.freq_tol * f {
                    stability = Stability::Frequency;
                    if (pole_damping(qp) - z).abs() <= c.damping_tol * z.abs() {
                        stability = Stability::FrequencyDamping;
                        vector_mac = match (op.vectors.get(r), prev.vectors.get(q)) {
                            (Some(a), Some(b)) => Some(mac(a, b)),
                            _ => None,
                        };
                        if vector_mac.is_some_and(|m| 1.0 - m <= c.vector_tol) {
                            stability = Stability::FrequencyDampingVector;
                        }
                    }
                }
            }
            out.push(DiagramPole {
                order: op.order,
                pole: p,
                freq_hz: f,
                damping: z,
                stability,
                vector_mac,
            });
        }
        previous = Some(op);
    }
    out
}

/// How a pole was selected, and so what its stable count counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Pick {
    /// The automatic selection: a column of poles stable in frequency, damping and vector
    /// (each criterion the diagram has data for).
    #[default]
    Auto,
    /// A CMIF peak that the stable columns leave unexplained, taken from a column of poles
    /// stable in frequency ([`rescue_cmif_peaks`]).
    CmifPeak,
    /// Near a frequency given by the user: the poles stable in frequency within the window.
    Near,
}

impl Pick {
    /// What the stable count of a pole picked this way counts, for a table's footnote.
    pub fn counts(self) -> &'static str {
        match self {
            Self::Auto => "poles stable in frequency, damping and mode vector in its column",
            Self::CmifPeak => "poles stable in frequency in its column (picked at a CMIF peak)",
            Self::Near => "poles stable in frequency within the window",
        }
    }
}

/// A selected physical mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SelectedPole {
    /// Pole λ, rad/s.
    pub pole: Complex64,
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Damping ratio.
    pub damping: f64,
    /// Stable poles in its cluster.
    pub count: usize,
    /// Spread of the cluster's frequencies (max − min), Hz.
    pub spread_hz: f64,
    /// Lowest and highest frequency of the cluster's poles, Hz.
    pub freq_range_hz: [f64; 2],
    /// Lowest and highest damping ratio of the cluster's poles.
    pub damping_range: [f64; 2],
    /// How it was selected (what `count` counts).
    #[serde(default)]
    pub pick: Pick,
}

impl SelectedPole {
    /// Whether a pole (Hz, damping ratio) lies in this pole's column: inside its frequency
    /// range widened by its spread or the stability tolerance `c.freq_tol` (whichever is
    /// larger), and inside its damping range widened by its spread or half its median damping.
    /// The damping allowance is wide because removing the linearised LSCF's damping bias (tens
    /// of per cent on a close pair) is what the refinement is for; a refined pole outside this
    /// has run away (noise, a neighbouring mode) and is not to be kept.
    pub fn holds(&self, freq_hz: f64, damping: f64, c: &StabilityCriteria) -> bool {
        let [freq, damp] = self.bounds(c);
        (freq[0]..=freq[1]).contains(&freq_hz) && (damp[0]..=damp[1]).contains(&damping)
    }

    /// The point of this pole's column ([`Self::holds`]) nearest (Hz, damping ratio): each of
    /// the two clamped into the column's widened range; a point the column holds is returned
    /// as it is.
    pub fn clamp(&self, freq_hz: f64, damping: f64, c: &StabilityCriteria) -> (f64, f64) {
        let [freq, damp] = self.bounds(c);
        // max then min rather than `f64::clamp`, which panics on bounds out of order.
        (
            freq_hz.max(freq[0]).min(freq[1]),
            damping.max(damp[0]).min(damp[1]),
        )
    }

    /// The point a refined pole (Hz, damping ratio) that was not taken widens this pole's
    /// standard deviation to: the refined pole itself where its frequency lies in the column's
    /// widened frequency range ([`Self::holds`]), whatever its damping; else the column's
    /// nearest point ([`Self::clamp`]). A refined pole at the column's frequency is another
    /// estimate of the same resonance: where the noise is high the linearised LSCF's damping,
    /// the column's with it, can be biased far beyond the column's damping allowance, and the
    /// truth may lie by either estimate. A refined pole beyond the column's frequency has moved
    /// to another resonance or out of the band, and widens the deviation only to the edge.
    pub fn widening_point(&self, freq_hz: f64, damping: f64, c: &StabilityCriteria) -> (f64, f64) {
        if self.reaches_frequency(freq_hz, c) {
            (freq_hz, damping)
        } else {
            self.clamp(freq_hz, damping, c)
        }
    }

    /// Whether `freq_hz` lies in the column's widened frequency range ([`Self::holds`]).
    pub fn reaches_frequency(&self, freq_hz: f64, c: &StabilityCriteria) -> bool {
        let [freq, _] = self.bounds(c);
        (freq[0]..=freq[1]).contains(&freq_hz)
    }

    /// The column's widened ranges of frequency (Hz) and damping ratio ([`Self::holds`]).
    fn bounds(&self, c: &StabilityCriteria) -> [[f64; 2]; 2] {
        let [f0, f1] = self.freq_range_hz;
        let [d0, d1] = self.damping_range;
        let wf = (f1 - f0).max(c.freq_tol * self.freq_hz);
        let wd = (d1 - d0).max(0.5 * self.damping);
        [[f0 - wf, f1 + wf], [d0 - wd, d1 + wd]]
    }
}

/// (min, max) of `key` over `poles`.
fn range_of<'a>(
    poles: impl Iterator<Item = &'a DiagramPole>,
    key: fn(&DiagramPole) -> f64,
) -> [f64; 2] {
    poles.fold([f64::INFINITY, f64::NEG_INFINITY], |[a, b], p| {
        [a.min(key(p)), b.max(key(p))]
    })
}

fn median_by<T: Copy>(v: &mut [T], key: impl Fn(&T) -> f64) -> T {
    v.sort_by(|a, b| key(a).total_cmp(&key(b)));
    v[v.len() / 2]
}

/// Automatic selection (module docs).
pub fn select_auto(diagram: &[DiagramPole], c: &StabilityCriteria) -> Vec<SelectedPole> {
    let mut out = physical_columns(diagram, c, DiagramPole::is_stable, Pick::Auto);
    out.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    out
}

/// The columns of the poles that pass `admit` (module docs: one pole per order, the nearest
/// column by median frequency within `freq_tol`) that hold such poles at no fewer than
/// `min_fraction` of the orders above their first and at three orders at least, each as its
/// pole at the median frequency.
fn physical_columns(
    diagram: &[DiagramPole],
    c: &StabilityCriteria,
    admit: impl Fn(&DiagramPole) -> bool,
    pick: Pick,
) -> Vec<SelectedPole> {
    let orders: Vec<usize> = {
        let mut o: Vec<usize> = diagram.iter().map(|p| p.order).collect();
        o.dedup();
        o
    };
    let mut clusters: Vec<Vec<DiagramPole>> = Vec::new();
    for p in diagram.iter().filter(|p| admit(p)) {
        let median = |cl: &Vec<DiagramPole>| {
            let mut f: Vec<f64> = cl.iter().map(|q| q.freq_hz).collect();
            f.sort_by(f64::total_cmp);
            f[f.len() / 2]
        };
        let hit = clusters
            .iter_mut()
            .filter(|cl| {
                (median(cl) - p.freq_hz).abs() <= c.freq_tol * p.freq_hz
                    && cl.iter().all(|q| q.order != p.order)
            })
            .min_by(|a, b| {
                (median(a) - p.freq_hz)
                    .abs()
                    .total_cmp(&(median(b) - p.freq_hz).abs())
            });
        match hit {
            Some(cl) => cl.push(*p),
            None => clusters.push(vec![*p]),
        }
    }
    clusters
        .into_iter()
        .filter_map(|mut cl| {
            let first = cl.iter().map(|p| p.order).min()?;
            let available = orders.iter().filter(|o| **o >= first).count().max(1);
            let mut distinct: Vec<usize> = cl.iter().map(|p| p.order).collect();
            distinct.sort_unstable();
            distinct.dedup();
            if (distinct.len() as f64) < c.min_fraction * available as f64 || distinct.len() < 3 {
                return None;
            }
            let freq_range_hz = range_of(cl.iter(), |p| p.freq_hz);
            let damping_range = range_of(cl.iter(), |p| p.damping);
            let count = cl.len();
            let m = median_by(&mut cl, |p| p.freq_hz);
            Some(SelectedPole {
                pole: m.pole,
                freq_hz: m.freq_hz,
                damping: m.damping,
                count,
                spread_hz: freq_range_hz[1] - freq_range_hz[0],
                freq_range_hz,
                damping_range,
                pick,
            })
        })
        .collect()
}

/// Whether the column `col` found at a peak of CMIF curve `curve` is the selected pole `p`:
/// for the first curve, within the frequency tolerance of it; for a later curve, which stands
/// for modes closer than that tolerance, `p` inside the column's frequency range.
fn same_mode(p: &SelectedPole, col: &SelectedPole, curve: usize, c: &StabilityCriteria) -> bool {
    if curve <= 1 {
        (p.freq_hz - col.freq_hz).abs() <= c.freq_tol * col.freq_hz
    } else {
        (col.freq_range_hz[0]..=col.freq_range_hz[1]).contains(&p.freq_hz)
    }
}

/// The peaks of one singular value curve of the CMIF.
#[derive(Debug, Clone, Copy)]
pub struct CmifCurvePeaks<'a> {
    /// Which singular value: 1 for the first (largest), 2 for the second.
    pub curve: usize,
    /// The peaks' frequencies, Hz.
    pub freqs_hz: &'a [f64],
}

/// Whether a pole at `freq_hz` with damping ratio `damping` explains a CMIF peak at
/// `peak_hz`: within twice the frequency tolerance or three half-power half-widths (ζ f) of it.
pub fn explains(freq_hz: f64, damping: f64, peak_hz: f64, c: &StabilityCriteria) -> bool {
    (freq_hz - peak_hz).abs() <= (2.0 * c.freq_tol).max(3.0 * damping) * freq_hz
}

/// Adds to `selected` the modes behind the peaks of the CMIF's `curve`-th singular value
/// (1: the first) that it leaves unexplained. The k-th singular value of the FRF matrix peaks
/// where k modes respond together, so a peak of curve k is unexplained while fewer than k
/// selected poles explain it (within twice the frequency tolerance or three half-power
/// half-widths ζf of the peak): a close pair that several references see shows as a peak of
/// the second curve beside the first's. For each such peak, within `reach` (relative, each
/// side) the columns of poles stable in frequency alone that pass the selection's order rule
/// (module docs) are added, each unless a selected pole already lies within the frequency
/// tolerance of it. Where measured data move the damping from order to order by more than its
/// tolerance, a mode has a long column stable in frequency and too few fully stable poles to
/// be selected: on the measured dam (26 channels, one reference) the strongest CMIF peak, a
/// pair at 4.08 / 4.17 Hz, had 3 and 5 fully stable poles over 20 orders and was dropped.
/// Returns the poles added, by increasing frequency (`selected` sorted likewise).
pub fn rescue_cmif_peaks(
    diagram: &[DiagramPole],
    selected: &mut Vec<SelectedPole>,
    peaks: CmifCurvePeaks<'_>,
    c: &StabilityCriteria,
    reach: f64,
) -> Vec<SelectedPole> {
    let mut added = Vec::new();
    for &peak in peaks.freqs_hz {
        let explaining = selected
            .iter()
            .filter(|p| explains(p.freq_hz, p.damping, peak, c))
            .count();
        if explaining >= peaks.curve {
            continue;
        }
        let near = |p: &DiagramPole| {
            p.stability != Stability::New && (p.freq_hz - peak).abs() <= reach * peak
        };
        for col in physical_columns(diagram, c, near, Pick::CmifPeak) {
            let taken = selected.iter().any(|p| same_mode(p, &col, peaks.curve, c));
            if !taken {
                selected.push(col);
                added.push(col);
            }
        }
    }
    selected.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    added.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    added
}

/// Selection near given frequencies (module docs); `None` where no stable pole lies within
/// `window_hz`. A pick's `count` is the stable poles within the window over all orders (its
/// column), as an automatic pick's is its cluster's.
pub fn select_near(
    diagram: &[DiagramPole],
    targets_hz: &[f64],
    window_hz: f64,
) -> Vec<Option<SelectedPole>> {
    targets_hz
        .iter()
        .map(|&t| {
            let stable = diagram
                .iter()
                .filter(|p| p.stability != Stability::New && (p.freq_hz - t).abs() <= window_hz);
            // Its column: the stable poles within the window at every order.
            let column: Vec<&DiagramPole> = stable.collect();
            let top = column.iter().map(|p| p.order).max()?;
            let p = column
                .iter()
                .filter(|p| p.order == top)
                .min_by(|a, b| (a.freq_hz - t).abs().total_cmp(&(b.freq_hz - t).abs()))?;
            Some(SelectedPole {
                pole: p.pole,
                freq_hz: p.freq_hz,
                damping: p.damping,
                count: column.len(),
                spread_hz: 0.0,
                freq_range_hz: range_of(column.iter().copied(), |p| p.freq_hz),
                damping_range: range_of(column.iter().copied(), |p| p.damping),
                pick: Pick::Near,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column(f: [f64; 2], z: [f64; 2]) -> SelectedPole {
        let (fm, zm) = (0.5 * (f[0] + f[1]), 0.5 * (z[0] + z[1]));
        SelectedPole {
            pole: Complex64::new(0.0, 0.0),
            freq_hz: fm,
            damping: zm,
            count: 10,
            spread_hz: f[1] - f[0],
            freq_range_hz: f,
            damping_range: z,
            pick: Pick::Auto,
        }
    }

    /// A diagram at orders 10, 12, …, 40 holding a column at each (f Hz, ζ, fully stable)
    /// of `columns`, its frequency moved by ±1e-4 from order to order.
    fn diagram_of(columns: &[(f64, f64, bool)]) -> Vec<DiagramPole> {
        (10..=40)
            .step_by(2)
            .flat_map(|order| {
                columns.iter().map(move |&(f, z, stable)| {
                    let f = f * (1.0 + 1e-4 * if order % 4 == 0 { 1.0 } else { -1.0 });
                    DiagramPole {
                        order,
                        pole: Complex64::new(0.0, 2.0 * std::f64::consts::PI * f),
                        freq_hz: f,
                        damping: z,
                        stability: if order == 10 {
                            Stability::New
                        } else if stable {
                            Stability::FrequencyDamping
                        } else {
                            Stability::Frequency
                        },
                        vector_mac: None,
                    }
                })
            })
            .collect()
    }

    /// A pair 0.5 % apart (ζ 2 %) whose upper pole is stable in frequency only: the automatic
    /// selection takes the lower; the first curve's peak at 40.05 Hz is explained by it, so
    /// only the second curve's peak at 40.25 Hz brings back the upper pole. A second-curve
    /// peak between modes far apart (a crossing of their curves) adds nothing.
    #[test]
    fn a_peak_of_the_second_cmif_curve_brings_back_a_close_pair() {
        let c = StabilityCriteria::default();
        let diag = diagram_of(&[(40.0, 0.02, true), (40.2, 0.024, false), (60.0, 0.02, true)]);
        let first = [40.05, 60.0];
        let mut selected = select_auto(&diag, &c);
        assert_eq!(selected.len(), 2);
        let peaks = |curve, freqs_hz| CmifCurvePeaks { curve, freqs_hz };
        assert!(rescue_cmif_peaks(&diag, &mut selected, peaks(1, &first), &c, 0.03).is_empty());
        assert!(rescue_cmif_peaks(&diag, &mut selected, peaks(2, &[50.0]), &c, 0.03).is_empty());
        let added = rescue_cmif_peaks(&diag, &mut selected, peaks(2, &[40.25]), &c, 0.03);
        assert_eq!(added.len(), 1, "{added:?}");
        assert!((added[0].freq_hz - 40.2).abs() < 0.01 && added[0].pick == Pick::CmifPeak);
        let found: Vec<f64> = selected.iter().map(|p| p.freq_hz).collect();
        assert_eq!(found.len(), 3, "{found:?}");
        // Both explain the peak now: nothing more is added.
        assert!(rescue_cmif_peaks(&diag, &mut selected, peaks(2, &[40.25]), &c, 0.03).is_empty());
    }

    #[test]
    fn a_runaway_refinement_leaves_its_column() {
        let c = StabilityCriteria::default();
        // The cases: 75.0 Hz refined to 135.7 Hz at zeta 73 %; a pick at 66.5 Hz to
        // 100.8 Hz at 72 %.
        let col = column([74.95, 75.05], [0.010, 0.012]);
        assert!(!col.holds(135.7, 0.73, &c));
        assert!(!column([66.4, 66.6], [0.01, 0.02]).holds(100.8, 0.72, &c));
        // A refined pole a little outside a tight column, by less than the frequency tolerance
        // (1 %) or half the damping (the LSCF's damping bias), stays.
        assert!(col.holds(75.5, 0.0115, &c));
        assert!(col.holds(75.0, 0.016, &c));
        // Beyond the allowance or the column's own spread, whichever is larger: out.
        assert!(!col.holds(76.0, 0.011, &c));
        assert!(!col.holds(75.0, 0.018, &c));
        // A column with a wide damping scatter allows as much again.
        let wide = column([74.9, 75.1], [0.01, 0.03]);
        assert!(wide.holds(75.0, 0.045, &c) && !wide.holds(75.0, 0.06, &c));
    }

    /// The clamp returns a point its column holds unchanged, moves one outside onto the edge
    /// of the widened ranges (each quantity alone), and the point it returns is held.
    #[test]
    fn a_runaway_pole_is_clamped_onto_its_columns_edge() {
        let c = StabilityCriteria::default();
        let col = column([74.95, 75.05], [0.010, 0.012]);
        assert_eq!(col.clamp(75.5, 0.0115, &c), (75.5, 0.0115));
        // Frequency allowance 1 % of 75 Hz = 0.75 Hz beyond 75.05; damping half of 0.011.
        let (f, z) = col.clamp(135.7, 0.73, &c);
        assert!(
            (f - 75.8).abs() < 1e-12 && (z - 0.0175).abs() < 1e-12,
            "{f} {z}"
        );
        assert!(col.holds(f, z, &c));
        let (f, z) = col.clamp(1.1e8, 0.0111, &c);
        assert!((f - 75.8).abs() < 1e-12 && z == 0.0111, "{f} {z}");
        let (f, z) = col.clamp(10.0, 0.0, &c);
        assert!(
            (f - 74.2).abs() < 1e-12 && (z - 0.0045).abs() < 1e-12,
            "{f} {z}"
        );
        // A column without poles (empty ranges) has bounds out of order: the clamp does not
        // panic (`f64::clamp` would), and what it returns is not held either.
        let empty = column([f64::INFINITY, f64::NEG_INFINITY], [0.01, 0.01]);
        let (f, z) = empty.clamp(75.0, 0.01, &c);
        assert!(!empty.holds(f, z, &c) && !empty.holds(75.0, 0.01, &c));
    }

    /// A refined pole at the column's frequency widens the deviation to itself, damping far
    /// outside the column's allowance included (the LSCF's damping biased low by noise); one
    /// beyond the column's frequency only to the column's edge, in damping too.
    #[test]
    fn a_refined_pole_at_the_columns_frequency_widens_the_deviation_to_itself() {
        let c = StabilityCriteria::default();
        let col = column([74.95, 75.05], [0.010, 0.012]);
        // Damping 8 % against a column of 1.0-1.2 %: not held, but at the column's frequency.
        assert!(!col.holds(75.3, 0.08, &c));
        assert_eq!(col.widening_point(75.3, 0.08, &c), (75.3, 0.08));
        // Beyond the column's widened frequency range (74.2-75.8 Hz): clamped as a runaway.
        assert_eq!(col.widening_point(77.2, 0.08, &c), (75.8, 0.0175));
        assert_eq!(col.widening_point(1.1e8, 0.0111, &c), (75.8, 0.0111));
    }
}
