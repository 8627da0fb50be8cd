"""Batch runs: one closed-loop run described as data, and an executor that maps many of them.

A :class:`RunSpec` is everything that defines a run (experiment, controller, plant, stiffness,
latency, noise seed, gains, loop); :func:`execute` turns one into a flat row (every parameter and
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
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, TypeVar

from fuzzkit.control.names import ADAPTIVE_PREFIX
from fuzzkit.errors import ConfigError
from fuzzkit.studies.runner import RunResult
from fuzzkit.studies.task import Experiment

T = TypeVar("T")
R = TypeVar("R")

LOOPS = ("auto", "compiled", "python")
#: How the Python loop's reference controller evaluates a fuzzy-PI's surface: the ``exact``
#: engine (``auto``), the generated double lookup ``table``, or the rule base's generated ``c``
#: through ctypes. The compiled loop runs the generated controller, whose surface is the spec's.
FUZZY_IMPLS = ("auto", "exact", "table", "c")
#: Which controller runs: ``c``, the run's controller spec generated as C and run whole in the
#: compiled loop; ``python``, fuzzkit's reference controller in the Python loop; ``auto``: C
#: where the compiled loop runs (arm6, planar) and a C compiler exists, else the reference.
CONTROLLER_IMPLS = ("auto", "python", "c")


@dataclass(frozen=True, slots=True)
class RunSpec:
    """One closed-loop run, as data.

    ``stiffness_n_per_mm``: None keeps the experiment's own. ``latency``: ``(sensor, command)``
    delays in periods (None: the experiment's). ``fault``: a fault kind of
    :data:`fuzzkit.studies.faults.FAULTS`, seeded by ``seed`` (None: the experiment's).
    ``gains``: overrides of the default gains, as sorted ``(name, value)`` pairs;
    ``gains_label`` names where they came from (a file) for the table. ``loop``:
    ``compiled`` (arm6, planar), ``python``, or ``auto`` (compiled where supported).
    ``duration_s``: None runs the experiment's whole duration. ``controller_spec``: a
    controller spec file (``docs/controller.md``) whose controller runs instead of
    ``controller`` with ``gains`` (a scenario with a ``controller:`` runs its own).
    ``controller_impl``: ``auto``, ``c`` (the run's controller spec, given or built from the
    settings, generated as C and run in the compiled loop) or ``python`` (the reference
    controller in the Python loop); :data:`CONTROLLER_IMPLS`.
    """

    experiment: str
    controller: str = "fuzzy-pi"
    plant: str = "arm6"
    stiffness_n_per_mm: float | None = None
    latency: tuple[int, int] | None = None
    seed: int = 0
    gains: tuple[tuple[str, float], ...] = ()
    gains_label: str = "default"
    rulebase: str = "macvicar_whelan"
    loop: str = "auto"
    duration_s: float | None = None
    fuzzy_impl: str = "auto"
    fault: str | None = None
    controller_spec: str | None = None
    controller_impl: str = "auto"

    def resolved_loop(self) -> str:
        """``compiled`` or ``python``: what ``auto`` means for this plant."""
        from fuzzkit.studies.compiled.loop import compiled_supports

        if self.loop not in LOOPS:
            raise ConfigError(f"unknown loop {self.loop!r} (expected {', '.join(LOOPS)})")
        if self.loop == "auto":
            reference = self.controller_impl == "python" or self.fuzzy_impl != "auto"
            return "compiled" if compiled_supports(self.plant) and not reference else "python"
        if self.loop == "compiled" and not compiled_supports(self.plant):
            raise ConfigError(
                f"the compiled loop does not model the {self.plant} plant (it runs on arm6 and "
                "planar); "
                "use --loop python"
            )
        return self.loop


@lru_cache(maxsize=8)
def _exact_surface(rulebase: str) -> Any:
    from fuzzkit.studies.runner import load_surface

    return load_surface(rulebase)


def run_spec(spec: RunSpec) -> RunResult:
    """Run ``spec`` and return the whole :class:`RunResult` (traces included).

    Every run executes the run's controller spec as ``fuzzkit compile`` generates it (C
    double; the generated Python without a C compiler): in the compiled loop where it models
    the plant, else in the Python loop (MuJoCo; a scenario the kernels lack, a run without a
    compiler: ``loop`` is then ``python (fallback: ...)``); ``controller_impl`` names the code.
    The reference controller runs only when asked for (``controller_impl="python"``, a
    ``fuzzy_impl``, ``loop="python"``), and for a spec that adapts its gains outside the
    compiled loop (``loop`` says so).
    """
    from fuzzkit.studies.experiments import with_stiffness

    spec, exp, plant = resolve(spec)
    if spec.stiffness_n_per_mm is not None:
        k = spec.stiffness_n_per_mm
        if not (math.isfinite(k) and k > 0.0):
            raise ConfigError(f"stiffness must be a positive number of N/mm (got {k})")
        exp = with_stiffness(exp, k * 1e3)
    return run_resolved(spec, exp, plant)


def run_resolved(spec: RunSpec, exp: Experiment, plant: Any) -> RunResult:
    """Run ``spec`` on an experiment and plant already resolved (:func:`resolve`, its
    stiffness applied), choosing the loop as :func:`run_spec` does: for callers that build
    their own experiment (the stability region's cells)."""
    from fuzzkit.studies.faults import fault

    if spec.controller == "fuzzy-pi":  # what the loop needs, said before anything runs
        from fuzzkit.control.loop_rulebase import check_loop_rulebase, load_loop_rulebase

        cs = exp.controller_spec
        if cs is not None and cs.rulebase is not None:
            check_loop_rulebase(cs.rulebase, spec.rulebase)
        else:
            load_loop_rulebase(spec.rulebase)
    faults = fault(spec.fault or exp.fault, spec.seed)
    impl = spec.fuzzy_impl
    if impl not in FUZZY_IMPLS:
        raise ConfigError(f"unknown fuzzy implementation {impl!r} (expected {FUZZY_IMPLS})")
    if spec.controller_impl not in CONTROLLER_IMPLS:
        raise ConfigError(
            f"unknown controller implementation {spec.controller_impl!r} "
            f"(expected {', '.join(CONTROLLER_IMPLS)})"
        )
    loop = spec.resolved_loop()
    if loop == "compiled" and impl != "auto":
        raise ConfigError(
            f"--fuzzy-impl {impl} chooses the Python loop's surface; the compiled loop runs the "
            "generated controller (the spec's surface): leave out --loop compiled"
        )
    # The reference controller runs only when asked for: --controller-impl python, a
    # --fuzzy-impl, or the Python loop named (--loop python). Every other run executes the
    # spec's generated controller: in the compiled loop where it models the plant and the
    # scenario, else in the Python loop.
    if spec.controller_impl == "python" or impl != "auto" or spec.loop == "python":
        if spec.controller_impl == "c":
            raise ConfigError(
                "--controller-impl c runs the generated controller (in the compiled loop "
                "where it models the plant); --loop python and --fuzzy-impl run the reference "
                "controller: leave them out"
            )
        return _run_reference(spec, exp, plant, faults, "")
    if loop == "compiled":
        try:
            return _run_generated(spec, exp, plant, faults)
        except _Fallback as exc:
            if spec.loop == "compiled":
                raise ConfigError(f"{exc}; use --loop python") from exc
            fallback = f" (fallback: {exc})"
    else:
        fallback = ""  # a plant the compiled loop does not model (mujoco)
    return _run_generated_python_loop(spec, exp, plant, faults, fallback)


class _Fallback(Exception):
    """Why the compiled loop cannot take a run the Python loop can."""


def _run_generated_python_loop(
    spec: RunSpec, exp: Experiment, plant: Any, faults: Any, fallback: str
) -> RunResult:
    """``spec`` with the run's generated controller (C, or the generated Python without a
    compiler) in the Python loop; ``loop`` says so, with ``fallback`` (why the compiled loop
    could not take it). A spec that adapts its gains still runs the reference there, and
    ``loop`` says so: the Python loop does not yet record the generated controller's
    stiffness estimate and gain factor."""
    from fuzzkit.studies.loop_controller import run_controller
    from fuzzkit.studies.runner import run

    cs = exp.controller_spec
    if cs is not None and cs.adaptation.mode != "none":
        if spec.controller_impl == "c":
            raise ConfigError(
                f"the Python loop runs a spec that adapts its gains ({cs.adaptation.mode}) on "
                "the reference controller only; leave out --controller-impl c"
            )
        why = " (an adapting spec runs on the reference controller in the Python loop)"
        return _run_reference(spec, exp, plant, faults, fallback or why)
    gains, impl_c = dict(spec.gains), spec.controller_impl == "c"
    ctrl = run_controller(
        exp, spec.controller, gains, spec.rulebase, spec.seed, faults, spec.latency, impl_c
    )
    result = run(exp, plant, ctrl.kind, hybrid=ctrl, seed=spec.seed, faults=faults,
                 latency=spec.latency, duration_s=spec.duration_s)  # fmt: skip
    result.loop += fallback
    return result


def _run_reference(
    spec: RunSpec, exp: Experiment, plant: Any, faults: Any, fallback: str
) -> RunResult:
    """``spec`` in the Python loop, on the reference controller."""
    from fuzzkit.studies.runner import run

    surface: Any = None
    label = "pi (python)"
    cs = exp.controller_spec
    if spec.controller == "fuzzy-pi":
        impl = spec.fuzzy_impl
        if cs is not None and impl in ("auto", "exact"):
            surface, label = _spec_reference_surface(cs, impl, spec.rulebase)
        elif impl in ("auto", "exact"):
            surface = _exact_surface(spec.rulebase)
            label = f"exact engine {spec.rulebase} (python)"
        else:
            if cs is not None:
                _require_positional_roles(cs, impl)
            if impl == "table":
                from fuzzkit.control.controllers import lookup_table_surface
                from fuzzkit.studies.compiled.table import load_table, table_arrays

                table = load_table(spec.rulebase)
                surface = lookup_table_surface(table)
                label = table_arrays(table).label + " (python)"
            else:
                from fuzzkit.studies.compiled.generated_c import c_surface

                surface = c_surface(spec.rulebase)
                label = f"{surface.__name__} (python loop)"
    if exp.controller_spec is not None:
        label = f"spec {exp.controller_spec.name}: {label}"
    result = run(
        exp,
        plant,
        spec.controller,
        gains=dict(spec.gains),
        surface=surface,
        seed=spec.seed,
        faults=faults,
        latency=spec.latency,
        duration_s=spec.duration_s,
        controller_impl=label,
    )
    result.loop += fallback
    return result


def _spec_reference_surface(cs: Any, impl: str, rulebase: str) -> tuple[Any, str]:
    """A controller spec's surface on the reference controller, in the spec's input roles:
    its own (``auto``: the exact engine, or a ``table`` spec's lookup table) or the exact
    engine (``exact``), with the run's label."""
    from fuzzkit.control.loop_rulebase import exact_surface
    from fuzzkit.control.spec import surface_inputs
    from fuzzkit.studies.controller_code import spec_surface

    if impl == "auto" and cs.surface.method == "table":
        return spec_surface(cs), "the spec's lookup table (python)"
    return exact_surface(cs.rulebase, surface_inputs(cs, cs.rulebase)), (
        f"exact engine {rulebase} (python)"
    )


def _require_positional_roles(cs: Any, impl: str) -> None:
    """``--fuzzy-impl table|c`` builds the rule base's own table or C, which take its inputs in
    file order: refuse a spec whose ``inputs:`` maps them the other way round."""
    from fuzzkit.control.loop_rulebase import POSITIONAL_ROLES
    from fuzzkit.control.spec import surface_inputs

    if surface_inputs(cs, cs.rulebase) != POSITIONAL_ROLES:
        raise ConfigError(
            f"--fuzzy-impl {impl} evaluates rule base {cs.rulebase.name}'s inputs in file "
            f"order, and controller spec {cs.name!r} maps them the other way round (inputs: "
            f"{', '.join(cs.inputs)}): leave out --fuzzy-impl (the spec's own surface runs)"
        )


def _run_generated(spec: RunSpec, exp: Experiment, plant: Any, faults: Any) -> RunResult:
    """``spec`` with the run's generated C controller in the compiled loop.

    Raises
    ------
    _Fallback
        The compiled loop cannot run it (adaptation, a plant mode the kernel lacks, no C
        compiler); the caller decides whether the Python loop may.
    """
    from fuzzkit.errors import ToolchainError
    from fuzzkit.plants.contract import UnsupportedPlant
    from fuzzkit.studies.compiled.generated_controller import (
        load_generated_controller,
        run_controller_spec,
    )
    from fuzzkit.studies.compiled.loop import run_compiled

    cs = exp.controller_spec
    if cs is not None and cs.adaptation.mode != "none":
        raise _Fallback(f"the compiled loop does not run adaptation ({cs.adaptation.mode})")
    ctl_spec = run_controller_spec(exp, spec.controller, dict(spec.gains), spec.rulebase)
    try:
        generated = load_generated_controller(ctl_spec)
    except ToolchainError as exc:
        if spec.controller_impl == "c":
            raise ConfigError(
                f"--controller-impl c runs the generated C controller and {exc}"
            ) from exc
        raise _Fallback(f"the compiled loop runs the generated C controller and {exc}") from exc
    try:
        return run_compiled(
            exp,
            plant,
            seed=spec.seed,
            faults=faults,
            latency=spec.latency,
            duration_s=spec.duration_s,
            generated_controller=generated,
        )
    except UnsupportedPlant as exc:
        raise _Fallback(str(exc)) from exc


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
    from fuzzkit.studies.runner import check_latency

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
    from fuzzkit.studies.experiments import DEFAULT_GAINS
    from fuzzkit.studies.task import spec_for

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
