#!/usr/bin/env python3
"""Small seeds for the image fuzz targets, cut from the bundled KITTI frames.

The frames (1241x376, ~200 KB) are too big to fuzz quickly, so this decodes
a few of them (8-bit gray PNG, Python's standard library only), cuts small
windows and re-encodes each with every PNG row filter in turn and the data
over one or several IDAT chunks. Used by tests/fuzz/run.sh.

    seed_frames.py OUT_DIR PREFIX_BYTE FRAME.png [FRAME.png ...]
"""
import struct
import sys
import zlib
from pathlib import Path


def chunks(data):
    i = 8
    while i + 8 <= len(data):
        n, kind = struct.unpack(">I4s", data[i:i + 8])
        yield kind, data[i + 8:i + 8 + n]
        i += 12 + n


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    return a if pa <= pb and pa <= pc else (b if pb <= pc else c)


def decode_gray8(data):
    hdr, idat = None, b""
    for kind, body in chunks(data):
        if kind == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
    w, h, depth, colour, _, _, interlace = hdr
    assert (depth, colour, interlace) == (8, 0, 0), "not an 8-bit gray frame"
    raw = zlib.decompress(idat)
    rows, prev = [], bytearray(w)
    for y in range(h):
        f, line = raw[y * (w + 1)], bytearray(raw[y * (w + 1) + 1:(y + 1) * (w + 1)])
        for x in range(w):
            a = line[x - 1] if x else 0
            c = prev[x - 1] if x else 0
            line[x] = (line[x] + [0, a, prev[x], (a + prev[x]) // 2, paeth(a, prev[x], c)][f]) & 255
        rows.append(line)
        prev = line
    return w, h, rows


def encode_gray8(rows, parts):
    w, h = len(rows[0]), len(rows)
    raw, prev = bytearray(), bytearray(w)
    for y, line in enumerate(rows):
        f = y % 5
        raw.append(f)
        for x in range(w):
            a = line[x - 1] if x else 0
            c = prev[x - 1] if x else 0
            raw.append((line[x] - [0, a, prev[x], (a + prev[x]) // 2, paeth(a, prev[x], c)][f]) & 255)
        prev = line
    z = zlib.compress(bytes(raw), 9)

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    out = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
    step = max(1, -(-len(z) // parts))
    for i in range(0, len(z), step):
        out += chunk(b"IDAT", z[i:i + step])
    return out + chunk(b"IEND", b"")


def main():
    out, prefix, frames = Path(sys.argv[1]), bytes([int(sys.argv[2])]), sys.argv[3:]
    out.mkdir(parents=True, exist_ok=True)
    for path in frames:
        w, h, rows = decode_gray8(Path(path).read_bytes())
        for k, (cw, ch) in enumerate([(16, 12), (40, 30), (64, 48), (1, 9), (97, 3)]):
            x0, y0 = (w // 3 + 17 * k) % (w - cw), (h // 4 + 11 * k) % (h - ch)
            crop = [r[x0:x0 + cw] for r in rows[y0:y0 + ch]]
            png = encode_gray8(crop, 1 + k % 3)
            (out / f"{Path(path).stem}-{cw}x{ch}").write_bytes(prefix + png)


if __name__ == "__main__":
    main()
