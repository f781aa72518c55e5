//! JSON, the one reader and writer of the workspace (the core has no serde):
//! the marking's harness protocol and reports (`siftlab-mark`), the CLI's
//! class files, and the tests' goldens and `--json` outputs.
//!
//! The reader keeps integers exact ([`Json::Int`], or their digits in
//! [`Json::BigInt`]) and other numbers as the f64 their text names; it takes
//! what Python's `json` writes (`repr(float)`, which round-trips, and `NaN`,
//! `Infinity`, `-Infinity`). [`Json::as_f32`] gives the f32 a number's text
//! names. The writer ([`Json::to_json`], [`push_str`], [`push_f64`]) escapes
//! everything outside printable ASCII, so any pipe encoding carries it, and
//! writes floats as Python's `repr`.
//!
//! This file holds the value and the writer; beside it, `json/parse.rs` is
//! the reader.

use crate::pyfmt::{py_float, py_str};

mod parse;
#[cfg(test)]
mod tests;

pub use parse::parse;

/// A JSON value. Integers that do not fit an i128 keep their digits.
#[derive(Clone, Debug, PartialEq)]
pub enum Json {
    Null,
    Bool(bool),
    Int(i128),
    BigInt(String),
    Float(f64),
    Str(String),
    Arr(Vec<Json>),
    Obj(Vec<(String, Json)>),
}

impl Json {
    /// The value of `key` in an object.
    pub fn get(&self, key: &str) -> Option<&Json> {
        match self {
            Json::Obj(kv) => kv.iter().find(|(k, _)| k == key).map(|(_, v)| v),
            _ => None,
        }
    }

    pub fn as_str(&self) -> Option<&str> {
        match self {
            Json::Str(s) => Some(s),
            _ => None,
        }
    }

    pub fn as_arr(&self) -> Option<&[Json]> {
        match self {
            Json::Arr(v) => Some(v),
            _ => None,
        }
    }

    /// A whole number (an integral float too: Python's `1.0 == 1`).
    pub fn as_i64(&self) -> Option<i64> {
        match *self {
            Json::Int(v) => i64::try_from(v).ok(),
            Json::Float(f) if f.fract() == 0.0 && f.abs() < 9.2e18 => Some(f as i64),
            _ => None,
        }
    }

    /// A number as the f32 its text names, as `text.parse::<f32>()` reads
    /// it: from the f64 the reader kept, which rounds to the same f32 unless
    /// it lies exactly halfway between two f32s. There the text's side is
    /// lost and the answer is `None` (no f32's shortest text, nor the exact
    /// f64 value of an f32 as Python writes it, lands there in practice).
    pub fn as_f32(&self) -> Option<f32> {
        match self {
            // i128 → f32 rounds to nearest, ties to even, as parsing does.
            Json::Int(v) => Some(*v as f32),
            Json::BigInt(s) => s.parse().ok(),
            Json::Float(f) => {
                let g = *f as f32;
                // The f32 on the other side of `f` from `g`: the two
                // straddle `f`; halfway between them the text decides.
                let other = if (g as f64) < *f { g.next_up() } else { g.next_down() };
                let halfway = f.is_finite() && (g as f64 + other as f64) / 2.0 == *f && g as f64 != *f;
                (!halfway).then_some(g)
            }
            _ => None,
        }
    }

    /// A number as f64 (ints converted).
    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            Json::Int(v) => Some(v as f64),
            Json::Float(f) => Some(f),
            _ => None,
        }
    }

    /// Python's `==` on the values the JSON stands for: numbers by value
    /// (an int equals a float exactly when the float is that integer),
    /// arrays and objects element by element. `NaN` equals nothing.
    pub fn py_eq(&self, other: &Json) -> bool {
        use Json::*;
        match (self, other) {
            (Null, Null) => true,
            // Python: True == 1 and False == 0.
            (Bool(a), Bool(b)) => a == b,
            (Bool(a), n @ (Int(_) | Float(_))) | (n @ (Int(_) | Float(_)), Bool(a)) => n.py_eq(&Int(*a as i128)),
            (Int(a), Int(b)) => a == b,
            (BigInt(a), BigInt(b)) => a == b,
            (Float(a), Float(b)) => a == b,
            (Int(i), Float(f)) | (Float(f), Int(i)) => {
                f.fract() == 0.0 && f.abs() < 1.7e38 && (*f as i128) == *i && (*i as f64) == *f
            }
            (Str(a), Str(b)) => a == b,
            (Arr(a), Arr(b)) => a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.py_eq(y)),
            (Obj(a), Obj(b)) => a.len() == b.len() && a.iter().all(|(k, v)| other.get(k).is_some_and(|w| v.py_eq(w))),
            _ => false,
        }
    }

    /// The JSON type as Python names the value's type.
    pub fn py_type(&self) -> &'static str {
        match self {
            Json::Null => "NoneType",
            Json::Bool(_) => "bool",
            Json::Int(_) | Json::BigInt(_) => "int",
            Json::Float(_) => "float",
            Json::Str(_) => "str",
            Json::Arr(_) => "list",
            Json::Obj(_) => "dict",
        }
    }

    /// Python-like `repr`: lists in brackets, floats as `repr(float)`,
    /// strings quoted, `None`/`True`/`False`.
    pub fn py_repr(&self) -> String {
        let mut s = String::new();
        self.py_repr_into(&mut s);
        s
    }

    fn py_repr_into(&self, out: &mut String) {
        match self {
            Json::Null => out.push_str("None"),
            Json::Bool(b) => out.push_str(if *b { "True" } else { "False" }),
            Json::Int(v) => out.push_str(&v.to_string()),
            Json::BigInt(s) => out.push_str(s),
            Json::Float(f) => out.push_str(&py_float(*f)),
            Json::Str(s) => out.push_str(&py_str(s)),
            Json::Arr(v) => {
                out.push('[');
                for (i, x) in v.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    x.py_repr_into(out);
                }
                out.push(']');
            }
            Json::Obj(kv) => {
                out.push('{');
                for (i, (k, v)) in kv.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    out.push_str(&py_str(k));
                    out.push_str(": ");
                    v.py_repr_into(out);
                }
                out.push('}');
            }
        }
    }

    /// Standard JSON text (non-finite floats as null).
    pub fn to_json(&self) -> String {
        let mut s = String::new();
        self.write(&mut s);
        s
    }

    /// Appends [`Json::to_json`]'s text to `out`.
    pub fn write(&self, out: &mut String) {
        match self {
            Json::Null => out.push_str("null"),
            Json::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
            Json::Int(v) => out.push_str(&v.to_string()),
            Json::BigInt(s) => out.push_str(s),
            Json::Float(f) => push_f64(out, *f),
            Json::Str(s) => push_str(out, s),
            Json::Arr(v) => {
                out.push('[');
                for (i, x) in v.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    x.write(out);
                }
                out.push(']');
            }
            Json::Obj(kv) => {
                out.push('{');
                for (i, (k, v)) in kv.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    push_str(out, k);
                    out.push_str(": ");
                    v.write(out);
                }
                out.push('}');
            }
        }
    }
}

/// A finite f64 as Python's `repr` (valid JSON: `1e-05`, `1.5e+16`); a
/// non-finite one as `null`.
pub fn push_f64(out: &mut String, v: f64) {
    if v.is_finite() {
        out.push_str(&py_float(v));
    } else {
        out.push_str("null");
    }
}

/// `s` as a JSON string literal, escaping quotes, backslashes, control
/// characters and everything outside ASCII (`\uXXXX`, surrogate pairs).
pub fn push_str(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            ' '..='~' => out.push(c),
            _ => {
                let mut buf = [0u16; 2];
                for unit in c.encode_utf16(&mut buf) {
                    out.push_str(&format!("\\u{unit:04x}"));
                }
            }
        }
    }
    out.push('"');
}

/// `s` as a JSON string literal.
pub fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    push_str(&mut out, s);
    out
}
