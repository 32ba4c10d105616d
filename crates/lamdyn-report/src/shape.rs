//! Mode shapes as filled contour maps over the plan of the part.
//!
//! The measured shape is known at the sensors only. It is spread over a regular grid by
//! inverse-distance weighting (Shepard's method, weights 1/d², exact at the sensors), scaled by
//! its largest magnitude and cut into an odd number of equal classes between −1 and +1, each
//! drawn in one colour of a blue–white–red scale (white: the nodal lines). The sensors are
//! drawn as dots on top, so the reader sees where the map is measured and where it is
//! interpolated.

use crate::chart::{Axis, Chart, Mark, Series};

/// Grid cells along the longer side of the plan.
const CELLS: usize = 48;

/// Shepard interpolation of `values` at `points` to (x, y): Σ wᵢvᵢ / Σ wᵢ, wᵢ = 1/dᵢ².
fn shepard(points: &[[f64; 2]], values: &[f64], x: f64, y: f64) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (p, v) in points.iter().zip(values) {
        let d2 = (p[0] - x).powi(2) + (p[1] - y).powi(2);
        if d2 < 1e-24 {
            return *v;
        }
        num += v / d2;
        den += 1.0 / d2;
    }
    num / den
}

/// Colour of class `k` of `n` (odd) from blue (−1) through white (0) to red (+1).
fn class_color(k: usize, n: usize) -> [u8; 3] {
    let t = 2.0 * k as f64 / (n - 1) as f64 - 1.0;
    let mix = |a: f64, b: f64, s: f64| (a + (b - a) * s).round() as u8;
    if t < 0.0 {
        let s = -t;
        [
            mix(255.0, 33.0, s),
            mix(255.0, 102.0, s),
            mix(255.0, 172.0, s),
        ]
    } else {
        [
            mix(255.0, 178.0, t),
            mix(255.0, 24.0, t),
            mix(255.0, 43.0, t),
        ]
    }
}

/// A filled contour map of a real mode shape measured at `points` (x, y in m), `levels`
/// classes (made odd, at least 3). Non-finite values are left out.
pub fn shape_map(title: &str, points: &[[f64; 2]], values: &[f64], levels: usize) -> Chart {
    let n = (levels.max(3) / 2) * 2 + 1;
    let (pts, vals): (Vec<[f64; 2]>, Vec<f64>) = points
        .iter()
        .zip(values)
        .filter(|(p, v)| v.is_finite() && p.iter().all(|c| c.is_finite()))
        .map(|(p, v)| (*p, *v))
        .unzip();
    let bound = |k: usize| {
        pts.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p[k]), b.max(p[k]))
            })
    };
    let ((x0, x1), (y0, y1)) = (bound(0), bound(1));
    let mut chart = Chart::new(title, Axis::linear("x (m)"), Axis::linear("y (m)"));
    chart.size = (640, 600);
    if pts.is_empty() || !(x1 > x0 && y1 > y0) {
        return chart;
    }
    let scale = vals.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let h = (x1 - x0).max(y1 - y0) / CELLS as f64;
    let (nx, ny) = (
        ((x1 - x0) / h).ceil() as usize,
        ((y1 - y0) / h).ceil() as usize,
    );
    let (dx, dy) = ((x1 - x0) / nx as f64, (y1 - y0) / ny as f64);
    let mut classes: Vec<Vec<[f64; 2]>> = vec![vec![]; n];
    for i in 0..nx {
        for j in 0..ny {
            let (x, y) = (x0 + (i as f64 + 0.5) * dx, y0 + (j as f64 + 0.5) * dy);
            let v = if scale > 0.0 {
                shepard(&pts, &vals, x, y) / scale
            } else {
                0.0
            };
            let k = (((v + 1.0) / 2.0 * n as f64).floor() as usize).min(n - 1);
            classes[k].push([x, y]);
        }
    }
    chart.x = chart.x.with_range(x0, x1);
    chart.y = chart.y.with_range(y0, y1);
    for (k, cells) in classes.into_iter().enumerate() {
        let lo = 2.0 * k as f64 / n as f64 - 1.0;
        let name = if k == 0 || k == n / 2 || k == n - 1 {
            format!("{lo:+.2} .. {:+.2}", lo + 2.0 / n as f64)
        } else {
            String::new()
        };
        chart.series.push(Series::new(
            &name,
            class_color(k, n),
            Mark::Tile {
                width: dx * 1.02,
                height: dy * 1.02,
            },
            cells,
        ));
    }
    chart
        .series
        .push(Series::new("sensors", [0, 0, 0], Mark::Dot, pts));
    chart
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shepard_is_exact_at_the_sensors_and_bounded_between() {
        let p = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let v = [1.0, -2.0, 0.5];
        for k in 0..3 {
            assert_eq!(shepard(&p, &v, p[k][0], p[k][1]), v[k]);
        }
        let mid = shepard(&p, &v, 0.3, 0.3);
        assert!((-2.0..=1.0).contains(&mid));
    }

    #[test]
    fn a_linear_shape_fills_every_class_and_renders() {
        let mut pts = vec![];
        let mut vals = vec![];
        for i in 0..5 {
            for j in 0..4 {
                let (x, y) = (0.2 * i as f64, 0.25 * j as f64);
                pts.push([x, y]);
                vals.push(x - 0.4);
            }
        }
        let c = shape_map("mode 1", &pts, &vals, 9);
        // 9 classes + the sensors.
        assert_eq!(c.series.len(), 10);
        let cells: usize = c.series[..9].iter().map(|s| s.points.len()).sum();
        assert!(cells > 1000);
        // The map is symmetric in x about 0.4: the outer classes are both filled.
        assert!(!c.series[0].points.is_empty() && !c.series[8].points.is_empty());
        assert_eq!(class_color(4, 9), [255, 255, 255]);
        let svg = c.render_svg().unwrap();
        assert!(svg.contains("mode 1") && svg.matches("<rect").count() > 1000);
    }
}
