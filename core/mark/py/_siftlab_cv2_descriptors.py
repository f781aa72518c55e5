"""Part of siftlab's `cv2` (cv2.py re-exports what it defines): descriptors as
detectAndCompute gives them, and the read-only stand-in for numpy's array when this Python
has no numpy.

The harness loads it from this folder before cv2.py (siftlab_harness.py, `_load_shim`).
"""

from _siftlab_cv2_base import _np, _numpy_missing


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
