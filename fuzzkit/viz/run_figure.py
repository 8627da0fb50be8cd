"""A static figure of one closed-loop run, for a look without the Rerun viewer.

One row of panels per force-controlled axis: the measured and true force against the set point
(N), the force error ``e`` (N), and the correction ``u`` with its per-period step ``du`` (mm,
``du`` on a second scale). The engagement and a safety trip are marked on every panel. After a
trip the controller computes no error and no increment (it retreats): those panels draw
nothing there and say "tripped: retreating", rather than a frozen last value. The title gives
each axis's outcome in the words of :mod:`fuzzkit.studies.outcome`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fuzzkit.loop.result import RunResult
from fuzzkit.studies.metrics import summary
from fuzzkit.studies.outcome import TRIPPED, limit_exceeded, settling_text
from fuzzkit.viz.figures import new_figure
from fuzzkit.viz.run_series import engaged_index

_FORCE = "tab:blue"
_TRUE = "tab:gray"
_SETPOINT = "tab:orange"
_TRIP = "tab:red"
_ENGAGED = "tab:green"


def run_figure(result: RunResult, ran: str | None = None) -> Any:
    """The run's figure (a matplotlib Figure, no pyplot); ``ran``, when given, names what ran
    (the spec or rule base and the gains' source) on a line of the title."""
    exp = result.experiment
    axes_idx = [i for i in (2, 0, 1) if exp.selection[i]]
    fig = new_figure(12.0, 2.6 * len(axes_idx) + 0.9)
    grid = fig.subplots(len(axes_idx), 3, squeeze=False, sharex=True)
    # before engagement the loop computes no error: draw none (a 0 would read "no error" while
    # 0 N meets the set point), as the recordings log none
    idle = slice(0, engaged_index(result))
    retreat = slice(_trip_index(result), len(result.t))
    for row, i in enumerate(axes_idx):
        a = "xyz"[i]
        ax_f, ax_e, ax_u = grid[row]
        ax_f.plot(result.t, result.force_true[:, i], color=_TRUE, lw=0.8, label="true")
        ax_f.plot(result.t, result.force[:, i], color=_FORCE, lw=0.8, label="measured")
        ax_f.plot(result.t, result.setpoint[:, i], color=_SETPOINT, ls="--", lw=1.2, label="set")
        ax_f.axhline(exp.force_limit_n, color=_TRIP, lw=0.6, ls=":", label="safety limit")
        ax_f.set_ylabel(f"f{a} [N]")
        e = result.e[:, i].astype(float)
        e[idle] = np.nan
        e[retreat] = np.nan
        ax_e.plot(result.t, e, color=_FORCE, lw=0.8)
        ax_e.axhline(0.0, color="0.4", lw=0.5)
        ax_e.set_ylabel(f"e{a} = set - measured [N]")
        ax_u.plot(result.t, result.u[:, i] * 1e3, color=_FORCE, lw=1.0, label=f"u{a}")
        ax_u.set_ylabel(f"u{a} [mm]", color=_FORCE)
        ax_du = ax_u.twinx()
        du = result.du[:, i] * 1e3
        du[idle] = np.nan
        du[retreat] = np.nan
        ax_du.plot(result.t, du, color=_TRUE, lw=0.5, alpha=0.6)
        ax_u.set_zorder(ax_du.get_zorder() + 1)  # u in front of the noisier du
        ax_u.patch.set_visible(False)
        ax_du.set_ylabel(f"du{a} per period [mm]", color=_TRUE)
        for ax in (ax_f, ax_e, ax_u):
            ax.grid(alpha=0.3)
            _mark_events(ax, result)
        if result.trip_time_s is not None:
            for ax, what in ((ax_e, "no error computed"), (ax_u, "u: the back-off")):
                ax.annotate(
                    f"{TRIPPED}: retreating,\n{what}",
                    (0.5 * (result.trip_time_s + float(result.t[-1])), 0.5),
                    xycoords=("data", "axes fraction"),
                    ha="center",
                    va="center",
                    color=_TRIP,
                    fontsize=8,
                )
        if row == 0:
            ax_f.set_title("force")
            ax_e.set_title("force error")
            ax_u.set_title("correction")
            ax_f.legend(fontsize=7, loc="best")
    for ax in grid[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(_title(result) + (f"\n{ran}" if ran else ""), fontsize=10)
    fig.tight_layout()
    return fig


def _trip_index(result: RunResult) -> int:
    """The first period after the trip (the run's length when it did not trip)."""
    if result.trip_time_s is None:
        return len(result.t)
    return int(np.searchsorted(result.t, result.trip_time_s, side="right"))


def _mark_events(ax: Any, result: RunResult) -> None:
    if result.engaged_time_s is not None:
        ax.axvline(result.engaged_time_s, color=_ENGAGED, lw=0.8, ls="--")
    if result.trip_time_s is not None:
        ax.axvline(result.trip_time_s, color=_TRIP, lw=1.5)
        ax.axvspan(result.trip_time_s, float(result.t[-1]), color=_TRIP, alpha=0.08)
        ax.annotate(
            "TRIP",
            (result.trip_time_s, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(3, -12),
            textcoords="offset points",
            color=_TRIP,
            fontsize=8,
            fontweight="bold",
        )


def _title(result: RunResult) -> str:
    exp = result.experiment
    peak = float(np.nanmax(np.abs(result.force_true))) if len(result.t) else 0.0
    trip = f"TRIPPED at {result.trip_time_s:.3f} s" if result.trip_time_s is not None else "no trip"
    exceeded = limit_exceeded(result.t, result.force_true, exp.force_limit_n)
    if exceeded is not None:
        trip += f", LIMIT EXCEEDED from {exceeded['time_s']:.3f} s"
    engaged = (
        f"engaged at {result.engaged_time_s:.3f} s (green)"
        if result.engaged_time_s is not None
        else "never engaged"
    )
    outcomes = ", ".join(
        f"{axis} {settling_text(m, result.tripped)}" for axis, m in summary(result)["axes"].items()
    )
    return (
        f"{exp.name} {result.controller} on {result.plant} ({result.controller_impl})\n"
        f"{engaged}, {trip}, peak true force {peak:.1f} N (limit {exp.force_limit_n:g} N); "
        f"settling: {outcomes}"
    )
