"""The published bound holds between check points: dense searches of shipped default tables."""

from __future__ import annotations

import numpy as np
import pytest
from _codegen_util import rulebase

from fuzzkit.codegen.emit import build_spec
from fuzzkit.codegen.lookup_table import LookupTable
from fuzzkit.codegen.table_search import make_table, round_up
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import RuleBase

TWO_INPUT = ["macvicar_whelan", "paper_table1", "gaussian5"]


def _errors(rb: RuleBase, tab: LookupTable, x0: np.ndarray, x1: np.ndarray) -> np.ndarray:
    """|table - exact| per point and output, on the inputs the generated code would see."""
    if tab.number_type == "float":
        x0, x1 = (x.astype(np.float32).astype(np.float64) for x in (x0, x1))
    res = Engine(rb).evaluate({rb.inputs[0].name: x0, rb.inputs[1].name: x1})
    got = tab.interpolate([x0, x1])
    return np.stack(
        [
            np.abs(g - np.asarray(res[v.name], dtype=np.float64))
            for g, v in zip(got, rb.outputs, strict=True)
        ]
    )


def _dense_max(rb: RuleBase, tab: LookupTable, worst: int = 16, per: int = 96) -> np.ndarray:
    """Largest error per output: ``per`` x per axis in the ``worst`` cells, plus 1e5 random."""
    b0, b1 = tab.breakpoints
    n0, n1 = len(b0) - 1, len(b1) - 1
    # Rank cells by the error on a 6x grid, edges included (not the builder's 8x grid).
    u = np.linspace(0.0, 1.0, 7)
    c0 = (b0[:-1, None] + np.diff(b0)[:, None] * u).ravel()
    c1 = (b1[:-1, None] + np.diff(b1)[:, None] * u).ravel()
    g0, g1 = np.meshgrid(c0, c1, indexing="ij")
    err = _errors(rb, tab, g0, g1).max(axis=0).reshape(n0, 7, n1, 7).max(axis=(1, 3))
    best = np.zeros(len(rb.outputs))
    fine = np.linspace(0.0, 1.0, per + 1)
    for cell in np.argsort(err.ravel())[::-1][:worst]:
        i, j = divmod(int(cell), n1)
        f0, f1 = np.meshgrid(
            b0[i] + (b0[i + 1] - b0[i]) * fine, b1[j] + (b1[j + 1] - b1[j]) * fine, indexing="ij"
        )
        best = np.maximum(best, _errors(rb, tab, f0.ravel(), f1.ravel()).max(axis=1))
    rng = np.random.default_rng(7)
    r0 = rng.uniform(rb.inputs[0].low, rb.inputs[0].high, 100_000)
    r1 = rng.uniform(rb.inputs[1].low, rb.inputs[1].high, 100_000)
    return np.maximum(best, _errors(rb, tab, r0, r1).max(axis=1))


@pytest.mark.parametrize("number_type", ["float", "q15"])
@pytest.mark.parametrize("name", TWO_INPUT)
def test_default_table_never_exceeds_its_printed_bound(name: str, number_type: str) -> None:
    # gaussian5 at the default tolerance exceeded its printed bound by 2 %: a bounded-sum
    # crease put the peak error between check points (and .3g printed the bound rounded down).
    rb = rulebase(name)
    tab = make_table(rb, number_type=number_type)  # type: ignore[arg-type]
    printed = [float(o.bound) for o in build_spec(rb, tab, "c").outputs]
    found = _dense_max(rb, tab)
    for k, var in enumerate(rb.outputs):
        assert found[k] <= printed[k], f"{var.name}: {found[k]:.6g} > printed {printed[k]}"
        assert printed[k] >= tab.bound[k]


@pytest.mark.parametrize(
    "value, expected",
    [(0.0018001, 0.00181), (0.00180, 0.0018), (1.234e-7, 1.24e-7), (999.1, 1000.0), (0.0, 0.0)],
)
def test_bounds_are_rounded_up_not_to_nearest(value: float, expected: float) -> None:
    assert round_up(value) == pytest.approx(expected, rel=1e-12)
    assert round_up(value) >= value
