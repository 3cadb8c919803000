//! The fuselage waist `case init` proposes ([`waist`]): the section reduction at the wing
//! junction of the paper's Fig. 9, a surface-level modifier (Eq. 38) along the normal of the
//! fuselage surface the wing meets. Along the fuselage's long axis it is the Bernstein
//! function B₂⁴(s) = 6 s² (1 − s)² over the axial extent of the junction widened by a
//! quarter of it on each side (zero with zero slope at both ends, largest, 0.375, in the
//! middle); round the fuselage it is constant (B₀⁰ = 1). One variable, `<role>.waist`.
//! Without a wing the waist is at the middle third of the fuselage.

use geom_db::eval::ParamSurface;
use geom_db::prelude::Point3;
use geom_db::{CurveCompId, GeomDb, SurfaceId};
use param::{Basis, DesignVariable, Direction, Param, SurfaceForm, SurfaceModifier};

use super::parts::{bbox, boundary_points};

/// Largest value of B₂⁴ (at s = ½).
const PEAK: f64 = 0.375;
/// Samples of the axial parameter when its range is located.
const N_AXIAL: usize = 401;

/// The waist of fuselage `role` with components `comps`, at the junction curves
/// `junction` (empty: no wing meets it); `Err` says why there is none.
pub fn waist(
    db: &GeomDb,
    role: &str,
    comps: &[usize],
    junction: &[CurveCompId],
) -> Result<(SurfaceModifier, String), String> {
    let pts: Vec<Point3> = comps.iter().flat_map(|&k| boundary_points(db, k)).collect();
    let (lo, hi) = bbox(&pts);
    let ext = hi - lo;
    let k = (0..3)
        .max_by(|&a, &b| ext[a].total_cmp(&ext[b]))
        .expect("three axes");
    let radius = 0.5
        * (0..3)
            .filter(|&j| j != k)
            .map(|j| ext[j])
            .fold(0.0, f64::max);
    let (a0, a1) = if junction.is_empty() {
        (lo[k] + ext[k] / 3.0, hi[k] - ext[k] / 3.0)
    } else {
        let xs: Vec<f64> = junction
            .iter()
            .flat_map(|&c| (0..=32).map(move |i| db.curve_component_point(c, i as f64 / 32.0)[k]))
            .collect();
        (
            xs.iter().copied().fold(f64::INFINITY, f64::min),
            xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        )
    };
    let margin = 0.25 * (a1 - a0);
    let (a0, a1) = (a0 - margin, a1 + margin);
    // the fuselage surface that holds the junction (or the middle): the one whose samples
    // fall most often inside [a0, a1]
    let mut surfaces: Vec<SurfaceId> = comps
        .iter()
        .map(|&c| db.surface_components[c].surface)
        .collect();
    surfaces.sort_unstable();
    surfaces.dedup();
    let inside = |s: SurfaceId| {
        let surf = db.surface(s);
        let ([u0, u1], [v0, v1]) = surf.domain();
        (0..=8)
            .flat_map(|i| (0..=8).map(move |j| (i, j)))
            .filter(|&(i, j)| {
                let p = surf.point(
                    u0 + (u1 - u0) * i as f64 / 8.0,
                    v0 + (v1 - v0) * j as f64 / 8.0,
                );
                (a0..=a1).contains(&p[k])
            })
            .count()
    };
    let s = surfaces
        .iter()
        .copied()
        .max_by_key(|&s| inside(s))
        .filter(|&s| inside(s) > 0)
        .ok_or_else(|| format!("{role}: no fuselage surface reaches the junction"))?;
    let surf = db.surface(s);
    let ([u0, u1], [v0, v1]) = surf.domain();
    // the axial parameter: the one along which the axial coordinate changes most
    let change = |along_u: bool| -> f64 {
        let mut sum = 0.0;
        for i in 0..=8 {
            for j in 0..8 {
                let (a, b) = (j as f64 / 8.0, (j + 1) as f64 / 8.0);
                let c = i as f64 / 8.0;
                let (p, q) = if along_u {
                    (
                        surf.point(u0 + (u1 - u0) * a, v0 + (v1 - v0) * c),
                        surf.point(u0 + (u1 - u0) * b, v0 + (v1 - v0) * c),
                    )
                } else {
                    (
                        surf.point(u0 + (u1 - u0) * c, v0 + (v1 - v0) * a),
                        surf.point(u0 + (u1 - u0) * c, v0 + (v1 - v0) * b),
                    )
                };
                sum += (q[k] - p[k]).abs();
            }
        }
        sum
    };
    let axial = if change(true) >= change(false) {
        Param::U
    } else {
        Param::V
    };
    let ([p0, p1], [q0, q1]) = match axial {
        Param::U => ([u0, u1], [v0, v1]),
        Param::V => ([v0, v1], [u0, u1]),
    };
    // the axial parameters whose points (at a quarter, half and three quarters round) lie in
    // [a0, a1]
    let mut range = [f64::INFINITY, f64::NEG_INFINITY];
    for i in 0..N_AXIAL {
        let p = p0 + (p1 - p0) * i as f64 / (N_AXIAL - 1) as f64;
        let x = [0.25, 0.5, 0.75]
            .iter()
            .map(|f| {
                let q = q0 + (q1 - q0) * f;
                match axial {
                    Param::U => surf.point(p, q)[k],
                    Param::V => surf.point(q, p)[k],
                }
            })
            .sum::<f64>()
            / 3.0;
        if (a0..=a1).contains(&x) {
            range[0] = range[0].min(p);
            range[1] = range[1].max(p);
        }
    }
    if range[1].partial_cmp(&range[0]) != Some(std::cmp::Ordering::Greater) {
        return Err(format!(
            "{role}: the junction's axial extent [{a0:.4}, {a1:.4}] is not on surface {}",
            s.index()
        ));
    }
    let bound = 0.05 * radius / PEAK;
    let name = format!("{role}.waist");
    let (basis_axial, basis_round) = (
        Basis::Bernstein { degree: 4 },
        Basis::Bernstein { degree: 0 },
    );
    let (range_u, range_v, basis_u, basis_v, active_u, active_v) = match axial {
        Param::U => (
            Some(range),
            None,
            basis_axial,
            basis_round,
            Some(vec![2]),
            None,
        ),
        Param::V => (
            None,
            Some(range),
            basis_round,
            basis_axial,
            None,
            Some(vec![2]),
        ),
    };
    let m = SurfaceModifier {
        name: name.clone(),
        surfaces: vec![s],
        range_u,
        range_v,
        basis_u,
        basis_v,
        active_u,
        active_v,
        direction: Direction::Normal,
        form: SurfaceForm::Tensor {
            variables: vec![
                DesignVariable::new(name, -bound, bound)
                    .with_group(role.to_string())
                    .with_scale(bound / 10.0),
            ],
        },
    };
    let axis = ["x", "y", "z"][k];
    let summary = format!(
        "{role}: waist on surface {} over {axis} ∈ [{a0:.4}, {a1:.4}] ({}), parameter {} ∈ \
         [{:.4}, {:.4}], radius {radius:.4}",
        s.index(),
        if junction.is_empty() {
            "the middle third: no wing meets it"
        } else {
            "the wing junction widened by a quarter each side"
        },
        match axial {
            Param::U => "u",
            Param::V => "v",
        },
        range[0],
        range[1]
    );
    Ok((m, summary))
}
