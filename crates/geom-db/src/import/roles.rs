//! What each imported face is, recognised by shape from the geometry and the sewn topology
//! alone (never from the entity order), so that an imported model comes out with names a
//! person can read: `fuselage`, `wing`, `wing_tip`, `fuselage_tail_cap`, `symmetry`,
//! `farfield`.
//!
//! 1. **Symmetry plane**: a planar face in an axis-aligned plane through the origin
//!    (x, y or z = 0) that is a side of the model's bounding box (e.g. y = 0 of a half
//!    model).
//! 2. **Far field**: the other faces are grouped into connected sets through the curve
//!    components they share (the symmetry plane does not connect them); when there are
//!    several sets and the largest one's bounding box holds all the others, it is the far
//!    field.
//! 3. **Thin and thick faces**: each curved face's support surface is sampled and its
//!    principal extents (square roots of the eigenvalues of the samples' covariance) are
//!    compared: the smallest below a quarter of the middle one is *thin* (a lifting
//!    surface: thickness against chord, whatever the sweep or dihedral), otherwise *thick*.
//!    Curved faces of one kind connected through shared curves form a component.
//! 4. **Caps**: a planar face, or a thick component next to a wing (a rounded tip), all of whose
//!    neighbours (the symmetry plane aside) belong to one component and whose size
//!    (bounding-box diagonal) is at most half the component's is a cap of that component: `wing_tip`, or a fuselage's `nose_cap`/`tail_cap` (by
//!    where it lies along the fuselage's long axis, "tail" towards +x, y or z). Another
//!    planar face (e.g. a flat trailing-edge strip) joins the component it shares most
//!    curves with.
//! 5. **Names**: a thin component is a `wing`; a thick one is a `fuselage` when it is long
//!    (its largest principal extent at least twice the next), a `body` otherwise. The k-th
//!    (k ≥ 2) of a kind is numbered `wing_2`, `wing_2_tip`, ….
//!
//! `aeroshape geom import --roles FILE.ron` overrides the guess (see
//! [`ImportOptions::roles`](super::ImportOptions::roles)).

use std::collections::BTreeMap;

use crate::eval::{ParamCurve, ParamSurface};
use crate::prelude::{Matrix3, Point3, Vector3};
use crate::{CurveCompId, GeomDb};

/// The role of a face (surface component).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaceRole {
    /// In a symmetry plane x, y or z = 0 (axis 0, 1, 2) on the model's boundary.
    Symmetry {
        /// The plane's normal axis.
        axis: usize,
    },
    /// Encloses every other face.
    FarField,
    /// Part of the `k`-th wing (thin lifting surface), counted from 0.
    Wing(usize),
    /// The planar tip cap of the `k`-th wing.
    WingTip(usize),
    /// Part of the `k`-th fuselage (long thick body), counted from 0.
    Fuselage(usize),
    /// A planar end cap of the `k`-th fuselage.
    FuselageCap {
        /// The fuselage.
        k: usize,
        /// True at the downstream end (towards + of the long axis), false at the nose.
        tail: bool,
    },
    /// Part of the `k`-th other thick body, counted from 0.
    Body(usize),
    /// A planar cap of the `k`-th other body.
    BodyCap(usize),
}

impl FaceRole {
    /// The component name for this role: `symmetry`, `farfield`, `wing`, `wing_tip`,
    /// `fuselage`, `fuselage_nose_cap`, `fuselage_tail_cap`, `body`, `body_cap`; the k-th
    /// (k ≥ 2) of a kind is `wing_2`, `wing_2_tip`, ….
    pub fn name(self) -> String {
        let numbered = |base: &str, k: usize, suffix: &str| {
            let mut s = base.to_string();
            if k > 0 {
                s += &format!("_{}", k + 1);
            }
            s + suffix
        };
        match self {
            Self::Symmetry { .. } => "symmetry".into(),
            Self::FarField => "farfield".into(),
            Self::Wing(k) => numbered("wing", k, ""),
            Self::WingTip(k) => numbered("wing", k, "_tip"),
            Self::Fuselage(k) => numbered("fuselage", k, ""),
            Self::FuselageCap { k, tail } => {
                numbered("fuselage", k, if tail { "_tail_cap" } else { "_nose_cap" })
            }
            Self::Body(k) => numbered("body", k, ""),
            Self::BodyCap(k) => numbered("body", k, "_cap"),
        }
    }
}

/// Samples per curve component for extents.
const CURVE_SAMPLES: usize = 32;
/// Samples per direction of a support surface for planarity and principal extents.
const SURFACE_SAMPLES: usize = 12;
/// Thin: smallest principal extent below this fraction of the middle one.
const THIN: f64 = 0.25;
/// Long: largest principal extent at least this multiple of the middle one.
const LONG: f64 = 2.0;
/// A cap is at most this fraction of its component's size.
const CAP: f64 = 0.5;

type Bounds = (Point3, Point3);

fn bounds(points: impl IntoIterator<Item = Point3>) -> Option<Bounds> {
    points.into_iter().fold(None, |acc, p| match acc {
        None => Some((p, p)),
        Some((lo, hi)) => Some((lo.inf(&p), hi.sup(&p))),
    })
}

fn diag(b: Option<Bounds>) -> f64 {
    b.map_or(0.0, |(lo, hi)| (hi - lo).norm())
}

fn curve_samples(db: &GeomDb, id: CurveCompId) -> impl Iterator<Item = Point3> + '_ {
    let cc = db.curve_component(id);
    let c = db.curve(cc.curve);
    (0..=CURVE_SAMPLES).map(move |k| c.point(cc.param_at(k as f64 / CURVE_SAMPLES as f64)))
}

/// Centroid and principal axes (columns, by increasing extent) with extents (square roots
/// of the covariance's eigenvalues, increasing).
fn principal(points: &[Point3]) -> (Point3, Matrix3, [f64; 3]) {
    let n = points.len().max(1) as f64;
    let c = points.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n;
    let cov = points.iter().fold(Matrix3::zeros(), |a, p| {
        let d = p.coords - c;
        a + d * d.transpose()
    }) / n;
    let eig = cov.symmetric_eigen();
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let axes = Matrix3::from_columns(&order.map(|i| eig.eigenvectors.column(i).into_owned()));
    let ext = order.map(|i| eig.eigenvalues[i].max(0.0).sqrt());
    (Point3::from(c), axes, ext)
}

/// What the recognition needs of one face.
struct FaceShape {
    /// Curve components of its loops.
    curves: Vec<CurveCompId>,
    /// Bounding box of its boundary.
    bounds: Option<Bounds>,
    /// Samples of its support surface.
    samples: Vec<Point3>,
    /// Within `tol` of one plane (support and boundary).
    planar: bool,
}

fn shape(db: &GeomDb, i: usize, tol: f64) -> FaceShape {
    let f = &db.surface_components[i];
    let curves: Vec<CurveCompId> = f.loops.iter().flatten().map(|oc| oc.comp).collect();
    let boundary: Vec<Point3> = curves.iter().flat_map(|&c| curve_samples(db, c)).collect();
    let s = db.surface(f.surface);
    let ([u0, u1], [v0, v1]) = s.domain();
    let m = SURFACE_SAMPLES as f64;
    let samples: Vec<Point3> = (0..=SURFACE_SAMPLES)
        .flat_map(|a| {
            (0..=SURFACE_SAMPLES)
                .map(move |b| s.point(u0 + (u1 - u0) * a as f64 / m, v0 + (v1 - v0) * b as f64 / m))
        })
        .collect();
    let all: Vec<Point3> = samples.iter().chain(&boundary).copied().collect();
    let (c, axes, _) = principal(&all);
    let normal = axes.column(0).into_owned();
    let planar = all.iter().all(|p| (p - c).dot(&normal).abs() <= tol);
    FaceShape {
        curves,
        bounds: bounds(boundary),
        samples,
        planar,
    }
}

/// The role of every surface component of `db` (same order as `db.surface_components`);
/// `tol` (model units) decides whether a face lies in a plane (the import uses its sewing
/// tolerance).
pub fn recognise(db: &GeomDb, tol: f64) -> Vec<FaceRole> {
    let n = db.surface_components.len();
    let shapes: Vec<FaceShape> = (0..n).map(|i| shape(db, i, tol)).collect();
    let Some(model) = bounds(
        shapes
            .iter()
            .flat_map(|s| s.bounds)
            .flat_map(|(lo, hi)| [lo, hi]),
    ) else {
        return vec![FaceRole::Body(0); n];
    };
    let mut roles: Vec<Option<FaceRole>> = vec![None; n];

    // 1. Symmetry planes.
    for (i, sh) in shapes.iter().enumerate() {
        let Some((lo, hi)) = sh.bounds else { continue };
        if !sh.planar {
            continue;
        }
        for axis in 0..3 {
            let c = 0.5 * (lo[axis] + hi[axis]);
            let on_side = (c - model.0[axis]).abs() <= tol || (c - model.1[axis]).abs() <= tol;
            let flat =
                hi[axis] - lo[axis] <= tol && sh.samples.iter().all(|p| (p[axis] - c).abs() <= tol);
            if flat && on_side && c.abs() <= tol {
                roles[i] = Some(FaceRole::Symmetry { axis });
                break;
            }
        }
    }

    // Neighbours through shared curve components (the symmetry plane aside).
    let mut users: BTreeMap<CurveCompId, Vec<usize>> = BTreeMap::new();
    for (i, sh) in shapes.iter().enumerate() {
        if roles[i].is_none() {
            for &c in &sh.curves {
                users.entry(c).or_default().push(i);
            }
        }
    }
    let neighbours = |i: usize| -> Vec<usize> {
        let mut v: Vec<usize> = shapes[i]
            .curves
            .iter()
            .flat_map(|c| users.get(c).into_iter().flatten().copied())
            .filter(|&g| g != i)
            .collect();
        v.sort_unstable();
        v
    };

    // 2. The far field: connected sets; the largest holds every other.
    let sets = connected(n, |i| roles[i].is_none(), |_, _| true, &neighbours);
    let set_box: Vec<Option<Bounds>> = sets
        .iter()
        .map(|m| {
            bounds(
                m.iter()
                    .flat_map(|&f| shapes[f].bounds)
                    .flat_map(|(a, b)| [a, b]),
            )
        })
        .collect();
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
    if let Some(l) = far_field {
        for &f in &sets[l] {
            roles[f] = Some(FaceRole::FarField);
        }
    }

    // 3. Curved faces: thin or thick, grouped by kind.
    let thin: Vec<bool> = shapes
        .iter()
        .map(|sh| {
            let (_, _, e) = principal(&sh.samples);
            e[0] < THIN * e[1]
        })
        .collect();
    let curved = |i: usize| roles[i].is_none() && !shapes[i].planar;
    let groups = connected(n, curved, |i, g| thin[i] == thin[g], &neighbours);
    let mut group_of = vec![usize::MAX; n];
    for (k, m) in groups.iter().enumerate() {
        for &f in m {
            group_of[f] = k;
        }
    }
    let mut members = groups.clone();
    let group_size = |m: &[usize]| {
        diag(bounds(
            m.iter()
                .flat_map(|&f| shapes[f].bounds)
                .flat_map(|(a, b)| [a, b]),
        ))
    };

    // 4. Caps: a small thick component closing a wing (a rounded tip) ...
    let mut cap_of: Vec<Option<usize>> = vec![None; n];
    for k in 0..groups.len() {
        let mut outer: Vec<usize> = groups[k]
            .iter()
            .flat_map(|&f| neighbours(f))
            .filter(|&g| group_of[g] != usize::MAX && group_of[g] != k)
            .map(|g| group_of[g])
            .collect();
        outer.sort_unstable();
        outer.dedup();
        if let [g] = outer[..]
            && thin[groups[g][0]]
            && !thin[groups[k][0]]
            && cap_of[groups[g][0]].is_none()
            && group_size(&groups[k]) <= CAP * group_size(&groups[g])
        {
            for &f in &groups[k] {
                cap_of[f] = Some(g);
                group_of[f] = usize::MAX;
            }
            members[k].clear();
        }
    }
    // ... and planar faces: caps, or part of a neighbouring component.
    for i in 0..n {
        if roles[i].is_some() || !shapes[i].planar {
            continue;
        }
        let nb: Vec<usize> = neighbours(i)
            .into_iter()
            .filter(|&g| group_of[g] != usize::MAX)
            .map(|g| group_of[g])
            .collect();
        let Some(&first) = nb.first() else {
            // A planar face on its own: a component of its own.
            group_of[i] = members.len();
            members.push(vec![i]);
            continue;
        };
        if nb.iter().all(|&g| g == first)
            && diag(shapes[i].bounds) <= CAP * group_size(&members[first])
        {
            cap_of[i] = Some(first);
            continue;
        }
        let mut count: BTreeMap<usize, usize> = BTreeMap::new();
        for &g in &nb {
            *count.entry(g).or_default() += 1;
        }
        let best = count
            .iter()
            .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
            .map_or(first, |(&g, _)| g);
        group_of[i] = best;
        members[best].push(i);
    }

    // 5. Names.
    let (mut wings, mut fuselages, mut bodies) = (0, 0, 0);
    let mut kind: Vec<FaceRole> = Vec::with_capacity(members.len());
    let mut long_axis: Vec<(Vector3, f64)> = Vec::with_capacity(members.len());
    for m in &members {
        if m.is_empty() {
            kind.push(FaceRole::Body(usize::MAX));
            long_axis.push((Vector3::zeros(), 0.0));
            continue;
        }
        let samples: Vec<Point3> = m.iter().flat_map(|&f| shapes[f].samples.clone()).collect();
        let (c, axes, e) = principal(&samples);
        let is_thin = m.iter().any(|&f| !shapes[f].planar && thin[f]);
        let mut a = axes.column(2).into_owned();
        let dominant = (0..3)
            .max_by(|&x, &y| a[x].abs().total_cmp(&a[y].abs()))
            .unwrap_or(0);
        if a[dominant] < 0.0 {
            a = -a;
        }
        long_axis.push((a, a.dot(&c.coords)));
        kind.push(if is_thin {
            wings += 1;
            FaceRole::Wing(wings - 1)
        } else if e[2] >= LONG * e[1] {
            fuselages += 1;
            FaceRole::Fuselage(fuselages - 1)
        } else {
            bodies += 1;
            FaceRole::Body(bodies - 1)
        });
    }
    for i in 0..n {
        if roles[i].is_some() {
            continue;
        }
        roles[i] = Some(if let Some(g) = cap_of[i] {
            match kind[g] {
                FaceRole::Wing(k) => FaceRole::WingTip(k),
                FaceRole::Fuselage(k) => {
                    let (a, mid) = long_axis[g];
                    let c = shapes[i]
                        .bounds
                        .map_or(Point3::origin(), |(lo, hi)| lo + 0.5 * (hi - lo));
                    FaceRole::FuselageCap {
                        k,
                        tail: a.dot(&c.coords) > mid,
                    }
                }
                FaceRole::Body(k) => FaceRole::BodyCap(k),
                other => other,
            }
        } else if group_of[i] != usize::MAX {
            kind[group_of[i]]
        } else {
            FaceRole::Body(0)
        });
    }
    roles
        .into_iter()
        .map(|r| r.unwrap_or(FaceRole::Body(0)))
        .collect()
}

/// Connected sets of the faces that pass `keep`, joined across shared curves where `join`
/// allows it; each set lists its faces in increasing order of discovery.
fn connected(
    n: usize,
    keep: impl Fn(usize) -> bool,
    join: impl Fn(usize, usize) -> bool,
    neighbours: &impl Fn(usize) -> Vec<usize>,
) -> Vec<Vec<usize>> {
    let mut set_of = vec![usize::MAX; n];
    let mut sets: Vec<Vec<usize>> = Vec::new();
    for start in 0..n {
        if !keep(start) || set_of[start] != usize::MAX {
            continue;
        }
        let k = sets.len();
        let mut members = vec![start];
        set_of[start] = k;
        let mut next = 0;
        while next < members.len() {
            let f = members[next];
            next += 1;
            for g in neighbours(f) {
                if keep(g) && set_of[g] == usize::MAX && join(f, g) {
                    set_of[g] = k;
                    members.push(g);
                }
            }
        }
        sets.push(members);
    }
    sets
}
