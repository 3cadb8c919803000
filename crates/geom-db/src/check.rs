//! The check report: counts, bounding box, topology (closed / open, free and non-manifold
//! edges, orientation of shared edges) and C0 gaps between components, measured by sampling.
//!
//! Gaps measured:
//! * corner gaps: distance between a curve component's end points and its corners;
//! * patch-border gaps: distance between neighbouring patches along their common border,
//!   within each support surface, and between neighbouring arcs of each support curve;
//! * curve–surface gaps: for each curve component bounding a surface component, the largest
//!   distance from samples of the curve to the support surface (foot of the normal, Eq. 11,
//!   [`crate::invert`]: the shared safeguarded Newton started from the nearest points of a
//!   sample grid).

use std::collections::BTreeMap;

use serde::Serialize;

use crate::db::GeomDb;
use crate::eval::ParamCurve;
use crate::ids::{CurveCompId, CurveId, SurfCompId, SurfaceId};
use crate::invert::{InvertOptions, SurfaceInverter};
use crate::surface::SupportSurface;

/// Options of [`GeomDb::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckOptions {
    /// Gaps above `gap_rel × reference length` are reported as problems (default 1e-6).
    pub gap_rel: f64,
    /// Samples per curve component for the curve–surface gaps (default 33).
    pub samples: usize,
}

impl Default for CheckOptions {
    fn default() -> Self {
        Self {
            gap_rel: 1e-6,
            samples: 33,
        }
    }
}

/// Entity counts.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Counts {
    /// Corners.
    pub corners: usize,
    /// Support curves.
    pub curves: usize,
    /// Arcs over all support curves.
    pub arcs: usize,
    /// Support surfaces.
    pub surfaces: usize,
    /// Patches over all support surfaces.
    pub patches: usize,
    /// Curve components.
    pub curve_components: usize,
    /// Surface components.
    pub surface_components: usize,
    /// Control nodes.
    pub control_nodes: usize,
    /// Highest arc degree.
    pub max_curve_degree: usize,
    /// Highest patch degree (in u or v).
    pub max_surface_degree: usize,
}

/// How the surface components use the curve components (§2.1).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Topology {
    /// True when every curve component is used exactly twice with opposite orientations.
    pub closed: bool,
    /// Curve components used once (free edges: open model, e.g. a symmetry plane).
    pub free_edges: Vec<CurveCompId>,
    /// Curve components used more than twice.
    pub non_manifold: Vec<CurveCompId>,
    /// Curve components used twice in the same direction (inconsistent orientation).
    pub same_direction: Vec<CurveCompId>,
    /// Curve components no loop uses.
    pub unused: Vec<CurveCompId>,
    /// Loops (surface component, loop index) whose direction contradicts the inward normal
    /// (outer loops must run counter-clockwise seen from the inward side, holes clockwise).
    pub misoriented_loops: Vec<(SurfCompId, usize)>,
}

/// The largest gap found for one pair of entities.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gap {
    /// What was compared ("curve component 3 vs surface component 1 (surface 2)").
    pub what: String,
    /// Largest distance found (model units).
    pub max: f64,
}

/// The result of [`GeomDb::check`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckReport {
    /// Model name.
    pub name: String,
    /// Entity counts.
    pub counts: Counts,
    /// Bounding box [min, max] (zeros for an empty model).
    pub bbox: [[f64; 3]; 2],
    /// The reference length (bounding-box diagonal).
    pub reference_length: f64,
    /// Gap tolerance used (model units).
    pub gap_tolerance: f64,
    /// Topology.
    pub topology: Topology,
    /// Corner gaps, patch-border gaps and curve–surface gaps, one entry per pair.
    pub gaps: Vec<Gap>,
    /// Largest gap overall.
    pub max_gap: f64,
    /// Problems found: non-manifold or inconsistently oriented edges, gaps above tolerance.
    /// Free edges are reported in `topology`, not here.
    pub problems: Vec<String>,
}

impl CheckReport {
    /// True when no problem was found.
    pub fn is_ok(&self) -> bool {
        self.problems.is_empty()
    }
}

impl GeomDb {
    /// Checks a (validated) database: counts, bounding box, topology and C0 gaps.
    ///
    /// A database that does not pass [`validate`](GeomDb::validate) gets a report with the
    /// validation error as its only problem (and no topology or gaps), so `check` never
    /// panics.
    pub fn check(&self, opts: &CheckOptions) -> CheckReport {
        let l = self.reference_length();
        let gap_tol = opts.gap_rel * l;
        if let Err(e) = self.validate() {
            return CheckReport {
                name: self.name.clone(),
                counts: self.counts(),
                bbox: self.bbox_array(),
                reference_length: l,
                gap_tolerance: gap_tol,
                topology: Topology {
                    closed: false,
                    free_edges: Vec::new(),
                    non_manifold: Vec::new(),
                    same_direction: Vec::new(),
                    unused: Vec::new(),
                    misoriented_loops: Vec::new(),
                },
                gaps: Vec::new(),
                max_gap: f64::NAN,
                problems: vec![e.to_string()],
            };
        }
        let counts = self.counts();
        let bbox = self.bbox_array();
        let mut topology = self.topology_report();
        topology.misoriented_loops = self.misoriented_loops(gap_tol);
        let mut problems = Vec::new();
        for (c, l) in &topology.misoriented_loops {
            problems.push(format!(
                "{c} loop {l} runs against the convention for its inward normal (outer loops counter-clockwise seen from the inward side, holes clockwise)"
            ));
        }
        for c in &topology.non_manifold {
            problems.push(format!("{c} is used by more than two surface components"));
        }
        for c in &topology.same_direction {
            problems.push(format!(
                "{c} is traversed in the same direction by both surface components that use it"
            ));
        }
        let mut gaps = Vec::new();
        gaps.extend(self.corner_gaps());
        gaps.extend(self.border_gaps());
        gaps.extend(self.curve_surface_gaps(opts.samples.max(2), &mut problems));
        let max_gap = gaps.iter().map(|g| g.max).fold(0.0, f64::max);
        for g in &gaps {
            if g.max.is_nan() || g.max > gap_tol {
                problems.push(format!(
                    "gap {:.3e} between {} exceeds the tolerance {gap_tol:.3e}",
                    g.max, g.what
                ));
            }
        }
        CheckReport {
            name: self.name.clone(),
            counts,
            bbox,
            reference_length: l,
            gap_tolerance: gap_tol,
            topology,
            gaps,
            max_gap,
            problems,
        }
    }

    /// Entity counts.
    pub fn counts(&self) -> Counts {
        Counts {
            corners: self.corners.len(),
            curves: self.curves.len(),
            arcs: self.curves.iter().map(|c| c.arcs.len()).sum(),
            surfaces: self.surfaces.len(),
            patches: self.surfaces.iter().map(|s| s.patches.len()).sum(),
            curve_components: self.curve_components.len(),
            surface_components: self.surface_components.len(),
            control_nodes: self.control_nodes.len(),
            max_curve_degree: self
                .curves
                .iter()
                .flat_map(|c| c.arcs.iter().map(|a| a.degree))
                .max()
                .unwrap_or(0),
            max_surface_degree: self
                .surfaces
                .iter()
                .flat_map(|s| s.patches.iter().map(|p| p.deg_u.max(p.deg_v)))
                .max()
                .unwrap_or(0),
        }
    }

    fn bbox_array(&self) -> [[f64; 3]; 2] {
        self.bbox()
            .map(|(a, b)| [[a.x, a.y, a.z], [b.x, b.y, b.z]])
            .unwrap_or([[0.0; 3]; 2])
    }

    /// Uses of each curve component by the loops: free, non-manifold and orientation.
    pub fn topology_report(&self) -> Topology {
        // comp -> list of reversed flags
        let mut uses: BTreeMap<CurveCompId, Vec<bool>> = BTreeMap::new();
        for sc in &self.surface_components {
            for lp in &sc.loops {
                for oc in lp {
                    uses.entry(oc.comp).or_default().push(oc.reversed);
                }
            }
        }
        let mut t = Topology {
            closed: true,
            free_edges: Vec::new(),
            non_manifold: Vec::new(),
            same_direction: Vec::new(),
            unused: Vec::new(),
            misoriented_loops: Vec::new(),
        };
        for i in 0..self.curve_components.len() {
            let id = CurveCompId::from_index(i);
            match uses.get(&id).map(|v| v.as_slice()) {
                None => t.unused.push(id),
                Some([_]) => t.free_edges.push(id),
                Some([a, b]) => {
                    if a == b {
                        t.same_direction.push(id)
                    }
                }
                Some(_) => t.non_manifold.push(id),
            }
        }
        t.closed =
            t.free_edges.is_empty() && t.non_manifold.is_empty() && t.same_direction.is_empty();
        t
    }

    /// Loops whose winding in the parametric plane contradicts their surface component's
    /// inward normal. Each loop is sampled at interior points of its curve components, the
    /// samples projected onto the support surface with continuation from the previous sample
    /// (so that seams are crossed on the right side), and the signed area of the parametric
    /// polygon is compared with the expected sign (outer loop: +1 for a Positive surface,
    /// holes the opposite).
    pub fn misoriented_loops(&self, gap_tol: f64) -> Vec<(SurfCompId, usize)> {
        const K: usize = 12;
        let mut out = Vec::new();
        let opts = InvertOptions::for_model(self);
        for (sci, sc) in self.surface_components.iter().enumerate() {
            let Ok(inv) = self.inverter(sc.surface, &opts) else {
                out.push((SurfCompId::from_index(sci), 0));
                continue;
            };
            for (li, lp) in sc.loops.iter().enumerate() {
                let mut poly: Vec<(f64, f64)> = Vec::with_capacity(lp.len() * K);
                for oc in lp {
                    let cc = &self.curve_components[oc.comp.index()];
                    let curve = &self.curves[cc.curve.index()];
                    for k in 0..K {
                        let f = (k as f64 + 0.5) / K as f64;
                        let f = if oc.reversed { 1.0 - f } else { f };
                        let p = curve.point(cc.param_at(f));
                        let cont = poly.last().map(|&(u, v)| inv.foot_from(&p, [u, v]));
                        let uv = match cont {
                            Some(f) if f.report.converged && f.distance <= gap_tol => f.uv,
                            // a sample that cannot be projected makes the area NaN: reported
                            _ => inv.nearest_indexed(&p, 0).map_or([f64::NAN; 2], |f| f.uv),
                        };
                        poly.push((uv[0], uv[1]));
                    }
                }
                let n = poly.len();
                let area: f64 = (0..n)
                    .map(|i| {
                        let (a, b) = (poly[i], poly[(i + 1) % n]);
                        a.0 * b.1 - b.0 * a.1
                    })
                    .sum::<f64>()
                    * 0.5;
                let expected = if li == 0 { 1.0 } else { -1.0 } * sc.inward.sign();
                if area * expected <= 0.0 || area.is_nan() {
                    out.push((SurfCompId::from_index(sci), li));
                }
            }
        }
        out
    }

    fn corner_gaps(&self) -> Vec<Gap> {
        self.curve_components
            .iter()
            .enumerate()
            .map(|(i, cc)| {
                let c = &self.curves[cc.curve.index()];
                let d0 = (c.point(cc.t0) - self.corners[cc.start.index()].point).norm();
                let d1 = (c.point(cc.t1) - self.corners[cc.end.index()].point).norm();
                Gap {
                    what: format!(
                        "{} ends and {} / {}",
                        CurveCompId::from_index(i),
                        cc.start,
                        cc.end
                    ),
                    max: d0.max(d1),
                }
            })
            .collect()
    }

    fn border_gaps(&self) -> Vec<Gap> {
        let mut out = Vec::new();
        const N: usize = 17;
        for (ci, c) in self.curves.iter().enumerate() {
            if c.arcs.len() < 2 {
                continue;
            }
            let mut m: f64 = 0.0;
            for w in c.arcs.windows(2) {
                m = m.max((w[0].point(1.0) - w[1].point(0.0)).norm());
            }
            out.push(Gap {
                what: format!("arcs of {}", CurveId::from_index(ci)),
                max: m,
            });
        }
        for (si, s) in self.surfaces.iter().enumerate() {
            if s.patches.len() < 2 {
                continue;
            }
            let mut m: f64 = 0.0;
            for j in 0..s.n_v {
                for i in 0..s.n_u {
                    let p = s.patch(i, j);
                    for k in 0..N {
                        let t = k as f64 / (N - 1) as f64;
                        if i + 1 < s.n_u {
                            let q = s.patch(i + 1, j);
                            m = m.max((p.point(1.0, t) - q.point(0.0, t)).norm());
                        }
                        if j + 1 < s.n_v {
                            let q = s.patch(i, j + 1);
                            m = m.max((p.point(t, 1.0) - q.point(t, 0.0)).norm());
                        }
                    }
                }
            }
            out.push(Gap {
                what: format!("patches of {}", SurfaceId::from_index(si)),
                max: m,
            });
        }
        out
    }

    /// The point inversion on support surface `s`, labelled for messages.
    fn inverter<'a>(
        &'a self,
        s: SurfaceId,
        opts: &InvertOptions,
    ) -> crate::Result<SurfaceInverter<'a, SupportSurface>> {
        let name = &self.surfaces[s.index()].name;
        let label = if name.is_empty() {
            s.to_string()
        } else {
            format!("{s} ({name})")
        };
        SurfaceInverter::new(label, &self.surfaces[s.index()], opts)
    }

    /// Largest distance from samples of each curve component to each surface component it
    /// bounds (foot of the normal, Eq. 11; the nearest surface point found, an upper bound
    /// of the distance); a sample that cannot be projected gives a NaN gap (a problem) and
    /// its error in `problems`.
    fn curve_surface_gaps(&self, samples: usize, problems: &mut Vec<String>) -> Vec<Gap> {
        let mut out = Vec::new();
        let opts = InvertOptions::for_model(self);
        let finders: Vec<_> = (0..self.surfaces.len())
            .map(|i| self.inverter(SurfaceId::from_index(i), &opts))
            .collect();
        for (sci, sc) in self.surface_components.iter().enumerate() {
            for lp in &sc.loops {
                for oc in lp {
                    let cc = &self.curve_components[oc.comp.index()];
                    let curve = &self.curves[cc.curve.index()];
                    let mut m: f64 = 0.0;
                    for k in 0..samples {
                        let s = k as f64 / (samples - 1) as f64;
                        let p = curve.point(cc.param_at(s));
                        let d = match &finders[sc.surface.index()] {
                            Ok(inv) => inv
                                .nearest_indexed(&p, k)
                                .map(|f| f.distance)
                                .map_err(|e| e.to_string()),
                            Err(e) => Err(e.to_string()),
                        };
                        match d {
                            Ok(d) => m = m.max(d),
                            Err(e) => {
                                problems.push(format!("{} sample {k}: {e}", oc.comp));
                                m = f64::NAN;
                                break;
                            }
                        }
                    }
                    out.push(Gap {
                        what: format!(
                            "{} and {} ({})",
                            oc.comp,
                            SurfCompId::from_index(sci),
                            sc.surface
                        ),
                        max: m,
                    });
                }
            }
        }
        out
    }
}

// ------------------------------------------------------------------- junction accuracy

/// Options of the junction accuracy measure ([`GeomDb::junction_accuracy`],
/// [`curve_surfaces_distance`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
pub struct AccuracyOptions {
    /// Fewest samples per arc (default 200).
    pub min_samples_per_arc: usize,
    /// Largest turning of the curve's tangent between two samples, radians (default 0.5°):
    /// an arc that turns more gets more samples, up to `max_samples_per_arc`.
    pub max_turn: f64,
    /// Most samples per arc (default 4000).
    pub max_samples_per_arc: usize,
    /// A sample whose local foot (continued from the previous sample) is farther than
    /// `recheck_rel × length scale`, did not converge or is held on the domain boundary is
    /// re-projected by the global search of [`SurfaceInverter`] (default 1e-10).
    pub recheck_rel: f64,
}

impl Default for AccuracyOptions {
    fn default() -> Self {
        Self {
            min_samples_per_arc: 200,
            max_turn: 0.5f64.to_radians(),
            max_samples_per_arc: 4000,
            recheck_rel: 1e-10,
        }
    }
}

/// The distance of a curve's samples to one surface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
pub struct SurfaceDistance {
    /// Largest distance (model units).
    pub max: f64,
    /// Root mean square of the distances over the samples.
    pub rms: f64,
    /// Global curve parameter of the sample with the largest distance.
    pub at_t: f64,
    /// That sample's point.
    pub at_point: [f64; 3],
}

/// The sampled distance of a curve to its two defining surfaces.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct CurveSurfacesDistance {
    /// Number of samples (all arcs).
    pub samples: usize,
    /// To surface 1 and to surface 2.
    pub surfaces: [SurfaceDistance; 2],
    /// Per arc, the largest distance to either surface (where a re-fit is needed).
    pub arc_max: Vec<f64>,
}

impl CurveSurfacesDistance {
    /// The larger of the two maxima.
    pub fn max(&self) -> f64 {
        self.surfaces[0].max.max(self.surfaces[1].max)
    }
}

/// The accuracy of one junction (a support curve with two defining surfaces) of a database.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct JunctionAccuracy {
    /// The curve.
    pub curve: CurveId,
    /// Its label (`curve N (name)`).
    pub label: String,
    /// Its two defining surfaces.
    pub surfaces: [SurfaceId; 2],
    /// The sampled distances.
    pub distance: CurveSurfacesDistance,
    /// The larger maximum as a fraction of the model's reference length.
    pub max_rel: f64,
}

impl JunctionAccuracy {
    /// The larger of the two maxima (model units).
    pub fn max(&self) -> f64 {
        self.distance.max()
    }
}

/// Sample parameters of one arc [a, b] of `curve`: at least `min_samples_per_arc` uniform
/// intervals, more when the tangent turns by more than `max_turn` per interval (the turning
/// ∫|r′ × r″| / |r′|² dt estimated on 64 intervals). Includes a, excludes b.
fn arc_samples<C: ParamCurve + ?Sized>(curve: &C, a: f64, b: f64, o: &AccuracyOptions) -> Vec<f64> {
    const PRE: usize = 64;
    let h = (b - a) / PRE as f64;
    let turn: f64 = (0..PRE)
        .map(|k| {
            let d = curve.derivs(a + (k as f64 + 0.5) * h);
            let n2 = d.d1.norm_squared();
            if n2 > 0.0 {
                d.d1.cross(&d.d2).norm() / n2 * h
            } else {
                0.0
            }
        })
        .sum();
    let by_turn = if o.max_turn > 0.0 && turn.is_finite() {
        (turn / o.max_turn).ceil() as usize
    } else {
        0
    };
    let n = by_turn
        .max(o.min_samples_per_arc)
        .min(o.max_samples_per_arc.max(o.min_samples_per_arc))
        .max(1);
    (0..n).map(|j| a + (b - a) * j as f64 / n as f64).collect()
}

/// The distance of `curve` to the surfaces of `inv` (two point inversions) at samples of
/// every arc (≥ `min_samples_per_arc`, more where the curve turns, see [`AccuracyOptions`])
/// plus the curve's end.
///
/// Each distance is that of a true foot of the normal (Eq. 11, [`crate::invert`]): a local
/// Newton continued from the previous sample's parameters, and the global search of
/// [`SurfaceInverter::nearest_indexed`] at the first sample of each arc and wherever the local
/// foot is not converged, is held on the domain boundary or is farther than the recheck
/// distance; the nearer of the two is kept. A distance is therefore never under-estimated by
/// a wrong local minimum above the recheck distance. Arcs are measured in parallel, each
/// sequentially, so the result does not depend on the number of threads.
pub fn curve_surfaces_distance<C, S1, S2>(
    curve: &C,
    inv: (&SurfaceInverter<'_, S1>, &SurfaceInverter<'_, S2>),
    opts: &AccuracyOptions,
) -> crate::Result<CurveSurfacesDistance>
where
    C: ParamCurve + ?Sized,
    S1: crate::eval::ParamSurface + ?Sized,
    S2: crate::eval::ParamSurface + ?Sized,
{
    let (lo, hi) = curve.domain();
    let mut edges = vec![lo];
    let mut b: Vec<f64> = curve
        .breaks()
        .into_iter()
        .filter(|x| *x > lo && *x < hi)
        .collect();
    b.sort_by(f64::total_cmp);
    b.dedup();
    edges.extend(b);
    edges.push(hi);
    let recheck = opts.recheck_rel * inv.0.options().length_scale;
    let arcs: Vec<(f64, f64, bool)> = edges
        .windows(2)
        .enumerate()
        .map(|(k, w)| (w[0], w[1], k + 2 == edges.len()))
        .collect();
    // per arc: samples (t, point, d1, d2)
    let per_arc = crate::par_map(&arcs, |&(a, b, last)| {
        let mut ts = arc_samples(curve, a, b, opts);
        if last {
            ts.push(b);
        }
        let mut uv: [Option<[f64; 2]>; 2] = [None, None];
        let mut out = Vec::with_capacity(ts.len());
        for (i, &t) in ts.iter().enumerate() {
            let p = curve.point(t);
            let d1 = nearest(inv.0, &p, &mut uv[0], recheck, i)?;
            let d2 = nearest(inv.1, &p, &mut uv[1], recheck, i)?;
            out.push((t, p, d1, d2));
        }
        Ok::<_, crate::Error>(out)
    });
    let mut res = CurveSurfacesDistance {
        samples: 0,
        surfaces: [SurfaceDistance {
            max: 0.0,
            rms: 0.0,
            at_t: lo,
            at_point: {
                let p = curve.point(lo);
                [p.x, p.y, p.z]
            },
        }; 2],
        arc_max: Vec::with_capacity(arcs.len()),
    };
    let mut sum = [0.0; 2];
    for arc in per_arc {
        let mut m: f64 = 0.0;
        for (t, p, d1, d2) in arc? {
            for (k, d) in [d1, d2].into_iter().enumerate() {
                let s = &mut res.surfaces[k];
                if d > s.max || d.is_nan() {
                    s.max = d;
                    s.at_t = t;
                    s.at_point = [p.x, p.y, p.z];
                }
                sum[k] += d * d;
            }
            m = m.max(d1).max(d2);
            res.samples += 1;
        }
        res.arc_max.push(m);
    }
    for k in 0..2 {
        res.surfaces[k].rms = (sum[k] / res.samples.max(1) as f64).sqrt();
    }
    Ok(res)
}

/// The distance from `p` to the surface of `inv`: the local foot from `uv` (the previous
/// sample's), re-checked by the global search when it is not trusted; `uv` is updated.
fn nearest<S: crate::eval::ParamSurface + ?Sized>(
    inv: &SurfaceInverter<'_, S>,
    p: &crate::prelude::Point3,
    uv: &mut Option<[f64; 2]>,
    recheck: f64,
    index: usize,
) -> crate::Result<f64> {
    let local = uv.map(|x| inv.foot_from(p, x));
    let trusted = local.filter(|f| f.report.converged && !f.on_boundary && f.distance <= recheck);
    let best = match (trusted, local) {
        (Some(f), _) => f,
        (None, Some(l)) => {
            let g = inv.nearest_indexed(p, index)?;
            if l.distance.is_finite() && l.distance < g.distance {
                l
            } else {
                g
            }
        }
        (None, None) => inv.nearest_indexed(p, index)?,
    };
    *uv = Some(best.uv);
    Ok(best.distance)
}

impl GeomDb {
    /// The accuracy of junction `c` (a support curve with two defining surfaces): its sampled
    /// distance to both surfaces ([`curve_surfaces_distance`]). `None` when the curve has not
    /// two defining surfaces or no arc.
    pub fn junction_accuracy(
        &self,
        c: CurveId,
        opts: &AccuracyOptions,
    ) -> crate::Result<Option<JunctionAccuracy>> {
        let curve = &self.curves[c.index()];
        if curve.defining_surfaces.len() != 2 || curve.arcs.is_empty() {
            return Ok(None);
        }
        let s = [curve.defining_surfaces[0], curve.defining_surfaces[1]];
        let io = InvertOptions::for_model(self);
        let (a, b) = (self.inverter(s[0], &io)?, self.inverter(s[1], &io)?);
        let distance = curve_surfaces_distance(curve, (&a, &b), opts)?;
        let label = if curve.name.is_empty() {
            c.to_string()
        } else {
            format!("{c} ({})", curve.name)
        };
        Ok(Some(JunctionAccuracy {
            curve: c,
            label,
            surfaces: s,
            max_rel: distance.max() / self.reference_length(),
            distance,
        }))
    }

    /// [`junction_accuracy`](Self::junction_accuracy) of every junction, in curve order.
    pub fn junctions_accuracy(
        &self,
        opts: &AccuracyOptions,
    ) -> crate::Result<Vec<JunctionAccuracy>> {
        let mut out = Vec::new();
        for i in 0..self.curves.len() {
            if let Some(j) = self.junction_accuracy(CurveId::from_index(i), opts)? {
                out.push(j);
            }
        }
        Ok(out)
    }
}
