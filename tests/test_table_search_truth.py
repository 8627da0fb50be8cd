"""The table search tells the truth: what it says cannot be met is not met by any resolution it
names, and a resolution that meets a tolerance is found.

The search proves most resolutions too coarse from their cell edges alone
(``codegen/edge_floor.py``: half the surface's distance from an edge's chord is a floor under
every table's error there); the floor is checked here against the error of built tables, and
the verdicts against building every table the claim covers.
"""

from __future__ import annotations

import numpy as np
import pytest
from _codegen_util import rulebase

from fuzzkit.codegen.edge_floor import chord_floor
from fuzzkit.codegen.table_search import (
    _check_axes,
    _sample,
    _table_breakpoints,
    build_table,
    check_factor_for,
    make_table,
)
from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy.inference import evaluate


@pytest.mark.parametrize(
    "name, counts, number_type",
    [
        ("macvicar_whelan", [5, 5], "double"),
        ("macvicar_whelan", [12, 9], "float"),
        ("gaussian5", [7, 7], "double"),
        ("temperature_pd", [9, 6], "q15"),
        ("three_input", [4, 5, 3], "double"),
    ],
)
def test_the_edge_floor_is_below_the_error_of_the_table_built(
    name: str, counts: list[int], number_type: str
) -> None:
    rb = rulebase(name)
    table = build_table(rb, counts, number_type=number_type)  # type: ignore[arg-type]
    _, bps = _table_breakpoints(rb, counts, number_type)  # type: ignore[arg-type]
    factor = check_factor_for(counts)
    axes = _check_axes(bps, factor, number_type)  # type: ignore[arg-type]
    exact = _sample(rb, lambda x: evaluate(rb, x), axes)
    assert table.check_factor == factor
    for k, values in enumerate(exact):
        floor = 0.0
        for a in range(len(axes)):
            lines = np.moveaxis(values, a, -1).reshape(-1, len(axes[a]))
            floor = max(floor, float(chord_floor(axes[a], lines, factor)[0].max()))
        full_scale = max(abs(v) for v in table.output_ranges[k])
        # the table's own error on its check grid, which holds every edge, is at least the floor
        assert floor <= table.measured[k] + 8 / 32768 * full_scale
        assert floor > 0.05 * table.measured[k]  # and it is a floor worth having


CAP, TOL = 200, 2e-3  # macvicar_whelan within 200 points cannot reach 0.2 % of its range


def test_a_tolerance_out_of_reach_is_said_to_be_so_with_what_was_settled() -> None:
    with pytest.raises(CodegenError, match=f"cannot be met within {CAP} table points") as err:
        make_table(rulebase("macvicar_whelan"), number_type="double", tolerance=TOL, max_points=CAP)
    assert "no table of 2 to 14 breakpoints on every input (up to 14x14)" in str(err.value)


@pytest.mark.verify
def test_a_tolerance_said_to_be_out_of_reach_is_met_by_no_resolution_within_the_cap() -> None:
    rb, tol = rulebase("macvicar_whelan"), TOL
    for count in range(2, 15):  # every one the refusal above covers, built and certified
        table = build_table(rb, [count, count], number_type="double", tolerance=tol)
        assert max(b / t for b, t in zip(table.bound, table.tolerance, strict=True)) > 1, count


def test_a_resolution_that_meets_the_tolerance_is_found_when_the_first_guesses_miss() -> None:
    # 2 % of the range within 120 points: the search's spacing-based guesses for gaussian5 miss
    # (before this check it said "cannot be met within 120 table points"); 10x10 meets it
    rb = rulebase("gaussian5")
    tol, cap = 0.02, 120
    found = make_table(rb, number_type="double", tolerance=tol, max_points=cap)
    assert all(b <= t for b, t in zip(found.bound, found.tolerance, strict=True))
    assert found.n_points <= cap
    # found by bisection: the next coarser uniform table misses
    count = found.shape[0]
    assert list(found.shape) == [count, count]
    coarser = build_table(rb, [count - 1, count - 1], number_type="double", tolerance=tol)
    assert any(b > t for b, t in zip(coarser.bound, coarser.tolerance, strict=True))
