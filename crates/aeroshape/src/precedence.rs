//! Precedence of boundary conditions where markers meet: a node on a fixed marker (named
//! `fixed`, or named nowhere) never moves, even where the marker meets a sliding one (the
//! far-field box's edge on the symmetry plane). `deform` alone would let such a node slide
//! along the seam; holding it is done by prescribing it a zero displacement, which takes
//! precedence over sliding in `deform` ([`held_nodes`]). A node on two sliding markers keeps
//! to both (their intersection), as `deform` does by itself.

use std::collections::BTreeSet;

use mesh::Mesh;

/// The nodes of `grid` that lie both on a sliding marker (`slide`) and on a fixed marker:
/// any marker named neither in `moving` nor in `slide`. Sorted, without duplicates.
///
/// ```
/// use mesh::{ElementKind, Elements, Marker, Mesh};
/// let mut g = Mesh::new(3);
/// g.coords = vec![[0.0; 3]; 4];
/// let marker = |name: &str, nodes: [u32; 2]| {
///     let mut e = Elements::new();
///     e.push(ElementKind::Line, &nodes, None);
///     Marker { name: name.into(), tag: None, elements: e }
/// };
/// g.markers = vec![marker("symmetry", [0, 1]), marker("farfield", [1, 2]), marker("wing", [2, 3])];
/// let held = aeroshape::precedence::held_nodes(&g, &["wing".into()], &["symmetry".into()]);
/// assert_eq!(held, vec![1]);
/// ```
pub fn held_nodes(grid: &Mesh, moving: &[String], slide: &[String]) -> Vec<u32> {
    let sliding: BTreeSet<u32> = grid
        .markers
        .iter()
        .filter(|m| slide.contains(&m.name))
        .flat_map(|m| m.elements.node_set())
        .collect();
    let fixed: BTreeSet<u32> = grid
        .markers
        .iter()
        .filter(|m| !slide.contains(&m.name) && !moving.contains(&m.name))
        .flat_map(|m| m.elements.node_set())
        .collect();
    sliding.intersection(&fixed).copied().collect()
}

/// Holds the nodes of [`held_nodes`] in `request` on `grid`: each gets a zero displacement,
/// unless the request already prescribes one for it. What `aeroshape deform` and the Python
/// package's `deform` do before they run a request, so that both give the same grid.
pub fn hold_fixed_nodes(grid: &Mesh, request: &mut deform::Request) {
    let given: BTreeSet<u32> = request.displacements.iter().map(|d| d.0).collect();
    let held = held_nodes(grid, &request.rigid, &request.slide);
    request.displacements.extend(
        held.into_iter()
            .filter(|v| !given.contains(v))
            .map(|v| (v, [0.0; 3])),
    );
}
