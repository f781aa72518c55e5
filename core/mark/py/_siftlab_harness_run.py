"""Running the student's code: a part of the harness (siftlab_harness.py). The call's prints
captured, whatever it raises made an error reply, and `_in_student`, which the import rule
(_siftlab_harness_imports.py) reads, true while it runs.
"""

import gc
import io
import sys
import traceback

STUDENT_FILE = "vision_tasks.py"
MAX_OUTPUT = 4000  # characters of the student's printed output kept in a reply

_in_student = False


class _Failure(Exception):
    def __init__(self, reply, exc=None):
        Exception.__init__(self)
        self.reply = reply
        self.exc = exc


def _error_reply(exc, kind):
    """{"error": last traceback line + (vision_tasks.py, line N), "kind", "traceback"}."""
    last = "".join(traceback.format_exception_only(type(exc), exc)).strip().splitlines()
    msg = last[-1] if last else type(exc).__name__
    if isinstance(exc, SyntaxError):
        where = STUDENT_FILE if exc.lineno is None else "%s, line %d" % (STUDENT_FILE, exc.lineno)
        msg = "%s: %s (%s)" % (type(exc).__name__, exc.msg, where)
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if f.filename == STUDENT_FILE]
    if frames and not isinstance(exc, SyntaxError):
        msg += " (%s, line %d)" % (STUDENT_FILE, frames[-1].lineno)
    tb = "".join(traceback.format_list(frames[-20:])) + "\n".join(last)
    return {"error": msg, "kind": kind, "traceback": tb}


class _Capture(io.TextIOBase):
    """The student's stdout/stderr: keeps the first MAX_OUTPUT characters (an endless loop
    that prints must not fill the memory)."""

    def __init__(self):
        io.TextIOBase.__init__(self)
        self.parts = []
        self.size = 0
        self.cut = False

    def writable(self):
        return True

    def write(self, text):
        if not isinstance(text, str):
            raise TypeError("write() argument must be str, not %s" % type(text).__name__)
        if self.size < MAX_OUTPUT:
            self.parts.append(text[:MAX_OUTPUT - self.size])
            self.size += len(self.parts[-1])
        if self.size >= MAX_OUTPUT and len(text):
            self.cut = self.cut or self.size + len(text) > MAX_OUTPUT
        return len(text)

    def getvalue(self):
        return "".join(self.parts) + ("\n[...]" if self.cut else "")


def _run(fn, args):
    """fn(*args) with the student's prints captured; (value, output) or _Failure. A
    KeyboardInterrupt (Pyodide's interrupt buffer, SIGINT in the CLI) ends the call with
    kind "interrupted"."""
    buf = _Capture()
    saved = sys.stdout, sys.stderr, sys.stdin
    sys.stdout = sys.stderr = buf
    sys.stdin = io.StringIO("")
    # No cyclic garbage collection during the call: a dt call makes millions of DMatch, and
    # the collector's passes over them would cost more than the rest of the call.
    gc_was_on = gc.isenabled()
    gc.disable()
    global _in_student
    _in_student = True
    try:
        value = fn(*args)
    except KeyboardInterrupt:
        reply = _add_output({"error": "KeyboardInterrupt: the call was interrupted", "kind": "interrupted"}, buf)
        raise _Failure(reply) from None
    except BaseException as e:  # SystemExit too: the student's code must not end the harness
        reply = _error_reply(e, "runtime")
        _add_output(reply, buf)
        raise _Failure(reply, e) from None
    finally:
        _in_student = False
        sys.stdout, sys.stderr, sys.stdin = saved
        if gc_was_on:
            gc.enable()
    return value, buf


def _add_output(reply, buf):
    text = buf.getvalue()
    if text:
        reply["output"] = text
    return reply
