"""Part of siftlab's `cv2` (cv2.py re-exports what it defines): KeyPoint and DMatch,
which store float32 as OpenCV's do, and the builders of the host's values.

The harness loads it from this folder before cv2.py (siftlab_harness.py, `_load_shim`).
"""

from operator import attrgetter as _attrgetter

from _siftlab_cv2_base import _bad_argument, _f32, _int, _missing, _np, _numpy_missing


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
