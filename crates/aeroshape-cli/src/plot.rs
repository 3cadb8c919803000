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
use geom_db::eval::ParamSurface;
use geom_db::prelude::Point3;
use geom_db::{GeomDb, SupportSurface, SurfaceId};
use plotters::prelude::*;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

fn register_font() {
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
}

const PALETTE: [(u8, u8, u8); 8] = [
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
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
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
                .copied()
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
                        _ => PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                            .into_dyn(),
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

/// Bins for [`quality_histogram`]: the mean-ratio quality lies in (−∞, 1], inverted cells
/// (q ≤ 0) are counted in the first bin.
const QUALITY_BINS: usize = 50;

fn histogram_steps(q: &[f64]) -> Vec<(f64, f64)> {
    let mut counts = [0usize; QUALITY_BINS];
    for &x in q {
        let k = ((x.clamp(0.0, 1.0) * QUALITY_BINS as f64) as usize).min(QUALITY_BINS - 1);
        counts[k] += 1;
    }
    let w = 1.0 / QUALITY_BINS as f64;
    let mut pts = vec![(0.0, 0.0)];
    for (k, &c) in counts.iter().enumerate() {
        let h = c as f64;
        pts.push((k as f64 * w, h));
        pts.push(((k + 1) as f64 * w, h));
    }
    pts.push((1.0, 0.0));
    pts
}

/// Draws the distribution of cell quality (the mean ratio of DESIGN.md, one value per cell)
/// before and after a deformation as two step histograms of 50 bins over [0, 1]; the title
/// gets the minimum and the inverted count (q ≤ 0, counted in the first bin) of each.
pub fn quality_histogram(path: &Path, before: &[f64], after: &[f64], title: &str) -> Result<()> {
    let summary = |q: &[f64]| {
        let min = q.iter().copied().fold(f64::INFINITY, f64::min);
        let inverted = q.iter().filter(|&&x| x <= 0.0).count();
        format!("min {min:.3}, {inverted} inverted")
    };
    let mut p = Plot::new(&format!(
        "{title} — before: {}; after: {}",
        summary(before),
        summary(after)
    ))
    .labels("cell quality (mean ratio)", "cells");
    p.push(Series::line("before", histogram_steps(before)).color(PALETTE[0]));
    p.push(
        Series::line("after", histogram_steps(after))
            .color(PALETTE[1])
            .mark(Mark::Dashed),
    );
    p.write_png(path)
}

/// Samples per parameter direction and per patch when drawing wing surfaces.
const WING_SAMPLES: usize = 24;

/// Points of the surfaces sampled on a regular grid of each patch.
fn wing_samples(db: &GeomDb, surfaces: &[SurfaceId]) -> Result<Vec<Point3>> {
    let mut pts = Vec::new();
    for &id in surfaces {
        let s = db.surfaces.get(id.index()).with_context(|| {
            format!(
                "{id} does not exist (the model has {} surfaces)",
                db.surfaces.len()
            )
        })?;
        let ([u0, u1], [v0, v1]) = s.domain();
        let nu = WING_SAMPLES * s.n_u.max(1);
        let nv = WING_SAMPLES * s.n_v.max(1);
        for j in 0..=nv {
            let v = v0 + (v1 - v0) * j as f64 / nv as f64;
            for i in 0..=nu {
                let u = u0 + (u1 - u0) * i as f64 / nu as f64;
                pts.push(s.point(u, v));
            }
        }
    }
    Ok(pts)
}

/// The planform outline of sampled points: per spanwise station, the smallest and largest x
/// (leading and trailing edges), as one closed polyline in the (y, x) plane. Stations are the
/// clusters of points whose y values follow each other within 1e-6 of the span (a wing
/// sampled along its spanwise parameter lines: one cluster per line, whatever the round-off);
/// when that gives too many stations (sections not at constant y), the span is cut into
/// `BINS` equal bins instead.
fn planform_outline(pts: &[Point3]) -> Vec<(f64, f64)> {
    const BINS: usize = 60;
    const MAX_STATIONS: usize = 400;
    let mut sorted: Vec<&Point3> = pts
        .iter()
        .filter(|p| p.x.is_finite() && p.y.is_finite())
        .collect();
    sorted.sort_by(|a, b| a.y.total_cmp(&b.y));
    let (Some(first), Some(last)) = (sorted.first(), sorted.last()) else {
        return Vec::new();
    };
    let (y0, y1) = (first.y, last.y);
    if y1.partial_cmp(&y0) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    let gap = 1e-6 * (y1 - y0);
    let mut station = vec![0usize; sorted.len()];
    for k in 1..sorted.len() {
        station[k] = station[k - 1] + usize::from(sorted[k].y - sorted[k - 1].y > gap);
    }
    if station[sorted.len() - 1] + 1 > MAX_STATIONS {
        for (k, p) in sorted.iter().enumerate() {
            station[k] = (((p.y - y0) / (y1 - y0) * BINS as f64) as usize).min(BINS - 1);
        }
    }
    // (y sum, count, min x, max x) per station, in increasing y.
    let mut acc: Vec<(f64, usize, f64, f64)> = Vec::new();
    let mut index = std::collections::BTreeMap::new();
    for (p, &k) in sorted.iter().zip(&station) {
        let i = *index.entry(k).or_insert_with(|| {
            acc.push((0.0, 0, f64::INFINITY, f64::NEG_INFINITY));
            acc.len() - 1
        });
        let a = &mut acc[i];
        *a = (a.0 + p.y, a.1 + 1, a.2.min(p.x), a.3.max(p.x));
    }
    let y_of = |a: &(f64, usize, f64, f64)| a.0 / a.1 as f64;
    let mut out: Vec<(f64, f64)> = acc.iter().map(|a| (y_of(a), a.2)).collect();
    out.extend(acc.iter().rev().map(|a| (y_of(a), a.3)));
    out.push(out[0]);
    out
}

/// Draws the planform (top view: span y across, x down the chord) of the wing made of the
/// support surfaces `wing_surfaces`, before and after a modification, with equal axes.
pub fn wing_planform(
    path: &Path,
    before: &GeomDb,
    after: &GeomDb,
    wing_surfaces: &[SurfaceId],
) -> Result<()> {
    let mut p = Plot::new("Wing planform")
        .labels("y (span)", "x (chord)")
        .equal_aspect(true);
    p.push(
        Series::line(
            "before",
            planform_outline(&wing_samples(before, wing_surfaces)?),
        )
        .color(PALETTE[0]),
    );
    p.push(
        Series::line(
            "after",
            planform_outline(&wing_samples(after, wing_surfaces)?),
        )
        .color(PALETTE[1])
        .mark(Mark::Dashed),
    );
    p.write_png(path)
}

/// The section of a surface by the plane y = `y`: along the surface's spanwise parameter
/// direction (the one along which y varies most at the domain centre), the first crossing of
/// the plane on each line of the other parameter is refined by bisection; points are returned
/// in order of the other parameter.
fn surface_cut(s: &SupportSurface, y: f64) -> Vec<Point3> {
    let ([u0, u1], [v0, v1]) = s.domain();
    let (uc, vc) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
    let d = s.derivs(uc, vc);
    let span_is_v = (d.dv.y * (v1 - v0)).abs() >= (d.du.y * (u1 - u0)).abs();
    // `along`: the chordwise parameter (one cut point per value); `across`: the spanwise one.
    let at = |along: f64, across: f64| {
        if span_is_v {
            s.point(along, across)
        } else {
            s.point(across, along)
        }
    };
    let ((a0, a1), (c0, c1)) = if span_is_v {
        ((u0, u1), (v0, v1))
    } else {
        ((v0, v1), (u0, u1))
    };
    let n_along = WING_SAMPLES * 8 * if span_is_v { s.n_u } else { s.n_v }.max(1);
    let n_across = WING_SAMPLES * if span_is_v { s.n_v } else { s.n_u }.max(1);
    let mut out = Vec::new();
    for i in 0..=n_along {
        let a = a0 + (a1 - a0) * i as f64 / n_along as f64;
        let f = |c: f64| at(a, c).y - y;
        let mut prev = (c0, f(c0));
        for j in 1..=n_across {
            let c = c0 + (c1 - c0) * j as f64 / n_across as f64;
            let fc = f(c);
            if prev.1 == 0.0 || prev.1.signum() != fc.signum() {
                let (mut lo, mut hi, mut flo) = (prev.0, c, prev.1);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    let fm = f(mid);
                    if (fm <= 0.0) == (flo <= 0.0) {
                        (lo, flo) = (mid, fm);
                    } else {
                        hi = mid;
                    }
                }
                out.push(at(a, 0.5 * (lo + hi)));
                break;
            }
            prev = (c, fc);
        }
    }
    out
}

/// Draws the sections of the wing made of `wing_surfaces` by the planes y = `stations_y`,
/// before and after a modification, one panel per station (x across, z up, equal axes).
pub fn wing_sections(
    path: &Path,
    before: &GeomDb,
    after: &GeomDb,
    wing_surfaces: &[SurfaceId],
    stations_y: &[f64],
) -> Result<()> {
    anyhow::ensure!(
        !stations_y.is_empty(),
        "{}: no section station given",
        path.display()
    );
    let cut = |db: &GeomDb, y: f64| -> Result<Vec<Vec<(f64, f64)>>> {
        wing_surfaces
            .iter()
            .map(|&id| {
                let s = db.surfaces.get(id.index()).with_context(|| {
                    format!(
                        "{id} does not exist (the model has {} surfaces)",
                        db.surfaces.len()
                    )
                })?;
                Ok(surface_cut(s, y).iter().map(|p| (p.x, p.z)).collect())
            })
            .collect()
    };
    let mut plots = Vec::new();
    for &y in stations_y {
        let mut p = Plot::new(&format!("Section y = {y:.4}"))
            .labels("x", "z")
            .equal_aspect(true)
            .size(1200, 450);
        for (k, (db, label)) in [(before, "before"), (after, "after")]
            .into_iter()
            .enumerate()
        {
            for (j, pts) in cut(db, y)?.into_iter().enumerate() {
                let s = Series::line(if j == 0 { label } else { "" }, pts).color(PALETTE[k]);
                p.push(if k == 1 { s.mark(Mark::Dashed) } else { s });
            }
        }
        plots.push(p);
    }
    write_stack(path, &plots)
}

#[cfg(test)]
mod tests {
    use super::*;

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

    fn wing_body() -> GeomDb {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../fixtures/geom/wing_body.ron"
        );
        let text = std::fs::read_to_string(path).unwrap();
        GeomDb::from_ron_str(&text, path).unwrap()
    }

    #[test]
    fn planform_outline_of_a_trapezoid_follows_its_edges() {
        // Leading edge x = 0.5 y, trailing edge x = 2 + 0.2 y, y in [0, 3]; sampled on 301
        // spanwise stations whose y carries round-off (±1e-12, as a real surface gives).
        let (le, te) = (|y: f64| 0.5 * y, |y: f64| 2.0 + 0.2 * y);
        let trapezoid = |y_at: &dyn Fn(usize, usize) -> f64| {
            let mut pts = Vec::new();
            for j in 0..=300 {
                for i in 0..=20 {
                    let y = y_at(j, i);
                    let t = i as f64 / 20.0;
                    pts.push(Point3::new(le(y) + t * (te(y) - le(y)), y, 0.0));
                }
            }
            planform_outline(&pts)
        };
        let out = trapezoid(&|j, i| 0.01 * j as f64 + if i % 2 == 0 { 1e-12 } else { -1e-12 });
        assert_eq!(out.len(), 2 * 301 + 1);
        assert_eq!(out.first(), out.last());
        for &(y, x) in &out[..301] {
            assert!((x - le(y)).abs() < 1e-11, "LE at y={y}: {x}");
        }
        for &(y, x) in &out[301..602] {
            assert!((x - te(y)).abs() < 1e-11, "TE at y={y}: {x}");
        }
        // Sections not at constant y (every point its own y): 60 equal bins instead, each
        // edge within the bin's width times the edge's slope.
        let out = trapezoid(&|j, i| (0.01 * j as f64 + 1e-4 * i as f64).min(3.0));
        assert_eq!(out.len(), 2 * 60 + 1);
        let n = 60;
        for &(y, x) in &out[..n] {
            assert!(
                (x - le(y)).abs() < 0.5 * 3.0 / 60.0 + 1e-12,
                "LE at y={y}: {x}"
            );
        }
        for &(y, x) in &out[n..2 * n] {
            assert!(
                (x - te(y)).abs() < 0.2 * 3.0 / 60.0 + 1e-12,
                "TE at y={y}: {x}"
            );
        }
    }

    #[test]
    fn wing_cut_points_lie_in_the_plane_and_span_the_chord() {
        let db = wing_body();
        let wing = &db.surfaces[1];
        let y = 0.5 * (wing.point(0.0, 0.0).y + wing.point(0.0, 1.0).y);
        let cut = surface_cut(wing, y);
        assert!(cut.len() > 100, "{} points", cut.len());
        let scale = db.reference_length();
        for p in &cut {
            assert!((p.y - y).abs() < 1e-12 * scale, "{p:?} off y = {y}");
        }
        // The trailing edge (u = 0, v from root to tip) at this station, found independently
        // by bisection on v, is the section's aftmost point.
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if wing.point(0.0, mid).y < y {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let te = wing.point(0.0, lo).x;
        let x1 = cut.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max);
        assert!(
            (x1 - te).abs() < 1e-9 * scale,
            "aftmost {x1}, trailing edge {te}"
        );
    }

    #[test]
    fn pictures_are_written() {
        let db = wing_body();
        let dir = tempfile::tempdir().unwrap();
        let ids = [SurfaceId(1)];
        wing_planform(&dir.path().join("p.png"), &db, &db, &ids).unwrap();
        wing_sections(&dir.path().join("s.png"), &db, &db, &ids, &[1.0, 3.0]).unwrap();
        quality_histogram(
            &dir.path().join("q.png"),
            &[0.5, 0.7, -0.1],
            &[0.6, 0.8],
            "t",
        )
        .unwrap();
        for f in ["p.png", "s.png", "q.png"] {
            let bytes = std::fs::read(dir.path().join(f)).unwrap();
            assert_eq!(&bytes[1..4], b"PNG", "{f}");
        }
        let e = wing_planform(&dir.path().join("x.png"), &db, &db, &[SurfaceId(99)]);
        assert!(e.unwrap_err().to_string().contains("does not exist"));
    }
}
