//! The in-memory IGES file: start text, global parameters and entity records.

use crate::directory::{DeId, DirectoryEntry};
use crate::entity::{Entity, TransformationMatrix};
use crate::error::{EntityProblem, Error, Result};
use crate::global::Global;
use crate::param::Param;

/// Where an entity was found in the file it was read from (not used when writing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Sequence number of the first directory line.
    pub de_line: u32,
    /// Sequence number of the first parameter data line.
    pub pd_line: u32,
    /// Number of parameter data lines.
    pub pd_lines: u32,
}

/// One entity: its directory entry, its decoded parameters, and any parameters after them
/// (associativity and property pointers, kept raw).
#[derive(Debug, Clone, PartialEq)]
pub struct EntityRecord {
    /// The directory entry.
    pub de: DirectoryEntry,
    /// The decoded entity.
    pub entity: Entity,
    /// Parameters following the entity's own (written back unchanged).
    pub extra: Vec<Param>,
    /// Position in the file read (`None` for entities built in memory).
    pub layout: Option<Layout>,
}

/// A note about an entity that was read but not decoded or not fully understood.
#[derive(Debug, Clone, PartialEq)]
pub struct Warning {
    /// The entity.
    pub de: DeId,
    /// Its type number.
    pub entity_type: i32,
    /// What was not understood.
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "entity at D line {} (type {}): {}",
            self.de.line(),
            self.entity_type,
            self.message
        )
    }
}

/// An IGES file: what [`read`](crate::read) returns and [`IgesFile::write`] writes.
///
/// Entities are addressed by [`DeId`]: the entity at position i has DE pointer 2i + 1.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct IgesFile {
    /// The Start section text (lines joined with `\n`, trailing blanks removed).
    pub start: String,
    /// The Global section.
    pub global: Global,
    /// The entities in directory order.
    pub entities: Vec<EntityRecord>,
    /// Entities kept raw or partly understood (unknown types).
    pub warnings: Vec<Warning>,
    /// The file name used in error messages.
    pub name: String,
}

impl IgesFile {
    /// An empty file with the given global parameters.
    pub fn new(global: Global) -> Self {
        IgesFile {
            global,
            ..Default::default()
        }
    }

    /// Appends an entity with a default directory entry (form 0) and returns its pointer.
    pub fn push(&mut self, entity: Entity) -> DeId {
        self.push_with(entity, 0, None)
    }

    /// Appends an entity with the given form number and transformation and returns its
    /// pointer. The type of [`Entity::Unknown`] cannot be inferred; use
    /// [`IgesFile::push_record`].
    pub fn push_with(&mut self, entity: Entity, form: i32, transform: Option<DeId>) -> DeId {
        let mut de = DirectoryEntry::new(entity.type_number().unwrap_or(0), form);
        de.transform = transform;
        self.push_record(EntityRecord {
            de,
            entity,
            extra: Vec::new(),
            layout: None,
        })
    }

    /// Appends a full record and returns its pointer.
    pub fn push_record(&mut self, record: EntityRecord) -> DeId {
        self.entities.push(record);
        DeId::from_index(self.entities.len() - 1)
    }

    /// The entity a pointer names, if it is in range.
    pub fn get(&self, id: DeId) -> Option<&EntityRecord> {
        self.entities.get(id.index())
    }

    /// Iterates over (pointer, record).
    pub fn iter(&self) -> impl Iterator<Item = (DeId, &EntityRecord)> {
        self.entities
            .iter()
            .enumerate()
            .map(|(i, r)| (DeId::from_index(i), r))
    }

    /// Number of entities per type number, sorted by type.
    pub fn type_counts(&self) -> Vec<(i32, usize)> {
        let mut m = std::collections::BTreeMap::new();
        for r in &self.entities {
            *m.entry(r.de.entity_type).or_insert(0usize) += 1;
        }
        m.into_iter().collect()
    }

    /// An error about entity `id` (for consumers that find a problem while converting).
    pub fn entity_error(&self, id: DeId, problem: EntityProblem) -> Error {
        Error::Entity {
            file: self.name.clone(),
            de: id.line(),
            entity_type: self.get(id).map_or(0, |r| r.de.entity_type),
            problem,
        }
    }

    /// The entity named by `id`, checking that its type is one of `types`; `from` is the
    /// entity holding the pointer, named in the error.
    pub fn expect(&self, from: DeId, id: DeId, types: &[i32]) -> Result<&EntityRecord> {
        match self.get(id) {
            Some(r) if types.contains(&r.de.entity_type) => Ok(r),
            other => Err(self.entity_error(
                from,
                EntityProblem::Pointer {
                    index: 0,
                    pointer: id.line() as i64,
                    reason: match other {
                        Some(r) => format!(
                            "names an entity of type {}, expected one of {types:?}",
                            r.de.entity_type
                        ),
                        None => "names no entity".to_string(),
                    },
                },
            )),
        }
    }

    /// The transformation that maps entity `id`'s definition space to model space: its
    /// directory transformation matrix (124) composed with the chain of 124s that matrix
    /// references (each applied after the one referencing it). `None` means identity.
    ///
    /// Errors name the entity when a pointer in the chain is not a 124 or the chain loops.
    pub fn transform(&self, id: DeId) -> Result<Option<TransformationMatrix>> {
        let Some(rec) = self.get(id) else {
            return Err(self.entity_error(
                id,
                EntityProblem::Pointer {
                    index: 0,
                    pointer: id.line() as i64,
                    reason: "names no entity".into(),
                },
            ));
        };
        let mut next = rec.de.transform;
        let mut total: Option<TransformationMatrix> = None;
        let mut seen = Vec::new();
        while let Some(t) = next {
            if seen.contains(&t) {
                return Err(self.entity_error(id, EntityProblem::TransformCycle { at: t.line() }));
            }
            seen.push(t);
            let r = self.expect(id, t, &[124])?;
            let Entity::TransformationMatrix(m) = &r.entity else {
                return Err(self.entity_error(
                    id,
                    EntityProblem::Pointer {
                        index: 0,
                        pointer: t.line() as i64,
                        reason: "names a 124 that could not be decoded".into(),
                    },
                ));
            };
            total = Some(match total {
                None => *m,
                Some(inner) => inner.then(m),
            });
            next = r.de.transform;
        }
        Ok(total)
    }
}
