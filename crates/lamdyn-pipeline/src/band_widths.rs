//! How wide the layered route's 95 % bands are, and what would narrow them.
//!
//! The report and `lamdyn run` state, after the law:
//! - the median half-width of the law's band over the measured band (ln G' and ln η, from the
//!   first identified mode to the last: [`CURVE_POINTS`] frequencies even in ln f) and of the
//!   per-mode bands;
//! - per part (G', η), the widest band of the law at a mode, the source contributing most to
//!   it and what would narrow that source ([`what_would_narrow`]);
//! - the modes whose own band spans more than a factor [`UNDETERMINED_FACTOR`] either way: that
//!   mode alone does not determine the core (a mode that mostly moves the part on its
//!   supports); the law still uses it, weighted by its band.
//!
//! A half-width h is that of ln x: the band is [x e^−h, x e^h], and h ≈ the relative half-width
//! when small.

pub use crate::band::what_would_narrow;
use crate::band::{LayeredBand, ModulusPart};
use crate::chain::CorePoint;
use lamdyn_fit::joint::CoreLawFit;
use serde::Serialize;

/// Frequencies of the law's curve over which the median half-width is taken.
pub const CURVE_POINTS: usize = 60;

/// A mode whose own band spans more than this factor either way of its value (hi/lo above its
/// square) does not determine the core by itself.
pub const UNDETERMINED_FACTOR: f64 = 10.0;

/// Names of the parts, in the order of every `[G', η]` pair.
const PARTS: [&str; 2] = ["G'", "eta"];

/// The widest band of one part and what would narrow it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WidestBand {
    /// "G'" or "eta".
    pub part: &'static str,
    /// The mode's frequency, Hz.
    pub freq_hz: f64,
    /// Half-width of the band of ln G' or ln η.
    pub half_width: f64,
    /// The source contributing most to it (an input's name, "EMA pole", "discretization", ...).
    pub source: String,
    /// What would narrow that source ([`what_would_narrow`]).
    pub advice: String,
}

/// A mode whose own band does not determine the core.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UndeterminedMode {
    /// Its frequency, Hz.
    pub freq_hz: f64,
    /// Per part, G' and η, whether its band spans more than [`UNDETERMINED_FACTOR`] either way.
    pub parts: [bool; 2],
    /// The source contributing most to its widest part.
    pub source: String,
    /// What would narrow that source.
    pub advice: String,
}

/// The band widths of one run (module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandWidths {
    /// Median half-width of the law's band over the measured band, ln G' and ln η (`None`
    /// without a law).
    pub law_median: Option<[f64; 2]>,
    /// Median half-width of the per-mode layered bands, ln G' and ln η, over the modes that
    /// have one and determine the core (`None` when none does).
    pub modes_median: Option<[f64; 2]>,
    /// Per part, the widest band: the law's at a mode where there is a law, else the modes'.
    pub widest: Vec<WidestBand>,
    /// The modes whose own band does not determine the core.
    pub undetermined: Vec<UndeterminedMode>,
}

/// The band widths of a run's per-mode layered points `modal` and its law `law` (module
/// docs); `None` when neither has a band.
pub fn band_widths(modal: &[CorePoint], law: Option<&CoreLawFit>) -> Option<BandWidths> {
    let bands: Vec<(f64, &LayeredBand)> = modal
        .iter()
        .filter_map(|p| Some((p.freq_hz, p.layered_band.as_ref()?.as_ref().ok()?)))
        .collect();
    let undetermined: Vec<UndeterminedMode> = bands
        .iter()
        .filter_map(|(f, b)| {
            let dominant = [
                b.dominant_label(ModulusPart::Storage),
                b.dominant_label(ModulusPart::Loss),
            ];
            undetermined(*f, b.half_width.to_array(), dominant)
        })
        .collect();
    let determined: Vec<(f64, &LayeredBand)> = bands
        .iter()
        .filter(|(f, _)| !undetermined.iter().any(|u| u.freq_hz == *f))
        .copied()
        .collect();
    let halves: Vec<[f64; 2]> = determined
        .iter()
        .map(|(_, b)| b.half_width.to_array())
        .collect();
    let modes_median = median_pair(&halves);
    let law_median = law.and_then(|l| {
        let curve: Vec<[f64; 2]> = l.curve(CURVE_POINTS).iter().map(half_widths).collect();
        median_pair(&curve)
    });
    let widest: Vec<WidestBand> = match law {
        Some(l) => widest_of_law(l),
        None => widest_of_modes(&determined),
    };
    if law_median.is_none() && modes_median.is_none() && undetermined.is_empty() {
        return None;
    }
    Some(BandWidths {
        law_median,
        modes_median,
        widest,
        undetermined,
    })
}

/// Whether a band of half-width `h` (of a logarithm) determines its value: finite and within
/// [`UNDETERMINED_FACTOR`] either way.
pub fn determines(h: f64) -> bool {
    h.is_finite() && h <= UNDETERMINED_FACTOR.ln()
}

/// The mode at `freq_hz` if its band (half-widths `half_width` of ln G' and ln η, main
/// sources `dominant`) spans more than [`UNDETERMINED_FACTOR`] either way; a NaN band counts.
fn undetermined(
    freq_hz: f64,
    half_width: [f64; 2],
    dominant: [&str; 2],
) -> Option<UndeterminedMode> {
    let parts = half_width.map(|h| !determines(h));
    if !parts.iter().any(|&p| p) {
        return None;
    }
    // The part beyond the factor; of two, the wider.
    let worst = match parts {
        [true, false] => 0,
        [false, true] => 1,
        _ => usize::from(half_width[1] > half_width[0]),
    };
    let source = dominant[worst].to_string();
    Some(UndeterminedMode {
        freq_hz,
        parts,
        advice: what_would_narrow(&source),
        source,
    })
}

/// Half-widths of ln G' and ln η of a law point's band.
fn half_widths(p: &lamdyn_fit::joint::LawPoint) -> [f64; 2] {
    [
        0.5 * (p.storage_ci95[1] / p.storage_ci95[0]).ln(),
        0.5 * (p.loss_factor_ci95[1] / p.loss_factor_ci95[0]).ln(),
    ]
}

/// Per part, the widest of the law's bands at its modes.
fn widest_of_law(law: &CoreLawFit) -> Vec<WidestBand> {
    (0..2)
        .filter_map(|c| {
            let p = law
                .at_modes
                .iter()
                .max_by(|a, b| half_widths(a)[c].total_cmp(&half_widths(b)[c]))?;
            let source = p.dominant[c].clone();
            Some(WidestBand {
                part: PARTS[c],
                freq_hz: p.freq_hz,
                half_width: half_widths(p)[c],
                advice: what_would_narrow(&source),
                source,
            })
        })
        .collect()
}

/// Per part, the widest of the per-mode bands that determine the core.
fn widest_of_modes(determined: &[(f64, &LayeredBand)]) -> Vec<WidestBand> {
    [ModulusPart::Storage, ModulusPart::Loss]
        .into_iter()
        .enumerate()
        .filter_map(|(c, part)| {
            let (f, b) = determined.iter().max_by(|a, b| {
                a.1.half_width
                    .part(part)
                    .total_cmp(&b.1.half_width.part(part))
            })?;
            let source = b.dominant_label(part).to_string();
            Some(WidestBand {
                part: PARTS[c],
                freq_hz: *f,
                half_width: b.half_width.part(part),
                advice: what_would_narrow(&source),
                source,
            })
        })
        .collect()
}

/// Per part, the median of `v` (the upper of the two middle values); `None` when empty.
fn median_pair(v: &[[f64; 2]]) -> Option<[f64; 2]> {
    if v.is_empty() {
        return None;
    }
    Some([0, 1].map(|c| {
        let mut x: Vec<f64> = v.iter().map(|p| p[c]).collect();
        x.sort_by(f64::total_cmp);
        x[x.len() / 2]
    }))
}

impl BandWidths {
    /// One paragraph for the report and one line for the console: the medians, the widest band
    /// per part with its source and advice, and the modes that do not determine the core.
    pub fn describe(&self) -> String {
        let pct = |h: f64| width_text(h);
        let mut parts = Vec::new();
        if let Some(m) = self.law_median {
            parts.push(format!(
                "the law's 95 % band has a median half-width of {} in G' and {} in eta over the \
                 measured band",
                pct(m[0]),
                pct(m[1])
            ));
        }
        if let Some(m) = self.modes_median {
            parts.push(format!(
                "each mode's own band {} / {} (median)",
                pct(m[0]),
                pct(m[1])
            ));
        }
        let mut text = capitalise(&parts.join("; "));
        // Each remedy once: the widest bands that one source dominates share a sentence.
        let mut stated: Vec<&str> = Vec::new();
        for w in &self.widest {
            if stated.contains(&w.advice.as_str()) {
                continue;
            }
            let alike: Vec<String> = self
                .widest
                .iter()
                .filter(|v| v.advice == w.advice)
                .map(|v| format!("{} {} at {:.1} Hz", v.part, pct(v.half_width), v.freq_hz))
                .collect();
            let (it, one) = if alike.len() > 1 {
                ("them", "both")
            } else {
                ("it", "")
            };
            text += &format!(
                ". Widest in {}, {one}{}mainly from the {}; what would narrow {it}: {}",
                alike.join(" and in "),
                if one.is_empty() { "" } else { " " },
                w.source,
                w.advice
            );
            stated.push(&w.advice);
        }
        if let Some(first) = self.undetermined.first() {
            let list: Vec<String> = self
                .undetermined
                .iter()
                .map(|u| format!("{:.1} Hz ({})", u.freq_hz, u.source))
                .collect();
            let advice = if stated.contains(&first.advice.as_str()) {
                "as above".to_string()
            } else {
                first.advice.clone()
            };
            text += &format!(
                ". Not determined by its own mode (band wider than a factor {UNDETERMINED_FACTOR} \
                 either way; the law weighs it by that band): {}; what would narrow them: {advice}",
                list.join(", "),
            );
        }
        text + "."
    }
}

/// A half-width h of a logarithm in words: "±2.7 %" below 20 %, "a factor 3.1 either way"
/// above, where ±h would understate the upper side (e^h − 1) and overstate the lower.
fn width_text(h: f64) -> String {
    if h < 0.2 {
        format!("±{:.1} %", 100.0 * h)
    } else {
        format!("a factor {:.2} either way", h.exp())
    }
}

/// `s` with its first letter in upper case.
fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every source a band can name gets advice of its own, not the fallback: the inputs, the
    /// per-mode sources and the joint fit's rows.
    #[test]
    fn every_band_source_has_its_own_advice() {
        for s in crate::band::BandSource::all() {
            let advice = what_would_narrow(s.label());
            assert!(
                !advice.starts_with("a narrower prior on the"),
                "{s}: {advice}"
            );
        }
    }

    /// A band wider than the factor in either part, or NaN, is not determined by its mode,
    /// and the wider part names the source; one just inside is.
    #[test]
    fn a_band_beyond_the_factor_does_not_determine_its_mode() {
        let limit = UNDETERMINED_FACTOR.ln();
        let src = ["face modulus", "support stiffness"];
        assert_eq!(undetermined(20.0, [0.05, 0.999 * limit], src), None);
        let u = undetermined(20.0, [0.05, 1.001 * limit], src).expect("undetermined");
        assert_eq!(u.parts, [false, true]);
        assert_eq!(u.source, "support stiffness");
        assert_eq!(u.advice, what_would_narrow("support stiffness"));
        let nan = undetermined(20.0, [f64::NAN, 0.1], src).expect("NaN is not determined");
        assert_eq!(nan.parts, [true, false]);
        assert_eq!(nan.source, "face modulus");
    }

    /// Bands that one source dominates share one sentence and one remedy; an undetermined
    /// mode with that remedy points to it instead of repeating it.
    #[test]
    fn each_remedy_is_stated_once() {
        let widest = |part, f, source: &str| WidestBand {
            part,
            freq_hz: f,
            half_width: 0.05,
            source: source.into(),
            advice: what_would_narrow(source),
        };
        let b = BandWidths {
            law_median: Some([0.03, 0.04]),
            modes_median: None,
            widest: vec![
                widest("G'", 20.0, "EMA pole"),
                widest("eta", 40.0, "EMA pole"),
            ],
            undetermined: vec![UndeterminedMode {
                freq_hz: 90.0,
                parts: [true, false],
                source: "EMA pole".into(),
                advice: what_would_narrow("EMA pole"),
            }],
        };
        let text = b.describe();
        assert_eq!(
            text.matches(&what_would_narrow("EMA pole")).count(),
            1,
            "{text}"
        );
        assert!(
            text.contains(
                "Widest in G' ±5.0 % at 20.0 Hz and in eta ±5.0 % at 40.0 Hz, both \
                 mainly from the EMA pole; what would narrow them: "
            ),
            "{text}"
        );
        assert!(
            text.ends_with("what would narrow them: as above."),
            "{text}"
        );
    }

    #[test]
    fn widths_read_as_percent_or_factor() {
        assert_eq!(width_text(0.027), "±2.7 %");
        assert_eq!(width_text(2.0f64.ln()), "a factor 2.00 either way");
    }

    #[test]
    fn medians_take_each_part_apart() {
        let v = [[0.03, 0.5], [0.01, 0.1], [0.02, 0.2]];
        assert_eq!(median_pair(&v), Some([0.02, 0.2]));
        assert_eq!(median_pair(&[]), None);
    }
}
