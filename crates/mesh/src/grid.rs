//! The grid types: nodes as a structure of arrays, elements stored per kind as flat
//! connectivity arrays, boundary markers, Gmsh-like node classification and MSH entities.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The element kinds this crate stores. The declaration order is the canonical order in
/// which element groups are kept and written (and so defines global element ids).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum ElementKind {
    /// 2-node line (boundary of 2D grids).
    Line,
    /// 3-node triangle.
    Triangle,
    /// 4-node quadrilateral.
    Quad,
    /// 4-node tetrahedron.
    Tetra,
    /// 5-node pyramid (quadrilateral base 0-3, apex 4; the base's right-hand normal points
    /// towards the apex, as in VTK, SU2 and Gmsh).
    Pyramid,
    /// 6-node prism (wedge): triangle 0-2 and triangle 3-5, with edges 0-3, 1-4, 2-5. VTK's
    /// and SU2's order: the right-hand normal of 0-1-2 points *away* from 3-4-5. Gmsh's
    /// order is the other one (nodes 1 and 2, 4 and 5 swapped); [`ElementKind::gmsh_order`].
    Prism,
    /// 8-node hexahedron: face 0-3 and face 4-7 (edges 0-4, 1-5, 2-6, 3-7); the right-hand
    /// normal of 0-1-2-3 points towards 4-7, as in VTK, SU2 and Gmsh.
    Hexa,
}

/// All kinds, in canonical order.
pub const ALL_KINDS: [ElementKind; 7] = [
    ElementKind::Line,
    ElementKind::Triangle,
    ElementKind::Quad,
    ElementKind::Tetra,
    ElementKind::Pyramid,
    ElementKind::Prism,
    ElementKind::Hexa,
];

impl ElementKind {
    /// Number of nodes of one element.
    pub const fn n_nodes(self) -> usize {
        match self {
            ElementKind::Line => 2,
            ElementKind::Triangle => 3,
            ElementKind::Quad => 4,
            ElementKind::Tetra => 4,
            ElementKind::Pyramid => 5,
            ElementKind::Prism => 6,
            ElementKind::Hexa => 8,
        }
    }

    /// Topological dimension (1, 2 or 3).
    pub const fn dim(self) -> u8 {
        match self {
            ElementKind::Line => 1,
            ElementKind::Triangle | ElementKind::Quad => 2,
            _ => 3,
        }
    }

    /// The VTK cell type, which SU2 uses as its element code.
    pub const fn vtk_code(self) -> u8 {
        match self {
            ElementKind::Line => 3,
            ElementKind::Triangle => 5,
            ElementKind::Quad => 9,
            ElementKind::Tetra => 10,
            ElementKind::Hexa => 12,
            ElementKind::Prism => 13,
            ElementKind::Pyramid => 14,
        }
    }

    /// The kind of a VTK / SU2 element code.
    pub fn from_vtk_code(code: i64) -> Option<Self> {
        ALL_KINDS
            .into_iter()
            .find(|k| i64::from(k.vtk_code()) == code)
    }

    /// The Gmsh MSH element type.
    pub const fn gmsh_code(self) -> i32 {
        match self {
            ElementKind::Line => 1,
            ElementKind::Triangle => 2,
            ElementKind::Quad => 3,
            ElementKind::Tetra => 4,
            ElementKind::Hexa => 5,
            ElementKind::Prism => 6,
            ElementKind::Pyramid => 7,
        }
    }

    /// The kind of a Gmsh MSH element type (first-order types only).
    pub fn from_gmsh_code(code: i64) -> Option<Self> {
        ALL_KINDS
            .into_iter()
            .find(|k| i64::from(k.gmsh_code()) == code)
    }

    /// Gmsh's local node numbers in this crate's order: node `i` of an element here is node
    /// `gmsh_order()[i]` of the same element in a Gmsh file. The identity except for the
    /// prism, whose Gmsh numbering puts the right-hand normal of 0-1-2 towards 3-4-5 (Gmsh's
    /// reference prism: (0,0,0), (1,0,0), (0,1,0), then the same at z = 1) where VTK and
    /// SU2 (this crate's order) put it away: `[0, 2, 1, 3, 5, 4]`, its own inverse.
    ///
    /// ```
    /// use mesh::ElementKind;
    /// assert_eq!(ElementKind::Prism.gmsh_order(), &[0, 2, 1, 3, 5, 4]);
    /// assert_eq!(ElementKind::Hexa.gmsh_order(), &[0, 1, 2, 3, 4, 5, 6, 7]);
    /// ```
    pub const fn gmsh_order(self) -> &'static [u8] {
        match self {
            ElementKind::Line => &[0, 1],
            ElementKind::Triangle => &[0, 1, 2],
            ElementKind::Quad | ElementKind::Tetra => &[0, 1, 2, 3],
            ElementKind::Pyramid => &[0, 1, 2, 3, 4],
            ElementKind::Prism => &[0, 2, 1, 3, 5, 4],
            ElementKind::Hexa => &[0, 1, 2, 3, 4, 5, 6, 7],
        }
    }

    /// The element's edges as pairs of local node numbers (this crate's numbering, which is
    /// VTK's and SU2's; see [`ElementKind::gmsh_order`] for Gmsh's).
    pub const fn edges(self) -> &'static [[u8; 2]] {
        match self {
            ElementKind::Line => &[[0, 1]],
            ElementKind::Triangle => &[[0, 1], [1, 2], [2, 0]],
            ElementKind::Quad => &[[0, 1], [1, 2], [2, 3], [3, 0]],
            ElementKind::Tetra => &[[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]],
            ElementKind::Pyramid => &[
                [0, 1],
                [1, 2],
                [2, 3],
                [3, 0],
                [0, 4],
                [1, 4],
                [2, 4],
                [3, 4],
            ],
            ElementKind::Prism => &[
                [0, 1],
                [1, 2],
                [2, 0],
                [3, 4],
                [4, 5],
                [5, 3],
                [0, 3],
                [1, 4],
                [2, 5],
            ],
            ElementKind::Hexa => &[
                [0, 1],
                [1, 2],
                [2, 3],
                [3, 0],
                [4, 5],
                [5, 6],
                [6, 7],
                [7, 4],
                [0, 4],
                [1, 5],
                [2, 6],
                [3, 7],
            ],
        }
    }

    /// A lower-case name ("tetra", "triangle", ...).
    pub const fn name(self) -> &'static str {
        match self {
            ElementKind::Line => "line",
            ElementKind::Triangle => "triangle",
            ElementKind::Quad => "quad",
            ElementKind::Tetra => "tetra",
            ElementKind::Pyramid => "pyramid",
            ElementKind::Prism => "prism",
            ElementKind::Hexa => "hexa",
        }
    }
}

/// All elements of one kind: flat connectivity (`n_nodes()` node indices per element) and,
/// optionally, the MSH entity tag of each element.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ElementGroup {
    /// The kind of every element of the group.
    pub kind: ElementKind,
    /// Node indices (0-based), `kind.n_nodes()` per element.
    pub nodes: Vec<u32>,
    /// Entity tag per element (Gmsh), or empty when the grid has no entities.
    pub entity: Vec<i32>,
}

impl ElementGroup {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.nodes.len() / self.kind.n_nodes()
    }

    /// True when the group holds no element.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The nodes of element `i` of the group.
    pub fn element(&self, i: usize) -> &[u32] {
        let n = self.kind.n_nodes();
        &self.nodes[i * n..(i + 1) * n]
    }

    /// Iterator over the elements' node lists.
    pub fn iter(&self) -> std::slice::ChunksExact<'_, u32> {
        self.nodes.chunks_exact(self.kind.n_nodes())
    }
}

/// A set of elements of mixed kinds, kept as one [`ElementGroup`] per kind in canonical
/// kind order. Element `e` of the set is numbered by that order: all lines, then all
/// triangles, quads, tetrahedra, pyramids, prisms, hexahedra.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Elements {
    groups: Vec<ElementGroup>,
}

impl Elements {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// The groups, in canonical kind order, without empty groups.
    pub fn groups(&self) -> &[ElementGroup] {
        &self.groups
    }

    /// Mutable access to the groups (the caller keeps connectivity lengths consistent).
    pub fn groups_mut(&mut self) -> &mut [ElementGroup] {
        &mut self.groups
    }

    /// The group of one kind, if present.
    pub fn group(&self, kind: ElementKind) -> Option<&ElementGroup> {
        self.groups.iter().find(|g| g.kind == kind)
    }

    /// The group of one kind, created empty if absent.
    pub fn group_mut(&mut self, kind: ElementKind) -> &mut ElementGroup {
        let pos = match self.groups.binary_search_by(|g| g.kind.cmp(&kind)) {
            Ok(p) => p,
            Err(p) => {
                self.groups.insert(
                    p,
                    ElementGroup {
                        kind,
                        nodes: Vec::new(),
                        entity: Vec::new(),
                    },
                );
                p
            }
        };
        &mut self.groups[pos]
    }

    /// Appends an element. `entity` is recorded when given; a group mixing elements with and
    /// without entity is reported by [`crate::Mesh::validate`].
    pub fn push(&mut self, kind: ElementKind, nodes: &[u32], entity: Option<i32>) {
        debug_assert_eq!(nodes.len(), kind.n_nodes());
        let g = self.group_mut(kind);
        g.nodes.extend_from_slice(nodes);
        if let Some(e) = entity {
            g.entity.push(e);
        }
    }

    /// Removes empty groups (after bulk edits through [`Elements::group_mut`]).
    pub fn prune(&mut self) {
        self.groups.retain(|g| !g.is_empty());
    }

    /// Total number of elements.
    pub fn len(&self) -> usize {
        self.groups.iter().map(ElementGroup::len).sum()
    }

    /// True when there is no element.
    pub fn is_empty(&self) -> bool {
        self.groups.iter().all(ElementGroup::is_empty)
    }

    /// Number of elements of one kind.
    pub fn count(&self, kind: ElementKind) -> usize {
        self.group(kind).map_or(0, ElementGroup::len)
    }

    /// The kind of element `id` (canonical order), or `None` past the end.
    ///
    /// ```
    /// use mesh::{ElementKind, Elements};
    /// let mut e = Elements::new();
    /// e.push(ElementKind::Prism, &[0, 1, 2, 3, 4, 5], None);
    /// e.push(ElementKind::Tetra, &[0, 1, 2, 3], None);
    /// assert_eq!(e.kind_of(0), Some(ElementKind::Tetra));
    /// assert_eq!(e.kind_of(1), Some(ElementKind::Prism));
    /// assert_eq!(e.kind_of(2), None);
    /// ```
    pub fn kind_of(&self, id: usize) -> Option<ElementKind> {
        let mut at = 0;
        for g in &self.groups {
            at += g.len();
            if id < at {
                return Some(g.kind);
            }
        }
        None
    }

    /// Iterator over `(kind, nodes)` of every element in canonical order.
    pub fn iter(&self) -> impl Iterator<Item = (ElementKind, &[u32])> + '_ {
        self.groups
            .iter()
            .flat_map(|g| g.iter().map(move |e| (g.kind, e)))
    }

    /// The distinct nodes used by the set, sorted.
    pub fn node_set(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self
            .groups
            .iter()
            .flat_map(|g| g.nodes.iter().copied())
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }
}

/// A named group of boundary elements (SU2 marker, Gmsh physical group of dimension
/// `dim - 1`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// The marker name (SU2 `MARKER_TAG`, Gmsh physical name).
    pub name: String,
    /// The Gmsh physical tag, when the grid came from (or is written to) MSH.
    pub tag: Option<i32>,
    /// The boundary elements (lines in 2D, triangles and quads in 3D).
    pub elements: Elements,
}

/// Classification of a node on the geometric entity it lies on, as Gmsh does.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NodeClass {
    /// Entity dimension: 0 corner, 1 curve, 2 surface, 3 volume.
    pub dim: u8,
    /// Entity tag (id).
    pub entity: i32,
    /// Parametric coordinates: `[u, 0]` on a curve, `[u, v]` on a surface, unused otherwise.
    pub param: [f64; 2],
}

/// A Gmsh model entity (point, curve, surface or volume) as listed in `$Entities`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Entity {
    /// Dimension 0..=3.
    pub dim: u8,
    /// Tag.
    pub tag: i32,
    /// Bounding box `[min x, min y, min z, max x, max y, max z]`; for a point, its
    /// coordinates twice.
    pub bbox: [f64; 6],
    /// Physical group tags the entity belongs to.
    pub physical: Vec<i32>,
    /// Signed tags of the bounding entities of dimension `dim - 1` (empty for points).
    pub bounding: Vec<i32>,
}

/// A Gmsh physical group name.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PhysicalName {
    /// Dimension of the group.
    pub dim: u8,
    /// Physical tag.
    pub tag: i32,
    /// Name.
    pub name: String,
}

/// An unstructured grid.
///
/// Nodes are a structure of arrays (`coords`, optional `classes`); volume elements (the
/// cells: tetrahedra, pyramids, prisms, hexahedra in 3D; triangles and quads in 2D) are
/// held per kind in [`Elements`]; boundary elements are grouped by [`Marker`]. Node and
/// element indices are 0-based `u32`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Mesh {
    /// Spatial dimension of the grid (2 or 3). 2D grids have z = 0.
    pub dim: u8,
    /// Node coordinates.
    pub coords: Vec<[f64; 3]>,
    /// Cells: elements of dimension `dim`.
    pub cells: Elements,
    /// Boundary markers: elements of dimension `dim - 1`.
    pub markers: Vec<Marker>,
    /// Node classification, one per node, when known (MSH input; none from SU2).
    pub classes: Option<Vec<NodeClass>>,
    /// True when curve and surface nodes carry parametric coordinates (MSH
    /// `parametric = 1`).
    pub parametric: bool,
    /// Gmsh entities, when the grid came from MSH.
    pub entities: Vec<Entity>,
    /// Gmsh physical names (all dimensions), when the grid came from MSH.
    pub physical_names: Vec<PhysicalName>,
    /// Unknown trailing sections of an SU2 file (e.g. FFD boxes), kept verbatim.
    pub su2_extra: String,
    /// The OpenFOAM case the grid was read from ([`crate::foam::read`]), which
    /// [`crate::foam::write`] writes back with new points.
    #[serde(default)]
    pub foam: Option<Box<crate::foam::Source>>,
    /// Non-fatal remarks made while reading (skipped sections, dropped elements).
    pub warnings: Vec<String>,
}

impl Mesh {
    /// An empty grid of dimension `dim`.
    pub fn new(dim: u8) -> Self {
        Mesh {
            dim,
            ..Default::default()
        }
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.coords.len()
    }

    /// The tetrahedra (empty slice when there are none).
    pub fn tets(&self) -> &[[u32; 4]] {
        self.cells
            .group(ElementKind::Tetra)
            .map_or(&[][..], |g| g.nodes.as_chunks::<4>().0)
    }

    /// The triangles among the cells (2D grids).
    pub fn triangles(&self) -> &[[u32; 3]] {
        self.cells
            .group(ElementKind::Triangle)
            .map_or(&[][..], |g| g.nodes.as_chunks::<3>().0)
    }

    /// The marker called `name`.
    pub fn marker(&self, name: &str) -> Option<&Marker> {
        self.markers.iter().find(|m| m.name == name)
    }

    /// Axis-aligned bounding box `(min, max)` of the nodes (zeros for an empty grid).
    pub fn bbox(&self) -> ([f64; 3], [f64; 3]) {
        if self.coords.is_empty() {
            return ([0.0; 3], [0.0; 3]);
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.coords {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// Length of the diagonal of [`Mesh::bbox`] (the grid's size, for relative tolerances).
    pub fn bbox_diagonal(&self) -> f64 {
        let (lo, hi) = self.bbox();
        ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt()
    }

    /// Checks the invariants: dimension 2 or 3, at most [`crate::adjacency::MAX_ELEMENTS`]
    /// cells, node indices in range, cells of dimension
    /// `dim`, marker elements of dimension `dim - 1`, entity arrays empty or one per
    /// element, classification one per node with dimension ≤ 3, finite coordinates.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(Error::Invalid { what });
        if self.dim != 2 && self.dim != 3 {
            return bad(format!("dimension {} (expected 2 or 3)", self.dim));
        }
        crate::adjacency::check_element_count(self.cells.len())?;
        let n = self.coords.len();
        if let Some((i, _)) = self
            .coords
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|x| !x.is_finite()))
        {
            return bad(format!("node {i} has a non-finite coordinate"));
        }
        let check_set = |set: &Elements, what: &str, dim: u8| -> Result<()> {
            for g in set.groups() {
                if g.kind.dim() != dim {
                    return bad(format!(
                        "{what}: {} elements in a {}-D grid",
                        g.kind.name(),
                        self.dim
                    ));
                }
                if !g.nodes.len().is_multiple_of(g.kind.n_nodes()) {
                    return bad(format!("{what}: {} connectivity length", g.kind.name()));
                }
                if !g.entity.is_empty() && g.entity.len() != g.len() {
                    return bad(format!(
                        "{what}: {} entity tags for {} {} elements",
                        g.entity.len(),
                        g.len(),
                        g.kind.name()
                    ));
                }
                if let Some(pos) = g.nodes.iter().position(|&v| v as usize >= n) {
                    return bad(format!(
                        "{what}: {} element {} refers to node {} (grid has {n} nodes)",
                        g.kind.name(),
                        pos / g.kind.n_nodes(),
                        g.nodes[pos]
                    ));
                }
            }
            Ok(())
        };
        check_set(&self.cells, "cells", self.dim)?;
        for m in &self.markers {
            check_set(&m.elements, &format!("marker {}", m.name), self.dim - 1)?;
        }
        if let Some(c) = &self.classes {
            if c.len() != n {
                return bad(format!("{} node classes for {n} nodes", c.len()));
            }
            if let Some(i) = c.iter().position(|c| c.dim > 3) {
                return bad(format!("node {i} classified on dimension {}", c[i].dim));
            }
        }
        Ok(())
    }

    /// Renumbers the nodes: node `i` becomes node `perm[i]`. Coordinates, classification,
    /// cells and markers follow; element order is unchanged.
    pub fn renumber_nodes(&mut self, perm: &[u32]) -> Result<()> {
        let n = self.coords.len();
        if perm.len() != n {
            return Err(Error::Invalid {
                what: format!("permutation of length {} for {n} nodes", perm.len()),
            });
        }
        let mut seen = vec![false; n];
        for &p in perm {
            let p = p as usize;
            if p >= n || seen[p] {
                return Err(Error::Invalid {
                    what: format!("not a permutation (entry {p})"),
                });
            }
            seen[p] = true;
        }
        let mut coords = vec![[0.0; 3]; n];
        for (i, &p) in perm.iter().enumerate() {
            coords[p as usize] = self.coords[i];
        }
        self.coords = coords;
        if let Some(c) = &self.classes {
            let mut out = c.clone();
            for (i, &p) in perm.iter().enumerate() {
                out[p as usize] = c[i];
            }
            self.classes = Some(out);
        }
        let remap = |set: &mut Elements| {
            for g in set.groups_mut() {
                for v in &mut g.nodes {
                    *v = perm[*v as usize];
                }
            }
        };
        remap(&mut self.cells);
        for m in &mut self.markers {
            remap(&mut m.elements);
        }
        Ok(())
    }
}
