//! Analytic curves and surfaces with exactly known geometry, for the tests and the bench.
#![allow(dead_code)]

use geom_db::eval::{CurveDerivs, ParamCurve, ParamSurface, SurfaceDerivs};
use geom_db::prelude::{Point3, Vector3};
use std::f64::consts::PI;

/// r(u, v) = o + u e1 + v e2 on [u0, u1] × [v0, v1].
#[derive(Debug, Clone)]
pub struct Plane {
    pub o: Point3,
    pub e1: Vector3,
    pub e2: Vector3,
    pub dom: ([f64; 2], [f64; 2]),
}

impl Plane {
    /// The plane z = h, (u, v) = (x, y) on [-a, a]².
    pub fn horizontal(h: f64, a: f64) -> Self {
        Self {
            o: Point3::new(0.0, 0.0, h),
            e1: Vector3::x(),
            e2: Vector3::y(),
            dom: ([-a, a], [-a, a]),
        }
    }
    /// Unit normal e1 × e2 / |e1 × e2|.
    pub fn normal(&self) -> Vector3 {
        self.e1.cross(&self.e2).normalize()
    }
    /// The same plane translated by d.
    pub fn translated(&self, d: Vector3) -> Self {
        Self {
            o: self.o + d,
            ..self.clone()
        }
    }
}

impl ParamSurface for Plane {
    fn domain(&self) -> ([f64; 2], [f64; 2]) {
        self.dom
    }
    fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
        let z = Vector3::zeros();
        SurfaceDerivs {
            point: self.o + self.e1 * u + self.e2 * v,
            du: self.e1,
            dv: self.e2,
            duu: z,
            duv: z,
            dvv: z,
        }
    }
}

/// Sphere: u azimuth in [0, 2π], v polar angle in [0.05, π − 0.05] (poles cut off).
#[derive(Debug, Clone)]
pub struct Sphere {
    pub c: Point3,
    pub r: f64,
}

impl ParamSurface for Sphere {
    fn domain(&self) -> ([f64; 2], [f64; 2]) {
        ([0.0, 2.0 * PI], [0.05, PI - 0.05])
    }
    fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
        let (su, cu) = u.sin_cos();
        let (sv, cv) = v.sin_cos();
        let r = self.r;
        SurfaceDerivs {
            point: self.c + Vector3::new(sv * cu, sv * su, cv) * r,
            du: Vector3::new(-sv * su, sv * cu, 0.0) * r,
            dv: Vector3::new(cv * cu, cv * su, -sv) * r,
            duu: Vector3::new(-sv * cu, -sv * su, 0.0) * r,
            duv: Vector3::new(-cv * su, cv * cu, 0.0) * r,
            dvv: Vector3::new(-sv * cu, -sv * su, -cv) * r,
        }
    }
}

/// Circular cylinder r = o + R cos u a + R sin u b + v c (a, b, c orthonormal),
/// u ∈ [u0, u1], v ∈ [v0, v1].
#[derive(Debug, Clone)]
pub struct Cylinder {
    pub o: Point3,
    pub a: Vector3,
    pub b: Vector3,
    pub c: Vector3,
    pub r: f64,
    pub dom: ([f64; 2], [f64; 2]),
}

impl Cylinder {
    /// Axis z through the origin: x² + y² = R²; u ∈ [-π, π], v = z ∈ [-l, l].
    pub fn axis_z(r: f64, l: f64) -> Self {
        Self {
            o: Point3::origin(),
            a: Vector3::x(),
            b: Vector3::y(),
            c: Vector3::z(),
            r,
            dom: ([-PI, PI], [-l, l]),
        }
    }
    /// Axis x through the origin: y² + z² = R², point (v, R cos u, R sin u); u ∈ [-π, π],
    /// v = x ∈ [-l, l].
    pub fn axis_x(r: f64, l: f64) -> Self {
        Self {
            o: Point3::origin(),
            a: Vector3::y(),
            b: Vector3::z(),
            c: Vector3::x(),
            r,
            dom: ([-PI, PI], [-l, l]),
        }
    }
}

impl ParamSurface for Cylinder {
    fn domain(&self) -> ([f64; 2], [f64; 2]) {
        self.dom
    }
    fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
        let (s, c) = u.sin_cos();
        let r = self.r;
        SurfaceDerivs {
            point: self.o + (self.a * c + self.b * s) * r + self.c * v,
            du: (self.b * c - self.a * s) * r,
            dv: self.c,
            duu: -(self.a * c + self.b * s) * r,
            duv: Vector3::zeros(),
            dvv: Vector3::zeros(),
        }
    }
}

/// A torus (axis z, major radius `big`, tube radius `small`) cut into nu × nv patches with
/// global parameters u ∈ [0, nu], v ∈ [0, nv]. Inside patch i the angle runs
/// θ = θ_i + Δθ (s + κ_i s(1 − s)), s = u − i, with κ_i alternating ±0.3: the geometry is
/// smooth but the parametrisation is only C0 across patch borders (like a real patch set).
#[derive(Debug, Clone)]
pub struct TorusPatches {
    pub big: f64,
    pub small: f64,
    pub nu: usize,
    pub nv: usize,
}

fn warp(x: f64, n: usize, span: f64) -> (f64, f64, f64) {
    // angle, d angle / dx, d² angle / dx²
    let i = (x.floor() as isize).clamp(0, n as isize - 1) as usize;
    let s = x - i as f64;
    let k = if i.is_multiple_of(2) { 0.3 } else { -0.3 };
    let d = span / n as f64;
    (
        d * (i as f64 + s + k * s * (1.0 - s)),
        d * (1.0 + k * (1.0 - 2.0 * s)),
        d * (-2.0 * k),
    )
}

impl TorusPatches {
    /// The exact foot of the normal from p (p not on the axis nor on the core circle).
    pub fn exact_foot(&self, p: &Point3) -> (Point3, f64) {
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let core = Point3::new(p.x / rho * self.big, p.y / rho * self.big, 0.0);
        let d = p - core;
        let foot = core + d * (self.small / d.norm());
        (foot, (d.norm() - self.small).abs())
    }
}

impl ParamSurface for TorusPatches {
    fn domain(&self) -> ([f64; 2], [f64; 2]) {
        ([0.0, self.nu as f64], [0.0, self.nv as f64])
    }
    fn breaks(&self) -> (Vec<f64>, Vec<f64>) {
        (
            (1..self.nu).map(|i| i as f64).collect(),
            (1..self.nv).map(|i| i as f64).collect(),
        )
    }
    fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
        let (th, th1, th2) = warp(u, self.nu, 2.0 * PI);
        let (ph, ph1, ph2) = warp(v, self.nv, 2.0 * PI);
        let (st, ct) = th.sin_cos();
        let (sp, cp) = ph.sin_cos();
        let (rb, rs) = (self.big, self.small);
        let w = rb + rs * cp;
        // derivatives with respect to the angles
        let p = Point3::new(w * ct, w * st, rs * sp);
        let pt = Vector3::new(-w * st, w * ct, 0.0);
        let pp = Vector3::new(-rs * sp * ct, -rs * sp * st, rs * cp);
        let ptt = Vector3::new(-w * ct, -w * st, 0.0);
        let ptp = Vector3::new(rs * sp * st, -rs * sp * ct, 0.0);
        let ppp = Vector3::new(-rs * cp * ct, -rs * cp * st, -rs * sp);
        SurfaceDerivs {
            point: p,
            du: pt * th1,
            dv: pp * ph1,
            duu: ptt * th1 * th1 + pt * th2,
            duv: ptp * th1 * ph1,
            dvv: ppp * ph1 * ph1 + pp * ph2,
        }
    }
}

/// r(u, v) = (u, v, h(u, v)) with h a bicubic polynomial Σ c_kl u^k v^l on [0, 1]².
#[derive(Debug, Clone)]
pub struct BicubicGraph {
    pub c: [[f64; 4]; 4],
}

impl BicubicGraph {
    /// A fixed, non-trivial bicubic.
    pub fn sample() -> Self {
        Self {
            c: [
                [0.1, 0.3, -0.2, 0.05],
                [0.4, -0.5, 0.3, 0.1],
                [-0.3, 0.2, 0.25, -0.1],
                [0.15, 0.1, -0.05, 0.02],
            ],
        }
    }
    /// h and its partial derivatives (h, h_u, h_v, h_uu, h_uv, h_vv).
    pub fn h(&self, u: f64, v: f64) -> [f64; 6] {
        let pw = |x: f64| [1.0, x, x * x, x * x * x];
        let dp = |x: f64| [0.0, 1.0, 2.0 * x, 3.0 * x * x];
        let ddp = |x: f64| [0.0, 0.0, 2.0, 6.0 * x];
        let (u0, u1, u2) = (pw(u), dp(u), ddp(u));
        let (v0, v1, v2) = (pw(v), dp(v), ddp(v));
        let mut out = [0.0; 6];
        for k in 0..4 {
            for l in 0..4 {
                let c = self.c[k][l];
                out[0] += c * u0[k] * v0[l];
                out[1] += c * u1[k] * v0[l];
                out[2] += c * u0[k] * v1[l];
                out[3] += c * u2[k] * v0[l];
                out[4] += c * u1[k] * v1[l];
                out[5] += c * u0[k] * v2[l];
            }
        }
        out
    }
}

impl ParamSurface for BicubicGraph {
    fn domain(&self) -> ([f64; 2], [f64; 2]) {
        ([0.0, 1.0], [0.0, 1.0])
    }
    fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
        let h = self.h(u, v);
        SurfaceDerivs {
            point: Point3::new(u, v, h[0]),
            du: Vector3::new(1.0, 0.0, h[1]),
            dv: Vector3::new(0.0, 1.0, h[2]),
            duu: Vector3::new(0.0, 0.0, h[3]),
            duv: Vector3::new(0.0, 0.0, h[4]),
            dvv: Vector3::new(0.0, 0.0, h[5]),
        }
    }
}

/// A smooth closed body cut into nu × nv bicubic-Hermite patches (C1 across borders) in
/// global parameters: a test stand-in for a database surface made of many patches.
/// The underlying smooth shape is a bumped ellipsoid-like body of revolution; each patch
/// interpolates the shape's values and first derivatives (and the twist) at its corners.
#[derive(Debug, Clone)]
pub struct HermitePatches {
    pub nu: usize,
    pub nv: usize,
    /// per patch: 4×4 power-basis coefficient vectors a_kl (local u^k v^l), Eq. 7.
    pub coef: Vec<[[Vector3; 4]; 4]>,
}

fn body(s: f64, t: f64) -> (Point3, Vector3, Vector3, Vector3) {
    // s ∈ [0,1] along the body, t ∈ [0,1] around; returns r, r_s, r_t, r_st (analytic).
    let x = 10.0 * s;
    let rad = 1.0 + 0.15 * (2.0 * PI * 3.0 * s).sin();
    let rad_s = 0.15 * 2.0 * PI * 3.0 * (2.0 * PI * 3.0 * s).cos();
    let ph = 2.0 * PI * t;
    let (sp, cp) = ph.sin_cos();
    let ell = 1.0 + 0.2 * cp; // slightly non-circular section
    let ell_t = -0.2 * sp * 2.0 * PI;
    let r = Point3::new(x, rad * ell * cp, rad * sp);
    let r_s = Vector3::new(10.0, rad_s * ell * cp, rad_s * sp);
    let r_t = Vector3::new(
        0.0,
        rad * (ell_t * cp - ell * sp * 2.0 * PI),
        rad * cp * 2.0 * PI,
    );
    let r_st = Vector3::new(
        0.0,
        rad_s * (ell_t * cp - ell * sp * 2.0 * PI),
        rad_s * cp * 2.0 * PI,
    );
    (r, r_s, r_t, r_st)
}

impl HermitePatches {
    /// nu × nv patches over s ∈ [0.05, 0.95] (open body) and the full turn in t.
    pub fn new(nu: usize, nv: usize) -> Self {
        let (s0, s1) = (0.05, 0.95);
        let hs = (s1 - s0) / nu as f64;
        let ht = 1.0 / nv as f64;
        // Hermite basis in power form: H0 = 1 - 3x² + 2x³, H1 = x - 2x² + x³,
        // H2 = 3x² - 2x³, H3 = -x² + x³  (values at 0, slope at 0, value at 1, slope at 1)
        let hb: [[f64; 4]; 4] = [
            [1.0, 0.0, -3.0, 2.0],
            [0.0, 1.0, -2.0, 1.0],
            [0.0, 0.0, 3.0, -2.0],
            [0.0, 0.0, -1.0, 1.0],
        ];
        let mut coef = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                // geometry matrix G[a][b] for a, b in (val0, der0, val1, der1)
                let mut g = [[Vector3::zeros(); 4]; 4];
                for cu in 0..2 {
                    for cv in 0..2 {
                        let s = s0 + hs * (i + cu) as f64;
                        let t = ht * (j + cv) as f64;
                        let (r, rs, rt, rst) = body(s, t);
                        g[2 * cu][2 * cv] = r.coords;
                        g[2 * cu + 1][2 * cv] = rs * hs;
                        g[2 * cu][2 * cv + 1] = rt * ht;
                        g[2 * cu + 1][2 * cv + 1] = rst * hs * ht;
                    }
                }
                // a_kl = Σ_ab hb[a][k] G[a][b] hb[b][l]
                let mut a = [[Vector3::zeros(); 4]; 4];
                for k in 0..4 {
                    for l in 0..4 {
                        let mut acc = Vector3::zeros();
                        for ga in 0..4 {
                            for gb in 0..4 {
                                acc += g[ga][gb] * (hb[ga][k] * hb[gb][l]);
                            }
                        }
                        a[k][l] = acc;
                    }
                }
                coef.push(a);
            }
        }
        Self { nu, nv, coef }
    }
}

impl ParamSurface for HermitePatches {
    fn domain(&self) -> ([f64; 2], [f64; 2]) {
        ([0.0, self.nu as f64], [0.0, self.nv as f64])
    }
    fn breaks(&self) -> (Vec<f64>, Vec<f64>) {
        (
            (1..self.nu).map(|i| i as f64).collect(),
            (1..self.nv).map(|i| i as f64).collect(),
        )
    }
    fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
        let i = (u.floor() as isize).clamp(0, self.nu as isize - 1) as usize;
        let j = (v.floor() as isize).clamp(0, self.nv as isize - 1) as usize;
        let (s, t) = (u - i as f64, v - j as f64);
        let a = &self.coef[j * self.nu + i];
        let p = |x: f64| [1.0, x, x * x, x * x * x];
        let d = |x: f64| [0.0, 1.0, 2.0 * x, 3.0 * x * x];
        let dd = |x: f64| [0.0, 0.0, 2.0, 6.0 * x];
        let (u0, u1, u2) = (p(s), d(s), dd(s));
        let (v0, v1, v2) = (p(t), d(t), dd(t));
        let mut out = [Vector3::zeros(); 6];
        for k in 0..4 {
            for l in 0..4 {
                let c = a[k][l];
                out[0] += c * (u0[k] * v0[l]);
                out[1] += c * (u1[k] * v0[l]);
                out[2] += c * (u0[k] * v1[l]);
                out[3] += c * (u2[k] * v0[l]);
                out[4] += c * (u1[k] * v1[l]);
                out[5] += c * (u0[k] * v2[l]);
            }
        }
        SurfaceDerivs {
            point: Point3::from(out[0]),
            du: out[1],
            dv: out[2],
            duu: out[3],
            duv: out[4],
            dvv: out[5],
        }
    }
}

/// A circle c + R cos t e1 + R sin t e2, t ∈ [t0, t1].
#[derive(Debug, Clone)]
pub struct Circle {
    pub c: Point3,
    pub e1: Vector3,
    pub e2: Vector3,
    pub r: f64,
    pub dom: (f64, f64),
}

impl ParamCurve for Circle {
    fn domain(&self) -> (f64, f64) {
        self.dom
    }
    fn derivs(&self, t: f64) -> CurveDerivs {
        let (s, c) = t.sin_cos();
        CurveDerivs {
            point: self.c + (self.e1 * c + self.e2 * s) * self.r,
            d1: (self.e2 * c - self.e1 * s) * self.r,
            d2: -(self.e1 * c + self.e2 * s) * self.r,
        }
    }
}

/// A straight segment o + t d, t ∈ [t0, t1].
#[derive(Debug, Clone)]
pub struct Line {
    pub o: Point3,
    pub d: Vector3,
    pub dom: (f64, f64),
}

impl ParamCurve for Line {
    fn domain(&self) -> (f64, f64) {
        self.dom
    }
    fn derivs(&self, t: f64) -> CurveDerivs {
        CurveDerivs {
            point: self.o + self.d * t,
            d1: self.d,
            d2: Vector3::zeros(),
        }
    }
}

/// A curve through control points: arcs of degree n through n+1 points each (Lagrange interpolation at equally spaced local parameters),
/// global parameter t ∈ [0, n_arcs]. Mirrors the database's power-basis curve of Eq. 4.
#[derive(Debug, Clone)]
pub struct LagrangeCurve {
    pub degree: usize,
    pub points: Vec<Point3>,
}

impl LagrangeCurve {
    pub fn arcs(&self) -> usize {
        (self.points.len() - 1) / self.degree
    }
}

impl ParamCurve for LagrangeCurve {
    fn domain(&self) -> (f64, f64) {
        (0.0, self.arcs() as f64)
    }
    fn breaks(&self) -> Vec<f64> {
        (1..self.arcs()).map(|i| i as f64).collect()
    }
    fn derivs(&self, t: f64) -> CurveDerivs {
        let n = self.degree;
        let a = (t.floor() as isize).clamp(0, self.arcs() as isize - 1) as usize;
        let s = t - a as f64;
        let pts = &self.points[a * n..=a * n + n];
        let nodes: Vec<f64> = (0..=n).map(|k| k as f64 / n as f64).collect();
        // value, first and second derivative of each Lagrange basis polynomial at s
        let mut out = [Vector3::zeros(); 3];
        for k in 0..=n {
            let mut l = [1.0, 0.0, 0.0];
            for m in 0..=n {
                if m == k {
                    continue;
                }
                let den = nodes[k] - nodes[m];
                let f = [(s - nodes[m]) / den, 1.0 / den];
                // product rule for (l0, l1, l2) * (f0, f1, 0)
                l = [
                    l[0] * f[0],
                    l[1] * f[0] + l[0] * f[1],
                    l[2] * f[0] + 2.0 * l[1] * f[1],
                ];
            }
            for d in 0..3 {
                out[d] += pts[k].coords * l[d];
            }
        }
        CurveDerivs {
            point: Point3::from(out[0]),
            d1: out[1],
            d2: out[2],
        }
    }
}
