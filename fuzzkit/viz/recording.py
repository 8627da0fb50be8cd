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
    path: str | os.PathLike[str], application_id: str, recording_id: str, **kwargs: Any
) -> Iterator[Any]:
    """A ``rr.RecordingStream`` whose data lands in ``path`` atomically when the block ends.

    Raises
    ------
    ConfigError
        If ``path`` is a folder or its folder does not exist.
    """
    import rerun as rr

    with atomic_output(path, what=".rrd file") as tmp:
        rec = rr.RecordingStream(application_id, recording_id=recording_id, **kwargs)
        # saving first sends everything logged afterwards into the file
        rec.save(tmp)
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
