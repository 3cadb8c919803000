//! The surface grid tied to the geometry: every node knows its support entity and its
//! parameters there; every surface component keeps its own parametric triangulation (local
//! nodes with (u, v); a node on a seam appears twice, once per side).

use geom_db::eval::{ParamCurve, ParamSurface};
use geom_db::prelude::Point3;
use geom_db::{CornerId, CurveCompId, GeomDb, SurfCompId};
use mesh::{ElementKind, Elements, Marker, Mesh, NodeClass};

use crate::pole::{Domain, Side, pole_copy_uv};

/// Where a node lies and its parameters there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NodeSupport {
    /// On a corner.
    Corner(CornerId),
    /// On a curve component, at global support-curve parameter `t`.
    Curve {
        /// The curve component.
        comp: CurveCompId,
        /// Global parameter on the component's support curve.
        t: f64,
    },
    /// Inside a surface component, at global parameters (u, v) of its support surface.
    Surface {
        /// The surface component.
        comp: SurfCompId,
        /// Global parameters.
        uv: [f64; 2],
    },
    /// Not on the geometry (a node of an imported grid used by no marker, e.g. a volume
    /// node); it keeps its position.
    Free,
}

/// The parametric triangulation of one surface component.
#[derive(Debug, Clone, PartialEq)]
pub struct ComponentGrid {
    /// The surface component.
    pub comp: SurfCompId,
    /// Local node → global node.
    pub nodes: Vec<u32>,
    /// Local node parameters (u, v) on the component's support surface.
    pub uv: Vec<[f64; 2]>,
    /// Local nodes `0..n_boundary` lie on the boundary loops (curve or corner nodes).
    pub n_boundary: usize,
    /// Triangles (local nodes), counter-clockwise in the (u, v) plane.
    pub triangles: Vec<[u32; 3]>,
    /// True when the inward normal is −r_u × r_v: output triangles are then reversed so
    /// that every triangle is positively oriented with respect to the inward normal.
    pub flip: bool,
    /// Local nodes that are copies of a pole (a node on a degenerate side of the parameter
    /// rectangle, see [`crate::pole`]): one copy per triangle of the pole's fan, each a
    /// boundary local node. Empty for a component without poles.
    pub pole_copies: Vec<PoleCopy>,
}

/// A local copy of a pole in a component grid: the local node and the degenerate side it
/// lies on. Its (u, v) follows the convention of [`crate::pole::pole_copy_uv`]: on the side,
/// along-side coordinate the mean of the two other vertices of its (only) triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoleCopy {
    /// The local node.
    pub local: u32,
    /// The degenerate side.
    pub side: Side,
}

impl ComponentGrid {
    /// Sets the (u, v) of every pole copy by the convention (on its side, along-side
    /// coordinate the mean of its triangle's two other vertices'); `dom` is the support
    /// surface's parameter rectangle.
    pub fn refresh_pole_copies(&mut self, dom: Domain) {
        if self.pole_copies.is_empty() {
            return;
        }
        let mut side_of = vec![None; self.uv.len()];
        for pc in &self.pole_copies {
            side_of[pc.local as usize] = Some(pc.side);
        }
        for t in &self.triangles {
            for i in 0..3 {
                if let Some(side) = side_of[t[i] as usize] {
                    let (a, b) = (
                        self.uv[t[(i + 1) % 3] as usize],
                        self.uv[t[(i + 2) % 3] as usize],
                    );
                    self.uv[t[i] as usize] = pole_copy_uv(side, dom, a, b);
                }
            }
        }
    }

    /// Marks the pole copies (true at their local index).
    pub fn pole_mask(&self) -> Vec<bool> {
        let mut m = vec![false; self.uv.len()];
        for pc in &self.pole_copies {
            m[pc.local as usize] = true;
        }
        m
    }

    /// Triangles in global node numbers, oriented positively w.r.t. the inward normal.
    pub fn global_triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.triangles.iter().map(|t| {
            let g = t.map(|v| self.nodes[v as usize]);
            if self.flip { [g[0], g[2], g[1]] } else { g }
        })
    }
}

/// A surface grid: nodes with their support, curve discretisations and component grids.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceGrid {
    /// Node positions.
    pub coords: Vec<Point3>,
    /// Node supports (same length as `coords`).
    pub support: Vec<NodeSupport>,
    /// Per curve component, its nodes from start to end (empty when not discretised).
    pub curve_nodes: Vec<Vec<u32>>,
    /// The component grids.
    pub components: Vec<ComponentGrid>,
}

impl SurfaceGrid {
    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.coords.len()
    }

    /// Number of triangles.
    pub fn n_triangles(&self) -> usize {
        self.components.iter().map(|c| c.triangles.len()).sum()
    }

    /// The position of node `i` evaluated on its support in `db` (Eq. 2 / Eq. 7 at the
    /// node's parameters).
    pub fn evaluate_node(&self, db: &GeomDb, i: usize) -> Point3 {
        match self.support[i] {
            NodeSupport::Corner(c) => db.corner(c).point,
            NodeSupport::Curve { comp, t } => db.curve(db.curve_component(comp).curve).point(t),
            NodeSupport::Surface { comp, uv } => db
                .surface(db.surface_component(comp).surface)
                .point(uv[0], uv[1]),
            NodeSupport::Free => self.coords[i],
        }
    }

    /// The grid as a `mesh::Mesh`: a 3-D grid without cells whose markers hold each surface
    /// component's triangles (named after the component, or "component k"), with nodes
    /// classified as Gmsh does: corner k → (0, k+1), curve component k → (1, k+1, [t, 0]),
    /// surface component k → (2, k+1, [u, v]). Tags are ids + 1 because Gmsh tags are
    /// positive. Writable as MSH 4.1 with parametric nodes, SU2 or VTU by `mesh`.
    pub fn to_mesh(&self, db: &GeomDb) -> Mesh {
        let mut m = Mesh::new(3);
        m.coords = self.coords.iter().map(|p| [p.x, p.y, p.z]).collect();
        m.markers = self
            .components
            .iter()
            .map(|c| {
                let mut el = Elements::new();
                for t in c.global_triangles() {
                    el.push(ElementKind::Triangle, &t, None);
                }
                Marker {
                    name: marker_name(db, c.comp),
                    tag: None,
                    elements: el,
                }
            })
            .collect();
        m.classes = Some(self.to_mesh_classes());
        m.parametric = true;
        m
    }

    /// The volume grid `grid` (whose wall this grid is: same node numbering) with its cells
    /// and markers (names kept) and this grid's classification: wall nodes snapped onto
    /// their entity and classified as in [`to_mesh`](Self::to_mesh) (corner k → (0, k+1),
    /// curve component k → (1, k+1, [t, 0]), surface component k → (2, k+1, [u, v])), the
    /// other nodes in the volume (3, 1). The mesher's entities, entity tags and physical
    /// names are dropped (their numbering is not the database's); the MSH writer makes one
    /// entity per marker. Writable as MSH 4.1 with parametric nodes.
    pub fn volume_with_params(&self, grid: &Mesh) -> Mesh {
        let mut m = grid.clone();
        let classes = self.to_mesh_classes();
        for (i, c) in classes.iter().enumerate() {
            if c.dim < 3 {
                let p = self.coords[i];
                m.coords[i] = [p.x, p.y, p.z];
            }
        }
        m.classes = Some(classes);
        m.parametric = true;
        m.entities.clear();
        m.physical_names.clear();
        for g in m.cells.groups_mut() {
            g.entity.clear();
        }
        for mk in &mut m.markers {
            for g in mk.elements.groups_mut() {
                g.entity.clear();
            }
        }
        m
    }

    /// The Gmsh-like classification of every node (see [`to_mesh`](Self::to_mesh)).
    fn to_mesh_classes(&self) -> Vec<NodeClass> {
        self.support
            .iter()
            .map(|s| match *s {
                NodeSupport::Corner(c) => NodeClass {
                    dim: 0,
                    entity: c.0 as i32 + 1,
                    param: [0.0, 0.0],
                },
                NodeSupport::Curve { comp, t } => NodeClass {
                    dim: 1,
                    entity: comp.0 as i32 + 1,
                    param: [t, 0.0],
                },
                NodeSupport::Surface { comp, uv } => NodeClass {
                    dim: 2,
                    entity: comp.0 as i32 + 1,
                    param: uv,
                },
                NodeSupport::Free => NodeClass {
                    dim: 3,
                    entity: 1,
                    param: [0.0, 0.0],
                },
            })
            .collect()
    }

    /// Writes the parameters of this grid's nodes into the classification of a grid with the
    /// same node numbering (e.g. the volume grid whose wall this grid is, after an update):
    /// a node classified on a curve gets [t, 0], one on a surface (u, v), when its support
    /// here is of the same dimension; other nodes, and grids without parametric
    /// classification, are left as they are.
    pub fn write_params(&self, grid: &mut Mesh) {
        if let (Some(cls), true) = (grid.classes.as_mut(), grid.parametric) {
            for (c, s) in cls.iter_mut().zip(&self.support) {
                match *s {
                    NodeSupport::Curve { t, .. } if c.dim == 1 => c.param = [t, 0.0],
                    NodeSupport::Surface { uv, .. } if c.dim == 2 => c.param = uv,
                    _ => {}
                }
            }
        }
    }
}

/// The marker name of a surface component: its name, or "component k" when it has none.
pub fn marker_name(db: &GeomDb, c: SurfCompId) -> String {
    let name = &db.surface_component(c).name;
    if name.is_empty() {
        format!("component {}", c.0)
    } else {
        name.clone()
    }
}
