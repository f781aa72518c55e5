#!/usr/bin/env python3
"""Gradescope's and PrairieLearn's contracts simulated on this machine, with the autograders
`siftlab autograder {gradescope,prairielearn}` writes (docs/marking.md, "Gradescope",
"PrairieLearn"), and the attacks a submission can make from inside them
(tests/fixtures/mark/platform/README.md).

Per case and platform, a fresh folder laid out as the platform lays out its container:

    Gradescope                                      PrairieLearn
    /autograder/source/   the bundle's files        /siftlab/          the grader image's files
    /autograder/submission/vision_tasks.py          /grade/student/vision_tasks.py
    /autograder/results/  (results.json)            /grade/results/    (results.json)

and the entrypoint (run_autograder, run_grader) runs as root in bubblewrap standing for the
container (platform_sim.py): the host's
files read-only, that folder bound at /autograder, a private /tmp and /dev, no network, its
own PID namespace, **bwrap masked** (a file of nothing at its path: Docker's default profile
forbids the namespaces it needs), so siftlab runs its container tier; in a cgroup holding it
to Gradescope's defaults, 768 MB and half a CPU (cgroup v1 memory and cpu, or v2's memory.max
and cpu.max, made under the hierarchy this process is in; root needed). After run_autograder
ends, the container lives on 2 s before its results are read (a daemon would write then).

Checks, per case: results.json is siftlab's, in the platform's format field by field
(Gradescope: score, max_score 20, output, output_format, execution_time, extra_data.sandbox
"container", four tests with name, score, max_score 5, status, output, output_format,
visibility; PrairieLearn: gradable, score in [0, 1], message, output, sandbox "container",
four tests with name, points, max_points 5, message, output; a file that does not compile is
not gradable and has format_errors), its score and each test's are the reference's (the same file marked by the host's `siftlab mark --json` in bubblewrap, where
none of the attacks can happen; 20/20 for the good solution), the bundle's files unchanged,
nothing new in /autograder/source or /autograder/results but results.json. Each attack also
runs once as a control with `--no-sandbox` in run_autograder, where it must show (a forged or
missing results.json, a changed bundle): so the check is seen to catch it. Prints each run's
peak memory (the cgroup's) and seconds.

    python3 tests/security/platform_check.py [--siftlab PATH] [-n N] [--seed S] [-j JOBS]
        [--platform gradescope|prairielearn]... [--python PATH] [--keep] [CASE...]

SIFTLAB in the environment is the default --siftlab; SIFTLAB_PYTHON (default /usr/bin/python3)
is the container's interpreter, run by the student's uid, so not one under /root. Needs Linux,
root, bubblewrap; Python 3.8+, standard library only.
"""

import argparse
import base64
import concurrent.futures
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

from platform_sim import Cgroup, container_argv

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FIXTURES = os.path.join(REPO, "tests", "fixtures", "mark")
DATASET = os.path.join(REPO, "www", "demo", "MyKITTI")
CASES = ["good", "inverted", "syntax", "platform/kill_marker", "platform/daemon_results",
         "platform/overwrite_bundle", "platform/write_results"]
# Where each platform puts the bundle, the submission and the results, and its entrypoint.
LAYOUT = {
    "gradescope": {"bundle": "autograder/source", "student": "autograder/submission",
                   "results": "autograder/results", "mounts": ["autograder"],
                   "entry": "/autograder/source/run_autograder"},
    "prairielearn": {"bundle": "siftlab", "student": "grade/student", "results": "grade/results",
                     "mounts": ["siftlab", "grade"], "entry": "/siftlab/run_grader"},
}
TASKS = ["dt", "nn", "nndr", "matching_info"]


def digest_tree(root):
    out = {}
    for d, _, files in os.walk(root):
        for f in files:
            p = os.path.join(d, f)
            if os.path.islink(p):
                out[os.path.relpath(p, root)] = "link:" + os.readlink(p)
            else:
                with open(p, "rb") as fh:
                    out[os.path.relpath(p, root)] = hashlib.sha256(fh.read()).hexdigest()
    return out


def reference(siftlab, variant, n, seed):
    """The file's marks in bubblewrap on the host: {task: marks} and the total."""
    r = subprocess.run([siftlab, "-d", DATASET, "mark", os.path.join(FIXTURES, variant, "vision_tasks.py"),
                        "-n", str(n), "--seed", str(seed), "--json"], capture_output=True, text=True, timeout=900)
    j = json.loads(r.stdout)
    return {t["task"]: round(t["marks"], 2) for t in j["tasks"]}, round(j["total"], 2)


def run_case(platform, variant, bundle, siftlab, n, seed, python, keep, control=False):
    reasons = []
    lay = LAYOUT[platform]
    base = tempfile.mkdtemp(prefix="siftlab-platform-")
    os.chmod(base, 0o755)
    src = os.path.join(base, lay["bundle"])
    shutil.copytree(bundle[platform], src, symlinks=True)
    if os.path.exists(os.path.join(src, "autograder.zip")):
        os.remove(os.path.join(src, "autograder.zip"))
    entry = os.path.join(base, lay["entry"].lstrip("/"))
    if control:
        # The control: the same run without the sandbox, where the attack must show.
        text = open(entry).read().replace(" mark /", " mark --no-sandbox /")
        open(entry, "w").write(text)
    for d in (lay["student"], lay["results"]):
        os.makedirs(os.path.join(base, d))
    shutil.copy(os.path.join(FIXTURES, variant, "vision_tasks.py"), os.path.join(base, lay["student"]))
    # The platforms' folders: root's, readable by all.
    for d, _, _ in os.walk(base):
        os.chmod(d, 0o755)
    before = digest_tree(src)
    # The platform's folders bound over the host's (read-only) on bubblewrap's own root.
    cmd = container_argv(["/bin/sh", "-c", lay["entry"] + "; echo \"entrypoint: $?\" >&2; sleep 2"],
                         binds=[(os.path.join(base, m), "/" + m) for m in lay["mounts"]],
                         setenv=[("SIFTLAB_PYTHON", python)])
    group = Cgroup("siftlab-platform-%d-%s-%s%s" % (os.getpid(), platform, variant.replace("/", "-"),
                                                   "-control" if control else ""))
    t0 = time.time()
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=1200, preexec_fn=group.join)
    finally:
        seconds = time.time() - t0
        peak = group.peak_bytes()
        group.remove()
    after = digest_tree(src)
    if after != before:
        changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
        reasons.append("the bundle changed: %s" % changed[:5])
    extra = sorted(set(os.listdir(os.path.join(base, lay["results"]))) - {"results.json"})
    if extra:
        reasons.append("new files in results/: %s" % extra)
    res_path = os.path.join(base, lay["results"], "results.json")
    got = None
    if os.path.islink(res_path) or not os.path.isfile(res_path):
        reasons.append("no results.json written by siftlab (a link or missing); stderr: %s" % r.stderr[-600:])
    else:
        try:
            got = json.load(open(res_path))
        except ValueError as e:
            reasons.append("results.json is not JSON: %s" % e)
    if got is not None:
        want_tasks, want_total = reference(siftlab, variant, n, seed)
        # A refused file's report lists no task: each is 0.
        want_tasks = want_tasks or {t: 0.0 for t in TASKS}
        if variant == "good" and want_total != 20.0:
            reasons.append("the good solution's reference is %s, not 20" % want_total)
        if platform == "gradescope":
            reasons += gradescope_fields(got, "container")
            total = got.get("score")
            tasks = {t.get("name"): t.get("score") for t in got.get("tests", [])}
        else:
            reasons += prairielearn_fields(got, variant == "syntax")
            # PrairieLearn's images: the first wrong case of each task drawn
            # (the good file: none; inverted: nndr's), a JPEG data URL, the file under 1 MB.
            reasons += prairielearn_images(got, os.path.getsize(res_path), variant)
            total = round(got.get("score", -1) * 20, 2) if isinstance(got.get("score"), float) else None
            tasks = {t.get("name"): t.get("points") for t in got.get("tests", [])}
        if total != want_total:
            reasons.append("score %s of 20, the reference %s" % (total, want_total))
        if tasks != want_tasks:
            reasons.append("tests %s, the reference %s" % (tasks, want_tasks))
        if "FORGED" in json.dumps(got):
            reasons.append("forged text in results.json")
    if not keep:
        shutil.rmtree(base, ignore_errors=True)
    name = "%s %s" % (platform, variant)
    if control:
        return {"case": name + " (control, no sandbox)", "ok": bool(reasons),
                "reasons": ["the attack did not show without the sandbox: the check cannot see it"],
                "seconds": seconds, "peak": peak, "score": got and got.get("score")}
    return {"case": name, "ok": not reasons, "reasons": reasons, "seconds": seconds, "peak": peak,
            "score": got and got.get("score")}


def prairielearn_fields(j, not_gradable):
    bad = []
    if j.get("gradable") is not (not not_gradable):
        bad.append("gradable %r" % j.get("gradable"))
    if not_gradable and not (isinstance(j.get("format_errors"), list) and j["format_errors"]):
        bad.append("no format_errors for a file that does not compile")
    score = j.get("score")
    if not isinstance(score, float) or not 0.0 <= score <= 1.0:
        bad.append("score %r not in [0, 1]" % score)
    for key in ("message", "output"):
        if not isinstance(j.get(key), str):
            bad.append("%s is %r" % (key, j.get(key)))
    if j.get("sandbox") != "container":
        bad.append("sandbox %r" % j.get("sandbox"))
    tests = j.get("tests") or []
    if [t.get("name") for t in tests] != TASKS:
        bad.append("tests named %s" % [t.get("name") for t in tests])
    for t in tests:
        for key, kind in (("points", float), ("max_points", float), ("message", str), ("output", str)):
            if not isinstance(t.get(key), kind):
                bad.append("test %s: %s is %r" % (t.get("name"), key, t.get(key)))
        if t.get("max_points") != 5.0:
            bad.append("test %s: max_points %r" % (t.get("name"), t.get("max_points")))
    return bad


def prairielearn_images(j, size, variant):
    bad = []
    if size > 1000000:
        bad.append("results.json is %d bytes, over PrairieLearn's 1 MB" % size)
    tests = j.get("tests") or []
    have = [t.get("name") for t in tests if "images" in t]
    # A picture only where a task lost marks; the good file none, inverted nndr's.
    lost = [t.get("name") for t in tests if t.get("points") != 5.0]
    if any(h not in lost for h in have):
        bad.append("pictures for %s, but only %s lost marks" % (have, lost))
    want = {"good": [], "inverted": ["nndr"]}.get(variant)
    if want is not None and have != want:
        bad.append("pictures for %s, not %s" % (have, want))
    for t in tests:
        for im in t.get("images", []):
            url = im.get("url", "") if isinstance(im, dict) else ""
            head = "data:image/jpeg;base64,"
            if not isinstance(im.get("label"), str) or not url.startswith(head):
                bad.append("test %s: image %r" % (t.get("name"), str(im)[:80]))
            elif not base64.b64decode(url[len(head):]).startswith(b"\xff\xd8\xff"):
                bad.append("test %s: the image is not a JPEG" % t.get("name"))
    return bad


def gradescope_fields(j, sandbox):
    bad = []
    def want(obj, key, kind, where):
        if not isinstance(obj.get(key), kind):
            bad.append("%s: %s is %r" % (where, key, obj.get(key)))
    for key, kind in (("score", float), ("max_score", float), ("output", str), ("output_format", str),
                      ("execution_time", float), ("tests", list), ("extra_data", dict)):
        want(j, key, kind, "results.json")
    if j.get("max_score") != 20.0:
        bad.append("max_score %r" % j.get("max_score"))
    if (j.get("extra_data") or {}).get("sandbox") != sandbox:
        bad.append("sandbox %r, not %r" % ((j.get("extra_data") or {}).get("sandbox"), sandbox))
    tests = j.get("tests") or []
    if [t.get("name") for t in tests] != TASKS:
        bad.append("tests named %s" % [t.get("name") for t in tests])
    for t in tests:
        for key, kind in (("score", float), ("max_score", float), ("status", str), ("output", str),
                          ("output_format", str), ("visibility", str)):
            want(t, key, kind, "test %s" % t.get("name"))
        if t.get("status") != ("passed" if t.get("score") == 5.0 else "failed"):
            bad.append("test %s: status %r for score %r" % (t.get("name"), t.get("status"), t.get("score")))
    return bad


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="*", default=CASES)
    ap.add_argument("--platform", dest="platforms", action="append", choices=sorted(LAYOUT),
                    help="the platforms to simulate (default: both)")
    ap.add_argument("--siftlab", default=os.environ.get("SIFTLAB") or os.path.join(REPO, "target", "release", "siftlab"))
    ap.add_argument("-n", type=int, default=1)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("-j", "--jobs", type=int, default=2)
    ap.add_argument("--python", default=os.environ.get("SIFTLAB_PYTHON", "/usr/bin/python3"))
    ap.add_argument("--keep", action="store_true")
    a = ap.parse_args()
    siftlab = os.path.abspath(a.siftlab)
    a.platforms = a.platforms or sorted(LAYOUT)
    if os.geteuid() != 0:
        print("platform_check: needs root (the platforms run the autograder as root)", file=sys.stderr)
        return 2
    bundle = {}
    for platform in LAYOUT:
        bundle[platform] = tempfile.mkdtemp(prefix="siftlab-platform-bundle-")
        shutil.rmtree(bundle[platform])
        subprocess.run([siftlab, "-d", DATASET, "autograder", platform, "--out", bundle[platform],
                        "--seed", str(a.seed), "-n", str(a.n)], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
    runs = [(p, c, False) for p in a.platforms for c in a.cases]
    # The attacks' controls, once each, on Gradescope.
    runs += [("gradescope", c, True) for c in a.cases if c.startswith("platform/")]
    try:
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
            results = list(pool.map(
                lambda r: run_case(r[0], r[1], bundle, siftlab, a.n, a.seed, a.python, a.keep, r[2]), runs))
    finally:
        for b in bundle.values():
            shutil.rmtree(b, ignore_errors=True)
    for r in results:
        print("%s %-45s score %-6s %5.1f s, peak %4d MB%s" % (
            "PASS" if r["ok"] else "FAIL", r["case"], r["score"], r["seconds"], r["peak"] >> 20,
            "" if r["ok"] else ": " + "; ".join(r["reasons"])))
    failed = sum(not r["ok"] for r in results)
    print("%d fixture(s): %d passed, %d failed" % (len(results), len(results) - failed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
