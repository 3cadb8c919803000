//! What each marker of a user's grid is, by shape alone ([`marker_roles`]): the far field
//! (the marker whose box holds every other marker) is fixed, a plane is a sliding plane
//! (the symmetry plane), a marker on the geometry is wall; any other marker is fixed.
//! Names and a mesher's tags are never read.

use geom_db::GeomDb;
use mesh::Mesh;
use serde::Serialize;

use super::InitError;

/// The role of a marker in the case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Role {
    /// On the geometry: follows the design (`wall`).
    Wall,
    /// A plane: nodes slide on it (`slide`).
    Slide,
    /// Does not move (`fixed`).
    Fixed,
}

/// A marker's role and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MarkerRole {
    /// The marker.
    pub marker: String,
    /// Its role.
    pub role: Role,
    /// Why, in words, with the figure that decided it.
    pub why: String,
}

/// The box of a set of nodes.
fn bbox(grid: &Mesh, nodes: &[u32]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &v in nodes {
        for k in 0..3 {
            lo[k] = lo[k].min(grid.coords[v as usize][k]);
            hi[k] = hi[k].max(grid.coords[v as usize][k]);
        }
    }
    (lo, hi)
}

/// The roles of every marker of `grid` against `db`; `tol` is the largest distance of a
/// wall node from the geometry (and of a plane's node from its plane).
pub fn marker_roles(db: &GeomDb, grid: &Mesh, tol: f64) -> Result<Vec<MarkerRole>, InitError> {
    let nodes: Vec<Vec<u32>> = grid.markers.iter().map(|m| m.elements.node_set()).collect();
    let boxes: Vec<_> = nodes.iter().map(|n| bbox(grid, n)).collect();
    let holds = |a: usize, b: usize| {
        let (la, ha) = boxes[a];
        let (lb, hb) = boxes[b];
        (0..3).all(|k| la[k] <= lb[k] + tol && ha[k] >= hb[k] - tol)
    };
    let n = grid.markers.len();
    let projectors = surfgrid::classify::component_projectors(db)?;
    let mut out = Vec::with_capacity(n);
    for (i, m) in grid.markers.iter().enumerate() {
        let points: Vec<[f64; 3]> = nodes[i].iter().map(|&v| grid.coords[v as usize]).collect();
        let (_, normal, dev) = deform::bc::fit_plane(&points, 3);
        let encloses = n > 1 && (0..n).all(|j| j == i || holds(i, j));
        let (role, why) = if encloses && dev > tol {
            (
                Role::Fixed,
                "far field: its box holds every other marker".to_string(),
            )
        } else if dev <= tol {
            (
                Role::Slide,
                format!(
                    "a plane (normal ({:.3}, {:.3}, {:.3}), nodes within {dev:.1e} of it)",
                    normal[0], normal[1], normal[2]
                ),
            )
        } else {
            let d = surfgrid::classify::marker_distance(&projectors, grid, &m.name, tol)?;
            if d.max_distance <= tol {
                (
                    Role::Wall,
                    format!("on the geometry (nodes within {:.1e})", d.max_distance),
                )
            } else {
                (
                    Role::Fixed,
                    format!(
                        "off the geometry (node {} at {:.3e})",
                        d.worst_node, d.max_distance
                    ),
                )
            }
        };
        out.push(MarkerRole {
            marker: m.name.clone(),
            role,
            why,
        });
    }
    Ok(out)
}
