//! The pictures of `aeroshape run`: the cell-quality histogram before/after, and the wing's
//! planform (top view) and sections before/after a modification, drawn from the support
//! surfaces of the wing's components.

use std::path::Path;

use anyhow::{Context, Result};
use geom_db::eval::ParamSurface;
use geom_db::prelude::Point3;
use geom_db::{GeomDb, SupportSurface, SurfaceId};

use crate::plot::{Mark, PALETTE, Plot, Series, write_stack};

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

/// The surface `id` of `db`, or an error naming it.
fn surface(db: &GeomDb, id: SurfaceId) -> Result<&SupportSurface> {
    db.surfaces.get(id.index()).with_context(|| {
        format!(
            "{id} does not exist (the model has {} surfaces)",
            db.surfaces.len()
        )
    })
}

/// True when the surface's spanwise parameter is v: the one along which y varies most at
/// the centre of the domain.
fn span_is_v(s: &SupportSurface) -> bool {
    let ([u0, u1], [v0, v1]) = s.domain();
    let d = s.derivs(0.5 * (u0 + u1), 0.5 * (v0 + v1));
    (d.dv.y * (v1 - v0)).abs() >= (d.du.y * (u1 - u0)).abs()
}

/// One chordwise line of a wing surface (a line of constant spanwise parameter), sampled:
/// its leading-edge point (smallest x), trailing-edge point (largest x) and mean y.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Station {
    y: f64,
    le: Point3,
    te: Point3,
}

/// Surfaces whose extent in y is under this fraction of the wing's are left out of the
/// planform: a tip cap, whose top view is a sliver along the wing's tip line (its lines all
/// lie at about the tip's y, and taken as stations they would interleave with the wing's).
const MIN_SPAN_FRACTION: f64 = 0.05;

/// The extent in y of a surface, sampled on its parameter grid.
fn y_range(s: &SupportSurface) -> (f64, f64) {
    let ([u0, u1], [v0, v1]) = s.domain();
    let (nu, nv) = (WING_SAMPLES * s.n_u.max(1), WING_SAMPLES * s.n_v.max(1));
    let mut r = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..=nu {
        for j in 0..=nv {
            let y = s
                .point(
                    u0 + (u1 - u0) * i as f64 / nu as f64,
                    v0 + (v1 - v0) * j as f64 / nv as f64,
                )
                .y;
            if y.is_finite() {
                r = (r.0.min(y), r.1.max(y));
            }
        }
    }
    r
}

/// The chordwise lines of the wing's spanwise surfaces (all but those spanning less than
/// [`MIN_SPAN_FRACTION`] of the wing), `WING_SAMPLES` per patch along the span, each sampled
/// `WING_SAMPLES` times per patch along the chord, in increasing mean y. Lines with a
/// non-finite point are left out.
fn wing_stations(db: &GeomDb, surfaces: &[SurfaceId]) -> Result<Vec<Station>> {
    let mut spanwise = Vec::new();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &id in surfaces {
        let s = surface(db, id)?;
        let r = y_range(s);
        (lo, hi) = (lo.min(r.0), hi.max(r.1));
        spanwise.push((s, r.1 - r.0));
    }
    let mut out = Vec::new();
    for (s, extent) in spanwise {
        // A surface with no finite point has a NaN extent: left out too.
        let spans = extent.is_finite() && extent >= MIN_SPAN_FRACTION * (hi - lo);
        if !spans {
            continue;
        }
        let ([u0, u1], [v0, v1]) = s.domain();
        let by_v = span_is_v(s);
        let ((a0, a1), (c0, c1)) = if by_v {
            ((u0, u1), (v0, v1))
        } else {
            ((v0, v1), (u0, u1))
        };
        let n_along = WING_SAMPLES * if by_v { s.n_u } else { s.n_v }.max(1);
        let n_span = WING_SAMPLES * if by_v { s.n_v } else { s.n_u }.max(1);
        for j in 0..=n_span {
            let c = c0 + (c1 - c0) * j as f64 / n_span as f64;
            let line: Vec<Point3> = (0..=n_along)
                .map(|i| {
                    let a = a0 + (a1 - a0) * i as f64 / n_along as f64;
                    if by_v { s.point(a, c) } else { s.point(c, a) }
                })
                .collect();
            if line.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
                continue;
            }
            let le = *line
                .iter()
                .min_by(|p, q| p.x.total_cmp(&q.x))
                .expect("points");
            let te = *line
                .iter()
                .max_by(|p, q| p.x.total_cmp(&q.x))
                .expect("points");
            let y = line.iter().map(|p| p.y).sum::<f64>() / line.len() as f64;
            out.push(Station { y, le, te });
        }
    }
    out.sort_by(|a, b| a.y.total_cmp(&b.y));
    Ok(out)
}

/// The planform outline in the (y, x) plane, closed: the leading-edge points of the
/// stations root to tip, then their trailing-edge points tip to root, then the first point
/// again. Each edge follows its stations in span order, so the outline does not cross
/// itself while every station's leading edge lies ahead of its trailing edge.
fn planform_outline(stations: &[Station]) -> Vec<(f64, f64)> {
    if stations.is_empty() {
        return Vec::new();
    }
    let mut out: Vec<(f64, f64)> = stations.iter().map(|s| (s.le.y, s.le.x)).collect();
    out.extend(stations.iter().rev().map(|s| (s.te.y, s.te.x)));
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
        .labels("y (span)", "x (chord, downstream)")
        .equal_aspect(true)
        .y_down(true);
    p.push(
        Series::line(
            "before",
            planform_outline(&wing_stations(before, wing_surfaces)?),
        )
        .color(PALETTE[0]),
    );
    p.push(
        Series::line(
            "after",
            planform_outline(&wing_stations(after, wing_surfaces)?),
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
    let by_v = span_is_v(s);
    // `along`: the chordwise parameter (one cut point per value); `across`: the spanwise one.
    let at = |along: f64, across: f64| {
        if by_v {
            s.point(along, across)
        } else {
            s.point(across, along)
        }
    };
    let ((a0, a1), (c0, c1)) = if by_v {
        ((u0, u1), (v0, v1))
    } else {
        ((v0, v1), (u0, u1))
    };
    let n_along = WING_SAMPLES * 8 * if by_v { s.n_u } else { s.n_v }.max(1);
    let n_across = WING_SAMPLES * if by_v { s.n_v } else { s.n_u }.max(1);
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
                Ok(surface_cut(surface(db, id)?, y)
                    .iter()
                    .map(|p| (p.x, p.z))
                    .collect())
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

    fn load(path: &str) -> GeomDb {
        let text = std::fs::read_to_string(path).unwrap();
        GeomDb::from_ron_str(&text, path).unwrap()
    }

    fn wing_body() -> GeomDb {
        load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../fixtures/geom/wing_body.ron"
        ))
    }

    /// The default chain case's geometry before and after its design vector (the model
    /// update of `cargo xtask chain`, without the grid), and its wing surfaces.
    fn default_case() -> (GeomDb, GeomDb, Vec<SurfaceId>) {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/cases/default");
        let case_path = std::path::PathBuf::from(dir).join("case.ron");
        let case = aeroshape::case::Case::load(&case_path).unwrap();
        let db = load(case.geometry_path(&case_path).to_str().unwrap());
        let prep = case
            .parametrisation
            .bind(&db, &param::MasterSources::new())
            .unwrap();
        let dv = aeroshape::case::load_design_values(&case_path.with_file_name("dv.ron")).unwrap();
        let x = prep.registry().vector_from_values(&dv).unwrap();
        let pts = prep.apply(&x).unwrap();
        let opts = intersect::update::UpdateOptions::default();
        let (after, _) = intersect::update::update_model(&db, &pts, &opts).unwrap();
        let wings = crate::run::wing_surfaces(&db);
        (db, after, wings)
    }

    /// Orientation of the triangle (a, b, c): > 0 counter-clockwise.
    fn orient(a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> f64 {
        (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
    }

    /// The pairs of non-adjacent edges of a closed polyline that cross (strictly).
    fn crossings(poly: &[(f64, f64)]) -> Vec<(usize, usize)> {
        let n = poly.len() - 1; // edges; the last point repeats the first
        let mut out = Vec::new();
        for i in 0..n {
            for j in i + 2..n {
                if i == 0 && j == n - 1 {
                    continue; // adjacent through the closing point
                }
                let (a, b, c, d) = (poly[i], poly[i + 1], poly[j], poly[j + 1]);
                let (o1, o2) = (orient(a, b, c), orient(a, b, d));
                let (o3, o4) = (orient(c, d, a), orient(c, d, b));
                if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
                    out.push((i, j));
                }
            }
        }
        out
    }

    /// Distance from `p` to the segment [a, b].
    fn segment_distance(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let l2 = dx * dx + dy * dy;
        let t = if l2 > 0.0 {
            (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        ((p.0 - a.0 - t * dx).powi(2) + (p.1 - a.1 - t * dy).powi(2)).sqrt()
    }

    /// True when `p` is inside the closed polyline (even-odd rule) or within `tol` of it.
    fn inside(poly: &[(f64, f64)], p: (f64, f64), tol: f64) -> bool {
        let mut odd = false;
        for w in poly.windows(2) {
            let (a, b) = (w[0], w[1]);
            if segment_distance(p, a, b) <= tol {
                return true;
            }
            if (a.1 > p.1) != (b.1 > p.1) && p.0 < a.0 + (p.1 - a.1) * (b.0 - a.0) / (b.1 - a.1) {
                odd = !odd;
            }
        }
        odd
    }

    /// Every sampled point of the surfaces, as (y, x).
    fn top_view(db: &GeomDb, surfaces: &[SurfaceId]) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for &id in surfaces {
            let s = db.surface(id);
            let ([u0, u1], [v0, v1]) = s.domain();
            for i in 0..=40 {
                for j in 0..=40 {
                    let p = s.point(
                        u0 + (u1 - u0) * i as f64 / 40.0,
                        v0 + (v1 - v0) * j as f64 / 40.0,
                    );
                    out.push((p.y, p.x));
                }
            }
        }
        out
    }

    #[test]
    fn planform_of_the_deformed_default_wing_is_a_simple_closed_outline() {
        let (before, after, wings) = default_case();
        assert!(!wings.is_empty());
        for (label, db) in [("before", &before), ("after", &after)] {
            let stations = wing_stations(db, &wings).unwrap();
            assert!(stations.len() > 20, "{label}: {} stations", stations.len());
            let outline = planform_outline(&stations);
            assert_eq!(outline.len(), 2 * stations.len() + 1);
            assert_eq!(outline.first(), outline.last(), "{label}: not closed");
            let x = crossings(&outline);
            assert!(x.is_empty(), "{label}: edges cross: {x:?}");
            // Root to tip along the leading edge, back along the trailing edge.
            let n = stations.len();
            assert!(
                outline[..n].windows(2).all(|w| w[0].0 <= w[1].0),
                "{label}: LE order"
            );
            assert!(
                outline[n..2 * n].windows(2).all(|w| w[0].0 >= w[1].0),
                "{label}: TE order"
            );
            // The outline holds the whole wing seen from above.
            let tol = 1e-3 * db.reference_length();
            let out: Vec<_> = top_view(db, &wings)
                .into_iter()
                .filter(|&p| !inside(&outline, p, tol))
                .collect();
            assert!(
                out.is_empty(),
                "{label}: {} points outside, e.g. {:?}",
                out.len(),
                out[0]
            );
        }
    }

    #[test]
    fn a_zigzag_outline_is_caught() {
        // The check above can fail: a trapezoid whose leading edge visits its stations out
        // of order crosses itself.
        let ok = vec![(0.0, 0.0), (1.0, 0.5), (1.0, 2.2), (0.0, 2.0), (0.0, 0.0)];
        assert!(crossings(&ok).is_empty());
        let zigzag = vec![
            (0.0, 0.0),
            (0.5, 0.25),
            (0.25, 2.1),
            (1.0, 0.5),
            (1.0, 2.2),
            (0.0, 2.0),
            (0.0, 0.0),
        ];
        assert!(!crossings(&zigzag).is_empty());
        assert!(!inside(&ok, (0.5, 3.0), 1e-9) && inside(&ok, (0.5, 1.0), 1e-9));
    }

    #[test]
    fn planform_outline_of_a_trapezoid_follows_its_edges() {
        // Leading edge x = 0.5 y, trailing edge x = 2 + 0.2 y, y in [0, 3]; 301 chordwise
        // lines whose y drifts along the chord (a section rotated about a swept axis).
        let (le, te) = (|y: f64| 0.5 * y, |y: f64| 2.0 + 0.2 * y);
        let mut stations: Vec<Station> = (0..=300)
            .map(|j| {
                let y = 0.01 * j as f64;
                Station {
                    y,
                    le: Point3::new(le(y - 1e-3), y - 1e-3, 0.0),
                    te: Point3::new(te(y + 1e-3), y + 1e-3, 0.0),
                }
            })
            .collect();
        stations.reverse();
        stations.sort_by(|a, b| a.y.total_cmp(&b.y));
        let out = planform_outline(&stations);
        assert_eq!(out.len(), 2 * 301 + 1);
        assert_eq!(out.first(), out.last());
        for &(y, x) in &out[..301] {
            assert!((x - le(y)).abs() < 1e-12, "LE at y={y}: {x}");
        }
        for &(y, x) in &out[301..602] {
            assert!((x - te(y)).abs() < 1e-12, "TE at y={y}: {x}");
        }
        assert!(crossings(&out).is_empty());
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
