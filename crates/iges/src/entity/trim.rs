//! Trimming entities: 141 boundary, 142 curve on a parametric surface, 143 bounded
//! surface, 144 trimmed surface.

use super::{Dec, Enc};
use crate::directory::DeId;
use crate::error::EntityProblem;

/// One curve of a 141 boundary.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundaryCurve {
    /// CRVPT: the model-space curve.
    pub model_curve: DeId,
    /// SENSE 2: the curve runs against the boundary's direction (SENSE 1: with it).
    pub reversed: bool,
    /// PSCPT(1..K): its parameter-space curves.
    pub param_curves: Vec<DeId>,
}

/// 141 boundary: a closed loop of model-space curves (and their parameter-space images)
/// on a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Boundary {
    /// TYPE: 0 model-space curves only, 1 both model and parameter space.
    pub kind: i64,
    /// PREF: preferred representation (0 unspecified, 1 model, 2 parameter, 3 equal).
    pub preferred: i64,
    /// SPTR: the untrimmed surface.
    pub surface: DeId,
    /// The curves, in loop order.
    pub curves: Vec<BoundaryCurve>,
}

impl Boundary {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let kind = d.int("TYPE")?;
        let preferred = d.int("PREF")?;
        let surface = d.ptr("surface")?;
        let n = d.count("N (number of curves)", 3, 0)?;
        let mut curves = Vec::with_capacity(n);
        for _ in 0..n {
            let model_curve = d.ptr("model space curve")?;
            let is = d.index();
            let sense = d.int("SENSE")?;
            let reversed = match sense {
                1 => false,
                2 => true,
                v => {
                    return Err(EntityProblem::Param {
                        index: is,
                        expected: "1 or 2 (SENSE)".into(),
                        found: v.to_string(),
                    });
                }
            };
            let k = d.count("K (number of parameter space curves)", 1, 0)?;
            let param_curves = (0..k)
                .map(|_| d.ptr("parameter space curve"))
                .collect::<Result<_, _>>()?;
            curves.push(BoundaryCurve {
                model_curve,
                reversed,
                param_curves,
            });
        }
        Ok(Boundary {
            kind,
            preferred,
            surface,
            curves,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.int(self.kind);
        e.int(self.preferred);
        e.ptr(self.surface);
        e.len(self.curves.len());
        for c in &self.curves {
            e.ptr(c.model_curve);
            e.int(if c.reversed { 2 } else { 1 });
            e.len(c.param_curves.len());
            c.param_curves.iter().for_each(|&p| e.ptr(p));
        }
    }
}

/// 142 curve on a parametric surface: the same curve as a parameter-space curve B(t)
/// (x, y of its points are the surface's (u, v)) and as a model-space curve C(t).
#[derive(Debug, Clone, PartialEq)]
pub struct CurveOnSurface {
    /// CRTN: how created (0 unspecified, 1 projection, 2 intersection, 3 isoparametric).
    pub creation: i64,
    /// SPTR: the surface.
    pub surface: DeId,
    /// BPTR: the parameter-space curve (may be absent).
    pub param_curve: Option<DeId>,
    /// CPTR: the model-space curve (may be absent).
    pub model_curve: Option<DeId>,
    /// PREF: preferred representation (0 unspecified, 1 S∘B, 2 C, 3 equal).
    pub preferred: i64,
}

impl CurveOnSurface {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(CurveOnSurface {
            creation: d.int("CRTN")?,
            surface: d.ptr("surface")?,
            param_curve: d.opt_ptr("parameter space curve")?,
            model_curve: d.opt_ptr("model space curve")?,
            preferred: d.int("PREF")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.int(self.creation);
        e.ptr(self.surface);
        e.opt_ptr(self.param_curve);
        e.opt_ptr(self.model_curve);
        e.int(self.preferred);
    }
}

/// 143 bounded surface: a surface and its 141 boundaries.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundedSurface {
    /// TYPE: 0 model-space boundaries only, 1 both representations.
    pub kind: i64,
    /// SPTR: the untrimmed surface.
    pub surface: DeId,
    /// BDPT(1..N): the 141 boundaries.
    pub boundaries: Vec<DeId>,
}

impl BoundedSurface {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let kind = d.int("TYPE")?;
        let surface = d.ptr("surface")?;
        let n = d.count("N (number of boundaries)", 1, 0)?;
        let boundaries = (0..n)
            .map(|_| d.ptr("boundary"))
            .collect::<Result<_, _>>()?;
        Ok(BoundedSurface {
            kind,
            surface,
            boundaries,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.int(self.kind);
        e.ptr(self.surface);
        e.len(self.boundaries.len());
        self.boundaries.iter().for_each(|&b| e.ptr(b));
    }
}

/// 144 trimmed surface: a surface, an outer boundary and inner boundaries (holes), each a
/// 142 curve on the surface.
#[derive(Debug, Clone, PartialEq)]
pub struct TrimmedSurface {
    /// PTS: the untrimmed surface.
    pub surface: DeId,
    /// PTO: the outer boundary; `None` (N1 = 0) when it is the boundary of the surface's
    /// parameter domain.
    pub outer: Option<DeId>,
    /// PTI(1..N2): the inner boundaries.
    pub inner: Vec<DeId>,
}

impl TrimmedSurface {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let surface = d.ptr("surface")?;
        let n1 = d.flag("N1")?;
        let n2 = d.count("N2 (number of inner boundaries)", 1, 0)?;
        let pto = d.opt_ptr("outer boundary")?;
        let outer = if n1 { pto } else { None };
        let inner = (0..n2)
            .map(|_| d.ptr("inner boundary"))
            .collect::<Result<_, _>>()?;
        Ok(TrimmedSurface {
            surface,
            outer,
            inner,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.surface);
        e.flag(self.outer.is_some());
        e.len(self.inner.len());
        e.opt_ptr(self.outer);
        self.inner.iter().for_each(|&b| e.ptr(b));
    }
}
