"""The module tree: `#[path]`, mod.rs, `#[cfg(test)]` modules, `include!`."""

from .case import CrateCase


class ModuleTree(CrateCase):
    def test_path_attribute_and_mod_rs(self):
        edges, _ = self.graph({
            "src/lib.rs": '#[path = "platform/linux.rs"]\nmod sys;\nmod deep;\n',
            "src/platform/linux.rs": "pub fn now() {}\n",
            "src/deep/mod.rs": "mod leaf;\n",
            "src/deep/leaf.rs": "fn f() { crate::sys::now() }\n",
        })
        self.assertEqual(edges, {("src/deep/leaf.rs", "src/platform/linux.rs"): {"now"}})

    def test_mod_declaration_is_no_edge(self):
        edges, _ = self.graph({
            "src/lib.rs": "pub mod a;\n",
            "src/a.rs": "pub mod b;\nfn f() { self::b::g(); crate::a::h(); }\nfn h() {}\n",
            "src/a/b.rs": "pub fn g() {}\n",
        })
        self.assertEqual(edges, {("src/a.rs", "src/a/b.rs"): {"g"}})  # no lib -> a, no a -> a

    def test_cfg_test_modules(self):
        files = {
            "src/lib.rs": "mod a;\nmod b;\n#[cfg(test)]\nmod testutil;\n",
            "src/a.rs": """
                pub fn a() {}
                #[cfg(all(test, target_arch = "x86_64"))]
                mod tests;
                #[cfg(test)]
                mod inline { fn t() { crate::b::only_tests(); } }
                """,
            "src/a/tests.rs": "use super::*;\nfn t() { a(); crate::testutil::fixture(); }\n",
            "src/b.rs": "pub fn only_tests() {}\n",
            "src/testutil.rs": "pub fn fixture() {}\n",
        }
        edges, _ = self.graph(files)
        self.assertEqual(edges, {
            ("src/a.rs", "src/b.rs"): {"only_tests"},
            ("src/a/tests.rs", "src/a.rs"): {"a"},
            ("src/a/tests.rs", "src/testutil.rs"): {"fixture"},
        })
        edges, _ = self.graph(files, skip_tests=True)
        self.assertEqual(edges, {})

    def test_include_is_read_as_part_of_the_file(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod a;\nmod b;\n",
            "src/a.rs": 'include!("../data/gen.rs");\n',
            "data/gen.rs": "fn generated() { crate::b::g() }\n",
            "src/b.rs": "pub fn g() {}\n",
        })
        self.assertEqual(edges, {("src/a.rs", "src/b.rs"): {"g"}})
