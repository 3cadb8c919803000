//! OpenFOAM field files (`volScalarField`, `volVectorField`, `pointScalarField`,
//! `pointVectorField`, …): the `internalField` and each patch's `value` in `boundaryField`,
//! as `uniform` values or `nonuniform List<scalar|vector>` lists (ASCII or binary, as the
//! header says). Other entries (`dimensions`, `type`, …) are skipped.

use std::path::Path;

use super::file::FoamFile;
use crate::error::Result;

/// The values of a field entry.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    /// `uniform v` (one scalar, or the 3 components of a vector).
    Uniform(Vec<f64>),
    /// `nonuniform List<…> N (…)`: `components` values per item (1 or 3), flat.
    List {
        /// 1 (scalar) or 3 (vector).
        components: usize,
        /// The values, `components` per item.
        values: Vec<f64>,
    },
}

impl Values {
    /// Number of components per item (1 or 3).
    pub fn components(&self) -> usize {
        match self {
            Values::Uniform(v) => v.len(),
            Values::List { components, .. } => *components,
        }
    }

    /// Item `i` as a vector (`[s, 0, 0]` for a scalar); a uniform value for every `i`.
    pub fn at(&self, i: usize) -> [f64; 3] {
        let (c, v) = match self {
            Values::Uniform(v) => (v.as_slice(), 0),
            Values::List { components, values } => (values.as_slice(), i * components),
        };
        if self.components() == 3 {
            [c[v], c[v + 1], c[v + 2]]
        } else {
            [c[v], 0.0, 0.0]
        }
    }

    /// Number of items of a list (`None` for a uniform value).
    pub fn items(&self) -> Option<usize> {
        match self {
            Values::Uniform(_) => None,
            Values::List { components, values } => Some(values.len() / components),
        }
    }
}

/// A field file read by [`read_field`].
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// The header's `class` (`pointVectorField`, `volScalarField`, …).
    pub class: String,
    /// The header's `object` is not kept; the file name is.
    pub file: String,
    /// `internalField`.
    pub internal: Values,
    /// Each patch of `boundaryField` with its `value`, if it has one, in the file's order.
    pub patches: Vec<(String, Option<Values>)>,
}

impl Field {
    /// The `value` of patch `name`.
    pub fn patch(&self, name: &str) -> Option<&Values> {
        self.patches
            .iter()
            .find(|(n, _)| n == name)
            .and_then(|(_, v)| v.as_ref())
    }
}

fn values(f: &mut FoamFile, what: &str) -> Result<Values> {
    let kind = f.word_or(&format!("file ends inside {what}"))?.to_vec();
    let v = match &kind[..] {
        b"uniform" => {
            f.skip_blank();
            if f.bytes.get(f.pos) == Some(&b'(') {
                f.pos += 1;
                let mut v = Vec::with_capacity(3);
                for _ in 0..3 {
                    v.push(f.ascii_scalar(what)?);
                }
                f.expect(b')')?;
                Values::Uniform(v)
            } else {
                Values::Uniform(vec![f.ascii_scalar(what)?])
            }
        }
        b"nonuniform" => {
            let list = f.word_or(&format!("file ends inside {what}"))?.to_vec();
            match &list[..] {
                b"List<scalar>" => Values::List {
                    components: 1,
                    values: f.scalars(what)?,
                },
                b"List<vector>" => Values::List {
                    components: 3,
                    values: f.vectors(what)?.into_iter().flatten().collect(),
                },
                other => {
                    return Err(f.err(format!(
                        "{what}: {:?} (scalar and vector lists are read)",
                        String::from_utf8_lossy(other)
                    )));
                }
            }
        }
        other => {
            return Err(f.err(format!(
                "{what}: expected uniform or nonuniform, found {:?}",
                String::from_utf8_lossy(other)
            )));
        }
    };
    f.expect(b';')?;
    Ok(v)
}

/// Reads the field file `path` (gunzipped when it ends in `.gz`).
pub fn read_field(path: &Path) -> Result<Field> {
    let mut f = FoamFile::open(path)?;
    let mut internal = None;
    let mut patches = Vec::new();
    loop {
        f.skip_blank();
        if f.pos >= f.bytes.len() {
            break;
        }
        let key = f.name_or("file ends inside an entry")?;
        match key.as_str() {
            "internalField" => internal = Some(values(&mut f, "internalField")?),
            "boundaryField" => {
                f.expect(b'{')?;
                loop {
                    f.skip_blank();
                    if f.bytes.get(f.pos) == Some(&b'}') {
                        f.pos += 1;
                        break;
                    }
                    let name = f.name_or("file ends inside boundaryField")?;
                    f.expect(b'{')?;
                    let mut value = None;
                    loop {
                        f.skip_blank();
                        if f.bytes.get(f.pos) == Some(&b'}') {
                            f.pos += 1;
                            break;
                        }
                        let k = f.name_or(&format!("file ends inside patch {name}"))?;
                        if k == "value" {
                            value = Some(values(&mut f, &format!("the value of patch {name}"))?);
                        } else {
                            f.skip_value()?;
                        }
                    }
                    patches.push((name, value));
                }
            }
            _ => f.skip_value()?,
        }
    }
    let Some(internal) = internal else {
        return Err(f.err("no internalField"));
    };
    Ok(Field {
        class: f.class.clone(),
        file: f.name.clone(),
        internal,
        patches,
    })
}
