"""Benchmark of the closed loop at the speed limit (issue 11): Python loop vs compiled loop.

Run: ``.venv/bin/python bench/bench_loop.py [--budget N] [--skip-tune]`` (prints four tables;
a few minutes on a 2-core machine, most of it the Python-loop tuning runs).

Tables
------
1. Real-time factors, CPU time (``time.process_time`` of the loop alone, start-up excluded;
   best of 5 compiled, 2 Python runs): E1-E3 on ``arm6`` and on the pymunk ``planar`` arm
   with PI and fuzzy-PI, the Python reference loop (fuzzy-PI on the exact engine, as
   ``simulate --controller-impl reference`` runs it) next to the compiled loop (the run's
   generated C controller); the same on the MuJoCo IRB 140 (``mujoco``: 1 kHz physics, the
   servo ramp as a C control callback). Targets (issue 37): 1,000x on arm6, 400x on planar,
   40x on mujoco. Then the
   first-call cost of each compiled kernel in a fresh numba cache (what the first run after an
   install pays).
2. Where the planar period's time goes: in the Python loop, pymunk's step through its Python
   wrapper and through the bare C call, the other pymunk calls of a substep, and the cap they
   put on the real-time factor with 4 substeps per 4 ms period; in the compiled loop, the
   whole period, the same Chipmunk calls made alone from numba, and their share.
3. Sweep throughput: runs per wall second of ``fuzzkit sweep`` (all local cores), compiled
   loop (60 runs) vs Python loop (12 runs), on each plant.
5. The engine at scale: ``Engine.evaluate`` on 1e6 MacVicar-Whelan points, traced peak memory
   and CPU time, chunked (now) vs one pass (``chunk_points`` set huge: the old behaviour); and
   an output with gaussian terms (compiled grid integration), ms per point.
4. Tuning time: ``tune E1 --budget N`` over 5/10/20 N/mm, and a robust tune over 3 stiffnesses x
   3 latencies, on arm6 with the Python loop (before) and the compiled loop (after); the same
   on the planar plant.

Tables 1, 3 and 4 say what ran the controller in each row, read from the runs themselves
(their ``controller_impl``, :func:`fuzzkit.loop.result.implementations`).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from fuzzkit.loop.result import RunResult

ARM6_CASES = ("E1", "E2", "E3")
CONTROLLERS = ("pi", "fuzzy-pi")


def _best_rtf(fn: Callable[[], RunResult], repeat: int = 3) -> tuple[float, str]:
    """Best real-time factor of ``repeat`` runs (CPU time): the least disturbed; and what ran
    the controller (:func:`fuzzkit.loop.result.implementations` of the runs)."""
    from fuzzkit.loop.result import implementations

    runs = [fn() for _ in range(repeat)]
    return max(r.real_time_factor for r in runs), implementations(r.controller_impl for r in runs)


#: (plant, target real-time factor of its compiled loop)
LOOP_TARGETS = (("arm6", 1000), ("planar", 400), ("mujoco", 40))  # issue 37, items 4 and 6


def real_time_factors(
    plants: Sequence[tuple[str, int]] = LOOP_TARGETS,
) -> list[tuple[str, float, float | None, int, str]]:
    """``(case, python rtf, compiled rtf, target, what ran)`` rows, CPU time; what ran: the
    ``controller_impl`` of each column's runs."""
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    rows: list[tuple[str, float, float | None, int, str]] = []
    for plant, target in plants:
        for name in ARM6_CASES:
            for ctrl in CONTROLLERS:
                spec = RunSpec(name, ctrl, plant=plant)
                # build tables, load caches: start-up is not what is measured
                compiled = run_spec(spec).loop == "compiled"
                py, py_ran = _best_rtf(
                    lambda s=spec: run_spec(
                        RunSpec(s.experiment, s.controller, s.plant, controller_impl="reference")
                    ),
                    repeat=2,
                )
                if not compiled:  # a plant the kernel does not model: the Python loop ran it
                    rows.append((f"{name} {plant} {ctrl} fallback", py, None, target, py_ran))
                    continue
                co, co_ran = _best_rtf(lambda s=spec: run_spec(s), repeat=5)
                rows.append((f"{name} {plant} {ctrl}", py, co, target, f"{py_ran} | {co_ran}"))
    return rows


_FIRST_CALLS = """
import json, time
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import run_spec
from fuzzkit.loop.compiled import generated_controller as G
from fuzzkit.studies.experiments import experiment
G.load_generated_controller(G.run_controller_spec(experiment("E1"), "fuzzy-pi", None))  # not numba
out = {}
for label, plant in (
    ("arm6 (whole kernel)", "arm6"),
    ("planar (its plant and loop)", "planar"),
    ("mujoco (its loop, servo callback built)", "mujoco"),
):
    c0, w0 = time.process_time(), time.perf_counter()
    run_spec(RunSpec("E1", "fuzzy-pi", plant, duration_s=0.1))
    out[label] = (time.process_time() - c0, time.perf_counter() - w0)
print(json.dumps(out))
"""


def first_call_costs() -> list[tuple[str, float, float]]:
    """``(variant, CPU s, wall s)`` of the first compiled run in a fresh numba cache: the arm6
    kernel, then the planar loop's plant and loop (the shared period is cached by then)."""
    import json
    import os
    import subprocess
    import tempfile

    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        done = subprocess.run(
            [sys.executable, "-c", _FIRST_CALLS], env=env, capture_output=True, text=True
        )
    if done.returncode != 0:
        print(done.stderr, file=sys.stderr)
        return []
    costs: dict[str, list[float]] = json.loads(done.stdout.splitlines()[-1])
    return [(label, cpu, wall) for label, (cpu, wall) in costs.items()]


def planar_breakdown() -> list[tuple[str, float]]:
    """CPU microseconds of the pymunk calls one planar substep makes, and the resulting caps."""
    import numpy as np
    from pymunk._chipmunk import lib

    from fuzzkit.planar_sim import PlanarArmPlant
    from fuzzkit.studies.experiments import experiment

    exp = experiment("E1")
    plant = PlanarArmPlant()
    plant.reset(exp.scenario)
    space, tool, motor = plant._space, plant._tool, plant._motor1
    dt = plant._dt
    n = 20000

    def per_call(fn: Callable[[], object]) -> float:
        t0 = time.process_time()
        for _ in range(n):
            fn()
        return 1e6 * (time.process_time() - t0) / n

    ptr = space._space
    step_py = per_call(lambda: space.step(dt))
    step_c = per_call(lambda: lib.cpSpaceStep(ptr, dt))
    reads = per_call(lambda: (tool.position, tool.velocity))

    def set_rate() -> None:
        motor.rate = 0.1

    rate = per_call(set_rate)
    impulse = per_call(lambda: motor.impulse)
    force = per_call(lambda: tool.apply_force_at_world_point((0.0, 0.0), (0.0, 0.0)))
    sub = plant.params.substeps
    pymunk_min = step_py + reads + 2 * rate + 2 * impulse + force
    zero = np.zeros(3)
    plant.reset(exp.scenario)
    t0 = time.process_time()
    periods = 1000
    for k in range(periods):
        plant.step(zero, (k + 1) * exp.scenario.period_s)
    plant_us = 1e6 * (time.process_time() - t0) / periods
    period_us = 1e6 * exp.scenario.period_s
    compiled_us, chipmunk_us = _compiled_planar_split()
    return [
        ("pymunk Space.step (Python wrapper), per substep", step_py),
        ("cpSpaceStep (the C step alone), per substep", step_c),
        ("tool position + velocity read, per substep", reads),
        ("motor rate set (x2 per substep), each", rate),
        ("motor impulse read (x2 per substep), each", impulse),
        ("apply_force_at_world_point, per substep", force),
        (f"pymunk calls of one period ({sub} substeps)", sub * pymunk_min),
        ("whole planar plant step (Python), per period", plant_us),
        ("cap: real-time factor if only the pymunk calls ran", period_us / (sub * pymunk_min)),
        ("cap: real-time factor if only cpSpaceStep ran", period_us / (sub * step_c)),
        ("planar plant alone, real-time factor", period_us / plant_us),
        ("compiled loop (E2 PI), whole period", compiled_us),
        ("  of which its Chipmunk calls (same calls, from numba)", chipmunk_us),
        ("  of which the rest (contact, sensor, controller ...)", compiled_us - chipmunk_us),
        ("  Chipmunk share of the compiled period, %", 100.0 * chipmunk_us / compiled_us),
        ("cap: real-time factor if only the Chipmunk calls ran", period_us / chipmunk_us),
    ]


def _compiled_planar_split() -> tuple[float, float]:
    """CPU us per period of the compiled planar loop (E2, PI, best of 5), and of the Chipmunk
    calls it makes per period alone (the same calls from a numba loop on the same arm, the
    force applied every substep: an upper bound)."""
    import numba

    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.planar_sim import PlanarArmPlant
    from fuzzkit.planar_sim import chipmunk_calls as cc
    from fuzzkit.planar_sim.arm_period import (
        X_LINK1,
        X_LINK2,
        X_MOTOR1,
        X_MOTOR2,
        X_SPACE,
        X_TOOL,
        pack,
    )
    from fuzzkit.studies.batch import run_spec
    from fuzzkit.studies.experiments import experiment

    spec = RunSpec("E2", "pi", plant="planar")
    run_spec(spec)
    best = min(
        (r.cpu_time_s / len(r.t) for r in (run_spec(spec) for _ in range(5))),
    )

    @numba.njit
    def calls_only(f: object, x: object, dt: float, substeps: int, periods: int) -> float:
        acc = 0.0
        for _ in range(periods):
            for _ in range(substeps):
                q1 = cc.call_d_p(f[cc.F_GET_ANGLE], x[X_LINK1])
                q2 = cc.call_d_p(f[cc.F_GET_ANGLE], x[X_LINK2]) - q1
                cc.call_v_pd(f[cc.F_MOTOR_SET_RATE], x[X_MOTOR1], 0.0 * q1)
                cc.call_v_pd(f[cc.F_MOTOR_SET_RATE], x[X_MOTOR2], 0.0 * q2)
                px, pz = cc.call_vec_p(f[cc.F_GET_POSITION], x[X_TOOL])
                vx, vz = cc.call_vec_p(f[cc.F_GET_VELOCITY], x[X_TOOL])
                cc.call_v_pvv(f[cc.F_APPLY_FORCE], x[X_TOOL], 0.0, 0.0, px, pz)
                cc.call_v_pd(f[cc.F_SPACE_STEP], x[X_SPACE], dt)
                acc += cc.call_d_p(f[cc.F_GET_IMPULSE], x[X_MOTOR1]) + vx + vz
                acc += cc.call_d_p(f[cc.F_GET_IMPULSE], x[X_MOTOR2])
            acc += cc.call_d_p(f[cc.F_GET_ANGLE], x[X_LINK1])  # the sample's reads
            acc += cc.call_d_p(f[cc.F_GET_ANGLE], x[X_LINK2])
            acc += cc.call_vec_p(f[cc.F_GET_POSITION], x[X_TOOL])[0]
        return acc

    plant = PlanarArmPlant()
    plant.reset(experiment("E2").scenario)
    a = pack(plant)
    dt, sub = plant._dt, plant.params.substeps
    calls_only(a.functions, a.pointers, dt, sub, 1)  # compile
    periods = 20000
    t0 = time.process_time()
    calls_only(a.functions, a.pointers, dt, sub, periods)
    chipmunk = (time.process_time() - t0) / periods
    return 1e6 * best, 1e6 * chipmunk


def sweep_throughput(workers: int) -> list[tuple[str, float, int, str]]:
    """Runs per wall second of a sweep of whole runs on each plant: 60 compiled, 12 Python (the
    pool's start-up is included, so small sweeps understate the compiled rate), and what ran
    the controller (the rows' ``controller_impl``)."""
    from fuzzkit.loop.result import implementations
    from fuzzkit.studies.sweep import run_sweep, sweep_specs

    out = []
    for plant, loop, seeds in (
        ("arm6", "compiled", 5),
        ("arm6", "python", 1),
        ("planar", "compiled", 5),
        ("planar", "python", 1),
    ):
        specs = sweep_specs(
            ["E1", "E2", "E3"],
            list(CONTROLLERS),
            stiffnesses_n_per_mm=[5.0, 20.0],
            seeds=seeds,
            plant=plant,
            loop=loop,
        )
        t0 = time.perf_counter()
        rows = run_sweep(specs, workers=workers)
        out.append(
            (
                f"sweep, {len(specs)} {plant} runs, {loop} loop",
                len(specs) / (time.perf_counter() - t0),
                len(specs),
                implementations(str(r["controller_impl"]) for r in rows),
            )
        )
    return out


def tune_times(budget: int, workers: int) -> list[tuple[str, float, int, float, float, str]]:
    """``(case, wall s, evaluations, cost, default cost, what ran)`` of the tuning runs."""
    from fuzzkit.studies.tuning import tune

    cases: list[tuple[str, dict[str, object]]] = [
        ("E1 pi planar, python loop (before)", {"plant": "planar", "loop": "python"}),
        ("E1 pi planar, compiled loop (after)", {"plant": "planar", "loop": "compiled"}),
        ("E1 pi arm6, python loop (before)", {"plant": "arm6", "loop": "python"}),
        ("E1 pi arm6, compiled loop (after)", {"plant": "arm6", "loop": "compiled"}),
        (
            "E1 pi arm6 robust 3k x 3 lat, python (before)",
            {"plant": "arm6", "loop": "python", "latencies": [(0, 0), (1, 1), (2, 2)]},
        ),
        (
            "E1 pi arm6 robust 3k x 3 lat, compiled (after)",
            {"plant": "arm6", "loop": "compiled", "latencies": [(0, 0), (1, 1), (2, 2)]},
        ),
    ]
    rows = []
    for label, kw in cases:
        r = tune(["E1"], "pi", budget=budget, seed=0, workers=workers, **kw)  # type: ignore[arg-type]
        rows.append(
            (label, r.wall_time_s, r.evaluations, r.cost, r.baseline_cost, r.controller_impl)
        )
    return rows


def engine_scale() -> list[tuple[str, float, float]]:
    """``(case, peak MB, CPU s)`` of large batches, and ms per point of a gaussian output."""
    import dataclasses
    import tracemalloc

    import numpy as np

    from fuzzkit.formats.registry import load
    from fuzzkit.fuzzy.inference import Engine
    from fuzzkit.fuzzy.model import Term

    rb = load("macvicar_whelan")
    eng = Engine(rb)
    rng = np.random.default_rng(0)
    e, de = rng.uniform(-1, 1, 1_000_000), rng.uniform(-1, 1, 1_000_000)
    rows = []
    for label, chunk in (
        ("1e6 points, chunked (now)", eng.chunk_points),
        ("1e6 points, one pass", 10**9),
    ):
        eng.chunk_points = chunk
        tracemalloc.start()
        t0 = time.process_time()
        eng.evaluate({"e": e, "de": de})
        cpu = time.process_time() - t0
        peak = tracemalloc.get_traced_memory()[1] / 1e6
        tracemalloc.stop()
        rows.append((label, peak, cpu))
    out = rb.outputs[0]
    terms = tuple(Term(t.name, "gaussian", (float(t.params[1]), 0.15)) for t in out.terms)
    for d in ("centroid", "bisector", "mean_of_maximum"):
        g = Engine(
            dataclasses.replace(rb, outputs=(dataclasses.replace(out, terms=terms),), defuzzifier=d)
        )
        g.evaluate({"e": e[:2], "de": de[:2]})  # load the compiled kernel
        tracemalloc.start()
        t0 = time.process_time()
        g.evaluate({"e": e[:200], "de": de[:200]})
        cpu = time.process_time() - t0
        peak = tracemalloc.get_traced_memory()[1] / 1e6
        tracemalloc.stop()
        rows.append((f"gaussian output, {d}, ms per point", peak, 1e3 * cpu / 200))
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    """Run the benchmark and print its tables; returns 0."""
    from fuzzkit.studies.batch import default_workers

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--budget", type=int, default=60)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--skip-tune", action="store_true")
    args, _ = parser.parse_known_args(argv)  # `make bench` passes options for other benches
    workers = args.workers or default_workers()

    print("1. real-time factor, simulated s per CPU s of the loop (best of runs)")
    head = f"{'case':<22}{'python loop':>13}{'compiled':>11}{'speed-up':>10}   target"
    print(head)
    print("-" * (len(head) + 12))
    ran: dict[str, str] = {}
    for name, py, co, target, what in real_time_factors():
        ran[name] = what
        if co is None:
            print(
                f"{name:<22}{py:>12.0f}x{'-':>11}{'-':>10}   >= {target}x "
                f"{'ok' if py >= target else 'MISS'}"
            )
        else:
            print(
                f"{name:<22}{py:>12.0f}x{co:>10.0f}x{co / py:>9.0f}x   >= {target}x "
                f"{'ok' if co >= target else 'MISS'}"
            )

    print("what ran the controller (the runs' controller_impl; python loop | compiled):")
    for name, what in ran.items():
        print(f"  {name:<22}{what}")

    print("\n1b. first compiled run in a fresh numba cache (compile cost; CPU s, wall s)")
    for label, cpu, wall in first_call_costs():
        print(f"  {label:<40}{cpu:>8.1f}{wall:>8.1f}")

    print("\n2. planar plant: where a period's CPU time goes (us, or x real time for caps)")
    for name, value in planar_breakdown():
        print(f"  {name:<54}{value:>9.2f}")

    print("\n5. the engine at scale (traced peak MB, CPU s or ms per point)")
    for name, peak, cpu in engine_scale():
        print(f"  {name:<44}{peak:>10.1f} MB{cpu:>10.3f}")

    print(f"\n3. sweep throughput on {workers} local processes")
    for name, rate, _, what in sweep_throughput(workers):
        print(f"  {name:<40}{rate:>8.2f} runs/s   {what}")

    if not args.skip_tune:
        print(f"\n4. tune E1, budget {args.budget}, {workers} workers, 5/10/20 N/mm")
        head = f"{'case':<48}{'wall s':>8}{'evals':>7}{'cost':>10}{'default':>10}"
        print(head)
        print("-" * len(head))
        for label, wall, evals, cost, base, what in tune_times(args.budget, workers):
            print(f"{label:<48}{wall:>8.1f}{evals:>7}{cost:>10.4f}{base:>10.4f}   {what}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
