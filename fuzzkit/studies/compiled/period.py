"""The plant-independent part of one compiled period, shared by every compiled loop.

Per period, as :func:`fuzzkit.studies.runner.run` does it (the cross-branch timing agreement):
the plant's measured force -> :func:`inject_faults` -> :func:`sensor_latency` (the controller
consumes the sample of ``sensor_delay`` periods ago, a delay fault's periods included; the queue
starts filled with the reset sample's force) -> :func:`controller_step` -> :func:`command_latency`
(the plant receives the correction computed ``command_delay`` periods ago; the queue starts with
zeros). The plant kernels (:mod:`fuzzkit.studies.compiled.arm6_run` for arm6,
:mod:`fuzzkit.studies.compiled.planar_run` for the pymunk arm) wrap their plant step with
these, and call the controller through
:func:`fuzzkit.studies.compiled.generated_controller.controller_period`: this module's
controller, or a spec's whole generated C controller (``--controller-impl c``).

The controller is :class:`fuzzkit.control.controllers.HybridForceController` (spike gate,
debounced engagement, trip rule, back-off, sensor faults; the sensor front end of
:mod:`fuzzkit.control.frontend`: tare screened by the gate, gravity compensation with the
scenario's fixed tool rotation, first-order low-pass) over PI or fuzzy-PI axis
controllers, the fuzzy surface being a double lookup table
(:mod:`fuzzkit.studies.compiled.table`) or, when ``c_eval`` is a ctypes function, the generated
C itself (:mod:`fuzzkit.studies.compiled.generated_c`). Its state lives in two arrays made by
:func:`controller_state`: scalars ``cs`` (``CS_*``) and 3-vectors ``cv`` (rows ``V_*``).

Twins: this is the **compiled copy** of the controller's period (spike gate, engagement, trip
and back-off, the front end, PI / fuzzy-PI, output limits); :mod:`fuzzkit.control.controllers`
and :mod:`fuzzkit.control.frontend` are the independent reference that
``tests/test_compiled_loop.py`` and ``tests/test_spec_runs.py`` hold it to, so the two are
written twice on purpose.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit
from fuzzkit.studies.compiled.generated_c import call_c_surface
from fuzzkit.studies.compiled.table import table2

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

KIND_PI, KIND_FUZZY = 0, 1

# Controller parameter vector (``cp``)
C_KIND, C_KP, C_KI, C_KX, C_UMIN, C_UMAX, C_RATE = 0, 1, 2, 3, 4, 5, 6
C_FORCE_LIMIT, C_ENGAGE_THR, C_TRIP_SAMPLES, C_BACKOFF, C_BACKOFF_SPEED = 7, 8, 9, 10, 11
C_ENGAGE_SAMPLES, C_HOLD, C_PERIOD = 12, 13, 14
C_SENSOR_DELAY, C_COMMAND_DELAY = 15, 16  # the fault's delay included in the sensor delay
C_DROPOUT_START, C_DROPOUT_LENGTH, C_SPIKE_N = 17, 18, 19
C_SPIKE_GATE, C_SPIKE_CONFIRM = 20, 21
# The sensor front end: tare samples (0: none), the tool's weight as the sensor reads it (the
# compiled plants never turn the tool, so it is constant), the low-pass gain (1: no filter)
C_TARE_N, C_WEIGHT, C_ALPHA = 22, 23, 26
N_CP = 27

# Scalar results (``out_scalars``)
R_FAULTS, R_TRIPPED, R_TRIP_TIME, R_ENGAGED_TIME = 0, 1, 2, 3
N_RESULTS = 4

# Controller scalar state (``cs``); flags are 0.0 / 1.0, times NaN until they happen
CS_FAULTS, CS_ENGAGED, CS_ENGAGE_COUNT, CS_HAS_ACCEPTED, CS_REJECTED_RUN = 0, 1, 2, 3, 4
CS_TRIPPED, CS_TRIP_TIME, CS_OVER, CS_CTRL_T, CS_ENGAGED_AT, CS_HAS_E_LAST = 5, 6, 7, 8, 9, 10
CS_TARING, CS_TARE_COUNT, CS_HAS_FILTERED = 11, 12, 13
N_CS = 14

# Controller vector state (rows of ``cv``)
V_U, V_E, V_DE, V_DU, V_E_LAST, V_AX_U, V_AX_PREV, V_AX_HAS_PREV = 0, 1, 2, 3, 4, 5, 6, 7
V_BACKOFF, V_BACKOFF_DIR, V_ACCEPTED = 8, 9, 10
V_BIAS, V_TARE_SUM, V_FILTERED = 11, 12, 13
N_CV = 14


@jit
def controller_state(cp: FloatArray) -> tuple[FloatArray, FloatArray]:
    """A fresh controller state ``(cs, cv)``: nothing seen, engaged at once without threshold."""
    cs = np.zeros(N_CS)
    cs[CS_ENGAGED] = 1.0 if math.isnan(cp[C_ENGAGE_THR]) else 0.0
    cs[CS_TRIP_TIME] = math.nan
    cs[CS_ENGAGED_AT] = math.nan
    cs[CS_TARING] = 1.0 if cp[C_TARE_N] > 0.0 else 0.0
    return cs, np.zeros((N_CV, 3))


@jit
def path_held(cp: FloatArray, cs: FloatArray) -> bool:
    """The runner's rule: the path stops after a trip, or once engaged in a hold experiment."""
    return cs[CS_TRIPPED] > 0.0 or (
        cp[C_HOLD] > 0.0 and cs[CS_ENGAGED] > 0.0 and not math.isnan(cs[CS_ENGAGED_AT])
    )


@jit
def inject_faults(
    cp: FloatArray,
    spike_sign: float,
    nan_sample: bool,
    t_s: float,
    f_meas: FloatArray,
    measured: FloatArray,
) -> None:
    """``FaultInjector``: ``measured`` = ``f_meas`` with this period's spike, NaN or dropout."""
    for j in range(3):
        measured[j] = f_meas[j]
    if spike_sign != 0.0:
        s = spike_sign * cp[C_SPIKE_N]
        measured[0] += s * 1.0
        measured[1] += s * 0.0
        measured[2] += s * 1.0
    if nan_sample:
        measured[:] = np.nan
    start = cp[C_DROPOUT_START]
    if not math.isnan(start) and start <= t_s < start + cp[C_DROPOUT_LENGTH]:
        measured[:] = np.nan


@jit
def sensor_latency(
    k: int, sd: int, sensor_q: FloatArray, measured: FloatArray, reset_force: FloatArray
) -> FloatArray:
    """Push period ``k``'s sample into the ring ``sensor_q`` (``sd + 1`` rows); the one the
    controller consumes: ``sd`` periods old, the reset sample's force before that."""
    sensor_q[k % (sd + 1), :] = measured
    if sd == 0:
        return measured
    if k + 1 <= sd:
        return reset_force
    oldest: FloatArray = sensor_q[(k + 1) % (sd + 1)]
    return oldest


@jit
def command_latency(
    k: int, cd: int, command_q: FloatArray, correction: FloatArray, applied: FloatArray
) -> None:
    """Push period ``k``'s correction into the ring ``command_q``; ``applied`` = the one
    computed ``cd`` periods ago (zeros before that)."""
    command_q[k % (cd + 1), :] = correction
    if cd == 0:
        applied[:] = correction
    elif k + 1 <= cd:
        applied[:] = 0.0
    else:
        applied[:] = command_q[(k + 1) % (cd + 1)]


@jit
def _axis_increment(
    cp: FloatArray,
    bp0: FloatArray,
    bp1: FloatArray,
    tab: FloatArray,
    splits: IntArray,
    c_eval: Any,
    c_io: FloatArray,
    e: float,
    de: float,
) -> float:
    if int(cp[C_KIND]) == KIND_PI:
        return float(cp[C_KP] * de + cp[C_KI] * e)
    en = min(max(cp[C_KI] * e, -1.0), 1.0)
    den = min(max(cp[C_KP] * de, -1.0), 1.0)
    if c_eval is None:  # a compile-time branch: c_eval is typed None or a C function
        return float(cp[C_KX] * table2(bp0, bp1, tab, splits, en, den))
    return float(cp[C_KX] * call_c_surface(c_eval, c_io, en, den))


@jit
def controller_step(
    cp: FloatArray,
    selection: FloatArray,
    setpoints: FloatArray,
    bp0: FloatArray,
    bp1: FloatArray,
    tab: FloatArray,
    splits: IntArray,
    c_eval: Any,
    c_io: FloatArray,
    consumed: FloatArray,
    t_s: float,
    cs: FloatArray,
    cv: FloatArray,
    correction: FloatArray,
) -> None:
    """``HybridForceController.step`` on the consumed sample: updates ``cs``/``cv`` and writes
    the task-frame correction ``S*u + back-off``; records the plant time ``t_s`` at engagement.
    ``c_eval``: None (the table ``bp0 .. splits``) or the generated C's ``NAME_eval`` (ctypes),
    ``c_io`` its 3-double scratch buffer."""
    period = cp[C_PERIOD]
    engage_thr = cp[C_ENGAGE_THR]  # NaN: engaged from the start
    rate = cp[C_RATE]  # NaN: no rate limit
    spike_confirm = int(cp[C_SPIKE_CONFIRM])
    u, du = cv[V_U], cv[V_DU]
    accepted, backoff, backoff_dir = cv[V_ACCEPTED], cv[V_BACKOFF], cv[V_BACKOFF_DIR]
    f = np.empty(3)
    cs[CS_CTRL_T] += period
    du[:] = 0.0
    valid = True
    for i in range(3):
        if selection[i] > 0.0 and not math.isfinite(consumed[i]):
            valid = False
    all_finite = True
    for i in range(3):
        if not math.isfinite(consumed[i]):
            all_finite = False
    taring = cs[CS_TARING] > 0.0
    if not valid or (taring and not all_finite):
        # HybridForceController.wait: in the first sensor-delay periods no measurement can
        # have arrived yet (the queue holds the reset sample): held, but not a sensor fault
        if round(cs[CS_CTRL_T] / period) > cp[C_SENSOR_DELAY]:
            cs[CS_FAULTS] += 1.0
        cs[CS_ENGAGE_COUNT] = 0.0
    elif taring:
        _tare_step(cp, consumed, cs, cv)
    else:
        fmax = 0.0
        for i in range(3):
            c = consumed[i] - cp[C_WEIGHT + i] - cv[V_BIAS][i]
            f[i] = c if math.isfinite(c) else 0.0
            fmax = max(fmax, abs(f[i]))
        plausible = _gate(cp, f, cs, accepted)
        tripped = cs[CS_TRIPPED] > 0.0
        if not tripped:
            # the trip sees every finite sample, gated or not
            cs[CS_OVER] = cs[CS_OVER] + 1.0 if fmax > cp[C_FORCE_LIMIT] else 0.0
            if cs[CS_OVER] >= (int(cp[C_TRIP_SAMPLES]) if plausible else spike_confirm):
                tripped = True
                cs[CS_TRIPPED] = 1.0
                cs[CS_TRIP_TIME] = cs[CS_CTRL_T]
                nf = math.sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2])
                for i in range(3):
                    backoff_dir[i] = -f[i] / nf if nf > 0.0 else 0.0
        if not plausible and not tripped:
            cs[CS_FAULTS] += 1.0
            cs[CS_ENGAGE_COUNT] = 0.0
        elif tripped:
            step = cp[C_BACKOFF_SPEED] * period
            nb = math.sqrt(backoff[0] ** 2 + backoff[1] ** 2 + backoff[2] ** 2)
            if nb < cp[C_BACKOFF]:
                for i in range(3):
                    backoff[i] = backoff[i] + step * backoff_dir[i]
        else:
            _filter(cp, f, cs, cv)
            fmax = 0.0
            for i in range(3):
                fmax = max(fmax, abs(f[i]))
            go = True
            if cs[CS_ENGAGED] == 0.0:
                cs[CS_ENGAGE_COUNT] = cs[CS_ENGAGE_COUNT] + 1.0 if fmax > engage_thr else 0.0
                if cs[CS_ENGAGE_COUNT] < int(cp[C_ENGAGE_SAMPLES]):
                    go = False
                else:
                    cs[CS_ENGAGED] = 1.0
            if go:
                _axes_step(
                    cp, selection, setpoints, bp0, bp1, tab, splits, c_eval, c_io, f, rate, cs, cv
                )
    for i in range(3):
        correction[i] = selection[i] * u[i] + backoff[i]
    if cs[CS_ENGAGED] > 0.0 and math.isnan(cs[CS_ENGAGED_AT]):
        cs[CS_ENGAGED_AT] = t_s


@jit
def _gate(cp: FloatArray, f: FloatArray, cs: FloatArray, accepted: FloatArray) -> bool:
    """The spike gate (``HybridForceController._plausible``): True when ``f`` is accepted."""
    if cs[CS_HAS_ACCEPTED] > 0.0 and cs[CS_REJECTED_RUN] < int(cp[C_SPIKE_CONFIRM]):
        jump = 0.0
        for i in range(3):
            jump = max(jump, abs(f[i] - accepted[i]))
        if jump > cp[C_SPIKE_GATE]:
            cs[CS_REJECTED_RUN] += 1.0
            return False
    for i in range(3):
        accepted[i] = f[i]
    cs[CS_HAS_ACCEPTED] = 1.0
    cs[CS_REJECTED_RUN] = 0.0
    return True


@jit
def _tare_step(cp: FloatArray, raw: FloatArray, cs: FloatArray, cv: FloatArray) -> None:
    """One tare sample (``HybridForceController._tare``): screened by the gate, a confirmed
    new level restarts the tare, the N-th accepted sample sets the bias."""
    c = np.empty(3)
    for i in range(3):
        c[i] = raw[i] - cp[C_WEIGHT + i]
    confirmed = cs[CS_HAS_ACCEPTED] > 0.0 and cs[CS_REJECTED_RUN] >= int(cp[C_SPIKE_CONFIRM])
    if not _gate(cp, c, cs, cv[V_ACCEPTED]):
        cs[CS_FAULTS] += 1.0
        return
    total = cv[V_TARE_SUM]
    if confirmed:
        total[:] = 0.0
        cs[CS_TARE_COUNT] = 0.0
    for i in range(3):
        total[i] = total[i] + c[i]
    cs[CS_TARE_COUNT] += 1.0
    if cs[CS_TARE_COUNT] >= cp[C_TARE_N]:
        for i in range(3):
            cv[V_BIAS][i] = total[i] / cs[CS_TARE_COUNT]
        cs[CS_TARING] = 0.0
        cs[CS_HAS_FILTERED] = 0.0
        cs[CS_HAS_ACCEPTED] = 0.0  # the bias moved: the gate starts afresh
        cs[CS_REJECTED_RUN] = 0.0


@jit
def _filter(cp: FloatArray, f: FloatArray, cs: FloatArray, cv: FloatArray) -> None:
    """The low-pass on an accepted sample, in place (``FrontEnd.filter``)."""
    alpha = cp[C_ALPHA]
    y = cv[V_FILTERED]
    if cs[CS_HAS_FILTERED] == 0.0 or alpha == 1.0:
        for i in range(3):
            y[i] = f[i]
    else:
        for i in range(3):
            y[i] = y[i] + alpha * (f[i] - y[i])
            f[i] = y[i]
    cs[CS_HAS_FILTERED] = 1.0


@jit
def _axes_step(
    cp: FloatArray,
    selection: FloatArray,
    setpoints: FloatArray,
    bp0: FloatArray,
    bp1: FloatArray,
    tab: FloatArray,
    splits: IntArray,
    c_eval: Any,
    c_io: FloatArray,
    f: FloatArray,
    rate: float,
    cs: FloatArray,
    cv: FloatArray,
) -> None:
    """The axis controllers' incremental steps (``_Incremental.step``) and e, de, du."""
    u, e, du = cv[V_U], cv[V_E], cv[V_DU]
    ax_u, ax_prev, ax_has_prev = cv[V_AX_U], cv[V_AX_PREV], cv[V_AX_HAS_PREV]
    for i in range(3):
        if selection[i] <= 0.0:
            continue
        before = u[i]
        ei = setpoints[i] - f[i]
        dei = ei - ax_prev[i] if ax_has_prev[i] > 0.0 else 0.0
        ax_prev[i] = ei
        ax_has_prev[i] = 1.0
        inc = _axis_increment(cp, bp0, bp1, tab, splits, c_eval, c_io, ei, dei)
        if not math.isfinite(inc):
            inc = 0.0
        if not math.isnan(rate):
            inc = min(max(inc, -rate), rate)
        ax_u[i] = min(max(ax_u[i] + inc, cp[C_UMIN]), cp[C_UMAX])
        u[i] = ax_u[i]
        du[i] = u[i] - before
        e[i] = setpoints[i] - f[i]
    error_change(cs, cv)


@jit
def error_change(cs: FloatArray, cv: FloatArray) -> None:
    """After the axes stepped: ``de = e - e_last`` (0 the first time), then ``e_last = e``."""
    e, de, e_last = cv[V_E], cv[V_DE], cv[V_E_LAST]
    has_e_last = cs[CS_HAS_E_LAST] > 0.0
    for i in range(3):
        de[i] = e[i] - e_last[i] if has_e_last else 0.0
        e_last[i] = e[i]
    cs[CS_HAS_E_LAST] = 1.0


@jit
def credit_normal(rot: FloatArray, nx: float, ny: float, nz: float, out: FloatArray) -> None:
    """``normal_force_by_axis`` for one contact: add its base-frame normal force ``(nx, ny,
    nz)``, in the task frame (``rot`` base-from-task), to the task axis it lies closest to."""
    best = 0
    best_abs = -1.0
    tv = np.empty(3)
    for j in range(3):
        tv[j] = rot[0, j] * nx + rot[1, j] * ny + rot[2, j] * nz
        if abs(tv[j]) > best_abs:
            best, best_abs = j, abs(tv[j])
    out[best] += tv[best]


@jit
def store_results(cs: FloatArray, out_scalars: FloatArray) -> None:
    """The run's scalar results (``R_*``) from the final controller state."""
    out_scalars[R_FAULTS] = cs[CS_FAULTS]
    out_scalars[R_TRIPPED] = cs[CS_TRIPPED]
    out_scalars[R_TRIP_TIME] = cs[CS_TRIP_TIME]
    out_scalars[R_ENGAGED_TIME] = cs[CS_ENGAGED_AT]
