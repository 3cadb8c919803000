//! Cells from faces: each cell's faces (from `owner` and `neighbour`, turned to point out
//! of the cell), recognised by their number and sizes as a tetrahedron (4 triangles), a
//! pyramid (1 quadrilateral, 4 triangles), a prism (2 triangles, 3 quadrilaterals) or a
//! hexahedron (6 quadrilaterals) and written in the project's (VTK's) node order:
//!
//! - tetrahedron `abcd`, pyramid `abcd e`, hexahedron `abcd efgh`: the first face's
//!   right-hand normal points into the cell (to `d`, the apex `e`, the face `efgh`);
//! - prism `abc def`: the first triangle's normal points out of the cell, away from `def`.
//!
//! In each, the second face's nodes follow the first's along the cell's edges (`a`–`e`,
//! `b`–`f`, …). Any other cell (a polyhedron, or a cell whose faces do not close) is an error
//! naming the cell, since [`crate::Mesh`] holds these four kinds only.

use crate::error::{Error, Result};
use crate::grid::{ElementKind, Elements};

/// The faces as CSR: `off[f]..off[f + 1]` indexes `pts`.
pub(crate) struct Faces<'a> {
    /// Offsets, one more than faces.
    pub off: &'a [usize],
    /// Point indices.
    pub pts: &'a [u32],
}

impl Faces<'_> {
    /// The points of face `f`.
    pub fn face(&self, f: usize) -> &[u32] {
        &self.pts[self.off[f]..self.off[f + 1]]
    }
    /// Number of faces.
    pub fn len(&self) -> usize {
        self.off.len() - 1
    }
}

/// Each cell's faces in CSR form, `(face, outward)`: `outward` when the cell owns the face
/// (its stored normal points out of the cell).
pub(crate) fn cell_faces(
    n_cells: usize,
    owner: &[u32],
    neighbour: &[u32],
) -> (Vec<usize>, Vec<(u32, bool)>) {
    let mut count = vec![0usize; n_cells + 1];
    for &c in owner.iter().chain(neighbour) {
        count[c as usize + 1] += 1;
    }
    for i in 0..n_cells {
        count[i + 1] += count[i];
    }
    let mut fill = count.clone();
    let mut out = vec![(0u32, false); count[n_cells]];
    for (f, &c) in owner.iter().enumerate() {
        out[fill[c as usize]] = (f as u32, true);
        fill[c as usize] += 1;
    }
    for (f, &c) in neighbour.iter().enumerate() {
        out[fill[c as usize]] = (f as u32, false);
        fill[c as usize] += 1;
    }
    (count, out)
}

/// The faces of one cell, each as its points in outward order.
fn outward_faces(faces: &Faces, list: &[(u32, bool)]) -> Vec<Vec<u32>> {
    list.iter()
        .map(|&(f, out)| {
            let mut p = faces.face(f as usize).to_vec();
            if !out {
                p.reverse();
            }
            p
        })
        .collect()
}

/// The point joined to `x` by an edge of the cell's faces that is not in `base`.
fn across(faces: &[Vec<u32>], x: u32, base: &[u32]) -> Option<u32> {
    let mut found = None;
    for f in faces {
        let n = f.len();
        for i in 0..n {
            let (u, v) = (f[i], f[(i + 1) % n]);
            let other = if u == x {
                v
            } else if v == x {
                u
            } else {
                continue;
            };
            if base.contains(&other) {
                continue;
            }
            match found {
                None => found = Some(other),
                Some(o) if o == other => {}
                Some(_) => return None,
            }
        }
    }
    found
}

/// The kind and node order of one cell (see the module doc), or `None` when its faces are
/// not those of a tetrahedron, pyramid, prism or hexahedron.
pub(crate) fn shape(faces: &[Vec<u32>]) -> Option<(ElementKind, Vec<u32>)> {
    let tris: Vec<&Vec<u32>> = faces.iter().filter(|f| f.len() == 3).collect();
    let quads: Vec<&Vec<u32>> = faces.iter().filter(|f| f.len() == 4).collect();
    if tris.len() + quads.len() != faces.len() {
        return None;
    }
    let (kind, nodes) = match (tris.len(), quads.len()) {
        (4, 0) => {
            let t = tris[0];
            let d = *tris[1].iter().find(|p| !t.contains(p))?;
            (ElementKind::Tetra, vec![t[0], t[2], t[1], d])
        }
        (4, 1) => {
            let q = quads[0];
            let e = *tris[0].iter().find(|p| !q.contains(p))?;
            (ElementKind::Pyramid, vec![q[0], q[3], q[2], q[1], e])
        }
        (2, 3) => {
            let t = tris[0];
            let top = t
                .iter()
                .map(|&x| across(faces, x, t))
                .collect::<Option<Vec<u32>>>()?;
            (
                ElementKind::Prism,
                vec![t[0], t[1], t[2], top[0], top[1], top[2]],
            )
        }
        (0, 6) => {
            let q = quads[0];
            let base = [q[0], q[3], q[2], q[1]];
            let top = base
                .iter()
                .map(|&x| across(faces, x, &base))
                .collect::<Option<Vec<u32>>>()?;
            let mut v = base.to_vec();
            v.extend(top);
            (ElementKind::Hexa, v)
        }
        _ => return None,
    };
    // the faces close: every point of the cell appears, and no point twice
    let mut all: Vec<u32> = faces.iter().flatten().copied().collect();
    all.sort_unstable();
    all.dedup();
    let mut mine = nodes.clone();
    mine.sort_unstable();
    mine.dedup();
    (all == mine && mine.len() == kind.n_nodes()).then_some((kind, nodes))
}

/// The cells of the grid, in the project's node order, with the index of every stored
/// element's OpenFOAM cell (`origin[e]` for element `e` of [`Elements::iter`]'s order).
pub(crate) fn cells(
    file: &str,
    faces: &Faces,
    owner: &[u32],
    neighbour: &[u32],
    n_cells: usize,
) -> Result<(Elements, Vec<u32>)> {
    let (off, list) = cell_faces(n_cells, owner, neighbour);
    let mut cells = Elements::new();
    let mut origin: Vec<(ElementKind, u32)> = Vec::with_capacity(n_cells);
    for c in 0..n_cells {
        let fl = outward_faces(faces, &list[off[c]..off[c + 1]]);
        match shape(&fl) {
            Some((kind, nodes)) => {
                cells.push(kind, &nodes, None);
                origin.push((kind, c as u32));
            }
            None => {
                let sizes: Vec<String> = fl.iter().map(|f| f.len().to_string()).collect();
                let mut pts: Vec<u32> = fl.iter().flatten().copied().collect();
                pts.sort_unstable();
                pts.dedup();
                return Err(Error::Invalid {
                    what: format!(
                        "{file}: cell {c} is a polyhedron ({} faces of {} points, {} points): aeroshape's grids hold tetrahedra, pyramids, prisms and hexahedra only",
                        fl.len(),
                        sizes.join("+"),
                        pts.len()
                    ),
                });
            }
        }
    }
    // canonical order: by kind, then cell index (a stable sort of what was pushed)
    origin.sort_by_key(|&(k, _)| k);
    Ok((cells, origin.into_iter().map(|(_, c)| c).collect()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quality::tet_volume;

    /// The unit cube's corners, and its six faces with outward normals.
    fn cube() -> (Vec<[f64; 3]>, Vec<Vec<u32>>) {
        let x = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        let f = vec![
            vec![0, 3, 2, 1],
            vec![4, 5, 6, 7],
            vec![0, 1, 5, 4],
            vec![1, 2, 6, 5],
            vec![2, 3, 7, 6],
            vec![3, 0, 4, 7],
        ];
        (x, f)
    }

    fn corner_volume(x: &[[f64; 3]], n: &[u32], a: usize, b: usize, c: usize, d: usize) -> f64 {
        tet_volume([
            x[n[a] as usize],
            x[n[b] as usize],
            x[n[c] as usize],
            x[n[d] as usize],
        ])
    }

    #[test]
    fn a_cube_is_a_positive_hexahedron_whatever_face_comes_first() {
        let (x, f) = cube();
        for r in 0..6 {
            let mut fr = f.clone();
            fr.rotate_left(r);
            let (kind, n) = shape(&fr).unwrap();
            assert_eq!(kind, ElementKind::Hexa);
            // corner 0's tetrahedron (0, 1, 3, 4) positive in VTK order
            assert!(corner_volume(&x, &n, 0, 1, 3, 4) > 0.0, "{n:?}");
            assert!(corner_volume(&x, &n, 6, 2, 5, 7) > 0.0, "{n:?}");
        }
    }

    #[test]
    fn tet_pyramid_and_prism_orders() {
        let x = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 0.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        // tetrahedron 0 1 2 3, outward faces
        let tet = vec![vec![0, 2, 1], vec![0, 1, 3], vec![1, 2, 3], vec![2, 0, 3]];
        let (k, n) = shape(&tet).unwrap();
        assert_eq!(k, ElementKind::Tetra);
        assert!(corner_volume(&x, &n, 0, 1, 2, 3) > 0.0);
        // pyramid on the square 0 1 4 2 with apex 3
        let pyr = vec![
            vec![0, 2, 4, 1],
            vec![0, 1, 3],
            vec![1, 4, 3],
            vec![4, 2, 3],
            vec![2, 0, 3],
        ];
        let (k, n) = shape(&pyr).unwrap();
        assert_eq!(k, ElementKind::Pyramid);
        assert_eq!(n[4], 3);
        assert!(corner_volume(&x, &n, 0, 1, 3, 4) > 0.0);
        // prism: triangle 0 1 2 at z = 0 and 3 5 6 at z = 1
        let prism = vec![
            vec![0, 2, 1],
            vec![3, 5, 6],
            vec![0, 1, 5, 3],
            vec![1, 2, 6, 5],
            vec![2, 0, 3, 6],
        ];
        let (k, n) = shape(&prism).unwrap();
        assert_eq!(k, ElementKind::Prism);
        // VTK: the first triangle's normal points away from the second
        assert!(corner_volume(&x, &n, 0, 2, 1, 3) > 0.0, "{n:?}");
        assert_eq!(n[3..], [3, 6, 5]);
    }

    #[test]
    fn open_or_polyhedral_cells_are_refused() {
        let (_, mut f) = cube();
        f.pop();
        assert!(shape(&f).is_none());
        let (_, mut f) = cube();
        // split the top face in two triangles: 7 faces, a polyhedron
        f[1] = vec![4, 5, 6];
        f.push(vec![4, 6, 7]);
        assert!(shape(&f).is_none());
    }
}
