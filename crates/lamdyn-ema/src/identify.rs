//! The whole identification of an FRF set: LSCF poles at every order → stabilization diagram →
//! physical poles (automatic, or near given frequencies) → pole refinement and residues (LSFD
//! with residual terms) → modes with damping, shapes (each from the lines around its pole,
//! [`crate::local_residues`]) and indicators, the regenerated FRFs' correlation with the
//! measured ones, and the CMIF.

use crate::columns::{
    HeldPoles, PutBack, exchanged_into_columns, in_their_columns, left_their_columns,
};
use crate::context::{Estimate, LscfContext, RefinementCheck};
use crate::error::{EmaError, invalid};
use crate::local_refit::{RefitBand, refitted_alone};
use crate::local_residues::local_residues;
use crate::lscf::{
    LscfSettings, half_power_bands_overlap, lscf, pole_damping, pole_freq_hz, sample_interval,
};
use crate::lsfd::{
    ModalFit, PoleSd, RefineLines, lsfd, pole_deviations, refined_poles, refinement_lines, shape_of,
};
use crate::noise::CurveNoise;
use crate::projection::LineSamples;
use crate::quality::{
    Contributions, Measured, ModeEvidence, ModeQuality, SecondShape, assess, contributions,
    second_shape_calibrated,
};
use crate::second_shape::second_shapes;
use crate::shapes::{
    CmifPeak, cmif_line, cmif_peaks, mac, mpc, mpd, real_mode, to_unit, transposed_indices,
};
use crate::spectra::correct_exponential_window;
use crate::stabilization::{
    CmifCurvePeaks, DiagramPole, Pick, SelectedPole, StabilityCriteria, diagram, explains,
    rescue_cmif_peaks, select_auto, select_near, top_order_stable,
};
use lamdyn_frf::FrfSet;
use num_complex::Complex64;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Settings of [`identify`].
#[derive(Debug, Clone, PartialEq)]
pub struct EmaSettings {
    /// Band [f_lo, f_hi], Hz (default: the set's lines above 0 Hz).
    pub band_hz: Option<[f64; 2]>,
    /// Lowest, highest model order and step (default 2, 60, 2: the orders of sdypy-EMA's
    /// `pol_order_high = 30`).
    pub orders: (usize, usize, usize),
    /// Stability tolerances.
    pub criteria: StabilityCriteria,
    /// With several references: PolyMAX (pLSCF, the references of each response modelled
    /// jointly) when true, single-reference LSCF over every curve when false.
    pub polymax: bool,
    /// Mode vectors in the diagram (the vector stability criterion).
    pub mode_vectors: bool,
    /// Pick the stable pole nearest each of these frequencies (Hz) instead of the automatic
    /// selection.
    pub near_hz: Option<Vec<f64>>,
    /// Window around each `near_hz` and `reject_hz` frequency, Hz.
    pub window_hz: f64,
    /// Poles to reject (support resonances, rigid-body modes on soft supports), Hz: the modes
    /// within `window_hz` of one stay in the modal model (they shape the regenerated FRFs) but
    /// are reported apart, not as structural modes.
    pub reject_hz: Vec<f64>,
    /// Levenberg–Marquardt iterations of the pole refinement (0: LSFD on the diagram's poles).
    pub refine_iterations: usize,
    /// How the selected poles are finally estimated.
    pub estimator: PoleEstimator,
    /// The lines the refinement's iterations fit (long records: the poles' neighbourhoods and
    /// a thinned band; the residues always on every line).
    pub refine_lines: RefineLines,
    /// Index of the driving-point response (mass-normalised shapes), if any.
    pub driving: Option<usize>,
    /// Time constant of an exponential window applied to the data, s: its damping is removed
    /// from the identified poles.
    pub exp_tau_s: Option<f64>,
    /// The CMIF peaks listed are those whose topographic prominence within the band is at
    /// least this ratio (2: 6 dB; `shapes::cmif_peaks`).
    pub cmif_prominence: f64,
}

impl Default for EmaSettings {
    fn default() -> Self {
        Self {
            band_hz: None,
            orders: (2, 60, 2),
            criteria: StabilityCriteria::default(),
            polymax: true,
            mode_vectors: true,
            near_hz: None,
            window_hz: 1.0,
            reject_hz: vec![],
            refine_iterations: 30,
            estimator: PoleEstimator::default(),
            refine_lines: RefineLines::default(),
            driving: None,
            exp_tau_s: None,
            cmif_prominence: 2.0,
        }
    }
}

/// The final estimate of each selected pole.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PoleEstimator {
    /// The diagram's pole.
    Diagram,
    /// The refined pole (the output error beside real residual terms and the outside model:
    /// pseudo-modes above the band, the LSCF model's roots below it; [`crate::lsfd`]),
    /// unchecked.
    Refined,
    /// The refined pole where the LSCF model's context says it fits the curves significantly
    /// better than the diagram's, the diagram's pole elsewhere ([`crate::context`]).
    Checked,
    /// With several responses: the joint fit of the poles and each mode's participation
    /// factors with rank-one residues (shape times participation, module `rank_one`), beside
    /// the modes the selection left out that the curves need; with one reference each mode's
    /// residues over the responses are free, and each fitted pole is then checked as
    /// [`Self::Checked`] checks the refined ones. With one response (a roving hammer's one
    /// accelerometer), as [`Self::Checked`].
    #[default]
    RankOne,
}

impl PoleEstimator {
    /// The estimator that runs on curves of `responses`: [`Self::RankOne`] needs several and is
    /// [`Self::Checked`] on one; the others run as they are.
    pub fn on(self, responses: usize) -> Self {
        match self {
            Self::RankOne if responses < 2 => Self::Checked,
            e => e,
        }
    }
}

/// One identified mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Mode {
    /// Natural frequency |λ|/2π, Hz.
    pub freq_hz: f64,
    /// Viscous damping ratio ζ.
    pub damping_ratio: f64,
    /// Loss factor η = 2ζ (hysteretic equivalent at resonance).
    pub loss_factor: f64,
    /// Pole λ, rad/s (exponential-window damping removed).
    pub pole: Complex64,
    /// Stable poles in its column of the diagram (for a pole picked near a given frequency: the
    /// stable poles within the window).
    pub stable_count: usize,
    /// Complex shape over the responses (reference 0; mass-normalised with a driving point), or
    /// over the references when there is one response and several (a roving hammer).
    pub shape: Vec<Complex64>,
    /// Modal participation factors over the references: the dominant right singular vector of
    /// the mode's residue matrix (responses × references), largest component 1.
    pub participation: Vec<Complex64>,
    /// Real mode closest to the shape.
    pub real_shape: Vec<f64>,
    /// Modal phase collinearity.
    pub mpc: f64,
    /// Mean phase deviation, degrees.
    pub mpd_deg: f64,
    /// Standard deviations of `freq_hz` and `damping_ratio` from the noise of the fit
    /// ([`crate::lsfd::pole_deviations`]; None without refinement or where the covariance is
    /// singular). The noise's part of the error only: not the estimator's bias.
    #[serde(default)]
    pub sd: Option<PoleSd>,
    /// How its pole was selected (what `stable_count` counts).
    #[serde(default)]
    pub pick: Pick,
    /// The diagram's pole it started from, rad/s (exponential-window damping removed): equal
    /// to `pole` where the diagram's pole was kept ([`PoleEstimator`]).
    #[serde(default)]
    pub diagram_pole: Complex64,
    /// Whether `pole` is the refined pole (false: the diagram's).
    #[serde(default)]
    pub refined: bool,
    /// The pole the refinement reached from `diagram_pole` and what became of it; None where
    /// no refinement ran (`--no-refine`, `--poles diagram`).
    #[serde(default)]
    pub refinement: Option<Refinement>,
    /// The verdict on it: sound, doubtful or a smear over a cluster ([`crate::quality`]).
    #[serde(default)]
    pub quality: ModeQuality,
}

/// What the refinement made of a mode's diagram pole.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Refinement {
    /// The pole it reached, rad/s (exponential-window damping removed), taken or not.
    pub pole: Complex64,
    /// What became of it.
    pub outcome: RefinementOutcome,
}

/// Whether the refined pole is the mode's, and why not.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RefinementOutcome {
    /// It is the mode's pole.
    Taken,
    /// The check found it no significantly better than the diagram's ([`crate::context`]).
    NotBetter,
    /// It left its column in the diagram; the diagram's pole was put back.
    LeftItsColumn,
    /// Its diagram pole's half-power band overlaps that of a pole that left its column; the
    /// diagram's pole was put back.
    BesideALostPole,
}

impl From<PutBack> for RefinementOutcome {
    fn from(p: PutBack) -> Self {
        match p {
            PutBack::LeftItsColumn => Self::LeftItsColumn,
            PutBack::BesideALostPole => Self::BesideALostPole,
        }
    }
}

/// Everything [`identify`] found.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EmaResult {
    /// Band used, Hz.
    pub band_hz: [f64; 2],
    /// The stabilization diagram.
    pub diagram: Vec<DiagramPole>,
    /// The modes, increasing frequency.
    pub modes: Vec<Mode>,
    /// Modes rejected by `reject_hz` (still in the modal model).
    pub rejected: Vec<Mode>,
    /// Modes set aside as smears over clusters ([`EmaResult::set_aside_smears`]; still in the
    /// modal model).
    #[serde(default)]
    pub set_aside: Vec<Mode>,
    /// MAC between the modes' shapes.
    pub auto_mac: Vec<Vec<f64>>,
    /// FRAC of each regenerated curve (response-major, then reference) over the band.
    pub correlation: Vec<f64>,
    /// Curve labels `response@reference`, in the order of `correlation`.
    pub curve_names: Vec<String>,
    /// CMIF singular values per line (largest first).
    pub cmif: Vec<Vec<f64>>,
    /// Peaks of the first CMIF in the band.
    pub cmif_peaks: Vec<CmifPeak>,
    /// Frequencies asked for (`near_hz`) where no stable pole was found.
    pub missing_hz: Vec<f64>,
    /// The modal model (poles as identified, before the window correction).
    #[serde(skip)]
    pub fit: Option<ModalFit>,
    /// What the identification noticed (refined poles that left their column, ...).
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Wall-clock time of each step (zero in a result stored before they were kept).
    #[serde(default)]
    pub timings: EmaTimings,
    /// Whether the second-shape test judged the modes ([`crate::quality`]: the data calibrate
    /// it); where not, each mode's statistics are reported and judge nothing.
    #[serde(default)]
    pub second_shape_calibrated: bool,
}

/// Wall-clock seconds of each step of [`identify`]; a step run twice (the fit after split modes
/// are merged) counts both times.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct EmaTimings {
    /// The LSCF at every order and the stabilization diagram.
    pub diagram: f64,
    /// The CMIF, its peaks and the selection of poles; each curve's noise level (for the check
    /// and the second-shape test), estimated beside the CMIF.
    pub selection: f64,
    /// The poles' refinement (Levenberg–Marquardt with the residues eliminated); with the
    /// refined estimator, the residues of its poles; with the checked one, the check's context
    /// model too, built on another thread meanwhile.
    pub refinement: f64,
    /// The check of each refined pole in the LSCF model's context (after its model), and the
    /// residues of the poles it takes.
    pub check: f64,
    /// The residues of the diagram's poles (without refinement), and those fitted again where
    /// a refined pole left its column and was put back.
    pub residues: f64,
    /// The poles' standard deviations, computed on another thread beside the modes' evidence:
    /// their time lies within [`Self::modes`] and is not added to [`Self::total`].
    pub deviations: f64,
    /// Shapes, quality verdicts and the regenerated FRFs' correlation, with the poles' standard
    /// deviations computed meanwhile.
    pub modes: f64,
}

impl EmaTimings {
    /// The steps' labels and seconds, in the order they run.
    pub fn steps(&self) -> [(&'static str, f64); 7] {
        [
            ("diagram", self.diagram),
            ("selection", self.selection),
            ("refinement", self.refinement),
            ("check", self.check),
            ("residues", self.residues),
            ("deviations", self.deviations),
            ("modes", self.modes),
        ]
    }

    /// The wall-clock time of the steps: their sum but the deviations (within the modes').
    pub fn total(&self) -> f64 {
        self.diagram + self.selection + self.refinement + self.check + self.residues + self.modes
    }
}

/// The power of two 2^−e that brings the largest magnitude of `curves` over the band's `lines`
/// into [1, 2): FRFs in any unit (1e±100 would overflow or underflow in the LSCF's sums of
/// products) are identified at a unit scale. A power of two scales every value exactly, so the
/// poles of the scaled curves are those of the curves, bit for bit, and the residues and CMIF
/// scale back exactly.
///
/// # Errors
/// [`EmaError::Invalid`] when every curve is zero over the band.
fn unit_scale(curves: &[&[Complex64]], lines: &[usize], band: [f64; 2]) -> Result<f64, EmaError> {
    // The largest of `value` over each curve's band lines, the curves in parallel.
    let largest_of = |value: &(dyn Fn(Complex64) -> f64 + Sync)| {
        curves
            .par_iter()
            .map(|c| lines.iter().map(|&k| value(c[k])).fold(0.0, f64::max))
            .reduce(|| 0.0, f64::max)
    };
    // |z| ≥ max(|Re z|, |Im z|) ≥ |z|/√2: only values whose larger component is within √2 of
    // the largest component can hold the largest modulus (its hypot is slow on every line).
    // The bound is taken 1e-9 under m/√2, so its rounding cannot leave that value out.
    let component = |v: Complex64| v.re.abs().max(v.im.abs());
    let largest_component = largest_of(&component);
    let bound = largest_component * std::f64::consts::FRAC_1_SQRT_2 * (1.0 - 1e-9);
    let largest = largest_of(&|v| if component(v) >= bound { v.norm() } else { 0.0 });
    if largest == 0.0 {
        return Err(invalid(
            "FRFs",
            format!(
                "every FRF is zero over the band {}-{} Hz: there is nothing to identify (a unit or \
                 channel mapping lost on export?)",
                band[0], band[1]
            ),
        ));
    }
    Ok(to_unit(largest))
}

/// One warning per curve that is zero over the band's `lines` (a dead channel, or one that
/// was never connected): it takes no part in the poles and its shape entries are zero.
fn zero_curves(
    curves: &[&[Complex64]],
    lines: &[usize],
    names: &[String],
    band: [f64; 2],
) -> Vec<String> {
    curves
        .par_iter()
        .zip(names)
        .filter(|(c, _)| lines.iter().all(|&k| c[k] == Complex64::new(0.0, 0.0)))
        .map(|(_, name)| {
            format!(
                "the FRF {name} is zero over the band {}-{} Hz: a dead or unconnected channel?",
                band[0], band[1]
            )
        })
        .collect()
}

/// Seconds since `clock` started, restarting it.
fn lap(clock: &mut Instant) -> f64 {
    let t = clock.elapsed().as_secs_f64();
    *clock = Instant::now();
    t
}

impl EmaResult {
    /// Moves the modes judged smears over clusters of modes ([`crate::quality::Verdict::Smear`])
    /// from `modes` to `set_aside`, the auto-MAC recomputed: their frequency and damping
    /// describe no mode, and what reads `modes` (a chain's inverses) should not take them.
    /// They stay in the modal model (`fit`, `correlation`). Returns how many were moved.
    pub fn set_aside_smears(&mut self) -> usize {
        let (smears, modes): (Vec<Mode>, Vec<Mode>) = std::mem::take(&mut self.modes)
            .into_iter()
            .partition(|m| m.quality.verdict == crate::quality::Verdict::Smear);
        self.modes = modes;
        self.auto_mac = auto_mac(&self.modes);
        let n = smears.len();
        self.set_aside.extend(smears);
        n
    }
}

/// MAC between the modes' shapes.
fn auto_mac(modes: &[Mode]) -> Vec<Vec<f64>> {
    modes
        .iter()
        .map(|a| modes.iter().map(|b| mac(&a.shape, &b.shape)).collect())
        .collect()
}

/// The band lies inside the data's lines: a band beyond the last line (or before the first)
/// is refused with both ranges, and a hint when the data end far below the band (a time
/// column in ms read as s gives lines a thousand times too low).
fn check_band_in_data(band: [f64; 2], freqs: &[f64]) -> Result<(), EmaError> {
    let (first, last) = (freqs[0], freqs[freqs.len() - 1]);
    let [lo, hi] = band;
    if lo >= hi {
        return Err(invalid("band", format!("[{lo}, {hi}] Hz is empty")));
    }
    if hi <= last * (1.0 + 1e-9) && lo >= first * (1.0 - 1e-9) {
        return Ok(());
    }
    let mut why = format!("[{lo}, {hi}] Hz reaches beyond the data's lines, {first} to {last} Hz");
    if last < 0.1 * lo || last < 0.01 * hi {
        why += ": the data end far below the band; is the time column in s (not ms) and the \
                sampling as recorded?";
    }
    Err(invalid("band", why))
}

/// How far from a CMIF peak (relative, each side) the poles of a mode the selection missed
/// are looked for ([`rescue_cmif_peaks`]): three times the default frequency tolerance.
const CMIF_REACH: f64 = 0.03;

/// Two poles whose shapes agree to at least this MAC and whose half-power bands overlap are
/// one mode split in two ([`merge_split_modes`]).
const SPLIT_MAC: f64 = 0.9;

/// The peaks of the CMIF's `curve`-th singular value (1: the first) over the band's lines
/// `in_band` (prominence ratio `prominence`); none where the FRF matrix has fewer singular
/// values (one reference has one).
fn cmif_curve_peaks(
    freqs: &[f64],
    cmif: &[Vec<f64>],
    in_band: &[usize],
    prominence: f64,
    curve: usize,
) -> Vec<CmifPeak> {
    let Some(values) = cmif
        .iter()
        .map(|v| v.get(curve - 1).copied())
        .collect::<Option<Vec<f64>>>()
    else {
        return vec![];
    };
    match (in_band.first(), in_band.last()) {
        (Some(&a), Some(&b)) => cmif_peaks(&freqs[a..=b], &values[a..=b], prominence),
        _ => vec![],
    }
}

/// The automatic selection ([`select_auto`]) with the modes behind the CMIF peaks it leaves
/// unexplained ([`rescue_cmif_peaks`]: the first curve's `first` and the second's `second`),
/// one warning per pole so added.
fn select_with_cmif(
    diag: &[DiagramPole],
    first: &[CmifPeak],
    second: &[CmifPeak],
    c: &StabilityCriteria,
    warnings: &mut Vec<String>,
) -> Vec<SelectedPole> {
    let mut selected = select_auto(diag, c);
    for (curve, peaks) in [(1, first), (2, second)] {
        let freqs_hz: Vec<f64> = peaks.iter().map(|p| p.freq_hz).collect();
        let peaks = CmifCurvePeaks {
            curve,
            freqs_hz: &freqs_hz,
        };
        for p in rescue_cmif_peaks(diag, &mut selected, peaks, c, CMIF_REACH) {
            let which = if curve == 1 {
                "the CMIF"
            } else {
                "the second CMIF curve (a close pair)"
            };
            warnings.push(format!(
                "a peak of {which} had no stable pole: the pole at {:.4} Hz (zeta {:.3} %) is \
                 taken from a column of {} poles stable in frequency but not in damping or mode \
                 vector",
                p.freq_hz,
                100.0 * p.damping,
                p.count
            ));
        }
    }
    selected
}

/// One warning per peak of the CMIF's second curve (`second`) that a single mode of `modes`
/// explains ([`explains`]): two modes respond together there, and one was found.
fn lone_modes_at_second_peaks(
    modes: &[Mode],
    second: &[CmifPeak],
    c: &StabilityCriteria,
) -> Vec<String> {
    second
        .iter()
        .filter(|p| {
            let near = modes
                .iter()
                .filter(|m| explains(m.freq_hz, m.damping_ratio, p.freq_hz, c))
                .count();
            near == 1
        })
        .map(|p| {
            format!(
                "the CMIF's second curve peaks at {:.4} Hz, where one mode was found: two modes \
                 respond together there (a close pair); pick them with --near-hz, or raise the \
                 model order",
                p.freq_hz
            )
        })
        .collect()
}

/// The curves an identification fits.
#[derive(Clone, Copy)]
struct BandCurves<'a> {
    /// The lines, Hz.
    freqs_hz: &'a [f64],
    /// The curves at unit scale.
    curves: &'a [&'a [Complex64]],
    quantity: lamdyn_frf::Quantity,
    /// The band, Hz.
    band_hz: [f64; 2],
    /// Each curve's noise level over the band's positive lines.
    noise: &'a CurveNoise,
    /// References per response (the curves response-major).
    references: usize,
}

impl<'a> BandCurves<'a> {
    /// The curves `curves` of `set` (at unit scale) in `band_hz`, their noise levels `noise`.
    fn of(
        set: &'a FrfSet,
        curves: &'a [&'a [Complex64]],
        band_hz: [f64; 2],
        noise: &'a CurveNoise,
    ) -> Self {
        Self {
            freqs_hz: set.freqs_hz(),
            curves,
            quantity: set.quantity(),
            band_hz,
            noise,
            references: set.references().len(),
        }
    }

    /// The curves at the lines `lines`, for the modes' contributions.
    fn on_lines(&self, lines: &'a [usize]) -> Measured<'a> {
        Measured {
            freqs_hz: self.freqs_hz,
            curves: self.curves,
            lines,
        }
    }
}

/// The modal model of the selected poles by `s.estimator` (the diagram's poles when
/// `s.refine_iterations` is 0; the check needs `context`, without it the refined poles are
/// taken), the refined poles first put back into their columns ([`in_their_columns`], with one
/// warning per pole that left its column).
fn fit_selected(
    data: BandCurves<'_>,
    selected: &[SelectedPole],
    context: Option<&LscfContext>,
    top: &[Complex64],
    s: &EmaSettings,
    on_stage: &dyn Fn(&str),
    timings: &mut EmaTimings,
) -> Result<SelectedFit, EmaError> {
    let BandCurves {
        freqs_hz: freqs,
        curves,
        quantity,
        band_hz: band,
        ..
    } = data;
    let mut clock = Instant::now();
    let poles: Vec<Complex64> = selected.iter().map(|p| p.pole).collect();
    let n = poles.len();
    let progress = |k: usize, max: usize| {
        on_stage(&format!(
            "refining {n} poles: iteration {k} of at most {max}"
        ))
    };
    let responses = curves.len() / data.references.max(1);
    let estimator = if s.refine_iterations == 0 {
        PoleEstimator::Diagram
    } else {
        s.estimator.on(responses)
    };
    let refine = || refined_jointly(data, selected, context, s, &progress);
    let fitted = match (estimator, context) {
        (PoleEstimator::Diagram, _) => {
            on_stage("residues (LSFD)");
            let fit = lsfd(freqs, curves, quantity, &poles, band)?;
            timings.residues += lap(&mut clock);
            SelectedFit {
                fit,
                warnings: vec![],
                refined: None,
                deviations: None,
                beside: vec![],
                spreads: vec![],
            }
        }
        (PoleEstimator::Checked, Some(c)) => {
            checked_selected(data, selected, c, s, timings, refine, None)?
        }
        (PoleEstimator::RankOne, _) => {
            on_stage(&if data.references < 2 {
                format!("fitting {n} poles with their residues (variable projection)")
            } else {
                format!("fitting {n} poles and their participation factors (rank-one residues)")
            });
            rank_one_selected(data, selected, context, top, s, timings, &progress)?
        }
        _ => {
            let refined = refine()?;
            let held = in_their_columns(&refined.poles, selected, &s.criteria);
            timings.refinement += lap(&mut clock);
            let fit = lsfd(freqs, curves, quantity, &held.poles, band)?;
            timings.residues += lap(&mut clock);
            SelectedFit::refined(fit, refined.poles, held)
        }
    };
    Ok(fitted)
}

/// The modal model of the `selected` poles by the rank-one fit ([`rank_one_refined`], each
/// pole put back where it left its column, [`in_their_columns`]), with the fit's own standard
/// deviations. With one reference each mode's residues over the responses are free, and the
/// fit leans on the model's outside terms as the refinement does (on exact FRFs of damped modes
/// near the band's upper edge it moves the diagram's exact poles): there each fitted pole is
/// checked in the LSCF model's `context` as [`PoleEstimator::Checked`] checks the refined ones
/// (kept where it fits the curves significantly better than the diagram's; the fit refits no
/// pole alone, module `local_refit`: docs/ema.md, "One reference: the modes left out"), and
/// where the check keeps the diagram's pole in its column, the checked estimator's refined pole
/// ([`refined_jointly`]: the joint refinement, each lone pole refitted on its own lines) is
/// checked in its place ([`checked_selected`]): the rank-one fit may resolve two modes where the
/// context has one pole (a second mode under a pole), and one pole over the pair is all the
/// context can judge (docs/ema.md, "Where the fit and the context disagree"). The deviations
/// are then [`pole_deviations`]' at the poles taken.
/// `on_iteration` counts the fit's steps.
///
/// # Errors
/// As [`lsfd`].
fn rank_one_selected(
    data: BandCurves<'_>,
    selected: &[SelectedPole],
    context: Option<&LscfContext>,
    top: &[Complex64],
    s: &EmaSettings,
    timings: &mut EmaTimings,
    on_iteration: &dyn Fn(usize, usize),
) -> Result<SelectedFit, EmaError> {
    if let Some(c) = context.filter(|_| data.references < 2) {
        let (mut warnings, mut beside, mut spreads) = (vec![], vec![], vec![]);
        let rank_one = || {
            let joint = rank_one_refined(data, selected, top, s, on_iteration)?;
            warnings = joint.warnings;
            beside = joint.beside;
            spreads = joint.spreads;
            let alone = vec![false; joint.poles.len()];
            Ok(RefinedPoles {
                poles: joint.poles,
                alone,
            })
        };
        let jointly = || refined_jointly(data, selected, Some(c), s, &|_, _| {});
        let mut fitted = checked_selected(data, selected, c, s, timings, rank_one, Some(&jointly))?;
        fitted.warnings.extend(warnings);
        fitted.beside = beside;
        fitted.spreads = spreads;
        return Ok(fitted);
    }
    let mut clock = Instant::now();
    let joint = rank_one_refined(data, selected, top, s, on_iteration)?;
    let held = in_their_columns(&joint.poles, selected, &s.criteria);
    timings.refinement += lap(&mut clock);
    let fit = lsfd(
        data.freqs_hz,
        data.curves,
        data.quantity,
        &held.poles,
        data.band_hz,
    )?;
    timings.residues += lap(&mut clock);
    let mut fitted = SelectedFit::refined(fit, joint.poles, held);
    fitted.warnings.extend(joint.warnings);
    fitted.deviations = joint.deviations;
    fitted.spreads = joint.spreads;
    fitted.beside = joint.beside;
    Ok(fitted)
}

/// The modal model of the `selected` poles, each pole `refine` returns put back where it left
/// its column ([`in_their_columns`]) and then checked in the LSCF model's `context`
/// ([`RefinementCheck`], built on another thread while `refine` runs): the refined pole where it
/// fits the curves significantly better than the diagram's. Where it does not, and the pole
/// stayed in its column, the `fallback` estimate's pole is checked in its place
/// ([`RefinementCheck::taken_after`]); the diagram's where neither is taken. The fallback runs
/// only there, after the check (run beside `refine` on the other thread whether wanted or not,
/// it made the long records' process slower, where it is never wanted, by more than it made
/// the measured dam's faster: docs/ema.md, "Speed"). The refined pole reported beside each
/// mode is the taken estimate's, `refine`'s elsewhere; where the fallback's is taken,
/// `refine`'s is kept beside it ([`RefinedPole::passed_over`]) and widens the mode's deviation
/// as a refined pole not taken does ([`widened_by_the_refinement`]): the check could not judge
/// it, and the truth may lie by either. The warnings are those of `refine`'s poles that left their columns (the diagram's
/// pole stands there).
///
/// # Errors
/// As [`lsfd`], and what `refine` returns (a `fallback` that fails is not tried).
fn checked_selected(
    data: BandCurves<'_>,
    selected: &[SelectedPole],
    context: &LscfContext,
    s: &EmaSettings,
    timings: &mut EmaTimings,
    refine: impl FnOnce() -> Result<RefinedPoles, EmaError>,
    fallback: Option<&dyn Fn() -> Result<RefinedPoles, EmaError>>,
) -> Result<SelectedFit, EmaError> {
    let poles: Vec<Complex64> = selected.iter().map(|p| p.pole).collect();
    let mut clock = Instant::now();
    let (first, check) = refined_beside_the_check(data, &poles, s.refine_lines, context, refine)?;
    let first_held = in_their_columns(&first.poles, selected, &s.criteria);
    timings.refinement += lap(&mut clock);
    // The scope has run the spawned check; without it (never) the diagram's poles.
    let Some(check) = check else {
        let fit = lsfd_of(data, &poles)?;
        return Ok(SelectedFit::refined(fit, first.poles, first_held));
    };
    let first_taken = check.taken(&first_held.poles, &first.alone);
    let refused = |r: usize| first_held.put_back[r].is_none() && first_taken[r] == poles[r];
    timings.check += lap(&mut clock);
    // Where the fallback fails, the first stands.
    let second = fallback
        .filter(|_| (0..poles.len()).any(refused))
        .and_then(|estimate| estimate().ok());
    timings.refinement += lap(&mut clock);
    let Some(second) = second else {
        let fit = lsfd_of(data, &first_taken)?;
        timings.check += lap(&mut clock);
        return Ok(SelectedFit::refined(fit, first.poles, first_held));
    };
    // The fallback where the first was refused in its column, the diagram's elsewhere.
    let second_held = in_their_columns(&second.poles, selected, &s.criteria);
    let tried: Vec<Complex64> = (0..poles.len())
        .map(|r| {
            if refused(r) {
                second_held.poles[r]
            } else {
                poles[r]
            }
        })
        .collect();
    // The first estimate's poles are judged once, above.
    let second_estimate = Estimate {
        poles: &tried,
        refitted_alone: &second.alone,
    };
    let taken = check.taken_after(first_taken.clone(), second_estimate);
    let fit = lsfd_of(data, &taken)?;
    timings.check += lap(&mut clock);
    let from_second = |r: usize| refused(r) && taken[r] != poles[r] && taken[r] == tried[r];
    let refined = (0..poles.len())
        .map(|r| {
            if from_second(r) {
                RefinedPole {
                    pole: second.poles[r],
                    put_back: None,
                    passed_over: Some(first.poles[r]),
                }
            } else {
                RefinedPole {
                    pole: first.poles[r],
                    put_back: first_held.put_back[r],
                    passed_over: None,
                }
            }
        })
        .collect();
    Ok(SelectedFit {
        fit,
        warnings: first_held.warnings,
        refined: Some(refined),
        deviations: None,
        beside: vec![],
        spreads: vec![],
    })
}

/// The modal model of `poles` over the band of `data` ([`lsfd`]).
///
/// # Errors
/// As [`lsfd`].
fn lsfd_of(data: BandCurves<'_>, poles: &[Complex64]) -> Result<ModalFit, EmaError> {
    lsfd(
        data.freqs_hz,
        data.curves,
        data.quantity,
        poles,
        data.band_hz,
    )
}

/// The rank-one joint fit's poles from the `selected` poles (module `rank_one`) on the
/// refinement's lines, with four times the refinement's iterations (it fits the participation
/// factors too, and a damped pair moves further from the diagram's biased start than one pole
/// does); the selected poles themselves where the residue problem fails. Beside them the fit
/// holds the modes of `top` (the diagram's highest order, stable) that are none of theirs and
/// that the curves need ([`crate::rank_one::left_out`],
/// [`crate::rank_one::fitted_with_the_modes_needed`]): a mode left out of the model would pull
/// its neighbours towards it; with one reference, a second mode under each selected pole that
/// holds a second shape ([`with_a_second_shape`]) is tried too. A selected pole that left its
/// column trades places with a held mode in that column ([`exchanged_into_columns`]).
///
/// # Errors
/// [`EmaError::Invalid`] for a value that is not finite.
fn rank_one_refined(
    data: BandCurves<'_>,
    selected: &[SelectedPole],
    top: &[Complex64],
    s: &EmaSettings,
    on_iteration: &dyn Fn(usize, usize),
) -> Result<JointPoles, EmaError> {
    let diagram: Vec<Complex64> = selected.iter().map(|p| p.pole).collect();
    let poles = diagram.as_slice();
    let candidates = crate::rank_one::left_out(top, poles);
    let around: Vec<Complex64> = poles.iter().chain(&candidates).copied().collect();
    let band_lines = crate::band::positive_lines(data.freqs_hz, data.band_hz);
    let lines = refinement_lines(data.freqs_hz, &band_lines, &around, s.refine_lines);
    let (refs, quantity) = (data.references, data.quantity);
    // The one error the start could raise (a value that is not finite) is raised here.
    let samples = crate::rank_one::StackedCurves::new(
        data.freqs_hz,
        data.curves,
        refs,
        quantity,
        &lines,
        data.band_hz[1],
    )?;
    let start = |set: &[Complex64]| {
        let (freqs, curves) = (data.freqs_hz, data.curves);
        crate::rank_one::start_participation(freqs, curves, refs, quantity, &lines, set)
            .ok()
            .flatten()
    };
    let splittable = if refs == 1 {
        with_a_second_shape(data, poles, &band_lines)
    } else {
        vec![]
    };
    let fit = crate::rank_one::fitted_with_the_modes_needed(
        &samples,
        poles,
        &candidates,
        &splittable,
        start,
        4 * s.refine_iterations,
        on_iteration,
    );
    let Some(crate::rank_one::HeldFit { fit, found_beside }) = fit else {
        return Ok(JointPoles {
            poles: poles.to_vec(),
            warnings: vec![],
            deviations: None,
            spreads: vec![],
            beside: vec![],
        });
    };
    let n = poles.len();
    let order = exchanged_into_columns(&fit.poles, selected, &s.criteria);
    // The fitted poles in their original order: a selected pole's fit is at its own index.
    let fitted = &fit.poles;
    let traded = (0..n)
        .filter(|&r| order[r] >= n)
        .map(|r| traded_places(selected[r].freq_hz, fitted[r], fitted[order[r]]));
    let held = order[n..]
        .iter()
        .filter(|&&k| k >= n)
        .map(|&k| match found_beside[k - n] {
            Some(r) => held_found_beside(selected[r].freq_hz, fitted[k]),
            None => held_beside(fitted[k]),
        });
    let warnings = traded.chain(held).collect();
    let beside = order[n..].iter().map(|&k| fitted[k]).collect();
    let fit = fit.in_order(&order[..n]);
    Ok(JointPoles {
        poles: fit.poles,
        warnings,
        deviations: fit.deviations,
        spreads: fit.spreads,
        beside,
    })
}

/// The indices of `poles` under which the curves of `data` hold a second shape on the band's
/// positive `lines` ([`second_shapes`], [`crate::quality::shows_a_second_shape`]), where the
/// data calibrate that test ([`second_shape_calibrated`]: the modal model holds to the noise at
/// the other poles); none elsewhere. On measured curves whose misfit is not noise every pole
/// shows one, and a mode tried under each would fit the misfit.
fn with_a_second_shape(data: BandCurves<'_>, poles: &[Complex64], lines: &[usize]) -> Vec<usize> {
    let tests = second_shapes(poles, data.on_lines(lines), data.noise);
    if !second_shape_calibrated(&tests) {
        return vec![];
    }
    (0..poles.len())
        .filter(|&r| tests[r].is_some_and(|t| crate::quality::shows_a_second_shape(&t)))
        .collect()
}

/// The rank-one fit's poles: those of the selection (index-aligned) with their standard
/// deviations, and one warning per mode it held beside them and per place a held mode took.
struct JointPoles {
    poles: Vec<Complex64>,
    warnings: Vec<String>,
    deviations: Option<Vec<PoleSd>>,
    /// How far each pole may lie beyond the noise's part of its deviation, rad/s; empty where
    /// the fit failed.
    spreads: Vec<f64>,
    /// The modes the fit held beside the selection, as fitted.
    beside: Vec<Complex64>,
}

/// The warning for the pole selected at `selected_hz` whose fit `ended` (rad/s) outside its
/// column while the mode the fit held at `taken_by` lies in it ([`exchanged_into_columns`]).
fn traded_places(selected_hz: f64, ended: Complex64, taken_by: Complex64) -> String {
    format!(
        "the rank-one fit moved the pole selected at {selected_hz:.2} Hz to {:.2} Hz (damping \
         ratio {:.2} %), out of its column, and the mode it held at {:.2} Hz ({:.2} %) lies in \
         that column: the two trade places, the first held beside the selected ones",
        pole_freq_hz(ended),
        100.0 * pole_damping(ended),
        pole_freq_hz(taken_by),
        100.0 * pole_damping(taken_by)
    )
}

/// The warning for a mode `pole` (rad/s) the rank-one fit held beside the selection.
fn held_beside(pole: Complex64) -> String {
    format!(
        "the rank-one fit held a mode at {:.2} Hz (damping ratio {:.2} %) beside the selected \
         ones: the diagram's highest order has it stable, the selection left it out, and the \
         curves need it; it is not in the mode list (pick it to have it there)",
        pole_freq_hz(pole),
        100.0 * pole_damping(pole)
    )
}

/// The warning for a mode `pole` (rad/s) the rank-one fit held beside the selection that it
/// found beside the pole selected at `selected_hz` (one reference: a second mode under it,
/// [`crate::rank_one::fitted_with_the_modes_needed`]); it may have ended elsewhere, at a mode
/// the diagram lacks.
fn held_found_beside(selected_hz: f64, pole: Complex64) -> String {
    format!(
        "the rank-one fit held a mode at {:.2} Hz (damping ratio {:.2} %) beside the selected \
         ones: no pole of the diagram stands for it, the curves need it, and it was found \
         beside the pole selected at {selected_hz:.2} Hz (with one reference the diagram has one \
         pole over two close damped modes); it is not in the mode list, and the verdicts are \
         made without it",
        pole_freq_hz(pole),
        100.0 * pole_damping(pole)
    )
}

/// The joint refinement's poles ([`refined_poles`], the LSCF model's `context` outside the band
/// where there is one) from the `selected` poles, each that stands alone refitted on its own
/// lines ([`refitted_where_alone`]); `on_iteration` counts the refinement's steps.
///
/// # Errors
/// As [`lsfd`].
fn refined_jointly(
    data: BandCurves<'_>,
    selected: &[SelectedPole],
    context: Option<&LscfContext>,
    s: &EmaSettings,
    on_iteration: &dyn Fn(usize, usize),
) -> Result<RefinedPoles, EmaError> {
    let poles: Vec<Complex64> = selected.iter().map(|p| p.pole).collect();
    let joint = refined_poles(
        data.freqs_hz,
        data.curves,
        data.quantity,
        &poles,
        data.band_hz,
        s.refine_lines,
        s.refine_iterations,
        context,
        on_iteration,
    )?;
    refitted_where_alone(data, joint, selected, s)
}

/// The joint refinement's poles `joint` (index-aligned with `selected`) with each pole that
/// stayed in its column and stands alone refitted on its own lines, the rest of the band's model
/// held at `joint` with the poles that left their columns put back (module `local_refit`); a
/// refit that leaves the column gives way to the joint pole, and the poles put back are as
/// `joint` has them, for the caller's own put-back and warnings. Says which poles are the
/// local step's: the check judges those by their own rule (module `context`, "Poles refitted
/// alone").
///
/// # Errors
/// As [`lsfd`].
fn refitted_where_alone(
    data: BandCurves<'_>,
    joint: Vec<Complex64>,
    selected: &[SelectedPole],
    s: &EmaSettings,
) -> Result<RefinedPoles, EmaError> {
    let held = in_their_columns(&joint, selected, &s.criteria);
    let kept = |r: usize| held.put_back[r].is_none();
    let members: Vec<usize> = (0..joint.len()).filter(|&r| kept(r)).collect();
    // The curves were checked by the joint refinement; the lines are its, around these poles.
    let band_lines = crate::band::positive_lines(data.freqs_hz, data.band_hz);
    let lines = refinement_lines(data.freqs_hz, &band_lines, &held.poles, s.refine_lines);
    let samples = LineSamples::new(data.freqs_hz, data.curves, data.quantity, &lines)?;
    let band = RefitBand {
        upper_hz: data.band_hz[1],
        spacing_hz: crate::band::line_spacing(data.freqs_hz, &band_lines),
    };
    let local = refitted_alone(samples, band, &held.poles, &members, s.refine_iterations);
    let left = left_their_columns(&local, selected, &s.criteria);
    let alone: Vec<bool> = (0..joint.len())
        .map(|r| kept(r) && !left[r] && local[r] != held.poles[r])
        .collect();
    let poles = (0..joint.len())
        .map(|r| if alone[r] { local[r] } else { joint[r] })
        .collect();
    Ok(RefinedPoles { poles, alone })
}

/// The refinement's poles, index-aligned with the selection, and which of them the local step
/// refitted alone ([`refitted_where_alone`]).
struct RefinedPoles {
    poles: Vec<Complex64>,
    alone: Vec<bool>,
}

/// The poles `refine` returns, and the check of the diagram's `poles` built on another thread
/// while this one refines (the check's model needs the diagram's poles only); None in place of
/// the check only where the scope did not run it.
fn refined_beside_the_check<'a, T>(
    data: BandCurves<'a>,
    poles: &[Complex64],
    fit_lines: RefineLines,
    context: &'a LscfContext,
    refine: impl FnOnce() -> Result<T, EmaError>,
) -> Result<(T, Option<RefinementCheck<'a>>), EmaError> {
    let mut check = None;
    let refined = rayon::in_place_scope(|scope| {
        scope.spawn(|_| {
            check = Some(RefinementCheck::new(
                data.freqs_hz,
                data.curves,
                poles,
                data.band_hz,
                fit_lines,
                context,
                data.noise,
            ));
        });
        refine()
    })?;
    Ok((refined, check))
}

/// The modal model of the selected poles ([`fit_selected`]) and what the refinement made of
/// them.
struct SelectedFit {
    fit: ModalFit,
    /// One line per refined pole put back into its column.
    warnings: Vec<String>,
    /// With an estimator that refines: the refined poles, index-aligned with the selection,
    /// taken or not.
    refined: Option<Vec<RefinedPole>>,
    /// The estimator's own standard deviations of the refined poles (the rank-one fit's), in
    /// place of [`pole_deviations`]; None where it has none.
    deviations: Option<Vec<PoleSd>>,
    /// The modes the rank-one fit held beside the selection, as fitted; none with another
    /// estimator.
    beside: Vec<Complex64>,
    /// With the rank-one fit: how far each pole (index-aligned with the selection) may lie
    /// beyond the noise's part of its deviation, rad/s (module `residual_spread`); empty with
    /// another estimator.
    spreads: Vec<f64>,
}

impl SelectedFit {
    /// The fit of the poles `held` to their columns, with the refined poles `refined` it was
    /// chosen from and the warnings of `held`.
    fn refined(fit: ModalFit, refined: Vec<Complex64>, held: HeldPoles) -> Self {
        let refined = refined
            .into_iter()
            .zip(held.put_back)
            .map(|(pole, put_back)| RefinedPole {
                pole,
                put_back,
                passed_over: None,
            })
            .collect();
        Self {
            fit,
            warnings: held.warnings,
            refined: Some(refined),
            deviations: None,
            beside: vec![],
            spreads: vec![],
        }
    }
}

/// A pole as the refinement left it, and why the diagram's was put back in its place.
#[derive(Debug, Clone, Copy)]
struct RefinedPole {
    pole: Complex64,
    put_back: Option<PutBack>,
    /// Where this pole is a fallback estimate's ([`checked_selected`]): the first estimate's
    /// pole, which the check refused; the truth may lie by either.
    passed_over: Option<Complex64>,
}

/// The standard deviation `sd` of a mode whose reported pole `pole` is the diagram's while the
/// refinement found another, at `refined` = (f in Hz, ζ) as far as the pole's column reaches
/// ([`SelectedPole::widening_point`]): widened by the two estimates' difference,
/// √(sd² + (diagram − refined)²), in f and ζ. The check found neither significantly better, or
/// the refinement left the column, so the truth may lie by either; `sd` is the noise's part at
/// `pole` and describes its scatter only. The reach keeps a pole that ran away (to another
/// resonance, or out of the band) from widening the deviation without bound.
fn widened_by_the_refinement(sd: PoleSd, pole: Complex64, refined: (f64, f64)) -> PoleSd {
    let spread = |s: f64, d: f64| s.hypot(d);
    PoleSd {
        freq_hz: spread(sd.freq_hz, pole_freq_hz(pole) - refined.0),
        damping_ratio: spread(sd.damping_ratio, pole_damping(pole) - refined.1),
    }
}

/// The deviations `sd` of `poles` widened by the spread beyond the noise (`spreads`, rad/s,
/// index-aligned) that the rank-one fit's residual holds at each ([`SelectedFit::spreads`],
/// [`PoleSd::widened_by`]): a mode the model lacks under a pole, a weak one beside a strong one
/// that no column shows, biases the pole by far more than the noise's part says. `sd` as it is
/// where there are no spreads.
fn widened_by_the_residual(sd: Vec<PoleSd>, poles: &[Complex64], spreads: &[f64]) -> Vec<PoleSd> {
    if spreads.len() != sd.len() {
        return sd;
    }
    sd.into_iter()
        .zip(poles)
        .zip(spreads)
        .map(|((sd, &pole), &spread)| sd.widened_by(pole, spread))
        .collect()
}

/// [`widened_by_the_refinement`] by the farthest of `points` in f and, apart, in ζ; `sd` itself
/// where there is none.
fn widened_by_the_estimates(sd: PoleSd, pole: Complex64, points: &[(f64, f64)]) -> PoleSd {
    let far = |q: fn(&(f64, f64)) -> f64, at: f64| {
        points
            .iter()
            .map(q)
            .max_by(|a, b| (a - at).abs().total_cmp(&(b - at).abs()))
    };
    let (f, z) = (pole_freq_hz(pole), pole_damping(pole));
    match (far(|p| p.0, f), far(|p| p.1, z)) {
        (Some(pf), Some(pz)) => widened_by_the_refinement(sd, pole, (pf, pz)),
        _ => sd,
    }
}

/// One mode split in two poles: neighbours of `fit` whose half-power bands overlap
/// (|f₁ − f₂| < ζ₁f₁ + ζ₂f₂) and whose residues over every curve agree (MAC ≥ [`SPLIT_MAC`]),
/// or, with fewer than three curves, whose bands overlap (the shapes cannot tell two modes
/// apart there, and one curve cannot resolve two poles that close). Of each such pair the pole
/// with the longer column in `selected` (index-aligned with the fit's poles) is kept, on equal
/// columns the one with the larger residues. The shapes are the fitted ones: at the diagram's
/// poles, a true pair 0.14 % apart (distinct shapes, MAC 0.0 once refined) had residues that
/// agreed. A single swept-sine record of a measured plate gave 446.3 / 452.1 Hz (ζ 3.1 / 3.3 %)
/// for the mode at 450.5 Hz of the four records' average. Returns the poles kept and one line
/// per merge.
fn merge_split_modes(
    selected: Vec<SelectedPole>,
    fit: &ModalFit,
) -> (Vec<SelectedPole>, Vec<String>) {
    let shapes: Vec<Vec<Complex64>> = (0..fit.poles.len()).map(|r| fit.shape(r, None)).collect();
    let few_curves = fit.residues.len() < 3;
    let size = |r: usize| shapes[r].iter().map(|a| a.norm_sqr()).sum::<f64>();
    let mut dropped = vec![false; selected.len()];
    let mut notes = Vec::new();
    for r in 0..selected.len().saturating_sub(1) {
        if dropped[r] {
            continue;
        }
        let (pa, pb) = (fit.poles[r], fit.poles[r + 1]);
        let (fa, fb) = (pole_freq_hz(pa), pole_freq_hz(pb));
        let (za, zb) = (pole_damping(pa), pole_damping(pb));
        let agree = few_curves || mac(&shapes[r], &shapes[r + 1]) >= SPLIT_MAC;
        if !(half_power_bands_overlap(pa, pb) && agree) {
            continue;
        }
        let keep_a = (selected[r].count, size(r)) > (selected[r + 1].count, size(r + 1));
        let (kept_f, kept_count) = if keep_a {
            (fa, selected[r].count)
        } else {
            (fb, selected[r + 1].count)
        };
        dropped[if keep_a { r + 1 } else { r }] = true;
        notes.push(format!(
            "the poles at {fa:.3} Hz and {fb:.3} Hz (zeta {:.2} / {:.2} %) overlap and their \
             shapes agree{}: one mode split in two; the one at {kept_f:.3} Hz ({kept_count} stable \
             poles) is kept and refitted",
            100.0 * za,
            100.0 * zb,
            if few_curves {
                " (fewer than three curves: the shapes cannot tell)"
            } else {
                ""
            },
        ));
    }
    let kept = selected
        .into_iter()
        .zip(dropped)
        .filter(|(_, d)| !d)
        .map(|(p, _)| p)
        .collect();
    (kept, notes)
}

/// Refuses settings that do not fit `set`: a driving point beyond its responses, a CMIF
/// prominence below 1.
fn check_settings(set: &FrfSet, s: &EmaSettings) -> Result<(), EmaError> {
    let nr = set.responses().len();
    if let Some(d) = s.driving {
        if d >= nr {
            return Err(invalid(
                "driving point",
                format!("response index {d}, but the set has {nr} responses"),
            ));
        }
    }
    if s.cmif_prominence.is_nan() || s.cmif_prominence < 1.0 {
        return Err(invalid(
            "CMIF prominence",
            format!(
                "{} must be at least 1 (a factor above the peak's bases)",
                s.cmif_prominence
            ),
        ));
    }
    Ok(())
}

/// Each curve's name, `response@reference`, response-major.
fn curve_names(set: &FrfSet) -> Vec<String> {
    let references = set.references();
    set.responses()
        .iter()
        .flat_map(|r| {
            references
                .iter()
                .map(move |f| format!("{}@{}", r.name, f.name))
        })
        .collect()
}

/// `curves` times `scale`, or `None` at scale 1 (the curves are used as they are).
fn at_scale(curves: &[&[Complex64]], scale: f64) -> Option<Vec<Vec<Complex64>>> {
    (scale != 1.0).then(|| {
        curves
            .par_iter()
            .map(|c| c.iter().map(|v| v * scale).collect())
            .collect()
    })
}

/// The estimator of the stabilization diagram for an FRF matrix of `responses` × `references`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DiagramEstimator {
    /// One LSCF over every curve (a scalar common denominator): one response or one reference,
    /// or PolyMAX turned off.
    Lscf,
    /// PolyMAX, its matrix denominator the smaller side's of the FRF matrix: the references',
    /// or, `transposed`, the responses' where they are fewer (H and Hᵀ have the same poles; a
    /// 9 × 9 denominator for one response and nine hammer points would have nine times the
    /// roots per order).
    PolyMax {
        /// Whether Hᵀ is fitted (the references taken as the outputs).
        transposed: bool,
    },
}

impl DiagramEstimator {
    /// The estimator for `responses` × `references` curves, PolyMAX where `polymax` allows.
    pub fn of(responses: usize, references: usize, polymax: bool) -> Self {
        if !polymax || responses.min(references) <= 1 {
            Self::Lscf
        } else {
            Self::PolyMax {
                transposed: responses < references,
            }
        }
    }
}

/// The stabilization diagram over `s.orders` (PolyMAX over the `references` when
/// `s.polymax`), and the highest order's denominator as the context of the refinement's check.
fn stabilization(
    freqs: &[f64],
    curves: &[&[Complex64]],
    band: [f64; 2],
    references: usize,
    s: &EmaSettings,
    on_stage: &dyn Fn(&str),
) -> Result<(Vec<DiagramPole>, Option<LscfContext>), EmaError> {
    let (lo, hi, step) = s.orders;
    on_stage(&format!(
        "stabilization diagram: orders {lo} to {hi}, {} curves",
        curves.len()
    ));
    let responses = curves.len() / references.max(1);
    let (curves, references) = match DiagramEstimator::of(responses, references, s.polymax) {
        DiagramEstimator::Lscf => (curves.to_vec(), 1),
        DiagramEstimator::PolyMax { transposed: false } => (curves.to_vec(), references),
        DiagramEstimator::PolyMax { transposed: true } => (
            transposed_indices(responses, references)
                .map(|k| curves[k])
                .collect(),
            responses,
        ),
    };
    let orders = lscf(
        freqs,
        &curves,
        &LscfSettings {
            references,
            mode_vectors: s.mode_vectors,
            ..LscfSettings::new(band, (lo, hi, step))
        },
    )?;
    let diag = diagram(&orders, &s.criteria);
    let context = orders.into_iter().last().map(|top| LscfContext {
        dt: sample_interval(band),
        roots: top.roots,
    });
    Ok((diag, context))
}

/// The CMIF at each of `lines` lines: the singular values of the FRF matrix (curves at unit
/// scale `scale`, `references` per response), scaled back.
fn cmif_curves(
    lines: usize,
    curves: &[&[Complex64]],
    references: usize,
    scale: f64,
) -> Vec<Vec<f64>> {
    (0..lines)
        .into_par_iter()
        .map(|k| {
            let h: Vec<Complex64> = curves.iter().map(|c| c[k]).collect();
            let mut sigma = cmif_line(&h, references);
            sigma.iter_mut().for_each(|v| *v /= scale);
            sigma
        })
        .collect()
}

/// The selected poles and the given frequencies without one: near `s.near_hz` when given
/// ([`select_near`]), else automatic with the CMIF's first and second curves' `peaks`
/// ([`select_with_cmif`]).
fn select(
    diag: &[DiagramPole],
    peaks: &[Vec<CmifPeak>; 2],
    s: &EmaSettings,
    warnings: &mut Vec<String>,
) -> (Vec<SelectedPole>, Vec<f64>) {
    let Some(targets) = &s.near_hz else {
        let selected = select_with_cmif(diag, &peaks[0], &peaks[1], &s.criteria, warnings);
        return (selected, vec![]);
    };
    let picks = select_near(diag, targets, s.window_hz);
    let missing = targets
        .iter()
        .zip(&picks)
        .filter(|(_, p)| p.is_none())
        .map(|(t, _)| *t)
        .collect();
    (picks.into_iter().flatten().collect(), missing)
}

/// What the regenerated curves say of the fit's modes ([`crate::quality`]).
struct FitEvidence {
    /// FRAC of each curve and each mode's FRAC drop.
    contributions: Contributions,
    /// Each mode's second-shape test.
    second_shapes: Vec<Option<SecondShape>>,
    /// Whether the data calibrate that test.
    calibrated: bool,
    /// Each mode's residues from the lines around its pole ([`residues_near_each_pole`]).
    local_residues: Vec<Option<Vec<Complex64>>>,
}

impl FitEvidence {
    /// The evidence of `fit` (in the data's units) on `measured` (its curves in the data's
    /// units times `scale`), whose curves' noise levels are `noise`.
    fn of(fit: &ModalFit, measured: Measured, noise: &CurveNoise, scale: f64) -> Self {
        let (second_shapes, (contributions, local_residues)) = rayon::join(
            || second_shapes(&fit.poles, measured, noise),
            || {
                rayon::join(
                    || contributions(fit, measured),
                    || residues_near_each_pole(fit, measured, scale),
                )
            },
        );
        Self {
            contributions,
            calibrated: second_shape_calibrated(&second_shapes),
            second_shapes,
            local_residues,
        }
    }
}

/// What each identified mode is made of ([`ModeSources::mode`]).
struct ModeSources<'a> {
    /// The modal model in the data's units.
    fit: &'a ModalFit,
    settings: &'a EmaSettings,
    responses: usize,
    references: usize,
    /// The selection, index-aligned with the fit's poles.
    selected: &'a [SelectedPole],
    /// With an estimator that refines: the refined poles, taken or not.
    refined: Option<&'a [RefinedPole]>,
    /// The poles' standard deviations.
    deviations: Option<&'a [PoleSd]>,
    /// The modes the rank-one fit held beside the selection ([`SelectedFit::beside`]).
    beside: &'a [Complex64],
    /// Each mode's FRAC drop ([`contributions`]).
    frac_drop: &'a [f64],
    /// Each mode's residues from the lines around its pole ([`local_residues`]), index-aligned
    /// with the fit's poles; None where the fit's own stand.
    local_residues: &'a [Option<Vec<Complex64>>],
    /// Each mode's second-shape test ([`second_shapes`]).
    second_shapes: &'a [Option<SecondShape>],
    /// Whether the data calibrate that test ([`second_shape_calibrated`]).
    second_shape_calibrated: bool,
    line_spacing_hz: f64,
    /// The first CMIF curve's peaks.
    cmif_peaks: &'a [CmifPeak],
}

impl ModeSources<'_> {
    /// The modes the fit held beside the selection whose frequency the column `col` reaches
    /// ([`SelectedPole::reaches_frequency`]), as (Hz, damping ratio): other estimates of the
    /// column's resonance, whatever their damping (as [`SelectedPole::widening_point`] takes a
    /// refined pole).
    fn held_at(&self, col: &SelectedPole) -> Vec<(f64, f64)> {
        let c = &self.settings.criteria;
        self.beside
            .iter()
            .map(|&p| (pole_freq_hz(p), pole_damping(p)))
            .filter(|&(f, _)| col.reaches_frequency(f, c))
            .collect()
    }

    /// Every mode of the fit, split into those `--reject-hz` names (within the window) and
    /// the others: (rejected, modes).
    fn modes(&self) -> (Vec<Mode>, Vec<Mode>) {
        let s = self.settings;
        (0..self.fit.poles.len())
            .map(|r| self.mode(r))
            .partition(|m| {
                s.reject_hz
                    .iter()
                    .any(|f| (m.freq_hz - f).abs() <= s.window_hz)
            })
    }

    /// Mode `r`: its shape over the responses for reference 0 (over the references for a
    /// roving hammer: one response, several references; by reciprocity the residues of the
    /// response to each hammer point) from its local residues (the fit's where it has none),
    /// its pole with the exponential window's damping removed,
    /// its standard deviation (widened where the diagram's pole was kept) and its verdict.
    fn mode(&self, r: usize) -> Mode {
        let (fit, s, nr, nf) = (self.fit, self.settings, self.responses, self.references);
        let residues = self.local_residues[r]
            .clone()
            .unwrap_or_else(|| fit.residues.iter().map(|res| res[r]).collect());
        let participation_factors = crate::shapes::participation(&residues, nr, nf);
        let for_reference = |all: Vec<Complex64>| -> Vec<Complex64> {
            if nr == 1 && nf > 1 {
                all[..nf].to_vec()
            } else {
                (0..nr).map(|i| all[i * nf]).collect()
            }
        };
        let driving = s.driving.map(|d| d * nf);
        let shape = for_reference(shape_of(residues, fit.poles[r], driving));
        let band_shape = for_reference(fit.shape(r, driving));
        let corrected = |p: Complex64| {
            s.exp_tau_s
                .map_or(p, |tau| correct_exponential_window(p, tau))
        };
        let pole = corrected(fit.poles[r]);
        let selected = self.selected.get(r);
        let diagram_pole = selected.map_or(fit.poles[r], |p| p.pole);
        let z = pole_damping(pole);
        let evidence = ModeEvidence {
            freq_hz: pole_freq_hz(pole),
            damping_ratio: z,
            mpc: mpc(&shape),
            band_mpc: mpc(&band_shape),
            mpd_deg: mpd(&shape),
            shape_len: shape.len(),
            stable_count: selected.map_or(0, |p| p.count),
            frac_drop: self.frac_drop[r],
            line_spacing_hz: self.line_spacing_hz,
            second_shape: self.second_shapes.get(r).copied().flatten(),
            second_shape_calibrated: self.second_shape_calibrated,
        };
        let refined = self.refined.and_then(|p| p.get(r));
        let outcome = refined.map(|q| match q.put_back {
            Some(why) => why.into(),
            None if q.pole == fit.poles[r] => RefinementOutcome::Taken,
            None => RefinementOutcome::NotBetter,
        });
        // The refined pole not taken (where a fallback's was, the first estimate's), as far as
        // its column reaches, and where the diagram's pole stands, each mode the fit held beside
        // the selection at the column's frequency: what widens the sd.
        let not_taken = refined.and_then(|q| match outcome {
            Some(RefinementOutcome::Taken) => q.passed_over,
            _ => Some(q.pole),
        });
        let held_here = selected
            .filter(|_| !matches!(outcome, None | Some(RefinementOutcome::Taken)))
            .map(|col| self.held_at(col))
            .unwrap_or_default();
        let points: Vec<(f64, f64)> = not_taken
            .zip(selected)
            .map(|(p, col)| col.widening_point(pole_freq_hz(p), pole_damping(p), &s.criteria))
            .into_iter()
            .chain(held_here)
            .collect();
        let sd = self
            .deviations
            .and_then(|d| d.get(r).copied())
            .map(|sd| widened_by_the_estimates(sd, fit.poles[r], &points));
        Mode {
            freq_hz: evidence.freq_hz,
            damping_ratio: z,
            loss_factor: 2.0 * z,
            pole,
            stable_count: evidence.stable_count,
            real_shape: real_mode(&shape),
            participation: participation_factors,
            mpc: evidence.mpc,
            mpd_deg: evidence.mpd_deg,
            shape,
            sd,
            pick: selected.map_or(Pick::Auto, |p| p.pick),
            diagram_pole: corrected(diagram_pole),
            refined: diagram_pole != fit.poles[r],
            refinement: refined.zip(outcome).map(|(q, outcome)| Refinement {
                pole: corrected(q.pole),
                outcome,
            }),
            quality: assess(&evidence, self.cmif_peaks),
        }
    }
}

/// The band of `s`, by default the data's from its first positive line, checked against the
/// data's lines ([`check_band_in_data`]).
fn band_of(s: &EmaSettings, freqs: &[f64]) -> Result<[f64; 2], EmaError> {
    let band = s.band_hz.unwrap_or([
        freqs.iter().copied().find(|f| *f > 0.0).unwrap_or(0.0),
        freqs[freqs.len() - 1],
    ]);
    check_band_in_data(band, freqs)?;
    Ok(band)
}

/// Every curve of `set`, response-major.
fn set_curves(set: &FrfSet) -> Vec<&[Complex64]> {
    let nf = set.references().len();
    (0..set.responses().len())
        .flat_map(|i| (0..nf).map(move |j| (i, j)))
        .map(|(i, j)| set.curve(i, j))
        .collect()
}

/// The error of a diagram with no stable pole in `band` up to order `highest`.
fn no_stable_pole(band: [f64; 2], highest: usize) -> EmaError {
    invalid(
        "poles",
        format!(
            "no stable pole in [{}, {}] Hz up to order {highest}: raise the order or widen the \
             band",
            band[0], band[1]
        ),
    )
}

/// A note for a roving-hammer test (one response, several references): what the shapes are
/// over.
fn roving_hammer_note(set: &FrfSet) -> Option<String> {
    let nf = set.references().len();
    (set.responses().len() == 1 && nf > 1).then(|| {
        format!(
            "one response and {nf} references (a roving-hammer test): the shapes, MPC, MPD and \
             auto-MAC are over the references (by reciprocity, the residues of the response to \
             each hammer point)"
        )
    })
}

/// The residues of each pole of `fit` (in the data's units) fitted near it ([`local_residues`])
/// on `measured`, curves in the data's units times `scale`.
fn residues_near_each_pole(
    fit: &ModalFit,
    measured: Measured,
    scale: f64,
) -> Vec<Option<Vec<Complex64>>> {
    local_residues(&fit.poles, fit.quantity, measured)
        .into_iter()
        .map(|r| r.map(|r| r.into_iter().map(|a| a / scale).collect()))
        .collect()
}

/// With the automatic selection, the `selected` poles and their `fitted` model after split modes
/// are merged ([`merge_split_modes`], one warning each into `warnings`, the model refitted by
/// `fit_poles`); as they are otherwise.
///
/// # Errors
/// As `fit_poles`.
fn without_split_modes(
    fitted: SelectedFit,
    selected: Vec<SelectedPole>,
    s: &EmaSettings,
    warnings: &mut Vec<String>,
    mut fit_poles: impl FnMut(&[SelectedPole]) -> Result<SelectedFit, EmaError>,
) -> Result<(Vec<SelectedPole>, SelectedFit), EmaError> {
    if s.near_hz.is_some() {
        return Ok((selected, fitted));
    }
    let (fewer, merged) = merge_split_modes(selected, &fitted.fit);
    if merged.is_empty() {
        return Ok((fewer, fitted));
    }
    warnings.extend(merged);
    let refitted = fit_poles(&fewer)?;
    Ok((fewer, refitted))
}

/// The evidence of `fit` (in the data's units) on the positive lines of `data` (its curves
/// at unit scale, the data's units times `scale`; [`FitEvidence::of`]), and beside it on
/// another thread the poles' standard deviations ([`deviations_of`]; `own` where the
/// estimator gave its own): neither needs the other. The whole adds to `timings.modes`, the
/// deviations' own time to `timings.deviations` ([`EmaTimings`]).
///
/// # Errors
/// As [`deviations_of`].
fn evidence_beside_deviations(
    data: BandCurves<'_>,
    fit: &ModalFit,
    own: Option<Vec<PoleSd>>,
    scale: f64,
    s: &EmaSettings,
    on_stage: &dyn Fn(&str),
    timings: &mut EmaTimings,
) -> Result<(FitEvidence, Option<Vec<PoleSd>>), EmaError> {
    if s.refine_iterations > 0 {
        on_stage("the modes' evidence and the poles' standard deviations");
    }
    let clock = Instant::now();
    let (evidence, (deviations, deviations_s)) = rayon::join(
        || {
            let positive = crate::band::positive_lines(data.freqs_hz, data.band_hz);
            FitEvidence::of(fit, data.on_lines(&positive), data.noise, scale)
        },
        || {
            let clock = Instant::now();
            let deviations = match own {
                Some(own) => Ok(Some(own)),
                None => deviations_of(data, &fit.poles, s),
            };
            (deviations, clock.elapsed().as_secs_f64())
        },
    );
    timings.modes += clock.elapsed().as_secs_f64();
    timings.deviations += deviations_s;
    Ok((evidence, deviations?))
}

/// The poles' standard deviations ([`pole_deviations`]) when the settings refine them, else
/// none.
fn deviations_of(
    data: BandCurves<'_>,
    poles: &[Complex64],
    s: &EmaSettings,
) -> Result<Option<Vec<PoleSd>>, EmaError> {
    if s.refine_iterations == 0 {
        return Ok(None);
    }
    let BandCurves {
        freqs_hz,
        curves,
        quantity,
        band_hz,
        ..
    } = data;
    pole_deviations(freqs_hz, curves, quantity, poles, band_hz, s.refine_lines)
}

/// Identifies the modes of `set` (module docs).
///
/// # Errors
/// [`EmaError::Invalid`] for bad bands (beyond the data's lines) or orders ([`lscf`]), no physical
/// pole, or a driving-point index out of range.
pub fn identify(set: &FrfSet, s: &EmaSettings) -> Result<EmaResult, EmaError> {
    identify_with(set, s, &|_| {})
}

/// [`identify`], calling `on_stage` with a line as each step starts (the diagram, each
/// refinement iteration, the residues): progress for a caller to show.
///
/// # Errors
/// As [`identify`].
pub fn identify_with(
    set: &FrfSet,
    s: &EmaSettings,
    on_stage: &dyn Fn(&str),
) -> Result<EmaResult, EmaError> {
    let mut clock = Instant::now();
    let mut timings = EmaTimings::default();
    check_settings(set, s)?;
    let freqs = set.freqs_hz();
    let nf = set.references().len();
    let band = band_of(s, freqs)?;
    let curves = set_curves(set);
    let names = curve_names(set);
    let in_band = crate::band::lines(freqs, band);
    let mut warnings = zero_curves(&curves, &in_band, &names, band);
    let scale = unit_scale(&curves, &in_band, band)?;
    let scaled = at_scale(&curves, scale);
    let curves: Vec<&[Complex64]> = match &scaled {
        Some(owned) => owned.iter().map(Vec::as_slice).collect(),
        None => curves,
    };
    let (diag, context) = stabilization(freqs, &curves, band, nf, s, on_stage)?;
    let top = top_order_stable(&diag);
    timings.diagram = lap(&mut clock);
    let positive = crate::band::positive_lines(freqs, band);
    let (cmif, noise) = rayon::join(
        || cmif_curves(freqs.len(), &curves, nf, scale),
        || CurveNoise::of(&curves, &positive),
    );
    let peaks = [1, 2].map(|k| cmif_curve_peaks(freqs, &cmif, &in_band, s.cmif_prominence, k));
    let (selected, missing_hz) = select(&diag, &peaks, s, &mut warnings);
    if selected.is_empty() {
        return Err(no_stable_pole(band, s.orders.1));
    }
    timings.selection = lap(&mut clock);
    let data = BandCurves::of(set, &curves, band, &noise);
    let fit_poles = |selected: &[SelectedPole], timings: &mut EmaTimings| {
        fit_selected(data, selected, context.as_ref(), &top, s, on_stage, timings)
    };
    let first = fit_poles(&selected, &mut timings)?;
    let (selected, mut fitted) = without_split_modes(first, selected, s, &mut warnings, |p| {
        fit_poles(p, &mut timings)
    })?;
    warnings.extend(std::mem::take(&mut fitted.warnings));
    let scaled_fit = fitted.fit.scaled(1.0 / scale);
    let (evidence, deviations) = evidence_beside_deviations(
        data,
        &scaled_fit,
        fitted.deviations.take(),
        scale,
        s,
        on_stage,
        &mut timings,
    )?;
    let deviations =
        deviations.map(|sd| widened_by_the_residual(sd, &scaled_fit.poles, &fitted.spreads));
    warnings.extend(roving_hammer_note(set));
    clock = Instant::now();
    let sources = ModeSources {
        fit: &scaled_fit,
        settings: s,
        responses: set.responses().len(),
        references: nf,
        selected: &selected,
        refined: fitted.refined.as_deref(),
        deviations: deviations.as_deref(),
        beside: &fitted.beside,
        frac_drop: &evidence.contributions.frac_drop,
        local_residues: &evidence.local_residues,
        second_shapes: &evidence.second_shapes,
        second_shape_calibrated: evidence.calibrated,
        line_spacing_hz: crate::band::line_spacing(freqs, &positive),
        cmif_peaks: &peaks[0],
    };
    let (rejected, modes) = sources.modes();
    if s.near_hz.is_none() {
        warnings.extend(lone_modes_at_second_peaks(&modes, &peaks[1], &s.criteria));
    }
    let auto_mac = auto_mac(&modes);
    let [cmif_peaks, _] = peaks;
    timings.modes += lap(&mut clock);
    Ok(EmaResult {
        band_hz: band,
        diagram: diag,
        auto_mac,
        modes,
        rejected,
        set_aside: vec![],
        correlation: evidence.contributions.frac,
        curve_names: names,
        cmif,
        cmif_peaks,
        missing_hz,
        fit: Some(scaled_fit),
        warnings,
        timings,
        second_shape_calibrated: evidence.calibrated,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sd is widened by the farthest point in f and, apart, in ζ; with no point it stands.
    #[test]
    fn the_deviation_is_widened_by_the_farthest_estimate_in_each_quantity() {
        let pole = crate::lscf::pole_at(100.0, 0.02);
        let sd = PoleSd {
            freq_hz: 0.03,
            damping_ratio: 0.001,
        };
        assert_eq!(widened_by_the_estimates(sd, pole, &[]), sd);
        let points = [(100.4, 0.021), (99.9, 0.05), (100.1, 0.019)];
        let wide = widened_by_the_estimates(sd, pole, &points);
        let f = pole_freq_hz(pole);
        let z = pole_damping(pole);
        assert!((wide.freq_hz - 0.03f64.hypot(100.4 - f)).abs() < 1e-12);
        assert!((wide.damping_ratio - 0.001f64.hypot(0.05 - z)).abs() < 1e-12);
    }

    /// The rank-one fit needs several responses; the rest run as chosen.
    #[test]
    fn the_default_is_the_rank_one_fit_where_there_are_several_responses() {
        let default = PoleEstimator::default();
        assert_eq!(default.on(12), PoleEstimator::RankOne);
        assert_eq!(default.on(1), PoleEstimator::Checked);
        assert_eq!(PoleEstimator::Refined.on(12), PoleEstimator::Refined);
        assert_eq!(PoleEstimator::Diagram.on(12), PoleEstimator::Diagram);
    }

    fn mode_at(freq_hz: f64, damping_ratio: f64) -> Mode {
        let w = 2.0 * std::f64::consts::PI * freq_hz;
        let pole = Complex64::new(-damping_ratio * w, w);
        Mode {
            freq_hz,
            damping_ratio,
            loss_factor: 2.0 * damping_ratio,
            pole,
            stable_count: 10,
            shape: vec![],
            participation: vec![],
            real_shape: vec![],
            mpc: 1.0,
            mpd_deg: 0.0,
            sd: None,
            pick: Pick::Auto,
            diagram_pole: pole,
            refined: false,
            refinement: None,
            quality: ModeQuality::default(),
        }
    }

    /// A peak of the second CMIF curve with one mode near it is said (a pair's second mode
    /// was not found); with two modes near it, or none (a crossing of two modes' curves far
    /// from both), nothing is said.
    #[test]
    fn a_lone_mode_at_a_second_curve_peak_is_said() {
        let c = StabilityCriteria::default();
        let peak = |freq_hz| CmifPeak {
            freq_hz,
            value: 1.0,
        };
        let lone = [mode_at(40.0, 0.01), mode_at(60.0, 0.01)];
        let said = lone_modes_at_second_peaks(&lone, &[peak(40.2), peak(50.0)], &c);
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(said[0].contains("40.2000 Hz"), "{said:?}");
        let pair = [
            mode_at(40.0, 0.01),
            mode_at(40.2, 0.01),
            mode_at(60.0, 0.01),
        ];
        assert!(lone_modes_at_second_peaks(&pair, &[peak(40.2), peak(50.0)], &c).is_empty());
    }
}
