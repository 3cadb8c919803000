//! Thickness at a station: the outermost intersections of the line p + t d with a part's
//! support surfaces ([`geom_db::newton::line`]), seeded from a sampling of every patch, and
//! the derivative dt = n·δr / n·d of each (the line held).

use geom_db::eval::ParamSurface;
use geom_db::linearise::ModelTangent;
use geom_db::newton::Settings;
use geom_db::newton::line::LineSurface;
use geom_db::prelude::{Point3, Vector3};
use geom_db::{GeomDb, SurfaceId, Tolerances};

/// Samples per patch side for the seeds of the line–surface Newton.
const SAMPLES: usize = 8;

/// One intersection of a station's line with a surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineHit {
    /// The surface.
    pub surface: SurfaceId,
    /// Global parameters on it.
    pub uv: [f64; 2],
    /// The line parameter (length units: the direction is a unit vector).
    pub t: f64,
}

/// A thickness measured at one station: the line and its lower and upper intersections.
#[derive(Debug, Clone, PartialEq)]
pub struct Thickness {
    /// The station.
    pub point: Point3,
    /// The unit direction.
    pub direction: Vector3,
    /// The intersection with the smallest t.
    pub lower: LineHit,
    /// The intersection with the largest t.
    pub upper: LineHit,
}

impl Thickness {
    /// The thickness t_upper − t_lower.
    pub fn value(&self) -> f64 {
        self.upper.t - self.lower.t
    }

    /// The lower and upper surface points.
    pub fn points(&self) -> [Point3; 2] {
        [
            self.point + self.direction * self.lower.t,
            self.point + self.direction * self.upper.t,
        ]
    }

    fn dt(&self, db: &GeomDb, h: &LineHit, dr: &Vector3) -> Option<f64> {
        LineSurface::new(db.surface(h.surface), self.point, self.direction)
            .dt_of(h.uv[0], h.uv[1], dr)
    }

    /// Err(the surface) where the line is tangent to the surface (or the surface singular)
    /// at an intersection: no derivative there.
    pub fn check_derivable(&self, db: &GeomDb) -> Result<(), SurfaceId> {
        for h in [&self.lower, &self.upper] {
            if self.dt(db, h, &Vector3::zeros()).is_none() {
                return Err(h.surface);
            }
        }
        Ok(())
    }

    /// d(thickness) for the model perturbation `t`: dt_upper − dt_lower.
    pub(crate) fn tangent(&self, db: &GeomDb, t: &ModelTangent) -> f64 {
        let at = |h: &LineHit| {
            let dr = t.surface_at(db, h.surface, h.uv[0], h.uv[1]).point;
            self.dt(db, h, &dr).unwrap_or(0.0)
        };
        at(&self.upper) - at(&self.lower)
    }

    /// The transpose of [`tangent`](Self::tangent): adds `bar` · d(thickness)/d(model) to
    /// the cotangent `w`.
    pub(crate) fn add_cotangent(&self, db: &GeomDb, bar: f64, w: &mut ModelTangent) {
        for (h, sign) in [(&self.upper, 1.0), (&self.lower, -1.0)] {
            let e = db.surface(h.surface).derivs(h.uv[0], h.uv[1]);
            let n = e.du.cross(&e.dv);
            let nd = n.dot(&self.direction);
            if nd != 0.0 {
                let tb = geom_db::linearise::SurfaceTangent {
                    point: n * (sign * bar / nd),
                    ..Default::default()
                };
                w.add_surface_at(db, h.surface, h.uv[0], h.uv[1], &tb);
            }
        }
    }
}

/// Why a thickness could not be measured: fewer than two intersections.
#[derive(Debug, Clone)]
pub struct LineFailure {
    /// Intersections found.
    pub hits: usize,
    /// The Newton solves that did not converge: surface and final residual.
    pub failed: Vec<(SurfaceId, f64)>,
}

/// The line through `p` along the unit `d` against triangle (a, b, c): (s, w, t) with
/// p + t d = a + s (b − a) + w (c − a), or `None` when the line is parallel to it.
fn line_triangle(p: &Point3, d: &Vector3, a: &Point3, b: &Point3, c: &Point3) -> Option<[f64; 3]> {
    let (e1, e2) = (b - a, c - a);
    let h = d.cross(&e2);
    let det = e1.dot(&h);
    if det.abs() <= 1e-14 * e1.norm() * e2.norm() {
        return None;
    }
    let q = p - a;
    let s = q.dot(&h) / det;
    let r = q.cross(&e1);
    let w = d.dot(&r) / det;
    let t = e2.dot(&r) / det;
    Some([s, w, t])
}

/// Every intersection of the line p + t d (d a unit vector) with `surfaces` (distinct to
/// 1e-7 of the model size along the line); seeds from the sampled patches, then the
/// line–surface Newton (residual 1e-10 of the model size).
pub fn line_hits(
    db: &GeomDb,
    surfaces: &[SurfaceId],
    p: &Point3,
    d: &Vector3,
) -> (Vec<LineHit>, Vec<(SurfaceId, f64)>) {
    let l = db.reference_length();
    let settings = Settings {
        tol: Tolerances::newton(l).abs,
        max_iters: 50,
    };
    let t_max = 10.0 * l + p.coords.norm();
    let same = 1e-7 * l;
    let mut hits: Vec<LineHit> = Vec::new();
    let mut failed = Vec::new();
    for &sid in surfaces {
        let surf = db.surface(sid);
        let line = LineSurface::new(surf, *p, *d);
        let n = SAMPLES;
        for pj in 0..surf.n_v {
            for pi in 0..surf.n_u {
                let at = |i: usize, j: usize| {
                    let (u, v) = (
                        pi as f64 + i as f64 / n as f64,
                        pj as f64 + j as f64 / n as f64,
                    );
                    ((u, v), surf.point(u, v))
                };
                let grid: Vec<((f64, f64), Point3)> = (0..=n)
                    .flat_map(|j| (0..=n).map(move |i| (i, j)))
                    .map(|(i, j)| at(i, j))
                    .collect();
                let g = |i: usize, j: usize| &grid[j * (n + 1) + i];
                for j in 0..n {
                    for i in 0..n {
                        let tris = [
                            [g(i, j), g(i + 1, j), g(i + 1, j + 1)],
                            [g(i, j), g(i + 1, j + 1), g(i, j + 1)],
                        ];
                        for [a, b, c] in tris {
                            let Some([s, w, t]) = line_triangle(p, d, &a.1, &b.1, &c.1) else {
                                continue;
                            };
                            let margin = 0.05;
                            if s < -margin || w < -margin || s + w > 1.0 + margin {
                                continue;
                            }
                            let u0 = a.0.0 + s * (b.0.0 - a.0.0) + w * (c.0.0 - a.0.0);
                            let v0 = a.0.1 + s * (b.0.1 - a.0.1) + w * (c.0.1 - a.0.1);
                            let o = line.solve([u0, v0, t], t_max, settings);
                            if !o.report.converged {
                                failed.push((sid, o.report.residual));
                                continue;
                            }
                            let hit = LineHit {
                                surface: sid,
                                uv: [o.x[0], o.x[1]],
                                t: o.x[2],
                            };
                            if !hits.iter().any(|h| (h.t - hit.t).abs() <= same) {
                                hits.push(hit);
                            }
                        }
                    }
                }
            }
        }
    }
    hits.sort_by(|a, b| a.t.total_cmp(&b.t));
    (hits, failed)
}

/// The thickness of the part made of `surfaces` at `p` along the unit direction `d`
/// (module doc of [`super`]).
pub fn thickness(
    db: &GeomDb,
    surfaces: &[SurfaceId],
    p: &[f64; 3],
    d: &[f64; 3],
) -> Result<Thickness, LineFailure> {
    let (p, d) = (
        Point3::new(p[0], p[1], p[2]),
        Vector3::new(d[0], d[1], d[2]),
    );
    let (hits, failed) = line_hits(db, surfaces, &p, &d);
    if hits.len() < 2 {
        return Err(LineFailure {
            hits: hits.len(),
            failed,
        });
    }
    Ok(Thickness {
        point: p,
        direction: d,
        lower: hits[0],
        upper: hits[hits.len() - 1],
    })
}
