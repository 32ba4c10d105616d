//! The FRF route's answer ([`FrfRoute`]): the core's law fitted to the measured FRFs through
//! the layered model ([`lamdyn_fit::frf_fit`]) on the converged scale of the mesh ladder
//! ([`DiscretizationCorrection`]); when the run takes it as the answer and why ([`WhyFrfFit`],
//! [`reasons`]). A leaf: the layered stage fills it, the report and the CLI read it.
//!
//! **The rule.** The pole route reads each mode's core from its identified pole; it is exact
//! where the poles are (well separated, lightly damped modes: the demo roof within 1 %), and
//! breaks where modes are damped or overlap: poles missed, merged or smeared over a cluster,
//! pairs matched to the wrong modes (on an independent glass/acoustic-PVB plate with modal
//! damping 6–15 % the per-mode answers were −17 … +113 % off in G'). The FRF fit needs no
//! pole. The run takes it as the answer (`inverse.frf_fit = "auto"`) when any identified mode
//! in the band is damped beyond [`FrfRule::damped_zeta`], when two neighbours' half-power bands
//! overlap by more than [`FrfRule::overlap_factor`] of their spacing, when the EMA set a pole
//! aside as a smear over a cluster (`lamdyn_ema::quality`), or when a mode got no layered core;
//! else the pole route stays the answer and the FRF fit is not run. `"always"` runs it and
//! takes it; `"never"` does not run it.

use crate::chain::CorePoint;
use lamdyn_ema::identify::Mode;
use lamdyn_fit::frf_fit::{FrfFit, FrfLawPoint, LawComparison};
use num_complex::Complex64;

/// Why the FRF fit is the answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WhyFrfFit {
    /// The job asks for it (`inverse.frf_fit = "always"`).
    Asked,
    /// A mode damped beyond the rule's limit ([`FrfRule::damped_zeta`]).
    Damped {
        /// Its frequency, Hz.
        freq_hz: f64,
        /// Its damping ratio.
        damping_ratio: f64,
        /// The limit.
        limit: f64,
    },
    /// Two neighbours overlapping beyond the rule's limit ([`FrfRule::overlap_factor`]).
    Overlapping {
        /// Their frequencies, Hz.
        freqs_hz: [f64; 2],
        /// Their overlap (module docs).
        overlap: f64,
        /// The limit.
        limit: f64,
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
                limit,
            } => write!(
                f,
                "the mode at {freq_hz:.2} Hz is damped {:.1} % (above {:.0} %)",
                100.0 * damping_ratio,
                100.0 * limit
            ),
            Self::Overlapping {
                freqs_hz,
                overlap,
                limit,
            } => write!(
                f,
                "the modes at {:.2} and {:.2} Hz overlap (half-power half-widths {:.2} of their \
                 spacing, above {limit})",
                freqs_hz[0], freqs_hz[1], overlap
            ),
            Self::Smear { freq_hz, mpc } => write!(
                f,
                "the pole at {freq_hz:.2} Hz (MPC {mpc:.2}) is one pole over a cluster of modes, \
                 set aside"
            ),
            Self::NoLayeredCore { freq_hz } => {
                write!(f, "the pole route found no core at {freq_hz:.2} Hz")
            }
        }
    }
}

/// The limits beyond which the pole route is not trusted (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrfRule {
    /// A mode's damping ratio: default 0.05, where the independent plate's poles began to fail
    /// (ζ 6–15 %), with a margin.
    pub damped_zeta: f64,
    /// Two neighbours' overlap, the sum of their half-power half-widths ζ_a f_a + ζ_b f_b over
    /// their spacing f_b − f_a (1: the half-power bands touch): default 0.5.
    pub overlap_factor: f64,
}

impl Default for FrfRule {
    fn default() -> Self {
        Self {
            damped_zeta: 0.05,
            overlap_factor: 0.5,
        }
    }
}

/// Why the identified `modes` (any order), the poles the EMA `set_aside` as smears and the
/// pole route's `modal` points call for the FRF fit under `rule` (module docs); empty: they do
/// not.
pub fn reasons(
    modes: &[Mode],
    set_aside: &[Mode],
    modal: &[CorePoint],
    rule: FrfRule,
) -> Vec<WhyFrfFit> {
    let mut sorted: Vec<&Mode> = modes.iter().collect();
    sorted.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    let mut why: Vec<WhyFrfFit> = sorted
        .iter()
        .filter(|m| m.damping_ratio > rule.damped_zeta)
        .map(|m| WhyFrfFit::Damped {
            freq_hz: m.freq_hz,
            damping_ratio: m.damping_ratio,
            limit: rule.damped_zeta,
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
        if overlap > rule.overlap_factor {
            why.push(WhyFrfFit::Overlapping {
                freqs_hz: [a.freq_hz, b.freq_hz],
                overlap,
                limit: rule.overlap_factor,
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
/// mode the ladder converged (or estimated, where it missed its tolerance on its last level:
/// [`CorePoint::ladder_estimate`]), c = G*_converged / G*_level, by which the G* that level alone
/// finds for the mode's pole misses the converged one (to first order:
/// [`lamdyn_layered::convergence::ConvergedMode::level_corrections`]).
///
/// The FRF fit fits one law to every mode at once, so the level's error moves that law as a
/// least-squares fit through the modes' errors would: each mode weighs by |S|², S = ∂ln λ/∂ln G*
/// (a mode whose eigenvalue barely feels the core, say one mixed with the supports, has a
/// large ln c, but its pole's shift also barely moves the law). The correction applied is a
/// straight line in ln f through the modes' ln c, fitted by weighted Theil–Sen (the weighted
/// median of the pairwise slopes, pair weights w_i w_j, then the weighted median intercept [Sen
/// 1968; Jaeckel 1972]: one mode the pole route matched to the wrong model mode does not bend
/// it), held beyond the modes. Its uncertainty: the modes' ladder half-widths (their grid
/// convergence index) with a quarter of |ln c| for the first order and the interpolation, as a
/// weighted mean over the modes, and the modes' robust scatter about the line (1.4826 × their
/// weighted median absolute residual), in quadrature.
///
/// The fit runs on the converged scale: at each line the level's model takes G*(f)/c(f), c on
/// the line, so the law fitted is the converged model's, and the inputs fitted beside it under
/// their priors see a model without the level's error (applied after the fit, a face modulus
/// 0.1 % lower that softens every mode as a finer mesh does would have taken up part of it,
/// and moved a stiff-core laminate's G' by several per cent; docs/fit.md, "The mesh correction
/// on the foam roof").
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DiscretizationCorrection {
    /// Each converged mode's correction, increasing f.
    pub modes: Vec<ModeCorrection>,
    /// The line ln c = a + b ln f (complex a, b; real and imaginary parts fitted apart).
    pub line: [Complex64; 2],
    /// The correction's relative standard deviation in (G', η): the modes' own, weighted, with
    /// the scatter about the line.
    pub rel_sd: [f64; 2],
}

/// Fraction of the correction |ln c| taken as its uncertainty between modes (module docs of
/// [`DiscretizationCorrection`]).
const INTERPOLATION_SHARE: f64 = 0.25;

/// One mode's correction of a level ([`DiscretizationCorrection`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeCorrection {
    /// ln f, f the pole's frequency in Hz.
    pub x: f64,
    /// ln c.
    pub y: Complex64,
    /// |S|², its weight in the line.
    pub weight: f64,
    /// Its relative standard deviations of G' and η (the ladder's band, a quarter of |ln c|).
    pub sd: [f64; 2],
}

impl DiscretizationCorrection {
    /// The correction of the ladder's level `level` (0: the coarsest) from the ladder's modes
    /// among `modal` (none converged, or none with that level's correction: no correction, and
    /// `modes` is empty).
    pub fn from_ladder(modal: &[CorePoint], level: usize) -> Self {
        let mut points: Vec<ModeCorrection> = Vec::new();
        // The largest d ln η / d arg G* over the modes, for the scatter's η part.
        let mut eta_factor = 0.0f64;
        for p in modal {
            let Some(c) = p
                .layered_convergence
                .as_ref()
                .or(p.ladder_estimate.as_ref())
            else {
                continue;
            };
            let Some(&ln) = c.level_corrections.get(level) else {
                continue;
            };
            let weight = c.sensitivity.norm_sqr();
            if !(ln.is_finite() && weight.is_finite() && weight > 0.0) {
                continue;
            }
            // ln c's real part moves ln G' (to first order), its imaginary part the phase:
            // η = tan(arg G*), so d ln η = d(arg)/(sin cos) of the core's phase.
            let arg = c.core_shear_pa.arg();
            let to_eta = 1.0 / (arg.sin() * arg.cos()).abs().max(1e-6);
            eta_factor = eta_factor.max(to_eta);
            let sd = [
                (c.storage_band / 1.96).hypot(INTERPOLATION_SHARE * ln.re),
                (c.loss_band / 1.96).hypot(INTERPOLATION_SHARE * ln.im * to_eta),
            ];
            points.push(ModeCorrection {
                x: p.freq_hz.ln(),
                y: ln,
                weight,
                sd,
            });
        }
        points.sort_by(|a, b| a.x.total_cmp(&b.x));
        let part = |pick: fn(Complex64) -> f64| {
            let pts: Vec<[f64; 3]> = points.iter().map(|p| [p.x, pick(p.y), p.weight]).collect();
            weighted_theil_sen(&pts)
        };
        let (re, im) = (part(|c| c.re), part(|c| c.im));
        let line = [Complex64::new(re.0, im.0), Complex64::new(re.1, im.1)];
        // The modes' robust scatter about the line, in ln G' and ln η (as above).
        let scatter = |pick: fn(Complex64) -> f64, (a, b): (f64, f64)| {
            let mut r: Vec<[f64; 2]> = points
                .iter()
                .map(|p| [(pick(p.y) - a - b * p.x).abs(), p.weight])
                .collect();
            1.4826 * weighted_median(&mut r).unwrap_or(0.0)
        };
        let (s_re, s_im) = (scatter(|c| c.re, re), scatter(|c| c.im, im));
        let total: f64 = points.iter().map(|p| p.weight).sum();
        let own = |k: usize| points.iter().map(|p| p.weight * p.sd[k]).sum::<f64>() / total;
        let rel_sd = if points.is_empty() {
            [0.0; 2]
        } else {
            [own(0).hypot(s_re), own(1).hypot(s_im * eta_factor)]
        };
        Self {
            modes: points,
            line,
            rel_sd,
        }
    }

    /// Over the modes, the smallest and largest change of G' the fit's model takes (Re c − 1
    /// on the line), and the same of the modes' own c.
    pub fn storage_ranges(&self) -> [[f64; 2]; 2] {
        let range = |v: &mut dyn Iterator<Item = f64>| {
            v.fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], x| {
                [lo.min(x), hi.max(x)]
            })
        };
        let applied = range(&mut self.modes.iter().map(|m| self.factor(m.x.exp()).re - 1.0));
        let own = range(&mut self.modes.iter().map(|m| m.y.exp().re - 1.0));
        [applied, own]
    }

    /// c at `f_hz` on the line, held beyond the modes (1 without converged modes).
    pub fn factor(&self, f_hz: f64) -> Complex64 {
        let (Some(first), Some(last)) = (self.modes.first(), self.modes.last()) else {
            return Complex64::new(1.0, 0.0);
        };
        let x = f_hz.ln().clamp(first.x, last.x);
        (self.line[0] + self.line[1] * x).exp()
    }
}

/// The weighted Theil–Sen line (a, b) of y = a + b x through `points` [x, y, w]: b the
/// weighted median of the pairwise slopes (pair weights w_i w_j), a the weighted median of
/// y − b x (one point: b = 0; none: (0, 0)). Equal weights give the plain Theil–Sen line.
fn weighted_theil_sen(points: &[[f64; 3]]) -> (f64, f64) {
    let mut slopes: Vec<[f64; 2]> = Vec::new();
    for (i, p) in points.iter().enumerate() {
        for q in &points[i + 1..] {
            if q[0] != p[0] {
                slopes.push([(q[1] - p[1]) / (q[0] - p[0]), p[2] * q[2]]);
            }
        }
    }
    let b = weighted_median(&mut slopes).unwrap_or(0.0);
    let mut intercepts: Vec<[f64; 2]> = points.iter().map(|p| [p[1] - b * p[0], p[2]]).collect();
    (weighted_median(&mut intercepts).unwrap_or(0.0), b)
}

/// The weighted median of `v` [value, weight] (reordered): the value where the cumulative
/// weight reaches half the total, the mean of two values where it lands exactly between them
/// (equal weights: the median); None when empty or weightless.
fn weighted_median(v: &mut [[f64; 2]]) -> Option<f64> {
    let total: f64 = v.iter().map(|p| p[1]).sum();
    if v.is_empty() || total.is_nan() || total <= 0.0 {
        return None;
    }
    v.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let half = 0.5 * total;
    let mut cumulative = 0.0;
    for (k, p) in v.iter().enumerate() {
        cumulative += p[1];
        if cumulative >= half {
            let between = (cumulative - half).abs() <= 1e-12 * total;
            return Some(match v.get(k + 1) {
                Some(next) if between => 0.5 * (p[0] + next[0]),
                _ => p[0],
            });
        }
    }
    v.last().map(|p| p[0])
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
    /// The fit on one of the ladder's levels (`model_line` names it), its law on the converged
    /// scale.
    pub fit: FrfFit,
    /// Why it is the answer (empty: the pole route is, and this is beside it).
    pub why: Vec<WhyFrfFit>,
    /// The ladder's correction of the mesh: the line through its modes' errors.
    pub correction: DiscretizationCorrection,
    /// Where the answer's model also took what the line leaves of each ladder mode's own
    /// error out.
    pub mode_by_mode: Option<ModeByMode>,
    /// The poles (Hz) whose ladder mode the pole route had found on another branch of the
    /// model's modes, converged again from the law fitted with the line: their modes, not the
    /// pole route's, are in `correction` (and the law was fitted again with it).
    pub converged_again_hz: Vec<f64>,
    /// The model: mesh, dofs, basis.
    pub model_line: String,
    /// Measured against model at a few channels.
    pub curves: Vec<FrfCurve>,
    /// Seconds of the basis build and of the fit.
    pub times_s: [f64; 2],
    /// The laws fitted and which one was kept (`inverse.core_law = "auto"`).
    pub laws: LawsCompared,
}

/// The mesh correction mode by mode (`layered::frf_fit`): the answer's model, on the line's
/// converged scale ([`DiscretizationCorrection`]), also took what the line leaves of each
/// ladder mode's own error out of the level's model
/// ([`lamdyn_layered::frf::ObservedModel::take_out_mode_errors`]), and was fitted from the law
/// fitted with the line alone. The two laws' difference measures the line's error between
/// and at the modes and is part of the band.
#[derive(Debug, Clone)]
pub struct ModeByMode {
    /// The ladder modes (Hz) whose error was taken out.
    pub taken_hz: Vec<f64>,
    /// Those whose error was given but left to the line: their scales beyond
    /// [`lamdyn_layered::reduced::mode_errors::SCALE_LIMIT`], or the mode not found. (Modes the
    /// law misses by more than a factor 1.5, and two poles on one model mode, give none.)
    pub left_hz: Vec<f64>,
    /// The law fitted with the line alone.
    pub line_law: FrfFit,
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
                    "; {} kept by the corrected Akaike criterion ({} on {:.0} independent \
                     residuals; the comparison took {seconds:.1} s)",
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
    /// The law's G*(f), Pa: the fit's, on the converged scale ([`DiscretizationCorrection`]).
    pub fn modulus(&self, f_hz: f64) -> Complex64 {
        self.fit.modulus(f_hz)
    }

    /// The law and its 95 % band at `f_hz`: the fit's band (its covariance, the inputs'
    /// priors) widened in quadrature by the mesh correction's uncertainty, by the law's
    /// difference to the law fitted with the correction's line alone ([`ModeByMode`]) and by its
    /// difference to the law with the inputs held, each difference as one standard deviation
    /// ([`FrfFit::inputs_held_step`]). The data pin the inputs to a fraction of their priors (the
    /// faces' modulus to 0.1 % on the foam roof's 243 channels), so a model error the level's
    /// correction leaves moves them by more than their own band, and a stiff core's G' by ten
    /// to twenty times that (docs/fit.md, "The mesh correction on the foam roof").
    pub fn at(&self, f_hz: f64) -> FrfLawPoint {
        let p = self.fit.at(f_hz);
        let widen = |ci: [f64; 2], value: f64, sd_extra: f64| {
            let sd = ((ci[1] / value).ln().max(0.0) / 1.96).hypot(sd_extra);
            [value * (-1.96 * sd).exp(), value * (1.96 * sd).exp()]
        };
        // |Δ| as the relative sd; a first-order move that cannot be read (η of a G' through
        // zero) counts as a factor e.
        let relative = |d: f64| if d.is_finite() { d.abs() } else { 1.0 };
        let [held_storage, held_loss] = self
            .inputs_held_change(f_hz)
            .map_or([0.0; 2], |d| d.map(relative));
        let [line_storage, line_loss] = self
            .line_law_change(f_hz)
            .map_or([0.0; 2], |d| d.map(relative));
        let [sd_storage, sd_loss] = [
            self.correction.rel_sd[0]
                .hypot(held_storage)
                .hypot(line_storage),
            self.correction.rel_sd[1].hypot(held_loss).hypot(line_loss),
        ];
        FrfLawPoint {
            storage_ci95: widen(p.storage_ci95, p.storage_pa, sd_storage),
            loss_factor_ci95: widen(p.loss_factor_ci95, p.loss_factor, sd_loss),
            ..p
        }
    }

    /// The law fitted with the mesh correction's line alone against the law, at `f_hz`:
    /// (G'_line/G' − 1, η_line/η − 1); `None` where the answer is that law.
    pub fn line_law_change(&self, f_hz: f64) -> Option<[f64; 2]> {
        let line = &self.mode_by_mode.as_ref()?.line_law;
        Some(relative_change(self.fit.modulus(f_hz), line.modulus(f_hz)))
    }

    /// The smallest and largest [`Self::line_law_change`] in G' and η over the fit's band (at
    /// 64 log-spaced lines, the ranges taken from zero; zeros without the correction mode by
    /// mode).
    pub fn line_law_ranges(&self) -> [[f64; 2]; 2] {
        if self.mode_by_mode.is_none() {
            return [[0.0; 2]; 2];
        }
        self.change_ranges(64, [[0.0; 2]; 2], |f| self.line_law_change(f))
    }

    /// The law with the inputs held against the law, at `f_hz`: (G'_held/G' − 1, η_held/η − 1);
    /// `None` without inputs fitted.
    pub fn inputs_held_change(&self, f_hz: f64) -> Option<[f64; 2]> {
        let held = self.fit.modulus_inputs_held(f_hz)?;
        Some(relative_change(self.fit.modulus(f_hz), held))
    }

    /// The smallest and largest of `change` (G', η; a line without one counts as zero) at `n`
    /// (at least 2) lines evenly spaced in ln f over the fit's band, folded into `from`.
    fn change_ranges(
        &self,
        n: usize,
        from: [[f64; 2]; 2],
        change: impl Fn(f64) -> Option<[f64; 2]>,
    ) -> [[f64; 2]; 2] {
        let [lo, hi] = self.fit.band_hz.map(f64::ln);
        let n = n.max(2);
        (0..n).fold(from, |mut ranges, k| {
            let f = (lo + (hi - lo) * k as f64 / (n - 1) as f64).exp();
            for (range, x) in ranges.iter_mut().zip(change(f).unwrap_or([0.0; 2])) {
                *range = [range[0].min(x), range[1].max(x)];
            }
            ranges
        })
    }

    /// [`Self::at`] on `n` (at least 2) lines evenly spaced in ln f over the fitted band.
    pub fn curve(&self, n: usize) -> Vec<FrfLawPoint> {
        let [lo, hi] = self.fit.band_hz.map(f64::ln);
        let n = n.max(2);
        (0..n)
            .map(|k| self.at((lo + (hi - lo) * k as f64 / (n - 1) as f64).exp()))
            .collect()
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
                    "not corrected for the mesh (no mode converged on the ladder): its bands lack \
                     the discretization error"
                        .to_string()
                } else {
                    let [applied, own] = r.correction.storage_ranges();
                    format!(
                        "corrected for the mesh by the ladder at {} mode(s){}: the level's model \
                         takes G*/c, c − 1 in G' {:+.2} … {:+.2} % (the level's own error at each \
                         mode {:+.2} … {:+.2} %){}",
                        r.correction.modes.len(),
                        converged_again_clause(r),
                        100.0 * applied[0],
                        100.0 * applied[1],
                        100.0 * own[0],
                        100.0 * own[1],
                        mode_by_mode_clause(r),
                    )
                };
                format!(
                    "{role}; {}{}; model {}{}; {correction}; basis {:.1} s, fit {:.1} s",
                    r.fit.describe(),
                    r.laws.describe(),
                    r.model_line,
                    inputs_found(r),
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

/// " (at 67.0 Hz the ladder's mode converged again ...)" where the FRF fit ran the ladder
/// again on a pole ([`FrfRoute::converged_again_hz`]; empty otherwise).
fn converged_again_clause(route: &FrfRoute) -> String {
    if route.converged_again_hz.is_empty() {
        return String::new();
    }
    format!(
        " (at {} the ladder's mode converged again from the law: the pole route's lay on \
         another branch)",
        crate::text::hz_list(&route.converged_again_hz)
    )
}

/// ", and what the line leaves of each mode's own error taken out ..." where the answer's
/// model was corrected mode by mode ([`ModeByMode`]; empty otherwise).
fn mode_by_mode_clause(route: &FrfRoute) -> String {
    let Some(by_mode) = &route.mode_by_mode else {
        return String::new();
    };
    let [storage, loss] = route.line_law_ranges();
    format!(
        ", and what c leaves of each mode's own error taken out of the model at {} (left to \
         c: {}), fitted from the law with c alone, which differs by G' {:+.2} … {:+.2} %, η \
         {:+.2} … {:+.2} % over the band (in the band as one sd)",
        crate::text::hz_list(&by_mode.taken_hz),
        crate::text::hz_list(&by_mode.left_hz),
        100.0 * storage[0],
        100.0 * storage[1],
        100.0 * loss[0],
        100.0 * loss[1],
    )
}

/// `other` against `law` (G*, Pa): (G'_other/G' − 1, η_other/η − 1).
fn relative_change(law: Complex64, other: Complex64) -> [f64; 2] {
    [
        other.re / law.re - 1.0,
        (other.im / other.re) / (law.im / law.re) - 1.0,
    ]
}

/// "; inputs found: face modulus +0.06 % (sd 0.98 %, prior 1.00 %), ...; with them held, G'
/// −0.2 … +1.0 %, η ..." for the inputs the fit moved beside the law (empty without).
fn inputs_found(route: &FrfRoute) -> String {
    let found: Vec<String> = route
        .fit
        .inputs
        .iter()
        .map(|i| {
            format!(
                "{} {:+.2} % (sd {:.2} %, prior {:.2} %)",
                i.input.name(),
                100.0 * i.change,
                100.0 * i.sd,
                100.0 * i.prior_sd
            )
        })
        .collect();
    if found.is_empty() {
        return String::new();
    }
    let range = route.change_ranges(21, [[f64::INFINITY, f64::NEG_INFINITY]; 2], |f| {
        route.inputs_held_change(f)
    });
    let held = format!(
        "; with them held the law moves G' {:+.2} … {:+.2} %, η {:+.2} … {:+.2} % (in its band as \
         one sd)",
        100.0 * range[0][0],
        100.0 * range[0][1],
        100.0 * range[1][0],
        100.0 * range[1][1]
    );
    format!("; inputs found: {}{held}", found.join(", "))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::chain::NoSandwichInverse;
    use lamdyn_layered::convergence::ConvergedMode;

    /// A modal point at `freq_hz` without any route's result.
    pub(crate) fn at(freq_hz: f64) -> CorePoint {
        CorePoint {
            freq_hz,
            e_eff_pa: None,
            e_pole_pa: None,
            e_sd: None,
            paper: Err(NoSandwichInverse::NotASandwich),
            exact: Err(NoSandwichInverse::NotASandwich),
            layered: None,
            layered_convergence: None,
            ladder_estimate: None,
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
            refinement: None,
            refined: false,
            quality: Default::default(),
        }
    }

    /// Separated light modes call for nothing; a damped one, an overlapping pair (widths 0.6 of
    /// the spacing) each name themselves.
    #[test]
    fn the_rule_names_damped_and_overlapping_modes() {
        let light = [mode(20.0, 0.01), mode(40.0, 0.02), mode(70.0, 0.01)];
        let rule = FrfRule::default();
        assert!(reasons(&light, &[], &[], rule).is_empty());
        let damped = [mode(20.0, 0.01), mode(40.0, 0.08)];
        assert_eq!(
            reasons(&damped, &[], &[], rule),
            vec![WhyFrfFit::Damped {
                freq_hz: 40.0,
                damping_ratio: 0.08,
                limit: 0.05
            }]
        );
        // A stricter rule, set by the tuning, names the lighter mode too.
        let strict = FrfRule {
            damped_zeta: 0.005,
            ..rule
        };
        assert_eq!(reasons(&damped, &[], &[], strict).len(), 2);
        assert!(
            reasons(&damped, &[], &[], strict)[0]
                .to_string()
                .contains("above 0 %")
        );
        // 0.03 × 50 + 0.03 × 50 = 3 Hz of half-widths over 5 Hz: 0.6.
        let close = [mode(55.0, 0.03), mode(50.0, 0.03)];
        let why = reasons(&close, &[], &[], rule);
        assert!(
            matches!(why[..], [WhyFrfFit::Overlapping { freqs_hz, overlap, .. }]
                if freqs_hz == [50.0, 55.0] && (overlap - 0.63).abs() < 0.01),
            "{why:?}"
        );
        assert!(why[0].to_string().contains("overlap"), "{}", why[0]);
        // A pole set aside as a smear calls for the fit, and says so.
        let smear = Mode {
            mpc: 0.1,
            ..mode(150.0, 0.04)
        };
        let why = reasons(&light, &[smear], &[], rule);
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
            DiscretizationCorrection::from_ladder(&[point(10.0, 1.04), point(40.0, 1.01)], 0);
        assert!((corr.factor(5.0).re - 1.04).abs() < 1e-12);
        assert!((corr.factor(80.0).re - 1.01).abs() < 1e-12);
        let mid = corr.factor(20.0).re;
        let expected = (0.5 * (1.04f64.ln() + 1.01f64.ln())).exp();
        assert!((mid - expected).abs() < 1e-12, "{mid}");
        let own = 0.25 * 0.5 * (1.04f64.ln() + 1.01f64.ln());
        assert!((corr.rel_sd[0] - own).abs() < 1e-12, "{:?}", corr.rel_sd);
        // A mode the ladder did not converge within its tolerance corrects by its estimate.
        let mut missed = point(10.0, 1.04);
        missed.ladder_estimate = missed.layered_convergence.take();
        let estimated = DiscretizationCorrection::from_ladder(&[missed], 0);
        assert!(
            (estimated.factor(10.0).re - 1.04).abs() < 1e-12,
            "{estimated:?}"
        );
        // Modes weigh by |S|²: two that barely feel the core (S = 0.2) and want 10 % do not
        // move the line of two that feel it fully and want 2 %.
        let weighted = |freq_hz: f64, ln_c: f64, s: f64| {
            let mut p = point(freq_hz, ln_c.exp());
            if let Some(c) = p.layered_convergence.as_mut() {
                c.sensitivity = Complex64::new(s, 0.0);
            }
            p
        };
        let heavy = DiscretizationCorrection::from_ladder(
            &[
                weighted(10.0, 0.02, 1.0),
                weighted(20.0, 0.02, 1.0),
                weighted(30.0, 0.1, 0.2),
                weighted(40.0, 0.1, 0.2),
            ],
            0,
        );
        assert!(
            (heavy.factor(35.0).re.ln() - 0.02).abs() < 1e-12,
            "{heavy:?}"
        );
        // A finer level: its own correction, with its ladder band in the uncertainty; a level
        // the modes have no correction for gives none.
        let mut finer = point(10.0, 1.04);
        if let Some(c) = finer.layered_convergence.as_mut() {
            c.level_corrections.push(Complex64::new(0.01, 0.002));
            c.storage_band = 0.003;
        }
        let one = DiscretizationCorrection::from_ladder(std::slice::from_ref(&finer), 1);
        assert!((one.factor(10.0).ln() - Complex64::new(0.01, 0.002)).norm() < 1e-12);
        assert!((one.rel_sd[0] - (0.003f64 / 1.96).hypot(0.0025)).abs() < 1e-12);
        let beyond = DiscretizationCorrection::from_ladder(&[finer], 2);
        assert!(beyond.modes.is_empty());
        assert_eq!(beyond.factor(10.0), Complex64::new(1.0, 0.0));
        // Three modes on a line and one off it: the line holds the three, the outlier widens
        // the band.
        let bent = DiscretizationCorrection::from_ladder(
            &[
                point(10.0, 1.04),
                point(20.0, 1.02),
                point(40.0, 1.0),
                point(30.0, 0.93),
            ],
            0,
        );
        let on_line = |f: f64| 1.04f64.ln() * (1.0 - (f / 10.0).ln() / 4f64.ln());
        assert!((bent.factor(20.0).re.ln() - on_line(20.0)).abs() < 0.002);
        assert!(bent.rel_sd[0] > corr.rel_sd[0]);
        let none = DiscretizationCorrection::from_ladder(&[at(10.0)], 0);
        assert_eq!(none.factor(10.0), Complex64::new(1.0, 0.0));
    }
}
