//! The oracle of the `mark_reply` fuzz target: the harness's lines as the
//! marker reads them (the reply decoder, the judge, the report, and the
//! knn requests siftlab answers). Every byte of a line is the student's
//! (docs/marking.md), so whatever it is: no panic, no verdict "correct"
//! for a value that is not the reference's, no control character in a text
//! the report shows, and no knn answer beyond the lab's shapes. Included by
//! `tests/fuzz/fuzz_targets/mark_reply.rs` (nightly) and replayed on stable
//! by `core/mark/tests/fuzz_regressions.rs`. docs/fuzzing.md.
#![allow(dead_code)]

use siftlab_core::json::{parse, Json};
use siftlab_core::matching::Strategy;
use siftlab_core::sift::{Features, KeyPoint};
use siftlab_mark::{
    base64, info_type_problem, info_value, is_clean, judge, knn_answer_until, max_rows, parse_line, reference,
    report_json, report_text, unbase64, Case, Expected, HarnessLine, Marks, Pair, PyValue, Reply, Status,
};

/// Query and train rows of the pair the cases are judged on: small, with
/// ties (rows repeat), so every diagnosis is cheap to reach.
const NQ: usize = 12;
const NT: usize = 16;

fn features(n: usize, seed: usize) -> Features {
    Features {
        keypoints: (0..n)
            .map(|i| KeyPoint {
                x: (i * 37 % 97) as f32 + 0.5,
                y: (i * 11 % 53) as f32 + 0.25,
                size: 2.0,
                angle: 0.0,
                response: 0.1,
                octave: 0,
            })
            .collect(),
        // Rows repeat every 5 (ties), values 0..=9 (small distances).
        descriptors: (0..n).map(|i| std::array::from_fn(|j| ((i % 5) * 3 + j * 7 + seed) as u8 % 10)).collect(),
    }
}

fn pair() -> &'static Pair {
    static PAIR: std::sync::OnceLock<Pair> = std::sync::OnceLock::new();
    PAIR.get_or_init(|| Pair { id: 1, prev: features(NQ, 0), cur: features(NT, 3) })
}

/// Values where lengths and counts overflow or wrap.
const EDGES: [i128; 12] = [
    0,
    1,
    2,
    3,
    NQ as i128,
    NT as i128,
    -1,
    i32::MAX as i128,
    u32::MAX as i128 + 1,
    i64::MAX as i128,
    i64::MAX as i128 / 2 + 1,
    u64::MAX as i128,
];

struct Bytes<'a>(&'a [u8], usize);

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        let b = self.0.get(self.1).copied().unwrap_or(0);
        self.1 += 1;
        b
    }
    fn edge(&mut self) -> i128 {
        let b = self.u8();
        if b < 0xc0 {
            (b % 24) as i128
        } else {
            EDGES[b as usize % EDGES.len()]
        }
    }
    fn rest(&self) -> &[u8] {
        &self.0[self.1.min(self.0.len())..]
    }
}

fn case_of(b: u8) -> Case {
    let t = [0.0, 5.0, 9.5, 12.0, 30.0][(b >> 2) as usize % 5];
    match b % 4 {
        0 => Case::Dt { frame: 1, threshold: t },
        1 => Case::Nn { frame: 1, threshold: (b & 0x40 == 0).then_some(t) },
        2 => Case::Nndr { frame: 1, threshold: [0.0, 0.5, 0.8, 1.0][(b >> 4) as usize % 4] },
        _ => Case::Info {
            frame: 1,
            strategy: [Strategy::Dt(t), Strategy::Nn(None), Strategy::Nndr(0.8)][(b >> 4) as usize % 3],
            feature: (b >> 2) as usize % NQ,
        },
    }
}

/// The compact lists `{"n", "q", "t", "d"}` of the expected value.
fn honest_compact(want: &[Vec<siftlab_core::matching::DMatch>]) -> String {
    let (mut q, mut t, mut d, mut n) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for row in want {
        n.push(row.len().to_string());
        for m in row {
            q.extend_from_slice(&(m.query_idx as i32).to_le_bytes());
            t.extend_from_slice(&(m.train_idx as i32).to_le_bytes());
            d.extend_from_slice(&m.distance.to_le_bytes());
        }
    }
    format!(r#"{{"n": [{}], "q": "{}", "t": "{}", "d": "{}"}}"#, n.join(", "), base64(&q), base64(&t), base64(&d))
}

/// A compact value built from fuzzed lengths and words (lengths that wrap
/// when summed, words that do or do not add up).
fn fuzzed_compact(r: &mut Bytes) -> String {
    let rows = r.u8() as usize % 20;
    let n: Vec<String> = (0..rows).map(|_| r.edge().to_string()).collect();
    let words = |r: &mut Bytes| {
        let k = r.u8() as usize % 40;
        let w: Vec<u8> = (0..4 * k).map(|_| r.u8()).collect();
        base64(&w)
    };
    let (q, t, d) = (words(r), words(r), words(r));
    format!(r#"{{"n": [{}], "q": "{q}", "t": "{t}", "d": "{d}"}}"#, n.join(", "))
}

/// A knn request from fuzzed counts, k and rows (by value or by reference).
fn fuzzed_knn(r: &mut Bytes) -> String {
    let mode = r.u8();
    let side = |r: &mut Bytes, name: &str, count: &str, by_ref: bool| {
        if by_ref {
            return format!(r#""{name}id": "1/{}""#, 1 + r.u8() % 3);
        }
        let n = r.edge();
        let rows = r.u8() as usize % 24;
        let bytes: Vec<u8> = (0..rows * 128 + r.u8() as usize % 3).map(|_| r.u8()).collect();
        format!(r#""{name}": "{}", "{count}": {n}"#, base64(&bytes))
    };
    let q = side(r, "q", "nq", mode & 1 != 0);
    let t = side(r, "t", "nt", mode & 2 != 0);
    format!(r#"{{"op": "knn", {q}, {t}, "k": {}}}"#, r.edge())
}

/// Whether a returned value (the list form or the compact one) is exactly
/// the reference's lists, decoded here on its own (lengths summed in u128).
fn naive_equal(want: &[Vec<siftlab_core::matching::DMatch>], value: &Json) -> bool {
    let same = |m: &siftlab_core::matching::DMatch, q: i64, t: i64, d: f64| {
        q == m.query_idx as i64 && t == m.train_idx as i64 && d == m.distance as f64
    };
    if let Json::Obj(_) = value {
        let Some(n) = value.get("n").and_then(Json::as_arr) else { return false };
        let Some(n) = n.iter().map(|x| x.as_i64().and_then(|x| u64::try_from(x).ok())).collect::<Option<Vec<u64>>>()
        else {
            return false;
        };
        let words = |k: &str| value.get(k).and_then(Json::as_str).and_then(unbase64).filter(|b| b.len() % 4 == 0);
        let (Some(q), Some(t), Some(d)) = (words("q"), words("t"), words("d")) else { return false };
        let total: u128 = n.iter().map(|&x| x as u128).sum();
        if [q.len(), t.len(), d.len()].iter().any(|&l| (l / 4) as u128 != total) || n.len() != want.len() {
            return false;
        }
        let word = |b: &[u8], i: usize| [b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]];
        let mut at = 0usize;
        for (row, &len) in want.iter().zip(&n) {
            if row.len() as u64 != len {
                return false;
            }
            for m in row {
                let (qi, ti) = (i32::from_le_bytes(word(&q, at)), i32::from_le_bytes(word(&t, at)));
                let di = f32::from_le_bytes(word(&d, at)) as f64;
                if !same(m, qi as i64, ti as i64, di) {
                    return false;
                }
                at += 1;
            }
        }
        return true;
    }
    let Some(rows) = value.as_arr() else { return false };
    rows.len() == want.len()
        && rows.iter().zip(want).all(|(r, w)| {
            r.as_arr().is_some_and(|r| {
                r.len() == w.len()
                    && r.iter().zip(w).all(|(m, w)| {
                        let Some(m) = m.as_arr().filter(|m| m.len() == 3) else { return false };
                        let d = match &m[2] {
                            Json::Str(s) if s == "inf" => Some(f64::INFINITY),
                            Json::Str(s) if s == "-inf" => Some(f64::NEG_INFINITY),
                            Json::Str(s) if s == "nan" => Some(f64::NAN),
                            v => v.as_f64(),
                        };
                        match (m[0].as_i64(), m[1].as_i64(), d) {
                            (Some(q), Some(t), Some(d)) => same(w, q, t, d),
                            _ => false,
                        }
                    })
            })
        })
}

/// Checks one judged reply against what the reference says it is.
fn check_judged(case: &Case, expected: &Expected, reply: &Reply) {
    let p = pair();
    let r = judge(case, expected, reply, &p.prev, &p.cur, 0.5);
    let correct = match (reply, expected) {
        (Reply::Error { .. }, _) => false,
        (Reply::Ok { value }, Expected::Matches(want)) => naive_equal(want, value),
        (Reply::Ok { value }, Expected::Info { info, .. }) => {
            let got = PyValue::from_json(value);
            info_type_problem(&got).is_none() && got.py_eq(&info_value(info))
        }
    };
    assert_eq!(r.status == Status::Correct, correct, "{case:?} {reply:?}: {r:?}");
    assert_eq!(r.diagnosis.is_none(), correct, "{r:?}");
    for text in [&r.returned, &r.expected] {
        assert!(is_clean(text) && text.chars().count() < 2000, "unsafe or unbounded text: {text:?}");
    }
    if let Some(d) = &r.diagnosis {
        let words = d.describe();
        assert!(is_clean(&words) && words.chars().count() < 5000, "{words:?}");
    }
    let marks = Marks::new(0, 1, vec![r]);
    assert!(marks.total >= 0.0 && marks.total <= 20.0);
    let text = report_text(&marks);
    assert!(is_clean(&text), "{text:?}");
    parse(&report_json(&marks)).expect("the JSON report parses");
}

/// Checks a knn answer: JSON, within the lab's shapes, or an error.
fn check_knn(request: &str, stop_after: u8) {
    let p = pair();
    let pairs = std::slice::from_ref(p);
    let mut asked = 0u8;
    let Some(answer) = knn_answer_until(request, pairs, &mut || {
        asked = asked.saturating_add(1);
        asked <= stop_after
    }) else {
        assert!(asked > stop_after, "stopped without being told to");
        return;
    };
    let v = parse(&answer).unwrap_or_else(|e| panic!("the answer is not JSON ({e}): {answer}"));
    let max = max_rows(pairs);
    if let Some(e) = v.get("error") {
        assert!(e.as_str().is_some_and(|e| !e.is_empty()), "{answer}");
    } else if let Some(rows) = v.get("matches").and_then(Json::as_arr) {
        assert!(rows.len() <= max, "{} rows answered, the frames have {max}", rows.len());
        assert!(rows.iter().all(|r| r.as_arr().is_some_and(|r| r.len() <= max)));
    } else {
        let kk = v.get("kk").and_then(Json::as_i64).expect("kk") as usize;
        let t = unbase64(v.get("t").and_then(Json::as_str).expect("t")).expect("base64");
        let d = unbase64(v.get("d").and_then(Json::as_str).expect("d")).expect("base64");
        assert!(kk >= 1 && kk <= max, "kk {kk}");
        assert!(t.len() == d.len() && t.len().is_multiple_of(4 * kk) && t.len() / (4 * kk) <= max);
        // Every train index names a train row.
        assert!(t.chunks(4).all(|b| (i32::from_le_bytes(b.try_into().unwrap()) as usize) < max));
    }
}

/// `mark_reply`: a mode byte, a case byte, then the line's material.
pub fn mark_reply(data: &[u8]) {
    let mut r = Bytes(data, 0);
    let mode = r.u8();
    let case = case_of(r.u8());
    let p = pair();
    let expected = reference(&case, &p.prev, &p.cur).expect("the reference of a small pair");
    let line = match mode % 5 {
        // The line as written.
        0 | 1 => String::from_utf8_lossy(r.rest()).into_owned(),
        // A compact reply from fuzzed lengths and words.
        2 => format!(r#"{{"req": 1, "ok": {}}}"#, fuzzed_compact(&mut r)),
        // A knn request.
        3 => {
            let stop = r.u8() % 4;
            let req =
                if mode & 0x80 != 0 { String::from_utf8_lossy(r.rest()).into_owned() } else { fuzzed_knn(&mut r) };
            check_knn(&req, stop);
            return;
        }
        // The honest reply: must be judged correct.
        _ => {
            let value = match &expected {
                Expected::Matches(want) => honest_compact(want),
                Expected::Info { info, .. } => typed_info(info),
            };
            let line = format!(r#"{{"req": 1, "ok": {value}}}"#);
            let HarnessLine::Reply(reply) = parse_line(&line, 1) else { panic!("{line}") };
            let got = judge(&case, &expected, &reply, &p.prev, &p.cur, 0.1);
            assert_eq!(got.status, Status::Correct, "{line}: {got:?}");
            return;
        }
    };
    match parse_line(&line, 1) {
        HarnessLine::Reply(reply) => check_judged(&case, &expected, &reply),
        HarnessLine::Knn => check_knn(&line, 255),
        HarnessLine::Stray(why) => assert!(!why.is_empty()),
    }
}

/// matching_info's tuple as the harness types it.
fn typed_info(info: &siftlab_core::matching::MatchInfo) -> String {
    let pt = |(x, y): (i64, i64)| format!(r#"{{"tuple": [{x}, {y}]}}"#);
    let points: Vec<String> = info.points.iter().copied().map(pt).collect();
    let dists: Vec<String> = info.distances.iter().map(|&d| format!("{:?}", d as f64)).collect();
    format!(
        r#"{{"tuple": [{}, {{"list": [{}]}}, {{"list": [{}]}}]}}"#,
        pt(info.query),
        points.join(", "),
        dists.join(", ")
    )
}
