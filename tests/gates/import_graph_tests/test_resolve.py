"""Paths resolved to their defining files: re-exports, use forms, globs, macros."""

from .case import CrateCase


class ReExports(CrateCase):
    FILES = {
        "src/lib.rs": "pub mod m;\nmod user;\n",
        # m/mod.rs only hands Thing on; it also defines util, which inner uses.
        "src/m/mod.rs": "mod inner;\npub use inner::Thing;\npub fn util() -> u32 { 1 }\n",
        "src/m/inner.rs": "pub struct Thing;\npub fn make() -> u32 { super::util() }\n",
        "src/user.rs": "use crate::m::Thing;\nfn f() -> Thing { Thing }\n",
    }

    def test_reexport_is_followed_to_the_defining_file(self):
        edges, cycles = self.graph(self.FILES)
        self.assertEqual(edges[("src/user.rs", "src/m/inner.rs")], {"Thing"})
        self.assertNotIn(("src/user.rs", "src/m/mod.rs"), edges)
        # The re-export itself is no edge: no false mod.rs <-> inner.rs cycle.
        self.assertNotIn(("src/m/mod.rs", "src/m/inner.rs"), edges)
        self.assertEqual(edges[("src/m/inner.rs", "src/m/mod.rs")], {"util"})
        self.assertEqual(cycles, [])

    def test_reexport_chain_and_rename(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod a;\nmod b;\nmod c;\nmod d;\n",
            "src/a.rs": "pub use crate::b::Shown as Renamed;\n",
            "src/b.rs": "pub(crate) use crate::c::Real as Shown;\n",
            "src/c.rs": "pub struct Real;\n",
            "src/d.rs": "fn f() { let _ = crate::a::Renamed; }\n",
        })
        self.assertEqual(edges, {("src/d.rs", "src/c.rs"): {"Renamed"}})

    def test_reexport_that_its_file_uses_is_an_edge(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod a;\nmod b;\n",
            "src/a.rs": "pub use crate::b::B;\npub fn mk() -> B { B }\n",
            "src/b.rs": "pub struct B;\n",
        })
        self.assertEqual(edges, {("src/a.rs", "src/b.rs"): {"B"}})

    def test_module_and_item_of_one_name(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod linalg;\nmod svd;\n",
            "src/linalg/mod.rs": "pub mod hypot;\npub use hypot::hypot;\n",
            "src/linalg/hypot.rs": "pub const EPS: f64 = 1e-9;\npub fn hypot(x: f64, y: f64) -> f64 { x + y }\n",
            "src/svd.rs": "fn f() -> f64 { crate::linalg::hypot(1.0, 2.0) + crate::linalg::hypot::EPS }\n",
        })
        self.assertEqual(edges, {("src/svd.rs", "src/linalg/hypot.rs"): {"hypot", "EPS"}})


class UseForms(CrateCase):
    def test_nested_use_group(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod a;\nmod d;\nmod user;\n",
            "src/a/mod.rs": "pub mod b;\npub mod c;\n",
            "src/a/b.rs": "pub struct B;\n",
            "src/a/c.rs": "pub fn f() {}\n",
            "src/d.rs": "pub fn dee() {}\npub const UNUSED: u8 = 0;\n",
            "src/user.rs": """
                use crate::{a::{b::B, c}, d::*};
                fn g(_: B) { c::f(); dee(); }
                """,
        })
        self.assertEqual(edges, {
            ("src/user.rs", "src/a/b.rs"): {"B"},
            ("src/user.rs", "src/a/c.rs"): {"f"},
            ("src/user.rs", "src/d.rs"): {"dee"},
        })

    def test_self_super_and_as(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod p;\n",
            "src/p/mod.rs": "mod q;\nmod r;\npub struct T;\n",
            "src/p/q.rs": """
                use self::inner::g as gee;
                use super::r::{self as arr};
                mod inner { pub fn g() {} }
                fn f(_: super::T) { gee(); arr::h(); }
                """,
            "src/p/r.rs": "pub fn h() {}\n",
        })
        self.assertEqual(edges, {
            ("src/p/q.rs", "src/p/mod.rs"): {"T"},
            ("src/p/q.rs", "src/p/r.rs"): {"h"},
        })

    def test_unused_private_module_import_is_an_edge(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod a;\nmod b;\n",
            "src/a.rs": "use crate::b;\n",
            "src/b.rs": "pub fn f() {}\n",
        })
        self.assertEqual(edges, {("src/a.rs", "src/b.rs"): {"b"}})

    def test_inline_test_module_super_super(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod m;\n",
            "src/m/mod.rs": "mod w;\npub fn kernel() {}\n",
            "src/m/w.rs": """
                pub fn x() {}
                #[cfg(test)]
                mod tests {
                    use super::*;
                    use super::super::kernel;
                    #[test]
                    fn t() { x(); kernel(); }
                }
                """,
        })
        self.assertEqual(edges, {("src/m/w.rs", "src/m/mod.rs"): {"kernel"}})

    def test_glob_through_glob_reexport(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod prelude;\nmod deep;\nmod user;\n",
            "src/prelude.rs": "pub use crate::deep::*;\n",
            "src/deep.rs": "pub fn deep_fn() {}\n",
            "src/user.rs": "use crate::prelude::*;\nfn f() { deep_fn() }\n",
        })
        self.assertEqual(edges, {("src/user.rs", "src/deep.rs"): {"deep_fn"}})

    def test_unused_glob_is_an_edge_to_the_module(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod a;\nmod b;\n",
            "src/a.rs": "use crate::b::*;\n",
            "src/b.rs": "pub fn f() {}\n",
        })
        self.assertEqual(edges, {("src/a.rs", "src/b.rs"): {"b::*"}})

    def test_external_crates_are_ignored(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod a;\npub mod image;\n",
            "src/image.rs": "pub struct Img;\n",
            # `image` here is the external crate: a.rs has no `image` of its own.
            "src/a.rs": """
                use std::collections::HashMap;
                use siftlab_core::matching::Strategy;
                use ::image::Rgb;
                fn f() { let _ = image::open("x"); siftlab_core::vo::run(); }
                """,
        })
        self.assertEqual(edges, {})
        self.assertEqual(self.unresolved, [])

    def test_macros(self):
        edges, _ = self.graph({
            "src/lib.rs": "mod num;\nmod user;\n",
            "src/num/mod.rs": "macro_rules! each { () => {} }\nmod x86;\nmod fma;\n",
            "src/num/x86.rs": "each! {}\n",
            "src/num/fma.rs": """
                #[macro_export]
                macro_rules! with_fma { ($e:expr) => { $crate::user::probe($e) } }
                """,
            "src/user.rs": "pub fn probe(x: u8) -> u8 { x }\nfn f() { crate::with_fma!(1); }\n",
        })
        self.assertEqual(edges, {
            ("src/num/x86.rs", "src/num/mod.rs"): {"each!"},
            ("src/num/fma.rs", "src/user.rs"): {"probe"},
            ("src/user.rs", "src/num/fma.rs"): {"with_fma"},
        })
