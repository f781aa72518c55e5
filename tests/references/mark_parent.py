"""The reference marker's parent: the file checks, the child's timeouts and restarts, the marks."""
from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import time

from mark_cases import TASKS
from mark_worker import STUDENT_FILE

# The child is the command itself in its --worker mode.
ENTRY = os.path.join(os.path.dirname(os.path.abspath(__file__)), "mark_reference.py")
CALL_LIMIT = 10.0
TASK_LIMIT = 300.0


def ascii_problem(data: bytes):
    """None when every byte is printable ASCII, tab or newline (CR only before LF), else a
    message naming the first other byte's line and column."""
    line, col = 1, 0
    for i, b in enumerate(data):
        col += 1
        if b == 0x0A:
            line, col = line + 1, 0
            continue
        if b == 0x09 or 0x20 <= b <= 0x7E:
            continue
        if b == 0x0D and data[i + 1:i + 2] == b"\n":
            continue
        return "byte 0x%02X at line %d, column %d is not printable ASCII" % (b, line, col)
    return None


class Worker:
    def __init__(self, student, dataset):
        self.args = [sys.executable, ENTRY, "--worker", student, "--dataset", dataset]
        self.start()

    def start(self):
        self.p = subprocess.Popen(self.args, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                  stderr=subprocess.DEVNULL, text=True, bufsize=1)
        self.buf = b""
        self.load = self.read(60.0)
        if self.load is None:
            self.kill()
            self.load = {"error": "loading the file took over 60 s", "kind": "timeout"}

    def read(self, timeout):
        """The next line as JSON, None after `timeout` seconds. Reads the pipe's file
        descriptor itself: a buffered reader could hold a line select() does not see."""
        deadline = time.monotonic() + timeout
        fd = self.p.stdout.fileno()
        while b"\n" not in self.buf:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                return None
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                return {"status": "error", "kind": "runtime", "message": "the Python process ended"}
            self.buf += chunk
        line, self.buf = self.buf.split(b"\n", 1)
        return json.loads(line)

    def kill(self):
        self.p.kill()
        self.p.wait()

    def close(self):
        try:
            self.p.stdin.close()
        except OSError:
            pass
        self.p.wait()


def mark(student, cases, dataset, call_limit=CALL_LIMIT, task_limit=TASK_LIMIT, log=None, wall_factor=3.0):
    """The report. The limits are on the CPU time the call used (the child measures it), so a
    busy machine does not turn slow calls into timeouts; a call still running after
    wall_factor x call_limit seconds of wall time is killed (and is over the limit)."""
    with open(student, "rb") as fh:
        data = fh.read()
    report = {"file": student, "ascii": True, "tasks": {}, "total": 0.0, "cases": []}
    problem = ascii_problem(data)
    if problem:
        report["ascii"] = False
        report["load"] = {"error": "not printable ASCII: " + problem, "kind": "ascii"}
    else:
        try:
            compile(data.decode("ascii"), STUDENT_FILE, "exec", dont_inherit=True)
        except (SyntaxError, ValueError) as e:
            report["load"] = {"error": "%s: %s" % (type(e).__name__, getattr(e, "msg", e)), "kind": "syntax"}
    w = None
    if "load" not in report:
        w = Worker(student, dataset)
        report["load"] = w.load
    loaded = "ok" in report["load"]
    spent = {t: 0.0 for t in TASKS}
    for case in cases:
        task = case["task"]
        rec = dict(case)
        if not loaded:
            rec.update(status="error", kind="load", message=report["load"]["error"])
        elif spent[task] >= task_limit:
            rec.update(status="error", kind="task-time", message="the task's %g s are used up" % task_limit)
        else:
            w.p.stdin.write(json.dumps(case) + "\n")
            w.p.stdin.flush()
            started = w.read(600.0)
            if started is None or "started" not in started:
                raise RuntimeError("worker did not start the call: %r" % (started,))
            t0 = time.monotonic()
            out = w.read(wall_factor * min(call_limit, task_limit - spent[task]) + 0.5)
            wall = time.monotonic() - t0
            if out is None:
                w.kill()
                spent[task] += call_limit
                rec.update(status="error", kind="timeout", message="over %g s" % call_limit,
                           seconds=None, wall=round(wall, 3))
                w.start()
            else:
                secs = out.pop("seconds", wall)
                spent[task] += secs
                if secs > call_limit:
                    out = {"status": "error", "kind": "timeout", "message": "over %g s" % call_limit}
                rec.update(out)
                rec["seconds"] = round(secs, 3)
                rec["wall"] = round(wall, 3)
        report["cases"].append(rec)
        if log:
            print("%-13s frame %3d t=%-6s %s %s" % (task, case["frame"], case["threshold"], rec["status"],
                                                    rec.get("message", "")[:150]), file=log)
    if w is not None:
        w.close()
    total = 0.0
    for task in TASKS:
        recs = [r for r in report["cases"] if r["task"] == task]
        if not recs:
            continue
        correct = sum(r["status"] == "correct" for r in recs)
        errors = sum(r["status"] == "error" for r in recs)
        m = (0.5 if errors == 0 else 0.0) + 4.5 * correct / len(recs) if loaded else 0.0
        report["tasks"][task] = {"calls": len(recs), "correct": correct, "errors": errors, "mark": m}
        total += m
    report["total"] = total
    return report
