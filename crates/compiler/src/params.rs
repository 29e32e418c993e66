//! Typed pass parameters: what a plugin declares ([`ParamSpec`]) and what it receives
//! ([`Params`], already checked for type and range, defaults filled in).
//!
//! Declaring parameters as data rather than only as a serde struct lets the compiler name the
//! exact parameter in errors (wrong type, unknown, out of range) and lets the viewer draw a
//! widget per knob.

use std::collections::BTreeMap;

/// The type, default and valid range of one parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamKind {
    /// A real number in `[min, max]`.
    Float {
        /// Used when the graph does not set it.
        default: f64,
        /// Smallest valid value.
        min: f64,
        /// Largest valid value.
        max: f64,
    },
    /// A non-negative integer in `[min, max]`.
    UInt {
        /// Used when the graph does not set it.
        default: u64,
        /// Smallest valid value.
        min: u64,
        /// Largest valid value.
        max: u64,
    },
    /// true / false.
    Bool {
        /// Used when the graph does not set it.
        default: bool,
    },
    /// One of a fixed set of names, written as a string.
    Choice {
        /// Used when the graph does not set it.
        default: &'static str,
        /// The valid names.
        options: &'static [&'static str],
    },
}

impl ParamKind {
    /// The type's name as shown in messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            ParamKind::Float { .. } => "a number",
            ParamKind::UInt { .. } => "a non-negative integer",
            ParamKind::Bool { .. } => "true or false",
            ParamKind::Choice { .. } => "a string",
        }
    }

    fn default_value(&self) -> ParamValue {
        match self {
            ParamKind::Float { default, .. } => ParamValue::Float(*default),
            ParamKind::UInt { default, .. } => ParamValue::UInt(*default),
            ParamKind::Bool { default } => ParamValue::Bool(*default),
            ParamKind::Choice { default, .. } => ParamValue::Choice((*default).to_string()),
        }
    }
}

/// One declared parameter of a pass kind.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    /// The name used in graph files.
    pub name: &'static str,
    /// What it does, in one line (shown in errors and the viewer).
    pub doc: &'static str,
    /// Type, default, range.
    pub kind: ParamKind,
}

impl ParamSpec {
    /// A float parameter.
    pub const fn float(name: &'static str, default: f64, min: f64, max: f64, doc: &'static str) -> Self {
        Self { name, doc, kind: ParamKind::Float { default, min, max } }
    }

    /// An unsigned integer parameter.
    pub const fn uint(name: &'static str, default: u64, min: u64, max: u64, doc: &'static str) -> Self {
        Self { name, doc, kind: ParamKind::UInt { default, min, max } }
    }

    /// A boolean parameter.
    pub const fn boolean(name: &'static str, default: bool, doc: &'static str) -> Self {
        Self { name, doc, kind: ParamKind::Bool { default } }
    }

    /// A choice among names.
    pub const fn choice(
        name: &'static str,
        default: &'static str,
        options: &'static [&'static str],
        doc: &'static str,
    ) -> Self {
        Self { name, doc, kind: ParamKind::Choice { default, options } }
    }
}

/// A checked parameter value.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// A number.
    Float(f64),
    /// An integer.
    UInt(u64),
    /// A boolean.
    Bool(bool),
    /// A choice.
    Choice(String),
}

impl std::fmt::Display for ParamValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamValue::Float(v) => write!(f, "{v}"),
            ParamValue::UInt(v) => write!(f, "{v}"),
            ParamValue::Bool(v) => write!(f, "{v}"),
            ParamValue::Choice(v) => write!(f, "\"{v}\""),
        }
    }
}

/// The checked parameters of one pass, every declared parameter present.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params {
    values: BTreeMap<String, ParamValue>,
}

impl Params {
    /// All defaults of `specs`.
    pub fn defaults(specs: &[ParamSpec]) -> Self {
        Self { values: specs.iter().map(|s| (s.name.to_string(), s.kind.default_value())).collect() }
    }

    /// Sets one value (the compiler has checked it against the spec).
    pub fn set(&mut self, name: &str, value: ParamValue) {
        self.values.insert(name.to_string(), value);
    }

    /// Iterates `(name, value)` in name order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &ParamValue)> {
        self.values.iter().map(|(k, v)| (k.as_str(), v))
    }

    /// The value of a declared parameter. Asking for one the plugin never declared is a plugin
    /// bug: debug builds (every test) panic naming it, so a misspelled name cannot silently read
    /// as 0; release builds fall back to 0 / false / "". Code that serves several kinds reads a
    /// shared block through its `pass_params!` struct's `try_from_params` instead.
    fn declared(&self, name: &str, ty: &str) -> Option<&ParamValue> {
        let v = self.values.get(name);
        debug_assert!(
            v.is_some(),
            "parameter \"{name}\" ({ty}) was never declared by this pass (declared: {:?}); a misspelled name, \
             or a shared block to read with its pass_params! struct's try_from_params",
            self.values.keys().collect::<Vec<_>>()
        );
        v
    }

    /// The value of `name`, `None` where the pass does not declare it (comparing blocks).
    pub fn value(&self, name: &str) -> Option<&ParamValue> {
        self.values.get(name)
    }

    /// Whether the pass declares parameter `name` (a shared block's `try_from_params`).
    pub fn declares(&self, name: &str) -> bool {
        self.values.contains_key(name)
    }

    /// A float parameter (an integer one widens).
    pub fn float(&self, name: &str) -> f64 {
        match self.declared(name, "float") {
            Some(ParamValue::Float(v)) => *v,
            Some(ParamValue::UInt(v)) => *v as f64,
            _ => 0.0,
        }
    }

    /// An integer parameter.
    pub fn uint(&self, name: &str) -> u64 {
        match self.declared(name, "uint") {
            Some(ParamValue::UInt(v)) => *v,
            _ => 0,
        }
    }

    /// A boolean parameter.
    pub fn boolean(&self, name: &str) -> bool {
        matches!(self.declared(name, "boolean"), Some(ParamValue::Bool(true)))
    }

    /// A choice parameter.
    pub fn choice(&self, name: &str) -> &str {
        match self.declared(name, "choice") {
            Some(ParamValue::Choice(v)) => v,
            _ => "",
        }
    }
}

/// Why one RON value does not fit its [`ParamSpec`].
#[derive(Clone, Debug, PartialEq)]
pub enum ParamProblem {
    /// Wrong type; `found` describes the value.
    WrongType {
        /// What the value is.
        found: String,
    },
    /// Outside `[min, max]`.
    OutOfRange {
        /// The value.
        value: String,
    },
    /// A choice not among the options.
    UnknownChoice {
        /// The value.
        value: String,
    },
}

/// Checks one RON value against its spec.
pub fn check_param(spec: &ParamSpec, value: &ron::Value) -> Result<ParamValue, ParamProblem> {
    use ron::Value as V;
    let number = |v: &V| -> Option<f64> {
        match v {
            V::Number(n) => Some((*n).into_f64()),
            _ => None,
        }
    };
    match &spec.kind {
        ParamKind::Float { min, max, .. } => {
            let x = number(value).ok_or_else(|| ParamProblem::WrongType { found: describe(value) })?;
            if !x.is_finite() || x < *min || x > *max {
                return Err(ParamProblem::OutOfRange { value: format!("{x}") });
            }
            // Shaders read parameters as f32: beyond its range a value would arrive as inf.
            if x.abs() > f32::MAX as f64 {
                return Err(ParamProblem::OutOfRange { value: format!("{x} (beyond a 32-bit float's ±3.4e38)") });
            }
            Ok(ParamValue::Float(x))
        }
        ParamKind::UInt { min, max, .. } => {
            let x = number(value).ok_or_else(|| ParamProblem::WrongType { found: describe(value) })?;
            if x.fract() != 0.0 {
                return Err(ParamProblem::WrongType { found: format!("the number {x}") });
            }
            if x < *min as f64 || x > *max as f64 {
                return Err(ParamProblem::OutOfRange { value: format!("{x}") });
            }
            Ok(ParamValue::UInt(x as u64))
        }
        ParamKind::Bool { .. } => match value {
            V::Bool(b) => Ok(ParamValue::Bool(*b)),
            other => Err(ParamProblem::WrongType { found: describe(other) }),
        },
        ParamKind::Choice { options, .. } => match value {
            V::String(s) if options.contains(&s.as_str()) => Ok(ParamValue::Choice(s.clone())),
            V::String(s) => Err(ParamProblem::UnknownChoice { value: s.clone() }),
            other => Err(ParamProblem::WrongType { found: describe(other) }),
        },
    }
}

/// A short description of a RON value for messages: `the string "x"`, `the number 3`.
pub fn describe(value: &ron::Value) -> String {
    use ron::Value as V;
    match value {
        V::Bool(b) => format!("the boolean {b}"),
        V::Char(c) => format!("the character '{c}'"),
        V::String(s) => format!("the string \"{s}\""),
        V::Number(n) => format!("the number {}", (*n).into_f64()),
        V::Option(_) => "an option".to_string(),
        V::Seq(_) => "a list".to_string(),
        V::Map(_) => "a map".to_string(),
        V::Unit => "()".to_string(),
        V::Bytes(_) => "bytes".to_string(),
    }
}
