"""Where a certificate holds: the largest level set of its Lyapunov function inside the region
where the model's bounds are valid, and the force deviation it allows (``region_n``).

The loop model (:mod:`fuzzkit.analysis.loop_model`) is exact only while

* the contact stays in its sector: the spring-damper force deviation ``d`` from the rest force
  ``f0`` keeps ``d >= -f0 / sigma_min`` (``[sigma_min, 1]``; ``d >= -f0`` with contact held), so
  ``max(0, f0 + d) - f0 = sigma d`` with ``sigma`` in the sector;
* the fuzzy-PI's inputs stay in the box its surface was bounded on: ``|Ki (e - e0)| <= rho``
  and ``|Kp de| <= rho`` (:mod:`fuzzkit.analysis.fuzzy_bounds`; none for PI).

Each is a linear function of the state ``h' x`` bounded by ``b``, at every vertex of the
parameter box (the rows of :func:`fuzzkit.analysis.loop_model.vertex_rows`). ``V = x' P x``
decreases along every trajectory that stays there, so the level set ``V <= gamma`` with

    gamma = min_i b_i^2 / (h_i' P^-1 h_i)

(the largest ellipsoid ``V <= gamma`` inside every slab ``|h_i' x| <= b_i``) is invariant: a
trajectory starting in it never leaves it and converges to the rest point. ``region_n`` states it
in newtons: the largest ``|d|`` for which the state "at rest, every force and correction ``d``
away from the rest point" (all states equal to ``d``: positions, samples and corrections are
kept in newtons) is in the level set, ``sqrt(gamma / (1' P 1))``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.analysis.loop_model import AxisLoop, vertex_rows

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Slab:
    """``|h' x| <= bound``: one validity condition of the model at one vertex."""

    h: FloatArray
    bound: float
    what: str


@dataclass(frozen=True, slots=True)
class LevelSet:
    """The invariant level set ``x' P x <= gamma`` and the condition that limits it."""

    gamma: float
    region_n: float
    limited_by: str


def validity_slabs(
    loop: AxisLoop,
    rest_force_n: float,
    fuzzy_box: tuple[float, float, float] | None = None,
    limits_m: tuple[float, float] | None = None,
) -> list[Slab]:
    """The model's validity conditions as slabs, at every vertex of ``loop``'s box.

    ``rest_force_n``: the contact force at the rest point (N, > 0). ``fuzzy_box``:
    ``(rho, ki, kp)`` with the fuzzy-PI's input scaling ``ki``, ``kp`` (per N, per N per
    period) and the half-width ``rho`` of the box its surface was bounded on. ``limits_m``:
    a spec's ``(step_m, correction_m)``: the model holds while no limit clips, ``|du| <=
    step_m`` and ``|u| <= correction_m`` (the correction at rest taken as at most the rest
    indentation ``rest_force_n / k``, the path being held once the loop engages).
    """
    k = loop.stiffness_n_per_m
    slabs: list[Slab] = []
    seen: set[bytes] = set()
    for rows in vertex_rows(loop):
        candidates = [(rows.spring_next, rest_force_n / loop.sigma_min, "contact sector")]
        if fuzzy_box is not None:
            rho, ki, kp = fuzzy_box
            candidates.append((rows.c_next, rho / ki, "fuzzy region (error)"))
            candidates.append((rows.c_next - rows.c_now, rho / kp, "fuzzy region (change)"))
        if limits_m is not None:
            step_m, correction_m = limits_m
            candidates.append((rows.u_next - rows.u_now, k * step_m, "step limit"))
            room = max(k * correction_m - rest_force_n, 0.0)
            candidates.append((rows.u_now, room, "correction limit"))
        for h, bound, what in candidates:
            key = np.round(h, 15).tobytes() + what.encode()
            if key not in seen:
                seen.add(key)
                slabs.append(Slab(h, bound, what))
    return slabs


def level_set(p: FloatArray, slabs: Sequence[Slab]) -> LevelSet:
    """The largest ``x' P x <= gamma`` inside every slab, and its ``region_n``."""
    p = 0.5 * (p + p.T)
    p_inv = np.linalg.inv(p)
    best, limit = math.inf, ""
    for slab in slabs:
        reach = float(slab.h @ p_inv @ slab.h)  # max of (h' x)^2 over x' P x <= 1
        if reach <= 0.0:
            continue
        if slab.bound <= 0.0:
            return LevelSet(0.0, 0.0, slab.what)
        g = slab.bound**2 / reach
        if g < best:
            best, limit = g, slab.what
    ones = np.ones(p.shape[0])
    return LevelSet(best, math.sqrt(best / float(ones @ p @ ones)), limit)
