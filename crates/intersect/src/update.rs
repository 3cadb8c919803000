//! The model update after control nodes moved (§3, Figure 5): surfaces re-solved → support
//! curves re-intersected (Eq. 12) → corners re-intersected (Eq. 13) → curve components'
//! parameter ranges.
//!
//! [`ModelBaseline::new`] does, once, what depends only on the initial model: for every
//! support curve with two defining surfaces, the parameters of its control points on both
//! surfaces (Eq. 11, [`IntersectionSeeds`]). [`ModelBaseline::update`] then takes new control
//! node positions and, in dependency order:
//!
//! 1. **Surfaces** (and curves without two defining surfaces) are re-solved from their
//!    control nodes by the database (A = V⁻¹R, Eqs. 4 and 9). A surface whose nodes did not
//!    move gets its baseline coefficients back bit for bit.
//! 2. **Intersection curves** whose defining surfaces changed are re-intersected point by
//!    point (Eq. 12, [`crate::ssi`]); the arcs through the new control points are re-solved
//!    (Eq. 4). Shared arc ends are solved once, so arcs stay C0. A curve whose surfaces did
//!    not change keeps its initial arcs.
//! 3. **Corners** touched by a changed curve are re-intersected (Eq. 13,
//!    [`crate::corner`]) from two of their curves — the pair with the most transversal
//!    tangents — starting at the old parameters; parameters may run past the curve ends by
//!    `corner_extension` because a moved curve may end just short of its new corner. An
//!    intersection curve that *ends* at a corner has that end control point set to the corner
//!    (the triple point of its surfaces and the other curve's), so curves meet exactly there;
//!    a corner inside a curve's range gives the component's new end parameter by the foot of
//!    the normal on the final curve. A corner more than the meeting tolerance away from any
//!    of its curves is an error naming the corner and the curves.
//! 4. **Curve components** get their new end parameters; control nodes used only by
//!    intersection curves are moved to the new curve control points (averaged when several
//!    curves share one), nodes used by a surface are never changed. The result is validated.
//!
//! The update is deterministic and independent of the number of threads: every parallel loop
//! maps independent items and collects in order. Zero control-node change returns the
//! initial model bit for bit (nothing is marked changed, so nothing is recomputed).

use crate::check::curve_surface_deviation;
use crate::corner::{CornerOptions, solve_corner};
use crate::error::{Error, Result};
use crate::project::{ProjectOptions, SurfaceProjector};
use crate::ssi::{IntersectionSeeds, SsiOptions, update_curve_points};
use geom_db::eval::ParamCurve;
use geom_db::prelude::{Point3, Vector3};
use geom_db::{Arc, CornerId, CurveId, GeomDb, SurfaceId};

/// Knobs of the model update.
#[derive(Debug, Clone, PartialEq)]
pub struct UpdateOptions {
    /// Tolerance of |r₁ − r₂| at curve control points (Eq. 12) relative to the model size
    /// (default 1e-10, see [`SsiOptions::rel_tol`]). Feet of the normal and corners (Eqs.
    /// 11, 13) converge to 1e-12 of the model size.
    pub rel_tol: f64,
    /// Largest allowed gap of an initial curve control point from its defining surfaces,
    /// relative (default 1e-6).
    pub max_initial_gap_rel: f64,
    /// Curves meet at a corner if their distance is at most this, relative (default 1e-7).
    pub meet_rel_tol: f64,
    /// How far (in arcs) corner parameters may run past a curve's ends (default 0.5).
    pub corner_extension: f64,
    /// Samples per arc at which updated curves are checked against both surfaces
    /// (0: no check; default 0). The check is the real accuracy between control points.
    pub deviation_samples_per_arc: usize,
}

impl Default for UpdateOptions {
    fn default() -> Self {
        Self {
            rel_tol: 1e-10,
            max_initial_gap_rel: 1e-6,
            meet_rel_tol: 1e-7,
            corner_extension: 0.5,
            deviation_samples_per_arc: 0,
        }
    }
}

impl UpdateOptions {
    /// Measures updated curves against their surfaces at `n` samples per arc.
    pub fn with_deviation_samples(mut self, n: usize) -> Self {
        self.deviation_samples_per_arc = n;
        self
    }
    /// Sets the allowed initial gap (relative).
    pub fn with_max_initial_gap_rel(mut self, g: f64) -> Self {
        self.max_initial_gap_rel = g;
        self
    }
}

/// What happened to one support curve.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CurveReport {
    /// The curve.
    pub curve: CurveId,
    /// Its label (`curve N (name)`).
    pub label: String,
    /// Re-intersected (false: its defining surfaces did not change, or it has no two
    /// defining surfaces).
    pub reintersected: bool,
    /// Newton iterations (all control points).
    pub iterations: usize,
    /// Largest |r₁ − r₂| at the control points.
    pub residual: f64,
    /// Largest control-point move.
    pub max_move: f64,
    /// Control points solved by the normal-plane fallback.
    pub fallbacks: usize,
    /// Largest distance from surface 1 and 2 at the check samples (when requested).
    pub deviation: Option<[f64; 2]>,
    /// Curve parameters where those largest distances occur.
    pub deviation_at: Option<[f64; 2]>,
}

/// What happened to one corner.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CornerReport {
    /// The corner.
    pub corner: CornerId,
    /// Re-intersected (false: none of its curves changed).
    pub updated: bool,
    /// The two curves of Eq. (13) (None: a single curve, re-evaluated).
    pub curves: Option<[CurveId; 2]>,
    /// Newton iterations.
    pub iterations: usize,
    /// Residual distance between the two curves.
    pub residual: f64,
    /// How far the corner moved.
    pub moved: f64,
}

/// The report of a model update.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct UpdateReport {
    /// Surfaces whose coefficients changed.
    pub surfaces_changed: Vec<SurfaceId>,
    /// One entry per support curve.
    pub curves: Vec<CurveReport>,
    /// One entry per corner.
    pub corners: Vec<CornerReport>,
    /// Largest curve control-point residual |r₁ − r₂|.
    pub max_curve_residual: f64,
    /// Largest corner residual distance.
    pub max_corner_residual: f64,
    /// Largest deviation of an updated curve from its surfaces at the check samples.
    pub max_deviation: Option<f64>,
    /// The length scale (model size) of the tolerances.
    pub length_scale: f64,
}

struct CurveSeeds {
    seeds: IntersectionSeeds,
    surfaces: [SurfaceId; 2],
}

/// Everything the update needs from the initial model, computed once.
pub struct ModelBaseline {
    db: GeomDb,
    scale: f64,
    seeds: Vec<Option<CurveSeeds>>,
    surface_node: Vec<bool>,
    opts: UpdateOptions,
}

/// A curve's label for messages: `curve N` or `curve N (name)`.
pub fn curve_label(db: &GeomDb, c: CurveId) -> String {
    let name = &db.curve(c).name;
    if name.is_empty() {
        c.to_string()
    } else {
        format!("{c} ({name})")
    }
}

fn surface_label(db: &GeomDb, s: SurfaceId) -> String {
    let name = &db.surface(s).name;
    if name.is_empty() {
        s.to_string()
    } else {
        format!("{s} ({name})")
    }
}

fn corner_label(db: &GeomDb, k: CornerId) -> String {
    let name = &db.corner(k).name;
    if name.is_empty() {
        k.to_string()
    } else {
        format!("{k} ({name})")
    }
}

/// The distinct control points of a curve, arc by arc, the shared end of consecutive arcs
/// once, with the curve tangent at each (from the arcs' derivatives, d/dt).
fn chained_control_points(arcs: &[Arc]) -> (Vec<Point3>, Vec<Vector3>) {
    let mut pts = Vec::new();
    let mut tan = Vec::new();
    for (a, arc) in arcs.iter().enumerate() {
        let x = geom_db::control::nodes(arc.degree);
        for (i, &u) in x.iter().enumerate() {
            if a > 0 && i == 0 {
                continue;
            }
            let d = arc.derivs(u);
            pts.push(d.point);
            tan.push(d.d1);
        }
    }
    (pts, tan)
}

/// Arcs through chained control points (inverse of [`chained_control_points`]).
fn arcs_from_chain(degrees: &[usize], pts: &[Point3]) -> Vec<Arc> {
    let mut out = Vec::with_capacity(degrees.len());
    let mut k = 0;
    for &n in degrees {
        out.push(Arc::from_control_points(&pts[k..=k + n]));
        k += n;
    }
    out
}

impl ModelBaseline {
    /// Seeds every support curve with two defining surfaces on the initial model (Eq. 11).
    pub fn new(initial: &GeomDb, opts: &UpdateOptions) -> Result<Self> {
        let scale = initial.reference_length();
        let po = ProjectOptions::default().with_length_scale(scale);
        let so = SsiOptions::default()
            .with_length_scale(scale)
            .with_max_initial_gap_rel(opts.max_initial_gap_rel);
        let projectors: Vec<SurfaceProjector<'_, geom_db::SupportSurface>> = initial
            .surfaces
            .iter()
            .enumerate()
            .map(|(i, s)| {
                SurfaceProjector::new(surface_label(initial, SurfaceId::from_index(i)), s, &po)
            })
            .collect::<Result<_>>()?;
        let mut seeds = Vec::with_capacity(initial.curves.len());
        for (ci, c) in initial.curves.iter().enumerate() {
            if c.defining_surfaces.len() != 2 || c.arcs.is_empty() {
                seeds.push(None);
                continue;
            }
            let [a, b] = [c.defining_surfaces[0], c.defining_surfaces[1]];
            let (pts, tan) = chained_control_points(&c.arcs);
            let label = curve_label(initial, CurveId::from_index(ci));
            let degrees: Vec<usize> = c.arcs.iter().map(|a| a.degree).collect();
            let s = IntersectionSeeds::new(
                label,
                &pts,
                Some(&tan),
                Some(&degrees),
                &projectors[a.index()],
                &projectors[b.index()],
                &so,
            )?;
            seeds.push(Some(CurveSeeds {
                seeds: s,
                surfaces: [a, b],
            }));
        }
        let mut surface_node = vec![false; initial.control_nodes.len()];
        for s in &initial.surfaces {
            for ids in &s.control.nodes {
                for id in ids {
                    surface_node[id.index()] = true;
                }
            }
        }
        Ok(Self {
            db: initial.clone(),
            scale,
            seeds,
            surface_node,
            opts: opts.clone(),
        })
    }

    /// The initial model.
    pub fn initial(&self) -> &GeomDb {
        &self.db
    }

    /// The updated model for control nodes at `nodes`, with the report.
    pub fn update(&self, nodes: &[Point3]) -> Result<(GeomDb, UpdateReport)> {
        let init = &self.db;
        let opts = &self.opts;
        let mut db = init.with_control_points(nodes)?;
        let surf_changed: Vec<bool> = db
            .surfaces
            .iter()
            .zip(&init.surfaces)
            .map(|(a, b)| a.patches != b.patches)
            .collect();
        let so = SsiOptions {
            length_scale: Some(self.scale),
            rel_tol: opts.rel_tol,
            ..SsiOptions::default()
        };
        // 2. curves
        let nc = db.curves.len();
        let mut curve_changed = vec![false; nc];
        let mut chains: Vec<Option<Vec<Point3>>> = vec![None; nc];
        let mut reports = Vec::with_capacity(nc);
        for ci in 0..nc {
            let id = CurveId::from_index(ci);
            let mut rep = CurveReport {
                curve: id,
                label: curve_label(init, id),
                reintersected: false,
                iterations: 0,
                residual: 0.0,
                max_move: 0.0,
                fallbacks: 0,
                deviation: None,
                deviation_at: None,
            };
            match &self.seeds[ci] {
                Some(cs)
                    if surf_changed[cs.surfaces[0].index()]
                        || surf_changed[cs.surfaces[1].index()] =>
                {
                    let s1 = &db.surfaces[cs.surfaces[0].index()];
                    let s2 = &db.surfaces[cs.surfaces[1].index()];
                    let up = update_curve_points(&cs.seeds, s1, s2, &so)?;
                    rep.reintersected = true;
                    rep.iterations = up.iterations;
                    rep.residual = up.max_residual;
                    rep.max_move = up.max_move;
                    rep.fallbacks = up.fallbacks;
                    chains[ci] = Some(up.new_points());
                    curve_changed[ci] = true;
                }
                Some(_) => {
                    // defining surfaces unchanged: the initial arcs stand
                    db.curves[ci].arcs = init.curves[ci].arcs.clone();
                }
                None => {
                    curve_changed[ci] = db.curves[ci].arcs != init.curves[ci].arcs;
                }
            }
            if let Some(ch) = &chains[ci] {
                let degrees: Vec<usize> = init.curves[ci].arcs.iter().map(|a| a.degree).collect();
                db.curves[ci].arcs = arcs_from_chain(&degrees, ch);
            }
            reports.push(rep);
        }
        // 3. corners
        let meet = opts.meet_rel_tol * self.scale;
        let tol = 1e-12 * self.scale;
        let copts = CornerOptions {
            length_scale: Some(self.scale),
            rel_tol: 1e-12,
            meet_rel_tol: opts.meet_rel_tol,
            extension: opts.corner_extension,
            ..CornerOptions::default()
        };
        // per corner: (component index, is_end, curve, t)
        let mut at_corner: Vec<Vec<(usize, bool, CurveId, f64)>> =
            vec![Vec::new(); db.corners.len()];
        for (k, cc) in init.curve_components.iter().enumerate() {
            at_corner[cc.start.index()].push((k, false, cc.curve, cc.t0));
            at_corner[cc.end.index()].push((k, true, cc.curve, cc.t1));
        }
        let mut corner_reports = Vec::with_capacity(db.corners.len());
        // snapped curve ends: (curve, at_end) → corner point
        let mut snaps: Vec<(CurveId, bool, Point3)> = Vec::new();
        // component ends to set from the final curves: (component, is_end, corner point, t0)
        let mut comp_ends: Vec<(usize, bool, CornerId, Point3, f64)> = Vec::new();
        for (ki, list) in at_corner.iter().enumerate() {
            let kid = CornerId::from_index(ki);
            let mut rep = CornerReport {
                corner: kid,
                updated: false,
                curves: None,
                iterations: 0,
                residual: 0.0,
                moved: 0.0,
            };
            let mut distinct: Vec<(CurveId, f64)> = Vec::new();
            for &(_, _, c, t) in list {
                if !distinct.iter().any(|d| d.0 == c) {
                    distinct.push((c, t));
                }
            }
            if !distinct.iter().any(|d| curve_changed[d.0.index()]) {
                corner_reports.push(rep);
                continue;
            }
            rep.updated = true;
            let old = init.corners[ki].point;
            let new_point = if distinct.len() == 1 {
                let (c, t) = distinct[0];
                db.curves[c.index()].point(t)
            } else {
                // the pair with the most transversal tangents at the old corner
                let mut best = (f64::NEG_INFINITY, 0usize, 1usize);
                for i in 0..distinct.len() {
                    for j in i + 1..distinct.len() {
                        let ta = db.curves[distinct[i].0.index()].derivs(distinct[i].1).d1;
                        let tb = db.curves[distinct[j].0.index()].derivs(distinct[j].1).d1;
                        let s = ta.normalize().cross(&tb.normalize()).norm();
                        if s > best.0 {
                            best = (s, i, j);
                        }
                    }
                }
                let (ca, ta) = distinct[best.1];
                let (cb, tb) = distinct[best.2];
                let r = solve_corner(
                    &corner_label(init, kid),
                    (&curve_label(init, ca), &db.curves[ca.index()]),
                    (&curve_label(init, cb), &db.curves[cb.index()]),
                    Some([ta, tb]),
                    &copts,
                )?;
                rep.curves = Some([ca, cb]);
                rep.iterations = r.iterations;
                rep.residual = r.distance;
                Point3::new(r.point[0], r.point[1], r.point[2])
            };
            rep.moved = (new_point - old).norm();
            db.corners[ki].point = new_point;
            for &(comp, is_end, c, t) in list {
                let n = init.curves[c.index()].arcs.len() as f64;
                let curve_end = t == 0.0 || t == n;
                if curve_end && self.seeds[c.index()].is_some() && curve_changed[c.index()] {
                    snaps.push((c, t == n, new_point));
                } else {
                    comp_ends.push((comp, is_end, kid, new_point, t));
                }
            }
            corner_reports.push(rep);
        }
        // snap intersection-curve ends to their corners and rebuild the end arcs
        for &(c, at_end, p) in &snaps {
            if let Some(ch) = chains[c.index()].as_mut() {
                if at_end {
                    *ch.last_mut().expect("curve with arcs") = p;
                } else {
                    ch[0] = p;
                }
            }
        }
        for ci in 0..nc {
            if let (Some(ch), true) = (&chains[ci], snaps.iter().any(|s| s.0.index() == ci)) {
                let degrees: Vec<usize> = init.curves[ci].arcs.iter().map(|a| a.degree).collect();
                db.curves[ci].arcs = arcs_from_chain(&degrees, ch);
            }
        }
        // component end parameters from the final curves
        for &(comp, is_end, kid, p, t) in &comp_ends {
            let c = init.curve_components[comp].curve;
            let curve = &db.curves[c.index()];
            let n = curve.arcs.len() as f64;
            if !curve_changed[c.index()] && (curve.point(t) - p).norm() <= tol {
                continue;
            }
            let settings = geom_db::newton::Settings { tol, max_iters: 50 };
            let o = geom_db::invert::foot_on_curve(curve, &p, t, 0.0, n, settings);
            let (tn, dist) = (o.x[0], (curve.point(o.x[0]) - p).norm());
            if dist.is_nan() || dist > meet {
                return Err(Error::CornerOffCurve {
                    corner: corner_label(init, kid),
                    curve: curve_label(init, c),
                    distance: dist,
                    tol: meet,
                });
            }
            let cc = &mut db.curve_components[comp];
            if is_end {
                cc.t1 = tn;
            } else {
                cc.t0 = tn;
            }
        }
        // 4. control nodes used only by intersection curves follow the new control points
        let mut acc: Vec<(Vector3, usize)> = vec![(Vector3::zeros(), 0); db.control_nodes.len()];
        for ci in 0..nc {
            if chains[ci].is_none() {
                continue;
            }
            let c = &db.curves[ci];
            for (ids, arc) in c.control.nodes.iter().zip(&c.arcs) {
                for (id, p) in ids.iter().zip(arc.control_points()) {
                    if !self.surface_node[id.index()] {
                        acc[id.index()].0 += p.coords;
                        acc[id.index()].1 += 1;
                    }
                }
            }
        }
        let mut moved_nodes = db.control_nodes.clone();
        for (i, (sum, n)) in acc.iter().enumerate() {
            if *n > 0 {
                moved_nodes[i] = Point3::from(sum / *n as f64);
            }
        }
        db.control_nodes = moved_nodes;
        // deviation between control points
        let mut max_dev = None;
        if opts.deviation_samples_per_arc > 0 {
            let po = ProjectOptions::default().with_length_scale(self.scale);
            for ci in 0..nc {
                let Some(cs) = &self.seeds[ci] else { continue };
                if !reports[ci].reintersected {
                    continue;
                }
                let (a, b) = (cs.surfaces[0], cs.surfaces[1]);
                let pa =
                    SurfaceProjector::new(surface_label(init, a), &db.surfaces[a.index()], &po)?;
                let pb =
                    SurfaceProjector::new(surface_label(init, b), &db.surfaces[b.index()], &po)?;
                let d = curve_surface_deviation(
                    &reports[ci].label,
                    &db.curves[ci],
                    &pa,
                    &pb,
                    opts.deviation_samples_per_arc,
                )?;
                reports[ci].deviation = Some(d.max_distance);
                reports[ci].deviation_at = Some(d.at_t);
                max_dev = Some(max_dev.unwrap_or(0.0f64).max(d.max()));
            }
        }
        db.validate()?;
        let report = UpdateReport {
            surfaces_changed: surf_changed
                .iter()
                .enumerate()
                .filter(|(_, c)| **c)
                .map(|(i, _)| SurfaceId::from_index(i))
                .collect(),
            max_curve_residual: reports.iter().map(|r| r.residual).fold(0.0, f64::max),
            max_corner_residual: corner_reports
                .iter()
                .map(|r| r.residual)
                .fold(0.0, f64::max),
            curves: reports,
            corners: corner_reports,
            max_deviation: max_dev,
            length_scale: self.scale,
        };
        Ok((db, report))
    }
}

/// One-shot update: seeds `initial` (Eq. 11) and updates it for control nodes at `nodes`.
/// In an optimisation loop, build a [`ModelBaseline`] once instead.
pub fn update_model(
    initial: &GeomDb,
    nodes: &[Point3],
    opts: &UpdateOptions,
) -> Result<(GeomDb, UpdateReport)> {
    ModelBaseline::new(initial, opts)?.update(nodes)
}
