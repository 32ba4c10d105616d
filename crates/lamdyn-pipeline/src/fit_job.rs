//! A fit job (`lamdyn fit JOB`, `lamdyn.fit_job` in Python): the measured FRFs of a job's
//! `[measurement]`, the modal model of its `[model]` and the settings of its `[fit]`, validated
//! and ready for [`lamdyn_fit::fit::fit`] (paper eqs. 2–10).
//!
//! A fit job file has the layout of a `lamdyn run` job (`[measurement]`, `[model]` with `file`
//! or `spec`, `[fit]` with `[fit.misfit]`), so one file serves both; the run job's other
//! sections are accepted and not used. The older layout (`model` as a path,
//! top-level `modes`, `residual` and `[misfit]`) is still read, with a deprecation note.

use crate::error::{Context, Result};
use crate::io::{CsvTable, read_toml};
use crate::job::{Measurement, ModelSource, base_of, default_misfit, default_prominence, relative};
use crate::measurement::read_measurement_section;
use crate::{AsProgress, Reporter, err};
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::{ModalParams, solve_modes};
use lamdyn_fem::model::ModelSpec;
use lamdyn_fit::fit::{Covariance, FitSettings, LawKind, Pole};
use lamdyn_fit::misfit::MisfitSpec;
use lamdyn_fit::probe::{SensorPlacement, placement_line, probes_with};
use lamdyn_fit::supports::GroundedSupport;
use lamdyn_fit::synthesis::{ModalModel, ResidualTerm};
use lamdyn_frf::FrfSet;
use lamdyn_material::law::ViscoelasticLaw;
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)] // the run job's sections are read to be accepted, not used
struct FitJob {
    #[serde(default)]
    title: Option<String>,
    measurement: Measurement,
    /// `[model]` (file or spec, modes, residual), or a path (deprecated).
    model: toml::Value,
    #[serde(default)]
    fit: FitOptions,
    /// Deprecated: `[model] modes`.
    #[serde(default)]
    modes: Option<usize>,
    /// Deprecated: `[model] residual`.
    #[serde(default)]
    residual: Option<bool>,
    /// Deprecated: `[fit.misfit]`.
    #[serde(default)]
    misfit: Option<MisfitSpec>,
    // Sections of a run job that the fit does not use.
    #[serde(default)]
    stack: Option<toml::Value>,
    #[serde(default)]
    ema: Option<toml::Value>,
    #[serde(default)]
    inverse: Option<toml::Value>,
    #[serde(default)]
    uncertainty: Option<toml::Value>,
    #[serde(default)]
    truth: Option<toml::Value>,
    #[serde(default)]
    temperature_k: Option<f64>,
}

/// `[fit]` of a job: the run job's keys; the law defaults to the paper's eq. 7 here (`lamdyn
/// run` defaults to `per_mode`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FitOptions {
    #[serde(default = "default_law")]
    law: LawKind,
    #[serde(default)]
    covariance: Covariance,
    /// Peak prominence for the starts (ratio over the neighbouring valleys).
    #[serde(default = "default_prominence")]
    prominence: f64,
    #[serde(default)]
    misfit: Option<MisfitSpec>,
    /// Estimate the model's discretization error and add it to the intervals
    /// ([`with_discretization_error`]).
    #[serde(default = "yes")]
    discretization_error: bool,
    /// Identified poles (`lamdyn ema`'s modes.csv) for the starts, peak matching and mode-wise
    /// estimate, relative to the job ([`read_poles`]).
    #[serde(default)]
    poles: Option<PathBuf>,
}

fn yes() -> bool {
    true
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            law: default_law(),
            covariance: Covariance::default(),
            prominence: default_prominence(),
            misfit: None,
            discretization_error: true,
            poles: None,
        }
    }
}

fn default_law() -> LawKind {
    LawKind::PaperEq7
}

/// The job's model, misfit and their deprecation notes, in the current layout.
struct Resolved {
    model: ModelSource,
    misfit: MisfitSpec,
    notes: Vec<String>,
}

impl FitJob {
    /// Reads the old spellings into the current layout, noting each; both spellings at once
    /// is an error.
    fn resolve(&self) -> Result<Resolved> {
        let mut notes = Vec::new();
        let mut model = match &self.model {
            toml::Value::String(p) => {
                notes.push(format!(
                    "deprecated: model = \"{p}\" is the old layout; write [model] with file = \
                     \"{p}\" (as in a lamdyn run job)"
                ));
                ModelSource {
                    file: Some(PathBuf::from(p)),
                    spec: None,
                    modes: None,
                    residual: true,
                }
            }
            v => ModelSource::deserialize(v.clone()).map_err(|e| err!("model: {e}"))?,
        };
        if let Some(n) = self.modes {
            if model.modes.is_some() {
                return Err(err!("modes: give [model] modes only"));
            }
            notes.push("deprecated: top-level modes; write it in [model]".into());
            model.modes = Some(n);
        }
        if let Some(r) = self.residual {
            notes.push("deprecated: top-level residual; write it in [model]".into());
            model.residual = r;
        }
        let misfit = match (&self.misfit, &self.fit.misfit) {
            (Some(_), Some(_)) => return Err(err!("misfit: give [fit.misfit] only")),
            (Some(m), None) => {
                notes.push(
                    "deprecated: [misfit]; write [fit.misfit] (as in a lamdyn run job)".into(),
                );
                m.clone()
            }
            (None, Some(m)) => m.clone(),
            (None, None) => default_misfit(),
        };
        Ok(Resolved {
            model,
            misfit,
            notes,
        })
    }
}

/// Everything a fit needs, validated.
pub struct FitProblem {
    /// Where the measurement came from (for reports).
    pub source: String,
    /// A line describing the modal model.
    pub model_line: String,
    /// The modal model at the measurement's channels.
    pub model: ModalModel,
    /// The measured FRFs.
    pub measured: FrfSet,
    /// The fit's settings.
    pub settings: FitSettings,
    /// The law the data were made from and its parameters in the fit's order (built-in
    /// examples).
    pub truth: Option<(Box<dyn ViscoelasticLaw>, Vec<f64>)>,
    /// Time to build the modal model, s.
    pub model_seconds: f64,
    /// Deprecated spellings met and the measurement's warnings.
    pub notes: Vec<String>,
}

/// The modal model of a shell model at the channels of `set`: mesh, assembly, the lowest
/// `modes` free modes, each channel placed on the mesh as `placement` says, and the static
/// residual term when `residual` (paper eq. 4: K*(ω) = s(ω) K0); the model file's node
/// springs, which do not scale with the modulus, couple the modes
/// ([`lamdyn_fit::supports`]). Returns the model and a line describing it; `name` names the
/// model and `source` the measurement in messages.
///
/// # Errors
/// An invalid model, fewer than 7 modes, channels off the mesh, and the solver's failures.
#[allow(clippy::too_many_arguments)]
pub fn modal_model(
    spec: &ModelSpec,
    base: &Path,
    name: &str,
    source: &str,
    set: &FrfSet,
    placement: SensorPlacement,
    modes: usize,
    residual: bool,
    progress: &dyn Reporter,
) -> Result<(ModalModel, String)> {
    if modes < 7 {
        crate::bail!(
            "model.modes: {modes}: keep at least the 6 rigid-body modes and one elastic mode"
        );
    }
    let SensorPlacement {
        tolerance_m,
        mapping,
    } = placement;
    if !(tolerance_m.is_finite() && tolerance_m > 0.0) {
        crate::bail!("measurement.tolerance_m: {tolerance_m} must be a positive length in m");
    }
    let invalid = || format!("invalid model {name}");
    let (mesh, springs) = spec.build(base).with_context(invalid)?;
    let supports: Vec<GroundedSupport> = springs
        .iter()
        .flat_map(GroundedSupport::from_node_spring)
        .collect();
    let asm = Assembly::new(&mesh, &spec.material, &[]).with_context(invalid)?;
    let channels = || format!("channels of {source}");
    let resp = probes_with(&mesh, set.responses(), tolerance_m, mapping).with_context(channels)?;
    let refs = probes_with(&mesh, set.references(), tolerance_m, mapping).with_context(channels)?;
    let sol = solve_modes(&asm, &ModalParams::lowest(modes), &AsProgress(progress))?;
    progress.stage("projecting modes and residual terms");
    let term = if residual {
        ResidualTerm::Static
    } else {
        ResidualTerm::None
    };
    let young = spec.material.young_pa;
    let model = ModalModel::supported(&asm, &sol, &resp, &refs, young, term, &supports)?;
    let mut line = format!(
        "{name}: {} nodes, {} {}, {modes} modes{}, E_ref = {:.4e} Pa; {}",
        mesh.nodes().len(),
        mesh.n_elements(),
        mesh.order().name(),
        if residual { " + residual term" } else { "" },
        spec.material.young_pa,
        placement_line(mapping, &[resp.as_slice(), refs.as_slice()].concat())
    );
    if !supports.is_empty() {
        line.push_str(&crate::text::shell_model_on_supports(
            0,
            springs.len(),
            model.eigenvalues().len() - sol.modes.len(),
            &model.support_hz(),
        ));
    }
    Ok((model, line))
}

/// Poles from a CSV table with columns `freq_hz` (Hz) and `damping_ratio` (others ignored,
/// text or numbers): `lamdyn ema --out DIR` writes one as DIR/modes.csv.
///
/// # Errors
/// The file's, naming it and the line: missing columns, a frequency that is not positive, a
/// damping ratio outside [0, 1), no rows.
pub fn read_poles(path: &Path) -> Result<Vec<Pole>> {
    let table = CsvTable::read_columns(path, &["freq_hz", "damping_ratio"])?;
    let (f, z) = (
        table.require_any(&["freq_hz"])?,
        table.require_any(&["damping_ratio"])?,
    );
    let mut poles = Vec::with_capacity(table.rows().len());
    for (line, row) in table.rows() {
        let (freq_hz, damping_ratio) = (row[f], row[z]);
        if !(freq_hz.is_finite() && freq_hz > 0.0) {
            crate::bail!(
                "'{}' line {line}: freq_hz = {freq_hz} must be a positive frequency in Hz",
                path.display()
            );
        }
        if !(damping_ratio.is_finite() && (0.0..1.0).contains(&damping_ratio)) {
            crate::bail!(
                "'{}' line {line}: damping_ratio = {damping_ratio} must lie in [0, 1) (a ratio, \
                 not %)",
                path.display()
            );
        }
        poles.push(Pole {
            freq_hz,
            damping_ratio,
        });
    }
    if poles.is_empty() {
        crate::bail!("'{}' holds no pole", path.display());
    }
    Ok(poles)
}

/// The model with its modes' estimated discretization errors attached
/// ([`lamdyn_fem::convergence::mesh_errors`]: the model's mesh and its 2 × 2 and 3 × 3
/// subdivisions, Richardson per mode), so that the fit's intervals include them
/// ([`lamdyn_fit::fit`]). Modes up to 1.25 `top_hz` are estimated; those above get the largest
/// error found below them. Returns the model and a line saying what was found.
///
/// # Errors
/// The model's and the solver's errors.
pub fn with_discretization_error(
    model: ModalModel,
    spec: &ModelSpec,
    base: &Path,
    top_hz: f64,
    progress: &dyn Reporter,
) -> Result<(ModalModel, String)> {
    // The estimate is of the free modes the basis starts from: the supports stay out.
    let (mesh, _) = spec.build(base)?;
    let n_all = model.eigenvalues().len();
    let within = model
        .eigenvalues()
        .iter()
        .filter(|&&l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI) <= 1.25 * top_hz)
        .count();
    let n_est = (within + 2).clamp(7, n_all);
    progress.stage("estimating the model's discretization error (2x2 and 3x3 refined meshes)");
    let surface = spec.surface();
    let (mut errors, study) = lamdyn_fem::convergence::mesh_errors(
        &mesh,
        surface.as_deref(),
        &spec.material,
        &[],
        n_est,
        &AsProgress(progress),
    )?;
    let largest = errors.iter().fold(0.0f64, |a, d| a.max(d.abs()));
    errors.resize(n_all, largest);
    let finest = study.levels.last().map_or(0, |l| l.n_dofs);
    let mut line = format!(
        "discretization error estimated on 3 meshes (up to {finest} dofs): largest {largest:.2e} \
         in frequency over {} modes up to {:.0} Hz",
        n_est,
        1.25 * top_hz
    );
    for w in &study.warnings {
        line.push_str("; warning: ");
        line.push_str(w);
    }
    Ok((model.with_frequency_errors(errors)?, line))
}

/// Reads and validates a fit job, builds its modal model (module docs).
///
/// # Errors
/// The file's errors naming the field, the measurement's, the model's (see [`modal_model`]).
pub fn load_fit_job(path: &Path, progress: &dyn Reporter) -> Result<FitProblem> {
    let job: FitJob = read_toml(path)?;
    let base = base_of(path);
    let in_job = |why: String| err!("error in '{}': {why}", path.display());
    let Resolved {
        model: source,
        misfit,
        notes,
    } = job.resolve().map_err(|e| in_job(e.to_string()))?;
    let prominence = job.fit.prominence;
    if !(prominence.is_finite() && prominence > 1.0) {
        return Err(in_job(format!(
            "fit.prominence: {prominence} must be a ratio above 1"
        )));
    }
    let (spec, model_base, model_name) = match (&source.file, &source.spec) {
        (Some(f), None) => {
            let p = relative(&base, f);
            let spec: ModelSpec = read_toml(&p)?;
            (spec, base_of(&p), format!("'{}'", p.display()))
        }
        (None, Some(spec)) => (spec.clone(), base.clone(), "[model.spec]".to_string()),
        _ => {
            return Err(in_job(
                "model: give either file (a model TOML) or [model.spec], not both or neither"
                    .into(),
            ));
        }
    };
    let modes = source.modes.unwrap_or(spec.solver.modes);
    let measured = read_measurement_section(&job.measurement, misfit.band_hz, &base, path)?;
    let set = measured.set;
    if misfit.reference >= set.references().len() {
        return Err(in_job(format!(
            "fit.misfit.reference: {} but the measurement has {} reference(s), counted from 0",
            misfit.reference,
            set.references().len()
        )));
    }
    let clock = std::time::Instant::now();
    let (model, model_line) = modal_model(
        &spec,
        &model_base,
        &model_name,
        &measured.source,
        &set,
        SensorPlacement {
            tolerance_m: job.measurement.tolerance_m,
            mapping: job.measurement.sensor_mapping,
        },
        modes,
        source.residual,
        progress,
    )
    .map_err(|e| match e {
        crate::PipelineError::Invalid(m) => in_job(m),
        e => e,
    })?;
    let (model, model_line) = if job.fit.discretization_error {
        let top_hz = misfit
            .band_hz
            .map_or_else(|| set.freqs_hz().last().copied().unwrap_or(0.0), |b| b[1]);
        let (model, line) = with_discretization_error(model, &spec, &model_base, top_hz, progress)?;
        (model, format!("{model_line}; {line}"))
    } else {
        (model, model_line)
    };
    let mut settings = FitSettings::new(job.fit.law, misfit);
    if let Some(p) = &job.fit.poles {
        settings.poles = Some(read_poles(&relative(&base, p))?);
    }
    settings.covariance = job.fit.covariance;
    settings.prominence = prominence;
    let mut notes = notes;
    notes.extend(crate::io::encoding_notes([path]));
    notes.extend(measured.warnings);
    Ok(FitProblem {
        source: format!("job '{}': {}", path.display(), measured.source),
        model_line,
        model,
        measured: set,
        settings,
        truth: None,
        model_seconds: clock.elapsed().as_secs_f64(),
        notes,
    })
}
