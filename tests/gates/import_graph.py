#!/usr/bin/env python3
"""File-level import graph of the workspace's Rust crates, and its cycles.

    python3 tests/gates/import_graph.py [CRATE_ROOT.rs ...] [--edges] [--dot]
                                        [--skip-test-modules] [--verbose]

With no root given it reads core/src/lib.rs and app/src/lib.rs (relative to the
workspace, found from this script's place; --workspace DIR names another).
Python 3 standard library only; nothing is built or run.

A node is one .rs file of a crate's module tree; an edge A -> B says that A
names an item that B DEFINES. The rules:

* The module tree comes from `mod x;` (any visibility): x.rs or x/mod.rs,
  or `#[path = "..."]`. An inline `mod x { ... }` belongs to its file.
  `#[cfg(test)]` module files are included (said in the output) unless
  --skip-test-modules. Other `cfg`s are all taken as on.
* Comments, strings (raw ones too) and char literals are blanked first.
* References are `use` declarations (nested groups, `self`, `super`, `crate`,
  globs, `as`), and paths in code and macro bodies (`crate::x::f()`,
  `super::T`, `self::m::g`, `$crate::...`, `alias::item` after `use a::alias`).
  A path whose first segment is not of this crate (std, siftlab_core, ...)
  is ignored: no edge crosses crates.
* A path is walked as far as it names modules; the next segment is an item.
  Where that module does not define the item (fn, struct, enum, union, trait,
  type, const, static, macro_rules, mod) but imports it (`pub use`, or any
  `use`: a child module may name its parent's imports), the import is
  followed to the defining file. Passing through a re-export is no edge.
* A `pub use` (any `pub(...)`) is an edge only where its own file names the
  name too; a private `use` of an item is an edge. A `use` of a module makes
  no edge by itself: the paths through it do (`m::f()` -> the file that
  defines f); if nothing names it, a private one is an edge to the module's
  file.
* A glob `use a::b::*` is an edge to the files that define the names of b
  (its own, and those it imports or globs in turn) that the importing scope
  names; if it names none of them, an edge to b's file. A glob of an enum is
  an edge to the enum's file.
* A bare `m!()` finds a `macro_rules! m` of its module or an enclosing one;
  `#[macro_export]` macros sit at the crate root. `include!("f.rs")` is read
  as part of the including file.
* An edge from a file to itself is dropped; `mod x;` alone is no edge.

A child module naming its parent's items (`use super::helper` in x86.rs,
while mod.rs calls `x86::kernel()`) makes a cycle by these rules.
--upward-ok keeps such edges (a file to the file of a module that encloses
its own) but does not let them close a cycle.

A cycle is a strongly connected component of more than one file; each is
printed with the names that make its edges.

Layer rules (LAYERS, CRATE_RULES in import_graph_lib/layers.py; checked on the
workspace's crates):
* app/src is in role layers, by the first part of a file's path under it
  (page/odometry/frame.rs is in page): page -> services -> model -> protocol,
  with worker and platform beside them. An edge from one layer to another that
  its entry does not list breaks the rule.
* A crate's paths into another crate of the workspace (`use siftlab_core::x`,
  `siftlab_core::x::f()`, `::siftlab_core::x`, through a `use` alias or a glob
  of the other crate too) are resolved in that crate's module tree, following
  its re-exports: siftlab-mark may not reach core/src/vo, and siftlab-core
  names neither siftlab-mark nor siftlab-cli.
Each violation is printed with the file, the line, the import and the rule.
LAYER_ALLOW lists the violations that are let through for now.

Exit 1 if there is a cycle or a violation that LAYER_ALLOW does not list, 0 if
none, 2 if a crate root cannot be read.
"""

import argparse
import os
import sys

from import_graph_lib.graph import build
from import_graph_lib.layers import APP_SRC, check_rules

# Layer-rule violations let through, each (importing file, imported name); printed as
# allowed, and as stale once it no longer occurs. Empty: every rule holds. Keep it so.
LAYER_ALLOW: set = set()


def _names(names, lines=False):
    items = sorted(names.items(), key=lambda kv: (kv[1], kv[0]))
    if lines:
        return ", ".join(f"{n} (line {ln})" for n, ln in items)
    return ", ".join(n for n, _ in items)


def _dot(graph, rel, cycle_edges):
    q = lambda s: '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'
    out = ["digraph imports {", "  rankdir=LR;", "  node [shape=box, fontsize=10];",
           "  edge [fontsize=8];"]
    for n in sorted(graph.nodes, key=rel):
        out.append(f"  {q(rel(n))};")
    for (src, dst), names in sorted(graph.edges.items(), key=lambda kv: (rel(kv[0][0]), rel(kv[0][1]))):
        label = _names(names)
        if len(names) > 3:
            label = ", ".join(sorted(names)[:3]) + f", +{len(names) - 3}"
        style = ", color=red, penwidth=2" if (src, dst) in cycle_edges else ""
        out.append(f"  {q(rel(src))} -> {q(rel(dst))} [label={q(label)}{style}];")
    out.append("}")
    return "\n".join(out)


def main(argv=None):
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description="File-level import graph of Rust crates; exit 1 on a cycle.")
    ap.add_argument("roots", nargs="*", help="crate root files (default: the crates of the workspace)")
    ap.add_argument("--workspace", default=os.path.normpath(os.path.join(here, "..", "..")),
                    help="where the default roots are, and what printed paths are relative to")
    ap.add_argument("--edges", action="store_true", help="print every edge with its names")
    ap.add_argument("--dot", action="store_true", help="print the graph as Graphviz dot (the report goes to stderr)")
    ap.add_argument("--skip-test-modules", action="store_true",
                    help="leave out #[cfg(test)] code: test module files, inline test modules, other items")
    ap.add_argument("--upward-ok", action="store_true",
                    help="an edge from a file to the file of a module enclosing its own (a child naming "
                         "its parent's items: super::x, crate::x) closes no cycle; it stays an edge")
    ap.add_argument("--verbose", "-v", action="store_true", help="list unresolved paths and unreached files")
    args = ap.parse_args(argv)

    ws = os.path.abspath(args.workspace)
    if args.roots:
        roots = [os.path.abspath(r) if os.path.exists(r) else os.path.join(ws, r) for r in args.roots]
    else:
        roots = [os.path.join(ws, *r.split("/")) for r in
                 ("core/src/lib.rs", "core/mark/src/lib.rs", "core/cli/src/lib.rs", "app/src/lib.rs")]
    roots = [os.path.normpath(r) for r in roots]
    for r in roots:
        if not os.path.isfile(r):
            print(f"import_graph: no such crate root: {r}", file=sys.stderr)
            return 2

    def rel(p):
        r = os.path.relpath(p, ws)
        return p if r.startswith("..") else r

    report = sys.stderr if args.dot else sys.stdout
    say = lambda *a: print(*a, file=report)

    crates, graph, unresolved = build(roots, args.skip_test_modules, args.upward_ok)
    comps = graph.cycles()

    for c in crates:
        say(f"crate {rel(c.root_file)}: {len(c.files)} files")
        for file, line, name, cands in c.missing:
            say(f"  warning: {rel(file)}:{line}: `mod {name};` has no file (looked for "
                + ", ".join(rel(x) for x in cands) + ")")
        if c.test_files:
            say(f"  {len(c.test_files)} of them are #[cfg(test)] module files, included "
                "(--skip-test-modules leaves them out)")
        if c.skip_tests:
            say(f"  #[cfg(test)] code left out: {len(c.skipped_tests)} test module files, "
                "and the inline test modules and items")
        reached = set(c.files) | c.included | set(c.skipped_tests)
        src_dir = os.path.dirname(c.root_file)
        others = []
        for d, dirs, files in os.walk(src_dir):
            dirs.sort()
            for f in sorted(files):
                p = os.path.join(d, f)
                if f.endswith(".rs") and p not in reached and not any(os.path.samefile(p, r) for r in roots):
                    others.append(p)
        if others:
            shown = others if args.verbose else others[:6]
            more = "" if len(shown) == len(others) else f", ... (+{len(others) - len(shown)}, --verbose)"
            say(f"  not in its module tree (another crate's root, or unreached): "
                + ", ".join(rel(p) for p in shown) + more)

    if unresolved:
        say(f"note: {len(unresolved)} crate-internal paths found no module "
            + ("(listed below)" if args.verbose else "(--verbose lists them)"))
        if args.verbose:
            for src, line, path in sorted(unresolved):
                say(f"  {rel(src)}:{line}: {path}")

    if args.edges:
        for (src, dst), names in sorted(graph.edges.items(), key=lambda kv: (rel(kv[0][0]), rel(kv[0][1]))):
            say(f"{rel(src)} -> {rel(dst)}: {_names(names)}")

    cycle_edges = set()
    for k, comp in enumerate(comps, 1):
        members = set(comp)
        inside = [(e, names) for e, names in graph.edges.items() if e[0] in members and e[1] in members]
        cycle_edges.update(e for e, _ in inside)
        say(f"CYCLE {k} ({len(comp)} files): " + ", ".join(rel(f) for f in comp))
        say("  e.g. " + " -> ".join(rel(f) for f in graph.shortest_loop(comp)))
        for (src, dst), names in sorted(inside, key=lambda kv: (rel(kv[0][0]), rel(kv[0][1]))):
            say(f"  {rel(src)} -> {rel(dst)}: {_names(names, lines=True)}")

    broken, let_through = 0, set()
    for file, line, name, what, rule in check_rules(crates, graph, rel):
        if (file, name) in LAYER_ALLOW:
            let_through.add((file, name))
            say(f"allowed for now (LAYER_ALLOW): {file}:{line}: {what}: {rule}")
        else:
            broken += 1
            say(f"LAYER RULE BROKEN: {file}:{line}: {what}: {rule}")
    if any(rel(os.path.dirname(c.root_file)) == APP_SRC for c in crates):
        for file, name in sorted(LAYER_ALLOW - let_through):
            say(f"note: LAYER_ALLOW lets {file} import {name}, which breaks no rule now: delete its line")

    if args.dot:
        print(_dot(graph, rel, cycle_edges))

    aside = (f" (--upward-ok: {len(graph.set_aside)} edges into an enclosing module's file left out of "
             "cycles)") if args.upward_ok else ""
    say(f"import graph: {len(graph.nodes)} files, {len(graph.edges)} edges, {len(comps)} cycles{aside}, "
        f"{broken} layer-rule violations ({len(let_through)} more allowed for now)")
    return 1 if comps or broken else 0


if __name__ == "__main__":
    sys.exit(main())
