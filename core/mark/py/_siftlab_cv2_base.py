"""Part of siftlab's `cv2` (cv2.py re-exports what it defines): numpy when this
Python has it, and OpenCV's errors and argument conversions, which every part of cv2 uses.

The harness loads it from this folder before cv2.py (siftlab_harness.py, `_load_shim`).
"""

import math as _math
import struct as _struct
import sys as _sys

try:
    import numpy as _np
except ImportError:  # the browser's Python (Pyodide without numpy)
    _np = None

_PACK_F = _struct.Struct("<f")
_IN_BROWSER = _sys.platform == "emscripten"


class error(Exception):
    """OpenCV's exception class (cv2.error)."""


class NumpyMissing(ImportError):
    """Raised where the student's code needs numpy and this Python has none."""


def _numpy_missing(what):
    where = "the browser's Python" if _IN_BROWSER else "this python3"
    return NumpyMissing("this needs numpy, which %s does not have: %s" % (where, what))


def _f32(value, name="value"):
    """OpenCV's float conversion: a real number, stored as float32 (read back widened)."""
    if value is None:
        return 0.0
    if isinstance(value, (str, bytes)) or isinstance(value, complex):
        raise TypeError("Argument '%s' can't be treated as a float" % name)
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TypeError("Argument '%s' can't be treated as a float" % name) from None
    if v != v or v in (_math.inf, -_math.inf):
        return v
    try:
        return _PACK_F.unpack(_PACK_F.pack(v))[0]
    except OverflowError:  # beyond float32's range: OpenCV's cast gives an infinity
        return _math.copysign(_math.inf, v)


def _int(value, name="value"):
    """OpenCV's int conversion: an integer (not bool, not float) that fits a C int."""
    if isinstance(value, bool) or (_np is not None and isinstance(value, _np.bool_)):
        raise TypeError("Argument '%s' must be integer, not bool" % name)
    if isinstance(value, int):
        v = value
    elif _np is not None and isinstance(value, _np.integer):
        v = int(value)
    else:
        raise TypeError("Argument '%s' is required to be an integer" % name)
    if not -2 ** 31 <= v < 2 ** 31:
        raise TypeError("integer won't fit into a C int")
    return v


def _bad_argument(fn, msg):
    return error("OpenCV(4.8.0) :-1: error: (-5:Bad argument) in function '%s'\n"
                 "> Overload resolution failed:\n>  - %s\n" % (fn, msg))


def _assert_failed(cond, fn, where="matchers.cpp"):
    return error("OpenCV(4.8.0) %s: error: (-215:Assertion failed) %s in function '%s'\n"
                 % (where, cond, fn))


def _missing(name):
    return ("siftlab's cv2 has no cv2.%s: the lab's tasks need only BFMatcher, DMatch, KeyPoint "
            "(and SIFT_create for the base class)" % name)
