use super::*;

#[test]
fn reads_what_python_writes() {
    let v =
        parse(r#"{"ok": [[[0, 12, 61.400001525878906]], []], "x": NaN, "y": -Infinity, "s": "a\"\u00e9\ud83d\ude00"}"#)
            .unwrap();
    let ok = v.get("ok").unwrap().as_arr().unwrap();
    assert_eq!(ok[0].as_arr().unwrap()[0], Json::Arr(vec![Json::Int(0), Json::Int(12), Json::Float(61.4f32 as f64)]));
    assert!(matches!(v.get("x"), Some(Json::Float(f)) if f.is_nan()));
    assert_eq!(v.get("y"), Some(&Json::Float(f64::NEG_INFINITY)));
    assert_eq!(v.get("s").unwrap().as_str(), Some("a\"é😀"));
    assert_eq!(parse("123456789012345678901234567890123456789012").unwrap().py_repr().len(), 42);
    assert!(parse("[1, 2").is_err());
    assert!(parse("[1] x").is_err());
    assert!(parse("-").is_err());
    assert!(parse(&"[".repeat(10_000)).is_err());
}

#[test]
fn python_equality_and_repr() {
    let a = parse("[[523, 181], [[517, 183]], [61.400001525878906]]").unwrap();
    let b = parse("[[523.0, 181], [[517, 183]], [61.400001525878906]]").unwrap();
    let c = parse("[[523.5, 181], [[517, 183]], [61.4]]").unwrap();
    assert!(a.py_eq(&b));
    assert!(!a.py_eq(&c));
    assert!(!parse("NaN").unwrap().py_eq(&parse("NaN").unwrap()));
    assert_eq!(b.py_repr(), "[[523.0, 181], [[517, 183]], [61.400001525878906]]");
    assert_eq!(
        parse(r#"{"a": null, "b": true, "c": "it's"}"#).unwrap().py_repr(),
        "{'a': None, 'b': True, 'c': \"it's\"}"
    );
}

#[test]
fn f32_as_its_text_names_it() {
    for text in ["0.1", "226.12345", "1e-45", "3.4028235e38", "-0.0", "16777217", "12"] {
        let want: f32 = text.parse().unwrap();
        assert_eq!(parse(text).unwrap().as_f32().map(f32::to_bits), Some(want.to_bits()), "{text}");
    }
    // An f32's exact value as Python writes it (repr of the f64).
    assert_eq!(parse("61.400001525878906").unwrap().as_f32(), Some(61.4f32));
    // Exactly halfway between 1 and the next f32: the text's side is lost.
    assert_eq!(parse("1.000000059604644775390625").unwrap().as_f32(), None);
    assert_eq!(parse("\"1\"").unwrap().as_f32(), None);
}

#[test]
fn writes_ascii_json() {
    assert_eq!(quote("a\"b\\c\nd\u{1}é😀"), r#""a\"b\\c\nd\u0001\u00e9\ud83d\ude00""#);
    let v = Json::Arr(vec![Json::Float(0.8), Json::Float(f64::NAN), Json::Int(-3), Json::Null]);
    assert_eq!(v.to_json(), "[0.8, null, -3, null]");
    assert_eq!(parse(&quote("x\u{7f}\t")).unwrap().as_str(), Some("x\u{7f}\t"));
}
