//! What the chain found ([`ChainResult`]): every stage's result, as the report, the CLI and
//! the Python module read it.

use crate::band_widths::{BandWidths, band_widths};
use crate::chain::{CorePoint, StageTime, Truth};
use crate::frf_route::FrfOutcome;
use crate::job::Job;
use crate::measurement::Measured;
use crate::uncertainty;
use lamdyn_ema::identify::EmaResult;
use lamdyn_fit::fit::FitResult;
use lamdyn_fit::modes::PeakComparison;
use lamdyn_material::causality::CausalityVerdict;
use lamdyn_material::laminate::{Kinematics, PaperInverseOptions, SandwichStack};
use std::path::PathBuf;

/// Everything the chain found.
pub struct ChainResult {
    /// The job.
    pub job: Job,
    /// Its file.
    pub job_path: PathBuf,
    /// The measurement.
    pub measured: Measured,
    /// The modal identification.
    pub ema: EmaResult,
    /// A line describing the FE model.
    pub model_line: String,
    /// A line describing the layered inverse's model (None: not run).
    pub layered_line: Option<String>,
    /// The core's law fitted to all layered modes with the inputs shared (None: not asked
    /// for, or no layered mode with a band), or why it failed.
    pub core_law: Option<std::result::Result<lamdyn_fit::joint::CoreLawFit, lamdyn_fit::FitError>>,
    /// The FRF route: the core's law fitted to the measured FRFs through the layered model,
    /// the answer where the rule calls for it ([`crate::frf_route`]).
    pub frf: FrfOutcome,
    /// The paper's route: the effective modulus fitted to the FRFs on the shell model; `None`
    /// when its fit failed and the layered route went on alone (`paper_route_error` says why).
    pub fit: Option<FitResult>,
    /// Why the paper's route has no result (its stage's error), if it has none.
    pub paper_route_error: Option<String>,
    /// Lines of the misfit.
    pub fit_lines: Vec<usize>,
    /// RMS FRF over the responses, measured and fitted, per line (paper Fig. 5).
    pub measured_rms: Vec<f64>,
    /// As `measured_rms`, from the fitted law.
    pub fitted_rms: Vec<f64>,
    /// Table 3: peaks of the RMS curves.
    pub table3: Vec<PeakComparison>,
    /// The sandwich of the paper's route; `None` for a stack of other than three layers,
    /// which only the layered route takes.
    pub stack: Option<SandwichStack>,
    /// The inverse's kinematics.
    pub kinematics: Kinematics,
    /// The paper inverse's options.
    pub paper_options: PaperInverseOptions,
    /// The inverse at the modal frequencies (`modal_frequencies`: the fit's peaks and the
    /// EMA modes no peak claims).
    pub modal: Vec<CorePoint>,
    /// The inverse on the curve grid.
    pub curve: Vec<CorePoint>,
    /// Kramers–Kronig verdicts on the curve grid: paper, exact.
    pub causality: [Vec<Option<CausalityVerdict>>; 2],
    /// Monte Carlo bands at the modal frequencies and on the curve grid.
    pub uncertainty: Option<uncertainty::McResult>,
    /// The truth of a virtual test.
    pub truth: Option<Truth>,
    /// Warnings for the report.
    pub warnings: Vec<String>,
    /// Stage timings.
    pub timings: Vec<StageTime>,
}

impl ChainResult {
    /// How wide the layered route's bands are and what would narrow them
    /// ([`crate::band_widths`]); `None` without a layered band.
    pub fn band_widths(&self) -> Option<BandWidths> {
        band_widths(
            &self.modal,
            self.core_law.as_ref().and_then(|l| l.as_ref().ok()),
        )
    }

    /// Frequencies (Hz) of the modes where no inverse found a core it can stand behind: no
    /// exact and no layered result, and the paper's none or beyond its validity
    /// (|φ| > [`PHI_ACCURACY_LIMIT`](lamdyn_material::laminate::PHI_ACCURACY_LIMIT)), and no
    /// FRF fit as the answer over its band. The run has no answer there, and the CLI exits 1.
    pub fn modes_without_core(&self) -> Vec<f64> {
        use lamdyn_material::laminate::PHI_ACCURACY_LIMIT;
        let frf_band = self.frf.answer().map(|r| r.fit.band_hz);
        self.modal
            .iter()
            .filter(|p| frf_band.is_none_or(|b| p.freq_hz < b[0] || p.freq_hz > b[1]))
            .filter(|p| {
                let paper_valid =
                    p.paper_g().is_some() && p.phi().is_some_and(|phi| phi <= PHI_ACCURACY_LIMIT);
                !paper_valid && p.exact_g().is_none() && p.layered_g().is_none()
            })
            .map(|p| p.freq_hz)
            .collect()
    }
}
