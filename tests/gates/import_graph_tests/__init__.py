"""The self-test of import_graph.py, one module per part it tests."""
