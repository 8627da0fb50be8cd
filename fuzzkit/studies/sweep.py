"""Sweeps: the cartesian product of run parameters, executed in batch, written as one tidy table.

:func:`sweep_specs` expands the product (experiment x controller x stiffness x latency x gains x
seed, in that nesting order) into :class:`fuzzkit.studies.batch.RunSpec` items;
:func:`run_sweep` executes them with :func:`fuzzkit.studies.batch.map_runs` (local processes or
a Dask cluster) and :func:`write_table` writes one row per run, CSV or Parquet by extension.
"""

from __future__ import annotations

import csv
import io
import itertools
import math
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from fuzzkit.errors import ConfigError
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import execute, gains_items, map_runs

#: Columns that depend on the machine, not on the run (left out when comparing executors).
TIMING_COLUMNS = ("wall_time_s", "cpu_time_s", "real_time_factor")

TABLE_SUFFIXES = (".csv", ".parquet")


def sweep_specs(
    experiments: Sequence[str],
    controllers: Sequence[str],
    *,
    stiffnesses_n_per_mm: Sequence[float | None] = (None,),
    latencies: Sequence[tuple[int, int] | None] = (None,),
    seeds: int = 1,
    gains: Mapping[str, Mapping[str, Mapping[str, float]]] | None = None,
    plant: str = "arm6",
    rulebase: str = "macvicar_whelan",
    loop: str = "auto",
    duration_s: float | None = None,
    controller_specs: Sequence[str] = (),
    controller_impl: str = "auto",
) -> list[RunSpec]:
    """Every combination, as run specs.

    ``controller_specs``: controller spec files, each a value of the sweep in place of the
    ``controllers`` (a spec holds its controller and gains, so ``gains`` must be None).
    ``controller_impl``: which code runs the controller,
    :data:`fuzzkit.loop.spec.CONTROLLER_IMPLS` (:class:`~fuzzkit.loop.spec.RunSpec`).

    ``gains`` maps a label (a gains file name) to per-controller overrides
    (``{label: {controller: {name: value}}}``); None runs the default gains only.
    ``latencies``: ``(sensor, command)`` delays in periods; None: each experiment's own.

    Raises
    ------
    ConfigError
        If a list is empty or ``seeds < 1``.
    """
    if seeds < 1:
        raise ConfigError(f"--seeds must be >= 1 (got {seeds})")
    for what, values in (
        ("experiments", experiments),
        ("controllers", controllers),
        ("stiffnesses", stiffnesses_n_per_mm),
        ("latencies", latencies),
    ):
        if not values:
            raise ConfigError(f"a sweep needs at least one value for {what}")
    gain_sets = gains or {"default": {}}
    choices: list[tuple[str, str | None]] = [(c, None) for c in controllers]
    if controller_specs:
        from fuzzkit.control.spec_reader import load_spec

        if gains:
            raise ConfigError("controller specs hold their gains; give specs or gains, not both")
        choices = [(load_spec(path).kind, path) for path in controller_specs]
    specs = []
    for exp, (ctrl, cspec), k, lat, label, seed in itertools.product(
        experiments, choices, stiffnesses_n_per_mm, latencies, gain_sets, range(seeds)
    ):
        specs.append(
            RunSpec(
                experiment=exp,
                controller=ctrl,
                plant=plant,
                stiffness_n_per_mm=k,
                latency=lat,
                seed=seed,
                gains=gains_items(gain_sets[label].get(ctrl, {})),
                gains_label=label if cspec is None else cspec,  # a spec's gains are its own
                rulebase=rulebase,
                loop=loop,
                duration_s=duration_s,
                controller_spec=cspec,
                controller_impl=controller_impl,
            )
        )
    return specs


def run_sweep(
    specs: Sequence[RunSpec],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[int], None] | None = None,
) -> list[dict[str, Any]]:
    """One row per spec, in order (see :func:`fuzzkit.studies.batch.execute`)."""
    for s in specs:
        s.resolved_loop()  # a plant the loop cannot run fails here, not in a worker
    return map_runs(execute, list(specs), workers=workers, scheduler=scheduler, progress=progress)


def columns(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """Every column of ``rows``, in order of first appearance."""
    seen: dict[str, None] = {}
    for r in rows:
        for k in r:
            seen.setdefault(k, None)
    return list(seen)


def check_table_path(path: str | os.PathLike[str]) -> Path:
    """``path`` if it names a .csv or .parquet file in an existing folder, else ConfigError."""
    from fuzzkit.fileio import check_output_path

    p = check_output_path(path, "sweep table")
    if p.suffix.lower() not in TABLE_SUFFIXES:
        raise ConfigError(f"{path}: the table must end in .csv or .parquet (got {p.suffix!r})")
    return p


def write_table(rows: Sequence[Mapping[str, Any]], path: str | os.PathLike[str]) -> Path:
    """Write ``rows`` as CSV or Parquet (by extension), atomically; missing cells are empty.

    Raises
    ------
    ConfigError
        For another extension or a missing folder.
    """
    from fuzzkit.fileio import write_atomic

    p = check_table_path(path)
    cols = columns(rows)
    if p.suffix.lower() == ".csv":
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
        writer.writeheader()
        for r in rows:
            writer.writerow({k: _cell(r.get(k)) for k in cols})
        return write_atomic(p, buf.getvalue())
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({k: [r.get(k) for r in rows] for k in cols})
    out = pa.BufferOutputStream()
    pq.write_table(table, out)
    return write_atomic(p, out.getvalue().to_pybytes())


def _cell(v: Any) -> Any:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    return v
