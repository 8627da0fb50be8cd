"""Benchmark of ``fuzzkit stability`` (issue 21): a 10 stiffness x 8 latency grid certified.

Run: ``.venv/bin/python bench/bench_stability.py`` (prints a table). Rows: PI and fuzzy-PI
(``macvicar_whelan``) on each plant, the regulation task, default gains; wall and CPU time of
certifying the 80 cells (target < 10 s), with the plant's inner-loop identification (done once
per plant and process) timed separately, and how many cells were certified. Then user-style
specs (``tests/data/user/spec_*.yaml``, ``--spec``): their wall time includes building the
table their surface is bounded on (no disk cache), as a first ``fuzzkit stability --spec`` pays.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence
from typing import Any

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
            missed |= _row(f"{plant} {controller}", ident, w0, c0, region, cells)
            ident = 0.0
    missed |= _user_specs(exp, cells)
    return 1 if missed else 0


def _user_specs(exp: object, cells: int) -> bool:
    """Time ``stability --spec`` on the user-style specs of the tests (arm6); True if missed."""
    from pathlib import Path

    from fuzzkit.analysis.spec_certificate import certify_spec
    from fuzzkit.control.spec_reader import load_spec

    folder = Path(__file__).resolve().parents[1] / "tests" / "data" / "user"
    missed = False
    for path in sorted(folder.glob("spec_*.yaml")):
        spec = load_spec(path)
        w0, c0 = time.perf_counter(), time.process_time()
        region = certify_spec(exp, spec, "arm6", STIFFNESSES, LATENCIES)  # type: ignore[arg-type]
        missed |= _row(f"arm6 {path.stem}", 0.0, w0, c0, region, cells)
    return missed


def _row(case: str, ident: float, w0: float, c0: float, region: Any, cells: int) -> bool:
    """Print one row (timed from ``w0``, ``c0``); True if the target is missed."""
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    n = sum(c.certified for c in region.cells)
    ok = wall < TARGET_S
    print(
        f"{case:<22}{ident:>11.2f}{wall:>8.2f}{cpu:>8.2f}"
        f"{f'{n}/{cells}':>11}   < {TARGET_S:g} s {'ok' if ok else 'MISS'}"
    )
    return not ok


if __name__ == "__main__":
    sys.exit(main())
