"""One closed-loop run as a table: one row per controller period, for a spreadsheet or pandas.

The columns, in order (units in the names; ``<a>`` is x, y, z):
``t_s``; ``f<a>_measured_n`` (the sample the controller consumed, NaN where none reached it)
and ``f<a>_true_n`` (the contact force) for every axis; for each force-controlled axis
``f<a>_setpoint_n``, ``e<a>_n`` (``setpoint - measured``), ``de<a>_n`` (change of ``e`` since
the last controlled period), ``du<a>_m`` (correction this period) and ``u<a>_m`` (the correction
the controller commands: the sum of ``du``, plus the back-off after a trip); then ``status``
(:data:`STATUSES`). Numbers are written with ``repr``, so they read back bit for bit.
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np

from fuzzkit.control.names import AXES
from fuzzkit.studies.runner import RunResult

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


def run_columns(result: RunResult) -> list[str]:
    """The header of :func:`run_csv` for ``result`` (its force-controlled axes)."""
    cols = ["t_s"]
    for a in AXES:
        cols += [f"f{a}_measured_n", f"f{a}_true_n"]
    for i, a in enumerate(AXES):
        if result.experiment.selection[i]:
            cols += [f"f{a}_setpoint_n", f"e{a}_n", f"de{a}_n", f"du{a}_m", f"u{a}_m"]
    return [*cols, "status"]


def run_csv(result: RunResult) -> str:
    """``result`` as CSV text, one row per period (columns: the module docstring)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(run_columns(result))
    controlled = [i for i in range(3) if result.experiment.selection[i]]
    for k, status in enumerate(period_status(result)):
        row = [repr(float(result.t[k]))]
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
        writer.writerow([*row, status])
    return buf.getvalue()
