//! Classification of an imported surface grid (e.g. SU2, no parameters) against a database:
//! every node gets its support entity and parameters by projection (Eq. 11).
//!
//! Markers are matched to surface components by name. A node used by two or more markers, or
//! lying on a free edge of its marker (an edge used by one triangle of it), or lying (within
//! the tolerance) on a seam curve of its component (a curve component its loops use twice,
//! e.g. the wing's trailing edge, a cylinder cap's radius) or one of its corners, is a
//! boundary node: it is a corner if within the tolerance of a corner of its components' loops,
//! otherwise it is projected on the curve components of those loops (the nearest foot inside
//! a component's range wins). Other nodes are projected on their component's surface.
//! A node farther than the tolerance from every candidate is an error naming it.
//! Boundary nodes get their (u, v) on each adjacent component by projection seeded at a
//! neighbouring interior node of each triangle, so a node on a seam gets one local copy per
//! side. A node at a pole (the image of a degenerate side of the surface's parameter
//! rectangle, see [`crate::pole`]) gets one local copy per triangle, by the pole-copy
//! convention. Nodes are snapped onto their entity (their positions become the evaluation at the
//! recovered parameters); the report gives the distances moved.
//!
//! [`classify`] runs named stages over typed intermediate results:
//! 1. `topology::components`: markers → surface components (`ComponentTriangles`);
//! 2. `topology::topology`: boundary nodes (`Topology`);
//! 3. `supports::supports`: every node's support and parameters (`Supports`);
//! 4. `local::component_grid`: each component's parametric grid ([`ComponentGrid`](crate::ComponentGrid));
//! 5. `supports::curve_nodes`: each curve component's nodes in order;
//! 6. the report, then the nodes snapped onto their entity.
//!
//! [`wall`] ties the wall of a volume grid to the geometry: it splits the wall markers'
//! triangles by surface component by geometry alone (the input of [`classify`]), then
//! classifies them. [`markers`] measures how far a marker lies from the geometry (which
//! markers are the body's).

use geom_db::GeomDb;
use geom_db::prelude::Point3;
use intersect::project::{ProjectOptions, SurfaceProjector};
use mesh::Mesh;

use crate::error::Result;
use crate::grid::{NodeSupport, SurfaceGrid};

mod local;
pub mod markers;
mod supports;
mod topology;
pub mod wall;

pub use markers::{MarkerDistance, marker_distance, node_distance};
pub use wall::{classify_wall, component_projectors, nearest_component, wall_surface};

/// Knobs of the classification.
#[derive(Debug, Clone, PartialEq)]
pub struct ClassifyOptions {
    /// Largest accepted node distance from its entity, relative to the model's reference
    /// length (default 1e-6).
    pub rel_tol: f64,
}

impl Default for ClassifyOptions {
    fn default() -> Self {
        Self { rel_tol: 1e-6 }
    }
}

/// Distances found by the classification.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClassifyReport {
    /// Nodes classified on corners.
    pub corners: usize,
    /// Nodes classified on curve components.
    pub curve_nodes: usize,
    /// Nodes classified inside surface components.
    pub surface_nodes: usize,
    /// Largest node–entity distance.
    pub max_distance: f64,
    /// The node with that distance.
    pub worst_node: usize,
    /// Mean node–entity distance.
    pub mean_distance: f64,
}

/// What every stage reads: the database, the node positions, the tolerance and the
/// projectors on the surface components' supports.
struct Context<'a> {
    db: &'a GeomDb,
    coords: Vec<Point3>,
    /// Largest accepted node–entity distance (absolute).
    tol: f64,
    popts: ProjectOptions,
    /// One projector per surface component (index = component index).
    surf_proj: Vec<SurfaceProjector<'a, geom_db::SupportSurface>>,
}

/// Classifies the triangles of `mesh`'s markers (one per surface component, named as
/// [`marker_name`](crate::grid::marker_name)) on `db`; returns the grid tied to the geometry
/// and a report.
pub fn classify(
    mesh: &Mesh,
    db: &GeomDb,
    opts: &ClassifyOptions,
) -> Result<(SurfaceGrid, ClassifyReport)> {
    let popts = ProjectOptions::default().with_length_scale(db.reference_length());
    let mut ctx = Context {
        db,
        coords: mesh
            .coords
            .iter()
            .map(|p| Point3::new(p[0], p[1], p[2]))
            .collect(),
        tol: opts.rel_tol * db.reference_length(),
        popts,
        surf_proj: Vec::new(),
    };
    let comps = topology::components(mesh, &ctx)?;
    ctx.surf_proj = db
        .surface_components
        .iter()
        .map(|sc| SurfaceProjector::new(sc.name.clone(), db.surface(sc.surface), &ctx.popts))
        .collect::<std::result::Result<_, _>>()?;
    let topo = topology::topology(&comps, &ctx)?;
    let supports = supports::supports(&ctx, &topo)?;
    let components = comps
        .iter()
        .map(|c| local::component_grid(c, &ctx, &topo, &supports))
        .collect::<Result<Vec<_>>>()?;
    let curve_nodes = supports::curve_nodes(&ctx, &supports);
    let report = report(&supports);
    let mut grid = SurfaceGrid {
        coords: ctx.coords,
        support: supports.support,
        curve_nodes,
        components,
    };
    // nodes snapped onto their entity (the distances are in the report), so the grid is
    // exactly the evaluation of its parameters and a zero model change leaves it unchanged
    for i in 0..grid.coords.len() {
        grid.coords[i] = grid.evaluate_node(db, i);
    }
    Ok((grid, report))
}

/// Stage 6: counts and distances of the classified nodes.
fn report(s: &supports::Supports) -> ClassifyReport {
    let mut report = ClassifyReport {
        corners: 0,
        curve_nodes: 0,
        surface_nodes: 0,
        max_distance: 0.0,
        worst_node: 0,
        mean_distance: 0.0,
    };
    let mut count = 0usize;
    for i in 0..s.support.len() {
        if !s.used[i] {
            continue;
        }
        count += 1;
        match s.support[i] {
            NodeSupport::Corner(_) => report.corners += 1,
            NodeSupport::Curve { .. } => report.curve_nodes += 1,
            NodeSupport::Surface { .. } => report.surface_nodes += 1,
            NodeSupport::Free => {}
        }
        report.mean_distance += s.dist[i];
        if s.dist[i] > report.max_distance {
            report.max_distance = s.dist[i];
            report.worst_node = i;
        }
    }
    report.mean_distance /= count.max(1) as f64;
    report
}
