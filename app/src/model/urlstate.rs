//! The view's state in the URL query, so a teacher can link a prepared view:
//! `?src=demo&frame=1&feature=7&algo=nndr&t=0.8&ex=42&q=3`.
//!
//! Two layers: [`UrlState::from_pairs`] / [`UrlState::to_pairs`] read and
//! write decoded (key, value) pairs (plain Rust, tested natively), and
//! [`UrlState::from_query`] / [`UrlState::to_query`] let the browser's
//! `URLSearchParams` do the percent-encoding.
//!
//! Values are kept as the user typed them (the threshold text in particular):
//! validation is the core's job (`Strategy::parse`), not the URL's.

use siftlab_core::matching::StrategyKind;
use wasm_bindgen::JsCast;

#[derive(Debug, Clone, PartialEq, Default)]
pub struct UrlState {
    /// `demo` or `folder` (files picked one by one cannot be linked).
    pub src: Option<String>,
    /// The lab's FRAME_ID: frames FRAME_ID-1 and FRAME_ID are matched.
    pub frame: Option<u32>,
    pub feature: Option<usize>,
    pub algo: Option<StrategyKind>,
    /// Threshold text; absent = none (only meaningful for nn).
    pub t: Option<String>,
    /// Exercise seed and question number.
    pub ex: Option<u64>,
    pub q: Option<u32>,
    /// OpenCV SIMD width to reproduce (absent = 8, AVX2).
    pub lanes: Option<u32>,
    /// The open "see inside" view (`anatomy` or `matches`), its epipolar
    /// threshold text (absent = 2 px) and the anatomy's selected keypoint.
    pub see: Option<String>,
    pub px: Option<String>,
    pub kp: Option<usize>,
    /// "Mark my code": the cases' seed and how many per task.
    pub mark: Option<u64>,
    pub mn: Option<u32>,
}

impl UrlState {
    /// Reads decoded (key, value) pairs; unknown keys, unknown strategies and
    /// unparsable numbers are ignored (a broken link still opens the app); a
    /// repeated key: the last one counts.
    pub fn from_pairs<K: AsRef<str>, V: AsRef<str>>(pairs: impl IntoIterator<Item = (K, V)>) -> Self {
        let mut st = UrlState::default();
        for (k, v) in pairs {
            let v = v.as_ref();
            match k.as_ref() {
                "src" => st.src = Some(v.to_string()),
                "frame" => st.frame = v.parse().ok(),
                "feature" => st.feature = v.parse().ok(),
                "algo" => st.algo = StrategyKind::parse(v),
                "t" => st.t = Some(v.to_string()),
                "ex" => st.ex = v.parse().ok(),
                "q" => st.q = v.parse().ok(),
                "lanes" => st.lanes = v.parse().ok(),
                "see" => st.see = Some(v.to_string()),
                "px" => st.px = Some(v.to_string()),
                "kp" => st.kp = v.parse().ok(),
                "mark" => st.mark = v.parse().ok(),
                "mn" => st.mn = v.parse().ok(),
                _ => {}
            }
        }
        st
    }

    /// The decoded (key, value) pairs of the set fields, keys in a fixed order.
    pub fn to_pairs(&self) -> Vec<(&'static str, String)> {
        let num = |k: &'static str, v: Option<u64>| v.map(|v| (k, v.to_string()));
        [
            self.src.clone().map(|v| ("src", v)),
            num("frame", self.frame.map(u64::from)),
            num("feature", self.feature.map(|f| f as u64)),
            self.algo.map(|a| ("algo", a.name().to_string())),
            self.t.clone().map(|v| ("t", v)),
            num("ex", self.ex),
            num("q", self.q.map(u64::from)),
            num("lanes", self.lanes.map(u64::from)),
            self.see.clone().map(|v| ("see", v)),
            self.px.clone().map(|v| ("px", v)),
            num("kp", self.kp.map(|k| k as u64)),
            num("mark", self.mark),
            num("mn", self.mn.map(u64::from)),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// Parses a query string (with or without the leading `?`), decoded by
    /// the browser's `URLSearchParams` (browser only).
    pub fn from_query(q: &str) -> Self {
        let Ok(params) = web_sys::UrlSearchParams::new_with_str(q) else { return UrlState::default() };
        let entries = js_sys::try_iter(&params).ok().flatten();
        let pairs = entries.into_iter().flatten().filter_map(|entry| {
            let pair = entry.ok()?.dyn_into::<js_sys::Array>().ok()?;
            Some((pair.get(0).as_string()?, pair.get(1).as_string()?))
        });
        UrlState::from_pairs(pairs)
    }

    /// The query string, `?`-prefixed (empty when nothing is set), encoded by
    /// the browser's `URLSearchParams` (browser only).
    pub fn to_query(&self) -> String {
        let Ok(params) = web_sys::UrlSearchParams::new() else { return String::new() };
        for (k, v) in self.to_pairs() {
            params.append(k, &v);
        }
        let q: String = params.to_string().into();
        if q.is_empty() {
            q
        } else {
            format!("?{q}")
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
            algo: Some(StrategyKind::Nndr),
            t: Some("0.8".into()),
            ex: Some(42),
            q: Some(3),
            lanes: Some(16),
            see: Some("matches".into()),
            px: Some("1.5".into()),
            kp: Some(12),
            mark: Some(7),
            mn: Some(5),
        };
        let pairs = st.to_pairs();
        let keys: Vec<&str> = pairs.iter().map(|(k, _)| *k).collect();
        assert_eq!(keys, ["src", "frame", "feature", "algo", "t", "ex", "q", "lanes", "see", "px", "kp", "mark", "mn"]);
        let values: Vec<&str> = pairs.iter().map(|(_, v)| v.as_str()).collect();
        assert_eq!(values, ["demo", "1", "7", "nndr", "0.8", "42", "3", "16", "matches", "1.5", "12", "7", "5"]);
        assert_eq!(UrlState::from_pairs(pairs), st);
    }

    #[test]
    fn tolerates_broken_links() {
        let st =
            UrlState::from_pairs([("feature", "abc"), ("algo", "dt"), ("t", "1.5"), ("junk", ""), ("frame", "-3")]);
        assert_eq!(st.feature, None);
        assert_eq!(st.frame, None);
        assert_eq!(st.algo, Some(StrategyKind::Dt));
        assert_eq!(st.t.as_deref(), Some("1.5"));
        assert_eq!(UrlState::from_pairs([("algo", "knn")]).algo, None);
        assert_eq!(UrlState::from_pairs([("frame", "3"), ("frame", "4")]).frame, Some(4));
        assert_eq!(UrlState::from_pairs(Vec::<(&str, &str)>::new()), UrlState::default());
        assert!(UrlState::default().to_pairs().is_empty());
    }
}
