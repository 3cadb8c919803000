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
