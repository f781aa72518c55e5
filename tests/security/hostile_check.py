#!/usr/bin/env python3
"""Marks each hostile student file (tests/fixtures/mark/hostile/NAME/vision_tasks.py) with
`siftlab mark` and checks that the marker held (tests/fixtures/mark/hostile/README.md).

Per fixture, in a fresh class folder under the system's temporary directory:

    ROOT/student_a/vision_tasks.py       the hostile file (what is marked)
    ROOT/other_student/vision_tasks.py   a copy of tests/fixtures/mark/good/ (must not change)
    ROOT/siftlab-canary-secret.txt       a random token (SIFTLAB_CANARY_FILE names it)

the marker runs as `SIFTLAB -d DATASET mark student_a/vision_tasks.py -n N --seed S --json
[--no-sandbox]` (cwd ROOT, its own session), with SIFTLAB_CANARY_FILE, SIFTLAB_CANARY_ENV (a
second random token) and SIFTLAB_CANARY_PORT (a TCP listener of this script's, which also
listens on 47011 when that port is free) in its environment, and TMPDIR set to a scratch folder
of its own (where the marker makes its marking folder). The script also plants a decoy marking
folder, /tmp/siftlab-mark-0-hostilecheck-*/ with siftlab_harness.py and cv2.py, and a canary
/tmp/siftlab-canary-*.txt (both under fresh random names). Then it checks:

- the marker exited with 0 or 1 before --timeout (default 600 s; a marker stopped with
  SIGSTOP for 10 s is killed and fails at once);
- stdout is one JSON report with a numeric "total", and the total is at most the fixture's
  maximum (the "Max" column of the README's table);
- neither canary token is in stdout or stderr; no connection reached the listeners;
- stdout and stderr hold no control character but newline and tab (no ESC, CR, BEL...),
  no C1 control and no bidirectional or invisible formatting character; nor do the strings
  of the JSON report once decoded;
- no process the marking started is alive ~1 s after the marker ended (this script makes
  itself a child subreaper, so an escaped daemon comes back to it; also any new process
  whose command line names the harness, the class folder or the fixture's sleeper, or
  whose environment holds the canary token). They are then killed;
- nothing in the class folder changed (a new file beside the submission, the other
  student's file rewritten...), the decoy is intact, no file of the fixtures' litter
  (siftlab_pwned*) new or modified at the top of /tmp or of the account's home, and the
  scratch folder is empty again (the marker's own siftlab-mark-<pid>-* folder is gone).
  Only what this check made, and the fixtures' own litter, is watched: what else runs on
  the machine and writes /tmp cannot fail it;
- with --tier T, the marker also writes Gradescope's results.json (`--gradescope`, in a
  fresh folder of root's, alone there) and its sandbox (extra_data.sandbox) must be T: a
  fixture marked by another tier fails.

Prints one PASS/FAIL line per fixture with the reasons, then a summary; exit status 1 when
any fixture fails (2: nothing to run).

    python3 tests/security/hostile_check.py [NAME...] [--only NAME] [--siftlab PATH]
        [--dataset DIR] [-n N] [--seed 0] [--timeout 600] [--no-sandbox] [--tier T] [--keep]
        [-v] [-j JOBS] [--in-platform [--no-controls]]

Each fixture runs at the smallest n that shows its attack (CALLS in hostile_fixtures.py: 1
call per task, 2 for leak_secrets, whose matching_info leaks one way on odd calls and another
on even ones); -n N runs every fixture at N instead.

--in-platform runs each fixture's check inside a simulated Gradescope container of its own
(hostile_platform.py: root, no network, bwrap masked, so siftlab runs its container tier;
768 MB and one CPU each), with --tier container, then the controls (outlive, network,
write_files, leak_secrets again with --no-sandbox: each must fail for its attack). Needs root
and bubblewrap.

As a module: `hostile_check.check(name, **options) -> dict` (keys name, ok, reasons, total,
max, exit, seconds, stdout, stderr, root), `fixtures()`, `max_marks()`. check() makes the
calling process a child subreaper and kills what the marking left running, including new
children adopted by that process: run one check at a time per process. SIFTLAB in the
environment is the default --siftlab. Needs Linux (/proc) and Python 3.8+, standard library
only. Files the fixtures leave that are recognisably theirs (siftlab_pwned_* in /tmp and the
home folders) are removed after they are reported. The fixtures' table and the report's
checks are in hostile_fixtures.py, the watchers (processes, files, listeners) in
hostile_watch.py.
"""

import argparse
import json
import os
import pwd
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

# Its modules beside it, however it is loaded (a script, an import, a file path).
if os.path.dirname(os.path.abspath(__file__)) not in sys.path:
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import hostile_watch as watch  # noqa: E402
from hostile_fixtures import (CALLS, DEFAULT_DATASET, DEFAULT_SIFTLAB, GOOD, HOSTILE, README, REPO,  # noqa: E402
                              fixtures, line, max_marks, report_reasons, safe, tier_reasons)

__all__ = ["check", "fixtures", "max_marks", "line", "main"]

FIXED_PORT = 47011  # the port a fixture tries when SIFTLAB_CANARY_PORT is not in its environment
TMP = "/tmp"
STOP_LIMIT = 10.0  # seconds a stopped marker is waited for before it is killed
OUTPUT_CAP = 64 << 20  # bytes of the marker's stdout / stderr kept


def _pump(stream, buf):
    while True:
        chunk = stream.read1(1 << 16) if hasattr(stream, "read1") else stream.read(1 << 16)
        if not chunk:
            break
        if len(buf) < OUTPUT_CAP:
            buf.extend(chunk[:OUTPUT_CAP - len(buf)])


def _kill_group(proc):
    for sig in (signal.SIGKILL, signal.SIGCONT):
        for kill in (os.killpg, os.kill):
            try:
                kill(proc.pid, sig)
            except OSError:
                pass
    proc.wait()


def _plant(name, source):
    """The class folder, the canaries, the decoy and the marker's TMPDIR: a dict of paths."""
    c = {"root": tempfile.mkdtemp(prefix="siftlab-hostile-%s-" % name)}
    c["student"] = os.path.join(c["root"], "student_a", "vision_tasks.py")
    other = os.path.join(c["root"], "other_student", "vision_tasks.py")
    for path, src in ((c["student"], source), (other, GOOD)):
        os.makedirs(os.path.dirname(path))
        shutil.copyfile(src, path)
    c["file_token"], c["env_token"] = secrets.token_hex(16), secrets.token_hex(16)
    c["canary"] = os.path.join(c["root"], "siftlab-canary-secret.txt")
    with open(c["canary"], "w") as f:
        f.write(c["file_token"] + "\n")
    # A canary in the host's /tmp (leak_secrets looks for /tmp/siftlab-canary-*.txt) and a decoy
    # marking folder there (outlive's daemon edits /tmp/siftlab-* folders): fresh random names,
    # so that concurrent checks and other programs never meet them.
    fd, c["tmp_canary"] = tempfile.mkstemp(prefix="siftlab-canary-", suffix=".txt", dir=TMP)
    with os.fdopen(fd, "w") as f:
        f.write(c["file_token"] + "\n")
    c["decoy"] = tempfile.mkdtemp(prefix="siftlab-mark-0-hostilecheck-", dir=TMP)
    # The marker's TMPDIR: its marking folder goes here, and must be gone at the end.
    c["scratch"] = tempfile.mkdtemp(prefix="siftlab-hostile-tmp-%s-" % name)
    # The decoy holds what a real marking folder holds: the harness files (core/mark/py/).
    py = os.path.join(REPO, "core", "mark", "py")
    for fname in sorted(f for f in os.listdir(py) if f.endswith(".py")):
        shutil.copyfile(os.path.join(py, fname), os.path.join(c["decoy"], fname))
    c["decoy_tree"] = _digests(c["decoy"])
    c["hashes"] = {c["student"]: watch.sha(c["student"]), other: watch.sha(other)}
    return c


def _digests(folder):
    return {r: watch.sha(os.path.join(folder, r)) for r in watch.tree(folder)}


def _run(cmd, cwd, env, timeout):
    """Runs the marker in its own session until it ends, is stopped for STOP_LIMIT s or runs
    over timeout (then killed). Returns (proc, stdout, stderr, seen, killed, seconds): seen
    holds (pid, starttime) of its descendants as polled."""
    out, err = bytearray(), bytearray()
    t0 = time.time()
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True)
    try:
        pumps = [threading.Thread(target=_pump, args=(proc.stdout, out), daemon=True),
                 threading.Thread(target=_pump, args=(proc.stderr, err), daemon=True)]
        for t in pumps:
            t.start()
        seen, stopped_since, killed = set(), None, None
        while proc.poll() is None:
            now = time.time()
            procs = watch.processes()
            for pid in watch.descendants(procs, proc.pid):
                seen.add((pid, procs[pid][0]))
            if watch.state(proc.pid) == "T":
                stopped_since = stopped_since or now
                if now - stopped_since >= STOP_LIMIT:
                    killed = "the marker was stopped (SIGSTOP) for %.0f s: killed" % STOP_LIMIT
            else:
                stopped_since = None
            if now - t0 > timeout:
                killed = "the marker ran over %.0f s: killed" % timeout
            if killed:
                _kill_group(proc)
                break
            time.sleep(0.25)
        seconds = time.time() - t0
        for t in pumps:
            t.join(3)  # a leftover child may hold the pipes open: do not wait for it
    finally:
        # Also after an interruption: the marker's group.
        if proc.poll() is None:
            _kill_group(proc)
    return proc, bytes(out).decode("utf-8", "replace"), bytes(err).decode("utf-8", "replace"), seen, killed, seconds


def _homes():
    homes = []
    for h in (pwd.getpwuid(os.getuid()).pw_dir, os.environ.get("HOME")):
        if h and os.path.isdir(h) and os.path.realpath(h) not in [os.path.realpath(x) for x in homes]:
            homes.append(h)
    return homes


def _file_reasons(c, before, litter):
    """What the marking changed: the class folder, the decoy, /tmp's and the homes' litter (its
    paths added to `litter`), the marker's TMPDIR."""
    reasons, root = [], c["root"]
    changes = watch.changed(before["tree"], watch.tree(root))
    if changes:
        reasons.append("class folder changed: %s" % ", ".join("%s (%s)" % x for x in changes[:6]))
    for path, digest in c["hashes"].items():
        if watch.sha(path) != digest:
            reasons.append("%s is not byte-identical any more" % os.path.relpath(path, root))
    after_decoy = _digests(c["decoy"])
    edited = sorted(r for r in set(after_decoy) | set(c["decoy_tree"]) if after_decoy.get(r) != c["decoy_tree"].get(r))
    if edited:
        reasons.append("the decoy marking folder %s was edited: %s" % (c["decoy"], ", ".join(edited)))
    tmp_changes = watch.changed(before["tmp"], watch.litter(TMP))
    tmp_bad = ["%s (%s)" % x for x in tmp_changes]
    litter += [os.path.join(TMP, n) for n, _ in tmp_changes]
    left = sorted(watch.tree(c["scratch"], depth=0))
    if left:
        tmp_bad.append("the marker's TMPDIR still holds %s" % ", ".join(left[:3]))
    if tmp_bad:
        reasons.append("/tmp: %s" % ", ".join(tmp_bad[:6]))
    for home, before_home in before["homes"].items():
        home_bad = watch.changed(before_home, watch.litter(home))
        if home_bad:
            reasons.append("%s: %s" % (home, ", ".join("%s (%s)" % x for x in home_bad[:6])))
            litter += [os.path.join(home, n) for n, _ in home_bad]
    return reasons


def _remove(paths):
    for path in paths:
        if os.path.isdir(path) and not os.path.islink(path):
            shutil.rmtree(path, ignore_errors=True)
        else:
            try:
                os.unlink(path)
            except OSError:
                pass


def check(name, siftlab=None, dataset=None, n=None, seed=0, no_sandbox=False, timeout=600.0, keep=False,
          max_total=None, log=None, tier=None):
    """Marks fixture `name` and checks the marker held (with `tier`, that it ran in that
    sandbox). Returns {"name", "ok", "reasons", "total", "max", "exit", "seconds", "stdout",
    "stderr", "root"}."""
    siftlab = os.path.abspath(siftlab or DEFAULT_SIFTLAB)
    dataset = os.path.abspath(dataset or DEFAULT_DATASET)
    source = os.path.join(HOSTILE, name, "vision_tasks.py")
    limit = max_marks().get(name) if max_total is None else max_total
    result = {"name": name, "ok": False, "reasons": [], "total": None, "max": limit, "exit": None,
              "seconds": None, "stdout": "", "stderr": "", "root": None}
    reasons = result["reasons"]
    if not os.path.isfile(source):
        reasons.append("no fixture %s" % source)
        return result
    if not os.access(siftlab, os.X_OK):
        reasons.append("no siftlab at %s (build it, or give --siftlab / SIFTLAB)" % siftlab)
        return result
    if limit is None:
        reasons.append("no maximum for %s in %s" % (name, README))
    subreaper = watch.become_subreaper()

    c = _plant(name, source)
    result["root"] = c["root"]
    listeners = [watch.Listener(0)]
    try:
        listeners.append(watch.Listener(FIXED_PORT))
    except OSError:
        pass  # in use: the fixtures' fallback port is not watched this time
    env = dict(os.environ)
    env.update(SIFTLAB_CANARY_FILE=c["canary"], SIFTLAB_CANARY_ENV=c["env_token"],
               SIFTLAB_CANARY_PORT=str(listeners[0].port), TMPDIR=c["scratch"])
    if n is None:
        n = CALLS.get(name, 1)
    result["n"] = n
    cmd = [siftlab, "-d", dataset, "mark", os.path.join("student_a", "vision_tasks.py"), "-n", str(n),
           "--seed", str(seed), "--json"]
    if no_sandbox:
        cmd.append("--no-sandbox")
    # The tier is named in Gradescope's results.json, written in a folder of root's (0755).
    results = tempfile.mkdtemp(prefix="siftlab-hostile-results-%s-" % name) if tier else None
    if results:
        os.chmod(results, 0o755)
        cmd += ["--gradescope", os.path.join(results, "results.json")]

    litter = []
    try:
        homes = _homes()
        before_procs = watch.processes()
        before = {"tree": watch.tree(c["root"]), "tmp": watch.litter(TMP),
                  "homes": {h: watch.litter(h) for h in homes}}
        proc, stdout, stderr, seen, killed, seconds = _run(cmd, c["root"], env, timeout)
        result.update(exit=proc.returncode, seconds=round(seconds, 1), stdout=stdout, stderr=stderr)
        if killed:
            reasons.append(killed)

        time.sleep(1.0)  # what the marking left running has had time to show itself

        left = watch.leftovers(before_procs, seen, c["root"], c["env_token"], subreaper)
        if left:
            shown = sorted(left.items())[:3]
            reasons.append("%d process(es) outlived the marker: %s%s" % (
                len(left), "; ".join("%d [%s] %s" % (p, s, safe(cl[:80])) for p, (s, cl) in shown),
                " ..." if len(left) > 3 else ""))
            watch.kill_and_reap(list(left))

        reasons += _file_reasons(c, before, litter)

        # Secrets, network.
        for label, token in (("canary file", c["file_token"]), ("canary environment variable", c["env_token"])):
            where = [s for s, text in (("stdout", stdout), ("stderr", stderr)) if token in text]
            if where:
                reasons.append("the %s's token is in the marker's %s" % (label, " and ".join(where)))
        connections = sum(lst.count for lst in listeners)
        if connections:
            reasons.append("%d connection(s) reached the canary listener (%s)" % (
                connections, ", ".join("127.0.0.1:%d" % lst.port for lst in listeners if lst.count)))

        reasons += report_reasons(stdout, stderr, limit, result)
        if results:
            reasons += tier_reasons(results, tier)
        if not killed and proc.returncode not in (0, 1):
            reasons.append("the marker exited with %s (0 or 1 expected)%s" % (
                proc.returncode if proc.returncode >= 0 else "signal %d" % -proc.returncode,
                ": " + safe(stderr.strip().splitlines()[-1][:160]) if stderr.strip() else ""))
    finally:
        # Clean up, also after an interruption: our listeners, the decoy, the canary in /tmp,
        # the litter the fixtures are known to leave.
        for lst in listeners:
            lst.close()
        _remove(litter + [c["decoy"], c["scratch"], c["tmp_canary"]] + ([results] if results else []))
        if not keep:
            shutil.rmtree(c["root"], ignore_errors=True)
    result["ok"] = not reasons
    if log:
        log(result)
    return result


def _check_one(job):
    name, options = job
    return check(name, **options)


def _print(r, a):
    print(line(r), flush=True)
    _extras(r, a)


def _extras(r, a):
    if a.keep:
        print("     class folder: %s" % r["root"], flush=True)
    if a.verbose and not r["ok"] and r["stderr"].strip():
        tail = r["stderr"].strip().splitlines()[-8:]
        print("     stderr: " + "\n             ".join(safe(t)[:200] for t in tail), flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", help="fixtures to run (default: all)")
    ap.add_argument("--only", action="append", default=[], metavar="NAME", help="a fixture to run (repeatable)")
    ap.add_argument("--siftlab", default=DEFAULT_SIFTLAB, help="the siftlab binary (default: $SIFTLAB or %(default)s)")
    ap.add_argument("--dataset", default=DEFAULT_DATASET, help="default: %(default)s")
    ap.add_argument("-n", type=int, default=None,
                    help="calls per task for every fixture (default: each fixture's own, CALLS)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds before the marker is killed (a failure)")
    ap.add_argument("--no-sandbox", action="store_true", help="pass --no-sandbox to siftlab mark")
    ap.add_argument("--tier", help="the sandbox the marker must name (bubblewrap, container): read from the "
                    "Gradescope results.json it then also writes")
    ap.add_argument("--keep", action="store_true", help="keep each class folder (its path is printed)")
    ap.add_argument("-v", "--verbose", action="store_true", help="print the end of the marker's stderr on failure")
    ap.add_argument("-j", "--jobs", type=int, default=1,
                    help="fixtures checked at once, each in a process of its own (default: %(default)s)")
    ap.add_argument("--in-platform", action="store_true",
                    help="each fixture inside a simulated Gradescope container (hostile_platform.py)")
    ap.add_argument("--no-controls", action="store_true", help="with --in-platform: no control runs")
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    known = fixtures()
    names = a.names + a.only or known
    unknown = [x for x in names if x not in known]
    if unknown or not names:
        print("unknown fixture(s): %s (known: %s)" % (", ".join(unknown), ", ".join(known)), file=sys.stderr)
        return 2
    options = dict(siftlab=a.siftlab, dataset=a.dataset, n=a.n, seed=a.seed, no_sandbox=a.no_sandbox,
                   timeout=a.timeout, keep=a.keep, tier=a.tier)
    if a.in_platform:
        import hostile_platform
        return hostile_platform.main(names, options, a.jobs, not a.no_controls, lambda r: _extras(r, a))
    if a.inside:
        # One check in a simulated container (hostile_platform.py): its result as one line.
        from hostile_platform import RESULT
        r = check(names[0], **options)
        r.update(stdout=r["stdout"][:2000], stderr=r["stderr"][-4000:])
        print(RESULT + json.dumps(r), flush=True)
        return 0
    results = []
    # Several at once: each check runs in a worker process of its own, which becomes the
    # subreaper of what its marking leaves; what each watches is its own (a fresh class
    # folder, scratch TMPDIR, canary tokens and listener), so two never see each other's.
    if a.jobs > 1:
        import multiprocessing
        pool = multiprocessing.get_context("fork").Pool(a.jobs, maxtasksperchild=1)
        done = pool.imap(_check_one, [(name, options) for name in names])
    else:
        done = (check(name, **options) for name in names)
    for r in done:
        results.append(r)
        _print(r, a)
    if a.jobs > 1:
        pool.close()
        pool.join()
    failed = [r["name"] for r in results if not r["ok"]]
    print("%d fixture(s): %d passed, %d failed%s" % (
        len(results), len(results) - len(failed), len(failed), (": " + ", ".join(failed)) if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
