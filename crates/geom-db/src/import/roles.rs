//! What each imported face is: a symmetry plane, the far field, or part of a body (a wing
//! or another body), recognised from the geometry and the sewn topology alone, so that an
//! imported half model comes out with the component names a case file uses.
//!
//! * **Symmetry plane**: a face whose boundary and support surface lie in one
//!   axis-aligned plane that is a side of the model's bounding box (e.g. y = 0 for a half
//!   model), within the "same point" tolerance. Only axis-aligned planes are recognised:
//!   that is how half models are built in practice.
//! * **Bodies and far field**: the other faces are grouped into connected sets through the
//!   curve components they share (the symmetry plane does not connect them). When there are
//!   several sets and the largest one's bounding box contains all the others, it is the far
//!   field.
//! * **Wing or body**: a set whose bounding box is thin in one direction (smallest extent
//!   below a quarter of the middle one: a wing's thickness against its chord) is a wing;
//!   otherwise a body (a fuselage is about as high as it is wide).

use std::collections::BTreeMap;

use crate::eval::{ParamCurve, ParamSurface};
use crate::prelude::Point3;
use crate::{CurveCompId, GeomDb};

/// The role of a face (surface component).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaceRole {
    /// In a symmetry plane x, y or z = constant (axis 0, 1, 2) on the model's boundary.
    Symmetry {
        /// The plane's normal axis.
        axis: usize,
    },
    /// Encloses every other face.
    FarField,
    /// Part of the `k`-th wing-like set (thin in one direction), counted from 0.
    Wing(usize),
    /// Part of the `k`-th other body, counted from 0.
    Body(usize),
}

impl FaceRole {
    /// The component name for this role: `symmetry`, `farfield`, `wing` (`wing 2`, …) or
    /// `body` (`body 2`, …).
    pub fn name(self) -> String {
        let numbered = |base: &str, k: usize| {
            if k == 0 {
                base.to_string()
            } else {
                format!("{base} {}", k + 1)
            }
        };
        match self {
            Self::Symmetry { .. } => "symmetry".into(),
            Self::FarField => "farfield".into(),
            Self::Wing(k) => numbered("wing", k),
            Self::Body(k) => numbered("body", k),
        }
    }
}

/// Samples per curve component for extents.
const CURVE_SAMPLES: usize = 32;
/// Samples per direction of a support surface for the planarity check.
const SURFACE_SAMPLES: usize = 9;

fn bounds(points: impl IntoIterator<Item = Point3>) -> Option<(Point3, Point3)> {
    points.into_iter().fold(None, |acc, p| match acc {
        None => Some((p, p)),
        Some((lo, hi)) => Some((lo.inf(&p), hi.sup(&p))),
    })
}

fn curve_samples(db: &GeomDb, id: CurveCompId) -> impl Iterator<Item = Point3> + '_ {
    let cc = db.curve_component(id);
    let c = db.curve(cc.curve);
    (0..=CURVE_SAMPLES).map(move |k| c.point(cc.param_at(k as f64 / CURVE_SAMPLES as f64)))
}

/// The role of every surface component of `db` (same order as `db.surface_components`);
/// `tol` (model units) decides whether a face lies in a plane (the import uses its sewing
/// tolerance).
pub fn recognise(db: &GeomDb, tol: f64) -> Vec<FaceRole> {
    let n = db.surface_components.len();
    let face_curves: Vec<Vec<CurveCompId>> = db
        .surface_components
        .iter()
        .map(|f| f.loops.iter().flatten().map(|oc| oc.comp).collect())
        .collect();
    let face_box: Vec<Option<(Point3, Point3)>> = face_curves
        .iter()
        .map(|cs| bounds(cs.iter().flat_map(|&c| curve_samples(db, c))))
        .collect();
    let Some(model) = bounds(face_box.iter().flatten().flat_map(|&(lo, hi)| [lo, hi])) else {
        return vec![FaceRole::Body(0); n];
    };

    let mut roles: Vec<Option<FaceRole>> = vec![None; n];
    for (i, f) in db.surface_components.iter().enumerate() {
        let Some((lo, hi)) = face_box[i] else {
            continue;
        };
        let s = db.surface(f.surface);
        let ([u0, u1], [v0, v1]) = s.domain();
        for axis in 0..3 {
            if hi[axis] - lo[axis] > tol {
                continue;
            }
            let c = 0.5 * (lo[axis] + hi[axis]);
            let on_side = (c - model.0[axis]).abs() <= tol || (c - model.1[axis]).abs() <= tol;
            let planar = (0..=SURFACE_SAMPLES).all(|a| {
                (0..=SURFACE_SAMPLES).all(|b| {
                    let p = s.point(
                        u0 + (u1 - u0) * a as f64 / SURFACE_SAMPLES as f64,
                        v0 + (v1 - v0) * b as f64 / SURFACE_SAMPLES as f64,
                    );
                    (p[axis] - c).abs() <= tol
                })
            });
            if on_side && planar {
                roles[i] = Some(FaceRole::Symmetry { axis });
                break;
            }
        }
    }

    // Connected sets of the other faces through shared curve components.
    let mut users: BTreeMap<CurveCompId, Vec<usize>> = BTreeMap::new();
    for (i, cs) in face_curves.iter().enumerate() {
        if roles[i].is_none() {
            for &c in cs {
                users.entry(c).or_default().push(i);
            }
        }
    }
    let mut set_of = vec![usize::MAX; n];
    let mut sets: Vec<Vec<usize>> = Vec::new();
    for start in 0..n {
        if roles[start].is_some() || set_of[start] != usize::MAX {
            continue;
        }
        let k = sets.len();
        let mut members = vec![start];
        set_of[start] = k;
        let mut next = 0;
        while next < members.len() {
            let f = members[next];
            next += 1;
            for c in &face_curves[f] {
                for &g in &users[c] {
                    if set_of[g] == usize::MAX {
                        set_of[g] = k;
                        members.push(g);
                    }
                }
            }
        }
        sets.push(members);
    }
    let set_box: Vec<Option<(Point3, Point3)>> = sets
        .iter()
        .map(|m| {
            bounds(
                m.iter()
                    .flat_map(|&f| face_box[f])
                    .flat_map(|(a, b)| [a, b]),
            )
        })
        .collect();
    let diag = |b: Option<(Point3, Point3)>| b.map_or(0.0, |(lo, hi)| (hi - lo).norm());
    let largest = (0..sets.len()).max_by(|&a, &b| diag(set_box[a]).total_cmp(&diag(set_box[b])));
    let far_field = largest.filter(|&l| {
        sets.len() > 1
            && (0..sets.len()).all(|k| {
                k == l
                    || match (set_box[l], set_box[k]) {
                        (Some((llo, lhi)), Some((klo, khi))) => {
                            (0..3).all(|a| llo[a] <= klo[a] + tol && khi[a] <= lhi[a] + tol)
                        }
                        _ => true,
                    }
            })
    });
    let (mut wings, mut bodies) = (0, 0);
    for (k, members) in sets.iter().enumerate() {
        let role = if Some(k) == far_field {
            FaceRole::FarField
        } else {
            let mut e = set_box[k].map_or([0.0; 3], |(lo, hi)| (hi - lo).into());
            e.sort_by(f64::total_cmp);
            if e[0] < 0.25 * e[1] {
                wings += 1;
                FaceRole::Wing(wings - 1)
            } else {
                bodies += 1;
                FaceRole::Body(bodies - 1)
            }
        };
        for &f in members {
            roles[f] = Some(role);
        }
    }
    roles
        .into_iter()
        .map(|r| r.unwrap_or(FaceRole::Body(0)))
        .collect()
}
