//! Directory entries: the two fixed-format 80-column `D` lines describing each entity.

use std::fmt;

/// A pointer to an entity: the sequence number of its first directory line (odd, ≥ 1).
///
/// In the file, pointers between entities are written as this number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DeId(u32);

impl DeId {
    /// The pointer for the entity at 0-based position `index` in the directory.
    pub fn from_index(index: usize) -> Self {
        DeId(u32::try_from(2 * index + 1).expect("fewer than 2^31 entities"))
    }

    /// Validates a pointer value read from a file against a directory of `n_entities`.
    pub fn from_pointer(pointer: i64, n_entities: usize) -> Option<Self> {
        if pointer >= 1 && pointer % 2 == 1 && ((pointer - 1) / 2) < n_entities as i64 {
            u32::try_from(pointer).ok().map(DeId)
        } else {
            None
        }
    }

    /// The sequence number of the first directory line (what the file writes).
    pub fn line(self) -> u32 {
        self.0
    }

    /// The 0-based position in the directory.
    pub fn index(self) -> usize {
        (self.0 as usize - 1) / 2
    }
}

impl fmt::Display for DeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "D{}", self.0)
    }
}

/// The status number (directory field 9): four two-digit flags.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Status {
    /// 0 visible, 1 blanked.
    pub blank: u8,
    /// 0 independent, 1 physically dependent, 2 logically dependent, 3 both.
    pub subordinate: u8,
    /// Entity use: 0 geometry, 1 annotation, 2 definition, 3 other, 4 logical/positional,
    /// 5 2D parametric, 6 construction geometry.
    pub use_flag: u8,
    /// 0 global top down, 1 global defer, 2 use hierarchy property.
    pub hierarchy: u8,
}

impl Status {
    /// Parses the 8-digit field (blanks read as zeros).
    pub(crate) fn parse(field: &str) -> Option<Self> {
        let s: Vec<u8> = format!("{field:>8}")
            .bytes()
            .map(|b| if b == b' ' { b'0' } else { b })
            .collect();
        if s.len() != 8 || !s.iter().all(u8::is_ascii_digit) {
            return None;
        }
        let two = |k: usize| (s[k] - b'0') * 10 + (s[k + 1] - b'0');
        Some(Status {
            blank: two(0),
            subordinate: two(2),
            use_flag: two(4),
            hierarchy: two(6),
        })
    }

    /// The 8-digit field.
    pub(crate) fn format(&self) -> String {
        format!(
            "{:02}{:02}{:02}{:02}",
            self.blank.min(99),
            self.subordinate.min(99),
            self.use_flag.min(99),
            self.hierarchy.min(99)
        )
    }
}

/// The attributes of a directory entry (fields 1–20 except the layout fields, which the
/// reader keeps in [`Layout`](crate::Layout) and the writer computes).
///
/// Fields that may hold either a value or a negated pointer to a definition entity (line
/// font, level, colour) are kept as the signed integer the file holds.
#[derive(Debug, Clone, PartialEq)]
pub struct DirectoryEntry {
    /// Field 1/11: entity type number.
    pub entity_type: i32,
    /// Field 3: structure (negated pointer to a definition entity, or 0).
    pub structure: i64,
    /// Field 4: line font pattern (value or negated pointer).
    pub line_font: i64,
    /// Field 5: level (value or negated pointer).
    pub level: i64,
    /// Field 6: view pointer (0 for none).
    pub view: i64,
    /// Field 7: transformation matrix (entity 124) applied to this entity, if any.
    pub transform: Option<DeId>,
    /// Field 8: label display associativity pointer (0 for none).
    pub label_display: i64,
    /// Field 9: status number.
    pub status: Status,
    /// Field 12: line weight number.
    pub line_weight: i64,
    /// Field 13: colour number (value or negated pointer to a 314 entity).
    pub color: i64,
    /// Field 15: form number.
    pub form: i32,
    /// Field 18: entity label (up to 8 characters).
    pub label: String,
    /// Field 19: entity subscript number.
    pub subscript: i64,
}

impl DirectoryEntry {
    /// A directory entry with defaults for an entity of the given type and form.
    pub fn new(entity_type: i32, form: i32) -> Self {
        DirectoryEntry {
            entity_type,
            structure: 0,
            line_font: 0,
            level: 0,
            view: 0,
            transform: None,
            label_display: 0,
            status: Status::default(),
            line_weight: 0,
            color: 0,
            form,
            label: String::new(),
            subscript: 0,
        }
    }
}

/// Names of the 20 directory fields, for error messages.
pub(crate) const FIELD_NAMES: [&str; 20] = [
    "entity type",
    "parameter data pointer",
    "structure",
    "line font pattern",
    "level",
    "view",
    "transformation matrix",
    "label display",
    "status number",
    "sequence number",
    "entity type",
    "line weight",
    "colour",
    "parameter line count",
    "form",
    "reserved",
    "reserved",
    "entity label",
    "entity subscript",
    "sequence number",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pointers_validate() {
        assert_eq!(DeId::from_pointer(1, 1).map(DeId::index), Some(0));
        assert_eq!(DeId::from_pointer(5, 3).map(DeId::index), Some(2));
        assert_eq!(DeId::from_pointer(7, 3), None);
        assert_eq!(DeId::from_pointer(2, 3), None);
        assert_eq!(DeId::from_pointer(0, 3), None);
        assert_eq!(DeId::from_pointer(-1, 3), None);
        assert_eq!(DeId::from_index(4).line(), 9);
    }

    #[test]
    fn status_round_trip() {
        let s = Status::parse("01010500").unwrap();
        assert_eq!(s.subordinate, 1);
        assert_eq!(s.use_flag, 5);
        assert_eq!(s.format(), "01010500");
        assert_eq!(Status::parse("").unwrap(), Status::default());
        assert!(Status::parse("0x010000").is_none());
    }
}
