//! Stage 8, shells: each connected set of faces, its enclosed volume V = ⅓ ∮ x·n dA (with
//! Green's theorem in each face's parameter plane), whether it is closed, and the global
//! choice of normals: every shell is turned to V > 0, i.e. the inward normal (towards the
//! region to be meshed) points away from the volume the shell encloses, as for a body
//! (OpenCASCADE's outward normals of a solid). A shell that encloses the fluid (a far
//! field, recognised by [`roles`](super::super::roles)) is turned round by the database
//! stage, and so is every shell with
//! [`ImportOptions::flip`](super::super::ImportOptions::flip).

use super::super::model::CadModel;
use super::corners::Corners;
use super::edges::Edges;
use super::faces::Faces;
use super::orientation::{Oriented, flip_face};
use super::sewing::Sewn;
use super::{green_flux_area, loop_polygon};
use crate::prelude::Point3;
use rayon::prelude::*;

/// What stage 8 produces.
pub(crate) struct Shells {
    /// Enclosed volume per shell, with the final normals.
    pub volumes: Vec<f64>,
    /// Bounding-box diagonal of each shell's corners.
    pub sizes: Vec<f64>,
    /// Every edge of the shell is used twice.
    pub closed: Vec<bool>,
    /// Per face: its area.
    pub areas: Vec<f64>,
}

/// Runs stage 8, flipping shells in `oriented`.
pub(crate) fn run(
    model: &CadModel,
    faces: &Faces,
    edges: &Edges,
    corners: &Corners,
    sewn: &Sewn,
    oriented: &mut Oriented,
) -> Shells {
    let n = oriented.n_shells;
    let mut volumes = vec![0.0; n];
    let mut areas = vec![0.0; oriented.loops.len()];
    let inf = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let mut boxes = vec![(inf, -inf); n];
    // Each loop's (flux, area) on its own, in parallel (the surface integrals are most of
    // the import's time); summed below in loop order, so the result does not depend on the
    // number of threads.
    let integrals: Vec<Vec<(f64, f64)>> = oriented
        .loops
        .par_iter()
        .enumerate()
        .map(|(fi, loops)| {
            loops
                .iter()
                .map(|lp| {
                    let poly = loop_polygon(model, faces, fi, lp, sewn, edges);
                    green_flux_area(faces, fi, &poly)
                })
                .collect()
        })
        .collect();
    for (fi, loops) in oriented.loops.iter().enumerate() {
        let sh = oriented.shell_of[fi];
        for (lp, &(flux, area)) in loops.iter().zip(&integrals[fi]) {
            volumes[sh] += flux / 3.0;
            areas[fi] += area * oriented.inward[fi].sign();
            for &(s, _) in lp {
                let (a, b) = sewn.edges[s].corners;
                for p in [corners.points[a.index()], corners.points[b.index()]] {
                    boxes[sh].0 = boxes[sh].0.inf(&p);
                    boxes[sh].1 = boxes[sh].1.sup(&p);
                }
            }
        }
    }
    let sizes: Vec<f64> = boxes
        .iter()
        .map(|(a, b)| {
            let d = (b - a).norm();
            if d.is_finite() { d } else { 0.0 }
        })
        .collect();
    let mut shell_flip = vec![false; n];
    for sh in 0..n {
        shell_flip[sh] = volumes[sh] < 0.0;
        if shell_flip[sh] {
            volumes[sh] = -volumes[sh];
        }
    }
    for fi in 0..oriented.loops.len() {
        if shell_flip[oriented.shell_of[fi]] {
            let (inward, loops) = (&mut oriented.inward[fi], &mut oriented.loops[fi]);
            flip_face(inward, loops);
        }
    }
    let mut closed = vec![true; n];
    for s in &sewn.edges {
        if s.uses.len() != 2 {
            for u in &s.uses {
                closed[oriented.shell_of[u.face]] = false;
            }
        }
    }
    Shells {
        volumes,
        sizes,
        closed,
        areas,
    }
}
