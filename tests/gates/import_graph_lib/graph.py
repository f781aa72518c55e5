"""The file graph of one or more crates, and its cycles."""

from collections import deque

from .crate import Crate
from .resolve import crate_edges


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
