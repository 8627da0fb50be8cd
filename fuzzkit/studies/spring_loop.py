"""A one-axis spring contact whose stiffness can change mid-contact, closed around a controller.

A small, exact test bench for adaptation (issue 24): the tool approaches a surface along the
task z axis at ``approach_m_s`` (the nominal path), the controller's correction ``u`` is added
to it, and the contact force is a spring with no damping, ``f = f_s + k(t) * (p - p_s)`` on the
penetration ``p > 0``, where ``(p_s, f_s)`` is where the stiffness last changed: the force is
continuous when ``k`` steps (a soft layer over a hard one, or a tool moving onto steel). The
sign convention is the plant contract's (``fuzzkit.plants.contract``): a positive correction
moves into the surface and raises the force. Latency: the controller sees the force
``latency_in`` periods late, and its correction acts ``1 + latency_out`` periods after it is
computed. Noise: Gaussian, seeded; ``spikes`` adds single-sample spikes; ``drop`` NaN samples.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
#: ``step(force_n[3]) -> (correction_m[3], status)``: any controller (reference, generated).
Step = Callable[[list[float]], tuple[list[float], int]]


@dataclass(frozen=True)
class SpringBench:
    """The bench: stiffness schedule ``[(t_s, k_n_mm), ...]`` (the first entry at t = 0)."""

    stiffness: tuple[tuple[float, float], ...] = ((0.0, 5.0),)
    duration_s: float = 2.0
    period_s: float = 0.004
    start_gap_m: float = 2.0e-4
    approach_m_s: float = 2.0e-4
    stop_s: float | None = 1.5
    latency_in: int = 0
    latency_out: int = 0
    noise_std_n: float = 0.1
    spikes: Sequence[int] = field(default_factory=tuple)
    spike_n: float = 40.0
    drop: Sequence[int] = field(default_factory=tuple)
    seed: int = 0


@dataclass(frozen=True)
class SpringRun:
    """Per period: the true force (N), the sample the controller got, its correction z (m),
    its status, and the true stiffness (N/mm)."""

    force_n: FloatArray
    measured_n: FloatArray
    u_m: FloatArray
    status: npt.NDArray[np.int64]
    k_n_mm: FloatArray


def stiffness_at(bench: SpringBench, t: float) -> float:
    """The true stiffness (N/mm) at time ``t``."""
    k = bench.stiffness[0][1]
    for t_s, value in bench.stiffness:
        if t >= t_s:
            k = value
    return k


def run_spring(bench: SpringBench, step: Step) -> SpringRun:
    """Close the loop for ``bench.duration_s``; every period one controller ``step``."""
    n = round(bench.duration_s / bench.period_s)
    rng = np.random.default_rng(bench.seed)
    noise = rng.normal(0.0, bench.noise_std_n, n)
    force = np.zeros(n)
    measured = np.zeros(n)
    u_out = np.zeros(n)
    status = np.zeros(n, dtype=np.int64)
    k_true = np.zeros(n)
    pending = [0.0] * (bench.latency_out + 1)  # corrections on their way to the robot
    k_now = stiffness_at(bench, 0.0)
    p_s, f_s = 0.0, 0.0  # where the stiffness last changed (penetration m, force N)
    spikes, drop = set(bench.spikes), set(bench.drop)
    for i in range(n):
        t = i * bench.period_s
        applied = pending.pop(0)
        moving = t if bench.stop_s is None else min(t, bench.stop_s)
        p = bench.approach_m_s * moving - bench.start_gap_m + applied
        k = stiffness_at(bench, t)
        if k != k_now:
            # the force is continuous where the stiffness changes
            if p > 0.0:
                f_s, p_s = max(f_s + k_now * 1000.0 * (p - p_s), 0.0), p
            else:
                f_s, p_s = 0.0, 0.0
            k_now = k
        f = f_s + k_now * 1000.0 * (p - p_s)
        force[i] = max(f, 0.0) if p > 0.0 else 0.0
        k_true[i] = k_now
        seen = force[max(i - bench.latency_in, 0)] + noise[i]
        if i in spikes:
            seen += bench.spike_n
        if i in drop:
            seen = math.nan
        measured[i] = seen
        correction, status[i] = step([0.0, 0.0, seen])
        u_out[i] = correction[2]
        pending.append(correction[2])
    return SpringRun(force, measured, u_out, status, k_true)
