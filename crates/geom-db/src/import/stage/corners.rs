//! Stage 4, corners: the end points of the pieces merged within the sewing tolerance by
//! geom-db's one point merger ([`PointMerger`]: a point joins the nearest earlier corner
//! within the tolerance, deterministic).

use super::edges::Edges;
use crate::ids::CornerId;
use crate::merge::PointMerger;
use crate::prelude::Point3;

/// What stage 4 produces.
pub(crate) struct Corners {
    /// Corner positions (the first point of each cluster).
    pub points: Vec<Point3>,
    /// Per edge: its start and end corners.
    pub edge_corners: Vec<(CornerId, CornerId)>,
    /// Largest distance from an end point to its corner.
    pub max_gap: f64,
}

/// Runs stage 4.
pub(crate) fn run(edges: &Edges, sew: f64) -> Corners {
    let mut m = PointMerger::new(sew);
    let mut max_gap: f64 = 0.0;
    let mut edge_corners = Vec::with_capacity(edges.edges.len());
    for e in &edges.edges {
        let (a, b) = (m.insert(e.start), m.insert(e.end));
        max_gap = max_gap.max(a.distance).max(b.distance);
        edge_corners.push((CornerId::from_index(a.index), CornerId::from_index(b.index)));
    }
    Corners {
        points: m.into_points(),
        edge_corners,
        max_gap,
    }
}
