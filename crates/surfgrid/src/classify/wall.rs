//! The wall of a volume grid tied to the geometry: its markers' triangles split by surface
//! component by geometry alone ([`wall_surface`]: the component its three nodes lie on, or
//! else the one nearest to its centroid among those whose foot of the normal, Eq. 11,
//! converges; never by marker names or a mesher's entity tags), then classified
//! ([`classify_wall`]).

use geom_db::prelude::Point3;
use geom_db::{GeomDb, SupportSurface, SurfCompId};
use intersect::project::{ProjectOptions, SurfaceProjector};
use mesh::{ElementKind, Elements, Marker, Mesh};
use rayon::prelude::*;

use super::{ClassifyOptions, ClassifyReport, classify};
use crate::error::{Error, Result};
use crate::grid::{SurfaceGrid, marker_name};

/// One projector per surface component of a database (index = component index).
pub type ComponentProjectors<'a> = Vec<SurfaceProjector<'a, SupportSurface>>;

/// Projectors on every surface component's support surface, with the model's length scale.
pub fn component_projectors(db: &GeomDb) -> Result<ComponentProjectors<'_>> {
    let popts = ProjectOptions::default().with_length_scale(db.reference_length());
    db.surface_components
        .iter()
        .map(|sc| {
            SurfaceProjector::new(sc.name.clone(), db.surface(sc.surface), &popts)
                .map_err(Error::from)
        })
        .collect()
}

/// The wall triangles of `grid` (the markers named in `wall`) split by surface component,
/// as a surface `Mesh` over all of the grid's nodes with one marker per component (named as
/// [`marker_name`]), ready for [`classify`]. A triangle's component is found by geometry
/// alone: the one component on which its three nodes all lie (within the tolerance of
/// `opts`: the nodes of a grid lie on the surfaces, where a flat triangle's centroid does
/// not); where there are several (a triangle at a junction) or none, the one nearest to its
/// centroid ([`nearest_component`]). The grid's entity tags and marker names are not read,
/// so a grid from any mesher (SU2, Gmsh's MSH with its own entity numbering) is accepted.
pub fn wall_surface(
    db: &GeomDb,
    grid: &Mesh,
    wall: &[String],
    opts: &ClassifyOptions,
) -> Result<Mesh> {
    let nc = db.surface_components.len();
    let tol = opts.rel_tol * db.reference_length();
    let mut per: Vec<Elements> = (0..nc).map(|_| Elements::new()).collect();
    let projectors = component_projectors(db)?;
    let mut markers = Vec::new();
    for name in wall {
        let m = grid.marker(name).ok_or_else(|| Error::MissingMarker {
            marker: name.clone(),
            available: grid.markers.iter().map(|m| m.name.clone()).collect(),
        })?;
        for g in m.elements.groups() {
            if g.kind != ElementKind::Triangle {
                return Err(Error::WallElements {
                    marker: name.clone(),
                    kind: g.kind,
                });
            }
        }
        markers.push(m);
    }
    // every wall node's distance from every component (infinite where none converged)
    let mut nodes: Vec<u32> = markers.iter().flat_map(|m| m.elements.node_set()).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let dist: Vec<Vec<f64>> = nodes
        .par_iter()
        .map(|&v| {
            let c = grid.coords[v as usize];
            let p = Point3::new(c[0], c[1], c[2]);
            projectors
                .iter()
                .map(|pr| match pr.project(&p) {
                    Ok(f) => Ok(f.distance),
                    Err(intersect::Error::ProjectionFailed { .. }) => Ok(f64::INFINITY),
                    Err(e) => Err(Error::from(e)),
                })
                .collect::<Result<Vec<f64>>>()
        })
        .collect::<Result<_>>()?;
    let on = |v: u32, k: usize| dist[nodes.binary_search(&v).expect("wall node")][k] <= tol;
    for (m, name) in markers.iter().zip(wall) {
        let g = m.elements.group(ElementKind::Triangle);
        let tris: Vec<&[u32]> = g.map(|g| g.iter().collect()).unwrap_or_default();
        let comps = tris
            .par_iter()
            .map(|t| {
                let cands: Vec<usize> = (0..nc).filter(|&k| t.iter().all(|&v| on(v, k))).collect();
                match cands.as_slice() {
                    [k] => Ok(SurfCompId::from_index(*k)),
                    _ => nearest_component(&projectors, grid, t, name),
                }
            })
            .collect::<Result<Vec<_>>>()?;
        for (t, c) in tris.into_iter().zip(comps) {
            per[c.index()].push(ElementKind::Triangle, t, None);
        }
    }
    let mut s = Mesh::new(3);
    s.coords = grid.coords.clone();
    s.markers = per
        .into_iter()
        .enumerate()
        .filter(|(_, e)| !e.is_empty())
        .map(|(k, elements)| Marker {
            name: marker_name(db, SurfCompId::from_index(k)),
            tag: None,
            elements,
        })
        .collect();
    Ok(s)
}

/// The surface component (of the projectors' database, see [`component_projectors`]) whose
/// support surface is nearest (Eq. 11) to the centroid of the triangle `t` of `grid`, among
/// those whose projection converges (a projection that fails, e.g. a Newton stalled on a
/// surface far from the point, only rules its component out); the first one on a tie. When
/// none converges the error names the triangle's first node, `marker` and every
/// component's residual.
pub fn nearest_component(
    projectors: &ComponentProjectors<'_>,
    grid: &Mesh,
    t: &[u32],
    marker: &str,
) -> Result<SurfCompId> {
    let mut c = [0.0; 3];
    for &v in t {
        for k in 0..3 {
            c[k] += grid.coords[v as usize][k] / t.len() as f64;
        }
    }
    let p = Point3::new(c[0], c[1], c[2]);
    let mut best: Option<(f64, usize)> = None;
    let mut attempts = Vec::new();
    for (k, pr) in projectors.iter().enumerate() {
        match pr.project(&p) {
            Ok(f) => {
                if best.is_none_or(|b| f.distance < b.0) {
                    best = Some((f.distance, k));
                }
            }
            Err(intersect::Error::ProjectionFailed { residual, .. }) => {
                attempts.push((pr.label().to_string(), residual));
            }
            Err(e) => return Err(e.into()),
        }
    }
    best.map(|b| SurfCompId::from_index(b.1))
        .ok_or_else(|| Error::NoComponent {
            marker: marker.to_string(),
            node: t.first().map_or(0, |&v| v as usize),
            attempts,
        })
}

/// The wall of a volume grid (the markers named in `wall`) tied to the geometry:
/// [`wall_surface`] then [`classify`]. The returned grid numbers its nodes as `grid` does;
/// the nodes of no wall marker are [`NodeSupport::Free`](crate::NodeSupport::Free).
pub fn classify_wall(
    db: &GeomDb,
    grid: &Mesh,
    wall: &[String],
    opts: &ClassifyOptions,
) -> Result<(SurfaceGrid, ClassifyReport)> {
    classify(&wall_surface(db, grid, wall, opts)?, db, opts)
}
