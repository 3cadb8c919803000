//! Reading the fixed-format ASCII form: sections, directory entries, parameter data.

use std::io::BufRead;

use crate::directory::{DeId, DirectoryEntry, FIELD_NAMES, Status};
use crate::entity::{Entity, SUPPORTED_TYPES};
use crate::error::{EntityProblem, Error, Result};
use crate::file::{EntityRecord, IgesFile, Layout, Warning};
use crate::global::Global;
use crate::param::{Param, split};

/// Reads an IGES file in the fixed 80-column ASCII form. `name` is used in error messages
/// (usually the path).
///
/// Every error names the file and the physical line, Global parameter or directory entry
/// at fault; corrupt input never panics.
pub fn read(mut reader: impl BufRead, name: &str) -> Result<IgesFile> {
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes).map_err(|source| Error::Io {
        file: name.to_string(),
        source,
    })?;
    parse(&bytes, name)
}

/// The lines of one section: (physical line number, line bytes).
type Lines<'a> = Vec<(usize, &'a [u8])>;

fn line_err(file: &str, line: usize, reason: impl Into<String>) -> Error {
    Error::Line {
        file: file.to_string(),
        line,
        reason: reason.into(),
    }
}

fn structure_err(file: &str, reason: impl Into<String>) -> Error {
    Error::Structure {
        file: file.to_string(),
        reason: reason.into(),
    }
}

/// Columns `a..b` (0-based, exclusive) of a line, padded with blanks when short.
fn cols(line: &[u8], a: usize, b: usize) -> Vec<u8> {
    let mut v: Vec<u8> = line.get(a..b.min(line.len())).unwrap_or(&[]).to_vec();
    v.resize(b - a, b' ');
    v
}

fn parse_seq(line: &[u8]) -> Option<u32> {
    std::str::from_utf8(&cols(line, 73, 80))
        .ok()?
        .trim()
        .parse()
        .ok()
}

/// Parses a whole file held in memory.
pub fn parse(bytes: &[u8], name: &str) -> Result<IgesFile> {
    let mut lines: Vec<&[u8]> = bytes
        .split(|&b| b == b'\n')
        .map(|l| l.strip_suffix(b"\r").unwrap_or(l))
        .collect();
    while lines
        .last()
        .is_some_and(|l| l.iter().all(|&b| b == b' ' || b == 0x1a))
    {
        lines.pop();
    }
    if lines.is_empty() {
        return Err(structure_err(name, "the file is empty"));
    }
    match lines[0].get(72) {
        Some(b'C') => {
            return Err(Error::UnsupportedForm {
                file: name.to_string(),
                form: "compressed ASCII",
            });
        }
        Some(b'B') => {
            return Err(Error::UnsupportedForm {
                file: name.to_string(),
                form: "binary",
            });
        }
        _ => {}
    }
    let order = b"SGDPT";
    let mut sections: [Lines; 5] = Default::default();
    let mut current = 0usize;
    for (k, line) in lines.iter().enumerate() {
        let ln = k + 1;
        if line.len() < 73 {
            return Err(line_err(
                name,
                ln,
                format!(
                    "the line has {} columns; IGES records have 80, with the section letter in column 73",
                    line.len()
                ),
            ));
        }
        let letter = line[72];
        let Some(s) = order.iter().position(|&c| c == letter) else {
            return Err(line_err(
                name,
                ln,
                format!(
                    "unknown section letter '{}' in column 73 (expected S, G, D, P or T)",
                    letter.escape_ascii()
                ),
            ));
        };
        if s < current {
            return Err(line_err(
                name,
                ln,
                format!(
                    "section {} after section {}",
                    letter as char, order[current] as char
                ),
            ));
        }
        current = s;
        let expected = sections[s].len() + 1;
        match parse_seq(line) {
            Some(n) if n as usize == expected => {}
            Some(n) => {
                return Err(line_err(
                    name,
                    ln,
                    format!(
                        "sequence number {}{n}, expected {}{expected}",
                        letter as char, letter as char
                    ),
                ));
            }
            None => {
                return Err(line_err(
                    name,
                    ln,
                    "columns 74-80 do not hold a sequence number",
                ));
            }
        }
        sections[s].push((ln, line));
    }
    let [s_lines, g_lines, d_lines, p_lines, t_lines] = sections;

    // Terminate section.
    let Some(&(t_ln, t_line)) = t_lines.first() else {
        return Err(structure_err(
            name,
            format!(
                "the file ends at line {} without a Terminate (T) section (truncated?)",
                lines.len()
            ),
        ));
    };
    if t_lines.len() > 1 {
        return Err(line_err(name, t_lines[1].0, "more than one Terminate line"));
    }
    let counts = [s_lines.len(), g_lines.len(), d_lines.len(), p_lines.len()];
    for (k, &c) in b"SGDP".iter().enumerate() {
        let field = cols(t_line, 8 * k, 8 * k + 8);
        let ok_letter = field[0] == c;
        let n = std::str::from_utf8(&field[1..])
            .ok()
            .and_then(|s| s.trim().parse::<usize>().ok());
        match n {
            Some(n) if ok_letter && n == counts[k] => {}
            Some(n) if ok_letter => {
                return Err(line_err(
                    name,
                    t_ln,
                    format!(
                        "the Terminate section counts {n} {} lines, the file has {} (truncated or edited?)",
                        c as char, counts[k]
                    ),
                ));
            }
            _ => {
                return Err(line_err(
                    name,
                    t_ln,
                    format!(
                        "Terminate field {} should be '{}' followed by a count",
                        k + 1,
                        c as char
                    ),
                ));
            }
        }
    }

    // Start and Global sections.
    let start = s_lines
        .iter()
        .map(|(_, l)| String::from_utf8_lossy(&l[..72]).trim_end().to_string())
        .collect::<Vec<_>>()
        .join("\n");
    if g_lines.is_empty() {
        return Err(structure_err(name, "the file has no Global (G) section"));
    }
    let g_text: Vec<u8> = g_lines.iter().flat_map(|(_, l)| l[..72].to_vec()).collect();
    let global = Global::parse(&g_text).map_err(|(param, reason)| Error::Global {
        file: name.to_string(),
        param,
        reason,
    })?;

    // Directory entries.
    if d_lines.len() % 2 != 0 {
        return Err(line_err(
            name,
            d_lines.last().map_or(0, |l| l.0),
            format!(
                "the Directory Entry section has {} lines; entries take two lines each",
                d_lines.len()
            ),
        ));
    }
    let n = d_lines.len() / 2;
    let mut file = IgesFile {
        start,
        global,
        entities: Vec::with_capacity(n),
        warnings: Vec::new(),
        name: name.to_string(),
    };
    let (pd, rd) = (file.global.param_delim, file.global.record_delim);
    for k in 0..n {
        let id = DeId::from_index(k);
        let (l1, l2) = (d_lines[2 * k].1, d_lines[2 * k + 1].1);
        let raw_type = field_text(l1, 0);
        let entity_type: i32 = raw_type.trim().parse().map_err(|_| Error::Entity {
            file: name.to_string(),
            de: id.line(),
            entity_type: 0,
            problem: EntityProblem::DirectoryField {
                field: 1,
                name: FIELD_NAMES[0],
                reason: format!("'{}' is not an entity type number", raw_type.trim()),
            },
        })?;
        let ent_err = |problem| Error::Entity {
            file: name.to_string(),
            de: id.line(),
            entity_type,
            problem,
        };
        let (de, pd_line, pd_lines) = parse_de(l1, l2, entity_type, n).map_err(ent_err)?;
        // Parameter data lines.
        let first = pd_line as usize;
        let last = first + pd_lines as usize - 1;
        if last > p_lines.len() {
            return Err(ent_err(EntityProblem::DirectoryField {
                field: 14,
                name: FIELD_NAMES[13],
                reason: format!(
                    "parameter data P{first}..P{last} runs past the last P line P{}",
                    p_lines.len()
                ),
            }));
        }
        let mut text = Vec::with_capacity(64 * pd_lines as usize);
        for (_, l) in &p_lines[first - 1..last] {
            let back = String::from_utf8_lossy(&cols(l, 64, 72)).trim().to_string();
            let seq = parse_seq(l).unwrap_or(0);
            if back.parse::<u32>().ok() != Some(id.line()) {
                return Err(ent_err(EntityProblem::Syntax {
                    line: seq,
                    reason: format!(
                        "the back-pointer in columns 65-72 is '{back}', expected {}",
                        id.line()
                    ),
                }));
            }
            text.extend_from_slice(&cols(l, 0, 64));
        }
        let params = split(&text, pd, rd, 0).map_err(|e| {
            ent_err(match e.bad_token {
                Some(found) => EntityProblem::Param {
                    index: e.index,
                    expected: "a number".into(),
                    found,
                },
                None => EntityProblem::Syntax {
                    line: pd_line,
                    reason: format!("parameter {}: {}", e.index, e.reason),
                },
            })
        })?;
        match params.first() {
            Some(Param::Int(t)) if *t == entity_type as i64 => {}
            other => {
                return Err(ent_err(EntityProblem::Param {
                    index: 0,
                    expected: format!("the entity type {entity_type}"),
                    found: other.map_or("nothing".into(), Param::describe),
                }));
            }
        }
        let (entity, extra) = Entity::decode(entity_type, de.form, &params, n).map_err(ent_err)?;
        if !SUPPORTED_TYPES.contains(&entity_type) {
            file.warnings.push(Warning {
                de: id,
                entity_type,
                message: format!(
                    "entity type {entity_type} (form {}) is not supported; kept as {} raw parameters",
                    de.form,
                    params.len() - 1
                ),
            });
        }
        file.entities.push(EntityRecord {
            de,
            entity,
            extra,
            layout: Some(Layout {
                de_line: id.line(),
                pd_line,
                pd_lines,
            }),
        });
    }
    // Directory transformation pointers must name 124 entities.
    for k in 0..n {
        let id = DeId::from_index(k);
        if let Some(t) = file.entities[k].de.transform {
            let ty = file.entities[t.index()].de.entity_type;
            if ty != 124 {
                return Err(file.entity_error(
                    id,
                    EntityProblem::DirectoryField {
                        field: 7,
                        name: FIELD_NAMES[6],
                        reason: format!("D{} is of type {ty}, not 124", t.line()),
                    },
                ));
            }
        }
    }
    Ok(file)
}

/// The text of directory field `k` (0-based, 0..9) of a directory line.
fn field_text(line: &[u8], k: usize) -> String {
    String::from_utf8_lossy(&cols(line, 8 * k, 8 * k + 8)).into_owned()
}

/// Parses the two directory lines. Returns the entry, the parameter data pointer and the
/// parameter line count.
fn parse_de(
    l1: &[u8],
    l2: &[u8],
    entity_type: i32,
    n: usize,
) -> Result<(DirectoryEntry, u32, u32), EntityProblem> {
    let int = |line: &[u8], k: usize, field: usize| -> Result<i64, EntityProblem> {
        let t = field_text(line, k);
        let t = t.trim();
        if t.is_empty() {
            return Ok(0);
        }
        t.parse().map_err(|_| EntityProblem::DirectoryField {
            field,
            name: FIELD_NAMES[field - 1],
            reason: format!("'{t}' is not an integer"),
        })
    };
    let t2 = int(l2, 0, 11)?;
    if t2 != entity_type as i64 {
        return Err(EntityProblem::DirectoryField {
            field: 11,
            name: FIELD_NAMES[10],
            reason: format!("the second line says type {t2}"),
        });
    }
    let pd_pointer = int(l1, 1, 2)?;
    let pd_count = int(l2, 3, 14)?;
    if pd_pointer < 1 || pd_pointer > u32::MAX as i64 / 2 {
        return Err(EntityProblem::DirectoryField {
            field: 2,
            name: FIELD_NAMES[1],
            reason: format!("{pd_pointer} is not a P line number"),
        });
    }
    if pd_count < 1 || pd_count > u32::MAX as i64 / 2 {
        return Err(EntityProblem::DirectoryField {
            field: 14,
            name: FIELD_NAMES[13],
            reason: format!("{pd_count} is not a valid number of P lines"),
        });
    }
    let tp = int(l1, 6, 7)?;
    let transform = if tp == 0 {
        None
    } else {
        Some(
            DeId::from_pointer(tp, n).ok_or_else(|| EntityProblem::DirectoryField {
                field: 7,
                name: FIELD_NAMES[6],
                reason: format!("pointer {tp} does not name a directory entry"),
            })?,
        )
    };
    let status_text = field_text(l1, 8);
    let status = Status::parse(&status_text).ok_or_else(|| EntityProblem::DirectoryField {
        field: 9,
        name: FIELD_NAMES[8],
        reason: format!("'{}' is not an 8-digit status number", status_text.trim()),
    })?;
    let form = int(l2, 4, 15)?;
    let form = i32::try_from(form).map_err(|_| EntityProblem::DirectoryField {
        field: 15,
        name: FIELD_NAMES[14],
        reason: format!("{form} is out of range"),
    })?;
    let de = DirectoryEntry {
        entity_type,
        structure: int(l1, 2, 3)?,
        line_font: int(l1, 3, 4)?,
        level: int(l1, 4, 5)?,
        view: int(l1, 5, 6)?,
        transform,
        label_display: int(l1, 7, 8)?,
        status,
        line_weight: int(l2, 1, 12)?,
        color: int(l2, 2, 13)?,
        form,
        label: field_text(l2, 7).trim().to_string(),
        subscript: int(l2, 8, 19)?,
    };
    Ok((de, pd_pointer as u32, pd_count as u32))
}
