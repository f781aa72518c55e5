"""What the student's calls returned, as the replies carry it: a part of the harness
(siftlab_harness.py; docs/marking.md, "Messages" and "Typed values"). dt, nn and nndr's
DMatch lists as rows or compact, matching_info's value by type, JSON without NaN.
"""

import array
import base64
import json
import math
import operator
import sys

import cv2
from _siftlab_harness_run import _Failure


def _type_error(msg):
    return _Failure({"error": msg, "kind": "type"})


def _tname(v):
    return type(v).__name__


def _check_matches(fn, value, compact=False):
    """The list of lists of DMatch as rows of (queryIdx, trainIdx, distance), or with
    compact the {"n", "q", "t", "d"} of docs/marking.md (a wrong type: _Failure)."""
    if type(value) is not list:
        raise _type_error("%s must return a list (one list per query), got %s" % (fn, _tname(value)))
    DM = cv2.DMatch
    ours = {DM, cv2._Match}
    if compact:
        n, q, t, d = [], array.array("i"), array.array("i"), array.array("f")
        gq, gt, gd = operator.attrgetter("_q"), operator.attrgetter("_t"), operator.attrgetter("_d")
    else:
        get = operator.attrgetter("_q", "_t", "_d")
        out = []
    for qi, row in enumerate(value):
        if type(row) is not list and type(row) is not tuple:
            raise _type_error("%s: the item for query %d is %s, not a list of DMatch"
                              % (fn, qi, _tname(row)))
        if not ours.issuperset(map(type, row)):
            for j, m in enumerate(row):
                if not isinstance(m, DM):
                    raise _type_error("%s: item %d of query %d is %s, not a DMatch" % (fn, j, qi, _tname(m)))
        if compact:
            n.append(len(row))
            q.extend(map(gq, row))
            t.extend(map(gt, row))
            d.extend(map(gd, row))
        else:
            out.append(list(map(get, row)))
    if not compact:
        return out
    if sys.byteorder != "little":
        q.byteswap()
        t.byteswap()
        d.byteswap()
    enc = lambda a: base64.b64encode(a.tobytes()).decode("ascii")  # noqa: E731
    return {"n": n, "q": enc(q), "t": enc(t), "d": enc(d)}


def _finite(v):
    """JSON has no infinities or NaN: those travel as the strings "inf", "-inf", "nan"."""
    if isinstance(v, float) and not math.isfinite(v):
        return "nan" if v != v else ("inf" if v > 0 else "-inf")
    if isinstance(v, (list, tuple)):
        return [_finite(x) for x in v]
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    return v


def _dumps(obj):
    try:
        return json.dumps(obj, allow_nan=False, separators=(",", ":"))
    except ValueError:
        return json.dumps(_finite(obj), allow_nan=False, separators=(",", ":"))


# --- typed values (docs/marking.md, "Typed values") -----------------------------------------
# matching_info's value goes to siftlab by type, and siftlab applies Python's == outside this
# interpreter. Every conversion below is the base type's own (int.__int__, float.__float__,
# tuple.__iter__, ...), so no method of the student's classes runs: a subclass is its base
# value, tagged with its class name.

MAX_DEPTH = 32
MAX_NODES = 100000


def _np_types():
    np = cv2._np
    if np is None:
        return None, None
    return np.generic, np.ndarray


_NP_GENERIC, _NP_NDARRAY = _np_types()


def _sub(t, base, out):
    if t is not base:
        out["sub"] = str.__str__(t.__name__) if isinstance(t.__name__, str) else "?"
    return out


def _enc(v, depth, budget):
    budget[0] -= 1
    t = type(v)
    if budget[0] < 0:
        return {"opaque": t.__name__, "why": "over %d items" % MAX_NODES}
    if depth > MAX_DEPTH:
        return {"opaque": t.__name__, "why": "nested over %d levels" % MAX_DEPTH}
    if v is None:
        return None
    if t is bool:
        return v is True
    if issubclass(t, int):
        i = int.__int__(v)
        if t is not int:
            return _sub(t, int, {"int": str(i)})
        return i if -(1 << 63) <= i < (1 << 63) else {"int": str(i)}
    if issubclass(t, float):
        f = float.__float__(v)
        if t is float and math.isfinite(f):
            return f
        return _sub(t, float, {"float": f if math.isfinite(f) else ("nan" if f != f else ("inf" if f > 0 else "-inf"))})
    if issubclass(t, str):
        x = str.__str__(v)
        return x if t is str else _sub(t, str, {"str": x})
    if issubclass(t, tuple):
        return _sub(t, tuple, {"tuple": [_enc(x, depth + 1, budget) for x in tuple.__iter__(v)]})
    if issubclass(t, list):
        return _sub(t, list, {"list": [_enc(x, depth + 1, budget) for x in list(list.__iter__(v))]})
    if _NP_GENERIC is not None and issubclass(t, _NP_GENERIC):
        # A numpy scalar is its Python value (np.float32 widens exactly), as == sees it.
        x = _NP_GENERIC.item(v)
        if type(x) in (bool, int, float, str):
            return _sub(t, t, {"np": t.__name__, "value": _enc(x, depth + 1, budget)})
        return {"opaque": t.__name__}
    if _NP_NDARRAY is not None and issubclass(t, _NP_NDARRAY):
        return {"opaque": "ndarray", "shape": [int(n) for n in _NP_NDARRAY.__getattribute__(v, "shape")]}
    return {"opaque": t.__name__ if isinstance(t.__name__, str) else "?"}


def _typed(v):
    try:
        return _enc(v, 0, [MAX_NODES])
    except Exception as e:  # a class whose layout lies about its base
        return {"opaque": "?", "why": "%s: %s" % (type(e).__name__, e)}


def _describe(v):
    if isinstance(v, (tuple, list)):
        return "a %s of %d items" % (_tname(v), len(v))
    return _tname(v)
