"""How one force-controlled axis of a run ended, in words defined once.

``fuzzkit simulate`` (text and ``--json``), ``compare``, ``tune``, the run figure and the
report say *never settled*, *no contact* and *tripped* with these words and mean the same
thing by them; a settling time of None is never printed as ``-``, which would say none of
them.

* :data:`TRIPPED`: the run tripped the safety limit (the controller stopped and retreated;
  what follows says nothing about settling).
* :data:`NO_CONTACT`: the tool never touched anything, so there was nothing to settle.
* :data:`NEVER_SETTLED`: in contact, but the force was outside the settling band at the end.
* :data:`SETTLED`: in the band at the end (the settling time says since when).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

SETTLED = "settled"
NEVER_SETTLED = "never settled"
NO_CONTACT = "no contact"
TRIPPED = "tripped"
#: Every outcome, in order of precedence (a tripped run is "tripped" whatever else holds).
OUTCOMES = (TRIPPED, NO_CONTACT, NEVER_SETTLED, SETTLED)


def axis_outcome(metrics: Mapping[str, Any], tripped: bool) -> str:
    """The outcome of one axis from its metrics (``fuzzkit.studies.metrics.axis_metrics``:
    ``contact_lost_s`` is None only when the run never touched anything) and the run's trip."""
    if tripped:
        return TRIPPED
    if metrics.get("settling_time_s") is not None:
        return SETTLED
    return NO_CONTACT if metrics.get("contact_lost_s") is None else NEVER_SETTLED


def settling_text(metrics: Mapping[str, Any], tripped: bool, digits: int = 2) -> str:
    """The settling time as printed: ``0.12 s``, or the outcome's word when there is none
    (or when the run tripped)."""
    outcome = axis_outcome(metrics, tripped)
    value = metrics.get("settling_time_s")
    if outcome != SETTLED or value is None:
        return outcome
    return f"{value:.{digits}f} s"
