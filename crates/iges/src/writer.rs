//! Writing the fixed-format ASCII form with sequence numbers and back-pointers.

use std::io::Write;

use crate::directory::DeId;
use crate::error::{EntityProblem, Error, Result};
use crate::file::IgesFile;
use crate::param::{Param, format_param};

/// Wraps parameters into lines of `width` columns, each parameter followed by the
/// parameter delimiter and the last by the record delimiter. Numbers never straddle lines;
/// strings longer than the space left are split (readers join the lines' columns).
fn wrap(params: &[Param], pd: u8, rd: u8, width: usize) -> Vec<Vec<u8>> {
    let mut lines = vec![Vec::with_capacity(width)];
    for (k, p) in params.iter().enumerate() {
        let mut tok = format_param(p).into_bytes();
        tok.push(if k + 1 == params.len() { rd } else { pd });
        let cur = lines.last_mut().expect("at least one line");
        if cur.len() + tok.len() <= width {
            cur.extend_from_slice(&tok);
            continue;
        }
        if !matches!(p, Param::Str(_)) || tok.len() <= width {
            lines.push(tok);
            continue;
        }
        // A long string: fill the current line, then whole lines.
        let mut rest = &tok[..];
        loop {
            let cur = lines.last_mut().expect("at least one line");
            let room = width - cur.len();
            if rest.len() <= room {
                cur.extend_from_slice(rest);
                break;
            }
            cur.extend_from_slice(&rest[..room]);
            rest = &rest[room..];
            lines.push(Vec::with_capacity(width));
        }
    }
    lines
}

fn io(file: &str) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        file: file.to_string(),
        source,
    }
}

fn check_string(s: &str) -> bool {
    s.bytes().all(|b| (b' '..=b'~').contains(&b))
}

impl IgesFile {
    /// Writes the file in the fixed 80-column ASCII form. `name` is used in error messages.
    ///
    /// Checks before writing anything: pointers name entities of the file, transformation
    /// pointers name 124 entities, array lengths agree with their counts, strings and
    /// labels are printable ASCII and fit their fields.
    pub fn write(&self, mut w: impl Write, name: &str) -> Result<()> {
        let n = self.entities.len();
        let g = &self.global;
        let ent_err = |k: usize, reason: String| Error::Entity {
            file: name.to_string(),
            de: DeId::from_index(k).line(),
            entity_type: self.entities[k].de.entity_type,
            problem: EntityProblem::Write { reason },
        };
        // Parameter data, per entity.
        let mut pd_blocks = Vec::with_capacity(n);
        for (k, r) in self.entities.iter().enumerate() {
            if let Some(t) = r.entity.type_number()
                && t != r.de.entity_type
            {
                return Err(ent_err(
                    k,
                    format!(
                        "the entity is a {t} but its directory entry says {}",
                        r.de.entity_type
                    ),
                ));
            }
            for p in r.entity.pointers() {
                if p.index() >= n {
                    return Err(ent_err(k, format!("pointer {} names no entity", p.line())));
                }
            }
            if let Some(t) = r.de.transform
                && self.entities.get(t.index()).map(|e| e.de.entity_type) != Some(124)
            {
                return Err(ent_err(
                    k,
                    format!("transformation pointer {} does not name a 124", t.line()),
                ));
            }
            if !check_string(&r.de.label) || r.de.label.len() > 8 {
                return Err(ent_err(
                    k,
                    format!("label '{}' is not 8 ASCII characters", r.de.label),
                ));
            }
            let mut params = vec![Param::Int(r.de.entity_type as i64)];
            params.extend(r.entity.encode().map_err(|problem| Error::Entity {
                file: name.to_string(),
                de: DeId::from_index(k).line(),
                entity_type: r.de.entity_type,
                problem,
            })?);
            params.extend(r.extra.iter().cloned());
            for p in &params {
                match p {
                    Param::Str(s) if !check_string(s) => {
                        return Err(ent_err(k, format!("string '{s}' is not printable ASCII")));
                    }
                    Param::Real(x) if !x.is_finite() => {
                        return Err(ent_err(k, format!("non-finite real {x}")));
                    }
                    _ => {}
                }
            }
            pd_blocks.push(wrap(&params, g.param_delim, g.record_delim, 64));
        }
        // Start section.
        if !self.start.lines().all(check_string) {
            return Err(Error::Structure {
                file: name.to_string(),
                reason: "the start section is not printable ASCII".into(),
            });
        }
        let mut s_lines: Vec<Vec<u8>> = Vec::new();
        for l in self.start.lines() {
            let b = l.as_bytes();
            if b.is_empty() {
                s_lines.push(Vec::new());
            }
            s_lines.extend(b.chunks(72).map(<[u8]>::to_vec));
        }
        if s_lines.is_empty() {
            s_lines.push(Vec::new());
        }
        // Global section.
        let mut gp = vec![
            Param::Str((g.param_delim as char).to_string()),
            Param::Str((g.record_delim as char).to_string()),
        ];
        gp.extend(g.params());
        for (i, p) in gp.iter().enumerate() {
            if let Param::Str(s) = p
                && !check_string(s)
            {
                return Err(Error::Global {
                    file: name.to_string(),
                    param: i + 1,
                    reason: "string is not printable ASCII".into(),
                });
            }
        }
        let bad_delim = |c: u8| !c.is_ascii_graphic() || c.is_ascii_digit() || c == b'H';
        if g.param_delim == g.record_delim || bad_delim(g.param_delim) || bad_delim(g.record_delim)
        {
            return Err(Error::Global {
                file: name.to_string(),
                param: 1,
                reason: "unusable delimiters".into(),
            });
        }
        let g_lines = wrap(&gp, g.param_delim, g.record_delim, 72);

        let e = io(name);
        for (k, l) in s_lines.iter().enumerate() {
            record(&mut w, l, 72, b"", 'S', k + 1).map_err(&e)?;
        }
        for (k, l) in g_lines.iter().enumerate() {
            record(&mut w, l, 72, b"", 'G', k + 1).map_err(&e)?;
        }
        let mut pd_start = Vec::with_capacity(n);
        let mut next = 1usize;
        for b in &pd_blocks {
            pd_start.push(next);
            next += b.len();
        }
        for (k, r) in self.entities.iter().enumerate() {
            let d = &r.de;
            let seq = 2 * k + 1;
            let f = |v: i64| format!("{v:>8}");
            let l1 = [
                f(d.entity_type as i64),
                f(pd_start[k] as i64),
                f(d.structure),
                f(d.line_font),
                f(d.level),
                f(d.view),
                f(d.transform.map_or(0, |t| t.line() as i64)),
                f(d.label_display),
                d.status.format(),
            ];
            let l2 = [
                f(d.entity_type as i64),
                f(d.line_weight),
                f(d.color),
                f(pd_blocks[k].len() as i64),
                f(d.form as i64),
                " ".repeat(8),
                " ".repeat(8),
                format!("{:>8}", d.label),
                f(d.subscript),
            ];
            for (i, t) in l1.iter().chain(l2.iter()).enumerate() {
                if t.len() > 8 {
                    return Err(ent_err(
                        k,
                        format!("directory field {} value '{t}' exceeds 8 columns", i + 1),
                    ));
                }
            }
            record(&mut w, l1.concat().as_bytes(), 72, b"", 'D', seq).map_err(&e)?;
            record(&mut w, l2.concat().as_bytes(), 72, b"", 'D', seq + 1).map_err(&e)?;
        }
        for (k, b) in pd_blocks.iter().enumerate() {
            let back = format!("{:>8}", 2 * k + 1);
            for (j, l) in b.iter().enumerate() {
                record(&mut w, l, 64, back.as_bytes(), 'P', pd_start[k] + j).map_err(&e)?;
            }
        }
        let t = format!(
            "S{:>7}G{:>7}D{:>7}P{:>7}",
            s_lines.len(),
            g_lines.len(),
            2 * n,
            next - 1
        );
        record(&mut w, t.as_bytes(), 72, b"", 'T', 1).map_err(&e)?;
        w.flush().map_err(&e)
    }
}

/// Writes one 80-column record: `data` padded to `width`, then `extra` (the back-pointer
/// field of P lines), the section letter and the sequence number.
fn record(
    w: &mut impl Write,
    data: &[u8],
    width: usize,
    extra: &[u8],
    letter: char,
    seq: usize,
) -> std::io::Result<()> {
    w.write_all(data)?;
    for _ in data.len()..width {
        w.write_all(b" ")?;
    }
    w.write_all(extra)?;
    writeln!(w, "{letter}{seq:>7}")
}
