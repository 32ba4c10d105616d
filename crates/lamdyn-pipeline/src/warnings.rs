//! The run's warnings: what the chain's results say about themselves that a user must read
//! before trusting them (poor coherence, poles set aside, modes without a core, poles an EMA
//! cannot be trusted to give, per-mode cores that contradict a passive core), each a sentence
//! from [`crate::text`].

use crate::chain::{CorePoint, NoSandwichInverse};
use crate::config::RunConfig;
use crate::measurement::Measured;
use crate::text;
use lamdyn_ema::identify::{EmaResult, Mode};
use lamdyn_fit::fit::FitResult;
use lamdyn_material::causality::CausalityVerdict;

/// The modes damped more than `limit` (or with a damping ratio that is not a number), as
/// "f Hz (ζ %)".
pub(crate) fn damped_beyond(modes: &[Mode], limit: f64) -> Vec<String> {
    modes
        .iter()
        .filter(|m| m.damping_ratio > limit || m.damping_ratio.is_nan())
        .map(|m| text::pole_with_damping(m.freq_hz, m.damping_ratio))
        .collect()
}

/// Appends the run's warnings to `out` (module docs): the Monte Carlo left out, poor coherence,
/// the EMA's poles rejected, set aside or missing and its own warnings, the paper's fit, each
/// mode's inverses that gave no core or |φ| beyond validity, the layered route's contradictions,
/// the poles an EMA cannot be trusted to give, and the inverses' causality.
pub(crate) fn collect_warnings(
    config: &RunConfig,
    measured: &Measured,
    ema: &EmaResult,
    fit: Option<&FitResult>,
    modal: &[CorePoint],
    causality: &[Vec<Option<CausalityVerdict>>; 2],
    out: &mut Vec<String>,
) {
    use lamdyn_material::laminate::PHI_ACCURACY_LIMIT;
    let u = &config.uncertainty;
    if config.sandwich.stack.is_none() && u.options.samples > 0 {
        out.push(text::monte_carlo_skipped(u.stack.layers.len()));
    }
    let min_coherence = config.measurement.section.min_coherence;
    if let Some(c) = &measured.min_coherence {
        let names = measured.set.responses();
        let poor: Vec<String> = c
            .iter()
            .enumerate()
            .filter(|(_, g)| **g < min_coherence)
            .map(|(i, g)| text::response_with_coherence(&names[i].name, *g))
            .collect();
        if !poor.is_empty() {
            out.push(text::poor_coherence(min_coherence, &poor, c.len()));
        }
    }
    for m in &ema.rejected {
        out.push(text::support_resonance_rejected(m.freq_hz, m.damping_ratio));
    }
    for m in &ema.set_aside {
        out.push(text::smear_set_aside(
            m.freq_hz,
            m.damping_ratio,
            m.mpc,
            &m.quality.reasons(),
        ));
    }
    for f in &ema.missing_hz {
        out.push(text::no_stable_pole_near(*f));
    }
    out.extend(ema.warnings.iter().map(|w| text::from_the_ema(w)));
    if let Some(r) = fit {
        fit_warnings(ema, r, out);
    }
    // Without a fit the run's warnings say once why the paper's route has no result.
    let paper_route_ran = fit.is_some();
    for p in modal {
        if let Some(phi) = p.phi() {
            if phi > PHI_ACCURACY_LIMIT {
                out.push(text::phi_beyond_validity(p.freq_hz, phi));
            }
        }
        let sandwich =
            |e: Option<&NoSandwichInverse>| e.filter(|_| paper_route_ran).map(ToString::to_string);
        let layered = p.layered.as_ref().and_then(|l| l.as_ref().err());
        for (name, e) in [
            ("paper", sandwich(p.paper.as_ref().err())),
            ("exact", sandwich(p.exact.as_ref().err())),
            ("layered", layered.map(ToString::to_string)),
        ] {
            if let Some(e) = e {
                out.push(text::no_inverse(p.freq_hz, name, &e));
            }
        }
    }
    out.extend(shared_layered_modes(modal));
    out.extend(falling_layered_storage(modal));
    out.extend(poles_beyond_the_ema(
        &ema.modes,
        config.layered.max_damping_alone,
    ));
    for (name, v) in ["paper", "exact"].iter().zip(causality) {
        let bad = v
            .iter()
            .filter(|x| x.is_some_and(|x| !x.is_consistent()))
            .count();
        if bad > 0 {
            out.push(text::not_causal(name, bad, v.len()));
        }
    }
}

/// The fit's warnings: EMA modes without an RMS peak, a best start that did not converge.
fn fit_warnings(ema: &EmaResult, r: &FitResult, out: &mut Vec<String>) {
    let fe: Vec<f64> = r.peaks.iter().map(|p| p.freq_hz).collect();
    for m in &ema.modes {
        if !fe.iter().any(|f| (f / m.freq_hz - 1.0).abs() < 0.02) {
            out.push(text::no_rms_peak(m.freq_hz));
        }
    }
    if !r.converged {
        out.push(text::fit_not_converged(&r.reason));
    }
}

/// Two poles more than 2 % apart that the layered inverse matched to the same elastic mode of
/// the model (its rank at each pole's own G*): one of them sits on a neighbour's branch (a
/// close pair, a start far off), or the core's G* changes so fast between them that two modes
/// swap order. Either way the per-mode points there are not to be trusted without a look.
fn shared_layered_modes(modal: &[CorePoint]) -> Vec<String> {
    let ranked: Vec<(f64, usize)> = modal
        .iter()
        .filter_map(|p| Some((p.freq_hz, p.layered_convergence.as_ref()?.rank)))
        .collect();
    let mut out = Vec::new();
    for (i, &(fa, ra)) in ranked.iter().enumerate() {
        for &(fb, rb) in &ranked[i + 1..] {
            if ra == rb && (fb / fa - 1.0).abs() > 0.02 {
                out.push(text::one_layered_mode_for_two_poles([fa, fb], ra));
            }
        }
    }
    out
}

/// Consecutive modes (in frequency, among those with a layered G* and band) whose layered G'
/// falls by more than their two 95 % bands together, ln G'₂ − ln G'₁ < −(h₁ + h₂). A passive
/// core's storage modulus does not fall with frequency (a completely monotone relaxation
/// function: a generalized Maxwell law with positive weights, a fractional Zener law), so one
/// of the two poles sits on a neighbouring mode's branch of the model (a start far off) or is
/// not a true pole. The sum of the half-widths is wider than the band of the difference:
/// a warning here is a contradiction, not noise. On the small laminate with a fixed start far
/// off, the layered G' went 44 → 9.4 MPa from 103 to 153 Hz.
fn falling_layered_storage(modal: &[CorePoint]) -> Vec<String> {
    let banded: Vec<(f64, f64, f64)> = modal
        .iter()
        .filter_map(|p| {
            let g = p.layered_g()?;
            let band = p.layered_band.as_ref()?.as_ref().ok()?;
            Some((p.freq_hz, g.re, band.half_width.storage))
        })
        .filter(|(_, g, h)| *g > 0.0 && h.is_finite())
        .collect();
    banded
        .windows(2)
        .filter(|w| (w[1].1 / w[0].1).ln() < -(w[0].2 + w[1].2))
        .map(|w| text::layered_storage_falls([w[0].0, w[1].0], [w[0].1, w[1].1]))
        .collect()
}

/// The poles whose values an EMA cannot be trusted to give to the accuracy a core needs: poles
/// damped more than `max_damping` ([`crate::config::MAX_DAMPING_ALONE`] by default), and
/// neighbouring poles that overlap, closer than the sum of their half-power half-widths,
/// |f₂ − f₁| < ζ₁f₁ + ζ₂f₂. Both move every inverse's G* at those modes by more than the pole's
/// scatter says, the layered one most (d ln f / d ln G is a few per cent on a stiff
/// interlayer): the in-band foam roof's pair at 20.1 and 20.5 Hz (0.17 of its half-widths
/// apart) comes out 16 % and 24 % off from noise-free FRFs where its own poles give 2 % and
/// 8 %; the soft-core panel's poles at ζ 16–22 % 104–224 % in G'. On the demo roof the nearest
/// neighbours lie two or more half-widths apart (the tests below).
fn poles_beyond_the_ema(modes: &[Mode], max_damping: f64) -> Vec<String> {
    let mut out = Vec::new();
    let damped = damped_beyond(modes, max_damping);
    if !damped.is_empty() {
        out.push(text::damped_poles(&damped, modes.len(), max_damping));
    }
    let mut by_freq: Vec<&Mode> = modes.iter().collect();
    by_freq.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    for w in by_freq.windows(2) {
        let widths = w[0].damping_ratio * w[0].freq_hz + w[1].damping_ratio * w[1].freq_hz;
        let apart = w[1].freq_hz - w[0].freq_hz;
        if apart < widths {
            out.push(text::overlapping_poles(
                [w[0].freq_hz, w[1].freq_hz],
                apart,
                apart / widths,
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::MAX_DAMPING_ALONE;
    use lamdyn_layered::convergence::ConvergedMode;
    use num_complex::Complex64;

    /// A modal point at `freq_hz` whose layered core matched the elastic mode of `rank`.
    fn point(freq_hz: f64, rank: usize) -> CorePoint {
        let g = Complex64::new(5e6, 2e6);
        CorePoint {
            layered: Some(Ok(g)),
            layered_convergence: Some(ConvergedMode::exact(g, g, rank)),
            ..crate::frf_route::tests::at(freq_hz)
        }
    }

    /// A layered G' that falls with frequency beyond the two modes' bands is named; one that
    /// falls within them, one that rises, and a mode without a band are not.
    #[test]
    fn layered_storage_falling_beyond_the_bands_is_named() {
        let banded = |freq_hz: f64, g: f64, h: f64| {
            let mut p = point(freq_hz, 0);
            p.layered = Some(Ok(Complex64::new(g, 0.5 * g)));
            p.layered_band = Some(Ok(crate::band::LayeredBand {
                sources: Vec::new(),
                half_width: crate::band::StorageAndLoss::new(h, h),
                inputs: Vec::new(),
                second_order: Vec::new(),
                inputs_at: Vec::new(),
                found_at_hz: Complex64::new(freq_hz, 0.0),
                found_pa: Complex64::new(g, 0.5 * g),
                coarse: crate::band::CoarsePole {
                    rank: 0,
                    eigenvalue: Complex64::new(0.0, 0.0),
                },
            }));
            p
        };
        // ln(44/37) rises; ln(9.4/44) = -1.54 < -(0.05 + 0.05); ln(9.0/9.4) = -0.043 > -0.1.
        let w = falling_layered_storage(&[
            banded(77.0, 37e6, 0.05),
            banded(103.0, 44e6, 0.05),
            banded(153.0, 9.4e6, 0.05),
            banded(185.0, 9.0e6, 0.05),
        ]);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("from 44.0000 MPa at 103.00 Hz to 9.4000 MPa at 153.00 Hz (-78.6 %)"),
            "{}",
            w[0]
        );
        // Without a band the mode is left out: 37 -> (44 unbanded) -> 30 is one step, -19 %,
        // within 0.1 + 0.15.
        let mut unbanded = banded(103.0, 44e6, 0.05);
        unbanded.layered_band = None;
        assert!(
            falling_layered_storage(&[
                banded(77.0, 37e6, 0.1),
                unbanded,
                banded(153.0, 30e6, 0.15)
            ])
            .is_empty()
        );
    }

    use crate::frf_route::tests::mode;

    /// The poles that keep the layered route from going on without the paper's fit: those
    /// damped beyond the limit, and one whose damping ratio is not a number.
    #[test]
    fn poles_damped_beyond_the_limit_are_named() {
        let modes = [
            mode(80.0, 0.05),
            mode(110.0, 0.10),
            mode(130.0, 0.163),
            mode(170.0, f64::NAN),
        ];
        assert_eq!(
            damped_beyond(&modes, MAX_DAMPING_ALONE),
            ["130.0 Hz (16.3 %)", "170.0 Hz (NaN %)"]
        );
        assert!(damped_beyond(&modes[..2], MAX_DAMPING_ALONE).is_empty());
    }

    /// The in-band foam roof's poles as its EMA found them (frequencies and damping ratios
    /// of its run, out of order here): its overlapping pair at 20.1 / 20.5 Hz is named, its
    /// neighbours 2.2 or more half-widths apart are not; a pole damped 16.3 % is named; the demo
    /// roof's five poles give no warning.
    #[test]
    fn overlapping_and_heavily_damped_poles_are_named() {
        let in_band = [
            mode(20.4525, 0.0516),
            mode(16.4229, 0.0402),
            mode(20.0933, 0.0506),
            mode(26.1270, 0.0107),
            mode(31.2930, 0.0627),
            mode(130.0, 0.163),
        ];
        let w = poles_beyond_the_ema(&in_band, MAX_DAMPING_ALONE);
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].contains("1 of 6 poles") && w[0].contains("130.0 Hz (16.3 %)"));
        assert!(w[1].contains("20.09 Hz and 20.45 Hz") && w[1].contains("0.17 of"));
        let demo_roof = [
            mode(17.1507, 0.01183),
            mode(25.1785, 0.00399),
            mode(43.70, 0.0137),
            mode(50.99, 0.0123),
            mode(64.26, 0.0173),
        ];
        assert!(poles_beyond_the_ema(&demo_roof, MAX_DAMPING_ALONE).is_empty());
    }

    /// Two poles 3 % apart on one model mode are named; distinct modes, and two fit peaks
    /// on one pole (within 2 %: the same target), are not.
    #[test]
    fn poles_sharing_one_layered_mode_are_named() {
        let w = shared_layered_modes(&[point(100.0, 2), point(103.0, 2), point(140.0, 3)]);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("100.00 Hz and 103.00 Hz") && w[0].contains("elastic mode 3"),
            "{}",
            w[0]
        );
        assert!(
            shared_layered_modes(&[point(100.0, 2), point(101.0, 2), point(140.0, 3)]).is_empty()
        );
    }
}
