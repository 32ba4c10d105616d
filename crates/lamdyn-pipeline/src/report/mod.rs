//! The report of a chain run: one self-contained HTML file (figures inline as SVG), the figures
//! again as SVG and PNG files, the tables as CSV and everything as JSON, written into the
//! results folder only when everything is built (`crate::output::OutputDir`: a failed run
//! leaves the old report as it was, and nothing lamdyn did not write is touched).
//!
//! Figures: the RMS FRF measured vs fitted (paper Fig. 5), the stabilization diagram and the
//! CMIF, the identified mode shapes as contour maps, E'(f) and η(f) of the laminate (Fig. 4),
//! G'(f) and η(f) of the core by both inverses with the Monte Carlo bands (Fig. 7). Tables: the
//! modes, the law's parameters, Table 3, the core at each modal frequency (with the errors
//! against the truth of a virtual test, and |φ| against the paper model's validity limit), the
//! Kramers–Kronig verdict, the warnings and the stage timings.

mod answer;
pub mod core_table;
mod frf;

use super::uncertainty::{Band, Bands};
use super::{ChainResult, CorePoint};
use crate::band::{ModulusPart, StorageAndLoss};
use crate::err;
use crate::error::Result;
use lamdyn_fit::fit::FitResult;
use lamdyn_fit::joint::CoreLawFit;
use lamdyn_material::laminate::PHI_ACCURACY_LIMIT;
use lamdyn_report::chart::{Axis, Chart, Mark, Series};
use lamdyn_report::{HtmlReport, shape_map};
use num_complex::Complex64;
use std::fmt::Write as _;

const BLUE: [u8; 3] = [31, 119, 180];
const ORANGE: [u8; 3] = [230, 110, 0];
const GREEN: [u8; 3] = [44, 160, 44];
const BLACK: [u8; 3] = [0, 0, 0];
const PURPLE: [u8; 3] = [148, 60, 189];

/// How the layered inverse finds the core at a mode and what its band holds (the report's text
/// under its table).
const LAYERED_METHOD: &str = "How the layered inverse finds it: each EMA pole p (frequency and \
                              damping) matched by a layered solid model of the part, converged \
                              over a ladder of meshes (Richardson extrapolation, model line \
                              below); the core so found holds at the pole's complex frequency −ip, \
                              and is moved from there to the mode's real frequency by the fitted \
                              law (or the modes' log-slope): 1–1.5 % of η on a lightly damped \
                              glass laminate. Its 95 % band holds, in quadrature, the inputs known \
                              within a tolerance ([uncertainty]: face modulus, thicknesses, \
                              densities, each through its sensitivity on the layered model), the \
                              pole's scatter over the stabilization diagram (and, from hammer \
                              hits, how the pole moves when each hit is left out), the \
                              discretization in plane (grid convergence index of the finest mesh) \
                              and through the thickness (the coarsest mesh with two elements per \
                              layer); the modal table names each band's main source. It does not \
                              hold a model-form error (an unmodelled support); the law fitted to \
                              all modes below narrows it.";

/// A positive parameter whose 95 % interval spans more decades than this is shown as not
/// determined.
const UNDETERMINED_DECADES: f64 = 3.0;

/// Most mode-shape maps drawn.
const MAX_SHAPES: usize = 8;

/// Picks one quantity's band from a frequency's bands.
type BandPick = fn(&Bands) -> Option<Band>;

/// The report's files: (relative path, bytes).
pub type Files = Vec<(String, Vec<u8>)>;

fn fmt(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or("-".into(), |x| format!("{:.*}", digits, x / scale))
}

fn band_text(b: Option<Band>, scale: f64, digits: usize) -> String {
    b.map_or("-".into(), |[lo, hi]| {
        format!("{:.*} - {:.*}", digits, lo / scale, digits, hi / scale)
    })
}

/// A layered band as [`band_text`], or "not determined" where it spans more than
/// [`crate::band_widths::UNDETERMINED_FACTOR`] either way (the CSV keeps the numbers).
fn layered_band_text(b: Option<Band>, scale: f64, digits: usize) -> String {
    match b {
        Some([lo, hi]) if !crate::band_widths::determines(0.5 * (hi / lo).ln()) => {
            "not determined".into()
        }
        _ => band_text(b, scale, digits),
    }
}

fn rel_err(got: Option<f64>, truth: Option<f64>) -> Option<f64> {
    Some(got? / truth? - 1.0)
}

fn pct(v: Option<f64>) -> String {
    v.map_or("-".into(), |x| format!("{:+.1}", 100.0 * x))
}

fn storage(g: Option<Complex64>) -> Option<f64> {
    g.map(|g| g.re)
}
fn loss(g: Option<Complex64>) -> Option<f64> {
    g.map(|g| g.im / g.re)
}

/// A band polygon (upper forwards, lower backwards) from per-point bands.
fn band_series(
    name: &str,
    color: [u8; 3],
    xs: &[f64],
    bands: &[Option<Band>],
    scale: f64,
) -> Series {
    let pts: Vec<(f64, Band)> = xs
        .iter()
        .zip(bands)
        .filter_map(|(x, b)| b.map(|b| (*x, b)))
        .collect();
    let mut poly: Vec<[f64; 2]> = pts.iter().map(|(x, b)| [*x, b[1] / scale]).collect();
    poly.extend(pts.iter().rev().map(|(x, b)| [*x, b[0] / scale]));
    Series::new(name, color, Mark::Band, poly).not_scaling()
}

/// Renders each chart to SVG and PNG, adds it to the report and the files.
fn add_figure(
    html: &mut HtmlReport,
    files: &mut Files,
    name: &str,
    caption: &str,
    chart: &Chart,
) -> Result<()> {
    let svg = chart
        .render_svg()
        .map_err(|e| err!("figure '{name}': {e}"))?;
    let png = chart
        .render_png()
        .map_err(|e| err!("figure '{name}': {e}"))?;
    files.push((format!("figures/{name}.svg"), svg.clone().into_bytes()));
    files.push((format!("figures/{name}.png"), png));
    html.figure(name, caption, svg);
    Ok(())
}

/// The curve's bands for one quantity.
fn curve_bands(r: &ChainResult, pick: fn(&Bands) -> Option<Band>) -> Vec<Option<Band>> {
    r.curve
        .iter()
        .map(|p| {
            r.uncertainty
                .as_ref()
                .and_then(|m| m.at(p.freq_hz))
                .and_then(pick)
        })
        .collect()
}

fn modal_bands(r: &ChainResult, p: &CorePoint) -> Bands {
    r.uncertainty
        .as_ref()
        .and_then(|m| m.at(p.freq_hz))
        .copied()
        .unwrap_or_default()
}

fn rms_chart(r: &ChainResult) -> Chart {
    let f = r.measured.set.freqs_hz();
    let unit = r.measured.set.quantity().unit();
    let mut c = Chart::new(
        "RMS FRF over the responses: measured vs fitted (paper Fig. 5)",
        Axis::linear("frequency (Hz)"),
        Axis::log(&format!("RMS FRF ({unit})")),
    );
    let pts = |v: &[f64]| {
        r.fit_lines
            .iter()
            .map(|&k| [f[k], v[k]])
            .collect::<Vec<_>>()
    };
    c.series.push(Series::new(
        "measured",
        BLACK,
        Mark::Line,
        pts(&r.measured_rms),
    ));
    c.series.push(Series::new(
        "fitted",
        ORANGE,
        Mark::Line,
        pts(&r.fitted_rms),
    ));
    c
}

fn laminate_charts(r: &ChainResult) -> (Chart, Chart) {
    let xs: Vec<f64> = r.curve.iter().map(|p| p.freq_hz).collect();
    let mut e = Chart::new(
        "Laminate: effective storage modulus E'(f) (paper Fig. 4)",
        Axis::linear("frequency (Hz)"),
        Axis::linear("E' (GPa)"),
    );
    let mut eta = Chart::new(
        "Laminate: loss factor of E*(f) (paper Fig. 4)",
        Axis::linear("frequency (Hz)"),
        Axis::linear("loss factor"),
    );
    if r.uncertainty.is_some() {
        e.series.push(band_series(
            "95 % band",
            BLUE,
            &xs,
            &curve_bands(r, |b| b.e_storage),
            1e9,
        ));
        eta.series.push(band_series(
            "95 % band",
            BLUE,
            &xs,
            &curve_bands(r, |b| b.e_loss_factor),
            1.0,
        ));
    }
    e.series.push(Series::new(
        "fitted law",
        BLUE,
        Mark::Line,
        r.curve
            .iter()
            .filter_map(|p| Some([p.freq_hz, p.e_storage_pa()? / 1e9]))
            .collect(),
    ));
    eta.series.push(Series::new(
        "fitted law",
        BLUE,
        Mark::Line,
        r.curve
            .iter()
            .filter_map(|p| Some([p.freq_hz, p.e_loss_factor()?]))
            .collect(),
    ));
    e.series.push(Series::new(
        "modal frequencies",
        BLACK,
        Mark::Disc,
        r.modal
            .iter()
            .filter_map(|p| Some([p.freq_hz, p.e_storage_pa()? / 1e9]))
            .collect(),
    ));
    eta.series.push(Series::new(
        "modal frequencies",
        BLACK,
        Mark::Disc,
        r.modal
            .iter()
            .filter_map(|p| Some([p.freq_hz, p.e_loss_factor()?]))
            .collect(),
    ));
    (e, eta)
}

fn core_chart(r: &ChainResult, loss_factor: bool) -> Chart {
    let (title, label, scale) = if loss_factor {
        (
            "Core: loss factor eta(f) (paper Fig. 7)",
            "loss factor",
            1.0,
        )
    } else {
        (
            "Core: shear storage modulus G'(f) (paper Fig. 7)",
            "G' (MPa)",
            1e6,
        )
    };
    let value = |g: Option<Complex64>| if loss_factor { loss(g) } else { storage(g) };
    let mut c = Chart::new(title, Axis::linear("frequency (Hz)"), Axis::linear(label));
    let xs: Vec<f64> = r.curve.iter().map(|p| p.freq_hz).collect();
    c.series.extend(inverse_bands(r, &xs, loss_factor, scale));
    let line = |name: &str, color, g: fn(&CorePoint) -> Option<Complex64>, mark| {
        Series::new(
            name,
            color,
            mark,
            r.curve
                .iter()
                .filter_map(|p| value(g(p)).map(|v| [p.freq_hz, v / scale]))
                .collect(),
        )
    };
    c.series.push(line(
        "paper inverse (eqs. 33-45)",
        BLUE,
        CorePoint::paper_g,
        Mark::Line,
    ));
    c.series.push(line(
        "exact inverse (Mead-Markus)",
        ORANGE,
        CorePoint::exact_g,
        Mark::Line,
    ));
    let modal = |name: &str, color, g: fn(&CorePoint) -> Option<Complex64>| {
        Series::new(
            name,
            color,
            Mark::Disc,
            r.modal
                .iter()
                .filter_map(|p| value(g(p)).map(|v| [p.freq_hz, v / scale]))
                .collect(),
        )
    };
    c.series.push(modal("", BLUE, CorePoint::paper_g));
    c.series.push(modal("", ORANGE, CorePoint::exact_g));
    let beyond: Vec<[f64; 2]> = r
        .modal
        .iter()
        .filter(|p| p.phi().is_some_and(|phi| phi > PHI_ACCURACY_LIMIT))
        .filter_map(|p| value(p.paper_g()).map(|v| [p.freq_hz, v / scale]))
        .collect();
    if !beyond.is_empty() {
        c.series.push(Series::new(
            "paper: |phi| beyond validity",
            [200, 0, 0],
            Mark::Cross,
            beyond,
        ));
    }
    let span = [
        xs.first().copied().unwrap_or(0.0),
        xs.last().copied().unwrap_or(0.0),
    ];
    c.series.extend(truth_series(r, span, loss_factor, scale));
    c.series.extend(law_series(r, loss_factor, scale));
    // The answer last, on top of everything.
    if r.modal.iter().any(|p| p.layered_g().is_some()) {
        let mut layered = modal(
            "layered inverse per mode (lamdyn's answer)",
            PURPLE,
            CorePoint::layered_g,
        );
        layered.mark = Mark::Highlight;
        c.series.push(layered);
    }
    c
}

/// The Monte Carlo's 95 % bands of the paper's and the exact inverse over the curve's lines
/// `xs` (none without a Monte Carlo): G' divided by `scale`, or η.
fn inverse_bands(r: &ChainResult, xs: &[f64], loss_factor: bool, scale: f64) -> Vec<Series> {
    let mut out = Vec::new();
    if r.uncertainty.is_none() {
        return out;
    }
    let (pb, eb): (BandPick, BandPick) = if loss_factor {
        (|b| b.paper_loss_factor, |b| b.exact_loss_factor)
    } else {
        (|b| b.paper_storage, |b| b.exact_storage)
    };
    out.push(band_series(
        "paper: 95 % band",
        BLUE,
        xs,
        &curve_bands(r, pb),
        scale,
    ));
    out.push(band_series(
        "exact: 95 % band",
        ORANGE,
        xs,
        &curve_bands(r, eb),
        scale,
    ));
    out
}

/// The core's law over all modes and its 95 % band (none without one): G' divided by
/// `scale`, or η.
fn law_series(r: &ChainResult, loss_factor: bool, scale: f64) -> Vec<Series> {
    let mut out = Vec::new();
    let Some(Ok(law)) = &r.core_law else {
        return out;
    };
    let curve = law.curve(60);
    let xs: Vec<f64> = curve.iter().map(|p| p.freq_hz).collect();
    let bands: Vec<Option<Band>> = curve
        .iter()
        .map(|p| {
            Some(if loss_factor {
                p.loss_factor_ci95
            } else {
                p.storage_ci95
            })
        })
        .collect();
    out.push(band_series(
        "core law fitted to all modes: 95 % band",
        PURPLE,
        &xs,
        &bands,
        scale,
    ));
    out.push(Series::new(
        &format!("core law ({})", law.law.name()),
        PURPLE,
        Mark::Line,
        curve
            .iter()
            .map(|p| {
                let v = if loss_factor {
                    p.loss_factor
                } else {
                    p.storage_pa
                };
                [p.freq_hz, v / scale]
            })
            .collect(),
    ));
    out
}

/// The truth of a virtual test (none without one) as a line over `span` Hz widened by 10 %:
/// G' divided by `scale`, or η.
fn truth_series(r: &ChainResult, span: [f64; 2], loss_factor: bool, scale: f64) -> Option<Series> {
    let t = r.truth.as_ref()?;
    Some(Series::new(
        "truth (virtual test)",
        GREEN,
        Mark::Line,
        t.lines
            .iter()
            .filter(|(f, _)| *f >= 0.9 * span[0] && *f <= 1.1 * span[1])
            .filter_map(|(f, g)| {
                let v = if loss_factor {
                    g.im / g.re
                } else {
                    g.re / scale
                };
                v.is_finite().then_some([*f, v])
            })
            .collect(),
    ))
}

/// The mode shape maps: normal-ish channels (|d_z| > 0.7), value signed along +z.
fn shape_charts(r: &ChainResult) -> Vec<(String, String, Chart)> {
    let resp = r.measured.set.responses();
    let normal: Vec<usize> = (0..resp.len())
        .filter(|&i| resp[i].direction[2].abs() > 0.7)
        .collect();
    if normal.len() < 4 {
        return vec![];
    }
    let pts: Vec<[f64; 2]> = normal
        .iter()
        .map(|&i| [resp[i].point_m[0], resp[i].point_m[1]])
        .collect();
    r.ema
        .modes
        .iter()
        .take(MAX_SHAPES)
        .enumerate()
        .filter(|(_, m)| m.real_shape.len() == resp.len())
        .map(|(k, m)| {
            let v: Vec<f64> = normal
                .iter()
                .map(|&i| m.real_shape[i] * resp[i].direction[2].signum())
                .collect();
            let title = format!(
                "Mode {}: {:.2} Hz, zeta {:.2} \
                 %",
                k + 1,
                m.freq_hz,
                100.0 * m.damping_ratio
            );
            (
                format!("mode{}", k + 1),
                format!(
                    "Mode {} shape (EMA, real part, normal channels) at {:.3} Hz, contour map \
                     interpolated between the sensors (dots)",
                    k + 1,
                    m.freq_hz
                ),
                shape_map(&title, &pts, &v, 11),
            )
        })
        .collect()
}

fn csv_line(cells: &[String]) -> String {
    let mut s = cells.join(",");
    s.push('\n');
    s
}

/// Table of the core at the modal frequencies for HTML: (header, rows). All columns, in full
/// precision: `core_modal.csv` ([`core_table`]).
fn modal_table(r: &ChainResult) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let truth = r.truth.is_some();
    let mut header = vec![
        "f [Hz]",
        "E' [GPa]",
        "eta_E",
        "|phi|",
        "valid (|phi|<=0.1)",
        "G'_paper [MPa]",
        "95% band",
        "eta_paper",
        "95% band",
        "G'_exact [MPa]",
        "95% band",
        "eta_exact",
        "95% band",
        "G'_layered [MPa]",
        "95% band",
        "eta_layered",
        "95% band",
        "layered f err, finest mesh",
        "layered eta err, finest mesh",
        "G' change by convergence [%]",
        "layered band's main source (G'; eta)",
    ];
    if truth {
        header.extend([
            "G'_true [MPa]",
            "eta_true",
            "err G'_paper [%]",
            "err eta_paper [%]",
            "err G'_exact [%]",
            "err eta_exact [%]",
            "err G'_layered [%]",
            "err eta_layered [%]",
        ]);
    }
    let mut rows = vec![];
    for p in &r.modal {
        let b = modal_bands(r, p);
        let phi = p.phi();
        let valid = phi.map_or("-", |x| if x <= PHI_ACCURACY_LIMIT { "yes" } else { "NO" });
        let (gp, ge, gl) = (p.paper_g(), p.exact_g(), p.layered_g());
        let lb = LayeredColumns::of(p);
        let mut row = vec![
            format!("{:.3}", p.freq_hz),
            p.e_storage_pa()
                .map_or("-".into(), |e| format!("{:.4}", e / 1e9)),
            p.e_loss_factor().map_or("-".into(), |e| format!("{e:.3e}")),
            fmt(phi, 1.0, 4),
            valid.to_string(),
            fmt(storage(gp), 1e6, 3),
            band_text(b.paper_storage, 1e6, 3),
            fmt(loss(gp), 1.0, 3),
            band_text(b.paper_loss_factor, 1.0, 3),
            fmt(storage(ge), 1e6, 3),
            band_text(b.exact_storage, 1e6, 3),
            fmt(loss(ge), 1.0, 3),
            band_text(b.exact_loss_factor, 1.0, 3),
            fmt(storage(gl), 1e6, 3),
            layered_band_text(lb.storage, 1e6, 3),
            fmt(loss(gl), 1.0, 3),
            layered_band_text(lb.loss, 1.0, 3),
            lb.freq_error.map_or("-".into(), |e| format!("{e:+.1e}")),
            lb.loss_error.map_or("-".into(), |e| format!("{e:+.1e}")),
            pct(lb.coarsest.and_then(|c| rel_err(storage(gl), Some(c.re)))),
            lb.dominant.clone().unwrap_or_else(|| "-".into()),
        ];
        if let Some(t) = &r.truth {
            let g = t.at(p.freq_hz);
            let errs = [
                rel_err(storage(gp), storage(g)),
                rel_err(loss(gp), loss(g)),
                rel_err(storage(ge), storage(g)),
                rel_err(loss(ge), loss(g)),
                rel_err(storage(gl), storage(g)),
                rel_err(loss(gl), loss(g)),
            ];
            row.push(fmt(storage(g), 1e6, 3));
            row.push(fmt(loss(g), 1.0, 3));
            row.extend(errs.iter().map(|e| pct(*e)));
        }
        rows.push(row);
    }
    (header, rows)
}

/// The layered inverse's columns of one modal point: its 95 % band (inputs, pole scatter and
/// discretization, [`crate::band::LayeredBand`]; the discretization residual alone when the
/// band could not be made), the main sources, the finest mesh's errors, the residual, and the
/// coarsest mesh's uncorrected G*.
struct LayeredColumns {
    storage: Option<Band>,
    loss: Option<Band>,
    discretization_half_width: Option<[f64; 2]>,
    /// 1.96 times the band's source
    /// [`BandSource::ThroughThickness`](crate::band::BandSource::ThroughThickness).
    through_thickness_half_width: Option<[f64; 2]>,
    dominant: Option<String>,
    freq_error: Option<f64>,
    loss_error: Option<f64>,
    residual: Option<f64>,
    coarsest: Option<Complex64>,
}

impl LayeredColumns {
    fn of(p: &CorePoint) -> Self {
        let c = p.layered_convergence.as_ref();
        let g = p.layered_g();
        let full = p.layered_band.as_ref().and_then(|b| b.as_ref().ok());
        let half = full
            .map(|b| b.half_width)
            .or(c.map(|c| StorageAndLoss::new(c.storage_band, c.loss_band)));
        let band = |v: Option<f64>, rel: Option<f64>| match (v, rel) {
            // Log-normal: G' and η are positive, and a band of tens of per cent is not
            // symmetric about them (the same as v(1 ± r) for small r).
            (Some(v), Some(r)) => Some([v * (-r).exp(), v * r.exp()]),
            _ => None,
        };
        Self {
            storage: band(storage(g), half.map(|h| h.storage)),
            loss: band(loss(g), half.map(|h| h.loss)),
            discretization_half_width: c.map(|c| [c.storage_band, c.loss_band]),
            through_thickness_half_width: full.and_then(|b| {
                let s = b
                    .sources
                    .iter()
                    .find(|s| s.0 == crate::band::BandSource::ThroughThickness)?;
                Some(s.1.map(|v| 1.96 * v).to_array())
            }),
            dominant: full.map(|b| {
                let label = |part| b.dominant_label(part);
                format!(
                    "{}; {}",
                    label(ModulusPart::Storage),
                    label(ModulusPart::Loss)
                )
            }),
            freq_error: c.map(|c| c.freq_error),
            loss_error: c.map(|c| c.loss_error),
            residual: c.map(|c| c.residual_freq_error),
            coarsest: c.map(|c| c.coarsest_pa),
        }
    }
}

/// Columns of a table by header name: `(name, k)` is the column `k` places after `name`'s
/// first occurrence (a value's band follows it). Names not in the header are left out.
fn pick_columns(
    header: &[&'static str],
    rows: &[Vec<String>],
    names: &[(&'static str, usize)],
) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let idx: Vec<usize> = names
        .iter()
        .filter_map(|(n, k)| header.iter().position(|h| h == n).map(|i| i + k))
        .filter(|i| *i < header.len())
        .collect();
    (
        idx.iter().map(|i| header[*i]).collect(),
        rows.iter()
            .map(|r| idx.iter().map(|i| r[*i].clone()).collect())
            .collect(),
    )
}

/// The report's opening: the core by the best route the run has — the layered inverse (each
/// EMA pole matched by a layered model) where it ran, else the exact sandwich inverse with its
/// Monte Carlo band — with the truth of a virtual test, and how far the paper's route is from
/// it.
fn lead_section(
    html: &mut HtmlReport,
    r: &ChainResult,
    header: &[&'static str],
    rows: &[Vec<String>],
) {
    let layered = r.modal.iter().any(|p| p.layered_g().is_some());
    html.heading("The core: lamdyn's answer");
    let mut cols: Vec<(&'static str, usize)> = if layered {
        vec![
            ("f [Hz]", 0),
            ("G'_layered [MPa]", 0),
            ("G'_layered [MPa]", 1),
            ("eta_layered", 0),
            ("eta_layered", 1),
        ]
    } else {
        vec![
            ("f [Hz]", 0),
            ("G'_exact [MPa]", 0),
            ("G'_exact [MPa]", 1),
            ("eta_exact", 0),
            ("eta_exact", 1),
        ]
    };
    if r.truth.is_some() {
        cols.extend([("G'_true [MPa]", 0), ("eta_true", 0)]);
        cols.extend(if layered {
            [("err G'_layered [%]", 0), ("err eta_layered [%]", 0)]
        } else {
            [("err G'_exact [%]", 0), ("err eta_exact [%]", 0)]
        });
    }
    let (mut h, mut t) = pick_columns(header, rows, &cols);
    h.extend(["paper's G' vs this [%]", "paper's eta vs this [%]"]);
    for (row, p) in t.iter_mut().zip(&r.modal) {
        let best = if layered { p.layered_g() } else { p.exact_g() };
        row.push(pct(rel_err(storage(p.paper_g()), storage(best))));
        row.push(pct(rel_err(loss(p.paper_g()), loss(best))));
    }
    if layered {
        html.table(
            "G*(f) of the core at each identified mode by the layered inverse, with its 95 % band; \
             the last columns: how far the paper's route lies from it.",
            &h,
            t,
        );
        html.paragraph(LAYERED_METHOD);
    } else {
        html.table(
            "G*(f) of the core at each identified mode by the exact Mead-Markus inverse, with 95 % \
             Monte Carlo bands (the layered inverse did not run); the last columns: the paper's \
             route against it.",
            &h,
            t,
        );
    }
}

/// The core's law fitted to all modes with the inputs shared ([`lamdyn_fit::joint`]): its
/// value and band at each mode, its parameters and the inputs it finds, and its curve in
/// core_law.csv.
fn law_section(html: &mut HtmlReport, files: &mut Files, r: &ChainResult) {
    let Some(result) = &r.core_law else {
        return;
    };
    html.heading("The core's law over all modes");
    let law = match result {
        Ok(l) => l,
        Err(e) => {
            html.paragraph(&format!("The joint law fit failed: {e}"));
            return;
        }
    };
    law_summary(html, law);
    if let Some(why) = &law.selection {
        html.paragraph(&format!("The {} law was {why}.", law.form()));
    }
    law_at_modes(html, r, law);
    law_parameters(html, law);
    files.push(("core_law.csv".into(), law_csv(law).into_bytes()));
}

/// The joint law fit in a paragraph: the law, χ², the scale of the noise, the inputs found
/// and what the data do not determine.
fn law_summary(html: &mut HtmlReport, law: &CoreLawFit) {
    // The shared remainder's two terms are no physical inputs (their unit is their prior's sd).
    let inputs: Vec<String> = law
        .inputs()
        .iter()
        .filter(|p| {
            !matches!(
                crate::band::BandSource::from_label(&p.name),
                Some(crate::band::BandSource::SharedRemainder { .. })
            )
        })
        .map(|p| {
            format!(
                "{} {:+.2} % [{:+.2}, {:+.2}]",
                p.name,
                100.0 * p.value,
                100.0 * p.ci95[0],
                100.0 * p.ci95[1]
            )
        })
        .collect();
    html.paragraph(&format!(
        "A {} law fitted to every layered mode at once (ln G' and ln eta, each mode weighted by \
         its pole scatter and discretization error), jointly with the inputs known within a \
         tolerance, one change per input shared by all modes under its prior from [uncertainty] \
         (lamdyn_fit::joint). chi2 = {:.2} over {} degrees of freedom{}. The inputs the fit finds \
         (relative change, 95 %): {}.{}",
        law.law.name(),
        law.chi2,
        law.dof,
        if law.scale > 1.0 {
            format!(
                "; the scatter about the law exceeds the stated noise by {:.2}x, so the fit scales \
                 the modes' noise by that much (the inputs' priors keep their weight) and the \
                 bands use Student's t",
                law.scale
            )
        } else {
            String::new()
        },
        if inputs.is_empty() {
            "none".to_string()
        } else {
            inputs.join("; ")
        },
        if law.undetermined.is_empty() {
            String::new()
        } else {
            format!(
                " Not determined by the data and priors: {}.",
                law.undetermined.join("; ")
            )
        }
    ));
}

/// The law and its band at each mode, the mode's own point against it, and the errors
/// against the truth of a virtual test.
fn law_at_modes(html: &mut HtmlReport, r: &ChainResult, law: &CoreLawFit) {
    let truth = |f: f64| r.truth.as_ref().and_then(|t| t.at(f));
    let mut header = vec![
        "f [Hz]",
        "G'_law [MPa]",
        "95% low",
        "95% high",
        "eta_law",
        "95% low",
        "95% high",
        "band's main source (G'; eta)",
        "mode's point vs law, G' [%]",
    ];
    if r.truth.is_some() {
        header.extend(["err G'_law [%]", "err eta_law [%]"]);
    }
    let rows = law
        .at_modes
        .iter()
        .zip(&law.corrected_points)
        .map(|(p, g)| {
            let mut row = vec![
                format!("{:.2}", p.freq_hz),
                format!("{:.3}", p.storage_pa / 1e6),
                format!("{:.3}", p.storage_ci95[0] / 1e6),
                format!("{:.3}", p.storage_ci95[1] / 1e6),
                format!("{:.3}", p.loss_factor),
                format!("{:.3}", p.loss_factor_ci95[0]),
                format!("{:.3}", p.loss_factor_ci95[1]),
                format!("{}; {}", p.dominant[0], p.dominant[1]),
                format!("{:+.2}", 100.0 * (g.re / p.storage_pa - 1.0)),
            ];
            if let Some(t) = truth(p.freq_hz) {
                row.push(format!("{:+.2}", 100.0 * (p.storage_pa / t.re - 1.0)));
                row.push(format!(
                    "{:+.2}",
                    100.0 * (p.loss_factor / (t.im / t.re) - 1.0)
                ));
            } else if r.truth.is_some() {
                row.extend(["-".to_string(), "-".to_string()]);
            }
            row
        })
        .collect();
    html.table(
        "The law and its 95 % band at each mode (log-normal, all sources); the last column: each \
         mode's layered point, moved by the inputs found, against the law.",
        &header,
        rows,
    );
}

/// The law's parameters and the inputs' changes with their 95 % intervals; a parameter the
/// data do not determine is said to be.
fn law_parameters(html: &mut HtmlReport, law: &CoreLawFit) {
    html.table(
        "The law's parameters and the inputs' relative changes with 95 % intervals (correlations \
         in result.json).",
        &["parameter", "value", "95% low", "95% high"],
        law.parameters
            .iter()
            .map(|p| {
                // A parameter the data do not determine has no interval (lamdyn_fit::joint),
                // nor has one whose interval spans decades: it is not a measurement.
                let decades = (p.ci95[1] / p.ci95[0]).log10();
                let bound = |b: f64| {
                    if !p.sd.is_finite() {
                        "not determined".to_string()
                    } else if decades > UNDETERMINED_DECADES {
                        format!("not determined ({decades:.0} decades)")
                    } else {
                        format!("{b:.5e}")
                    }
                };
                // Its value is where the search stopped along a direction that changes nothing
                // (G0 -> 0, G_inf and tau trading off): shown as such, not as a result.
                let value = if p.sd.is_finite() {
                    format!("{:.5e}", p.value)
                } else {
                    format!("(search stopped at {:.1e})", p.value)
                };
                vec![p.name.clone(), value, bound(p.ci95[0]), bound(p.ci95[1])]
            })
            .collect(),
    );
    html.paragraph(
        "Positive parameters and alpha have intervals of their logarithm or logit, \
         mapped back; the two terms 'inputs beyond second order, shared' are in units \
         of their unit prior. An interval spanning more than three decades is shown as \
         not determined: the data do not fix that parameter (core_law.csv and \
         result.json keep the numbers).",
    );
}

/// `core_law.csv`: the law and its band on 60 lines over the modes.
fn law_csv(law: &CoreLawFit) -> String {
    let mut csv = String::from(
        "f_hz,storage_pa,storage_lo_pa,storage_hi_pa,loss_factor,loss_factor_lo,loss_factor_hi,\
         main_source_storage,main_source_loss_factor\n",
    );
    for p in law.curve(60) {
        let _ = writeln!(
            csv,
            "{},{:e},{:e},{:e},{},{},{},{},{}",
            p.freq_hz,
            p.storage_pa,
            p.storage_ci95[0],
            p.storage_ci95[1],
            p.loss_factor,
            p.loss_factor_ci95[0],
            p.loss_factor_ci95[1],
            p.dominant[0],
            p.dominant[1]
        );
    }
    csv
}

fn curve_csv(r: &ChainResult) -> String {
    let mut s = String::from(
        "f_hz,e_storage_pa,e_loss_factor,phi_abs,g_paper_storage_pa,g_paper_loss_factor,\
         g_exact_storage_pa,g_exact_loss_factor,causality_paper,causality_exact\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
    for (k, p) in r.curve.iter().enumerate() {
        let kk = |i: usize| r.causality[i][k].map_or("n/a", |v| v.label());
        s.push_str(&csv_line(&[
            format!("{}", p.freq_hz),
            opt(p.e_storage_pa()),
            opt(p.e_loss_factor()),
            opt(p.phi()),
            opt(storage(p.paper_g())),
            opt(loss(p.paper_g())),
            opt(storage(p.exact_g())),
            opt(loss(p.exact_g())),
            kk(0).into(),
            kk(1).into(),
        ]));
    }
    s
}

fn causality_verdict(r: &ChainResult) -> String {
    let count = |i: usize| {
        let v = &r.causality[i];
        let checked = v.iter().flatten().count();
        let bad = v.iter().flatten().filter(|x| !x.is_consistent()).count();
        (checked, bad)
    };
    let text = |name: &str, (checked, bad): (usize, usize)| {
        if checked == 0 {
            format!("{name} inverse: not checked (fewer than 3 lines with a solution)")
        } else if bad == 0 {
            format!(
                "{name} inverse: consistent with causality (Kramers-Kronig) at all {checked} lines"
            )
        } else {
            format!(
                "{name} inverse: fails the Kramers-Kronig check at {bad} of {checked} lines: no \
                 causal material has exactly this G*(f)"
            )
        }
    };
    format!("{}. {}.", text("Paper", count(0)), text("Exact", count(1)))
}

/// Builds the HTML report and all files of the results folder.
pub fn build(r: &ChainResult) -> Result<Files> {
    let mut files: Files = vec![];
    let mut html = HtmlReport::new(&r.job.title);
    // The first screen: the answer in a sentence, then its figures.
    answer_section(&mut html, &mut files, r)?;
    let (header, rows) = modal_table(r);
    lead_section(&mut html, r, &header, &rows);
    law_section(&mut html, &mut files, r);
    frf::section(&mut html, &mut files, r)?;
    let band_widths = r.band_widths();
    if let Some(b) = &band_widths {
        html.paragraph(&format!("Band widths. {}", b.describe()));
    }
    html.heading("Warnings");
    if r.warnings.is_empty() {
        html.paragraph("None.");
    } else {
        html.warnings(&r.warnings);
    }
    reference_methods_section(&mut html, &mut files, r, &header, &rows)?;
    identification_section(&mut html, &mut files, r)?;
    uncertainty_and_run_section(&mut html, r);
    files.push(("result.json".into(), result_json(r, band_widths)?));
    files.push(("report.html".into(), html.render().into_bytes()));
    Ok(files)
}

/// The report's first screen: the answer's sentence and its two figures.
fn answer_section(html: &mut HtmlReport, files: &mut Files, r: &ChainResult) -> Result<()> {
    html.answer(&answer::sentence(r));
    add_figure(
        html,
        files,
        "answer_storage",
        "The core's G'(f): the answer with its 95 % band and the layered inverse at each mode.",
        &answer::chart(r, false),
    )?;
    add_figure(
        html,
        files,
        "answer_loss",
        "The core's loss factor η(f), as above.",
        &answer::chart(r, true),
    )?;
    Ok(())
}

/// The paper's and the exact inverse at the modal frequencies (figures, tables picked from
/// the modal table's `header` and `rows`, `core_modal.csv`) and the paper's route's sections.
fn reference_methods_section(
    html: &mut HtmlReport,
    files: &mut Files,
    r: &ChainResult,
    header: &[&'static str],
    rows: &[Vec<String>],
) -> Result<()> {
    html.heading("The reference methods at the modal frequencies");
    add_figure(
        html,
        files,
        "core_storage",
        "Core G'(f) by every route: the paper's and the exact inverse with their 95 % bands (paper \
         Fig. 7), the law and the layered inverse per mode.",
        &core_chart(r, false),
    )?;
    html.paragraph(
        "The axes are scaled to the estimates: a band beyond them is clipped, and its \
         legend entry says so.",
    );
    add_figure(
        html,
        files,
        "core_loss",
        "Core loss factor eta(f), as above.",
        &core_chart(r, true),
    )?;
    let pick = |names: &[(&'static str, usize)]| pick_columns(header, rows, names);
    let with_truth = |mut cols: Vec<(&'static str, usize)>, errs: [&'static str; 2]| {
        if r.truth.is_some() {
            cols.extend(errs.map(|e| (e, 0)));
        }
        cols
    };
    let (h, t) = pick(&with_truth(
        vec![
            ("f [Hz]", 0),
            ("|phi|", 0),
            ("valid (|phi|<=0.1)", 0),
            ("G'_paper [MPa]", 0),
            ("G'_paper [MPa]", 1),
            ("eta_paper", 0),
            ("eta_paper", 1),
        ],
        ["err G'_paper [%]", "err eta_paper [%]"],
    ));
    html.table(
        "The paper's route: E*(f) fitted to the FRFs, then the paper's inverse (eqs. 33-45, 41), \
         with 95 % Monte Carlo bands; |phi| > 0.1 is beyond its validity (NO).",
        &h,
        t,
    );
    let (h, t) = pick(&with_truth(
        vec![
            ("f [Hz]", 0),
            ("E' [GPa]", 0),
            ("eta_E", 0),
            ("G'_exact [MPa]", 0),
            ("G'_exact [MPa]", 1),
            ("eta_exact", 0),
            ("eta_exact", 1),
        ],
        ["err G'_exact [%]", "err eta_exact [%]"],
    ));
    html.table(
        "The same effective modulus through the exact Mead-Markus sandwich inverse, with 95 % \
         Monte Carlo bands (all columns: core_modal.csv)",
        &h,
        t,
    );
    files.push((
        "core_modal.csv".into(),
        core_table::core_table(r).csv().into_bytes(),
    ));
    if let Some(t) = &r.truth {
        html.paragraph(&format!(
            "Truth: {}. Errors are recovered/true - 1 at each modal frequency.",
            t.source
        ));
    }
    match &r.fit {
        Some(fit) => paper_route_sections(html, files, r, fit)?,
        None => html.paragraph(&format!(
            "The paper's route has no result: {}. Its figures and files (core_curve.csv, \
             parameters.csv, table3.csv, rms.csv) are not written; the layered route above does \
             not depend on it.",
            r.paper_route_error.as_deref().unwrap_or("not run")
        )),
    }

    Ok(())
}

/// The modal identification: the stabilization diagram, the CMIF, the modes' table and
/// verdicts (`ema_modes.csv`), the shapes.
fn identification_section(html: &mut HtmlReport, files: &mut Files, r: &ChainResult) -> Result<()> {
    html.heading("Modal identification");
    let f = r.measured.set.freqs_hz();
    add_figure(
        html,
        files,
        "stabilization",
        "Stabilization diagram with the first CMIF behind it",
        &lamdyn_report::ema::stabilization_chart(&r.ema, f),
    )?;
    add_figure(
        html,
        files,
        "cmif",
        "Complex mode indicator function",
        &lamdyn_report::ema::cmif_chart(&r.ema, f),
    )?;
    let (modes, modes_csv) = ema_table(r);
    html.table(
        "Identified modes",
        &[
            "mode",
            "f [Hz]",
            "zeta [%]",
            "eta",
            "MPC",
            "MPD [deg]",
            "stable",
            "FRAC drop",
            "verdict",
        ],
        modes,
    );
    let verdicts = verdict_sentences(r);
    if !verdicts.is_empty() {
        html.paragraph(&format!(
            "Mode verdicts (lamdyn_ema::quality): {}",
            verdicts.join(" ")
        ));
    }
    files.push(("ema_modes.csv".into(), modes_csv.into_bytes()));
    for (name, caption, chart) in shape_charts(r) {
        add_figure(html, files, &name, &caption, &chart)?;
    }

    Ok(())
}

/// The Monte Carlo's settings and the run's inputs and stage times.
fn uncertainty_and_run_section(html: &mut HtmlReport, r: &ChainResult) {
    html.heading("Uncertainty");
    html.paragraph(&match &r.uncertainty {
        Some(m) => format!(
            "Monte Carlo: {} samples, seed {}, {} threads, {:.2} s. Drawn: the faces' Young's \
             modulus (relative sd {}), thickness (sd {} m) and density (relative sd {}), one draw \
             for both faces and one for the core{}. Bands: 2.5 % and 97.5 % quantiles of the \
             samples with a solution.",
            m.samples,
            m.seed,
            m.threads,
            m.seconds,
            r.job.uncertainty.face_modulus_rel_sd,
            r.job.uncertainty.thickness_sd_m,
            r.job.uncertainty.density_rel_sd,
            if m.fit_covariance {
                ", and the law's parameters from the fit's covariance"
            } else {
                "; the fit's covariance was not used (none, or switched off)"
            }
        ),
        None => "No Monte Carlo (uncertainty.samples = 0).".into(),
    });
    html.heading("Run");
    html.paragraph(&format!(
        "Job '{}'. Measurement: {}. Model: {}. Layered inverse: {}. lamdyn {}.",
        r.job_path.display(),
        r.measured.source,
        r.model_line,
        r.layered_line.as_deref().unwrap_or("not run"),
        env!("CARGO_PKG_VERSION")
    ));
    html.table(
        "Stages",
        &["stage", "time [s]", "cached"],
        r.timings
            .iter()
            .map(|t| {
                vec![
                    t.name.to_string(),
                    format!("{:.3}", t.seconds),
                    if t.cached { "yes" } else { "" }.into(),
                ]
            })
            .collect(),
    );
}

/// `result.json`: the run's inputs, the paper's fit, the core's law, the FRF route, the modes,
/// the uncertainty, the band widths, the warnings and the stage times.
fn result_json(
    r: &ChainResult,
    band_widths: Option<crate::band_widths::BandWidths>,
) -> Result<Vec<u8>> {
    let json = serde_json::json!({
        "job": r.job_path.display().to_string(),
        "measurement": r.measured.source,
        "model": r.model_line,
        "fit": r.fit,
        "paper_route_error": r.paper_route_error,
        "core_law": r.core_law.as_ref().map(|l| l.as_ref().map_err(ToString::to_string)),
        "frf_fit": frf::json(r),
        "ema_modes": r.ema.modes.iter().map(|m| serde_json::json!({"freq_hz": m.freq_hz, "damping_ratio": m.damping_ratio, "mpc": m.mpc})).collect::<Vec<_>>(),
        "uncertainty": r.uncertainty,
        "band_widths": band_widths,
        "warnings": r.warnings,
        "timings": r.timings.iter().map(|t| serde_json::json!({"stage": t.name, "seconds": t.seconds, "cached": t.cached})).collect::<Vec<_>>(),
    });
    Ok(serde_json::to_vec_pretty(&json)?)
}

/// The paper's route's own sections: causality of its curve, the laminate's effective
/// modulus, the fitted law's parameters and the fit against the measured RMS FRF.
fn paper_route_sections(
    html: &mut HtmlReport,
    files: &mut Files,
    r: &ChainResult,
    fit: &FitResult,
) -> Result<()> {
    html.heading("Causality");
    html.paragraph(&causality_verdict(r));
    files.push(("core_curve.csv".into(), curve_csv(r).into_bytes()));

    html.heading("Laminate effective modulus");
    let (e, eta) = laminate_charts(r);
    add_figure(
        html,
        files,
        "laminate_storage",
        "Laminate E'(f) of the fitted law (paper Fig. 4)",
        &e,
    )?;
    add_figure(
        html,
        files,
        "laminate_loss",
        "Laminate loss factor (paper Fig. 4)",
        &eta,
    )?;
    let (params, params_csv) = parameter_table(fit);
    html.table(
        "Fitted law parameters (SI: Pa, s, Pa s); 95 % intervals +-1.96 sd",
        &["parameter", "value", "sd", "95% low", "95% high"],
        params,
    );
    files.push(("parameters.csv".into(), params_csv.into_bytes()));

    html.heading("Fit: measured vs fitted FRFs");
    add_figure(
        html,
        files,
        "rms_frf",
        "RMS FRF over the responses, measured and fitted (paper Fig. 5)",
        &rms_chart(r),
    )?;
    let (t3, t3_csv) = table3(r);
    html.table(
        "Table 3: RMS FRF peaks, measured vs fitted",
        &[
            "f meas [Hz]",
            "f fit [Hz]",
            "err [%]",
            "amp meas",
            "amp fit",
            "err [%]",
            "zeta meas",
            "zeta fit",
            "err [%]",
        ],
        t3,
    );
    files.push(("table3.csv".into(), t3_csv.into_bytes()));
    let mut rms = format!(
        "# RMS FRF over the responses ({})\nf_hz,measured,fitted\n",
        r.measured.set.quantity().unit()
    );
    for &k in &r.fit_lines {
        let _ = writeln!(
            rms,
            "{},{:e},{:e}",
            r.measured.set.freqs_hz()[k],
            r.measured_rms[k],
            r.fitted_rms[k]
        );
    }
    files.push(("rms.csv".into(), rms.into_bytes()));

    Ok(())
}

fn parameter_table(fit: &FitResult) -> (Vec<Vec<String>>, String) {
    let mut csv = String::from("name,value,std_dev,ci95_low,ci95_high\n");
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
    let rows = fit
        .parameters
        .iter()
        .map(|p| {
            csv.push_str(&csv_line(&[
                p.name.clone(),
                format!("{:e}", p.value),
                opt(p.std_dev),
                opt(p.ci95.map(|c| c[0])),
                opt(p.ci95.map(|c| c[1])),
            ]));
            let s = |v: Option<f64>| v.map_or("-".into(), |x| format!("{x:.4e}"));
            vec![
                p.name.clone(),
                format!("{:.6e}", p.value),
                s(p.std_dev),
                s(p.ci95.map(|c| c[0])),
                s(p.ci95.map(|c| c[1])),
            ]
        })
        .collect();
    (rows, csv)
}

fn table3(r: &ChainResult) -> (Vec<Vec<String>>, String) {
    let mut csv = String::from(
        "f_measured_hz,f_fitted_hz,f_error,amplitude_measured,amplitude_fitted,amplitude_error,\
         damping_ratio_measured,damping_ratio_fitted,damping_ratio_error\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
    let rows = r
        .table3
        .iter()
        .map(|c| {
            csv.push_str(&csv_line(&[
                format!("{}", c.measured.freq_hz),
                format!("{}", c.fitted.freq_hz),
                format!("{:e}", c.freq_error),
                format!("{:e}", c.measured.amplitude),
                format!("{:e}", c.fitted.amplitude),
                format!("{:e}", c.amplitude_error),
                opt(c.measured.damping_ratio),
                opt(c.fitted.damping_ratio),
                opt(c.damping_error),
            ]));
            vec![
                format!("{:.3}", c.measured.freq_hz),
                format!("{:.3}", c.fitted.freq_hz),
                format!("{:+.3}", 100.0 * c.freq_error),
                format!("{:.4e}", c.measured.amplitude),
                format!("{:.4e}", c.fitted.amplitude),
                format!("{:+.2}", 100.0 * c.amplitude_error),
                fmt(c.measured.damping_ratio, 1.0, 4),
                fmt(c.fitted.damping_ratio, 1.0, 4),
                pct(c.damping_error),
            ]
        })
        .collect();
    (rows, csv)
}

/// The identified modes, then the poles set aside as smears (marked "set aside"), as table
/// rows and as `ema_modes.csv`.
fn ema_table(r: &ChainResult) -> (Vec<Vec<String>>, String) {
    let mut csv = String::from(
        "mode,f_hz,f_sd_hz,damping_ratio,damping_sd,loss_factor,mpc,mpd_deg,stable_count,frac_drop,\
         verdict,in_chain\n",
    );
    let numbered = r.ema.modes.iter().map(|m| (m, true));
    let aside = r.ema.set_aside.iter().map(|m| (m, false));
    let rows = numbered
        .chain(aside)
        .enumerate()
        .map(|(k, (m, in_chain))| {
            csv.push_str(&csv_line(&[
                (k + 1).to_string(),
                format!("{}", m.freq_hz),
                m.sd.map_or(String::new(), |d| format!("{:e}", d.freq_hz)),
                format!("{:e}", m.damping_ratio),
                m.sd.map_or(String::new(), |d| format!("{:e}", d.damping_ratio)),
                format!("{:e}", m.loss_factor),
                format!("{}", m.mpc),
                format!("{}", m.mpd_deg),
                m.stable_count.to_string(),
                format!("{:e}", m.quality.frac_drop),
                m.quality.verdict.label().to_string(),
                in_chain.to_string(),
            ]));
            let verdict = if in_chain {
                m.quality.verdict.label().to_string()
            } else {
                format!("{} (set aside)", m.quality.verdict.label())
            };
            vec![
                (k + 1).to_string(),
                format!("{:.4}", m.freq_hz),
                format!("{:.3}", 100.0 * m.damping_ratio),
                format!("{:.3e}", m.loss_factor),
                format!("{:.4}", m.mpc),
                format!("{:.2}", m.mpd_deg),
                m.stable_count.to_string(),
                format!("{:.1e}", m.quality.frac_drop),
                verdict,
            ]
        })
        .collect();
    (rows, csv)
}

/// One sentence per mode that is not sound (why), set-aside poles first; empty when all are.
fn verdict_sentences(r: &ChainResult) -> Vec<String> {
    let aside = r.ema.set_aside.iter().map(|m| (m, true));
    let doubtful = r
        .ema
        .modes
        .iter()
        .filter(|m| m.quality.verdict != lamdyn_ema::quality::Verdict::Sound)
        .map(|m| (m, false));
    aside
        .chain(doubtful)
        .map(|(m, set_aside)| {
            format!(
                "{:.3} Hz is {}{}: {}.",
                m.freq_hz,
                m.quality.verdict.label(),
                if set_aside {
                    ", set aside from the inverses (ema.keep_smears = true keeps it)"
                } else {
                    ""
                },
                m.quality.reasons()
            )
        })
        .collect()
}
