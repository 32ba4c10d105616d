//! What the identification's noise and settings do to one mode's pole ([`pole_scatter`]):
//! the scatter of its stable poles over the stabilization diagram, the spread of the response
//! groups' and the other model orders' identifications, and the delete-one-hit jackknife. The
//! band's sources `EmaPole` and `HitsLeftOut` ([`crate::band::BandSource`]) are made of them.

use crate::chain::nearest_within;
use crate::stats::sample_sd;
use lamdyn_ema::identify::EmaResult;

/// The identifications beside the whole that a pole's scatter is read from (`pole_scatter`).
#[derive(Debug, Clone, Default)]
pub struct PoleChecks {
    /// The identification on each group of responses (stage "ema by response group").
    pub groups: Vec<EmaResult>,
    /// The identification at other highest model orders (stage "ema at other model orders").
    pub orders: Vec<EmaResult>,
    /// The identification without each hammer hit in turn (stage "ema without each hit"):
    /// empty, or one per hit.
    pub hits: Vec<EmaResult>,
}

/// What the identification's noise does to one mode's pole ([`pole_scatter`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PoleScatter {
    /// Standard deviations (Hz, damping ratio) from the stabilization diagram, the response
    /// groups and the model orders; `None` when nothing measured them.
    pub noise: Option<[f64; 2]>,
    /// The delete-one-hit jackknife's standard deviations (Hz, damping ratio)
    /// ([`hit_jackknife`]); `None` without enough hits.
    pub hits: Option<[f64; 2]>,
}

/// The scatter of the pole of the EMA mode nearest `f` ([`PoleScatter`]): as `noise`, the
/// largest, per part, of three estimates of the noise's effect: the scatter of its stable
/// poles in the stabilization diagram ([`stabilization_scatter`]), the spread of the poles the
/// response groups' own identifications find for it ([`group_spread`]) and the pole's own
/// standard deviations from the identification's covariance (`Mode::sd`,
/// [`lamdyn_ema::lsfd::pole_deviations`], widened where the estimator kept the diagram's
/// pole); with it in quadrature the spread across model orders ([`order_spread`]), the
/// method's; as `hits`, the delete-one-hit jackknife ([`hit_jackknife`]).
pub fn pole_scatter(ema: &EmaResult, checks: &PoleChecks, f: f64) -> PoleScatter {
    let Some(mode) = nearest_within(ema, f, 0.02) else {
        return PoleScatter::default();
    };
    let m = &ema.modes[mode];
    let own = m.sd.map(|sd| [sd.freq_hz, sd.damping_ratio]);
    let noise = [
        stabilization_scatter(ema, mode),
        group_spread(&same_pole(ema, mode, &checks.groups)),
        own.filter(|sd| sd.iter().all(|x| x.is_finite())),
    ]
    .into_iter()
    .flatten()
    .reduce(|a, b| [a[0].max(b[0]), a[1].max(b[1])]);
    let orders = order_spread(
        [m.freq_hz, m.damping_ratio],
        &same_pole(ema, mode, &checks.orders),
    );
    let noise = match (noise, orders) {
        (Some(a), Some(b)) => Some([a[0].hypot(b[0]), a[1].hypot(b[1])]),
        (a, b) => a.or(b),
    };
    PoleScatter {
        noise,
        hits: hit_jackknife(&same_pole(ema, mode, &checks.hits)),
    }
}

/// The delete-one jackknife's standard deviation (Hz, damping ratio) of a pole from its
/// estimates `found` without each hit in turn, n ≥ [`crate::measurement::JACKKNIFE_HITS`] of
/// them: √((n − 1)/n Σ (θ_i − θ̄)²) [Efron & Tibshirani 1993, eq. 11.5]. A hit missing from
/// n − 1 averages at a time moves the pole by 1/(n − 1) of what it does to the mean, hence the
/// factor n − 1 over the sample variance. It measures what the hits' noise does to the pole,
/// the identification's bias from it included, where the stabilization diagram and the
/// response groups read the same noisy FRFs and agree with each other: on the damped-sandwich
/// example's hammer data (seed 1, five hits) the first mode's damping ratio came out 2.473,
/// 2.475, 2.480, 2.525 and 2.474 % without each hit, 2.527 % from all five and 2.475 % from
/// noise-free hits; its jackknife sd is 0.040 %, the response groups' 0.01 %.
pub(super) fn hit_jackknife(found: &[[f64; 2]]) -> Option<[f64; 2]> {
    if found.len() < crate::measurement::JACKKNIFE_HITS {
        return None;
    }
    let n = found.len() as f64;
    Some(sample_sd(found).map(|sd| sd * (n - 1.0) / n.sqrt()))
}

/// Each other identification's pole (Hz, damping ratio) of EMA mode `mode`: its pole nearest
/// the mode, within 1 % and nearer it than any other mode of the whole.
fn same_pole(ema: &EmaResult, mode: usize, others: &[EmaResult]) -> Vec<[f64; 2]> {
    let m = &ema.modes[mode];
    others
        .iter()
        .filter_map(|g| {
            let k = nearest_within(g, m.freq_hz, 0.01)?;
            let p = &g.modes[k];
            (nearest_within(ema, p.freq_hz, 0.02) == Some(mode))
                .then_some([p.freq_hz, p.damping_ratio])
        })
        .collect()
}

/// How much a pole (Hz, damping ratio) depends on the highest model order of the
/// identification: the sample standard deviation of the whole's estimate `main` and those
/// `found` at the other orders ([`crate::config::OTHER_ORDERS`]); `None` without another. It is
/// not divided by √n: the orders are not independent draws that average out, each is an
/// equally good choice of a setting, and the whole's estimate is one of them.
pub(super) fn order_spread(main: [f64; 2], found: &[[f64; 2]]) -> Option<[f64; 2]> {
    if found.is_empty() {
        return None;
    }
    let all: Vec<[f64; 2]> = std::iter::once(main).chain(found.iter().copied()).collect();
    Some(sample_sd(&all))
}

/// The standard error of the mean of the response groups' estimates (Hz, damping ratio) of
/// one pole: their sample standard deviation over √n, n ≥ 2 groups. The whole set reads the
/// pole from all n groups' responses at once, so its estimate is about as uncertain as their
/// mean [a delete-a-group jackknife; Efron & Tibshirani 1993, ch. 11].
pub(super) fn group_spread(found: &[[f64; 2]]) -> Option<[f64; 2]> {
    if found.len() < 2 {
        return None;
    }
    let root_n = (found.len() as f64).sqrt();
    Some(sample_sd(found).map(|sd| sd / root_n))
}

/// Standard deviations (Hz, damping ratio) of the stable poles of the stabilization diagram
/// within 1 % of EMA mode `mode` and nearer it than any other mode (a close pair's poles are
/// not pooled), at least three; else `None`.
fn stabilization_scatter(ema: &EmaResult, mode: usize) -> Option<[f64; 2]> {
    let near: Vec<[f64; 2]> = ema
        .diagram
        .iter()
        .filter(|p| p.is_stable() && nearest_within(ema, p.freq_hz, 0.01) == Some(mode))
        .map(|p| [p.freq_hz, p.damping])
        .collect();
    (near.len() >= 3).then(|| sample_sd(&near))
}
