"""A crate's module tree, from its root file through `mod x;` and `#[path]`."""

import os
from collections import deque

from .parse import FileParser, Module


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
