//! A cursor over one record's parameters that reads typed attributes and reports the
//! parameter (and list item) at fault.

use crate::error::EntityProblem;
use crate::value::{Id, Record, Value};

/// Reads the attributes of one record in order.
pub(crate) struct Dec<'a> {
    rec: &'a Record,
    /// Index of the next parameter (0-based).
    i: usize,
    /// `" of NAME"` when the record is one part of a complex instance.
    part: String,
}

/// Unwraps typed measures (`LENGTH_MEASURE(2.)`, `PARAMETER_VALUE(0.5)`): the schemas put
/// them where a select type allows several measures.
fn untyped(v: &Value) -> &Value {
    match v {
        Value::Typed(_, inner) => untyped(inner),
        v => v,
    }
}

fn real_of(v: &Value) -> Option<f64> {
    match untyped(v) {
        Value::Real(x) => Some(*x),
        Value::Int(i) => Some(*i as f64),
        _ => None,
    }
}

impl<'a> Dec<'a> {
    /// A cursor over `rec`, which needs at least `arity` parameters; `complex` when the record
    /// is one part of a complex instance (named in messages).
    pub(crate) fn new(rec: &'a Record, arity: usize, complex: bool) -> Result<Self, EntityProblem> {
        if rec.params.len() < arity {
            return Err(EntityProblem::Arity {
                record: rec.name.clone(),
                found: rec.params.len(),
                expected: arity,
            });
        }
        Ok(Dec {
            rec,
            i: 0,
            part: if complex {
                format!(" of {}", rec.name)
            } else {
                String::new()
            },
        })
    }

    fn next(&mut self) -> (usize, &'a Value) {
        let i = self.i;
        self.i += 1;
        // The arity was checked; a shorter record cannot reach here, but stay total.
        (i + 1, self.rec.params.get(i).unwrap_or(&Value::Unset))
    }

    fn wrong(
        &self,
        index: usize,
        name: &'static str,
        path: &str,
        expected: &str,
        v: &Value,
    ) -> EntityProblem {
        EntityProblem::Param {
            index,
            name,
            path: format!("{}{path}", self.part),
            expected: expected.to_string(),
            found: v.describe(),
        }
    }

    /// Skips `n` attributes (inherited names, derived `*`).
    pub(crate) fn skip(&mut self, n: usize) {
        self.i += n;
    }

    /// Any value, unread.
    pub(crate) fn value(&mut self) -> (usize, &'a Value) {
        self.next()
    }

    /// A real (an integer or a typed measure is accepted).
    pub(crate) fn real(&mut self, name: &'static str) -> Result<f64, EntityProblem> {
        let (i, v) = self.next();
        real_of(v).ok_or_else(|| self.wrong(i, name, "", "a real", v))
    }

    /// An integer.
    pub(crate) fn int(&mut self, name: &'static str) -> Result<i64, EntityProblem> {
        let (i, v) = self.next();
        match untyped(v) {
            Value::Int(k) => Ok(*k),
            _ => Err(self.wrong(i, name, "", "an integer", v)),
        }
    }

    /// A count or degree: an integer ≥ `min`.
    pub(crate) fn count(&mut self, name: &'static str, min: i64) -> Result<usize, EntityProblem> {
        let (i, v) = self.next();
        match untyped(v) {
            Value::Int(k) if *k >= min => Ok(*k as usize),
            _ => Err(self.wrong(i, name, "", &format!("an integer ≥ {min}"), v)),
        }
    }

    /// A reference.
    pub(crate) fn id(&mut self, name: &'static str) -> Result<Id, EntityProblem> {
        let (i, v) = self.next();
        match v {
            Value::Ref(id) => Ok(*id),
            _ => Err(self.wrong(i, name, "", "a reference #n", v)),
        }
    }

    /// A reference or `$`.
    pub(crate) fn opt_id(&mut self, name: &'static str) -> Result<Option<Id>, EntityProblem> {
        let (i, v) = self.next();
        match v {
            Value::Ref(id) => Ok(Some(*id)),
            Value::Unset => Ok(None),
            _ => Err(self.wrong(i, name, "", "a reference #n or $", v)),
        }
    }

    /// `.T.` or `.F.`.
    pub(crate) fn boolean(&mut self, name: &'static str) -> Result<bool, EntityProblem> {
        let (i, v) = self.next();
        match v {
            Value::Enum(e) if e == "T" => Ok(true),
            Value::Enum(e) if e == "F" => Ok(false),
            _ => Err(self.wrong(i, name, "", ".T. or .F.", v)),
        }
    }

    /// `.T.`, `.F.` or `.U.` (unknown: `None`).
    pub(crate) fn logical(&mut self, name: &'static str) -> Result<Option<bool>, EntityProblem> {
        let (i, v) = self.next();
        match v {
            Value::Enum(e) if e == "T" => Ok(Some(true)),
            Value::Enum(e) if e == "F" => Ok(Some(false)),
            Value::Enum(e) if e == "U" => Ok(None),
            _ => Err(self.wrong(i, name, "", ".T., .F. or .U.", v)),
        }
    }

    /// An enumeration value (its name), or `$` (empty).
    pub(crate) fn enumeration(&mut self, name: &'static str) -> Result<String, EntityProblem> {
        let (i, v) = self.next();
        match v {
            Value::Enum(e) => Ok(e.clone()),
            Value::Unset => Ok(String::new()),
            _ => Err(self.wrong(i, name, "", "an enumeration .X.", v)),
        }
    }

    fn list(
        &self,
        i: usize,
        name: &'static str,
        v: &'a Value,
    ) -> Result<&'a [Value], EntityProblem> {
        match v {
            Value::List(items) => Ok(items),
            _ => Err(self.wrong(i, name, "", "a list", v)),
        }
    }

    /// A list of reals.
    pub(crate) fn reals(&mut self, name: &'static str) -> Result<Vec<f64>, EntityProblem> {
        let (i, v) = self.next();
        self.list(i, name, v)?
            .iter()
            .enumerate()
            .map(|(k, x)| {
                real_of(x)
                    .ok_or_else(|| self.wrong(i, name, &format!(": item {}", k + 1), "a real", x))
            })
            .collect()
    }

    /// A list of lists of reals (rows).
    pub(crate) fn reals2(&mut self, name: &'static str) -> Result<Vec<Vec<f64>>, EntityProblem> {
        let (i, v) = self.next();
        let rows = self.list(i, name, v)?;
        rows.iter()
            .enumerate()
            .map(|(r, row)| match row {
                Value::List(items) => items
                    .iter()
                    .enumerate()
                    .map(|(k, x)| {
                        real_of(x).ok_or_else(|| {
                            self.wrong(
                                i,
                                name,
                                &format!(": row {}, item {}", r + 1, k + 1),
                                "a real",
                                x,
                            )
                        })
                    })
                    .collect(),
                _ => Err(self.wrong(i, name, &format!(": row {}", r + 1), "a list", row)),
            })
            .collect()
    }

    /// A list of non-negative integers.
    pub(crate) fn counts(&mut self, name: &'static str) -> Result<Vec<usize>, EntityProblem> {
        let (i, v) = self.next();
        self.list(i, name, v)?
            .iter()
            .enumerate()
            .map(|(k, x)| match untyped(x) {
                Value::Int(n) if *n >= 0 => Ok(*n as usize),
                _ => Err(self.wrong(i, name, &format!(": item {}", k + 1), "an integer ≥ 0", x)),
            })
            .collect()
    }

    /// A list of references.
    pub(crate) fn ids(&mut self, name: &'static str) -> Result<Vec<Id>, EntityProblem> {
        let (i, v) = self.next();
        self.list(i, name, v)?
            .iter()
            .enumerate()
            .map(|(k, x)| match x {
                Value::Ref(id) => Ok(*id),
                _ => Err(self.wrong(i, name, &format!(": item {}", k + 1), "a reference #n", x)),
            })
            .collect()
    }

    /// A list of lists of references (rows).
    pub(crate) fn ids2(&mut self, name: &'static str) -> Result<Vec<Vec<Id>>, EntityProblem> {
        let (i, v) = self.next();
        let rows = self.list(i, name, v)?;
        rows.iter()
            .enumerate()
            .map(|(r, row)| match row {
                Value::List(items) => items
                    .iter()
                    .enumerate()
                    .map(|(k, x)| match x {
                        Value::Ref(id) => Ok(*id),
                        _ => Err(self.wrong(
                            i,
                            name,
                            &format!(": row {}, item {}", r + 1, k + 1),
                            "a reference #n",
                            x,
                        )),
                    })
                    .collect(),
                _ => Err(self.wrong(i, name, &format!(": row {}", r + 1), "a list", row)),
            })
            .collect()
    }
}
