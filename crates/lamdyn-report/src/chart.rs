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

    fn tick_label(&self, v: f64) -> String {
        if self.log {
            let x = 10f64.powf(v);
            if (v - v.round()).abs() < 1e-9 {
                format!("1e{}", v.round())
            } else {
                format!("{x:.1e}")
            }
        } else if v.abs() >= 1e4 || (v != 0.0 && v.abs() < 1e-3) {
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
            points,
        }
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
        let all = |secondary: bool, pick: fn(&[f64; 2]) -> f64| {
            self.series
                .iter()
                .filter(move |s| s.secondary == secondary)
                .flat_map(move |s| s.points.iter().map(pick))
        };
        let xr = self.x.extent(
            self.series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p[0])),
        );
        let yr = self.y.extent(all(false, |p| p[1]));
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
            .x_label_formatter(&|v| xa.tick_label(*v))
            .y_label_formatter(&|v| ya.tick_label(*v))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(draw_error)?;
        if let Some(y2) = &self.y2 {
            chart
                .configure_secondary_axes()
                .y_desc(y2.label.as_str())
                .y_label_formatter(&|v| y2.tick_label(*v))
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 16))
                .draw()
                .map_err(draw_error)?;
        }
        for s in &self.series {
            let pts = self.mapped(s);
            let color = RGBColor(s.color[0], s.color[1], s.color[2]);
            let legend = move |(x, y): (i32, i32)| Circle::new((x + 10, y), 4, color.filled());
            macro_rules! put {
                ($series:expr) => {{
                    let drawn = if s.secondary {
                        chart.draw_secondary_series($series)
                    } else {
                        chart.draw_series($series)
                    }
                    .map_err(draw_error)?;
                    if !s.name.is_empty() {
                        drawn.label(s.name.as_str()).legend(legend);
                    }
                }};
            }
            match s.mark {
                Mark::Line => put!(LineSeries::new(pts, color.stroke_width(2))),
                Mark::Dot => put!(pts.iter().map(|p| Circle::new(*p, 2, color.filled()))),
                Mark::Disc => put!(pts.iter().map(|p| Circle::new(*p, 4, color.filled()))),
                Mark::Circle => put!(
                    pts.iter()
                        .map(|p| Circle::new(*p, 4, color.stroke_width(1)))
                ),
                Mark::Cross => put!(pts.iter().map(|p| Cross::new(*p, 4, color.stroke_width(1)))),
                Mark::Band => put!(std::iter::once(Polygon::new(
                    pts.clone(),
                    color.mix(0.25).filled()
                ))),
                Mark::Tile { width, height } => put!(pts.iter().map(|&(x, y)| {
                    let (hw, hh) = (width / 2.0, height / 2.0);
                    Rectangle::new([(x - hw, y - hh), (x + hw, y + hh)], color.filled())
                })),
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

fn draw_error<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> ReportError {
    ReportError::Draw(e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
