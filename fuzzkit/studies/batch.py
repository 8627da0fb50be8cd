"""Batch runs: one closed-loop run described as data, and an executor that maps many of them.

A :class:`~fuzzkit.loop.spec.RunSpec` is everything that defines a run (experiment, controller,
plant, stiffness, latency, noise seed, gains, loop); :func:`run_spec` resolves its names (the
experiment, a controller spec, the stiffness) and runs it through the loop
(:func:`fuzzkit.loop.run.run_loop`); :func:`execute` turns one into a flat row (every parameter and
every metric of ``fuzzkit simulate --json``). :func:`map_runs` executes many, in order, in this
process, in a local process pool (all cores by default), or on a ``dask.distributed`` cluster
(``scheduler="tcp://host:8786"``). Specs and rows are plain picklable data, so a worker needs
only fuzzkit installed; the runs are deterministic, so every executor gives the same rows.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from functools import lru_cache
from typing import Any, TypeVar

from fuzzkit.control.names import ADAPTIVE_PREFIX
from fuzzkit.errors import ConfigError
from fuzzkit.loop.result import RunResult
from fuzzkit.loop.run import run_loop
from fuzzkit.loop.spec import RunSpec
from fuzzkit.loop.task import Experiment

T = TypeVar("T")
R = TypeVar("R")


def run_spec(spec: RunSpec) -> RunResult:
    """Run ``spec`` (:func:`resolve`, its stiffness applied, then
    :func:`fuzzkit.loop.run.run_loop`) and return the whole :class:`RunResult` (traces
    included)."""
    from fuzzkit.studies.experiments import with_stiffness

    spec, exp, plant = resolve(spec)
    if spec.stiffness_n_per_mm is not None:
        k = spec.stiffness_n_per_mm
        if not (math.isfinite(k) and k > 0.0):
            raise ConfigError(f"stiffness must be a positive number of N/mm (got {k})")
        exp = with_stiffness(exp, k * 1e3)
    return run_loop(spec, exp, plant)


@lru_cache(maxsize=8)
def _load_controller_spec(path: str) -> Any:
    from fuzzkit.control.spec_reader import load_spec

    return load_spec(path)


def resolve(spec: RunSpec) -> tuple[RunSpec, Experiment, Any]:
    """The run, its experiment and its plant, with a controller spec (``spec.controller_spec``
    or the scenario's own) applied: the run's ``controller`` and ``rulebase`` become the spec's.

    Raises
    ------
    ConfigError
        Gains given with a controller spec (the spec holds its gains), or a spec whose period is
        not the scenario's.
    """
    from dataclasses import replace

    from fuzzkit.studies.experiments import with_spec

    exp, plant = experiment_and_plant(spec)
    if spec.controller_spec is not None:
        exp = with_spec(exp, _load_controller_spec(spec.controller_spec))
    elif spec.controller.startswith(ADAPTIVE_PREFIX):
        exp = with_spec(exp, adaptive_spec(spec, exp))
        spec = replace(spec, gains=())
    cs = exp.controller_spec
    if cs is None:
        return spec, exp, plant
    if spec.gains:
        raise ConfigError(
            f"controller spec {cs.name!r} holds its gains; give a spec or gains, not both"
        )
    rulebase = cs.rulebase_source or spec.rulebase
    return replace(spec, controller=cs.kind, rulebase=rulebase), exp, plant


def adaptive_spec(spec: RunSpec, exp: Experiment) -> Any:
    """The spec ``--controller adaptive-pi | adaptive-fuzzy-pi`` runs (:func:`adaptive_spec_for`
    with the run's gain overrides, rule base and latency)."""
    from fuzzkit.loop.timing import check_latency

    latency = sum(check_latency(exp.latency_periods if spec.latency is None else spec.latency))
    return adaptive_spec_for(exp, spec.controller, spec.rulebase, latency, dict(spec.gains))


def adaptive_spec_for(
    exp: Experiment,
    controller: str,
    rulebase: str,
    latency_periods: int,
    gains: Mapping[str, float] | None = None,
) -> Any:
    """The experiment's task on the shipped gains (``gains`` override them) under the kit's
    default stiffness schedule, its estimator's delay matched to ``latency_periods`` (sensor +
    command): what ``adaptive-pi`` and ``adaptive-fuzzy-pi`` mean."""
    from dataclasses import replace

    from fuzzkit.control.adaptation_spec import default_schedule
    from fuzzkit.formats.registry import load
    from fuzzkit.loop.task import spec_for
    from fuzzkit.studies.experiments import DEFAULT_GAINS

    kind = controller.removeprefix(ADAPTIVE_PREFIX)
    if not controller.startswith(ADAPTIVE_PREFIX) or kind not in DEFAULT_GAINS:
        raise ConfigError(
            f"unknown controller {controller!r} (expected adaptive-pi or adaptive-fuzzy-pi)"
        )
    merged = dict(DEFAULT_GAINS[kind]) | dict(gains or {})
    name = controller.replace("-", "_")
    fuzzy = kind == "fuzzy-pi"
    cs = spec_for(exp, kind, merged, name, load(rulebase) if fuzzy else None, rulebase)
    return replace(
        cs,
        adaptation=default_schedule(latency_periods),
        rulebase_source=rulebase if fuzzy else None,
        description=f"{kind} on the shipped gains, kit's default stiffness schedule",
    )


def experiment_and_plant(spec: RunSpec) -> tuple[Experiment, Any]:
    """The experiment and the plant to run it on (:func:`fuzzkit.studies.e3_arm6.resolve`): a
    plant object where the pair needs its own (E3 on arm6), else the plant's name, so that the
    compiled loop can reuse its per-process plant."""
    from fuzzkit.studies.e3_arm6 import resolve
    from fuzzkit.studies.experiments import experiment

    if spec.experiment.upper() == "E3" and spec.plant == "arm6":
        return resolve(spec.experiment, spec.plant)
    return experiment(spec.experiment), spec.plant


def execute(spec: RunSpec) -> dict[str, Any]:
    """Run ``spec`` and return its tidy row: every parameter, then every metric.

    Per-axis metrics are flattened as ``<axis>_<metric>`` (``z_overshoot_pct`` ...); axes that
    are not force-controlled are absent (the table fills them with empty cells).
    """
    return result_row(spec, run_spec(spec))


def result_row(spec: RunSpec, result: RunResult) -> dict[str, Any]:
    """The tidy row of :func:`execute` for a run of ``spec`` that already ran."""
    from fuzzkit.studies.metrics import summary

    data = summary(result)
    asked = spec.controller  # adaptive-*: the name, not the kind its spec resolves to
    spec = resolve(spec)[0]  # the controller and rule base a controller spec chose
    row: dict[str, Any] = {
        "experiment": spec.experiment,
        "controller": asked if asked.startswith(ADAPTIVE_PREFIX) else spec.controller,
        "plant": spec.plant,
        "stiffness_n_per_mm": spec.stiffness_n_per_mm,
        "sensor_delay": data["latency_periods"][0],
        "command_delay": data["latency_periods"][1],
        "seed": spec.seed,
        "gains": spec.gains_label,
        **{f"gain_{k}": v for k, v in spec.gains},
        "rulebase": spec.rulebase if spec.controller == "fuzzy-pi" else None,
        "controller_spec": spec.controller_spec,
    }
    for key, value in data.items():
        if key == "axes":
            for axis, metrics in value.items():
                for name, v in metrics.items():
                    row[f"{axis}_{name}"] = v
        elif key in ("stiffness_estimate_n_mm", "gain_scale_final"):  # per axis too
            for axis, v in value.items():
                row[f"{axis}_{key}"] = v
        elif key == "limit_exceeded":  # flat, as a table's columns are: None when it held
            row["limit_exceeded_s"] = None if value is None else value["time_s"]
            row["limit_exceeded_peak_n"] = None if value is None else value["peak_true_n"]
        elif key not in ("experiment", "controller", "plant"):
            row[key] = value
    return row


def default_workers() -> int:
    """The number of cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


#: How long a run waits to reach a Dask scheduler before it says it cannot (a scheduler on
#: another machine may take a few seconds to answer).
SCHEDULER_TIMEOUT = "10s"


class BatchExecutor:
    """Maps a function over items, in order, on a pool that lives as long as the executor.

    ``scheduler``: address of a ``dask.distributed`` scheduler (``tcp://host:8786``); the items
    run on its workers (each needs fuzzkit installed, e.g. ``dask worker`` started from the
    project's environment). Otherwise ``workers`` local processes (None: every core; 1: in this
    process). Local workers ignore Ctrl-C: stopping is the parent's business.

    Raises
    ------
    ConfigError
        If the scheduler cannot be reached, or ``workers < 1``.
    """

    def __init__(self, workers: int | None = None, scheduler: str | None = None) -> None:
        self.scheduler = scheduler
        self.workers = default_workers() if workers is None else workers
        if self.workers < 1:
            raise ConfigError(f"workers must be >= 1 (got {self.workers})")
        self._pool: ProcessPoolExecutor | None = None
        self._client: Any = None
        if scheduler is not None:
            import distributed

            client_class: Any = distributed.Client  # untyped library
            try:
                self._client = client_class(scheduler, timeout=SCHEDULER_TIMEOUT)
            except (OSError, TimeoutError) as exc:
                raise ConfigError(
                    f"cannot reach the dask scheduler at {scheduler} ({exc})"
                ) from exc
        elif self.workers > 1:
            import multiprocessing

            methods = multiprocessing.get_all_start_methods()
            # fork shares the already imported modules (fast start); spawn elsewhere
            ctx = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
            self._pool = ProcessPoolExecutor(
                self.workers, mp_context=ctx, initializer=_ignore_sigint
            )

    @property
    def where(self) -> str:
        """Where the items run, for messages."""
        if self._client is not None:
            return f"dask cluster {self.scheduler}"
        return "this process" if self._pool is None else f"{self.workers} local processes"

    def map(
        self,
        fn: Callable[[T], R],
        items: Sequence[T],
        progress: Callable[[int], None] | None = None,
    ) -> list[R]:
        """``[fn(x) for x in items]``; ``progress`` gets the count finished after each item.

        ``fn`` must be a module-level function and the items picklable.
        """
        items = list(items)
        if not items:
            return []
        if self._client is not None:
            import distributed

            dask_completed: Any = distributed.as_completed  # untyped library

            # pure=False: equal items are still separate runs (each counted in the progress)
            futures = self._client.map(fn, items, pure=False)
            for done, _ in enumerate(dask_completed(futures), start=1):
                if progress:
                    progress(done)
            results: list[R] = self._client.gather(futures)
            return results
        if self._pool is None or len(items) == 1:
            out: list[R] = []
            for x in items:
                out.append(fn(x))
                if progress:
                    progress(len(out))
            return out
        pending = [self._pool.submit(fn, x) for x in items]
        for done, _ in enumerate(_as_completed(pending), start=1):
            if progress:
                progress(done)
        return [f.result() for f in pending]

    def close(self, abort: bool = False) -> None:
        """Stop the workers (``abort``: drop queued items instead of finishing them).

        Either way the local worker processes have ended when this returns (an abort waits
        for the items already running, one per worker): none is left behind to outlive the
        command, which may end without the interpreter's own shutdown (``fuzzkit.cli``).
        """
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=abort)
            self._pool = None
        if self._client is not None:
            self._client.close()
            self._client = None

    def __enter__(self) -> BatchExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close(abort=exc[0] is not None)


def _ignore_sigint() -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def map_runs(
    fn: Callable[[T], R],
    items: Sequence[T],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[int], None] | None = None,
) -> list[R]:
    """``[fn(x) for x in items]`` in order, on a one-off :class:`BatchExecutor`."""
    if not items:
        return []
    n = default_workers() if workers is None else workers
    with BatchExecutor(min(n, len(items)), scheduler) as ex:
        return ex.map(fn, items, progress)


def _as_completed(futures: Iterable[Any]) -> Iterator[Any]:
    from concurrent.futures import as_completed

    yield from as_completed(list(futures))


def gains_items(gains: Mapping[str, float]) -> tuple[tuple[str, float], ...]:
    """Gain overrides as the sorted pairs a :class:`RunSpec` holds."""
    return tuple(sorted((str(k), float(v)) for k, v in gains.items()))
