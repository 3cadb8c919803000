//! Perturbations of the database's geometry by its control points (issue 22): the tangent
//! of a curve or surface point, and of its first derivatives, for given control-point
//! perturbations, and the transposed map (cotangents).
//!
//! An arc of degree n interpolates its control points r_i at the Chebyshev–Lobatto nodes x_i
//! (Eq. 4: A = V⁻¹ R), so r(u) = Uᵀ V⁻¹ R = Σ_i ℓ_i(u) r_i with the Lagrange polynomials
//! ℓ_i(u) = Σ_k (V⁻¹)_{ki} u^k; a patch (Eq. 9: A = V_u⁻¹ R V_v⁻ᵀ) is r(u, v) =
//! Σ_{i,j} ℓ_i(u) ℓ_j(v) r_ij. Both are linear in the control points: a perturbation δr_i
//! moves the point by δr(u) = Σ ℓ_i(u) δr_i and its derivatives by the derivatives of the ℓ_i,
//! and the cotangent r̄ at u gives each control point ℓ_i(u) r̄. The same weights serve both
//! directions, so ⟨J δr, r̄⟩ = ⟨δr, Jᵀ r̄⟩ to round-off.
//!
//! [`ModelTangent`] holds a perturbation of a whole model (or its cotangent): one vector per
//! control node (surfaces, and curves re-solved from their nodes), per-arc control-point
//! perturbations for curves whose points are computed otherwise (the junctions re-intersected
//! by `intersect`), corners and curve components' parameter ranges. See
//! docs/crates/geom-db.md, "Linearisation".

use crate::GeomDb;
use crate::control::{self, MAX_DEGREE};
use crate::curve::locate;
use crate::ids::{CurveId, SurfaceId};
use crate::prelude::Vector3;

const M: usize = MAX_DEGREE + 1;

/// The Lagrange polynomials of the control nodes of one degree at one local parameter:
/// ℓ_i(x), ℓ_i′(x), ℓ_i″(x), i = 0..=degree.
#[derive(Debug, Clone, Copy)]
pub struct Lagrange {
    /// The degree n (n + 1 polynomials).
    pub degree: usize,
    /// ℓ_i(x).
    pub value: [f64; M],
    /// ℓ_i′(x).
    pub d1: [f64; M],
    /// ℓ_i″(x).
    pub d2: [f64; M],
}

impl Lagrange {
    /// The polynomials of degree `degree` at local `x` (any real x: outside [0, 1] the
    /// polynomials are extended, as the curves' end arcs are).
    ///
    /// # Panics
    /// If `degree > MAX_DEGREE`.
    pub fn at(degree: usize, x: f64) -> Self {
        let m = degree + 1;
        let vinv = control::inverse_vandermonde(degree);
        let mut out = Self {
            degree,
            value: [0.0; M],
            d1: [0.0; M],
            d2: [0.0; M],
        };
        for i in 0..m {
            // Horner over the powers of x of column i of V⁻¹, with two derivatives
            let (mut p, mut p1, mut p2) = (0.0, 0.0, 0.0);
            for k in (0..m).rev() {
                p2 = p2 * x + p1;
                p1 = p1 * x + p;
                p = p * x + vinv[k * m + i];
            }
            out.value[i] = p;
            out.d1[i] = p1;
            out.d2[i] = 2.0 * p2;
        }
        out
    }
}

/// The perturbation of a curve point: δr, δr′, δr″ (derivatives in the global parameter).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CurveTangent {
    /// δr(t).
    pub point: Vector3,
    /// δr′(t).
    pub d1: Vector3,
    /// δr″(t).
    pub d2: Vector3,
}

/// The perturbation of a surface point: δr, δr_u, δr_v (global parameters).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceTangent {
    /// δr(u, v).
    pub point: Vector3,
    /// δr_u(u, v).
    pub du: Vector3,
    /// δr_v(u, v).
    pub dv: Vector3,
}

/// δr at global `t` of the curve whose arc a has control-point perturbations `arcs[a]`
/// (arc ⌊t⌋ clamped, the end arcs extended as the curves are).
pub fn arcs_at(arcs: &[Vec<Vector3>], t: f64) -> CurveTangent {
    let mut out = CurveTangent::default();
    if arcs.is_empty() {
        return out;
    }
    let (a, u) = locate(t, arcs.len());
    let r = &arcs[a];
    if r.is_empty() {
        return out;
    }
    let l = Lagrange::at(r.len() - 1, u);
    for (i, d) in r.iter().enumerate() {
        out.point += d * l.value[i];
        out.d1 += d * l.d1[i];
        out.d2 += d * l.d2[i];
    }
    out
}

/// The transpose of [`arcs_at`]: adds to the arcs' control-point cotangents what the
/// cotangent `bar` of the curve point at global `t` gives them.
pub fn add_arcs_at(arcs: &mut [Vec<Vector3>], t: f64, bar: &CurveTangent) {
    if arcs.is_empty() {
        return;
    }
    let (a, u) = locate(t, arcs.len());
    let r = &mut arcs[a];
    if r.is_empty() {
        return;
    }
    let l = Lagrange::at(r.len() - 1, u);
    for (i, d) in r.iter_mut().enumerate() {
        *d += bar.point * l.value[i] + bar.d1 * l.d1[i] + bar.d2 * l.d2[i];
    }
}

/// A perturbation of a model's geometry, or its cotangent (the same layout): see the module
/// doc. `curves[c] = None` means curve c follows its control nodes (`nodes`);
/// `Some(arcs)` gives its control-point perturbations arc by arc (each arc's degree + 1
/// points, the arcs of the model the tangent belongs to).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelTangent {
    /// Per control node.
    pub nodes: Vec<Vector3>,
    /// Per support curve (see the struct doc).
    pub curves: Vec<Option<Vec<Vec<Vector3>>>>,
    /// Per corner.
    pub corners: Vec<Vector3>,
    /// Per curve component: its parameter range (t0, t1).
    pub ranges: Vec<[f64; 2]>,
}

impl ModelTangent {
    /// The zero perturbation of `db` (every curve following its control nodes).
    pub fn zeros(db: &GeomDb) -> Self {
        Self {
            nodes: vec![Vector3::zeros(); db.control_nodes.len()],
            curves: vec![None; db.curves.len()],
            corners: vec![Vector3::zeros(); db.corners.len()],
            ranges: vec![[0.0; 2]; db.curve_components.len()],
        }
    }

    /// Makes curve `c` carry its own control-point perturbations (zero), one per control
    /// point of each arc of `db`'s curve.
    pub fn own_curve(&mut self, db: &GeomDb, c: CurveId) {
        self.curves[c.index()] = Some(
            db.curve(c)
                .arcs
                .iter()
                .map(|a| vec![Vector3::zeros(); a.degree + 1])
                .collect(),
        );
    }

    /// δr, δr′, δr″ of curve `c` of `db` at global `t`.
    pub fn curve_at(&self, db: &GeomDb, c: CurveId, t: f64) -> CurveTangent {
        if let Some(arcs) = &self.curves[c.index()] {
            return arcs_at(arcs, t);
        }
        let curve = db.curve(c);
        if curve.control.is_empty() || curve.arcs.is_empty() {
            return CurveTangent::default();
        }
        let (a, u) = locate(t, curve.arcs.len());
        let ids = &curve.control.nodes[a];
        let l = Lagrange::at(ids.len() - 1, u);
        let mut out = CurveTangent::default();
        for (i, id) in ids.iter().enumerate() {
            let d = &self.nodes[id.index()];
            out.point += d * l.value[i];
            out.d1 += d * l.d1[i];
            out.d2 += d * l.d2[i];
        }
        out
    }

    /// The transpose of [`curve_at`](Self::curve_at): adds the cotangent `bar` of curve
    /// `c`'s point at `t` to the control nodes (or the curve's own control points).
    pub fn add_curve_at(&mut self, db: &GeomDb, c: CurveId, t: f64, bar: &CurveTangent) {
        if let Some(arcs) = &mut self.curves[c.index()] {
            add_arcs_at(arcs, t, bar);
            return;
        }
        let curve = db.curve(c);
        if curve.control.is_empty() || curve.arcs.is_empty() {
            return;
        }
        let (a, u) = locate(t, curve.arcs.len());
        let ids = &curve.control.nodes[a];
        let l = Lagrange::at(ids.len() - 1, u);
        for (i, id) in ids.iter().enumerate() {
            self.nodes[id.index()] += bar.point * l.value[i] + bar.d1 * l.d1[i] + bar.d2 * l.d2[i];
        }
    }

    /// δr, δr_u, δr_v of surface `s` of `db` at global (u, v).
    pub fn surface_at(&self, db: &GeomDb, s: SurfaceId, u: f64, v: f64) -> SurfaceTangent {
        let surf = db.surface(s);
        let mut out = SurfaceTangent::default();
        if surf.control.is_empty() {
            return out;
        }
        let (p, lu, lv) = surf.locate(u, v);
        let patch = &surf.patches[p];
        let (a, b) = (Lagrange::at(patch.deg_u, lu), Lagrange::at(patch.deg_v, lv));
        let m1 = patch.deg_v + 1;
        for (k, id) in surf.control.nodes[p].iter().enumerate() {
            let (i, j) = (k / m1, k % m1);
            let d = &self.nodes[id.index()];
            out.point += d * (a.value[i] * b.value[j]);
            out.du += d * (a.d1[i] * b.value[j]);
            out.dv += d * (a.value[i] * b.d1[j]);
        }
        out
    }

    /// The transpose of [`surface_at`](Self::surface_at).
    pub fn add_surface_at(
        &mut self,
        db: &GeomDb,
        s: SurfaceId,
        u: f64,
        v: f64,
        bar: &SurfaceTangent,
    ) {
        let surf = db.surface(s);
        if surf.control.is_empty() {
            return;
        }
        let (p, lu, lv) = surf.locate(u, v);
        let patch = &surf.patches[p];
        let (a, b) = (Lagrange::at(patch.deg_u, lu), Lagrange::at(patch.deg_v, lv));
        let m1 = patch.deg_v + 1;
        for (k, id) in surf.control.nodes[p].iter().enumerate() {
            let (i, j) = (k / m1, k % m1);
            self.nodes[id.index()] += bar.point * (a.value[i] * b.value[j])
                + bar.du * (a.d1[i] * b.value[j])
                + bar.dv * (a.value[i] * b.d1[j]);
        }
    }

    /// ⟨self, other⟩ over every entry (nodes, the curves' own control points where both
    /// carry them, corners, ranges).
    pub fn dot(&self, other: &Self) -> f64 {
        let mut s: f64 = self
            .nodes
            .iter()
            .zip(&other.nodes)
            .map(|(a, b)| a.dot(b))
            .sum();
        for (a, b) in self.curves.iter().zip(&other.curves) {
            if let (Some(a), Some(b)) = (a, b) {
                for (x, y) in a.iter().zip(b) {
                    s += x.iter().zip(y).map(|(p, q)| p.dot(q)).sum::<f64>();
                }
            }
        }
        s += self
            .corners
            .iter()
            .zip(&other.corners)
            .map(|(a, b)| a.dot(b))
            .sum::<f64>();
        s + self
            .ranges
            .iter()
            .zip(&other.ranges)
            .map(|(a, b)| a[0] * b[0] + a[1] * b[1])
            .sum::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::ParamSurface;
    use crate::prelude::Point3;
    use crate::surface::Patch;

    #[test]
    fn lagrange_is_the_cardinal_basis_with_its_derivatives() {
        for n in [1, 3, 8, 10] {
            let x = control::nodes(n);
            for (i, &xi) in x.iter().enumerate() {
                let l = Lagrange::at(n, xi);
                for j in 0..=n {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((l.value[j] - want).abs() < 1e-9, "n={n} i={i} j={j}");
                }
            }
            // derivatives by central differences at an interior point
            let (t, h) = (0.37, 1e-5);
            let (l, lp, lm) = (
                Lagrange::at(n, t),
                Lagrange::at(n, t + h),
                Lagrange::at(n, t - h),
            );
            for j in 0..=n {
                let d1 = (lp.value[j] - lm.value[j]) / (2.0 * h);
                let d2 = (lp.d1[j] - lm.d1[j]) / (2.0 * h);
                assert!(
                    (d1 - l.d1[j]).abs() < 1e-6 * (1.0 + d1.abs()),
                    "n={n} d1 {j}"
                );
                assert!(
                    (d2 - l.d2[j]).abs() < 1e-5 * (1.0 + d2.abs()),
                    "n={n} d2 {j}"
                );
            }
        }
    }

    #[test]
    fn patch_through_lagrange_weights_is_the_patch() {
        let (nu, nv) = (3, 2);
        let pts: Vec<Point3> = (0..(nu + 1) * (nv + 1))
            .map(|k| Point3::new((k as f64).sin(), (k as f64 * 0.3).cos(), k as f64 * 0.1))
            .collect();
        let patch = Patch::from_control_points(nu, nv, &pts);
        let (u, v) = (0.31, 0.77);
        let (a, b) = (Lagrange::at(nu, u), Lagrange::at(nv, v));
        let mut p = Vector3::zeros();
        let mut pu = Vector3::zeros();
        let mut pv = Vector3::zeros();
        for (k, q) in pts.iter().enumerate() {
            let (i, j) = (k / (nv + 1), k % (nv + 1));
            p += q.coords * (a.value[i] * b.value[j]);
            pu += q.coords * (a.d1[i] * b.value[j]);
            pv += q.coords * (a.value[i] * b.d1[j]);
        }
        let d = patch.derivs(u, v);
        assert!((d.point.coords - p).norm() < 1e-12);
        assert!((d.du - pu).norm() < 1e-11);
        assert!((d.dv - pv).norm() < 1e-11);
        let _ = ParamSurface::domain(&crate::SupportSurface::new("s", 1, 1, vec![patch]));
    }
}
