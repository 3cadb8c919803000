//! Master discretisations (§5.4): the [`MasterSource`] trait a master generator implements,
//! the projection of control nodes onto the initial master (their master parameters), and
//! the built-in [`StationsMaster`].
//!
//! A master is a structured n_s × n_t grid of points with parameters s_i = i / (n_s − 1),
//! t_j = j / (n_t − 1). Between grid points it is taken bilinear:
//! B(a, b) = (1−a)(1−b) P₀₀ + a(1−b) P₁₀ + (1−a) b P₀₁ + a b P₁₁ on each cell. A linked
//! control node gets, once, the cell and local (a, b) of its closest point on the bilinear
//! initial master; its displacement is then Σ w_k (M_k(x) − M_k(x₀)) with the bilinear
//! weights w_k of that point.

use geom_db::eval::ParamSurface;
use geom_db::prelude::{Point3, Vector3};
use geom_db::{GeomDb, SurfaceId};
use serde::{Deserialize, Serialize};

use crate::modifier::Param;

/// A master discretisation: `points[j * n_s + i]` at (s_i, t_j).
#[derive(Debug, Clone, PartialEq)]
pub struct MasterGrid {
    /// Points in s (≥ 2).
    pub n_s: usize,
    /// Points in t (≥ 2).
    pub n_t: usize,
    /// The points, s fastest.
    pub points: Vec<Point3>,
}

impl MasterGrid {
    /// Checks the counts and that every point is finite.
    pub fn validate(&self) -> Result<(), String> {
        if self.n_s < 2 || self.n_t < 2 {
            return Err(format!(
                "{} × {} grid, at least 2 × 2 needed",
                self.n_s, self.n_t
            ));
        }
        if self.points.len() != self.n_s * self.n_t {
            return Err(format!(
                "{} points for a {} × {} grid",
                self.points.len(),
                self.n_s,
                self.n_t
            ));
        }
        if let Some(i) = self
            .points
            .iter()
            .position(|p| !p.coords.iter().all(|c| c.is_finite()))
        {
            return Err(format!("master point {i} is not finite"));
        }
        Ok(())
    }
}

/// The error of a [`MasterSource`]: the implementing crate's own typed error (e.g.
/// `wingmaster::Error`), boxed because `param` cannot name the error types of the crates
/// above it. [`Error::MasterSource`](crate::Error::MasterSource) keeps it as its `source`;
/// a caller reaches the typed error with `downcast_ref`.
pub type MasterError = Box<dyn std::error::Error + Send + Sync + 'static>;

/// A master generator (e.g. the wing master of `wingmaster`, §6.2).
///
/// `generate(x)` returns the master for the modifier's design variables `x` (physical units,
/// in the order of [`variable_names`](Self::variable_names)); the grid size must not depend
/// on `x`. [`jacobian`](Self::jacobian) may return the exact d(master points)/dx; without
/// it, central differences are used.
pub trait MasterSource: Send + Sync {
    /// The names of the design variables, in the order `generate` takes them.
    fn variable_names(&self) -> Vec<String>;
    /// The master discretisation at `x`.
    fn generate(&self, x: &[f64]) -> Result<MasterGrid, MasterError>;
    /// d(point k)/d(x_l) as `out[k][l]`, if the generator has it.
    ///
    /// This stays dense, unlike the user-facing [`Jacobian`](crate::Jacobian): a master has a
    /// few thousand points and a handful of variables, and each variable (a spanwise law)
    /// moves nearly every point, so a sparse matrix would store the same entries plus indices.
    fn jacobian(&self, x: &[f64]) -> Option<Result<Vec<Vec<Vector3>>, MasterError>> {
        let _ = x;
        None
    }
}

/// Position of a point on the bilinear master: cell (i, j) and local (a, b) ∈ [0, 1]².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MasterLocation {
    /// Cell index in s.
    pub i: usize,
    /// Cell index in t.
    pub j: usize,
    /// Local coordinate in s.
    pub a: f64,
    /// Local coordinate in t.
    pub b: f64,
    /// Distance from the point to the master.
    pub distance: f64,
}

impl MasterLocation {
    /// Master parameters (s, t) ∈ [0, 1]².
    pub fn st(&self, g: &MasterGrid) -> (f64, f64) {
        (
            (self.i as f64 + self.a) / (g.n_s - 1) as f64,
            (self.j as f64 + self.b) / (g.n_t - 1) as f64,
        )
    }

    /// The four grid indices and bilinear weights.
    pub fn weights(&self, g: &MasterGrid) -> [(usize, f64); 4] {
        let k = self.j * g.n_s + self.i;
        let (a, b) = (self.a, self.b);
        [
            (k, (1.0 - a) * (1.0 - b)),
            (k + 1, a * (1.0 - b)),
            (k + g.n_s, (1.0 - a) * b),
            (k + g.n_s + 1, a * b),
        ]
    }
}

fn bilinear(p: &[Point3; 4], a: f64, b: f64) -> (Vector3, Vector3, Vector3, Vector3) {
    let [p00, p10, p01, p11] = p.map(|q| q.coords);
    let r = p00 * ((1.0 - a) * (1.0 - b))
        + p10 * (a * (1.0 - b))
        + p01 * ((1.0 - a) * b)
        + p11 * (a * b);
    let ra = (p10 - p00) * (1.0 - b) + (p11 - p01) * b;
    let rb = (p01 - p00) * (1.0 - a) + (p11 - p10) * a;
    let rab = p11 - p10 - p01 + p00;
    (r, ra, rb, rab)
}

/// Closest point of the segment [p, q] to x: (parameter, squared distance).
fn segment_foot(p: Vector3, q: Vector3, x: Vector3) -> (f64, f64) {
    let d = q - p;
    let l2 = d.norm_squared();
    let t = if l2 > 0.0 {
        ((x - p).dot(&d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (t, (p + d * t - x).norm_squared())
}

/// The closest point of one bilinear cell to x: (a, b, squared distance). Interior minimum
/// by Newton on ∇½|B − x|² from the centre, compared with the exact minima on the four
/// straight edges.
fn cell_foot(p: &[Point3; 4], x: Vector3) -> (f64, f64, f64) {
    let [p00, p10, p01, p11] = p.map(|q| q.coords);
    let mut best = (0.0, 0.0, f64::INFINITY);
    for (t, d2, ab) in [
        {
            let (t, d) = segment_foot(p00, p10, x);
            (t, d, 0)
        },
        {
            let (t, d) = segment_foot(p01, p11, x);
            (t, d, 1)
        },
        {
            let (t, d) = segment_foot(p00, p01, x);
            (t, d, 2)
        },
        {
            let (t, d) = segment_foot(p10, p11, x);
            (t, d, 3)
        },
    ] {
        if d2 < best.2 {
            best = match ab {
                0 => (t, 0.0, d2),
                1 => (t, 1.0, d2),
                2 => (0.0, t, d2),
                _ => (1.0, t, d2),
            };
        }
    }
    let (mut a, mut b) = (0.5, 0.5);
    for _ in 0..30 {
        let (r, ra, rb, rab) = bilinear(p, a, b);
        let e = r - x;
        let g = [ra.dot(&e), rb.dot(&e)];
        let h = [ra.dot(&ra), ra.dot(&rb) + rab.dot(&e), rb.dot(&rb)];
        let det = h[0] * h[2] - h[1] * h[1];
        if !(det > 0.0 && h[0] > 0.0) {
            break;
        }
        let da = -(h[2] * g[0] - h[1] * g[1]) / det;
        let db = -(h[0] * g[1] - h[1] * g[0]) / det;
        a += da;
        b += db;
        if !(-0.5..=1.5).contains(&a) || !(-0.5..=1.5).contains(&b) {
            break;
        }
        if da.abs() + db.abs() < 1e-15 {
            break;
        }
    }
    if (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) {
        let d2 = (bilinear(p, a, b).0 - x).norm_squared();
        if d2 < best.2 {
            best = (a, b, d2);
        }
    }
    best
}

/// Projects points onto the bilinear master `g` (closest point over all cells, cells
/// visited in order of their bounding-box distance, stopping when no closer cell can
/// exist). Deterministic; ties go to the first cell in (j, i) order.
pub fn locate_on_master(g: &MasterGrid, pts: &[Point3]) -> Vec<MasterLocation> {
    let (ns, nt) = (g.n_s, g.n_t);
    let mut cells = Vec::with_capacity((ns - 1) * (nt - 1));
    for j in 0..nt - 1 {
        for i in 0..ns - 1 {
            let k = j * ns + i;
            let c = [
                g.points[k],
                g.points[k + 1],
                g.points[k + ns],
                g.points[k + ns + 1],
            ];
            let mut lo = c[0];
            let mut hi = c[0];
            for q in &c[1..] {
                lo = lo.inf(q);
                hi = hi.sup(q);
            }
            cells.push((i, j, c, lo, hi));
        }
    }
    pts.iter()
        .map(|x| {
            let mut order: Vec<(f64, usize)> = cells
                .iter()
                .enumerate()
                .map(|(n, (_, _, _, lo, hi))| {
                    let d = (x.coords - x.coords.sup(&lo.coords).inf(&hi.coords)).norm_squared();
                    (d, n)
                })
                .collect();
            order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut best = MasterLocation {
                i: 0,
                j: 0,
                a: 0.0,
                b: 0.0,
                distance: f64::INFINITY,
            };
            let mut best2 = f64::INFINITY;
            for (lb, n) in order {
                if lb > best2 {
                    break;
                }
                let (i, j, c, _, _) = &cells[n];
                let (a, b, d2) = cell_foot(c, x.coords);
                if d2 < best2 {
                    best2 = d2;
                    best = MasterLocation {
                        i: *i,
                        j: *j,
                        a,
                        b,
                        distance: d2.sqrt(),
                    };
                }
            }
            best
        })
        .collect()
}

/// One key station of a [`StationsMaster`]: the named design variables that set its
/// deviations (absent: zero deviation).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Station {
    /// Station position t ∈ [0, 1] along the master's t direction.
    pub t: f64,
    /// Twist deviation (radians, right-handed about the master's axis).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub twist: Option<String>,
    /// Relative scale deviation σ (the section is scaled by 1 + σ about the reference line,
    /// normal to the axis).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<String>,
    /// Translation deviations x, y, z (length units).
    #[serde(default)]
    pub shift: [Option<String>; 3],
}

/// A built-in master for wing-like components: the initial master is the linked surface
/// sampled on an n_s × n_t grid (s along the section, t along the span, uniform in the
/// surface's global parameters); design variables set, at key stations t_k, a twist θ, a
/// scale σ and a shift d, linearly interpolated in t between stations (held constant
/// outside) — the paper's rule of interpolating deviations, not shapes (§6.2). A master
/// point at t moves to ref(t) + P_b R + (1 + σ) (R − P_b R) + d with R = Rot_b(θ) (M₀ −
/// ref(t)), P_b R = b (b · R) its component along the axis: the section is scaled in its
/// plane, not along the span. ref(t) is the reference line from `reference[0]` (t = 0) to
/// `reference[1]` (t = 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StationsMaster {
    /// The sampled surface.
    pub surface: SurfaceId,
    /// Which surface parameter runs along t (the span).
    pub spanwise: Param,
    /// Samples along s.
    pub n_s: usize,
    /// Samples along t.
    pub n_t: usize,
    /// Twist axis direction b.
    pub axis: Vector3,
    /// Reference line end points at t = 0 and t = 1 (twist and scale centre).
    pub reference: [Point3; 2],
    /// Key stations, t increasing.
    pub stations: Vec<Station>,
}

/// [`StationsMaster`] bound to a geometry: a [`MasterSource`].
#[derive(Debug, Clone)]
pub struct StationsSource {
    spec: StationsMaster,
    names: Vec<String>,
    base: MasterGrid,
    /// Per station: variable index of twist, scale, shift x/y/z.
    slots: Vec<[Option<usize>; 5]>,
    axis: Vector3,
}

impl StationsMaster {
    /// Binds the spec to `db` and to the modifier's variable names; errors are messages.
    pub fn bind(&self, db: &GeomDb, names: &[String]) -> Result<StationsSource, String> {
        let s = db.surfaces.get(self.surface.index()).ok_or_else(|| {
            format!(
                "{} does not exist (the model has {} surfaces)",
                self.surface,
                db.surfaces.len()
            )
        })?;
        if self.n_s < 2 || self.n_t < 2 {
            return Err(format!(
                "{} × {} samples, at least 2 × 2",
                self.n_s, self.n_t
            ));
        }
        let len = self.axis.norm();
        if !(len > 0.0 && len.is_finite()) {
            return Err("axis direction must be non-zero".into());
        }
        if self.stations.is_empty() {
            return Err("no stations".into());
        }
        for w in self.stations.windows(2) {
            if w[1].t.partial_cmp(&w[0].t) != Some(std::cmp::Ordering::Greater) {
                return Err(format!(
                    "stations must have increasing t ({} then {})",
                    w[0].t, w[1].t
                ));
            }
        }
        let find = |n: &Option<String>| -> Result<Option<usize>, String> {
            match n {
                None => Ok(None),
                Some(n) => names.iter().position(|m| m == n).map(Some).ok_or_else(|| {
                    format!("station variable '{n}' is not one of the modifier's variables")
                }),
            }
        };
        let mut slots = Vec::new();
        let mut used = vec![false; names.len()];
        for st in &self.stations {
            let sl = [
                find(&st.twist)?,
                find(&st.scale)?,
                find(&st.shift[0])?,
                find(&st.shift[1])?,
                find(&st.shift[2])?,
            ];
            for k in sl.iter().flatten() {
                used[*k] = true;
            }
            slots.push(sl);
        }
        if let Some(k) = used.iter().position(|u| !u) {
            return Err(format!(
                "variable '{}' is not used by any station",
                names[k]
            ));
        }
        let ([u0, u1], [v0, v1]) = s.domain();
        let mut points = Vec::with_capacity(self.n_s * self.n_t);
        for j in 0..self.n_t {
            let t = j as f64 / (self.n_t - 1) as f64;
            for i in 0..self.n_s {
                let sp = i as f64 / (self.n_s - 1) as f64;
                let (a, b) = match self.spanwise {
                    Param::V => (sp, t),
                    Param::U => (t, sp),
                };
                points.push(s.point(u0 + a * (u1 - u0), v0 + b * (v1 - v0)));
            }
        }
        Ok(StationsSource {
            spec: self.clone(),
            names: names.to_vec(),
            base: MasterGrid {
                n_s: self.n_s,
                n_t: self.n_t,
                points,
            },
            slots,
            axis: self.axis / len,
        })
    }
}

/// Rodrigues: (Rot_b(θ) v, d/dθ Rot_b(θ) v), right-handed about the unit vector b.
pub(crate) fn rotate(v: Vector3, b: Vector3, theta: f64) -> (Vector3, Vector3) {
    let (s, c) = theta.sin_cos();
    let bxv = b.cross(&v);
    let bb = b * b.dot(&v);
    (v * c + bxv * s + bb * (1.0 - c), -v * s + bxv * c + bb * s)
}

impl StationsSource {
    /// Station weights at t: list of (station, weight), linear between neighbours.
    fn station_weights(&self, t: f64) -> Vec<(usize, f64)> {
        let st = &self.spec.stations;
        let n = st.len();
        if t <= st[0].t {
            return vec![(0, 1.0)];
        }
        if t >= st[n - 1].t {
            return vec![(n - 1, 1.0)];
        }
        let k = st.partition_point(|s| s.t <= t).max(1) - 1;
        let w = (t - st[k].t) / (st[k + 1].t - st[k].t);
        vec![(k, 1.0 - w), (k + 1, w)]
    }

    /// Point j·n_s+i of the master and optionally its derivatives with respect to x.
    fn point(&self, k: usize, x: &[f64], ders: Option<&mut Vec<Vector3>>) -> Point3 {
        let n_s = self.base.n_s;
        let j = k / n_s;
        let t = j as f64 / (self.base.n_t - 1) as f64;
        let w = self.station_weights(t);
        let mut q = [0.0; 5]; // twist, scale, dx, dy, dz
        for &(s, ws) in &w {
            for (c, slot) in self.slots[s].iter().enumerate() {
                if let Some(v) = slot {
                    q[c] += ws * x[*v];
                }
            }
        }
        let r = self.spec.reference;
        let refp = r[0].coords + (r[1] - r[0]) * t;
        let m0 = self.base.points[k].coords;
        let (rv, drv) = rotate(m0 - refp, self.axis, q[0]);
        // the scale acts in the section's plane (normal to the axis): a section scaled at
        // one station does not move along the span, so a planar cap at the tip stays
        // planar wherever its nodes fall on the master (∂/∂θ is normal to the axis too)
        let along = self.axis * self.axis.dot(&rv);
        let across = rv - along;
        let shift = Vector3::new(q[2], q[3], q[4]);
        if let Some(d) = ders {
            d.clear();
            d.resize(x.len(), Vector3::zeros());
            for &(s, ws) in &w {
                let sl = &self.slots[s];
                if let Some(v) = sl[0] {
                    d[v] += drv * ((1.0 + q[1]) * ws);
                }
                if let Some(v) = sl[1] {
                    d[v] += across * ws;
                }
                for c in 0..3 {
                    if let Some(v) = sl[2 + c] {
                        d[v][c] += ws;
                    }
                }
            }
        }
        Point3::from(refp + along + across * (1.0 + q[1]) + shift)
    }
}

impl MasterSource for StationsSource {
    fn variable_names(&self) -> Vec<String> {
        self.names.clone()
    }

    fn generate(&self, x: &[f64]) -> Result<MasterGrid, MasterError> {
        if x.len() != self.names.len() {
            return Err(Box::new(crate::Error::VectorLength {
                expected: self.names.len(),
                found: x.len(),
            }));
        }
        Ok(MasterGrid {
            n_s: self.base.n_s,
            n_t: self.base.n_t,
            points: (0..self.base.points.len())
                .map(|k| self.point(k, x, None))
                .collect(),
        })
    }

    fn jacobian(&self, x: &[f64]) -> Option<Result<Vec<Vec<Vector3>>, MasterError>> {
        Some(Ok((0..self.base.points.len())
            .map(|k| {
                let mut d = Vec::new();
                self.point(k, x, Some(&mut d));
                d
            })
            .collect()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_foot_on_flat_cell() {
        let c = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(2.0, 1.0, 0.5),
        ];
        let (a, b, d2) = cell_foot(&c, Vector3::new(0.5, 0.25, 0.0));
        let p = bilinear(&c, a, b).0;
        // the foot is the closest point: the residual is normal to the cell
        let (_, ra, rb, _) = bilinear(&c, a, b);
        let e = p - Vector3::new(0.5, 0.25, 0.0);
        assert!(e.dot(&ra).abs() < 1e-12 && e.dot(&rb).abs() < 1e-12);
        assert!(d2 < 0.01);
        // a point beyond an edge projects onto the edge
        let (a, b, _) = cell_foot(&c, Vector3::new(1.0, -1.0, 0.0));
        assert!((a - 0.5).abs() < 1e-12 && b == 0.0);
    }

    #[test]
    fn rotate_matches_quarter_turn() {
        let (r, d) = rotate(Vector3::x(), Vector3::z(), std::f64::consts::FRAC_PI_2);
        assert!((r - Vector3::y()).norm() < 1e-15);
        assert!((d + Vector3::x()).norm() < 1e-15);
    }
}
