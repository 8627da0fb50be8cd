"""Matplotlib figures without pyplot: created, rendered and saved without touching global state.

Every figure fuzzkit makes is a :class:`matplotlib.figure.Figure` with its own Agg canvas, so
nothing here calls ``matplotlib.use`` or ``pyplot``: a notebook's backend (inline, widget) is
left as the user set it, and a Figure returned by the Python API displays there as usual.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

from fuzzkit.errors import ConfigError
from fuzzkit.fileio import write_atomic

#: File formats the figure writers accept, by suffix.
FORMATS = {".png": "png", ".svg": "svg"}


def new_figure(width: float, height: float, dpi: float = 100) -> Any:
    """A blank Figure of ``width`` x ``height`` inches with its own Agg canvas (no pyplot)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def figure_format(path: str | os.PathLike[str], option: str = "output") -> str:
    """The matplotlib format for ``path`` by its suffix; ConfigError naming ``option`` if none."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ConfigError(
            f"{option} {path}: expected a file name ending in "
            f"{' or '.join(FORMATS)}, got {suffix or 'no suffix'!r}"
        )
    return FORMATS[suffix]


def figure_bytes(fig: Any, fmt: str = "png", dpi: float | None = None) -> bytes:
    """The figure rendered as ``fmt`` (png or svg); the same figure gives the same bytes.

    SVGs carry no date, and their element ids come from a fixed salt instead of a random one.
    """
    import matplotlib

    buf = io.BytesIO()
    metadata = {"Date": None} if fmt == "svg" else None
    with matplotlib.rc_context({"svg.hashsalt": "fuzzkit"}):
        fig.savefig(buf, format=fmt, dpi=dpi if dpi is not None else "figure", metadata=metadata)
    return buf.getvalue()


def save_figure(fig: Any, path: str | os.PathLike[str], dpi: float | None = None) -> Path:
    """Write ``fig`` to ``path`` (.png or .svg by suffix) atomically: whole file or none."""
    return write_atomic(path, figure_bytes(fig, figure_format(path), dpi))
