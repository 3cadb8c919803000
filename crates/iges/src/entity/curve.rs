//! Curve entities: 100 circular arc, 102 composite curve, 104 conic arc, 106 copious
//! data, 110 line, 112 parametric spline curve, 126 rational B-spline curve, 130 offset
//! curve.

use super::{Dec, Enc, write_err};
use crate::directory::DeId;
use crate::error::EntityProblem;

/// 100 circular arc, in the plane z = `z` of its definition space, counter-clockwise from
/// `start` to `end` around `center` (a full circle when `start == end`).
#[derive(Debug, Clone, PartialEq)]
pub struct CircularArc {
    /// ZT: the plane's z.
    pub z: f64,
    /// (X1, Y1): centre.
    pub center: [f64; 2],
    /// (X2, Y2): start point.
    pub start: [f64; 2],
    /// (X3, Y3): end point.
    pub end: [f64; 2],
}

impl CircularArc {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(CircularArc {
            z: d.real("ZT")?,
            center: d.reals("centre")?,
            start: d.reals("start point")?,
            end: d.reals("end point")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.real(self.z);
        e.reals(&self.center);
        e.reals(&self.start);
        e.reals(&self.end);
    }
}

/// 102 composite curve: the curves joined end to end, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct CompositeCurve {
    /// DE(1..N): the constituent curves.
    pub curves: Vec<DeId>,
}

impl CompositeCurve {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let n = d.count("N (number of curves)", 1, 0)?;
        let curves = (0..n)
            .map(|_| d.ptr("constituent curve"))
            .collect::<Result<_, _>>()?;
        Ok(CompositeCurve { curves })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.len(self.curves.len());
        self.curves.iter().for_each(|&c| e.ptr(c));
    }
}

/// 104 conic arc A x² + B xy + C y² + D x + E y + F = 0 in the plane z = `z`, from
/// `start` to `end` (the form number says ellipse 1, hyperbola 2, parabola 3).
#[derive(Debug, Clone, PartialEq)]
pub struct ConicArc {
    /// A, B, C, D, E, F.
    pub coefficients: [f64; 6],
    /// ZT: the plane's z.
    pub z: f64,
    /// (X1, Y1): start point.
    pub start: [f64; 2],
    /// (X2, Y2): end point.
    pub end: [f64; 2],
}

impl ConicArc {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(ConicArc {
            coefficients: d.reals("conic coefficient")?,
            z: d.real("ZT")?,
            start: d.reals("start point")?,
            end: d.reals("end point")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.reals(&self.coefficients);
        e.real(self.z);
        e.reals(&self.start);
        e.reals(&self.end);
    }
}

/// 110 line from `start` to `end` (form 0 segment, 1 ray, 2 infinite line); parameter
/// t ∈ [0, 1] maps to start + t (end − start).
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// (X1, Y1, Z1).
    pub start: [f64; 3],
    /// (X2, Y2, Z2).
    pub end: [f64; 3],
}

impl Line {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(Line {
            start: d.reals("start point")?,
            end: d.reals("end point")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.reals(&self.start);
        e.reals(&self.end);
    }
}

/// 112 parametric spline curve: N cubic segments; on segment i, with
/// s = t − T(i), x(t) = A + B s + C s² + D s³ (likewise y, z).
#[derive(Debug, Clone, PartialEq)]
pub struct SplineCurve {
    /// CTYPE: 1 linear, 2 quadratic, 3 cubic, 4 Wilson-Fowler, 5 modified Wilson-Fowler,
    /// 6 B-spline.
    pub spline_type: i64,
    /// H: degree of continuity with respect to arc length.
    pub continuity: i64,
    /// NDIM: 2 (planar) or 3.
    pub dimension: i64,
    /// T(1..N+1): break points.
    pub breakpoints: Vec<f64>,
    /// Per segment, `[x, y, z]` each `[A, B, C, D]`.
    pub segments: Vec<[[f64; 4]; 3]>,
    /// At the last break point, per axis: value, first derivative, second derivative / 2!,
    /// third derivative / 3!.
    pub terminal: [[f64; 4]; 3],
}

impl SplineCurve {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let spline_type = d.int("CTYPE")?;
        let continuity = d.int("H")?;
        let dimension = d.int("NDIM")?;
        let n = d.count("N (number of segments)", 13, 1)?;
        let breakpoints = d.real_vec(n + 1, "break point")?;
        let mut segments = Vec::with_capacity(n);
        for _ in 0..n {
            let mut s = [[0.0; 4]; 3];
            for axis in &mut s {
                *axis = d.reals("segment coefficient")?;
            }
            segments.push(s);
        }
        let mut terminal = [[0.0; 4]; 3];
        for axis in &mut terminal {
            *axis = d.reals("terminal point value")?;
        }
        Ok(SplineCurve {
            spline_type,
            continuity,
            dimension,
            breakpoints,
            segments,
            terminal,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) -> Result<(), EntityProblem> {
        if self.segments.is_empty() || self.breakpoints.len() != self.segments.len() + 1 {
            return Err(write_err(format!(
                "112 needs N ≥ 1 segments and N + 1 break points, has {} and {}",
                self.segments.len(),
                self.breakpoints.len()
            )));
        }
        e.int(self.spline_type);
        e.int(self.continuity);
        e.int(self.dimension);
        e.len(self.segments.len());
        e.reals(&self.breakpoints);
        for s in &self.segments {
            s.iter().for_each(|a| e.reals(a));
        }
        self.terminal.iter().for_each(|a| e.reals(a));
        Ok(())
    }
}

/// 126 rational B-spline curve of degree M with K + 1 control points:
/// C(t) = Σ wᵢ Pᵢ Nᵢ(t) / Σ wᵢ Nᵢ(t), t ∈ [V(0), V(1)].
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineCurve {
    /// M: degree.
    pub degree: usize,
    /// PROP1: planar.
    pub planar: bool,
    /// PROP2: closed.
    pub closed: bool,
    /// PROP3: polynomial (all weights equal).
    pub polynomial: bool,
    /// PROP4: periodic.
    pub periodic: bool,
    /// T(−M..N+M): K + M + 2 knots.
    pub knots: Vec<f64>,
    /// W(0..K).
    pub weights: Vec<f64>,
    /// (X, Y, Z)(0..K).
    pub control_points: Vec<[f64; 3]>,
    /// V(0), V(1): parameter range.
    pub range: [f64; 2],
    /// Unit normal of the plane when planar (optional in files).
    pub normal: Option<[f64; 3]>,
}

impl BSplineCurve {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let ik = d.index();
        let k = d.int("K (upper index of sum)")?;
        let im = d.index();
        let m = d.int("M (degree)")?;
        if m < 1 {
            return Err(EntityProblem::Count {
                index: im,
                name: "M (degree)",
                value: m,
                reason: "must be at least 1".into(),
            });
        }
        let props = [
            d.flag("PROP1")?,
            d.flag("PROP2")?,
            d.flag("PROP3")?,
            d.flag("PROP4")?,
        ];
        // K + M + 2 knots, K + 1 weights, 3 (K + 1) coordinates, 2 range values.
        let k = d.check_count(ik, "K (upper index of sum)", k, 1, 0, 0)?;
        let m = d.check_count(im, "M (degree)", m, 1, 1, 0)?;
        let need = (k as u128 + m as u128 + 2) + 4 * (k as u128 + 1) + 2;
        d.require(ik, "K (upper index of sum)", k as i64, need)?;
        let knots = d.real_vec(k + m + 2, "knot")?;
        let weights = d.real_vec(k + 1, "weight")?;
        let mut control_points = Vec::with_capacity(k + 1);
        for _ in 0..=k {
            control_points.push(d.reals("control point")?);
        }
        let range = d.reals("parameter range")?;
        let normal = if d.has_more() {
            Some(d.reals("unit normal")?)
        } else {
            None
        };
        Ok(BSplineCurve {
            degree: m,
            planar: props[0],
            closed: props[1],
            polynomial: props[2],
            periodic: props[3],
            knots,
            weights,
            control_points,
            range,
            normal,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) -> Result<(), EntityProblem> {
        let n = self.control_points.len();
        if n == 0
            || self.degree == 0
            || self.weights.len() != n
            || self.knots.len() != n + self.degree + 1
        {
            return Err(write_err(format!(
                "126 of degree {} with {} control points needs as many weights (has {}) and {} knots (has {})",
                self.degree,
                n,
                self.weights.len(),
                n + self.degree + 1,
                self.knots.len()
            )));
        }
        e.len(n - 1);
        e.len(self.degree);
        e.flag(self.planar);
        e.flag(self.closed);
        e.flag(self.polynomial);
        e.flag(self.periodic);
        e.reals(&self.knots);
        e.reals(&self.weights);
        self.control_points.iter().for_each(|p| e.reals(p));
        e.reals(&self.range);
        e.reals(&self.normal.unwrap_or([0.0; 3]));
        Ok(())
    }
}

/// 106 copious data: a list of points, read as a polyline through them. The form says
/// what the data is (1–3: a point set, 11–13: a piecewise linear curve, 63: a closed
/// planar curve; 20–40: drafting forms); `ip` says how the tuples are laid out.
#[derive(Debug, Clone, PartialEq)]
pub struct CopiousData {
    /// IP: 1 (x, y) pairs on the plane z = `z`, 2 (x, y, z) triples, 3 (x, y, z, i, j, k)
    /// sextuples (a point and a vector).
    pub ip: i64,
    /// ZT: the common z of IP = 1 (0 otherwise).
    pub z: f64,
    /// The points (for IP = 1, z is `z`).
    pub points: Vec<[f64; 3]>,
    /// The vectors of IP = 3 (empty otherwise).
    pub vectors: Vec<[f64; 3]>,
}

impl CopiousData {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let iip = d.index();
        let ip = d.int("IP (interpretation flag)")?;
        let per = match ip {
            1 => 2,
            2 => 3,
            3 => 6,
            v => {
                return Err(EntityProblem::Param {
                    index: iip,
                    expected: "1, 2 or 3 (IP)".into(),
                    found: v.to_string(),
                });
            }
        };
        let ino = d.index();
        let n = d.int("N (number of tuples)")?;
        let z = if ip == 1 { d.real("ZT")? } else { 0.0 };
        let n = d.check_count(ino, "N (number of tuples)", n, per, 0, 0)?;
        let mut points = Vec::with_capacity(n);
        let mut vectors = Vec::with_capacity(if ip == 3 { n } else { 0 });
        for _ in 0..n {
            match ip {
                1 => {
                    let [x, y] = d.reals("point")?;
                    points.push([x, y, z]);
                }
                2 => points.push(d.reals("point")?),
                _ => {
                    points.push(d.reals("point")?);
                    vectors.push(d.reals("vector")?);
                }
            }
        }
        Ok(CopiousData {
            ip,
            z,
            points,
            vectors,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) -> Result<(), EntityProblem> {
        if !(1..=3).contains(&self.ip) || (self.ip == 3 && self.vectors.len() != self.points.len())
        {
            return Err(write_err(format!(
                "106 with IP = {} needs IP 1, 2 or 3 (and one vector per point for 3), has {} points and {} vectors",
                self.ip,
                self.points.len(),
                self.vectors.len()
            )));
        }
        e.int(self.ip);
        e.len(self.points.len());
        if self.ip == 1 {
            e.real(self.z);
        }
        for (k, p) in self.points.iter().enumerate() {
            match self.ip {
                1 => e.reals(&p[..2]),
                2 => e.reals(p),
                _ => {
                    e.reals(p);
                    e.reals(&self.vectors[k]);
                }
            }
        }
        Ok(())
    }
}

/// 130 offset curve: the base curve offset in its plane, O(t) = C(t) + d(t) (C'(t) × V) /
/// |C'(t) × V|, for t between `range[0]` and `range[1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetCurve {
    /// BC: the base curve.
    pub base: DeId,
    /// FLAG: 1 constant distance `d1`, 2 varying linearly from `d1` at `td1` to `d2` at
    /// `td2`, 3 given by a coordinate of the curve `function`.
    pub flag: i64,
    /// BDDC: the curve whose coordinate gives the distance (FLAG = 3).
    pub function: Option<DeId>,
    /// NDIM: which coordinate of `function` (1 x, 2 y, 3 z).
    pub function_coordinate: i64,
    /// PF: the linear taper (FLAG = 2) is a function of 1 arc length, 2 parameter.
    pub taper: i64,
    /// D1: first offset distance.
    pub d1: f64,
    /// TD1: arc length or parameter of D1.
    pub td1: f64,
    /// D2: second offset distance.
    pub d2: f64,
    /// TD2: arc length or parameter of D2.
    pub td2: f64,
    /// (VX, VY, VZ): unit normal of the plane of the base curve.
    pub normal: [f64; 3],
    /// TT1, TT2: parameter range of the offset curve (on the base curve's parameter).
    pub range: [f64; 2],
}

impl OffsetCurve {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(OffsetCurve {
            base: d.ptr("base curve")?,
            flag: d.int("FLAG")?,
            function: d.opt_ptr("distance function curve")?,
            function_coordinate: d.int("NDIM")?,
            taper: d.int("PF")?,
            d1: d.real("D1")?,
            td1: d.real("TD1")?,
            d2: d.real("D2")?,
            td2: d.real("TD2")?,
            normal: d.reals("plane normal")?,
            range: d.reals("parameter range")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.base);
        e.int(self.flag);
        e.opt_ptr(self.function);
        e.int(self.function_coordinate);
        e.int(self.taper);
        e.reals(&[self.d1, self.td1, self.d2, self.td2]);
        e.reals(&self.normal);
        e.reals(&self.range);
    }
}
