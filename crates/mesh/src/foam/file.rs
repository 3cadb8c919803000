//! One OpenFOAM file: the `FoamFile` header dictionary and the lists that follow it, in
//! ASCII or binary (`format`), with the label and scalar widths and byte order of the
//! header's `arch` (`"LSB;label=32;scalar=64"`; absent means that). Gzipped files
//! (`points.gz`) are read transparently.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::error::{Error, Location, Result};
use crate::text::{parse_f64, parse_i64, reserve_capped};

/// A file's data layout, from its header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Layout {
    /// `format binary` (else ASCII).
    pub binary: bool,
    /// Bytes of a label: 4 (`label=32`) or 8 (`label=64`).
    pub label_bytes: u8,
    /// Bytes of a scalar: 4 (`scalar=32`) or 8 (`scalar=64`).
    pub scalar_bytes: u8,
    /// Big-endian binary (`arch "MSB;…"`).
    pub msb: bool,
}

/// A file read into memory, with its header parsed and a cursor after the header.
pub(crate) struct FoamFile {
    /// The path (for messages).
    pub name: String,
    /// The (decompressed) bytes.
    pub bytes: Vec<u8>,
    /// The layout of its data.
    pub layout: Layout,
    /// The header's `class`.
    pub class: String,
    /// The cursor.
    pub pos: usize,
}

/// The path of `dir/name` or, failing that, `dir/name.gz`; `None` when neither exists.
pub(crate) fn find(dir: &Path, name: &str) -> Option<PathBuf> {
    let p = dir.join(name);
    if p.is_file() {
        return Some(p);
    }
    let gz = dir.join(format!("{name}.gz"));
    gz.is_file().then_some(gz)
}

impl FoamFile {
    /// Reads `path` (gunzipped when its name ends in `.gz`) and parses its header.
    pub fn open(path: &Path) -> Result<FoamFile> {
        let name = path.display().to_string();
        let io = |error| Error::Io {
            file: name.clone(),
            error,
        };
        let raw = std::fs::read(path).map_err(io)?;
        let bytes = if path.extension().is_some_and(|e| e == "gz") {
            let mut out = Vec::new();
            flate2::read::MultiGzDecoder::new(&raw[..])
                .read_to_end(&mut out)
                .map_err(io)?;
            out
        } else {
            raw
        };
        Self::parse(bytes, name)
    }

    /// Parses the header of `bytes` (named `name` in messages).
    pub fn parse(bytes: Vec<u8>, name: String) -> Result<FoamFile> {
        let mut f = FoamFile {
            name,
            bytes,
            layout: Layout {
                binary: false,
                label_bytes: 4,
                scalar_bytes: 8,
                msb: false,
            },
            class: String::new(),
            pos: 0,
        };
        match f.word()? {
            Some(w) if w == b"FoamFile" => {}
            _ => return Err(f.err("expected the FoamFile header")),
        }
        f.expect(b'{')?;
        let mut arch = String::new();
        let mut format = String::new();
        loop {
            f.skip_blank();
            if f.peek() == Some(b'}') {
                f.pos += 1;
                break;
            }
            let key = f.word_or("header ends inside FoamFile")?;
            let key = String::from_utf8_lossy(key).into_owned();
            let value = f.header_value()?;
            match key.as_str() {
                "format" => format = value,
                "class" => f.class = value,
                "arch" => arch = value,
                _ => {}
            }
        }
        match format.as_str() {
            "ascii" => {}
            "binary" => f.layout.binary = true,
            other => {
                return Err(f.err(format!(
                    "format {other:?} in the header (expected ascii or binary)"
                )));
            }
        }
        for part in arch.split(';') {
            let part = part.trim();
            match part {
                "MSB" => f.layout.msb = true,
                "LSB" | "" => {}
                "label=32" => f.layout.label_bytes = 4,
                "label=64" => f.layout.label_bytes = 8,
                "scalar=32" => f.layout.scalar_bytes = 4,
                "scalar=64" => f.layout.scalar_bytes = 8,
                _ => return Err(f.err(format!("arch {arch:?}: unknown part {part:?}"))),
            }
        }
        Ok(f)
    }

    /// A syntax error at the cursor (line in ASCII, byte offset inside binary data).
    pub fn err(&self, msg: impl Into<String>) -> Error {
        Error::Syntax {
            file: self.name.clone(),
            at: self.location(self.pos),
            msg: msg.into(),
        }
    }

    /// The location of byte `pos`: its line.
    pub fn location(&self, pos: usize) -> Location {
        let end = pos.min(self.bytes.len());
        Location::Line(1 + self.bytes[..end].iter().filter(|&&c| c == b'\n').count())
    }

    fn peek(&self) -> Option<u8> {
        self.bytes.get(self.pos).copied()
    }

    /// Skips white space and `//` and `/* */` comments.
    pub fn skip_blank(&mut self) {
        let b = &self.bytes;
        loop {
            while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
            if b[self.pos..].starts_with(b"//") {
                while self.pos < b.len() && b[self.pos] != b'\n' {
                    self.pos += 1;
                }
            } else if b[self.pos..].starts_with(b"/*") {
                match b[self.pos + 2..].windows(2).position(|w| w == b"*/") {
                    Some(k) => self.pos += 2 + k + 2,
                    None => self.pos = b.len(),
                }
            } else {
                return;
            }
        }
    }

    /// The span of the next word (letters, digits and `_.:<>+-,#`), after blanks; `None` at
    /// the end.
    fn span(&mut self) -> Result<Option<std::ops::Range<usize>>> {
        self.skip_blank();
        let start = self.pos;
        let b = &self.bytes;
        while self.pos < b.len()
            && (b[self.pos].is_ascii_alphanumeric() || b"_.:<>+-,#".contains(&b[self.pos]))
        {
            self.pos += 1;
        }
        if self.pos == start {
            if self.pos == b.len() {
                return Ok(None);
            }
            return Err(self.err(format!(
                "unexpected {:?}",
                char::from(b[self.pos]).to_string()
            )));
        }
        Ok(Some(start..self.pos))
    }

    /// The next word; `None` at the end.
    pub fn word(&mut self) -> Result<Option<&[u8]>> {
        Ok(self.span()?.map(|r| &self.bytes[r]))
    }

    /// The next word; at the end, the error `msg`.
    pub fn word_or(&mut self, msg: &str) -> Result<&[u8]> {
        match self.span()? {
            Some(r) => Ok(&self.bytes[r]),
            None => Err(self.err(msg)),
        }
    }

    /// The next word or double-quoted string (quotes removed); at the end, the error `msg`.
    pub fn name_or(&mut self, msg: &str) -> Result<String> {
        self.skip_blank();
        if self.peek() == Some(b'"') {
            let start = self.pos + 1;
            match self.bytes[start..].iter().position(|&c| c == b'"') {
                Some(k) => {
                    self.pos = start + k + 1;
                    return Ok(String::from_utf8_lossy(&self.bytes[start..start + k]).into_owned());
                }
                None => return Err(self.err("unterminated string")),
            }
        }
        Ok(String::from_utf8_lossy(self.word_or(msg)?).into_owned())
    }

    /// Expects the character `c` after blanks.
    pub fn expect(&mut self, c: u8) -> Result<()> {
        self.skip_blank();
        if self.peek() == Some(c) {
            self.pos += 1;
            Ok(())
        } else {
            let found = match self.peek() {
                Some(x) => format!("{:?}", char::from(x).to_string()),
                None => "the end of the file".into(),
            };
            Err(self.err(format!(
                "expected {:?}, found {found}",
                char::from(c).to_string()
            )))
        }
    }

    /// A header value up to `;` (quotes removed).
    fn header_value(&mut self) -> Result<String> {
        self.skip_blank();
        let start = self.pos;
        let b = &self.bytes;
        let mut quoted = false;
        while self.pos < b.len() && (quoted || (b[self.pos] != b';' && b[self.pos] != b'}')) {
            quoted ^= b[self.pos] == b'"';
            self.pos += 1;
        }
        if self.peek() != Some(b';') {
            return Err(self.err("expected ';' after a header entry"));
        }
        let v = String::from_utf8_lossy(&b[start..self.pos])
            .trim()
            .trim_matches('"')
            .to_string();
        self.pos += 1;
        Ok(v)
    }

    /// Skips one value of a dictionary entry (up to its `;` at depth 0, or a `{…}` block).
    pub fn skip_value(&mut self) -> Result<()> {
        let mut depth = 0i32;
        loop {
            self.skip_blank();
            let Some(c) = self.peek() else {
                return Err(self.err("file ends inside an entry"));
            };
            match c {
                b'"' => {
                    self.pos += 1;
                    while self.peek().is_some_and(|c| c != b'"') {
                        self.pos += 1;
                    }
                    self.pos += 1;
                    continue;
                }
                b'(' | b'{' | b'[' => depth += 1,
                b')' | b'}' | b']' => {
                    depth -= 1;
                    if depth < 0 {
                        return Err(self.err("unbalanced bracket in an entry"));
                    }
                    if depth == 0 && c == b'}' {
                        self.pos += 1;
                        return Ok(());
                    }
                }
                b';' if depth == 0 => {
                    self.pos += 1;
                    return Ok(());
                }
                _ => {}
            }
            self.pos += 1;
        }
    }

    /// The count that opens a list.
    pub fn count(&mut self) -> Result<usize> {
        let at = self.pos;
        let w = self.word_or("file ends before a list")?;
        match parse_i64(w).and_then(|n| usize::try_from(n).ok()) {
            Some(n) => Ok(n),
            None => {
                let w = String::from_utf8_lossy(w).into_owned();
                self.pos = at;
                Err(self.err(format!("expected a list size, found {w:?}")))
            }
        }
    }

    /// A list of labels: `N ( … )` in the file's format, or `N{v}` (uniform).
    pub fn labels(&mut self, what: &str) -> Result<Vec<i64>> {
        let n = self.count()?;
        self.skip_blank();
        if self.peek() == Some(b'{') {
            self.pos += 1;
            let v = self.ascii_label(what)?;
            self.expect(b'}')?;
            return Ok(vec![v; n]);
        }
        self.expect(b'(')?;
        let mut out = Vec::new();
        reserve_capped(&mut out, n);
        if self.layout.binary {
            let w = usize::from(self.layout.label_bytes);
            let raw = self.binary_block(n, w, what)?.to_vec();
            for c in raw.chunks_exact(w) {
                out.push(self.label_bytes(c));
            }
        } else {
            for _ in 0..n {
                out.push(self.ascii_label(what)?);
            }
        }
        self.expect(b')')
            .map_err(|_| self.err(format!("{what}: more than {n} entries")))?;
        Ok(out)
    }

    fn label_bytes(&self, c: &[u8]) -> i64 {
        match (c.len(), self.layout.msb) {
            (4, false) => i64::from(i32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            (4, true) => i64::from(i32::from_be_bytes([c[0], c[1], c[2], c[3]])),
            (_, false) => i64::from_le_bytes(c.try_into().unwrap_or([0; 8])),
            (_, true) => i64::from_be_bytes(c.try_into().unwrap_or([0; 8])),
        }
    }

    fn scalar_bytes(&self, c: &[u8]) -> f64 {
        match (c.len(), self.layout.msb) {
            (4, false) => f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            (4, true) => f64::from(f32::from_be_bytes([c[0], c[1], c[2], c[3]])),
            (_, false) => f64::from_le_bytes(c.try_into().unwrap_or([0; 8])),
            (_, true) => f64::from_be_bytes(c.try_into().unwrap_or([0; 8])),
        }
    }

    /// `n` items of `w` bytes of binary data at the cursor.
    fn binary_block(&mut self, n: usize, w: usize, what: &str) -> Result<&[u8]> {
        let len = n.saturating_mul(w);
        if self.bytes.len() - self.pos < len {
            return Err(Error::Truncated {
                file: self.name.clone(),
                at: Location::Byte(self.bytes.len() as u64),
                what: format!("{what} ({n} binary entries of {w} bytes)"),
            });
        }
        let start = self.pos;
        self.pos += len;
        Ok(&self.bytes[start..start + len])
    }

    pub fn ascii_label(&mut self, what: &str) -> Result<i64> {
        let at = self.pos;
        let w = self.word_or(&format!("file ends inside {what}"))?;
        match parse_i64(w) {
            Some(v) => Ok(v),
            None => {
                let w = String::from_utf8_lossy(w).into_owned();
                self.pos = at;
                self.skip_blank();
                Err(self.err(format!("{what}: {w:?} is not a label")))
            }
        }
    }

    pub fn ascii_scalar(&mut self, what: &str) -> Result<f64> {
        let at = self.pos;
        let w = self.word_or(&format!("file ends inside {what}"))?;
        match parse_f64(w).filter(|v| v.is_finite()) {
            Some(v) => Ok(v),
            None => {
                let w = String::from_utf8_lossy(w).into_owned();
                self.pos = at;
                self.skip_blank();
                Err(self.err(format!("{what}: {w:?} is not a finite number")))
            }
        }
    }

    /// A list of scalars `N ( … )`, or `N{v}`.
    pub fn scalars(&mut self, what: &str) -> Result<Vec<f64>> {
        let n = self.count()?;
        self.skip_blank();
        if self.peek() == Some(b'{') {
            self.pos += 1;
            let v = self.ascii_scalar(what)?;
            self.expect(b'}')?;
            return Ok(vec![v; n]);
        }
        self.expect(b'(')?;
        let mut out = Vec::new();
        reserve_capped(&mut out, n);
        if self.layout.binary {
            let w = usize::from(self.layout.scalar_bytes);
            let raw = self.binary_block(n, w, what)?.to_vec();
            out.extend(raw.chunks_exact(w).map(|c| self.scalar_bytes(c)));
        } else {
            for _ in 0..n {
                out.push(self.ascii_scalar(what)?);
            }
        }
        self.expect(b')')
            .map_err(|_| self.err(format!("{what}: more than {n} entries")))?;
        Ok(out)
    }

    /// A list of vectors `N ( (x y z) … )` (binary: 3 scalars each), or `N{(x y z)}`.
    pub fn vectors(&mut self, what: &str) -> Result<Vec<[f64; 3]>> {
        let n = self.count()?;
        self.skip_blank();
        if self.peek() == Some(b'{') {
            self.pos += 1;
            let v = self.ascii_vector(what)?;
            self.expect(b'}')?;
            return Ok(vec![v; n]);
        }
        self.expect(b'(')?;
        let mut out = Vec::new();
        reserve_capped(&mut out, n);
        if self.layout.binary {
            let w = usize::from(self.layout.scalar_bytes);
            let raw = self.binary_block(n, 3 * w, what)?.to_vec();
            for c in raw.chunks_exact(3 * w) {
                out.push([
                    self.scalar_bytes(&c[..w]),
                    self.scalar_bytes(&c[w..2 * w]),
                    self.scalar_bytes(&c[2 * w..]),
                ]);
            }
        } else {
            for _ in 0..n {
                out.push(self.ascii_vector(what)?);
            }
        }
        self.expect(b')')
            .map_err(|_| self.err(format!("{what}: more than {n} entries")))?;
        Ok(out)
    }

    fn ascii_vector(&mut self, what: &str) -> Result<[f64; 3]> {
        self.expect(b'(')?;
        let v = [
            self.ascii_scalar(what)?,
            self.ascii_scalar(what)?,
            self.ascii_scalar(what)?,
        ];
        self.expect(b')')
            .map_err(|_| self.err(format!("{what}: a vector with more than 3 components")))?;
        Ok(v)
    }

    /// The faces: a `faceList` (`N ( k(a b …) … )`, ASCII) or a `faceCompactList` (offsets
    /// then labels, as binary files always have them), as CSR offsets and point labels.
    pub fn faces(&mut self) -> Result<(Vec<usize>, Vec<i64>)> {
        if self.class == "faceCompactList" {
            let offsets = self.labels("face offsets")?;
            let at = self.pos;
            let labels = self.labels("face points")?;
            let mut off = Vec::with_capacity(offsets.len());
            for (i, &o) in offsets.iter().enumerate() {
                let ok = usize::try_from(o)
                    .ok()
                    .filter(|&o| o <= labels.len() && off.last().is_none_or(|&l| o >= l));
                match ok {
                    Some(o) => off.push(o),
                    None => {
                        self.pos = at;
                        return Err(self.err(format!(
                            "face offset {i} is {o}: not increasing within 0..={}",
                            labels.len()
                        )));
                    }
                }
            }
            if off.first().is_some_and(|&o| o != 0) || off.last() != Some(&labels.len()) {
                return Err(self.err(format!(
                    "face offsets do not span the {} face points",
                    labels.len()
                )));
            }
            return Ok((off, labels));
        }
        if self.layout.binary {
            return Err(self.err(format!(
                "class {:?} in binary (OpenFOAM writes binary faces as faceCompactList)",
                self.class
            )));
        }
        let n = self.count()?;
        self.expect(b'(')?;
        let mut off = Vec::new();
        reserve_capped(&mut off, n + 1);
        off.push(0);
        let mut labels = Vec::new();
        reserve_capped(&mut labels, 4 * n);
        for i in 0..n {
            let k = self
                .count()
                .map_err(|_| self.err(format!("face {i}: expected its point count")))?;
            self.expect(b'(')?;
            for _ in 0..k {
                labels.push(self.ascii_label("a face")?);
            }
            self.expect(b')')
                .map_err(|_| self.err(format!("face {i}: more than {k} points")))?;
            off.push(labels.len());
        }
        self.expect(b')')
            .map_err(|_| self.err(format!("faces: more than {n} faces")))?;
        Ok((off, labels))
    }
}
