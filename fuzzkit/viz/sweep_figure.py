"""The summary figure of a sweep: each force-control metric per case, one colour per controller.

A case is one (experiment, stiffness, latency, gains) combination; every seed is a dot and the
mean a bar, so the spread over sensor noise shows next to the difference between controllers.
"""

from __future__ import annotations

import io
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

#: (column suffix, axis label) of the metrics shown, for the first force-controlled axis (z).
METRICS = (
    ("overshoot_pct", "overshoot (%)"),
    ("settling_time_s", "settling time (s)"),
    ("steady_state_error_std", "steady error std (N)"),
    ("peak_force", "peak force (N)"),
)


def case_label(row: Mapping[str, Any]) -> str:
    """Short name of a row's case (everything but controller and seed)."""
    k = row.get("stiffness_n_per_mm")
    parts = [
        str(row["experiment"]),
        "k=own" if k is None else f"k={k:g}",
        f"lat={row['sensor_delay']}:{row['command_delay']}",
    ]
    if row.get("gains", "default") != "default":
        parts.append(Path(str(row["gains"])).stem)
    return " ".join(parts)


def write_sweep_figure(
    rows: Sequence[Mapping[str, Any]], path: str | os.PathLike[str], axis: str = "z"
) -> Path:
    """Render the sweep summary to a PNG (matplotlib, Agg), atomically."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from fuzzkit.fileio import write_atomic

    cases = list(dict.fromkeys(case_label(r) for r in rows))
    controllers = list(dict.fromkeys(str(r["controller"]) for r in rows))
    fig = Figure(figsize=(max(7.0, 1.1 * len(cases) + 3.0), 2.4 * len(METRICS)), dpi=100)
    axes = fig.subplots(len(METRICS), 1, sharex=True, squeeze=False)[:, 0]
    width = 0.8 / max(1, len(controllers))
    colours = ("tab:blue", "tab:orange", "tab:green", "tab:red")
    for ax, (metric, label) in zip(axes, METRICS, strict=True):
        col = f"{axis}_{metric}"
        for ci, ctrl in enumerate(controllers):
            xs: list[float] = []
            ys: list[float] = []
            means: list[float] = []
            for i, case in enumerate(cases):
                vals = [
                    float(r[col])
                    for r in rows
                    if r["controller"] == ctrl and case_label(r) == case and r.get(col) is not None
                ]
                x = i + (ci - (len(controllers) - 1) / 2) * width
                xs.extend([x] * len(vals))
                ys.extend(vals)
                means.append(sum(vals) / len(vals) if vals else float("nan"))
            centres = [i + (ci - (len(controllers) - 1) / 2) * width for i in range(len(cases))]
            colour = colours[ci % len(colours)]
            ax.bar(centres, means, width=width * 0.9, color=colour, alpha=0.35, label=ctrl)
            ax.plot(xs, ys, "o", color=colour, markersize=3)
        ax.set_ylabel(label)
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(f"sweep: {len(rows)} runs, force axis {axis} (dots: seeds, bars: mean)")
    axes[-1].set_xticks(range(len(cases)))
    axes[-1].set_xticklabels(cases, rotation=30, ha="right", fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return write_atomic(path, buf.getvalue())
