//! Support surfaces (Eqs. 7–10): a regular grid of n_u × n_v patches
//! r(u, v) = U·A·V = Σ_{k,l} a_{k,l} u^k v^l, local (u, v) ∈ [0, 1]² per patch, global
//! (u, v) ∈ [0, n_u] × [0, n_v].

use serde::{Deserialize, Serialize};

use crate::control;
use crate::curve::{Arc, locate};
use crate::eval::{ParamSurface, SurfaceDerivs};
use crate::ids::ControlNodeId;
use crate::prelude::{Point3, Vector3};

/// One patch: r(u, v) = Σ_{k=0..n} Σ_{l=0..m} a_{k,l} u^k v^l (Eq. 7).
///
/// Coefficient order: `coeffs[k * (deg_v + 1) + l]` = a_{k,l} (k the power of u, l the power
/// of v; rows of A in Eq. 10 are contiguous).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Patch {
    /// Degree n in u.
    pub deg_u: usize,
    /// Degree m in v.
    pub deg_v: usize,
    /// a_{k,l}, (n+1)(m+1) of them, row-major in k.
    pub coeffs: Vec<Point3>,
}

impl Patch {
    /// The coefficient a_{k,l}.
    #[inline]
    pub fn coeff(&self, k: usize, l: usize) -> Point3 {
        self.coeffs[k * (self.deg_v + 1) + l]
    }

    /// r(u, v) at local parameters (Horner in v for each power of u, then Horner in u).
    #[inline]
    pub fn point(&self, u: f64, v: f64) -> Point3 {
        // Bicubic patches (the common CAD case) take a path with the loop bounds known at
        // compile time; the arithmetic, and so the result, is the same.
        if self.deg_u == 3
            && self.deg_v == 3
            && let Ok(c) = <&[Point3; 16]>::try_from(self.coeffs.as_slice())
        {
            return horner_2d_fixed::<4, 16>(c, u, v);
        }
        let m1 = self.deg_v + 1;
        let mut acc = Vector3::zeros();
        for row in self.coeffs.chunks_exact(m1).rev() {
            let mut c = Vector3::zeros();
            for a in row.iter().rev() {
                c = c * v + a.coords;
            }
            acc = acc * u + c;
        }
        Point3::from(acc)
    }

    /// r and its first and second partial derivatives at local parameters.
    #[inline]
    pub fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
        let m1 = self.deg_v + 1;
        let z = Vector3::zeros();
        // Horner in u over the rows' values c_k(v), c_k'(v), c_k''(v).
        let (mut p, mut pu, mut puu) = (z, z, z);
        let (mut q, mut qu) = (z, z); // from c_k'(v)
        let mut s = z; // from c_k''(v)
        for row in self.coeffs.chunks_exact(m1).rev() {
            let (mut c, mut c1, mut c2) = (z, z, z);
            for a in row.iter().rev() {
                c2 = c2 * v + c1;
                c1 = c1 * v + c;
                c = c * v + a.coords;
            }
            puu = puu * u + pu;
            pu = pu * u + p;
            p = p * u + c;
            qu = qu * u + q;
            q = q * u + c1;
            s = s * u + c2;
        }
        SurfaceDerivs {
            point: Point3::from(p),
            du: pu,
            dv: q,
            duu: puu * 2.0,
            duv: qu,
            dvv: s * 2.0,
        }
    }

    /// The patch interpolating control points at the frozen tensor grid of nodes
    /// (A = V_u⁻¹ R V_v⁻ᵀ, Eq. 9); `pts[i * (deg_v + 1) + j]` = r(x_i, y_j).
    ///
    /// # Panics
    /// If `pts.len() != (deg_u + 1)(deg_v + 1)` or a degree exceeds [`control::MAX_DEGREE`].
    pub fn from_control_points(deg_u: usize, deg_v: usize, pts: &[Point3]) -> Self {
        assert_eq!(pts.len(), (deg_u + 1) * (deg_v + 1));
        Self {
            deg_u,
            deg_v,
            coeffs: control::coeffs_from_points_2d(deg_u, deg_v, pts),
        }
    }

    /// The patch of degree `deg_u × deg_v` interpolating `f(u, v)` on the frozen tensor grid
    /// of nodes (exact when `f` is a polynomial of at most those degrees).
    ///
    /// # Panics
    /// If a degree exceeds [`control::MAX_DEGREE`].
    pub fn interpolate(deg_u: usize, deg_v: usize, f: impl Fn(f64, f64) -> Point3) -> Self {
        let mut pts = Vec::with_capacity((deg_u + 1) * (deg_v + 1));
        for &u in control::nodes(deg_u) {
            for &v in control::nodes(deg_v) {
                pts.push(f(u, v));
            }
        }
        Self::from_control_points(deg_u, deg_v, &pts)
    }

    /// The control points r(x_i, y_j) on the frozen node grid, `[i * (deg_v + 1) + j]`.
    pub fn control_points(&self) -> Vec<Point3> {
        let xu = control::nodes(self.deg_u);
        let xv = control::nodes(self.deg_v);
        let mut out = Vec::with_capacity(xu.len() * xv.len());
        for &u in xu {
            for &v in xv {
                out.push(self.point(u, v));
            }
        }
        out
    }

    /// The border v = const (`v` = 0 or 1) as an arc in u, or u = const as an arc in v.
    pub fn border(&self, side: Side) -> Arc {
        let (n1, m1) = (self.deg_u + 1, self.deg_v + 1);
        match side {
            Side::VMin => Arc::new((0..n1).map(|k| self.coeff(k, 0)).collect()),
            Side::VMax => Arc::new(
                (0..n1)
                    .map(|k| {
                        Point3::from(
                            (0..m1).fold(Vector3::zeros(), |s, l| s + self.coeff(k, l).coords),
                        )
                    })
                    .collect(),
            ),
            Side::UMin => Arc::new((0..m1).map(|l| self.coeff(0, l)).collect()),
            Side::UMax => Arc::new(
                (0..m1)
                    .map(|l| {
                        Point3::from(
                            (0..n1).fold(Vector3::zeros(), |s, k| s + self.coeff(k, l).coords),
                        )
                    })
                    .collect(),
            ),
        }
    }
}

/// Σ_{k,l} a_{k,l} u^k v^l for a square coefficient array of side M (M² = N), in the same
/// operation order as [`Patch::point`].
#[inline(always)]
fn horner_2d_fixed<const M: usize, const N: usize>(c: &[Point3; N], u: f64, v: f64) -> Point3 {
    let mut acc = Vector3::zeros();
    for k in (0..M).rev() {
        let mut r = Vector3::zeros();
        for l in (0..M).rev() {
            r = r * v + c[k * M + l].coords;
        }
        acc = acc * u + r;
    }
    Point3::from(acc)
}

/// A side of a patch's parameter square.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Side {
    /// u = 0 (an arc in v).
    UMin,
    /// u = 1 (an arc in v).
    UMax,
    /// v = 0 (an arc in u).
    VMin,
    /// v = 1 (an arc in u).
    VMax,
}

/// Control nodes of a support surface: `nodes[p]` lists the (n+1)(m+1) ids of patch p,
/// `[i * (m + 1) + j]` at local parameters (x_i, y_j) of [`control::nodes`]. Empty when the
/// surface has no control nodes.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct SurfaceControl {
    /// Per patch, its control node ids.
    pub nodes: Vec<Vec<ControlNodeId>>,
}

impl SurfaceControl {
    /// True when the surface carries no control nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// A support surface: `n_u × n_v` patches on a regular grid of the parametric plane.
///
/// Patch order: patch (i, j) (i-th in u, j-th in v) is `patches[j * n_u + i]` and covers
/// global parameters [i, i+1] × [j, j+1].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportSurface {
    /// A name for messages and reports (may be empty).
    #[serde(default)]
    pub name: String,
    /// Number of patches in u.
    pub n_u: usize,
    /// Number of patches in v.
    pub n_v: usize,
    /// The patches, `patches[j * n_u + i]`.
    pub patches: Vec<Patch>,
    /// The control nodes of each patch (§3).
    #[serde(default, skip_serializing_if = "SurfaceControl::is_empty")]
    pub control: SurfaceControl,
}

impl SupportSurface {
    /// A surface without control nodes.
    pub fn new(name: impl Into<String>, n_u: usize, n_v: usize, patches: Vec<Patch>) -> Self {
        Self {
            name: name.into(),
            n_u,
            n_v,
            patches,
            control: SurfaceControl::default(),
        }
    }

    /// Index of patch (i, j) in `patches`.
    #[inline]
    pub fn patch_index(&self, i: usize, j: usize) -> usize {
        j * self.n_u + i
    }

    /// The patch (i, j).
    #[inline]
    pub fn patch(&self, i: usize, j: usize) -> &Patch {
        &self.patches[self.patch_index(i, j)]
    }

    /// Patch index and local parameters of global (u, v) (cells clamped to the grid; outside
    /// the domain the border patches are extended).
    #[inline]
    pub fn locate(&self, u: f64, v: f64) -> (usize, f64, f64) {
        let (i, lu) = locate(u, self.n_u);
        let (j, lv) = locate(v, self.n_v);
        (j * self.n_u + i, lu, lv)
    }

    /// Points at many global parameter pairs (in parallel above a size threshold; the result
    /// does not depend on the number of threads).
    pub fn points(&self, uv: &[(f64, f64)]) -> Vec<Point3> {
        crate::par_map(uv, |&(u, v)| ParamSurface::point(self, u, v))
    }

    /// Points and derivatives at many global parameter pairs (parallel, deterministic).
    pub fn derivs_many(&self, uv: &[(f64, f64)]) -> Vec<SurfaceDerivs> {
        crate::par_map(uv, |&(u, v)| ParamSurface::derivs(self, u, v))
    }
}

impl ParamSurface for SupportSurface {
    fn domain(&self) -> ([f64; 2], [f64; 2]) {
        ([0.0, self.n_u as f64], [0.0, self.n_v as f64])
    }

    #[inline]
    fn point(&self, u: f64, v: f64) -> Point3 {
        let (p, lu, lv) = self.locate(u, v);
        self.patches[p].point(lu, lv)
    }

    #[inline]
    fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
        let (p, lu, lv) = self.locate(u, v);
        self.patches[p].derivs(lu, lv)
    }

    fn breaks(&self) -> (Vec<f64>, Vec<f64>) {
        (
            (1..self.n_u).map(|i| i as f64).collect(),
            (1..self.n_v).map(|j| j as f64).collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_patch() -> Patch {
        let mut coeffs = Vec::new();
        for k in 0..3 {
            for l in 0..4 {
                coeffs.push(Point3::new(
                    (k + 2 * l) as f64 * 0.1 + 1.0,
                    (k * l) as f64 * 0.3 - 0.2,
                    (3 * k + l) as f64 * 0.05,
                ));
            }
        }
        Patch {
            deg_u: 2,
            deg_v: 3,
            coeffs,
        }
    }

    #[test]
    fn point_is_double_sum() {
        let p = sample_patch();
        let (u, v): (f64, f64) = (0.37, 0.81);
        let mut want = Vector3::zeros();
        for k in 0..=2 {
            for l in 0..=3 {
                want += p.coeff(k, l).coords * u.powi(k as i32) * v.powi(l as i32);
            }
        }
        assert!((p.point(u, v).coords - want).norm() < 1e-14);
        assert!((p.derivs(u, v).point.coords - want).norm() < 1e-14);
    }

    #[test]
    fn bicubic_fast_path_is_bit_identical() {
        let mut coeffs = Vec::new();
        for k in 0..16 {
            coeffs.push(Point3::new(
                k as f64 * 0.37 - 1.0,
                (k * k) as f64 * 0.01,
                0.5 - k as f64 * 0.1,
            ));
        }
        let p = Patch {
            deg_u: 3,
            deg_v: 3,
            coeffs,
        };
        for &(u, v) in &[(0.0, 0.0), (0.3, 0.9), (1.0, 0.5), (0.77, 0.123)] {
            // the general loop, written out
            let mut acc = Vector3::zeros();
            for row in p.coeffs.chunks_exact(4).rev() {
                let mut c = Vector3::zeros();
                for a in row.iter().rev() {
                    c = c * v + a.coords;
                }
                acc = acc * u + c;
            }
            assert_eq!(p.point(u, v), Point3::from(acc));
            assert_eq!(p.point(u, v), p.derivs(u, v).point);
        }
    }

    #[test]
    fn borders_match_patch() {
        let p = sample_patch();
        for &t in &[0.0, 0.3, 1.0] {
            assert!((p.border(Side::VMin).point(t) - p.point(t, 0.0)).norm() < 1e-14);
            assert!((p.border(Side::VMax).point(t) - p.point(t, 1.0)).norm() < 1e-14);
            assert!((p.border(Side::UMin).point(t) - p.point(0.0, t)).norm() < 1e-14);
            assert!((p.border(Side::UMax).point(t) - p.point(1.0, t)).norm() < 1e-14);
        }
    }

    #[test]
    fn control_points_round_trip() {
        let p = sample_patch();
        let q = Patch::from_control_points(2, 3, &p.control_points());
        for (a, b) in p.coeffs.iter().zip(&q.coeffs) {
            assert!((a - b).norm() < 1e-12);
        }
    }
}
