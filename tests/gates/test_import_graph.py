#!/usr/bin/env python3
"""Self-test of import_graph.py on small synthetic crates in a temp dir.

    python3 tests/gates/test_import_graph.py
"""

import contextlib
import io
import os
import subprocess
import sys
import tempfile
import textwrap
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import import_graph as ig  # noqa: E402


class CrateCase(unittest.TestCase):
    """Writes a crate (a dict of path -> source) and reads its graph."""

    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory()
        self.dir = self._tmp.name

    def tearDown(self):
        self._tmp.cleanup()

    def write(self, files):
        for rel, text in files.items():
            path = os.path.join(self.dir, rel)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "w", encoding="utf-8") as f:
                f.write(textwrap.dedent(text).lstrip("\n"))

    def graph(self, files, roots=("src/lib.rs",), **kw):
        self.write(files)
        crates, g, unresolved = ig.build([os.path.join(self.dir, r) for r in roots], **kw)
        rel = lambda p: os.path.relpath(p, self.dir)
        edges = {(rel(s), rel(t)): set(names) for (s, t), names in g.edges.items()}
        cycles = [[rel(f) for f in comp] for comp in g.cycles()]
        self.unresolved = unresolved
        return edges, cycles

    def run_cli(self, *args):
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = ig.main(["--workspace", self.dir, *args])
        return code, out.getvalue(), err.getvalue()


class Cycles(CrateCase):
    def test_two_file_cycle_through_use(self):
        edges, cycles = self.graph({
            "src/lib.rs": "mod a;\nmod b;\n",
            "src/a.rs": "use crate::b::Bee;\npub fn ay() -> Bee { Bee }\n",
            "src/b.rs": "use crate::a::ay;\npub struct Bee;\nfn f() { ay(); }\n",
        })
        self.assertEqual(edges[("src/a.rs", "src/b.rs")], {"Bee"})
        self.assertEqual(edges[("src/b.rs", "src/a.rs")], {"ay"})
        self.assertEqual(cycles, [["src/a.rs", "src/b.rs"]])

    def test_cycle_through_inline_paths(self):
        edges, cycles = self.graph({
            "src/lib.rs": "pub mod x;\npub mod y;\n",
            "src/x.rs": "pub fn f() -> u32 { crate::y::g() + 1 }\n",
            "src/y.rs": "pub fn g() -> u32 { if false { crate::x::f() } else { 0 } }\n",
        })
        self.assertEqual(edges[("src/x.rs", "src/y.rs")], {"g"})
        self.assertEqual(edges[("src/y.rs", "src/x.rs")], {"f"})
        self.assertEqual(cycles, [["src/x.rs", "src/y.rs"]])

    def test_no_cycle_exit_0_and_cycle_exit_1(self):
        self.write({
            "src/lib.rs": "mod a;\nmod b;\n",
            "src/a.rs": "pub fn a() { crate::b::b() }\n",
            "src/b.rs": "pub fn b() {}\n",
        })
        code, out, _ = self.run_cli("src/lib.rs")
        self.assertEqual(code, 0)
        self.assertIn("import graph: 3 files, 1 edges, 0 cycles", out)
        self.write({"src/b.rs": "pub fn b() { crate::a::a() }\n"})
        code, out, _ = self.run_cli("src/lib.rs")
        self.assertEqual(code, 1)
        self.assertIn("CYCLE 1 (2 files): src/a.rs, src/b.rs", out)
        self.assertIn("src/b.rs -> src/a.rs: a (line 1)", out)
        self.assertIn("import graph: 3 files, 2 edges, 1 cycles", out)

    def test_three_file_cycle_is_one_component(self):
        _, cycles = self.graph({
            "src/lib.rs": "mod a;\nmod b;\nmod c;\n",
            "src/a.rs": "pub fn a() { crate::b::b() }\n",
            "src/b.rs": "pub fn b() { crate::c::c() }\n",
            "src/c.rs": "pub fn c() { crate::a::a() }\n",
        })
        self.assertEqual(cycles, [["src/a.rs", "src/b.rs", "src/c.rs"]])

    def test_parent_child_loop_and_upward_ok(self):
        files = {
            "src/lib.rs": "mod m;\n",
            "src/m/mod.rs": "mod x;\npub fn helper() {}\npub fn run() { x::kernel() }\n",
            "src/m/x.rs": "use super::helper;\npub fn kernel() { helper() }\n",
        }
        edges, cycles = self.graph(files)
        self.assertEqual(cycles, [["src/m/mod.rs", "src/m/x.rs"]])
        edges2, cycles2 = self.graph(files, upward_ok=True)
        self.assertEqual(edges2, edges)  # the edge stays; it closes no cycle
        self.assertEqual(cycles2, [])

    def test_upward_ok_keeps_sibling_cycles(self):
        _, cycles = self.graph({
            "src/lib.rs": "mod a;\nmod b;\npub fn top() {}\n",
            "src/a.rs": "pub fn a() { crate::b::b(); crate::top() }\n",
            "src/b.rs": "pub fn b() { crate::a::a() }\n",
        }, upward_ok=True)
        self.assertEqual(cycles, [["src/a.rs", "src/b.rs"]])


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
        clean, strings = ig.strip_rust(
            "fn f<'a>(x: &'a str) -> char { 'x' } // c\n"
            "let s = \"a\\\"b\nc\"; let r = r#\"q\"#; let c = '\\''; /* x\n y */ z")
        self.assertNotIn("//", clean)
        self.assertNotIn("x\n y", clean)
        self.assertIn("'a", clean)               # lifetimes stay
        self.assertNotIn("'x'", clean)           # char literals go
        self.assertEqual(clean.count("\n"), 3)   # every newline is kept
        self.assertEqual(sorted(strings.values()), ['a\\"b\nc', "q"])
        toks = ig.tokenize("r#type::x")
        self.assertEqual([t[:2] for t in toks], [("id", "type"), ("p", "::"), ("id", "x")])


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


class Cli(CrateCase):
    FILES = {
        "src/lib.rs": "mod a;\nmod b;\n",
        "src/a.rs": "pub fn a() { crate::b::b() }\n",
        "src/b.rs": "pub fn b() { crate::a::a() }\n",
    }

    def test_edges_and_dot(self):
        self.write(self.FILES)
        code, out, _ = self.run_cli("--edges", "src/lib.rs")
        self.assertEqual(code, 1)
        self.assertIn("src/a.rs -> src/b.rs: b\n", out)
        code, out, err = self.run_cli("--dot", "src/lib.rs")
        self.assertEqual(code, 1)
        self.assertTrue(out.startswith("digraph imports {"))
        self.assertIn('"src/a.rs" -> "src/b.rs" [label="b", color=red', out)
        self.assertIn("import graph: 3 files, 2 edges, 1 cycles", err)  # the report keeps stdout dot

    def test_missing_root_and_missing_module_file(self):
        self.write({"src/lib.rs": "mod gone;\n"})
        code, _, err = self.run_cli("src/nope.rs")
        self.assertEqual(code, 2)
        self.assertIn("no such crate root", err)
        code, out, _ = self.run_cli("src/lib.rs")
        self.assertEqual(code, 0)
        self.assertIn("`mod gone;` has no file", out)

    def test_runs_as_a_script(self):
        self.write(self.FILES)
        run = subprocess.run([sys.executable, os.path.join(HERE, "import_graph.py"), "--workspace", self.dir,
                              "src/lib.rs"], capture_output=True, text=True)
        self.assertEqual(run.returncode, 1)
        self.assertIn("1 cycles", run.stdout)


class LayerRules(CrateCase):
    """LAYERS and CRATE_RULES on a small workspace laid out like ours: core/src,
    core/mark/src, core/cli/src, app/src (the default roots)."""

    CORE = {
        "core/src/lib.rs": "pub mod json;\npub mod vo;\npub use vo::Pose;\n",
        "core/src/json.rs": "pub struct Json;\npub fn parse() {}\n",
        "core/src/vo/mod.rs": "mod pose;\npub use pose::Pose;\npub fn run() {}\n",
        "core/src/vo/pose.rs": "pub struct Pose;\n",
        "core/mark/src/lib.rs": "use siftlab_core::json::Json;\npub fn mark(_: Json) {}\n",
        "core/cli/src/lib.rs": "pub fn cli() { siftlab_mark::mark(siftlab_core::json::Json) }\n",
    }
    APP = {
        "app/src/lib.rs": "pub mod model;\npub mod page;\npub mod platform;\npub mod protocol;\n"
                          "pub mod services;\npub mod worker;\npub use page::App;\n",
        "app/src/page/mod.rs": "mod odometry;\npub struct App;\n",
        "app/src/page/odometry/mod.rs": "mod frame;\n",
        "app/src/page/odometry/frame.rs": "use crate::services::load;\nuse crate::model::Lab;\n"
                                          "use crate::protocol::Req;\nfn f(_: Lab, _: Req) { load(); crate::platform::now_ms(); }\n",
        "app/src/services/mod.rs": "use crate::model::Lab;\nuse crate::protocol::Req;\n"
                                   "pub fn load() { crate::platform::now_ms(); }\nfn g(_: Lab, _: Req) {}\n",
        "app/src/model/mod.rs": "use crate::protocol::Req;\npub struct Lab;\nfn h(_: Req) {}\n",
        "app/src/protocol/mod.rs": "pub struct Req;\n",
        "app/src/worker/mod.rs": "use crate::protocol::Req;\nuse crate::model::Lab;\npub const NAME: &str = \"w\";\n"
                                 "fn k(_: Req, _: Lab) {}\n",
        "app/src/platform.rs": "pub fn now_ms() -> f64 { 0.0 }\n",
    }

    def setUp(self):
        super().setUp()
        self._allow = ig.LAYER_ALLOW
        ig.LAYER_ALLOW = set()

    def tearDown(self):
        ig.LAYER_ALLOW = self._allow
        super().tearDown()

    def check(self, **changed):
        """Writes the workspace with `changed` (path with / as __) over it; (exit code, the
        violation lines)."""
        files = {**self.CORE, **self.APP}
        for key, text in changed.items():
            files[key.replace("__", "/")] = text
        self.write(files)
        code, out, _ = self.run_cli()
        return code, [l for l in out.splitlines() if l.startswith(("LAYER RULE BROKEN", "allowed for now"))]

    def assertBroken(self, lines, file, line, what, rule):
        self.assertIn(f"LAYER RULE BROKEN: {file}:{line}: {what}: {rule}", lines)

    def test_the_layers_as_they_should_be_pass(self):
        code, lines = self.check()
        self.assertEqual((code, lines), (0, []))

    def test_page_may_not_import_worker(self):
        code, lines = self.check(**{"app__src__page__odometry__frame.rs":
                                    "fn f() -> &'static str { crate::worker::NAME }\n"})
        self.assertEqual(code, 1)
        self.assertBroken(lines, "app/src/page/odometry/frame.rs", 1, "imports NAME from app/src/worker/mod.rs",
                          "page may import services, model, protocol, platform, not worker "
                          "(layers: page -> services -> model -> protocol)")

    def test_services_may_not_import_page_or_worker(self):
        code, lines = self.check(**{"app__src__services__mod.rs":
                                    "use crate::page::App;\npub fn load(_: App) { crate::worker::NAME; }\n"})
        self.assertEqual(code, 1)
        rule = "services may import model, protocol, platform, not {} (layers: page -> services -> model -> protocol)"
        self.assertBroken(lines, "app/src/services/mod.rs", 1, "imports App from app/src/page/mod.rs",
                          rule.format("page"))
        self.assertBroken(lines, "app/src/services/mod.rs", 2, "imports NAME from app/src/worker/mod.rs",
                          rule.format("worker"))

    def test_model_may_import_protocol_only(self):
        code, lines = self.check(**{"app__src__model__mod.rs":
                                    "use crate::protocol::Req;\npub struct Lab;\n"
                                    "fn h(_: Req) { crate::platform::now_ms(); crate::services::load(); }\n"})
        self.assertEqual(code, 1)
        rule = "model may import protocol, not {} (layers: page -> services -> model -> protocol)"
        self.assertBroken(lines, "app/src/model/mod.rs", 3, "imports now_ms from app/src/platform.rs",
                          rule.format("platform"))
        self.assertBroken(lines, "app/src/model/mod.rs", 3, "imports load from app/src/services/mod.rs",
                          rule.format("services"))
        self.assertEqual(len(lines), 2)

    def test_protocol_imports_no_other_layer(self):
        code, lines = self.check(**{"app__src__protocol__mod.rs": "pub struct Req(crate::model::Lab);\n"})
        self.assertEqual(code, 1)
        self.assertBroken(lines, "app/src/protocol/mod.rs", 1, "imports Lab from app/src/model/mod.rs",
                          "protocol may import no other app layer, not model "
                          "(layers: page -> services -> model -> protocol)")

    def test_worker_may_import_protocol_model_and_platform_only(self):
        code, lines = self.check(**{"app__src__worker__mod.rs":
                                    "use crate::protocol::Req;\nuse crate::model::Lab;\nfn k(_: Req, _: Lab) {\n"
                                    "    crate::platform::now_ms();\n    crate::services::load();\n}\n"})
        self.assertEqual(code, 1)
        rule = "worker may import protocol, model, platform, not {} (layers: page -> services -> model -> protocol)"
        self.assertBroken(lines, "app/src/worker/mod.rs", 5, "imports load from app/src/services/mod.rs",
                          rule.format("services"))
        self.assertEqual(len(lines), 1)

    def test_platform_imports_no_other_layer(self):
        code, lines = self.check(**{"app__src__platform.rs":
                                    "pub fn now_ms() -> f64 { 0.0 }\npub fn f(_: crate::protocol::Req) {}\n"})
        self.assertEqual(code, 1)
        self.assertBroken(lines, "app/src/platform.rs", 2, "imports Req from app/src/protocol/mod.rs",
                          "platform may import no other app layer, not protocol "
                          "(layers: page -> services -> model -> protocol)")

    def test_lib_may_name_every_layer_and_a_new_top_level_module_needs_a_layer(self):
        code, lines = self.check(**{
            "app__src__lib.rs": self.APP["app/src/lib.rs"] + "pub mod util;\n"
                                "pub fn start() { crate::worker::NAME; services::load(); }\n",
            "app__src__util.rs": "pub fn u(_: crate::model::Lab) {}\n"})
        self.assertEqual(code, 1)
        self.assertEqual(lines, ["LAYER RULE BROKEN: app/src/util.rs:1: imports Lab from app/src/model/mod.rs: "
                                 "every file of app/src is in a layer: page, services, model, protocol, worker, "
                                 "platform, lib"])

    def test_allow_list_lets_a_listed_import_through_and_names_stale_entries(self):
        ig.LAYER_ALLOW = {("app/src/model/mod.rs", "now_ms"), ("app/src/model/mod.rs", "gone")}
        code, lines = self.check(**{"app__src__model__mod.rs": "pub struct Lab;\nfn h() { crate::platform::now_ms(); }\n"})
        self.assertEqual(code, 0)
        self.assertEqual(lines, ["allowed for now (LAYER_ALLOW): app/src/model/mod.rs:2: imports now_ms from "
                                 "app/src/platform.rs: model may import protocol, not platform "
                                 "(layers: page -> services -> model -> protocol)"])
        _, out, _ = self.run_cli()
        self.assertIn("note: LAYER_ALLOW lets app/src/model/mod.rs import gone, which breaks no rule now", out)

    MARK_RULE = "siftlab-mark never reaches core's vo module (siftlab_core::vo, core/src/vo/)"

    def test_mark_never_reaches_core_vo(self):
        code, lines = self.check(**{"core__mark__src__lib.rs": """\
            use siftlab_core::json::Json;
            use siftlab_core::vo::run;
            use siftlab_core::{json, vo};
            pub fn mark(_: Json) { run(); json::parse(); }
            fn a() { siftlab_core::vo::run(); }
            fn b(_: siftlab_core::Pose) {}
            fn c() { ::siftlab_core::vo::run(); }
            """})
        self.assertEqual(code, 1)
        f = "core/mark/src/lib.rs"
        self.assertBroken(lines, f, 2, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 3, "imports siftlab_core::vo (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 5, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        # A re-export at core's root is followed to the file that defines it.
        self.assertBroken(lines, f, 6, "imports siftlab_core::Pose (core/src/vo/pose.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 7, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertEqual(len(lines), 5, lines)

    def test_mark_reaches_vo_through_an_alias_or_a_glob(self):
        code, lines = self.check(**{"core__mark__src__lib.rs": """\
            use siftlab_core as core;
            pub fn mark() { core::vo::run(); }
            mod g {
                use siftlab_core::*;
                fn f(_: json::Json) { vo::run(); }
                fn p(_: Pose) {}
            }
            """})
        self.assertEqual(code, 1)
        f = "core/mark/src/lib.rs"
        self.assertBroken(lines, f, 2, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 5, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 6, "imports siftlab_core::Pose (core/src/vo/pose.rs)", self.MARK_RULE)
        self.assertEqual(len(lines), 3, lines)

    def test_core_never_imports_mark_or_cli(self):
        code, lines = self.check(**{"core__src__json.rs": """\
            use siftlab_mark::mark;
            pub struct Json;
            pub fn parse() { mark(Json); siftlab_cli::cli(); }
            """})
        self.assertEqual(code, 1)
        self.assertEqual(lines, [
            "LAYER RULE BROKEN: core/src/json.rs:1: imports siftlab_mark::mark: siftlab-core never imports siftlab-mark",
            "LAYER RULE BROKEN: core/src/json.rs:3: imports siftlab_cli::cli: siftlab-core never imports siftlab-cli",
        ])


if __name__ == "__main__":
    unittest.main(verbosity=1)
