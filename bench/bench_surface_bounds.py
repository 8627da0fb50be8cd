"""The sound bounds of the exact surface against a dense engine grid, and their cost.

Per rule base: the branch and bound's time and largest excess over the measured secants
(``fuzzkit.analysis.surface_bounds``), the enclosure's hull of ``dF/de`` over the whole square
and over ``|x|, |y| <= 0.1``, beside the secants of a 1025 x 1025 engine grid and the slopes of
the 129-point table the certificate reads today. ``python bench/bench_surface_bounds.py
[names...]`` (default: the shipped loop rule bases).
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace

import numpy as np

from fuzzkit.analysis.fuzzy_bounds import gradient_bounds
from fuzzkit.analysis.surface_bounds import compute
from fuzzkit.analysis.surface_source import surface_source
from fuzzkit.control.loop_rulebase import load_loop_rulebase
from fuzzkit.fuzzy.inference import evaluate

DEFAULT = ("macvicar_whelan", "gaussian5")
DENSE = 1025
NEAR = 0.1


def _row(name: str) -> str:
    rb = replace(load_loop_rulebase(name), out_of_range="clamp")
    start = time.perf_counter()
    sb = compute(rb)
    took = time.perf_counter() - start
    whole, near = sb.over(-1, 1, -1, 1), sb.over(-NEAR, NEAR, -NEAR, NEAR)
    xs = np.linspace(-1.0, 1.0, DENSE)
    xx, yy = np.meshgrid(xs, xs, indexing="ij")
    out = evaluate(rb, {rb.inputs[0].name: xx.ravel(), rb.inputs[1].name: yy.ravel()})
    f = np.asarray(out[rb.outputs[0].name]).reshape(xx.shape)
    sx = np.diff(f, axis=0) / (xs[1] - xs[0])
    inside = np.abs(xs) <= NEAR
    sx_near = sx[inside[:-1]][:, inside]
    t = surface_source(rb).table
    table = gradient_bounds(t.bp0, t.bp1, t.values, t.splits, 1.0, 0.0).a_range
    return (
        f"{name:18s} {took:6.1f} {sb.gap:7.3g} {sb.tolerance:6.3g}  "
        f"[{whole.dx[0]:6.3f}, {whole.dx[1]:6.3f}] [{sx.min():6.3f}, {sx.max():6.3f}] "
        f"[{table[0]:6.3f}, {table[1]:6.3f}]  "
        f"[{near.dx[0]:6.3f}, {near.dx[1]:6.3f}] [{sx_near.min():6.3f}, {sx_near.max():6.3f}]"
    )


def main(argv: list[str]) -> None:
    names = [a for a in argv if not a.startswith("-") and a != "surface_bounds"] or DEFAULT
    print(
        "rule base            B&B s  excess    tol  dF/de sound        dense (1025^2)    "
        "table (129)        near: sound        near: dense"
    )
    for name in names:
        print(_row(name), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
