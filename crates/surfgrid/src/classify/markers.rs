//! How far a grid marker lies from the geometry ([`marker_distance`]): the largest distance
//! of its nodes from the nearest surface component (Eq. 11). A marker of the body is within
//! the CAD's tolerance; a far-field box or a symmetry plane that is no face of the CAD is
//! not. The first node beyond a given distance stops the search.

use geom_db::prelude::Point3;
use mesh::Mesh;

use super::wall::ComponentProjectors;
use crate::error::{Error, Result};

/// The distance of a marker from the geometry.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MarkerDistance {
    /// The marker.
    pub marker: String,
    /// Its nodes.
    pub nodes: usize,
    /// Largest node distance from the nearest surface component, over the nodes visited
    /// (all of them unless one was beyond the stopping distance).
    pub max_distance: f64,
    /// The node at that distance.
    pub worst_node: usize,
    /// The surface component nearest to that node (`None`: no projection converged).
    pub nearest: Option<geom_db::SurfCompId>,
}

/// The distance of the node `p` from the nearest surface component whose projection
/// converges, with that component (infinite and `None` when none does).
pub fn node_distance(
    projectors: &ComponentProjectors<'_>,
    p: &Point3,
) -> Result<(f64, Option<geom_db::SurfCompId>)> {
    let mut best = (f64::INFINITY, None);
    for (k, pr) in projectors.iter().enumerate() {
        match pr.project(p) {
            Ok(f) if f.distance < best.0 => {
                best = (f.distance, Some(geom_db::SurfCompId::from_index(k)));
            }
            Ok(_) | Err(intersect::Error::ProjectionFailed { .. }) => {}
            Err(e) => return Err(e.into()),
        }
    }
    Ok(best)
}

/// The distance of `marker` of `grid` from the geometry of `projectors` (see
/// [`super::component_projectors`]); nodes are visited in index order, and the first one
/// farther than `stop_above` ends the search.
pub fn marker_distance(
    projectors: &ComponentProjectors<'_>,
    grid: &Mesh,
    marker: &str,
    stop_above: f64,
) -> Result<MarkerDistance> {
    let m = grid.marker(marker).ok_or_else(|| Error::MissingMarker {
        marker: marker.to_string(),
        available: grid.markers.iter().map(|m| m.name.clone()).collect(),
    })?;
    let nodes = m.elements.node_set();
    let mut out = MarkerDistance {
        marker: marker.to_string(),
        nodes: nodes.len(),
        max_distance: 0.0,
        worst_node: nodes.first().map_or(0, |&v| v as usize),
        nearest: None,
    };
    for &v in &nodes {
        let c = grid.coords[v as usize];
        let (d, comp) = node_distance(projectors, &Point3::new(c[0], c[1], c[2]))?;
        if d > out.max_distance {
            out.max_distance = d;
            out.worst_node = v as usize;
            out.nearest = comp;
        }
        if d > stop_above {
            break;
        }
    }
    Ok(out)
}
