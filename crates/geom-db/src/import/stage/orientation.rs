//! Stage 7, orientation: each face's inward sign, then faces flipped so that neighbours
//! traverse their shared edges in opposite directions.
//!
//! * A face whose file gives its orientation in a shell (STEP `same_sense` and shell
//!   orientation, IGES 514 flags; the front ends turn its loops to run counter-clockwise
//!   about that normal) takes it: inward = + (S_u × S_v) when the normals agree.
//! * Otherwise the outer loop is placed on the face's exact surface (closed form or
//!   Gauss–Newton, Eq. 11, unwrapped across periods) and its signed area in (u, v) decides:
//!   counter-clockwise ⇒ +S_u × S_v (the loop convention of [`topology`](crate::topology)).
//! * A breadth-first walk over edges shared by two faces then flips faces (reverse loops and
//!   sign) so that the two uses run in opposite directions; conflicts are counted. Each
//!   connected set of faces is a shell.

use std::collections::VecDeque;

use super::super::model::CadModel;
use super::edges::Edges;
use super::faces::Faces;
use super::sewing::Sewn;
use super::{loop_polygon, shoelace};
use crate::topology::Orientation;
use rayon::prelude::*;

/// What stage 7 produces.
pub(crate) struct Oriented {
    /// Per face: its inward sign.
    pub inward: Vec<Orientation>,
    /// Per face, per loop: (sewn edge, reversed), after the flips.
    pub loops: Vec<Vec<Vec<(usize, bool)>>>,
    /// Per face: its shell.
    pub shell_of: Vec<usize>,
    /// Number of shells.
    pub n_shells: usize,
    /// Shared edges whose faces could not be oriented consistently.
    pub conflicts: usize,
}

/// Reverses a face: its loops run backwards and its inward sign changes.
pub(crate) fn flip_face(inward: &mut Orientation, loops: &mut [Vec<(usize, bool)>]) {
    for lp in loops.iter_mut() {
        lp.reverse();
        lp.iter_mut().for_each(|x| x.1 = !x.1);
    }
    *inward = match inward {
        Orientation::Positive => Orientation::Negative,
        Orientation::Negative => Orientation::Positive,
    };
}

/// Runs stage 7.
pub(crate) fn run(model: &CadModel, faces: &Faces, edges: &Edges, sewn: &Sewn) -> Oriented {
    let nf = model.faces.len();
    let mut loops = sewn.loops.clone();
    // Per face on its own, in parallel (a face without a sense from the file needs its outer
    // loop's exact parameters, which is much of the import's time).
    let mut inward: Vec<Orientation> = (0..nf)
        .into_par_iter()
        .map(|fi| match model.faces[fi].same_sense {
            Some(true) => Orientation::Positive,
            Some(false) => Orientation::Negative,
            None => {
                let poly = loop_polygon(model, faces, fi, &sewn.loops[fi][0], sewn, edges);
                let flat: Vec<(f64, f64)> = poly.into_iter().flatten().collect();
                if shoelace(&flat) >= 0.0 {
                    Orientation::Positive
                } else {
                    Orientation::Negative
                }
            }
        })
        .collect();
    // Breadth-first consistency over edges shared by exactly two faces.
    let mut adj: Vec<Vec<(usize, bool)>> = vec![Vec::new(); nf];
    for s in &sewn.edges {
        if let [a, b] = s.uses.as_slice()
            && a.face != b.face
        {
            // flips must differ iff the uses run the same way
            adj[a.face].push((b.face, a.reversed == b.reversed));
            adj[b.face].push((a.face, a.reversed == b.reversed));
        }
    }
    let mut flip: Vec<Option<bool>> = vec![None; nf];
    let mut shell_of = vec![usize::MAX; nf];
    let mut n_shells = 0;
    let mut conflicts = 0;
    for start in 0..nf {
        if flip[start].is_some() {
            continue;
        }
        flip[start] = Some(false);
        shell_of[start] = n_shells;
        let mut q = VecDeque::from([start]);
        while let Some(f) = q.pop_front() {
            for &(g, differ) in &adj[f] {
                let want = flip[f].expect("visited") ^ differ;
                match flip[g] {
                    None => {
                        flip[g] = Some(want);
                        shell_of[g] = n_shells;
                        q.push_back(g);
                    }
                    Some(x) if x != want => conflicts += 1,
                    _ => {}
                }
            }
        }
        n_shells += 1;
    }
    for fi in 0..nf {
        if flip[fi] == Some(true) {
            flip_face(&mut inward[fi], &mut loops[fi]);
        }
    }
    Oriented {
        inward,
        loops,
        shell_of,
        n_shells,
        conflicts,
    }
}
