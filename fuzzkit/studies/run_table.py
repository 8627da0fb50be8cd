"""One closed-loop run as a table: one row per controller period, for a spreadsheet or pandas.

The columns, in order (units in the names; ``<a>`` is x, y, z): ``t_s`` (the period index times the
period, :func:`period_times`); ``f<a>_measured_n`` (the sample the controller consumed, NaN where
none reached it) and ``f<a>_true_n`` (the contact force) for every axis; for each force-controlled
axis ``f<a>_setpoint_n``, ``e<a>_n`` (``setpoint - measured``), ``de<a>_n`` (change of ``e`` since
the last controlled period), ``du<a>_m`` (correction this period) and ``u<a>_m`` (the correction
the controller commands: the sum of ``du``, plus the back-off after a trip); for each motion-only
axis ``u<a>_m`` (the back-off after a trip, else 0); when the run's controller spec compensates the
tool's weight, the tool rotation the controller received with each sample, ``r11`` .. ``r33``
(row-major, world-from-sensor); when the run's controller reports them, ``status_bits`` (the
status bits it returned, :mod:`fuzzkit.control.status`, an integer); then ``status``
(:data:`STATUSES`). Numbers are written with ``repr``, so they read back bit for bit: ``fuzzkit
replay SPEC --forces RUN.csv`` reads the file as it is and reproduces the ``u<a>_m`` and
``status_bits`` columns.
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import numpy.typing as npt

from fuzzkit.control.names import AXES
from fuzzkit.loop.result import RunResult

#: What the loop did in a period: ``approach`` (not engaged yet: no correction), ``engaged``
#: (the force loop runs), ``no sample`` (no valid force reached the controller: held),
#: ``tripped`` (the safety trip fired: the tool backs off).
STATUSES = ("approach", "engaged", "no sample", "tripped")


def period_status(result: RunResult) -> list[str]:
    """The :data:`STATUSES` entry of every period of ``result``."""
    selected = np.asarray(result.experiment.selection, dtype=bool)
    half = 0.5 * result.experiment.scenario.period_s
    trip = math.inf if result.trip_time_s is None else result.trip_time_s - half
    engaged = math.inf if result.engaged_time_s is None else result.engaged_time_s - half
    out: list[str] = []
    for k, t in enumerate(result.t):
        if t >= trip:
            out.append("tripped")
        elif not np.all(np.isfinite(result.force[k, selected])):
            out.append("no sample")
        elif t >= engaged:
            out.append("engaged")
        else:
            out.append("approach")
    return out


def period_times(result: RunResult) -> npt.NDArray[np.float64]:
    """The time of every period's sample, computed from its index as ``k / rate`` (``k *
    period`` where the rate is no whole number of hertz), not accumulated: the CSV's ``t_s``
    then reads ``1.876``, the decimal it is, where the plants' sum of periods has drifted to
    ``1.8759999999999042``."""
    period = result.experiment.scenario.period_s
    n = len(result.t)
    first = round(float(result.t[0]) / period) if n else 0
    k = np.arange(first, first + n, dtype=np.float64)
    rate = 1.0 / period
    if abs(rate - round(rate)) < 1e-9 * rate:
        return k / round(rate)  # correctly rounded: the nearest double to the decimal time
    return k * period


def run_columns(result: RunResult) -> list[str]:
    """The header of :func:`run_csv` for ``result`` (its force-controlled axes)."""
    cols = ["t_s"]
    for a in AXES:
        cols += [f"f{a}_measured_n", f"f{a}_true_n"]
    for i, a in enumerate(AXES):
        if result.experiment.selection[i]:
            cols += [f"f{a}_setpoint_n", f"e{a}_n", f"de{a}_n", f"du{a}_m", f"u{a}_m"]
    cols += [f"u{a}_m" for i, a in enumerate(AXES) if not result.experiment.selection[i]]
    if _writes_rotation(result):
        cols += [f"r{i}{j}" for i in range(1, 4) for j in range(1, 4)]
    if result.status is not None:
        cols.append("status_bits")
    return [*cols, "status"]


def _writes_rotation(result: RunResult) -> bool:
    """The controller needs the tool's rotation (its spec compensates gravity) and the run
    recorded it."""
    spec = result.experiment.controller_spec
    return spec is not None and spec.sensor.tool is not None and result.rotation is not None


def run_csv(result: RunResult) -> str:
    """``result`` as CSV text, one row per period (columns: the module docstring)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(run_columns(result))
    controlled = [i for i in range(3) if result.experiment.selection[i]]
    rotation = result.rotation if _writes_rotation(result) else None
    times = period_times(result)
    for k, status in enumerate(period_status(result)):
        row = [repr(float(times[k]))]
        for i in range(3):
            row += [repr(float(result.force[k, i])), repr(float(result.force_true[k, i]))]
        for i in controlled:
            row += [
                repr(float(v))
                for v in (
                    result.setpoint[k, i],
                    result.e[k, i],
                    result.de[k, i],
                    result.du[k, i],
                    result.u[k, i],
                )
            ]
        row += [repr(float(result.u[k, i])) for i in range(3) if i not in controlled]
        if rotation is not None:
            row += [repr(float(v)) for v in rotation[k]]
        if result.status is not None:
            row.append(str(int(result.status[k])))
        writer.writerow([*row, status])
    return buf.getvalue()
