//! The Part 21 syntax (ISO 10303-21 clear text encoding): tokens, records, instances and the
//! sections of an exchange structure, by recursive descent over the bytes with line
//! counting.

use crate::error::{Error, Result};
use crate::value::{Id, Instance, Record, Value};

/// Lists may nest this deep (B-spline surfaces need 2; corrupt files may ask for more).
const MAX_DEPTH: usize = 32;

/// The sections of an exchange structure, before typing.
pub(crate) struct Exchange {
    /// The header section's records (FILE_DESCRIPTION, FILE_NAME, FILE_SCHEMA, …).
    pub header: Vec<Record>,
    /// The instances of every data section, in file order.
    pub instances: Vec<Instance>,
}

pub(crate) struct Parser<'a> {
    b: &'a [u8],
    i: usize,
    line: usize,
    file: &'a str,
}

impl<'a> Parser<'a> {
    pub(crate) fn new(b: &'a [u8], file: &'a str) -> Self {
        Parser {
            b,
            i: 0,
            line: 1,
            file,
        }
    }

    fn err(&self, reason: impl Into<String>) -> Error {
        Error::Syntax {
            file: self.file.to_string(),
            line: self.line,
            reason: reason.into(),
        }
    }

    fn bump(&mut self) -> Option<u8> {
        let c = *self.b.get(self.i)?;
        self.i += 1;
        if c == b'\n' {
            self.line += 1;
        }
        Some(c)
    }

    /// Skips blanks, line ends and `/* … */` comments.
    fn skip(&mut self) -> Result<()> {
        loop {
            match self.b.get(self.i) {
                Some(b' ' | b'\t' | b'\r' | b'\n' | b'\x0c') => {
                    self.bump();
                }
                Some(b'/') if self.b.get(self.i + 1) == Some(&b'*') => {
                    let start = self.line;
                    self.i += 2;
                    loop {
                        match self.bump() {
                            Some(b'*') if self.b.get(self.i) == Some(&b'/') => {
                                self.i += 1;
                                break;
                            }
                            Some(_) => {}
                            None => {
                                return Err(Error::Syntax {
                                    file: self.file.to_string(),
                                    line: start,
                                    reason: "the comment opened here is never closed".into(),
                                });
                            }
                        }
                    }
                }
                _ => return Ok(()),
            }
        }
    }

    fn peek(&mut self) -> Result<Option<u8>> {
        self.skip()?;
        Ok(self.b.get(self.i).copied())
    }

    fn found(&self) -> String {
        match self.b.get(self.i) {
            None => "the end of the file".into(),
            Some(_) => {
                let end = (self.i + 12).min(self.b.len());
                let s = String::from_utf8_lossy(&self.b[self.i..end]);
                let s = s.split(['\n', '\r']).next().unwrap_or("");
                format!("'{s}'")
            }
        }
    }

    fn expect(&mut self, c: u8) -> Result<()> {
        if self.peek()? == Some(c) {
            self.bump();
            Ok(())
        } else {
            Err(self.err(format!("expected '{}', found {}", c as char, self.found())))
        }
    }

    /// A literal word such as `ISO-10303-21` or `ENDSEC` (case-insensitive).
    fn word(&mut self, w: &str) -> Result<bool> {
        self.skip()?;
        let end = self.i + w.len();
        let ok = self
            .b
            .get(self.i..end)
            .is_some_and(|s| s.eq_ignore_ascii_case(w.as_bytes()))
            && !self
                .b
                .get(end)
                .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_' || *c == b'-');
        if ok {
            self.i = end;
        }
        Ok(ok)
    }

    fn expect_word(&mut self, w: &str) -> Result<()> {
        if self.word(w)? {
            Ok(())
        } else {
            Err(self.err(format!("expected {w}, found {}", self.found())))
        }
    }

    /// A standard (`NAME`) or user-defined (`!NAME`) keyword, returned upper case.
    fn keyword(&mut self) -> Result<String> {
        self.skip()?;
        let start = self.i;
        if self.b.get(self.i) == Some(&b'!') {
            self.i += 1;
        }
        match self.b.get(self.i) {
            Some(c) if c.is_ascii_alphabetic() || *c == b'_' => {}
            _ => return Err(self.err(format!("expected a keyword, found {}", self.found()))),
        }
        while self
            .b
            .get(self.i)
            .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_' || *c == b'-')
        {
            self.i += 1;
        }
        Ok(String::from_utf8_lossy(&self.b[start..self.i]).to_ascii_uppercase())
    }

    fn number(&mut self) -> Result<Value> {
        let start = self.i;
        if matches!(self.b.get(self.i), Some(b'+' | b'-')) {
            self.i += 1;
        }
        let digits = |p: &mut Self| {
            let s = p.i;
            while p.b.get(p.i).is_some_and(u8::is_ascii_digit) {
                p.i += 1;
            }
            p.i > s
        };
        if !digits(self) {
            self.i = start;
            return Err(self.err(format!("expected a number, found {}", self.found())));
        }
        let mut real = false;
        if self.b.get(self.i) == Some(&b'.') {
            self.i += 1;
            digits(self);
            real = true;
        }
        if matches!(self.b.get(self.i), Some(b'E' | b'e')) {
            let save = self.i;
            self.i += 1;
            if matches!(self.b.get(self.i), Some(b'+' | b'-')) {
                self.i += 1;
            }
            if digits(self) {
                real = true;
            } else {
                self.i = save;
            }
        }
        let text = std::str::from_utf8(&self.b[start..self.i]).unwrap_or("");
        if real {
            match text.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(Value::Real(x)),
                _ => {
                    self.i = start;
                    Err(self.err(format!("the real {text} is out of range")))
                }
            }
        } else {
            text.parse::<i64>().map(Value::Int).map_err(|_| {
                self.i = start;
                self.err(format!("the integer {text} is out of range"))
            })
        }
    }

    fn string(&mut self) -> Result<Value> {
        let start_line = self.line;
        self.bump(); // opening quote
        let mut raw = Vec::new();
        loop {
            match self.bump() {
                Some(b'\'') => {
                    if self.b.get(self.i) == Some(&b'\'') {
                        self.i += 1;
                        raw.push(b'\'');
                    } else {
                        break;
                    }
                }
                // Line ends inside a string are layout, not content.
                Some(b'\n' | b'\r') => {}
                Some(c) => raw.push(c),
                None => {
                    return Err(Error::Syntax {
                        file: self.file.to_string(),
                        line: start_line,
                        reason: "the string opened here is never closed".into(),
                    });
                }
            }
        }
        Ok(Value::Str(decode_string(&raw)))
    }

    fn value(&mut self, depth: usize) -> Result<Value> {
        if depth > MAX_DEPTH {
            return Err(self.err(format!("lists nest more than {MAX_DEPTH} deep")));
        }
        let Some(c) = self.peek()? else {
            return Err(self.err("the file ends inside a record"));
        };
        Ok(match c {
            b'$' => {
                self.bump();
                Value::Unset
            }
            b'*' => {
                self.bump();
                Value::Derived
            }
            b'#' => {
                self.bump();
                Value::Ref(self.id_digits()?)
            }
            b'\'' => self.string()?,
            b'"' => {
                self.bump();
                let start = self.i;
                while self.b.get(self.i).is_some_and(|c| c.is_ascii_hexdigit()) {
                    self.i += 1;
                }
                let s = String::from_utf8_lossy(&self.b[start..self.i]).into_owned();
                self.expect(b'"')?;
                Value::Binary(s)
            }
            b'.' if self
                .b
                .get(self.i + 1)
                .is_some_and(|c| c.is_ascii_alphabetic()) =>
            {
                self.bump();
                let start = self.i;
                while self
                    .b
                    .get(self.i)
                    .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
                {
                    self.i += 1;
                }
                let s = String::from_utf8_lossy(&self.b[start..self.i]).to_ascii_uppercase();
                if self.b.get(self.i) != Some(&b'.') {
                    return Err(self.err(format!(
                        "the enumeration .{s} is not closed by '.', found {}",
                        self.found()
                    )));
                }
                self.i += 1;
                Value::Enum(s)
            }
            b'(' => {
                self.bump();
                Value::List(self.list_rest(depth)?)
            }
            b'+' | b'-' | b'0'..=b'9' => self.number()?,
            c if c.is_ascii_alphabetic() || c == b'!' => {
                let k = self.keyword()?;
                self.expect(b'(')?;
                let v = self.value(depth + 1)?;
                self.expect(b')')?;
                Value::Typed(k, Box::new(v))
            }
            _ => return Err(self.err(format!("expected a parameter, found {}", self.found()))),
        })
    }

    /// The items of a list after its `(`, through its `)`.
    fn list_rest(&mut self, depth: usize) -> Result<Vec<Value>> {
        let mut out = Vec::new();
        if self.peek()? == Some(b')') {
            self.bump();
            return Ok(out);
        }
        loop {
            out.push(self.value(depth + 1)?);
            match self.peek()? {
                Some(b',') => {
                    self.bump();
                }
                Some(b')') => {
                    self.bump();
                    return Ok(out);
                }
                _ => {
                    return Err(self.err(format!("expected ',' or ')', found {}", self.found())));
                }
            }
        }
    }

    fn id_digits(&mut self) -> Result<Id> {
        let start = self.i;
        while self.b.get(self.i).is_some_and(u8::is_ascii_digit) {
            self.i += 1;
        }
        std::str::from_utf8(&self.b[start..self.i])
            .ok()
            .and_then(|s| s.parse::<u64>().ok())
            .map(Id)
            .ok_or_else(|| {
                self.i = start;
                self.err(format!(
                    "expected an instance name #<digits>, found {}",
                    self.found()
                ))
            })
    }

    fn record(&mut self) -> Result<Record> {
        let name = self.keyword()?;
        self.expect(b'(')?;
        let params = self.list_rest(0)?;
        Ok(Record { name, params })
    }

    fn instance(&mut self) -> Result<Instance> {
        self.skip()?;
        let line = self.line;
        self.expect(b'#')?;
        let id = self.id_digits()?;
        self.expect(b'=')?;
        let records = if self.peek()? == Some(b'(') {
            self.bump();
            let mut v = Vec::new();
            while self.peek()? != Some(b')') {
                v.push(self.record()?);
            }
            self.bump();
            if v.is_empty() {
                return Err(self.err(format!("{id}: complex instance without records")));
            }
            v
        } else {
            vec![self.record()?]
        };
        self.expect(b';')?;
        Ok(Instance { id, line, records })
    }

    /// The whole exchange structure.
    pub(crate) fn exchange(&mut self) -> Result<Exchange> {
        // A UTF-8 byte order mark is tolerated.
        if self.b.starts_with(&[0xEF, 0xBB, 0xBF]) {
            self.i = 3;
        }
        if !self.word("ISO-10303-21")? {
            return Err(self.err(format!(
                "expected ISO-10303-21; (not a STEP Part 21 file?), found {}",
                self.found()
            )));
        }
        self.expect(b';')?;
        self.expect_word("HEADER")?;
        self.expect(b';')?;
        let mut header = Vec::new();
        while !self.word("ENDSEC")? {
            header.push(self.record()?);
            self.expect(b';')?;
        }
        self.expect(b';')?;
        // ANCHOR and REFERENCE sections (Part 21 edition 3) are skipped.
        for section in ["ANCHOR", "REFERENCE"] {
            if self.word(section)? {
                while !self.word("ENDSEC")? {
                    if self.bump().is_none() {
                        return Err(self.err(format!("the {section} section has no ENDSEC")));
                    }
                }
                self.expect(b';')?;
            }
        }
        let mut instances = Vec::new();
        let mut data_sections = 0;
        while self.word("DATA")? {
            data_sections += 1;
            if self.peek()? == Some(b'(') {
                self.bump();
                self.list_rest(0)?;
            }
            self.expect(b';')?;
            loop {
                if self.word("ENDSEC")? {
                    self.expect(b';')?;
                    break;
                }
                if self.peek()?.is_none() {
                    return Err(self.err("the file ends inside the DATA section (truncated?)"));
                }
                instances.push(self.instance()?);
            }
        }
        if data_sections == 0 {
            return Err(self.err(format!("expected DATA, found {}", self.found())));
        }
        if self.word("SIGNATURE")? {
            while !self.word("ENDSEC")? {
                if self.bump().is_none() {
                    return Err(self.err("the SIGNATURE section has no ENDSEC"));
                }
            }
            self.expect(b';')?;
        }
        if !self.word("END-ISO-10303-21")? {
            return Err(self.err(format!(
                "expected END-ISO-10303-21; (truncated?), found {}",
                self.found()
            )));
        }
        self.expect(b';')?;
        Ok(Exchange { header, instances })
    }
}

/// A `\X2\…\X0\` (UTF-16) or `\X4\…\X0\` (UTF-32) run at the start of `rest`: its text
/// and its length in bytes.
fn wide(rest: &[u8], hex: &dyn Fn(&[u8]) -> Option<u32>) -> Option<(String, usize)> {
    let width = if rest.starts_with(b"\\X2\\") {
        4
    } else if rest.starts_with(b"\\X4\\") {
        8
    } else {
        return None;
    };
    let end = rest.windows(4).position(|w| w == b"\\X0\\")?;
    let body = rest.get(4..end)?;
    if body.len() % width != 0 {
        return None;
    }
    let units: Vec<u32> = body.chunks(width).map(hex).collect::<Option<_>>()?;
    let text = if width == 4 {
        let u16s: Vec<u16> = units.iter().map(|&u| u as u16).collect();
        String::from_utf16_lossy(&u16s)
    } else {
        units
            .iter()
            .map(|&u| char::from_u32(u).unwrap_or('\u{fffd}'))
            .collect()
    };
    Some((text, end + 4))
}

/// Decodes the escapes of a Part 21 string: `\\`, `\X\hh` (ISO 8859-1), `\X2\…\X0\`
/// (UTF-16) and `\X4\…\X0\` (UTF-32); other directives (`\S\`, `\P?\`) are kept as written.
pub(crate) fn decode_string(raw: &[u8]) -> String {
    let hex = |s: &[u8]| {
        std::str::from_utf8(s)
            .ok()
            .and_then(|t| u32::from_str_radix(t, 16).ok())
    };
    let mut out = String::with_capacity(raw.len());
    let mut i = 0;
    while i < raw.len() {
        if raw[i] == b'\\' {
            let rest = &raw[i..];
            if rest.starts_with(b"\\\\") {
                out.push('\\');
                i += 2;
                continue;
            }
            if rest.len() >= 5
                && rest.starts_with(b"\\X\\")
                && let Some(c) = hex(&rest[3..5]).and_then(char::from_u32)
            {
                out.push(c);
                i += 5;
                continue;
            }
            if let Some((text, len)) = wide(rest, &hex) {
                out.push_str(&text);
                i += len;
                continue;
            }
            out.push('\\');
            i += 1;
            continue;
        }
        // Bytes outside ASCII are taken as UTF-8 where valid (some writers use it).
        let start = i;
        while i < raw.len() && raw[i] != b'\\' {
            i += 1;
        }
        out.push_str(&String::from_utf8_lossy(&raw[start..i]));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Exchange> {
        Parser::new(s.as_bytes(), "t.stp").exchange()
    }

    #[test]
    fn values_of_every_kind() {
        let ex = parse(
            "ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('AP214'));\nENDSEC;\nDATA;\n\
             #10=A('it''s',$,*,-12,1.5E-3,.T.,\"0F\",#7,(1,(2.,3.)),LENGTH_MEASURE(2.));\n\
             /* comment */ #11 = ( B() C(4) );\nENDSEC;\nEND-ISO-10303-21;\n",
        )
        .unwrap();
        assert_eq!(ex.header[0].name, "FILE_SCHEMA");
        let a = &ex.instances[0];
        assert_eq!((a.id, a.line), (Id(10), 6));
        assert_eq!(
            a.records[0].params,
            vec![
                Value::Str("it's".into()),
                Value::Unset,
                Value::Derived,
                Value::Int(-12),
                Value::Real(1.5e-3),
                Value::Enum("T".into()),
                Value::Binary("0F".into()),
                Value::Ref(Id(7)),
                Value::List(vec![
                    Value::Int(1),
                    Value::List(vec![Value::Real(2.0), Value::Real(3.0)])
                ]),
                Value::Typed("LENGTH_MEASURE".into(), Box::new(Value::Real(2.0))),
            ]
        );
        let b = &ex.instances[1];
        assert_eq!((b.id, b.line, b.records.len()), (Id(11), 7, 2));
        assert_eq!(b.type_name(), "(B C)");
    }

    #[test]
    fn string_escapes() {
        assert_eq!(decode_string(b"a\\\\b"), "a\\b");
        assert_eq!(decode_string(b"\\X\\E9t\\X\\E9"), "été");
        assert_eq!(decode_string(b"\\X2\\00E9006C\\X0\\ve"), "élve");
        assert_eq!(decode_string(b"\\X4\\0001F600\\X0\\"), "\u{1F600}");
        assert_eq!(decode_string(b"\\S\\a"), "\\S\\a");
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=A(1,\n2 3);\nENDSEC;\n")
            .err()
            .unwrap()
            .to_string();
        assert_eq!(e, "t.stp: line 6: expected ',' or ')', found '3);'");
        let e = parse("ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=A('x);\n")
            .err()
            .unwrap()
            .to_string();
        assert_eq!(e, "t.stp: line 5: the string opened here is never closed");
        let e = parse("ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=A(1);\n")
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("truncated"), "{e}");
        let deep = format!(
            "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=A({}{});\nENDSEC;\nEND-ISO-10303-21;",
            "(".repeat(100),
            ")".repeat(100)
        );
        assert!(parse(&deep).err().unwrap().to_string().contains("nest"));
        let e = parse("solid cube\n").err().unwrap().to_string();
        assert!(e.contains("not a STEP Part 21 file"), "{e}");
    }
}
