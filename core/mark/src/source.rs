//! What is checked before the file is run: its size, that it is not empty,
//! and that it is printable ASCII as the lab requires; and the outcomes that
//! score 0 on every task.

use crate::protocol::ErrorKind;
use std::fmt;

/// Larger files are refused unread (a vision_tasks.py is a few KB).
pub const MAX_SOURCE_BYTES: usize = 1_000_000;

/// Why a file scores 0 on every task without any call being marked.
#[derive(Clone, Debug, PartialEq)]
pub enum Rejection {
    /// No bytes, or only whitespace.
    Empty,
    /// Over [`MAX_SOURCE_BYTES`].
    TooLarge { bytes: usize },
    /// A character the lab does not accept; line and column count from 1
    /// (the column in characters where the text is UTF-8).
    NotAscii { line: usize, column: usize, found: String, binary: bool },
    /// The harness could not load it: a syntax error, a missing module, or
    /// an exception at import or in `VisionTasks()`.
    Load { kind: ErrorKind, message: String },
    /// Loading it ran over the time limit.
    LoadTimeout { seconds: f64 },
}

impl Rejection {
    /// A stable name for the JSON report and tests.
    pub fn code(&self) -> &'static str {
        match self {
            Rejection::Empty => "empty",
            Rejection::TooLarge { .. } => "too_large",
            Rejection::NotAscii { binary: true, .. } => "binary",
            Rejection::NotAscii { .. } => "not_ascii",
            Rejection::Load { kind: ErrorKind::Syntax, .. } => "syntax",
            Rejection::Load { kind: ErrorKind::Import, .. } => "import",
            Rejection::Load { .. } => "load",
            Rejection::LoadTimeout { .. } => "load_timeout",
        }
    }
}

impl fmt::Display for Rejection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Rejection::Empty => write!(f, "the file is empty: it must define class VisionTasks(VisionTasksBase) with dt, nn, nndr and matching_info"),
            Rejection::TooLarge { bytes } => write!(
                f,
                "the file is {bytes} bytes, over the {MAX_SOURCE_BYTES}-byte limit: a vision_tasks.py is a few KB (is it the right file?)"
            ),
            Rejection::NotAscii { line, column, found, binary: true } => write!(
                f,
                "this is not a Python text file: line {line}, column {column} has {found}; the lab accepts printable ASCII only"
            ),
            Rejection::NotAscii { line, column, found, .. } => write!(
                f,
                "the file is not printable ASCII: line {line}, column {column} has {found}; the lab accepts only printable \
                 ASCII, tabs and newlines, and scores any other file 0"
            ),
            Rejection::Load { kind: ErrorKind::Syntax, message } => write!(f, "Python does not accept the file: {message}"),
            Rejection::Load { kind: ErrorKind::Import, message } => {
                write!(f, "the file imports what the lab's Python does not have: {message}")
            }
            Rejection::Load { message, .. } => write!(f, "loading the file or creating VisionTasks() failed: {message}"),
            Rejection::LoadTimeout { seconds } => write!(
                f,
                "loading the file and creating VisionTasks() took over {seconds} s (an endless loop at import?)"
            ),
        }
    }
}

/// The file's text if the lab would run it: not empty, at most
/// [`MAX_SOURCE_BYTES`], printable ASCII plus newline, tab and CRLF.
pub fn check_source(bytes: &[u8]) -> Result<&str, Rejection> {
    if bytes.len() > MAX_SOURCE_BYTES {
        return Err(Rejection::TooLarge { bytes: bytes.len() });
    }
    let (mut line, mut start) = (1, 0);
    for (i, &b) in bytes.iter().enumerate() {
        match b {
            b'\n' => {
                line += 1;
                start = i + 1;
            }
            b'\t' | b' '..=b'~' => {}
            b'\r' if bytes.get(i + 1) == Some(&b'\n') => {}
            _ => {
                // Columns in characters when the line so far is text (it is
                // ASCII up to here), else in bytes.
                let column = i - start + 1;
                let (found, binary) = describe(&bytes[i..], b);
                return Err(Rejection::NotAscii { line, column, found, binary });
            }
        }
    }
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(Rejection::Empty);
    }
    // Every byte is ASCII here.
    std::str::from_utf8(bytes).map_err(|_| Rejection::Empty)
}

/// The offending character (decoded if it starts valid UTF-8) and whether
/// the file looks binary.
fn describe(rest: &[u8], b: u8) -> (String, bool) {
    if b == b'\r' {
        return (
            "a carriage return not followed by a newline (old Mac line ending): save with \\n or \\r\\n".into(),
            false,
        );
    }
    if b < 0x80 {
        let binary = b == 0 || !matches!(b, 0x0b | 0x0c | 0x1b | 0x7f);
        return (format!("the control character 0x{b:02x}"), binary);
    }
    let len = match b {
        0xc2..=0xdf => 2,
        0xe0..=0xef => 3,
        0xf0..=0xf4 => 4,
        _ => 0,
    };
    let ch = rest.get(..len).and_then(|s| std::str::from_utf8(s).ok()).and_then(|s| s.chars().next());
    match ch {
        Some(c) => {
            let hint = match c {
                '\u{2018}' | '\u{2019}' | '\u{201c}' | '\u{201d}' => ", a typographic quote: use ' or \"",
                '\u{a0}' | '\u{202f}' | '\u{2009}' => ", a non-breaking or thin space: use a plain space",
                '\u{2013}' | '\u{2014}' | '\u{2212}' => ", a dash: use -",
                '\u{feff}' => ", a byte-order mark: save the file as plain ASCII",
                '\u{d7}' => ", a multiplication sign: use *",
                _ => "",
            };
            (format!("'{c}' (U+{:04X}{hint})", c as u32), false)
        }
        None => (format!("the byte 0x{b:02x}, which is not text"), true),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_rules() {
        assert_eq!(check_source(b"x = 1\r\n\ty = 2\n"), Ok("x = 1\r\n\ty = 2\n"));
        assert_eq!(check_source(b""), Err(Rejection::Empty));
        assert_eq!(check_source(b" \n\n\t"), Err(Rejection::Empty));
        let r = check_source("# ok\nx = \u{2019}a\u{2019}\n".as_bytes()).unwrap_err();
        assert_eq!(
            r,
            Rejection::NotAscii {
                line: 2,
                column: 5,
                found: "'\u{2019}' (U+2019, a typographic quote: use ' or \")".into(),
                binary: false
            }
        );
        assert!(r.to_string().contains("line 2, column 5"));
        let r = check_source(b"\x89PNG\r\n\x1a\n\0\0").unwrap_err();
        assert_eq!(r.code(), "binary");
        assert!(r.to_string().contains("not a Python text file"), "{r}");
        assert_eq!(check_source(b"a\x00b").unwrap_err().code(), "binary");
        assert_eq!(check_source(b"a\rb").unwrap_err().code(), "not_ascii");
        assert_eq!(check_source(b"a\x0cb").unwrap_err().code(), "not_ascii");
        let big = vec![b'#'; MAX_SOURCE_BYTES + 1];
        assert_eq!(check_source(&big), Err(Rejection::TooLarge { bytes: MAX_SOURCE_BYTES + 1 }));
        assert!(check_source(&big[1..]).is_ok());
    }
}
