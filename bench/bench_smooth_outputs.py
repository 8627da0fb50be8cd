"""Benchmark: a 3x3 rule base with Gaussian inputs and outputs (tests/data/gaussian3x3.yaml).

Prints the engine's 101x101 surface with the closed-form Gaussian output stage
(``fuzzy.gaussian_geometry``) and with the a-priori grid it replaced (``GridGeometry``, the
engine's path for other smooth outputs), and ``fuzzkit compile`` of the rule base (C float,
default method) with and without ``--verify``, as the command runs them (targets: surface
1 s, compile --verify 10 s).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from fuzzkit.codegen.method import compile_rulebase
from fuzzkit.codegen.target import load_target
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.output_geometry import GridGeometry

RULEBASE = Path(__file__).parent.parent / "tests" / "data" / "gaussian3x3.yaml"


def _surface(engine: Engine, n: int = 101) -> float:
    g = np.linspace(-1.0, 1.0, n)
    e, de = np.meshgrid(g, g)
    start = time.perf_counter()
    engine.evaluate({"e": e, "de": de})
    return time.perf_counter() - start


def main() -> None:
    rb = load(RULEBASE)
    closed = Engine(rb)
    _surface(closed, 11)  # warm
    rows = [("surface 101x101, closed form (erf)", _surface(closed))]
    grid = Engine(rb)
    out = grid._outputs[0]
    out.geometry = GridGeometry(rb, rb.outputs[0], out.pieces)  # type: ignore[union-attr]
    _surface(grid, 3)  # compile the grid kernel first
    rows.append(("surface 21x21, grid (the old path; x23 for 101x101)", _surface(grid, 21)))
    start = time.perf_counter()
    result = compile_rulebase(rb, "c", "float")
    rows.append((f"compile (c float, {result.method})", time.perf_counter() - start))
    target = load_target("c")
    if result.table is not None:
        proof = target.verify_table(rb, result.table, result.files)
    else:
        proof = target.verify_exact(rb, "float", result.files)
    if not proof.ok:
        raise RuntimeError(proof.describe())
    rows.append(("compile --verify", time.perf_counter() - start))
    print(f"{'what':<56} {'seconds':>8}")
    for what, secs in rows:
        print(f"{what:<56} {secs:8.2f}")


if __name__ == "__main__":
    main()
