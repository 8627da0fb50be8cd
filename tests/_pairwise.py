"""A covering set of a test matrix: every pair of values of any two axes in at least one row.

``make test`` runs this set of each deep matrix (the experiment x controller x fault x plant x
implementation product of ``tests/test_safety.py``, say) and ``make verify`` the full product.
A bug that needs one setting, or the meeting of two settings, shows in the covering set; only
a bug that needs three or more at once can wait for ``make verify``.

The construction is greedy (in the manner of AETG, without its randomness, so that the rows and
hence the test ids are the same on every machine): while a pair is uncovered, a new row starts
from the first uncovered pair, and each remaining axis, in order, takes the value that covers
the most uncovered pairs with the values already chosen (the first such value on a tie).
"""

from __future__ import annotations

import itertools
from collections.abc import Hashable, Mapping, Sequence
from typing import Any

import pytest

Row = tuple[Hashable, ...]


def _pairs(row: Sequence[Hashable]) -> set[tuple[int, Hashable, int, Hashable]]:
    return {(i, row[i], j, row[j]) for i, j in itertools.combinations(range(len(row)), 2)}


def pairwise(axes: Sequence[Sequence[Hashable]]) -> list[Row]:
    """Rows (one value per axis, in the axes' order) covering every pair of values of any two
    axes, and so every value of every axis.

    Deterministic: the same axes give the same rows in the same order. Fewer than two axes:
    every value of the one axis (or the one empty row), which is the full product.
    """
    if any(len(values) == 0 for values in axes):
        raise ValueError("every axis needs at least one value")
    if len(axes) < 2:
        return [tuple(row) for row in itertools.product(*axes)]
    uncovered = {
        (i, a, j, b)
        for i, j in itertools.combinations(range(len(axes)), 2)
        for a in axes[i]
        for b in axes[j]
    }
    order = sorted(
        uncovered, key=lambda p: (p[0], p[2], axes[p[0]].index(p[1]), axes[p[2]].index(p[3]))
    )
    rows: list[Row] = []
    while uncovered:
        i, a, j, b = next(p for p in order if p in uncovered)
        chosen: dict[int, Hashable] = {i: a, j: b}
        for k in range(len(axes)):
            if k in chosen:
                continue
            # the value of axis k that covers the most uncovered pairs with the chosen values
            chosen[k] = max(
                axes[k],
                key=lambda v: sum(
                    ((m, chosen[m], k, v) if m < k else (k, v, m, chosen[m])) in uncovered
                    for m in chosen
                ),
            )
        row = tuple(chosen[k] for k in range(len(axes)))
        uncovered -= _pairs(row)
        rows.append(row)
    return rows


#: The mark of a deep test case: ``make verify`` selects it (``-m verify``), ``make test``
#: deselects it (``-m "not verify"``) and runs the covering set instead.
verify = pytest.mark.verify
#: The seeds each covering row runs with in ``make test``.
COVER_SEEDS = (0, 1)
#: The seeds of the full product in ``make verify``.
VERIFY_SEEDS = tuple(range(50))


def rotated_product(axes: Sequence[Sequence[Hashable]], inner: int) -> list[Row]:
    """Every row of the product of ``axes[inner:]`` once, each with one combination of the
    first ``inner`` axes, taken in turn (product order): a fraction of the full product for a
    matrix whose first axes act on a stage the later axes do not reach (the firing strengths
    against the output stage, say). Which combinations of the later axes each leading
    combination meets depends on the axes' lengths: the caller states and checks it.
    """
    lead = list(itertools.product(*axes[:inner]))
    return [
        (*lead[r % len(lead)], *rest) for r, rest in enumerate(itertools.product(*axes[inner:]))
    ]


def matrix_params(
    axes: Sequence[Sequence[Hashable]],
    cover_seeds: Sequence[int] = COVER_SEEDS,
    verify_seeds: Sequence[int] = VERIFY_SEEDS,
    marks: Mapping[Hashable, pytest.MarkDecorator] | None = None,
    full_rows: Sequence[Row] | None = None,
) -> list[Any]:
    """The cases of a matrix test, each ``(*row, seed)``: the covering set
    (:func:`pairwise`) at ``cover_seeds``, ids ``cover-...``, and the full product of the
    axes (or ``full_rows``, a trimmed set such as :func:`rotated_product`) at
    ``verify_seeds``, marked :data:`verify`, ids ``full-...``.

    ``marks`` adds a mark to every case holding a value (``{"generated-c": needs_cc}``).
    """
    marks = marks or {}
    rows = list(itertools.product(*axes)) if full_rows is None else full_rows

    def case(kind: str, row: Sequence[Hashable], seed: int, *extra: pytest.MarkDecorator) -> Any:
        own = [marks[v] for v in row if v in marks]
        name = "-".join(str(v) for v in (kind, *row, seed))
        return pytest.param(*row, seed, marks=[*own, *extra], id=name)

    cover = [case("cover", row, s) for row in pairwise(axes) for s in cover_seeds]
    full = [case("full", row, s, verify) for row in rows for s in verify_seeds]
    return cover + full
