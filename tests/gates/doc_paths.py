#!/usr/bin/env python3
"""The code map cannot rot: every path docs/architecture.md names exists.

    python3 tests/gates/doc_paths.py [DOC...]      (default: docs/architecture.md)
    python3 tests/gates/doc_paths.py --self-test

A path is a `backticked` token that starts at one of the repository's top-level folders
(core/, app/, www/, tests/, docs/, .cargo/, .ci/) or is a top-level file (README.md,
Cargo.toml, Cargo.lock); a trailing `/` names a folder, `#anchor` and `:line` are cut off.
Module names inside a crate (`sift/`, `render::plot`) are the map's words, not checked
paths. Exit 1 with each missing path and its line; the map must name some paths at all.
"""
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TOP = ("core/", "app/", "www/", "tests/", "docs/", ".cargo/", ".ci/")
FILES = ("README.md", "Cargo.toml", "Cargo.lock")
TOKEN = re.compile(r"`([^`\s]+)`")


def paths(text):
    """(line number, path) of each path the text names."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        for tok in TOKEN.findall(line):
            tok = re.split(r"[#:]", tok, maxsplit=1)[0].rstrip(".,;")
            if tok.startswith(TOP) or tok in FILES:
                out.append((n, tok))
    return out


def missing(text, root=ROOT):
    bad = []
    for n, p in paths(text):
        full = os.path.join(root, p)
        ok = os.path.isdir(full) if p.endswith("/") else os.path.exists(full)
        if not ok:
            bad.append((n, p))
    return bad


def self_test():
    text = "see `core/src/lib.rs`, `app/` and `tests/nope.py:12`, `sift/` and `README.md#x`\n`docs/gone/`"
    got = [p for _, p in paths(text)]
    assert got == ["core/src/lib.rs", "app/", "tests/nope.py", "README.md", "docs/gone/"], got
    assert missing(text) == [(1, "tests/nope.py"), (2, "docs/gone/")], missing(text)
    print("doc_paths self-test: ok")


def main(argv):
    if argv == ["--self-test"]:
        self_test()
        return 0
    docs = argv or [os.path.join(ROOT, "docs", "architecture.md")]
    status = 0
    for doc in docs:
        text = open(doc, encoding="utf-8").read()
        found = paths(text)
        bad = missing(text)
        for n, p in bad:
            print("%s:%d: names %s, which does not exist" % (os.path.relpath(doc, ROOT), n, p))
        if not found:
            print("%s names no path: is it still the code map?" % os.path.relpath(doc, ROOT))
            status = 1
        if bad:
            status = 1
        else:
            print("doc paths: %s names %d paths, all present" % (os.path.relpath(doc, ROOT), len(found)))
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
