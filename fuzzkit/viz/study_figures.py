"""Figures of the PI vs fuzzy-PI comparison: force against time, and the stiffness study.

Both return a :class:`matplotlib.figure.Figure` (own Agg canvas, no pyplot); the report renders
them to PNG with :func:`fuzzkit.viz.figures.figure_bytes`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from fuzzkit.viz.figures import new_figure

#: How each gains set is drawn: the default as a wide pale band under the tuned line, so both
#: stay visible where they coincide. (colour, line width, alpha, zorder)
GAINS_STYLE: dict[str, tuple[str, float, float, int]] = {
    "default": ("tab:orange", 3.0, 0.55, 2),
    "matched": ("tab:green", 1.6, 0.8, 3),
    "tuned": ("tab:blue", 1.1, 1.0, 3),
}
SETPOINT_STYLE = {"color": "black", "ls": "--", "lw": 0.9, "zorder": 4}
CONTROLLER_NAMES = {"pi": "PI", "fuzzy-pi": "fuzzy-PI"}
#: Overshoots below this (%) are drawn on the floor of the log axis, with their own marker.
OVERSHOOT_FLOOR_PCT = 0.1


def _controller_name(ctrl: str) -> str:
    return CONTROLLER_NAMES.get(ctrl, ctrl)


def _first_contact_s(results: Mapping[tuple[str, str], Any]) -> float | None:
    """The earliest time any run touches something (where the transient starts)."""
    times = [float(r.t[np.argmax(r.in_contact)]) for r in results.values() if r.in_contact.any()]
    return min(times) if times else None


def _add_zoom(
    ax: Any, runs: Sequence[tuple[str, Any]], axis: int, window: tuple[float, float]
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
        colour, lw, alpha, z = GAINS_STYLE.get(label, ("tab:gray", 1.0, 1.0, 2))
        keep = (r.t >= t0) & (r.t <= t1)
        ins.plot(r.t[keep], r.force_true[keep, axis], color=colour, lw=lw, alpha=alpha, zorder=z)
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


def force_figure(
    results: Mapping[tuple[str, str], Any], title: str, zoom_s: float | None = None
) -> Any:
    """Force vs time per controlled axis, one column per controller, both gains sets and the set
    point in every panel, and one legend for the figure.

    ``results`` maps ``(controller, gains label)`` to a ``RunResult`` of one experiment. With
    ``zoom_s``, every panel gets an inset magnifying ``zoom_s`` seconds from just before the
    first contact, where a short transient (E1's impact) is invisible at the full time scale.
    """
    any_run = next(iter(results.values()))
    exp = any_run.experiment
    axes_idx = [i for i in (2, 0, 1) if exp.selection[i]]
    controllers = list(dict.fromkeys(c for c, _ in results))
    height = 2.7 * len(axes_idx) + 1.0
    fig = new_figure(10.0, height)
    grid = fig.subplots(len(axes_idx), len(controllers), squeeze=False, sharex=True)
    contact = _first_contact_s(results) if zoom_s else None
    for col, ctrl in enumerate(controllers):
        runs = [(label, r) for (c, label), r in results.items() if c == ctrl]
        for row, i in enumerate(axes_idx):
            ax = grid[row][col]
            for label, r in runs:
                colour, lw, alpha, z = GAINS_STYLE.get(label, ("tab:gray", 1.0, 1.0, 2))
                ax.plot(
                    r.t,
                    r.force_true[:, i],
                    color=colour,
                    lw=lw,
                    alpha=alpha,
                    zorder=z,
                    label=f"{label} gains",
                )
            ax.plot(any_run.t, any_run.setpoint[:, i], label="set point", **SETPOINT_STYLE)
            ax.set_ylabel(f"f{'xyz'[i]} [N]")
            ax.grid(alpha=0.3)
            if row == 0:
                ax.set_title(_controller_name(ctrl))
            if row == len(axes_idx) - 1:
                ax.set_xlabel("time [s]")
            if contact is not None and zoom_s is not None:
                start = max(float(any_run.t[0]), contact - 0.2 * zoom_s)
                _add_zoom(ax, runs, i, (start, start + zoom_s))
    handles, labels = grid[0][0].get_legend_handles_labels()
    # Title, then the legend, then the panels, spaced in inches whatever the figure's height.
    fig.suptitle(title, fontsize=11, y=1 - 0.06 / height)
    fig.legend(
        handles,
        labels,
        loc="upper center",
        ncol=len(labels),
        bbox_to_anchor=(0.5, 1 - 0.3 / height),
    )
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.58 / height))
    return fig


def stiffness_figure(study: Mapping[tuple[str, str], Sequence[tuple[float, Any]]]) -> Any:
    """Overshoot and settling time against environment stiffness, per (controller, gains).

    ``study`` maps ``(controller, label)`` to ``[(stiffness N/mm, z-axis metrics)]``. Both
    axes are logarithmic; overshoots below :data:`OVERSHOOT_FLOOR_PCT` sit on the floor with a
    triangle marker, and runs that never settle are shown in a row of their own marked "never
    settled" instead of at an invented time.
    """
    colours = {"pi": "tab:orange", "fuzzy-pi": "tab:blue"}
    series = list(study.items())
    fig = new_figure(10.0, 4.6)
    spec = fig.add_gridspec(2, 2, height_ratios=(3.2, 1.2), hspace=0.22, wspace=0.3)
    ax1 = fig.add_subplot(spec[:, 0])
    ax2 = fig.add_subplot(spec[0, 1])
    never_ax = fig.add_subplot(spec[1, 1], sharex=ax2)
    floor_used = False
    for row, ((ctrl, label), rows) in enumerate(series):
        colour = colours.get(ctrl, "tab:gray")
        ls = {"tuned": "-", "matched": ":"}.get(label, "--")
        name = f"{_controller_name(ctrl)} {label}"
        ks = np.array([k for k, _ in rows])
        over = np.array(
            [math.nan if m["overshoot_pct"] is None else m["overshoot_pct"] for _, m in rows]
        )
        low = over < OVERSHOOT_FLOOR_PCT
        floor_used |= bool(low.any())
        ax1.plot(ks, np.maximum(over, OVERSHOOT_FLOOR_PCT), ls=ls, color=colour, label=name)
        ax1.plot(ks[~low], over[~low], "o", ms=3.5, color=colour)
        ax1.plot(ks[low], np.full(int(low.sum()), OVERSHOOT_FLOOR_PCT), "v", ms=6, color=colour)
        settle = np.array(
            [math.nan if m["settling_time_s"] is None else m["settling_time_s"] for _, m in rows]
        )
        ax2.plot(ks, settle, ls=ls, marker="o", ms=3.5, color=colour, label=name)
        never = np.isnan(settle)
        never_ax.plot(ks[never], np.full(int(never.sum()), row), "x", ms=8, mew=2, color=colour)
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(alpha=0.3, which="both")
    ax1.set_xlabel("environment stiffness [N/mm]")
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
    ax2.tick_params(labelbottom=False)
    never_ax.set_yticks(range(len(series)), [f"{_controller_name(c)} {g}" for (c, g), _ in series])
    never_ax.set_ylim(-0.7, len(series) - 0.3)
    never_ax.tick_params(axis="y", labelsize=7)
    never_ax.set_title("x = never settled (within the run)", fontsize=8, loc="left", pad=3)
    never_ax.grid(alpha=0.3, axis="x", which="both")
    never_ax.set_xlabel("environment stiffness [N/mm]")
    handles, labels = ax1.get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=len(labels), bbox_to_anchor=(0.5, 0.93))
    fig.suptitle("press 10 N on the hammer (planar plant)", fontsize=11)
    fig.subplots_adjust(left=0.07, right=0.98, top=0.84, bottom=0.11)
    return fig
