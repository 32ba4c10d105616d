//! Charts of an experimental modal analysis: the stabilization diagram (poles by model order
//! and stability class over frequency, the first CMIF behind them on a log axis) and the CMIF
//! (every singular value of the FRF matrix per line, its peaks, the identified modes).

use crate::chart::{Axis, Chart, Mark, Series};
use lamdyn_ema::identify::EmaResult;
use lamdyn_ema::stabilization::Stability;

const GREY: [u8; 3] = [170, 170, 170];
const BLUE: [u8; 3] = [31, 119, 180];
const ORANGE: [u8; 3] = [255, 127, 14];
const RED: [u8; 3] = [214, 39, 40];
const BLACK: [u8; 3] = [0, 0, 0];
const LIGHT: [u8; 3] = [200, 215, 235];

/// A vertical line at each mode from `lo` to `hi`, the first one named `name`.
fn mode_lines(r: &EmaResult, lo: f64, hi: f64, name: &str, color: [u8; 3]) -> Vec<Series> {
    r.modes
        .iter()
        .enumerate()
        .map(|(k, m)| {
            Series::new(
                if k == 0 { name } else { "" },
                color,
                Mark::Line,
                vec![[m.freq_hz, lo], [m.freq_hz, hi]],
            )
        })
        .collect()
}

/// The stabilization diagram of `r` (lines at `freqs_hz`).
pub fn stabilization_chart(r: &EmaResult, freqs_hz: &[f64]) -> Chart {
    let [lo, hi] = r.band_hz;
    let max_order = r.diagram.iter().map(|p| p.order).max().unwrap_or(1) as f64;
    let mut c = Chart::new(
        "Stabilization diagram",
        Axis::linear("frequency (Hz)").with_range(lo, hi),
        Axis::linear("model order").with_range(0.0, max_order + 2.0),
    );
    c.y2 = Some(Axis::log("CMIF sigma_1"));
    let band: Vec<usize> = (0..freqs_hz.len())
        .filter(|&k| freqs_hz[k] >= lo && freqs_hz[k] <= hi)
        .collect();
    c.series.push(
        Series::new(
            "CMIF",
            GREY,
            Mark::Line,
            band.iter().map(|&k| [freqs_hz[k], r.cmif[k][0]]).collect(),
        )
        .on_secondary(),
    );
    let class = |name: &str,
                 color,
                 mark,
                 keep: &dyn Fn(&lamdyn_ema::stabilization::DiagramPole) -> bool| {
        Series::new(
            name,
            color,
            mark,
            r.diagram
                .iter()
                .filter(|p| keep(p))
                .map(|p| [p.freq_hz, p.order as f64])
                .collect(),
        )
    };
    // Mode lines first, light, so the poles stay visible on them.
    c.series.extend(mode_lines(
        r,
        0.0,
        max_order + 2.0,
        "identified mode",
        LIGHT,
    ));
    c.series.push(class("new", GREY, Mark::Dot, &|p| {
        p.stability == Stability::New
    }));
    c.series
        .push(class("stable in frequency", BLUE, Mark::Cross, &|p| {
            p.stability == Stability::Frequency
        }));
    c.series
        .push(class("+ damping", ORANGE, Mark::Circle, &|p| {
            !p.is_stable() && p.stability == Stability::FrequencyDamping
        }));
    c.series
        .push(class("stable (+ vector)", RED, Mark::Disc, &|p| {
            p.is_stable()
        }));
    c
}

/// The CMIF of `r` over the band (lines at `freqs_hz`).
pub fn cmif_chart(r: &EmaResult, freqs_hz: &[f64]) -> Chart {
    let [lo, hi] = r.band_hz;
    let band: Vec<usize> = (0..freqs_hz.len())
        .filter(|&k| freqs_hz[k] >= lo && freqs_hz[k] <= hi)
        .collect();
    let mut c = Chart::new(
        "Complex mode indicator function",
        Axis::linear("frequency (Hz)").with_range(lo, hi),
        Axis::log("singular value of the FRF matrix"),
    );
    let n_sv = r.cmif.first().map_or(0, Vec::len);
    let colors = [BLUE, ORANGE, [44, 160, 44], RED, [148, 103, 189]];
    for j in 0..n_sv {
        c.series.push(Series::new(
            &format!("sigma_{}", j + 1),
            colors[j % colors.len()],
            Mark::Line,
            band.iter().map(|&k| [freqs_hz[k], r.cmif[k][j]]).collect(),
        ));
    }
    c.series.push(Series::new(
        "peaks",
        BLACK,
        Mark::Cross,
        r.cmif_peaks.iter().map(|p| [p.freq_hz, p.value]).collect(),
    ));
    let values = band.iter().flat_map(|&k| r.cmif[k].iter().copied());
    let (vmin, vmax) = values
        .filter(|v| *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if vmin.is_finite() {
        c.series
            .extend(mode_lines(r, vmin, vmax, "identified mode", GREY));
    }
    c
}
