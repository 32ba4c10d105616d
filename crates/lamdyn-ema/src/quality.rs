//! A verdict on each identified mode: is it one mode of the structure, a doubtful pole, or a
//! smear over a cluster of modes?
//!
//! The evidence, per mode:
//! - **MPC** and **MPD** of its shape ([`crate::shapes`]): a mode of a structure whose damping
//!   is spread like its stiffness (a laminate's uniform core) is nearly real, MPC near 1. The
//!   shape is fitted on the lines around the pole ([`crate::local_residues`]); the MPC of the
//!   band's fit's residues ([`crate::lsfd`]) is kept beside it.
//! - **The stable count**: how many poles of the diagram's orders support it.
//! - **Its contribution**: the FRAC of the regenerated FRFs with and without its term
//!   (residues kept), averaged over the curves. A pole that fits noise or a residual's
//!   curvature takes little away when removed.
//! - **The CMIF**: a peak of the first CMIF within three half-power half-widths of it.
//!
//! **A smear** is one pole standing in for a cluster of modes: its residues over the
//! responses add the cluster's modes at different phases (each mode's term turns by up to
//! 180° across its resonance), so its MPC is low, and it is damped (it spans the cluster). A
//! pole with MPC below [`SMEAR_MPC`] in both residue estimates and ζ at least
//! [`SMEAR_DAMPING`] is flagged as one: its frequency and damping describe no mode, and an
//! inverse from it is meaningless (on an independent damped laminate, two such poles with MPC
//! 0.05 and 0.15 gave G' 113 % off). Both, since each estimate can be spoilt alone by what its
//! model lacks: the band's fit by damped modes outside the band (its real residual terms
//! cannot hold them), the local fit by a mode without a pole inside its window; a pole over a
//! cluster is complex in both.
//! A low MPC on a lightly damped pole is a complex or weakly excited mode: doubtful, not a
//! smear. A low MPC in the local estimate alone still makes the mode doubtful: a mode without
//! its own pole inside the pole's window is a mode the list misses, and the pole fitted to that
//! window may stand for it too (one pole over a damped pair whose band's residues look real).
//! The band's estimate alone is no such evidence: its residual terms spoil it at isolated
//! damped modes. With fewer than three response components the MPC carries no information (one
//! component is always collinear) and no smear can be told.
//!
//! **A pole over two close modes** (one reference, a pair closer than its bandwidth) keeps a
//! high MPC; it is told by the second shape its curves hold under it ([`crate::second_shape`]):
//! a statistic Z of at least [`SECOND_SHAPE_STATISTIC`] times its chance level, a chance of at
//! most [`SECOND_SHAPE_CHANCE`] that noise gives as much (with few curves Z scatters widely)
//! and a second shape of at least [`SECOND_SHAPE_AMPLITUDE`] of the pole's own peak make it
//! doubtful (a weak close mode, or a neighbour the model misses), and one of at least
//! [`SECOND_SHAPE_SMEAR_AMPLITUDE`] a smear. Z is a noise test, so it is trusted only where it
//! is calibrated: the median Z over the data's poles (at least [`CALIBRATING_POLES`] of them)
//! at most [`CALIBRATED_MEDIAN`], the modal model holding to the noise at the other modes.
//! Where it is not (measured curves whose poles shift from curve to curve), Z is reported and
//! judges nothing.
//!
//! **No resonance**: a pole damped at ζ ≥ 1/√2 ([`NO_RESONANCE_DAMPING`]) gives a receptance
//! term without a peak (|1/(ω_n² − ω² + 2iζω_nω)| falls monotonically from ω = 0 when
//! ζ ≥ 1/√2), so no resonance of the data stands behind it: it shapes the curves between the
//! modes, as a residual does. Such a pole is doubtful whatever its shape says, and its
//! damping is named.

use crate::lsfd::{FracSums, ModalFit};
use crate::shapes::CmifPeak;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par, c64};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// Below this MPC, in both residue estimates (the band's fit's and the lines' around the
/// pole), a damped pole's shape is not one mode's: the figures it lies between are in
/// docs/ema.md, method step 7.
pub const SMEAR_MPC: f64 = 0.5;

/// A smear is damped at least this much (ζ): a cluster spans several half-power bandwidths.
pub const SMEAR_DAMPING: f64 = 0.02;

/// At or above this Z a second shape under a pole is more than noise (module docs): above what
/// one mode gives on the damped plates of tools/ema/damped_bias.py, below what a pole over an
/// unresolved pair gives there (docs/ema.md, method step 7).
pub const SECOND_SHAPE_STATISTIC: f64 = 5.0;

/// At most this chance that noise alone gives the Z found: with few curves Z scatters widely
/// (with two it is an exponential variable, and Z ≥ 5 is then no rare event).
pub const SECOND_SHAPE_CHANCE: f64 = 1e-6;

/// At or above this relative amplitude a second shape is worth naming (the mode is doubtful):
/// above what the modal model's own imprecision gives on noise-free curves.
pub const SECOND_SHAPE_AMPLITUDE: f64 = 0.02;

/// At or above this relative amplitude the pole stands for two modes (a smear): below what the
/// poles over the damped plates' unresolved pairs give, above what a weakly excited mode beside
/// a second one gives where its pole still describes it (the demo roof's; docs/ema.md, method
/// step 7).
pub const SECOND_SHAPE_SMEAR_AMPLITUDE: f64 = 0.08;

/// Z is trusted where its median over the data's poles is at most this (module docs).
pub const CALIBRATED_MEDIAN: f64 = 2.0;

/// The fewest poles with a Z for the median to say anything.
pub const CALIBRATING_POLES: usize = 3;

/// At or above this damping ratio (1/√2) a pole's receptance term has no peak: no resonance
/// (module docs).
pub const NO_RESONANCE_DAMPING: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Fewer stable poles than this in the mode's column make it doubtful (the automatic selection
/// asks for three orders at least; a mode seen at a handful of orders may be noise).
pub const FEW_STABLE: usize = 5;

/// Below this FRAC drop (mean over the curves) a mode without a CMIF peak of its own
/// contributes too little to the FRFs to be told from noise.
pub const LITTLE_CONTRIBUTION: f64 = 1e-3;

/// What a mode's evidence says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    /// Every indicator is that of one mode.
    Sound,
    /// Some indicator is weak ([`ModeQuality::flags`] say which); kept in the chain.
    Doubtful,
    /// One pole over a cluster of modes (module docs); kept out of the chain's inverses.
    Smear,
}

impl Verdict {
    /// A short lower-case label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Self::Sound => "sound",
            Self::Doubtful => "doubtful",
            Self::Smear => "smear",
        }
    }
}

/// One reason for a verdict other than [`Verdict::Sound`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum QualityFlag {
    /// MPC below [`SMEAR_MPC`] at ζ ≥ [`SMEAR_DAMPING`], from both residue estimates.
    Smear {
        /// MPC of the shape.
        mpc: f64,
        /// MPC of the shape from the band's fit's residues.
        band_mpc: f64,
        /// Damping ratio.
        damping_ratio: f64,
    },
    /// MPC below [`SMEAR_MPC`] at light damping, from both residue estimates: a complex or
    /// weakly excited mode.
    ComplexShape {
        /// MPC of the shape.
        mpc: f64,
        /// MPC of the shape from the band's fit's residues.
        band_mpc: f64,
        /// MPD, degrees.
        mpd_deg: f64,
    },
    /// MPC below [`SMEAR_MPC`] in the shape from the lines around the pole alone, the band's
    /// fit's at or above it: a mode without its own pole within the pole's window, or a complex
    /// mode (module docs).
    LocalComplexShape {
        /// MPC of the shape (from the lines around the pole).
        mpc: f64,
        /// MPC of the shape from the band's fit's residues.
        band_mpc: f64,
    },
    /// Damped at or above [`NO_RESONANCE_DAMPING`]: no resonance peak behind the pole.
    NoResonance {
        /// Damping ratio.
        damping_ratio: f64,
    },
    /// Fewer than [`FEW_STABLE`] stable poles in its column.
    FewStable {
        /// Stable poles.
        count: usize,
    },
    /// A second shape under the pole ([`crate::second_shape`]): a weak close mode (doubtful)
    /// or, from [`SECOND_SHAPE_SMEAR_AMPLITUDE`] on, one pole over two modes (a smear).
    SecondShape {
        /// Z, over its chance level.
        statistic: f64,
        /// The second shape's peak over the pole's.
        relative_amplitude: f64,
    },
    /// FRAC drop below [`LITTLE_CONTRIBUTION`] and no CMIF peak near it.
    LittleContribution {
        /// Mean FRAC lost without the mode.
        frac_drop: f64,
    },
}

impl QualityFlag {
    /// Whether this flag alone makes the mode a smear: a low MPC at ζ ≥ [`SMEAR_DAMPING`], or a
    /// second shape of at least [`SECOND_SHAPE_SMEAR_AMPLITUDE`].
    pub fn makes_a_smear(&self) -> bool {
        match *self {
            Self::Smear { .. } => true,
            Self::SecondShape {
                relative_amplitude, ..
            } => relative_amplitude >= SECOND_SHAPE_SMEAR_AMPLITUDE,
            _ => false,
        }
    }
}

impl std::fmt::Display for QualityFlag {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::Smear {
                mpc,
                band_mpc,
                damping_ratio,
            } => write!(
                f,
                "MPC {mpc:.2} ({band_mpc:.2} from the band's fit) at zeta {:.1} %: one pole \
                 over a cluster of modes, not a mode",
                100.0 * damping_ratio
            ),
            Self::ComplexShape {
                mpc,
                band_mpc,
                mpd_deg,
            } => write!(
                f,
                "MPC {mpc:.2} ({band_mpc:.2} from the band's fit), MPD {mpd_deg:.0} deg: a \
                 complex or weakly excited shape"
            ),
            Self::LocalComplexShape { mpc, band_mpc } => write!(
                f,
                "MPC {mpc:.2} from the lines around the pole ({band_mpc:.2} from the band's fit): \
                 a mode without its own pole beside it, which the pole may stand for too, or a \
                 complex shape"
            ),
            Self::NoResonance { damping_ratio } => write!(
                f,
                "zeta {:.0} % is at or above 1/sqrt(2) (70.7 %): its FRF term has no resonance \
                 peak, so the pole shapes the curves between modes rather than being a mode",
                100.0 * damping_ratio
            ),
            Self::SecondShape {
                statistic,
                relative_amplitude,
            } => write!(
                f,
                "a second shape under the pole, {:.1} % of its peak ({statistic:.0} times the \
                 noise's chance level): {}",
                100.0 * relative_amplitude,
                if self.makes_a_smear() {
                    "one pole over two close modes, not a mode"
                } else {
                    "a weak close mode or a neighbour the model misses, which may pull the pole"
                }
            ),
            Self::FewStable { count } => write!(f, "only {count} stable poles in its column"),
            Self::LittleContribution { frac_drop } => write!(
                f,
                "the regenerated FRFs lose {frac_drop:.1e} of FRAC without it and the CMIF has no \
                 peak there"
            ),
        }
    }
}

/// The second-shape statistics of one pole ([`crate::second_shape`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SecondShape {
    /// Z: the orthogonal part's energy over its chance level (mean 1 for one mode).
    pub statistic: f64,
    /// ρ: the second shape's peak over the pole's own.
    pub relative_amplitude: f64,
    /// The chance that noise alone gives a Z this large at one mode: P(χ²₂₍ₙ₋₁₎ ≥ 2(n − 1)Z).
    pub chance: f64,
}

/// The verdict on one mode and its evidence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeQuality {
    /// The verdict.
    pub verdict: Verdict,
    /// Why it is not [`Verdict::Sound`] (empty when it is).
    pub flags: Vec<QualityFlag>,
    /// Mean over the curves of the FRAC lost when the mode's term is removed from the
    /// regenerated FRFs (residues kept).
    pub frac_drop: f64,
    /// The first CMIF's peak within three half-power half-widths of the mode, Hz.
    pub cmif_peak_hz: Option<f64>,
    /// The second-shape test's statistics ([`crate::second_shape`]), whether they judge or not.
    #[serde(default)]
    pub second_shape: Option<SecondShape>,
}

impl ModeQuality {
    /// Why the mode is not sound, one clause per flag joined by "; " (empty when sound).
    pub fn reasons(&self) -> String {
        let why: Vec<String> = self.flags.iter().map(ToString::to_string).collect();
        why.join("; ")
    }
}

impl Default for ModeQuality {
    /// Sound, no evidence (a mode read from a file written before verdicts existed).
    fn default() -> Self {
        Self {
            verdict: Verdict::Sound,
            flags: vec![],
            frac_drop: f64::NAN,
            cmif_peak_hz: None,
            second_shape: None,
        }
    }
}

/// What [`assess`] needs of one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeEvidence {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// MPC of its shape (from its residues near its pole, [`crate::local_residues`]).
    pub mpc: f64,
    /// MPC of its shape from the band's fit's residues ([`crate::lsfd`]).
    pub band_mpc: f64,
    /// MPD of its shape, degrees.
    pub mpd_deg: f64,
    /// Components of its shape (responses, or references for a roving hammer).
    pub shape_len: usize,
    /// Stable poles in its column.
    pub stable_count: usize,
    /// The mean FRAC the regenerated curves lose without it ([`contributions`]).
    pub frac_drop: f64,
    /// The spacing of the measured lines, Hz (the CMIF peak's least reach).
    pub line_spacing_hz: f64,
    /// The second-shape test's statistics (None where it has none).
    pub second_shape: Option<SecondShape>,
    /// Whether the second-shape test judges on these data ([`second_shape_calibrated`]).
    pub second_shape_calibrated: bool,
}

/// Whether the second-shape test is calibrated on data whose poles gave `tests` (module docs).
pub fn second_shape_calibrated(tests: &[Option<SecondShape>]) -> bool {
    let mut z: Vec<f64> = tests.iter().flatten().map(|t| t.statistic).collect();
    if z.len() < CALIBRATING_POLES {
        return false;
    }
    let mid = z.len() / 2;
    let (_, median, _) = z.select_nth_unstable_by(mid, f64::total_cmp);
    *median <= CALIBRATED_MEDIAN
}

/// The measured curves the modal model was fitted to, and the lines of the band.
#[derive(Debug, Clone, Copy)]
pub struct Measured<'a> {
    /// Frequencies of the lines, Hz.
    pub freqs_hz: &'a [f64],
    /// The curves, in the order of the fit's residues.
    pub curves: &'a [&'a [Complex64]],
    /// Indices of the band's lines.
    pub lines: &'a [usize],
}

/// What the MPCs of a mode's two residue estimates say (module docs): low in both, a smear
/// (damped) or a complex shape (light); low in the local estimate alone, a mode without its own
/// pole in the window or a complex mode; nothing where the local one is high or fewer than
/// three response components carry no MPC.
fn shape_flag(mode: &ModeEvidence) -> Option<QualityFlag> {
    let (mpc, band_mpc) = (mode.mpc, mode.band_mpc);
    if mode.shape_len < 3 || mpc >= SMEAR_MPC {
        return None;
    }
    Some(if band_mpc >= SMEAR_MPC {
        QualityFlag::LocalComplexShape { mpc, band_mpc }
    } else if mode.damping_ratio >= SMEAR_DAMPING {
        QualityFlag::Smear {
            mpc,
            band_mpc,
            damping_ratio: mode.damping_ratio,
        }
    } else {
        QualityFlag::ComplexShape {
            mpc,
            band_mpc,
            mpd_deg: mode.mpd_deg,
        }
    })
}

/// Whether the test `t` finds a second shape under its pole worth naming (module docs): Z of
/// at least [`SECOND_SHAPE_STATISTIC`], a chance of at most [`SECOND_SHAPE_CHANCE`] and a
/// relative amplitude of at least [`SECOND_SHAPE_AMPLITUDE`]. Meaningful only where the data
/// calibrate the test ([`second_shape_calibrated`]).
pub fn shows_a_second_shape(t: &SecondShape) -> bool {
    t.statistic >= SECOND_SHAPE_STATISTIC
        && t.chance <= SECOND_SHAPE_CHANCE
        && t.relative_amplitude >= SECOND_SHAPE_AMPLITUDE
}

/// The verdict on a mode from its evidence (module docs).
pub fn assess(mode: &ModeEvidence, cmif_peaks: &[CmifPeak]) -> ModeQuality {
    let frac_drop = mode.frac_drop;
    let reach = 3.0 * (mode.damping_ratio * mode.freq_hz).max(mode.line_spacing_hz);
    let cmif_peak_hz = cmif_peaks
        .iter()
        .map(|p| p.freq_hz)
        .filter(|f| (f - mode.freq_hz).abs() <= reach)
        .min_by(|a, b| {
            (a - mode.freq_hz)
                .abs()
                .total_cmp(&(b - mode.freq_hz).abs())
        });
    let mut flags: Vec<QualityFlag> = shape_flag(mode).into_iter().collect();
    if mode.damping_ratio >= NO_RESONANCE_DAMPING {
        flags.push(QualityFlag::NoResonance {
            damping_ratio: mode.damping_ratio,
        });
    }
    if mode.stable_count < FEW_STABLE {
        flags.push(QualityFlag::FewStable {
            count: mode.stable_count,
        });
    }
    if let Some(t) = mode
        .second_shape
        .filter(|t| mode.second_shape_calibrated && shows_a_second_shape(t))
    {
        flags.push(QualityFlag::SecondShape {
            statistic: t.statistic,
            relative_amplitude: t.relative_amplitude,
        });
    }
    if frac_drop < LITTLE_CONTRIBUTION && cmif_peak_hz.is_none() {
        flags.push(QualityFlag::LittleContribution { frac_drop });
    }
    let verdict = if flags.iter().any(QualityFlag::makes_a_smear) {
        Verdict::Smear
    } else if flags.is_empty() {
        Verdict::Sound
    } else {
        Verdict::Doubtful
    };
    ModeQuality {
        verdict,
        flags,
        frac_drop,
        cmif_peak_hz,
        second_shape: mode.second_shape,
    }
}

/// How well a modal model regenerates the measured curves, and what each mode adds to that.
#[derive(Debug, Clone, PartialEq)]
pub struct Contributions {
    /// FRAC of each regenerated curve ([`crate::lsfd::frac`]) over the lines.
    pub frac: Vec<f64>,
    /// Per mode: the mean over the curves of the FRAC lost when its term is removed from the
    /// regenerated curves (residues kept).
    pub frac_drop: Vec<f64>,
}

/// Lines per block of [`ModelProducts`]' accumulation: each block's columns stay in cache.
const PRODUCT_BLOCK: usize = 2048;

/// The [`Contributions`] of `fit`'s modes on `data`: every FRAC sum, with and without each mode,
/// is a quadratic form in a curve's coefficients over the products (`ModelProducts`) of the
/// model's columns, accumulated in one pass over the lines.
pub fn contributions(fit: &ModalFit, data: Measured) -> Contributions {
    use rayon::prelude::*;
    let (modes, curves) = (fit.poles.len(), data.curves.len());
    let products = data
        .lines
        .par_chunks(PRODUCT_BLOCK)
        .map(|lines| ModelProducts::on(fit, data, lines))
        .reduce(
            || ModelProducts::zeros(modes, curves),
            ModelProducts::merged,
        );
    let mut frac = Vec::with_capacity(curves);
    let mut lost = vec![0.0; modes];
    for o in 0..curves {
        let mut c = fit.coefficients(o);
        let with = products.frac_sums(o, &c).frac();
        for (r, lost) in lost.iter_mut().enumerate() {
            let kept = [c[2 * r], c[2 * r + 1]];
            c[2 * r..2 * r + 2].fill(c64::default());
            *lost += with - products.frac_sums(o, &c).frac();
            c[2 * r..2 * r + 2].copy_from_slice(&kept);
        }
        frac.push(with);
    }
    let curves = curves.max(1) as f64;
    let frac_drop = lost.into_iter().map(|l| l / curves).collect();
    Contributions { frac, frac_drop }
}

/// Over some lines, the products of the modal model's columns B with themselves and with the
/// curves H: G = BᴴB and E = BᴴH, side by side in one matrix, and each curve's Σ|H|². B holds
/// per line the model's columns ([`ModalFit::columns_on`]). A curve's model is Bc
/// ([`ModalFit::coefficients`]), so its FRAC sums are Σ H (Bc)* = cᴴE_o and Σ|Bc|² = cᴴGc,
/// for any c: with a mode's two coefficients zeroed, those without it.
struct ModelProducts {
    /// [G | E]: 2m + 2 rows, 2m + 2 + curves columns.
    products: Mat<c64>,
    /// Σ|H_o|² per curve.
    measured: Vec<f64>,
}

impl ModelProducts {
    /// No line's products, for `modes` modes and `curves` curves.
    fn zeros(modes: usize, curves: usize) -> Self {
        let columns = 2 * modes + 2;
        Self {
            products: Mat::zeros(columns, columns + curves),
            measured: vec![0.0; curves],
        }
    }

    /// The products over `lines` of `data` with `fit`'s columns.
    fn on(fit: &ModalFit, data: Measured, lines: &[usize]) -> Self {
        let columns = 2 * fit.poles.len() + 2;
        let mut side_by_side = Mat::<c64>::zeros(lines.len(), columns + data.curves.len());
        let mut basis = fit.line_basis(0.0);
        let mut line = vec![c64::default(); columns];
        for (i, &k) in lines.iter().enumerate() {
            fit.set_line_basis(&mut basis, data.freqs_hz[k]);
            fit.columns_on(&basis, &mut line);
            for (j, v) in line.iter().enumerate() {
                side_by_side[(i, j)] = *v;
            }
            for (o, curve) in data.curves.iter().enumerate() {
                side_by_side[(i, columns + o)] = curve[k];
            }
        }
        let mut products = Mat::zeros(columns, side_by_side.ncols());
        let model = side_by_side.as_ref().subcols(0, columns);
        matmul(
            products.as_mut(),
            Accum::Replace,
            model.adjoint(),
            side_by_side.as_ref(),
            c64::new(1.0, 0.0),
            Par::Seq,
        );
        let measured = (0..data.curves.len())
            .map(|o| side_by_side.col(columns + o).squared_norm_l2())
            .collect();
        Self { products, measured }
    }

    /// The products over both sets of lines.
    fn merged(mut self, other: Self) -> Self {
        self.products += &other.products;
        self.measured
            .iter_mut()
            .zip(&other.measured)
            .for_each(|(a, b)| *a += b);
        self
    }

    /// The FRAC sums of curve `o` against the model Bc.
    fn frac_sums(&self, o: usize, c: &[c64]) -> FracSums {
        let columns = c.len();
        let (gram, cross) = (
            self.products.subcols(0, columns),
            self.products.col(columns + o),
        );
        let cross: c64 = c
            .iter()
            .zip(cross.iter())
            .map(|(cj, e)| cj.conj() * e)
            .sum();
        let model: f64 = (0..columns)
            .map(|j| {
                let row: c64 = (0..columns).map(|l| gram[(j, l)] * c[l]).sum();
                (c[j].conj() * row).re
            })
            .sum();
        FracSums::of(cross, self.measured[o], model)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The FRAC sums from the products of the model's columns are those of the regenerated
    /// curves line by line ([`crate::lsfd::frac`] of the model with and without each mode's
    /// term): three modes, lower and upper residuals, accelerance, over every other line of
    /// 5000 (several blocks), curves that are the model plus a misfit.
    #[test]
    fn the_contributions_are_the_fracs_of_the_regenerated_curves() {
        use crate::lscf::pole_at;
        use crate::lsfd::frac;
        use lamdyn_frf::Quantity;
        let poles = vec![
            pole_at(40.0, 0.02),
            pole_at(55.0, 0.08),
            pole_at(90.0, 0.01),
        ];
        let residue = |o: usize, r: usize| {
            let (o, r) = (o as f64, r as f64);
            Complex64::new((1.0 + o + r).sin(), 0.3 * (2.0 * o - r).cos()) * 1e3
        };
        let fit = ModalFit {
            residues: (0..4)
                .map(|o| (0..3).map(|r| residue(o, r)).collect())
                .collect(),
            lower: vec![2.0, -1.0, 0.5, 0.0],
            upper: vec![-1e-3, 2e-3, 0.0, 1e-3],
            poles,
            quantity: Quantity::Accelerance,
        };
        let freqs: Vec<f64> = (0..5000).map(|k| 10.0 + 0.02 * k as f64).collect();
        let lines: Vec<usize> = (0..freqs.len()).step_by(2).collect();
        let model =
            |o: usize| -> Vec<Complex64> { freqs.iter().map(|&f| fit.synthesize(o, f)).collect() };
        let curves: Vec<Vec<Complex64>> = (0..4)
            .map(|o| {
                let misfit =
                    |k: usize| Complex64::new((0.37 * k as f64).sin(), (0.11 * k as f64).cos());
                model(o)
                    .iter()
                    .enumerate()
                    .map(|(k, h)| h + 0.2 * misfit(k + o))
                    .collect()
            })
            .collect();
        let refs: Vec<&[Complex64]> = curves.iter().map(Vec::as_slice).collect();
        let data = Measured {
            freqs_hz: &freqs,
            curves: &refs,
            lines: &lines,
        };
        let got = contributions(&fit, data);
        let mut drops = [0.0; 3];
        for (o, curve) in refs.iter().enumerate() {
            let full = model(o);
            let with = frac(curve, &full, &lines);
            assert!(
                (got.frac[o] - with).abs() < 1e-12,
                "curve {o}: {} vs {with}",
                got.frac[o]
            );
            for (r, drop) in drops.iter_mut().enumerate() {
                let without: Vec<Complex64> = full
                    .iter()
                    .zip(&freqs)
                    .map(|(h, &f)| h - fit.mode_term(o, r, f))
                    .collect();
                *drop += (with - frac(curve, &without, &lines)) / 4.0;
            }
        }
        for (r, drop) in drops.iter().enumerate() {
            assert!(
                *drop > 1e-3,
                "mode {r} takes {drop} of FRAC: the test needs each to count"
            );
            assert!(
                (got.frac_drop[r] - drop).abs() < 1e-12,
                "mode {r}: {} vs {drop}",
                got.frac_drop[r]
            );
        }
    }

    /// A sound mode's evidence, damped `damping_ratio`.
    fn evidence(damping_ratio: f64) -> ModeEvidence {
        ModeEvidence {
            freq_hz: 100.0,
            damping_ratio,
            mpc: 0.99,
            band_mpc: 0.99,
            mpd_deg: 2.0,
            shape_len: 9,
            stable_count: 20,
            frac_drop: 0.1,
            line_spacing_hz: 0.25,
            second_shape: None,
            second_shape_calibrated: false,
        }
    }

    /// The single degree of freedom's receptance has a peak below ζ = 1/√2 and none at or above
    /// it (checked on a grid: the bound is the formula's, not a tuning); a pole damped beyond it
    /// is doubtful whatever its shape, with its damping named; the heavily damped modes of
    /// laminated glass (ζ 6-22 %) stay sound.
    #[test]
    fn a_pole_without_a_resonance_peak_is_doubtful() {
        let has_peak = |z: f64| {
            let receptance = |r: f64| 1.0 / ((1.0 - r * r).powi(2) + (2.0 * z * r).powi(2)).sqrt();
            (1..400).any(|k| receptance(k as f64 * 0.005) > receptance(0.0) * (1.0 + 1e-12))
        };
        assert!(has_peak(NO_RESONANCE_DAMPING - 0.01));
        assert!(!has_peak(NO_RESONANCE_DAMPING));
        for z in [0.001, 0.06, 0.15, 0.22, 0.5] {
            let q = assess(&evidence(z), &[]);
            assert_eq!(q.verdict, Verdict::Sound, "zeta {z}: {q:?}");
        }
        let q = assess(&evidence(0.95), &[]);
        assert_eq!(q.verdict, Verdict::Doubtful, "{q:?}");
        assert_eq!(
            q.flags,
            vec![QualityFlag::NoResonance {
                damping_ratio: 0.95
            }]
        );
        assert!(q.reasons().contains("zeta 95 %"), "{}", q.reasons());
    }

    /// A low MPC makes a smear (or, lightly damped, a complex shape) only where both residue
    /// estimates show it; the flag names both. Low in the local estimate alone the mode is
    /// doubtful; low in the band's alone (its residual terms) it stays sound.
    #[test]
    fn a_smear_is_complex_in_both_residue_estimates() {
        let with = |mpc, band_mpc, damping_ratio| {
            let mode = ModeEvidence {
                mpc,
                band_mpc,
                ..evidence(damping_ratio)
            };
            assess(&mode, &[])
        };
        for damping in [0.08, 0.01] {
            assert_eq!(with(0.9, 0.3, damping).verdict, Verdict::Sound);
            let local = with(0.3, 0.9, damping);
            assert_eq!(local.verdict, Verdict::Doubtful, "{local:?}");
            assert!(matches!(
                local.flags[..],
                [QualityFlag::LocalComplexShape { .. }]
            ));
            assert!(
                local
                    .reasons()
                    .contains("MPC 0.30 from the lines around the pole (0.90")
            );
        }
        let smear = with(0.3, 0.4, 0.08);
        assert_eq!(smear.verdict, Verdict::Smear, "{smear:?}");
        assert!(
            smear
                .reasons()
                .contains("MPC 0.30 (0.40 from the band's fit)")
        );
        let complex = with(0.3, 0.4, 0.01);
        assert_eq!(complex.verdict, Verdict::Doubtful, "{complex:?}");
        assert!(matches!(complex.flags[0], QualityFlag::ComplexShape { .. }));
    }

    /// A second shape judges only where the data calibrate the test, and only at both bounds.
    #[test]
    fn a_second_shape_judges_where_the_test_is_calibrated() {
        let test = |statistic, relative_amplitude| SecondShape {
            statistic,
            relative_amplitude,
            chance: 1e-9,
        };
        let judged = |t: SecondShape, calibrated: bool| {
            let mode = ModeEvidence {
                second_shape: Some(t),
                second_shape_calibrated: calibrated,
                ..evidence(0.08)
            };
            assess(&mode, &[])
        };
        let q = judged(test(25.0, 0.11), true);
        assert_eq!(q.verdict, Verdict::Smear, "{q:?}");
        assert!(q.reasons().contains("two close modes"), "{}", q.reasons());
        assert_eq!(q.second_shape, Some(test(25.0, 0.11)));
        // A weaker second shape leaves the pole in the chain, doubtful.
        let q = judged(test(10.0, 0.044), true);
        assert_eq!(q.verdict, Verdict::Doubtful, "{q:?}");
        assert!(q.reasons().contains("a weak close mode"), "{}", q.reasons());
        for (t, calibrated) in [
            (test(25.0, 0.11), false),
            (test(4.9, 0.11), true),
            (test(25.0, 0.019), true),
            (
                SecondShape {
                    chance: 2e-6,
                    ..test(25.0, 0.11)
                },
                true,
            ),
        ] {
            let q = judged(t, calibrated);
            assert_eq!(q.verdict, Verdict::Sound, "{t:?} {calibrated}: {q:?}");
            assert_eq!(q.second_shape, Some(t));
        }
    }

    #[test]
    fn the_test_is_calibrated_where_most_poles_show_chance_level() {
        let z = |v: &[f64]| -> Vec<Option<SecondShape>> {
            v.iter()
                .map(|&statistic| {
                    Some(SecondShape {
                        statistic,
                        relative_amplitude: 0.1,
                        chance: 0.5,
                    })
                })
                .collect()
        };
        // The damped plate's: two poles over pairs among seven.
        assert!(second_shape_calibrated(&z(&[
            1.3, 0.8, 0.8, 0.1, 0.0, 12.5, 31.7
        ])));
        // The measured dam's (26 channels): every mode above chance.
        assert!(!second_shape_calibrated(&z(&[
            8.2, 11.1, 4.7, 17.4, 29.3, 1.5, 0.8, 0.8, 4.5
        ])));
        // Too few poles, or poles without a test, say nothing.
        assert!(!second_shape_calibrated(&z(&[1.0, 1.0])));
        let mut sparse = z(&[1.0, 1.0]);
        sparse.extend([None, None, None]);
        assert!(!second_shape_calibrated(&sparse));
    }
}
