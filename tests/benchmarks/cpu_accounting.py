#!/usr/bin/env python3
"""Where a run's CPU went, by kind of process, from Linux process accounting.

Every process that ends while accounting is on leaves a record (BSD acct v3: command name,
pid, parent, start, elapsed, user and system time of all its threads), so a whole
`tests/run` can be measured without instrumenting it: short-lived compilers, sandboxed
students and browser helpers included, which `times` and /proc sampling miss.

    apt-get install acct            # accton (root)
    touch /tmp/run.acct && accton /tmp/run.acct && date +%s > /tmp/run.t0
    tests/run; accton off
    tests/benchmarks/cpu_accounting.py /tmp/run.acct --t0 $(cat /tmp/run.t0) --split 706

--split T1 T2 ... cuts the run into windows (seconds from --t0; a process counts in the
window it ended in), e.g. at the "lanes done" second of the step table. The native CLI's and
the students' Pythons' CPU is also attributed to the nearest ancestor that names a step (a
test binary, node for the e2e suites, python3 for the hostile checks).
"""
import argparse
import collections
import struct

FAMILIES = {
    "build": ("rustc", "clippy-driver", "rust-lld", "cargo", "wasm-bindgen", "wasm-opt"),
    "chromium": ("chromium", "chromedriver", "ThreadPoolForeg", "HangWatcher", "Chrome_ChildIOT",
                 "ThreadPoolServi", "ThreadPoolSingl", "PerfettoTrace", "AsyncSi~lThread"),
    "firefox": ("firefox-esr", "Isolated Web Co", "Web Content", "geckodriver", "forkserver",
                "Socket Process", "WebExtensions", "RDD Process", "Utility Process", "Privileged Cont",
                "rruptDispatcher", "DOM Worker"),
    "webkit": ("WebKitWebProces", "WebKitNetworkPr", "WebKitWebDriver", "MiniBrowser", "Xvfb"),
    "siftlab": ("siftlab", "ctrl-c"),
    "node": ("node",),
}
# Wrappers between a process and the step that started it.
WRAPPERS = {"siftlab", "ctrl-c", "bwrap", "sh", "bash", "env", "timeout", "setpriv", "ldd", "ld-linux-x86-64"}


def comp_t(c):
    """acct's comp_t: 13-bit mantissa, 3-bit base-8 exponent (clock ticks)."""
    return (c & 0x1FFF) << (3 * (c >> 13))


def read(path, hz=100):
    data = open(path, "rb").read()
    recs = []
    for off in range(0, len(data) - 63, 64):
        r = data[off:off + 64]
        if r[1] != 3:
            continue  # not an acct_v3 record
        pid, ppid, btime, etime = struct.unpack("<IIIf", r[16:32])
        ut, st = struct.unpack("<2H", r[32:36])
        comm = r[48:64].split(b"\0")[0].decode(errors="replace")
        recs.append({"pid": pid, "ppid": ppid, "start": btime, "end": btime + etime / hz,
                     "cpu": (comp_t(ut) + comp_t(st)) / hz, "comm": comm})
    return recs


def family(comm):
    if comm.startswith("python"):
        return "python"
    for name, comms in FAMILIES.items():
        if comm in comms:
            return name
    return "other"


def owner(rec, by_pid):
    """The nearest ancestor that is not a wrapper (pids are reused: the one alive then)."""
    r = rec
    for _ in range(40):
        cands = [p for p in by_pid.get(r["ppid"], []) if p["start"] <= r["start"] + 1 and p["end"] >= r["start"] - 1]
        if not cands:
            return "?"
        r = max(cands, key=lambda p: p["start"])
        if r["comm"] not in WRAPPERS and not r["comm"].startswith("python3."):
            return r["comm"]
    return "?"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("acct")
    ap.add_argument("--t0", type=float, help="the run's start (epoch seconds); default: the first record's")
    ap.add_argument("--split", type=float, nargs="*", default=[], help="window edges, seconds from t0")
    a = ap.parse_args()
    recs = read(a.acct)
    t0 = a.t0 if a.t0 is not None else min(r["start"] for r in recs)
    edges = [float("-inf")] + sorted(a.split) + [float("inf")]
    for lo, hi in zip(edges, edges[1:]):
        by = collections.Counter()
        for r in recs:
            if lo <= r["end"] - t0 < hi:
                by[family(r["comm"])] += r["cpu"]
        name = f"{'start' if lo == float('-inf') else int(lo)}-{'end' if hi == float('inf') else int(hi)} s"
        print(f"{name}: {sum(by.values()):.0f} CPU-s  " + ", ".join(f"{k} {v:.0f}" for k, v in by.most_common()))
    by_pid = collections.defaultdict(list)
    for r in recs:
        by_pid[r["pid"]].append(r)
    who = collections.Counter()
    for r in recs:
        if family(r["comm"]) in ("siftlab", "python"):
            who[(family(r["comm"]), owner(r, by_pid))] += r["cpu"]
    print("the CLI and Python by the step that started them:")
    for (fam, o), v in who.most_common(16):
        print(f"  {v:7.1f}  {fam:8s} under {o}")


if __name__ == "__main__":
    main()
