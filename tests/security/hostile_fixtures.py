"""The hostile fixtures (tests/fixtures/mark/hostile) and what a marking of each must show:
their names, the marks their honest parts can earn, the calls each needs, and the checks on
the marker's report (its total, its JSON, the characters it may hold). Used by
hostile_check.py (docs/testing.md); Python 3.8+, standard library only.
"""

import json
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
HOSTILE = os.path.join(REPO, "tests", "fixtures", "mark", "hostile")
GOOD = os.path.join(REPO, "tests", "fixtures", "mark", "good", "vision_tasks.py")
README = os.path.join(HOSTILE, "README.md")
DEFAULT_SIFTLAB = os.environ.get("SIFTLAB") or os.path.join(REPO, "target", "release", "siftlab")
DEFAULT_DATASET = os.path.join(REPO, "www", "demo", "MyKITTI")

# The marks each fixture's honest parts can earn (the README's "Max" column is authoritative;
# this is the fallback when the README cannot be read).
MAX_MARKS = {
    "browser_escape": 20.0,
    "browser_storage": 20.0,
    "run_marker": 6.5,
    "steal_expected": 15.5,
    "always_equal": 15.5,
    "patch_expected": 15.5,
    "shadow_bool": 15.5,
    "wrap_handle": 15.5,
    "leak_secrets": 15.0,
    "write_files": 20.0,
    "network": 20.0,
    "outlive": 20.0,
    "sigstop": 20.0,
    "forge_report": 20.0,
    "ansi_escapes": 10.0,
    "protocol_lines": 15.5,
    "slow_reload": 15.0,
    "import_module": 0.0,
    "import_dunder": 0.0,
    "import_builtins": 0.0,
    "import_exec": 0.0,
    "import_spec": 0.0,
    "fork_bomb": 20.0,
    "memory_bomb": 20.0,
    "overflow_rows": 15.0,
    "knn_huge": 20.0,
    "huge_lines": 20.0,
    "memfd_hold": 20.0,
    "reaped_cpu": 15.0,
    "cpu_farm": 15.0,
    "load_sleep": 0.0,
    "pair_sleep": 0.0,
}

# Calls per task each fixture needs for its attack to show (others: 1). leak_secrets'
# matching_info raises its secrets on odd calls and returns them on even ones.
CALLS = {"leak_secrets": 2}

# The fixtures that wait longest by design (their attackers' sleeps and limits: ~60 s each
# and more): started first when several run at once, so none is left to run alone at the end.
SLOW_FIRST = ["pair_sleep", "slow_reload", "load_sleep", "cpu_farm", "reaped_cpu", "knn_huge", "sigstop"]

# The controls: fixtures marked again with --no-sandbox, where each attack must show, so that
# the check is seen to catch it ({name: what its reasons must then say}). Each is safe to run
# without the sandbox only inside the simulated container (its own PID namespace, network,
# /tmp; the host read-only): hostile_platform.py runs them there.
CONTROLS = {
    "outlive": "outlived the marker",
    "network": "reached the canary listener",
    "write_files": "class folder changed",
    "leak_secrets": "token is in the marker's",
}

# Characters no report may hold raw: C0 controls but newline and tab, DEL, C1 controls, and
# the characters that reorder or hide text (as core::mark::escape).
_BAD_CHARS = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u00ad\u061c\u180e\u200b-\u200f\u2028-\u202e"
                        "\u2060-\u206f\ufeff\ufff9-\ufffb]")


def fixtures():
    """The hostile fixtures' names (folders holding a vision_tasks.py), sorted."""
    if not os.path.isdir(HOSTILE):
        return []
    return sorted(d for d in os.listdir(HOSTILE) if os.path.isfile(os.path.join(HOSTILE, d, "vision_tasks.py")))


def max_marks():
    """{name: max} from the README's table (rows `| \\`name/\\` | ... | max |`), else MAX_MARKS."""
    out = {}
    try:
        with open(README, encoding="utf-8") as f:
            for line in f:
                cells = [c.strip() for c in line.strip().strip("|").split("|")]
                if len(cells) < 3 or not cells[0].startswith("`"):
                    continue
                name = cells[0].strip("`").rstrip("/")
                try:
                    out[name] = float(cells[-1].strip("*` "))
                except ValueError:
                    continue
    except OSError:
        pass
    merged = dict(MAX_MARKS)
    merged.update(out)
    return merged


def slow_first(names):
    """names, those of SLOW_FIRST first (in its order), the rest as given."""
    return [x for x in SLOW_FIRST if x in names] + [x for x in names if x not in SLOW_FIRST]


def bad_chars(text):
    """None, or how many characters of text a terminal would obey or hide, and the first."""
    m = _BAD_CHARS.search(text)
    if m is None:
        return None
    n = len(_BAD_CHARS.findall(text))
    return "%d (first U+%04X at %d)" % (n, ord(m.group()), m.start())


def safe(text):
    """text with the characters a terminal would obey shown as escapes (for our own output)."""
    return _BAD_CHARS.sub(lambda m: "\\x%02x" % ord(m.group()) if ord(m.group()) < 0x100
                          else "\\u%04x" % ord(m.group()), text)


def _json_strings(v):
    if isinstance(v, str):
        yield v
    elif isinstance(v, dict):
        for k, x in v.items():
            yield k
            yield from _json_strings(x)
    elif isinstance(v, list):
        for x in v:
            yield from _json_strings(x)


def report_reasons(stdout, stderr, limit, result):
    """What is wrong with the marker's output: characters a terminal would obey, no JSON
    report with a numeric total, a total over `limit`. Sets result["total"]."""
    reasons = []
    for label, text in (("stdout", stdout), ("stderr", stderr)):
        bad = bad_chars(text)
        if bad:
            reasons.append("%s holds control/hidden characters: %s" % (label, bad))
    try:
        report = json.loads(stdout)
    except ValueError as e:
        return reasons + ["stdout is not one JSON report (%s): %r" % (e, stdout[:120])]
    total = report.get("total") if isinstance(report, dict) else None
    if not isinstance(total, (int, float)) or isinstance(total, bool):
        reasons.append("the report has no numeric total")
    else:
        result["total"] = float(total)
        if limit is not None and total > limit + 1e-6:
            reasons.append("total %.4g is over the %.4g the honest parts earn" % (total, limit))
    inner_bad = [b for b in (bad_chars(s) for s in _json_strings(report)) if b]
    if inner_bad:
        reasons.append("%d string(s) of the JSON report hold control/hidden characters once decoded, "
                       "e.g. %s" % (len(inner_bad), inner_bad[0]))
    return reasons


def tier_reasons(results_dir, tier):
    """What is wrong with the Gradescope results.json the marker wrote in results_dir (alone
    there): its sandbox (extra_data.sandbox) must be `tier`."""
    path = os.path.join(results_dir, "results.json")
    extra = sorted(set(os.listdir(results_dir)) - {"results.json"})
    reasons = ["new files beside results.json: %s" % ", ".join(extra[:4])] if extra else []
    try:
        with open(path, encoding="utf-8") as f:
            sandbox = (json.load(f).get("extra_data") or {}).get("sandbox")
    except (OSError, ValueError, AttributeError) as e:
        return reasons + ["no results.json with the sandbox tier (%s): the tier is unknown" % e]
    if sandbox != tier:
        reasons.append("marked by the %r tier, not %r" % (sandbox, tier))
    return reasons


def line(r, note=""):
    """A check's result as hostile_check.py prints it: PASS/FAIL, the fixture, its n, total,
    maximum, exit status and seconds (then `note`), and on a failure its reasons."""
    total = "-" if r["total"] is None else "%.2f" % r["total"]
    limit = "?" if r["max"] is None else "%g" % r["max"]
    head = "%s %-16s n %d total %6s / max %-5s exit %-4s %6ss%s" % (
        "PASS" if r["ok"] else "FAIL", r["name"], r.get("n") or 0, total, limit,
        "-" if r["exit"] is None else r["exit"], "-" if r["seconds"] is None else r["seconds"], note)
    if r["ok"]:
        return head
    return head + "\n     - " + "\n     - ".join(safe(x) for x in r["reasons"])
