//! The FRF route's answer ([`FrfRoute`]): the core's law fitted to the measured FRFs through
//! the layered model ([`lamdyn_fit::frf_fit`]), corrected for the mesh by the ladder
//! ([`DiscretizationCorrection`]); when the run takes it as the answer and why ([`WhyFrfFit`],
//! [`reasons`]). A leaf: the layered stage fills it, the report and the CLI read it.
//!
//! **The rule.** The pole route reads each mode's core from its identified pole; it is exact
//! where the poles are (well separated, lightly damped modes: the demo roof within 1 %), and
//! breaks where modes are damped or overlap: poles missed, merged or smeared over a cluster,
//! pairs matched to the wrong modes (on an independent glass/acoustic-PVB plate with modal
//! damping 6–15 % the per-mode answers were −17 … +113 % off in G'). The FRF fit needs no
//! pole. The run takes it as the answer (`inverse.frf_fit = "auto"`) when any identified mode
//! in the band is damped beyond [`DAMPED_ZETA`], when two neighbours' half-power bands overlap
//! by more than [`OVERLAP_FACTOR`] of their spacing, when the EMA set a pole aside as a smear
//! over a cluster (`lamdyn_ema::quality`), or when a mode got no layered core; else
//! the pole route stays the answer and the FRF fit is not run. `"always"` runs it and takes it;
//! `"never"` does not run it.

use crate::chain::CorePoint;
use lamdyn_ema::identify::Mode;
use lamdyn_fit::frf_fit::{FrfFit, FrfLawPoint, LawComparison};
use num_complex::Complex64;

/// Modal damping ratio above which the pole route is not trusted (module docs): where the
/// independent plate's poles began to fail (ζ 6–15 %), with a margin.
pub const DAMPED_ZETA: f64 = 0.05;

/// Modal overlap of two neighbours above which the pole route is not trusted: the sum of their
/// half-power half-widths ζ_a f_a + ζ_b f_b over their spacing f_b − f_a (1: the half-power
/// bands touch).
pub const OVERLAP_FACTOR: f64 = 0.5;

/// Why the FRF fit is the answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WhyFrfFit {
    /// The job asks for it (`inverse.frf_fit = "always"`).
    Asked,
    /// A mode damped beyond [`DAMPED_ZETA`].
    Damped {
        /// Its frequency, Hz.
        freq_hz: f64,
        /// Its damping ratio.
        damping_ratio: f64,
    },
    /// Two neighbours overlapping beyond [`OVERLAP_FACTOR`].
    Overlapping {
        /// Their frequencies, Hz.
        freqs_hz: [f64; 2],
        /// Their overlap (module docs).
        overlap: f64,
    },
    /// A pole the EMA set aside as a smear over a cluster of modes.
    Smear {
        /// Its frequency, Hz.
        freq_hz: f64,
        /// Its shape's MPC.
        mpc: f64,
    },
    /// A mode the pole route gave no core.
    NoLayeredCore {
        /// Its frequency, Hz.
        freq_hz: f64,
    },
}

impl std::fmt::Display for WhyFrfFit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::Asked => write!(f, "the job asks for it (inverse.frf_fit = \"always\")"),
            Self::Damped {
                freq_hz,
                damping_ratio,
            } => write!(
                f,
                "the mode at {freq_hz:.2} Hz is damped {:.1} % (above {:.0} %)",
                100.0 * damping_ratio,
                100.0 * DAMPED_ZETA
            ),
            Self::Overlapping { freqs_hz, overlap } => write!(
                f,
                "the modes at {:.2} and {:.2} Hz overlap (half-power half-widths {:.2} of their spacing, above {OVERLAP_FACTOR})",
                freqs_hz[0], freqs_hz[1], overlap
            ),
            Self::Smear { freq_hz, mpc } => write!(
                f,
                "the pole at {freq_hz:.2} Hz (MPC {mpc:.2}) is one pole over a cluster of modes, set aside"
            ),
            Self::NoLayeredCore { freq_hz } => {
                write!(f, "the pole route found no core at {freq_hz:.2} Hz")
            }
        }
    }
}

/// Why the identified `modes` (any order), the poles the EMA `set_aside` as smears and the
/// pole route's `modal` points call for the FRF fit (module docs); empty: they do not.
pub fn reasons(modes: &[Mode], set_aside: &[Mode], modal: &[CorePoint]) -> Vec<WhyFrfFit> {
    let mut sorted: Vec<&Mode> = modes.iter().collect();
    sorted.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    let mut why: Vec<WhyFrfFit> = sorted
        .iter()
        .filter(|m| m.damping_ratio > DAMPED_ZETA)
        .map(|m| WhyFrfFit::Damped {
            freq_hz: m.freq_hz,
            damping_ratio: m.damping_ratio,
        })
        .collect();
    for pair in sorted.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let spacing = b.freq_hz - a.freq_hz;
        let widths = a.damping_ratio * a.freq_hz + b.damping_ratio * b.freq_hz;
        let overlap = if spacing > 0.0 {
            widths / spacing
        } else {
            f64::INFINITY
        };
        if overlap > OVERLAP_FACTOR {
            why.push(WhyFrfFit::Overlapping {
                freqs_hz: [a.freq_hz, b.freq_hz],
                overlap,
            });
        }
    }
    why.extend(set_aside.iter().map(|m| WhyFrfFit::Smear {
        freq_hz: m.freq_hz,
        mpc: m.mpc,
    }));
    why.extend(
        modal
            .iter()
            .filter(|p| p.layered.is_some() && p.layered_g().is_none())
            .map(|p| WhyFrfFit::NoLayeredCore { freq_hz: p.freq_hz }),
    );
    why
}

/// The mesh ladder's correction of the FRF fit's model (one of the ladder's levels): at each
/// mode the ladder converged, c₀ = G*_extrapolated / G*_coarsest is the factor by which the
/// coarsest mesh's answer misses the converged one
/// ([`lamdyn_layered::convergence::ConvergedMode`]); a level whose element size is r times the
/// coarsest's misses it by ln c = Re(ln c₀) r^p + i Im(ln c₀) r^q, p and q the mode's observed
/// orders of Re λ and Im λ (the error of G* follows the eigenvalue's, to first order), at least
/// the element's asymptotic 4 (a pre-asymptotic observed order scales a large coarsest error
/// into too large a correction: docs/fit.md); the difference to the observed order's
/// correction is part of the uncertainty.
/// The correction applied is a straight line in ln f through the modes' ln c, fitted by
/// Theil–Sen (the median of the pairwise slopes, then the median intercept [Sen 1968]: one
/// mode the pole route matched to the wrong model mode does not bend it), held beyond the
/// modes. Its uncertainty: the ladder's own half-widths (its grid convergence index), a
/// quarter of |ln c| for the interpolation between modes, and the modes' robust scatter about
/// the line (1.4826 × their median absolute residual), in quadrature.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DiscretizationCorrection {
    /// (f in Hz, c) at each converged mode, increasing f.
    pub modes: Vec<(f64, Complex64)>,
    /// The line ln c = a + b ln f (complex a, b; real and imaginary parts fitted apart).
    pub line: [Complex64; 2],
    /// The correction's relative standard deviation in (G', η): the largest over the modes,
    /// with the scatter about the line.
    pub rel_sd: [f64; 2],
}

/// The asymptotic order of the 20-node hexahedron's eigenvalues (2k with k = 2), the least
/// order the correction is scaled with ([`DiscretizationCorrection`]).
const ELEMENT_ORDER: f64 = 4.0;

/// Fraction of the correction |ln c| taken as its uncertainty between modes (module docs of
/// [`DiscretizationCorrection`]).
const INTERPOLATION_SHARE: f64 = 0.25;

impl DiscretizationCorrection {
    /// The correction of a level with elements `size_ratio` times the coarsest's in size (1:
    /// the coarsest) from the ladder's modes among `modal` (none converged: no correction, and
    /// `modes` is empty).
    pub fn from_ladder(modal: &[CorePoint], size_ratio: f64) -> Self {
        let mut modes: Vec<(f64, Complex64)> = Vec::new();
        let mut rel_sd = [0.0f64; 2];
        // The largest d ln η / d arg G* over the modes, for the scatter's η part.
        let mut eta_factor = 0.0f64;
        for p in modal {
            let Some(c) = p.layered_convergence else {
                continue;
            };
            let coarsest = c.core_shear_pa / c.coarsest_pa;
            if !(coarsest.is_finite() && coarsest.re > 0.0) {
                continue;
            }
            let ln0 = coarsest.ln();
            // At the element's asymptotic order at least: an observed order below it (a
            // pre-asymptotic ladder) scales a coarsest error of tens of per cent into a
            // correction several times too large; the spread between the two is uncertainty.
            let scaled = |p: [f64; 2]| {
                Complex64::new(
                    ln0.re * size_ratio.powf(p[0]),
                    ln0.im * size_ratio.powf(p[1]),
                )
            };
            let ln = scaled([c.order.max(ELEMENT_ORDER), c.loss_order.max(ELEMENT_ORDER)]);
            let spread = scaled([c.order, c.loss_order]) - ln;
            let factor = ln.exp();
            // ln c's real part moves ln G' (to first order), its imaginary part the phase:
            // η = tan(arg G*), so d ln η = d(arg)/(sin cos) of the core's phase.
            let arg = c.core_shear_pa.arg();
            let to_eta = 1.0 / (arg.sin() * arg.cos()).abs().max(1e-6);
            eta_factor = eta_factor.max(to_eta);
            let sd_g = (c.storage_band / 1.96)
                .hypot(INTERPOLATION_SHARE * ln.re)
                .hypot(spread.re);
            let sd_eta = (c.loss_band / 1.96)
                .hypot(INTERPOLATION_SHARE * ln.im * to_eta)
                .hypot(spread.im * to_eta);
            rel_sd = [rel_sd[0].max(sd_g), rel_sd[1].max(sd_eta)];
            modes.push((p.freq_hz, factor));
        }
        modes.sort_by(|a, b| a.0.total_cmp(&b.0));
        let points: Vec<(f64, Complex64)> = modes.iter().map(|&(f, c)| (f.ln(), c.ln())).collect();
        let part = |pick: fn(Complex64) -> f64| {
            let pts: Vec<[f64; 2]> = points.iter().map(|&(x, y)| [x, pick(y)]).collect();
            theil_sen(&pts)
        };
        let (re, im) = (part(|c| c.re), part(|c| c.im));
        let line = [Complex64::new(re.0, im.0), Complex64::new(re.1, im.1)];
        // The modes' robust scatter about the line, in ln G' and ln η (as above).
        let scatter = |pick: fn(Complex64) -> f64, (a, b): (f64, f64)| {
            let mut r: Vec<f64> = points
                .iter()
                .map(|&(x, y)| (pick(y) - a - b * x).abs())
                .collect();
            1.4826 * median(&mut r).unwrap_or(0.0)
        };
        let (s_re, s_im) = (scatter(|c| c.re, re), scatter(|c| c.im, im));
        rel_sd = [rel_sd[0].hypot(s_re), rel_sd[1].hypot(s_im * eta_factor)];
        Self {
            modes,
            line,
            rel_sd,
        }
    }

    /// c at `f_hz` on the line, held beyond the modes (1 without converged modes).
    pub fn factor(&self, f_hz: f64) -> Complex64 {
        let (Some(first), Some(last)) = (self.modes.first(), self.modes.last()) else {
            return Complex64::new(1.0, 0.0);
        };
        let x = f_hz.clamp(first.0, last.0).ln();
        (self.line[0] + self.line[1] * x).exp()
    }
}

/// The Theil–Sen line (a, b) of y = a + b x through `points` [x, y]: b the median of the
/// pairwise slopes, a the median of y − b x (one point: b = 0; none: (0, 0)).
fn theil_sen(points: &[[f64; 2]]) -> (f64, f64) {
    let mut slopes: Vec<f64> = Vec::new();
    for (i, p) in points.iter().enumerate() {
        for q in &points[i + 1..] {
            if q[0] != p[0] {
                slopes.push((q[1] - p[1]) / (q[0] - p[0]));
            }
        }
    }
    let b = median(&mut slopes).unwrap_or(0.0);
    let mut intercepts: Vec<f64> = points.iter().map(|p| p[1] - b * p[0]).collect();
    (median(&mut intercepts).unwrap_or(0.0), b)
}

/// The median of `v` (reordered), None when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// A measured FRF and the fitted model's over the band, at one channel and reference.
#[derive(Debug, Clone)]
pub struct FrfCurve {
    /// The response channel.
    pub channel: String,
    /// The reference.
    pub reference: String,
    /// Frequencies, Hz.
    pub freqs_hz: Vec<f64>,
    /// The measured FRF (the set's quantity).
    pub measured: Vec<Complex64>,
    /// The model's, with the fitted law and gain.
    pub model: Vec<Complex64>,
}

/// The FRF route's answer.
#[derive(Debug, Clone)]
pub struct FrfRoute {
    /// The fit on one of the ladder's levels (`model_line` names it; its law uncorrected).
    pub fit: FrfFit,
    /// Why it is the answer (empty: the pole route is, and this is beside it).
    pub why: Vec<WhyFrfFit>,
    /// The ladder's correction of the mesh.
    pub correction: DiscretizationCorrection,
    /// The model: mesh, dofs, basis.
    pub model_line: String,
    /// Measured against model at a few channels.
    pub curves: Vec<FrfCurve>,
    /// Seconds of the basis build and of the fit.
    pub times_s: [f64; 2],
    /// The laws fitted and which one was kept (`inverse.core_law = "auto"`).
    pub laws: LawsCompared,
}

/// The laws the FRF fit tried and the one it kept.
#[derive(Debug, Clone, PartialEq)]
pub enum LawsCompared {
    /// One law, as the job asked.
    One,
    /// Several fitted to the same lines, the lowest corrected Akaike criterion kept
    /// ([`lamdyn_fit::frf_fit::compare_laws`]).
    Compared {
        /// Each law's name, in the comparison's order.
        names: Vec<&'static str>,
        /// The comparison.
        comparison: LawComparison,
        /// Seconds the laws after the first took.
        seconds: f64,
    },
    /// The second law's fit failed; the first is kept.
    OtherFailed {
        /// The law that failed.
        name: &'static str,
        /// Why.
        error: String,
    },
}

impl LawsCompared {
    /// One clause for the run's line (empty for one law).
    pub fn describe(&self) -> String {
        match self {
            Self::One => String::new(),
            Self::Compared {
                names,
                comparison,
                seconds,
            } => {
                let scores: Vec<String> = names
                    .iter()
                    .zip(&comparison.akaike)
                    .map(|(n, a)| format!("{n} {a:.1}"))
                    .collect();
                format!(
                    "; {} kept by the corrected Akaike criterion ({} on {:.0} independent residuals; the comparison took {seconds:.1} s)",
                    names[comparison.chosen],
                    scores.join(", "),
                    comparison.effective_residuals
                )
            }
            Self::OtherFailed { name, error } => {
                format!("; {name} also tried, its fit failed: {error}")
            }
        }
    }
}

impl FrfRoute {
    /// The corrected law's G*(f), Pa.
    pub fn modulus(&self, f_hz: f64) -> Complex64 {
        self.fit.modulus(f_hz) * self.correction.factor(f_hz)
    }

    /// The corrected law and its 95 % band at `f_hz`: the fit's band (its covariance, the
    /// inputs' priors) widened by the correction's uncertainty in quadrature.
    pub fn at(&self, f_hz: f64) -> FrfLawPoint {
        let p = self.fit.at(f_hz);
        let g = self.modulus(f_hz);
        let eta = g.im / g.re;
        let widen = |ci: [f64; 2], value: f64, sd_extra: f64, new: f64| {
            let sd = (ci[1] / value).ln().max(0.0) / 1.96;
            let sd = sd.hypot(sd_extra);
            [new * (-1.96 * sd).exp(), new * (1.96 * sd).exp()]
        };
        FrfLawPoint {
            f_hz,
            storage_pa: g.re,
            loss_factor: eta,
            storage_ci95: widen(
                p.storage_ci95,
                p.storage_pa,
                self.correction.rel_sd[0],
                g.re,
            ),
            loss_factor_ci95: widen(
                p.loss_factor_ci95,
                p.loss_factor,
                self.correction.rel_sd[1],
                eta,
            ),
        }
    }

    /// Whether the run takes it as its answer.
    pub fn is_the_answer(&self) -> bool {
        !self.why.is_empty()
    }
}

/// The FRF route's outcome in a run.
#[derive(Debug)]
pub enum FrfOutcome {
    /// Not run: the job says never, or the rule did not call for it (module docs), or there
    /// is no layered model.
    NotRun(&'static str),
    /// Run and failed (the pole route stays the answer).
    Failed {
        /// Why it was run.
        why: Vec<WhyFrfFit>,
        /// What failed.
        error: crate::PipelineError,
    },
    /// Fitted.
    Fitted(Box<FrfRoute>),
}

impl FrfOutcome {
    /// The route, if it was fitted.
    pub fn route(&self) -> Option<&FrfRoute> {
        match self {
            Self::Fitted(r) => Some(r),
            _ => None,
        }
    }

    /// One line: whether it ran, its answer and why, or why not.
    pub fn describe(&self) -> String {
        let reasons = |why: &[WhyFrfFit]| {
            why.iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join("; ")
        };
        match self {
            Self::NotRun(why) => format!("not run: {why}"),
            Self::Failed { why, error } => format!(
                "failed ({}); the pole route stays the answer; run because {}",
                crate::error::chain_text(error),
                reasons(why)
            ),
            Self::Fitted(r) => {
                let role = if r.is_the_answer() {
                    format!("the answer, because {}", reasons(&r.why))
                } else {
                    "beside the pole route".to_string()
                };
                let correction = if r.correction.modes.is_empty() {
                    "not corrected for the mesh (no mode converged on the ladder): its bands lack the discretization error".to_string()
                } else {
                    format!(
                        "corrected for the mesh by the ladder at {} mode(s) (G' by {:+.2} … {:+.2} %)",
                        r.correction.modes.len(),
                        100.0
                            * r.correction
                                .modes
                                .iter()
                                .map(|m| m.1.re - 1.0)
                                .fold(f64::INFINITY, f64::min),
                        100.0
                            * r.correction
                                .modes
                                .iter()
                                .map(|m| m.1.re - 1.0)
                                .fold(f64::NEG_INFINITY, f64::max)
                    )
                };
                format!(
                    "{role}; {}{}; model {}; {correction}; basis {:.1} s, fit {:.1} s",
                    r.fit.describe(),
                    r.laws.describe(),
                    r.model_line,
                    r.times_s[0],
                    r.times_s[1]
                )
            }
        }
    }

    /// The route, if it was fitted and is the run's answer.
    pub fn answer(&self) -> Option<&FrfRoute> {
        self.route().filter(|r| r.is_the_answer())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::chain::NoSandwichInverse;
    use lamdyn_layered::convergence::ConvergedMode;

    fn at(freq_hz: f64) -> CorePoint {
        CorePoint {
            freq_hz,
            e_eff_pa: None,
            e_pole_pa: None,
            e_sd: None,
            paper: Err(NoSandwichInverse::NotASandwich),
            exact: Err(NoSandwichInverse::NotASandwich),
            layered: None,
            layered_convergence: None,
            layered_band: None,
        }
    }

    /// An identified mode at `freq_hz` with `damping_ratio` and nothing else (the tests' own).
    pub(crate) fn mode(freq_hz: f64, damping_ratio: f64) -> Mode {
        Mode {
            freq_hz,
            damping_ratio,
            loss_factor: 2.0 * damping_ratio,
            pole: Complex64::new(0.0, 0.0),
            stable_count: 5,
            shape: Vec::new(),
            participation: Vec::new(),
            real_shape: Vec::new(),
            mpc: 1.0,
            mpd_deg: 0.0,
            sd: None,
            pick: Default::default(),
            diagram_pole: Complex64::new(0.0, 0.0),
            refined: false,
            quality: Default::default(),
        }
    }

    /// Separated light modes call for nothing; a damped one, an overlapping pair (widths 0.6 of
    /// the spacing) each name themselves.
    #[test]
    fn the_rule_names_damped_and_overlapping_modes() {
        let light = [mode(20.0, 0.01), mode(40.0, 0.02), mode(70.0, 0.01)];
        assert!(reasons(&light, &[], &[]).is_empty());
        let damped = [mode(20.0, 0.01), mode(40.0, 0.08)];
        assert_eq!(
            reasons(&damped, &[], &[]),
            vec![WhyFrfFit::Damped {
                freq_hz: 40.0,
                damping_ratio: 0.08
            }]
        );
        // 0.03 × 50 + 0.03 × 50 = 3 Hz of half-widths over 5 Hz: 0.6.
        let close = [mode(55.0, 0.03), mode(50.0, 0.03)];
        let why = reasons(&close, &[], &[]);
        assert!(
            matches!(why[..], [WhyFrfFit::Overlapping { freqs_hz, overlap }]
                if freqs_hz == [50.0, 55.0] && (overlap - 0.63).abs() < 0.01),
            "{why:?}"
        );
        assert!(why[0].to_string().contains("overlap"), "{}", why[0]);
        // A pole set aside as a smear calls for the fit, and says so.
        let smear = Mode {
            mpc: 0.1,
            ..mode(150.0, 0.04)
        };
        let why = reasons(&light, &[smear], &[]);
        assert_eq!(
            why,
            vec![WhyFrfFit::Smear {
                freq_hz: 150.0,
                mpc: 0.1
            }]
        );
        assert!(why[0].to_string().contains("cluster"), "{}", why[0]);
    }

    /// The correction is each mode's c at the mode, log-linear between, held beyond; without
    /// converged modes it is 1.
    #[test]
    fn the_correction_interpolates_between_modes() {
        let point = |freq_hz: f64, c: f64| {
            let g = Complex64::new(1e6, 1e6);
            CorePoint {
                layered_convergence: Some(ConvergedMode::exact(g * c, g, 0)),
                ..at(freq_hz)
            }
        };
        let corr =
            DiscretizationCorrection::from_ladder(&[point(10.0, 1.04), point(40.0, 1.01)], 1.0);
        assert!((corr.factor(5.0).re - 1.04).abs() < 1e-12);
        assert!((corr.factor(80.0).re - 1.01).abs() < 1e-12);
        let mid = corr.factor(20.0).re;
        let expected = (0.5 * (1.04f64.ln() + 1.01f64.ln())).exp();
        assert!((mid - expected).abs() < 1e-12, "{mid}");
        assert!((corr.rel_sd[0] - 0.25 * 1.04f64.ln()).abs() < 1e-12);
        // A level at half the coarsest's element size: a sixteenth of the coarsest's ln c
        // (order 4; the ladder's observed 2 of ConvergedMode::exact would give a quarter, and
        // the difference widens the band).
        let half = DiscretizationCorrection::from_ladder(&[point(10.0, 1.04)], 0.5);
        assert!((half.factor(10.0).re.ln() - 1.04f64.ln() / 16.0).abs() < 1e-12);
        let spread = (0.25 - 1.0 / 16.0) * 1.04f64.ln();
        assert!(half.rel_sd[0] >= spread, "{:?}", half.rel_sd);
        // Three modes on a line and one off it: the line holds the three, the outlier widens
        // the band.
        let bent = DiscretizationCorrection::from_ladder(
            &[
                point(10.0, 1.04),
                point(20.0, 1.02),
                point(40.0, 1.0),
                point(30.0, 0.93),
            ],
            1.0,
        );
        let on_line = |f: f64| 1.04f64.ln() * (1.0 - (f / 10.0).ln() / 4f64.ln());
        assert!((bent.factor(20.0).re.ln() - on_line(20.0)).abs() < 0.002);
        assert!(bent.rel_sd[0] > corr.rel_sd[0]);
        let none = DiscretizationCorrection::from_ladder(&[at(10.0)], 1.0);
        assert_eq!(none.factor(10.0), Complex64::new(1.0, 0.0));
    }
}
