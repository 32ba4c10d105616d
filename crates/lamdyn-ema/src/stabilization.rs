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
//! **Automatic selection.** Stable poles are clustered across orders
//! by frequency (a pole joins the cluster whose median frequency is within `freq_tol`); a
//! cluster holding stable poles at no fewer than `min_fraction` of the orders above its first
//! appearance is a physical mode, represented by its pole at the median frequency (spurious
//! poles of over-modelled noise wander and do not build long columns). Clusters closer than
//! `freq_tol` merge, so two modes must be further apart than that to be told apart.
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
}

fn median_by<T: Copy>(v: &mut [T], key: impl Fn(&T) -> f64) -> T {
    v.sort_by(|a, b| key(a).total_cmp(&key(b)));
    v[v.len() / 2]
}

/// Automatic selection (module docs).
pub fn select_auto(diagram: &[DiagramPole], c: &StabilityCriteria) -> Vec<SelectedPole> {
    let orders: Vec<usize> = {
        let mut o: Vec<usize> = diagram.iter().map(|p| p.order).collect();
        o.dedup();
        o
    };
    let mut clusters: Vec<Vec<DiagramPole>> = Vec::new();
    for p in diagram.iter().filter(|p| p.is_stable()) {
        let hit = clusters.iter_mut().find(|cl| {
            let mut f: Vec<f64> = cl.iter().map(|q| q.freq_hz).collect();
            f.sort_by(f64::total_cmp);
            (f[f.len() / 2] - p.freq_hz).abs() <= c.freq_tol * p.freq_hz
        });
        match hit {
            Some(cl) => cl.push(*p),
            None => clusters.push(vec![*p]),
        }
    }
    let mut out: Vec<SelectedPole> = clusters
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
            let fmin = cl.iter().map(|p| p.freq_hz).fold(f64::INFINITY, f64::min);
            let fmax = cl.iter().map(|p| p.freq_hz).fold(0.0, f64::max);
            let count = cl.len();
            let m = median_by(&mut cl, |p| p.freq_hz);
            Some(SelectedPole {
                pole: m.pole,
                freq_hz: m.freq_hz,
                damping: m.damping,
                count,
                spread_hz: fmax - fmin,
            })
        })
        .collect();
    out.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    out
}

/// Selection near given frequencies (module docs); `None` where no stable pole lies within
/// `window_hz`.
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
            let top = stable.clone().map(|p| p.order).max()?;
            let p = stable
                .filter(|p| p.order == top)
                .min_by(|a, b| (a.freq_hz - t).abs().total_cmp(&(b.freq_hz - t).abs()))?;
            Some(SelectedPole {
                pole: p.pole,
                freq_hz: p.freq_hz,
                damping: p.damping,
                count: 1,
                spread_hz: 0.0,
            })
        })
        .collect()
}
