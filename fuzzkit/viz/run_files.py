"""A run's traces as files without Rerun: the PNG of :mod:`fuzzkit.viz.run_figure` and the CSV
of :mod:`fuzzkit.studies.run_table`, for ``simulate --png/--csv`` and ``compare``/``sweep``
``--png-dir/--csv-dir``. Every file is written atomically (whole or not at all)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fuzzkit.errors import ConfigError
from fuzzkit.fileio import check_output_path, write_atomic
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import result_row, run_spec
from fuzzkit.studies.run_table import run_csv


def check_trace_path(path: str | os.PathLike[str], option: str, suffix: str) -> Path:
    """``path`` when it ends in ``suffix`` and its folder exists; ConfigError naming ``option``."""
    p = Path(path)
    if p.suffix.lower() != suffix:
        raise ConfigError(f"{option} {path}: expected a file name ending in {suffix}")
    return check_output_path(p, f"{option} file")


def check_trace_dir(path: str | os.PathLike[str] | None, option: str) -> Path | None:
    """``path`` as an existing folder (None stays None); ConfigError naming ``option``."""
    if path is None:
        return None
    p = Path(path)
    if not p.is_dir():
        raise ConfigError(f"{option} {path}: folder does not exist")
    return p


@dataclass(frozen=True, slots=True)
class TraceFiles:
    """The contents of a run's trace files (None where not asked for)."""

    png: bytes | None = None
    csv: str | None = None


def trace_files(result: RunResult, png: bool, csv: bool, ran: str | None = None) -> TraceFiles:
    """Render the asked-for traces of ``result`` in memory (``ran``: what ran, for the
    figure's title, :func:`fuzzkit.viz.run_figure.run_figure`)."""
    data: bytes | None = None
    if png:
        from fuzzkit.viz.figures import figure_bytes
        from fuzzkit.viz.run_figure import run_figure

        data = figure_bytes(run_figure(result, ran), "png", dpi=100)
    return TraceFiles(png=data, csv=run_csv(result) if csv else None)


def write_traces(
    files: TraceFiles,
    png: str | os.PathLike[str] | None = None,
    csv: str | os.PathLike[str] | None = None,
) -> list[Path]:
    """Write the rendered traces to ``png`` and ``csv`` (where given), atomically."""
    written = []
    if png is not None and files.png is not None:
        written.append(write_atomic(png, files.png))
    if csv is not None and files.csv is not None:
        written.append(write_atomic(csv, files.csv))
    return written


def write_run_traces(
    result: RunResult,
    png: str | os.PathLike[str] | None = None,
    csv: str | os.PathLike[str] | None = None,
    ran: str | None = None,
) -> list[Path]:
    """Render and write ``result``'s traces to ``png`` and/or ``csv`` (``ran``: what ran, for
    the figure's title)."""
    return write_traces(trace_files(result, png is not None, csv is not None, ran), png, csv)


def execute_traced(item: tuple[RunSpec, bool, bool]) -> tuple[dict[str, Any], TraceFiles]:
    """A batch worker: run ``spec`` and return its row (:func:`fuzzkit.studies.batch.execute`)
    with its traces rendered in memory (``item = (spec, png, csv)``), so that only the parent
    writes files, on whatever machine the run took place."""
    spec, png, csv = item
    result = run_spec(spec)
    return result_row(spec, result), trace_files(result, png, csv)
