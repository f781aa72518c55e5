"""The lab's import rule for the student's file: a part of the harness (siftlab_harness.py;
docs/marking.md, "Imports").

Loading this module puts the rule in place. The harness loads it after its other modules and
before any of the student's code runs: it takes the real import functions, this thread and
the cv2 the harness loaded at that moment, as the harness did when it held this code.
"""

import builtins
import importlib.util
import os
import sys
import threading

import _siftlab_harness_run as _running
import cv2

HERE = os.path.dirname(os.path.abspath(__file__))


# --- what the student's file may import ----------------------------------------------------
# The lab's rule (for fidelity; the sandbox is what keeps a file in): the standard library,
# cv2, numpy and vision_tasks_base. Checked on every route in: `import` and `__import__`
# (builtins, also for exec with the real builtins), importlib.import_module and
# importlib.__import__, and every module built from a spec (importlib.util's file loading
# included), by name and by the file it comes from.

_LAB_MODULES = {"cv2", "numpy", "vision_tasks_base"}


def _stdlib_names():
    names = getattr(sys, "stdlib_module_names", None)
    return frozenset(names) if names else None


_STDLIB = _stdlib_names()


def _is_stdlib(top):
    if _STDLIB is not None:
        return top in _STDLIB
    if top in sys.builtin_module_names:
        return True
    try:
        spec = importlib.util.find_spec(top)
    except (ImportError, ValueError):
        return False
    if spec is None or spec.origin is None:
        return False
    return _origin_allowed(spec.origin)


def _allowed_roots():
    import sysconfig
    paths = sysconfig.get_paths()
    roots = {os.path.realpath(paths[k]) for k in ("stdlib", "platstdlib") if k in paths}
    roots.update(os.path.realpath(p) for p in sys.path if p.endswith(".zip"))
    roots.add(os.path.realpath(HERE))
    return tuple(r + os.sep for r in roots)


_PACKAGE_DIRS = ("site-packages", "dist-packages")


def _origin_allowed(origin):
    """A module's file is the standard library's (not a package installed beside it),
    numpy's, or one of our shims."""
    if not isinstance(origin, str) or not os.path.isabs(origin):
        return True  # built-in, frozen, namespace
    path = os.path.realpath(origin)
    np = cv2._np
    if np is not None and path.startswith(os.path.dirname(os.path.realpath(np.__file__)) + os.sep):
        return True
    parts = path.split(os.sep)
    return path.startswith(_ROOTS) and not any(d in parts for d in _PACKAGE_DIRS)


def _name_allowed(name):
    top = name.partition(".")[0]
    return top in _LAB_MODULES or _is_stdlib(top)


def _refuse(name):
    top = name.partition(".")[0]
    raise ModuleNotFoundError(
        "No module named '%s': the lab's machines have only Python's standard library, "
        "cv2 (OpenCV) and numpy" % top, name=top)


_MAIN_THREAD = threading.get_ident()


def _gated():
    """The rule holds while the student's code runs, and in any thread it started."""
    return _running._in_student or threading.get_ident() != _MAIN_THREAD


_real_import = builtins.__import__
_bootstrap = importlib._bootstrap
_real_gcd_import = _bootstrap._gcd_import
_real_bootstrap_import = _bootstrap.__import__
_real_module_from_spec = _bootstrap.module_from_spec


def _guarded_import(name, globals=None, locals=None, fromlist=(), level=0):
    if level == 0 and _gated() and not _name_allowed(name):
        _refuse(name)
    return _real_import(name, globals, locals, fromlist, level)


def _guarded_gcd_import(name, package=None, level=0):
    if level == 0 and _gated() and not _name_allowed(name):
        _refuse(name)
    return _real_gcd_import(name, package, level)


def _guarded_bootstrap_import(name, globals=None, locals=None, fromlist=(), level=0):
    if level == 0 and _gated() and not _name_allowed(name):
        _refuse(name)
    return _real_bootstrap_import(name, globals, locals, fromlist, level)


def _guarded_module_from_spec(spec):
    if _gated():
        name = getattr(spec, "name", "") or "?"
        if not _name_allowed(name):
            _refuse(name)
        origin = getattr(spec, "origin", None)
        if not _origin_allowed(origin):
            raise ModuleNotFoundError(
                "%s is not a module of Python's standard library, cv2 or numpy: the lab's machines "
                "have only those" % (origin,), name=name)
    return _real_module_from_spec(spec)


# Computed before the gate is in place (it imports sysconfig).
_ROOTS = _allowed_roots()
builtins.__import__ = _guarded_import
_bootstrap._gcd_import = _guarded_gcd_import
_bootstrap.__import__ = _guarded_bootstrap_import
importlib.__import__ = _guarded_bootstrap_import
_bootstrap.module_from_spec = _guarded_module_from_spec
importlib.util.module_from_spec = _guarded_module_from_spec
