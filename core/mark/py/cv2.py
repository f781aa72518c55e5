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

This file holds the link to the host, BFMatcher, SIFT and norm. Its parts beside it hold the
rest, and their classes and functions are cv2's: `_siftlab_cv2_base.py` (numpy, OpenCV's
errors and conversions), `_siftlab_cv2_types.py` (KeyPoint, DMatch) and
`_siftlab_cv2_descriptors.py` (descriptors, and their stand-in without numpy). The harness
loads them first, from this folder.
"""

import base64 as _base64
import math as _math
from itertools import repeat as _repeat
import sys as _sys

from _siftlab_cv2_base import (_IN_BROWSER, _PACK_F, NumpyMissing, _assert_failed, _bad_argument, _f32,
                               _int, _missing, _np, _numpy_missing, error)
from _siftlab_cv2_types import DMatch, KeyPoint, KeyPoint_convert, _dmatch, _keypoint, _Match
from _siftlab_cv2_descriptors import (_FLOAT32, DescriptorRow, Descriptors, _descriptors, _DType, _index,
                                      _NeedsNumpy)

# What the parts define is cv2's, as OpenCV's is: `<class 'cv2.KeyPoint'>`, and `cv2.error: ...`
# as a traceback's last line (a marking's error message).
for _o in (error, NumpyMissing, _numpy_missing, _f32, _int, _bad_argument, _assert_failed, _missing,
           KeyPoint, _keypoint, KeyPoint_convert, DMatch, _Match, _DType, _NeedsNumpy, DescriptorRow,
           Descriptors, _index, _descriptors):
    _o.__module__ = __name__
del _o

__version__ = "4.8.0"

NORM_INF = 1
NORM_L1 = 2
NORM_L2 = 4
NORM_L2SQR = 5
NORM_HAMMING = 6
NORM_HAMMING2 = 7


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


def __getattr__(name):
    if name.startswith("__"):
        raise AttributeError(name)
    raise AttributeError(_missing(name))
