"""The reference marker's cases: drawn from a seed, or read from siftlab's report."""
from __future__ import annotations

import json
import random

TASKS = ("dt", "nn", "nndr", "matching_info")
STRATEGIES = ("dt", "nn", "nndr")


def draw_threshold(rng: random.Random, strategy: str):
    if strategy == "nn" and rng.random() < 0.2:
        return None
    hi, digits = (1.0, 2) if strategy == "nndr" else (500.0, 1)
    u = rng.random()
    if u < 0.05:
        return 0.0
    if u < 0.10:
        return hi
    return round(rng.uniform(0.0, hi), digits)


def draw_cases(seed: int, n: int, frames: int, keypoints_of):
    """n cases per task: frame uniform in 1..frames, thresholds as docs/marking.md says."""
    rng = random.Random(seed)
    cases = []
    for task in TASKS:
        for _ in range(n):
            frame = rng.randint(1, frames)
            if task == "matching_info":
                strategy = rng.choice(STRATEGIES)
                t = draw_threshold(rng, strategy)
                feature = rng.randrange(keypoints_of(frame - 1))
                cases.append({"task": task, "frame": frame, "threshold": t, "strategy": strategy,
                              "feature": feature})
            else:
                cases.append({"task": task, "frame": frame, "threshold": draw_threshold(rng, task)})
    return cases


def read_cases(path):
    with open(path) as fh:
        data = json.load(fh)
    if isinstance(data, dict):
        data = data["cases"]
    keep = ("task", "frame", "threshold", "strategy", "feature")
    out = []
    for c in data:
        case = {k: c[k] for k in keep if k in c}
        if case["task"] not in TASKS:
            raise ValueError("unknown task %r" % (case["task"],))
        if case["task"] == "matching_info" and ("strategy" not in case or "feature" not in case):
            raise ValueError("a matching_info case needs strategy and feature: %r" % (c,))
        out.append(case)
    return out
