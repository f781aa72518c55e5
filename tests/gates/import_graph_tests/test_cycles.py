"""Cycles: found, reported with their edges, and --upward-ok's edges set aside."""

from .case import CrateCase


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
