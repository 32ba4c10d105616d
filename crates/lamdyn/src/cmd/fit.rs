//! `lamdyn fit`: measured FRFs + FE model → the effective modulus law E*(ω) of the laminate
//! (paper eqs. 2–10, Tables 2–3), with 95 % intervals, the mode-wise estimate, the Table-3
//! comparison and E'(f), η(f) at the modal frequencies.
//!
//! Two sources: a job file (TOML, see `examples/fit/`) naming a `lamdyn modes` model file and the
//! measurement as CSV (`lamdyn_frf::csv`), or `--example paper-plate[-zener]`, the recovery case
//! of docs/fit.md synthesized in memory from a known law. `--write-example DIR` writes that case
//! as a job with its files, so the file route can be tried on data whose truth is known.

use crate::Outcome;
use crate::cli::{CovarianceArg, FitArgs, FitExample, LawArg, MisfitArg};
use crate::progress::Spinner;
use crate::table::{Cell, Column, Fmt, Report, Section, write_csv_table};
use anyhow::{Context, Result, bail};
use lamdyn_fem::model::{MeshSpec, ModelSpec, SolverSpec};
use lamdyn_fit::fit::{Covariance, FitResult, FitSettings, LawKind, fit};
use lamdyn_fit::misfit::{MisfitKind, MisfitSpec, Objective};
use lamdyn_fit::modes::{compare_peaks, modewise};
use lamdyn_fit::synthetic::PaperPlateCase;
use lamdyn_material::law::{FractionalZener, PaperEq7Law, ViscoelasticLaw};
use lamdyn_pipeline::Reporter;
use lamdyn_pipeline::fit_job::{FitProblem, load_fit_job};
use lamdyn_pipeline::job::default_misfit;
use lamdyn_pipeline::output::OutputDir;
use std::f64::consts::PI;
use std::io::Write;
use std::path::PathBuf;

/// Everything a fit needs ([`lamdyn_pipeline::fit_job`]).
type Problem = FitProblem;

/// Runs `lamdyn fit`.
pub fn run(args: &FitArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    if !(args.noise.is_finite() && (0.0..1.0).contains(&args.noise)) {
        bail!("--noise {} must be a fraction in [0, 1)", args.noise);
    }
    let inputs: Vec<PathBuf> = args.job.iter().cloned().collect();
    let prepare = |d: &PathBuf| OutputDir::prepare(d, &inputs, args.force);
    let out_dir = args.out.as_ref().map(prepare).transpose()?;
    let example_dir = args.write_example.as_ref().map(prepare).transpose()?;
    let spinner = Spinner::new();
    let mut problem = match (&args.job, args.example) {
        (Some(path), _) => load_fit_job(path, &spinner)?,
        (None, Some(e)) => from_example(e, args.seed, args.noise)?,
        (None, None) => bail!("give a fit job file or --example"),
    };
    if let (Some(dir), Some(e)) = (&example_dir, args.example) {
        write_example(dir, e, &problem)?;
        writeln!(
            err,
            "lamdyn: wrote the example as a job to '{}'",
            dir.path().display()
        )?;
    }
    let flag_notes = apply_flags(args, &mut problem.settings);
    problem.notes.extend(flag_notes);
    if let Some(path) = &args.poles {
        problem.settings.poles = Some(lamdyn_pipeline::fit_job::read_poles(path)?);
    }
    if let Some(poles) = &problem.settings.poles {
        problem.notes.push(format!(
            "peaks: {} identified poles (freq_hz, damping_ratio) instead of the RMS FRF's peaks; \
             the mode-wise eta from each pole's zeta",
            poles.len()
        ));
    }
    spinner.stage("fitting the modulus law");
    let result =
        fit(&problem.model, &problem.measured, &problem.settings).context("the fit failed")?;
    spinner.finish();
    let objective = Objective::new(
        &problem.model,
        &problem.measured,
        problem.settings.misfit.clone(),
    )?;
    let fitted_rms = objective.model_rms(&|w| result.modulus(w));
    let report = build_report(&problem, &result, &objective, &fitted_rms);
    if let Some(dir) = &out_dir {
        write_outputs(
            dir,
            &report,
            &problem,
            objective.measured_rms(),
            &fitted_rms,
        )?;
    }
    report.write(args.output.format(), out, err)?;
    Ok(if result.converged {
        Outcome::Done
    } else {
        writeln!(
            err,
            "lamdyn: the best start did not converge ({}): the parameters are the last iterate",
            result.reason
        )?;
        Outcome::ChecksFailed
    })
}

/// The command line's overrides; old spellings (`eq7`, `zener`, `per-mode`, `log-rms`, `hc3`)
/// are read with a deprecation note.
fn apply_flags(args: &FitArgs, settings: &mut FitSettings) -> Vec<String> {
    let mut notes = Vec::new();
    let mut old = |was: &str, now: &str| {
        notes.push(format!(
            "deprecated: {was}; write {now} (the job file's spelling)"
        ));
    };
    if let Some(law) = args.law {
        settings.law = match law {
            LawArg::PaperEq7 => LawKind::PaperEq7,
            LawArg::FractionalZener => LawKind::FractionalZener,
            LawArg::PerMode => LawKind::PerMode,
            LawArg::Eq7 => {
                old("--law eq7", "--law paper_eq7");
                LawKind::PaperEq7
            }
            LawArg::Zener => {
                old("--law zener", "--law fractional_zener");
                LawKind::FractionalZener
            }
            LawArg::PerModeKebab => {
                old("--law per-mode", "--law per_mode");
                LawKind::PerMode
            }
        };
    }
    if let Some(m) = args.misfit {
        settings.misfit.kind = match m {
            MisfitArg::Rms => MisfitKind::Rms,
            MisfitArg::LogRms => MisfitKind::LogRms,
            MisfitArg::Complex => MisfitKind::Complex,
            MisfitArg::LogRmsKebab => {
                old("--misfit log-rms", "--misfit log_rms");
                MisfitKind::LogRms
            }
        };
    }
    if let Some(c) = args.covariance {
        settings.covariance = match c {
            CovarianceArg::RobustHc3 => Covariance::RobustHc3,
            CovarianceArg::Classical => Covariance::Classical,
            CovarianceArg::Hc3 => {
                old("--covariance hc3", "--covariance robust_hc3");
                Covariance::RobustHc3
            }
        };
    }
    notes
}

/// The truth of a built-in example and its parameters in the fit's order: the paper's Table 2
/// law, or the fractional Zener of the recovery test (G0 60 GPa, G∞ 75 GPa, τ 3 ms, α 0.5).
fn truth_law(e: FitExample) -> Result<(Box<dyn ViscoelasticLaw>, Vec<f64>)> {
    Ok(match e {
        FitExample::PaperPlate => (
            Box::new(PaperEq7Law::paper_table2()),
            vec![67.45e9, 0.686e-3, 4.295e-3, 1.617e6],
        ),
        FitExample::PaperPlateZener => {
            let p = [60e9, 75e9, 3e-3, 0.5];
            (
                Box::new(FractionalZener::new(p[0], p[1], p[2], p[3])?),
                p.to_vec(),
            )
        }
    })
}

fn from_example(e: FitExample, seed: u64, noise: f64) -> Result<Problem> {
    let (truth, truth_params) = truth_law(e)?;
    let case = PaperPlateCase {
        seed,
        noise,
        ..PaperPlateCase::default()
    };
    let built = case.build(&|w| truth.modulus(w))?;
    let law = match e {
        FitExample::PaperPlate => LawKind::PaperEq7,
        FitExample::PaperPlateZener => LawKind::FractionalZener,
    };
    Ok(Problem {
        source: format!(
            "built-in {e:?}: synthetic FRFs from {}, {:.1} % complex noise, seed {seed}",
            truth.describe(),
            100.0 * noise
        ),
        model_line: format!(
            "flat 0.923 x 0.8632 m plate, {0}, {1} modes + residual term, E_ref = {2:.4e} Pa",
            case.mesh_line(),
            case.modes,
            PaperPlateCase::GLASS.young_pa
        ),
        model: built.model,
        measured: built.measured,
        settings: FitSettings::new(law, default_misfit()),
        truth: Some((truth, truth_params)),
        model_seconds: built.model_seconds,
        notes: Vec::new(),
    })
}

/// Writes the example case as a job directory: model.toml, channels.csv, frf.csv, job.toml.
fn write_example(dir: &OutputDir, e: FitExample, problem: &Problem) -> Result<()> {
    let case = PaperPlateCase::default();
    let spec = ModelSpec {
        mesh: MeshSpec::Rectangle(case.mesh_spec()),
        material: PaperPlateCase::GLASS,
        supports: vec![],
        solver: SolverSpec {
            modes: case.modes,
            shift_hz: None,
        },
    };
    // TOML has no infinity literal for a flat plate in this spec: leave the radii out.
    let model = toml::to_string(&spec)?
        .lines()
        .filter(|l| !l.starts_with("radius_"))
        .collect::<Vec<_>>()
        .join("\n");
    let law = match e {
        FitExample::PaperPlate => "paper_eq7",
        FitExample::PaperPlateZener => "fractional_zener",
    };
    let job = format!(
        "# lamdyn fit job written by `lamdyn fit --example {}`: {}\n\
         [measurement]\nchannels = \"channels.csv\"\nfrf = \"frf.csv\"\ntolerance_m = 1e-6\n\n\
         [model]\nfile = \"model.toml\"\nresidual = true\n\n\
         [fit]\nlaw = \"{law}\"\ncovariance = \"robust_hc3\"\n\n[fit.misfit]\nkind = \"log_rms\"\n",
        match e {
            FitExample::PaperPlate => "paper-plate",
            FitExample::PaperPlateZener => "paper-plate-zener",
        },
        problem.source
    );
    Ok(dir.write(&[
        (
            "model.toml",
            format!("# The paper's plate, flat, free.\n{model}\n").into_bytes(),
        ),
        (
            "channels.csv",
            lamdyn_frf::csv::write_channels(&problem.measured).into_bytes(),
        ),
        (
            "frf.csv",
            lamdyn_frf::csv::write_frf(&problem.measured).into_bytes(),
        ),
        ("job.toml", job.into_bytes()),
    ])?)
}

fn build_report(
    problem: &Problem,
    r: &FitResult,
    objective: &Objective<'_>,
    fitted_rms: &[f64],
) -> Report {
    let truth = problem.truth.as_ref().map(|(t, _)| t.as_ref());
    let mut report = Report::new("fit", law_columns(truth.is_some()));
    add_inputs(&mut report, problem, r, objective);
    let s = &problem.settings;
    let truth_params = problem.truth.as_ref().map(|(_, p)| p.as_slice());
    report.sections.push(parameters_section(r, truth_params));
    report.sections.push(starts_section(r));
    report
        .sections
        .push(table3_section(problem, objective, fitted_rms));
    report.sections.push(modewise_section(problem, r));
    for pk in &r.peaks {
        let w = 2.0 * PI * pk.freq_hz;
        let (e, eta, sd) = r.modulus_uncertainty(w);
        let mut row: Vec<Cell> = vec![
            pk.freq_hz.into(),
            e.into(),
            sd.map(|s| s.0).into(),
            eta.into(),
            sd.map(|s| s.1).into(),
        ];
        if let Some(t) = truth {
            let tm = t.modulus(w);
            row.push((e / tm.re - 1.0).into());
            row.push((eta / (tm.im / tm.re) - 1.0).into());
        }
        report.row(row);
    }
    report.notes.push(
        "Main table: the fitted law at the measured resonances (sd by the delta \
         method through the parameter covariance); its CSV (--csv) is a `lamdyn core \
         --table` input."
            .into(),
    );
    report.notes.push(
        "Table 3: peaks of the measured and fitted RMS FRFs, parabolic refinement in \
         log magnitude; damping ratio by the half-power bandwidth on the RMS curve, \
         linearly interpolated between lines ('-' when the bandwidth spans less than \
         two lines)."
            .into(),
    );
    report.notes.push(
        "Mode-wise: E' = E_ref (f_exp/f_num)^2 at each measured peak (or identified pole); eta = 2 \
         zeta (1 - beta/2), zeta the resonance's damping (half-power or the pole's), beta = d ln \
         E'/d ln f between neighbouring resonances (docs/fit.md)."
            .into(),
    );
    report.warnings.extend(problem.notes.iter().cloned());
    report.warnings.extend(r.warnings.iter().cloned());
    if !r.converged {
        report.warnings.push(format!(
            "the best start stopped without meeting a tolerance: {}",
            r.reason
        ));
    }
    report.extra = Some(
        serde_json::json!({ "fit": r, "settings": { "law": s.law, "misfit": s.misfit, "covariance": s.covariance } }),
    );
    report
}

/// The main table's columns: the law at the resonances, with its errors against a truth.
fn law_columns(truth: bool) -> Vec<Column> {
    let mut columns = vec![
        Column::new("f_hz", "f", "Hz", Fmt::Fixed(3)),
        Column::new("e_storage_pa", "E'", "GPa", Fmt::Fixed(4)).scaled(1e9),
        Column::new("e_storage_sd_pa", "sd E'", "GPa", Fmt::Fixed(4)).scaled(1e9),
        Column::new("loss_factor", "eta", "", Fmt::Sci(4)),
        Column::new("loss_factor_sd", "sd eta", "", Fmt::Sci(2)),
    ];
    if truth {
        columns
            .push(Column::new("truth_e_storage_error", "E' err", "%", Fmt::Fixed(4)).scaled(0.01));
        columns.push(
            Column::new("truth_loss_factor_error", "eta err", "%", Fmt::Fixed(2)).scaled(0.01),
        );
    }
    columns
}

/// The inputs: the data, the model, the measurement, the misfit, the law and the convergence.
fn add_inputs(report: &mut Report, problem: &Problem, r: &FitResult, objective: &Objective<'_>) {
    report.input("data", problem.source.clone());
    report.input(
        "model",
        format!(
            "{} (built in {:.2} s)",
            problem.model_line, problem.model_seconds
        ),
    );
    let m = &problem.measured;
    let s = &problem.settings;
    report.input(
        "measurement",
        format!(
            "{} responses x {} references, {} lines {:.3}-{:.3} Hz, {}",
            m.responses().len(),
            m.references().len(),
            m.n_lines(),
            m.freqs_hz()[0],
            m.freqs_hz()[m.n_lines() - 1],
            m.quantity().unit()
        ),
    );
    report.input("misfit", misfit_line(&s.misfit, objective.lines().len()));
    let law = match s.law {
        LawKind::PaperEq7 => "paper eq. 7",
        LawKind::FractionalZener => "fractional Zener",
        LawKind::PerMode => "per mode (E', eta at each resonance, splined in log-log)",
    };
    let cov = match s.covariance {
        Covariance::RobustHc3 => "HC3 sandwich",
        Covariance::Classical => "classical",
    };
    report.input(
        "law",
        format!("{law}; covariance {cov}; 95 % intervals = +-1.96 sd"),
    );
    report.input(
        "convergence",
        format!(
            "{} ({}), cost {:.6e}, residual rms {:.4e} over {} residuals, {} misfit evaluations, \
             {:.3} s",
            if r.converged {
                "converged"
            } else {
                "NOT converged"
            },
            r.reason,
            r.cost,
            r.residual_rms,
            r.n_residuals,
            r.evaluations,
            r.seconds
        ),
    );
}

/// "log_rms over 320 lines (band 1-80 Hz, excluding 17-21 Hz; 1 weighted band), reference 0".
fn misfit_line(m: &MisfitSpec, n_lines: usize) -> String {
    let kind = match m.kind {
        MisfitKind::Rms => "RMS (paper eqs. 2, 10)",
        MisfitKind::LogRms => "log-RMS",
        MisfitKind::Complex => "complex FRF",
    };
    let band = m
        .band_hz
        .map_or("all lines".to_string(), |[a, b]| format!("band {a}-{b} Hz"));
    let excluded: Vec<String> = m
        .exclude_hz
        .iter()
        .map(|[a, b]| format!("{a}-{b} Hz"))
        .collect();
    let excluded = if excluded.is_empty() {
        String::new()
    } else {
        format!(", excluding {}", excluded.join(", "))
    };
    format!(
        "{kind} over {n_lines} lines ({band}{excluded}; {} weighted bands), reference {}",
        m.weights.len(),
        m.reference
    )
}

fn parameters_section(r: &FitResult, truth_values: Option<&[f64]>) -> Section {
    let mut columns = vec![
        Column::new("name", "parameter", "", Fmt::Fixed(0)),
        Column::new("value", "value", "", Fmt::Sci(6)),
        Column::new("std_dev", "sd", "", Fmt::Sci(3)),
        Column::new("ci95_low", "95% low", "", Fmt::Sci(4)),
        Column::new("ci95_high", "95% high", "", Fmt::Sci(4)),
    ];
    // Truth columns only when the fitted law is the truth's family.
    let truth_values = truth_values.filter(|t| {
        t.len() == r.parameters.len()
            && !matches!(r.law, lamdyn_fit::law::LawChoice::PerMode { .. })
    });
    if truth_values.is_some() {
        columns.push(Column::new("truth", "truth", "", Fmt::Sci(6)));
        columns.push(Column::new(
            "truth_inside_ci95",
            "inside",
            "",
            Fmt::Fixed(0),
        ));
    }
    let mut sec = Section::new("parameters", "Parameters (SI: Pa, s, Pa s)", columns);
    for (k, p) in r.parameters.iter().enumerate() {
        let mut row: Vec<Cell> = vec![
            p.name.clone().into(),
            p.value.into(),
            p.std_dev.into(),
            p.ci95.map(|c| c[0]).into(),
            p.ci95.map(|c| c[1]).into(),
        ];
        if let Some(t) = truth_values {
            let tv = t.get(k).copied().unwrap_or(f64::NAN);
            row.push(tv.into());
            row.push(match p.ci95 {
                Some([lo, hi]) => if (lo..=hi).contains(&tv) { "yes" } else { "no" }.into(),
                None => Cell::Empty,
            });
        }
        sec.row(row);
    }
    sec
}

fn starts_section(r: &FitResult) -> Section {
    let mut sec = Section::new(
        "starts",
        "Levenberg-Marquardt starts (best screened grid points)",
        vec![
            Column::new("start", "start", "", Fmt::Fixed(0)),
            Column::new("parameters", "parameters at the start", "", Fmt::Fixed(0)),
            Column::new("cost", "final cost", "", Fmt::Sci(6)),
            Column::new("iterations", "iterations", "", Fmt::Fixed(0)),
            Column::new("converged", "converged", "", Fmt::Fixed(0)),
        ],
    );
    for (k, st) in r.starts.iter().enumerate() {
        let p: Vec<String> = st.start.iter().map(|v| format!("{v:.4e}")).collect();
        sec.row(vec![
            ((k + 1) as f64).into(),
            p.join(" ").into(),
            st.cost.into(),
            (st.iterations as f64).into(),
            if st.converged { "yes" } else { "no" }.into(),
        ]);
    }
    sec
}

fn table3_section(problem: &Problem, objective: &Objective<'_>, fitted_rms: &[f64]) -> Section {
    let unit = problem.measured.quantity().unit();
    let mut sec = Section::new(
        "table3",
        format!("Table 3: RMS FRF peaks, measured vs fitted (amplitude in {unit})"),
        vec![
            Column::new("f_measured_hz", "f meas", "Hz", Fmt::Fixed(3)),
            Column::new("f_fitted_hz", "f fit", "Hz", Fmt::Fixed(3)),
            Column::new("f_error", "err", "%", Fmt::Fixed(3)).scaled(0.01),
            Column::new("amplitude_measured", "amp meas", "", Fmt::Sci(4)),
            Column::new("amplitude_fitted", "amp fit", "", Fmt::Sci(4)),
            Column::new("amplitude_error", "err", "%", Fmt::Fixed(2)).scaled(0.01),
            Column::new("damping_ratio_measured", "zeta meas", "", Fmt::Sci(3)),
            Column::new("damping_ratio_fitted", "zeta fit", "", Fmt::Sci(3)),
            Column::new("damping_ratio_error", "err", "%", Fmt::Fixed(1)).scaled(0.01),
        ],
    );
    let rows = compare_peaks(
        problem.measured.freqs_hz(),
        objective.measured_rms(),
        fitted_rms,
        objective.lines(),
        problem.settings.prominence,
    );
    for c in rows {
        sec.row(vec![
            c.measured.freq_hz.into(),
            c.fitted.freq_hz.into(),
            c.freq_error.into(),
            c.measured.amplitude.into(),
            c.fitted.amplitude.into(),
            c.amplitude_error.into(),
            c.measured.damping_ratio.into(),
            c.fitted.damping_ratio.into(),
            c.damping_error.into(),
        ]);
    }
    sec
}

fn modewise_section(problem: &Problem, r: &FitResult) -> Section {
    let mut sec = Section::new(
        "modewise",
        "Mode-wise estimate: E' = E_ref (f_exp/f_num)^2, eta = 2 zeta (1 - beta/2)",
        vec![
            Column::new("f_measured_hz", "f meas", "Hz", Fmt::Fixed(3)),
            Column::new("f_fe_hz", "f FE at E_ref", "Hz", Fmt::Fixed(3)),
            Column::new("e_storage_pa", "E'", "GPa", Fmt::Fixed(4)).scaled(1e9),
            Column::new("loss_factor", "eta", "", Fmt::Sci(3)),
        ],
    );
    for m in modewise(&problem.model, &r.peaks) {
        sec.row(vec![
            m.freq_exp_hz.into(),
            m.freq_num_hz.into(),
            m.storage_pa.into(),
            m.loss_factor.into(),
        ]);
    }
    sec
}

/// `--out DIR`: report.json, one CSV per table, and the RMS curves (paper Fig. 5).
fn write_outputs(
    dir: &OutputDir,
    report: &Report,
    problem: &Problem,
    measured_rms: &[f64],
    fitted_rms: &[f64],
) -> Result<()> {
    let csv = |columns: &[Column], rows: &[Vec<Cell>]| -> Result<Vec<u8>> {
        let mut buf = Vec::new();
        write_csv_table(&mut buf, columns, rows)?;
        Ok(buf)
    };
    let mut files: Vec<(String, Vec<u8>)> = vec![
        (
            "report.json".into(),
            serde_json::to_vec_pretty(&report.to_json())?,
        ),
        ("modulus.csv".into(), csv(&report.columns, &report.rows)?),
    ];
    for s in &report.sections {
        files.push((format!("{}.csv", s.key), csv(&s.columns, &s.rows)?));
    }
    let unit = problem.measured.quantity().unit();
    let mut rms = format!("# RMS FRF over the responses ({unit})\nf_hz,measured,fitted\n");
    for ((f, a), b) in problem
        .measured
        .freqs_hz()
        .iter()
        .zip(measured_rms)
        .zip(fitted_rms)
    {
        rms.push_str(&format!("{f},{a:e},{b:e}\n"));
    }
    files.push(("rms.csv".into(), rms.into_bytes()));
    let named: Vec<(&str, Vec<u8>)> = files.iter().map(|(n, b)| (n.as_str(), b.clone())).collect();
    Ok(dir.write(&named)?)
}
