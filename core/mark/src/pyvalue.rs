//! matching_info's returned value as the harness encodes it by type
//! (docs/marking.md, "Typed values"), and Python's `==` applied to it here,
//! outside the student's interpreter: no method of the student's classes
//! takes part in the verdict.
//!
//! The wire form is JSON: `null`, `true`/`false`, a JSON int (within i64),
//! a float (finite) and a string are themselves; everything else is an object with one
//! tag: `{"int": "DIGITS"}`, `{"float": X | "nan" | "inf" | "-inf"}`,
//! `{"str": S}`, `{"tuple": [..]}`, `{"list": [..]}`, `{"np": NAME, "value": V}`
//! (a numpy scalar and its Python value), `{"opaque": TYPE, ...}` (anything
//! else: never equal); any tagged value may carry `"sub": CLASS` (an
//! instance of a subclass, encoded as its base value).

use siftlab_core::json::Json;
use siftlab_core::matching::MatchInfo;
use siftlab_core::pyfmt::py_float;

/// A Python value as the lab's comparison sees it.
#[derive(Clone, Debug, PartialEq)]
pub enum PyValue {
    None,
    Bool(bool),
    Int(i128),
    /// An int beyond i128, in decimal.
    BigInt(String),
    Float(f64),
    Str(String),
    Tuple(Vec<PyValue>),
    List(Vec<PyValue>),
    /// A numpy scalar (its class name) and its Python value.
    Np(String, Box<PyValue>),
    /// An instance of a subclass (its class name) of the base value's type.
    Sub(String, Box<PyValue>),
    /// Anything else (its type name): equal to nothing.
    Opaque(String),
}

/// Deeper than this is not followed (the harness stops at 32).
const MAX_DEPTH: usize = 40;

impl PyValue {
    /// The value a typed encoding stands for; what does not read as one is
    /// opaque (a forged or damaged reply compares equal to nothing).
    pub fn from_json(v: &Json) -> PyValue {
        Self::decode(v, 0)
    }

    fn decode(v: &Json, depth: usize) -> PyValue {
        if depth > MAX_DEPTH {
            return PyValue::Opaque("value nested too deep".into());
        }
        let items = |a: &Json| -> Option<Vec<PyValue>> {
            Some(a.as_arr()?.iter().map(|x| Self::decode(x, depth + 1)).collect())
        };
        let base = match v {
            Json::Null => return PyValue::None,
            Json::Bool(b) => return PyValue::Bool(*b),
            Json::Int(i) => return PyValue::Int(*i),
            Json::BigInt(s) => return PyValue::BigInt(s.clone()),
            Json::Float(f) if f.is_finite() => return PyValue::Float(*f),
            Json::Str(s) => return PyValue::Str(s.clone()),
            Json::Obj(kv) if !kv.is_empty() => {
                let (tag, val) = &kv[0];
                match (tag.as_str(), val) {
                    ("int", Json::Str(s)) => int_of(s),
                    ("float", Json::Float(f)) => Some(PyValue::Float(*f)),
                    ("float", Json::Int(i)) => Some(PyValue::Float(*i as f64)),
                    ("float", Json::Str(s)) => match s.as_str() {
                        "nan" => Some(PyValue::Float(f64::NAN)),
                        "inf" => Some(PyValue::Float(f64::INFINITY)),
                        "-inf" => Some(PyValue::Float(f64::NEG_INFINITY)),
                        _ => None,
                    },
                    ("str", Json::Str(s)) => Some(PyValue::Str(s.clone())),
                    ("tuple", a) => items(a).map(PyValue::Tuple),
                    ("list", a) => items(a).map(PyValue::List),
                    ("np", Json::Str(name)) => v.get("value").map(|x| match Self::decode(x, depth + 1) {
                        inner @ (PyValue::Bool(_)
                        | PyValue::Int(_)
                        | PyValue::BigInt(_)
                        | PyValue::Float(_)
                        | PyValue::Str(_)) => PyValue::Np(name.clone(), Box::new(inner)),
                        _ => PyValue::Opaque(name.clone()),
                    }),
                    ("opaque", Json::Str(name)) => Some(PyValue::Opaque(name.clone())),
                    _ => None,
                }
            }
            _ => None,
        };
        let Some(base) = base else {
            return PyValue::Opaque("a value siftlab cannot read".into());
        };
        match v.get("sub").and_then(Json::as_str) {
            Some(class) if !matches!(base, PyValue::Opaque(_) | PyValue::Np(..)) => {
                PyValue::Sub(class.to_string(), Box::new(base))
            }
            _ => base,
        }
    }

    /// The value under a subclass or numpy wrapper.
    fn base(&self) -> &PyValue {
        match self {
            PyValue::Sub(_, v) | PyValue::Np(_, v) => v.base(),
            v => v,
        }
    }

    /// Python's `==` on these types: numbers by value across bool, int and
    /// float (an int equals a float exactly when the float is that integer,
    /// at any size), NaN equal to nothing, tuples only to tuples and lists
    /// only to lists, item by item; an opaque value equals nothing.
    pub fn py_eq(&self, other: &PyValue) -> bool {
        use PyValue::*;
        let (a, b) = (self.base(), other.base());
        if let (Some(x), Some(y)) = (Num::of(a), Num::of(b)) {
            return x.eq(&y);
        }
        match (a, b) {
            (None, None) => true,
            (Str(x), Str(y)) => x == y,
            (Tuple(x), Tuple(y)) | (List(x), List(y)) => x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.py_eq(q)),
            _ => false,
        }
    }

    /// The name of the value's own type (a subclass's or numpy's class).
    pub fn type_name(&self) -> &str {
        match self {
            PyValue::None => "NoneType",
            PyValue::Bool(_) => "bool",
            PyValue::Int(_) | PyValue::BigInt(_) => "int",
            PyValue::Float(_) => "float",
            PyValue::Str(_) => "str",
            PyValue::Tuple(_) => "tuple",
            PyValue::List(_) => "list",
            PyValue::Np(n, _) | PyValue::Sub(n, _) | PyValue::Opaque(n) => n,
        }
    }

    /// Python-like text of the value (strings and class names escaped; an
    /// opaque value as `<TYPE object>`).
    pub fn py_repr(&self) -> String {
        let mut s = String::new();
        self.repr_into(&mut s);
        s
    }

    fn repr_into(&self, out: &mut String) {
        let seq = |out: &mut String, items: &[PyValue], open: char, close: char| {
            out.push(open);
            for (i, x) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                x.repr_into(out);
                if out.len() > 100_000 {
                    out.push_str(", …");
                    break;
                }
            }
            if open == '(' && items.len() == 1 {
                out.push(',');
            }
            out.push(close);
        };
        match self {
            PyValue::None => out.push_str("None"),
            PyValue::Bool(b) => out.push_str(if *b { "True" } else { "False" }),
            PyValue::Int(i) => out.push_str(&i.to_string()),
            PyValue::BigInt(s) => out.push_str(s),
            PyValue::Float(f) => out.push_str(&py_float(*f)),
            PyValue::Str(s) => out.push_str(&siftlab_core::pyfmt::py_str(s)),
            PyValue::Tuple(v) => seq(out, v, '(', ')'),
            PyValue::List(v) => seq(out, v, '[', ']'),
            PyValue::Np(_, v) => v.repr_into(out),
            PyValue::Sub(name, v) => {
                out.push_str(&crate::escape::escaped(name, 60));
                out.push('(');
                v.repr_into(out);
                out.push(')');
            }
            PyValue::Opaque(name) => {
                out.push('<');
                out.push_str(&crate::escape::escaped(name, 60));
                out.push_str(" object>");
            }
        }
    }

    /// The JSON the diagnoses compare with (tuples and lists both arrays,
    /// wrappers dropped, an opaque value its repr as a string).
    pub fn to_json(&self) -> Json {
        match self {
            PyValue::None => Json::Null,
            PyValue::Bool(b) => Json::Bool(*b),
            PyValue::Int(i) => Json::Int(*i),
            PyValue::BigInt(s) => Json::BigInt(s.clone()),
            PyValue::Float(f) => Json::Float(*f),
            PyValue::Str(s) => Json::Str(s.clone()),
            PyValue::Tuple(v) | PyValue::List(v) => Json::Arr(v.iter().map(PyValue::to_json).collect()),
            PyValue::Np(_, v) | PyValue::Sub(_, v) => v.to_json(),
            PyValue::Opaque(_) => Json::Str(self.py_repr()),
        }
    }
}

fn int_of(s: &str) -> Option<PyValue> {
    let digits = s.strip_prefix('-').unwrap_or(s);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some(s.parse::<i128>().map_or_else(|_| PyValue::BigInt(normalize(s)), PyValue::Int))
}

/// Decimal text without leading zeros (and no "-0").
fn normalize(s: &str) -> String {
    let (neg, digits) = s.strip_prefix('-').map_or((false, s), |d| (true, d));
    let digits = digits.trim_start_matches('0');
    match (neg, digits.is_empty()) {
        (_, true) => "0".into(),
        (true, false) => format!("-{digits}"),
        (false, false) => digits.to_string(),
    }
}

/// A number as Python's numeric tower compares it.
enum Num<'a> {
    Int(i128),
    Big(&'a str),
    Float(f64),
}

impl<'a> Num<'a> {
    fn of(v: &'a PyValue) -> Option<Num<'a>> {
        match v {
            PyValue::Bool(b) => Some(Num::Int(*b as i128)),
            PyValue::Int(i) => Some(Num::Int(*i)),
            PyValue::BigInt(s) => Some(Num::Big(s)),
            PyValue::Float(f) => Some(Num::Float(*f)),
            _ => None,
        }
    }

    fn eq(&self, other: &Num) -> bool {
        match (self, other) {
            (Num::Int(a), Num::Int(b)) => a == b,
            (Num::Big(a), Num::Big(b)) => a == b,
            (Num::Float(a), Num::Float(b)) => a == b,
            (Num::Int(i), Num::Float(f)) | (Num::Float(f), Num::Int(i)) => {
                // Exact, as CPython compares an int with a float: a float
                // below 2^127 in magnitude converts to i128 without loss.
                f.is_finite() && f.fract() == 0.0 && f.abs() < 1.7e38 && (*f as i128) == *i
            }
            (Num::Big(s), Num::Float(f)) | (Num::Float(f), Num::Big(s)) => {
                // Rust prints an integral f64 with every digit, exactly.
                f.is_finite() && f.fract() == 0.0 && format!("{f:.0}") == *s
            }
            (Num::Int(_), Num::Big(_)) | (Num::Big(_), Num::Int(_)) => false,
        }
    }
}

/// The lab's reference tuple `((x, y), [(x, y), …], [d, …])` as a value.
pub fn info_value(info: &MatchInfo) -> PyValue {
    let pt = |(x, y): (i64, i64)| PyValue::Tuple(vec![PyValue::Int(x as i128), PyValue::Int(y as i128)]);
    PyValue::Tuple(vec![
        pt(info.query),
        PyValue::List(info.points.iter().copied().map(pt).collect()),
        PyValue::List(info.distances.iter().map(|&d| PyValue::Float(d as f64)).collect()),
    ])
}

/// What the lab's base class asserts of matching_info's three items (a
/// `tuple`, a `list`, a `list`, exactly those types), or `None` when they
/// hold; the returned value is the harness's `(a, b, c)`.
pub fn info_type_problem(v: &PyValue) -> Option<String> {
    let PyValue::Tuple(parts) = v else {
        return Some(format!("matching_info must return ((x, y), [(x, y), ...], [d, ...]), got {}", v.type_name()));
    };
    if parts.len() != 3 {
        return Some(format!(
            "matching_info must return ((x, y), [(x, y), ...], [d, ...]), got a tuple of {} items",
            parts.len()
        ));
    }
    let named = [
        ("the feature's coordinates", "tuple"),
        ("the matches' coordinates", "list"),
        ("the matches' distances", "list"),
    ];
    for (part, (what, want)) in parts.iter().zip(named) {
        let ok = matches!((part, want), (PyValue::Tuple(_), "tuple") | (PyValue::List(_), "list"));
        if !ok {
            return Some(format!(
                "matching_info: {what} must be a {want}, got {}",
                crate::escape::escaped(part.type_name(), 60)
            ));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use siftlab_core::json::parse;

    fn v(text: &str) -> PyValue {
        PyValue::from_json(&parse(text).unwrap())
    }

    #[test]
    fn python_equality_over_the_encoded_types() {
        // True == 1 == 1.0; 0.1 != 0.1 as float32 widened.
        assert!(v("true").py_eq(&v("1")) && v("1").py_eq(&v("1.0")) && v("true").py_eq(&v("1.0")));
        assert!(!v("0.1").py_eq(&v("0.10000000149011612")));
        // Ints beyond i64 and i128 against floats, exactly as CPython: 2**53 + 1 != 2.0**53.
        assert!(v(r#"{"int": "9007199254740992"}"#).py_eq(&v("9007199254740992.0")));
        assert!(!v(r#"{"int": "9007199254740993"}"#).py_eq(&v("9007199254740992.0")));
        let big = format!("{:.0}", 1e40_f64);
        assert!(v(&format!(r#"{{"int": "{big}"}}"#)).py_eq(&v("1e40")));
        assert!(!v(r#"{"int": "10000000000000000000000000000000000000000"}"#).py_eq(&v("1e40")));
        // NaN equals nothing, itself included; an opaque value likewise.
        assert!(!v(r#"{"float": "nan"}"#).py_eq(&v(r#"{"float": "nan"}"#)));
        assert!(v(r#"{"float": "inf"}"#).py_eq(&v(r#"{"float": "inf"}"#)));
        assert!(!v(r#"{"opaque": "Always"}"#).py_eq(&v(r#"{"opaque": "Always"}"#)));
        // A tuple is not a list; a subclass is its base value; numpy scalars are their value.
        assert!(!v(r#"{"tuple": [1, 2]}"#).py_eq(&v(r#"{"list": [1, 2]}"#)));
        assert!(v(r#"{"tuple": [1, 2], "sub": "Always"}"#).py_eq(&v(r#"{"tuple": [1, 2]}"#)));
        assert!(!v(r#"{"tuple": [9, 9], "sub": "Always"}"#).py_eq(&v(r#"{"tuple": [1, 2]}"#)));
        assert!(v(r#"{"np": "float32", "value": 0.10000000149011612}"#).py_eq(&v("0.10000000149011612")));
        assert!(v(r#"{"np": "int64", "value": 523}"#).py_eq(&v("523.0")));
        // A plain str travels as a JSON string, a subclass tagged.
        assert_eq!(v(r#""5.0""#), PyValue::Str("5.0".into()));
        assert!(!v(r#""5.0""#).py_eq(&v("5.0")) && v(r#""a""#).py_eq(&v(r#"{"str": "a", "sub": "S"}"#)));
        // Forged or damaged encodings are opaque: equal to nothing.
        for bad in ["[1, 2]", r#"{"tuple": 3}"#, r#"{"int": "12a"}"#, r#"{"what": 1}"#, "{}"] {
            assert!(matches!(v(bad), PyValue::Opaque(_)), "{bad}");
        }
    }

    #[test]
    fn the_reference_tuple_and_its_types() {
        let info = MatchInfo { query: (523, 181), points: vec![(517, 183)], distances: vec![61.4] };
        let want = info_value(&info);
        assert_eq!(want.py_repr(), "((523, 181), [(517, 183)], [61.400001525878906])");
        let got = v(
            r#"{"tuple": [{"tuple": [523, 181]}, {"list": [{"tuple": [517, 183.0]}]}, {"list": [61.400001525878906]}]}"#,
        );
        assert!(got.py_eq(&want) && info_type_problem(&got).is_none());
        let sub = v(r#"{"tuple": [{"tuple": [523, 181], "sub": "P"}, {"list": []}, {"list": []}]}"#);
        assert_eq!(info_type_problem(&sub).unwrap(), "matching_info: the feature's coordinates must be a tuple, got P");
        assert_eq!(sub.py_repr(), "(P((523, 181)), [], [])");
        let ctl = v("{\"opaque\": \"\\u001b[2J\"}");
        assert_eq!(ctl.py_repr(), "<\\x1b[2J object>");
    }
}
