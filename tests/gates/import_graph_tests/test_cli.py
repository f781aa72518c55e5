"""The command line: --edges, --dot, exit codes, and the script run as a script."""

import os
import subprocess
import sys

from .case import GATES, CrateCase


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
        run = subprocess.run([sys.executable, os.path.join(GATES, "import_graph.py"), "--workspace", self.dir,
                              "src/lib.rs"], capture_output=True, text=True)
        self.assertEqual(run.returncode, 1)
        self.assertIn("1 cycles", run.stdout)
