"""`hostile_check.py --in-platform`: each hostile fixture checked through siftlab's container
tier inside a simulated course-platform container (platform_sim.py), as Gradescope and
PrairieLearn would run it (docs/marking.md, "Tiers"; docs/testing.md).

Per fixture, one simulated container of its own, as a platform gives each submission one:
root, the host read-only (this repository, the siftlab binary and the dataset bound read-only
at their own paths, so a clone or a build under /tmp stays visible), no network but its own
loopback, its own PID namespace, bwrap masked (so every `siftlab mark` in it runs the
container tier: nothing forces it, SIFTLAB_SANDBOX is unset), /sys read-only (siftlab makes
no cgroup of its own there, as in a container), and as /tmp a fresh folder of the host's
(1777, as a container's /tmp) for the check's class folder, decoy, canaries and the marker's
folders. In it `hostile_check.py --inside NAME --tier container` runs that fixture's whole
check (hostile_check.check): the processes left are looked for inside the container's PID
namespace before it ends (the check is the namespace's init, so an escaped daemon is
reparented to it; and its CPU time, its children's waited for, reaches its caller's), the
listeners are on its loopback, the litter in its /tmp; the marker also writes Gradescope's results.json, whose
sandbox must be "container". After it, the host checks that the container's /tmp is empty
again (all the check made is removed; what the student's uid left there, siftlab removes).

Limits: a cgroup per container of 768 MB (MEMORY, Gradescope's default; with --jobs J at most
J x 768 MB at once; the student's processes are the OOM killer's first pick, as siftlab sets
them) and one CPU (CPU: cpu.cfs_quota_us = cpu.cfs_period_us). Not Gradescope's half a CPU:
with it the run took 317 s instead of 278 s, for nothing the check needs (the CPU-bound
fixtures only wait longer). Not none: on the host siftlab's own cgroup holds a sandbox to one
core, in a container it has none, so without a quota cpu_farm's 48 chains would take every
core, the end-to-end suites' beside it too. Prints each container's
seconds, its CPU seconds and peak memory (its cgroup's: whatever ran in it, reaped or not;
page cache included) and the processes the kernel's OOM killer ended in it.

Then the controls (hostile_fixtures.CONTROLS: outlive, network, write_files, leak_secrets),
each fixture marked again in a container of its own with --no-sandbox (siftlab's tier
"none"): each must fail, for its attack's reason (a process outlived the marker, a connection
reached the listener, the class folder changed, a canary token in the report) and for the
tier, so that the check inside the simulation is seen to catch what it looks for. Only these
four run unsandboxed, and only inside the container: nothing of theirs reaches the host.

Needs Linux, root, bubblewrap and a cgroup hierarchy this process may write; Python 3.8+,
standard library only.
"""

import concurrent.futures
import json
import os
import subprocess
import sys
import tempfile
import time

from hostile_fixtures import CONTROLS, REPO, line, safe, slow_first
from platform_sim import MEMORY, Cgroup, container_argv

HERE = os.path.dirname(os.path.abspath(__file__))
CPU = 1.0  # CPUs per container (None: no quota)
PRIVATE = ("/tmp", "/dev", "/proc", "/run", "/var/tmp")  # the container's own, not the host's
RESULT = "hostile-check-result: "  # how `hostile_check.py --inside` prints its one result


def _inside_args(name, options, control):
    args = [sys.executable, os.path.join(HERE, "hostile_check.py"), "--inside", name, "--tier", "container",
            "--siftlab", options["siftlab"], "--dataset", options["dataset"], "--seed", str(options["seed"]),
            "--timeout", str(options["timeout"])]
    if options.get("n"):
        args += ["-n", str(options["n"])]
    if control or options.get("no_sandbox"):
        args.append("--no-sandbox")
    if options.get("keep"):
        args.append("--keep")
    return args


def _shown(paths):
    """The paths the container must see that are the host's: read-only at the same path."""
    out = []
    for p in sorted({os.path.realpath(x) for x in paths}):
        if not any(p.startswith(q + os.sep) for q in out):
            out.append(p)
    return out


def run(name, options, control=False):
    """One fixture's check in a simulated container of its own: the check's result, with the
    container's seconds, peak memory and OOM kills."""
    options = dict(options, siftlab=os.path.abspath(options["siftlab"]), dataset=os.path.abspath(options["dataset"]))
    shown = _shown([REPO, options["siftlab"], options["dataset"], sys.prefix, sys.base_prefix])
    tmp = tempfile.mkdtemp(prefix="siftlab-hostile-sim-%s-" % name)
    os.chmod(tmp, 0o1777)
    # bubblewrap makes the mount points of what it shows under /tmp in that folder.
    mountpoints = {p[len("/tmp/"):].split("/")[0] for p in shown if p.startswith("/tmp/")}
    cmd = container_argv(_inside_args(name, options, control), tmp=tmp, ro_binds=shown,
                         setenv=[("TMPDIR", "/tmp"),
                                 ("SIFTLAB_PYTHON", os.environ.get("SIFTLAB_PYTHON", "/usr/bin/python3"))],
                         unsetenv=["SIFTLAB_SANDBOX"], as_pid_1=True)
    group = Cgroup("siftlab-hostile-%d-%s%s" % (os.getpid(), name, "-control" if control else ""),
                   memory=MEMORY, cpu=CPU)
    t0 = time.time()
    try:
        p = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           timeout=options["timeout"] + 300, preexec_fn=group.join)
        out, err, rc = p.stdout.decode("utf-8", "replace"), p.stderr.decode("utf-8", "replace"), p.returncode
    except subprocess.TimeoutExpired as e:
        out, err, rc = (e.stdout or b"").decode("utf-8", "replace"), "", "killed at its time-out"
    finally:
        seconds = time.time() - t0
        peak, ooms, cpu = group.peak_bytes(), group.oom_kills(), group.cpu_seconds()
        group.remove()
    lines = [x[len(RESULT):] for x in out.splitlines() if x.startswith(RESULT)]
    if lines:
        r = json.loads(lines[-1])
    else:
        r = {"name": name, "ok": False, "total": None, "max": None, "exit": None, "seconds": None, "stdout": "",
             "stderr": err, "root": None,
             "reasons": ["the check in the container printed no result (exit %s): %s" % (rc, err.strip()[-600:])]}
    keep = {os.path.basename(r["root"])} if options.get("keep") and r.get("root") else set()
    left = sorted(set(os.listdir(tmp)) - mountpoints - keep)
    if left:
        r["reasons"].append("the container's /tmp still holds %s" % ", ".join(left[:4]))
    if not options.get("keep"):
        subprocess.run(["rm", "-rf", "--one-file-system", tmp], check=False)
    elif r.get("root"):
        r["root"] = os.path.join(tmp, os.path.relpath(r["root"], "/tmp"))  # where the host sees it
    r.update(ok=not r["reasons"], container=seconds, cpu=cpu, peak=peak, oom_kills=ooms, tmp=tmp)
    return _as_control(r) if control else r


def _as_control(r):
    """A control passes when its check failed for its attack's reason and for the tier."""
    want = [CONTROLS[r["name"]], "tier, not 'container'"]
    missed = [w for w in want if not any(w in x for x in r["reasons"])]
    shown = "; ".join(r["reasons"]) or "no failure"
    r["reasons"] = (["the control did not fail for %s: the check cannot see it (it said: %s)" % (missed, shown)]
                    if missed else [])
    r.update(ok=not missed, name="%s (control, no sandbox)" % r["name"], caught=shown)
    return r


def describe(r):
    """One fixture's lines: hostile_check's, with the container's figures."""
    text = line(r, "; container %5.1f s, %5.1f cpu-s, peak %4d MB%s" % (
        r["container"], r["cpu"], r["peak"] >> 20, ", %d OOM kill(s)" % r["oom_kills"] if r["oom_kills"] > 0 else ""))
    if r["ok"] and "caught" in r:
        text += "\n     caught: " + safe(r["caught"])[:600]
    return text


def main(names, options, jobs, controls, show):
    """Runs `names` (then their controls) `jobs` at a time; prints each as it ends (show(r)
    prints a result's extra lines) and a summary. Returns the exit status."""
    if os.geteuid() != 0:
        print("hostile_check --in-platform: needs root (the platforms run the marker as root)", file=sys.stderr)
        return 2
    if not os.access(options["siftlab"], os.X_OK):
        print("hostile_check --in-platform: no siftlab at %s (build it, or give --siftlab / SIFTLAB)"
              % options["siftlab"], file=sys.stderr)
        return 2
    runs = [(x, False) for x in slow_first(names)]
    if controls:
        runs += [(x, True) for x in names if x in CONTROLS]
    results = []
    with concurrent.futures.ThreadPoolExecutor(max(1, jobs)) as pool:
        futures = [pool.submit(run, x, options, control) for x, control in runs]
        for f in concurrent.futures.as_completed(futures):
            r = f.result()
            results.append(r)
            print(describe(r), flush=True)
            show(r)
    top = max(results, key=lambda r: r["peak"])
    print("containers: %.0f s, %.0f cpu-s in all (their cgroups'); the highest peak %d MB (%s)" % (
        sum(r["container"] for r in results), sum(max(0.0, r["cpu"]) for r in results), top["peak"] >> 20,
        top["name"]))
    failed = [r["name"] for r in results if not r["ok"]]
    n_controls = sum(1 for _, control in runs if control)
    print("%d fixture(s): %d passed, %d failed (%d in the container tier inside the simulated platform, "
          "%d control(s) without the sandbox)%s" % (
              len(results), len(results) - len(failed), len(failed), len(runs) - n_controls, n_controls,
              (": " + ", ".join(failed)) if failed else ""))
    return 1 if failed else 0
