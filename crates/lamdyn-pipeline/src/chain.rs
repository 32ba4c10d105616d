//! The chain's shared values: the core found at one frequency by every route ([`CorePoint`]),
//! why a mode has no layered result ([`NoLayered`]), the truth of a virtual test ([`Truth`]),
//! a stage's timing ([`StageTime`]), and the matching of a frequency to an identified mode
//! ([`nearest_within`]). A leaf: every stage may use it, it uses no stage.

use crate::band::LayeredBand;
use lamdyn_ema::identify::EmaResult;
use lamdyn_layered::LayeredError;
use lamdyn_layered::convergence::ConvergedMode;
use lamdyn_material::MaterialError;
use lamdyn_material::laminate::CoreEstimate;
use lamdyn_material::sandwich::ExactCoreEstimate;
use num_complex::Complex64;

/// The inverse at one frequency, both ways.
#[derive(Debug, Clone)]
pub struct CorePoint {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// The fitted laminate modulus E*, Pa (None: the paper's route failed).
    pub e_eff_pa: Option<Complex64>,
    /// Where the paper's fit failed: E* (Pa) the mode's own pole implies on the shell model
    /// ([`lamdyn_fit::fit::pole_moduli`]), the layered inverse's start. None with a fit.
    pub e_pole_pa: Option<Complex64>,
    /// Delta-method standard deviations of E' (Pa) and η from the fit.
    pub e_sd: Option<(f64, f64)>,
    /// Paper eqs. 33–45.
    pub paper: Result<CoreEstimate, NoSandwichInverse>,
    /// Exact Mead–Markus inverse.
    pub exact: Result<ExactCoreEstimate, NoSandwichInverse>,
    /// The layered inverse at the mode's (real) frequency, Pa: found at its pole's complex
    /// frequency and moved here by the layered stage's law (the value as found is
    /// the band's `found_pa`). None: not run here.
    pub layered: Option<Result<Complex64, NoLayered>>,
    /// The layered inverse's convergence over its mesh ladder (with a layered result).
    pub layered_convergence: Option<ConvergedMode>,
    /// The ladder's estimate where the mode missed its tolerance (`layered` is then that
    /// error): its levels' errors still correct the FRF route's model ([`crate::frf_route`]).
    pub ladder_estimate: Option<ConvergedMode>,
    /// The layered result's 95 % band and what makes it, or why it has none (with a layered
    /// result).
    pub layered_band: Option<Result<LayeredBand, LayeredError>>,
}

impl CorePoint {
    /// G* by the paper's inverse, if it has one.
    pub fn paper_g(&self) -> Option<Complex64> {
        self.paper.as_ref().ok().map(|c| c.core_shear_pa)
    }
    /// G* by the exact inverse, if it has one.
    pub fn exact_g(&self) -> Option<Complex64> {
        self.exact.as_ref().ok().map(|c| c.core_shear_pa)
    }
    /// G* by the layered inverse, if it has one.
    pub fn layered_g(&self) -> Option<Complex64> {
        self.layered.as_ref().and_then(|r| r.as_ref().ok()).copied()
    }
    /// E' of the fitted effective modulus, Pa (None: the paper's route failed).
    pub fn e_storage_pa(&self) -> Option<f64> {
        self.e_eff_pa.map(|e| e.re)
    }
    /// Loss factor E''/E' of the fitted effective modulus (None: the paper's route failed).
    pub fn e_loss_factor(&self) -> Option<f64> {
        self.e_eff_pa.map(|e| e.im / e.re)
    }
    /// |φ| of the paper's inverse (eq. 37).
    pub fn phi(&self) -> Option<f64> {
        self.paper.as_ref().ok().map(|c| c.phi.norm())
    }
}

/// The core's known law of a virtual test, per line.
#[derive(Debug, Clone)]
pub struct Truth {
    /// Where it came from.
    pub source: String,
    /// (f in Hz, G* in Pa), increasing.
    pub lines: Vec<(f64, Complex64)>,
}

impl Truth {
    /// G* at `f` Hz by linear interpolation (None outside the table).
    pub fn at(&self, f: f64) -> Option<Complex64> {
        let k = self.lines.partition_point(|(x, _)| *x < f);
        if k == 0 {
            return (self.lines.first()?.0 == f).then(|| self.lines[0].1);
        }
        let (x1, g1) = *self.lines.get(k)?;
        let (x0, g0) = self.lines[k - 1];
        Some(g0 + (g1 - g0) * ((f - x0) / (x1 - x0)))
    }
}

/// One timed stage.
#[derive(Debug, Clone)]
pub struct StageTime {
    /// Stage name.
    pub name: &'static str,
    /// Wall time, s.
    pub seconds: f64,
    /// Taken from the cache.
    pub cached: bool,
}

/// The EMA mode nearest `f` Hz within the relative distance `within`, if any.
pub fn nearest_within(ema: &EmaResult, f: f64, within: f64) -> Option<usize> {
    ema.modes
        .iter()
        .enumerate()
        .filter(|(_, m)| (m.freq_hz / f - 1.0).abs() < within)
        .min_by(|a, b| (a.1.freq_hz - f).abs().total_cmp(&(b.1.freq_hz - f).abs()))
        .map(|(k, _)| k)
}

/// Why a modal point has no paper or exact inverse.
#[derive(Debug, Clone, PartialEq)]
pub enum NoSandwichInverse {
    /// The paper's route failed: there is no effective modulus to invert.
    NoEffectiveModulus,
    /// The stack is not a three-layer sandwich: only the layered route takes it.
    NotASandwich,
    /// The inverse has no solution at this modulus.
    Inverse(MaterialError),
}

impl std::fmt::Display for NoSandwichInverse {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoEffectiveModulus => {
                f.write_str("no effective modulus: the paper's route failed")
            }
            Self::NotASandwich => {
                f.write_str("the stack is not a three-layer sandwich: only the layered route")
            }
            Self::Inverse(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for NoSandwichInverse {}

/// Why a mode has no layered result.
#[derive(Debug, Clone, PartialEq)]
pub enum NoLayered {
    /// No identified pole within 2 % of the mode's frequency.
    NoPole {
        /// The mode's frequency, Hz.
        freq_hz: f64,
    },
    /// The layered stage has no model for any mode (the coarsest mesh above the dof cap, the
    /// ladder not converged): why.
    Stage(String),
    /// The ladder did not converge for this mode: why.
    Ladder(String),
    /// The pole gives a core that no passive material has (G' or G'' not positive): its
    /// damping is below what the faces and the supports' dashpots give the mode, or the mode
    /// is a support's.
    NotPassive {
        /// The G* found, Pa.
        core_shear_pa: Complex64,
    },
}

impl std::fmt::Display for NoLayered {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoPole { freq_hz } => f.write_str(&crate::text::no_pole_near(*freq_hz)),
            Self::Stage(why) | Self::Ladder(why) => f.write_str(why),
            Self::NotPassive { core_shear_pa } => {
                f.write_str(&crate::text::not_passive(*core_shear_pa))
            }
        }
    }
}

impl std::error::Error for NoLayered {}
