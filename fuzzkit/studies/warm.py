"""Compile (or load) every numba kernel of the package once, ahead of the processes that use them.

numba compiles a kernel on its first call in a process and caches the machine code on disk;
processes started later load it. Started together (the test suite's workers, a sweep's
processes), each of them would compile the same kernels again. :func:`warm` makes that first
call once, beforehand: ``tests/conftest.py`` runs it in pytest's controller process before the
xdist workers start, and ``python -m fuzzkit.studies.warm`` does it by hand (and says
what it compiled and how long it took); ``--background LOCK`` starts it and returns at once,
so that ``make test`` compiles the kernels while its static checks run.

Each step is a short real call of an entry point that reaches kernels (a few periods of each
compiled loop, one point of each surface kernel), so that what is compiled has exactly the
argument types the real calls have: a kernel compiled for other types (another array layout, a
float where an int goes) would be compiled again on the real call, not loaded.
"""

from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fuzzkit.errors import ToolchainError
from fuzzkit.jit import has_cached_code
from fuzzkit.plants.contract import UnsupportedPlant

#: Simulated seconds of each warming run: a handful of periods reach every compiled path.
WARM_DURATION_S = 0.02

#: A rule base whose output term is smooth (gaussian): the exact engine integrates it on a grid,
#: in :mod:`fuzzkit.fuzzy.grid_kernel` (the shipped rule bases' outputs are piecewise linear).
_SMOOTH_OUTPUT = """\
name: warm_smooth
inputs:
  e: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
outputs:
  du:
    range: [-1, 1]
    terms:
      N: {shape: gaussian, mean: -0.5, sigma: 0.2}
      Z: {shape: gaussian, mean: 0.0, sigma: 0.2}
      P: {shape: gaussian, mean: 0.5, sigma: 0.2}
rules:
  - {if: {e: N}, then: {du: N}}
  - {if: {e: Z}, then: {du: Z}}
  - {if: {e: P}, then: {du: P}}
"""


def _compiled_run(experiment: str, plant: str, controller: str, fault: str | None = None) -> None:
    """A short run through the loop's entry point, on the plant's compiled loop."""
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    run_spec(
        RunSpec(experiment, controller, plant, loop="compiled", fault=fault,
                duration_s=WARM_DURATION_S)
    )  # fmt: skip


def _arm6_loop() -> None:
    # PI and fuzzy-PI are the same kernel (the controller is generated C called by address);
    # both are run so that each one's C controller is built and cached as well
    _compiled_run("E1", "arm6", "pi")
    _compiled_run("E2", "arm6", "fuzzy-pi", "spike")


def _planar_loop() -> None:
    _compiled_run("E1", "planar", "pi")
    _compiled_run("E2", "planar", "fuzzy-pi", "nan")


def _mujoco_loop() -> None:
    # E3: a rough profile (the substep-by-substep path) and a wall
    _compiled_run("E3", "mujoco", "pi")


def _height_field() -> None:
    from fuzzkit.plants.arm6_heightfield import height_field_contact, pack_height_field
    from fuzzkit.plants.environment3d import HeightField

    # as the kernel is called from Python (the loop's own call is compiled into the loop)
    field = HeightField.rough((0.0, 0.1), (0.0, 0.1), 0.0, 0.0001, seed=0)
    row, heights = pack_height_field(field)
    params = np.zeros(12)
    params[: len(row)] = row
    height_field_contact(params, heights, np.zeros(3), 0.01, np.empty(3), np.empty(3))


def _table_surface() -> None:
    from fuzzkit.loop.compiled.table import compiled_table, table2

    t = compiled_table()
    table2(t.bp0, t.bp1, t.values, t.splits, 0.1, -0.2)


def _exact_grid_surface() -> None:
    from fuzzkit.formats.registry import loads
    from fuzzkit.fuzzy.inference import evaluate

    evaluate(loads(_SMOOTH_OUTPUT, "warm_smooth"), {"e": np.array([0.3])})


def _type2_engine() -> None:
    from fuzzkit.formats.registry import load
    from fuzzkit.fuzzy.inference import evaluate

    evaluate(load("macvicar_whelan_it2"), {"e": np.array([0.3, -0.2]), "de": np.array([0.1, 0.4])})


@dataclass(frozen=True, slots=True)
class Step:
    """One warming call: ``run`` calls the ``kernels`` (``module:name``; the ones it calls from
    Python, their callees are compiled into them) with the argument types of the real calls."""

    name: str
    kernels: tuple[str, ...]
    run: Callable[[], None]

    def dispatchers(self) -> list[Any]:
        """The kernels, imported."""
        found = []
        for ref in self.kernels:
            module, _, name = ref.partition(":")
            found.append(getattr(importlib.import_module(module), name))
        return found


#: What :func:`warm` runs, in order.
STEPS = (
    Step(
        "arm6 loop (plant, faults, latency, generated C controller)",
        ("fuzzkit.loop.compiled.arm6_run:run_arm6",),
        _arm6_loop,
    ),
    Step(
        "planar loop (Chipmunk calls, faults, generated C controller)",
        ("fuzzkit.loop.compiled.planar_run:run_planar",),
        _planar_loop,
    ),
    Step(
        "mujoco loop (MuJoCo called by address, servo callback, generated C controller)",
        ("fuzzkit.loop.compiled.mujoco_run:run_mujoco",),
        _mujoco_loop,
    ),
    Step(
        "height-field contact, called from Python",
        ("fuzzkit.plants.arm6_heightfield:height_field_contact",),
        _height_field,
    ),
    Step("lookup-table surface", ("fuzzkit.loop.compiled.table:table2",), _table_surface),
    Step(
        "exact engine on a smooth output (grid kernel)",
        ("fuzzkit.fuzzy.grid_kernel:grid_defuzzify",),
        _exact_grid_surface,
    ),
    Step(
        "interval type-2 engine (firing, cut and Karnik-Mendel in one pass)",
        ("fuzzkit.fuzzy.type2_kernel:_evaluate",),
        _type2_engine,
    ),
)


def warm(
    report: Callable[[str, str, float], None] | None = None, part: tuple[int, int] = (0, 1)
) -> None:
    """Run each step of :data:`STEPS` whose kernels are not all in numba's disk cache yet.

    ``report(step, outcome, seconds)`` after each one; ``outcome`` is ``"compiled"``,
    ``"cached"`` (nothing to do: the step is not run, so a warm cache costs only the check)
    or why it could not run here (no C compiler: the compiled loop's controller and the C
    surface are generated C; a machine the planar loop's Chipmunk calls are not lowered for);
    such kernels compile on first use, as without warming. Any other error propagates: the
    step's call would fail in real use too. ``part = (k, n)`` runs only every n-th step from
    the k-th, so that n processes share the steps (:func:`warm_in_background`).
    """
    index, count = part
    for step in STEPS[index::count]:
        start = time.perf_counter()
        if all(has_cached_code(kernel) for kernel in step.dispatchers()):
            outcome = "cached"
        else:
            try:
                step.run()
                outcome = "compiled"
            except (ToolchainError, UnsupportedPlant) as exc:
                outcome = f"not here: {exc}"
        if report is not None:
            report(step.name, outcome, time.perf_counter() - start)


#: The environment variable that names the lock of a warm-up running in the background.
LOCK_ENV = "FUZZKIT_WARM_LOCK"


@dataclass(frozen=True, slots=True)
class Warming:
    """A warm-up running in the background: its processes, their log and the lock they hold."""

    processes: tuple[subprocess.Popen[bytes], ...]
    log: Path
    lock: Path

    def finish(self) -> str | None:
        """Wait for the processes; why the warm-up failed (the log's last lines), or None."""
        codes = [p.wait() for p in self.processes]
        self.lock.unlink(missing_ok=True)
        text = self.log.read_text(encoding="utf-8", errors="replace")
        self.log.unlink(missing_ok=True)
        if all(code == 0 for code in codes):
            return None
        return f"exit {max(codes, key=abs)}: " + " | ".join(text.strip().splitlines()[-3:])


def _warm_part(part: int, jobs: int) -> list[str]:
    return [sys.executable, "-m", "fuzzkit.studies.warm", "--part", f"{part}/{jobs}"]


def warm_in_background(
    jobs: int,
    command: Callable[[int, int], list[str]] = _warm_part,
    lock: Path | None = None,
) -> Warming | None:
    """Start ``jobs`` processes that warm the kernels between them, while this process goes
    on; processes started after it wait for them in :func:`wait_for_warming`. Part ``k`` runs
    ``command(k, jobs)``: ``python -m fuzzkit.studies.warm --part k/jobs``.

    The processes share one exclusive ``flock`` on a lock file, taken here before they start
    and inherited by them, so it is released only when the last of them exits (or dies); the
    file's path is put in this process's environment (:data:`LOCK_ENV`), which the processes
    it starts later inherit. ``lock``: that file instead of a new temporary one (a process that
    is not this one's child can then wait for it, given the path). None where ``flock`` does
    not exist (then call :func:`warm`).
    """
    try:
        import fcntl
    except ImportError:  # not POSIX
        return None
    if lock is None:
        handle, name = tempfile.mkstemp(prefix="fuzzkit-warm-", suffix=".lock")
    else:
        lock.parent.mkdir(parents=True, exist_ok=True)
        handle, name = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644), str(lock)
    log = Path(name).with_suffix(".log")
    fcntl.flock(handle, fcntl.LOCK_EX)
    processes = []
    with log.open("wb") as out:
        for k in range(jobs):
            processes.append(
                subprocess.Popen(
                    command(k, jobs), stdout=out, stderr=subprocess.STDOUT, pass_fds=(handle,)
                )
            )
    os.close(handle)  # the lock is the processes' now
    os.environ[LOCK_ENV] = name
    return Warming(tuple(processes), log, Path(name))


def wait_for_warming() -> None:
    """Block until the warm-up named by :data:`LOCK_ENV` (if any) has finished."""
    name = os.environ.get(LOCK_ENV)
    if not name:
        return
    import fcntl

    try:
        handle = os.open(name, os.O_RDONLY)
    except FileNotFoundError:  # finished and cleaned up already
        return
    try:
        fcntl.flock(handle, fcntl.LOCK_SH)
    finally:
        os.close(handle)


def _part(text: str) -> tuple[int, int]:
    index, _, count = text.partition("/")
    try:
        k, n = int(index), int(count)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected K/N, got {text!r}") from None
    if not 0 <= k < n:
        raise argparse.ArgumentTypeError(f"expected 0 <= K < N, got {text!r}")
    return k, n


def _jobs(text: str) -> int:
    try:
        jobs = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if not 1 <= jobs <= 64:
        raise argparse.ArgumentTypeError(f"expected 1 to 64 processes, got {jobs}")
    return jobs


def main(argv: list[str] | None = None) -> int:
    """Warm every kernel (or one part of the steps), printing each step, what it did and its
    wall time, after waiting for a warm-up already running (named by :data:`LOCK_ENV`); or,
    with ``--background LOCK``, start that in ``--jobs`` processes holding the lock ``LOCK``
    and return at once (their output goes to ``LOCK`` with the suffix ``.log``; a process given
    ``FUZZKIT_WARM_LOCK=LOCK`` waits for them in :func:`wait_for_warming`)."""
    parser = argparse.ArgumentParser(prog="python -m fuzzkit.studies.warm")
    parser.add_argument(
        "--part", type=_part, default=(0, 1), help="K/N: every N-th step from the K-th"
    )
    parser.add_argument(
        "--background", type=Path, metavar="LOCK", help="start it holding LOCK; return"
    )
    parser.add_argument(
        "--jobs", type=_jobs, default=1, help="processes of --background (default: 1)"
    )
    args = parser.parse_args(argv)
    if args.background is not None:
        warm_in_background(args.jobs, lock=args.background)
        return 0
    total = time.perf_counter()
    wait_for_warming()  # one already running: its kernels are then loaded, not compiled again

    def report(name: str, outcome: str, seconds: float) -> None:
        print(f"{seconds:7.2f} s  {name}: {outcome}", flush=True)

    warm(report, args.part)
    print(f"{time.perf_counter() - total:7.2f} s  in all")
    return 0


if __name__ == "__main__":
    sys.exit(main())
