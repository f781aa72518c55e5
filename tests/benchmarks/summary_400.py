#!/usr/bin/env python3
"""Times `siftlab mark --summary` on a class of 400 students (issue: <= 1 s natively).

    tests/benchmarks/summary_400.py SIFTLAB CLASS_OUT [--students 400] [--n 25]

CLASS_OUT is a folder `siftlab mark --out` wrote. Its marked students' report.json files are
copied round-robin to 400 new ids, each report's cases repeated up to n per task (so the
reports have a class marking's size at n = 25), sealed with CLASS_OUT's key as siftlab seals
them (HMAC-SHA256 over "siftlab report v1\\0<id>\\0<report>"), with a grades.csv; then the
summary is built three times and the best and median wall times printed.
"""
import argparse
import hashlib
import hmac
import json
import os
import statistics
import subprocess
import tempfile
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("siftlab")
    ap.add_argument("class_out")
    ap.add_argument("--students", type=int, default=400)
    ap.add_argument("--n", type=int, default=25)
    a = ap.parse_args()
    key = open(os.path.join(a.class_out, ".siftlab-key"), "rb").read()
    src = []
    for sid in sorted(os.listdir(os.path.join(a.class_out, "students"))):
        p = os.path.join(a.class_out, "students", sid, "report.json")
        if os.path.exists(p):
            r = json.load(open(p))
            if r.get("status") in ("ok", "zero"):
                src.append(r)
    work = tempfile.mkdtemp(prefix="siftlab-summary-400-")
    with open(os.path.join(work, ".siftlab-key"), "wb") as f:
        f.write(key)
    os.chmod(os.path.join(work, ".siftlab-key"), 0o600)
    rows = ["student,dt,nn,nndr,matching_info,total,status,reason"]
    for i in range(a.students):
        r = dict(src[i % len(src)])
        sid = "s%04d" % i
        r["student"] = sid
        cases = r.get("cases") or []
        if cases:
            per = max(1, r.get("cases_per_task", 1))
            reps = -(-a.n // per)
            grown = []
            for rep in range(reps):
                for c in cases:
                    c = dict(c)
                    c["index"] = c["index"] + rep * per
                    grown.append(c)
            r["cases"] = [c for c in grown if c["index"] < a.n]
            r["cases_per_task"] = a.n
        body = (json.dumps(r) + "\n").encode()
        d = os.path.join(work, "students", sid)
        os.makedirs(d)
        open(os.path.join(d, "report.json"), "wb").write(body)
        tag = hmac.new(key, b"siftlab report v1\0" + sid.encode() + b"\0" + body, hashlib.sha256).hexdigest()
        open(os.path.join(d, "report.seal"), "w").write(tag + "\n")
        marks = {t["task"]: t["marks"] for t in r["tasks"]}
        rows.append("%s,%s,%.2f,%s," % (sid, ",".join("%.2f" % marks.get(t, 0) for t in
                                                     ("dt", "nn", "nndr", "matching_info")), r["total"], r["status"]))
    open(os.path.join(work, "grades.csv"), "w").write("\r\n".join(rows) + "\r\n")
    size = sum(os.path.getsize(os.path.join(dp, f)) for dp, _, fs in os.walk(work) for f in fs)
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        subprocess.run([a.siftlab, "mark", "--summary", work], check=True, capture_output=True)
        times.append(time.perf_counter() - t0)
    s = json.load(open(os.path.join(work, "summary.json")))
    print("%d students (%d unsealed skipped), %.1f MB of reports: summary in %.3f s (best), %.3f s (median of 3)"
          % (s["students"], a.students - s["totals"]["marked"], size / 1e6, min(times), statistics.median(times)))


if __name__ == "__main__":
    main()
