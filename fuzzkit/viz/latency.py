"""The latency stability boundary of each controller, as a figure and a PNG."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from fuzzkit.fileio import write_atomic
from fuzzkit.studies.latency_sweep import StabilityMap
from fuzzkit.viz.figures import figure_bytes, new_figure
from fuzzkit.viz.palette import controller_colour


def stability_figure(maps: Sequence[StabilityMap], period_ms: float = 4.0) -> Any:
    """Per controller (in its colour), the largest stable delay against the gain factor."""
    fig = new_figure(6.4, 4.2, dpi=110)
    ax = fig.add_subplot(1, 1, 1)
    styles = {"pi": ("o-", "PI"), "fuzzy-pi": ("s--", "fuzzy-PI (macvicar_whelan)")}
    top = 0
    for m in maps:
        marker, label = styles.get(m.controller, ("^-", m.controller))
        bound = m.boundary()
        xs = list(bound)
        ys = [-1 if b is None else b for b in bound.values()]
        top = max(top, *m.delays)
        ax.plot(xs, ys, marker, label=label, color=controller_colour(m.controller))
    ax.set_xscale("log", base=2)
    factors = sorted({f for m in maps for f in m.factors})
    ax.set_xticks(factors, [f"{f:g}" for f in factors])
    ax.minorticks_off()
    ax.set_xlabel("gain factor (x the default gains)")
    ax.set_ylabel(f"largest stable sensor delay (periods of {period_ms:g} ms)")
    ax.set_ylim(-1.5, top + 0.5)
    ax.axhline(top, color="0.8", lw=0.8)
    ax.text(
        factors[-1],
        top - 0.35,
        f"top of the sweep ({top}): stable at every delay tried ",
        fontsize=8,
        ha="right",
    )
    ax.set_title("press 10 N at 10 N/mm: stable below each line")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="lower left")
    fig.tight_layout()
    return fig


def write_stability_png(
    maps: Sequence[StabilityMap], path: str | Path, period_ms: float = 4.0
) -> Path:
    """Write :func:`stability_figure` to a PNG at ``path``, atomically."""
    return write_atomic(path, figure_bytes(stability_figure(maps, period_ms)))
