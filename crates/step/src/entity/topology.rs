//! Topology (ISO 10303-42 topology schema) and the B-rep shape models.

/// `VERTEX_POINT(name, vertex_geometry)`.
#[derive(Debug, Clone, PartialEq)]
pub struct VertexPoint {
    /// A `CARTESIAN_POINT`.
    pub point: crate::Id,
}

/// `EDGE_CURVE(name, edge_start, edge_end, edge_geometry, same_sense)`.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeCurve {
    /// `VERTEX_POINT` at the start.
    pub start: crate::Id,
    /// `VERTEX_POINT` at the end.
    pub end: crate::Id,
    /// The curve (a `SURFACE_CURVE`, `SEAM_CURVE`, line, B-spline, …).
    pub curve: crate::Id,
    /// True when the edge runs in the curve's direction.
    pub same_sense: bool,
}

/// `ORIENTED_EDGE(name, *, *, edge_element, orientation)`.
#[derive(Debug, Clone, PartialEq)]
pub struct OrientedEdge {
    /// The `EDGE_CURVE`.
    pub edge: crate::Id,
    /// True when the loop runs along the edge's direction.
    pub orientation: bool,
}

/// `EDGE_LOOP(name, edge_list)`.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeLoop {
    /// `ORIENTED_EDGE`s in loop order.
    pub edges: Vec<crate::Id>,
}

/// `VERTEX_LOOP(name, loop_vertex)`: a loop of one vertex (the pole of a sphere).
#[derive(Debug, Clone, PartialEq)]
pub struct VertexLoop {
    /// The `VERTEX_POINT`.
    pub vertex: crate::Id,
}

/// `FACE_BOUND` / `FACE_OUTER_BOUND(name, bound, orientation)`.
#[derive(Debug, Clone, PartialEq)]
pub struct FaceBound {
    /// The loop (`EDGE_LOOP`, `VERTEX_LOOP`, `POLY_LOOP`).
    pub bound: crate::Id,
    /// False when the loop is used reversed.
    pub orientation: bool,
    /// True for `FACE_OUTER_BOUND`.
    pub outer: bool,
}

/// `ADVANCED_FACE` / `FACE_SURFACE(name, bounds, face_geometry, same_sense)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Face {
    /// `FACE_BOUND`s.
    pub bounds: Vec<crate::Id>,
    /// The surface.
    pub surface: crate::Id,
    /// True when the face normal is the surface's S_u × S_v.
    pub same_sense: bool,
}

/// `CLOSED_SHELL` / `OPEN_SHELL(name, cfs_faces)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Shell {
    /// The faces.
    pub faces: Vec<crate::Id>,
    /// True for `CLOSED_SHELL`.
    pub closed: bool,
}

/// `ORIENTED_CLOSED_SHELL` / `ORIENTED_OPEN_SHELL(name, *, shell_element, orientation)`.
#[derive(Debug, Clone, PartialEq)]
pub struct OrientedShell {
    /// The shell.
    pub shell: crate::Id,
    /// False when every face is reversed.
    pub orientation: bool,
}

/// `MANIFOLD_SOLID_BREP(name, outer)` and `BREP_WITH_VOIDS(name, outer, voids)`.
#[derive(Debug, Clone, PartialEq)]
pub struct ManifoldSolidBrep {
    /// The outer `CLOSED_SHELL`.
    pub outer: crate::Id,
    /// Void shells (`ORIENTED_CLOSED_SHELL`s).
    pub voids: Vec<crate::Id>,
}

/// `SHELL_BASED_SURFACE_MODEL(name, sbsm_boundary)`.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellBasedSurfaceModel {
    /// Open or closed shells.
    pub shells: Vec<crate::Id>,
}
