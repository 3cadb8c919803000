//! Structured test grids: a box split into tetrahedra (six per cube, the Kuhn
//! subdivision along the main diagonal, all positively oriented) with the six faces as
//! markers `x_m x_p y_m y_p z_m z_p` like SU2's brick, the same box of hexahedra or of
//! prisms (layers along z, as a boundary layer), and seeded random node renumbering.

use crate::grid::{ElementKind, Elements, Marker, Mesh};

/// A box `[lo, hi]` with `nx × ny × nz` cubes, each split into six tetrahedra that share
/// the cube's diagonal from its lowest to its highest corner. Node `(i, j, k)` has index
/// `i + (nx+1)(j + (ny+1)k)`. All tetrahedra have positive volume; boundary triangles are
/// grouped in markers `x_m x_p y_m y_p z_m z_p` and oriented with outward normals.
///
/// ```
/// let m = mesh::generate::box_tets(2, 3, 4, [0.0; 3], [1.0, 2.0, 3.0]);
/// assert_eq!(m.n_nodes(), 3 * 4 * 5);
/// assert_eq!(m.tets().len(), 6 * 24);
/// assert_eq!(m.marker("z_p").unwrap().elements.len(), 2 * 6);
/// ```
pub fn box_tets(nx: usize, ny: usize, nz: usize, lo: [f64; 3], hi: [f64; 3]) -> Mesh {
    let n = [nx.max(1), ny.max(1), nz.max(1)];
    let idx = |i: usize, j: usize, k: usize| (i + (n[0] + 1) * (j + (n[1] + 1) * k)) as u32;
    let coord = |a: usize, i: usize| {
        if i == n[a] {
            hi[a]
        } else {
            lo[a] + (hi[a] - lo[a]) * (i as f64 / n[a] as f64)
        }
    };
    let mut mesh = Mesh::new(3);
    mesh.coords.reserve((n[0] + 1) * (n[1] + 1) * (n[2] + 1));
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                mesh.coords.push([coord(0, i), coord(1, j), coord(2, k)]);
            }
        }
    }
    // Axis permutations with their parity.
    const PERMS: [([usize; 3], bool); 6] = [
        ([0, 1, 2], true),
        ([1, 2, 0], true),
        ([2, 0, 1], true),
        ([0, 2, 1], false),
        ([2, 1, 0], false),
        ([1, 0, 2], false),
    ];
    let tets = mesh.cells.group_mut(ElementKind::Tetra);
    tets.nodes.reserve_exact(6 * 4 * n[0] * n[1] * n[2]);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                for (p, even) in PERMS {
                    let mut c = [i, j, k];
                    let v0 = idx(c[0], c[1], c[2]);
                    c[p[0]] += 1;
                    let v1 = idx(c[0], c[1], c[2]);
                    c[p[1]] += 1;
                    let v2 = idx(c[0], c[1], c[2]);
                    c[p[2]] += 1;
                    let v3 = idx(c[0], c[1], c[2]);
                    if even {
                        tets.nodes.extend_from_slice(&[v0, v1, v2, v3]);
                    } else {
                        tets.nodes.extend_from_slice(&[v0, v2, v1, v3]);
                    }
                }
            }
        }
    }
    // Boundary faces: axis a fixed at 0 or n[a]; the face of cube (s, t) is split along the
    // diagonal from its lowest to its highest corner, as the tetrahedra are.
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for (side, name) in [(0usize, "_m"), (1, "_p")] {
            let mut el = Elements::new();
            let g = el.group_mut(ElementKind::Triangle);
            let fixed = side * n[a];
            for t in 0..n[c] {
                for s in 0..n[b] {
                    let at = |ds: usize, dt: usize| {
                        let mut ijk = [0; 3];
                        ijk[a] = fixed;
                        ijk[b] = s + ds;
                        ijk[c] = t + dt;
                        idx(ijk[0], ijk[1], ijk[2])
                    };
                    let (p00, p10, p11, p01) = (at(0, 0), at(1, 0), at(1, 1), at(0, 1));
                    // (b, c, a) is a right-handed frame, so (p00, p10, p11) has normal +a.
                    if side == 1 {
                        g.nodes.extend_from_slice(&[p00, p10, p11, p00, p11, p01]);
                    } else {
                        g.nodes.extend_from_slice(&[p00, p11, p10, p00, p01, p11]);
                    }
                }
            }
            mesh.markers.push(Marker {
                name: format!("{}{name}", ["x", "y", "z"][a]),
                tag: None,
                elements: el,
            });
        }
    }
    mesh
}

/// A box `[lo, hi]` of `nx × ny × nz` hexahedra ([`ElementKind::Hexa`]) or of prisms
/// ([`ElementKind::Prism`]: each cube split in two along the diagonal of its z faces, the
/// prism axes along z, as in a boundary layer over the plane z = lo), in this crate's node
/// order, all valid. Nodes as [`box_tets`]; markers `x_m x_p y_m y_p z_m z_p` with outward
/// normals: quadrilaterals, or triangles on the z faces of the prism box. Any other kind
/// gives the hexahedra.
///
/// ```
/// use mesh::ElementKind;
/// let m = mesh::generate::box_layers([2, 3, 4], [0.0; 3], [1.0, 2.0, 1e-3], ElementKind::Prism);
/// assert_eq!(m.cells.count(ElementKind::Prism), 2 * 24);
/// assert_eq!(m.marker("z_m").unwrap().elements.count(ElementKind::Triangle), 12);
/// let q = mesh::quality::summary(&mesh::quality::cell_quality(&m));
/// assert_eq!((q.measured, q.n_nonpositive), (48, 0));
/// ```
pub fn box_layers(n: [usize; 3], lo: [f64; 3], hi: [f64; 3], kind: ElementKind) -> Mesh {
    let prisms = kind == ElementKind::Prism;
    let n = n.map(|v| v.max(1));
    let mut mesh = box_tets(n[0], n[1], n[2], lo, hi);
    let idx = |i: usize, j: usize, k: usize| (i + (n[0] + 1) * (j + (n[1] + 1) * k)) as u32;
    let mut cells = Elements::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let p = [
                    idx(i, j, k),
                    idx(i + 1, j, k),
                    idx(i + 1, j + 1, k),
                    idx(i, j + 1, k),
                ];
                let q = [
                    idx(i, j, k + 1),
                    idx(i + 1, j, k + 1),
                    idx(i + 1, j + 1, k + 1),
                    idx(i, j + 1, k + 1),
                ];
                if prisms {
                    // VTK's order: the first triangle turns clockwise seen from the second.
                    cells.push(kind, &[p[0], p[2], p[1], q[0], q[2], q[1]], None);
                    cells.push(kind, &[p[0], p[3], p[2], q[0], q[3], q[2]], None);
                } else {
                    cells.push(
                        ElementKind::Hexa,
                        &[p[0], p[1], p[2], p[3], q[0], q[1], q[2], q[3]],
                        None,
                    );
                }
            }
        }
    }
    mesh.cells = cells;
    for mk in &mut mesh.markers {
        let a = ["x", "y", "z"]
            .iter()
            .position(|c| mk.name.starts_with(c))
            .unwrap_or(0);
        if prisms && a == 2 {
            continue;
        }
        // Pairs of triangles (p00, p10, p11), (p00, p11, p01) or their reverses: one quad.
        let t = mk
            .elements
            .group(ElementKind::Triangle)
            .map(|g| g.nodes.clone())
            .unwrap_or_default();
        let mut el = Elements::new();
        for c in t.chunks_exact(6) {
            if c[2] == c[4] {
                // Outward +a: (p00, p10, p11), (p00, p11, p01).
                el.push(ElementKind::Quad, &[c[0], c[1], c[2], c[5]], None);
            } else {
                // Outward −a: (p00, p11, p10), (p00, p01, p11).
                el.push(ElementKind::Quad, &[c[0], c[4], c[1], c[2]], None);
            }
        }
        mk.elements = el;
    }
    mesh
}

/// A seeded pseudo-random permutation of `0..n` (Fisher–Yates with SplitMix64).
pub fn random_permutation(n: usize, seed: u64) -> Vec<u32> {
    let mut state = seed;
    let mut next = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let mut p: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        let j = (next() % (i as u64 + 1)) as usize;
        p.swap(i, j);
    }
    p
}

/// Renumbers the nodes of `mesh` by a seeded random permutation (see
/// [`Mesh::renumber_nodes`]) and returns the permutation (old index → new index).
pub fn shuffle_nodes(mesh: &mut Mesh, seed: u64) -> Vec<u32> {
    let p = random_permutation(mesh.n_nodes(), seed);
    mesh.renumber_nodes(&p)
        .expect("a permutation of the right length is valid");
    p
}
