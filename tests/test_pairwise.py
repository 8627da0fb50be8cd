"""The covering-set generator of ``make test``'s matrices (tests/_pairwise.py), checked by
enumerating every pair of the full product independently of the construction."""

from __future__ import annotations

import itertools
from collections.abc import Hashable, Sequence
from typing import Any

import pytest
from _pairwise import COVER_SEEDS, VERIFY_SEEDS, matrix_params, pairwise, rotated_product

AXIS_SETS: dict[str, list[list[Hashable]]] = {
    # the safety matrix: impl, experiment, controller, fault, plant
    "safety": [
        ["reference", "generated-c"],
        ["E1", "E2", "E3"],
        ["pi", "fuzzy-pi"],
        ["delay", "dropout", "nan", "none", "spike"],
        ["planar", "arm6"],
    ],
    "mujoco": [
        ["E1", "E2", "E3"],
        ["pi", "fuzzy-pi"],
        ["delay", "dropout", "nan", "none", "spike"],
    ],
    "ten binary": [[0, 1]] * 10,
    "four ternary": [["a", "b", "c"]] * 4,
    "uneven": [[1, 2, 3, 4, 5], ["x"], [True, False], list(range(4)), [None, "y", 2.5]],
    "two axes": [[1, 2, 3], ["p", "q"]],
}


def _missing_pairs(axes: Sequence[Sequence[Hashable]], rows: list[tuple[Hashable, ...]]) -> list:
    """Every (axis i, value, axis j, value) of the full product that no row holds."""
    return [
        (i, a, j, b)
        for i, j in itertools.combinations(range(len(axes)), 2)
        for a in axes[i]
        for b in axes[j]
        if not any(row[i] == a and row[j] == b for row in rows)
    ]


@pytest.mark.parametrize("name", sorted(AXIS_SETS))
def test_every_pair_and_every_value_of_every_axis_is_covered(name: str) -> None:
    axes = AXIS_SETS[name]
    rows = pairwise(axes)
    assert all(len(row) == len(axes) for row in rows)
    for k, values in enumerate(axes):
        assert {row[k] for row in rows} == set(values), k  # only the axis' values, all of them
    assert _missing_pairs(axes, rows) == []
    assert len(set(rows)) == len(rows)  # no row twice


@pytest.mark.parametrize("name", sorted(AXIS_SETS))
def test_the_covering_set_is_small_and_the_same_on_every_call(name: str) -> None:
    axes = AXIS_SETS[name]
    rows = pairwise(axes)
    assert rows == pairwise([list(values) for values in axes])  # deterministic: test ids repeat
    sizes = sorted((len(values) for values in axes), reverse=True)
    full = 1
    for n in sizes:
        full *= n
    # at least the product of the two largest axes (every pair of those needs a row); well
    # below the full product once there are more than two axes
    assert sizes[0] * sizes[1] <= len(rows) <= full
    if len(axes) > 2:
        assert len(rows) <= full // 2


def test_the_safety_matrix_needs_only_its_two_largest_axes_product() -> None:
    # 5 faults x 3 experiments = 15 rows cover all 2 x 3 x 2 x 5 x 2 = 120 combinations' pairs
    assert len(pairwise(AXIS_SETS["safety"])) == 15


def test_one_axis_is_its_values_and_an_empty_axis_is_refused() -> None:
    assert pairwise([["a", "b"]]) == [("a",), ("b",)]
    with pytest.raises(ValueError, match="at least one value"):
        pairwise([["a"], []])


def _names(case: Any) -> set[str]:
    return {m.name for m in case.marks}


def test_matrix_params_are_the_covering_set_at_two_seeds_and_the_marked_full_product() -> None:
    axes = AXIS_SETS["safety"]
    cases = matrix_params(axes, marks={"generated-c": pytest.mark.needs_cc})
    cover = [c for c in cases if c.id.startswith("cover-")]
    full = [c for c in cases if c.id.startswith("full-")]
    assert len(cover) + len(full) == len(cases)
    assert [tuple(c.values) for c in cover] == [
        (*row, seed) for row in pairwise(axes) for seed in COVER_SEEDS
    ]
    product = set(itertools.product(*axes, VERIFY_SEEDS))
    assert {tuple(c.values) for c in full} == product and len(full) == len(product)
    assert len(full) == 120 * 50
    assert all("verify" in _names(c) for c in full)
    assert not any("verify" in _names(c) for c in cover)  # make test runs these
    for c in cases:  # the compiler mark on exactly the cases that need one
        assert ("needs_cc" in _names(c)) == ("generated-c" in c.values), c.id
    assert len({c.id for c in cases}) == len(cases)  # ids unique: each case selectable


def test_a_rotated_product_runs_each_later_row_once_with_the_leading_combinations_in_turn() -> None:
    axes = (("a", "b"), ("x", "y"), (1, 2, 3), (True, False))
    rows = rotated_product(axes, 2)
    later = list(itertools.product(*axes[2:]))
    assert [row[2:] for row in rows] == later  # every later row once, in product order
    lead = list(itertools.product(*axes[:2]))
    assert [row[:2] for row in rows] == [lead[r % 4] for r in range(len(later))]
    assert set(rows) <= set(itertools.product(*axes))
    cases = matrix_params(axes, full_rows=rows, verify_seeds=(7,))
    assert [tuple(c.values) for c in cases if c.id.startswith("full-")] == [
        (*row, 7) for row in rows
    ]
