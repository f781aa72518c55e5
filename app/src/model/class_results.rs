//! "Class results": a class's summary.json (what `siftlab mark --out`
//! writes, `siftlab_mark::summary`) read for the view. Plain functions,
//! tested natively; the view only lays them out.

use siftlab_mark::{parse_json, Json};

/// The summary's format this view reads.
pub const FORMAT: &str = "siftlab-class-summary/1";
/// The largest summary.json read (a class of thousands is tens of KB).
pub const MAX_BYTES: usize = 4 << 20;

/// The summary in `bytes`, or what is wrong with them and what to do.
pub fn read_summary(bytes: &[u8]) -> Result<Json, String> {
    let again = "pick the summary.json (or the folder) that `siftlab mark --out DIR` wrote";
    if bytes.len() > MAX_BYTES {
        return Err(format!("the file is {} bytes, more than a class summary's {MAX_BYTES}: {again}", bytes.len()));
    }
    let text = std::str::from_utf8(bytes).map_err(|_| format!("the file is not text: {again}"))?;
    let j = parse_json(text).map_err(|e| format!("the file is not JSON ({e}): {again}"))?;
    match j.get("format").and_then(Json::as_str) {
        Some(FORMAT) => Ok(j),
        Some(other) => Err(format!("a summary in format {other:?}, this siftlab reads {FORMAT:?}: rebuild it with `siftlab mark --summary DIR`")),
        None => Err(format!("not a siftlab class summary: {again}")),
    }
}

/// A number of the summary as text ("–" where it has none).
pub fn text(j: Option<&Json>) -> String {
    match j {
        Some(Json::Int(v)) => v.to_string(),
        Some(Json::Float(v)) => format!("{v}"),
        Some(Json::Str(s)) => s.clone(),
        _ => "–".into(),
    }
}

/// An array of the summary (empty where it has none).
pub fn list(j: Option<&Json>) -> &[Json] {
    j.and_then(Json::as_arr).unwrap_or(&[])
}

/// A link of the summary, if it is one of the app's own (a query string):
/// nothing from the file becomes any other kind of address.
pub fn app_link(j: Option<&Json>) -> Option<String> {
    j.and_then(Json::as_str)
        .filter(|q| q.starts_with("?src=demo&") && !q.contains(['"', '<', '>', ' ']))
        .map(str::to_string)
}

/// A histogram's counts.
pub fn counts(j: Option<&Json>) -> Vec<i64> {
    list(j).iter().map(|v| v.as_i64().unwrap_or(0)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_only_a_class_summary() {
        let ok = read_summary(br#"{"format": "siftlab-class-summary/1", "students": 3}"#).unwrap();
        assert_eq!(text(ok.get("students")), "3");
        for (bytes, says) in [
            (&b"{\"students\": 3}"[..], "not a siftlab class summary"),
            (b"{\"format\": \"siftlab-class-summary/9\"}", "format \"siftlab-class-summary/9\""),
            (b"\xff\xfe", "not text"),
            (b"[1, 2", "not JSON"),
        ] {
            let e = read_summary(bytes).unwrap_err();
            assert!(e.contains(says), "{e}");
        }
    }

    #[test]
    fn links_are_the_apps_own() {
        let j = parse_json(r#"["?src=demo&frame=3&feature=1&algo=dt", "javascript:alert(1)", "?src=demo&x=\"><b>"]"#)
            .unwrap();
        let l = list(Some(&j));
        assert_eq!(app_link(l.first()).as_deref(), Some("?src=demo&frame=3&feature=1&algo=dt"));
        assert_eq!(app_link(l.get(1)), None);
        assert_eq!(app_link(l.get(2)), None);
    }
}
