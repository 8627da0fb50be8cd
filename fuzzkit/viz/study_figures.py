"""Figures of the PI vs fuzzy-PI comparison: force against time, and the stiffness study.

Both return a :class:`matplotlib.figure.Figure` (own Agg canvas, no pyplot); the report renders
them to PNG with :func:`fuzzkit.viz.figures.figure_bytes`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter, NullLocator

from fuzzkit.viz.figures import new_figure
from fuzzkit.viz.palette import (
    SETPOINT_STYLE,
    TRIP_LABEL,
    TRIP_STYLE,
    controller_colour,
    controller_name,
    gains_legend,
    gains_style,
)

#: Overshoots below this (%) are drawn on the floor of the log axis, with their own marker.
OVERSHOOT_FLOOR_PCT = 0.1


def _first_contact_s(results: Mapping[tuple[str, str], Any]) -> float | None:
    """The earliest time any run touches something (where the transient starts)."""
    times = [float(r.t[np.argmax(r.in_contact)]) for r in results.values() if r.in_contact.any()]
    return min(times) if times else None


def _trip_index(r: Any) -> int | None:
    """The sample at which run ``r`` tripped the safety limit, or None."""
    trip = getattr(r, "trip_time_s", None)
    if not getattr(r, "tripped", False) or trip is None:
        return None
    return int(np.searchsorted(r.t, trip))


def _mark_trip(ax: Any, r: Any, values: Any) -> bool:
    """A trip marker on ``values`` (one per sample of ``r``) where ``r`` tripped; True if it did."""
    k = _trip_index(r)
    if k is None or len(r.t) == 0:
        return False
    k = min(k, len(r.t) - 1)
    ax.plot([r.t[k]], [values[k]], **TRIP_STYLE)
    return True


def _add_zoom(
    ax: Any, runs: Sequence[tuple[str, Any]], axis: int, window: tuple[float, float], colour: str
) -> None:
    """An inset magnifying ``window`` (s), placed where the traces leave room for it."""
    t0, t1 = window
    late = [r.force_true[r.t > t1, axis] for _, r in runs]
    late_mean = float(np.nanmean(np.concatenate(late))) if any(x.size for x in late) else 0.0
    lo, hi = ax.get_ylim()
    upper = (late_mean - lo) / (hi - lo) > 0.5  # the settled trace runs along the top
    ins = ax.inset_axes([0.5, 0.1 if upper else 0.42, 0.47, 0.5])
    ys: list[float] = []
    for label, r in runs:
        keep = (r.t >= t0) & (r.t <= t1)
        ins.plot(r.t[keep], r.force_true[keep, axis], color=colour, **gains_style(label))
        ins.plot(r.t[keep], r.setpoint[keep, axis], **SETPOINT_STYLE)
        ys += [
            float(np.nanmin(r.force_true[keep, axis])),
            float(np.nanmax(r.force_true[keep, axis])),
        ]
    pad = 0.08 * (max(ys) - min(ys) or 1.0)
    ins.set_xlim(t0, t1)
    ins.set_ylim(min(ys) - pad, max(ys) + pad)
    ins.tick_params(labelsize=7)
    ins.grid(alpha=0.3)
    ins.set_title(f"zoom: {(t1 - t0) * 1e3:.0f} ms", fontsize=7, pad=2)
    ax.indicate_inset_zoom(ins, edgecolor="0.35")


def _error_while_moving(ax: Any, runs: Sequence[tuple[str, Any]], axis: int, colour: str) -> bool:
    """Plot set point - true force where ``rms_error`` counts it (the path moving, after the
    contact transient), zoomed to that window; True if a run tripped there."""
    from fuzzkit.studies.metrics import moving_window

    tripped = False
    spans: list[float] = []
    rms: list[str] = []
    for label, r in runs:
        window = moving_window(r, axis)
        err = np.where(window, r.setpoint[:, axis] - r.force_true[:, axis], np.nan)
        ax.plot(r.t, err, color=colour, label=f"{label} gains", **gains_style(label))
        if window.any():
            rms.append(f"{label} {math.sqrt(float(np.nanmean(err**2))):.2f} N")
        k = _trip_index(r)
        if k is not None and k < len(r.t) and window[: k + 1].any():
            tripped |= _mark_trip(ax, r, np.nan_to_num(err))
        if window.any():
            spans += [float(r.t[window][0]), float(r.t[window][-1])]
    ax.axhline(0.0, **SETPOINT_STYLE)
    if rms:
        ax.set_title("RMS error while moving: " + ", ".join(rms), fontsize=8, loc="left")
    if spans:
        ax.set_xlim(min(spans), max(spans))
    return tripped


def force_figure(
    results: Mapping[tuple[str, str], Any],
    title: str,
    zoom_s: float | None = None,
    error_while_moving: bool = False,
) -> Any:
    """Force vs time per controlled axis, one column per controller in its own colour, every
    gains set and the set point in every panel, and one legend for the figure.

    ``results`` maps ``(controller, gains label)`` to a ``RunResult`` of one experiment. The
    panels of a row share their y scale, so the controllers compare at a glance; a run that
    tripped the safety limit carries a red cross where it tripped. With ``zoom_s``, every panel
    gets an inset magnifying ``zoom_s`` seconds from just before the first contact, where a
    short transient (E1's impact) is invisible at the full time scale. With
    ``error_while_moving``, a last row shows the first axis's force error where the RMS error
    while moving counts it (E2's claim), zoomed to that window.
    """
    any_run = next(iter(results.values()))
    exp = any_run.experiment
    axes_idx = [i for i in (2, 0, 1) if exp.selection[i]]
    controllers = list(dict.fromkeys(c for c, _ in results))
    rows = len(axes_idx) + (1 if error_while_moving else 0)
    height = 2.7 * rows + 1.0
    fig = new_figure(10.0, height)
    grid = fig.subplots(rows, len(controllers), squeeze=False, sharey="row")
    for row in range(1, len(axes_idx)):  # the force rows share time; the error row zooms
        for col in range(len(controllers)):
            grid[row][col].sharex(grid[0][col])
    contact = _first_contact_s(results) if zoom_s else None
    tripped = False
    order = tuple(controllers)
    for col, ctrl in enumerate(controllers):
        colour = controller_colour(ctrl, order)
        runs = [(label, r) for (c, label), r in results.items() if c == ctrl]
        for row, i in enumerate(axes_idx):
            ax = grid[row][col]
            for label, r in runs:
                ax.plot(r.t, r.force_true[:, i], color=colour, **gains_style(label))
                tripped |= _mark_trip(ax, r, r.force_true[:, i])
            ax.plot(any_run.t, any_run.setpoint[:, i], **SETPOINT_STYLE)
            ax.set_ylabel(f"true f{'xyz'[i]} [N]")
            ax.grid(alpha=0.3)
            if row == 0:
                ax.set_title(controller_name(ctrl), color=colour, fontweight="bold")
            if row < len(axes_idx) - 1:
                ax.tick_params(labelbottom=False)
            else:
                ax.set_xlabel("time [s]")
            if contact is not None and zoom_s is not None:
                start = max(float(any_run.t[0]), contact - 0.2 * zoom_s)
                _add_zoom(ax, runs, i, (start, start + zoom_s), colour)
        if error_while_moving:
            ax = grid[-1][col]
            tripped |= _error_while_moving(ax, runs, axes_idx[0], colour)
            axis = "xyz"[axes_idx[0]]
            ax.set_ylabel(f"{axis} error while moving [N]")
            ax.set_xlabel("time [s] (the RMS error while moving counts this window)")
            ax.grid(alpha=0.3)
    for row in range(rows):
        for col in range(1, len(controllers)):
            grid[row][col].tick_params(labelleft=True)  # shared scale, but every panel reads
    labels = list(dict.fromkeys(label for _, label in results))
    handles, names = gains_legend(labels, tripped)
    # Title, then the legend, then the panels, spaced in inches whatever the figure's height.
    fig.suptitle(title, fontsize=11, y=1 - 0.06 / height)
    fig.legend(
        handles,
        names,
        loc="upper center",
        ncol=len(names),
        bbox_to_anchor=(0.5, 1 - 0.3 / height),
    )
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.58 / height))
    return fig


def _strip(ax: Any, names: Sequence[str], title: str) -> None:
    """A row of markers per series under a log-x panel (``x`` at the stiffnesses it names)."""
    ax.set_yticks(range(len(names)), names)
    ax.set_ylim(-0.7, len(names) - 0.3)
    ax.tick_params(axis="y", labelsize=7)
    ax.set_title(title, fontsize=8, loc="left", pad=3)
    ax.grid(alpha=0.3, axis="x", which="both")
    ax.set_xlabel("environment stiffness [N/mm]")


def _metric(rows: Sequence[tuple[float, Any]], key: str, tripped: Any) -> Any:
    """Metric ``key`` of every row, NaN where it is None or the run tripped."""
    raw = [math.nan if m[key] is None else m[key] for _, m in rows]
    return np.where(tripped, math.nan, np.array(raw, dtype=float))


def plain_log_ticks(axis: Any) -> None:
    """Label a log axis with plain numbers (``1.5``, ``0.2``, ``10``), not ``1.5 x 10^0``;
    its minor ticks too when the axis spans too little for the decades to say much: all of
    them under 0.7 of a decade, those at 2, 3 and 5 up to 1.3 decades, none beyond."""

    def minor(x: float, _pos: int) -> str:
        low, high = sorted(axis.get_view_interval())
        span = math.log10(high / low) if low > 0 else math.inf
        mantissa = round(x / 10 ** math.floor(math.log10(x) + 1e-9), 6) if x > 0 else 0.0
        shown = span < 0.7 or (span <= 1.3 and mantissa in (2.0, 3.0, 5.0))
        return f"{x:g}" if shown else ""

    axis.set_major_formatter(FuncFormatter(lambda x, _pos: f"{x:g}"))
    axis.set_minor_formatter(FuncFormatter(minor))


def stiffness_figure(
    study: Mapping[tuple[str, str], Sequence[tuple[float, Any]]], plant: str = "planar"
) -> Any:
    """Overshoot and settling time against environment stiffness, per (controller, gains).

    ``study`` maps ``(controller, label)`` to ``[(stiffness N/mm, z-axis metrics)]`` (a
    ``tripped`` entry, when true, marks a run that tripped the safety limit). Both axes are
    logarithmic; overshoots below :data:`OVERSHOOT_FLOOR_PCT` sit on the floor with a triangle
    marker. Runs that tripped are not plotted as overshoot or settling time (they describe a
    stopped controller) but as red crosses in a row of their own under the overshoot; runs
    that never settle, as crosses in a row under the settling time, not at an invented time.
    Each controller has its colour (:mod:`fuzzkit.viz.palette`), each gains set its line.
    """
    series = list(study.items())
    order = tuple(dict.fromkeys(c for c, _ in study))
    fig = new_figure(10.0, 5.0)
    spec = fig.add_gridspec(2, 2, height_ratios=(3.2, 1.3), hspace=0.25, wspace=0.3)
    ax1 = fig.add_subplot(spec[0, 0])
    ax2 = fig.add_subplot(spec[0, 1], sharex=ax1)
    trip_ax = fig.add_subplot(spec[1, 0], sharex=ax1)
    never_ax = fig.add_subplot(spec[1, 1], sharex=ax1)
    floor_used = False
    for row, ((ctrl, label), rows) in enumerate(series):
        colour = controller_colour(ctrl, order)
        style = gains_style(label)
        name = f"{controller_name(ctrl)} {label}"
        ks = np.array([k for k, _ in rows])
        tripped = np.array([bool(m.get("tripped", False)) for _, m in rows], dtype=bool)
        over = _metric(rows, "overshoot_pct", tripped)
        low = over < OVERSHOOT_FLOOR_PCT
        floor_used |= bool(low.any())
        ax1.plot(ks, np.maximum(over, OVERSHOOT_FLOOR_PCT), color=colour, label=name, **style)
        ax1.plot(ks[over >= OVERSHOOT_FLOOR_PCT], over[over >= OVERSHOOT_FLOOR_PCT], "o", ms=3.5,
                 color=colour)  # fmt: skip
        ax1.plot(ks[low], np.full(int(low.sum()), OVERSHOOT_FLOOR_PCT), "v", ms=6, color=colour)
        settle = _metric(rows, "settling_time_s", tripped)
        ax2.plot(ks, settle, marker="o", ms=3.5, color=colour, label=name, **style)
        never = np.isnan(settle) & ~tripped
        never_ax.plot(ks[never], np.full(int(never.sum()), row), "x", ms=8, mew=2, color=colour)
        trip_ax.plot(ks[tripped], np.full(int(tripped.sum()), row), **TRIP_STYLE)
    studied = sorted({k for rows in study.values() for k, _ in rows})
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_yscale("log")
        plain_log_ticks(ax.yaxis)
        ax.grid(alpha=0.3, which="both")
        ax.tick_params(labelbottom=False)
    # the stiffnesses studied, as numbers, are the x ticks (shared by the four panels)
    ax1.set_xticks(studied, [f"{k:g}" for k in studied])
    ax1.xaxis.set_minor_locator(NullLocator())
    ax1.set_ylabel("overshoot [%]")
    if floor_used:
        ax1.text(
            0.02,
            0.02,
            f"▼ overshoot below {OVERSHOOT_FLOOR_PCT:g} %",
            transform=ax1.transAxes,
            fontsize=8,
        )
    ax2.set_ylabel("settling time [s]")
    names = [f"{controller_name(c)} {g}" for (c, g), _ in series]
    _strip(trip_ax, names, f"red X = {TRIP_LABEL}: stopped, no overshoot to plot")
    _strip(never_ax, names, "x = never settled (within the run)")
    # each series as it is drawn: its line style with the dots on it
    handles = [
        Line2D([], [], color=controller_colour(c, order), marker="o", ms=3.5, **gains_style(g))
        for c, g in study
    ]
    fig.legend(handles, names, loc="upper center", ncol=len(names), bbox_to_anchor=(0.5, 0.93))
    fig.suptitle(f"press 10 N on the hammer ({plant} plant)", fontsize=11)
    fig.subplots_adjust(left=0.1, right=0.98, top=0.84, bottom=0.1)
    return fig
