"""siftlab's `cv2`: the part of OpenCV 4.8's Python API the COMP24011 lab's tasks use.

A student's `vision_tasks.py` runs against this module (docs/marking.md). It behaves as
OpenCV's does where the lab's code can tell: `KeyPoint` and `DMatch` store float32 (a value
set is rounded to float32 and read back widened), `BFMatcher().knnMatch` returns a tuple
(one per query) of tuples of `DMatch` in OpenCV's order and ties, and the errors OpenCV
raises for bad arguments are raised here as `cv2.error`. The k-NN work itself is never done
in Python: `knnMatch` builds the knn request of docs/marking.md and hands it to the host
(siftlab's matcher) through `_host`, which siftlab_harness.py installs.

Anything else of cv2 raises AttributeError naming it. Descriptors are numpy float32 N x 128
arrays when numpy imports, else `Descriptors`, a small read-only stand-in.
"""

import base64 as _base64
import math as _math
from itertools import repeat as _repeat
from operator import attrgetter as _attrgetter
import struct as _struct
import sys as _sys

try:
    import numpy as _np
except ImportError:  # the browser's Python (Pyodide without numpy)
    _np = None

__version__ = "4.8.0"

NORM_INF = 1
NORM_L1 = 2
NORM_L2 = 4
NORM_L2SQR = 5
NORM_HAMMING = 6
NORM_HAMMING2 = 7

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


# --- KeyPoint ------------------------------------------------------------------------------

class KeyPoint:
    """cv2.KeyPoint: pt (float32 x, y as a tuple of floats), size, angle, response (float32),
    octave, class_id (int)."""

    __slots__ = ("pt", "size", "angle", "response", "octave", "class_id")

    def __init__(self, x=None, y=None, size=None, angle=-1, response=0, octave=0, class_id=-1):
        if x is None and y is None and size is None:
            object.__setattr__(self, "pt", (0.0, 0.0))
            object.__setattr__(self, "size", 0.0)
        else:
            if size is None:
                raise _bad_argument("KeyPoint", "KeyPoint() missing required argument 'size' (pos 3)")
            try:
                object.__setattr__(self, "pt", (_f32(x, "x"), _f32(y, "y")))
                object.__setattr__(self, "size", _f32(size, "size"))
            except TypeError as e:
                raise _bad_argument("KeyPoint", str(e)) from None
        self.angle = angle
        self.response = response
        self.octave = octave
        self.class_id = class_id

    def __setattr__(self, name, value):
        if name == "pt":
            try:
                x, y = value
            except (TypeError, ValueError):
                raise TypeError("Argument 'value' must be a tuple of 2 floats") from None
            value = (_f32(x), _f32(y))
        elif name in ("size", "angle", "response"):
            value = _f32(value)
        elif name in ("octave", "class_id"):
            value = _int(value)
        object.__setattr__(self, name, value)

    def __repr__(self):
        return "< cv2.KeyPoint %#x>" % id(self)

    @staticmethod
    def convert(keypoints, keypointIndexes=()):
        return KeyPoint_convert(keypoints, keypointIndexes)

    @staticmethod
    def overlap(kp1, kp2):
        raise AttributeError(_missing("KeyPoint.overlap"))


def _keypoint(x, y, size, angle, response, octave):
    """A KeyPoint from values that are float32 already (the host's)."""
    k = KeyPoint.__new__(KeyPoint)
    _set = object.__setattr__
    _set(k, "pt", (x, y))
    _set(k, "size", size)
    _set(k, "angle", angle)
    _set(k, "response", response)
    _set(k, "octave", octave)
    _set(k, "class_id", -1)
    return k


def KeyPoint_convert(keypoints, keypointIndexes=()):
    """cv2.KeyPoint_convert(keypoints): an N x 2 float32 array of the points (numpy only)."""
    if _np is None:
        raise _numpy_missing("cv2.KeyPoint_convert returns a numpy array")
    kps = list(keypoints)
    idx = list(keypointIndexes) if keypointIndexes is not None else []
    if idx:
        kps = [kps[i] for i in idx]
    return _np.array([k.pt for k in kps], dtype=_np.float32).reshape(-1, 2)


# --- DMatch --------------------------------------------------------------------------------

class DMatch:
    """cv2.DMatch: queryIdx, trainIdx, imgIdx (int) and distance (float32, read as a float).

    DMatch() is (-1, -1, -1, FLT_MAX); DMatch(q, t, d) has imgIdx -1, as OpenCV's; knnMatch's
    matches have imgIdx 0. `==` is identity and `<` is not supported, as OpenCV's. Setting
    an attribute converts as OpenCV does (int, or a float rounded to float32)."""

    __slots__ = ("_q", "_t", "_i", "_d")

    def __init__(self, *args, **kwargs):
        names = ("_queryIdx", "_trainIdx", "_imgIdx", "_distance")
        if not args and not kwargs:
            q, t, i, d = -1, -1, -1, 3.4028234663852886e+38
        else:
            if len(args) > 4:
                raise _bad_argument("DMatch", "DMatch() takes at most 4 arguments (%d given)" % len(args))
            given = dict(zip(names if len(args) == 4 else ("_queryIdx", "_trainIdx", "_distance"), args))
            for k, v in kwargs.items():
                if k not in names or k in given:
                    raise _bad_argument("DMatch", "DMatch() got an unexpected keyword argument '%s'" % k)
                given[k] = v
            for req in ("_queryIdx", "_trainIdx", "_distance"):
                if req not in given:
                    raise _bad_argument("DMatch", "DMatch() missing required argument '%s'" % req)
            try:
                q = _int(given["_queryIdx"], "_queryIdx")
                t = _int(given["_trainIdx"], "_trainIdx")
                i = _int(given.get("_imgIdx", -1), "_imgIdx")
                d = _f32(given["_distance"], "_distance")
            except TypeError as e:
                raise _bad_argument("DMatch", str(e)) from None
        self._q = q
        self._t = t
        self._i = i
        self._d = d

    def _set_q(self, v):
        self._q = _int(v)

    def _set_t(self, v):
        self._t = _int(v)

    def _set_i(self, v):
        self._i = _int(v)

    def _set_d(self, v):
        self._d = _f32(v)

    # attrgetter: reading runs no Python code (a dt call reads 2.25 million distances)
    queryIdx = property(_attrgetter("_q"), _set_q)
    trainIdx = property(_attrgetter("_t"), _set_t)
    imgIdx = property(_attrgetter("_i"), _set_i)
    distance = property(_attrgetter("_d"), _set_d)
    del _set_q, _set_t, _set_i, _set_d

    def __lt__(self, other):
        return NotImplemented

    __gt__ = __le__ = __ge__ = __lt__

    def __repr__(self):
        return "< cv2.DMatch %#x>" % id(self)


class _Match(DMatch):
    """The DMatch of the host's answers: built without conversions (the values are valid)."""

    __slots__ = ()

    def __init__(self, q, t, i, d):
        self._q = q
        self._t = t
        self._i = i
        self._d = d


_Match.__name__ = _Match.__qualname__ = "DMatch"
_dmatch = _Match


# --- descriptors without numpy -------------------------------------------------------------

class _DType(str):
    """'float32', and equal to numpy's name for it."""

    @property
    def name(self):
        return str(self)


_FLOAT32 = _DType("float32")


class _NeedsNumpy:
    """Arithmetic and anything unknown on the stand-ins: a clear 'needs numpy' error."""

    __slots__ = ()

    def _nope(self, *args, **kwargs):
        raise _numpy_missing("arithmetic on descriptors (%s)" % type(self).__name__)

    __add__ = __radd__ = __sub__ = __rsub__ = __mul__ = __rmul__ = _nope
    __truediv__ = __rtruediv__ = __pow__ = __neg__ = __abs__ = __matmul__ = __rmatmul__ = _nope
    __lt__ = __le__ = __gt__ = __ge__ = _nope

    def __bool__(self):
        raise ValueError("The truth value of an array with more than one element is ambiguous. "
                         "Use a.any() or a.all()")

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        raise _numpy_missing("%s.%s (the stand-in for numpy's array has len(), indexing, "
                             "iteration, shape, dtype and tolist())" % (type(self).__name__, name))


class DescriptorRow(_NeedsNumpy):
    """One descriptor (128 float values) of a `Descriptors`, read-only."""

    __slots__ = ("_b", "_o")

    def __init__(self, data, offset):
        self._b = data
        self._o = offset

    def __len__(self):
        return 128

    @property
    def shape(self):
        return (128,)

    @property
    def ndim(self):
        return 1

    @property
    def size(self):
        return 128

    dtype = _FLOAT32

    def __getitem__(self, j):
        if isinstance(j, slice):
            return [float(v) for v in self._b[self._o:self._o + 128][j]]
        j = _index(j, 128, "descriptor")
        return float(self._b[self._o + j])

    def __iter__(self):
        return iter([float(v) for v in self._b[self._o:self._o + 128]])

    def tolist(self):
        return [float(v) for v in self._b[self._o:self._o + 128]]

    def __eq__(self, other):
        if isinstance(other, DescriptorRow):
            return self._b[self._o:self._o + 128] == other._b[other._o:other._o + 128]
        return NotImplemented

    __hash__ = None

    def __repr__(self):
        return "DescriptorRow(%s)" % self.tolist()


class Descriptors(_NeedsNumpy):
    """The stand-in for OpenCV's N x 128 float32 descriptor array when numpy is absent:
    len(), rows by index (DescriptorRow) or slice (Descriptors), des[i, j], iteration,
    shape, dtype ('float32'), tolist(); read-only. Values are whole numbers 0-255 kept as
    bytes."""

    __slots__ = ("_b", "_n")

    def __init__(self, data, n):
        self._b = bytes(data)
        self._n = n

    def __len__(self):
        return self._n

    @property
    def shape(self):
        return (self._n, 128)

    @property
    def ndim(self):
        return 2

    @property
    def size(self):
        return self._n * 128

    dtype = _FLOAT32

    def __getitem__(self, i):
        if isinstance(i, tuple):
            if len(i) == 2 and not isinstance(i[0], slice) and not isinstance(i[1], slice):
                r = _index(i[0], self._n, "row")
                return float(self._b[r * 128 + _index(i[1], 128, "column")])
            raise _numpy_missing("indexing descriptors with %r" % (i,))
        if isinstance(i, slice):
            start, stop, step = i.indices(self._n)
            if step != 1:
                rows = range(start, stop, step)
                return Descriptors(b"".join(self._b[r * 128:(r + 1) * 128] for r in rows), len(rows))
            stop = max(stop, start)
            return Descriptors(self._b[start * 128:stop * 128], stop - start)
        r = _index(i, self._n, "row")
        return DescriptorRow(self._b, r * 128)

    def __iter__(self):
        b = self._b
        return iter([DescriptorRow(b, r * 128) for r in range(self._n)])

    def tolist(self):
        b = self._b
        return [[float(v) for v in b[r * 128:(r + 1) * 128]] for r in range(self._n)]

    def copy(self):
        return Descriptors(self._b, self._n)

    def __repr__(self):
        return "Descriptors(%d x 128, float32)" % self._n


def _index(i, n, what):
    if isinstance(i, bool) or not isinstance(i, int):
        if _np is not None and isinstance(i, _np.integer):
            i = int(i)
        elif hasattr(i, "__index__"):
            i = i.__index__()
        else:
            raise TypeError("%s indices must be integers, not %s" % (what, type(i).__name__))
    if i < 0:
        i += n
    if not 0 <= i < n:
        raise IndexError("index %d is out of bounds for axis 0 with size %d" % (i, n))
    return i


def _descriptors(data, n):
    """The harness's descriptors (bytes of n x 128 whole numbers) as detectAndCompute gives
    them: None when there are none, else float32 N x 128."""
    if n == 0:
        return None
    if _np is not None:
        return _np.frombuffer(data, dtype=_np.uint8).reshape(n, 128).astype(_np.float32)
    return Descriptors(data, n)


# --- the link to the host ------------------------------------------------------------------

# Set by siftlab_harness: _host(request: dict) -> answer dict (docs/marking.md, "knn").
_host = None
# Set by siftlab_harness for the running call: [(array object, "K/1", pristine bytes), ...].
_refs = []


def _descriptor_arg(arr, name):
    """(ref or None, base64 or None, rows, kind) for knnMatch's argument; kind is 'f32' or
    'u8' (OpenCV requires both sides of one type)."""
    for obj, ref, pristine in _refs:
        if arr is obj:
            if _np is None or (isinstance(arr, _np.ndarray) and arr.dtype == _np.float32
                               and arr.shape == (len(pristine) // 128, 128)
                               and _np.array_equal(arr, _np.frombuffer(pristine, _np.uint8).reshape(-1, 128))):
                return ref, None, len(pristine) // 128, "f32"
            break  # the student changed the array in place: send what it holds now
    if isinstance(arr, Descriptors):
        return None, _base64.b64encode(arr._b).decode("ascii"), arr._n, "f32"
    if isinstance(arr, DescriptorRow):
        raise _assert_failed("type == src2.type() && src1.cols == src2.cols && (type == CV_32F || type == CV_8U)",
                             "batchDistance", "batch_distance.cpp")
    if _np is None or not isinstance(arr, _np.ndarray):
        raise _bad_argument("knnMatch", "%s is not a numpy array, neither a scalar" % name)
    if arr.dtype == _np.float32:
        kind = "f32"
    elif arr.dtype == _np.uint8:
        kind = "u8"
    else:
        kind = str(arr.dtype)
    if arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2:
        raise _bad_argument("knnMatch", "%s: a 2-D array is expected, got %d dimensions" % (name, arr.ndim))
    n, cols = arr.shape
    if n == 0:
        return None, "", 0, kind
    if kind not in ("f32", "u8") or cols != 128:
        return None, None, n, (kind, cols)
    if kind == "f32":
        ok = bool(_np.all((arr >= 0) & (arr <= 255) & (arr == _np.floor(arr))))
        if not ok:
            raise error("siftlab's knnMatch takes SIFT's descriptors, whole numbers 0-255 "
                        "(as detectAndCompute returns them); %s holds other values" % name)
    data = _np.ascontiguousarray(arr.astype(_np.uint8)).tobytes()
    return None, _base64.b64encode(data).decode("ascii"), n, kind


def _knn(query, train, k, fn="knnMatch"):
    """The host's knnMatch: per query row, the (trainIdx, distance) of up to k nearest."""
    if isinstance(k, bool) or not isinstance(k, int) and not (_np is not None and isinstance(k, _np.integer)):
        raise _bad_argument(fn, "Argument 'k' is required to be an integer")
    k = int(k)
    if query is None:
        return 0, []
    qref, qdata, nq, qkind = _descriptor_arg(query, "queryDescriptors")
    if train is None:
        if nq == 0:
            return 0, []
        raise _assert_failed("_queryDescriptors.type() == trainDescType", "knnMatchImpl")
    tref, tdata, nt, tkind = _descriptor_arg(train, "trainDescriptors")
    if k <= 0:
        raise _assert_failed("knn > 0", fn)
    if nq == 0:
        return 0, []
    if qkind != tkind or isinstance(qkind, tuple):
        if nt == 0 and not isinstance(qkind, tuple):
            raise _assert_failed("_queryDescriptors.type() == trainDescType", "knnMatchImpl")
        if qkind != tkind:
            raise _assert_failed("_queryDescriptors.type() == trainDescType", "knnMatchImpl")
        raise _assert_failed("type == src2.type() && src1.cols == src2.cols && (type == CV_32F || type == CV_8U)",
                             "batchDistance", "batch_distance.cpp")
    if nt == 0:
        return nq, [[] for _ in range(nq)]
    if _host is None:
        raise RuntimeError("siftlab's cv2: no host to run knnMatch (siftlab_harness sets cv2._host)")
    req = {"op": "knn", "q": qdata if qref is None else None, "qid": qref, "nq": nq,
           "t": tdata if tref is None else None, "tid": tref, "nt": nt, "k": k}
    ans = _host(req)
    if "error" in ans:
        raise error("siftlab's matcher: %s" % ans["error"])
    rows = _decode_answer(ans, nq)
    return nq, rows


def _decode_answer(ans, nq):
    """The host's answer: {"matches": [[[t, d], ...], ...]} -> that list of rows; the compact
    {"kk": K, "t": B64 int32, "d": B64 float32} (K per row) -> (K, trainIdxs, distances)."""
    if "matches" in ans:
        rows = ans["matches"]
    else:
        import array
        kk = int(ans["kk"])
        ti = array.array("i")
        ti.frombytes(_base64.b64decode(ans["t"]))
        dd = array.array("f")
        dd.frombytes(_base64.b64decode(ans["d"]))
        if _sys.byteorder != "little":
            ti.byteswap()
            dd.byteswap()
        if len(ti) != nq * kk or len(dd) != nq * kk:
            raise RuntimeError("siftlab's matcher answered %d values for %d x %d" % (len(ti), nq, kk))
        return kk, ti.tolist(), dd.tolist()
    if len(rows) != nq:
        raise RuntimeError("siftlab's matcher answered %d rows for %d queries" % (len(rows), nq))
    return rows


def _pairs(rows):
    """A decoded answer as [[(trainIdx, distance), ...] per query]."""
    if isinstance(rows, tuple):
        kk, tl, dl = rows
        return [list(zip(tl[q * kk:(q + 1) * kk], dl[q * kk:(q + 1) * kk])) for q in range(len(tl) // kk)] \
            if kk else []
    return rows


# --- BFMatcher -----------------------------------------------------------------------------

class BFMatcher:
    """cv2.BFMatcher(normType=NORM_L2, crossCheck=False): knnMatch and match, the k-NN work
    done by siftlab's matcher (L2; NORM_L2SQR and the others are not offered)."""

    def __init__(self, normType=NORM_L2, crossCheck=False):
        self._norm = _int(normType, "normType")
        self._cross = bool(crossCheck)
        if self._norm != NORM_L2:
            names = {NORM_INF: "NORM_INF", NORM_L1: "NORM_L1", NORM_L2SQR: "NORM_L2SQR",
                     NORM_HAMMING: "NORM_HAMMING", NORM_HAMMING2: "NORM_HAMMING2"}
            raise NotImplementedError(
                "siftlab's cv2.BFMatcher matches with NORM_L2 (the lab's, BFMatcher()'s default) "
                "only, not %s" % names.get(self._norm, self._norm))

    @staticmethod
    def create(normType=NORM_L2, crossCheck=False):
        return BFMatcher(normType, crossCheck)

    def knnMatch(self, queryDescriptors, trainDescriptors=None, k=None, mask=None, compactResult=False):
        if k is None:
            raise _bad_argument("knnMatch", "DescriptorMatcher.knnMatch() missing required argument 'k' (pos 3)")
        if mask is not None:
            raise NotImplementedError("siftlab's cv2.BFMatcher.knnMatch takes no mask")
        if self._cross:
            return self._cross_knn(queryDescriptors, trainDescriptors, k, "knnMatch")
        nq, rows = _knn(queryDescriptors, trainDescriptors, k)
        if isinstance(rows, tuple):  # the compact answer: (kk, trainIdx list, distance list)
            kk, tl, dl = rows
            return tuple([tuple(map(_Match, _repeat(q, kk), tl[q * kk:(q + 1) * kk], _repeat(0, kk),
                                    dl[q * kk:(q + 1) * kk])) for q in range(nq)])
        return tuple([tuple([_Match(q, t, 0, d) for t, d in rows[q]]) for q in range(nq)])

    def match(self, queryDescriptors, trainDescriptors=None, mask=None):
        if mask is not None:
            raise NotImplementedError("siftlab's cv2.BFMatcher.match takes no mask")
        rows = self.knnMatch(queryDescriptors, trainDescriptors, 1)
        return tuple(row[0] for row in rows if row)

    def _cross_knn(self, query, train, k, fn):
        """OpenCV's crossCheck (batchDistance): k must be 1; query i keeps its nearest train
        row j (first on ties) when i is j's nearest query (first on ties)."""
        if isinstance(k, bool) or not isinstance(k, int) and not (_np is not None and isinstance(k, _np.integer)):
            raise _bad_argument(fn, "Argument 'k' is required to be an integer")
        if int(k) != 1:
            if int(k) <= 0:
                raise _assert_failed("knn > 0", fn)
            raise _assert_failed("K == 1 && update == 0 && mask.empty()", "batchDistance", "batch_distance.cpp")
        nq, fwd = _knn(query, train, 1, fn)
        fwd = _pairs(fwd)
        if nq == 0 or not any(fwd):
            return tuple(tuple() for _ in range(nq))
        nt, back = _knn(train, query, 1, fn)
        back = _pairs(back)
        out = []
        for q in range(nq):
            t, d = fwd[q][0]
            out.append((_Match(q, t, 0, d),) if back[t] and back[t][0][0] == q else ())
        return tuple(out)

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        raise AttributeError(_missing("BFMatcher.%s" % name))

    def __repr__(self):
        return "< cv2.BFMatcher %#x>" % id(self)


def BFMatcher_create(normType=NORM_L2, crossCheck=False):
    return BFMatcher(normType, crossCheck)


# --- SIFT ----------------------------------------------------------------------------------

class Frame:
    """An image as the harness gives it: the frame's precomputed SIFT keypoints and
    descriptors (siftlab's SIFT, equal to OpenCV's), which detectAndCompute returns."""

    def __init__(self, name, keypoints, data, n, shape=(376, 1241)):
        self.name = name
        self._kps = keypoints  # [(x, y, size, angle, response, octave), ...]
        self._data = data
        self._n = n
        self.shape = shape
        self.dtype = "uint8"

    def keypoints(self):
        return tuple(_keypoint(*k) for k in self._kps)

    def descriptors(self):
        return _descriptors(self._data, self._n)

    def __repr__(self):
        return "<siftlab frame %s>" % self.name


_LAB_SIFT = (1500, 3, 0.04, 10.0, 1.6)


class SIFT:
    """cv2.SIFT as the lab's base class creates it (nfeatures=1500): detectAndCompute and
    detect on the harness's frames return siftlab's results for them."""

    def __init__(self, nfeatures=0, nOctaveLayers=3, contrastThreshold=0.04, edgeThreshold=10.0,
                 sigma=1.6, descriptorType=None, enable_precise_upscale=False):
        self._params = (_int(nfeatures, "nfeatures"), _int(nOctaveLayers, "nOctaveLayers"),
                        float(contrastThreshold), float(edgeThreshold), float(sigma))

    @staticmethod
    def create(*args, **kwargs):
        return SIFT(*args, **kwargs)

    def getNFeatures(self):
        return self._params[0]

    def _frame(self, image, fn):
        if not isinstance(image, Frame):
            raise NotImplementedError(
                "siftlab's SIFT.%s runs on the frames siftlab gives, not on %s" % (fn, type(image).__name__))
        if self._params != _LAB_SIFT:
            raise NotImplementedError(
                "siftlab's SIFT has the lab's frames' keypoints for SIFT_create(nfeatures=1500) "
                "only (this detector: nfeatures, nOctaveLayers, contrastThreshold, edgeThreshold, "
                "sigma = %r)" % (self._params,))
        return image

    def detectAndCompute(self, image, mask, descriptors=None, useProvidedKeypoints=False):
        if mask is not None:
            raise NotImplementedError("siftlab's SIFT.detectAndCompute takes no mask")
        f = self._frame(image, "detectAndCompute")
        return f.keypoints(), f.descriptors()

    def detect(self, image, mask=None):
        return self._frame(image, "detect").keypoints()

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        raise AttributeError(_missing("SIFT.%s" % name))


def SIFT_create(nfeatures=0, nOctaveLayers=3, contrastThreshold=0.04, edgeThreshold=10.0, sigma=1.6,
                *args, **kwargs):
    return SIFT(nfeatures, nOctaveLayers, contrastThreshold, edgeThreshold, sigma, *args, **kwargs)


# --- small helpers a solution may use --------------------------------------------------------

def norm(src1, src2=None, normType=NORM_L2, mask=None):
    """cv2.norm(a[, b][, normType]) on vectors: L2 (default), L1, INF, computed in double as
    OpenCV does for float32 data."""
    if mask is not None:
        raise NotImplementedError("siftlab's cv2.norm takes no mask")
    if isinstance(src2, int) and not isinstance(src2, bool) and normType == NORM_L2:
        src2, normType = None, src2
    a = [float(v) for v in _flat(src1)]
    if src2 is not None:
        b = [float(v) for v in _flat(src2)]
        if len(a) != len(b):
            raise _assert_failed("src1.size == src2.size && src1.type() == src2.type()", "norm", "norm.cpp")
        a = [x - y for x, y in zip(a, b)]
    if normType == NORM_L2:
        return _math.sqrt(sum(x * x for x in a))
    if normType == NORM_L2SQR:
        return sum(x * x for x in a)
    if normType == NORM_L1:
        return sum(abs(x) for x in a)
    if normType == NORM_INF:
        return max((abs(x) for x in a), default=0.0)
    raise NotImplementedError("siftlab's cv2.norm: normType %r is not offered" % (normType,))


def _flat(x):
    if _np is not None and isinstance(x, _np.ndarray):
        return x.ravel().tolist()
    if isinstance(x, Descriptors):
        return [v for row in x.tolist() for v in row]
    if isinstance(x, DescriptorRow):
        return x.tolist()
    out = []
    for v in x:
        if isinstance(v, (int, float)):
            out.append(v)
        else:
            out.extend(_flat(v))
    return out


def _missing(name):
    return ("siftlab's cv2 has no cv2.%s: the lab's tasks need only BFMatcher, DMatch, KeyPoint "
            "(and SIFT_create for the base class)" % name)


def __getattr__(name):
    if name.startswith("__"):
        raise AttributeError(name)
    raise AttributeError(_missing(name))
