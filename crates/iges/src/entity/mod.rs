//! Typed entities: one struct per supported entity type, decoded from and encoded to the
//! free-format parameter list.
//!
//! Pointers between entities are [`DeId`]s, validated against the directory when read.
//! Entities of other types are kept as [`Entity::Unknown`] with their raw parameters.

mod brep;
mod curve;
mod other;
mod solid;
mod surface;
mod trim;

pub use brep::{Edge, EdgeList, Face, Loop, LoopEdge, ManifoldSolid, Shell, VertexList};
pub use curve::{
    BSplineCurve, CircularArc, CompositeCurve, ConicArc, CopiousData, Line, OffsetCurve,
    SplineCurve,
};
pub use other::{ColorDefinition, Direction, Point, TransformationMatrix};
pub use solid::{
    ConicalSurface, CylindricalSurface, PlaneSurface, SphericalSurface, ToroidalSurface,
};
pub use surface::{
    BSplineSurface, OffsetSurface, Plane, RuledSurface, SplineSurface, SurfaceOfRevolution,
    TabulatedCylinder,
};
pub use trim::{Boundary, BoundaryCurve, BoundedSurface, CurveOnSurface, TrimmedSurface};

use crate::directory::DeId;
use crate::error::EntityProblem;
use crate::param::Param;

/// A decoded entity. The directory entry (type, form, transformation...) is kept beside it
/// in [`EntityRecord`](crate::EntityRecord).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Entity {
    /// 100 circular arc.
    CircularArc(CircularArc),
    /// 102 composite curve.
    CompositeCurve(CompositeCurve),
    /// 104 conic arc.
    ConicArc(ConicArc),
    /// 106 copious data (point sets, polylines).
    CopiousData(CopiousData),
    /// 108 plane.
    Plane(Plane),
    /// 110 line.
    Line(Line),
    /// 112 parametric spline curve.
    SplineCurve(SplineCurve),
    /// 114 parametric spline surface.
    SplineSurface(SplineSurface),
    /// 116 point.
    Point(Point),
    /// 118 ruled surface.
    RuledSurface(RuledSurface),
    /// 120 surface of revolution.
    SurfaceOfRevolution(SurfaceOfRevolution),
    /// 122 tabulated cylinder.
    TabulatedCylinder(TabulatedCylinder),
    /// 123 direction.
    Direction(Direction),
    /// 124 transformation matrix.
    TransformationMatrix(TransformationMatrix),
    /// 126 rational B-spline curve.
    BSplineCurve(BSplineCurve),
    /// 128 rational B-spline surface.
    BSplineSurface(BSplineSurface),
    /// 130 offset curve.
    OffsetCurve(OffsetCurve),
    /// 140 offset surface.
    OffsetSurface(OffsetSurface),
    /// 141 boundary.
    Boundary(Boundary),
    /// 142 curve on a parametric surface.
    CurveOnSurface(CurveOnSurface),
    /// 143 bounded surface.
    BoundedSurface(BoundedSurface),
    /// 144 trimmed (parametric) surface.
    TrimmedSurface(TrimmedSurface),
    /// 186 manifold solid B-rep object.
    ManifoldSolid(ManifoldSolid),
    /// 190 plane surface.
    PlaneSurface(PlaneSurface),
    /// 192 right circular cylindrical surface.
    CylindricalSurface(CylindricalSurface),
    /// 194 right circular conical surface.
    ConicalSurface(ConicalSurface),
    /// 196 spherical surface.
    SphericalSurface(SphericalSurface),
    /// 198 toroidal surface.
    ToroidalSurface(ToroidalSurface),
    /// 314 colour definition.
    ColorDefinition(ColorDefinition),
    /// 502 vertex list.
    VertexList(VertexList),
    /// 504 edge list.
    EdgeList(EdgeList),
    /// 508 loop.
    Loop(Loop),
    /// 510 face.
    Face(Face),
    /// 514 shell.
    Shell(Shell),
    /// Any other entity type: its parameters after the type number, unparsed.
    Unknown(Vec<Param>),
}

/// The entity types decoded into typed structs.
pub const SUPPORTED_TYPES: [i32; 34] = [
    100, 102, 104, 106, 108, 110, 112, 114, 116, 118, 120, 122, 123, 124, 126, 128, 130, 140, 141,
    142, 143, 144, 186, 190, 192, 194, 196, 198, 314, 502, 504, 508, 510, 514,
];

impl Entity {
    /// Decodes the parameters (`params[0]` is the entity type number) of an entity of the
    /// given type and form. Returns the entity and the parameters left over after it
    /// (associativity and property pointers).
    pub(crate) fn decode(
        entity_type: i32,
        form: i32,
        params: &[Param],
        n_entities: usize,
    ) -> Result<(Entity, Vec<Param>), EntityProblem> {
        let mut d = Dec {
            p: params,
            i: 1,
            n: n_entities,
        };
        let e = match entity_type {
            100 => Entity::CircularArc(CircularArc::decode(&mut d)?),
            102 => Entity::CompositeCurve(CompositeCurve::decode(&mut d)?),
            104 => Entity::ConicArc(ConicArc::decode(&mut d)?),
            106 => Entity::CopiousData(CopiousData::decode(&mut d)?),
            108 => Entity::Plane(Plane::decode(&mut d)?),
            110 => Entity::Line(Line::decode(&mut d)?),
            112 => Entity::SplineCurve(SplineCurve::decode(&mut d)?),
            114 => Entity::SplineSurface(SplineSurface::decode(&mut d)?),
            116 => Entity::Point(Point::decode(&mut d)?),
            118 => Entity::RuledSurface(RuledSurface::decode(&mut d)?),
            120 => Entity::SurfaceOfRevolution(SurfaceOfRevolution::decode(&mut d)?),
            122 => Entity::TabulatedCylinder(TabulatedCylinder::decode(&mut d)?),
            123 => Entity::Direction(Direction::decode(&mut d)?),
            124 => Entity::TransformationMatrix(TransformationMatrix::decode(&mut d)?),
            126 => Entity::BSplineCurve(BSplineCurve::decode(&mut d)?),
            128 => Entity::BSplineSurface(BSplineSurface::decode(&mut d)?),
            130 => Entity::OffsetCurve(OffsetCurve::decode(&mut d)?),
            140 => Entity::OffsetSurface(OffsetSurface::decode(&mut d)?),
            141 => Entity::Boundary(Boundary::decode(&mut d)?),
            142 => Entity::CurveOnSurface(CurveOnSurface::decode(&mut d)?),
            143 => Entity::BoundedSurface(BoundedSurface::decode(&mut d)?),
            144 => Entity::TrimmedSurface(TrimmedSurface::decode(&mut d)?),
            186 => Entity::ManifoldSolid(ManifoldSolid::decode(&mut d)?),
            190 => Entity::PlaneSurface(PlaneSurface::decode(&mut d, form)?),
            192 => Entity::CylindricalSurface(CylindricalSurface::decode(&mut d, form)?),
            194 => Entity::ConicalSurface(ConicalSurface::decode(&mut d, form)?),
            196 => Entity::SphericalSurface(SphericalSurface::decode(&mut d, form)?),
            198 => Entity::ToroidalSurface(ToroidalSurface::decode(&mut d, form)?),
            314 => Entity::ColorDefinition(ColorDefinition::decode(&mut d)?),
            502 => Entity::VertexList(VertexList::decode(&mut d)?),
            504 => Entity::EdgeList(EdgeList::decode(&mut d)?),
            508 => Entity::Loop(Loop::decode(&mut d)?),
            510 => Entity::Face(Face::decode(&mut d)?),
            514 => Entity::Shell(Shell::decode(&mut d)?),
            _ => {
                return Ok((
                    Entity::Unknown(params.get(1..).unwrap_or(&[]).to_vec()),
                    Vec::new(),
                ));
            }
        };
        Ok((e, d.rest()))
    }

    /// Encodes the entity's own parameters (without the type number).
    pub(crate) fn encode(&self) -> Result<Vec<Param>, EntityProblem> {
        let mut e = Enc(Vec::new());
        match self {
            Entity::CircularArc(x) => x.encode(&mut e),
            Entity::CompositeCurve(x) => x.encode(&mut e),
            Entity::ConicArc(x) => x.encode(&mut e),
            Entity::CopiousData(x) => x.encode(&mut e)?,
            Entity::Plane(x) => x.encode(&mut e),
            Entity::Line(x) => x.encode(&mut e),
            Entity::SplineCurve(x) => x.encode(&mut e)?,
            Entity::SplineSurface(x) => x.encode(&mut e)?,
            Entity::Point(x) => x.encode(&mut e),
            Entity::RuledSurface(x) => x.encode(&mut e),
            Entity::SurfaceOfRevolution(x) => x.encode(&mut e),
            Entity::TabulatedCylinder(x) => x.encode(&mut e),
            Entity::Direction(x) => x.encode(&mut e),
            Entity::TransformationMatrix(x) => x.encode(&mut e),
            Entity::BSplineCurve(x) => x.encode(&mut e)?,
            Entity::BSplineSurface(x) => x.encode(&mut e)?,
            Entity::OffsetCurve(x) => x.encode(&mut e),
            Entity::OffsetSurface(x) => x.encode(&mut e),
            Entity::Boundary(x) => x.encode(&mut e),
            Entity::CurveOnSurface(x) => x.encode(&mut e),
            Entity::BoundedSurface(x) => x.encode(&mut e),
            Entity::TrimmedSurface(x) => x.encode(&mut e),
            Entity::ManifoldSolid(x) => x.encode(&mut e),
            Entity::PlaneSurface(x) => x.encode(&mut e),
            Entity::CylindricalSurface(x) => x.encode(&mut e),
            Entity::ConicalSurface(x) => x.encode(&mut e),
            Entity::SphericalSurface(x) => x.encode(&mut e),
            Entity::ToroidalSurface(x) => x.encode(&mut e),
            Entity::ColorDefinition(x) => x.encode(&mut e)?,
            Entity::VertexList(x) => x.encode(&mut e),
            Entity::EdgeList(x) => x.encode(&mut e),
            Entity::Loop(x) => x.encode(&mut e),
            Entity::Face(x) => x.encode(&mut e),
            Entity::Shell(x) => x.encode(&mut e),
            Entity::Unknown(p) => e.0.extend(p.iter().cloned()),
        }
        Ok(e.0)
    }

    /// The IGES type number of a typed entity (`None` for [`Entity::Unknown`], whose type
    /// is only in its directory entry).
    pub fn type_number(&self) -> Option<i32> {
        Some(match self {
            Entity::CircularArc(_) => 100,
            Entity::CompositeCurve(_) => 102,
            Entity::ConicArc(_) => 104,
            Entity::CopiousData(_) => 106,
            Entity::Plane(_) => 108,
            Entity::Line(_) => 110,
            Entity::SplineCurve(_) => 112,
            Entity::SplineSurface(_) => 114,
            Entity::Point(_) => 116,
            Entity::RuledSurface(_) => 118,
            Entity::SurfaceOfRevolution(_) => 120,
            Entity::TabulatedCylinder(_) => 122,
            Entity::Direction(_) => 123,
            Entity::TransformationMatrix(_) => 124,
            Entity::BSplineCurve(_) => 126,
            Entity::BSplineSurface(_) => 128,
            Entity::OffsetCurve(_) => 130,
            Entity::OffsetSurface(_) => 140,
            Entity::Boundary(_) => 141,
            Entity::CurveOnSurface(_) => 142,
            Entity::BoundedSurface(_) => 143,
            Entity::TrimmedSurface(_) => 144,
            Entity::ManifoldSolid(_) => 186,
            Entity::PlaneSurface(_) => 190,
            Entity::CylindricalSurface(_) => 192,
            Entity::ConicalSurface(_) => 194,
            Entity::SphericalSurface(_) => 196,
            Entity::ToroidalSurface(_) => 198,
            Entity::ColorDefinition(_) => 314,
            Entity::VertexList(_) => 502,
            Entity::EdgeList(_) => 504,
            Entity::Loop(_) => 508,
            Entity::Face(_) => 510,
            Entity::Shell(_) => 514,
            Entity::Unknown(_) => return None,
        })
    }

    /// Every pointer to another entity held in the parameters, in parameter order (used to
    /// check references when writing).
    pub fn pointers(&self) -> Vec<DeId> {
        let mut out = Vec::new();
        let mut push = |p: DeId| out.push(p);
        match self {
            Entity::CompositeCurve(x) => x.curves.iter().copied().for_each(&mut push),
            Entity::Point(x) => x.symbol.into_iter().for_each(&mut push),
            Entity::RuledSurface(x) => [x.curve1, x.curve2].into_iter().for_each(&mut push),
            Entity::SurfaceOfRevolution(x) => {
                [x.axis, x.generatrix].into_iter().for_each(&mut push)
            }
            Entity::TabulatedCylinder(x) => push(x.directrix),
            Entity::Plane(x) => x.boundary.into_iter().for_each(&mut push),
            Entity::OffsetCurve(x) => {
                push(x.base);
                x.function.into_iter().for_each(&mut push);
            }
            Entity::OffsetSurface(x) => push(x.surface),
            Entity::PlaneSurface(x) => {
                [x.location, x.normal].into_iter().for_each(&mut push);
                x.refdir.into_iter().for_each(&mut push);
            }
            Entity::CylindricalSurface(x) => {
                [x.location, x.axis].into_iter().for_each(&mut push);
                x.refdir.into_iter().for_each(&mut push);
            }
            Entity::ConicalSurface(x) => {
                [x.location, x.axis].into_iter().for_each(&mut push);
                x.refdir.into_iter().for_each(&mut push);
            }
            Entity::SphericalSurface(x) => {
                push(x.center);
                x.axis.into_iter().for_each(&mut push);
                x.refdir.into_iter().for_each(&mut push);
            }
            Entity::ToroidalSurface(x) => {
                [x.center, x.axis].into_iter().for_each(&mut push);
                x.refdir.into_iter().for_each(&mut push);
            }
            Entity::Boundary(x) => {
                push(x.surface);
                for c in &x.curves {
                    push(c.model_curve);
                    c.param_curves.iter().copied().for_each(&mut push);
                }
            }
            Entity::CurveOnSurface(x) => {
                push(x.surface);
                x.param_curve.into_iter().for_each(&mut push);
                x.model_curve.into_iter().for_each(&mut push);
            }
            Entity::BoundedSurface(x) => {
                push(x.surface);
                x.boundaries.iter().copied().for_each(&mut push);
            }
            Entity::TrimmedSurface(x) => {
                push(x.surface);
                x.outer.into_iter().for_each(&mut push);
                x.inner.iter().copied().for_each(&mut push);
            }
            Entity::ManifoldSolid(x) => {
                push(x.shell);
                x.voids.iter().for_each(|v| push(v.0));
            }
            Entity::EdgeList(x) => x.edges.iter().for_each(|e| {
                push(e.curve);
                push(e.start_list);
                push(e.end_list);
            }),
            Entity::Loop(x) => x.edges.iter().for_each(|e| {
                push(e.list);
                e.param_curves.iter().for_each(|c| push(c.1));
            }),
            Entity::Face(x) => {
                push(x.surface);
                x.loops.iter().copied().for_each(&mut push);
            }
            Entity::Shell(x) => x.faces.iter().for_each(|f| push(f.0)),
            _ => {}
        }
        out
    }
}

/// Sequential reader of an entity's parameters with error reporting by index.
pub(crate) struct Dec<'a> {
    p: &'a [Param],
    /// Index of the next parameter (`p[0]` is the entity type number).
    i: usize,
    /// Number of entities in the directory, for pointer validation.
    n: usize,
}

impl Dec<'_> {
    fn remaining(&self) -> usize {
        self.p.len().saturating_sub(self.i)
    }

    fn next(&mut self, what: &str) -> Result<(usize, &Param), EntityProblem> {
        let i = self.i;
        match self.p.get(i) {
            Some(p) => {
                self.i += 1;
                Ok((i, p))
            }
            None => Err(EntityProblem::Missing {
                index: i,
                what: what.to_string(),
                available: self.p.len().saturating_sub(1),
            }),
        }
    }

    fn wrong(index: usize, expected: &str, p: &Param) -> EntityProblem {
        EntityProblem::Param {
            index,
            expected: expected.to_string(),
            found: p.describe(),
        }
    }

    /// An integer; empty reads as 0; a real with an integral value is accepted.
    pub(crate) fn int(&mut self, what: &str) -> Result<i64, EntityProblem> {
        let (i, p) = self.next(what)?;
        match *p {
            Param::Empty => Ok(0),
            Param::Int(v) => Ok(v),
            Param::Real(x) if x.fract() == 0.0 && x.abs() < 9.0e15 => Ok(x as i64),
            ref p => Err(Self::wrong(i, &format!("an integer ({what})"), p)),
        }
    }

    /// A flag that must be 0 or 1 (empty reads as 0).
    pub(crate) fn flag(&mut self, what: &str) -> Result<bool, EntityProblem> {
        let i = self.i;
        match self.int(what)? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(EntityProblem::Param {
                index: i,
                expected: format!("0 or 1 ({what})"),
                found: v.to_string(),
            }),
        }
    }

    /// A real; empty reads as 0; integers are accepted.
    pub(crate) fn real(&mut self, what: &str) -> Result<f64, EntityProblem> {
        let (i, p) = self.next(what)?;
        match *p {
            Param::Empty => Ok(0.0),
            Param::Int(v) => Ok(v as f64),
            Param::Real(x) => Ok(x),
            ref p => Err(Self::wrong(i, &format!("a real ({what})"), p)),
        }
    }

    /// `N` reals.
    pub(crate) fn reals<const N: usize>(&mut self, what: &str) -> Result<[f64; N], EntityProblem> {
        let mut out = [0.0; N];
        for x in &mut out {
            *x = self.real(what)?;
        }
        Ok(out)
    }

    /// A vector of `n` reals (the count must have been checked with [`Dec::count`]).
    pub(crate) fn real_vec(&mut self, n: usize, what: &str) -> Result<Vec<f64>, EntityProblem> {
        (0..n).map(|_| self.real(what)).collect()
    }

    /// A pointer that may be null (0 or empty).
    pub(crate) fn opt_ptr(&mut self, what: &str) -> Result<Option<DeId>, EntityProblem> {
        let i = self.i;
        let v = self.int(what)?;
        if v == 0 {
            return Ok(None);
        }
        DeId::from_pointer(v, self.n)
            .map(Some)
            .ok_or_else(|| EntityProblem::Pointer {
                index: i,
                pointer: v,
                reason: format!(
                    "({what}) does not name a directory entry (odd numbers 1..{})",
                    2 * self.n.max(1) - 1
                ),
            })
    }

    /// A pointer that must not be null.
    pub(crate) fn ptr(&mut self, what: &str) -> Result<DeId, EntityProblem> {
        let i = self.i;
        self.opt_ptr(what)?.ok_or_else(|| EntityProblem::Pointer {
            index: i,
            pointer: 0,
            reason: format!("({what}) is null but required"),
        })
    }

    /// A count of items that each take `per_item` parameters; rejects negative counts and
    /// counts larger than the parameters left (so that corrupt files cannot request huge
    /// allocations). `min` is the smallest valid value.
    pub(crate) fn count(
        &mut self,
        name: &'static str,
        per_item: usize,
        min: i64,
    ) -> Result<usize, EntityProblem> {
        let i = self.i;
        let v = self.int(name)?;
        self.check_count(i, name, v, per_item, min, 0)
    }

    /// Validates a count `v` read at index `i`; `offset` items are implied beyond `v`
    /// (e.g. K + 1 control points for an upper index K).
    pub(crate) fn check_count(
        &self,
        i: usize,
        name: &'static str,
        v: i64,
        per_item: usize,
        min: i64,
        offset: i64,
    ) -> Result<usize, EntityProblem> {
        if v < min {
            return Err(EntityProblem::Count {
                index: i,
                name,
                value: v,
                reason: format!("must be at least {min}"),
            });
        }
        let items = v.checked_add(offset).unwrap_or(i64::MAX) as u128;
        self.require(i, name, v, items * per_item as u128)?;
        Ok(v as usize)
    }

    /// Checks that at least `need` parameters remain, blaming the count `name = value` read
    /// at index `i` otherwise.
    pub(crate) fn require(
        &self,
        i: usize,
        name: &'static str,
        value: i64,
        need: u128,
    ) -> Result<(), EntityProblem> {
        if need > self.remaining() as u128 {
            return Err(EntityProblem::Count {
                index: i,
                name,
                value,
                reason: format!(
                    "needs {need} more parameters, only {} remain",
                    self.remaining()
                ),
            });
        }
        Ok(())
    }

    /// A string; empty reads as `None`.
    pub(crate) fn opt_string(&mut self, what: &str) -> Result<Option<String>, EntityProblem> {
        if self.remaining() == 0 {
            return Ok(None);
        }
        let (i, p) = self.next(what)?;
        match p {
            Param::Empty => Ok(None),
            Param::Str(s) => Ok(Some(s.clone())),
            p => Err(Self::wrong(i, &format!("a string ({what})"), p)),
        }
    }

    /// Whether any parameters are left.
    pub(crate) fn has_more(&self) -> bool {
        self.remaining() > 0
    }

    /// The current 1-based parameter index.
    pub(crate) fn index(&self) -> usize {
        self.i
    }

    /// Skips `n` parameters (those present).
    pub(crate) fn skip(&mut self, n: usize) {
        self.i = (self.i + n).min(self.p.len());
    }

    fn rest(self) -> Vec<Param> {
        self.p.get(self.i..).unwrap_or(&[]).to_vec()
    }
}

/// Parameter list under construction.
pub(crate) struct Enc(pub(crate) Vec<Param>);

impl Enc {
    pub(crate) fn int(&mut self, v: i64) {
        self.0.push(Param::Int(v));
    }
    pub(crate) fn flag(&mut self, v: bool) {
        self.0.push(Param::Int(v as i64));
    }
    pub(crate) fn real(&mut self, v: f64) {
        self.0.push(Param::Real(v));
    }
    pub(crate) fn reals(&mut self, v: &[f64]) {
        self.0.extend(v.iter().map(|&x| Param::Real(x)));
    }
    pub(crate) fn ptr(&mut self, v: DeId) {
        self.0.push(Param::Int(v.line() as i64));
    }
    pub(crate) fn opt_ptr(&mut self, v: Option<DeId>) {
        self.0.push(Param::Int(v.map_or(0, |p| p.line() as i64)));
    }
    pub(crate) fn len(&mut self, n: usize) {
        self.0.push(Param::Int(n as i64));
    }
}

/// An encoding error.
pub(crate) fn write_err(reason: impl Into<String>) -> EntityProblem {
    EntityProblem::Write {
        reason: reason.into(),
    }
}
