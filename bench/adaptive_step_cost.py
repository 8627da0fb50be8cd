"""The generated C controller's step with and without adaptation (issue 24): ns per step.

200000 periods of a noisy 12 N log through NAME_controller_step (double, -O2, the harness loop
in C), best of 5, in CPU time of the process (``time.process_time``: a loaded machine's waits
are not counted, its shared caches and frequency still are: the figures are approximate).

    .venv/bin/python bench/adaptive_step_cost.py
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from fuzzkit.control.adaptation_spec import NONE, Adaptation
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.loop.controller_code import open_generated


def main() -> None:
    s = load_spec("docs/examples/controller_adaptive.yaml")
    variants = {
        "fixed": dataclasses.replace(s, adaptation=NONE),
        "stiffness-scheduled": s,
        "self-tuning": dataclasses.replace(s, adaptation=Adaptation("self-tuning")),
    }
    n = 200000
    rng = np.random.default_rng(0)
    f = np.zeros((n, 3))
    f[:, 2] = 12 + np.cumsum(rng.normal(0, 0.3, n)) * 0.01 + rng.normal(0, 0.5, n)
    r = np.tile(np.eye(3).ravel(), (n, 1))
    for name, spec in variants.items():
        c = open_generated(spec, "c", "double")
        best = 1e9
        for _ in range(5):
            c.reset()
            t = time.process_time()
            c.run(f, r)
            best = min(best, time.process_time() - t)
        print(
            f"{name:20s} {best / n * 1e9:7.1f} ns per step (C, double, -O2, {n} steps, best of 5, "
            "CPU time)"
        )


if __name__ == "__main__":
    main()
