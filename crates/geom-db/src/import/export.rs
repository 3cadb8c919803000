//! The way back: a geometric database as IGES trimmed surfaces.
//!
//! Support surfaces whose patches are all at most bicubic become 114 parametric spline
//! surfaces (power basis with unit break spacing, so the IGES coefficients are the patch
//! coefficients a_{pq} themselves, Eq. 7); others become 128 B-spline surfaces (each patch
//! converted to Bézier form, degree-elevated to the surface's highest degree and assembled
//! with knots of multiplicity p at the patch borders). Curves likewise become 112 or 126.
//! Each surface component becomes a 144 trimmed surface whose outer and inner boundaries are
//! 142 curves on the surface with a 102 composite model-space curve of its loop's curve
//! components, each written in the direction the loop traverses it.

use iges::{
    BSplineCurve, BSplineSurface, CompositeCurve, CurveOnSurface, DeId, DirectoryEntry, Entity,
    EntityRecord, Global, IgesFile, SplineCurve, SplineSurface, Status, TrimmedSurface,
};

use crate::control;
use crate::convert::{power_to_bezier, power_to_bezier_2d};
use crate::curve::Arc;
use crate::db::GeomDb;
use crate::prelude::Point3;
use crate::surface::SupportSurface;
use crate::topology::OrientedCurve;

/// Bézier degree elevation from n to `to` (b'_i = i/(n+1) b_{i−1} + (1 − i/(n+1)) b_i, repeated).
fn elevate(b: &[Point3], to: usize) -> Vec<Point3> {
    let mut b = b.to_vec();
    while b.len() - 1 < to {
        let n = b.len() - 1;
        let mut out = Vec::with_capacity(n + 2);
        out.push(b[0]);
        for i in 1..=n {
            let a = i as f64 / (n + 1) as f64;
            out.push(Point3::from(b[i - 1].coords * a + b[i].coords * (1.0 - a)));
        }
        out.push(b[n]);
        b = out;
    }
    b
}

/// The part [a, b] ⊂ [0, 1] of an arc, re-parametrised to [0, 1] (exact: interpolation of a
/// polynomial of the same degree).
pub(super) fn sub_arc(arc: &Arc, a: f64, b: f64) -> Arc {
    if a == 0.0 && b == 1.0 {
        return arc.clone();
    }
    let pts: Vec<Point3> = control::nodes(arc.degree)
        .iter()
        .map(|&x| arc.point(a + x * (b - a)))
        .collect();
    Arc::from_control_points(&pts)
}

fn curve_entity(arcs: &[Arc]) -> Entity {
    let p = arcs.iter().map(|a| a.degree).max().unwrap_or(1);
    if p <= 3 {
        let pad = |a: &Arc| -> [[f64; 4]; 3] {
            let mut c = [[0.0; 4]; 3];
            for (k, q) in a.coeffs.iter().enumerate() {
                for d in 0..3 {
                    c[d][k] = q[d];
                }
            }
            c
        };
        let last = arcs.last().expect("at least one arc");
        let mut terminal = [[0.0; 4]; 3];
        for (k, q) in last.coeffs.iter().enumerate() {
            // value, first derivative, second / 2!, third / 3! at u = 1
            let w = [
                1.0,
                k as f64,
                (k * k.saturating_sub(1)) as f64 / 2.0,
                crate::bspline::binomial(k, 3),
            ];
            for d in 0..3 {
                for m in 0..4 {
                    terminal[d][m] += w[m] * q[d];
                }
            }
        }
        return Entity::SplineCurve(SplineCurve {
            spline_type: 3,
            continuity: 0,
            dimension: 3,
            breakpoints: (0..=arcs.len()).map(|i| i as f64).collect(),
            segments: arcs.iter().map(pad).collect(),
            terminal,
        });
    }
    let mut ctrl: Vec<Point3> = Vec::new();
    for a in arcs {
        let b = elevate(&power_to_bezier(&a.coeffs), p);
        match ctrl.last_mut() {
            Some(last) => {
                *last = Point3::from((last.coords + b[0].coords) * 0.5);
                ctrl.extend_from_slice(&b[1..]);
            }
            None => ctrl.extend(b),
        }
    }
    let n = arcs.len();
    let mut knots = vec![0.0; p + 1];
    for i in 1..n {
        knots.extend(std::iter::repeat_n(i as f64, p));
    }
    knots.extend(std::iter::repeat_n(n as f64, p + 1));
    Entity::BSplineCurve(BSplineCurve {
        degree: p,
        planar: false,
        closed: false,
        polynomial: true,
        periodic: false,
        knots,
        weights: vec![1.0; ctrl.len()],
        control_points: ctrl.iter().map(|q| [q.x, q.y, q.z]).collect(),
        range: [0.0, n as f64],
        normal: None,
    })
}

fn surface_entity(s: &SupportSurface) -> Entity {
    let p = s.patches.iter().map(|q| q.deg_u).max().unwrap_or(1);
    let q = s.patches.iter().map(|q| q.deg_v).max().unwrap_or(1);
    if p <= 3 && q <= 3 {
        let mut patches = Vec::with_capacity(s.patches.len());
        for i in 0..s.n_u {
            for j in 0..s.n_v {
                let pt = s.patch(i, j);
                let mut c = [[0.0; 16]; 3];
                for k in 0..=pt.deg_u {
                    for l in 0..=pt.deg_v {
                        let a = pt.coeff(k, l);
                        for d in 0..3 {
                            c[d][4 * l + k] = a[d];
                        }
                    }
                }
                patches.push(c);
            }
        }
        return Entity::SplineSurface(SplineSurface {
            boundary_type: 3,
            patch_type: 1,
            u_breaks: (0..=s.n_u).map(|i| i as f64).collect(),
            v_breaks: (0..=s.n_v).map(|j| j as f64).collect(),
            patches,
        });
    }
    let (nu, nv) = (s.n_u * p + 1, s.n_v * q + 1);
    let mut ctrl = vec![Point3::origin(); nu * nv];
    let mut count = vec![0u32; nu * nv];
    for j in 0..s.n_v {
        for i in 0..s.n_u {
            let pt = s.patch(i, j);
            let b = power_to_bezier_2d(pt.deg_u, pt.deg_v, &pt.coeffs);
            // elevate in v (rows), then in u (columns)
            let rows: Vec<Vec<Point3>> = (0..=pt.deg_u)
                .map(|k| elevate(&b[k * (pt.deg_v + 1)..(k + 1) * (pt.deg_v + 1)], q))
                .collect();
            for l in 0..=q {
                let col: Vec<Point3> = rows.iter().map(|r| r[l]).collect();
                for (k, c) in elevate(&col, p).into_iter().enumerate() {
                    let idx = (i * p + k) + nu * (j * q + l);
                    ctrl[idx] = Point3::from(ctrl[idx].coords + c.coords);
                    count[idx] += 1;
                }
            }
        }
    }
    for (c, n) in ctrl.iter_mut().zip(&count) {
        *c = Point3::from(c.coords / *n as f64);
    }
    let knots = |n: usize, d: usize| {
        let mut k = vec![0.0; d + 1];
        for i in 1..n {
            k.extend(std::iter::repeat_n(i as f64, d));
        }
        k.extend(std::iter::repeat_n(n as f64, d + 1));
        k
    };
    Entity::BSplineSurface(BSplineSurface {
        degree_u: p,
        degree_v: q,
        n_u: nu,
        n_v: nv,
        closed_u: false,
        closed_v: false,
        polynomial: true,
        periodic_u: false,
        periodic_v: false,
        knots_u: knots(s.n_u, p),
        knots_v: knots(s.n_v, q),
        weights: vec![1.0; nu * nv],
        control_points: ctrl.iter().map(|c| [c.x, c.y, c.z]).collect(),
        u_range: [0.0, s.n_u as f64],
        v_range: [0.0, s.n_v as f64],
    })
}

/// The arcs of a curve component in the direction a loop traverses it.
fn component_arcs(db: &GeomDb, oc: OrientedCurve) -> Vec<Arc> {
    let cc = db.curve_component(oc.comp);
    let arcs = &db.curve(cc.curve).arcs;
    let (lo, hi) = (cc.t0.min(cc.t1), cc.t0.max(cc.t1));
    let mut out = Vec::new();
    for (k, a) in arcs.iter().enumerate() {
        let (s, e) = ((lo - k as f64).max(0.0), (hi - k as f64).min(1.0));
        if e - s > 1e-12 {
            out.push(sub_arc(a, s, e));
        }
    }
    if (cc.t1 < cc.t0) != oc.reversed {
        out.reverse();
        out.iter_mut().for_each(|a| *a = a.reversed());
    }
    out
}

fn record(entity: Entity, subordinate: bool) -> EntityRecord {
    let mut de = DirectoryEntry::new(entity.type_number().unwrap_or(0), 0);
    de.status = Status {
        subordinate: if subordinate { 1 } else { 0 },
        ..Status::default()
    };
    EntityRecord {
        de,
        entity,
        extra: Vec::new(),
        layout: None,
    }
}

/// Writes the database's surface components as IGES 144 trimmed surfaces (see the module
/// documentation). `name` goes into the Global section's file name.
pub fn to_iges(db: &GeomDb, name: &str) -> IgesFile {
    let l = db.reference_length();
    let (units_flag, units_name) = match db.units.as_deref() {
        Some("m") => (6, "M"),
        Some("in") => (1, "IN"),
        Some("ft") => (4, "FT"),
        Some("cm") => (10, "CM"),
        Some("km") => (7, "KM"),
        _ => (2, "MM"),
    };
    let max_coordinate = db
        .bbox()
        .map(|(a, b)| a.coords.abs().max().max(b.coords.abs().max()))
        .unwrap_or(0.0);
    let ascii = |s: &str| {
        s.chars()
            .filter(|c| (' '..='~').contains(c))
            .collect::<String>()
    };
    let global = Global {
        sender_product_id: ascii(&db.name),
        file_name: ascii(name),
        native_system_id: "aeroshape".into(),
        preprocessor_version: env!("CARGO_PKG_VERSION").into(),
        units_flag,
        units_name: units_name.into(),
        resolution: 1e-7 * l,
        max_coordinate,
        ..Global::default()
    };
    let mut f = IgesFile::new(global);
    f.start = format!("{} exported by aeroshape", ascii(&db.name))
        .trim()
        .to_string();
    f.name = name.to_string();
    let surfaces: Vec<DeId> = db
        .surfaces
        .iter()
        .map(|s| f.push_record(record(surface_entity(s), true)))
        .collect();
    for sc in &db.surface_components {
        let sid = surfaces[sc.surface.index()];
        let mut bounds = Vec::new();
        for lp in &sc.loops {
            let curves: Vec<DeId> = lp
                .iter()
                .map(|&oc| f.push_record(record(curve_entity(&component_arcs(db, oc)), true)))
                .collect();
            let model = if curves.len() == 1 {
                curves[0]
            } else {
                f.push_record(record(
                    Entity::CompositeCurve(CompositeCurve { curves }),
                    true,
                ))
            };
            bounds.push(f.push_record(record(
                Entity::CurveOnSurface(CurveOnSurface {
                    creation: 0,
                    surface: sid,
                    param_curve: None,
                    model_curve: Some(model),
                    preferred: 2,
                }),
                true,
            )));
        }
        let mut it = bounds.into_iter();
        let outer = it.next();
        let t = f.push_record(record(
            Entity::TrimmedSurface(TrimmedSurface {
                surface: sid,
                outer,
                inner: it.collect(),
            }),
            false,
        ));
        let label: String = ascii(&sc.name)
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .take(8)
            .collect();
        f.entities[t.index()].de.label = label;
    }
    f
}
