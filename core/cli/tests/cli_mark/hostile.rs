//! Files that attack the marking: forged equality, and values no picture can
//! show.

use crate::{fixture, mark, num, repo_root, report, stderr, stdout, table};
use siftlab_core::json::Json;
use std::fs;

/// A file whose matching_info returns objects that always say "equal"
/// (and patches the harness) earns nothing for it: the verdict is made
/// outside its interpreter. Its honest tasks keep their marks.
#[test]
fn forged_equality_earns_nothing() {
    let hostile = repo_root().join("tests/fixtures/mark/hostile");
    for name in ["always_equal", "patch_expected", "wrap_handle", "steal_expected", "shadow_bool"] {
        let o = mark(&hostile.join(name).join("vision_tasks.py"), &["-n", "2", "--seed", "92", "--json"]);
        let r = report(&o);
        let t = table(&r);
        assert_eq!(t[..3], [(2, 0, 5.0), (2, 0, 5.0), (2, 0, 5.0)], "{name}: {}", stdout(&o));
        assert_eq!(t[3].0, 0, "{name}: matching_info counted correct: {}", stdout(&o));
        assert!(num(&r, "total") <= 15.5, "{name}");
    }
}

/// PrairieLearn's pictures from a file that returns what no picture can show (indices past
/// the keypoints, negative ones, NaN and huge distances, 200 000 matches in a list, points at
/// NaN, infinity and 1e300): the marking ends normally with its honest 2 / 20, every task's
/// picture is a JPEG, and results.json stays under PrairieLearn's 1 MB.
#[test]
fn pictures_hold_against_hostile_values() {
    let dir = std::env::temp_dir().join(format!("siftlab-cli-mark-{}", std::process::id()));
    fs::create_dir_all(&dir).unwrap();
    let results = dir.join("pictures-results.json");
    let o =
        mark(&fixture("pictures_hostile"), &["-n", "2", "--seed", "3", "--prairielearn", results.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let text = fs::read_to_string(&results).unwrap();
    assert!(text.len() < 1_000_000, "{} bytes", text.len());
    let j = siftlab_core::json::parse(&text).unwrap();
    assert_eq!(j.get("score").and_then(Json::as_f64), Some(0.1), "{}", stderr(&o));
    for t in j.get("tests").and_then(Json::as_arr).unwrap() {
        let images = t.get("images").and_then(Json::as_arr).unwrap_or(&[]);
        assert_eq!(images.len(), 1, "{:?}", t.get("name"));
        let url = images[0].get("url").and_then(Json::as_str).unwrap();
        // FF D8 FF, a JPEG's first bytes, in base64.
        assert!(url.starts_with("data:image/jpeg;base64,/9j/"), "{}", &url[..40.min(url.len())]);
    }
}
