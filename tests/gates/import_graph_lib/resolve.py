"""Paths resolved to the files that define what they name, and the edges they make."""


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
