//! Volume and area of a set of support surfaces by Gauss–Legendre rules on their patches
//! (docs/constraints.md), and their derivatives for a model perturbation.

use geom_db::linearise::{ModelTangent, SurfaceTangent};
use geom_db::prelude::Vector3;
use geom_db::quadrature::gauss_legendre;
use geom_db::{GeomDb, SupportSurface, SurfaceId};

/// Relative agreement of two subdivision levels that ends the area's refinement.
const AREA_REL: f64 = 1e-12;
/// Largest subdivision level of the area (2^k × 2^k cells per patch).
const AREA_MAX_LEVEL: usize = 6;

/// The quadrature points of `surf` (global u, v, weight): on each patch the product rule of
/// `m(deg)` points per direction, on 2^level × 2^level cells.
fn rule(surf: &SupportSurface, level: usize, m: impl Fn(usize) -> usize) -> Vec<(f64, f64, f64)> {
    let cells = 1usize << level;
    let h = 1.0 / cells as f64;
    let mut out = Vec::new();
    for pj in 0..surf.n_v {
        for pi in 0..surf.n_u {
            let patch = surf.patch(pi, pj);
            let (ru, rv) = (
                gauss_legendre(m(patch.deg_u)),
                gauss_legendre(m(patch.deg_v)),
            );
            for cj in 0..cells {
                for ci in 0..cells {
                    for &(xv, wv) in &rv {
                        for &(xu, wu) in &ru {
                            out.push((
                                pi as f64 + (ci as f64 + xu) * h,
                                pj as f64 + (cj as f64 + xv) * h,
                                wu * wv * h * h,
                            ));
                        }
                    }
                }
            }
        }
    }
    out
}

/// Gauss points per direction that integrate (r·m)(m·(r_u × r_v)) exactly on a patch of
/// degree p (degree 3p − 1).
fn volume_points(p: usize) -> usize {
    (3 * p).div_ceil(2).max(1)
}

/// Gauss points per direction for the area on one cell.
fn area_points(p: usize) -> usize {
    volume_points(p) + 2
}

fn derivs(surf: &SupportSurface, q: &[(f64, f64, f64)]) -> Vec<geom_db::eval::SurfaceDerivs> {
    let uv: Vec<(f64, f64)> = q.iter().map(|&(u, v, _)| (u, v)).collect();
    surf.derivs_many(&uv)
}

/// V = Σ_s σ_s ∬ (r·m)(m·(r_u × r_v)) du dv over `surfaces` (surface, outward sign σ).
pub fn volume(db: &GeomDb, surfaces: &[(SurfaceId, f64)], m: &[f64; 3]) -> f64 {
    let m = Vector3::new(m[0], m[1], m[2]);
    let mut total = 0.0;
    for &(s, sigma) in surfaces {
        let surf = db.surface(s);
        let q = rule(surf, 0, volume_points);
        let e = derivs(surf, &q);
        let part: f64 = q
            .iter()
            .zip(&e)
            .map(|(&(_, _, w), e)| w * e.point.coords.dot(&m) * m.dot(&e.du.cross(&e.dv)))
            .sum();
        total += sigma * part;
    }
    total
}

/// δV for the model perturbation `t`.
pub(crate) fn volume_tangent(
    db: &GeomDb,
    surfaces: &[(SurfaceId, f64)],
    m: &[f64; 3],
    t: &ModelTangent,
) -> f64 {
    let m = Vector3::new(m[0], m[1], m[2]);
    let mut total = 0.0;
    for &(s, sigma) in surfaces {
        let surf = db.surface(s);
        let q = rule(surf, 0, volume_points);
        let e = derivs(surf, &q);
        let part: f64 = q
            .iter()
            .zip(&e)
            .map(|(&(u, v, w), e)| {
                let d = t.surface_at(db, s, u, v);
                let n = e.du.cross(&e.dv);
                let dn = d.du.cross(&e.dv) + e.du.cross(&d.dv);
                w * (d.point.dot(&m) * m.dot(&n) + e.point.coords.dot(&m) * m.dot(&dn))
            })
            .sum();
        total += sigma * part;
    }
    total
}

/// The transpose of [`volume_tangent`]: adds `bar` · dV/d(model) to `w`.
pub(crate) fn volume_cotangent(
    db: &GeomDb,
    surfaces: &[(SurfaceId, f64)],
    m: &[f64; 3],
    bar: f64,
    w: &mut ModelTangent,
) {
    let m = Vector3::new(m[0], m[1], m[2]);
    for &(s, sigma) in surfaces {
        let surf = db.surface(s);
        let q = rule(surf, 0, volume_points);
        let e = derivs(surf, &q);
        for (&(u, v, wt), e) in q.iter().zip(&e) {
            let c = sigma * bar * wt;
            let n = e.du.cross(&e.dv);
            let zm = e.point.coords.dot(&m);
            // (r·m) m·(δr_u × r_v) = δr_u · (r_v × m) (r·m); m·(r_u × δr_v) = δr_v · (m × r_u)
            let tb = SurfaceTangent {
                point: m * (m.dot(&n) * c),
                du: e.dv.cross(&m) * (zm * c),
                dv: m.cross(&e.du) * (zm * c),
            };
            w.add_surface_at(db, s, u, v, &tb);
        }
    }
}

fn area_at(surf: &SupportSurface, level: usize) -> f64 {
    let q = rule(surf, level, area_points);
    let e = derivs(surf, &q);
    q.iter()
        .zip(&e)
        .map(|(&(_, _, w), e)| w * e.du.cross(&e.dv).norm())
        .sum()
}

/// A = Σ ∬ |r_u × r_v| du dv over `surfaces`, and the subdivision level used on each.
pub fn area(db: &GeomDb, surfaces: &[SurfaceId]) -> (f64, Vec<usize>) {
    let mut total = 0.0;
    let mut levels = Vec::with_capacity(surfaces.len());
    for &s in surfaces {
        let surf = db.surface(s);
        let mut prev = area_at(surf, 0);
        let mut level = 0;
        while level < AREA_MAX_LEVEL {
            let next = area_at(surf, level + 1);
            level += 1;
            let done = (next - prev).abs() <= AREA_REL * next.abs();
            prev = next;
            if done {
                break;
            }
        }
        total += prev;
        levels.push(level);
    }
    (total, levels)
}

/// δA for the model perturbation `t` (on the levels [`area`] chose).
pub(crate) fn area_tangent(db: &GeomDb, surfaces: &[(SurfaceId, usize)], t: &ModelTangent) -> f64 {
    let mut total = 0.0;
    for &(s, level) in surfaces {
        let surf = db.surface(s);
        let q = rule(surf, level, area_points);
        let e = derivs(surf, &q);
        total += q
            .iter()
            .zip(&e)
            .map(|(&(u, v, w), e)| {
                let n = e.du.cross(&e.dv);
                let len = n.norm();
                if len == 0.0 {
                    return 0.0;
                }
                let d = t.surface_at(db, s, u, v);
                let dn = d.du.cross(&e.dv) + e.du.cross(&d.dv);
                w * n.dot(&dn) / len
            })
            .sum::<f64>();
    }
    total
}

/// The transpose of [`area_tangent`]: adds `bar` · dA/d(model) to `w`.
pub(crate) fn area_cotangent(
    db: &GeomDb,
    surfaces: &[(SurfaceId, usize)],
    bar: f64,
    w: &mut ModelTangent,
) {
    for &(s, level) in surfaces {
        let surf = db.surface(s);
        let q = rule(surf, level, area_points);
        let e = derivs(surf, &q);
        for (&(u, v, wt), e) in q.iter().zip(&e) {
            let n = e.du.cross(&e.dv);
            let len = n.norm();
            if len == 0.0 {
                continue;
            }
            let nh = n * (bar * wt / len);
            // n̂·(δr_u × r_v) = δr_u · (r_v × n̂); n̂·(r_u × δr_v) = δr_v · (n̂ × r_u)
            let tb = SurfaceTangent {
                point: Vector3::zeros(),
                du: e.dv.cross(&nh),
                dv: nh.cross(&e.du),
            };
            w.add_surface_at(db, s, u, v, &tb);
        }
    }
}
