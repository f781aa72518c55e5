//! Text a student's file controls (exception messages, what it printed,
//! a crash's stderr, class names) made safe to print: every control
//! character, and the Unicode marks that reorder or hide text, shown as an
//! escape (`\x1b`, `\n`, `\u202e`), and the length bounded. A report line
//! can then hold nothing that moves the cursor, repaints the screen or
//! starts a line that looks like the marks table.

/// `text` with control and formatting characters escaped, cut to `max`
/// characters (saying how many were left out).
pub fn escaped(text: &str, max: usize) -> String {
    let mut out = String::with_capacity(text.len().min(max + 16));
    let mut chars = text.chars();
    for (shown, c) in chars.by_ref().enumerate() {
        if shown >= max {
            let rest = 1 + chars.count();
            out.push_str(&format!(" … ({rest} more characters)"));
            return out;
        }
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 || c as u32 == 0x7f => out.push_str(&format!("\\x{:02x}", c as u32)),
            c if hidden(c) => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out
}

/// C1 controls, bidirectional overrides and isolates, zero-width and other
/// invisible formatting characters.
fn hidden(c: char) -> bool {
    matches!(c as u32,
        0x80..=0x9f | 0xad | 0x061c | 0x180e | 0x200b..=0x200f | 0x2028..=0x202e | 0x2060..=0x206f | 0xfeff
        | 0xfff9..=0xfffb)
}

/// Whether `text` holds nothing [`escaped`] would escape but newlines.
pub fn is_clean(text: &str) -> bool {
    text.chars().all(|c| c == '\n' || !(c.is_control() || hidden(c)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controls_are_shown_not_obeyed() {
        assert_eq!(
            escaped("\x1b[2J\x1b[Hvision_tasks.py: 20.00 / 20\n", 100),
            "\\x1b[2J\\x1b[Hvision_tasks.py: 20.00 / 20\\n"
        );
        assert_eq!(escaped("a\u{202e}b\u{9b}c\r", 100), "a\\u202eb\\u009bc\\r");
        assert_eq!(escaped("héllo wörld", 5), "héllo … (6 more characters)");
        assert!(is_clean("line one\nline two é") && !is_clean("x\x07") && !is_clean("\u{200b}"));
    }
}
