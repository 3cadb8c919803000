//! The first layer of cells at the moving wall, before and after a deformation
//! ([`FirstLayer`]): the promise of a viscous grid is that its first-layer heights and the
//! wall-normal direction of its layers survive the motion.
//!
//! For each moving node `v` with a neighbour off the moving boundary, the first-layer edge is
//! the shortest such edge `e = x_w − x_v` (in a boundary layer, the wall-normal edge of the
//! first prism or hexahedron; in a tetrahedral grid, simply the shortest edge off the wall).
//! The wall normal `n` at `v` is the area-weighted sum of the normals of the boundary faces
//! around `v` whose nodes all move, each turned to the side of `e` (so the faces'
//! orientation in the file does not matter). The first-layer height is `h = e · n̂`, its
//! angle to the normal `θ = acos(h / |e|)`. The report gives the ratio `h′ / h` and the
//! change `|θ′ − θ|` (radians) over all such nodes, with the worst node of each.

use serde::Serialize;

use mesh::{Adjacency, Mesh};

/// The first layer at the moving wall after a deformation (module doc).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct FirstLayer {
    /// Prescribed nodes measured (those with a neighbour that is not prescribed and a
    /// boundary face of prescribed nodes around them; the nodes of markers held fixed by
    /// prescribing a zero displacement count, with ratio 1).
    pub nodes: usize,
    /// Smallest and largest first-layer height ratio `h′ / h`.
    pub height_ratio: [f64; 2],
    /// The node (input numbering) whose ratio is farthest from 1.
    pub worst_height_node: Option<u32>,
    /// Largest change of the first-layer edge's angle to the wall normal (radians).
    pub max_turn: f64,
    /// The node (input numbering) where it is.
    pub worst_turn_node: Option<u32>,
}

impl FirstLayer {
    /// The largest deviation of the height ratio from 1.
    pub fn worst_height_change(&self) -> f64 {
        (self.height_ratio[0] - 1.0)
            .abs()
            .max((self.height_ratio[1] - 1.0).abs())
    }
}

/// The first layer of `mesh` (solver numbering) at the nodes flagged in `moving`, from the
/// baseline coordinates `x0` to `x1`; `input_id` maps a node to its input number. `None`
/// when no moving node has a neighbour off the boundary and a boundary face.
pub(crate) fn first_layer(
    mesh: &Mesh,
    adj: &Adjacency,
    moving: &[bool],
    x1: &[[f64; 3]],
    input_id: &dyn Fn(usize) -> u32,
) -> Option<FirstLayer> {
    let x0 = &mesh.coords;
    let n = x0.len();
    // the boundary faces whose nodes all move, per node
    let mut faces_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
    let faces: Vec<&[u32]> = mesh
        .markers
        .iter()
        .flat_map(|m| m.elements.iter().map(|(_, f)| f))
        .filter(|f| f.len() >= 3 && f.iter().all(|&v| moving[v as usize]))
        .collect();
    for (k, f) in faces.iter().enumerate() {
        for (i, &v) in f.iter().enumerate() {
            faces_of[v as usize].push((k, i));
        }
    }
    let mut out = FirstLayer {
        height_ratio: [f64::INFINITY, f64::NEG_INFINITY],
        ..FirstLayer::default()
    };
    let mut worst_h = -1.0;
    for v in 0..n {
        if !moving[v] || faces_of[v].is_empty() {
            continue;
        }
        let nb = &adj.indices[adj.offsets[v]..adj.offsets[v + 1]];
        let Some(&w) = nb
            .iter()
            .filter(|&&w| !moving[w as usize])
            .min_by(|&&a, &&b| dist2(x0, v, a as usize).total_cmp(&dist2(x0, v, b as usize)))
        else {
            continue;
        };
        let w = w as usize;
        let measure = |x: &[[f64; 3]]| {
            let e = sub(x[w], x[v]);
            let mut nsum = [0.0; 3];
            for &(k, _) in &faces_of[v] {
                let fnorm = face_normal(faces[k], x);
                let s = if dot(fnorm, e) < 0.0 { -1.0 } else { 1.0 };
                for c in 0..3 {
                    nsum[c] += s * fnorm[c];
                }
            }
            let (ln, le) = (dot(nsum, nsum).sqrt(), dot(e, e).sqrt());
            if ln == 0.0 || le == 0.0 {
                return None;
            }
            let h = dot(e, nsum) / ln;
            Some((h, (h / le).clamp(-1.0, 1.0).acos()))
        };
        let (Some((h0, t0)), Some((h1, t1))) = (measure(x0), measure(x1)) else {
            continue;
        };
        if h0 <= 0.0 {
            continue;
        }
        out.nodes += 1;
        let r = h1 / h0;
        out.height_ratio[0] = out.height_ratio[0].min(r);
        out.height_ratio[1] = out.height_ratio[1].max(r);
        if (r - 1.0).abs() > worst_h {
            worst_h = (r - 1.0).abs();
            out.worst_height_node = Some(input_id(v));
        }
        let turn = (t1 - t0).abs();
        if turn > out.max_turn || out.worst_turn_node.is_none() {
            out.max_turn = turn;
            out.worst_turn_node = Some(input_id(v));
        }
    }
    (out.nodes > 0).then_some(out)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn dist2(x: &[[f64; 3]], a: usize, b: usize) -> f64 {
    let d = sub(x[a], x[b]);
    dot(d, d)
}

/// Twice the area times the unit normal of a triangle, or of a quadrilateral by its
/// diagonals (the face's own orientation).
fn face_normal(f: &[u32], x: &[[f64; 3]]) -> [f64; 3] {
    let p = |i: usize| x[f[i] as usize];
    let (a, b) = if f.len() == 3 {
        (sub(p(1), p(0)), sub(p(2), p(0)))
    } else {
        (sub(p(2), p(0)), sub(p(3), p(1)))
    };
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A prism layer on a unit square wall (z = 0), first height 0.01, the wall moved: a
    /// translation keeps every height (ratio 1, no turn); stretching the layer above one
    /// node is seen at that node.
    #[test]
    fn heights_and_turns_of_a_prism_layer() {
        let mut m = mesh::generate::box_layers(
            [2, 2, 1],
            [0.0; 3],
            [1.0, 1.0, 0.01],
            mesh::ElementKind::Prism,
        );
        m.markers.retain(|mk| mk.name == "z_m");
        assert_eq!(m.markers.len(), 1, "the generator names the wall z_m");
        let adj = Adjacency::try_build(&m).unwrap();
        let moving: Vec<bool> = m.coords.iter().map(|p| p[2] == 0.0).collect();
        let up: Vec<[f64; 3]> = m
            .coords
            .iter()
            .map(|p| [p[0] + 0.3, p[1], p[2] + 0.2])
            .collect();
        let l = first_layer(&m, &adj, &moving, &up, &|v| v as u32).unwrap();
        assert_eq!(l.nodes, 9);
        assert!((l.height_ratio[0] - 1.0).abs() < 1e-12 && (l.height_ratio[1] - 1.0).abs() < 1e-12);
        assert!(l.max_turn < 1e-12);
        // the node above the wall's centre raised: the first-layer height there doubles
        let mut x1 = m.coords.clone();
        let top = (0..x1.len())
            .find(|&v| x1[v] == [0.5, 0.5, 0.01])
            .expect("a node above the centre");
        x1[top][2] = 0.02;
        let l = first_layer(&m, &adj, &moving, &x1, &|v| v as u32).unwrap();
        assert!((l.height_ratio[1] - 2.0).abs() < 1e-12, "{l:?}");
        let centre = (0..x1.len()).find(|&v| x1[v] == [0.5, 0.5, 0.0]).unwrap();
        assert_eq!(l.worst_height_node, Some(centre as u32));
    }
}
