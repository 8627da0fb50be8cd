"""Rerun recording plumbing shared by every writer of .rrd files (runs, 3-D runs, surfaces).

A recording is saved straight to a file (no viewer is spawned) and appears only when complete:
it is written to a temporary file that is renamed on success.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.fileio import atomic_output


@contextmanager
def open_recording(
    path: str | os.PathLike[str],
    application_id: str,
    recording_id: str,
    blueprint: Any = None,
    **kwargs: Any,
) -> Iterator[Any]:
    """A ``rr.RecordingStream`` whose data lands in ``path`` atomically when the block ends.

    ``blueprint`` (``fuzzkit.viz.blueprints``) is stored in the file as its default layout:
    the viewer opens on it instead of an automatic one.

    Raises
    ------
    ConfigError
        If ``path`` is a folder or its folder does not exist.
    """
    import rerun as rr

    with atomic_output(path, what=".rrd file") as tmp:
        rec = rr.RecordingStream(application_id, recording_id=recording_id, **kwargs)
        # saving first sends everything logged afterwards into the file
        rec.save(tmp, default_blueprint=blueprint)
        try:
            yield rec
        finally:
            rec.flush()
            rec.disconnect()


def log_series(
    rec: Any,
    entity: str,
    times: Any,
    values: npt.ArrayLike,
    name: str,
    colour: tuple[int, int, int],
) -> None:
    """Log a whole time series (one column per ``times``) with its line style."""
    import rerun as rr

    rec.log(entity, rr.SeriesLines(colors=[colour], names=[name]), static=True)
    rec.send_columns(
        entity,
        indexes=[times],
        columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)),
    )


#: The colours of the scene's axis arrows: x red, y green, z blue.
AXIS_ARROW_COLOURS = ((230, 80, 60), (60, 170, 80), (60, 110, 230))


def log_axes(
    rec: Any,
    entity: str,
    labels: tuple[str, str, str],
    length: float | tuple[float, float, float],
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> None:
    """Log three labelled arrows (x red, y green, z blue) from ``origin``: the scene's axes.

    Rerun draws no axis titles in 3-D views; these say what each direction is and its unit.
    """
    import rerun as rr

    lx, ly, lz = (length, length, length) if isinstance(length, float | int) else length
    rec.log(
        entity,
        rr.Arrows3D(
            origins=[origin] * 3,
            vectors=[(lx, 0.0, 0.0), (0.0, ly, 0.0), (0.0, 0.0, lz)],
            colors=list(AXIS_ARROW_COLOURS),
            labels=list(labels),
            show_labels=True,
        ),
        static=True,
    )
