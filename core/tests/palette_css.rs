//! The page's stylesheet and the core's palette agree: every colour custom
//! property of `www/styles.css` (`--c-…`) has the value the core defines for
//! it, none is missing or extra, and the rules that colour something with a
//! meaning take it from those properties rather than from a literal.

use siftlab_core::render::palette::{hex, CSS};
use std::collections::BTreeMap;

/// `www/styles.css` without its comments.
fn stylesheet() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../www/styles.css");
    let mut css = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    while let Some(a) = css.find("/*") {
        let b = css[a..].find("*/").map_or(css.len(), |b| a + b + 2);
        css.replace_range(a..b, "");
    }
    css
}

/// The `--c-…: value;` declarations of the `:root` rule.
fn root_colours(css: &str) -> BTreeMap<String, String> {
    let start = css.find(":root {").expect("a :root rule");
    let body = &css[start..start + css[start..].find('}').expect("the :root rule closes")];
    body.split(';')
        .filter_map(|d| {
            let (name, value) = d.split_once(':')?;
            let name = name.trim().rsplit(char::is_whitespace).next()?.to_string();
            name.starts_with("--c-").then(|| (name, value.trim().to_lowercase()))
        })
        .collect()
}

#[test]
fn the_stylesheets_colours_are_the_palettes() {
    let css = stylesheet();
    let declared = root_colours(&css);
    let want: BTreeMap<String, String> = CSS.iter().map(|(n, c)| (n.to_string(), hex(*c))).collect();
    assert_eq!(declared, want, "www/styles.css :root against core/src/render/palette CSS");
}

#[test]
fn meaningful_rules_use_the_palettes_properties() {
    let css = stylesheet();
    // Selector as written in the stylesheet, and the property its colour must come from.
    let rules = [
        (".kp-all", "--c-keypoints"),
        (".kp-sel", "--c-selected"),
        (".kp-sel-ori", "--c-selected"),
        (".kp-sel-dot", "--c-selected"),
        (".info-circle", "--c-info"),
        (".dbar", "--c-rest"),
        (".dbar.kept", "--c-kept"),
        (".thr", "--c-threshold"),
        (".hist-thr", "--c-threshold"),
        (".hist-peak", "--c-kept"),
    ];
    for (selector, property) in rules {
        let open = format!("\n{selector} {{");
        let at = css.find(&open).unwrap_or_else(|| panic!("no rule {selector}"));
        let body = &css[at + open.len()..];
        let body = &body[..body.find('}').unwrap()];
        assert!(body.contains(&format!("var({property})")), "{selector} {{{body}}} should use var({property})");
        assert!(!body.contains('#'), "{selector} {{{body}}} has a colour literal");
    }
    // Right and wrong in text (✓ and ✗ marks, verdicts) come from the palette too.
    assert!(css.contains("--ok: var(--c-ok-text);") && css.contains("--bad: var(--c-bad-text);"));
}
