"""The certificate of an adaptive spec: its gain factor bounded per stiffness, the estimate's
error bounded by ``rho``, one quadratic Lyapunov function per cell over every factor the
adaptation can run there, so that the factor may switch from one period to the next (no dwell).

The true stiffness ``k`` and its estimate ``k_hat`` are independent parameters: ``k`` is the
cell's, ``k_hat / k`` anywhere in ``[1 - rho, 1 + rho]``, projected into the estimator's
``[k_min, k_max]`` as the estimator projects it. The adaptation multiplies the axis's increment
by a factor ``s``, and the loop's model (:mod:`fuzzkit.analysis.loop_model`) is affine in that
factor (it multiplies ``phi``, the gain interval of the controller): so bounding ``s`` over
everything the adaptation can select at ``k`` by an interval ``[s_lo, s_hi]``
(:func:`scale_interval`) and certifying the cell on the interval's vertices proves the loop
stable for any sequence of factors in it. For a stiffness schedule the factors at ``k`` are
the scales of every band that meets the estimate's interval, the band of ``k_max`` (the safe
start: an untrusted estimate) and the most conservative band (a reading beyond ``k_max``); for
the 1/k schedule, ``min(1, k_0 / k_hat)`` from ``k_max`` to the estimate's lower end (it falls
with the estimate); for the self-tuning factor, ``[alpha_min, alpha_max]`` at every stiffness.

What it does not cover: ``k`` itself changing during contact (the cell's states are scaled by
``k``; a stiffness step is outside the model), stiffnesses between the grid's cells, and
whether the estimator meets ``rho`` (measured, ``fuzzkit.analysis.estimator_loop``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from fuzzkit.control.adaptation_spec import Adaptation

#: The estimate's error the certificate assumes by default: ``k_hat / k`` in ``[0.5, 1.5]``,
#: which holds when the estimate ends within a factor 1.5 above and 2 below the truth (issue
#: 42's closed-loop target is a factor 1.5 either way).
DEFAULT_RHO = 0.5
#: The estimate errors tried, largest first, to say which a refused schedule would need.
RHO_STEPS = (0.5, 0.3, 0.2, 0.1, 0.05, 0.0)


def estimate_interval(ad: Adaptation, k_n_mm: float, rho: float) -> tuple[float, float]:
    """The estimates (N/mm) a true stiffness ``k_n_mm`` admits: ``k (1 -+ rho)``, projected
    into the estimator's range."""
    est = ad.estimator
    lo = min(max(k_n_mm * (1.0 - rho), est.k_min_n_mm), est.k_max_n_mm)
    hi = min(max(k_n_mm * (1.0 + rho), est.k_min_n_mm), est.k_max_n_mm)
    return lo, hi


def scale_interval(ad: Adaptation, k_n_mm: float, rho: float) -> tuple[float, float]:
    """The interval of every factor ``ad`` can run at the true stiffness ``k_n_mm`` with an
    estimate within ``rho`` (see the module); ``(1, 1)`` without adaptation."""
    if ad.mode == "self-tuning":
        return ad.alpha_min, ad.alpha_max
    if ad.mode != "stiffness-scheduled":
        return 1.0, 1.0
    lo, hi = estimate_interval(ad, k_n_mm, rho)
    if ad.inverse_n_mm is not None:
        # decreasing in the estimate; k_max's until trusted and beyond k_max
        return ad.inverse_factor(ad.estimator.k_max_n_mm), ad.inverse_factor(lo)
    bands = set(range(ad.band_of(lo), ad.band_of(hi) + 1))
    bands |= {ad.safe_band(), ad.floor_band()}
    scales = [ad.bands[b].scale for b in sorted(bands)]
    return min(scales), max(scales)


def scale_function(ad: Adaptation, rho: float) -> Callable[[float], tuple[float, float]]:
    """:func:`scale_interval` at each stiffness (N/mm), for ``certify_region``'s
    ``gain_scale``."""
    return lambda k_n_mm: scale_interval(ad, k_n_mm, rho)


def adaptation_model(
    ad: Adaptation, rho: float, stiffnesses_n_per_mm: Sequence[float]
) -> dict[str, Any]:
    """What the certificate assumed of the adaptation, for the region's JSON."""
    out: dict[str, Any] = {
        "mode": ad.mode,
        "gain_factor_per_stiffness": {
            f"{k:g}": list(scale_interval(ad, k, rho)) for k in stiffnesses_n_per_mm
        },
        "switching": "arbitrary from one period to the next (no dwell): one quadratic "
        "Lyapunov function per cell over the factor interval's vertices",
        "not_covered": ["the true stiffness changing during contact", "the estimator's rho"],
    }
    if ad.mode == "stiffness-scheduled":
        est = ad.estimator
        out |= {
            "rho": rho,
            "estimate_over_true": [1.0 - rho, 1.0 + rho],
            "range_n_mm": [est.k_min_n_mm, est.k_max_n_mm],
            "safe_band": ad.safe_band(),
            "floor_band": ad.floor_band(),
            "inverse_n_mm": ad.inverse_n_mm,
        }
    return out
