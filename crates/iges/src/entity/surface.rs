//! Surface entities: 108 plane, 114 parametric spline surface, 118 ruled surface, 120
//! surface of revolution, 122 tabulated cylinder, 128 rational B-spline surface, 140 offset
//! surface.

use super::{Dec, Enc, write_err};
use crate::directory::DeId;
use crate::error::EntityProblem;

/// 114 parametric spline surface: an M × N grid of bicubic patches. On patch (i, j), with
/// s = u − TU(i) and t = v − TV(j), x(u, v) = Σ_{p,q ≤ 3} c\[4q + p\] sᵖ t^q (likewise y, z),
/// i.e. the file's order A, B, C, D, E, F, ... S of coefficients.
#[derive(Debug, Clone, PartialEq)]
pub struct SplineSurface {
    /// CTYPE: 1 linear, 2 quadratic, 3 cubic, 4 Wilson-Fowler, 5 modified Wilson-Fowler,
    /// 6 B-spline.
    pub boundary_type: i64,
    /// PTYPE: 1 Cartesian product, 0 unspecified.
    pub patch_type: i64,
    /// TU(1..M+1).
    pub u_breaks: Vec<f64>,
    /// TV(1..N+1).
    pub v_breaks: Vec<f64>,
    /// Patch (i, j) at `i * N + j` (u index major, as in the file): `[x, y, z]` coefficients.
    pub patches: Vec<[[f64; 16]; 3]>,
}

impl SplineSurface {
    /// Number of patches in u (M) and v (N).
    pub fn n_patches(&self) -> (usize, usize) {
        (
            self.u_breaks.len().saturating_sub(1),
            self.v_breaks.len().saturating_sub(1),
        )
    }

    /// The coefficients of patch (i, j), 0-based.
    pub fn patch(&self, i: usize, j: usize) -> &[[f64; 16]; 3] {
        &self.patches[i * self.n_patches().1 + j]
    }

    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let boundary_type = d.int("CTYPE")?;
        let patch_type = d.int("PTYPE")?;
        let im = d.index();
        let m = d.count("M (number of u segments)", 1, 1)?;
        let inn = d.index();
        let n = d.count("N (number of v segments)", 1, 1)?;
        // Break points, then 48 coefficients for each of the M × N patches plus 48
        // arbitrary values closing each u row (the last block of 48 (N + 1) may be absent).
        let need = (m + n + 2) as u128 + 48 * (m as u128) * (n as u128 + 1);
        d.require(im, "M (number of u segments)", m as i64, need)?;
        let _ = inn;
        let u_breaks = d.real_vec(m + 1, "u break point")?;
        let v_breaks = d.real_vec(n + 1, "v break point")?;
        let mut patches = Vec::with_capacity(m * n);
        for _ in 0..m {
            for _ in 0..n {
                let mut p = [[0.0; 16]; 3];
                for axis in &mut p {
                    *axis = d.reals("patch coefficient")?;
                }
                patches.push(p);
            }
            d.skip(48);
        }
        d.skip(48 * (n + 1));
        Ok(SplineSurface {
            boundary_type,
            patch_type,
            u_breaks,
            v_breaks,
            patches,
        })
    }

    pub(crate) fn encode(&self, e: &mut Enc) -> Result<(), EntityProblem> {
        let (m, n) = self.n_patches();
        if m == 0 || n == 0 || self.patches.len() != m * n {
            return Err(write_err(format!(
                "114 with {} u and {} v break points needs {} patches, has {}",
                self.u_breaks.len(),
                self.v_breaks.len(),
                m * n,
                self.patches.len()
            )));
        }
        e.int(self.boundary_type);
        e.int(self.patch_type);
        e.len(m);
        e.len(n);
        e.reals(&self.u_breaks);
        e.reals(&self.v_breaks);
        for i in 0..m {
            for j in 0..n {
                self.patch(i, j).iter().for_each(|a| e.reals(a));
            }
            e.reals(&[0.0; 48]);
        }
        for _ in 0..=n {
            e.reals(&[0.0; 48]);
        }
        Ok(())
    }
}

/// 118 ruled surface between two curves (form 0: equal relative arc length, form 1: equal
/// relative parametric values).
#[derive(Debug, Clone, PartialEq)]
pub struct RuledSurface {
    /// DE1: first curve.
    pub curve1: DeId,
    /// DE2: second curve.
    pub curve2: DeId,
    /// DIRFLG: false joins first to first point, true first to last.
    pub reversed: bool,
    /// DEVFLG: the surface is developable.
    pub developable: bool,
}

impl RuledSurface {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(RuledSurface {
            curve1: d.ptr("first curve")?,
            curve2: d.ptr("second curve")?,
            reversed: d.flag("DIRFLG")?,
            developable: d.flag("DEVFLG")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.curve1);
        e.ptr(self.curve2);
        e.flag(self.reversed);
        e.flag(self.developable);
    }
}

/// 120 surface of revolution: the generatrix rotated about the axis line from
/// `start_angle` to `end_angle` (radians). Parameters: (generatrix parameter, angle).
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceOfRevolution {
    /// L: the axis (a 110 line).
    pub axis: DeId,
    /// C: the generatrix curve.
    pub generatrix: DeId,
    /// SA: start angle.
    pub start_angle: f64,
    /// TA: terminate angle.
    pub end_angle: f64,
}

impl SurfaceOfRevolution {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(SurfaceOfRevolution {
            axis: d.ptr("axis line")?,
            generatrix: d.ptr("generatrix")?,
            start_angle: d.real("start angle")?,
            end_angle: d.real("terminate angle")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.axis);
        e.ptr(self.generatrix);
        e.real(self.start_angle);
        e.real(self.end_angle);
    }
}

/// 122 tabulated cylinder: the directrix swept along the vector from its start point to
/// `end`. Parameters: (directrix parameter normalised to [0, 1], 0..1 along the sweep).
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedCylinder {
    /// DE: the directrix curve.
    pub directrix: DeId,
    /// (LX, LY, LZ): terminate point of the generatrix line.
    pub end: [f64; 3],
}

impl TabulatedCylinder {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(TabulatedCylinder {
            directrix: d.ptr("directrix")?,
            end: d.reals("generatrix terminate point")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.directrix);
        e.reals(&self.end);
    }
}

/// 128 rational B-spline surface of degrees (M1, M2) with (K1 + 1) × (K2 + 1) control
/// points, stored with u varying fastest: point (i, j) at `i + (K1 + 1) j`.
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineSurface {
    /// M1: degree in u.
    pub degree_u: usize,
    /// M2: degree in v.
    pub degree_v: usize,
    /// K1 + 1: number of control points in u.
    pub n_u: usize,
    /// K2 + 1: number of control points in v.
    pub n_v: usize,
    /// PROP1: closed in u.
    pub closed_u: bool,
    /// PROP2: closed in v.
    pub closed_v: bool,
    /// PROP3: polynomial (all weights equal).
    pub polynomial: bool,
    /// PROP4: periodic in u.
    pub periodic_u: bool,
    /// PROP5: periodic in v.
    pub periodic_v: bool,
    /// S(−M1..N1+M1): K1 + M1 + 2 knots.
    pub knots_u: Vec<f64>,
    /// T(−M2..N2+M2): K2 + M2 + 2 knots.
    pub knots_v: Vec<f64>,
    /// W(i, j), u fastest.
    pub weights: Vec<f64>,
    /// (X, Y, Z)(i, j), u fastest.
    pub control_points: Vec<[f64; 3]>,
    /// U(0), U(1).
    pub u_range: [f64; 2],
    /// V(0), V(1).
    pub v_range: [f64; 2],
}

impl BSplineSurface {
    /// Control point (i, j).
    pub fn control_point(&self, i: usize, j: usize) -> [f64; 3] {
        self.control_points[i + self.n_u * j]
    }

    /// Weight (i, j).
    pub fn weight(&self, i: usize, j: usize) -> f64 {
        self.weights[i + self.n_u * j]
    }

    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let ik1 = d.index();
        let k1 = d.int("K1")?;
        let ik2 = d.index();
        let k2 = d.int("K2")?;
        let im1 = d.index();
        let m1 = d.int("M1 (u degree)")?;
        let im2 = d.index();
        let m2 = d.int("M2 (v degree)")?;
        let props = [
            d.flag("PROP1")?,
            d.flag("PROP2")?,
            d.flag("PROP3")?,
            d.flag("PROP4")?,
            d.flag("PROP5")?,
        ];
        let k1 = d.check_count(ik1, "K1", k1, 1, 0, 0)?;
        let k2 = d.check_count(ik2, "K2", k2, 1, 0, 0)?;
        let m1 = d.check_count(im1, "M1 (u degree)", m1, 1, 1, 0)?;
        let m2 = d.check_count(im2, "M2 (v degree)", m2, 1, 1, 0)?;
        let np = (k1 as u128 + 1) * (k2 as u128 + 1);
        let need = (k1 + m1 + 2) as u128 + (k2 + m2 + 2) as u128 + 4 * np + 4;
        d.require(ik1, "K1", k1 as i64, need)?;
        let np = np as usize;
        let knots_u = d.real_vec(k1 + m1 + 2, "u knot")?;
        let knots_v = d.real_vec(k2 + m2 + 2, "v knot")?;
        let weights = d.real_vec(np, "weight")?;
        let mut control_points = Vec::with_capacity(np);
        for _ in 0..np {
            control_points.push(d.reals("control point")?);
        }
        Ok(BSplineSurface {
            degree_u: m1,
            degree_v: m2,
            n_u: k1 + 1,
            n_v: k2 + 1,
            closed_u: props[0],
            closed_v: props[1],
            polynomial: props[2],
            periodic_u: props[3],
            periodic_v: props[4],
            knots_u,
            knots_v,
            weights,
            control_points,
            u_range: d.reals("u range")?,
            v_range: d.reals("v range")?,
        })
    }

    pub(crate) fn encode(&self, e: &mut Enc) -> Result<(), EntityProblem> {
        let np = self.n_u * self.n_v;
        if np == 0
            || self.degree_u == 0
            || self.degree_v == 0
            || self.weights.len() != np
            || self.control_points.len() != np
            || self.knots_u.len() != self.n_u + self.degree_u + 1
            || self.knots_v.len() != self.n_v + self.degree_v + 1
        {
            return Err(write_err(format!(
                "128 of degrees {}×{} with {}×{} control points has {} points, {} weights, {} u knots, {} v knots",
                self.degree_u,
                self.degree_v,
                self.n_u,
                self.n_v,
                self.control_points.len(),
                self.weights.len(),
                self.knots_u.len(),
                self.knots_v.len()
            )));
        }
        e.len(self.n_u - 1);
        e.len(self.n_v - 1);
        e.len(self.degree_u);
        e.len(self.degree_v);
        for f in [
            self.closed_u,
            self.closed_v,
            self.polynomial,
            self.periodic_u,
            self.periodic_v,
        ] {
            e.flag(f);
        }
        e.reals(&self.knots_u);
        e.reals(&self.knots_v);
        e.reals(&self.weights);
        self.control_points.iter().for_each(|p| e.reals(p));
        e.reals(&self.u_range);
        e.reals(&self.v_range);
        Ok(())
    }
}

/// 108 plane A x + B y + C z = D; form 0 unbounded, form 1 bounded by the closed curve
/// `boundary`, form −1 a hole bounded by it.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    /// A, B, C, D.
    pub coefficients: [f64; 4],
    /// PTR: the closed bounding curve (forms ±1), `None` when unbounded.
    pub boundary: Option<DeId>,
    /// (X, Y, Z): where the display symbol is drawn.
    pub symbol_location: [f64; 3],
    /// SIZE: display symbol size.
    pub symbol_size: f64,
}

impl Plane {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(Plane {
            coefficients: d.reals("plane coefficient")?,
            boundary: d.opt_ptr("bounding curve")?,
            symbol_location: d.reals("display symbol location")?,
            symbol_size: d.real("display symbol size")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.reals(&self.coefficients);
        e.opt_ptr(self.boundary);
        e.reals(&self.symbol_location);
        e.real(self.symbol_size);
    }
}

/// 140 offset surface: O(u, v) = S(u, v) + d N(u, v), N the unit normal of the surface
/// `surface`; `indicator` is a vector on the side of the offset.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetSurface {
    /// (NX, NY, NZ): offset indicator.
    pub indicator: [f64; 3],
    /// D: offset distance.
    pub distance: f64,
    /// DE: the surface offset.
    pub surface: DeId,
}

impl OffsetSurface {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(OffsetSurface {
            indicator: d.reals("offset indicator")?,
            distance: d.real("offset distance")?,
            surface: d.ptr("surface")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.reals(&self.indicator);
        e.real(self.distance);
        e.ptr(self.surface);
    }
}
