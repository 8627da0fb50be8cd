"""Benchmark of the 6-DOF inner loop (issue 5): simulated seconds per wall second, IK solves/s.

Run: ``.venv/bin/python bench/bench_arm6.py`` (prints a table; about 20 s on a 2-core machine).

Rows
----
* E2 closed loop on ``arm6``, PI and fuzzy-PI: the whole runner (plant + controller +
  recording), as ``fuzzkit compare --plant arm6`` runs it; target >= 500x real time.
* E2 plant only: the nominal path with a constant correction, no controller.
* IK, warm-started tracking: one 4 ms step of a 25 mm/s path per solve (what the plant does).
* IK, cold round trip: random reachable pose, seed 0.3 rad away (the round-trip test).
* FK batch: poses per second through ``SerialChain.fk_batch`` (1000 per call).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

import numpy as np


class _Clock:
    """Wall and CPU time of one measured stretch.

    The machine is shared: wall-clock rates swing with other processes' load, the process's
    CPU time much less, so both are reported.
    """

    def __init__(self) -> None:
        self.wall0 = time.perf_counter()
        self.cpu0 = time.process_time()

    def rates(self, work: float) -> tuple[float, float]:
        """``work`` per wall second and per CPU second since the clock started."""
        wall = time.perf_counter() - self.wall0
        cpu = max(time.process_time() - self.cpu0, 1e-9)
        return work / wall, work / cpu


def _best_of(fn: Callable[[], tuple[float, float]], repeat: int = 3) -> tuple[float, float]:
    """Best (largest) wall and CPU rates of ``repeat`` runs: the least disturbed."""
    runs = [fn() for _ in range(repeat)]
    return max(r[0] for r in runs), max(r[1] for r in runs)


def closed_loop_rate(controller: str) -> tuple[float, float]:
    """Simulated seconds per wall second and per CPU second of E2 on arm6 with ``controller``."""
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import run_spec

    spec = RunSpec("E2", controller, "arm6", controller_impl="reference")

    def once() -> tuple[float, float]:
        clock = _Clock()
        res = run_spec(spec)  # the loop's entry point, the reference asked for by name
        return clock.rates(res.sim_time_s)

    return _best_of(once)


def plant_only_rate() -> tuple[float, float]:
    """Simulated seconds per wall second of the arm6 plant alone on E2's path."""
    from fuzzkit.plants.arm6 import Arm6Plant
    from fuzzkit.studies.experiments import experiment

    scn = experiment("E2").scenario
    plant = Arm6Plant()
    n = round(scn.duration_s / scn.period_s)
    corr = np.array([0.0, 0.0, -0.003])

    def once() -> tuple[float, float]:
        plant.reset(scn, seed=0)
        clock = _Clock()
        for k in range(n):
            plant.step(corr, (k + 1) * scn.period_s)
        return clock.rates(n * scn.period_s)

    return _best_of(once)


def ik_tracking_rate() -> tuple[tuple[float, float], float]:
    """Warm-started IK solves per second along a 25 mm/s line, and mean iterations."""
    from fuzzkit.plants.kinematics import SerialChain

    chain = SerialChain()
    q = np.array([0.0, 0.3, 0.3, 0.0, 0.9, np.pi])
    start = chain.fk(q)
    n = 2000
    targets = []
    for k in range(n):
        t = start.copy()
        t[0, 3] += 0.025 * 0.004 * k
        targets.append(t)
    iters: list[int] = []

    def once() -> tuple[float, float]:
        seed = q
        iters.clear()
        clock = _Clock()
        for t in targets:
            res = chain.ik(
                t, seed, position_tolerance=1e-7, orientation_tolerance=1e-7, max_iterations=4
            )
            seed = res.q
            iters.append(res.iterations)
        return clock.rates(n)

    rate = _best_of(once)
    return rate, float(np.mean(iters))


def ik_cold_rate() -> tuple[tuple[float, float], float]:
    """Round-trip IK solves per second (seed 0.3 rad off), and the converged fraction."""
    from fuzzkit.plants.kinematics import SerialChain

    chain = SerialChain()
    rng = np.random.default_rng(0)
    qs = rng.uniform(chain.lower, chain.upper, (500, 6))
    targets = chain.fk_batch(qs)
    seeds = np.clip(qs + rng.uniform(-0.3, 0.3, qs.shape), chain.lower, chain.upper)
    ok: list[bool] = []

    def once() -> tuple[float, float]:
        ok.clear()
        clock = _Clock()
        for t, s in zip(targets, seeds, strict=True):
            ok.append(chain.ik(t, s).converged)
        return clock.rates(len(targets))

    rate = _best_of(once)
    return rate, float(np.mean(ok))


def fk_batch_rate() -> tuple[float, float]:
    """Poses per second through the vectorised batch FK."""
    from fuzzkit.plants.kinematics import SerialChain

    chain = SerialChain()
    qs = np.random.default_rng(1).uniform(chain.lower, chain.upper, (1000, 6))

    def once() -> tuple[float, float]:
        clock = _Clock()
        for _ in range(20):
            chain.fk_batch(qs)
        return clock.rates(20 * len(qs))

    return _best_of(once)


def main() -> int:
    """Measure and print the table; returns the process exit code."""
    rows: list[tuple[str, str, str, str]] = []
    for controller in ("pi", "fuzzy-pi"):
        wall, cpu = closed_loop_rate(controller)
        rows.append(
            (
                f"E2 closed loop on arm6, {controller}",
                f"{wall:,.0f}x",
                f"{cpu:,.0f}x",
                "sim s per s (target >= 500x)",
            )
        )
    wall, cpu = plant_only_rate()
    rows.append(
        (
            "E2 arm6 plant only (no controller)",
            f"{wall:,.0f}x",
            f"{cpu:,.0f}x",
            f"sim s per s; {1e6 * 0.004 / cpu:,.0f} us CPU per 4 ms step",
        )
    )
    (wall, cpu), it = ik_tracking_rate()
    rows.append(
        (
            "IK warm-started tracking (25 mm/s)",
            f"{wall:,.0f}",
            f"{cpu:,.0f}",
            f"solves/s, {it:.2f} iterations per solve",
        )
    )
    (wall, cpu), frac = ik_cold_rate()
    rows.append(
        (
            "IK round trip, seed 0.3 rad off",
            f"{wall:,.0f}",
            f"{cpu:,.0f}",
            f"solves/s, {100 * frac:.1f} % converged",
        )
    )
    wall, cpu = fk_batch_rate()
    rows.append(
        ("FK batch (1000 configurations per call)", f"{wall:,.0f}", f"{cpu:,.0f}", "poses/s")
    )
    head = ("arm6 benchmark", "per wall s", "per CPU s", "unit")
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(3)]
    print(f"{head[0]:<{widths[0]}}  {head[1]:>{widths[1]}}  {head[2]:>{widths[2]}}  {head[3]}")
    print("-" * (sum(widths) + 50))
    for a, b, c, d in rows:
        print(f"{a:<{widths[0]}}  {b:>{widths[1]}}  {c:>{widths[2]}}  {d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
