"""One .rs file read into its Module: declarations, imports and the paths it writes."""

import os

from .lex import DECLARES, tokenize


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
                if len(segs) == 1 and prev[0] == "kw" and prev[1] in DECLARES:
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
