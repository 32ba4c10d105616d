//! The job resolved once for the stages ([`RunConfig`]): `Job` is the file's schema; this is
//! what the stages of [`crate::run_job`] take, one configuration per stage with the job's
//! defaults applied, its model file read and its paths made absolute.
//!
//! A change of configuration (the layered route's re-run at the supports its law found:
//! [`crate::layered::LayeredSetup::at_supports`]) is a new value of the stage's configuration,
//! never a changed copy of the job.

use crate::error::{Context, Result};
use crate::job::{
    CoreLawChoice, FrfFitChoice, Job, KinematicsChoice, Measurement, ModelFile, UncertaintyOptions,
    base_of, relative,
};
use crate::layered::LayeredSetup;
use lamdyn_ema::identify::{EmaSettings, PoleEstimator};
use lamdyn_fit::fit::{Covariance, LawKind};
use lamdyn_fit::misfit::MisfitSpec;
use lamdyn_fit::probe::SensorMapping;
use lamdyn_layered::supports::PointSupport;
use lamdyn_material::laminate::{
    CoreShearFormula, FaceBending, FaceShear, Kinematics, PaperInverseOptions, SandwichStack,
    StackSpec,
};
use std::path::{Path, PathBuf};

/// Every stage's configuration of one run, resolved from the job once ([`RunConfig::resolve`]).
#[derive(Debug, Clone)]
pub struct RunConfig {
    /// Stage "measurement" and the hits left out.
    pub measurement: MeasurementConfig,
    /// The modal identifications.
    pub ema: EmaConfig,
    /// Stage "model": the shell model of the paper's route.
    pub model: ModelConfig,
    /// Stage "fit": the paper's effective-modulus fit.
    pub paper_fit: PaperFitConfig,
    /// The paper's and the exact sandwich inverse.
    pub sandwich: SandwichConfig,
    /// The layered route, its law and the FRF fit.
    pub layered: LayeredConfig,
    /// Stage "uncertainty": the paper's route's Monte Carlo.
    pub uncertainty: UncertaintyConfig,
    /// The truth table of a virtual test, absolute.
    pub truth: Option<PathBuf>,
}

impl RunConfig {
    /// The configuration of `job`, read from the file at `job_path` (its paths are relative to
    /// that file's folder).
    ///
    /// # Errors
    /// The model file cannot be read, a three-layer stack is no sandwich, or the layered
    /// model's plan (a Gmsh mesh) or core layer cannot be had.
    pub fn resolve(job: &Job, job_path: &Path) -> Result<Self> {
        let base = base_of(job_path);
        let model = job.model_file(&base)?;
        let layered = match job.inverse.layered {
            true => Some(LayeredSetup::resolve(job, &model)?),
            false => None,
        };
        Ok(Self {
            measurement: MeasurementConfig {
                section: job.measurement.clone(),
                band_hz: job.fit.misfit.band_hz,
                base: base.clone(),
                job_path: job_path.to_path_buf(),
            },
            ema: EmaConfig::of(job),
            model: ModelConfig {
                file: model,
                modes: job.model.modes,
                residual: job.model.residual,
                tolerance_m: job.measurement.tolerance_m,
                sensor_mapping: job.measurement.sensor_mapping,
                supports: job.inverse.supports.iter().map(|s| s.to_point()).collect(),
            },
            paper_fit: PaperFitConfig {
                law: job.fit.law,
                misfit: job.fit.misfit.clone(),
                covariance: job.fit.covariance,
                prominence: job.fit.prominence,
                curve_hz: job.inverse.freq_hz.clone(),
            },
            sandwich: SandwichConfig::of(job)?,
            layered: LayeredConfig {
                setup: layered,
                core_law: job.inverse.core_law,
                frf_fit: job.inverse.frf_fit,
                max_damping_alone: MAX_DAMPING_ALONE,
            },
            uncertainty: UncertaintyConfig {
                stack: job.stack.clone(),
                options: job.uncertainty.clone(),
                kinematics: job.inverse.kinematics,
            },
            truth: job.truth.as_ref().map(|p| relative(&base, p)),
        })
    }
}

/// Where the measurement is and how it is read.
#[derive(Debug, Clone)]
pub struct MeasurementConfig {
    /// The job's `[measurement]` (its paths relative to `base`).
    pub section: Measurement,
    /// Where the coherence of time data is judged (the fit's band; `None`: every line).
    pub band_hz: Option<[f64; 2]>,
    /// The job file's folder.
    pub base: PathBuf,
    /// The job file, for messages.
    pub job_path: PathBuf,
}

/// The modal identification's settings and the identifications beside it that measure each
/// pole's scatter.
#[derive(Debug, Clone)]
pub struct EmaConfig {
    /// The band: `ema.band_hz`, else the fit's, else every line (`None`).
    pub band_hz: Option<[f64; 2]>,
    /// The stabilization diagram's highest model order.
    pub max_order: usize,
    /// Support resonances, Hz: modes near them are reported as rejected.
    pub reject_hz: Vec<f64>,
    /// The poles the chain takes.
    pub estimator: PoleEstimator,
    /// Keep the poles judged smears over clusters among the modes.
    pub keep_smears: bool,
    /// Groups of responses identified apart (stage "ema by response group";
    /// default [`RESPONSE_GROUPS`]).
    pub response_groups: usize,
    /// The other highest model orders, as factors of `max_order` (stage "ema at other model
    /// orders"; default [`OTHER_ORDERS`]).
    pub other_orders: [f64; 2],
}

/// Groups of responses whose separate identifications measure how much a pole depends on the
/// responses it is read from. On a five-layer roof's hammer data the fourth mode's damping
/// ratio came out 1.78, 2.22 and 1.96 % from three groups, 1.96 % from all and 2.01 % from
/// noise-free FRFs, while its stable poles scattered by 0.1 %.
pub const RESPONSE_GROUPS: usize = 4;

/// The other highest model orders, as factors of the job's, rounded to even (40 and 80 for
/// the default 60). On an aluminium sandwich's hammer data (seed 1 of the damped-sandwich
/// example) order 60 missed the mode at 486 Hz and the first mode's damping ratio came out
/// 2.54 %, order 80 found it and gave 2.48 % (2.47 % from noise-free FRFs).
pub const OTHER_ORDERS: [f64; 2] = [2.0 / 3.0, 4.0 / 3.0];

/// The highest damping ratio of a pole the layered route takes without the paper's fit. The
/// cases it recovers reach 7.2 % (the damped sandwich's edge mode near 490 Hz); on the same
/// panel with a core 30 times softer (ζ 16–22 %, modes overlapping four deep) the fit found no
/// peak and the poles alone gave G' 104–224 % off the truth inside ±13 % bands.
pub const MAX_DAMPING_ALONE: f64 = 0.10;

impl EmaConfig {
    fn of(job: &Job) -> Self {
        Self {
            band_hz: job.ema.band_hz.or(job.fit.misfit.band_hz),
            max_order: job.ema.max_order,
            reject_hz: job.ema.reject_hz.clone(),
            estimator: job.ema.poles,
            keep_smears: job.ema.keep_smears,
            response_groups: RESPONSE_GROUPS,
            other_orders: OTHER_ORDERS,
        }
    }

    /// The identification's settings with the stabilization diagram up to `max_order`.
    pub fn settings(&self, max_order: usize) -> EmaSettings {
        EmaSettings {
            band_hz: self.band_hz,
            orders: (2, max_order, 2),
            reject_hz: self.reject_hz.clone(),
            estimator: self.estimator,
            ..Default::default()
        }
    }

    /// The other orders' highest model orders, even and at least 2.
    pub fn other_max_orders(&self) -> [usize; 2] {
        self.other_orders
            .map(|factor| 2 * ((self.max_order as f64 * factor / 2.0).round() as usize).max(2))
    }
}

/// The shell model of the paper's route.
#[derive(Debug, Clone)]
pub struct ModelConfig {
    /// The model as read.
    pub file: ModelFile,
    /// Modes kept, rigid-body modes included (`None`: the spec's `solver.modes`).
    pub modes: Option<usize>,
    /// Whether the residual flexibility of the modes left out is added.
    pub residual: bool,
    /// How far a channel may lie from the model's surface, m.
    pub tolerance_m: f64,
    /// How the channels' points map onto the model.
    pub sensor_mapping: SensorMapping,
    /// The supports the part rests on (`[[inverse.supports]]`, the layered model's too); the
    /// model file's node springs are added to them.
    pub supports: Vec<PointSupport>,
}

/// The paper's effective-modulus fit.
#[derive(Debug, Clone)]
pub struct PaperFitConfig {
    /// The law of E*(ω).
    pub law: LawKind,
    /// The misfit.
    pub misfit: MisfitSpec,
    /// The parameters' covariance.
    pub covariance: Covariance,
    /// Peak prominence for the starts.
    pub prominence: f64,
    /// The curves' lines, Hz (`inverse.freq_hz`; `None`: 40 log-spaced lines).
    pub curve_hz: Option<Vec<f64>>,
}

/// What the paper's and the exact inverse take from the job.
#[derive(Debug, Clone)]
pub struct SandwichConfig {
    /// The sandwich; `None` for a stack of other than three layers, which only the layered
    /// route takes.
    pub stack: Option<SandwichStack>,
    /// The inverses' kinematics.
    pub kinematics: Kinematics,
    /// The paper inverse's options.
    pub paper: PaperInverseOptions,
}

impl SandwichConfig {
    /// The job's sandwich inverses: eq. 41 for the core's shear, the faces' shear neglected.
    ///
    /// # Errors
    /// A three-layer stack that is no sandwich.
    fn of(job: &Job) -> Result<Self> {
        let stack = match job.stack.layers.len() {
            3 => Some(job.stack.to_sandwich().context("the job's [stack]")?),
            _ => None,
        };
        let kinematics = match job.inverse.kinematics {
            KinematicsChoice::Beam => Kinematics::Beam,
            KinematicsChoice::Plate => Kinematics::Plate {
                poisson: job.stack.layers[0].poisson,
            },
        };
        let paper = PaperInverseOptions::new(
            CoreShearFormula::Eq41,
            FaceShear::Neglected,
            FaceBending::CoreNeglected,
            kinematics,
        );
        Ok(Self {
            stack,
            kinematics,
            paper,
        })
    }
}

/// The layered route, the core's law and the FRF fit.
#[derive(Debug, Clone)]
pub struct LayeredConfig {
    /// The layered stage's setup; `None` when `inverse.layered` is off.
    pub setup: Option<LayeredSetup>,
    /// The law(s) fitted to the modes.
    pub core_law: CoreLawChoice,
    /// When the core's law is fitted to the FRFs.
    pub frf_fit: FrfFitChoice,
    /// The highest damping ratio of a pole the layered route takes without the paper's fit
    /// (default [`MAX_DAMPING_ALONE`]).
    pub max_damping_alone: f64,
}

/// The paper's route's Monte Carlo over the stack's priors.
#[derive(Debug, Clone)]
pub struct UncertaintyConfig {
    /// The stack as the job gives it.
    pub stack: StackSpec,
    /// The priors, sample count and seed.
    pub options: UncertaintyOptions,
    /// The inverses' kinematics.
    pub kinematics: KinematicsChoice,
}
