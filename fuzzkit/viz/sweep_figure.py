"""The summary figure of a sweep: each force-control metric per case, one colour per series.

A series is a controller, or a controller spec (:func:`series_of`: two specs are two series, never
one average), named in the legend. A case is one (experiment, stiffness, latency, gains)
combination; every seed is a dot and the mean of the dots a bar, so the spread over sensor noise
shows next to the difference between controllers. No run is dropped: a run that never settled is a
cross on the top edge of the settling-time panel, and a run that tripped the safety limit (its
overshoot, settling and steady error describe a stopped controller) a red cross on the top edge of
those panels; its peak force, what tripped it, is plotted.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fuzzkit.studies.outcome import NEVER_SETTLED
from fuzzkit.units import latency_text
from fuzzkit.viz.figures import figure_bytes, new_figure
from fuzzkit.viz.palette import TRIP_LABEL, TRIP_STYLE, controller_colour, controller_name

#: (column suffix, axis label, meaningless once tripped) of the metrics shown, for one axis.
METRICS = (
    ("overshoot_pct", "overshoot [%]", True),
    ("settling_time_s", "settling time [s]", True),
    ("steady_state_error_std", "steady error std [N]", True),
    ("peak_force", "peak force [N]", False),
)
#: The metric whose missing value means "never settled" (others are missing for no contact).
SETTLING = "settling_time_s"
NEVER_SETTLED_LABEL = NEVER_SETTLED  # the outcome word (fuzzkit.studies.outcome)


def case_label(row: Mapping[str, Any]) -> str:
    """Short name of a row's case (everything but controller and seed), with units."""
    k = row.get("stiffness_n_per_mm")
    parts = [
        str(row["experiment"]),
        "own stiffness" if k is None else f"{k:g} N/mm",
        f"latency {latency_text((row['sensor_delay'], row['command_delay']))} periods",
    ]
    if row.get("gains", "default") != "default" and not row.get("controller_spec"):
        parts.append(Path(str(row["gains"])).stem)
    return "\n".join(parts)


def series_of(row: Mapping[str, Any]) -> str:
    """The series a row belongs to: its controller, or its controller spec (``spec a``), so
    that two specs of one kind are never averaged together as if they were seeds."""
    spec = row.get("controller_spec")
    return f"spec {Path(str(spec)).stem}" if spec else str(row["controller"])


def _series_name(series: str, rows: Sequence[Mapping[str, Any]]) -> str:
    """The legend's name of a series: ``PI``, or ``spec a (fuzzy-PI)``."""
    if not series.startswith("spec "):
        return controller_name(series)
    kind = next(str(r["controller"]) for r in rows if series_of(r) == series)
    return f"{series} ({controller_name(kind)})"


def _tripped(row: Mapping[str, Any]) -> bool:
    return bool(row.get("tripped", False))


def sweep_figure(rows: Sequence[Mapping[str, Any]], axis: str = "z") -> Any:
    """The sweep summary as a Figure (no pyplot): one panel per metric of :data:`METRICS`.

    Rows are the sweep table's (``fuzzkit.studies.batch.execute``); the title names the
    plant(s), the axis and the run count.
    """
    from matplotlib.transforms import blended_transform_factory

    cases = list(dict.fromkeys(case_label(r) for r in rows))
    controllers = list(dict.fromkeys(series_of(r) for r in rows))
    plants = list(dict.fromkeys(str(r.get("plant", "?")) for r in rows))
    fig = new_figure(max(7.0, 1.3 * len(cases) + 3.0), 2.3 * len(METRICS) + 1.2)
    axes = fig.subplots(len(METRICS), 1, sharex=True, squeeze=False)[:, 0]
    width = 0.8 / max(1, len(controllers))
    order = tuple(controllers)
    marked = {"never": False, "trip": False}
    for ax, (metric, label, stops) in zip(axes, METRICS, strict=True):
        col = f"{axis}_{metric}"
        top = blended_transform_factory(ax.transData, ax.transAxes)
        for ci, ctrl in enumerate(controllers):
            colour = controller_colour(ctrl, order)
            offset = (ci - (len(controllers) - 1) / 2) * width
            xs: list[float] = []
            ys: list[float] = []
            edge: dict[str, list[float]] = {"never": [], "trip": []}
            means: list[float] = []
            for i, case in enumerate(cases):
                mine = [r for r in rows if series_of(r) == ctrl and case_label(r) == case]
                vals: list[float] = []
                marks: dict[str, int] = {"never": 0, "trip": 0}
                for r in mine:
                    if stops and _tripped(r):
                        marks["trip"] += 1
                    elif r.get(col) is not None:
                        vals.append(float(r[col]))
                    elif metric == SETTLING:
                        marks["never"] += 1
                for kind, n in marks.items():  # side by side, one per run, within the bar
                    spread = np.linspace(-0.3, 0.3, n) * width if n > 1 else np.zeros(n)
                    edge[kind].extend(float(i + offset + d) for d in spread)
                xs.extend([i + offset] * len(vals))
                ys.extend(vals)
                means.append(sum(vals) / len(vals) if vals else float("nan"))
            centres = [i + offset for i in range(len(cases))]
            ax.bar(centres, means, width=width * 0.9, color=colour, alpha=0.35)
            ax.plot(xs, ys, "o", color=colour, markersize=3)
            if edge["never"]:
                ax.plot(edge["never"], [0.97] * len(edge["never"]), "x", ms=8, mew=2,
                        color=colour, transform=top, clip_on=False)  # fmt: skip
                marked["never"] = True
            if edge["trip"]:
                ax.plot(edge["trip"], [0.97] * len(edge["trip"]), transform=top, clip_on=False,
                        **TRIP_STYLE)  # fmt: skip
                marked["trip"] = True
        ax.set_ylabel(label)
        ax.grid(axis="y", alpha=0.3)
        ax.set_ylim(bottom=0.0, top=ax.get_ylim()[1] * 1.12 or 1.0)  # room for the edge marks
    axes[-1].set_xticks(range(len(cases)))
    axes[-1].set_xticklabels(cases, fontsize=8)
    height = fig.get_figheight()
    fig.suptitle(
        f"sweep on the {', '.join(plants)} plant: {len(rows)} runs, force axis {axis} "
        f"(dots: seeds, bars: mean of the plotted dots)",
        fontsize=10,
        y=1 - 0.06 / height,
    )
    _legend(
        fig, controllers, marked, 1 - 0.3 / height, [_series_name(s, rows) for s in controllers]
    )
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.6 / height))
    return fig


def _legend(
    fig: Any,
    controllers: Sequence[str],
    marked: Mapping[str, bool],
    top: float,
    names: Sequence[str],
) -> None:
    """One legend above the panels: each series' colour and name, and the edge marks used."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    order = tuple(controllers)
    handles: list[Any] = [
        Patch(color=controller_colour(c, order), alpha=0.6, label=name)
        for c, name in zip(controllers, names, strict=True)
    ]
    if marked["never"]:
        handles.append(Line2D([], [], marker="x", ms=8, mew=2, color="0.3", ls="none",
                              label=f"{NEVER_SETTLED_LABEL} (top edge)"))  # fmt: skip
    if marked["trip"]:
        handles.append(Line2D([], [], label=f"{TRIP_LABEL} (top edge)", **TRIP_STYLE))
    fig.legend(
        handles=handles,
        loc="upper center",
        ncol=len(handles),
        fontsize=8,
        bbox_to_anchor=(0.5, top),
        frameon=False,
    )


def write_sweep_figure(
    rows: Sequence[Mapping[str, Any]], path: str | os.PathLike[str], axis: str = "z"
) -> Path:
    """Render :func:`sweep_figure` to a PNG at ``path``, atomically."""
    from fuzzkit.fileio import write_atomic

    return write_atomic(path, figure_bytes(sweep_figure(rows, axis)))
