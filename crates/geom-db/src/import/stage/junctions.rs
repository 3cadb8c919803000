//! Stage 5, T-junctions: a corner within the sewing tolerance of another edge's interior
//! (foot of the normal by sampling then Newton, Eq. 11) splits that edge there (exact
//! sub-arcs by re-interpolation at the control nodes), so that edges split differently on
//! the two sides of a seam still sew.

use super::corners::Corners;
use super::edges::{Edge, Edges};
use super::loops::Loops;
use super::{arcs_point, curve_samples, foot_on_arcs, split_arcs};
use crate::ids::CornerId;

/// Runs stage 5: the split edges replace the originals in `edges`, `loops` and `corners`.
pub(crate) fn run(edges: &mut Edges, loops: &mut Loops, corners: &mut Corners, sew: f64) {
    let old = std::mem::take(&mut edges.edges);
    let mut new_edges: Vec<Edge> = Vec::with_capacity(old.len());
    let mut new_corners = Vec::with_capacity(old.len());
    let mut replaced: Vec<Vec<usize>> = Vec::with_capacity(old.len());
    for (e, ed) in old.into_iter().enumerate() {
        let samples = curve_samples(&ed.arcs, 8);
        let (mut lo, mut hi) = (samples[0].1, samples[0].1);
        for (_, q) in &samples {
            lo = lo.inf(q);
            hi = hi.sup(q);
        }
        let n = ed.arcs.len() as f64;
        let (c0, c1) = corners.edge_corners[e];
        let mut cuts: Vec<(f64, CornerId)> = Vec::new();
        for (ci, c) in corners.points.iter().enumerate() {
            let cid = CornerId::from_index(ci);
            if cid == c0 || cid == c1 {
                continue;
            }
            let inside = (0..3).all(|k| c[k] >= lo[k] - sew && c[k] <= hi[k] + sew);
            if !inside {
                continue;
            }
            let (d, t) = foot_on_arcs(&ed.arcs, &samples, c);
            let ps = arcs_point(&ed.arcs, t);
            if d <= sew
                && (ps - ed.start).norm() > sew
                && (ps - ed.end).norm() > sew
                && t > 0.0
                && t < n
            {
                corners.max_gap = corners.max_gap.max(d);
                cuts.push((t, cid));
            }
        }
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut ids = Vec::new();
        let mut t_prev = 0.0;
        let mut c_prev = c0;
        let mut p_prev = ed.start;
        for (t, cid) in cuts.into_iter().chain(std::iter::once((n, c1))) {
            if t - t_prev <= 1e-9 * n {
                continue;
            }
            let arcs = split_arcs(&ed.arcs, t_prev, t);
            let end = if t == n {
                ed.end
            } else {
                arcs_point(&ed.arcs, t)
            };
            new_edges.push(Edge {
                face: ed.face,
                src: ed.src.clone(),
                file_edge: ed.file_edge.clone(),
                arcs,
                start: p_prev,
                end,
            });
            new_corners.push((c_prev, cid));
            ids.push(new_edges.len() - 1);
            t_prev = t;
            c_prev = cid;
            p_prev = end;
        }
        replaced.push(ids);
    }
    edges.edges = new_edges;
    corners.edge_corners = new_corners;
    for face in loops.iter_mut() {
        for lp in face.iter_mut() {
            let mut out = Vec::with_capacity(lp.len());
            for &(e, rev) in lp.iter() {
                let ids = &replaced[e];
                if rev {
                    out.extend(ids.iter().rev().map(|&k| (k, true)));
                } else {
                    out.extend(ids.iter().map(|&k| (k, false)));
                }
            }
            *lp = out;
        }
    }
}
