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

use crate::pyfmt::{py_float, py_str};

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

/// Parses one JSON text (surrounding whitespace allowed).
pub fn parse(text: &str) -> Result<Json, String> {
    let mut p = Parser { s: text.as_bytes(), i: 0, depth: 0 };
    let v = p.value()?;
    p.ws();
    if p.i != p.s.len() {
        return Err(format!("unexpected text after the JSON value at byte {}", p.i));
    }
    Ok(v)
}

/// Nesting deeper than this is refused rather than recursed into.
const MAX_DEPTH: usize = 512;

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
    depth: usize,
}

impl Parser<'_> {
    fn ws(&mut self) {
        while self.i < self.s.len() && matches!(self.s[self.i], b' ' | b'\t' | b'\n' | b'\r') {
            self.i += 1;
        }
    }

    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    fn err<T>(&self, what: &str) -> Result<T, String> {
        Err(format!("{what} at byte {}", self.i))
    }

    fn lit(&mut self, word: &str, v: Json) -> Result<Json, String> {
        if self.s[self.i..].starts_with(word.as_bytes()) {
            self.i += word.len();
            Ok(v)
        } else {
            self.err("unexpected character")
        }
    }

    fn value(&mut self) -> Result<Json, String> {
        self.ws();
        match self.peek() {
            None => self.err("unexpected end of the JSON text"),
            Some(b'n') => self.lit("null", Json::Null),
            Some(b't') => self.lit("true", Json::Bool(true)),
            Some(b'f') => self.lit("false", Json::Bool(false)),
            Some(b'N') => self.lit("NaN", Json::Float(f64::NAN)),
            Some(b'I') => self.lit("Infinity", Json::Float(f64::INFINITY)),
            Some(b'"') => Ok(Json::Str(self.string()?)),
            Some(b'[') => {
                self.enter()?;
                let mut v = Vec::new();
                self.i += 1;
                self.ws();
                if self.peek() == Some(b']') {
                    self.i += 1;
                } else {
                    loop {
                        v.push(self.value()?);
                        self.ws();
                        match self.peek() {
                            Some(b',') => self.i += 1,
                            Some(b']') => {
                                self.i += 1;
                                break;
                            }
                            _ => return self.err("expected ',' or ']'"),
                        }
                    }
                }
                self.depth -= 1;
                Ok(Json::Arr(v))
            }
            Some(b'{') => {
                self.enter()?;
                let mut kv = Vec::new();
                self.i += 1;
                self.ws();
                if self.peek() == Some(b'}') {
                    self.i += 1;
                } else {
                    loop {
                        self.ws();
                        let k = self.string()?;
                        self.ws();
                        if self.peek() != Some(b':') {
                            return self.err("expected ':'");
                        }
                        self.i += 1;
                        kv.push((k, self.value()?));
                        self.ws();
                        match self.peek() {
                            Some(b',') => self.i += 1,
                            Some(b'}') => {
                                self.i += 1;
                                break;
                            }
                            _ => return self.err("expected ',' or '}'"),
                        }
                    }
                }
                self.depth -= 1;
                Ok(Json::Obj(kv))
            }
            Some(b'-' | b'0'..=b'9') => self.number(),
            Some(_) => self.err("unexpected character"),
        }
    }

    fn enter(&mut self) -> Result<(), String> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return self.err("JSON nested too deeply");
        }
        Ok(())
    }

    fn number(&mut self) -> Result<Json, String> {
        let start = self.i;
        if self.peek() == Some(b'-') {
            self.i += 1;
            if self.s[self.i..].starts_with(b"Infinity") {
                self.i += 8;
                return Ok(Json::Float(f64::NEG_INFINITY));
            }
        }
        let mut float = false;
        while let Some(c) = self.peek() {
            match c {
                b'0'..=b'9' => {}
                b'.' | b'e' | b'E' | b'+' => float = true,
                b'-' => float = true,
                _ => break,
            }
            self.i += 1;
        }
        // The bytes are ASCII, so the slice is valid UTF-8.
        let text = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
        if float {
            text.parse::<f64>().map(Json::Float).or_else(|_| self.err("bad number"))
        } else if text.is_empty() || text == "-" {
            self.err("bad number")
        } else {
            Ok(text.parse::<i128>().map(Json::Int).unwrap_or_else(|_| Json::BigInt(text.to_string())))
        }
    }

    fn hex4(&mut self) -> Result<u32, String> {
        let Some(h) = self.s.get(self.i..self.i + 4) else {
            return self.err("bad \\u escape");
        };
        let v = std::str::from_utf8(h).ok().and_then(|h| u32::from_str_radix(h, 16).ok());
        match v {
            Some(v) => {
                self.i += 4;
                Ok(v)
            }
            None => self.err("bad \\u escape"),
        }
    }

    fn string(&mut self) -> Result<String, String> {
        if self.peek() != Some(b'"') {
            return self.err("expected a string");
        }
        self.i += 1;
        let mut out: Vec<u8> = Vec::new();
        loop {
            let Some(c) = self.peek() else {
                return self.err("unterminated string");
            };
            self.i += 1;
            match c {
                b'"' => break,
                b'\\' => {
                    let Some(e) = self.peek() else {
                        return self.err("unterminated string");
                    };
                    self.i += 1;
                    match e {
                        b'n' => out.push(b'\n'),
                        b't' => out.push(b'\t'),
                        b'r' => out.push(b'\r'),
                        b'b' => out.push(8),
                        b'f' => out.push(12),
                        b'/' => out.push(b'/'),
                        b'\\' => out.push(b'\\'),
                        b'"' => out.push(b'"'),
                        b'u' => {
                            let mut cp = self.hex4()?;
                            if (0xD800..0xDC00).contains(&cp) && self.s[self.i..].starts_with(b"\\u") {
                                let save = self.i;
                                self.i += 2;
                                let lo = self.hex4()?;
                                if (0xDC00..0xE000).contains(&lo) {
                                    cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
                                } else {
                                    self.i = save;
                                }
                            }
                            let ch = char::from_u32(cp).unwrap_or('\u{fffd}');
                            let mut buf = [0u8; 4];
                            out.extend_from_slice(ch.encode_utf8(&mut buf).as_bytes());
                        }
                        _ => return self.err("bad escape"),
                    }
                }
                _ => out.push(c),
            }
        }
        Ok(String::from_utf8(out).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_what_python_writes() {
        let v = parse(
            r#"{"ok": [[[0, 12, 61.400001525878906]], []], "x": NaN, "y": -Infinity, "s": "a\"\u00e9\ud83d\ude00"}"#,
        )
        .unwrap();
        let ok = v.get("ok").unwrap().as_arr().unwrap();
        assert_eq!(
            ok[0].as_arr().unwrap()[0],
            Json::Arr(vec![Json::Int(0), Json::Int(12), Json::Float(61.4f32 as f64)])
        );
        assert!(matches!(v.get("x"), Some(Json::Float(f)) if f.is_nan()));
        assert_eq!(v.get("y"), Some(&Json::Float(f64::NEG_INFINITY)));
        assert_eq!(v.get("s").unwrap().as_str(), Some("a\"é😀"));
        assert_eq!(parse("123456789012345678901234567890123456789012").unwrap().py_repr().len(), 42);
        assert!(parse("[1, 2").is_err());
        assert!(parse("[1] x").is_err());
        assert!(parse("-").is_err());
        assert!(parse(&"[".repeat(10_000)).is_err());
    }

    #[test]
    fn python_equality_and_repr() {
        let a = parse("[[523, 181], [[517, 183]], [61.400001525878906]]").unwrap();
        let b = parse("[[523.0, 181], [[517, 183]], [61.400001525878906]]").unwrap();
        let c = parse("[[523.5, 181], [[517, 183]], [61.4]]").unwrap();
        assert!(a.py_eq(&b));
        assert!(!a.py_eq(&c));
        assert!(!parse("NaN").unwrap().py_eq(&parse("NaN").unwrap()));
        assert_eq!(b.py_repr(), "[[523.0, 181], [[517, 183]], [61.400001525878906]]");
        assert_eq!(
            parse(r#"{"a": null, "b": true, "c": "it's"}"#).unwrap().py_repr(),
            "{'a': None, 'b': True, 'c': \"it's\"}"
        );
    }

    #[test]
    fn f32_as_its_text_names_it() {
        for text in ["0.1", "226.12345", "1e-45", "3.4028235e38", "-0.0", "16777217", "12"] {
            let want: f32 = text.parse().unwrap();
            assert_eq!(parse(text).unwrap().as_f32().map(f32::to_bits), Some(want.to_bits()), "{text}");
        }
        // An f32's exact value as Python writes it (repr of the f64).
        assert_eq!(parse("61.400001525878906").unwrap().as_f32(), Some(61.4f32));
        // Exactly halfway between 1 and the next f32: the text's side is lost.
        assert_eq!(parse("1.000000059604644775390625").unwrap().as_f32(), None);
        assert_eq!(parse("\"1\"").unwrap().as_f32(), None);
    }

    #[test]
    fn writes_ascii_json() {
        assert_eq!(quote("a\"b\\c\nd\u{1}é😀"), r#""a\"b\\c\nd\u0001\u00e9\ud83d\ude00""#);
        let v = Json::Arr(vec![Json::Float(0.8), Json::Float(f64::NAN), Json::Int(-3), Json::Null]);
        assert_eq!(v.to_json(), "[0.8, null, -3, null]");
        assert_eq!(parse(&quote("x\u{7f}\t")).unwrap().as_str(), Some("x\u{7f}\t"));
    }
}
