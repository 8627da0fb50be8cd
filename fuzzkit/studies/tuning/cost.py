"""The tuning cost of one closed-loop run (formula and reasons: :mod:`fuzzkit.studies.tuning`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fuzzkit.loop.result import RunResult


@dataclass(frozen=True, slots=True)
class CostWeights:
    """Weights of the penalty terms of :func:`run_cost` (the ITAE term has weight 1)."""

    overshoot: float = 0.5
    peak: float = 2.0
    trip: float = 1.0
    contact_loss: float = 2.0
    none: float = 10.0


def run_itae(result: RunResult) -> float:
    """The normalised ITAE of a run from its first contact on (:mod:`fuzzkit.studies.tuning`:
    ``sum_axes integral (t - t0) |f_d - f| dt / (F * T^2 / 2)``, the true force); NaN for a run
    without contact, with non-finite forces or of no duration in contact."""
    exp = result.experiment
    contact = np.nonzero(result.in_contact)[0]
    if len(contact) == 0 or not np.all(np.isfinite(result.force_true)):
        return math.nan
    i0 = int(contact[0])
    t = result.t[i0:]
    span = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    if span <= 0.0:
        return math.nan
    axes = [i for i in range(3) if exp.selection[i]]
    scale = max([abs(float(exp.setpoints[i])) for i in axes] + [1.0])
    dt = float(exp.scenario.period_s)
    tau = t - t[0]
    itae = 0.0
    for i in axes:
        f = result.force_true[i0:, i]
        itae += (
            float(np.sum(tau * np.abs(float(exp.setpoints[i]) - f)))
            * dt
            / (scale * 0.5 * span * span)
        )
    return itae


def run_cost(result: RunResult, weights: CostWeights = CostWeights()) -> float:
    """The tuning cost of one closed-loop run (module docstring: formula and reasons).

    Parameters
    ----------
    result : a run from ``fuzzkit.studies.experiments.run``.
    weights : penalty weights.

    Returns
    -------
    The cost (>= 0); ``weights.none`` for a run without contact or with non-finite forces.
    """
    exp = result.experiment
    itae = run_itae(result)
    if math.isnan(itae):
        return weights.none
    i0 = int(np.nonzero(result.in_contact)[0][0])
    t = result.t[i0:]
    overshoot = 0.0
    for i in (i for i in range(3) if exp.selection[i]):
        sp = float(exp.setpoints[i])
        f = result.force_true[i0:, i]
        if sp != 0.0:
            overshoot += max(0.0, float(np.max((f - sp) * math.copysign(1.0, sp)))) / abs(sp)
    peak = float(np.max(np.abs(result.force_true[i0:])))
    excess = max(0.0, peak - exp.force_limit_n) / exp.force_limit_n
    loss = float(np.count_nonzero(~result.in_contact[i0:])) / len(t)
    cost = (
        itae
        + weights.overshoot * overshoot
        + weights.peak * excess
        + weights.trip * float(result.tripped)
        + weights.contact_loss * loss
    )
    return cost if math.isfinite(cost) else weights.none
