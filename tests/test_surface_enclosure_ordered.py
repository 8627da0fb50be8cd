"""``surface_enclosure._ordered``: which output term is the largest clipped term in a bin, once
the order of the levels is known (min implication). Checked against the definitions on point
intervals, where the truth is a plain max of ``min(L_t, C_t)``."""

from __future__ import annotations

import numpy as np

from fuzzkit.analysis.intervals import Interval
from fuzzkit.analysis.surface_enclosure import _ordered

# two terms, three bins; L_0 = 0.6 > L_1 = 0.3 > 0 is known
LEVELS = np.array([[0.6, 0.3]])
TERMS = np.array([[1.0, 0.4, 0.0], [0.2, 0.9, 1.0]])  # C_t on each bin (point values)
ORDER = np.array([[[True, True], [False, True]]])  # order[:, s, t]: L_s > L_t (diagonal: > 0)


def _truth() -> tuple[np.ndarray, np.ndarray]:
    """Per (t, bin): t's clipped value is the largest, and t is clipped there (C_t > L_t)."""
    clipped_values = np.minimum(LEVELS[0][:, None], TERMS)
    top = clipped_values == clipped_values.max(axis=0)
    return top, top & (LEVELS[0][:, None] < TERMS)


def _settle(order: np.ndarray, spread: float) -> tuple[np.ndarray, np.ndarray]:
    """``_ordered`` from nothing known (every term possible, none sure) with the terms' values
    and the clipped values widened by ``spread``."""
    p = np.minimum(LEVELS[:, :, None], TERMS[None])
    can, sure = _ordered(
        np.ones((1, 2, 3), dtype=bool),
        np.zeros((1, 2, 3), dtype=bool),
        order,
        Interval.point(LEVELS),
        Interval(TERMS - spread, TERMS + spread),
        p - spread,
        p + spread,
    )
    return can[0], sure[0]


def test_the_known_order_decides_the_largest_and_the_clipped_term() -> None:
    can, sure = _settle(ORDER, 0.0)
    top, clipped_top = _truth()
    # sound: the true largest term stays possible, and "surely clipped" is never wrong
    assert np.all(can | ~top)
    assert np.all(~sure | clipped_top)
    # by hand: L_0 > L_1 and C_0 >= L_1 on bins 0 and 1, so term 1 is beaten there (bin 2,
    # where C_0 = 0, stays open to both: ruling term 0 out is the caller's test of the values)
    assert can.tolist() == [[True, True, True], [False, False, True]]
    # term 0 is clipped on bin 0 and above term 1 (known); term 1 is clipped on bin 2, where
    # term 0 is 0 and L_1 > 0: exactly the truth on point values
    assert np.array_equal(sure, clipped_top)


def test_without_a_known_order_nothing_is_settled() -> None:
    can, sure = _settle(np.zeros((1, 2, 2), dtype=bool), 0.5)
    assert can.all()
    assert not sure.any()
