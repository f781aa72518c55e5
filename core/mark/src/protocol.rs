//! The messages between the host (the CLI, or the app's worker) and
//! `www/py/siftlab_harness.py`, one JSON object a line (docs/marking.md
//! §Messages); the host's answer to the harness's `knnMatch` requests is
//! `knn.rs`.

use crate::b64::base64;
use crate::cases::Case;
use crate::reference::Expected;
use siftlab_core::json::{parse, quote, Json};
use siftlab_core::pyfmt::py_f32;
use siftlab_core::sift::{Features, KeyPoint};
use std::fmt::Write as _;

/// A frame pair the harness has been sent: `prev` (FRAME_ID-1) is the
/// query side (kp1/des1), `cur` the train side.
#[derive(Clone, Debug, Default)]
pub struct Pair {
    pub id: u32,
    pub prev: Features,
    pub cur: Features,
}

/// `{"op": "load", "source": …}`: the student's file.
pub fn load_message(source: &str) -> String {
    format!("{{\"op\": \"load\", \"source\": {}}}", quote(source))
}

/// `{"op": "pair", "id", "kp1", "des1", "kp2", "des2"}`: keypoints as
/// `[x, y, size, angle, response, octave]` (each f32 printed exactly),
/// descriptors as base64 of their N×128 bytes.
pub fn pair_message(id: u32, prev: &Features, cur: &Features) -> String {
    let mut s = String::with_capacity(16 * 128 * (prev.descriptors.len() + cur.descriptors.len()) / 12 + 1024);
    let _ = write!(s, "{{\"op\": \"pair\", \"id\": {id}");
    for (name, f) in [("1", prev), ("2", cur)] {
        let _ = write!(s, ", \"kp{name}\": ");
        push_keypoints(&mut s, &f.keypoints);
        let _ = write!(s, ", \"des{name}\": \"{}\"", base64(f.descriptors.as_flattened()));
    }
    s.push('}');
    s
}

fn push_keypoints(s: &mut String, kps: &[KeyPoint]) {
    s.push('[');
    for (i, k) in kps.iter().enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        let _ = write!(
            s,
            "[{}, {}, {}, {}, {}, {}]",
            py_f32(k.x),
            py_f32(k.y),
            py_f32(k.size),
            py_f32(k.angle),
            py_f32(k.response),
            k.octave
        );
    }
    s.push(']');
}

/// `{"op": "call", "fn", "pair", …}`: dt / nn / nndr with `threshold`
/// (null for None) and `"compact": true` (the lists come back as base64
/// arrays); matching_info with `matches` as `[[q, t, d], …]`, the reference
/// matches of the case. The expected value never goes to the harness: the
/// reply is judged here.
pub fn call_message(case: &Case, pair: u32, expected: &Expected) -> String {
    let name = case.task().name();
    match (case, expected) {
        (Case::Info { .. }, Expected::Info { matches, .. }) => {
            let mut s = format!("{{\"op\": \"call\", \"fn\": \"{name}\", \"pair\": {pair}, \"matches\": [");
            for (i, m) in matches.iter().enumerate() {
                if i > 0 {
                    s.push_str(", ");
                }
                let _ = write!(s, "[{}, {}, {}]", m.query_idx, m.train_idx, py_f32(m.distance));
            }
            s.push_str("]}");
            s
        }
        _ => {
            let t = case.strategy().threshold();
            let t = t.map_or("null".to_string(), siftlab_core::pyfmt::py_float);
            format!("{{\"op\": \"call\", \"fn\": \"{name}\", \"pair\": {pair}, \"threshold\": {t}, \"compact\": true}}")
        }
    }
}

/// A request with its id: `{"req": ID, …}`. The harness echoes the id in its
/// reply; a line with another id is never taken for this request's reply.
pub fn with_id(id: u64, message: &str) -> String {
    match message.strip_prefix('{') {
        Some(rest) => format!("{{\"req\": {id}, {rest}"),
        None => message.to_string(),
    }
}

/// The longest line siftlab reads from the harness; a longer one is dropped
/// as it is read, never held. The largest honest line is dt's compact reply:
/// 16 bytes of base64 a match, so at most 16 × 1502 × 1502 = 36.1 MB (every
/// pair of the largest frames under the threshold) plus the student's
/// output (at most 24 KB escaped). The good solution's largest on the demo
/// frames is 11.8 MB (frame 133, threshold 500: 735,610 matches).
pub const MAX_LINE_BYTES: usize = 40 << 20;

/// Characters of a student's message (an exception's text) kept.
pub const MAX_MESSAGE_CHARS: usize = 2000;

/// What a failed `load` or `call` was, as the harness names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file does not compile.
    Syntax,
    /// It imports a module the lab's Python does not have.
    Import,
    /// An exception.
    Runtime,
    /// A return value of the wrong type or shape.
    Type,
    /// The harness refused the request itself (a fault of siftlab's).
    Protocol,
}

impl ErrorKind {
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::Syntax => "syntax",
            ErrorKind::Import => "import",
            ErrorKind::Runtime => "runtime",
            ErrorKind::Type => "type",
            ErrorKind::Protocol => "protocol",
        }
    }
}

/// The harness's answer to `load`, `pair` or `call`.
#[derive(Clone, Debug, PartialEq)]
pub enum Reply {
    /// `{"ok": VALUE}`: dt/nn/nndr's lists, matching_info's typed value
    /// (`PyValue`), or `true`.
    Ok { value: Json },
    /// `{"error": MSG, "kind": KIND}` (an unknown kind is a runtime error);
    /// the message escaped and bounded (it is the student's text).
    Error { message: String, kind: ErrorKind },
}

/// One line from the harness, read for the request `id`.
#[derive(Clone, Debug, PartialEq)]
pub enum HarnessLine {
    /// The reply to the request.
    Reply(Reply),
    /// `{"op": "knn", …}`: answer it with [`knn_answer`](crate::knn_answer).
    Knn,
    /// Anything else (not JSON, another id, no id, a reply of no known
    /// shape): dropped, never taken for a reply; the text says why.
    Stray(String),
}

/// The most JSON values a line from the harness may hold. Its largest
/// honest lines are matching_info's typed value, at most 100,000 items
/// (the harness's MAX_NODES) of at most 5 values each, and dt's compact
/// lists (one value per query plus a few strings). A parsed value takes
/// 32–56 bytes, so a line within this bound parses into at most ~60 MB
/// whatever its shape (`[0,0,…]` would be 16 bytes of tree per byte).
pub const MAX_LINE_VALUES: usize = 1 << 20;

/// An upper bound of the values in a JSON text: one per `[`, `{` and `,`
/// outside strings, plus one; counted without parsing (or allocating).
pub fn values_bound(line: &str) -> usize {
    let (mut n, mut in_str, mut esc) = (1usize, false, false);
    for &b in line.as_bytes() {
        if in_str {
            match (esc, b) {
                (true, _) => esc = false,
                (false, b'\\') => esc = true,
                (false, b'"') => in_str = false,
                _ => {}
            }
        } else {
            match b {
                b'"' => in_str = true,
                b'[' | b'{' | b',' => n = n.saturating_add(1),
                _ => {}
            }
        }
    }
    n
}

/// Reads a line the harness wrote while siftlab waits for the reply to
/// request `id`.
pub fn parse_line(line: &str, id: u64) -> HarnessLine {
    if values_bound(line) > MAX_LINE_VALUES {
        return HarnessLine::Stray(bad_line(line, &format!("more than {MAX_LINE_VALUES} values")));
    }
    let v = match parse(line) {
        Ok(v) => v,
        Err(e) => return HarnessLine::Stray(bad_line(line, &e)),
    };
    if v.get("op").and_then(Json::as_str) == Some("knn") {
        return HarnessLine::Knn;
    }
    match v.get("req").and_then(Json::as_i64) {
        Some(got) if u64::try_from(got) == Ok(id) => {}
        Some(got) => return HarnessLine::Stray(format!("a line for request {got}, not {id}")),
        None => return HarnessLine::Stray(bad_line(line, "no request id")),
    }
    match reply_of(v) {
        Ok(r) => HarnessLine::Reply(r),
        Err(e) => HarnessLine::Stray(bad_line(line, &e)),
    }
}

/// Reads a reply line for request `id` (a knn request or a stray line
/// here is an error).
pub fn parse_reply(line: &str, id: u64) -> siftlab_core::Result<Reply> {
    match parse_line(line, id) {
        HarnessLine::Reply(r) => Ok(r),
        HarnessLine::Knn => {
            Err(siftlab_core::Error::InvalidArgument("a knn request where a reply was expected".into()))
        }
        HarnessLine::Stray(why) => Err(siftlab_core::Error::InvalidArgument(why)),
    }
}

fn bad_line(line: &str, why: &str) -> String {
    format!("a line siftlab cannot read ({why}): {}", crate::escape::escaped(line, 200))
}

fn reply_of(v: Json) -> Result<Reply, String> {
    let Json::Obj(kv) = v else {
        return Err("not a JSON object".into());
    };
    let mut value = None;
    let mut message = None;
    let mut kind = None;
    for (k, v) in kv {
        match k.as_str() {
            "ok" => value = Some(v),
            "error" => message = Some(v.as_str().map_or_else(|| v.py_repr(), str::to_string)),
            "kind" => kind = v.as_str().map(str::to_string),
            _ => {}
        }
    }
    if let Some(message) = message {
        let kind = match kind.as_deref() {
            Some("syntax") => ErrorKind::Syntax,
            Some("import") => ErrorKind::Import,
            Some("type") => ErrorKind::Type,
            Some("protocol") => ErrorKind::Protocol,
            _ => ErrorKind::Runtime,
        };
        return Ok(Reply::Error { message: crate::escape::escaped(&message, MAX_MESSAGE_CHARS), kind });
    }
    match value {
        Some(value) => Ok(Reply::Ok { value }),
        None => Err("neither \"ok\" nor \"error\"".into()),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::b64::unbase64;
    use siftlab_core::matching::{DMatch, MatchInfo, Strategy};

    /// `n` keypoints with distinct descriptors (also the knn tests' features).
    pub(crate) fn features(n: usize, seed: u8) -> Features {
        let kp = KeyPoint { x: 523.97, y: 181.2, size: 2.5, angle: 359.9, response: 0.0123, octave: 0x10203 };
        Features {
            keypoints: vec![kp; n],
            descriptors: (0..n)
                .map(|i| std::array::from_fn(|j| ((i * 7 + j * 13 + seed as usize) % 256) as u8))
                .collect(),
        }
    }

    #[test]
    fn messages_are_the_documented_json() {
        let load = parse(&load_message("class VisionTasks:\n\tpass\r\n")).unwrap();
        assert_eq!(load.get("source").unwrap().as_str(), Some("class VisionTasks:\n\tpass\r\n"));
        let (a, b) = (features(3, 0), features(2, 5));
        let p = parse(&pair_message(12, &a, &b)).unwrap();
        assert_eq!(p.get("id"), Some(&Json::Int(12)));
        let kp = &p.get("kp1").unwrap().as_arr().unwrap()[0];
        assert_eq!(
            kp.py_repr(),
            "[523.969970703125, 181.1999969482422, 2.5, 359.8999938964844, 0.012299999594688416, 66051]"
        );
        assert_eq!(unbase64(p.get("des2").unwrap().as_str().unwrap()).unwrap(), b.descriptors.as_flattened());
        let none = Expected::Matches(Vec::new());
        let c = Case::Nn { frame: 12, threshold: None };
        assert_eq!(
            call_message(&c, 12, &none),
            r#"{"op": "call", "fn": "nn", "pair": 12, "threshold": null, "compact": true}"#
        );
        let c = Case::Dt { frame: 3, threshold: 500.0 };
        assert_eq!(
            call_message(&c, 3, &none),
            r#"{"op": "call", "fn": "dt", "pair": 3, "threshold": 500.0, "compact": true}"#
        );
        let c = Case::Info { frame: 3, strategy: Strategy::Nn(None), feature: 1 };
        let e = Expected::Info {
            matches: vec![DMatch { query_idx: 1, train_idx: 928, distance: 61.4 }],
            info: MatchInfo { query: (523, 181), points: vec![(517, 183)], distances: vec![61.4] },
        };
        assert_eq!(
            call_message(&c, 3, &e),
            r#"{"op": "call", "fn": "matching_info", "pair": 3, "matches": [[1, 928, 61.400001525878906]]}"#
        );
    }

    #[test]
    fn replies_and_requests_are_read() {
        assert_eq!(with_id(7, r#"{"op": "hello"}"#), r#"{"req": 7, "op": "hello"}"#);
        assert_eq!(parse_reply(r#"{"req": 4, "ok": true}"#, 4).unwrap(), Reply::Ok { value: Json::Bool(true) });
        assert_eq!(
            parse_reply(r#"{"error": "line 3: invalid syntax", "kind": "syntax", "req": 1}"#, 1).unwrap(),
            Reply::Error { message: "line 3: invalid syntax".into(), kind: ErrorKind::Syntax }
        );
        assert_eq!(
            parse_reply(r#"{"req": 2, "error": "no pair 3", "kind": "protocol"}"#, 2).unwrap(),
            Reply::Error { message: "no pair 3".into(), kind: ErrorKind::Protocol }
        );
        // Fields the harness does not send (a forged "equal") change nothing.
        let r = parse_reply(r#"{"req":9,"ok":[[1,2],[],[]],"repr":"x","equal":true,"output":"hi\n"}"#, 9).unwrap();
        assert_eq!(r, Reply::Ok { value: parse("[[1,2],[],[]]").unwrap() });
        assert_eq!(parse_line(r#"{"op":"knn","qid":"1/1","tid":"1/2","k":2}"#, 3), HarnessLine::Knn);
        // Stray lines: never a reply, never an error that ends the marking.
        for (line, why) in [
            ("Traceback (most recent call last):", "cannot read"),
            (r#"{"ok": true}"#, "no request id"),
            (r#"{"req": 5, "ok": true}"#, "request 5, not 6"),
            (r#"{"req": 6, "x": 1}"#, "neither"),
            ("{\"req\": 6, \"ok\": [[[[[[[[", "cannot read"),
        ] {
            match parse_line(line, 6) {
                HarnessLine::Stray(w) => assert!(w.contains(why), "{line}: {w}"),
                other => panic!("{line}: {other:?}"),
            }
        }
        // A line that would parse into millions of values is not parsed.
        let flat = format!("{{\"req\": 6, \"ok\": [{}0]}}", "0,".repeat(MAX_LINE_VALUES));
        match parse_line(&flat, 6) {
            HarnessLine::Stray(w) => assert!(w.contains("more than 1048576 values"), "{w}"),
            other => panic!("{other:?}"),
        }
        assert_eq!(values_bound(r#"{"a": "[,{\"", "b": [1, 2]}"#), 5);
        assert_eq!(values_bound(""), 1);
        // A student's message: control characters escaped, the length bounded.
        let long = format!("{{\"req\": 1, \"error\": \"\\u001b[2J{}\", \"kind\": \"runtime\"}}", "x".repeat(5000));
        let Reply::Error { message, .. } = parse_reply(&long, 1).unwrap() else { panic!() };
        assert!(message.starts_with("\\x1b[2Jxxx") && message.ends_with("more characters)"), "{message}");
    }
}
