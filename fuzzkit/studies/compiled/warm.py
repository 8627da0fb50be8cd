"""Compile (or load) every numba kernel of the package once, ahead of the processes that use them.

numba compiles a kernel on its first call in a process and caches the machine code on disk;
processes started later load it. Started together (the test suite's workers, a sweep's
processes), each of them would compile the same kernels again. :func:`warm` makes that first
call once, beforehand: ``tests/conftest.py`` runs it in pytest's controller process before the
xdist workers start, and ``python -m fuzzkit.studies.compiled.warm`` does it by hand (and says
what it compiled and how long it took).

Each step is a short real call of an entry point that reaches kernels (a few periods of each
compiled loop, one point of each surface kernel), so that what is compiled has exactly the
argument types the real calls have: a kernel compiled for other types (another array layout, a
float where an int goes) would be compiled again on the real call, not loaded.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

import numpy as np

from fuzzkit.errors import ToolchainError

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


def _arm6_loop() -> None:
    from fuzzkit.studies.compiled.loop import run_compiled
    from fuzzkit.studies.experiments import experiment
    from fuzzkit.studies.faults import fault

    # PI and fuzzy-PI are the same kernel (the controller is generated C called by address);
    # both are run so that each one's C controller is built and cached as well
    run_compiled(experiment("E1"), "arm6", "pi", duration_s=WARM_DURATION_S)
    run_compiled(
        experiment("E2"), "arm6", "fuzzy-pi", faults=fault("spike"), duration_s=WARM_DURATION_S
    )


def _arm6_3d_loop() -> None:
    from fuzzkit.studies.compiled.loop import run_compiled
    from fuzzkit.studies.e3_arm6 import e3_arm6_experiment, make_e3_arm6_plant

    run_compiled(e3_arm6_experiment(), make_e3_arm6_plant(), "fuzzy-pi", duration_s=WARM_DURATION_S)


def _planar_loop() -> None:
    from fuzzkit.studies.compiled.loop import run_compiled
    from fuzzkit.studies.experiments import experiment
    from fuzzkit.studies.faults import fault

    run_compiled(experiment("E1"), "planar", "pi", duration_s=WARM_DURATION_S)
    run_compiled(
        experiment("E2"), "planar", "fuzzy-pi", faults=fault("nan"), duration_s=WARM_DURATION_S
    )


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
    from fuzzkit.studies.compiled.loop import compiled_table
    from fuzzkit.studies.compiled.table import table2

    t = compiled_table()
    table2(t.bp0, t.bp1, t.values, t.splits, 0.1, -0.2)


def _c_surface() -> None:
    from fuzzkit.studies.compiled.generated_c import call_c_surface, load_generated_c

    call_c_surface(load_generated_c().function, np.zeros(3), 0.1, -0.2)


def _exact_grid_surface() -> None:
    from fuzzkit.formats.registry import loads
    from fuzzkit.fuzzy.inference import evaluate

    evaluate(loads(_SMOOTH_OUTPUT, "warm_smooth"), {"e": np.array([0.3])})


#: What :func:`warm` runs, in order, by what it compiles.
STEPS: tuple[tuple[str, Callable[[], None]], ...] = (
    ("arm6 loop (plant, faults, latency, generated C controller)", _arm6_loop),
    ("arm6 loop on the 3-D E3 (height-field floor, wall)", _arm6_3d_loop),
    ("planar loop (Chipmunk calls, faults, generated C controller)", _planar_loop),
    ("height-field contact, called from Python", _height_field),
    ("lookup-table surface", _table_surface),
    ("generated C surface through ctypes", _c_surface),
    ("exact engine on a smooth output (grid kernel)", _exact_grid_surface),
)


def warm(report: Callable[[str, float], None] | None = None) -> list[str]:
    """Run every step of :data:`STEPS` once; ``report(step, seconds)`` after each one.

    Returns the steps skipped for want of a C compiler (the compiled loop's controller and
    the C surface are generated C): their kernels are compiled on first use instead, as
    before. Any other error propagates: a step that fails would fail in real use too.
    """
    skipped = []
    for name, step in STEPS:
        start = time.perf_counter()
        try:
            step()
        except ToolchainError:
            skipped.append(name)
            continue
        if report is not None:
            report(name, time.perf_counter() - start)
    return skipped


def main() -> int:
    """Warm every kernel, printing each step and its wall time."""
    total = time.perf_counter()
    skipped = warm(lambda name, seconds: print(f"{seconds:7.2f} s  {name}", flush=True))
    for name in skipped:
        print(f"skipped    {name} (no C compiler)")
    print(f"{time.perf_counter() - total:7.2f} s  in all")
    return 0


if __name__ == "__main__":
    sys.exit(main())
