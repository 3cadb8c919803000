//! The wall's parts ([`parts`]): its surface components grouped into wings, fuselages and
//! other parts by the role in each component's name, `<role>.<entity>` as the CAD import
//! names them after recognising them by shape (`wing.#31`, `fuselage.D17`, `wing_tip.#40`,
//! `fuselage_tail_cap.#52`), or as a person named them in a `.ron` (`wing`, `fuselage`).
//! A component of no known role that shares a curve with a wing and is at most half its
//! size (a tip cap, a trailing-edge strip) belongs to that wing.

use std::collections::{BTreeMap, BTreeSet};

use geom_db::prelude::Point3;
use geom_db::{CurveCompId, GeomDb};

/// What a part is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A lifting surface (`wing`, `wing_2`, …).
    Wing,
    /// A fuselage (`fuselage`, `fuselage_2`, …).
    Fuselage,
    /// Anything else (`body`, a pylon, a component named by hand).
    Other,
}

/// A part of the wall: a role and its surface components.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// The role (`wing`, `fuselage_2`, `body`, or the component's name).
    pub role: String,
    /// What it is.
    pub kind: Kind,
    /// Its own surface components (indices).
    pub comps: Vec<usize>,
    /// Caps that move with it (`wing_tip`, `fuselage_tail_cap`, or a small neighbour of a
    /// wing): no design variable of their own.
    pub caps: Vec<usize>,
}

/// The role in a component name: the text before the first `.`, lower case, blanks as `_`.
///
/// ```
/// use aeroshape::init::parts::role_of;
/// assert_eq!(role_of("wing.#31"), "wing");
/// assert_eq!(role_of("Tip cap"), "tip_cap");
/// ```
pub fn role_of(name: &str) -> String {
    name.split('.')
        .next()
        .unwrap_or("")
        .trim()
        .to_ascii_lowercase()
        .replace(char::is_whitespace, "_")
}

/// `base` or `base_<k>` (k ≥ 2).
fn numbered(role: &str, base: &str) -> bool {
    role == base
        || role
            .strip_prefix(base)
            .and_then(|r| r.strip_prefix('_'))
            .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
}

/// The part a cap role belongs to: `wing_tip` → `wing`, `fuselage_2_nose_cap` →
/// `fuselage_2`, `body_cap` → `body`.
fn cap_owner(role: &str) -> Option<&str> {
    ["_tip", "_nose_cap", "_tail_cap", "_cap"]
        .iter()
        .find_map(|s| role.strip_suffix(s))
}

/// The curve components bounding surface component `k`.
pub fn curves_of(db: &GeomDb, k: usize) -> BTreeSet<CurveCompId> {
    db.surface_components[k]
        .loops
        .iter()
        .flatten()
        .map(|oc| oc.comp)
        .collect()
}

/// Points along the boundary curves of surface component `k` (17 per curve).
pub fn boundary_points(db: &GeomDb, k: usize) -> Vec<Point3> {
    curves_of(db, k)
        .into_iter()
        .flat_map(|c| (0..=16).map(move |i| db.curve_component_point(c, i as f64 / 16.0)))
        .collect()
}

/// The box of `points` (lower, upper corner).
pub fn bbox(points: &[Point3]) -> (Point3, Point3) {
    let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let mut hi = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (lo, hi)
}

/// The diagonal of the box of the boundary of components `comps`.
fn size(db: &GeomDb, comps: &[usize]) -> f64 {
    let pts: Vec<Point3> = comps.iter().flat_map(|&k| boundary_points(db, k)).collect();
    let (lo, hi) = bbox(&pts);
    (hi - lo).norm()
}

/// The parts of the wall components `walls` (indices into `db.surface_components`), in
/// order of their first component.
pub fn parts(db: &GeomDb, walls: &[usize]) -> Vec<Part> {
    let mut by_role: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    let mut capped: Vec<(usize, String)> = Vec::new();
    for &k in walls {
        let role = role_of(&db.surface_components[k].name);
        let role = if role.is_empty() {
            format!("component{k}")
        } else {
            role
        };
        if let Some(owner) = cap_owner(&role)
            && (numbered(owner, "wing") || numbered(owner, "fuselage") || numbered(owner, "body"))
        {
            capped.push((k, owner.to_string()));
            continue;
        }
        if !by_role.contains_key(&role) {
            order.push(role.clone());
        }
        by_role.entry(role).or_default().push(k);
    }
    let mut parts: Vec<Part> = order
        .into_iter()
        .map(|role| {
            let kind = if numbered(&role, "wing") {
                Kind::Wing
            } else if numbered(&role, "fuselage") {
                Kind::Fuselage
            } else {
                Kind::Other
            };
            Part {
                comps: by_role.remove(&role).unwrap_or_default(),
                role,
                kind,
                caps: Vec::new(),
            }
        })
        .collect();
    for (k, owner) in capped {
        match parts.iter_mut().find(|p| p.role == owner) {
            Some(p) => p.caps.push(k),
            // a cap without its part: a part of its own
            None => parts.push(Part {
                role: role_of(&db.surface_components[k].name),
                kind: Kind::Other,
                comps: vec![k],
                caps: Vec::new(),
            }),
        }
    }
    // small neighbours of a wing with no role of their own move with it
    let wing_roles: Vec<String> = parts
        .iter()
        .filter(|p| p.kind == Kind::Wing)
        .map(|p| p.role.clone())
        .collect();
    for role in wing_roles {
        let Some(w) = parts.iter().position(|p| p.role == role) else {
            continue;
        };
        let wing_curves: BTreeSet<CurveCompId> = parts[w]
            .comps
            .iter()
            .flat_map(|&k| curves_of(db, k))
            .collect();
        let wing_size = size(db, &parts[w].comps);
        let small_neighbours: Vec<usize> = (0..parts.len())
            .filter(|&i| {
                let p = &parts[i];
                p.kind == Kind::Other
                    && p.comps.len() == 1
                    && !curves_of(db, p.comps[0]).is_disjoint(&wing_curves)
                    && size(db, &p.comps) <= 0.5 * wing_size
            })
            .collect();
        let mut caps = Vec::new();
        for &i in small_neighbours.iter().rev() {
            caps.extend(parts.remove(i).comps);
        }
        if let Some(w) = parts.iter_mut().find(|p| p.role == role) {
            w.caps.extend(caps);
            w.caps.sort_unstable();
        }
    }
    parts
}

/// The curve components shared by a component of `a` and one of `b` (their junctions).
pub fn shared_curves(db: &GeomDb, a: &[usize], b: &[usize]) -> Vec<CurveCompId> {
    let ca: BTreeSet<CurveCompId> = a.iter().flat_map(|&k| curves_of(db, k)).collect();
    let cb: BTreeSet<CurveCompId> = b.iter().flat_map(|&k| curves_of(db, k)).collect();
    ca.intersection(&cb).copied().collect()
}
