//! `get_info` against OpenCV: every golden call's stdout, and the lab manual's
//! eight examples.

use crate::golden_data::{golden_params, primary_set};
use crate::{dataset, golden_lanes_args, repo_root, siftlab, siftlab_in, stderr, stdout};
use siftlab_core::json;
use siftlab_core::manual::EXAMPLES;
use siftlab_core::matching::{match_feature, matching_info, Strategy};
use siftlab_core::sift::{detect_and_compute, Features};
use siftlab_core::GrayImage;
use std::fs;

/// Our features of bundled frame `frame` (golden SIFT parameters), once per test binary.
fn library_features(frame: usize) -> std::sync::Arc<Features> {
    use std::sync::{Arc, Mutex, OnceLock};
    static CACHE: OnceLock<Mutex<Vec<Option<Arc<Features>>>>> = OnceLock::new();
    let mut cache = CACHE.get_or_init(Default::default).lock().unwrap();
    if cache.len() <= frame {
        cache.resize(frame + 1, None);
    }
    cache[frame]
        .get_or_insert_with(|| {
            let bytes = fs::read(dataset().join(format!("gray/00/image_0/{frame:06}.png"))).unwrap();
            let img = GrayImage::decode(&bytes).unwrap();
            Arc::new(detect_and_compute(&img, &golden_params()))
        })
        .clone()
}

/// Each line of the primary set's `get_info.jsonl` (tests/references/gen_goldens.py)
/// holds one `get_info` call on the bundled frames, `{"dataset_frame", "feature",
/// "algo", "threshold"}`, and the exact stdout the lab's Python + OpenCV printed for
/// `-d www/demo/MyKITTI`, so the CLI runs from the repository root with that path.
///
/// The binary must print the lab's `vo params`, `debug run` and `ret count` lines
/// exactly, and as `ret value` exactly what the library gives (golden.rs compares the
/// library with OpenCV on every draw; the default wheel's IPP can move a distance in
/// rare draws, docs/fidelity.md §SIFT-14). Every process runs SIFT twice, so this runs the binary on
/// every 12th draw plus every `nn` draw without a threshold.
#[test]
fn get_info_prints_exactly_what_the_lab_prints() {
    let set = primary_set();
    let path = set.dir().join("get_info.jsonl");
    let text = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (mut n, mut identical) = (0, 0);
    let mut failures = Vec::new();
    for (lineno, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let rec = json::parse(line).unwrap_or_else(|e| panic!("line {}: {e}", lineno + 1));
        let no_threshold = rec.get("threshold") == Some(&json::Json::Null);
        if lineno % 12 != 0 && !no_threshold {
            continue;
        }
        let field = |k: &str| rec.get(k).unwrap_or_else(|| panic!("line {}: no {k:?}", lineno + 1));
        let algo = field("algo").as_str().expect("algo is a string").to_owned();
        let mut argv: Vec<String> = vec!["-d".into(), set.dataset.clone(), "get_info".into()];
        argv.extend(golden_lanes_args());
        argv.extend(["-a".into(), algo.clone()]);
        let threshold = match field("threshold") {
            json::Json::Null => None,
            // The number's JSON text is Python's repr of the float the lab
            // parsed; `py_float` writes the same text back.
            t @ (json::Json::Float(_) | json::Json::Int(_)) => {
                let t = t.as_f64().unwrap();
                argv.extend(["-t".into(), siftlab_core::pyfmt::py_float(t)]);
                Some(t)
            }
            other => panic!("line {}: bad threshold {other:?}", lineno + 1),
        };
        let frame = field("dataset_frame").as_i64().expect("dataset_frame") as usize;
        let feature = field("feature").as_i64().expect("feature") as usize;
        argv.extend([frame.to_string(), feature.to_string()]);
        let golden = field("stdout").as_str().expect("stdout is a string");

        let (prev, cur) = (library_features(frame - 1), library_features(frame));
        let s = Strategy::parse(&algo, threshold).unwrap();
        let m = match_feature(&s, &prev, &cur, feature).unwrap();
        let library = matching_info(&prev.keypoints, &cur.keypoints, &m).to_string();
        let expected: String = golden
            .lines()
            .map(|l| if l.starts_with("ret value: ") { format!("ret value: {library}\n") } else { format!("{l}\n") })
            .collect();

        let argv_ref: Vec<&str> = argv.iter().map(String::as_str).collect();
        let o = siftlab_in(&repo_root(), &argv_ref);
        assert!(o.status.success(), "siftlab {argv:?} failed: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
        let got = stdout(&o);
        if got != expected {
            failures.push(format!("siftlab {}\n--- expected\n{expected}--- siftlab\n{got}", argv.join(" ")));
        }
        identical += (got == golden) as usize;
        n += 1;
    }
    eprintln!("get_info CLI: {n} runs; {identical} byte-identical to the lab's stdout");
    assert!(n >= 30, "only {n} get_info goldens run");
    assert!(failures.is_empty(), "{} of {n} get_info outputs differ:\n{}", failures.len(), failures.join("\n"));
}

/// The lab manual's eight examples, through the binary on the bundled frames:
/// stdout is the lab's four lines with the manual's printed value; for the
/// introduction's example, OpenCV 4.8.0.76's value, and the manual's at the
/// index OpenCV 4.8.0.76 gives that keypoint.
#[test]
fn the_manuals_examples_print_the_manuals_values() {
    let cases = EXAMPLES.iter().map(|e| (e, e.feature, e.siftlab_value()));
    let moved = EXAMPLES.iter().filter_map(|e| e.differs.map(|d| (e, d.feature, e.expected)));
    for (e, feature, value) in cases.chain(moved) {
        let mut argv = vec!["-d".to_string(), "www/demo/MyKITTI".into(), "get_info".into(), "-a".into(), e.algo.into()];
        if let Some(t) = e.threshold {
            argv.extend(["-t".into(), t.to_string()]);
        }
        argv.extend([e.frame.to_string(), feature.to_string()]);
        let argv_ref: Vec<&str> = argv.iter().map(String::as_str).collect();
        let o = siftlab(&argv_ref);
        assert!(o.status.success(), "siftlab {argv:?}: {}", stderr(&o));
        let t = e.threshold.map_or("None".to_string(), siftlab_core::pyfmt::py_float);
        let want = format!(
            "vo params: ('{}', {t}, 'www/demo/MyKITTI')\ndebug run: get_info({}, {feature})\nret value: {value}\nret count: 3\n",
            e.algo, e.frame
        );
        assert_eq!(stdout(&o), want, "{}: {}", e.task, e.command_for(feature));
    }
}
