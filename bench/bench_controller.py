"""Benchmark of the whole generated controller (issue 20): step time, size, and the safety
matrix on the generated C controller in the compiled loop.

Run: ``.venv/bin/python bench/bench_controller.py [--seeds N]`` (three tables; about a minute
on a 2-core machine, most of it the Python reference loop).

Tables
------
1. One controller step: 3 force-controlled axes, fuzzy-PI on the exact ``macvicar_whelan``,
   front end on (tare, gravity compensation, 40 Hz low-pass): ``docs/examples/controller.yaml``
   with its gains on x, y and z. ``NAME_controller_step`` in C float and double (-O2, the
   strict flags), ns per step: a small C harness steps it 100 times in free air (the tare),
   then 1e6 times on cycling samples near the set points with the tool's weight (engaged,
   never tripped: the benchmark checks the last status) and reads the
   process CPU-time clock (best of three); beside it the reference controller
   (``fuzzkit.control.reference.Controller.step``) and the generated Python, us per step.
   Target: C float <= 150 ns.
2. Code + constant data bytes of the C float and double builds: ``text + data`` of ``size``
   on ``NAME_controller.o`` plus ``NAME_surface.o``. Target: float <= 8 KiB.
3. The safety matrix (``tests/test_safety.py``: E1-E3 x PI, fuzzy-PI x every fault kind x
   seeds) on ``arm6``: real-time factor (simulated time / CPU time of the loops, summed over
   the runs, start-up and compilation excluded) of the generated C controller in the compiled
   loop (``--controller-impl c``) beside the loop's own numba controller (fuzzy-PI as the
   double lookup table) and the Python reference loop. Target: generated C >= 1000x.
"""

from __future__ import annotations

import argparse
import dataclasses
import subprocess
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from fuzzkit.codegen.toolchain import STRICT_FLAGS, find_compiler, run_compiler
from fuzzkit.control import status as st
from fuzzkit.control.spec import AxisSpec, ControllerSpec
from fuzzkit.control.spec_reader import load_spec

EXAMPLE = Path(__file__).parent.parent / "docs" / "examples" / "controller.yaml"
STEPS = 1_000_000
TARGET_NS = 150.0
TARGET_BYTES = 8192
TARGET_RTF = 1000.0

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <time.h>
#include "{module}.h"

int main(void)
{{
    static {t} forces[1024][3];
    static const {t} rotation[9] = {{1, 0, 0, 0, -1, 0, 0, 0, -1}};
    {module}_t c;
    {t} out[3];
    double sum = 0.0;
    unsigned int status = 0;
    long k;
    struct timespec a, b;
    for (k = 0; k < 1024; k++) {{
        double w = (double)((k * 37) % 1024) / 1023.0 - 0.5;
        /* near the set points, plus the tool's weight the front end removes (0.35 kg, z down) */
        forces[k][0] = ({t})(0.4 * w);
        forces[k][1] = ({t})(2.0 - 0.3 * w);
        forces[k][2] = ({t})(10.0 + 0.5 * w - 0.35 * 9.80665);
    }}
    {module}_init(&c);
    for (k = 0; k < 100; k++) {{ /* free air first: the tare, then the loop engages */
        {t} air[3] = {{0, 0, ({t})(-0.35 * 9.80665)}};
        (void){module}_step(&c, air, rotation, out);
    }}
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
    for (k = 0; k < {steps}; k++) {{
        status = {module}_step(&c, forces[k & 1023], rotation, out);
        sum += out[2];
    }}
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
    printf("%.3f %u %g\n",
           ((double)(b.tv_sec - a.tv_sec) * 1e9 + (double)(b.tv_nsec - a.tv_nsec)) / {steps},
           status, sum);
    return 0;
}}
"""


def bench_spec() -> ControllerSpec:
    """``docs/examples/controller.yaml`` with its gains on all three axes (y at 2 N)."""
    spec = load_spec(EXAMPLE)
    z = spec.axes[-1]
    axes = (
        AxisSpec("x", 0.0, z.kp, z.ki, z.kx),
        AxisSpec("y", 2.0, z.kp, z.ki, z.kx),
        AxisSpec("z", 10.0, z.kp, z.ki, z.kx),
    )
    return dataclasses.replace(spec, name="bench3", axes=axes)


def c_step(spec: ControllerSpec, number_type: str) -> tuple[float, int, int]:
    """``(ns per step, code + data bytes, last status)`` of the generated C build."""
    from fuzzkit.loop.controller_code import generate

    cc = find_compiler()
    if cc is None:
        raise RuntimeError("no C compiler")
    files = generate(spec, "c", number_type)
    module = f"{spec.name}_controller"
    units = sorted(p for p in files if p.endswith(".c"))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for rel, text in files.items():
            (folder / rel).write_text(text)
        (folder / "bench.c").write_text(HARNESS.format(module=module, t=number_type, steps=STEPS))
        nbytes = 0
        for unit in units:
            run_compiler([*cc, *STRICT_FLAGS, "-O2", "-c", unit], folder)
            size = subprocess.run(
                ["size", unit[:-2] + ".o"], cwd=folder, capture_output=True, text=True, check=True
            ).stdout.splitlines()[1]
            text_bytes, data_bytes = size.split()[:2]
            nbytes += int(text_bytes) + int(data_bytes)
        run_compiler([*cc, *STRICT_FLAGS, "-O2", "-o", "bench", "bench.c", *units, "-lm"], folder)
        runs = []
        for _ in range(3):  # best of three: the machine is shared
            out = subprocess.run(
                [str(folder / "bench")], capture_output=True, text=True, check=True, timeout=300
            ).stdout.split()
            runs.append((float(out[0]), int(out[1])))
    ns, status = min(runs)
    return ns, nbytes, status


def python_step_us(make: object, n: int = 5000) -> float:
    """us per ``step`` of a controller made by ``make()`` on the harness's samples (CPU)."""
    ctl = make()  # type: ignore[operator]
    w = (np.arange(n) * 37 % 1024) / 1023.0 - 0.5
    forces = np.stack([0.4 * w, 2.0 - 0.3 * w, 10.0 + 0.5 * w - 0.35 * 9.80665], axis=1).tolist()
    rotation = [1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0]
    for _ in range(100):  # free air first: the tare, then the loop engages
        ctl.step([0.0, 0.0, -0.35 * 9.80665], rotation)
    t0 = time.process_time()
    for f in forces:
        _, status = ctl.step(f, rotation)
    us = (time.process_time() - t0) / n * 1e6
    if not status & st.ENGAGED or status & st.TRIPPED:
        raise RuntimeError(f"the benchmark's controller ended in status {st.describe(status)}")
    return us


def step_tables() -> None:
    from fuzzkit.control.reference import Controller
    from fuzzkit.loop.controller_code import open_generated

    spec = bench_spec()
    rows = []
    for number_type in ("float", "double"):
        ns, nbytes, status = c_step(spec, number_type)
        if not status & st.ENGAGED or status & st.TRIPPED:
            raise RuntimeError(f"C {number_type} ended in status {st.describe(status)}")
        rows.append((f"generated C {number_type} (-O2)", f"{ns:.0f} ns", f"{nbytes} B"))
    # the same controller as a PI: what the three fuzzy surfaces cost in the step above
    pi = dataclasses.replace(
        spec,
        kind="pi",
        axes=tuple(dataclasses.replace(a, kp=4e-5, ki=1e-5, kx=None) for a in spec.axes),
        rulebase=None,
        rulebase_ref=None,
        rulebase_source=None,
    )
    ns, nbytes, _ = c_step(pi, "float")
    rows.append(("generated C float, as PI", f"{ns:.0f} ns", f"{nbytes} B"))
    ref = python_step_us(lambda: Controller(spec))
    gen = python_step_us(lambda: open_generated(spec, "python"))
    rows.append(("reference controller (Python)", f"{ref * 1e3:.0f} ns", "-"))
    rows.append(("generated Python", f"{gen * 1e3:.0f} ns", "-"))
    print(
        "controller step: 3 axes, fuzzy-PI on the exact macvicar_whelan, front end on "
        "(tare, gravity, low-pass)"
    )
    print(f"{'implementation':<32}{'per step':>12}{'code + data':>14}")
    for name, per, size in rows:
        print(f"{name:<32}{per:>12}{size:>14}")
    print(f"targets: C float <= {TARGET_NS:g} ns per step, <= {TARGET_BYTES} B (text + data)")


def safety_matrix(seeds: int) -> None:
    from fuzzkit.loop.faults import FAULTS
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec
    from fuzzkit.studies.experiments import EXPERIMENTS

    durations = {"E1": 3.5, "E2": 5.0, "E3": None}  # tests/test_safety.py's
    impls = {"generated C controller, compiled loop": "c"}
    impls["reference controller, Python loop"] = "reference"
    totals = {"generated C controller, compiled loop": [0.0, 0.0, 0]}
    totals["reference controller, Python loop"] = [0.0, 0.0, 0]
    for name in sorted(EXPERIMENTS):
        for controller in ("pi", "fuzzy-pi"):
            for kind in sorted(FAULTS):
                for seed in range(seeds):
                    runs = {
                        label: run_spec(
                            RunSpec(
                                name,
                                controller,
                                "arm6",
                                seed=seed,
                                fault=kind,
                                duration_s=durations[name],
                                controller_impl=impl,
                            )
                        )
                        for label, impl in impls.items()
                    }
                    for label, r in runs.items():
                        t = totals[label]
                        t[0] += r.sim_time_s
                        t[1] += r.cpu_time_s
                        t[2] += 1
    print(
        f"safety matrix on arm6: E1-E3 x pi, fuzzy-pi x {len(FAULTS)} fault kinds x {seeds} "
        "seeds; real-time factor = simulated s / loop CPU s, summed"
    )
    print(f"{'controller, loop':<44}{'runs':>6}{'simulated s':>13}{'CPU s':>9}{'RTF':>9}")
    for label, (sim, cpu, n) in totals.items():
        print(f"{label:<44}{n:>6}{sim:>13.1f}{cpu:>9.2f}{sim / cpu:>8.0f}x")
    print(f"target: generated C controller >= {TARGET_RTF:g}x")


def main(argv: Sequence[str] = ()) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="seeds of the safety matrix")
    args, _ = parser.parse_known_args(list(argv))
    if find_compiler() is None:
        print("no C compiler: skipped")
        return
    step_tables()
    print()
    safety_matrix(args.seeds)


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
