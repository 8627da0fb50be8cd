"""The shipped ``sugeno_pi`` rule base worked by hand (shared by the engine and codegen tests).

Memberships and consequents are written out here, not taken from fuzzkit.
"""

from __future__ import annotations


def _part(x: float) -> tuple[float, float, float]:
    x = min(max(x, -1.0), 1.0)
    return max(0.0, -x), 1 - abs(x), max(0.0, x)


def sugeno_pi_by_hand(e: float, de: float) -> float:
    """The shipped rule base, one rule at a time; product AND makes the weights sum to 1."""
    ec, dc = min(max(e, -1.0), 1.0), min(max(de, -1.0), 1.0)
    gentle, firm, hold = 0.2 * ec + 0.5 * dc, 0.6 * ec + 1.0 * dc, 0.0
    table = [[firm, gentle, gentle], [gentle, hold, gentle], [gentle, gentle, firm]]
    me, md = _part(e), _part(de)
    return sum(me[i] * md[j] * table[i][j] for i in range(3) for j in range(3))
