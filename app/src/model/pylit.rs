//! A small reader for the Python literals a student pastes from their own
//! `get_info` output: tuples, lists, ints, floats, `None`, strings and
//! numpy scalar wrappers such as `np.float32(61.4)` (what numpy 2 prints).
//!
//! It only reads; what the values *should* be comes from the core.

#[derive(Debug, Clone, PartialEq)]
pub enum Py {
    Int(i128),
    /// The value and the text it was written as (to tell `61.4` from `61.400001525878906`).
    Float(f64, String),
    Str(String),
    None,
    Bool(bool),
    Tuple(Vec<Py>),
    List(Vec<Py>),
    /// `name(args)`, e.g. `np.float32(61.4)`.
    Call(String, Vec<Py>),
}

impl Py {
    /// The numeric value of an int, a float or a numpy scalar wrapping one.
    pub fn number(&self) -> Option<f64> {
        match self {
            Py::Int(i) => Some(*i as f64),
            Py::Float(f, _) => Some(*f),
            Py::Call(_, args) if args.len() == 1 => args[0].number(),
            _ => None,
        }
    }

    pub fn items(&self) -> Option<&[Py]> {
        match self {
            Py::Tuple(v) | Py::List(v) => Some(v),
            _ => None,
        }
    }
}

struct P<'a> {
    s: &'a [u8],
    i: usize,
    /// Brackets open around the current value.
    depth: usize,
}

/// The deepest nesting read: the lab's answer has 3 levels. Each level is a
/// recursive call, and a pasted `[[[[…` thousands deep would overflow the
/// stack (1 MB on wasm32) and kill the page (found by fuzzing,
/// tests/fuzz/regressions/app_state).
const MAX_DEPTH: usize = 32;

impl P<'_> {
    fn ws(&mut self) {
        while self.i < self.s.len() && (self.s[self.i] as char).is_whitespace() {
            self.i += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.ws();
        self.s.get(self.i).copied()
    }

    fn err<T>(&self, what: &str) -> Result<T, String> {
        Err(format!("{what} at character {}", self.i + 1))
    }

    fn seq(&mut self, close: u8) -> Result<(Vec<Py>, bool), String> {
        if self.depth >= MAX_DEPTH {
            return self.err(&format!("brackets nested more than {MAX_DEPTH} deep"));
        }
        self.depth += 1;
        let r = self.seq_items(close);
        self.depth -= 1;
        r
    }

    fn seq_items(&mut self, close: u8) -> Result<(Vec<Py>, bool), String> {
        // Returns the items and whether a comma was seen (to tell `(x)` from `(x,)`).
        let mut items = Vec::new();
        let mut comma = false;
        loop {
            if self.peek() == Some(close) {
                self.i += 1;
                return Ok((items, comma));
            }
            items.push(self.value()?);
            match self.peek() {
                Some(b',') => {
                    self.i += 1;
                    comma = true;
                }
                Some(c) if c == close => {}
                Some(_) => return self.err(&format!("expected ',' or '{}'", close as char)),
                None => return self.err(&format!("missing '{}'", close as char)),
            }
        }
    }

    fn value(&mut self) -> Result<Py, String> {
        match self.peek() {
            None => self.err("unexpected end"),
            Some(b'(') => {
                self.i += 1;
                let (mut items, comma) = self.seq(b')')?;
                if items.len() == 1 && !comma {
                    Ok(items.remove(0))
                } else {
                    Ok(Py::Tuple(items))
                }
            }
            Some(b'[') => {
                self.i += 1;
                Ok(Py::List(self.seq(b']')?.0))
            }
            Some(q @ (b'\'' | b'"')) => {
                self.i += 1;
                let start = self.i;
                while self.i < self.s.len() && self.s[self.i] != q {
                    self.i += 1;
                }
                if self.i >= self.s.len() {
                    return self.err("unterminated string");
                }
                let text = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                self.i += 1;
                Ok(Py::Str(text))
            }
            Some(c) if c == b'-' || c == b'+' || c == b'.' || c.is_ascii_digit() => self.number(),
            Some(c) if c.is_ascii_alphabetic() || c == b'_' => {
                let start = self.i;
                while self.i < self.s.len()
                    && (self.s[self.i].is_ascii_alphanumeric() || b"_.".contains(&self.s[self.i]))
                {
                    self.i += 1;
                }
                let name = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                match name.as_str() {
                    "None" => Ok(Py::None),
                    "True" => Ok(Py::Bool(true)),
                    "False" => Ok(Py::Bool(false)),
                    "inf" => Ok(Py::Float(f64::INFINITY, name)),
                    "nan" => Ok(Py::Float(f64::NAN, name)),
                    _ if self.peek() == Some(b'(') => {
                        self.i += 1;
                        Ok(Py::Call(name, self.seq(b')')?.0))
                    }
                    _ => self.err(&format!("unexpected name {name:?}")),
                }
            }
            Some(c) => self.err(&format!("unexpected character {:?}", c as char)),
        }
    }

    fn number(&mut self) -> Result<Py, String> {
        let start = self.i;
        if matches!(self.s.get(self.i), Some(b'-' | b'+')) {
            self.i += 1;
        }
        let mut float = false;
        while let Some(&c) = self.s.get(self.i) {
            if c.is_ascii_digit() {
                self.i += 1;
            } else if c == b'.' || c == b'e' || c == b'E' {
                float = true;
                self.i += 1;
                if (c == b'e' || c == b'E') && matches!(self.s.get(self.i), Some(b'-' | b'+')) {
                    self.i += 1;
                }
            } else {
                break;
            }
        }
        let text = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
        if float {
            text.parse::<f64>().map(|v| Py::Float(v, text.clone())).or_else(|_| self.err("bad number"))
        } else {
            text.parse::<i128>().map(Py::Int).or_else(|_| self.err("bad number"))
        }
    }
}

/// Parses one literal; a leading `ret value:` (the whole line pasted) is skipped.
pub fn parse(text: &str) -> Result<Py, String> {
    let t = text.trim();
    let t = t.strip_prefix("ret value:").unwrap_or(t);
    let mut p = P { s: t.as_bytes(), i: 0, depth: 0 };
    let v = p.value()?;
    if p.peek().is_some() {
        return p.err("unexpected text after the value");
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deep_nesting_is_an_error_not_a_stack_overflow() {
        let deep = "[".repeat(200_000);
        assert!(parse(&deep).unwrap_err().contains("nested more than 32 deep"));
        let ok = format!("{}1{}", "(".repeat(32), ")".repeat(32));
        assert_eq!(parse(&ok).unwrap(), Py::Int(1));
    }

    #[test]
    fn reads_the_lab_tuple() {
        let v = parse("ret value: ((523, 181), [(517, 183)], [61.400001525878906])").unwrap();
        assert_eq!(
            v,
            Py::Tuple(vec![
                Py::Tuple(vec![Py::Int(523), Py::Int(181)]),
                Py::List(vec![Py::Tuple(vec![Py::Int(517), Py::Int(183)])]),
                Py::List(vec![Py::Float(61.400001525878906, "61.400001525878906".into())]),
            ])
        );
    }

    #[test]
    fn reads_empty_answer_numpy_scalars_and_negatives() {
        assert_eq!(
            parse("((0, 0), [], [])").unwrap(),
            Py::Tuple(vec![Py::Tuple(vec![Py::Int(0), Py::Int(0)]), Py::List(vec![]), Py::List(vec![])])
        );
        let v = parse("[np.float32(61.4), -2, 1e3, (7,)]").unwrap();
        let items = v.items().unwrap();
        assert_eq!(items[0].number(), Some(61.4));
        assert_eq!(items[1], Py::Int(-2));
        assert_eq!(items[2].number(), Some(1000.0));
        assert_eq!(items[3], Py::Tuple(vec![Py::Int(7)]));
        // A parenthesised value without a comma is the value itself, as in Python.
        assert_eq!(parse("(5)").unwrap(), Py::Int(5));
    }

    #[test]
    fn reports_where_it_fails() {
        assert_eq!(parse("((1, 2), [").unwrap_err(), "unexpected end at character 11");
        assert!(parse("((1, 2) [])").unwrap_err().starts_with("expected ',' or ')'"));
        assert!(parse("(1, 2) x").unwrap_err().contains("unexpected text after the value"));
    }
}
