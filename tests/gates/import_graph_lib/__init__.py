"""The import-circle gate's parts; tests/gates/import_graph.py is the command."""
