//! The report's first screen: the core's G'(f) and η(f) in one sentence with their bands, how
//! the run judged itself and what to do if it did not pass, then the figures of the answer.
//!
//! The answer is, in this order of preference: the law fitted to the measured FRFs when the
//! run takes it ([`crate::frf_route`]), the law fitted to the layered inverse's cores at every
//! mode ([`lamdyn_fit::joint`]), the layered inverse's core at each mode, or the exact
//! sandwich inverse's (the layered inverse did not run).

use super::{BLUE, ORANGE, PURPLE, loss, modal_bands, storage, truth_series};
use crate::ChainResult;
use crate::band::ModulusPart;
use crate::frf_route::FrfRoute;
use lamdyn_fit::joint::{CoreLawFit, LawPoint};
use lamdyn_report::chart::{Axis, Chart, Mark, Series};

/// Lines of a law's curve in the figures.
const CURVE_LINES: usize = 60;

/// A band's half-width (of the logarithm) beyond which the sentence names a remedy.
const WIDE: f64 = 0.1;

/// G' and η at one frequency, each with its 95 % band where there is one.
#[derive(Debug, Clone, Copy)]
struct Point {
    freq_hz: f64,
    storage_pa: f64,
    storage_ci95: Option<[f64; 2]>,
    loss_factor: f64,
    loss_factor_ci95: Option<[f64; 2]>,
}

impl Point {
    /// The half-widths of the logarithms' bands, G' and η (`None` without a band).
    fn half_widths(&self) -> [Option<f64>; 2] {
        let h = |b: Option<[f64; 2]>| b.map(|[lo, hi]| 0.5 * (hi / lo).ln().abs());
        [h(self.storage_ci95), h(self.loss_factor_ci95)]
    }
}

impl From<&LawPoint> for Point {
    fn from(p: &LawPoint) -> Self {
        Self {
            freq_hz: p.freq_hz,
            storage_pa: p.storage_pa,
            storage_ci95: Some(p.storage_ci95),
            loss_factor: p.loss_factor,
            loss_factor_ci95: Some(p.loss_factor_ci95),
        }
    }
}

/// Where the run's answer comes from (module docs).
enum Source<'a> {
    FrfFit(&'a FrfRoute),
    Law(&'a CoreLawFit),
    Modes { layered: bool, points: Vec<Point> },
}

impl<'a> Source<'a> {
    /// The run's answer, if it has one.
    fn of(r: &'a ChainResult) -> Option<Self> {
        if let Some(route) = r.frf.answer() {
            return Some(Self::FrfFit(route));
        }
        if let Some(Ok(law)) = &r.core_law {
            return Some(Self::Law(law));
        }
        let layered = r.modal.iter().any(|p| p.layered_g().is_some());
        let points: Vec<Point> = r
            .modal
            .iter()
            .filter_map(|p| {
                let g = if layered { p.layered_g() } else { p.exact_g() }?;
                let (sb, lb) = if layered {
                    let h = p.layered_band.as_ref().and_then(|b| b.as_ref().ok());
                    let band = |k: ModulusPart, v: f64| {
                        let h = h.map(|h| h.half_width.part(k));
                        h.map(|h| [v * (-h).exp(), v * h.exp()])
                    };
                    (
                        band(ModulusPart::Storage, g.re),
                        band(ModulusPart::Loss, g.im / g.re),
                    )
                } else {
                    let b = modal_bands(r, p);
                    (b.exact_storage, b.exact_loss_factor)
                };
                Some(Point {
                    freq_hz: p.freq_hz,
                    storage_pa: g.re,
                    storage_ci95: sb,
                    loss_factor: g.im / g.re,
                    loss_factor_ci95: lb,
                })
            })
            .collect();
        (!points.is_empty()).then_some(Self::Modes { layered, points })
    }

    /// What the answer is, in words.
    fn name(&self, r: &ChainResult) -> String {
        match self {
            Self::FrfFit(route) => format!(
                "the {} law fitted to the measured FRFs through the layered model",
                route.fit.law.name()
            ),
            Self::Law(law) => format!(
                "the {} law fitted to the layered inverse's cores at {} modes",
                law.law.name(),
                law.at_modes.len()
            ),
            Self::Modes { layered: true, .. } => {
                "the layered inverse at each identified mode".into()
            }
            Self::Modes { layered: false, .. } => format!(
                "the exact sandwich inverse at each identified mode ({})",
                r.layered_line
                    .as_deref()
                    .unwrap_or("the layered inverse did not run")
            ),
        }
    }

    /// The answer at the identified modes' frequencies.
    fn at_modes(&self, r: &ChainResult) -> Vec<Point> {
        match self {
            Self::FrfFit(route) => r
                .modal
                .iter()
                .map(|p| frf_point(route, p.freq_hz))
                .collect(),
            Self::Law(law) => law.at_modes.iter().map(Point::from).collect(),
            Self::Modes { points, .. } => points.clone(),
        }
    }

    /// The answer as a curve over the modes' frequencies (the points themselves for a
    /// per-mode answer).
    fn curve(&self, r: &ChainResult) -> Option<Vec<Point>> {
        match self {
            Self::FrfFit(route) => {
                let [lo, hi] = modal_span(r);
                (lo < hi).then(|| {
                    (0..CURVE_LINES)
                        .map(|k| {
                            let t = k as f64 / (CURVE_LINES - 1) as f64;
                            frf_point(route, lo * (hi / lo).powf(t))
                        })
                        .collect()
                })
            }
            Self::Law(law) => Some(law.curve(CURVE_LINES).iter().map(Point::from).collect()),
            Self::Modes { .. } => None,
        }
    }
}

/// The smallest and largest of `values` (+inf and 0 when there are none).
fn extent(values: impl Iterator<Item = f64>) -> [f64; 2] {
    values.fold([f64::INFINITY, 0.0], |[a, b], x| [a.min(x), b.max(x)])
}

/// The lowest and highest identified modal frequency, Hz.
fn modal_span(r: &ChainResult) -> [f64; 2] {
    extent(r.modal.iter().map(|p| p.freq_hz))
}

/// The FRF route's law at `f_hz`.
fn frf_point(route: &FrfRoute, f_hz: f64) -> Point {
    let a = route.at(f_hz);
    Point {
        freq_hz: f_hz,
        storage_pa: a.storage_pa,
        storage_ci95: Some(a.storage_ci95),
        loss_factor: a.loss_factor,
        loss_factor_ci95: Some(a.loss_factor_ci95),
    }
}

/// The sentence that opens the report (module docs).
pub(super) fn sentence(r: &ChainResult) -> String {
    let Some(source) = Source::of(r) else {
        return format!(
            "No core: no identified mode gave one by any route. {}",
            judgement(r, &[])
        );
    };
    let points = source.at_modes(r);
    let (Some(first), Some(last)) = (points.first(), points.last()) else {
        return format!("No core at the identified modes. {}", judgement(r, &points));
    };
    let widths = |k: usize| {
        let h: Vec<f64> = points.iter().filter_map(|p| p.half_widths()[k]).collect();
        let [lo, hi] = extent(h.iter().copied());
        if h.is_empty() {
            "no band".to_string()
        } else if hi > crate::band_widths::UNDETERMINED_FACTOR.ln() {
            "not determined at some modes".to_string()
        } else if hi - lo < 0.001 {
            format!("±{:.1}\u{a0}%", 100.0 * hi)
        } else {
            format!("±{:.1} to {:.1}\u{a0}%", 100.0 * lo, 100.0 * hi)
        }
    };
    format!(
        "The core's shear storage modulus G' is {} MPa at {:.1} Hz and {} MPa at {:.1} Hz, its \
         loss factor η {} and {} (95 % bands: G' {}, η {}), from {}. {}",
        significant(first.storage_pa / 1e6),
        first.freq_hz,
        significant(last.storage_pa / 1e6),
        last.freq_hz,
        significant(first.loss_factor),
        significant(last.loss_factor),
        widths(0),
        widths(1),
        source.name(r),
        judgement(r, &points)
    )
}

/// `x` with three significant digits, as people write it (13.6, 0.673, 1250).
fn significant(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let digits = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.digits$}")
}

/// How the run judged itself and what to do if it did not pass.
fn judgement(r: &ChainResult, points: &[Point]) -> String {
    let mut s = Vec::new();
    let without = r.modes_without_core();
    if without.is_empty() {
        s.push("Every identified mode has a core.".to_string());
    } else {
        let list: Vec<String> = without.iter().map(|f| format!("{f:.1}")).collect();
        s.push(format!(
            "Not passed: {} identified mode(s) got no core ({} Hz; why under Warnings), and lamdyn \
             exits with status 1.",
            without.len(),
            list.join(", ")
        ));
    }
    if !r.warnings.is_empty() {
        s.push(format!("{} warning(s) below.", r.warnings.len()));
    }
    if let Some(t) = &r.truth {
        let errors: Vec<[f64; 2]> = points
            .iter()
            .filter_map(|p| {
                let g = t.at(p.freq_hz)?;
                Some([
                    (p.storage_pa / g.re - 1.0).abs(),
                    (p.loss_factor / (g.im / g.re) - 1.0).abs(),
                ])
            })
            .collect();
        if !errors.is_empty() {
            let max = |k: usize| errors.iter().map(|e| e[k]).fold(0.0, f64::max);
            s.push(format!(
                "Against the virtual test's truth: within {:.1} % in G' and {:.1} % in η at the \
                 modes.",
                100.0 * max(0),
                100.0 * max(1)
            ));
        }
    }
    if let Some(w) = r
        .band_widths()
        .and_then(|b| b.widest.into_iter().find(|w| w.half_width > WIDE))
    {
        // With the FRF fit as the answer, the bands' sources are the pole route's beside it.
        let whose = if r.frf.answer().is_some() {
            "Beside it, the pole route's widest band"
        } else {
            "The widest band"
        };
        s.push(format!(
            "{whose} ({} ±{:.0} % at {:.1} Hz) comes mainly from the {}; what would narrow it: {}.",
            w.part,
            100.0 * w.half_width,
            w.freq_hz,
            w.source,
            w.advice
        ));
    }
    s.join(" ")
}

/// The answer's figure for G' (`loss_factor` false) or η: its curve and band where it is a
/// law, the per-mode layered points, and the truth of a virtual test.
pub(super) fn chart(r: &ChainResult, loss_factor: bool) -> Chart {
    let (title, label, scale) = if loss_factor {
        ("The core's loss factor η(f)", "loss factor", 1.0)
    } else {
        ("The core's shear storage modulus G'(f)", "G' (MPa)", 1e6)
    };
    let mut c = Chart::new(title, Axis::linear("frequency (Hz)"), Axis::linear(label));
    let Some(source) = Source::of(r) else {
        return c;
    };
    let value = |p: &Point| {
        if loss_factor {
            (p.loss_factor, p.loss_factor_ci95)
        } else {
            (
                p.storage_pa / scale,
                p.storage_ci95.map(|[a, b]| [a / scale, b / scale]),
            )
        }
    };
    if let Some(curve) = source.curve(r) {
        let mut band: Vec<[f64; 2]> = Vec::new();
        let (ups, downs): (Vec<_>, Vec<_>) = curve
            .iter()
            .filter_map(|p| {
                value(p)
                    .1
                    .map(|[lo, hi]| ([p.freq_hz, hi], [p.freq_hz, lo]))
            })
            .unzip();
        band.extend(ups);
        band.extend(downs.into_iter().rev());
        if !band.is_empty() {
            c.series
                .push(Series::new("95 % band", PURPLE, Mark::Band, band));
        }
        c.series.push(Series::new(
            &format!("the answer: {}", short_name(&source)),
            PURPLE,
            Mark::Line,
            curve.iter().map(|p| [p.freq_hz, value(p).0]).collect(),
        ));
    }
    if let (Source::FrfFit(_), Some(Ok(law))) = (&source, &r.core_law) {
        c.series.push(Series::new(
            "law from the poles (layered inverse per mode)",
            ORANGE,
            Mark::Line,
            law.curve(CURVE_LINES)
                .iter()
                .map(|p| {
                    let v = if loss_factor {
                        p.loss_factor
                    } else {
                        p.storage_pa / scale
                    };
                    [p.freq_hz, v]
                })
                .collect(),
        ));
    }
    c.series
        .extend(truth_series(r, modal_span(r), loss_factor, scale));
    let per_mode: Vec<[f64; 2]> = match &source {
        Source::Modes { points, .. } => points.iter().map(|p| [p.freq_hz, value(p).0]).collect(),
        _ => r
            .modal
            .iter()
            .filter_map(|p| {
                let v = if loss_factor {
                    loss(p.layered_g())
                } else {
                    storage(p.layered_g())
                };
                v.map(|v| [p.freq_hz, v / scale])
            })
            .collect(),
    };
    if !per_mode.is_empty() {
        let name = match &source {
            Source::Modes { layered: false, .. } => "exact inverse per mode",
            _ => "layered inverse per mode",
        };
        c.series
            .push(Series::new(name, BLUE, Mark::Highlight, per_mode));
    }
    c
}

/// The answer's kind for a legend entry.
fn short_name(source: &Source) -> String {
    match source {
        Source::FrfFit(route) => format!("law fitted to the FRFs ({})", route.fit.law.name()),
        Source::Law(law) => format!("law over all modes ({})", law.law.name()),
        Source::Modes { .. } => "per mode".into(),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn three_significant_digits() {
        assert_eq!(super::significant(13.587), "13.6");
        assert_eq!(super::significant(0.6734), "0.673");
        assert_eq!(super::significant(1234.5), "1234");
        assert_eq!(super::significant(2.0), "2.00");
    }
}
