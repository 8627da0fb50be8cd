"""Benchmark of ``fuzzkit stability`` (issue 21): a 10 stiffness x 8 latency grid certified.

Run: ``.venv/bin/python bench/bench_stability.py`` (prints a table). Rows: PI and fuzzy-PI
(``macvicar_whelan``) on each plant, the regulation task, default gains; wall and CPU time of
certifying the 80 cells (target < 10 s), with the plant's inner-loop identification (done once
per plant and process) timed separately, and how many cells were certified.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence

STIFFNESSES = (5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 300.0, 500.0, 700.0, 1000.0)
LATENCIES = ((0, 0), (1, 0), (0, 1), (1, 1), (2, 1), (2, 2), (3, 3), (4, 4))
TARGET_S = 10.0


def main(argv: Sequence[str] | None = None) -> int:
    """Run the benchmark and print its table; returns 1 if a target is missed."""
    from fuzzkit.analysis.certificate import certify  # noqa: F401  (import the solver up front)
    from fuzzkit.analysis.inner_loop import identify
    from fuzzkit.analysis.region import certify_region, fuzzy_part
    from fuzzkit.analysis.regulation import regulation_experiment

    exp = regulation_experiment()
    cells = len(STIFFNESSES) * len(LATENCIES)
    head = f"{'case':<22}{'identify s':>11}{'wall s':>8}{'cpu s':>8}{'certified':>11}   target"
    print(f"fuzzkit stability regulate: {len(STIFFNESSES)} stiffness x {len(LATENCIES)} latency")
    print(head)
    print("-" * len(head))
    fuzzy_part("macvicar_whelan")  # the table (cached on disk) and its bounds, once
    missed = False
    for plant in ("arm6", "planar"):
        t0 = time.perf_counter()
        identify(plant)
        ident = time.perf_counter() - t0
        for controller in ("pi", "fuzzy-pi"):
            w0, c0 = time.perf_counter(), time.process_time()
            region = certify_region(exp, controller, plant, STIFFNESSES, LATENCIES)
            wall, cpu = time.perf_counter() - w0, time.process_time() - c0
            ok = wall < TARGET_S
            missed |= not ok
            n = sum(c.certified for c in region.cells)
            print(
                f"{plant + ' ' + controller:<22}{ident:>11.2f}{wall:>8.2f}{cpu:>8.2f}"
                f"{f'{n}/{cells}':>11}   < {TARGET_S:g} s {'ok' if ok else 'MISS'}"
            )
            ident = 0.0
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
