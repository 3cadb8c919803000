//! The nose droop (Fig. 10) and stretch (Fig. 12) `case init` proposes for a fuselage
//! ([`nose`]): two line modifiers along the fuselage's long axis (`param::LineSupport::Axis`,
//! Eq. 36 with s the coordinate along a straight line), both acting on every control node of
//! the fuselage and its caps ahead of a section x = x_s and on none behind it:
//!
//! * `<role>.droop` bends the nose down (positive: along −z, the vertical being the axis
//!   across both the fuselage and the wing's span): Δr = δ s² (−e_z) with
//!   s = (x_s − x) / (x_s − x_nose), zero with zero slope at x_s, δ at the nose tip;
//! * `<role>.stretch` lengthens the forward fuselage: Δr = δ s (−e_x), the affine map
//!   x ↦ x − δ (x_s − x) / (x_s − x_nose) of the part ahead of x_s; the nose tip moves forward
//!   by δ, so the fuselage is δ longer.
//!
//! x_s is the smallest axial coordinate of the control nodes of every fuselage patch that
//! reaches the wing junction widened by a quarter of its length on each side (the waist's
//! region; without a wing, the middle third): no patch that holds the junction or the waist
//! changes, so the junction is re-intersected on an unchanged fuselage and the aft body keeps
//! its bits. The nose is the fuselage's end of lowest axial coordinate (x pointing aft, as in
//! the paper's figures and the CAD fixtures).

use geom_db::prelude::{Point3, Vector3};
use geom_db::{CurveCompId, GeomDb, SurfaceId};
use param::{
    Axis, Basis, Decay, DesignVariable, Direction, LineModifier, LineSupport, Links, Modifier,
};

use super::parts::{bbox, boundary_points};

/// First bound of the droop, relative to the fuselage's radius.
const DROOP_REL: f64 = 0.5;
/// First bound of the stretch, relative to the length of the stretched part.
const STRETCH_REL: f64 = 0.25;
/// Shortest stretched part, relative to the fuselage's length.
const MIN_PART: f64 = 0.05;

/// The droop and stretch of fuselage `role` with components `comps` and caps `caps`, whose
/// wing junction is the curves `junction` (empty: no wing) on the wing components `wing`;
/// `Err` says why there are none.
pub fn nose(
    db: &GeomDb,
    role: &str,
    comps: &[usize],
    caps: &[usize],
    junction: &[CurveCompId],
    wing: &[usize],
) -> Result<(Vec<Modifier>, String), String> {
    let pts: Vec<Point3> = comps.iter().flat_map(|&k| boundary_points(db, k)).collect();
    let (lo, hi) = bbox(&pts);
    let ext = hi - lo;
    let k = (0..3)
        .max_by(|&a, &b| ext[a].total_cmp(&ext[b]))
        .expect("three axes");
    let across: Vec<usize> = (0..3).filter(|&j| j != k).collect();
    let radius = 0.5 * across.iter().map(|&j| ext[j]).fold(0.0, f64::max);
    // the region the nose must not reach: the junction widened as the waist's, or the
    // middle third
    let (g0, g1) = if junction.is_empty() {
        (lo[k] + ext[k] / 3.0, hi[k] - ext[k] / 3.0)
    } else {
        let xs: Vec<f64> = junction
            .iter()
            .flat_map(|&c| (0..=32).map(move |i| db.curve_component_point(c, i as f64 / 32.0)[k]))
            .collect();
        let a0 = xs.iter().copied().fold(f64::INFINITY, f64::min);
        let a1 = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let m = 0.25 * (a1 - a0);
        (a0 - m, a1 + m)
    };
    let mut surfaces: Vec<SurfaceId> = comps
        .iter()
        .chain(caps)
        .map(|&c| db.surface_components[c].surface)
        .collect();
    surfaces.sort_unstable();
    surfaces.dedup();
    let mut start = g0;
    let mut nodes: Vec<usize> = Vec::new();
    for &s in &surfaces {
        for ids in &db.surface(s).control.nodes {
            let xs = ids.iter().map(|i| db.control_nodes[i.index()][k]);
            let pmin = xs.clone().fold(f64::INFINITY, f64::min);
            let pmax = xs.fold(f64::NEG_INFINITY, f64::max);
            if pmax >= g0 && pmin <= g1 {
                start = start.min(pmin);
            }
            nodes.extend(ids.iter().map(|i| i.index()));
        }
    }
    nodes.sort_unstable();
    nodes.dedup();
    if nodes.is_empty() {
        return Err(format!("{role}: no control node on the fuselage"));
    }
    let centre = lo + ext * 0.5;
    let mut point = centre;
    point[k] = start;
    let mut along = Vector3::zeros();
    along[k] = -1.0;
    // the nose tip: the linked node farthest ahead; its coordinate along the axis, computed
    // as the modifier will, ends the range (s = 1 there exactly)
    let (tip, length) = nodes
        .iter()
        .map(|&n| (n, (db.control_nodes[n] - point).dot(&along)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("nodes");
    let ahead = nodes
        .iter()
        .filter(|&&n| (db.control_nodes[n] - point).dot(&along) > 0.0)
        .count();
    if length.partial_cmp(&(MIN_PART * ext[k])) != Some(std::cmp::Ordering::Greater) || ahead < 2 {
        return Err(format!(
            "{role}: no nose droop or stretch: the first patch reaching the junction starts \
             at {} = {start:.4}, {:.4} behind the nose",
            ["x", "y", "z"][k],
            length.max(0.0)
        ));
    }
    // the span: the wing's longest extent across the fuselage; without a wing, the
    // fuselage's shortest (a half model is cut by its symmetry plane); the vertical is the
    // third axis
    let span = if wing.is_empty() {
        across
            .iter()
            .copied()
            .min_by(|&a, &b| ext[a].total_cmp(&ext[b]))
    } else {
        let wp: Vec<Point3> = wing.iter().flat_map(|&c| boundary_points(db, c)).collect();
        let (wlo, whi) = bbox(&wp);
        across
            .iter()
            .copied()
            .max_by(|&a, &b| (whi[a] - wlo[a]).total_cmp(&(whi[b] - wlo[b])))
    }
    .expect("two axes across");
    let up = across
        .iter()
        .copied()
        .find(|&j| j != span)
        .expect("a vertical axis");
    let mut down = Vector3::zeros();
    down[up] = -1.0;
    let links = Links {
        surfaces: surfaces.clone(),
        ..Links::default()
    };
    let line = |name: &str, degree: usize, dir: Vector3, bound: f64| {
        Modifier::Line(LineModifier {
            name: name.to_string(),
            line: LineSupport::Axis(Axis {
                point,
                direction: along,
            }),
            links: links.clone(),
            range: Some([0.0, length]),
            basis: Basis::Bernstein { degree },
            active: Some(vec![degree]),
            direction: Direction::Axis(dir),
            decay: Decay::Uniform,
            variables: vec![
                DesignVariable::new(name, -bound, bound)
                    .with_group(role.to_string())
                    .with_scale(bound / 10.0),
            ],
        })
    };
    let droop = format!("{role}.droop");
    let stretch = format!("{role}.stretch");
    let mods = vec![
        line(&droop, 2, down, DROOP_REL * radius),
        line(&stretch, 1, along, STRETCH_REL * length),
    ];
    let axes = ["x", "y", "z"];
    let tip = db.control_nodes[tip];
    let summary = format!(
        "{role}: nose droop along -{} (Fig. 10, growing as s² to the nose) and stretch along \
         -{} (Fig. 12) ahead of {} = {start:.4} (the first patch reaching {}), nose tip \
         ({:.4}, {:.4}, {:.4}), {} control nodes ahead, surfaces {:?}",
        axes[up],
        axes[k],
        axes[k],
        if junction.is_empty() {
            "the middle third: no wing meets it"
        } else {
            "the wing junction widened by a quarter each side"
        },
        tip.x,
        tip.y,
        tip.z,
        ahead,
        surfaces.iter().map(|s| s.index()).collect::<Vec<_>>()
    );
    Ok((mods, summary))
}
