"""The certified region of ``fuzzkit stability`` as a figure: stiffness x latency cells, each
certified (with or without loss of contact) or not, and optionally the simulated outcome."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from fuzzkit.analysis.region import Region
from fuzzkit.studies.outcome import OSCILLATING, SETTLED, TRIPPED
from fuzzkit.units import latency_text

#: Fill colour per verdict, and the marker per simulated outcome.
_FILL = {
    "contact loss": "#2e7d32",
    "contact held": "#9ccc65",
    "stable, noisy": "#fff176",
    "stable, off set point": "#ffb74d",
    "not certified": "#e0e0e0",
}
_MARK = {SETTLED: ("o", "#1b5e20"), OSCILLATING: ("^", "#e65100"), TRIPPED: ("x", "#b71c1c")}


def _verdict(cell: Any, at_setpoint: bool) -> str:
    if cell.certified:
        return "contact held" if cell.contact_sector == (1.0, 1.0) else "contact loss"
    if not cell.stable:
        return "not certified"
    return "stable, noisy" if at_setpoint else "stable, off set point"


def region_figure(region: Region, simulated: Sequence[str] | None = None) -> Any:
    """A matplotlib Figure of the region (built without pyplot)."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    ks = sorted({c.stiffness_n_per_mm for c in region.cells})
    lats = list(dict.fromkeys(c.latency for c in region.cells))
    # constrained layout keeps the axis labels, the two-line title and the legend whole
    fig = Figure(
        figsize=(4.6 + 0.75 * len(ks), 2.6 + 0.45 * len(lats)), dpi=110, layout="constrained"
    )
    ax = fig.add_subplot(1, 1, 1)
    at_setpoint = bool(region.model["equilibrium"]["at_setpoint"])
    for idx, cell in enumerate(region.cells):
        x, y = ks.index(cell.stiffness_n_per_mm), lats.index(cell.latency)
        ax.add_patch(_rect(x, y, _FILL[_verdict(cell, at_setpoint)]))
        if cell.certified:
            # the certificate is local: within region_n of the set point
            ax.text(x, y - 0.3, f"±{cell.region_n:.3g}", ha="center", va="center", fontsize=7)
        if simulated is not None:
            marker, colour = _MARK[simulated[idx]]
            ax.plot(x, y, marker, color=colour, ms=9, mew=2, mfc="none")
    ax.set_xlim(-0.5, len(ks) - 0.5)
    ax.set_ylim(-0.5, len(lats) - 0.5)
    ax.set_xticks(range(len(ks)), [f"{k:g}" for k in ks])
    ax.set_yticks(range(len(lats)), [latency_text(lat) for lat in lats])
    period_ms = 1e3 * float(region.model["period_s"])
    ax.set_xlabel("contact stiffness (N/mm)")
    ax.set_ylabel(f"latency sensor:command\n(periods of {period_ms:g} ms)")
    ax.set_title(region_title(region.model), fontsize=9)
    handles: list[Any] = [
        Patch(facecolor=_FILL["contact loss"], label="certified (contact may be lost)"),
        Patch(facecolor=_FILL["contact held"], label="certified while contact is held"),
        Patch(facecolor=_FILL["stable, noisy"], label="stable, but noise > band"),
        Patch(facecolor=_FILL["stable, off set point"], label="stable, rest point off set point"),
        Patch(facecolor=_FILL["not certified"], label="not certified"),
        Patch(facecolor="none", edgecolor="none", label="±x: holds within x N (region_n)"),
    ]
    if simulated is not None:
        from matplotlib.lines import Line2D

        handles += [
            Line2D([], [], ls="", marker=mk, color=col, mfc="none", mew=2, label=f"sim: {name}")
            for name, (mk, col) in _MARK.items()
        ]
    fig.legend(handles=handles, loc="outside right upper", fontsize=8)
    return fig


def region_title(model: Mapping[str, Any]) -> str:
    """The figure's title: the task, the controller and plant, then what is certified (the
    spec and its axis, or the rule base and surface) and its gains."""
    deployed = model["deployed"]
    if deployed.get("assumed"):
        # "fuzzy-pi (kp=0.2, ...) on macvicar_whelan (exact surface)": name it, gains below
        what = deployed["controller"].split(" (", 1)[0]
        if " on " in deployed["controller"]:
            what += " on " + deployed["controller"].split(" on ", 1)[1]
    else:
        what = f"spec {deployed['spec']}, axis {deployed['axis']}, surface {deployed['surface']}"
    gains = model.get("gains", {})
    shown = ", ".join(f"{k}={gains[k]:g}" for k in ("kp", "ki", "kx") if k in gains)
    return f"{model['scenario']}: {model['controller']} on {model['plant']}\n{what}\n{shown}"


def _rect(x: int, y: int, colour: str) -> Any:
    from matplotlib.patches import Rectangle

    return Rectangle((x - 0.48, y - 0.48), 0.96, 0.96, facecolor=colour, edgecolor="white")


def write_region_png(
    region: Region, path: str | os.PathLike[str], simulated: Sequence[str] | None = None
) -> Path:
    """Draw :func:`region_figure` and write it as a PNG, atomically."""
    from fuzzkit.viz.figures import save_figure

    return save_figure(region_figure(region, simulated), path)
