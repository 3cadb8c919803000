//! The values of a Part 21 exchange structure: parameters, records and entity instances.

/// An entity instance name `#n`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Id(pub u64);

impl std::fmt::Display for Id {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "#{}", self.0)
    }
}

/// One parameter of a record (ISO 10303-21 §12.2).
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// `$`: the attribute has no value.
    Unset,
    /// `*`: the attribute is derived (redeclared) in this entity.
    Derived,
    /// An integer.
    Int(i64),
    /// A real (has a decimal point).
    Real(f64),
    /// A string, with `''` and the `\X\`, `\X2\`…`\X0\` encodings decoded.
    Str(String),
    /// An enumeration value `.NAME.` (the name without dots).
    Enum(String),
    /// A binary `"…"` (kept as written).
    Binary(String),
    /// A reference `#n` to another instance.
    Ref(Id),
    /// A list `( … )`.
    List(Vec<Value>),
    /// A typed parameter `KEYWORD( value )`, e.g. `LENGTH_MEASURE(1.E-10)`.
    Typed(String, Box<Value>),
}

impl Value {
    /// The value as it would be written, shortened, for error messages.
    pub fn describe(&self) -> String {
        let mut s = match self {
            Value::Unset => "$".to_string(),
            Value::Derived => "*".to_string(),
            Value::Int(i) => i.to_string(),
            Value::Real(x) => format!("{x:?}"),
            Value::Str(s) => format!("'{s}'"),
            Value::Enum(e) => format!(".{e}."),
            Value::Binary(b) => format!("\"{b}\""),
            Value::Ref(id) => id.to_string(),
            Value::List(v) => format!(
                "({})",
                v.iter().map(Value::describe).collect::<Vec<_>>().join(",")
            ),
            Value::Typed(k, v) => format!("{k}({})", v.describe()),
        };
        if s.len() > 60 {
            let mut cut = 57;
            while !s.is_char_boundary(cut) {
                cut -= 1;
            }
            s.truncate(cut);
            s.push_str("...");
        }
        s
    }

    /// Calls `f` on every reference held, depth first.
    pub fn for_each_ref(&self, f: &mut impl FnMut(Id)) {
        match self {
            Value::Ref(id) => f(*id),
            Value::List(v) => v.iter().for_each(|x| x.for_each_ref(f)),
            Value::Typed(_, v) => v.for_each_ref(f),
            _ => {}
        }
    }
}

/// A simple record `NAME(params)`: a whole simple instance, or one part of a complex one.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// The entity type name, upper case (`ADVANCED_FACE`).
    pub name: String,
    /// Its parameters in order.
    pub params: Vec<Value>,
}

/// One entity instance `#id = …;` of the data section.
#[derive(Debug, Clone, PartialEq)]
pub struct Instance {
    /// Its name `#id`.
    pub id: Id,
    /// The physical line where it starts (1-based).
    pub line: usize,
    /// Its records: one for a simple instance; the partial entities of a complex instance
    /// `( A(…) B(…) … )` in the order written (ISO 10303-21 requires alphabetical order).
    pub records: Vec<Record>,
}

impl Instance {
    /// True for a complex instance (several records).
    pub fn is_complex(&self) -> bool {
        self.records.len() > 1
    }

    /// The record named `name`, if the instance has one.
    pub fn record(&self, name: &str) -> Option<&Record> {
        self.records.iter().find(|r| r.name == name)
    }

    /// The type name for messages: `ADVANCED_FACE`, or `(A B C)` for a complex instance.
    pub fn type_name(&self) -> String {
        match self.records.as_slice() {
            [r] => r.name.clone(),
            rs => format!(
                "({})",
                rs.iter()
                    .map(|r| r.name.as_str())
                    .collect::<Vec<_>>()
                    .join(" ")
            ),
        }
    }
}
