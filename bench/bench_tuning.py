"""Benchmark of ``fuzzkit tune`` (issue 6): wall time of one tuning run on E1, cost vs defaults.

Run: ``.venv/bin/python bench/bench_tuning.py [--budget N] [--workers N]`` (prints a table;
about a minute on a 2-core machine with the default budget of 60).

Rows: PI and fuzzy-PI tuned on E1 over the default stiffnesses (5, 10, 20 N/mm), planar plant,
seed 0; wall time (target <= 60 s on 2 cores), gain sets simulated, best cost found and the
default gains' cost on the same cost function (``fuzzkit.studies.tuning.run_cost``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence


def main(argv: Sequence[str] | None = None) -> int:
    """Run the benchmark and print its table; returns the exit code (1 if a target is missed)."""
    from fuzzkit.studies.tuning import default_workers, tune

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--budget", type=int, default=60)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--controllers", default="pi,fuzzy-pi")
    args, _ = parser.parse_known_args(argv)  # `make bench` passes options for other benches
    workers = args.workers or default_workers()
    head = f"{'case':<34}{'wall s':>8}{'evals':>7}{'cost':>11}{'default':>11}{'gain %':>8}   target"
    print(f"fuzzkit tune E1, budget {args.budget}, {workers} workers, stiffness 5/10/20 N/mm")
    print(head)
    print("-" * len(head))
    missed = False
    for ctrl in args.controllers.split(","):
        r = tune(["E1"], ctrl, budget=args.budget, seed=0, workers=workers)
        ok = r.wall_time_s <= 60.0
        missed |= not ok
        print(
            f"{'E1 ' + ctrl:<34}{r.wall_time_s:>8.1f}{r.evaluations:>7}{r.cost:>11.5f}"
            f"{r.baseline_cost:>11.5f}{r.improvement_pct:>8.1f}   <= 60 s {'ok' if ok else 'MISS'}"
        )
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
