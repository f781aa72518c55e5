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

Layer rules (LAYERS, CRATE_RULES below; checked on the workspace's crates):
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
import re
import sys
from collections import deque

# Layer-rule violations let through, each (importing file, imported name); printed as
# allowed, and as stale once it no longer occurs. Empty: every rule holds. Keep it so.
LAYER_ALLOW: set = set()

# ------------------------------------------------------------ layer rules ----

# The app's role layers: a file's layer is the first part of its path under app/src
# (page/odometry/frame.rs and page.rs are in page; platform.rs is platform). Each layer
# lists the other layers its files may import; a file always imports its own layer.
# lib.rs is the crate root: it declares the layers and re-exports page::App, and may
# name any of them. main.rs and bin/worker.rs are crate roots of their own (the page's
# and the worker's binaries, `siftlab_app::...` from outside): not in this graph.
APP_SRC = "app/src"
ANY = "any"
LAYERS = {
    "page": ("services", "model", "protocol", "platform"),
    "services": ("model", "protocol", "platform"),
    "model": ("protocol",),
    "protocol": (),
    # A worker's job measures its time and memory: the platform's, as the page's.
    "worker": ("protocol", "model", "platform"),
    # The browser's clock, blob URLs, memory and thread count, in a window or a worker:
    # the bottom layer beside protocol, importing no app layer. model stays off it (plain
    # logic, tested natively): the page gives Lab its clock.
    "platform": (),
    "lib": ANY,
}

# The workspace's crates: the name other crates write, and where its sources are.
CRATES = {"siftlab_core": "core/src", "siftlab_mark": "core/mark/src",
          "siftlab_cli": "core/cli/src", "siftlab_app": "app/src"}
# (the crate whose files are checked, the crate they name, what they may not reach
#  there: a folder or file of it, or None for the whole crate, the rule)
CRATE_RULES = [
    ("core/mark/src", "siftlab_core", "core/src/vo",
     "siftlab-mark never reaches core's vo module (siftlab_core::vo, core/src/vo/)"),
    ("core/src", "siftlab_mark", None, "siftlab-core never imports siftlab-mark"),
    ("core/src", "siftlab_cli", None, "siftlab-core never imports siftlab-cli"),
]

# ---------------------------------------------------------------- lexing ----

_SPECIAL = re.compile(r"""//|/\*|["']|\b(?:br|cr|r|b|c)(?=["'#])""")


def _char_literal_end(text, j):
    """End (exclusive) of the char literal opening at text[j] == "'", or -1
    where the quote opens a lifetime or a label ('a, 'outer:)."""
    n = len(text)
    if j + 1 < n and text[j + 1] == "\\":
        e = text.find("'", j + 3)  # '\'' : the escaped char is at j + 2
        return n if e < 0 else e + 1
    if j + 2 < n and text[j + 2] == "'" and text[j + 1] != "\n":
        return j + 3
    return -1


def strip_rust(text):
    """Blank comments, strings and char literals; keep every newline.

    Returns (clean, strings): each string literal becomes `"` newlines `"` in
    clean, and strings maps the offset of its opening quote in clean to the
    literal's raw text (for `#[path = "..."]` and `include!("...")`)."""
    out, strings = [], {}
    olen = 0
    i, n = 0, len(text)

    def put(s):
        nonlocal olen
        out.append(s)
        olen += len(s)

    while True:
        m = _SPECIAL.search(text, i)
        if not m:
            put(text[i:])
            break
        j, tok = m.start(), m.group()
        put(text[i:j])
        if tok == "//":  # line, doc and inner-doc comments
            e = text.find("\n", j)
            put(" ")
            i = n if e < 0 else e
            continue
        if tok == "/*":  # block comments nest
            depth, k = 1, j + 2
            while k < n and depth:
                if text.startswith("/*", k):
                    depth, k = depth + 1, k + 2
                elif text.startswith("*/", k):
                    depth, k = depth - 1, k + 2
                else:
                    k += 1
            put(" " + "\n" * text.count("\n", j, k))
            i = k
            continue
        if tok == "'":
            e = _char_literal_end(text, j)
            if e < 0:
                put("'")  # a lifetime: the tokenizer reads 'a whole
                i = j + 1
            else:
                put(" 0 ")
                i = e
            continue
        k = j if tok == '"' else j + len(tok)  # past a b / c / r / br / cr prefix
        if tok == "b" and text[k] == "'":  # byte literal b'x'
            e = _char_literal_end(text, k)
            if e >= 0:
                put(" 0 ")
                i = e
                continue
        if "r" in tok:
            h = k
            while h < n and text[h] == "#":
                h += 1
            if h >= n or text[h] != '"':  # a raw identifier r#name, not a string
                put(text[j:h])
                i = h
                continue
            close = '"' + "#" * (h - k)
            e = text.find(close, h + 1)
            e = n if e < 0 else e
            content, i = text[h + 1:e], e + len(close)
        elif text[k] == '"':
            e = k + 1
            while e < n and text[e] != '"':
                e += 2 if text[e] == "\\" else 1
            content, i = text[k + 1:e], e + 1
        else:  # b# or c#: no literal
            put(text[j:k])
            i = k
            continue
        strings[olen] = content
        put('"' + "\n" * content.count("\n") + '"')
    return "".join(out), strings


_TOKEN = re.compile(r"""
    (?P<nl>\n)
  | (?P<ws>[^\S\n]+)
  | (?P<lt>'(?:r\#)?[^\W\d]\w*)
  | (?P<id>(?:r\#)?[^\W\d]\w*)
  | (?P<num>\d\w*)
  | (?P<str>"[^"]*")
  | (?P<p>::|.)
""", re.X)

KEYWORDS = frozenset("""
    as async await box break const continue crate do dyn else enum extern false fn
    for if impl in let loop match mod move mut pub ref return self Self static
    struct super trait true try type unsafe use where while yield
""".split())

# Keywords after which an identifier is declared, not referred to.
_DECLARES = frozenset("fn struct enum union trait type const static let mut mod as".split())


def tokenize(text):
    """(kind, value, line) triples of stripped Rust. kind: 'id' (a raw
    identifier is an id without its r#), 'kw', 'lt', 'num', 'str' (value: the
    literal's text), 'p' (punctuation; '::' is one token)."""
    clean, strings = strip_rust(text)
    toks, line = [], 1
    for m in _TOKEN.finditer(clean):
        kind, v = m.lastgroup, m.group()
        if kind == "nl":
            line += 1
        elif kind == "ws":
            continue
        elif kind == "str":
            toks.append(("str", strings.get(m.start(), ""), line))
            line += v.count("\n")
        elif kind == "id":
            if v.startswith("r#"):
                toks.append(("id", v[2:], line))
            else:
                toks.append(("kw" if v in KEYWORDS else "id", v, line))
        else:
            toks.append((kind, v, line))
    return toks


# --------------------------------------------------------------- modules ----

class Module:
    """A module: a file's, or an inline `mod x { ... }` inside a file."""

    def __init__(self, name, parent, file, inline=False, is_test=False, mod_rs=False):
        self.name, self.parent, self.file = name, parent, file
        self.inline, self.is_test = inline, is_test
        self.mod_rs = mod_rs          # its `mod x;` files sit beside it (lib.rs, mod.rs, #[path])
        self.children = {}            # name -> Module
        self.defs = {}                # item name -> the file that defines it
        self.macros = {}              # macro_rules name -> file (textual scope)
        self.imports = []             # Import, at module level and in blocks
        self.refs = []                # (segments, line, is_macro): paths of two segments or more
        self.bare = {}                # identifier -> first line: might come from a glob
        self.bare_macros = {}         # m of a bare `m!` -> first line
        self.heads = set()            # first segment of every path this scope writes
        self.externs = []             # (segments, line, is_glob): `use ::c::x`, `::c::x` in code

    @property
    def path(self):
        names, m = [], self
        while m.parent is not None:
            names.append(m.name)
            m = m.parent
        return "::".join(["crate"] + names[::-1])


class Import:
    def __init__(self, scope, segs, alias, glob, public, local, line):
        self.scope, self.segs, self.alias = scope, segs, alias
        self.glob, self.public, self.local, self.line = glob, public, local, line


def _matching(toks, i, open_, close):
    """Index of the bracket closing the one at toks[i]."""
    depth = 0
    for k in range(i, len(toks)):
        v = toks[k][1]
        if v == open_:
            depth += 1
        elif v == close:
            depth -= 1
            if depth == 0:
                return k
    return len(toks) - 1


def _skip_visibility(toks, i):
    """Index past `pub` or `pub(crate)` / `pub(super)` / `pub(in path)`."""
    if i + 1 < len(toks) and toks[i + 1][1] == "(":
        return _matching(toks, i + 1, "(", ")") + 1
    return i + 1


def _attr_is_cfg_test(attr):
    """`#[cfg(test)]`, or `#[cfg(all(test, ...))]`."""
    vals = [t[1] for t in attr]
    if vals[:4] == ["cfg", "(", "test", ")"]:
        return True
    if vals[:4] != ["cfg", "(", "all", "("]:
        return False
    depth = 0
    for k, v in enumerate(vals[3:], 3):
        depth += v == "("
        depth -= v == ")"
        if depth == 1 and v == "test" and vals[k - 1] in ("(", ",") and vals[k + 1] in (",", ")"):
            return True
    return False


def _skip_item(toks, i):
    """Index past the item that starts at toks[i]: its `;`, or the `}`
    closing its first brace outside parentheses and brackets."""
    depth = 0
    for k in range(i, len(toks)):
        v = toks[k][1]
        if v in ("(", "["):
            depth += 1
        elif v in (")", "]"):
            depth -= 1
        elif depth <= 0 and v == ";":
            return k + 1
        elif depth <= 0 and v == "{":
            return _matching(toks, k, "{", "}") + 1
    return len(toks)


def _attr_path(attrs):
    for attr in attrs:
        if len(attr) >= 3 and attr[0][1] == "path" and attr[1][1] == "=" and attr[2][0] == "str":
            return attr[2][1]
    return None


def parse_use_tree(toks, i):
    """Parse the tree after `use` at toks[i]. Returns (leaves, index past
    ';'); a leaf is (segments, alias or None, is_glob)."""
    n = len(toks)
    leaves = []

    def tree(i, prefix):
        segs = list(prefix)
        while i < n:
            kind, v, _ = toks[i]
            if v == "::":
                if not segs:
                    segs.append("::")  # ::name is an external crate
                i += 1
            elif v == "$" and i + 1 < n and toks[i + 1][1] == "crate":
                i += 1  # $crate in a macro body is crate
            elif v == "{":
                i += 1
                while i < n and toks[i][1] != "}":
                    j = tree(i, segs)
                    i = j if j > i else i + 1
                    if i < n and toks[i][1] == ",":
                        i += 1
                return i + 1
            elif v == "*":
                leaves.append((tuple(segs), None, True))
                return i + 1
            elif kind in ("id", "kw"):
                if i + 1 < n and toks[i + 1][1] == "::":
                    segs.append(v)
                    i += 2
                    continue
                alias, j = None, i + 1
                if j + 1 < n and toks[j][1] == "as":
                    alias, j = toks[j + 1][1], j + 2
                leaves.append((tuple(segs + [v]), alias, False))
                return j
            else:
                return i
        return i

    j = tree(i, [])
    while j < n and toks[j][1] != ";":  # error recovery: a use ends at ';'
        j += 1
    return leaves, j + 1


class FileParser:
    """Reads one file into its Module (and the inline modules in it)."""

    def __init__(self, crate, top):
        self.crate, self.top = crate, top
        self.decls = []  # (scope, name, path attribute, is_test, line, left out): `mod x;`

    def parse(self):
        path = self.top.file
        with open(path, encoding="utf-8", errors="replace") as f:
            toks = tokenize(f.read())
        self._walk(toks)
        return self.decls

    def _walk(self, toks):
        file = self.top.file
        stack = []  # one entry per open brace: the inline Module it opens, or None
        cur = self.top
        attrs, vis = [], False
        includes = 0
        i = 0
        while i < len(toks):
            n = len(toks)
            kind, v, line = toks[i]
            module_level = not stack or stack[-1] is not None

            # Attributes, visibility: they belong to the item that follows.
            if v == "#" and kind == "p":
                j = i + 1
                inner = j < n and toks[j][1] == "!"
                if inner:
                    j += 1
                if j < n and toks[j][1] == "[":
                    k = _matching(toks, j, "[", "]")
                    if not inner:
                        attrs.append(toks[j + 1:k])
                    i = k + 1
                    continue
            if kind == "kw" and v == "pub":
                i, vis = _skip_visibility(toks, i), True
                continue
            item_attrs, attrs = attrs, []
            item_public, vis = vis, False
            if self.crate.skip_tests and not cur.is_test and any(_attr_is_cfg_test(a) for a in item_attrs):
                if kind == "kw" and v == "mod" and i + 2 < n and toks[i + 1][0] == "id" and toks[i + 2][1] == ";":
                    self.decls.append((cur, toks[i + 1][1], _attr_path(item_attrs), True, line, True))
                i = _skip_item(toks, i)
                continue

            if kind == "kw" and v == "use" and not (i + 1 < n and toks[i + 1][1] == "<"):
                leaves, i = parse_use_tree(toks, i + 1)
                for segs, alias, glob in leaves:
                    self._add_import(cur, segs, alias, glob, item_public, not module_level, line)
                continue

            if kind == "kw" and v == "mod" and i + 2 < n and toks[i + 1][0] == "id":
                name, nxt = toks[i + 1][1], toks[i + 2][1]
                is_test = cur.is_test or any(_attr_is_cfg_test(a) for a in item_attrs)
                if nxt == ";":
                    self.decls.append((cur, name, _attr_path(item_attrs), is_test, line, False))
                    i += 3
                    continue
                if nxt == "{":
                    child = Module(name, cur, file, inline=True, is_test=is_test)
                    cur.children[name] = child
                    stack.append(child)
                    cur = child
                    i += 3
                    continue

            if kind == "id" and v == "macro_rules" and i + 2 < n and toks[i + 1][1] == "!" \
                    and toks[i + 2][0] == "id":
                name = toks[i + 2][1]
                cur.macros[name] = file
                if any(a and a[0][1] == "macro_export" for a in item_attrs):
                    self.crate.root.defs.setdefault(name, file)
                i += 3
                continue

            if kind == "id" and v == "include" and i + 3 < n and toks[i + 1][1] == "!" \
                    and toks[i + 2][1] == "(" and toks[i + 3][0] == "str" and includes < 16:
                target = os.path.normpath(os.path.join(os.path.dirname(file), toks[i + 3][1]))
                end = _matching(toks, i + 2, "(", ")") + 1
                if os.path.isfile(target):
                    includes += 1
                    self.crate.included.add(target)
                    with open(target, encoding="utf-8", errors="replace") as f:
                        spliced = [(k, t, line) for k, t, _ in tokenize(f.read())]
                    toks[i:end] = spliced
                    continue
                i = end
                continue

            if module_level and (kind == "kw" and v in ("fn", "struct", "enum", "trait", "type", "const",
                                                        "static")
                                 or kind == "id" and v == "union" and i + 2 < n
                                 and toks[i + 1][0] == "id" and toks[i + 2][1] in ("{", "<", "where")):
                j = i + 1
                if v == "static" and j < n and toks[j][1] == "mut":
                    j += 1
                generic_const = v == "const" and i > 0 and toks[i - 1][1] in ("<", ",")
                if j < n and toks[j][0] == "id" and not generic_const:
                    cur.defs.setdefault(toks[j][1], file)
                    i = j + 1
                    continue
                i += 1
                continue

            if kind == "p":
                if v == "{":
                    stack.append(None)
                elif v == "}" and stack:
                    if stack.pop() is not None:
                        cur = next((m for m in reversed(stack) if m is not None), self.top)
                i += 1
                continue

            if kind == "id" or (kind == "kw" and v in ("crate", "self", "super")):
                prev = toks[i - 1] if i else ("p", "", 0)
                before = toks[i - 2] if i >= 2 else ("p", "", 0)
                if prev[1] == "::" and kind == "id" and before[0] != "id" and before[1] not in (
                        "crate", "self", "super", "Self", ">", ")"):
                    segs, j = [v], i  # ::crate::path: another crate, for the layer rules
                    while j + 2 < n and toks[j + 1][1] == "::" and toks[j + 2][0] == "id":
                        segs.append(toks[j + 2][1])
                        j += 2
                    cur.externs.append((tuple(segs), line, False))
                    i = j + 1
                    continue
                if prev[1] in ("::", ".") or (prev[1] == "$" and v != "crate"):
                    i += 1
                    continue
                segs, j = [v], i
                while j + 2 < n and toks[j + 1][1] == "::" and (
                        toks[j + 2][0] == "id" or toks[j + 2][1] in ("self", "super")):
                    segs.append(toks[j + 2][1])
                    j += 2
                if len(segs) == 1 and prev[0] == "kw" and prev[1] in _DECLARES:
                    i += 1  # a name being declared (fn f, let x, as u32)
                    continue
                after = toks[j + 1][1] if j + 1 < n else ""
                is_macro = after == "!" and j + 2 < n and toks[j + 2][1] in ("(", "[", "{")
                cur.heads.add(v)
                if len(segs) > 1:
                    cur.refs.append((tuple(segs), line, is_macro))
                elif is_macro:
                    cur.bare_macros.setdefault(v, line)
                elif kind == "id" and after != ":":
                    cur.bare.setdefault(v, line)
                i = j + 1
                continue
            i += 1

    def _add_import(self, scope, segs, alias, glob, public, local, line):
        if not segs:
            return
        if segs[0] == "::":
            if len(segs) > 1:
                scope.externs.append((tuple(segs[1:]), line, glob))
            return  # an external crate
        if not glob and segs[-1] == "self":
            segs = segs[:-1]
            if not segs:
                return
        if not glob and alias is None:
            alias = segs[-1]
        scope.imports.append(Import(scope, segs, alias, glob, public, local, line))


class Crate:
    """One crate's module tree, from its root file."""

    def __init__(self, root_file, skip_tests=False):
        self.root_file = root_file
        self.skip_tests = skip_tests
        self.root = Module("crate", None, root_file, mod_rs=True)
        self.modules = []          # every Module, inline ones too
        self.files = {}            # file -> its (first) file Module
        self.test_files = []       # files of #[cfg(test)] modules
        self.skipped_tests = []    # #[cfg(test)] module files left out (--skip-test-modules)
        self.missing = []          # (declaring file, line, name, where looked)
        self.included = set()      # files read through include!
        self._load(skip_tests)

    def _load(self, skip_tests):
        queue = deque([self.root])
        self.files[self.root.file] = self.root
        while queue:
            fm = queue.popleft()
            for scope, name, path_attr, is_test, line, left_out in FileParser(self, fm).parse():
                found = self._locate(fm, scope, name, path_attr)
                if not found[0]:
                    self.missing.append((fm.file, line, name, found[1]))
                    continue
                file, by_path = found
                if left_out:
                    self.skipped_tests.append(file)
                    continue
                child = Module(name, scope, file, is_test=is_test, mod_rs=by_path or
                               os.path.basename(file) == "mod.rs")
                scope.children[name] = child
                if is_test:
                    self.test_files.append(file)
                if file not in self.files:
                    self.files[file] = child
                    queue.append(child)
        self.modules = list(self._walk(self.root))

    @staticmethod
    def _walk(m):
        todo = [m]
        while todo:
            m = todo.pop()
            yield m
            todo.extend(m.children.values())

    @staticmethod
    def _locate(fm, scope, name, path_attr):
        """(file, came by #[path]) of `mod name;` in scope (inside file module
        fm), or (None, candidates looked at)."""
        chain, m = [], scope
        while m is not fm:
            chain.append(m.name)
            m = m.parent
        chain.reverse()
        here = os.path.dirname(fm.file)
        own = here if fm.mod_rs else os.path.join(here, os.path.splitext(os.path.basename(fm.file))[0])
        if path_attr is not None:
            base = here if not chain else os.path.join(own, *chain)
            cand = os.path.normpath(os.path.join(base, path_attr))
            return (cand, True) if os.path.isfile(cand) else (None, [cand])
        base = os.path.join(own, *chain)
        cands = [os.path.join(base, name + ".rs"), os.path.join(base, name, "mod.rs")]
        for c in cands:
            if os.path.isfile(c):
                return c, False
        return None, cands


# ------------------------------------------------------------ resolution ----

class Resolver:
    """Finds the file that defines what a path names.

    A result is ("mod", Module), ("item", file, name) or ("partial", Module,
    segment): the path reached Module but it defines no `segment` we can see
    (made by a macro, say): its file is the best guess."""

    def __init__(self, crate):
        self.crate = crate
        self._globs = {}

    def resolve(self, scope, segs, local=True, trace=None, seen=None, more_after=False):
        """What the path segs, written in scope, names. An item result carries
        the segment as written there; more_after: the caller's path goes on
        past segs (so a last segment that is both a module and an item is the
        module)."""
        seen = set() if seen is None else seen
        first, rest = segs[0], list(segs[1:])
        if first == "crate":
            cur = ("mod", self.crate.root)
        elif first in ("self", "super"):
            m = scope
            if first == "super":
                m = m.parent
            while rest and rest[0] == "super" and m is not None:
                m, rest = m.parent, rest[1:]
            if m is None:
                return None
            cur = ("mod", m)
        else:
            cur = self.lookup(scope, first, more=bool(rest) or more_after, local=local, trace=trace, seen=seen)
            if cur is None:
                return None  # std, another crate, a local variable or a generic
            if cur[0] == "item":
                cur = ("item", cur[1], first)
        for k, seg in enumerate(rest):
            if cur[0] != "mod":
                break  # an item: what follows are its variants or associated items
            if seg == "self":
                continue
            found = self.lookup(cur[1], seg, more=k + 1 < len(rest) or more_after, local=False,
                                trace=trace, seen=seen)
            if found is None:
                return ("partial", cur[1], seg)
            cur = ("item", found[1], seg) if found[0] == "item" else found
        return cur

    def lookup(self, m, name, more, local, trace=None, seen=None):
        """What `name` names in module m: its child module, its own item, or
        what one of its imports brings (followed to the definition)."""
        seen = set() if seen is None else seen
        key = (id(m), name, more)
        if key in seen:
            return None
        seen.add(key)
        # A name may be a module and an item at once (`mod hypot; pub use
        # hypot::hypot;`): a path that goes on wants the module, a last
        # segment the item.
        child, own = m.children.get(name), m.defs.get(name)
        if more and child is not None:
            return ("mod", child)
        if own is not None:
            return ("item", own, name)
        imports = [imp for imp in m.imports if local or not imp.local]
        for imp in imports:
            if not imp.glob and imp.alias == name:
                found = self.resolve(imp.scope, imp.segs, local=imp.local, trace=trace, seen=seen,
                                     more_after=more)
                if found is not None:
                    if trace is not None:
                        trace.append(imp)
                    return found
        if child is not None:
            return ("mod", child)
        return self.lookup_globs(imports, name, more, trace, seen)

    def lookup_globs(self, imports, name, more, trace=None, seen=None):
        seen = set() if seen is None else seen
        for imp in imports:
            if not imp.glob:
                continue
            target = self.glob_target(imp, seen)
            if target is not None and target[0] == "mod":
                found = self.lookup(target[1], name, more, local=False, trace=trace, seen=seen)
                if found is not None:
                    if trace is not None:
                        trace.append(imp)
                    return found
        return None

    def glob_target(self, imp, seen=None):
        if id(imp) not in self._globs:
            self._globs[id(imp)] = None  # a glob reaching itself finds nothing
            self._globs[id(imp)] = self.resolve(imp.scope, imp.segs, local=imp.local,
                                                seen=set() if seen is None else set(seen))
        return self._globs[id(imp)]

    @staticmethod
    def macro_in_scope(m, name):
        while m is not None:
            if name in m.macros:
                return m.macros[name]
            m = m.parent
        return None


def target_file(found):
    if found is None:
        return None
    return found[1].file if found[0] in ("mod", "partial") else found[1]


def crate_edges(crate, add_edge, unresolved):
    """Calls add_edge(src file, dst file, name, line) for every reference."""
    res = Resolver(crate)
    for scope in crate.modules:
        src = scope.file
        used = set()  # ids of the imports that some path of this scope went through

        for segs, line, is_macro in scope.refs:
            trace = []
            found = res.resolve(scope, segs, trace=trace)
            used.update(id(imp) for imp in trace)
            if found is None:
                if segs[0] in ("crate", "self", "super"):
                    unresolved.append((src, line, "::".join(segs)))
                continue
            if found[0] == "item":
                add_edge(src, found[1], found[2], line)
            elif found[0] == "partial":
                add_edge(src, found[1].file, found[2], line)

        named = {imp.alias for imp in scope.imports if not imp.glob}
        for name, line in scope.bare.items():
            if name in scope.defs or name in scope.children or name in named:
                continue
            trace = []
            found = res.lookup_globs(scope.imports, name, False, trace=trace)
            used.update(id(imp) for imp in trace)
            if found is not None and found[0] == "item":
                add_edge(src, found[1], name, line)

        for name, line in scope.bare_macros.items():
            if name in named:
                continue
            file = res.macro_in_scope(scope, name)
            if file is not None:
                add_edge(src, file, name + "!", line)

        for imp in scope.imports:
            if imp.glob:
                if imp.public or id(imp) in used:
                    continue
                found = res.glob_target(imp)
                if found is None:
                    if imp.segs[0] in ("crate", "self", "super"):
                        unresolved.append((src, imp.line, "::".join(imp.segs) + "::*"))
                    continue
                label = ("::".join(imp.segs[-1:]) or imp.segs[0]) + "::*"
                add_edge(src, target_file(found), label, imp.line)
                continue
            found = res.resolve(imp.scope, imp.segs, local=imp.local)
            if found is None:
                if imp.segs[0] in ("crate", "self", "super"):
                    unresolved.append((src, imp.line, "::".join(imp.segs)))
                continue
            named_here = imp.alias in scope.heads
            if found[0] == "mod":
                # Paths through the module make the edges; an unnamed private one is an edge.
                if not imp.public and not named_here:
                    add_edge(src, found[1].file, imp.segs[-1], imp.line)
            elif not imp.public or named_here:
                add_edge(src, target_file(found), imp.segs[-1] if found[0] == "item" else found[2],
                         imp.line)


# ----------------------------------------------------------------- graph ----

class Graph:
    def __init__(self):
        self.nodes = set()
        self.edges = {}      # (src, dst) -> {name: first line}
        self.ancestors = {}  # file -> files of the modules that enclose its module
        self.set_aside = set()  # edges that cycles leave out (--upward-ok)

    def is_upward(self, edge):
        """A file naming an item of a module that encloses its own (super::x, crate::x)."""
        return edge[1] in self.ancestors.get(edge[0], ())

    def add(self, src, dst, name, line):
        if src == dst:
            return
        names = self.edges.setdefault((src, dst), {})
        if name not in names or line < names[name]:
            names[name] = line

    def successors(self):
        out = {n: [] for n in self.nodes}
        for src, dst in self.edges:
            if (src, dst) not in self.set_aside:
                out.setdefault(src, []).append(dst)
        for v in out.values():
            v.sort()
        return out

    def cycles(self):
        """Strongly connected components of more than one file (Tarjan, iterative)."""
        succ = self.successors()
        index, low, on_stack, stack, comps = {}, {}, set(), [], []
        counter = 0
        for start in sorted(succ):
            if start in index:
                continue
            work = [(start, 0)]
            index[start] = low[start] = counter
            counter += 1
            stack.append(start)
            on_stack.add(start)
            while work:
                v, k = work[-1]
                if k < len(succ[v]):
                    work[-1] = (v, k + 1)
                    w = succ[v][k]
                    if w not in index:
                        index[w] = low[w] = counter
                        counter += 1
                        stack.append(w)
                        on_stack.add(w)
                        work.append((w, 0))
                    elif w in on_stack:
                        low[v] = min(low[v], index[w])
                    continue
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        comps.append(sorted(comp))
        return sorted(comps)

    def shortest_loop(self, comp):
        """One loop through comp's first file, as a list of files."""
        members = set(comp)
        succ = self.successors()
        start = comp[0]
        prev = {}
        queue = deque([start])
        while queue:
            v = queue.popleft()
            for w in succ.get(v, []):
                if w not in members:
                    continue
                if w == start:
                    path = [v]
                    while path[-1] != start:
                        path.append(prev[path[-1]])
                    return [start] + path[::-1][1:] + [start] if len(path) > 1 else [start, v, start]
                if w not in prev:
                    prev[w] = v
                    queue.append(w)
        return comp + [start]


def build(roots, skip_tests=False, upward_ok=False):
    crates = [Crate(r, skip_tests) for r in roots]
    graph, unresolved = Graph(), []
    for c in crates:
        graph.nodes.update(c.files)
        for file, m in c.files.items():
            up = graph.ancestors.setdefault(file, set())
            m = m.parent
            while m is not None:
                up.add(m.file)
                m = m.parent
        crate_edges(c, graph.add, unresolved)
    if upward_ok:
        graph.set_aside = {e for e in graph.edges if graph.is_upward(e)}
    return crates, graph, unresolved


# ------------------------------------------------------------ layer rules ----

def app_layer(relpath):
    """The layer of a workspace-relative path under app/src (its first part, .rs
    dropped: page/odometry/frame.rs and page.rs are page), or None elsewhere."""
    if not relpath.startswith(APP_SRC + "/"):
        return None
    first = relpath[len(APP_SRC) + 1:].split("/")[0]
    return first[:-3] if first.endswith(".rs") else first


def _under(relpath, place):
    return relpath == place or relpath == place + ".rs" or relpath.startswith(place + "/")


def extern_paths(crate, loaded):
    """Every path from crate's files into another crate of the workspace, as
    (file, line, segments from that crate's name, is_glob). A `use` alias of such a
    path is followed; a path or name the crate finds nowhere is tried through its
    globs of another crate (`use siftlab_core::*`), and kept if that crate has it.
    loaded: crate name -> its Crate, for the crates that were read."""
    names = set(CRATES)
    own = Resolver(crate)
    found = []
    for scope in crate.modules:
        aliases, globs = {}, []
        for imp in scope.imports:
            if imp.segs[0] in names:
                found.append((scope.file, imp.line, tuple(imp.segs), imp.glob))
                if imp.glob:
                    globs.append(tuple(imp.segs))
                else:
                    aliases[imp.alias] = tuple(imp.segs)
        for segs, line, glob in scope.externs:
            if segs[0] in names:
                found.append((scope.file, line, segs, glob))
                if glob:
                    globs.append(segs)
        tries = [(segs, line) for segs, line, _ in scope.refs]
        named = {imp.alias for imp in scope.imports if not imp.glob}
        tries += [((name,), line) for name, line in scope.bare.items()
                  if name not in scope.defs and name not in scope.children and name not in named]
        for segs, line in tries:
            if segs[0] in names:
                found.append((scope.file, line, tuple(segs), False))
            elif segs[0] in aliases:
                found.append((scope.file, line, aliases[segs[0]] + tuple(segs[1:]), False))
            elif globs and own.resolve(scope, list(segs)) is None:
                for g in globs:
                    other = loaded.get(g[0])
                    full = g + tuple(segs)
                    hit = other and Resolver(other).resolve(other.root, ["crate"] + list(full[1:]))
                    if hit and hit[0] != "partial":
                        found.append((scope.file, line, full, False))
                        break
    return found


def check_rules(crates, graph, rel):
    """The violations of LAYERS and CRATE_RULES: (file, line, name, what, rule), file
    workspace-relative (rel), name the imported item as LAYER_ALLOW lists it."""
    out = []
    # The app's layers, on the graph's edges inside app/src.
    for (src, dst), names in graph.edges.items():
        a, b = app_layer(rel(src)), app_layer(rel(dst))
        if a is None or b is None or a == b:
            continue
        if a not in LAYERS:
            rule = "every file of app/src is in a layer: " + ", ".join(LAYERS)
        elif LAYERS[a] == ANY or b in LAYERS[a]:
            continue
        else:
            rule = (f"{a} may import " + (", ".join(LAYERS[a]) if LAYERS[a] else "no other app layer")
                    + f", not {b} (layers: page -> services -> model -> protocol)")
        for name, line in sorted(names.items(), key=lambda kv: (kv[1], kv[0])):
            out.append((rel(src), line, name, f"imports {name} from {rel(dst)}", rule))
    # Between crates.
    loaded = {}
    for c in crates:
        for name, place in CRATES.items():
            if rel(os.path.dirname(c.root_file)) == place:
                loaded[name] = c
    for c in crates:
        src_dir = rel(os.path.dirname(c.root_file))
        rules = [r for r in CRATE_RULES if r[0] == src_dir]
        if not rules:
            continue
        seen = set()
        for file, line, segs, glob in extern_paths(c, loaded):
            for _, other, place, rule in rules:
                if segs[0] != other or (file, line, segs, rule) in seen:
                    continue
                seen.add((file, line, segs, rule))
                text = "::".join(segs) + ("::*" if glob else "")
                if place is None:
                    out.append((rel(file), line, text, f"imports {text}", rule))
                    continue
                target = loaded.get(other)
                hit = target and Resolver(target).resolve(target.root, ["crate"] + list(segs[1:]))
                where = target_file(hit)
                if where is not None:
                    bad = _under(rel(where), place)
                    text_at = f"imports {text} ({rel(where)})"
                else:  # not found there (or not read): by the path's own segments
                    inside = place[len(CRATES[other]):].strip("/").split("/")
                    bad = list(segs[1:1 + len(inside)]) == inside
                    text_at = f"imports {text}"
                if bad:
                    out.append((rel(file), line, text, text_at, rule))
    return sorted(set(out))


# ------------------------------------------------------------------- CLI ----

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
