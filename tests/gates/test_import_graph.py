#!/usr/bin/env python3
"""Self-test of import_graph.py on small synthetic crates in a temp dir.

    python3 tests/gates/test_import_graph.py
"""

import os
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))


def load_tests(loader, standard_tests, pattern):
    # Discovered, not listed: a new test module in import_graph_tests/ runs without an edit here.
    return loader.discover(os.path.join(HERE, "import_graph_tests"), pattern="test_*.py", top_level_dir=HERE)


if __name__ == "__main__":
    unittest.main(verbosity=1)
