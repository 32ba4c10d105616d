//! `lamdyn ema`: measured FRFs (UFF or CSV) → stabilization diagram, modes with damping and
//! shapes, the regenerated FRFs' correlation and the CMIF peaks (lamdyn-ema does the work).

use crate::Outcome;
use crate::cli::EmaArgs;
use crate::table::{Column, Fmt, Report, Section};
use anyhow::{Context, Result, anyhow, bail};
use lamdyn_ema::identify::{EmaResult, EmaSettings, identify};
use lamdyn_frf::FrfSet;
use std::io::Write;
use std::path::Path;

/// The FRF set named by the arguments.
pub(crate) fn read_frfs(
    uff: Option<&Path>,
    channels: Option<&Path>,
    frf: Option<&Path>,
) -> Result<(FrfSet, String)> {
    match (uff, channels, frf) {
        (Some(u), _, _) => {
            let file = lamdyn_uff::read_path(u, Default::default()).map_err(|e| anyhow!(e))?;
            let set = lamdyn_uff::frf::to_frf_set(&file)
                .map_err(|e| anyhow!("'{}': {e}", u.display()))?;
            Ok((set, format!("UFF '{}'", u.display())))
        }
        (None, Some(c), Some(f)) => {
            let text = |p: &Path| {
                std::fs::read_to_string(p).with_context(|| format!("cannot read '{}'", p.display()))
            };
            let (r, q) = lamdyn_frf::csv::parse_channels(&c.display().to_string(), &text(c)?)?;
            let set = lamdyn_frf::csv::parse_frf(&f.display().to_string(), &text(f)?, r, q)?;
            Ok((
                set,
                format!("CSV '{}' with channels '{}'", f.display(), c.display()),
            ))
        }
        _ => bail!("give --uff FILE, or --channels FILE and --frf FILE"),
    }
}

fn settings(args: &EmaArgs, set: &FrfSet) -> Result<EmaSettings> {
    let mut s = EmaSettings {
        orders: (
            args.min_order as usize,
            args.max_order as usize,
            args.order_step as usize,
        ),
        near_hz: args.near_hz.clone(),
        window_hz: args.window_hz,
        exp_tau_s: args.exp_tau_s,
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
    let (set, source) = read_frfs(
        args.uff.as_deref(),
        args.channels.as_deref(),
        args.frf.as_deref(),
    )?;
    let s = settings(args, &set)?;
    let r = identify(&set, &s).context("identification failed")?;
    let report = build_report(&set, &source, &s, &r);
    report.write(args.output.format(), out, err)?;
    Ok(
        if r.correlation.iter().all(|c| *c >= 0.9) && r.missing_hz.is_empty() {
            Outcome::Done
        } else {
            Outcome::ChecksFailed
        },
    )
}

fn build_report(set: &FrfSet, source: &str, s: &EmaSettings, r: &EmaResult) -> Report {
    let mut report = Report::new(
        "ema",
        vec![
            Column::new("mode", "mode", "", Fmt::Fixed(0)),
            Column::new("freq_hz", "f", "Hz", Fmt::Fixed(4)),
            Column::new("damping_ratio", "zeta", "%", Fmt::Fixed(4)).scaled(0.01),
            Column::new("loss_factor", "eta", "", Fmt::Sci(4)),
            Column::new("mpc", "MPC", "", Fmt::Fixed(4)),
            Column::new("mpd_deg", "MPD", "deg", Fmt::Fixed(2)),
            Column::new("stable_poles", "stable", "", Fmt::Fixed(0)),
        ],
    );
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
    report.input(
        "method",
        format!(
            "LSCF (z-domain common denominator) orders {}-{} step {} on {:.3}-{:.3} Hz; stable: df/f <= {} %, dzeta/zeta <= {} %; {}; {}",
            s.orders.0,
            s.orders.1,
            s.orders.2,
            r.band_hz[0],
            r.band_hz[1],
            100.0 * s.criteria.freq_tol,
            100.0 * s.criteria.damping_tol,
            if s.near_hz.is_some() { "poles picked near the given frequencies" } else { "automatic selection (clusters stable over half the orders)" },
            if s.refine_iterations > 0 { "poles refined with LSFD residues (variable projection)" } else { "LSFD residues on the diagram's poles" }
        ),
    );
    if let Some(t) = s.exp_tau_s {
        report.input(
            "exponential window",
            format!(
                "tau = {t} s: 1/tau = {:.4} 1/s removed from every pole's decay rate",
                1.0 / t
            ),
        );
    }
    report.input(
        "time",
        format!(
            "poles and diagram {:.3} s, refinement and residues {:.3} s",
            r.seconds[0], r.seconds[1]
        ),
    );
    for (k, m) in r.modes.iter().enumerate() {
        report.row(vec![
            ((k + 1) as f64).into(),
            m.freq_hz.into(),
            m.damping_ratio.into(),
            m.loss_factor.into(),
            m.mpc.into(),
            m.mpd_deg.into(),
            (m.stable_count as f64).into(),
        ]);
    }
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
    report.sections.push(peaks);
    let low: Vec<&String> = r
        .curve_names
        .iter()
        .zip(&r.correlation)
        .filter(|(_, c)| **c < 0.9)
        .map(|(n, _)| n)
        .collect();
    if !low.is_empty() {
        report.warnings.push(format!("{} regenerated FRF(s) correlate below 0.9 with the measured ones ({}): modes may be missing", low.len(), low.iter().take(5).map(|s| s.as_str()).collect::<Vec<_>>().join(", ")));
    }
    if !r.missing_hz.is_empty() {
        report.warnings.push(format!(
            "no stable pole within {} Hz of {:?} Hz",
            s.window_hz, r.missing_hz
        ));
    }
    report.notes.push("zeta: viscous damping ratio -Re(lambda)/|lambda|; eta = 2 zeta; MPC 1 and MPD 0 for a real (normal) mode.".into());
    report.notes.push("stable: poles stable in frequency and damping in the mode's column of the diagram (0 when picked with --near-hz).".into());
    let cell = |v: f64| serde_json::json!(v);
    report.extra = Some(serde_json::json!({
        "modes": r.modes,
        "auto_mac": r.auto_mac,
        "diagram": r.diagram.iter().map(|p| serde_json::json!({"order": p.order, "freq_hz": cell(p.freq_hz), "damping_ratio": cell(p.damping), "stability": p.stability})).collect::<Vec<_>>(),
        "cmif_first": r.cmif.iter().map(|v| v[0]).collect::<Vec<_>>(),
        "freqs_hz": set.freqs_hz(),
        "responses": set.responses().iter().map(|c| &c.name).collect::<Vec<_>>(),
    }));
    report
}
