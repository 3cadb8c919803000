//! Units, measures, representation contexts and representations (ISO 10303-41 and -43).

use super::dec::Dec;
use crate::error::EntityProblem;
use crate::value::{Id, Instance, Value};

/// What a unit measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnitKind {
    /// `LENGTH_UNIT`.
    Length,
    /// `PLANE_ANGLE_UNIT`.
    PlaneAngle,
    /// `SOLID_ANGLE_UNIT`.
    SolidAngle,
    /// Any other (mass, time, …).
    Other,
}

/// How a unit is defined.
#[derive(Debug, Clone, PartialEq)]
pub enum UnitDefinition {
    /// `SI_UNIT(prefix, name)`: `prefix` is empty for none (`$`), else `MILLI`, `KILO`, ….
    Si {
        /// The prefix.
        prefix: String,
        /// `METRE`, `RADIAN`, `STERADIAN`, ….
        name: String,
    },
    /// `CONVERSION_BASED_UNIT(name, conversion_factor)`: one unit is `factor`, a
    /// `…MEASURE_WITH_UNIT` (e.g. `'INCH'` is 25.4 mm).
    Conversion {
        /// The unit's name as written (`INCH`, `DEGREE`, …).
        name: String,
        /// The measure it equals.
        factor: Id,
    },
}

/// A named unit: a simple `SI_UNIT`, or a complex instance such as
/// `( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) )`.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedUnit {
    /// What it measures.
    pub kind: UnitKind,
    /// Its definition.
    pub definition: UnitDefinition,
}

/// `…MEASURE_WITH_UNIT(value_component, unit_component)` (length, plane angle,
/// uncertainty, or the complex form with a `MEASURE_WITH_UNIT` record).
#[derive(Debug, Clone, PartialEq)]
pub struct MeasureWithUnit {
    /// The value, in `unit`.
    pub value: f64,
    /// The unit.
    pub unit: Id,
}

/// A representation context; for a geometric context, the complex instance with
/// `GLOBAL_UNIT_ASSIGNED_CONTEXT(units)` and `GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT(uncertainty)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Context {
    /// `GEOMETRIC_REPRESENTATION_CONTEXT(coordinate_space_dimension)`, if present.
    pub dimension: Option<i64>,
    /// The units assigned (named units).
    pub units: Vec<Id>,
    /// `UNCERTAINTY_MEASURE_WITH_UNIT`s.
    pub uncertainty: Vec<Id>,
}

/// Any `…REPRESENTATION(name, items, context_of_items)`: shape representations
/// (`ADVANCED_BREP_SHAPE_REPRESENTATION`, `MANIFOLD_SURFACE_SHAPE_REPRESENTATION`,
/// `SHAPE_REPRESENTATION`, …) and `DEFINITIONAL_REPRESENTATION` (of a pcurve).
#[derive(Debug, Clone, PartialEq)]
pub struct Representation {
    /// The record name.
    pub kind: String,
    /// The items.
    pub items: Vec<Id>,
    /// The context.
    pub context: Id,
}

/// A representation relationship with a transformation (an assembly placement),
/// `( REPRESENTATION_RELATIONSHIP(name, description, rep_1, rep_2)
/// REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(transformation) … )`.
#[derive(Debug, Clone, PartialEq)]
pub struct PlacedRepresentation {
    /// rep_1.
    pub rep_1: Id,
    /// rep_2.
    pub rep_2: Id,
    /// The transformation (an `ITEM_DEFINED_TRANSFORMATION`).
    pub transformation: Id,
}

fn kind_of(inst: &Instance, si_name: &str) -> UnitKind {
    if inst.record("LENGTH_UNIT").is_some() {
        UnitKind::Length
    } else if inst.record("PLANE_ANGLE_UNIT").is_some() {
        UnitKind::PlaneAngle
    } else if inst.record("SOLID_ANGLE_UNIT").is_some() {
        UnitKind::SolidAngle
    } else {
        match si_name {
            "METRE" => UnitKind::Length,
            "RADIAN" => UnitKind::PlaneAngle,
            "STERADIAN" => UnitKind::SolidAngle,
            _ => UnitKind::Other,
        }
    }
}

impl NamedUnit {
    /// Decodes a unit instance (simple `SI_UNIT` or a complex one); `None` when it is not a
    /// unit.
    pub(crate) fn decode(inst: &Instance) -> Result<Option<Self>, EntityProblem> {
        let complex = inst.is_complex();
        if let Some(r) = inst.record("SI_UNIT") {
            // Simple: (dimensions, prefix, name); complex part: (prefix, name).
            let mut d = Dec::new(r, if complex { 2 } else { 3 }, complex)?;
            if !complex {
                d.skip(1);
            }
            let prefix = d.enumeration("prefix")?;
            let name = d.enumeration("name")?;
            return Ok(Some(NamedUnit {
                kind: kind_of(inst, &name),
                definition: UnitDefinition::Si { prefix, name },
            }));
        }
        if let Some(r) = inst.record("CONVERSION_BASED_UNIT") {
            // Simple: (dimensions, name, factor); complex part: (name, factor).
            let mut d = Dec::new(r, if complex { 2 } else { 3 }, complex)?;
            if !complex {
                d.skip(1);
            }
            let (i, v) = d.value();
            let name = match v {
                Value::Str(s) => s.clone(),
                v => {
                    return Err(EntityProblem::Param {
                        index: i,
                        name: "name",
                        path: String::new(),
                        expected: "a string".into(),
                        found: v.describe(),
                    });
                }
            };
            let factor = d.id("conversion_factor")?;
            return Ok(Some(NamedUnit {
                kind: kind_of(inst, ""),
                definition: UnitDefinition::Conversion { name, factor },
            }));
        }
        Ok(None)
    }
}

impl MeasureWithUnit {
    /// Decodes any `…MEASURE_WITH_UNIT` (simple, or complex with a `MEASURE_WITH_UNIT` part).
    pub(crate) fn decode(inst: &Instance) -> Result<Self, EntityProblem> {
        let (rec, complex) = match inst.record("MEASURE_WITH_UNIT") {
            Some(r) if inst.is_complex() => (r, true),
            _ => (&inst.records[0], false),
        };
        let mut d = Dec::new(rec, 2, complex)?;
        Ok(MeasureWithUnit {
            value: d.real("value_component")?,
            unit: d.id("unit_component")?,
        })
    }
}

impl Context {
    /// Decodes a (complex) representation context.
    pub(crate) fn decode(inst: &Instance) -> Result<Self, EntityProblem> {
        let complex = inst.is_complex();
        let dimension = match inst.record("GEOMETRIC_REPRESENTATION_CONTEXT") {
            Some(r) => {
                let mut d = Dec::new(r, if complex { 1 } else { 3 }, complex)?;
                if !complex {
                    d.skip(2);
                }
                Some(d.int("coordinate_space_dimension")?)
            }
            None => None,
        };
        let units = match inst.record("GLOBAL_UNIT_ASSIGNED_CONTEXT") {
            Some(r) => {
                let mut d = Dec::new(r, if complex { 1 } else { 3 }, complex)?;
                if !complex {
                    d.skip(2);
                }
                d.ids("units")?
            }
            None => Vec::new(),
        };
        let uncertainty = match inst.record("GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT") {
            Some(r) => {
                let mut d = Dec::new(r, if complex { 1 } else { 3 }, complex)?;
                if !complex {
                    d.skip(2);
                }
                d.ids("uncertainty")?
            }
            None => Vec::new(),
        };
        Ok(Context {
            dimension,
            units,
            uncertainty,
        })
    }
}

impl Representation {
    pub(crate) fn decode(inst: &Instance) -> Result<Self, EntityProblem> {
        let rec = &inst.records[0];
        let mut d = Dec::new(rec, 3, false)?;
        d.skip(1);
        Ok(Representation {
            kind: rec.name.clone(),
            items: d.ids("items")?,
            context: d.id("context_of_items")?,
        })
    }
}

impl PlacedRepresentation {
    pub(crate) fn decode(inst: &Instance) -> Result<Self, EntityProblem> {
        let rel = inst
            .record("REPRESENTATION_RELATIONSHIP")
            .ok_or(EntityProblem::Complex {
                missing: "REPRESENTATION_RELATIONSHIP",
            })?;
        let mut d = Dec::new(rel, 4, true)?;
        d.skip(2);
        let rep_1 = d.id("rep_1")?;
        let rep_2 = d.id("rep_2")?;
        let t = inst
            .record("REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION")
            .ok_or(EntityProblem::Complex {
                missing: "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION",
            })?;
        let transformation = Dec::new(t, 1, true)?.id("transformation_operator")?;
        Ok(PlacedRepresentation {
            rep_1,
            rep_2,
            transformation,
        })
    }
}

/// The factor of an SI prefix (`MILLI` → 1e-3); `None` when unknown.
pub fn si_prefix(prefix: &str) -> Option<f64> {
    Some(match prefix {
        "" => 1.0,
        "EXA" => 1e18,
        "PETA" => 1e15,
        "TERA" => 1e12,
        "GIGA" => 1e9,
        "MEGA" => 1e6,
        "KILO" => 1e3,
        "HECTO" => 1e2,
        "DECA" => 1e1,
        "DECI" => 1e-1,
        "CENTI" => 1e-2,
        "MILLI" => 1e-3,
        "MICRO" => 1e-6,
        "NANO" => 1e-9,
        "PICO" => 1e-12,
        "FEMTO" => 1e-15,
        "ATTO" => 1e-18,
        _ => return None,
    })
}
