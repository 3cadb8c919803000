//! Element quality (DESIGN.md): validity and a quality measure for every element kind,
//! minimum dihedral (or corner) angles, summaries and the comparison of two grids with the
//! same connectivity.
//!
//! Tetrahedron, edges `l_1..l_6`, signed volume `V = (b-a)·((c-a)×(d-a))/6`: the signed
//! mean ratio `q = sign(V) · 12 (3|V|)^(2/3) / Σ l_i²` — 1 for the regular tetrahedron,
//! 0 when flat, negative when inverted. Triangle, area `A`: `q = 4√3 A / Σ l_i²`, signed by
//! the orientation in 2D grids (`A` from the z component of `(b-a)×(c-a)`), unsigned in 3D.
//!
//! Pyramids, prisms, hexahedra and quadrilaterals: the scaled Jacobian, the smallest over
//! the element's corners of `J_c / (|e_1| |e_2| |e_3|)`, where `e_1, e_2, e_3` are the edges
//! from corner `c` to its three neighbours taken so that `J_c = e_1 · (e_2 × e_3) > 0` in a
//! valid element (the volume of the corner's sub-tetrahedron, times 6). Each corner value
//! is in [−1, 1] (1: the three edges orthogonal). It is scaled so that the ideal element of
//! the kind gives 1 and clamped to at most 1: prisms by 2/√3 (the corners of an
//! equilateral triangle), pyramids by √2 (the base corners of the pyramid with all edges
//! equal); hexahedra unscaled. A pyramid's corners are its four base corners (the four
//! sub-tetrahedra that leave out one base node, which also cover the apex). Quadrilaterals:
//! corner values `(e_1 × e_2) · n / (|e_1| |e_2|)` with `n` the unit z axis in 2D grids and
//! the unit normal `(c-a)×(d-b)` of the quadrilateral in 3D.
//!
//! Validity is the same for every kind: an element is valid when every corner's Jacobian
//! is positive, that is when its quality is positive; `q ≤ 0` marks a flat or inverted
//! element (the guard's and the reports' "inverted" count). Zero-length edges give 0,
//! never NaN. Lines have no measure (NaN); they are never cells of a grid.
//!
//! Node orders are this crate's ([`ElementKind`]: VTK's and SU2's); readers of other
//! orders convert (Gmsh's prism: [`ElementKind::gmsh_order`]).

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::grid::{ElementKind, Elements, Mesh};

type P = [f64; 3];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: P, b: P) -> P {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Signed volume of the tetrahedron `abcd` (positive when `d` is on the side of the
/// right-hand normal of `abc`).
pub fn tet_volume(p: [P; 4]) -> f64 {
    dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0]))) / 6.0
}

/// Signed mean ratio of a tetrahedron: `sign(V) · 12 (3|V|)^(2/3) / Σ l²`.
///
/// ```
/// let s = 1.0 / 2f64.sqrt();
/// let regular = [[1.0, 0.0, -s], [0.0, 1.0, s], [-1.0, 0.0, -s], [0.0, -1.0, s]];
/// testkit::assert_close!(mesh::quality::tet_quality(regular), 1.0, rel = 1e-14);
/// let inverted = [regular[1], regular[0], regular[2], regular[3]];
/// testkit::assert_close!(mesh::quality::tet_quality(inverted), -1.0, rel = 1e-14);
/// ```
#[inline]
pub fn tet_quality(p: [P; 4]) -> f64 {
    let (a, b, c) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let v = dot(a, cross(b, c)) / 6.0;
    // Σ l² over the edges in the order of `ElementKind::Tetra.edges()`.
    let (d, e, f) = (sub(p[2], p[1]), sub(p[3], p[1]), sub(p[3], p[2]));
    let s = dot(a, a) + dot(d, d) + dot(b, b) + dot(c, c) + dot(e, e) + dot(f, f);
    if s == 0.0 {
        return 0.0;
    }
    // (3|V|)^(2/3) and the sign applied afterwards.
    v.signum() * 12.0 * two_thirds_power(3.0 * v.abs()) / s
}

/// x^(2/3) for `x ≥ 0`, within 3 units in the last place of the rounded `cbrt(x)²`:
/// x · x^(−1/3), the inverse cube root from an estimate of the exponent bits (within 3.5 %)
/// refined by four Newton steps r ← r (4 − x r³) / 3 (quadratic convergence: 3.5 % → 2e-3
/// → 1e-5 → 2e-10 → round-off). No division and no `f64::cbrt`, which the grid-quality loop
/// otherwise spends most of its time in; zero, subnormal and non-finite arguments go to
/// `f64::cbrt`.
#[inline]
fn two_thirds_power(x: f64) -> f64 {
    if !x.is_normal() {
        return x.cbrt() * x.cbrt();
    }
    // 4/3 of the exponent bias minus a third of the bits, tuned for the smallest error.
    const MAGIC: u64 = 0x553E_F0FF_289D_D796;
    let mut r = f64::from_bits(MAGIC - x.to_bits() / 3);
    for _ in 0..4 {
        r *= (4.0 - x * (r * r * r)) * (1.0 / 3.0);
    }
    x * r
}

/// Mean ratio of a triangle `4√3 A / Σ l²`; with `signed`, the sign of the z component of
/// `(b-a)×(c-a)` (2D grids).
pub fn triangle_quality(p: [P; 3], signed: bool) -> f64 {
    let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
    let area = if signed {
        0.5 * n[2]
    } else {
        0.5 * dot(n, n).sqrt()
    };
    let mut s = 0.0;
    for e in ElementKind::Triangle.edges() {
        let d = sub(p[e[1] as usize], p[e[0] as usize]);
        s += dot(d, d);
    }
    if s == 0.0 {
        return 0.0;
    }
    4.0 * 3f64.sqrt() * area / s
}

/// Angle at `a` between `b - a` and `c - a`, in radians.
fn angle(a: P, b: P, c: P) -> f64 {
    let (u, v) = (sub(b, a), sub(c, a));
    let n = dot(u, u).sqrt() * dot(v, v).sqrt();
    if n == 0.0 {
        return 0.0;
    }
    cross(u, v)
        .iter()
        .map(|x| x * x)
        .sum::<f64>()
        .sqrt()
        .atan2(dot(u, v))
}

/// Smallest of the six dihedral angles of a tetrahedron, in degrees (70.53° for the regular
/// one, 0 for a flat one).
pub fn tet_min_dihedral(p: [P; 4]) -> f64 {
    let mut best = f64::INFINITY;
    for e in ElementKind::Tetra.edges() {
        let (i, j) = (e[0] as usize, e[1] as usize);
        let others: Vec<usize> = (0..4).filter(|&k| k != i && k != j).collect();
        let axis = sub(p[j], p[i]);
        let l2 = dot(axis, axis);
        if l2 == 0.0 {
            return 0.0;
        }
        let perp = |q: P| {
            let d = sub(q, p[i]);
            let t = dot(d, axis) / l2;
            [d[0] - t * axis[0], d[1] - t * axis[1], d[2] - t * axis[2]]
        };
        let (u, w) = (perp(p[others[0]]), perp(p[others[1]]));
        best = best.min(angle([0.0; 3], u, w));
    }
    best.to_degrees()
}

/// Smallest corner angle of a triangle, in degrees.
pub fn triangle_min_angle(p: [P; 3]) -> f64 {
    let a = angle(p[0], p[1], p[2]);
    let b = angle(p[1], p[2], p[0]);
    let c = angle(p[2], p[0], p[1]);
    a.min(b).min(c).to_degrees()
}

fn per_element(
    mesh: &Mesh,
    set: &Elements,
    f: impl Fn(ElementKind, &[u32]) -> f64 + Sync,
) -> Vec<f64> {
    let _ = mesh;
    let mut out = vec![0.0; set.len()];
    let mut at = 0;
    for g in set.groups() {
        let n = g.kind.n_nodes();
        let m = g.nodes.len() / n;
        out[at..at + m]
            .par_chunks_mut(1024)
            .zip(g.nodes.par_chunks(n * 1024))
            .for_each(|(o, c)| {
                for (o, e) in o.iter_mut().zip(c.chunks_exact(n)) {
                    *o = f(g.kind, e);
                }
            });
        at += m;
    }
    out
}

/// Quality of every cell ([`element_quality`]: signed mean ratio of tetrahedra and
/// triangles, scaled Jacobian of the other kinds), in canonical element order; `q ≤ 0`
/// marks a flat or inverted cell. Node indices must be valid ([`Mesh::validate`]).
pub fn cell_quality(mesh: &Mesh) -> Vec<f64> {
    cell_quality_at(mesh, &mesh.coords)
}

/// [`cell_quality`] of the grid's cells with the node coordinates `x` instead of the grid's
/// own (same numbering; `x.len()` must be the node count).
pub fn cell_quality_at(mesh: &Mesh, x: &[P]) -> Vec<f64> {
    let signed = mesh.dim == 2;
    per_element(mesh, &mesh.cells, |kind, e| {
        element_quality(kind, e, x, signed)
    })
}

/// Quality of one element of kind `kind` with nodes `e` at coordinates `x`: the signed mean
/// ratio of a tetrahedron ([`tet_quality`]) or a triangle ([`triangle_quality`], signed in
/// 2-D grids), the scaled Jacobian of a pyramid, prism or hexahedron ([`scaled_jacobian`])
/// or a quadrilateral ([`quad_scaled_jacobian`], signed in 2-D grids). Positive exactly
/// when the element is valid (every corner Jacobian positive); NaN only for lines.
///
/// ```
/// use mesh::{ElementKind, quality::element_quality};
/// // The unit prism in this crate's (VTK's) order, and the same with Gmsh's order.
/// let x = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0],
///          [0.0, 0.0, 1.0], [0.0, 1.0, 1.0], [1.0, 0.0, 1.0]];
/// assert!(element_quality(ElementKind::Prism, &[0, 1, 2, 3, 4, 5], &x, false) > 0.0);
/// assert!(element_quality(ElementKind::Prism, &[0, 2, 1, 3, 5, 4], &x, false) < 0.0);
/// ```
#[inline]
pub fn element_quality(kind: ElementKind, e: &[u32], x: &[P], signed: bool) -> f64 {
    let p = |i: usize| x[e[i] as usize];
    match kind {
        ElementKind::Tetra => tet_quality([p(0), p(1), p(2), p(3)]),
        ElementKind::Triangle => triangle_quality([p(0), p(1), p(2)], signed),
        ElementKind::Quad => quad_scaled_jacobian([p(0), p(1), p(2), p(3)], signed),
        ElementKind::Pyramid | ElementKind::Prism | ElementKind::Hexa => {
            let mut q = [[0.0; 3]; 8];
            for (k, qk) in q.iter_mut().enumerate().take(kind.n_nodes()) {
                *qk = p(k);
            }
            scaled_jacobian(kind, &q[..kind.n_nodes()])
        }
        ElementKind::Line => f64::NAN,
    }
}

/// The corner sub-tetrahedra `(corner, a, b, c)` of a pyramid, prism or hexahedron in this
/// crate's node order: `(a−corner) · ((b−corner) × (c−corner)) > 0` in a valid element.
/// Empty for the other kinds.
///
/// ```
/// use mesh::{ElementKind, quality::{corners, tet_volume}};
/// // The unit cube: every corner's sub-tetrahedron has volume 1/6.
/// let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0],
///          [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0]];
/// for c in corners(ElementKind::Hexa) {
///     let v = tet_volume(c.map(|i| x[i as usize]));
///     assert!((v - 1.0 / 6.0).abs() < 1e-15);
/// }
/// ```
pub const fn corners(kind: ElementKind) -> &'static [[u8; 4]] {
    match kind {
        ElementKind::Pyramid => &[[0, 1, 3, 4], [1, 2, 0, 4], [2, 3, 1, 4], [3, 0, 2, 4]],
        ElementKind::Prism => &[
            [0, 2, 1, 3],
            [1, 0, 2, 4],
            [2, 1, 0, 5],
            [3, 4, 5, 0],
            [4, 5, 3, 1],
            [5, 3, 4, 2],
        ],
        ElementKind::Hexa => &[
            [0, 1, 3, 4],
            [1, 2, 0, 5],
            [2, 3, 1, 6],
            [3, 0, 2, 7],
            [4, 7, 5, 0],
            [5, 4, 6, 1],
            [6, 5, 7, 2],
            [7, 6, 4, 3],
        ],
        _ => &[],
    }
}

/// The factor that makes the ideal element's corners 1 ([`scaled_jacobian`]).
fn corner_scale(kind: ElementKind) -> f64 {
    match kind {
        // An equilateral triangle's corner: sin 60° = √3/2.
        ElementKind::Prism => 2.0 / 3f64.sqrt(),
        // The base corner of the pyramid with equal edges: height 1/√2 for unit edges.
        ElementKind::Pyramid => 2f64.sqrt(),
        _ => 1.0,
    }
}

/// One corner's scaled Jacobian `a · (b × c) / (|a| |b| |c|)` (0 with a zero-length edge).
#[inline]
fn corner_value(a: P, b: P, c: P) -> f64 {
    let l = (dot(a, a) * dot(b, b) * dot(c, c)).sqrt();
    if l == 0.0 {
        return 0.0;
    }
    let j = dot(a, cross(b, c)) / l;
    // Round-off can leave |j| a few ulps above 1; NaN only from non-finite coordinates.
    j.clamp(-1.0, 1.0)
}

/// Scaled Jacobian of a pyramid, prism or hexahedron with node coordinates `p` (this crate's
/// order, `kind.n_nodes()` points): the smallest corner value over [`corners`], scaled so
/// that the ideal element gives 1 and clamped to at most 1. Positive exactly when every
/// corner sub-tetrahedron is; NaN for other kinds.
///
/// ```
/// use mesh::{ElementKind, quality::scaled_jacobian};
/// let s = 3f64.sqrt() / 2.0;
/// // Equilateral unit prism (VTK order: 0-1-2 turns clockwise seen from 3-4-5).
/// let prism = [[0.0, 0.0, 0.0], [0.5, s, 0.0], [1.0, 0.0, 0.0],
///              [0.0, 0.0, 1.0], [0.5, s, 1.0], [1.0, 0.0, 1.0]];
/// testkit::assert_close!(scaled_jacobian(ElementKind::Prism, &prism), 1.0, rel = 1e-14);
/// // Its top lowered below the bottom: inverted.
/// let mut flat = prism;
/// for p in &mut flat[3..] { p[2] = -0.1; }
/// assert!(scaled_jacobian(ElementKind::Prism, &flat) < 0.0);
/// ```
pub fn scaled_jacobian(kind: ElementKind, p: &[P]) -> f64 {
    let cs = corners(kind);
    if cs.is_empty() || p.len() != kind.n_nodes() {
        return f64::NAN;
    }
    let mut q = f64::INFINITY;
    for c in cs {
        let o = p[c[0] as usize];
        let v = corner_value(
            sub(p[c[1] as usize], o),
            sub(p[c[2] as usize], o),
            sub(p[c[3] as usize], o),
        );
        q = q.min(v);
    }
    (q * corner_scale(kind)).min(1.0)
}

/// Scaled Jacobian of a quadrilateral `abcd`: the smallest over its corners of
/// `(e_1 × e_2) · n / (|e_1| |e_2|)`, `e_1` and `e_2` the edges to the next and the previous
/// corner. `n` is the z axis with `signed` (2-D grids: negative when the quadrilateral turns
/// clockwise) and the unit normal `(c−a) × (d−b)` otherwise (then a quadrilateral is
/// negative only where it folds: a reflex corner or a bow tie). 1 for a rectangle; 0 with
/// a zero-length edge or diagonal.
///
/// ```
/// use mesh::quality::quad_scaled_jacobian;
/// let sq = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
/// assert_eq!(quad_scaled_jacobian(sq, true), 1.0);
/// let cw = [sq[0], sq[3], sq[2], sq[1]];
/// assert_eq!(quad_scaled_jacobian(cw, true), -1.0);
/// assert_eq!(quad_scaled_jacobian(cw, false), 1.0);
/// // A reflex corner (the dart): negative either way.
/// let dart = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.0, 2.0, 0.0]];
/// assert!(quad_scaled_jacobian(dart, true) < 0.0);
/// assert!(quad_scaled_jacobian(dart, false) < 0.0);
/// ```
pub fn quad_scaled_jacobian(p: [P; 4], signed: bool) -> f64 {
    let n = if signed {
        [0.0, 0.0, 1.0]
    } else {
        let n = cross(sub(p[2], p[0]), sub(p[3], p[1]));
        let l = dot(n, n).sqrt();
        if l == 0.0 {
            return 0.0;
        }
        [n[0] / l, n[1] / l, n[2] / l]
    };
    let mut q = f64::INFINITY;
    for i in 0..4 {
        let o = p[i];
        let (a, b) = (sub(p[(i + 1) % 4], o), sub(p[(i + 3) % 4], o));
        let l = (dot(a, a) * dot(b, b)).sqrt();
        let v = if l == 0.0 {
            0.0
        } else {
            (dot(cross(a, b), n) / l).clamp(-1.0, 1.0)
        };
        q = q.min(v);
    }
    q
}

#[cfg(test)]
mod two_thirds_power_tests {
    use super::two_thirds_power;

    #[test]
    fn two_thirds_power_is_within_three_ulps_of_the_squared_cube_root() {
        let mut x = 1e-300f64;
        while x < 1e300 {
            for m in [1.0, 1.1, 1.37, 1.5, 1.9, 2.0, 3.3, 7.9] {
                let v = x * m;
                let (a, b) = (two_thirds_power(v), v.cbrt() * v.cbrt());
                assert!(
                    (a - b).abs() <= 3.0 * f64::EPSILON * b,
                    "({v:e})^(2/3): {a:e} vs {b:e}"
                );
            }
            x *= 7.3;
        }
        assert_eq!(two_thirds_power(0.0), 0.0);
        assert!((two_thirds_power(27.0) - 9.0).abs() <= 2.0 * f64::EPSILON * 9.0);
        assert!((two_thirds_power(1e-310) - 1e-310f64.cbrt().powi(2)).abs() < 1e-220);
    }
}

/// Minimum dihedral angle (tetrahedra) or corner angle (triangles) of every cell, in
/// degrees, canonical order (NaN for other kinds).
pub fn cell_min_angle(mesh: &Mesh) -> Vec<f64> {
    let x = &mesh.coords;
    per_element(mesh, &mesh.cells, |kind, e| match kind {
        ElementKind::Tetra => tet_min_dihedral([
            x[e[0] as usize],
            x[e[1] as usize],
            x[e[2] as usize],
            x[e[3] as usize],
        ]),
        ElementKind::Triangle => {
            triangle_min_angle([x[e[0] as usize], x[e[1] as usize], x[e[2] as usize]])
        }
        _ => f64::NAN,
    })
}

/// Per node, the smallest quality of the cells that use it (NaN for unused nodes).
pub fn node_quality(mesh: &Mesh, cell_q: &[f64]) -> Vec<f64> {
    let mut out = vec![f64::NAN; mesh.n_nodes()];
    let mut e = 0;
    for g in mesh.cells.groups() {
        for nodes in g.iter() {
            let q = cell_q[e];
            for &v in nodes {
                let o = &mut out[v as usize];
                if o.is_nan() || q < *o {
                    *o = q;
                }
            }
            e += 1;
        }
    }
    out
}

/// One cell of a quality field, for messages and reports.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CellQuality {
    /// Cell id (canonical order).
    pub id: usize,
    /// Its kind.
    pub kind: ElementKind,
    /// Its quality.
    pub quality: f64,
}

impl std::fmt::Display for CellQuality {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "cell {} ({}, q = {:.3e})",
            self.id,
            self.kind.name(),
            self.quality
        )
    }
}

/// The `k` lowest-quality cells of the field `q` over `cells` (canonical order, NaN
/// skipped), worst first, ties by id.
///
/// ```
/// use mesh::{ElementKind, Elements, quality::worst_cells};
/// let mut e = Elements::new();
/// e.push(ElementKind::Tetra, &[0, 1, 2, 3], None);
/// e.push(ElementKind::Hexa, &[0, 1, 2, 3, 4, 5, 6, 7], None);
/// let w = worst_cells(&e, &[0.5, -0.25], 1);
/// assert_eq!(w[0].to_string(), "cell 1 (hexa, q = -2.500e-1)");
/// ```
pub fn worst_cells(cells: &Elements, q: &[f64], k: usize) -> Vec<CellQuality> {
    let mut idx: Vec<usize> = (0..q.len()).filter(|&i| !q[i].is_nan()).collect();
    let k = k.min(idx.len());
    if k == 0 {
        return Vec::new();
    }
    let by = |a: &usize, b: &usize| q[*a].total_cmp(&q[*b]).then(a.cmp(b));
    idx.select_nth_unstable_by(k - 1, by);
    idx.truncate(k);
    idx.sort_unstable_by(by);
    idx.into_iter()
        .map(|id| CellQuality {
            id,
            kind: cells.kind_of(id).unwrap_or(ElementKind::Line),
            quality: q[id],
        })
        .collect()
}

/// The summary of the field `q` over `cells` per element kind, in canonical kind order
/// (kinds present only).
///
/// ```
/// use mesh::{ElementKind, Elements, quality::summary_by_kind};
/// let mut e = Elements::new();
/// e.push(ElementKind::Tetra, &[0, 1, 2, 3], None);
/// e.push(ElementKind::Prism, &[0, 1, 2, 3, 4, 5], None);
/// e.push(ElementKind::Prism, &[0, 1, 2, 3, 4, 5], None);
/// let s = summary_by_kind(&e, &[0.5, -0.1, 0.9]);
/// assert_eq!((s[0].0, s[0].1.count), (ElementKind::Tetra, 1));
/// assert_eq!((s[1].0, s[1].1.count, s[1].1.n_nonpositive), (ElementKind::Prism, 2, 1));
/// ```
pub fn summary_by_kind(cells: &Elements, q: &[f64]) -> Vec<(ElementKind, Summary)> {
    let mut at = 0;
    let mut out = Vec::new();
    for g in cells.groups() {
        let n = g.len();
        if n > 0 && at + n <= q.len() {
            out.push((g.kind, summary(&q[at..at + n])));
        }
        at += n;
    }
    out
}

/// Summary statistics of a quality field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Summary {
    /// Number of values.
    pub count: usize,
    /// Number of measured (non-NaN) values.
    pub measured: usize,
    /// Smallest value.
    pub min: f64,
    /// Mean value.
    pub mean: f64,
    /// 1st percentile (nearest rank).
    pub p1: f64,
    /// Largest value.
    pub max: f64,
    /// Number of values ≤ 0 (flat or inverted elements).
    pub n_nonpositive: usize,
}

/// Summarises a quality field, ignoring NaN entries (deterministic: sequential sum).
///
/// ```
/// let s = mesh::quality::summary(&[1.0, 0.5, f64::NAN, -0.2]);
/// assert_eq!((s.count, s.measured, s.n_nonpositive), (4, 3, 1));
/// assert_eq!((s.min, s.max, s.p1), (-0.2, 1.0, -0.2));
/// ```
pub fn summary(q: &[f64]) -> Summary {
    let mut measured = 0;
    let (mut sum, mut n_nonpositive) = (0.0, 0);
    // Under `f64::total_cmp` (−0 < +0); used only when a value was measured.
    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
    for &x in q {
        if x.is_nan() {
            continue;
        }
        min = std::cmp::min_by(min, x, f64::total_cmp);
        max = std::cmp::max_by(max, x, f64::total_cmp);
        measured += 1;
        sum += x;
        n_nonpositive += usize::from(x <= 0.0);
    }
    if measured == 0 {
        return Summary {
            count: q.len(),
            measured: 0,
            min: f64::NAN,
            mean: f64::NAN,
            p1: f64::NAN,
            max: f64::NAN,
            n_nonpositive: 0,
        };
    }
    // The value of rank ⌈n/100⌉ in increasing order.
    let rank = ((0.01 * measured as f64).ceil() as usize).max(1) - 1;
    Summary {
        count: q.len(),
        measured,
        min,
        mean: sum / measured as f64,
        p1: nth_smallest(q, rank, min, max),
        max,
        n_nonpositive,
    }
}

/// The value of rank `rank` (from 0, increasing `total_cmp` order) among the non-NaN values
/// of `q`, whose smallest and largest are `min` and `max`: the values are counted in 4096
/// bins of equal width over [min, max] (a monotone map, so ranks are kept), and only the
/// bin holding the rank is searched (a selection). Two passes and no copy of the field;
/// falls back to a selection over all values if the range is not finite.
fn nth_smallest(q: &[f64], rank: usize, min: f64, max: f64) -> f64 {
    const BINS: usize = 4096;
    let width = max - min;
    if !(width.is_finite() && width > 0.0) {
        if width == 0.0 {
            // One value, or +0 and −0: the order of total_cmp decides.
            let below = q.iter().filter(|x| x.total_cmp(&max).is_lt()).count();
            return if rank < below { min } else { max };
        }
        let mut v: Vec<f64> = q.iter().copied().filter(|x| !x.is_nan()).collect();
        return *v.select_nth_unstable_by(rank, f64::total_cmp).1;
    }
    let scale = BINS as f64 / width;
    let bin = |x: f64| (((x - min) * scale) as usize).min(BINS - 1);
    let mut count = vec![0usize; BINS];
    for &x in q {
        if !x.is_nan() {
            count[bin(x)] += 1;
        }
    }
    let (mut b, mut below) = (0, 0);
    while below + count[b] <= rank {
        below += count[b];
        b += 1;
    }
    let mut v: Vec<f64> = q
        .iter()
        .copied()
        .filter(|&x| !x.is_nan() && bin(x) == b)
        .collect();
    *v.select_nth_unstable_by(rank - below, f64::total_cmp).1
}

/// One of the worst elements of a comparison.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WorstElement {
    /// Element id (canonical order of the cells).
    pub id: usize,
    /// Element kind.
    pub kind: ElementKind,
    /// Quality in the first grid.
    pub before: f64,
    /// Quality in the second grid.
    pub after: f64,
    /// `after / before`.
    pub ratio: f64,
    /// Centroid in the second grid.
    pub centroid: [f64; 3],
}

/// Comparison of two grids with the same connectivity (e.g. before and after deformation).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// Summary of the first grid's cell quality.
    pub before: Summary,
    /// Summary of the second grid's cell quality.
    pub after: Summary,
    /// Per cell, `after / before` (NaN where unmeasured).
    pub ratio: Vec<f64>,
    /// Summary of the ratios.
    pub ratio_summary: Summary,
    /// The cells with the lowest quality in the second grid, worst first (ties by id).
    pub worst: Vec<WorstElement>,
}

/// Compares the cell quality of `b` with that of `a`; they must have the same number of
/// nodes and the same cells. Reports the `n_worst` lowest-quality cells of `b`.
pub fn compare(a: &Mesh, b: &Mesh, n_worst: usize) -> Result<Comparison> {
    if a.n_nodes() != b.n_nodes() {
        return Err(Error::Mismatch {
            what: format!("{} nodes vs {}", a.n_nodes(), b.n_nodes()),
        });
    }
    if a.cells.groups().len() != b.cells.groups().len()
        || a.cells
            .groups()
            .iter()
            .zip(b.cells.groups())
            .any(|(g, h)| g.kind != h.kind || g.nodes != h.nodes)
    {
        return Err(Error::Mismatch {
            what: "cell connectivity differs".into(),
        });
    }
    let qa = cell_quality(a);
    let qb = cell_quality(b);
    let ratio: Vec<f64> = qa.iter().zip(&qb).map(|(x, y)| y / x).collect();
    let mut order: Vec<usize> = (0..qb.len()).filter(|&i| !qb[i].is_nan()).collect();
    order.sort_unstable_by(|&i, &j| qb[i].total_cmp(&qb[j]).then(i.cmp(&j)));
    let kinds: Vec<(ElementKind, &[u32])> = b.cells.iter().collect();
    let worst = order
        .iter()
        .take(n_worst)
        .map(|&i| {
            let (kind, nodes) = kinds[i];
            let mut c = [0.0; 3];
            for &v in nodes {
                for k in 0..3 {
                    c[k] += b.coords[v as usize][k];
                }
            }
            for ck in &mut c {
                *ck /= nodes.len() as f64;
            }
            WorstElement {
                id: i,
                kind,
                before: qa[i],
                after: qb[i],
                ratio: ratio[i],
                centroid: c,
            }
        })
        .collect();
    Ok(Comparison {
        before: summary(&qa),
        after: summary(&qb),
        ratio_summary: summary(&ratio),
        ratio,
        worst,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_equals_the_sorted_order_statistics() {
        // Repeated values, both zeros, negatives and NaN, several sizes around the 1 % rank.
        for n in [1usize, 2, 99, 100, 101, 1000, 4321] {
            let q: Vec<f64> = (0..n)
                .map(|i| match i % 11 {
                    3 => f64::NAN,
                    5 => -0.0,
                    7 => 0.0,
                    _ => ((i * 7919) % 257) as f64 / 128.0 - 0.5,
                })
                .collect();
            let s = summary(&q);
            let mut v: Vec<f64> = q.iter().copied().filter(|x| !x.is_nan()).collect();
            if v.is_empty() {
                assert_eq!(s.measured, 0);
                continue;
            }
            v.sort_unstable_by(f64::total_cmp);
            let rank = ((0.01 * v.len() as f64).ceil() as usize).max(1) - 1;
            assert_eq!(s.min.to_bits(), v[0].to_bits(), "n = {n}");
            assert_eq!(s.max.to_bits(), v[v.len() - 1].to_bits(), "n = {n}");
            assert_eq!(s.p1.to_bits(), v[rank].to_bits(), "n = {n}");
        }
    }

    proptest::proptest! {
        /// The binned selection against a sort, for values clustered in one bin, infinite,
        /// equal or signed zeros.
        #[test]
        fn summary_percentile_equals_the_sorted_one(
            q in proptest::collection::vec(
                proptest::prop_oneof![
                    -1.0f64..1.0,
                    0.5f64..0.5 + 1e-12,
                    proptest::sample::select(vec![0.0, -0.0, 1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY]),
                ],
                1..700,
            )
        ) {
            let mut v: Vec<f64> = q.iter().copied().filter(|x| !x.is_nan()).collect();
            let s = summary(&q);
            v.sort_unstable_by(f64::total_cmp);
            proptest::prop_assert_eq!(s.measured, v.len());
            if !v.is_empty() {
                let rank = ((0.01 * v.len() as f64).ceil() as usize).max(1) - 1;
                proptest::prop_assert_eq!(s.p1.to_bits(), v[rank].to_bits());
                proptest::prop_assert_eq!(s.min.to_bits(), v[0].to_bits());
                proptest::prop_assert_eq!(s.max.to_bits(), v[v.len() - 1].to_bits());
            }
        }
    }
}
