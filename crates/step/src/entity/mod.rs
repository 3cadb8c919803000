//! Typed entities: one struct per supported entity type, decoded from an instance's
//! records. References stay [`Id`]s; [`StepFile`](crate::StepFile) checks that they name
//! instances and offers type-checked lookups.

mod dec;
mod geometry;
mod surface;
mod topology;
mod units;

pub use geometry::{
    Axis1Placement, Axis2Placement, BSplineCurve, CartesianPoint, CompositeCurve,
    CompositeCurveSegment, Conic, ConicKind, Direction, Line, OffsetCurve3d, Pcurve, Polyline,
    SurfaceCurve, Trim, TrimmedCurve, Vector,
};
pub use surface::{
    BSplineSurface, ElementaryKind, ElementarySurface, OffsetSurface, RectangularTrimmedSurface,
    SurfaceOfLinearExtrusion, SurfaceOfRevolution,
};
pub use topology::{
    EdgeCurve, EdgeLoop, Face, FaceBound, ManifoldSolidBrep, OrientedEdge, OrientedShell, Shell,
    ShellBasedSurfaceModel, VertexLoop, VertexPoint,
};
pub use units::{
    Context, MeasureWithUnit, NamedUnit, PlacedRepresentation, Representation, UnitDefinition,
    UnitKind, si_prefix,
};

use dec::Dec;

use crate::error::EntityProblem;
use crate::value::{Id, Instance};

/// A decoded instance.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Entity {
    /// `CARTESIAN_POINT`.
    CartesianPoint(CartesianPoint),
    /// `DIRECTION`.
    Direction(Direction),
    /// `VECTOR`.
    Vector(Vector),
    /// `AXIS1_PLACEMENT`.
    Axis1Placement(Axis1Placement),
    /// `AXIS2_PLACEMENT_2D` / `AXIS2_PLACEMENT_3D`.
    Axis2Placement(Axis2Placement),
    /// `LINE`.
    Line(Line),
    /// `CIRCLE`, `ELLIPSE`, `HYPERBOLA`, `PARABOLA`.
    Conic(Conic),
    /// `POLYLINE`.
    Polyline(Polyline),
    /// `B_SPLINE_CURVE_WITH_KNOTS` (and its rational complex form).
    BSplineCurve(BSplineCurve),
    /// `TRIMMED_CURVE`.
    TrimmedCurve(TrimmedCurve),
    /// `PCURVE`.
    Pcurve(Pcurve),
    /// `SURFACE_CURVE`, `SEAM_CURVE`, `INTERSECTION_CURVE`.
    SurfaceCurve(SurfaceCurve),
    /// `COMPOSITE_CURVE`.
    CompositeCurve(CompositeCurve),
    /// `COMPOSITE_CURVE_SEGMENT`.
    CompositeCurveSegment(CompositeCurveSegment),
    /// `OFFSET_CURVE_3D`.
    OffsetCurve3d(OffsetCurve3d),
    /// `PLANE`, `CYLINDRICAL_SURFACE`, `CONICAL_SURFACE`, `SPHERICAL_SURFACE`,
    /// `TOROIDAL_SURFACE`.
    Elementary(ElementarySurface),
    /// `B_SPLINE_SURFACE_WITH_KNOTS` (and its rational complex form).
    BSplineSurface(BSplineSurface),
    /// `SURFACE_OF_REVOLUTION`.
    SurfaceOfRevolution(SurfaceOfRevolution),
    /// `SURFACE_OF_LINEAR_EXTRUSION`.
    SurfaceOfLinearExtrusion(SurfaceOfLinearExtrusion),
    /// `OFFSET_SURFACE`.
    OffsetSurface(OffsetSurface),
    /// `RECTANGULAR_TRIMMED_SURFACE`.
    RectangularTrimmedSurface(RectangularTrimmedSurface),
    /// `VERTEX_POINT`.
    VertexPoint(VertexPoint),
    /// `EDGE_CURVE`.
    EdgeCurve(EdgeCurve),
    /// `ORIENTED_EDGE`.
    OrientedEdge(OrientedEdge),
    /// `EDGE_LOOP`.
    EdgeLoop(EdgeLoop),
    /// `VERTEX_LOOP`.
    VertexLoop(VertexLoop),
    /// `FACE_BOUND`, `FACE_OUTER_BOUND`.
    FaceBound(FaceBound),
    /// `ADVANCED_FACE`, `FACE_SURFACE`.
    Face(Face),
    /// `CLOSED_SHELL`, `OPEN_SHELL`.
    Shell(Shell),
    /// `ORIENTED_CLOSED_SHELL`, `ORIENTED_OPEN_SHELL`.
    OrientedShell(OrientedShell),
    /// `MANIFOLD_SOLID_BREP`, `BREP_WITH_VOIDS`.
    ManifoldSolidBrep(ManifoldSolidBrep),
    /// `SHELL_BASED_SURFACE_MODEL`.
    ShellBasedSurfaceModel(ShellBasedSurfaceModel),
    /// `…REPRESENTATION(name, items, context)`.
    Representation(Representation),
    /// A representation context (with its units).
    Context(Context),
    /// `SI_UNIT` or a complex named unit.
    NamedUnit(NamedUnit),
    /// `…MEASURE_WITH_UNIT`.
    MeasureWithUnit(MeasureWithUnit),
    /// An assembly placement (a representation relationship with a transformation).
    PlacedRepresentation(PlacedRepresentation),
    /// Any other type (products, styles, …): kept only as the raw [`Instance`].
    Other,
}

/// The simple entity types decoded into typed structs (complex instances are decoded when
/// they hold a B-spline, a unit, a context or a placed representation).
pub const SUPPORTED_TYPES: [&str; 45] = [
    "ADVANCED_BREP_SHAPE_REPRESENTATION",
    "ADVANCED_FACE",
    "AXIS1_PLACEMENT",
    "AXIS2_PLACEMENT_2D",
    "AXIS2_PLACEMENT_3D",
    "B_SPLINE_CURVE_WITH_KNOTS",
    "B_SPLINE_SURFACE_WITH_KNOTS",
    "BREP_WITH_VOIDS",
    "CARTESIAN_POINT",
    "CIRCLE",
    "CLOSED_SHELL",
    "COMPOSITE_CURVE",
    "COMPOSITE_CURVE_SEGMENT",
    "CONICAL_SURFACE",
    "CYLINDRICAL_SURFACE",
    "DEFINITIONAL_REPRESENTATION",
    "DIRECTION",
    "EDGE_CURVE",
    "EDGE_LOOP",
    "ELLIPSE",
    "FACE_BOUND",
    "FACE_OUTER_BOUND",
    "FACE_SURFACE",
    "HYPERBOLA",
    "LINE",
    "MANIFOLD_SOLID_BREP",
    "MANIFOLD_SURFACE_SHAPE_REPRESENTATION",
    "OFFSET_CURVE_3D",
    "OFFSET_SURFACE",
    "OPEN_SHELL",
    "ORIENTED_CLOSED_SHELL",
    "ORIENTED_EDGE",
    "PARABOLA",
    "PCURVE",
    "PLANE",
    "POLYLINE",
    "SEAM_CURVE",
    "SHELL_BASED_SURFACE_MODEL",
    "SPHERICAL_SURFACE",
    "SURFACE_CURVE",
    "SURFACE_OF_LINEAR_EXTRUSION",
    "SURFACE_OF_REVOLUTION",
    "TOROIDAL_SURFACE",
    "TRIMMED_CURVE",
    "VERTEX_POINT",
];

fn simple(inst: &Instance, arity: usize) -> Result<Dec<'_>, EntityProblem> {
    let mut d = Dec::new(&inst.records[0], arity, false)?;
    d.skip(1); // the name inherited from representation_item / topological_representation_item
    Ok(d)
}

impl Entity {
    /// Decodes an instance (simple or complex).
    pub(crate) fn decode(inst: &Instance) -> Result<Entity, EntityProblem> {
        if inst.is_complex() {
            return Self::decode_complex(inst);
        }
        let name = inst.records[0].name.as_str();
        Ok(match name {
            "CARTESIAN_POINT" => Entity::CartesianPoint(CartesianPoint {
                coordinates: simple(inst, 2)?.reals("coordinates")?,
            }),
            "DIRECTION" => Entity::Direction(Direction {
                ratios: simple(inst, 2)?.reals("direction_ratios")?,
            }),
            "VECTOR" => {
                let mut d = simple(inst, 3)?;
                Entity::Vector(Vector {
                    orientation: d.id("orientation")?,
                    magnitude: d.real("magnitude")?,
                })
            }
            "AXIS1_PLACEMENT" => {
                let mut d = simple(inst, 3)?;
                Entity::Axis1Placement(Axis1Placement {
                    location: d.id("location")?,
                    axis: d.opt_id("axis")?,
                })
            }
            "AXIS2_PLACEMENT_2D" => Entity::Axis2Placement(Axis2Placement::decode(inst, true)?),
            "AXIS2_PLACEMENT_3D" => Entity::Axis2Placement(Axis2Placement::decode(inst, false)?),
            "LINE" => {
                let mut d = simple(inst, 3)?;
                Entity::Line(Line {
                    point: d.id("pnt")?,
                    direction: d.id("dir")?,
                })
            }
            "CIRCLE" => Entity::Conic(Conic::decode(inst, ConicKind::Circle)?),
            "ELLIPSE" => Entity::Conic(Conic::decode(inst, ConicKind::Ellipse)?),
            "HYPERBOLA" => Entity::Conic(Conic::decode(inst, ConicKind::Hyperbola)?),
            "PARABOLA" => Entity::Conic(Conic::decode(inst, ConicKind::Parabola)?),
            "POLYLINE" => Entity::Polyline(Polyline {
                points: simple(inst, 2)?.ids("points")?,
            }),
            "B_SPLINE_CURVE_WITH_KNOTS" => Entity::BSplineCurve(BSplineCurve::decode(inst)?),
            "TRIMMED_CURVE" => Entity::TrimmedCurve(TrimmedCurve::decode(inst)?),
            "PCURVE" => {
                let mut d = simple(inst, 3)?;
                Entity::Pcurve(Pcurve {
                    surface: d.id("basis_surface")?,
                    representation: d.id("reference_to_curve")?,
                })
            }
            "SURFACE_CURVE" | "INTERSECTION_CURVE" => {
                Entity::SurfaceCurve(SurfaceCurve::decode(inst, false)?)
            }
            "SEAM_CURVE" => Entity::SurfaceCurve(SurfaceCurve::decode(inst, true)?),
            "COMPOSITE_CURVE" => Entity::CompositeCurve(CompositeCurve {
                segments: simple(inst, 3)?.ids("segments")?,
            }),
            "COMPOSITE_CURVE_SEGMENT" => {
                // (transition, same_sense, parent_curve): no inherited name.
                let mut d = Dec::new(&inst.records[0], 3, false)?;
                d.enumeration("transition")?;
                Entity::CompositeCurveSegment(CompositeCurveSegment {
                    same_sense: d.boolean("same_sense")?,
                    parent: d.id("parent_curve")?,
                })
            }
            "OFFSET_CURVE_3D" => {
                let mut d = simple(inst, 5)?;
                let basis = d.id("basis_curve")?;
                let distance = d.real("distance")?;
                d.logical("self_intersect")?;
                Entity::OffsetCurve3d(OffsetCurve3d {
                    basis,
                    distance,
                    ref_direction: d.id("ref_direction")?,
                })
            }
            "PLANE" => Entity::Elementary(ElementarySurface::decode(inst, ElementaryKind::Plane)?),
            "CYLINDRICAL_SURFACE" => {
                Entity::Elementary(ElementarySurface::decode(inst, ElementaryKind::Cylinder)?)
            }
            "CONICAL_SURFACE" => {
                Entity::Elementary(ElementarySurface::decode(inst, ElementaryKind::Cone)?)
            }
            "SPHERICAL_SURFACE" => {
                Entity::Elementary(ElementarySurface::decode(inst, ElementaryKind::Sphere)?)
            }
            "TOROIDAL_SURFACE" | "DEGENERATE_TOROIDAL_SURFACE" => {
                Entity::Elementary(ElementarySurface::decode(inst, ElementaryKind::Torus)?)
            }
            "B_SPLINE_SURFACE_WITH_KNOTS" => Entity::BSplineSurface(BSplineSurface::decode(inst)?),
            "SURFACE_OF_REVOLUTION" => {
                let mut d = simple(inst, 3)?;
                Entity::SurfaceOfRevolution(SurfaceOfRevolution {
                    curve: d.id("swept_curve")?,
                    axis: d.id("axis_position")?,
                })
            }
            "SURFACE_OF_LINEAR_EXTRUSION" => {
                let mut d = simple(inst, 3)?;
                Entity::SurfaceOfLinearExtrusion(SurfaceOfLinearExtrusion {
                    curve: d.id("swept_curve")?,
                    direction: d.id("extrusion_axis")?,
                })
            }
            "OFFSET_SURFACE" => {
                let mut d = simple(inst, 4)?;
                Entity::OffsetSurface(OffsetSurface {
                    surface: d.id("basis_surface")?,
                    distance: d.real("distance")?,
                })
            }
            "RECTANGULAR_TRIMMED_SURFACE" => {
                let mut d = simple(inst, 8)?;
                Entity::RectangularTrimmedSurface(RectangularTrimmedSurface {
                    surface: d.id("basis_surface")?,
                    bounds: [d.real("u1")?, d.real("u2")?, d.real("v1")?, d.real("v2")?],
                    senses: [d.boolean("usense")?, d.boolean("vsense")?],
                })
            }
            "VERTEX_POINT" => Entity::VertexPoint(VertexPoint {
                point: simple(inst, 2)?.id("vertex_geometry")?,
            }),
            "EDGE_CURVE" => {
                let mut d = simple(inst, 5)?;
                Entity::EdgeCurve(EdgeCurve {
                    start: d.id("edge_start")?,
                    end: d.id("edge_end")?,
                    curve: d.id("edge_geometry")?,
                    same_sense: d.boolean("same_sense")?,
                })
            }
            "ORIENTED_EDGE" => {
                let mut d = simple(inst, 5)?;
                d.skip(2); // edge_start, edge_end: derived
                Entity::OrientedEdge(OrientedEdge {
                    edge: d.id("edge_element")?,
                    orientation: d.boolean("orientation")?,
                })
            }
            "EDGE_LOOP" => Entity::EdgeLoop(EdgeLoop {
                edges: simple(inst, 2)?.ids("edge_list")?,
            }),
            "VERTEX_LOOP" => Entity::VertexLoop(VertexLoop {
                vertex: simple(inst, 2)?.id("loop_vertex")?,
            }),
            "FACE_BOUND" | "FACE_OUTER_BOUND" => {
                let mut d = simple(inst, 3)?;
                Entity::FaceBound(FaceBound {
                    bound: d.id("bound")?,
                    orientation: d.boolean("orientation")?,
                    outer: name == "FACE_OUTER_BOUND",
                })
            }
            "ADVANCED_FACE" | "FACE_SURFACE" => {
                let mut d = simple(inst, 4)?;
                Entity::Face(Face {
                    bounds: d.ids("bounds")?,
                    surface: d.id("face_geometry")?,
                    same_sense: d.boolean("same_sense")?,
                })
            }
            "CLOSED_SHELL" | "OPEN_SHELL" => Entity::Shell(Shell {
                faces: simple(inst, 2)?.ids("cfs_faces")?,
                closed: name == "CLOSED_SHELL",
            }),
            "ORIENTED_CLOSED_SHELL" | "ORIENTED_OPEN_SHELL" => {
                let mut d = simple(inst, 4)?;
                d.skip(1); // cfs_faces: derived
                Entity::OrientedShell(OrientedShell {
                    shell: d.id("shell_element")?,
                    orientation: d.boolean("orientation")?,
                })
            }
            "MANIFOLD_SOLID_BREP" => Entity::ManifoldSolidBrep(ManifoldSolidBrep {
                outer: simple(inst, 2)?.id("outer")?,
                voids: Vec::new(),
            }),
            "BREP_WITH_VOIDS" => {
                let mut d = simple(inst, 3)?;
                Entity::ManifoldSolidBrep(ManifoldSolidBrep {
                    outer: d.id("outer")?,
                    voids: d.ids("voids")?,
                })
            }
            "SHELL_BASED_SURFACE_MODEL" => Entity::ShellBasedSurfaceModel(ShellBasedSurfaceModel {
                shells: simple(inst, 2)?.ids("sbsm_boundary")?,
            }),
            "SI_UNIT" => NamedUnit::decode(inst)?.map_or(Entity::Other, Entity::NamedUnit),
            n if n.ends_with("MEASURE_WITH_UNIT") => {
                Entity::MeasureWithUnit(MeasureWithUnit::decode(inst)?)
            }
            n if n.ends_with("REPRESENTATION") && is_representation(inst) => {
                Entity::Representation(Representation::decode(inst)?)
            }
            _ => Entity::Other,
        })
    }

    fn decode_complex(inst: &Instance) -> Result<Entity, EntityProblem> {
        let has = |n: &str| inst.record(n).is_some();
        Ok(if has("B_SPLINE_CURVE_WITH_KNOTS") {
            Entity::BSplineCurve(BSplineCurve::decode(inst)?)
        } else if has("B_SPLINE_SURFACE_WITH_KNOTS") {
            Entity::BSplineSurface(BSplineSurface::decode(inst)?)
        } else if has("SI_UNIT") || has("CONVERSION_BASED_UNIT") {
            NamedUnit::decode(inst)?.map_or(Entity::Other, Entity::NamedUnit)
        } else if has("GLOBAL_UNIT_ASSIGNED_CONTEXT") || has("GEOMETRIC_REPRESENTATION_CONTEXT") {
            Entity::Context(Context::decode(inst)?)
        } else if has("REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION") {
            Entity::PlacedRepresentation(PlacedRepresentation::decode(inst)?)
        } else if has("MEASURE_WITH_UNIT") {
            Entity::MeasureWithUnit(MeasureWithUnit::decode(inst)?)
        } else {
            Entity::Other
        })
    }

    /// The references this entity holds, in attribute order.
    pub fn references(&self) -> Vec<Id> {
        let mut v = Vec::new();
        match self {
            Entity::Vector(x) => v.push(x.orientation),
            Entity::Axis1Placement(x) => {
                v.push(x.location);
                v.extend(x.axis);
            }
            Entity::Axis2Placement(x) => {
                v.push(x.location);
                v.extend(x.axis);
                v.extend(x.ref_direction);
            }
            Entity::Line(x) => v.extend([x.point, x.direction]),
            Entity::Conic(x) => v.push(x.position),
            Entity::Polyline(x) => v.extend(&x.points),
            Entity::BSplineCurve(x) => v.extend(&x.control_points),
            Entity::TrimmedCurve(x) => {
                v.push(x.basis);
                for t in x.trim1.iter().chain(&x.trim2) {
                    if let Trim::Point(p) = t {
                        v.push(*p);
                    }
                }
            }
            Entity::Pcurve(x) => v.extend([x.surface, x.representation]),
            Entity::SurfaceCurve(x) => {
                v.push(x.curve);
                v.extend(&x.associated);
            }
            Entity::CompositeCurve(x) => v.extend(&x.segments),
            Entity::CompositeCurveSegment(x) => v.push(x.parent),
            Entity::OffsetCurve3d(x) => v.extend([x.basis, x.ref_direction]),
            Entity::Elementary(x) => v.push(x.position),
            Entity::BSplineSurface(x) => x.control_points.iter().for_each(|r| v.extend(r)),
            Entity::SurfaceOfRevolution(x) => v.extend([x.curve, x.axis]),
            Entity::SurfaceOfLinearExtrusion(x) => v.extend([x.curve, x.direction]),
            Entity::OffsetSurface(x) => v.push(x.surface),
            Entity::RectangularTrimmedSurface(x) => v.push(x.surface),
            Entity::VertexPoint(x) => v.push(x.point),
            Entity::EdgeCurve(x) => v.extend([x.start, x.end, x.curve]),
            Entity::OrientedEdge(x) => v.push(x.edge),
            Entity::EdgeLoop(x) => v.extend(&x.edges),
            Entity::VertexLoop(x) => v.push(x.vertex),
            Entity::FaceBound(x) => v.push(x.bound),
            Entity::Face(x) => {
                v.extend(&x.bounds);
                v.push(x.surface);
            }
            Entity::Shell(x) => v.extend(&x.faces),
            Entity::OrientedShell(x) => v.push(x.shell),
            Entity::ManifoldSolidBrep(x) => {
                v.push(x.outer);
                v.extend(&x.voids);
            }
            Entity::ShellBasedSurfaceModel(x) => v.extend(&x.shells),
            Entity::Representation(x) => {
                v.extend(&x.items);
                v.push(x.context);
            }
            Entity::Context(x) => {
                v.extend(&x.units);
                v.extend(&x.uncertainty);
            }
            Entity::NamedUnit(x) => {
                if let UnitDefinition::Conversion { factor, .. } = &x.definition {
                    v.push(*factor);
                }
            }
            Entity::MeasureWithUnit(x) => v.push(x.unit),
            Entity::PlacedRepresentation(x) => v.extend([x.rep_1, x.rep_2, x.transformation]),
            Entity::CartesianPoint(_) | Entity::Direction(_) | Entity::Other => {}
        }
        v
    }
}

/// A representation is `(name, items: list, context: ref)`; other records whose name ends in
/// `REPRESENTATION` (e.g. `SHAPE_DEFINITION_REPRESENTATION(definition, used_representation)`)
/// are not.
fn is_representation(inst: &Instance) -> bool {
    let p = &inst.records[0].params;
    p.len() == 3 && matches!(p[1], crate::Value::List(_)) && matches!(p[2], crate::Value::Ref(_))
}
