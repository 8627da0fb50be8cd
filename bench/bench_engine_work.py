"""The engine's cost model against its measured time: what a compile's budget charges.

Run: ``.venv/bin/python bench/bench_engine_work.py`` (prints a table; about a minute on a
2-core machine). ``codegen/budget.py`` charges ``Engine.work_per_point() /
OPERATIONS_PER_SECOND`` per point before the work; the constants in
``fuzzkit/fuzzy/inference.py`` (``NS_*``) are set at about twice the largest cost per unit each
output path measures here under load, so the ratio estimated / measured should stay above 1
on every row (grid outputs stay at 50 ns a unit, well above: see ``NS_PER_GRID_PIECE``).

Rows: the shipped rule bases, random ones with and without MATLAB's smooth shapes
(tests/_random_rulebases.py), and the exact-product test's rule base for piecewise-linear,
Gaussian and smooth outputs under three defuzzifiers; the CPU time of one batch of 2,000
points (100 for grid outputs, which cost milliseconds a point) after a warm-up batch, and
the engine's construction.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from _random_rulebases import random_rulebase  # noqa: E402
from test_exact_product import rulebase as product_rulebase  # noqa: E402

from fuzzkit.formats.registry import load  # noqa: E402
from fuzzkit.fuzzy.inference import OPERATIONS_PER_SECOND, Engine  # noqa: E402
from fuzzkit.fuzzy.model import RuleBase  # noqa: E402


def _cases() -> list[tuple[str, RuleBase]]:
    names = ["macvicar_whelan", "three_input", "gaussian5", "sugeno_pi", "temperature_pd"]
    cases = [(n, load(n)) for n in names]
    cases.append(("gaussian3x3", load(HERE.parent / "tests" / "data" / "gaussian3x3.yaml")))
    for seed in range(6):
        cases.append((f"random{seed}", random_rulebase(seed)))
        cases.append((f"random{seed}-matlab", random_rulebase(seed, matlab_shapes=True)))
    for kind in ("pwl", "gaussian", "smooth"):
        for d in ("centroid", "bisector", "mean_of_maximum"):
            agg = "bounded_sum" if kind == "smooth" else "max"
            cases.append((f"{kind}-{d}", product_rulebase("min", "max", "product", agg, d, kind)))
    return cases


def main() -> None:
    rng = np.random.default_rng(0)
    print(f"{'rule base':24s} {'build ms':>9s} {'est ms':>8s} {'us/pt':>9s} {'est us':>9s} ratio")
    for name, rb in _cases():
        t = time.process_time()
        engine = Engine(rb)
        build = time.process_time() - t
        est = engine.work_per_point() / OPERATIONS_PER_SECOND
        n = 2000 if est < 1e-4 else 100
        points = {v.name: rng.uniform(v.low, v.high, n) for v in rb.inputs}
        engine.evaluate({k: v[:20] for k, v in points.items()})
        t = time.process_time()
        engine.evaluate(points)
        per = (time.process_time() - t) / n
        build_est = engine.construction_work() / OPERATIONS_PER_SECOND
        print(
            f"{name:24s} {1e3 * build:9.1f} {1e3 * build_est:8.1f} {1e6 * per:9.2f} "
            f"{1e6 * est:9.2f} {est / per:5.1f}"
        )


if __name__ == "__main__":
    main()
