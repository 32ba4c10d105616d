//! `lamdyn ema`: measured FRFs (UFF or CSV) or hammer-test time data (CSV, one file per hit) →
//! stabilization diagram, modes with damping and shapes, the regenerated FRFs' correlation and
//! the CMIF peaks (lamdyn-ema does the work), and with `--out` a results folder with the charts
//! (lamdyn-report draws them).

use crate::Outcome;
use crate::cli::{EmaArgs, Estimator, ExcitationArg, QuantityArg, WindowArg};
use crate::progress::Spinner;
use crate::table::{Column, Fmt, Report, Section};
use anyhow::{Context, Result, anyhow, bail};
use lamdyn_ema::identify::{
    DiagramEstimator, EmaResult, EmaSettings, EmaTimings, Mode, PoleEstimator, identify_with,
};
use lamdyn_ema::lscf::{pole_damping, pole_freq_hz};
use lamdyn_ema::quality::Verdict;
use lamdyn_ema::spectra::Spectra;
use lamdyn_ema::stabilization::Pick;
use lamdyn_ema::welch::Window;
use lamdyn_frf::FrfSet;
use lamdyn_pipeline::Reporter;
use lamdyn_pipeline::measurement::{Excitation, ExcitationKind, TimeOptions, read_frfs, time_frfs};
use lamdyn_pipeline::output::OutputDir;
use std::io::Write;
use std::path::{Path, PathBuf};

/// What the time data added: the estimator's warnings and each response's coherence.
struct TimeInfo {
    hits: usize,
    spectra: Spectra,
}

/// FRFs estimated from hammer-test time files (one per hit) and the channels table.
fn frfs_from_time(
    channels: &Path,
    files: &[PathBuf],
    args: &EmaArgs,
) -> Result<(FrfSet, TimeInfo)> {
    let options = TimeOptions {
        estimator: match args.estimator {
            Estimator::H1 => lamdyn_pipeline::measurement::Estimator::H1,
            Estimator::H2 => lamdyn_pipeline::measurement::Estimator::H2,
            Estimator::Hv => lamdyn_pipeline::measurement::Estimator::Hv,
        },
        trigger: args.trigger,
        pretrigger_s: args.pretrigger_s,
        force_window_s: args.force_window_s,
        record_s: args.record_s,
        exp_tau_s: args.exp_tau_s,
        excitation: excitation(args)?,
        quantity: args.quantity.map(|q| match q {
            QuantityArg::Receptance => lamdyn_frf::Quantity::Receptance,
            QuantityArg::Mobility => lamdyn_frf::Quantity::Mobility,
            QuantityArg::Accelerance => lamdyn_frf::Quantity::Accelerance,
        }),
    };
    let (set, spectra, hits) = time_frfs(channels, files, &options)?;
    Ok((set, TimeInfo { hits, spectra }))
}

/// The excitation's estimator settings from the flags (defaults as `--help` states).
fn excitation(args: &EmaArgs) -> Result<Excitation> {
    let kind = match args.excitation {
        ExcitationArg::Impact => ExcitationKind::Impact,
        ExcitationArg::Random => ExcitationKind::Random,
        ExcitationArg::Burst => ExcitationKind::Burst,
        ExcitationArg::Periodic => ExcitationKind::Periodic,
        ExcitationArg::Sweep => ExcitationKind::Sweep,
    };
    if kind == ExcitationKind::Impact {
        if args.window.is_some() || args.segment_s.is_some() || args.overlap.is_some() {
            bail!(
                "--window, --segment-s and --overlap are for continuous excitation: give \
                 --excitation random|burst|periodic|sweep"
            );
        }
    } else if args.exp_tau_s.is_some() {
        bail!("--exp-tau-s is a hammer-test window: continuous excitation takes --window");
    }
    let window = args.window.map(|w| match w {
        WindowArg::Hann => Window::Hann,
        WindowArg::Flattop => Window::FlatTop,
        WindowArg::Rect => Window::Rectangular,
    });
    let band_hz = match args.band_hz.as_deref() {
        Some(&[lo, hi]) => Some([lo, hi]),
        _ => None,
    };
    Excitation::new(kind, window, args.segment_s, args.overlap, band_hz)
        .map_err(|e| anyhow!("--excitation: {e}"))
}

fn settings(args: &EmaArgs, set: &FrfSet) -> Result<EmaSettings> {
    let mut s = EmaSettings {
        orders: (
            args.min_order as usize,
            args.max_order as usize,
            args.order_step as usize,
        ),
        near_hz: args.near_hz.clone(),
        reject_hz: args.reject_hz.clone().unwrap_or_default(),
        polymax: !args.single_reference,
        window_hz: args.window_hz,
        exp_tau_s: args.exp_tau_s,
        cmif_prominence: args.cmif_prominence,
        ..Default::default()
    };
    if let Some(b) = &args.band_hz {
        let [lo, hi] = b[..] else {
            bail!(
                "--band-hz takes two frequencies LO,HI, got {} values",
                b.len()
            )
        };
        s.band_hz = Some([lo, hi]);
    }
    s.estimator = args.poles.into();
    if args.no_refine {
        s.refine_iterations = 0;
    }
    if args.window_hz <= 0.0 {
        bail!("--window-hz {} must be positive", args.window_hz);
    }
    if let Some(t) = args.exp_tau_s {
        if t <= 0.0 {
            bail!("--exp-tau-s {t} must be a positive time constant");
        }
    }
    if let Some(name) = &args.driving {
        let i = set
            .responses()
            .iter()
            .position(|c| &c.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = set
                    .responses()
                    .iter()
                    .take(8)
                    .map(|c| c.name.as_str())
                    .collect();
                anyhow!(
                    "--driving '{name}' is not a response of the data (responses: {}{})",
                    names.join(", "),
                    if set.responses().len() > 8 {
                        ", ..."
                    } else {
                        ""
                    }
                )
            })?;
        s.driving = Some(i);
    }
    Ok(s)
}

/// Runs `lamdyn ema`.
pub fn run(args: &EmaArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let inputs: Vec<PathBuf> = [&args.uff, &args.channels, &args.frf]
        .into_iter()
        .flatten()
        .chain(&args.time)
        .cloned()
        .collect();
    let out_dir = args
        .out
        .as_ref()
        .map(|d| OutputDir::prepare(d, &inputs, args.force))
        .transpose()?;
    let clock = std::time::Instant::now();
    let (set, source, time) = match (&args.channels, args.time.is_empty()) {
        (Some(c), false) => {
            let (set, info) = frfs_from_time(c, &args.time, args)?;
            let src = format!(
                "{} hit(s) of time data ({:?} estimator) with channels '{}'",
                info.hits,
                args.estimator,
                c.display()
            );
            (set, src, Some(info))
        }
        _ => {
            let (set, src) = read_frfs(
                args.uff.as_deref(),
                args.channels.as_deref(),
                args.frf.as_deref(),
            )?;
            (set, src, None)
        }
    };
    let read_s = clock.elapsed().as_secs_f64();
    let s = settings(args, &set)?;
    let spinner = Spinner::new();
    let r = identify_with(&set, &s, &|step| spinner.stage(step));
    spinner.finish();
    let r = r.context("identification failed")?;
    let mut report = build_report(&set, &source, &s, &r, read_s);
    let texts = args.channels.iter().chain(&args.frf).chain(&args.time);
    report.warnings.extend(lamdyn_pipeline::io::encoding_notes(
        texts.map(|p| p.as_path()),
    ));
    report.warnings.extend(r.warnings.iter().cloned());
    if let Some(info) = &time {
        add_time_info(&mut report, &set, &r, info);
    }
    if let Some(dir) = &out_dir {
        write_results(dir, &set, &r, &report, time.as_ref())?;
        report.notes.push(format!(
            "results and charts written to '{}'",
            dir.path().display()
        ));
    }
    report.write(args.output.format(), out, err)?;
    Ok(
        if r.correlation.iter().all(|c| *c >= 0.9) && r.missing_hz.is_empty() {
            Outcome::Done
        } else {
            Outcome::ChecksFailed
        },
    )
}

/// The verdict cell: the verdict, with `*` for a pole picked at a CMIF peak.
fn verdict_cell(m: &Mode) -> String {
    let mark = if m.pick == Pick::CmifPeak { "*" } else { "" };
    format!("{}{mark}", m.quality.verdict.label())
}

/// Where the mode's pole comes from: "refined", "diagram", or "put back" (the diagram's, where
/// the refinement left the pole's column or moved a pole beside one that left).
fn pole_source(m: &Mode) -> &'static str {
    use lamdyn_ema::identify::RefinementOutcome::{BesideALostPole, LeftItsColumn};
    match m.refinement.map(|q| q.outcome) {
        Some(LeftItsColumn | BesideALostPole) => "put back",
        _ if m.refined => "refined",
        _ => "diagram",
    }
}

/// One line per mode that is not sound: its number, frequency, verdict and reasons.
fn verdict_lines(modes: &[Mode]) -> Vec<(Verdict, String)> {
    modes
        .iter()
        .enumerate()
        .filter(|(_, m)| m.quality.verdict != Verdict::Sound)
        .map(|(k, m)| {
            let line = format!(
                "mode {} ({:.4} Hz) is {}: {}.",
                k + 1,
                m.freq_hz,
                m.quality.verdict.label(),
                m.quality.reasons()
            );
            (m.quality.verdict, line)
        })
        .collect()
}

/// What the `stable` column counts, for each way the modes' poles were picked.
fn stable_footnote(modes: &[Mode]) -> String {
    let mut picks: Vec<Pick> = modes.iter().map(|m| m.pick).collect();
    picks.sort_by_key(|p| *p as u8);
    picks.dedup();
    let what: Vec<String> = picks
        .iter()
        .map(|p| match p {
            Pick::CmifPeak => format!("marked * in verdict: {}", p.counts()),
            _ => p.counts().to_string(),
        })
        .collect();
    format!("stable: {}.", what.join("; "))
}

/// The method's last step, in words, as it runs on `set`'s curves.
fn estimator_text(s: &EmaSettings, set: &FrfSet) -> &'static str {
    match s.estimator.on(set.responses().len()) {
        _ if s.refine_iterations == 0 => "LSFD residues on the diagram's poles",
        PoleEstimator::Diagram => "LSFD residues on the diagram's poles",
        PoleEstimator::Refined => "poles refined with LSFD residues (variable projection)",
        PoleEstimator::Checked => {
            "poles refined with LSFD residues (variable projection), each refined pole kept only \
             where it fits significantly better than the diagram's in the LSCF model's own context"
        }
        PoleEstimator::RankOne if set.references().len() < 2 => {
            "poles fitted jointly with each mode's residues over the responses (variable \
             projection), beside the modes the selection left out that the curves need, each \
             fitted pole kept only where it fits significantly better than the diagram's in the \
             LSCF model's own context, then LSFD residues"
        }
        PoleEstimator::RankOne => {
            "poles and participation factors fitted jointly with rank-one residues (shape times \
             participation), then LSFD residues"
        }
    }
}

/// Each step's label and seconds, reading the data first.
fn steps(read_s: f64, t: &EmaTimings) -> impl Iterator<Item = (&'static str, f64)> {
    std::iter::once(("read", read_s)).chain(t.steps())
}

/// The time of each step in seconds, reading the data first, and the total.
fn time_text(read_s: f64, t: &EmaTimings) -> String {
    let steps: Vec<String> = steps(read_s, t)
        .map(|(step, s)| format!("{step} {s:.3}"))
        .collect();
    format!("{} s; total {:.3} s", steps.join(", "), read_s + t.total())
}

/// The step times as JSON: seconds per step.
fn time_json(read_s: f64, t: &EmaTimings) -> serde_json::Value {
    steps(read_s, t)
        .map(|(step, s)| (step.to_string(), serde_json::json!(s)))
        .collect::<serde_json::Map<_, _>>()
        .into()
}

fn build_report(set: &FrfSet, source: &str, s: &EmaSettings, r: &EmaResult, read_s: f64) -> Report {
    let mut report = Report::new("ema", mode_columns());
    report.input("data", source.to_string());
    report.input(
        "FRFs",
        format!(
            "{} responses x {} references, {} lines, {}",
            set.responses().len(),
            set.references().len(),
            set.n_lines(),
            set.quantity().unit()
        ),
    );
    report.input("method", method_line(set, s, r));
    if let Some(t) = s.exp_tau_s {
        report.input(
            "exponential window",
            format!(
                "tau = {t} s: 1/tau = {:.4} 1/s removed from every pole's decay rate",
                1.0 / t
            ),
        );
    }
    report.input("time", time_text(read_s, &r.timings));
    for (k, m) in r.modes.iter().enumerate() {
        report.row(vec![
            ((k + 1) as f64).into(),
            m.freq_hz.into(),
            m.sd.map(|d| d.freq_hz).into(),
            m.damping_ratio.into(),
            m.sd.map(|d| d.damping_ratio).into(),
            m.loss_factor.into(),
            m.mpc.into(),
            m.mpd_deg.into(),
            (m.stable_count as f64).into(),
            m.quality.frac_drop.into(),
            m.quality.second_shape.map(|t| t.statistic).into(),
            m.quality.second_shape.map(|t| t.relative_amplitude).into(),
            verdict_cell(m).into(),
            pole_source(m).into(),
            pole_freq_hz(m.diagram_pole).into(),
            pole_damping(m.diagram_pole).into(),
            m.refinement.map(|q| pole_freq_hz(q.pole)).into(),
            m.refinement.map(|q| pole_damping(q.pole)).into(),
        ]);
    }
    for (verdict, line) in verdict_lines(&r.modes) {
        if verdict == Verdict::Smear {
            report.warnings.push(line);
        } else {
            report.notes.push(line);
        }
    }
    add_sections(&mut report, r);
    add_warnings_and_notes(&mut report, s, r);
    report.extra = Some(extra_json(set, r, read_s));
    report
}

/// The modes table's columns.
fn mode_columns() -> Vec<Column> {
    vec![
        Column::new("mode", "mode", "", Fmt::Fixed(0)),
        Column::new("freq_hz", "f", "Hz", Fmt::Fixed(4)),
        Column::new("freq_sd_hz", "sd(f)", "Hz", Fmt::Sci(1)),
        Column::new("damping_ratio", "zeta", "%", Fmt::Fixed(4)).scaled(0.01),
        Column::new("damping_sd", "sd(zeta)", "%", Fmt::Sci(1)).scaled(0.01),
        Column::new("loss_factor", "eta", "", Fmt::Sci(4)),
        Column::new("mpc", "MPC", "", Fmt::Fixed(4)),
        Column::new("mpd_deg", "MPD", "deg", Fmt::Fixed(2)),
        Column::new("stable_poles", "stable", "", Fmt::Fixed(0)),
        Column::new("frac_drop", "FRAC drop", "", Fmt::Sci(2)),
        Column::new("second_shape_z", "2nd shape Z", "", Fmt::Sci(2)),
        Column::new("second_shape_rho", "2nd shape rho", "", Fmt::Fixed(3)),
        Column::new("verdict", "verdict", "", Fmt::Fixed(0)),
        Column::new("pole", "pole", "", Fmt::Fixed(0)),
        Column::new("diagram_freq_hz", "f (diagram)", "Hz", Fmt::Fixed(4)),
        Column::new(
            "diagram_damping_ratio",
            "zeta (diagram)",
            "%",
            Fmt::Fixed(4),
        )
        .scaled(0.01),
        Column::new("refined_freq_hz", "f (refined)", "Hz", Fmt::Fixed(4)),
        Column::new(
            "refined_damping_ratio",
            "zeta (refined)",
            "%",
            Fmt::Fixed(4),
        )
        .scaled(0.01),
    ]
}

/// The diagram's estimator, as `identify` chooses it ([`DiagramEstimator::of`]).
fn estimator_name(set: &FrfSet, s: &EmaSettings) -> &'static str {
    let (responses, references) = (set.responses().len(), set.references().len());
    match DiagramEstimator::of(responses, references, s.polymax) {
        DiagramEstimator::Lscf => "LSCF (z-domain common denominator)",
        DiagramEstimator::PolyMax { transposed: true } => {
            "PolyMAX (multi-reference pLSCF, z-domain matrix-fraction model; over the responses, \
             fewer than the references)"
        }
        DiagramEstimator::PolyMax { transposed: false } => {
            "PolyMAX (multi-reference pLSCF, z-domain matrix-fraction model)"
        }
    }
}

/// The method line: the estimator, orders, band, stability criteria, selection and pole
/// estimator.
fn method_line(set: &FrfSet, s: &EmaSettings, r: &EmaResult) -> String {
    format!(
        "{} orders {}-{} step {} on {:.3}-{:.3} Hz; stable: df/f <= {} %, dzeta/zeta <= {} %{}; \
         {}; {}",
        estimator_name(set, s),
        s.orders.0,
        s.orders.1,
        s.orders.2,
        r.band_hz[0],
        r.band_hz[1],
        100.0 * s.criteria.freq_tol,
        100.0 * s.criteria.damping_tol,
        if s.mode_vectors {
            format!(
                ", 1 - MAC(mode vectors) <= {} %",
                100.0 * s.criteria.vector_tol
            )
        } else {
            String::new()
        },
        if s.near_hz.is_some() {
            "poles picked near the given frequencies"
        } else {
            "automatic selection (clusters stable over half the orders)"
        },
        estimator_text(s, set)
    )
}

/// The sections beside the modes: the regenerated FRFs' correlation, the rejected poles and
/// the CMIF peaks.
fn add_sections(report: &mut Report, r: &EmaResult) {
    let mut corr = Section::new(
        "correlation",
        "Regenerated FRFs against the measured ones (FRAC over the band)",
        vec![
            Column::new("curve", "response@reference", "", Fmt::Fixed(0)),
            Column::new("frac", "FRAC", "", Fmt::Fixed(4)),
        ],
    );
    for (name, c) in r.curve_names.iter().zip(&r.correlation) {
        corr.row(vec![name.clone().into(), (*c).into()]);
    }
    let mut peaks = Section::new(
        "cmif_peaks",
        "CMIF peaks (first singular value)",
        vec![
            Column::new("freq_hz", "f", "Hz", Fmt::Fixed(3)),
            Column::new("value", "sigma_1", "", Fmt::Sci(4)),
        ],
    );
    for p in &r.cmif_peaks {
        peaks.row(vec![p.freq_hz.into(), p.value.into()]);
    }
    report.sections.push(corr);
    if !r.rejected.is_empty() {
        let mut rej = Section::new(
            "rejected",
            "Rejected poles (--reject-hz: kept in the modal model, not structural modes)",
            vec![
                Column::new("freq_hz", "f", "Hz", Fmt::Fixed(4)),
                Column::new("damping_ratio", "zeta", "%", Fmt::Fixed(4)).scaled(0.01),
            ],
        );
        for m in &r.rejected {
            rej.row(vec![m.freq_hz.into(), m.damping_ratio.into()]);
        }
        report.sections.push(rej);
    }
    report.sections.push(peaks);
}

/// What the `2nd shape` columns say, and whether they judged (the bounds are the verdict's).
fn second_shape_note(calibrated: bool) -> String {
    use lamdyn_ema::quality::{
        CALIBRATED_MEDIAN, CALIBRATING_POLES, SECOND_SHAPE_AMPLITUDE, SECOND_SHAPE_CHANCE,
        SECOND_SHAPE_SMEAR_AMPLITUDE, SECOND_SHAPE_STATISTIC,
    };
    if calibrated {
        format!(
            "2nd shape Z: energy of a second shape under the pole over its chance level (1 for \
             one mode); rho: its peak over the pole's. Z >= {SECOND_SHAPE_STATISTIC} with a \
             chance <= {SECOND_SHAPE_CHANCE:e} and rho >= {SECOND_SHAPE_AMPLITUDE} makes the \
             mode doubtful (a weak close mode), rho >= {SECOND_SHAPE_SMEAR_AMPLITUDE} a smear \
             (one pole over two close modes)."
        )
    } else {
        format!(
            "2nd shape Z, rho: the second-shape test is not calibrated on these data (its \
             median Z over the poles is above {CALIBRATED_MEDIAN}, or fewer than \
             {CALIBRATING_POLES} poles have one: the curves do not follow one set of poles to \
             their noise), so it judges nothing here."
        )
    }
}

/// Low correlations and missing picks as warnings; the columns' notes.
fn add_warnings_and_notes(report: &mut Report, s: &EmaSettings, r: &EmaResult) {
    let low: Vec<&String> = r
        .curve_names
        .iter()
        .zip(&r.correlation)
        .filter(|(_, c)| **c < 0.9)
        .map(|(n, _)| n)
        .collect();
    if !low.is_empty() {
        report.warnings.push(format!(
            "{} regenerated FRF(s) correlate below 0.9 with the measured \
             ones ({}): modes may be \
             missing",
            low.len(),
            low.iter()
                .take(5)
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if !r.missing_hz.is_empty() {
        report.warnings.push(format!(
            "no stable pole within {} Hz of {:?} Hz",
            s.window_hz, r.missing_hz
        ));
    }
    report
        .notes
        .push(second_shape_note(r.second_shape_calibrated));
    report.notes.push(format!(
        "zeta: viscous damping ratio -Re(lambda)/|lambda|; eta = 2 zeta; shapes from each \
         mode's residues fitted within +-{} zeta f of its pole; MPC 1 and MPD 0 for a real \
         (normal) mode.",
        lamdyn_ema::local_residues::HALF_WIDTHS
    ));
    report.notes.push(
        "sd(f), sd(zeta): standard deviations from the fit's noise (the refinement's \
         covariance); they leave out the estimator's bias (modes outside the band, \
         an unmodelled mode)."
            .into(),
    );
    report.notes.push(stable_footnote(&r.modes));
    report.notes.push(
        "pole: refined, or diagram where the refinement did not fit the curves \
         significantly better in the LSCF model's context (or was not run); f and \
         zeta (diagram): the diagram's pole it started from."
            .into(),
    );
    report.notes.push(
        "FRAC drop: the mean FRAC the regenerated FRFs lose without the mode; \
         verdict: sound, doubtful (kept; the reasons above) or smear (one pole over \
         a cluster of modes: its f and zeta describe no mode)."
            .into(),
    );
}

/// The JSON's extra fields: the modes in full, the rejected poles, the auto-MAC, the diagram,
/// the first CMIF curve, the lines, the responses and the step times.
fn extra_json(set: &FrfSet, r: &EmaResult, read_s: f64) -> serde_json::Value {
    let cell = |v: f64| serde_json::json!(v);
    serde_json::json!({
        "modes": r.modes,
        "rejected": r.rejected,
        "auto_mac": r.auto_mac,
        "diagram": r.diagram.iter().map(|p| serde_json::json!({"order": p.order, "freq_hz": cell(p.freq_hz), "damping_ratio": cell(p.damping), "stability": p.stability})).collect::<Vec<_>>(),
        "cmif_first": r.cmif.iter().map(|v| v[0]).collect::<Vec<_>>(),
        "freqs_hz": set.freqs_hz(),
        "responses": set.responses().iter().map(|c| &c.name).collect::<Vec<_>>(),
        "seconds": time_json(read_s, &r.timings),
        "second_shape_calibrated": r.second_shape_calibrated,
    })
}

/// Coherence per response over the band and the estimator's warnings.
fn add_time_info(report: &mut Report, set: &FrfSet, r: &EmaResult, info: &TimeInfo) {
    let f = set.freqs_hz();
    let band: Vec<usize> = (0..f.len())
        .filter(|&k| f[k] >= r.band_hz[0] && f[k] <= r.band_hz[1])
        .collect();
    let mut sec = Section::new(
        "coherence",
        "Coherence over the band",
        vec![
            Column::new("response", "response", "", Fmt::Fixed(0)),
            Column::new("min", "min", "", Fmt::Fixed(4)),
            Column::new("mean", "mean", "", Fmt::Fixed(4)),
        ],
    );
    for (c, ch) in info.spectra.channels.iter().zip(set.responses()) {
        let vals: Vec<f64> = band.iter().map(|&k| c.coherence[k]).collect();
        let min = vals.iter().copied().fold(f64::INFINITY, f64::min);
        let mean = vals.iter().sum::<f64>() / vals.len().max(1) as f64;
        sec.row(vec![ch.name.clone().into(), min.into(), mean.into()]);
    }
    report.sections.push(sec);
    report
        .warnings
        .extend(info.spectra.warnings.iter().cloned());
}

/// The FRFs estimated from time data as files: frf.csv with channels.csv (lamdyn's CSV set,
/// read back by `lamdyn ema --channels --frf`), frf.uff (datasets 2411 and 58) and
/// coherence.csv (f_hz, one column per response).
fn estimated_frf_files(set: &FrfSet, info: &TimeInfo) -> Result<Vec<(&'static str, Vec<u8>)>> {
    let mut coherence = String::from("f_hz");
    for c in set.responses() {
        coherence += &format!(",{}", c.name);
    }
    coherence.push('\n');
    for (k, f) in info.spectra.freqs_hz.iter().enumerate() {
        coherence += &f.to_string();
        for c in &info.spectra.channels {
            coherence += &format!(",{}", c.coherence[k]);
        }
        coherence.push('\n');
    }
    let uff = lamdyn_uff::write(
        &lamdyn_uff::frf::from_frf_set(set)?,
        lamdyn_uff::Encoding::Ascii,
    )?;
    Ok(vec![
        ("frf.csv", lamdyn_frf::csv::write_frf(set).into_bytes()),
        (
            "channels.csv",
            lamdyn_frf::csv::write_channels(set).into_bytes(),
        ),
        ("coherence.csv", coherence.into_bytes()),
        ("frf.uff", uff),
    ])
}

/// Writes modes.csv, diagram.csv, result.json and the charts into `dir` atomically, and the
/// estimated FRFs for time data.
fn write_results(
    dir: &OutputDir,
    set: &FrfSet,
    r: &EmaResult,
    report: &Report,
    time: Option<&TimeInfo>,
) -> Result<()> {
    use lamdyn_report::ema::{cmif_chart, stabilization_chart};
    let mut modes = String::from(
        "mode,freq_hz,freq_sd_hz,damping_ratio,damping_sd,loss_factor,mpc,mpd_deg,stable_poles,\
         pick,frac_drop,second_shape_z,second_shape_rho,verdict,pole,diagram_freq_hz,\
         diagram_damping_ratio,refined_freq_hz,refined_damping_ratio\n",
    );
    let optional = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
    for (k, m) in r.modes.iter().enumerate() {
        modes += &format!(
            "{},{},{},{},{},{},{},{},{},{:?},{},{},{},{},{},{},{},{},{}\n",
            k + 1,
            m.freq_hz,
            optional(m.sd.map(|d| d.freq_hz)),
            m.damping_ratio,
            optional(m.sd.map(|d| d.damping_ratio)),
            m.loss_factor,
            m.mpc,
            m.mpd_deg,
            m.stable_count,
            m.pick,
            m.quality.frac_drop,
            optional(m.quality.second_shape.map(|t| t.statistic)),
            optional(m.quality.second_shape.map(|t| t.relative_amplitude)),
            m.quality.verdict.label(),
            pole_source(m),
            pole_freq_hz(m.diagram_pole),
            pole_damping(m.diagram_pole),
            optional(m.refinement.map(|q| pole_freq_hz(q.pole))),
            optional(m.refinement.map(|q| pole_damping(q.pole))),
        );
    }
    let mut diagram = String::from("order,freq_hz,damping_ratio,stability,vector_mac\n");
    for p in &r.diagram {
        diagram += &format!(
            "{},{},{},{:?},{}\n",
            p.order,
            p.freq_hz,
            p.damping,
            p.stability,
            p.vector_mac.map_or(String::new(), |m| m.to_string())
        );
    }
    let mut json = Vec::new();
    report.write(crate::table::Format::Json, &mut json, &mut std::io::sink())?;
    let (stab, cmif) = (
        stabilization_chart(r, set.freqs_hz()),
        cmif_chart(r, set.freqs_hz()),
    );
    let mut files: Vec<(&str, Vec<u8>)> = vec![
        ("modes.csv", modes.into_bytes()),
        ("diagram.csv", diagram.into_bytes()),
        ("result.json", json),
        ("stabilization.svg", stab.render_svg()?.into_bytes()),
        ("stabilization.png", stab.render_png()?),
        ("cmif.svg", cmif.render_svg()?.into_bytes()),
        ("cmif.png", cmif.render_png()?),
    ];
    if let Some(info) = time {
        files.extend(estimated_frf_files(set, info)?);
    }
    Ok(dir.write(&files)?)
}
