"""Comments, strings and char literals blanked before any path is read."""

from import_graph_lib.lex import strip_rust, tokenize

from .case import CrateCase


class Stripping(CrateCase):
    def test_paths_in_strings_and_comments_are_ignored(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod a;\nmod b;\nmod c;\n",
            "src/b.rs": "pub fn g() {}\n",
            "src/c.rs": "pub fn real() {}\n",
            "src/a.rs": r'''
                //! Docs: crate::b::g() and `use crate::b::g;`
                // use crate::b::g;
                /// See [`crate::b::g`].
                /* crate::b::g() /* nested: crate::b::g */ still comment crate::b::g */
                fn f<'a>(s: &'a str) -> &'a str {
                    let _x = "crate::b::g() \" crate::b::g";
                    let _y = r#"crate::b::g() "quoted" crate::b::g"#;
                    let _z = br##"crate::b::g "# "##;
                    let _q = '"'; let _e = '\''; let _b = b'\\';
                    let _w = "crate::b::g"; 'outer: loop { break 'outer; }
                    crate::c::real();
                    s
                }
                ''',
        })
        self.assertEqual(edges, {("src/a.rs", "src/c.rs"): {"real"}})

    def test_strip_rust(self):
        clean, strings = strip_rust(
            "fn f<'a>(x: &'a str) -> char { 'x' } // c\n"
            "let s = \"a\\\"b\nc\"; let r = r#\"q\"#; let c = '\\''; /* x\n y */ z")
        self.assertNotIn("//", clean)
        self.assertNotIn("x\n y", clean)
        self.assertIn("'a", clean)               # lifetimes stay
        self.assertNotIn("'x'", clean)           # char literals go
        self.assertEqual(clean.count("\n"), 3)   # every newline is kept
        self.assertEqual(sorted(strings.values()), ['a\\"b\nc', "q"])
        toks = tokenize("r#type::x")
        self.assertEqual([t[:2] for t in toks], [("id", "type"), ("p", "::"), ("id", "x")])
