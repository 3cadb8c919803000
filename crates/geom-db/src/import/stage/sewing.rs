//! Stage 6, sewing: pieces joining the same two corners whose interior samples lie within
//! the sewing tolerance of each other become one sewn edge (the first piece is its master,
//! whose arcs become the support curve), shared by the faces that use it. The result lists
//! each sewn edge's uses — the faces on either side of it.

use std::collections::BTreeMap;

use super::super::model::Source;
use super::corners::Corners;
use super::edges::Edges;
use super::loops::Loops;
use super::{arcs_point, curve_samples, foot_on_arcs};
use crate::ids::CornerId;
use crate::prelude::Point3;

/// One use of a sewn edge by a face loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Use {
    /// The model face.
    pub face: usize,
    /// Its loop.
    pub lp: usize,
    /// Position in the loop.
    pub pos: usize,
    /// The loop runs against the master's direction here.
    pub reversed: bool,
}

/// A sewn edge: one future curve component.
#[derive(Debug, Clone)]
pub(crate) struct SewnEdge {
    /// The master piece (index into the edges).
    pub master: usize,
    /// Its corners (start, end of the master).
    pub corners: (CornerId, CornerId),
    /// Every use, in face order.
    pub uses: Vec<Use>,
    /// The curve entities merged into it (in order of appearance).
    pub sources: Vec<Source>,
}

/// What stage 6 produces.
pub(crate) struct Sewn {
    /// The sewn edges.
    pub edges: Vec<SewnEdge>,
    /// Per face, per loop: (sewn edge, traversed against its master) in loop order.
    pub loops: Vec<Vec<Vec<(usize, bool)>>>,
    /// Largest distance between merged pieces.
    pub max_gap: f64,
}

/// Runs stage 6.
pub(crate) fn run(edges: &Edges, loops: &Loops, corners: &Corners, sew: f64) -> Sewn {
    let e = &edges.edges;
    let ec = &corners.edge_corners;
    let samples: Vec<Vec<(f64, Point3)>> = e.iter().map(|x| curve_samples(&x.arcs, 16)).collect();
    // master[k] = (master piece, k runs against the master)
    let mut master: Vec<(usize, bool)> = (0..e.len()).map(|k| (k, false)).collect();
    let mut by_pair: BTreeMap<(CornerId, CornerId), Vec<usize>> = BTreeMap::new();
    for (k, &(a, b)) in ec.iter().enumerate() {
        by_pair.entry((a.min(b), a.max(b))).or_default().push(k);
    }
    let mut max_gap = corners.max_gap;
    for group in by_pair.values() {
        let mut masters: Vec<usize> = Vec::new();
        for &k in group {
            let mut found = None;
            for &m in &masters {
                // Coincident: k's samples lie on m.
                let probe: Vec<Point3> = (1..8)
                    .map(|j| arcs_point(&e[k].arcs, e[k].arcs.len() as f64 * j as f64 / 8.0))
                    .collect();
                let d = probe
                    .iter()
                    .map(|p| foot_on_arcs(&e[m].arcs, &samples[m], p).0)
                    .fold(0.0, f64::max);
                if d <= sew {
                    let against = if ec[k].0 != ec[k].1 {
                        ec[k].0 != ec[m].0
                    } else {
                        // Closed edges: compare the quarter points.
                        let q = arcs_point(&e[k].arcs, e[k].arcs.len() as f64 * 0.25);
                        let nm = e[m].arcs.len() as f64;
                        (arcs_point(&e[m].arcs, 0.75 * nm) - q).norm()
                            < (arcs_point(&e[m].arcs, 0.25 * nm) - q).norm()
                    };
                    max_gap = max_gap.max(d);
                    found = Some((m, against));
                    break;
                }
            }
            match found {
                Some(x) => master[k] = x,
                None => masters.push(k),
            }
        }
    }
    // Sewn edges in order of their masters.
    let mut sewn_of = vec![usize::MAX; e.len()];
    let mut out: Vec<SewnEdge> = Vec::new();
    for k in 0..e.len() {
        if master[k].0 == k {
            sewn_of[k] = out.len();
            out.push(SewnEdge {
                master: k,
                corners: ec[k],
                uses: Vec::new(),
                sources: Vec::new(),
            });
        }
    }
    for (k, piece) in e.iter().enumerate() {
        let s = &mut out[sewn_of[master[k].0]];
        if let Some(src) = &piece.src
            && !s.sources.contains(src)
        {
            s.sources.push(src.clone());
        }
    }
    let mut face_loops = Vec::with_capacity(loops.len());
    for (fi, face) in loops.iter().enumerate() {
        let mut fl = Vec::with_capacity(face.len());
        for (li, lp) in face.iter().enumerate() {
            let mut l = Vec::with_capacity(lp.len());
            for (pos, &(k, rev)) in lp.iter().enumerate() {
                let (m, against) = master[k];
                let sid = sewn_of[m];
                let reversed = rev ^ against;
                out[sid].uses.push(Use {
                    face: fi,
                    lp: li,
                    pos,
                    reversed,
                });
                l.push((sid, reversed));
            }
            fl.push(l);
        }
        face_loops.push(fl);
    }
    Sewn {
        edges: out,
        loops: face_loops,
        max_gap,
    }
}
