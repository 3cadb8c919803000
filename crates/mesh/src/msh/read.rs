//! Reading Gmsh MSH 4.1 (ASCII and binary): sections, entities, nodes with their
//! classification, elements; the grid assembled from them (see the module doc of `msh`).

use std::collections::{BTreeMap, HashMap};
use std::io::BufRead;
use std::path::Path;

use crate::error::{Error, Location, Result};
use crate::grid::{ElementKind, Elements, Entity, Marker, Mesh, NodeClass, PhysicalName};
use crate::text::{parse_f64, parse_i64, parse_u64, reserve_capped};

/// Input cursor: text lines with a token position, or raw bytes in binary sections.
struct Src<R> {
    r: R,
    file: String,
    binary: bool,
    swap: bool,
    line: usize,
    offset: u64,
    buf: Vec<u8>,
    pos: usize,
    warnings: Vec<String>,
}

impl<R: BufRead> Src<R> {
    fn at(&self) -> Location {
        if self.binary {
            Location::Byte(self.offset)
        } else {
            Location::Line(self.line)
        }
    }

    fn syntax(&self, msg: impl Into<String>) -> Error {
        Error::Syntax {
            file: self.file.clone(),
            at: self.at(),
            msg: msg.into(),
        }
    }

    fn truncated(&self, what: &str) -> Error {
        Error::Truncated {
            file: self.file.clone(),
            at: if self.binary {
                Location::Byte(self.offset)
            } else {
                Location::Line(self.line + 1)
            },
            what: what.to_string(),
        }
    }

    fn io(&self, source: std::io::Error) -> Error {
        Error::Io {
            file: self.file.clone(),
            error: source,
        }
    }

    /// Loads the next line into `buf`; false at the end of the input.
    fn load_line(&mut self) -> Result<bool> {
        self.buf.clear();
        self.pos = 0;
        let n = self
            .r
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| self.io(e))?;
        if n == 0 {
            return Ok(false);
        }
        self.offset += n as u64;
        self.line += 1;
        while matches!(self.buf.last(), Some(b'\n' | b'\r')) {
            self.buf.pop();
        }
        Ok(true)
    }

    /// The next non-blank line, trimmed, as text (section headers and names).
    fn next_text_line(&mut self) -> Result<Option<String>> {
        loop {
            if !self.load_line()? {
                return Ok(None);
            }
            let t = self.buf.trim_ascii();
            if !t.is_empty() {
                let s = String::from_utf8_lossy(t).into_owned();
                self.pos = self.buf.len();
                return Ok(Some(s));
            }
        }
    }

    /// The next whitespace-separated token (ASCII mode), as a byte range of `buf`.
    fn token(&mut self, what: &str) -> Result<(usize, usize)> {
        loop {
            let b = &self.buf;
            let mut i = self.pos;
            while i < b.len() && b[i].is_ascii_whitespace() {
                i += 1;
            }
            if i < b.len() {
                let start = i;
                while i < b.len() && !b[i].is_ascii_whitespace() {
                    i += 1;
                }
                self.pos = i;
                if b[start] == b'$' {
                    return Err(self.syntax(format!(
                        "section ends early: found '{}' while reading {what}",
                        String::from_utf8_lossy(&b[start..i])
                    )));
                }
                return Ok((start, i));
            }
            if !self.load_line()? {
                return Err(self.truncated(what));
            }
        }
    }

    fn bad_token(&self, (s, e): (usize, usize), what: &str, expected: &str) -> Error {
        self.syntax(format!(
            "{what}: expected {expected}, found '{}'",
            String::from_utf8_lossy(&self.buf[s..e.min(s + 40)])
        ))
    }

    fn bytes<const N: usize>(&mut self, what: &str) -> Result<[u8; N]> {
        let mut b = [0u8; N];
        self.r.read_exact(&mut b).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                self.truncated(what)
            } else {
                self.io(e)
            }
        })?;
        self.offset += N as u64;
        if self.swap {
            b.reverse();
        }
        Ok(b)
    }

    /// Fills `buf` with raw bytes (binary sections).
    fn raw(&mut self, buf: &mut [u8], what: &str) -> Result<()> {
        self.r.read_exact(buf).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                self.truncated(what)
            } else {
                self.io(e)
            }
        })?;
        self.offset += buf.len() as u64;
        Ok(())
    }

    /// A `size_t` (binary) or non-negative integer token.
    fn size(&mut self, what: &str) -> Result<u64> {
        if self.binary {
            Ok(u64::from_le_bytes(self.bytes::<8>(what)?))
        } else {
            let t = self.token(what)?;
            parse_u64(&self.buf[t.0..t.1])
                .ok_or_else(|| self.bad_token(t, what, "a non-negative integer"))
        }
    }

    /// A count that must fit in memory.
    fn count(&mut self, what: &str) -> Result<usize> {
        let v = self.size(what)?;
        usize::try_from(v)
            .ok()
            .filter(|&v| v < u32::MAX as usize)
            .ok_or_else(|| self.syntax(format!("{what}: count {v} is too large")))
    }

    /// An `int` (binary, 4 bytes) or integer token.
    fn int(&mut self, what: &str) -> Result<i32> {
        if self.binary {
            Ok(i32::from_le_bytes(self.bytes::<4>(what)?))
        } else {
            let t = self.token(what)?;
            parse_i64(&self.buf[t.0..t.1])
                .and_then(|v| i32::try_from(v).ok())
                .ok_or_else(|| self.bad_token(t, what, "a 32-bit integer"))
        }
    }

    /// A `double` (binary) or floating-point token; must be finite.
    fn float(&mut self, what: &str) -> Result<f64> {
        let v = if self.binary {
            f64::from_le_bytes(self.bytes::<8>(what)?)
        } else {
            let t = self.token(what)?;
            parse_f64(&self.buf[t.0..t.1]).ok_or_else(|| self.bad_token(t, what, "a number"))?
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.syntax(format!("{what}: non-finite value {v}")))
        }
    }

    /// Checks that the section ends here with `$End<name>`.
    fn end_section(&mut self, name: &str) -> Result<()> {
        if !self.binary {
            let rest = &self.buf[self.pos.min(self.buf.len())..];
            if !rest.trim_ascii().is_empty() {
                return Err(self.syntax(format!(
                    "unexpected data '{}' at the end of ${name} (wrong count?)",
                    String::from_utf8_lossy(&rest.trim_ascii()[..rest.trim_ascii().len().min(40)])
                )));
            }
        }
        let was_binary = self.binary;
        self.binary = false;
        let line = self.next_text_line()?;
        let ok = matches!(&line, Some(l) if l == &format!("$End{name}"));
        if !ok {
            let found = line.map_or("the end of the file".to_string(), |l| {
                format!("'{}'", &l[..l.len().min(40)])
            });
            return Err(self.syntax(format!("expected $End{name}, found {found} (wrong count?)")));
        }
        self.binary = was_binary;
        Ok(())
    }

    /// Skips an unknown section up to its `$End` line.
    fn skip_section(&mut self, name: &str) -> Result<()> {
        let start = self.line;
        let end = format!("$End{name}");
        let was_binary = self.binary;
        self.binary = false;
        loop {
            if !self.load_line()? {
                return Err(self.truncated(&format!("section ${name}")));
            }
            if self.buf.trim_ascii() == end.as_bytes() {
                break;
            }
        }
        self.binary = was_binary;
        self.warnings.push(format!(
            "{}: line {start}: section ${name} skipped (not interpreted)",
            self.file
        ));
        Ok(())
    }
}

/// Node tag → index map: dense when tags are compact, hashed otherwise.
enum TagMap {
    /// `idx[tag - min]`; grows with the tags actually read (up to `span`), so a corrupt
    /// header cannot make it allocate more than the file holds.
    Dense {
        min: u64,
        span: u64,
        idx: Vec<u32>,
    },
    Sparse(HashMap<u64, u32>),
}

impl TagMap {
    fn new(min: u64, max: u64, n: usize) -> Self {
        let span = max.saturating_sub(min).saturating_add(1);
        if max >= min && span <= 4 * n as u64 + 1024 {
            let mut idx = Vec::new();
            reserve_capped(&mut idx, (span as usize).min(1 << 20));
            TagMap::Dense { min, span, idx }
        } else {
            TagMap::Sparse(HashMap::new())
        }
    }

    /// Records `tag → i`; false if the tag was already used.
    fn insert(&mut self, tag: u64, i: u32) -> bool {
        match self {
            TagMap::Dense { min, span, idx } => {
                if tag < *min || tag - *min >= *span {
                    // Outside the announced range: fall back to a hash map.
                    let mut h: HashMap<u64, u32> = idx
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| **v != u32::MAX)
                        .map(|(k, v)| (*min + k as u64, *v))
                        .collect();
                    let fresh = h.insert(tag, i).is_none();
                    *self = TagMap::Sparse(h);
                    return fresh;
                }
                let k = (tag - *min) as usize;
                if k >= idx.len() {
                    let want = (k + 1).max(2 * idx.len()).min(*span as usize);
                    idx.resize(want, u32::MAX);
                }
                let slot = &mut idx[k];
                if *slot != u32::MAX {
                    return false;
                }
                *slot = i;
                true
            }
            TagMap::Sparse(h) => h.insert(tag, i).is_none(),
        }
    }

    fn get(&self, tag: u64) -> Option<u32> {
        match self {
            TagMap::Dense { min, idx, .. } => {
                if tag < *min {
                    return None;
                }
                idx.get((tag - *min) as usize)
                    .copied()
                    .filter(|&v| v != u32::MAX)
            }
            TagMap::Sparse(h) => h.get(&tag).copied(),
        }
    }
}

fn read_entities<R: BufRead>(src: &mut Src<R>, mesh: &mut Mesh) -> Result<()> {
    let mut counts = [0usize; 4];
    for (d, c) in counts.iter_mut().enumerate() {
        *c = src.count(&format!("$Entities: number of entities of dimension {d}"))?;
    }
    for (d, &c) in counts.iter().enumerate() {
        for i in 0..c {
            let what = format!("$Entities: entity {i} of dimension {d}");
            let tag = src.int(&what)?;
            let mut bbox = [0.0; 6];
            if d == 0 {
                for k in 0..3 {
                    bbox[k] = src.float(&what)?;
                    bbox[k + 3] = bbox[k];
                }
            } else {
                for b in &mut bbox {
                    *b = src.float(&what)?;
                }
            }
            let np = src.count(&what)?;
            let mut physical = Vec::with_capacity(np.min(64));
            for _ in 0..np {
                physical.push(src.int(&what)?);
            }
            let mut bounding = Vec::new();
            if d > 0 {
                let nb = src.count(&what)?;
                reserve_capped(&mut bounding, nb.min(1 << 16));
                for _ in 0..nb {
                    bounding.push(src.int(&what)?);
                }
            }
            mesh.entities.push(Entity {
                dim: d as u8,
                tag,
                bbox,
                physical,
                bounding,
            });
        }
    }
    src.end_section("Entities")
}

fn read_physical_names<R: BufRead>(src: &mut Src<R>, mesh: &mut Mesh) -> Result<()> {
    let was_binary = src.binary;
    src.binary = false;
    let n = src
        .next_text_line()?
        .ok_or_else(|| src.truncated("$PhysicalNames"))?;
    let n = parse_u64(n.as_bytes())
        .ok_or_else(|| src.syntax("$PhysicalNames: expected the number of names"))?;
    for i in 0..n {
        let l = src
            .next_text_line()?
            .ok_or_else(|| src.truncated("$PhysicalNames"))?;
        let mut it = l.splitn(3, char::is_whitespace);
        let dim = it
            .next()
            .and_then(|t| t.parse::<u8>().ok())
            .filter(|&d| d <= 3);
        let tag = it.next().and_then(|t| t.parse::<i32>().ok());
        let name = it.next().map(|t| t.trim().trim_matches('"').to_string());
        match (dim, tag, name) {
            (Some(dim), Some(tag), Some(name)) => {
                mesh.physical_names.push(PhysicalName { dim, tag, name })
            }
            _ => {
                return Err(src.syntax(format!(
                    "$PhysicalNames: name {i}: expected 'dim tag \"name\"', found '{l}'"
                )));
            }
        }
    }
    src.end_section("PhysicalNames")?;
    src.binary = was_binary;
    Ok(())
}

fn read_nodes<R: BufRead>(src: &mut Src<R>, mesh: &mut Mesh) -> Result<TagMap> {
    let nblocks = src.count("$Nodes header")?;
    let n = src.count("$Nodes header")?;
    let min = src.size("$Nodes header")?;
    let max = src.size("$Nodes header")?;
    let mut map = TagMap::new(min, max, n);
    reserve_capped(&mut mesh.coords, n);
    let mut classes: Vec<NodeClass> = Vec::new();
    reserve_capped(&mut classes, n);
    let mut tags: Vec<u64> = Vec::new();
    for b in 0..nblocks {
        let what = format!("$Nodes block {b}");
        let edim = src.int(&what)?;
        let etag = src.int(&what)?;
        let parametric = src.int(&what)?;
        let nb = src.count(&what)?;
        if !(0..=3).contains(&edim) || !(0..=1).contains(&parametric) {
            return Err(src.syntax(format!(
                "{what}: entity dimension {edim} / parametric flag {parametric} out of range"
            )));
        }
        if mesh.coords.len() + nb > n {
            return Err(src.syntax(format!("{what}: more nodes than the {n} announced")));
        }
        tags.clear();
        reserve_capped(&mut tags, nb);
        for _ in 0..nb {
            let t = src.size(&what)?;
            tags.push(t);
        }
        let n_param = if parametric == 1 { edim as usize } else { 0 };
        if parametric == 1 && (edim == 1 || edim == 2) {
            mesh.parametric = true;
        }
        for &t in &tags {
            let i = mesh.coords.len() as u32;
            if !map.insert(t, i) {
                return Err(src.syntax(format!("{what}: node tag {t} used twice")));
            }
            let mut p = [0.0; 3];
            for x in &mut p {
                *x = src.float(&what)?;
            }
            let mut param = [0.0; 2];
            for k in 0..n_param {
                let u = src.float(&what)?;
                if k < 2 {
                    param[k] = u;
                }
            }
            mesh.coords.push(p);
            classes.push(NodeClass {
                dim: edim as u8,
                entity: etag,
                param,
            });
        }
    }
    if mesh.coords.len() != n {
        return Err(src.syntax(format!(
            "$Nodes: {} nodes in the blocks, {n} announced",
            mesh.coords.len()
        )));
    }
    mesh.classes = Some(classes);
    src.end_section("Nodes")?;
    Ok(map)
}

/// Elements read, staged by dimension until the grid's dimension is known.
struct Staged {
    by_dim: [Elements; 4],
    points: usize,
}

fn read_elements<R: BufRead>(
    src: &mut Src<R>,
    map: &TagMap,
    n_nodes: usize,
    staged: &mut Staged,
) -> Result<()> {
    let nblocks = src.count("$Elements header")?;
    let n = src.count("$Elements header")?;
    let _min = src.size("$Elements header")?;
    let _max = src.size("$Elements header")?;
    let mut total = 0usize;
    let mut conn = [0u32; 8];
    for b in 0..nblocks {
        let what = format!("$Elements block {b}");
        let edim = src.int(&what)?;
        let etag = src.int(&what)?;
        let at = src.at();
        let etype = src.int(&what)?;
        let nb = src.count(&what)?;
        total += nb;
        if total > n {
            return Err(src.syntax(format!("{what}: more elements than the {n} announced")));
        }
        if etype == 15 {
            for _ in 0..nb {
                src.size(&what)?;
                src.size(&what)?;
            }
            staged.points += nb;
            continue;
        }
        let kind = ElementKind::from_gmsh_code(i64::from(etype)).ok_or_else(|| {
            Error::UnknownElementType {
                file: src.file.clone(),
                at,
                code: i64::from(etype),
            }
        })?;
        if i32::from(kind.dim()) != edim {
            return Err(src.syntax(format!(
                "{what}: {} elements on an entity of dimension {edim}",
                kind.name()
            )));
        }
        let set = &mut staged.by_dim[edim as usize];
        let g = set.group_mut(kind);
        reserve_capped(&mut g.nodes, nb.saturating_mul(kind.n_nodes()));
        reserve_capped(&mut g.entity, nb);
        let nn = kind.n_nodes();
        // Gmsh's local numbering to this crate's (the prism's differs).
        let order = kind.gmsh_order();
        if src.binary {
            // Binary: decode chunks of whole element records (tag + nodes, 8 bytes each).
            const CHUNK: usize = 4096;
            let rec = 8 * (1 + nn);
            let mut buf = vec![0u8; rec * CHUNK.min(nb)];
            let mut done = 0;
            while done < nb {
                let k = (nb - done).min(CHUNK);
                let start = src.offset;
                src.raw(&mut buf[..k * rec], &what)?;
                let g = staged.by_dim[edim as usize].group_mut(kind);
                for e in 0..k {
                    for (j, c) in conn.iter_mut().take(nn).enumerate() {
                        let off = e * rec + 8 * (1 + j);
                        let word: [u8; 8] = buf[off..off + 8].try_into().expect("8 bytes");
                        let t = if src.swap {
                            u64::from_be_bytes(word)
                        } else {
                            u64::from_le_bytes(word)
                        };
                        *c = map.get(t).ok_or_else(|| Error::NodeOutOfRange {
                            file: src.file.clone(),
                            at: Location::Byte(start + off as u64),
                            node: t,
                            n_nodes,
                        })?;
                    }
                    g.nodes.extend(order.iter().map(|&j| conn[j as usize]));
                    g.entity.push(etag);
                }
                done += k;
            }
            continue;
        }
        for _ in 0..nb {
            let _tag = src.size(&what)?;
            for c in conn.iter_mut().take(nn) {
                let at = src.at();
                let t = src.size(&what)?;
                *c = map.get(t).ok_or(Error::NodeOutOfRange {
                    file: src.file.clone(),
                    at,
                    node: t,
                    n_nodes,
                })?;
            }
            let g = staged.by_dim[edim as usize].group_mut(kind);
            g.nodes.extend(order.iter().map(|&j| conn[j as usize]));
            g.entity.push(etag);
        }
    }
    if total != n {
        return Err(src.syntax(format!(
            "$Elements: {total} elements in the blocks, {n} announced"
        )));
    }
    src.end_section("Elements")
}

/// Reads a Gmsh MSH 4.1 file (ASCII or binary) from `r`; `file` names the input in errors.
///
/// ```
/// let m = mesh::generate::box_tets(2, 2, 2, [0.0; 3], [1.0; 3]);
/// let mut buf = Vec::new();
/// mesh::msh::write(&m, mesh::msh::Encoding::Binary, &mut buf).unwrap();
/// let back = mesh::msh::read(&buf[..], "box.msh".as_ref()).unwrap();
/// assert_eq!(back.tets(), m.tets());
/// assert_eq!(back.marker("x_m").unwrap().elements.len(), 8);
/// ```
pub fn read<R: BufRead>(r: R, file: &Path) -> Result<Mesh> {
    let mut src = Src {
        r,
        file: file.display().to_string(),
        binary: false,
        swap: false,
        line: 0,
        offset: 0,
        buf: Vec::with_capacity(256),
        pos: 0,
        warnings: Vec::new(),
    };
    let mut mesh = Mesh::new(3);
    let mut map: Option<TagMap> = None;
    let mut staged = Staged {
        by_dim: Default::default(),
        points: 0,
    };
    let mut seen_format = false;
    let mut seen_elements = false;
    while let Some(h) = src.next_text_line()? {
        let Some(name) = h.strip_prefix('$') else {
            return Err(src.syntax(format!(
                "expected a section header ($Name), found '{}'",
                &h[..h.len().min(40)]
            )));
        };
        let name = name.to_string();
        if !seen_format && name != "MeshFormat" {
            return Err(src.syntax(format!("expected $MeshFormat first, found ${name}")));
        }
        match name.as_str() {
            "MeshFormat" => {
                let l = src
                    .next_text_line()?
                    .ok_or_else(|| src.truncated("$MeshFormat"))?;
                let f: Vec<&str> = l.split_whitespace().collect();
                if f.len() != 3 || f[0] != "4.1" || !(f[1] == "0" || f[1] == "1") {
                    return Err(src.syntax(format!(
                        "unsupported format '{l}': only MSH 4.1 (ASCII or binary) is read"
                    )));
                }
                if f[2] != "8" {
                    return Err(src.syntax(format!("data size {} not supported (only 8)", f[2])));
                }
                if f[1] == "1" {
                    src.binary = true;
                    let one = src.bytes::<4>("$MeshFormat endianness mark")?;
                    if i32::from_le_bytes(one) == 1 {
                        src.swap = false;
                    } else if i32::from_be_bytes(one) == 1 {
                        src.swap = true;
                    } else {
                        return Err(src.syntax("binary endianness mark is not 1"));
                    }
                }
                src.end_section("MeshFormat")?;
                seen_format = true;
            }
            "PhysicalNames" => read_physical_names(&mut src, &mut mesh)?,
            "Entities" => read_entities(&mut src, &mut mesh)?,
            "Nodes" => {
                if map.is_some() {
                    return Err(src.syntax("a second $Nodes section"));
                }
                map = Some(read_nodes(&mut src, &mut mesh)?);
            }
            "Elements" => {
                let Some(m) = &map else {
                    return Err(src.syntax("$Elements before $Nodes"));
                };
                if seen_elements {
                    return Err(src.syntax("a second $Elements section"));
                }
                read_elements(&mut src, m, mesh.coords.len(), &mut staged)?;
                seen_elements = true;
            }
            _ => src.skip_section(&name)?,
        }
    }
    if !seen_format || map.is_none() || !seen_elements {
        let what = if !seen_format {
            "the header ($MeshFormat missing)"
        } else if map.is_none() {
            "the grid ($Nodes missing)"
        } else {
            "the grid ($Elements missing)"
        };
        return Err(Error::Truncated {
            file: src.file.clone(),
            at: Location::End,
            what: what.into(),
        });
    }
    let file = src.file.clone();
    mesh.warnings.append(&mut src.warnings);
    assemble(&mut mesh, staged, &file)?;
    Ok(mesh)
}

/// Sorts staged elements into cells and markers.
fn assemble(mesh: &mut Mesh, mut staged: Staged, file: &str) -> Result<()> {
    let dim = (2..=3)
        .rev()
        .find(|&d| !staged.by_dim[d].is_empty())
        .ok_or_else(|| Error::Invalid {
            what: format!("{file}: no 2-D or 3-D elements"),
        })?;
    mesh.dim = dim as u8;
    mesh.cells = std::mem::take(&mut staged.by_dim[dim]);
    let mut dropped = staged.points;
    for d in 0..dim - 1 {
        dropped += staged.by_dim[d].len();
    }
    if dropped > 0 {
        mesh.warnings.push(format!(
            "{file}: {dropped} elements of dimension below {} (points, edges) dropped",
            dim - 1
        ));
    }
    let phys: HashMap<i32, &[i32]> = mesh
        .entities
        .iter()
        .filter(|e| usize::from(e.dim) == dim - 1)
        .map(|e| (e.tag, e.physical.as_slice()))
        .collect();
    // Marker key: Ok(physical tag) sorts before Err(entity tag).
    let mut markers: BTreeMap<std::result::Result<i32, i32>, Elements> = BTreeMap::new();
    let bnd = std::mem::take(&mut staged.by_dim[dim - 1]);
    for g in bnd.groups() {
        for (i, nodes) in g.iter().enumerate() {
            let e = g.entity[i];
            match phys.get(&e) {
                Some(p) if !p.is_empty() => {
                    for &t in *p {
                        markers
                            .entry(Ok(t))
                            .or_default()
                            .push(g.kind, nodes, Some(e));
                    }
                }
                _ => markers
                    .entry(Err(e))
                    .or_default()
                    .push(g.kind, nodes, Some(e)),
            }
        }
    }
    for (key, elements) in markers {
        let (name, tag) = match key {
            Ok(t) => {
                let name = mesh
                    .physical_names
                    .iter()
                    .find(|p| usize::from(p.dim) == dim - 1 && p.tag == t)
                    .map_or_else(|| format!("physical_{t}"), |p| p.name.clone());
                (name, Some(t))
            }
            Err(e) => (format!("entity_{e}"), None),
        };
        mesh.markers.push(Marker {
            name,
            tag,
            elements,
        });
    }
    Ok(())
}
