//! Small PNG plots for the whole program (section fits, planforms, histograms): series of
//! (x, y) lines and points with a legend, a title, axis labels and an optional equal aspect
//! ratio, drawn with `plotters` and the embedded DejaVu Sans font.
//!
//! ```no_run
//! use crate::plot::{Plot, Series};
//! let mut p = Plot::new("NACA 0012").labels("x / c", "z / c").equal_aspect(true);
//! p.push(Series::line("fit", vec![(0.0, 0.0), (1.0, 0.0)]));
//! p.write_png(std::path::Path::new("fit.png")).unwrap();
//! ```

use std::path::Path;
use std::sync::Once;

use anyhow::{Context, Result};
use plotters::prelude::*;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

pub(crate) fn register_font() {
    REGISTER.call_once(|| {
        // The embedded font is valid; a failure would only mean text is not drawn.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// A polyline through the points.
    Line,
    /// A circle at every point.
    Points,
    /// A polyline with a small square at every point (e.g. a control polygon).
    LinePoints,
    /// A dashed polyline.
    Dashed,
}

/// One data series.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label (empty: no legend entry).
    pub label: String,
    /// The (x, y) points.
    pub points: Vec<(f64, f64)>,
    /// How to draw it.
    pub mark: Mark,
    /// RGB colour; `None` picks from the palette by series index.
    pub color: Option<(u8, u8, u8)>,
    /// Line width or marker size in pixels.
    pub size: u32,
}

impl Series {
    /// A line series.
    pub fn line(label: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            mark: Mark::Line,
            color: None,
            size: 2,
        }
    }

    /// A point series.
    pub fn points(label: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            mark: Mark::Points,
            color: None,
            size: 3,
        }
    }

    /// A polyline with markers (control polygons).
    pub fn polygon(label: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            mark: Mark::LinePoints,
            color: None,
            size: 1,
        }
    }

    /// Sets the drawing mark.
    pub fn mark(mut self, mark: Mark) -> Self {
        self.mark = mark;
        self
    }

    /// Sets the colour.
    pub fn color(mut self, rgb: (u8, u8, u8)) -> Self {
        self.color = Some(rgb);
        self
    }

    /// Sets the line width or marker size.
    pub fn size(mut self, px: u32) -> Self {
        self.size = px;
        self
    }
}

/// A 2-D plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// Title above the plot area.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// The series, drawn in order.
    pub series: Vec<Series>,
    /// Same scale on both axes.
    pub equal_aspect: bool,
    /// Image size in pixels.
    pub size: (u32, u32),
    /// The y axis grows downwards (a planform with the chord coordinate x down the page,
    /// leading edge on top).
    pub y_down: bool,
}

/// The colours of series without their own, by series index.
pub const PALETTE: [(u8, u8, u8); 8] = [
    (31, 119, 180),
    (214, 39, 40),
    (44, 160, 44),
    (255, 127, 14),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
];

impl Plot {
    /// An empty 1200×700 plot with a title.
    pub fn new(title: &str) -> Self {
        Self {
            title: title.into(),
            x_label: String::new(),
            y_label: String::new(),
            series: Vec::new(),
            equal_aspect: false,
            size: (1200, 700),
            y_down: false,
        }
    }

    /// Sets the axis labels.
    pub fn labels(mut self, x: &str, y: &str) -> Self {
        self.x_label = x.into();
        self.y_label = y.into();
        self
    }

    /// Same scale on both axes.
    pub fn equal_aspect(mut self, on: bool) -> Self {
        self.equal_aspect = on;
        self
    }

    /// The y axis grows downwards.
    pub fn y_down(mut self, on: bool) -> Self {
        self.y_down = on;
        self
    }

    /// Sets the image size in pixels.
    pub fn size(mut self, w: u32, h: u32) -> Self {
        self.size = (w, h);
        self
    }

    /// Adds a series.
    pub fn push(&mut self, s: Series) {
        self.series.push(s);
    }

    fn data_range(&self) -> ((f64, f64), (f64, f64)) {
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for s in &self.series {
            for &(x, y) in &s.points {
                let y = self.drawn_y(y);
                if x.is_finite() && y.is_finite() {
                    x0 = x0.min(x);
                    x1 = x1.max(x);
                    y0 = y0.min(y);
                    y1 = y1.max(y);
                }
            }
        }
        if x0 > x1 {
            return ((0.0, 1.0), (0.0, 1.0));
        }
        let pad = |a: f64, b: f64| {
            let d = (b - a).abs().max(1e-12 * (a.abs() + b.abs()).max(1.0));
            (a - 0.04 * d, b + 0.04 * d)
        };
        (pad(x0, x1), pad(y0, y1))
    }

    /// The drawn coordinate of a y value: −y when the axis grows downwards (the tick labels
    /// then show y again).
    fn drawn_y(&self, y: f64) -> f64 {
        if self.y_down { -y } else { y }
    }

    /// Draws the plot to a PNG file, atomically (temporary file in the same folder, renamed
    /// when complete).
    pub fn write_png(&self, path: &Path) -> Result<()> {
        write_stack(path, std::slice::from_ref(self))
    }

    fn draw(&self, root: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<()> {
        let (w, h) = root.dim_in_pixel();
        let ((mut x0, mut x1), (mut y0, mut y1)) = self.data_range();
        let (label_x, label_y, margin, caption) = (50u32, 80u32, 20u32, 40u32);
        if self.equal_aspect {
            let pw = (w.saturating_sub(label_y + 2 * margin)).max(1) as f64;
            let ph = (h.saturating_sub(label_x + caption + 2 * margin)).max(1) as f64;
            let sx = (x1 - x0) / pw;
            let sy = (y1 - y0) / ph;
            if sx > sy {
                let c = 0.5 * (y0 + y1);
                let half = 0.5 * sx * ph;
                (y0, y1) = (c - half, c + half);
            } else {
                let c = 0.5 * (x0 + x1);
                let half = 0.5 * sy * pw;
                (x0, x1) = (c - half, c + half);
            }
        }
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 26))
            .margin(margin)
            .x_label_area_size(label_x)
            .y_label_area_size(label_y)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let (x_span, y_span) = (x1 - x0, y1 - y0);
        let x_tick = move |v: &f64| tick_label(*v, x_span);
        let y_sign = if self.y_down { -1.0 } else { 1.0 };
        let y_tick = move |v: &f64| tick_label(y_sign * *v, y_span);
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .x_label_formatter(&x_tick)
            .y_label_formatter(&y_tick)
            .label_style(("sans-serif", 16))
            .axis_desc_style(("sans-serif", 18))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut any_label = false;
        for (k, s) in self.series.iter().enumerate() {
            let (r, g, b) = s.color.unwrap_or(PALETTE[k % PALETTE.len()]);
            let color = RGBColor(r, g, b);
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .map(|&(x, y)| (x, self.drawn_y(y)))
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .collect();
            let size = s.size;
            let anno = match s.mark {
                Mark::Line => {
                    chart.draw_series(LineSeries::new(pts.clone(), color.stroke_width(size)))
                }
                Mark::Dashed => chart.draw_series(DashedLineSeries::new(
                    pts.clone(),
                    8,
                    5,
                    color.stroke_width(size),
                )),
                Mark::Points => chart.draw_series(
                    pts.iter()
                        .map(|&p| Circle::new(p, size as i32, color.stroke_width(1))),
                ),
                Mark::LinePoints => {
                    chart
                        .draw_series(LineSeries::new(pts.clone(), color.stroke_width(size)))
                        .map_err(|e| anyhow::anyhow!("{e}"))?;
                    chart.draw_series(
                        pts.iter()
                            .map(|&p| Cross::new(p, 4 + size as i32, color.stroke_width(2))),
                    )
                }
            }
            .map_err(|e| anyhow::anyhow!("{e}"))?;
            if !s.label.is_empty() {
                any_label = true;
                let mark = s.mark;
                anno.label(s.label.clone())
                    .legend(move |(x, y)| match mark {
                        Mark::Points => {
                            Circle::new((x + 10, y), 4, color.stroke_width(1)).into_dyn()
                        }
                        Mark::Line => {
                            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                                .into_dyn()
                        }
                        Mark::Dashed => plotters::element::DashedPathElement::new(
                            vec![(x, y), (x + 22, y)],
                            7,
                            4,
                            color.stroke_width(3),
                        )
                        .into_dyn(),
                        Mark::LinePoints => {
                            Cross::new((x + 10, y), 5, color.stroke_width(2)).into_dyn()
                        }
                    });
            }
        }
        if any_label {
            chart
                .configure_series_labels()
                .label_font(("sans-serif", 16))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        Ok(())
    }
}

/// The tick label of `v` on an axis spanning `span`: as many decimals as a tick spacing of
/// about a tenth of the span needs, trailing zeros trimmed, and never "-0" (a tick at zero
/// computed as −1e-17 is "0"); an axis of counts gets whole numbers.
fn tick_label(v: f64, span: f64) -> String {
    let step = (span.abs() / 10.0).max(f64::MIN_POSITIVE);
    let decimals = (-step.log10()).ceil().clamp(0.0, 15.0) as usize;
    let mut s = format!("{v:.decimals$}");
    if s.contains('.') {
        s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    }
    if s.trim_start_matches('-').chars().all(|c| c == '0') {
        s = "0".to_string();
    }
    s
}

/// Draws several plots stacked vertically into one PNG (width: the widest plot; height: the
/// sum of the heights), atomically like [`Plot::write_png`].
pub fn write_stack(path: &Path, plots: &[Plot]) -> Result<()> {
    register_font();
    anyhow::ensure!(!plots.is_empty(), "{}: nothing to plot", path.display());
    let tmp = aeroshape::fsio::temp_beside(path)
        .with_context(|| format!("{}: cannot create a temporary file", path.display()))?;
    let w = plots.iter().map(|p| p.size.0).max().unwrap_or(800);
    let h: u32 = plots.iter().map(|p| p.size.1).sum();
    {
        let root = BitMapBackend::new(tmp.path(), (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut rest = root.clone();
        for p in plots {
            let (top, bottom) = rest.split_vertically(p.size.1);
            p.draw(&top)
                .with_context(|| format!("{}: cannot draw the plot", path.display()))?;
            rest = bottom;
        }
        root.present()
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    tmp.persist(path)
        .map_err(|e| e.error)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_have_the_decimals_of_the_spacing_and_no_negative_zero() {
        assert_eq!(tick_label(1200.0, 1300.0), "1200");
        assert_eq!(tick_label(-1e-17, 0.4), "0");
        assert_eq!(tick_label(-0.0, 1.0), "0");
        assert_eq!(tick_label(0.15, 0.35), "0.15");
        assert_eq!(tick_label(0.1, 0.35), "0.1");
        assert_eq!(tick_label(-0.00008, 2.2e-4), "-0.00008");
        assert_eq!(tick_label(2.5, 7.0), "2.5");
        assert_eq!(tick_label(3.0, 7.0), "3");
    }

    #[test]
    fn a_downward_y_axis_draws_minus_y() {
        let mut p = Plot::new("t");
        p.push(Series::line("a", vec![(0.0, 1.0), (1.0, 3.0)]));
        let (_, (y0, y1)) = p.data_range();
        assert!(y0 < 1.0 && y1 > 3.0);
        let p = p.y_down(true);
        let (_, (y0, y1)) = p.data_range();
        assert!(y0 < -3.0 && y1 > -1.0 && y1 < 0.0, "{y0} {y1}");
        assert_eq!(p.drawn_y(3.0), -3.0);
    }

    #[test]
    fn writes_a_png() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.png");
        let mut plot = Plot::new("test").labels("x", "y").equal_aspect(true);
        plot.push(Series::line(
            "sin",
            (0..50)
                .map(|i| (i as f64 / 10.0, (i as f64 / 10.0).sin()))
                .collect(),
        ));
        plot.push(Series::points("pts", vec![(0.0, 0.0), (1.0, 0.5)]));
        plot.push(Series::polygon("poly", vec![(0.0, 0.2), (2.0, 0.8)]));
        plot.write_png(&p).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
