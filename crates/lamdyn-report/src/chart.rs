//! A small chart description rendered to SVG or PNG with plotters.
//!
//! A [`Chart`] is data only: axes (linear or logarithmic, each with an optional fixed range),
//! series of points drawn as lines or markers, on the primary or a secondary y axis. Rendering
//! maps a logarithmic axis to log10 of the values (ticks labelled with the values themselves),
//! so one drawing routine serves every combination. Text uses the embedded DejaVu Sans
//! (`assets/`, Bitstream Vera licence beside it): no system font is needed, and PNG output is
//! identical on every machine. Non-finite points, and non-positive ones on a log axis, are
//! skipped rather than drawn.

use crate::error::ReportError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::sync::Once;

/// DejaVu Sans, registered once as plotters' "sans-serif".
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

fn register_font() {
    REGISTER.call_once(|| {
        // The embedded font is valid TrueType; a failure would only lose bitmap text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Label with unit, e.g. "frequency (Hz)".
    pub label: String,
    /// Logarithmic scale.
    pub log: bool,
    /// Fixed range (in the values' units); `None`: the data's extent.
    pub range: Option<[f64; 2]>,
}

impl Axis {
    /// A linear axis fitted to the data.
    pub fn linear(label: &str) -> Self {
        Self {
            label: label.into(),
            log: false,
            range: None,
        }
    }

    /// A logarithmic axis fitted to the data.
    pub fn log(label: &str) -> Self {
        Self {
            label: label.into(),
            log: true,
            range: None,
        }
    }

    /// The same axis with a fixed range.
    pub fn with_range(mut self, lo: f64, hi: f64) -> Self {
        self.range = Some([lo, hi]);
        self
    }

    /// A value in drawing coordinates (log10 on a log axis); `None` if it cannot be drawn.
    fn map(&self, v: f64) -> Option<f64> {
        let m = if self.log {
            (v > 0.0).then(|| v.log10())?
        } else {
            v
        };
        m.is_finite().then_some(m)
    }

    /// The drawing range from the fixed range or the mapped data, padded when degenerate.
    fn extent(&self, values: impl Iterator<Item = f64>) -> (f64, f64) {
        let (lo, hi) = match self.range {
            Some([a, b]) => (self.map(a).unwrap_or(0.0), self.map(b).unwrap_or(1.0)),
            None => values
                .filter_map(|v| self.map(v))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                }),
        };
        if !(lo.is_finite() && hi.is_finite()) {
            (0.0, 1.0)
        } else if hi - lo <= f64::EPSILON * hi.abs().max(1.0) {
            (lo - 0.5, hi + 0.5)
        } else {
            (lo, hi)
        }
    }

    /// A tick's label for people: the value on a log axis (powers of ten as 1e3), plain
    /// decimals from 1e-3 to 1e6 on a linear one, scientific beyond, and 0 for a value within
    /// rounding of zero on an axis spanning `span` (never `-5.6e-17`).
    fn tick_label(&self, v: f64, span: f64) -> String {
        if self.log {
            let x = 10f64.powf(v);
            if (v - v.round()).abs() < 1e-9 {
                format!("1e{}", v.round())
            } else {
                format!("{x:.1e}")
            }
        } else if v.abs() <= 1e-9 * span.abs() {
            "0".into()
        } else if v.abs() >= 1e6 || v.abs() < 1e-3 {
            format!("{v:.1e}")
        } else {
            let s = format!("{v:.3}");
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        }
    }
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mark {
    /// Points joined by a line.
    Line,
    /// Small filled dots.
    Dot,
    /// Crosses.
    Cross,
    /// Hollow circles.
    Circle,
    /// Large filled circles.
    Disc,
    /// Larger filled circles with a dark rim: the result a chart is about, drawn to stand out.
    Highlight,
    /// A filled, translucent polygon through the points (an uncertainty band: the upper curve
    /// forwards, then the lower curve backwards).
    Band,
    /// Filled rectangles of `width` × `height` (axis units, linear axes) centred on the points:
    /// a colour map drawn one colour class per series.
    Tile {
        /// Width along x, in x units.
        width: f64,
        /// Height along y, in y units.
        height: f64,
    },
}

/// One series.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// RGB colour.
    pub color: [u8; 3],
    /// How it is drawn.
    pub mark: Mark,
    /// On the secondary y axis.
    pub secondary: bool,
    /// Whether the series sets the y axis's extent (default true). An uncertainty band that
    /// can be far wider than the estimates is drawn without scaling the axis, and clipped to it
    /// (its legend entry then says so).
    pub scales_axis: bool,
    /// (x, y) points in the axes' units.
    pub points: Vec<[f64; 2]>,
}

impl Series {
    /// A series on the primary axis.
    pub fn new(name: &str, color: [u8; 3], mark: Mark, points: Vec<[f64; 2]>) -> Self {
        Self {
            name: name.into(),
            color,
            mark,
            secondary: false,
            scales_axis: true,
            points,
        }
    }

    /// The same series, drawn within the axis the other series set (clipped to it).
    pub fn not_scaling(mut self) -> Self {
        self.scales_axis = false;
        self
    }

    /// The same series on the secondary y axis.
    pub fn on_secondary(mut self) -> Self {
        self.secondary = true;
        self
    }
}

/// A chart: title, axes and series.
#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    /// Title above the plot.
    pub title: String,
    /// The x axis.
    pub x: Axis,
    /// The primary y axis (left).
    pub y: Axis,
    /// The secondary y axis (right), for series marked `secondary`.
    pub y2: Option<Axis>,
    /// The series, drawn in order.
    pub series: Vec<Series>,
    /// Size in pixels (PNG) or user units (SVG).
    pub size: (u32, u32),
}

impl Chart {
    /// An empty chart of 1000 × 600.
    pub fn new(title: &str, x: Axis, y: Axis) -> Self {
        Self {
            title: title.into(),
            x,
            y,
            y2: None,
            series: vec![],
            size: (1000, 600),
        }
    }

    /// The chart as an SVG document.
    ///
    /// # Errors
    /// [`ReportError::Draw`] if plotters fails.
    pub fn render_svg(&self) -> Result<String, ReportError> {
        let mut text = String::new();
        {
            let root = SVGBackend::with_string(&mut text, self.size).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(draw_error)?;
        }
        Ok(text)
    }

    /// The chart as a PNG file's bytes.
    ///
    /// # Errors
    /// [`ReportError::Draw`] if plotters fails, [`ReportError::Png`] if encoding does.
    pub fn render_png(&self) -> Result<Vec<u8>, ReportError> {
        let (w, h) = self.size;
        let mut rgb = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, self.size).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(draw_error)?;
        }
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc
            .write_header()
            .map_err(|e| ReportError::Png(e.to_string()))?;
        writer
            .write_image_data(&rgb)
            .map_err(|e| ReportError::Png(e.to_string()))?;
        writer
            .finish()
            .map_err(|e| ReportError::Png(e.to_string()))?;
        Ok(out)
    }

    fn mapped(&self, s: &Series) -> Vec<(f64, f64)> {
        let y = if s.secondary {
            self.y2.as_ref().unwrap_or(&self.y)
        } else {
            &self.y
        };
        s.points
            .iter()
            .filter_map(|p| Some((self.x.map(p[0])?, y.map(p[1])?)))
            .collect()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), ReportError> {
        // Both backends lay text out with the registered font.
        register_font();
        root.fill(&WHITE).map_err(draw_error)?;
        let any_scaling = self.series.iter().any(|s| s.scales_axis);
        let all = move |secondary: bool, pick: fn(&[f64; 2]) -> f64| {
            self.series
                .iter()
                .filter(move |s| s.secondary == secondary && (s.scales_axis || !any_scaling))
                .flat_map(move |s| s.points.iter().map(pick))
        };
        let xr = self.x.extent(
            self.series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p[0])),
        );
        let yr = self.with_headroom(self.y.extent(all(false, |p| p[1])));
        let mut builder = ChartBuilder::on(root);
        builder
            .caption(&self.title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70);
        if self.y2.is_some() {
            builder.right_y_label_area_size(70);
        }
        // The secondary coordinates take over the right label area: set them before the
        // primary mesh is drawn so the primary labels stay on the left only.
        let y2r = self
            .y2
            .as_ref()
            .map_or(yr, |y2| y2.extent(all(true, |p| p[1])));
        let mut chart = builder
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(draw_error)?
            .set_secondary_coord(xr.0..xr.1, y2r.0..y2r.1);
        let (xa, ya) = (&self.x, &self.y);
        chart
            .configure_mesh()
            .x_desc(xa.label.as_str())
            .y_desc(ya.label.as_str())
            .x_label_formatter(&|v| xa.tick_label(*v, xr.1 - xr.0))
            .y_label_formatter(&|v| ya.tick_label(*v, yr.1 - yr.0))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(draw_error)?;
        if let Some(y2) = &self.y2 {
            chart
                .configure_secondary_axes()
                .y_desc(y2.label.as_str())
                .y_label_formatter(&|v| y2.tick_label(*v, y2r.1 - y2r.0))
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 16))
                .draw()
                .map_err(draw_error)?;
        }
        for s in &self.series {
            let range = if s.secondary { y2r } else { yr };
            let (pts, clipped) = clip(self.mapped(s), range, s.mark);
            let name = if clipped && !s.name.is_empty() {
                format!("{} (clipped at the axis)", s.name)
            } else {
                s.name.clone()
            };
            let color = RGBColor(s.color[0], s.color[1], s.color[2]);
            // The legend draws each mark as the plot does: a line for a curve, a filled
            // swatch for a band, the marker's own shape and size for points.
            macro_rules! put {
                ($series:expr, $legend:expr) => {{
                    let drawn = if s.secondary {
                        chart.draw_secondary_series($series)
                    } else {
                        chart.draw_series($series)
                    }
                    .map_err(draw_error)?;
                    if !name.is_empty() {
                        drawn.label(name.as_str()).legend($legend);
                    }
                }};
            }
            let at = |(x, y): (i32, i32)| EmptyElement::at((x + 10, y));
            match s.mark {
                Mark::Line => put!(
                    LineSeries::new(pts, color.stroke_width(2)),
                    move |(x, y)| PathElement::new(
                        vec![(x, y), (x + 20, y)],
                        color.stroke_width(2)
                    )
                ),
                Mark::Dot => put!(
                    pts.iter().map(|p| Circle::new(*p, 2, color.filled())),
                    move |p| at(p) + Circle::new((0, 0), 2, color.filled())
                ),
                Mark::Disc => put!(
                    pts.iter().map(|p| Circle::new(*p, 4, color.filled())),
                    move |p| at(p) + Circle::new((0, 0), 4, color.filled())
                ),
                Mark::Circle => put!(
                    pts.iter()
                        .map(|p| Circle::new(*p, 4, color.stroke_width(1))),
                    move |p| at(p) + Circle::new((0, 0), 4, color.stroke_width(1))
                ),
                Mark::Cross => put!(
                    pts.iter().map(|p| Cross::new(*p, 4, color.stroke_width(1))),
                    move |p| at(p) + Cross::new((0, 0), 4, color.stroke_width(1))
                ),
                Mark::Highlight => {
                    put!(
                        pts.iter().map(|p| Circle::new(*p, 7, color.filled())),
                        move |p| at(p)
                            + Circle::new((0, 0), 6, color.filled())
                            + Circle::new((0, 0), 6, BLACK.stroke_width(1))
                    );
                    chart
                        .draw_series(
                            pts.iter()
                                .map(|p| Circle::new(*p, 7, BLACK.stroke_width(1))),
                        )
                        .map_err(draw_error)?;
                }
                Mark::Band => {
                    // A light fill and a thin rim of the band's colour, so that two
                    // overlapping bands stay apart.
                    put!(
                        std::iter::once(Polygon::new(pts.clone(), color.mix(0.15).filled())),
                        move |(x, y)| EmptyElement::at((x, y))
                            + Rectangle::new([(0, -6), (20, 6)], color.mix(0.15).filled())
                            + Rectangle::new([(0, -6), (20, 6)], color.stroke_width(1))
                    );
                    let mut rim = pts.clone();
                    rim.extend(pts.first().copied());
                    chart
                        .draw_series(std::iter::once(PathElement::new(
                            rim,
                            color.stroke_width(1),
                        )))
                        .map_err(draw_error)?;
                }
                Mark::Tile { width, height } => put!(
                    pts.iter().map(|&(x, y)| {
                        let (hw, hh) = (width / 2.0, height / 2.0);
                        Rectangle::new([(x - hw, y - hh), (x + hw, y + hh)], color.filled())
                    }),
                    move |(x, y)| Rectangle::new([(x, y - 6), (x + 20, y + 6)], color.filled())
                ),
            };
        }
        if self.series.iter().any(|s| !s.name.is_empty()) {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 13))
                .position(SeriesLabelPosition::UpperLeft)
                .draw()
                .map_err(draw_error)?;
        }
        Ok(())
    }
}

impl Chart {
    /// The y range with room above the data for the legend (upper left), so that it does not
    /// cover them: about one legend line in twenty of the plot's height per entry.
    fn with_headroom(&self, (lo, hi): (f64, f64)) -> (f64, f64) {
        let entries = self.series.iter().filter(|s| !s.name.is_empty()).count();
        let map = self
            .series
            .iter()
            .any(|s| matches!(s.mark, Mark::Tile { .. }));
        if entries == 0 || map {
            return (lo, hi);
        }
        let pad = 0.04 * (hi - lo);
        let head = (0.06 + 0.055 * entries as f64).min(0.6);
        (lo - pad, hi + (hi - lo) * head / (1.0 - head))
    }
}

/// Points of a series within the y range `(lo, hi)` (drawing coordinates): a band or a line is
/// clamped to it, markers outside it are left out; `true` when anything was outside.
fn clip(pts: Vec<(f64, f64)>, (lo, hi): (f64, f64), mark: Mark) -> (Vec<(f64, f64)>, bool) {
    let outside = pts.iter().any(|p| p.1 < lo || p.1 > hi);
    if !outside {
        return (pts, false);
    }
    let kept = match mark {
        Mark::Band | Mark::Line => pts.into_iter().map(|(x, y)| (x, y.clamp(lo, hi))).collect(),
        _ => pts.into_iter().filter(|p| p.1 >= lo && p.1 <= hi).collect(),
    };
    (kept, true)
}

fn draw_error<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> ReportError {
    ReportError::Draw(e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ticks read as people write them: zero as 0 even where the axis computes -5.6e-17.
    #[test]
    fn ticks_are_written_for_people() {
        let lin = Axis::linear("x");
        assert_eq!(lin.tick_label(-5.6e-17, 2.0), "0");
        assert_eq!(lin.tick_label(0.25, 2.0), "0.25");
        assert_eq!(lin.tick_label(12000.0, 2e4), "12000");
        assert_eq!(lin.tick_label(2.5e6, 1e7), "2.5e6");
        assert_eq!(lin.tick_label(2e-4, 1e-3), "2.0e-4");
        assert_eq!(Axis::log("y").tick_label(3.0, 5.0), "1e3");
    }

    /// Each mark has its own legend glyph: a line, a swatch, the marker's shape and size;
    /// checked on the SVG.
    #[test]
    fn legend_glyphs_differ_by_mark() {
        let glyph = |mark: Mark| {
            let mut c = Chart::new("", Axis::linear("x"), Axis::linear("y"));
            let pts = vec![[1.0, 1.0], [2.0, 2.0], [3.0, 1.5]];
            let mut band = pts.clone();
            band.extend(pts.iter().rev().map(|p| [p[0], p[1] - 0.5]));
            let points = if mark == Mark::Band { band } else { pts };
            c.series
                .push(Series::new("entry", [10, 20, 30], mark, points));
            let svg = c.render_svg().unwrap();
            // The legend's glyph follows its text, at the end of the document.
            let text = svg.rfind("entry\n</text>").expect("the legend's text");
            let (start, end) = (text + "entry\n</text>".len(), svg.rfind("</svg>").unwrap());
            // Element names and their size attributes, positions dropped.
            svg[start..end]
                .split('<')
                .filter(|e| !e.trim().is_empty())
                .map(|e| {
                    let name = e.split_whitespace().next().unwrap_or("").to_string();
                    let keep = ["r=", "opacity=", "stroke-width=", "fill="];
                    let attrs: Vec<&str> = e
                        .split_whitespace()
                        .filter(|a| keep.iter().any(|k| a.starts_with(k)))
                        .collect();
                    format!("{name} {}", attrs.join(" "))
                })
                .collect::<Vec<_>>()
        };
        let marks = [
            Mark::Line,
            Mark::Dot,
            Mark::Disc,
            Mark::Circle,
            Mark::Cross,
            Mark::Highlight,
            Mark::Band,
        ];
        let glyphs: Vec<_> = marks.iter().map(|&m| glyph(m)).collect();
        for (i, g) in glyphs.iter().enumerate() {
            assert!(!g.is_empty(), "{:?} draws no legend glyph", marks[i]);
            for j in 0..i {
                assert_ne!(g, &glyphs[j], "{:?} and {:?}", marks[j], marks[i]);
            }
        }
    }

    fn sample() -> Chart {
        let mut c = Chart::new("test", Axis::linear("f (Hz)"), Axis::log("|H|"));
        c.y2 = Some(Axis::linear("order"));
        c.series.push(Series::new(
            "curve",
            [0, 0, 200],
            Mark::Line,
            (1..100).map(|k| [k as f64, 1.0 / k as f64]).collect(),
        ));
        c.series.push(
            Series::new(
                "poles",
                [200, 0, 0],
                Mark::Disc,
                vec![[10.0, 4.0], [20.0, 6.0]],
            )
            .on_secondary(),
        );
        // Points that cannot be drawn are skipped: NaN, and zero on the log axis.
        c.series.push(Series::new(
            "bad",
            [0, 0, 0],
            Mark::Cross,
            vec![[f64::NAN, 1.0], [3.0, 0.0]],
        ));
        c
    }

    #[test]
    fn svg_holds_the_title_labels_and_one_element_per_marker() {
        let svg = sample().render_svg().unwrap();
        assert!(svg.starts_with("<svg"));
        for text in ["test", "f (Hz)", "|H|", "order", "curve", "poles"] {
            assert!(svg.contains(text), "{text} missing");
        }
        // Two discs plus the legend's marker for "poles" and "curve" (and "bad").
        assert!(svg.matches("<circle").count() >= 2);
        // The log axis labels decades.
        assert!(svg.contains("1e-1") || svg.contains("1e0"), "{svg}");
    }

    #[test]
    fn png_is_a_png_of_the_chart_size_with_text_drawn() {
        let c = sample();
        let png = c.render_png().unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        let decoder = png::Decoder::new(std::io::Cursor::new(&png));
        let reader = decoder.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), c.size);
        // With the embedded font the title is rendered: the caption strip is not all white.
        let mut r = png::Decoder::new(std::io::Cursor::new(&png))
            .read_info()
            .unwrap();
        let mut buf = vec![0; r.output_buffer_size().unwrap()];
        r.next_frame(&mut buf).unwrap();
        let row_bytes = (c.size.0 * 3) as usize;
        let caption = &buf[..row_bytes * 35];
        assert!(
            caption.iter().any(|b| *b < 128),
            "no text in the caption strip"
        );
    }

    /// A band far wider than the estimates (eta bands to 6 for values 0.3-0.7)
    /// set the axis; now the estimates set it, the band is clipped and its legend says so.
    #[test]
    fn bands_do_not_set_the_axis_and_say_when_clipped() {
        let mut c = Chart::new("eta", Axis::linear("f (Hz)"), Axis::linear("eta"));
        let xs = [10.0, 20.0, 30.0];
        let mut band: Vec<[f64; 2]> = xs.iter().map(|x| [*x, 6.0]).collect();
        band.extend(xs.iter().rev().map(|x| [*x, 0.01]));
        c.series
            .push(Series::new("95 % band", [0, 0, 200], Mark::Band, band).not_scaling());
        c.series.push(Series::new(
            "estimate",
            [200, 0, 0],
            Mark::Highlight,
            vec![[10.0, 0.3], [20.0, 0.5], [30.0, 0.7]],
        ));
        let svg = c.render_svg().unwrap();
        assert!(
            svg.contains("95 % band (clipped at the axis)"),
            "{svg:.200}"
        );
        // The axis runs over the estimates with room for the legend, far below 6.
        let ticks: Vec<&str> = svg
            .split("</text>")
            .filter_map(|t| t.rsplit('>').next())
            .collect();
        assert!(
            ticks.iter().any(|t| t.trim() == "0.5" || t.trim() == "0.6"),
            "{ticks:?}"
        );
        assert!(
            !ticks
                .iter()
                .any(|t| ["2", "4", "5", "6"].contains(&t.trim())),
            "{ticks:?}"
        );
    }
}
