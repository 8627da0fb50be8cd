"""A static figure of a few runs' true contact forces, one panel per force-controlled axis.

For documentation and quick looks (the report has its own, per gains label); each panel shows
every run's true force and the set point, so runs of different controllers or gains can be
compared on the same scale.
"""

from __future__ import annotations

import io
from collections.abc import Mapping

from fuzzkit.loop.result import RunResult
from fuzzkit.viz.palette import controller_colour


def force_axes_png(runs: Mapping[str, RunResult], title: str) -> bytes:
    """PNG bytes: true force against time per force-controlled axis, one line per run.

    ``runs`` maps a legend label to a run; all runs must be of the same experiment. Each run
    is drawn in its controller's colour (:mod:`fuzzkit.viz.palette`).
    """
    from matplotlib.figure import Figure

    first = next(iter(runs.values()))
    exp = first.experiment
    axes_idx = [i for i in (2, 0, 1) if exp.selection[i]]
    fig = Figure(figsize=(8.0, 2.3 * len(axes_idx) + 0.6))
    order = tuple(dict.fromkeys(r.controller for r in runs.values()))
    grid = fig.subplots(len(axes_idx), 1, squeeze=False, sharex=True)
    for row, i in enumerate(axes_idx):
        ax = grid[row][0]
        for label, r in runs.items():
            colour = controller_colour(r.controller, order)
            ax.plot(r.t, r.force_true[:, i], color=colour, lw=0.9, label=label)
        ax.plot(first.t, first.setpoint[:, i], "k--", lw=0.8, label="set point")
        ax.set_ylabel(f"true f{'xyz'[i]} (N)")
        ax.grid(alpha=0.3)
    grid[-1][0].set_xlabel("time (s)")
    grid[0][0].legend(fontsize=8, loc="lower right")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()
