//! The view's state in the URL query, so a teacher can link a prepared view:
//! `?src=demo&frame=1&feature=7&algo=nndr&t=0.8&ex=42&q=3`.
//!
//! Values are kept as the user typed them (the threshold text in particular):
//! validation is the core's job (`Strategy::parse`), not the URL's.

#[derive(Debug, Clone, PartialEq, Default)]
pub struct UrlState {
    /// `demo` or `folder` (files picked one by one cannot be linked).
    pub src: Option<String>,
    /// The lab's FRAME_ID: frames FRAME_ID-1 and FRAME_ID are matched.
    pub frame: Option<u32>,
    pub feature: Option<usize>,
    pub algo: Option<String>,
    /// Threshold text; absent = none (only meaningful for nn).
    pub t: Option<String>,
    /// Exercise seed and question number.
    pub ex: Option<u64>,
    pub q: Option<u32>,
    /// OpenCV SIMD width to reproduce (absent = 8, AVX2).
    pub lanes: Option<u32>,
}

fn decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'+' => out.push(b' '),
            b'%' if i + 2 < b.len() => {
                let hex = std::str::from_utf8(&b[i + 1..i + 3]).ok().and_then(|h| u8::from_str_radix(h, 16).ok());
                match hex {
                    Some(v) => {
                        out.push(v);
                        i += 2;
                    }
                    None => out.push(b'%'),
                }
            }
            c => out.push(c),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn encode(s: &str) -> String {
    let mut out = String::new();
    for c in s.bytes() {
        if c.is_ascii_alphanumeric() || b"-._~".contains(&c) {
            out.push(c as char);
        } else {
            out.push_str(&format!("%{c:02X}"));
        }
    }
    out
}

impl UrlState {
    /// Parses a query string (with or without the leading `?`); unknown keys
    /// and unparsable numbers are ignored (a broken link still opens the app).
    pub fn from_query(q: &str) -> Self {
        let mut st = UrlState::default();
        for pair in q.trim_start_matches('?').split('&').filter(|p| !p.is_empty()) {
            let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
            let v = decode(v);
            match decode(k).as_str() {
                "src" => st.src = Some(v),
                "frame" => st.frame = v.parse().ok(),
                "feature" => st.feature = v.parse().ok(),
                "algo" => st.algo = Some(v),
                "t" => st.t = Some(v),
                "ex" => st.ex = v.parse().ok(),
                "q" => st.q = v.parse().ok(),
                "lanes" => st.lanes = v.parse().ok(),
                _ => {}
            }
        }
        st
    }

    /// The query string, `?`-prefixed, keys in a fixed order.
    pub fn to_query(&self) -> String {
        let mut parts = Vec::new();
        let mut push = |k: &str, v: String| parts.push(format!("{k}={}", encode(&v)));
        if let Some(v) = &self.src {
            push("src", v.clone());
        }
        if let Some(v) = self.frame {
            push("frame", v.to_string());
        }
        if let Some(v) = self.feature {
            push("feature", v.to_string());
        }
        if let Some(v) = &self.algo {
            push("algo", v.clone());
        }
        if let Some(v) = &self.t {
            push("t", v.clone());
        }
        if let Some(v) = self.ex {
            push("ex", v.to_string());
        }
        if let Some(v) = self.q {
            push("q", v.to_string());
        }
        if let Some(v) = self.lanes {
            push("lanes", v.to_string());
        }
        if parts.is_empty() {
            String::new()
        } else {
            format!("?{}", parts.join("&"))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_a_prepared_view() {
        let st = UrlState {
            src: Some("demo".into()),
            frame: Some(1),
            feature: Some(7),
            algo: Some("nndr".into()),
            t: Some("0.8".into()),
            ex: Some(42),
            q: Some(3),
            lanes: Some(16),
        };
        let q = st.to_query();
        assert_eq!(q, "?src=demo&frame=1&feature=7&algo=nndr&t=0.8&ex=42&q=3&lanes=16");
        assert_eq!(UrlState::from_query(&q), st);
    }

    #[test]
    fn tolerates_broken_links() {
        let st = UrlState::from_query("?feature=abc&algo=dt&t=1%2E5&junk&frame=-3");
        assert_eq!(st.feature, None);
        assert_eq!(st.frame, None);
        assert_eq!(st.algo.as_deref(), Some("dt"));
        assert_eq!(st.t.as_deref(), Some("1.5"));
        assert_eq!(UrlState::from_query(""), UrlState::default());
        assert_eq!(UrlState::default().to_query(), "");
    }
}
