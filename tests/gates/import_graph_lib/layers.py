"""The layer rules: the app's role layers and what one crate may reach of another."""

import os

from .resolve import Resolver, target_file

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
