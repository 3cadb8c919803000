//! The in-memory STEP file: header, instances by name, their typed entities, and
//! type-checked lookups that name the referring instance in errors.

use std::collections::HashMap;
use std::io::BufRead;

use crate::entity::{Entity, MeasureWithUnit, NamedUnit, UnitDefinition, UnitKind, si_prefix};
use crate::error::{EntityProblem, Error, Result};
use crate::parse::Parser;
use crate::value::{Id, Instance, Record, Value};

/// A STEP file: what [`read`] and [`parse`] return.
#[derive(Debug, Clone, PartialEq)]
pub struct StepFile {
    /// The file name used in error messages.
    pub name: String,
    /// The header section's records.
    pub header: Vec<Record>,
    /// The schema names of `FILE_SCHEMA` (`AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }`,
    /// `CONFIG_CONTROL_DESIGN`, `AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF …`).
    pub schemas: Vec<String>,
    /// The instances in file order.
    pub instances: Vec<Instance>,
    /// The typed entity of each instance (same order).
    pub entities: Vec<Entity>,
    index: HashMap<Id, usize>,
}

/// Reads a STEP file (ISO 10303-21 clear text). `name` is used in error messages.
///
/// Every error names the file and the line or instance at fault; corrupt input never
/// panics.
pub fn read(mut reader: impl BufRead, name: &str) -> Result<StepFile> {
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes).map_err(|source| Error::Io {
        file: name.to_string(),
        source,
    })?;
    parse(&bytes, name)
}

/// Parses a whole file held in memory: the syntax, then every instance's typed entity, then
/// the references (each must name an instance of the file).
pub fn parse(bytes: &[u8], name: &str) -> Result<StepFile> {
    let ex = Parser::new(bytes, name).exchange()?;
    let schemas = ex
        .header
        .iter()
        .find(|r| r.name == "FILE_SCHEMA")
        .and_then(|r| r.params.first())
        .map(|v| match v {
            Value::List(items) => items
                .iter()
                .filter_map(|x| match x {
                    Value::Str(s) => Some(s.clone()),
                    _ => None,
                })
                .collect(),
            _ => Vec::new(),
        })
        .unwrap_or_default();
    let mut index = HashMap::with_capacity(ex.instances.len());
    for (k, inst) in ex.instances.iter().enumerate() {
        if let Some(&other) = index.get(&inst.id) {
            let o: &Instance = &ex.instances[other];
            return Err(instance_error(
                name,
                inst,
                EntityProblem::Duplicate { other_line: o.line },
            ));
        }
        index.insert(inst.id, k);
    }
    let mut entities = Vec::with_capacity(ex.instances.len());
    for inst in &ex.instances {
        entities.push(Entity::decode(inst).map_err(|p| instance_error(name, inst, p))?);
        // Every reference, typed or not, must name an instance.
        for rec in &inst.records {
            for (k, v) in rec.params.iter().enumerate() {
                let mut missing = None;
                v.for_each_ref(&mut |id| {
                    if missing.is_none() && !index.contains_key(&id) {
                        missing = Some(id);
                    }
                });
                if let Some(target) = missing {
                    return Err(instance_error(
                        name,
                        inst,
                        EntityProblem::Reference {
                            index: k + 1,
                            name: "reference",
                            target,
                            reason: "names no instance of the file".into(),
                        },
                    ));
                }
            }
        }
    }
    Ok(StepFile {
        name: name.to_string(),
        header: ex.header,
        schemas,
        instances: ex.instances,
        entities,
        index,
    })
}

fn instance_error(file: &str, inst: &Instance, problem: EntityProblem) -> Error {
    Error::Entity {
        file: file.to_string(),
        id: inst.id,
        line: inst.line,
        entity: inst.type_name(),
        problem: Box::new(problem),
    }
}

/// The units of a representation context, as factors to SI.
#[derive(Debug, Clone, PartialEq)]
pub struct Units {
    /// The length unit in metres (`None` when the context assigns none).
    pub length: Option<f64>,
    /// A short name of the length unit: `m`, `mm`, `cm`, `in`, `ft`, …, or its factor.
    pub length_name: Option<String>,
    /// The plane angle unit in radians (`None` when the context assigns none: radians
    /// are then assumed by readers).
    pub plane_angle: Option<f64>,
    /// The uncertainty (distance accuracy) in the length unit, if given.
    pub uncertainty: Option<f64>,
}

/// The short name of a length of `m` metres used as a unit.
pub fn length_unit_name(m: f64) -> String {
    const NAMES: [(f64, &str); 8] = [
        (1.0, "m"),
        (1e-3, "mm"),
        (1e-2, "cm"),
        (1e-1, "dm"),
        (1e3, "km"),
        (1e-6, "um"),
        (0.0254, "in"),
        (0.3048, "ft"),
    ];
    NAMES
        .iter()
        .find(|(v, _)| (v - m).abs() <= 1e-9 * v)
        .map_or_else(|| format!("{m} m"), |(_, n)| n.to_string())
}

impl StepFile {
    /// The instance named `id`.
    pub fn instance(&self, id: Id) -> Option<&Instance> {
        self.index.get(&id).map(|&k| &self.instances[k])
    }

    /// The typed entity of instance `id`.
    pub fn entity(&self, id: Id) -> Option<&Entity> {
        self.index.get(&id).map(|&k| &self.entities[k])
    }

    /// Iterates over (instance, entity) in file order.
    pub fn iter(&self) -> impl Iterator<Item = (&Instance, &Entity)> {
        self.instances.iter().zip(&self.entities)
    }

    /// Number of instances per type name (complex instances as `(A B …)`), sorted by name.
    pub fn type_counts(&self) -> Vec<(String, usize)> {
        let mut m = std::collections::BTreeMap::new();
        for i in &self.instances {
            *m.entry(i.type_name()).or_insert(0usize) += 1;
        }
        m.into_iter().collect()
    }

    /// An error about instance `id` (for consumers that find a problem while converting).
    pub fn error(&self, id: Id, problem: EntityProblem) -> Error {
        match self.instance(id) {
            Some(inst) => instance_error(&self.name, inst, problem),
            None => Error::Entity {
                file: self.name.clone(),
                id,
                line: 0,
                entity: "?".into(),
                problem: Box::new(problem),
            },
        }
    }

    /// An [`EntityProblem::Invalid`] error about instance `id`.
    pub fn invalid(&self, id: Id, reason: impl Into<String>) -> Error {
        self.error(
            id,
            EntityProblem::Invalid {
                reason: reason.into(),
            },
        )
    }

    /// The entity `id` that instance `from` refers to through attribute `what`; an error
    /// naming `from` when `id` names no instance.
    pub fn get(&self, from: Id, id: Id, what: &'static str) -> Result<(&Instance, &Entity)> {
        match self.index.get(&id) {
            Some(&k) => Ok((&self.instances[k], &self.entities[k])),
            None => Err(self.error(
                from,
                EntityProblem::Reference {
                    index: 0,
                    name: what,
                    target: id,
                    reason: "names no instance of the file".into(),
                },
            )),
        }
    }

    /// An error naming `from`: its attribute `what` refers to `id`, whose type is wrong.
    pub fn wrong_type(&self, from: Id, id: Id, what: &'static str, expected: &str) -> Error {
        let found = self
            .instance(id)
            .map_or("nothing".into(), Instance::type_name);
        self.error(
            from,
            EntityProblem::Reference {
                index: 0,
                name: what,
                target: id,
                reason: format!("is a {found}, expected {expected}"),
            },
        )
    }

    /// The coordinates of the `CARTESIAN_POINT` `id` (missing coordinates are 0).
    pub fn point(&self, from: Id, id: Id, what: &'static str) -> Result<[f64; 3]> {
        match self.get(from, id, what)?.1 {
            Entity::CartesianPoint(p) if !p.coordinates.is_empty() && p.coordinates.len() <= 3 => {
                let c = &p.coordinates;
                Ok([
                    c[0],
                    c.get(1).copied().unwrap_or(0.0),
                    c.get(2).copied().unwrap_or(0.0),
                ])
            }
            _ => Err(self.wrong_type(from, id, what, "CARTESIAN_POINT")),
        }
    }

    /// The ratios of the `DIRECTION` `id` (missing ratios are 0), not normalised.
    pub fn direction(&self, from: Id, id: Id, what: &'static str) -> Result<[f64; 3]> {
        match self.get(from, id, what)?.1 {
            Entity::Direction(d) if !d.ratios.is_empty() && d.ratios.len() <= 3 => {
                let c = &d.ratios;
                Ok([
                    c[0],
                    c.get(1).copied().unwrap_or(0.0),
                    c.get(2).copied().unwrap_or(0.0),
                ])
            }
            _ => Err(self.wrong_type(from, id, what, "DIRECTION")),
        }
    }

    /// The factor to SI (metres, radians) and kind of the named unit `id`, following
    /// conversion-based units (`INCH` = 25.4 × `MILLI METRE`).
    pub fn unit_factor(&self, from: Id, id: Id) -> Result<(UnitKind, f64)> {
        let mut cur = id;
        let mut factor = 1.0;
        let mut at = from;
        for _ in 0..8 {
            let unit: &NamedUnit = match self.get(at, cur, "unit")?.1 {
                Entity::NamedUnit(u) => u,
                _ => return Err(self.wrong_type(at, cur, "unit", "a named unit")),
            };
            match &unit.definition {
                UnitDefinition::Si { prefix, name } => {
                    let p = si_prefix(prefix).ok_or_else(|| {
                        self.invalid(cur, format!("unknown SI prefix .{prefix}."))
                    })?;
                    let _ = name;
                    return Ok((unit.kind, factor * p));
                }
                UnitDefinition::Conversion { factor: m, .. } => {
                    let mw: &MeasureWithUnit = match self.get(cur, *m, "conversion_factor")?.1 {
                        Entity::MeasureWithUnit(x) => x,
                        _ => {
                            return Err(self.wrong_type(
                                cur,
                                *m,
                                "conversion_factor",
                                "a MEASURE_WITH_UNIT",
                            ));
                        }
                    };
                    if !(mw.value.is_finite() && mw.value > 0.0) {
                        return Err(self.invalid(
                            *m,
                            format!("conversion factor {} is not positive", mw.value),
                        ));
                    }
                    factor *= mw.value;
                    at = *m;
                    cur = mw.unit;
                }
            }
        }
        Err(self.invalid(
            id,
            "conversion-based units nest more than 8 deep (a cycle?)",
        ))
    }

    /// The units of the representation context `ctx` (an error names the context or unit
    /// at fault).
    pub fn units(&self, ctx: Id) -> Result<Units> {
        let c = match self.entity(ctx) {
            Some(Entity::Context(c)) => c,
            _ => {
                return Ok(Units {
                    length: None,
                    length_name: None,
                    plane_angle: None,
                    uncertainty: None,
                });
            }
        };
        let mut out = Units {
            length: None,
            length_name: None,
            plane_angle: None,
            uncertainty: None,
        };
        for &u in &c.units {
            let (kind, f) = self.unit_factor(ctx, u)?;
            match kind {
                UnitKind::Length => {
                    out.length = Some(f);
                    out.length_name = Some(length_unit_name(f));
                }
                UnitKind::PlaneAngle => out.plane_angle = Some(f),
                _ => {}
            }
        }
        for &m in &c.uncertainty {
            if let Some(Entity::MeasureWithUnit(mw)) = self.entity(m)
                && let Ok((UnitKind::Length, f)) = self.unit_factor(m, mw.unit)
            {
                let per_unit = out.length.map_or(f, |l| f / l);
                out.uncertainty = Some(mw.value * per_unit);
            }
        }
        Ok(out)
    }
}
