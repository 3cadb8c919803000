//! Grid update after a model update (§3.3): nodes re-evaluated at their frozen parameters;
//! where a surface component's boundary moved in its parametric plane, the interior
//! parameters are first re-mapped by a boundary-conforming harmonic map, then smoothed.
//!
//! 1. Corners take the new corner positions.
//! 2. Curve nodes keep their fraction of the component's parameter range:
//!    t′ = t0′ + (t − t0)(t1′ − t0′)/(t1 − t0) (t unchanged when the range is unchanged),
//!    evaluated on the new curve.
//! 3. For each surface component, the boundary nodes' new (u, v) come from projecting their
//!    new positions on the new surface (Eq. 11) seeded at the old (u, v) (kept as they are
//!    when neither the node nor the surface changed). If no boundary (u, v) moved, interior
//!    nodes are re-evaluated at their frozen (u, v) (Eq. 7). Otherwise the parametric
//!    displacement δ of the interior nodes solves the graph Laplace problem
//!    Σ_{j ∈ N(i)} (δ_j − δ_i) = 0 with the boundary displacements as Dirichlet data
//!    ([`crate::harmonic`]: factorised once per component), and smoothing passes in (u, v)
//!    follow until no triangle is inverted and the worst quality is back to the given
//!    fraction of the initial one.
//!
//! Connectivity never changes. Zero model change gives the grid back bit for bit.
//!
//! [`Updater`] keeps what depends only on the grid (the factorised re-maps) between updates
//! of the same grid, as an optimisation loop makes them; [`update`] is the one-shot form.

use std::sync::OnceLock;

use rayon::prelude::*;

use geom_db::GeomDb;
use geom_db::eval::{ParamCurve, ParamSurface};
use geom_db::prelude::Point3;
use intersect::project::{ProjectOptions, SurfaceProjector};

use crate::error::{Error, Result};
use crate::grid::{NodeSupport, SurfaceGrid};
use crate::harmonic::HarmonicMap;
use crate::smooth::{Improve, orient, quality3};

/// Knobs of the update.
#[derive(Debug, Clone, PartialEq)]
pub struct UpdateOptions {
    /// Largest number of smoothing passes per component (default 50).
    pub max_passes: usize,
    /// Smoothing stops once the worst quality is at least this fraction of the initial
    /// worst quality (default 0.9).
    pub quality_fraction: f64,
    /// Largest accepted distance of a re-projected boundary node, relative to the model's
    /// reference length (default 1e-7).
    pub boundary_rel_tol: f64,
}

impl Default for UpdateOptions {
    fn default() -> Self {
        Self {
            max_passes: 50,
            quality_fraction: 0.9,
            boundary_rel_tol: 1e-7,
        }
    }
}

/// What the update did to one surface component.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ComponentUpdate {
    /// The component.
    pub comp: u32,
    /// Its boundary moved in the parametric plane, so its interior was re-mapped.
    pub remapped: bool,
    /// Largest boundary displacement in (u, v).
    pub max_boundary_shift: f64,
    /// Worst 3-D mean ratio in the initial grid.
    pub worst_initial: f64,
    /// Worst mean ratio at the frozen / re-mapped parameters, before smoothing (negative
    /// when a triangle is inverted in (u, v)).
    pub worst_before: f64,
    /// Worst mean ratio after smoothing.
    pub worst_after: f64,
    /// Smoothing passes made.
    pub passes: usize,
}

/// The update report.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct UpdateReport {
    /// Nodes whose position changed.
    pub moved_nodes: usize,
    /// Largest node displacement.
    pub max_displacement: f64,
    /// Per component.
    pub components: Vec<ComponentUpdate>,
}

fn worst(tris: &[[u32; 3]], uv: &[[f64; 2]], x: &[Point3]) -> f64 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| v as usize);
            let q = quality3(&x[a], &x[b], &x[c]);
            if orient(uv[a], uv[b], uv[c]) > 0.0 {
                q
            } else {
                -q
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Positions of all nodes evaluated at their frozen parameters on `db` (in parallel; the
/// result does not depend on the number of threads).
pub fn evaluate_frozen(grid: &SurfaceGrid, db: &GeomDb) -> Vec<Point3> {
    (0..grid.n_nodes())
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| grid.evaluate_node(db, i))
        .collect()
}

/// Updates `grid` (made on `old`) to the model `new` (the same topology after a model
/// update): see the module doc.
pub fn update(
    grid: &SurfaceGrid,
    old: &GeomDb,
    new: &GeomDb,
    opts: &UpdateOptions,
) -> Result<(SurfaceGrid, UpdateReport)> {
    Updater::new(grid).update(grid, old, new, opts)
}

/// What one update recorded for its linearisation ([`Updater::update_recorded`]): per
/// component, the smoothing moves (node, fraction) in the order made.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct UpdateRecord {
    pub(crate) moves: Vec<Vec<(u32, f64)>>,
}

/// The reusable part of [`update`] for one grid: each component's harmonic re-map,
/// factorised the first time the component is re-mapped and kept for later updates. The
/// answer is bit for bit that of [`update`].
#[derive(Debug)]
pub struct Updater {
    /// Node and triangle counts per component (checks that a grid is the one set up).
    shape: Vec<(usize, usize, usize)>,
    maps: Vec<OnceLock<HarmonicMap>>,
    /// The node positions of the grid set up, and per component its worst triangle quality
    /// there (recomputed for a grid of the same topology at other positions).
    coords: Vec<Point3>,
    worst_initial: Vec<f64>,
}

/// Per component of `grid`, the worst signed triangle quality.
fn worst_per_component(grid: &SurfaceGrid) -> Vec<f64> {
    grid.components
        .iter()
        .map(|cg| {
            let x0: Vec<Point3> = cg.nodes.iter().map(|&g| grid.coords[g as usize]).collect();
            worst(&cg.triangles, &cg.uv, &x0)
        })
        .collect()
}

impl Updater {
    /// An updater for `grid` (nothing is factorised yet).
    pub fn new(grid: &SurfaceGrid) -> Self {
        Self {
            shape: grid
                .components
                .iter()
                .map(|c| (c.nodes.len(), c.n_boundary, c.triangles.len()))
                .collect(),
            maps: grid.components.iter().map(|_| OnceLock::new()).collect(),
            coords: grid.coords.clone(),
            worst_initial: worst_per_component(grid),
        }
    }

    /// The harmonic re-map of component `ci` of `grid` (the grid this updater was made for),
    /// factorised on first use.
    pub(crate) fn harmonic(&self, ci: usize, grid: &SurfaceGrid) -> &HarmonicMap {
        let cg = &grid.components[ci];
        self.maps[ci].get_or_init(|| HarmonicMap::new(&cg.triangles, cg.nodes.len(), cg.n_boundary))
    }

    /// [`update`] of `grid`, the grid this updater was made for.
    pub fn update(
        &self,
        grid: &SurfaceGrid,
        old: &GeomDb,
        new: &GeomDb,
        opts: &UpdateOptions,
    ) -> Result<(SurfaceGrid, UpdateReport)> {
        self.run(grid, old, new, opts, None)
    }

    /// [`update`](Self::update), also returning what [`Updater::linearise_recorded`] needs
    /// to linearise it (per component, the smoothing moves it made; see
    /// [`crate::linearise`]). The grid and report are [`update`](Self::update)'s, bit for bit.
    pub fn update_recorded(
        &self,
        grid: &SurfaceGrid,
        old: &GeomDb,
        new: &GeomDb,
        opts: &UpdateOptions,
    ) -> Result<(SurfaceGrid, UpdateReport, UpdateRecord)> {
        let mut moves = Vec::new();
        let (out, report) = self.run(grid, old, new, opts, Some(&mut moves))?;
        Ok((out, report, UpdateRecord { moves }))
    }

    fn run(
        &self,
        grid: &SurfaceGrid,
        old: &GeomDb,
        new: &GeomDb,
        opts: &UpdateOptions,
        rec: Option<&mut Vec<Vec<(u32, f64)>>>,
    ) -> Result<(SurfaceGrid, UpdateReport)> {
        let shape: Vec<_> = grid
            .components
            .iter()
            .map(|c| (c.nodes.len(), c.n_boundary, c.triangles.len()))
            .collect();
        if shape != self.shape {
            return Err(Error::Mismatch {
                what: "the grid is not the one the updater was made for".into(),
            });
        }
        let other;
        let worst_initial = if grid.coords == self.coords {
            &self.worst_initial
        } else {
            other = worst_per_component(grid);
            &other
        };
        update_with(grid, old, new, opts, &self.maps, worst_initial, rec)
    }
}

fn update_with(
    grid: &SurfaceGrid,
    old: &GeomDb,
    new: &GeomDb,
    opts: &UpdateOptions,
    maps: &[OnceLock<HarmonicMap>],
    worst_initial: &[f64],
    mut rec: Option<&mut Vec<Vec<(u32, f64)>>>,
) -> Result<(SurfaceGrid, UpdateReport)> {
    if old.corners.len() != new.corners.len()
        || old.curve_components.len() != new.curve_components.len()
        || old.surface_components.len() != new.surface_components.len()
    {
        return Err(Error::Mismatch {
            what: "the old and new models have different topologies".into(),
        });
    }
    let mut out = grid.clone();
    // corners and curve nodes
    for (i, s) in grid.support.iter().enumerate() {
        match *s {
            NodeSupport::Corner(c) => out.coords[i] = new.corner(c).point,
            NodeSupport::Curve { comp, t } => {
                let (a, b) = (old.curve_component(comp), new.curve_component(comp));
                let t2 = if a.t0 == b.t0 && a.t1 == b.t1 {
                    t
                } else {
                    b.t0 + (t - a.t0) * (b.t1 - b.t0) / (a.t1 - a.t0)
                };
                out.support[i] = NodeSupport::Curve { comp, t: t2 };
                out.coords[i] = new.curve(b.curve).point(t2);
            }
            NodeSupport::Surface { .. } | NodeSupport::Free => {}
        }
    }
    let tol = opts.boundary_rel_tol * new.reference_length();
    let popts = ProjectOptions::default().with_length_scale(new.reference_length());
    let mut reports = Vec::new();
    for ci in 0..grid.components.len() {
        let cg = &grid.components[ci];
        let sc = new.surface_component(cg.comp);
        let surf = new.surface(sc.surface);
        let surf_same = old.surface(old.surface_component(cg.comp).surface) == surf;
        let nb = cg.n_boundary;
        let mut uv = cg.uv.clone();
        let mut proj: Option<SurfaceProjector<'_, geom_db::SupportSurface>> = None;
        let mut max_shift: f64 = 0.0;
        let is_pole = cg.pole_mask();
        for k in 0..nb {
            let g = cg.nodes[k] as usize;
            // a pole copy stays on its degenerate side (its along-side coordinate follows
            // the convention, refreshed below)
            if is_pole[k] || (surf_same && out.coords[g] == grid.coords[g]) {
                continue;
            }
            if proj.is_none() {
                proj = Some(SurfaceProjector::new(sc.name.clone(), surf, &popts)?);
            }
            let pr = proj.as_ref().expect("set above");
            let mut f = pr.project_from(&out.coords[g], uv[k]);
            if !f.report.converged || f.distance > tol {
                let h = pr.project(&out.coords[g])?;
                if !f.report.converged || h.distance < f.distance {
                    f = h;
                }
            }
            if f.distance > tol {
                return Err(Error::BoundaryProjection {
                    component: cg.comp,
                    name: sc.name.clone(),
                    node: g,
                    distance: f.distance,
                    tol,
                });
            }
            max_shift = max_shift.max((f.uv[0] - uv[k][0]).abs().max((f.uv[1] - uv[k][1]).abs()));
            uv[k] = f.uv;
        }
        let worst_initial = worst_initial[ci];
        let remapped = max_shift > 0.0;
        if remapped {
            let mut d: Vec<[f64; 2]> = (0..uv.len())
                .map(|k| {
                    if k < nb {
                        [uv[k][0] - cg.uv[k][0], uv[k][1] - cg.uv[k][1]]
                    } else {
                        [0.0, 0.0]
                    }
                })
                .collect();
            maps[ci]
                .get_or_init(|| HarmonicMap::new(&cg.triangles, cg.nodes.len(), nb))
                .solve(&mut d);
            for k in nb..uv.len() {
                uv[k] = [cg.uv[k][0] + d[k][0], cg.uv[k][1] + d[k][1]];
            }
        }
        let eval = |p: [f64; 2]| surf.point(p[0], p[1]);
        let x: Vec<Point3> = (0..uv.len())
            .into_par_iter()
            .with_min_len(4096)
            .map(|k| {
                if k < nb {
                    out.coords[cg.nodes[k] as usize]
                } else {
                    eval(uv[k])
                }
            })
            .collect();
        let worst_before = worst(&cg.triangles, &uv, &x);
        let mut imp = Improve {
            uv,
            x,
            tris: cg.triangles.clone(),
            n_fixed: nb,
            no_swap: Vec::new(),
            eval: &eval,
        };
        let mut passes = 0;
        let mut w = worst_before;
        let mut moves = Vec::new();
        if remapped {
            while passes < opts.max_passes
                && (imp.n_inverted() > 0 || w < opts.quality_fraction * worst_initial)
            {
                imp.smooth_pass_recorded(rec.is_some().then_some(&mut moves));
                passes += 1;
                w = worst(&imp.tris, &imp.uv, &imp.x);
            }
            let bad = imp.n_inverted();
            if bad > 0 {
                return Err(Error::UpdateInvalid {
                    component: cg.comp,
                    name: sc.name.clone(),
                    invalid: bad,
                    passes,
                });
            }
        }
        let oc = &mut out.components[ci];
        oc.uv = imp.uv;
        if remapped {
            oc.refresh_pole_copies(surf.domain());
        }
        for k in nb..oc.uv.len() {
            let g = oc.nodes[k] as usize;
            out.coords[g] = imp.x[k];
            out.support[g] = NodeSupport::Surface {
                comp: cg.comp,
                uv: oc.uv[k],
            };
        }
        if let Some(r) = rec.as_deref_mut() {
            r.push(moves);
        }
        reports.push(ComponentUpdate {
            comp: cg.comp.0,
            remapped,
            max_boundary_shift: max_shift,
            worst_initial,
            worst_before,
            worst_after: w,
            passes,
        });
    }
    let mut moved = 0;
    let mut maxd: f64 = 0.0;
    for (a, b) in grid.coords.iter().zip(&out.coords) {
        if a != b {
            moved += 1;
            maxd = maxd.max((a - b).norm());
        }
    }
    Ok((
        out,
        UpdateReport {
            moved_nodes: moved,
            max_displacement: maxd,
            components: reports,
        },
    ))
}
