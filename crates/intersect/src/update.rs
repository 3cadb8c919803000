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

mod linearise;
mod refit;

pub use linearise::ModelLinearisation;

use crate::corner::{CornerOptions, solve_corner};
use crate::error::{Error, Result};
use crate::project::{ProjectOptions, SurfaceProjector};
use crate::ssi::{IntersectionSeeds, SsiOptions, update_curve_points};
use geom_db::check::{AccuracyOptions, CurveSurfacesDistance, curve_surfaces_distance};
use geom_db::eval::ParamCurve;
use geom_db::invert::{InvertOptions, SurfaceInverter};
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
    /// Largest sampled distance of a re-intersected junction (and of an updated corner) to
    /// each surface and curve that defines it, relative to the model size (default 1e-8).
    /// Above it the junction is re-fitted, and an error if the re-fit does not bring it
    /// within.
    pub junction_rel_tol: f64,
    /// How junctions are sampled (≥ 200 samples per arc by default, more where the curve
    /// turns; [`AccuracyOptions`]).
    pub accuracy: AccuracyOptions,
    /// Re-fit rounds at most (default 3); each raises the degree of the arcs above the
    /// tolerance (see [`refit_degree`]).
    pub max_refits: usize,
    /// Highest arc degree a re-fit may reach (default 10). The arcs are power-basis
    /// polynomials solved from control points at Chebyshev–Lobatto nodes (A = V⁻¹R): the
    /// round-off of that solve, measured on a smooth arc of size ~4, is 3e-11 at degree 8,
    /// 7e-10 at 10, 2e-8 at 12 and 8e-6 at 16, so a higher degree adds error instead of
    /// removing it.
    pub max_refit_degree: usize,
}

impl Default for UpdateOptions {
    fn default() -> Self {
        Self {
            rel_tol: 1e-10,
            max_initial_gap_rel: 1e-6,
            meet_rel_tol: 1e-7,
            corner_extension: 0.5,
            junction_rel_tol: 1e-8,
            accuracy: AccuracyOptions::default(),
            max_refits: 3,
            max_refit_degree: 10,
        }
    }
}

impl UpdateOptions {
    /// Measures updated junctions against their surfaces at at least `n` samples per arc
    /// (the default is 200; the measure always runs).
    pub fn with_deviation_samples(mut self, n: usize) -> Self {
        self.accuracy.min_samples_per_arc = n.max(1);
        self
    }
    /// Sets the junction tolerance relative to the model size.
    pub fn with_junction_rel_tol(mut self, t: f64) -> Self {
        self.junction_rel_tol = t;
        self
    }
    /// Sets the number of re-fit rounds (0: measure only).
    pub fn with_max_refits(mut self, n: usize) -> Self {
        self.max_refits = n;
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
    /// Largest distance from surface 1 and 2 at the samples (re-intersected junctions).
    pub deviation: Option<[f64; 2]>,
    /// Curve parameters where those largest distances occur.
    pub deviation_at: Option<[f64; 2]>,
    /// The sampled distance to both surfaces in full (max, RMS, where; per arc), after the
    /// re-fit (re-intersected junctions).
    pub accuracy: Option<CurveSurfacesDistance>,
    /// The largest sampled distance before the re-fit (re-intersected junctions).
    pub deviation_before_refit: Option<f64>,
    /// Re-fit rounds done.
    pub refits: usize,
    /// The arc degrees of the updated curve (raised by a re-fit).
    pub degrees: Vec<usize>,
}

/// The distance of an updated corner to one entity that defines it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EntityDistance {
    /// The curve or surface label.
    pub entity: String,
    /// Distance (foot of the normal).
    pub distance: f64,
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
    /// Its distance to every curve ending there and to every defining or bounded surface of
    /// those curves (updated corners).
    pub distances: Vec<EntityDistance>,
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
    /// Largest sampled distance of a re-intersected junction from its surfaces (None: no
    /// junction was re-intersected).
    pub max_deviation: Option<f64>,
    /// Largest distance of an updated corner to a curve or surface defining it.
    pub max_corner_distance: Option<f64>,
    /// The junction tolerance (model units): `junction_rel_tol × length_scale`.
    pub junction_tolerance: f64,
    /// Re-fit rounds over all junctions.
    pub refits: usize,
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
                accuracy: None,
                deviation_before_refit: None,
                refits: 0,
                degrees: Vec::new(),
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
                distances: Vec::new(),
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
        // 3b. sampled accuracy of the re-intersected junctions, re-fitted where above
        // tolerance (before the component ends, which are feet on the final curves)
        let jtol = opts.junction_rel_tol * self.scale;
        let io = InvertOptions::new(self.scale);
        let mut max_dev: Option<f64> = None;
        let mut refits_total = 0;
        for ci in 0..nc {
            let Some(cs) = &self.seeds[ci] else { continue };
            if !reports[ci].reintersected {
                continue;
            }
            let (a, b) = (cs.surfaces[0], cs.surfaces[1]);
            let (s1, s2) = (&db.surfaces[a.index()], &db.surfaces[b.index()]);
            let ia = SurfaceInverter::new(surface_label(init, a), s1, &io)?;
            let ib = SurfaceInverter::new(surface_label(init, b), s2, &io)?;
            let label = &reports[ci].label.clone();
            let curve = &mut db.curves[ci];
            let mut dist = curve_surfaces_distance(&*curve, (&ia, &ib), &opts.accuracy)?;
            reports[ci].deviation_before_refit = Some(dist.max());
            let mut refits = 0;
            while dist.max() > jtol && refits < opts.max_refits {
                let degrees: Vec<usize> = curve
                    .arcs
                    .iter()
                    .zip(&dist.arc_max)
                    .map(|(arc, m)| {
                        if *m > jtol {
                            refit_degree(arc.degree, opts.max_refit_degree)
                        } else {
                            arc.degree
                        }
                    })
                    .collect();
                if degrees.iter().zip(&curve.arcs).all(|(n, a)| *n == a.degree) {
                    break; // every arc above tolerance is at the highest degree
                }
                curve.arcs = refit::refit_arcs(label, &curve.arcs, &degrees, s1, s2, &so)?.arcs;
                refits += 1;
                dist = curve_surfaces_distance(&*curve, (&ia, &ib), &opts.accuracy)?;
            }
            if dist.max() > jtol || dist.max().is_nan() {
                let k = usize::from(dist.surfaces[1].max > dist.surfaces[0].max);
                let sid = cs.surfaces[k];
                return Err(Error::JunctionOffSurface {
                    curve: label.clone(),
                    surface: surface_label(init, sid),
                    distance: dist.surfaces[k].max,
                    at_t: dist.surfaces[k].at_t,
                    tol: jtol,
                    samples: dist.samples,
                    refits,
                });
            }
            if refits > 0 {
                renumber_control(&mut db, ci);
            }
            let r = &mut reports[ci];
            r.deviation = Some([dist.surfaces[0].max, dist.surfaces[1].max]);
            r.deviation_at = Some([dist.surfaces[0].at_t, dist.surfaces[1].at_t]);
            r.refits = refits;
            max_dev = Some(max_dev.unwrap_or(0.0f64).max(dist.max()));
            r.accuracy = Some(dist);
            refits_total += refits;
        }
        for (r, c) in reports.iter_mut().zip(&db.curves) {
            r.degrees = c.arcs.iter().map(|a| a.degree).collect();
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
        // 3c. each updated corner against the curves and surfaces that define it
        let max_corner = self.corner_distances(&db, &mut corner_reports, &io, jtol)?;
        // 4. control nodes used only by intersection curves follow the new control points
        let mut acc: Vec<(Vector3, usize)> = vec![(Vector3::zeros(), 0); db.control_nodes.len()];
        for ci in 0..nc {
            if chains[ci].is_none() {
                continue;
            }
            let c = &db.curves[ci];
            for (ids, arc) in c.control.nodes.iter().zip(&c.arcs) {
                for (id, p) in ids.iter().zip(arc.control_points()) {
                    if !self.surface_node.get(id.index()).copied().unwrap_or(false) {
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
            max_corner_distance: max_corner,
            junction_tolerance: jtol,
            refits: refits_total,
            length_scale: self.scale,
        };
        Ok((db, report))
    }
}

/// The degree a re-fit gives an arc of degree `n` that is above the junction tolerance:
/// n + max(2, n/2), at most `cap` (Chebyshev–Lobatto interpolation of the smooth
/// intersection converges geometrically with the degree, so raising it where the error is
/// large is the adaptive refinement that keeps the curve's global parameter, hence the
/// grid's frozen parameters on the curve, unchanged).
pub fn refit_degree(n: usize, cap: usize) -> usize {
    (n + (n / 2).max(2))
        .min(cap.min(geom_db::control::MAX_DEGREE))
        .max(n)
}

/// Gives the arcs of curve `ci` whose degree a re-fit raised as many control nodes as they
/// need: the arc's end nodes and old interior nodes are kept, new nodes appended at the
/// arc's control points (step 4 then sets every node of the curve).
fn renumber_control(db: &mut GeomDb, ci: usize) {
    let arcs = db.curves[ci].arcs.clone();
    let mut nodes = db.curves[ci].control.nodes.clone();
    if nodes.len() != arcs.len() {
        return; // a curve without control nodes
    }
    for (ids, arc) in nodes.iter_mut().zip(&arcs) {
        let want = arc.degree + 1;
        if ids.len() == want || ids.len() < 2 {
            continue;
        }
        let pts = arc.control_points();
        let (first, last) = (ids[0], ids[ids.len() - 1]);
        let mut interior: Vec<geom_db::ControlNodeId> = ids[1..ids.len() - 1].to_vec();
        interior.truncate(want - 2);
        while interior.len() < want - 2 {
            let k = interior.len() + 1;
            interior.push(geom_db::ControlNodeId::from_index(db.control_nodes.len()));
            db.control_nodes.push(pts[k]);
        }
        let mut v = vec![first];
        v.extend(interior);
        v.push(last);
        *ids = v;
    }
    db.curves[ci].control.nodes = nodes;
}

impl ModelBaseline {
    /// The distance of each updated corner to every curve ending there (foot of the normal
    /// on the final curve from the component's end parameter) and to every defining surface
    /// of those curves and support surface of a surface component they bound (global foot);
    /// recorded in the corner reports. An entity farther than `tol` is
    /// [`Error::CornerOffEntity`]. Returns the largest distance (None: no corner updated).
    fn corner_distances(
        &self,
        db: &GeomDb,
        reports: &mut [CornerReport],
        io: &InvertOptions,
        tol: f64,
    ) -> Result<Option<f64>> {
        let init = &self.db;
        // curve component → support surfaces of the surface components it bounds
        let mut bounded: Vec<Vec<SurfaceId>> = vec![Vec::new(); init.curve_components.len()];
        for sc in &init.surface_components {
            for oc in sc.loops.iter().flatten() {
                let v = &mut bounded[oc.comp.index()];
                if !v.contains(&sc.surface) {
                    v.push(sc.surface);
                }
            }
        }
        let mut inverters: Vec<Option<SurfaceInverter<'_, geom_db::SupportSurface>>> =
            (0..db.surfaces.len()).map(|_| None).collect();
        let mut max: Option<f64> = None;
        for (ki, rep) in reports.iter_mut().enumerate() {
            if !rep.updated {
                continue;
            }
            let kid = CornerId::from_index(ki);
            let p = db.corners[ki].point;
            let mut curves: Vec<(CurveId, f64)> = Vec::new();
            let mut surfaces: Vec<SurfaceId> = Vec::new();
            for (k, cc) in db.curve_components.iter().enumerate() {
                for (end, t) in [(cc.start, cc.t0), (cc.end, cc.t1)] {
                    if end != kid {
                        continue;
                    }
                    if !curves.iter().any(|c| c.0 == cc.curve) {
                        curves.push((cc.curve, t));
                    }
                    let def = &db.curves[cc.curve.index()].defining_surfaces;
                    for s in def.iter().chain(&bounded[k]) {
                        if !surfaces.contains(s) {
                            surfaces.push(*s);
                        }
                    }
                }
            }
            let mut out = Vec::new();
            for (c, t) in curves {
                let curve = &db.curves[c.index()];
                let n = curve.arcs.len() as f64;
                let o = geom_db::invert::foot_on_curve(curve, &p, t, 0.0, n, io.settings());
                let d = (curve.point(o.x[0]) - p)
                    .norm()
                    .min((curve.point(t) - p).norm());
                out.push(EntityDistance {
                    entity: curve_label(init, c),
                    distance: d,
                });
            }
            for s in surfaces {
                let inv = match &mut inverters[s.index()] {
                    Some(i) => i,
                    slot => slot.insert(SurfaceInverter::new(
                        surface_label(init, s),
                        &db.surfaces[s.index()],
                        io,
                    )?),
                };
                out.push(EntityDistance {
                    entity: surface_label(init, s),
                    distance: inv.nearest_indexed(&p, ki)?.distance,
                });
            }
            for e in &out {
                if e.distance > tol || e.distance.is_nan() {
                    return Err(Error::CornerOffEntity {
                        corner: corner_label(init, kid),
                        entity: e.entity.clone(),
                        distance: e.distance,
                        tol,
                    });
                }
                max = Some(max.unwrap_or(0.0f64).max(e.distance));
            }
            rep.distances = out;
        }
        Ok(max)
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
