//! The report's section on the FRF route ([`crate::frf_route`]): whether it ran and why, the
//! core's law from the FRFs beside the pole route's at each modal frequency, and the measured
//! against the model FRFs at a few channels with their residual.

use super::{BLACK, ORANGE, PURPLE, add_figure};
use crate::ChainResult;
use crate::error::Result;
use crate::frf_route::{FrfCurve, FrfRoute};
use lamdyn_report::HtmlReport;
use lamdyn_report::chart::{Axis, Chart, Mark, Series};
use std::fmt::Write as _;

/// The section (nothing when the layered route is off), and the FRF route's law in
/// core_frf_law.csv.
///
/// # Errors
/// A figure that cannot be rendered.
pub(super) fn section(
    html: &mut HtmlReport,
    files: &mut super::Files,
    r: &ChainResult,
) -> Result<()> {
    if r.layered_line.is_none() {
        return Ok(());
    }
    html.heading("The core from the FRFs (no poles)");
    html.paragraph(&format!("FRF fit: {}.", r.frf.describe()));
    let Some(route) = r.frf.route() else {
        return Ok(());
    };
    files.push(("core_frf_law.csv".into(), law_csv(route).into_bytes()));
    let (header, rows) = law_table(r, route);
    html.table(
        "The core's law fitted to the FRFs (corrected for the mesh, 95 % band) beside the pole \
         route's law, at each modal frequency.",
        &header,
        rows,
    );
    for (k, curve) in route.curves.iter().enumerate() {
        add_figure(
            html,
            files,
            &format!("frf_fit_{}", k + 1),
            &format!(
                "|FRF| measured and from the fitted layered model at {} / {}, and their \
                 difference.",
                curve.channel, curve.reference
            ),
            &curve_chart(curve, r.measured.set.quantity().unit()),
        )?;
    }
    Ok(())
}

/// f, the FRF law with its band, the pole route's law, the truth where known.
fn law_table(r: &ChainResult, route: &FrfRoute) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let mut header = vec![
        "f (Hz)",
        "G' FRF fit (MPa)",
        "95 % band",
        "eta FRF fit",
        "95 % band",
        "G' pole route's law (MPa)",
        "eta pole route's law",
    ];
    if r.truth.is_some() {
        header.extend(["G' true (MPa)", "eta true"]);
    }
    let pole_law = r.core_law.as_ref().and_then(|l| l.as_ref().ok());
    let rows = r
        .modal
        .iter()
        .map(|p| {
            let f = p.freq_hz;
            let a = route.at(f);
            let mut row = vec![
                format!("{f:.2}"),
                format!("{:.3}", a.storage_pa / 1e6),
                format!(
                    "{:.3} … {:.3}",
                    a.storage_ci95[0] / 1e6,
                    a.storage_ci95[1] / 1e6
                ),
                format!("{:.3}", a.loss_factor),
                format!(
                    "{:.3} … {:.3}",
                    a.loss_factor_ci95[0], a.loss_factor_ci95[1]
                ),
            ];
            let g = pole_law.and_then(|l| l.modulus(f));
            row.push(g.map_or("-".into(), |g| format!("{:.3}", g.re / 1e6)));
            row.push(g.map_or("-".into(), |g| format!("{:.3}", g.im / g.re)));
            if let Some(t) = &r.truth {
                let g = t.at(f);
                row.push(g.map_or("-".into(), |g| format!("{:.3}", g.re / 1e6)));
                row.push(g.map_or("-".into(), |g| format!("{:.3}", g.im / g.re)));
            }
            row
        })
        .collect();
    (header, rows)
}

/// |H| measured and modelled and |H_model − H_measured| over the band.
fn curve_chart(c: &FrfCurve, unit: &str) -> Chart {
    let mut chart = Chart::new(
        &format!("{} / {}", c.channel, c.reference),
        Axis::linear("frequency (Hz)"),
        Axis::log(&format!("|FRF| ({unit})")),
    );
    let points = |v: &mut dyn Iterator<Item = f64>| -> Vec<[f64; 2]> {
        c.freqs_hz
            .iter()
            .zip(v)
            .filter(|(_, y)| *y > 0.0 && y.is_finite())
            .map(|(&f, y)| [f, y])
            .collect()
    };
    let measured = points(&mut c.measured.iter().map(|h| h.norm()));
    let model = points(&mut c.model.iter().map(|h| h.norm()));
    let residual = points(&mut c.model.iter().zip(&c.measured).map(|(a, b)| (a - b).norm()));
    chart
        .series
        .push(Series::new("measured", BLACK, Mark::Line, measured));
    chart.series.push(Series::new(
        "layered model, fitted law",
        ORANGE,
        Mark::Line,
        model,
    ));
    chart.series.push(Series::new(
        "|model - measured|",
        PURPLE,
        Mark::Line,
        residual,
    ));
    chart
}

/// Lines of core_frf_law.csv over the fitted band.
const LAW_LINES: usize = 60;

/// `core_frf_law.csv`: the FRF route's law (corrected for the mesh) and its 95 % band on
/// [`LAW_LINES`] lines evenly spaced in ln f over the fitted band.
fn law_csv(route: &FrfRoute) -> String {
    let mut csv = String::from(
        "f_hz,storage_pa,storage_lo_pa,storage_hi_pa,loss_factor,loss_factor_lo,loss_factor_hi\n",
    );
    for p in route.curve(LAW_LINES) {
        let _ = writeln!(
            csv,
            "{},{:e},{:e},{:e},{},{},{}",
            p.f_hz,
            p.storage_pa,
            p.storage_ci95[0],
            p.storage_ci95[1],
            p.loss_factor,
            p.loss_factor_ci95[0],
            p.loss_factor_ci95[1]
        );
    }
    csv
}

/// The FRF route in result.json: whether it is the answer and why, the law, its parameters
/// with their 95 % intervals (null: not determined), the inputs it fitted beside the law
/// (relative change, its standard deviation after the fit and before), the model, the mesh
/// correction and the
/// law's curve (as core_frf_law.csv); `null` when it did not run.
pub(super) fn json(r: &ChainResult) -> serde_json::Value {
    let Some(route) = r.frf.route() else {
        return serde_json::Value::Null;
    };
    let parameters: Vec<serde_json::Value> = route
        .fit
        .parameters
        .iter()
        .map(|p| serde_json::json!({"name": p.name, "value": p.value, "ci95": p.ci95}))
        .collect();
    let curve: Vec<serde_json::Value> = route
        .curve(LAW_LINES)
        .iter()
        .map(|p| {
            serde_json::json!({
                "f_hz": p.f_hz,
                "storage_pa": p.storage_pa,
                "storage_ci95_pa": p.storage_ci95,
                "loss_factor": p.loss_factor,
                "loss_factor_ci95": p.loss_factor_ci95,
            })
        })
        .collect();
    let inputs: Vec<serde_json::Value> = route
        .fit
        .inputs
        .iter()
        .map(|i| {
            serde_json::json!({
                "name": i.input.name(),
                "change": i.change,
                "sd": i.sd,
                "prior_sd": i.prior_sd,
            })
        })
        .collect();
    let [applied, own] = route.correction.storage_ranges();
    serde_json::json!({
        "the_answer": route.is_the_answer(),
        "why": route.why.iter().map(ToString::to_string).collect::<Vec<_>>(),
        "law": route.fit.law.name(),
        "parameters": parameters,
        "inputs": inputs,
        "band_hz": route.fit.band_hz,
        "relative_rms": route.fit.relative_rms,
        "model": route.model_line,
        "mesh_correction": {
            "modes": route.correction.modes.len(),
            "storage_applied": applied,
            "storage_level_error": own,
            "rel_sd": route.correction.rel_sd,
            "converged_again_hz": route.converged_again_hz,
            "per_mode": route.correction.modes.iter().map(|m| serde_json::json!({
                "f_hz": m.x.exp(),
                "ln_c": [m.y.re, m.y.im],
                "weight": m.weight,
                "rel_sd": m.sd,
            })).collect::<Vec<_>>(),
            "line_ln_c": route.correction.line.map(|z| [z.re, z.im]),
            "mode_by_mode": route.mode_by_mode.as_ref().map(|m| {
                let [storage, loss] = route.line_law_ranges();
                serde_json::json!({
                    "taken_hz": m.taken_hz,
                    "left_hz": m.left_hz,
                    "line_law_storage_change": storage,
                    "line_law_loss_factor_change": loss,
                })
            }),
        },
        "curve": curve,
    })
}
