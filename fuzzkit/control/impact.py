"""The approach speed above which the impact alone passes a spec's safety limit.

No controller acts on a contact before it has seen it. Let the first sample above the
engagement threshold be the force of period ``i0`` (the contact started during it or the period
before). The loop engages on the ``engage_samples``-th such sample (on the first when it is
engaged from the start), seen ``latency_in`` periods late; its first correction reaches the robot
``1 + latency_out`` periods after that, at period ``i0 + engage + latency_in + latency_out``.
Until then the tool keeps its approach speed ``v``: at period ``i0 + m`` with

    m = engage - 1 + latency_in + latency_out

the penetration is more than ``m * v * period`` and the force more than ``k * v * m * period``,
whatever the controller does (an actuator that retracts at once included; a robot's inner
motion loop only adds to it). On the stiffest contact the spec declares (its stiffness
schedule's ``range_n_mm``, ``k_max``) that passes the safety limit when

    v > limit_n / (k_max * m * period)          (the impact speed)

A spec without a schedule declares no ``k_max``: no impact speed. ``m = 0`` (engaged from the
start, no latency): no finite one. :func:`impact_speed_for` is that speed for any force, stiffness
and reaction time: the regulation task's approach speed and the report's impact limit are it too.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import Protocol

from fuzzkit.control.spec import ControllerSpec


class Waypoint(Protocol):
    """A point of a nominal path (``fuzzkit.plants.environment.Waypoint``): time and position."""

    @property
    def t_s(self) -> float: ...
    @property
    def x(self) -> float: ...
    @property
    def y(self) -> float: ...
    @property
    def z(self) -> float: ...


def impact_speed_for(force_n: float, stiffness_n_per_m: float, reaction_s: float) -> float:
    """The approach speed (m/s) at which a contact of ``stiffness_n_per_m`` reaches ``force_n``
    before anything reacts: the tool keeps its speed ``v`` for ``reaction_s`` after touching, so
    the force reaches ``stiffness * v * reaction_s``. Infinite for no reaction time; 0 for no
    force (a negative one counts as none)."""
    if reaction_s <= 0.0:
        return math.inf
    return max(force_n, 0.0) / (stiffness_n_per_m * reaction_s)


def reaction_periods(spec: ControllerSpec, latency_periods: int) -> int:
    """``m``: the whole periods of approach, after the first sample above the engagement
    threshold, that no correction can shorten."""
    engage = spec.safety.engage_samples if spec.safety.engage_threshold_n is not None else 1
    return engage - 1 + latency_periods


def impact_speed(spec: ControllerSpec, latency_periods: int | None = None) -> float | None:
    """The impact speed (m/s) of ``spec`` at ``latency_periods`` (sensor + command; None: the
    latency its estimator's delay assumes, ``delay_periods - 1``); None without a schedule."""
    ad = spec.adaptation
    if ad.mode != "stiffness-scheduled":
        return None
    est = ad.estimator
    latency = est.delay_periods - 1 if latency_periods is None else latency_periods
    m = reaction_periods(spec, latency)
    return impact_speed_for(spec.safety.limit_n, est.k_max_n_mm * 1e3, m * spec.period_s)


def impact_warning(
    spec: ControllerSpec, approach_m_s: float, latency_periods: int, where: str
) -> str | None:
    """The warning for a path approaching contact at ``approach_m_s``, or None when it is not
    faster than the impact speed (or the spec declares no ``k_max``)."""
    v = impact_speed(spec, latency_periods)
    if v is None or approach_m_s <= v:
        return None
    k_max = spec.adaptation.estimator.k_max_n_mm
    return (
        f"{where} approaches contact at {approach_m_s * 1e3:.3g} mm/s, faster than "
        f"{v * 1e3:.3g} mm/s: at the spec's k_max {k_max:g} N/mm and latency "
        f"{latency_periods} periods the impact alone passes the {spec.safety.limit_n:g} N "
        f"safety limit before any correction acts; no controller claim is made for this path"
    )


def path_approach_speed(path: Sequence[Waypoint], selection: Sequence[bool]) -> float:
    """The fastest the nominal path moves along a force-controlled axis (m/s), over its
    segments (the path's coordinates: the shipped tasks' task frame is the base frame)."""
    fastest = 0.0
    for w0, w1 in itertools.pairwise(path):
        dt = w1.t_s - w0.t_s
        if dt <= 0.0:
            continue
        moves = (w1.x - w0.x, w1.y - w0.y, w1.z - w0.z)
        for axis, d in enumerate(moves):
            if selection[axis]:
                fastest = max(fastest, abs(d) / dt)
    return fastest
