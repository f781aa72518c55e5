"""The base of the gate's tests: a crate written to a temp dir, its graph and CLI read back."""

import contextlib
import io
import os
import sys
import tempfile
import textwrap
import unittest

# tests/gates, where import_graph.py and import_graph_lib/ are: the tests import them by name.
GATES = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if GATES not in sys.path:
    sys.path.insert(0, GATES)
import import_graph as ig  # noqa: E402
from import_graph_lib.graph import build  # noqa: E402


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
        crates, g, unresolved = build([os.path.join(self.dir, r) for r in roots], **kw)
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
