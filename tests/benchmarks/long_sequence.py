#!/usr/bin/env python3
"""A long MyKITTI-layout sequence made of the bundled demo frames (issue 44's measurements).

    python3 tests/benchmarks/long_sequence.py OUT_DIR [N=4541]

Writes OUT_DIR/gray/00/image_0/000000.png … (N frames), OUT_DIR/poses/00.txt (N lines) and
OUT_DIR/README.md (the demo's licence and attribution, which must travel with its frames).
The demo has frames 0–150 (www/demo/MyKITTI); frame k of the long sequence is demo frame
f(k), driving there and back without repeating the turning frame:
    0, 1, …, 150, 149, …, 1, 0, 1, …      (period 300)
and pose line k is the demo's poses line f(k), so the ground truth drives the same way.
Each frame is a HARD LINK to its demo frame (no disk space; Chromium's folder upload does
not follow symbolic links), a copy when OUT_DIR is on another filesystem.
Idempotent: a complete folder is left as it is; frames past N-1 left by a longer run are
removed. Python 3 only, no dependencies.
"""
from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DEMO = ROOT / "www" / "demo" / "MyKITTI"
DEMO_LAST = 150
PERIOD = 2 * DEMO_LAST


def demo_frame(k: int) -> int:
    """The demo frame shown as frame k: 0 … 150 … 1, 0 … (ping-pong, no repeated turn)."""
    m = k % PERIOD
    return m if m <= DEMO_LAST else PERIOD - m


def frame_name(i: int) -> str:
    return f"{i:06d}.png"


def same_file(a: Path, b: Path) -> bool:
    try:
        sa, sb = a.stat(), b.stat()
    except FileNotFoundError:
        return False
    if (sa.st_dev, sa.st_ino) == (sb.st_dev, sb.st_ino):
        return True
    # A copy (across filesystems): same size and bytes.
    return sa.st_size == sb.st_size and a.read_bytes() == b.read_bytes()


def build(out: Path, n: int) -> str:
    if n < 2:
        raise SystemExit("N must be at least 2")
    src_dir = DEMO / "gray" / "00" / "image_0"
    demo_poses = (DEMO / "poses" / "00.txt").read_text().splitlines()
    assert len(demo_poses) > DEMO_LAST, "the demo's poses/00.txt is short"
    for i in range(DEMO_LAST + 1):
        assert (src_dir / frame_name(i)).is_file(), f"demo frame {i} missing"
    img = out / "gray" / "00" / "image_0"
    img.mkdir(parents=True, exist_ok=True)
    (out / "poses").mkdir(parents=True, exist_ok=True)

    made = linked = copied = 0
    for k in range(n):
        src = src_dir / frame_name(demo_frame(k))
        dst = img / frame_name(k)
        if dst.exists() or dst.is_symlink():
            if not dst.is_symlink() and same_file(src, dst):
                continue
            dst.unlink()
        try:
            os.link(src, dst)
            linked += 1
        except OSError:
            shutil.copyfile(src, dst)
            copied += 1
        made += 1
    # Frames past N-1 (a longer earlier run) would make the folder longer than asked.
    removed = 0
    for f in img.iterdir():
        stem = f.name[:-4] if f.name.endswith(".png") else ""
        if not (stem.isdigit() and len(stem) == 6 and int(stem) < n):
            f.unlink()
            removed += 1

    poses = "".join(demo_poses[demo_frame(k)] + "\n" for k in range(n))
    poses_file = out / "poses" / "00.txt"
    poses_new = not poses_file.is_file() or poses_file.read_text() != poses
    if poses_new:
        poses_file.write_text(poses)
    readme = out / "README.md"
    readme_src = (DEMO / "README.md").read_bytes()
    readme_new = not readme.is_file() or readme.read_bytes() != readme_src
    if readme_new:
        readme.write_bytes(readme_src)

    if made == 0 and removed == 0 and not poses_new and not readme_new:
        return f"{out}: complete ({n} frames), nothing to do"
    return (f"{out}: {n} frames (frames 0–{n - 1}, demo 0–{DEMO_LAST} there and back): "
            f"{linked} hard-linked, {copied} copied, {n - made} already there, {removed} removed; "
            f"poses/00.txt {'written' if poses_new else 'unchanged'}, README.md {'written' if readme_new else 'unchanged'}")


def main() -> None:
    if len(sys.argv) not in (2, 3) or sys.argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        raise SystemExit(0 if len(sys.argv) > 1 and sys.argv[1] in ("-h", "--help") else 2)
    n = int(sys.argv[2]) if len(sys.argv) == 3 else 4541
    print(build(Path(sys.argv[1]), n))


if __name__ == "__main__":
    main()
