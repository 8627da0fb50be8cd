"""How one force-controlled axis of a run ended, in words defined once.

``fuzzkit simulate`` (text and ``--json``), ``compare``, ``tune``, the run figure and the
report (its certified-region table too) say *never settled*, *no contact* and *tripped* with
these words and mean the same thing by them; a settling time of None is never printed as
``-``, which would say none of them.

* :data:`TRIPPED`: the run tripped the safety limit (the controller stopped and retreated;
  what follows says nothing about settling).
* :data:`NO_CONTACT`: the tool never touched anything, so there was nothing to settle.
* :data:`NEVER_SETTLED`: in contact, but the force was outside the settling band at the end.
* :data:`SETTLED`: in the band at the end (the settling time says since when).

A whole run's end state (:func:`end_state`), which the stability certificate's simulated check
and the latency sweep judge by, uses the same words and one more:

* :data:`SETTLED`: not tripped, and over the last :data:`TAIL_S` the true force on every
  force-controlled axis has its mean within :data:`BAND_N` of the set point and its standard
  deviation below it;
* :data:`OSCILLATING`: neither tripped nor settled;
* :data:`TRIPPED`: as above.

Beside them, for the whole run, :data:`LIMIT_EXCEEDED`: the true contact force passed the
safety limit (:func:`limit_exceeded`), tripped or not.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fuzzkit.loop.result import RunResult

SETTLED = "settled"
NEVER_SETTLED = "never settled"
NO_CONTACT = "no contact"
TRIPPED = "tripped"
OSCILLATING = "oscillating"
#: Every outcome, in order of precedence (a tripped run is "tripped" whatever else holds).
OUTCOMES = (TRIPPED, NO_CONTACT, NEVER_SETTLED, SETTLED)
#: Every end state of a run (:func:`end_state`), from best to worst.
END_STATES = (SETTLED, OSCILLATING, TRIPPED)
#: The settling band of a run's end state (N): a settled force has its mean within it of the
#: set point and its standard deviation below it (the sensor noise is 0.1 N).
BAND_N = 0.5
#: The end of the run the band is judged on (s).
TAIL_S = 0.5
#: A run whose *true* contact force passed the safety limit, whether or not the controller
#: saw it (:func:`limit_exceeded`); said beside the axes' outcomes, and ``--fail-on-trip``
#: fails on it as on a trip.
LIMIT_EXCEEDED = "limit exceeded"


def limit_exceeded(
    t: Sequence[float] | Any, force_true: Any, limit_n: float
) -> dict[str, Any] | None:
    """When and how far the true contact force (any axis, ``(n, 3)``) passed ``limit_n``:
    ``{"time_s": first period above, "peak_true_n": largest |force|, "axis": its axis}``,
    or None when it never did. Computed from the plant's force, not the sensor's: a delayed,
    filtered or gated sample can hide a force that the robot and the part did feel."""
    import numpy as np

    f = np.abs(np.asarray(force_true, dtype=np.float64))
    if f.size == 0:
        return None
    over = np.nanmax(f, axis=1) > limit_n
    if not over.any():
        return None
    k, axis = np.unravel_index(int(np.nanargmax(f)), f.shape)
    return {
        "time_s": float(np.asarray(t)[int(np.argmax(over))]),
        "peak_true_n": float(f[k, axis]),
        "axis": "xyz"[int(axis)],
    }


def limit_text(exceeded: Mapping[str, Any] | None, limit_n: float, tripped: bool) -> str:
    """The words for :func:`limit_exceeded`: ``limit exceeded: 400 N true (x) at 1.87 s, limit
    25 N; the controller did not trip`` (empty when the limit held)."""
    if exceeded is None:
        return ""
    seen = "the controller tripped" if tripped else "the controller did not trip"
    return (
        f"{LIMIT_EXCEEDED}: {exceeded['peak_true_n']:.1f} N true ({exceeded['axis']}) from "
        f"{exceeded['time_s']:.3f} s, limit {limit_n:g} N; {seen}"
    )


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


def end_state(result: RunResult) -> str:
    """:data:`SETTLED`, :data:`OSCILLATING` or :data:`TRIPPED`: how the whole run ended (the
    module docstring)."""
    import numpy as np

    if result.tripped:
        return TRIPPED
    exp = result.experiment
    tail = result.t >= result.t[-1] - TAIL_S
    for axis in range(3):
        if not exp.selection[axis]:
            continue
        f = result.force_true[tail, axis]
        sp = float(exp.setpoints[axis])
        if not (abs(float(np.mean(f)) - sp) < BAND_N and float(np.std(f)) < BAND_N):
            return OSCILLATING
    return SETTLED
