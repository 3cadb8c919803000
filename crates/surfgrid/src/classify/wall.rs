//! The wall of a volume grid tied to the geometry: its markers' triangles split by surface
//! component ([`wall_surface`]: by the element's entity tag when the grid carries one, as an
//! MSH does, else by the component nearest to the triangle's centroid, Eq. 11), then
//! classified ([`classify_wall`]).

use geom_db::prelude::Point3;
use geom_db::{GeomDb, SupportSurface, SurfCompId};
use intersect::project::{ProjectOptions, SurfaceProjector};
use mesh::{ElementKind, Elements, Marker, Mesh};

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
/// [`marker_name`]), ready for [`classify`]. A triangle's component is its element entity
/// tag − 1 when the grid carries entity tags (MSH), else the component whose support
/// surface is nearest to its centroid ([`nearest_component`]).
pub fn wall_surface(db: &GeomDb, grid: &Mesh, wall: &[String]) -> Result<Mesh> {
    let nc = db.surface_components.len();
    let mut per: Vec<Elements> = (0..nc).map(|_| Elements::new()).collect();
    let mut projectors = None;
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
            for (e, t) in g.iter().enumerate() {
                let tagged = g
                    .entity
                    .get(e)
                    .and_then(|&k| usize::try_from(k - 1).ok())
                    .filter(|&k| k < nc);
                let comp = match tagged {
                    Some(k) => k,
                    None => {
                        let pr = match &mut projectors {
                            Some(p) => p,
                            None => projectors.insert(component_projectors(db)?),
                        };
                        nearest_component(pr, grid, t)?.index()
                    }
                };
                per[comp].push(ElementKind::Triangle, t, None);
            }
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
/// support surface is nearest (Eq. 11) to the centroid of the triangle `t` of `grid`; the
/// first one on a tie.
pub fn nearest_component(
    projectors: &ComponentProjectors<'_>,
    grid: &Mesh,
    t: &[u32],
) -> Result<SurfCompId> {
    let mut c = [0.0; 3];
    for &v in t {
        for k in 0..3 {
            c[k] += grid.coords[v as usize][k] / 3.0;
        }
    }
    let p = Point3::new(c[0], c[1], c[2]);
    let mut best = (f64::INFINITY, 0);
    for (k, pr) in projectors.iter().enumerate() {
        let f = pr.project(&p)?;
        if f.distance < best.0 {
            best = (f.distance, k);
        }
    }
    Ok(SurfCompId::from_index(best.1))
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
    classify(&wall_surface(db, grid, wall)?, db, opts)
}
