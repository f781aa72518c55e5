//! The host's answer to the harness's `knnMatch` requests (docs/marking.md
//! §knn): siftlab's matcher on the pair's descriptors or on rows the
//! student's code sent. The work is done for the student, so it is bounded
//! by the lab's shapes and can be stopped when the call's time is up.

use crate::b64::{base64, unbase64};
use crate::protocol::Pair;
use siftlab_core::json::{parse, push_str, Json};
use siftlab_core::matching::{knn_match, DMatch};
use std::fmt::Write as _;

/// Queries matched between two questions to the caller's deadline: the
/// matcher's own block. At k = nt against 1500 train rows a block of 128
/// took 0.30 s on a loaded 2-core machine (the whole 1500 × 1500 answer
/// 3.6 s), so 32 is about 75 ms: the most a call can run past its limit.
const QUERY_BLOCK: usize = 32;

/// The descriptors of one side of a knn request.
enum Side<'a> {
    Rows(&'a [[u8; 128]]),
    Owned(Vec<[u8; 128]>),
}

impl Side<'_> {
    fn rows(&self) -> &[[u8; 128]] {
        match self {
            Side::Rows(r) => r,
            Side::Owned(v) => v,
        }
    }
}

/// Answers `{"op": "knn", "q", "qid", "nq", "t", "tid", "nt", "k"}` with
/// siftlab's `knnMatch` (per query the min(k, nt) nearest, in OpenCV's order
/// and ties), compactly: `{"kk": K, "t": B64, "d": B64}`, the K train
/// indices (int32) and distances (float32) of each query in turn, little
/// endian (the list form `{"matches": [[[t, d], …], …]}` when no query has a
/// match). A request that cannot be answered gets `{"error": MSG}` (k < 1 as
/// OpenCV words it; a side with more rows than any frame of `pairs` has).
pub fn knn_answer(request: &str, pairs: &[Pair]) -> String {
    knn_answer_until(request, pairs, &mut || true).unwrap_or_default()
}

/// [`knn_answer`], asking `go_on` before each block of queries whether the
/// call still has time; `None` once it says no (the call is over its limit:
/// the transport ends it as a time-out, no answer is sent).
pub fn knn_answer_until(request: &str, pairs: &[Pair], go_on: &mut dyn FnMut() -> bool) -> Option<String> {
    let (q, t, k) = match knn_request(request, pairs) {
        Ok(v) => v,
        Err(e) => {
            let mut s = String::from("{\"error\": ");
            push_str(&mut s, &e);
            s.push('}');
            return Some(s);
        }
    };
    let (q, t) = (q.rows(), t.rows());
    let mut all: Vec<Vec<DMatch>> = Vec::with_capacity(q.len());
    for block in q.chunks(QUERY_BLOCK) {
        if !go_on() {
            return None;
        }
        all.extend(knn_match(block, t, k));
    }
    let kk = all.first().map_or(0, Vec::len);
    if kk == 0 || all.iter().any(|r| r.len() != kk) {
        return Some(knn_answer_lists(&all));
    }
    // At most rows × rows of the lab's frames (k is cut to nt): no overflow.
    let bytes = 4 * kk * all.len();
    let (mut ti, mut di) = (Vec::with_capacity(bytes), Vec::with_capacity(bytes));
    for m in all.iter().flatten() {
        ti.extend_from_slice(&(m.train_idx as i32).to_le_bytes());
        di.extend_from_slice(&m.distance.to_le_bytes());
    }
    Some(format!("{{\"kk\": {kk}, \"t\": \"{}\", \"d\": \"{}\"}}", base64(&ti), base64(&di)))
}

/// `{"matches": [[[trainIdx, distance], …], …]}`.
pub(crate) fn knn_answer_lists(all: &[Vec<DMatch>]) -> String {
    let n: usize = all.iter().map(Vec::len).sum();
    let mut s = String::with_capacity(16 + 3 * all.len() + 24 * n);
    s.push_str("{\"matches\": [");
    for (i, row) in all.iter().enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        s.push('[');
        for (j, m) in row.iter().enumerate() {
            if j > 0 {
                s.push_str(", ");
            }
            // Rust's shortest round-trip text of the widened f32: the same
            // f64 as Python's repr.
            let _ = write!(s, "[{}, {:?}]", m.train_idx, m.distance as f64);
        }
        s.push(']');
    }
    s.push_str("]}");
    s
}

/// The most descriptors a side of a request may have: as many as the
/// largest frame of `pairs` (a student matching the lab's frames never
/// sends more; more is work siftlab would do for nothing the lab asks).
pub fn max_rows(pairs: &[Pair]) -> usize {
    pairs.iter().flat_map(|p| [p.prev.descriptors.len(), p.cur.descriptors.len()]).max().unwrap_or(0)
}

fn knn_request<'a>(request: &str, pairs: &'a [Pair]) -> Result<(Side<'a>, Side<'a>, usize), String> {
    let v = parse(request).map_err(|e| format!("knn request is not JSON: {e}"))?;
    if v.get("op").and_then(Json::as_str) != Some("knn") {
        return Err("not a knn request (\"op\" is not \"knn\")".into());
    }
    let k = v.get("k").and_then(Json::as_i64).ok_or("knn request without an integer \"k\"")?;
    if k < 1 {
        return Err("OpenCV(4.8.0) /io/opencv/modules/features2d/src/matchers.cpp:655: error: (-215:Assertion failed) knn > 0 in function 'knnMatch'".into());
    }
    let max = max_rows(pairs);
    let q = side(&v, "q", "qid", "nq", pairs, max)?;
    let t = side(&v, "t", "tid", "nt", pairs, max)?;
    // knnMatch returns min(k, nt) per query: a larger k asks for nothing
    // more, so it is cut here (the answer is the same, the work bounded).
    let k = usize::try_from(k).unwrap_or(usize::MAX).min(t.rows().len());
    Ok((q, t, k.max(1)))
}

fn side<'a>(v: &Json, data: &str, id: &str, count: &str, pairs: &'a [Pair], max: usize) -> Result<Side<'a>, String> {
    if let Some(r) = v.get(id).and_then(Json::as_str) {
        let (pair, which) = r.split_once('/').ok_or_else(|| format!("\"{id}\" {r:?} is not \"K/1\" or \"K/2\""))?;
        let pair: u32 = pair.parse().map_err(|_| format!("\"{id}\" {r:?} does not start with a pair id"))?;
        let p = pairs.iter().find(|p| p.id == pair).ok_or_else(|| format!("\"{id}\": no pair {pair} was sent"))?;
        return match which {
            "1" => Ok(Side::Rows(&p.prev.descriptors)),
            "2" => Ok(Side::Rows(&p.cur.descriptors)),
            _ => Err(format!("\"{id}\" {r:?} is not \"K/1\" or \"K/2\"")),
        };
    }
    let b64 =
        v.get(data).and_then(Json::as_str).ok_or_else(|| format!("knn request without \"{data}\" or \"{id}\""))?;
    let n = v.get(count).and_then(Json::as_i64).ok_or_else(|| format!("knn request without an integer \"{count}\""))?;
    // The shape first, from the numbers alone: nothing is decoded for a
    // side larger than the lab's frames.
    let rows = usize::try_from(n).map_err(|_| format!("\"{count}\" is {n}, not a number of rows"))?;
    if rows > max {
        return Err(format!(
            "{rows} descriptors in \"{data}\": siftlab's matcher takes at most {max}, the most a frame of the lab has \
             (match the frames' descriptors, des1 and des2)"
        ));
    }
    // rows <= max (a frame's keypoints), so rows × 128 cannot overflow.
    if b64.len() > (rows * 128).div_ceil(3) * 4 {
        return Err(format!("\"{data}\" holds more than {rows} rows of 128"));
    }
    let bytes = unbase64(b64).ok_or_else(|| format!("\"{data}\" is not base64"))?;
    if bytes.len() != rows * 128 {
        return Err(format!("\"{data}\" holds {} bytes, not {n} rows of 128", bytes.len()));
    }
    let (rows, _) = bytes.as_chunks::<128>();
    Ok(Side::Owned(rows.to_vec()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::tests::features;

    fn error_of(answer: &str) -> String {
        let v = parse(answer).unwrap();
        v.get("error").and_then(Json::as_str).unwrap_or_else(|| panic!("no error: {answer}")).to_string()
    }

    #[test]
    fn requests_beyond_the_labs_shapes_are_refused_before_any_work() {
        let pairs = [Pair { id: 7, prev: features(40, 1), cur: features(30, 9) }];
        assert_eq!(max_rows(&pairs), 40);
        assert_eq!(max_rows(&[]), 0);
        let row = base64(&[3u8; 128]);
        // 41 rows where the largest frame has 40: refused from the count, the
        // data never decoded (here it is not even there).
        for (req, says) in [
            (r#"{"op": "knn", "q": "", "nq": 41, "tid": "7/2", "k": 1}"#.to_string(), "41 descriptors in \"q\""),
            (r#"{"op": "knn", "qid": "7/1", "t": "", "nt": 200000, "k": 200000}"#.into(), "200000 descriptors"),
            (r#"{"op": "knn", "q": "", "nq": 9223372036854775807, "tid": "7/2", "k": 1}"#.into(), "at most 40"),
            (r#"{"op": "knn", "q": "", "nq": -1, "tid": "7/2", "k": 1}"#.into(), "not a number of rows"),
            // More text than 1 row: refused before decoding.
            (format!(r#"{{"op": "knn", "q": "{row}{row}", "nq": 1, "tid": "7/2", "k": 1}}"#), "more than 1 rows"),
            (format!(r#"{{"op": "knn", "q": "{row}", "nq": 2, "tid": "7/2", "k": 1}}"#), "not 2 rows of 128"),
        ] {
            assert!(error_of(&knn_answer(&req, &pairs)).contains(says), "{req}: {}", knn_answer(&req, &pairs));
        }
        // k past the train rows (even past i64) asks for no more than nt.
        for k in ["31", "200000", "9223372036854775807"] {
            let a = knn_answer(&format!(r#"{{"op": "knn", "qid": "7/1", "tid": "7/2", "k": {k}}}"#), &pairs);
            assert!(a.starts_with(r#"{"kk": 30, "#), "{k}: {}", &a[..40]);
        }
        // A request within the shapes: answered.
        let a = knn_answer(&format!(r#"{{"op": "knn", "q": "{row}", "nq": 1, "tid": "7/2", "k": 2}}"#), &pairs);
        assert!(a.starts_with(r#"{"kk": 2, "#), "{a}");
    }

    #[test]
    fn the_work_stops_when_the_caller_says_the_time_is_up() {
        let pairs = [Pair { id: 7, prev: features(300, 1), cur: features(300, 9) }];
        let req = r#"{"op": "knn", "qid": "7/1", "tid": "7/2", "k": 300}"#;
        // 300 queries: ten blocks of 32, the caller asked before each.
        let mut asked = 0;
        let full = knn_answer_until(req, &pairs, &mut || {
            asked += 1;
            true
        });
        assert_eq!(asked, 10);
        assert_eq!(full.as_deref(), Some(knn_answer(req, &pairs).as_str()));
        let mut asked = 0;
        let stopped = knn_answer_until(req, &pairs, &mut || {
            asked += 1;
            asked < 2
        });
        assert_eq!((stopped, asked), (None, 2));
        // A refused request is answered whatever the time.
        let refused = knn_answer_until(r#"{"op": "knn", "k": 0}"#, &pairs, &mut || false).unwrap();
        assert!(error_of(&refused).contains("knn > 0"));
    }

    /// A knn answer as (trainIdx, distance) rows, from either form.
    fn rows_of(answer: &str) -> Vec<Vec<(usize, f32)>> {
        let v = parse(answer).unwrap();
        if let Some(rows) = v.get("matches") {
            return rows
                .as_arr()
                .unwrap()
                .iter()
                .map(|r| {
                    r.as_arr()
                        .unwrap()
                        .iter()
                        .map(|m| {
                            let m = m.as_arr().unwrap();
                            (m[0].as_i64().unwrap() as usize, m[1].as_f64().unwrap() as f32)
                        })
                        .collect()
                })
                .collect();
        }
        let kk = v.get("kk").unwrap().as_i64().unwrap() as usize;
        let t = unbase64(v.get("t").unwrap().as_str().unwrap()).unwrap();
        let d = unbase64(v.get("d").unwrap().as_str().unwrap()).unwrap();
        let t: Vec<usize> = t.chunks(4).map(|b| i32::from_le_bytes(b.try_into().unwrap()) as usize).collect();
        let d: Vec<f32> = d.chunks(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        t.chunks(kk).zip(d.chunks(kk)).map(|(t, d)| t.iter().copied().zip(d.iter().copied()).collect()).collect()
    }

    #[test]
    fn knn_is_answered_by_reference_and_by_value() {
        let pairs = [Pair { id: 7, prev: features(40, 1), cur: features(30, 9) }];
        let by_ref = knn_answer(
            r#"{"op": "knn", "q": null, "qid": "7/1", "nq": 40, "t": null, "tid": "7/2", "nt": 30, "k": 3}"#,
            &pairs,
        );
        let q = base64(pairs[0].prev.descriptors.as_flattened());
        let t = base64(pairs[0].cur.descriptors.as_flattened());
        let by_value = knn_answer(
            &format!(
                r#"{{"op": "knn", "q": "{q}", "qid": null, "nq": 40, "t": "{t}", "tid": null, "nt": 30, "k": 3}}"#
            ),
            &pairs,
        );
        assert_eq!(by_ref, by_value);
        assert!(by_ref.starts_with(r#"{"kk": 3, "t": ""#), "{by_ref}");
        let want = knn_match(&pairs[0].prev.descriptors, &pairs[0].cur.descriptors, 3);
        let want: Vec<Vec<(usize, f32)>> =
            want.iter().map(|r| r.iter().map(|m| (m.train_idx, m.distance)).collect()).collect();
        assert_eq!(rows_of(&by_ref), want);
        // The list form reads the same.
        let lists = knn_answer_lists(&knn_match(&pairs[0].prev.descriptors, &pairs[0].cur.descriptors, 3));
        assert_eq!(rows_of(&lists), want);
        // Mixed: the query by value against a pair's train side; k above nt.
        let mixed = knn_answer(
            &format!(
                r#"{{"op": "knn", "q": "{q}", "qid": null, "nq": 40, "t": null, "tid": "7/2", "nt": 30, "k": 99}}"#
            ),
            &pairs,
        );
        assert!(rows_of(&mixed).iter().all(|r| r.len() == 30));
        let empty = knn_answer(r#"{"op": "knn", "q": "", "nq": 0, "tid": "7/2", "k": 2}"#, &pairs);
        assert_eq!(empty, r#"{"matches": []}"#);
        let no_train = knn_answer(r#"{"op": "knn", "qid": "7/1", "t": "", "nt": 0, "k": 2}"#, &pairs);
        assert!(no_train.starts_with(r#"{"matches": [[], []"#), "{no_train}");
        for (bad, says) in [
            (r#"{"op": "knn", "qid": "7/1", "tid": "7/2", "k": 0}"#, "knn > 0"),
            (r#"{"op": "knn", "qid": "8/1", "tid": "7/2", "k": 1}"#, "no pair 8"),
            (r#"{"op": "knn", "qid": "7/3", "tid": "7/2", "k": 1}"#, "K/1"),
            (r#"{"op": "knn", "q": "AAAA", "nq": 1, "tid": "7/2", "k": 1}"#, "not 1 rows of 128"),
            (r#"{"op": "knn", "tid": "7/2", "k": 1}"#, "without"),
            ("nonsense", "not JSON"),
        ] {
            let a = knn_answer(bad, &pairs);
            assert!(a.starts_with("{\"error\": ") && a.contains(says), "{bad}: {a}");
        }
    }
}
