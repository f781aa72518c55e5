"""The reference marker's SIFT per frame, cached on disk across runs and worker restarts."""

import os


class SiftCache:
    """lab_reference's SIFT per frame, kept in memory and in $TMPDIR/siftlab-mark-sift (one
    .npz per frame, named by the PNG's SHA-1: a changed file is computed again). KeyPoints
    come back through cv2.KeyPoint(x, y, size, angle, response, octave), exact: the values
    are float32 both ways."""

    def __init__(self, lab, cv2, np):
        import tempfile
        self.lab, self.cv2, self.np = lab, cv2, np
        self.dir = os.path.join(tempfile.gettempdir(), "siftlab-mark-sift")
        os.makedirs(self.dir, exist_ok=True)
        self.mem = {}

    def key(self, path):
        """The PNG's SHA-1 (20 hex digits)."""
        if ("key", path) not in self.mem:
            import hashlib
            with open(path, "rb") as fh:
                self.mem[("key", path)] = hashlib.sha1(fh.read()).hexdigest()[:20]
        return self.mem[("key", path)]

    def get(self, path):
        if path in self.mem:
            return self.mem[path]
        np, cv2 = self.np, self.cv2
        file = os.path.join(self.dir, self.key(path) + ".npz")
        if os.path.exists(file):
            z = np.load(file)
            kv, oc, des = z["kv"], z["oc"], z["des"]
            kps = tuple(cv2.KeyPoint(float(x), float(y), float(s), float(a), float(r), int(o))
                        for (x, y, s, a, r), o in zip(kv.tolist(), oc.tolist()))
            res = (kps, des if len(kps) else None)
        else:
            kps, des = self.lab.sift_frame(path)
            kv = np.array([(k.pt[0], k.pt[1], k.size, k.angle, k.response) for k in kps],
                          np.float32).reshape(-1, 5)
            oc = np.array([k.octave for k in kps], np.int32)
            tmp = file + ".%d.tmp.npz" % os.getpid()
            np.savez(tmp, kv=kv, oc=oc, des=des if des is not None else np.zeros((0, 128), np.float32))
            os.replace(tmp, file)
            res = (kps, des)
        self.mem[path] = res
        return res
