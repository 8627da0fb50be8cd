"""Evenly spaced triangular partitions: the ``partition: triangular`` shorthand as terms."""

from __future__ import annotations

from collections.abc import Sequence

from fuzzkit.fuzzy.model import Term

#: Partition kinds the shorthand knows, and how its outer terms end.
PARTITION_KINDS = ("triangular",)
PARTITION_ENDS = ("shoulder", "triangle")


def partition_terms(labels: Sequence[str], low: float, high: float, ends: str) -> tuple[Term, ...]:
    """The terms of a ``partition: triangular`` shorthand over ``[low, high]``.

    Label ``k`` of ``n`` peaks at ``((n-1-k)*low + k*high)/(n-1)``, the outer labels at
    ``low`` and ``high`` themselves, and falls to 0 at its neighbours' peaks: each foot *is* the
    neighbouring peak (the same double), so at a label peak every other term is exactly 0 (the
    slopes are rounded for that, see :mod:`fuzzkit.fuzzy.membership`). With
    ``ends="shoulder"`` the outer terms are shoulders (1 up to / from the range end); with
    ``ends="triangle"`` they are triangles centred on the range ends reaching one spacing
    beyond (clipped by the range at inference).
    """
    n = len(labels)
    step = (high - low) / (n - 1)
    # Weighted means, not low + k*step: mirror-symmetric, so a range symmetric about 0 puts the
    # middle peak exactly on 0 (and symmetric rule bases give exactly 0 there, not rounding
    # noise). The ends are the range ends themselves: (n-1)*low/(n-1) can be a double off, and
    # then an input at the range end (or clamped to it) sits beside the end peak, inside the
    # next term's foot.
    inner = [((n - 1 - k) * low + k * high) / (n - 1) for k in range(1, n - 1)]
    peaks = [low, *inner, high]
    terms: list[Term] = []
    for k, label in enumerate(labels):
        left = peaks[k - 1] if k > 0 else low - step
        right = peaks[k + 1] if k < n - 1 else high + step
        if ends == "shoulder" and k == 0:
            terms.append(Term(label, "left_shoulder", (low, right)))
        elif ends == "shoulder" and k == n - 1:
            terms.append(Term(label, "right_shoulder", (left, high)))
        else:
            terms.append(Term(label, "triangle", (left, peaks[k], right)))
    return tuple(terms)
