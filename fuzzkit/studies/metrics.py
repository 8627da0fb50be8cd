"""Force-control metrics of a run: overshoot, settling time, steady-state error, RMS, contact.

Computed on the *true* contact force, so sensor noise is not counted as control error.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.control.names import AXES
from fuzzkit.loop.result import RunResult
from fuzzkit.studies.outcome import axis_outcome, limit_exceeded

Vec = npt.NDArray[np.float64]


def overshoot_pct(f: Vec, setpoint: float) -> float | None:
    """Peak excursion beyond the set point in the direction of approach, % of ``|setpoint|``.

    ``f`` is the force from the moment of first contact on. None for a zero set point (no
    scale to compare with); 0 when the force never passes the set point.
    """
    if setpoint == 0.0 or len(f) == 0:
        return None
    excess = float(np.max((f - setpoint) * math.copysign(1.0, setpoint)))
    return max(0.0, 100.0 * excess / abs(setpoint))


def settling_time(
    t: Vec, f: Vec, setpoint: float, t0: float, band: float = 0.05, zero_band_n: float = 0.5
) -> float | None:
    """Time from ``t0`` until ``f`` enters and stays in the band around ``setpoint``.

    The band is ``band * |setpoint|`` (5 %) or ``zero_band_n`` newtons for a zero set point.
    None when the final sample is outside the band (never settled).
    """
    tol = band * abs(setpoint) if setpoint != 0.0 else zero_band_n
    mask = t >= t0
    tt, ff = t[mask], f[mask]
    if len(tt) == 0:
        return None
    outside = np.abs(ff - setpoint) > tol
    if outside[-1]:
        return None
    idx = np.nonzero(outside)[0]
    if len(idx) == 0:
        return float(tt[0] - t0)
    return float(tt[idx[-1] + 1] - t0)


def steady_state_error(f: Vec, setpoint: float) -> tuple[float, float]:
    """Mean and standard deviation of the error ``setpoint - f`` over the samples given."""
    if len(f) == 0:
        return (math.nan, math.nan)
    err = setpoint - f
    return (float(np.mean(err)), float(np.std(err)))


def rms(x: Vec) -> float | None:
    """Root mean square of ``x``; None for an empty selection."""
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else None


#: Normal force (N) that marks an axis's first contact when the experiment has no engage
#: threshold (the force loop active from the start, as in ``press_experiment``).
CONTACT_THRESHOLD_N = 1.0


def axis_contact(result: RunResult, axis: int) -> npt.NDArray[np.bool_] | None:
    """Per sample: does the tool touch a surface that faces task ``axis``?

    True where the normal contact force credited to that axis (``RunResult.force_normal``,
    friction excluded) is positive in the direction of the axis's set point (either direction
    for a 0 N set point). None when the plant does not report normal forces.
    """
    normal = result.force_normal[:, axis]
    if len(normal) == 0 or not np.all(np.isfinite(normal)):
        return None
    sp = float(result.experiment.setpoints[axis])
    pressing = normal * math.copysign(1.0, sp) if sp != 0.0 else np.abs(normal)
    touching: npt.NDArray[np.bool_] = pressing > 0.0
    return touching


def axis_first_contact(result: RunResult, axis: int) -> int | None:
    """Index of task ``axis``'s first contact: its normal force first reaches the threshold.

    The threshold is the experiment's engage threshold (``CONTACT_THRESHOLD_N`` without one),
    applied to the normal contact force credited to the axis in the direction of its set point,
    so friction from sliding on a floor (``mu * f_z`` along x) never counts as an x contact.
    Falls back to the run's first contact with any object when the plant does not report
    normal forces. None when the axis never touches a surface facing it.
    """
    normal = result.force_normal[:, axis]
    if len(normal) == 0 or not np.all(np.isfinite(normal)):
        idx = np.nonzero(result.in_contact)[0]
        return int(idx[0]) if len(idx) else None
    exp = result.experiment
    thr = exp.engage_threshold_n if exp.engage_threshold_n is not None else CONTACT_THRESHOLD_N
    sp = float(exp.setpoints[axis])
    pressing = normal * math.copysign(1.0, sp) if sp != 0.0 else np.abs(normal)
    idx = np.nonzero(pressing >= thr)[0]
    return int(idx[0]) if len(idx) else None


def path_driving(result: RunResult, axis: int) -> npt.NDArray[np.bool_]:
    """Per sample: the nominal path moved along task ``axis`` during that period."""
    nominal_task = result.nominal_position @ result.experiment.scenario.rotation
    driving = np.zeros(len(result.t), dtype=bool)
    if len(driving) > 1:
        driving[1:] = np.abs(np.diff(nominal_task[:, axis])) > 1e-9
    return driving


#: The RMS error while moving counts from this long after the axis's first contact (the
#: transient of the contact itself is the overshoot's and settling time's business).
MOVING_AFTER_CONTACT_S = 0.5


def moving_window(result: RunResult, axis: int) -> npt.NDArray[np.bool_]:
    """Per sample: counted in ``rms_error``, the path moving from 0.5 s after the first contact
    (the axis's own, or the run's with anything when no surface faces the axis)."""
    i0 = axis_first_contact(result, axis)
    if i0 is None:
        contacts = np.nonzero(result.in_contact)[0]
        if len(contacts) == 0:
            return np.zeros(len(result.t), dtype=bool)
        i0 = int(contacts[0])
    t = result.t
    return np.asarray(result.moving & (t >= t[i0] + MOVING_AFTER_CONTACT_S), dtype=bool)


def axis_metrics(result: RunResult, axis: int) -> dict[str, float | None]:
    """The per-axis figures of a run (keys as in ``fuzzkit simulate --json``).

    Each axis is measured from *its own* first contact (:func:`axis_first_contact`): in E3 the
    tool slides on the floor for seconds before x meets the wall. An axis that never touches a
    surface facing it (E1's x, held at 0 N while the cup rests on the hammer) has
    ``first_contact_s`` None and is measured from the run's first contact with anything, when
    its loop starts holding it.

    * ``overshoot_pct``: peak beyond the set point from the axis's first contact on. Where the
      nominal path keeps driving into the surface after contact, the force follows a ramp
      disturbance and this peak is the loop's ramp-following error (for an incremental PI,
      ``k * v * T / (ki * k)`` newtons: E3's x, 25 mm/s into a 10 N/mm wall, about 10 N).
    * ``settling_time_s``: into the 5 % band (0.5 N for 0 N) and staying there, counted from
      the end of the approach: the axis's first contact or, while the nominal path still moves
      along that axis, the period it stops (a force cannot settle while the path pushes it).
    * ``contact_lost_s``: time after the first contact without touching a surface facing the
      axis.
    """
    exp = result.experiment
    t, f = result.t, result.force_true[:, axis]
    sp = float(exp.setpoints[axis])
    out: dict[str, float | None] = {
        "setpoint": sp,
        "first_contact_s": None,
        "overshoot_pct": None,
        "settling_time_s": None,
        "steady_state_error_mean": None,
        "steady_state_error_std": None,
        "rms_error": None,
        "peak_force": float(np.max(np.abs(f))) if len(f) else None,
        # the plant's contact force (as peak_force) next to what the sensor delivered
        "peak_force_true": float(np.max(np.abs(f))) if len(f) else None,
        "peak_force_measured": _nanmax_abs(result.force_sensor[:, axis]),
        "contact_lost_s": None,
    }
    own = axis_first_contact(result, axis)
    touching = axis_contact(result, axis)
    if own is not None:
        i0 = own
        out["first_contact_s"] = float(t[i0])
    else:
        any_contact = np.nonzero(result.in_contact)[0]
        if len(any_contact) == 0:
            return out
        i0 = int(any_contact[0])
        touching = None  # no surface faces this axis: count contact with anything
    if touching is None:
        touching = result.in_contact
    out["overshoot_pct"] = overshoot_pct(f[i0:], sp)
    driving = path_driving(result, axis)
    i_settle = i0
    while i_settle < len(t) and driving[i_settle]:
        i_settle += 1
    if i_settle < len(t):
        out["settling_time_s"] = settling_time(t, f, sp, float(t[i_settle]))
    steady = t >= t[-1] - exp.steady_window_s
    mean, std = steady_state_error(f[steady], sp)
    out["steady_state_error_mean"] = mean
    out["steady_state_error_std"] = std
    out["rms_error"] = rms(sp - f[moving_window(result, axis)])
    period = float(exp.scenario.period_s)
    out["contact_lost_s"] = float(np.count_nonzero(~touching[i0:]) * period)
    return out


#: The per-axis keys of the JSON summary (``fuzzkit simulate --json``), in order.
SUMMARY_AXIS_KEYS = (
    "setpoint",
    "first_contact_s",
    "overshoot_pct",
    "settling_time_s",
    "steady_state_error_mean",
    "steady_state_error_std",
    "rms_error",
    "peak_force",
    "peak_force_true",
    "peak_force_measured",
    "contact_lost_s",
    "outcome",  # fuzzkit.studies.outcome: settled, never settled, no contact, tripped
)


def _nanmax_abs(x: Vec) -> float | None:
    finite = x[np.isfinite(x)]
    return float(np.max(np.abs(finite))) if len(finite) else None


def summary(result: RunResult) -> dict[str, Any]:
    """The JSON summary of a run: experiment, controller, plant, the run's conditions
    (``stiffness`` in N/mm, ``latency_periods`` [sensor, command], ``fault``, ``seed``,
    ``safety_limit``, ``tripped``, ``limit_exceeded``: when and how far the true force passed
    the limit, or None, :func:`~fuzzkit.studies.outcome.limit_exceeded`), times, and per-axis
    metrics.

    Only force-controlled axes appear under ``axes`` (z first). Values that do not apply (the
    overshoot of a 0 N set point, the RMS while moving of a held path) are None (JSON null);
    each axis's ``outcome`` says in words why a settling time is missing
    (:mod:`fuzzkit.studies.outcome`: settled, never settled, no contact, tripped).
    """
    axes: dict[str, dict[str, Any]] = {}
    for i in (2, 0, 1):
        if result.experiment.selection[i]:
            m = axis_metrics(result, i)
            row: dict[str, Any] = {k: m.get(k) for k in SUMMARY_AXIS_KEYS}
            row["outcome"] = axis_outcome(m, result.tripped)
            axes[AXES[i]] = row
    return {
        "experiment": result.experiment.name,
        "controller": result.controller,
        "plant": result.plant,
        "stiffness": result.experiment.scenario.contact.stiffness_n_per_m / 1e3,
        "latency_periods": list(result.latency_periods),
        "fault": result.fault,
        "seed": result.seed,
        "safety_limit": result.experiment.force_limit_n,
        "tripped": result.tripped,
        "limit_exceeded": limit_exceeded(
            result.t, result.force_true, result.experiment.force_limit_n
        ),
        "sim_time_s": round(result.sim_time_s, 6),
        "wall_time_s": round(result.wall_time_s, 4),
        "loop": result.loop,
        "controller_impl": result.controller_impl,
        "cpu_time_s": round(result.cpu_time_s, 6),
        # simulated seconds per CPU second of the loop alone (start-up excluded)
        "real_time_factor": (
            round(result.real_time_factor, 1) if math.isfinite(result.real_time_factor) else None
        ),
        "axes": axes,
        **adaptation_summary(result),
    }


def adaptation_summary(result: RunResult) -> dict[str, Any]:
    """An adaptive run's final stiffness estimate (N/mm) and gain factor per force-controlled
    axis (``{}`` for fixed gains; an estimate is None where the axis has no schedule)."""
    if result.gain_scale is None or result.stiffness_n_mm is None or not len(result.t):
        return {}
    chosen = [i for i in (2, 0, 1) if result.experiment.selection[i]]
    last_k = result.stiffness_n_mm[-1]
    return {
        "stiffness_estimate_n_mm": {
            AXES[i]: (None if math.isnan(last_k[i]) else round(float(last_k[i]), 3)) for i in chosen
        },
        "gain_scale_final": {AXES[i]: float(result.gain_scale[-1, i]) for i in chosen},
    }
