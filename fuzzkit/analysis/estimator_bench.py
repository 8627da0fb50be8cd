"""The stiffness estimator on a simulated robot: how close its estimate ends to the truth.

The plant (``planar``, ``arm6``, ...) is held in contact with the flat surface of the regulation
task (:mod:`fuzzkit.analysis.regulation`) at the indentation of a set point, and a binary
correction along task z (levels held 1 to 8 periods, the excitation of
:func:`fuzzkit.analysis.inner_loop.excite`) swings the force by ``swing`` of the set point. The
loop's latency is the closed loop's: the correction computed at period ``k`` reaches the plant at
``k + 1 + latency_out``, the force of period ``k`` is seen at ``k + latency_in``; the sensor's
own noise is the scenario's, set to ``noise_n``. Every period
:meth:`~fuzzkit.control.adaptation.StiffnessSchedule.observe` gets the seen force and the last
correction, exactly as the hybrid controller feeds it (engaged, untripped).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fuzzkit.analysis.inner_loop import InnerLoop
from fuzzkit.analysis.regulation import regulation_experiment
from fuzzkit.control.adaptation import StiffnessSchedule
from fuzzkit.control.adaptation_spec import Adaptation, Band, Estimator
from fuzzkit.loop.adapter import make_plant
from fuzzkit.plants.contract import task_to_base
from fuzzkit.studies.regulation import surface_height

#: The set point the contact is held around (N) and the force swing of the excitation.
SETPOINT_N = 12.0
SWING = 0.3
#: Periods in contact before the excitation starts (the estimator is fed from the first).
SETTLE = 50
#: The binary level is held HOLD periods (drawn uniformly) and smoothed by a first-order lag of
#: gain SMOOTH per period, as a controller's rate-limited corrections are.
HOLD = (4, 32)
SMOOTH = 0.2


@dataclass(frozen=True, slots=True)
class EstimateRun:
    """The estimate (N/mm) after each excited period, and the true stiffness."""

    k_true_n_mm: float
    estimates: tuple[float, ...]

    def ratio(self, after: int) -> float:
        """The worst factor between the estimate and the truth from excited period ``after`` on
        (``max(k/k_true, k_true/k)``)."""
        tail = np.asarray(self.estimates[after:])
        return float(np.max(np.maximum(tail / self.k_true_n_mm, self.k_true_n_mm / tail)))


def estimator_for(inner: InnerLoop | None, latency_periods: int, window: int = 4) -> Estimator:
    """The kit's default estimator with the loop's delay, knowing ``inner``'s mid-range model
    (None: the estimator that does not know the inner loop)."""
    est = Estimator(
        window_periods=window,
        delay_periods=1 + latency_periods,
        forgetting=0.9,
        min_step_m=2.0e-6,
        min_force_n=0.2,
        initial_n_mm=300.0,
        k_min_n_mm=1.0,
        k_max_n_mm=2000.0,
    )
    if inner is None:
        return est
    model = inner_model(inner)
    return replace(
        est, inner_q=model["inner_q"], inner_a=model["inner_a"], inner_g=model["inner_g"]
    )


def inner_model(inner: InnerLoop) -> dict[str, float]:
    """The estimator's ``inner_q``, ``inner_a``, ``inner_g``: the middle of the identified
    ranges."""
    return {
        "inner_q": round(0.5 * sum(inner.q_range), 3),
        "inner_a": round(0.5 * sum(inner.a_range), 3),
        "inner_g": round(0.5 * sum(inner.g_range), 3),
    }


def estimate_on_plant(
    plant_name: str,
    k_n_mm: float,
    estimator: Estimator,
    latency_in: int = 0,
    latency_out: int = 0,
    noise_n: float = 0.1,
    periods: int = 400,
    seed: int = 0,
) -> EstimateRun:
    """Excite ``plant_name`` in contact at ``k_n_mm`` for ``periods``; the estimates per period."""
    k = k_n_mm * 1e3
    exp = regulation_experiment(k, SETPOINT_N)
    scn = exp.scenario
    scn = replace(scn, sensor=replace(scn.sensor, noise_std_n=noise_n))
    plant = make_plant(plant_name)
    plant.reset(scn, seed=seed)
    period = scn.period_s
    sched = StiffnessSchedule(Adaptation("stiffness-scheduled", estimator, (Band(1.0),)), period)
    gap = float(scn.path[0].z) - (surface_height(exp) + scn.tool.radius_m)
    depth = SETPOINT_N / k
    rng = np.random.default_rng(seed + 1000)
    holds = rng.integers(HOLD[0], HOLD[1] + 1, SETTLE + periods)
    signs = np.where(rng.integers(0, 2, len(holds)) > 0, 1.0, -1.0)
    level = np.repeat(signs, holds)[: SETTLE + periods]
    level[:SETTLE] = 0.0
    command = np.empty(len(level))  # the controller's correction about the set point's
    c = 0.0
    for i, v in enumerate(level):
        c += SMOOTH * (depth * SWING * v - c)
        command[i] = c
    pending = [0.0] * (latency_out + 1)
    forces: list[float] = []
    last_u = 0.0
    out: list[float] = []
    for i in range(SETTLE + periods):
        applied = pending.pop(0)
        sample = plant.step(task_to_base(scn, np.array([0.0, 0.0, gap + depth + applied])), 0.0)
        forces.append(float(sample.force[2]))
        seen = forces[max(i - latency_in, 0)]
        sched.observe(seen, last_u)
        last_u = float(command[i])
        pending.append(last_u)
        if i >= SETTLE:
            out.append(sched.k)
    return EstimateRun(k_n_mm, tuple(out))
