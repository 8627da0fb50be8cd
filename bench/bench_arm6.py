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


def _best_of(fn: Callable[[], float], repeat: int = 3) -> float:
    """Best (largest) rate of ``repeat`` runs: the least disturbed by other processes."""
    return max(fn() for _ in range(repeat))


def closed_loop_rate(controller: str) -> float:
    """Simulated seconds per wall second of E2 on arm6 with ``controller``."""
    from fuzzkit.experiments import experiment, load_surface, run

    surface = load_surface() if controller == "fuzzy-pi" else None
    exp = experiment("E2")

    def once() -> float:
        t0 = time.perf_counter()
        res = run(exp, "arm6", controller, surface=surface)
        return res.sim_time_s / (time.perf_counter() - t0)

    return _best_of(once)


def plant_only_rate() -> float:
    """Simulated seconds per wall second of the arm6 plant alone on E2's path."""
    from fuzzkit.experiments import experiment
    from fuzzkit.motion import Arm6Plant

    scn = experiment("E2").scenario
    plant = Arm6Plant()
    n = round(scn.duration_s / scn.period_s)
    corr = np.array([0.0, 0.0, -0.003])

    def once() -> float:
        plant.reset(scn, seed=0)
        t0 = time.perf_counter()
        for k in range(n):
            plant.step(corr, (k + 1) * scn.period_s)
        return n * scn.period_s / (time.perf_counter() - t0)

    return _best_of(once)


def ik_tracking_rate() -> tuple[float, float]:
    """Warm-started IK solves per second along a 25 mm/s line, and mean iterations."""
    from fuzzkit.kinematics import SerialChain

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

    def once() -> float:
        seed = q
        iters.clear()
        t0 = time.perf_counter()
        for t in targets:
            res = chain.ik(
                t, seed, position_tolerance=1e-7, orientation_tolerance=1e-7, max_iterations=4
            )
            seed = res.q
            iters.append(res.iterations)
        return n / (time.perf_counter() - t0)

    rate = _best_of(once)
    return rate, float(np.mean(iters))


def ik_cold_rate() -> tuple[float, float]:
    """Round-trip IK solves per second (seed 0.3 rad off), and the converged fraction."""
    from fuzzkit.kinematics import SerialChain

    chain = SerialChain()
    rng = np.random.default_rng(0)
    qs = rng.uniform(chain.lower, chain.upper, (500, 6))
    targets = chain.fk_batch(qs)
    seeds = np.clip(qs + rng.uniform(-0.3, 0.3, qs.shape), chain.lower, chain.upper)
    ok: list[bool] = []

    def once() -> float:
        ok.clear()
        t0 = time.perf_counter()
        for t, s in zip(targets, seeds, strict=True):
            ok.append(chain.ik(t, s).converged)
        return len(targets) / (time.perf_counter() - t0)

    rate = _best_of(once)
    return rate, float(np.mean(ok))


def fk_batch_rate() -> float:
    """Poses per second through the vectorised batch FK."""
    from fuzzkit.kinematics import SerialChain

    chain = SerialChain()
    qs = np.random.default_rng(1).uniform(chain.lower, chain.upper, (1000, 6))

    def once() -> float:
        t0 = time.perf_counter()
        for _ in range(20):
            chain.fk_batch(qs)
        return 20 * len(qs) / (time.perf_counter() - t0)

    return _best_of(once)


def main() -> int:
    """Measure and print the table; returns the process exit code."""
    rows: list[tuple[str, str, str]] = []
    for controller in ("pi", "fuzzy-pi"):
        r = closed_loop_rate(controller)
        rows.append(
            (f"E2 closed loop on arm6, {controller}", f"{r:,.0f} x real time", "target >= 500x")
        )
    r = plant_only_rate()
    rows.append(
        (
            "E2 arm6 plant only (no controller)",
            f"{r:,.0f} x real time",
            f"{1e6 * 0.004 / r:,.0f} us per 4 ms step",
        )
    )
    rate, it = ik_tracking_rate()
    rows.append(
        (
            "IK warm-started tracking (25 mm/s)",
            f"{rate:,.0f} solves/s",
            f"{it:.2f} iterations per solve",
        )
    )
    rate, frac = ik_cold_rate()
    rows.append(
        (
            "IK round trip, seed 0.3 rad off",
            f"{rate:,.0f} solves/s",
            f"{100 * frac:.1f} % converged",
        )
    )
    r = fk_batch_rate()
    rows.append(("FK batch (1000 configurations per call)", f"{r:,.0f} poses/s", ""))
    w0 = max(len(a) for a, _, _ in rows)
    w1 = max(len(b) for _, b, _ in rows)
    print(f"{'arm6 benchmark':<{w0}}  {'rate':>{w1}}  note")
    print("-" * (w0 + w1 + 30))
    for a, b, c in rows:
        print(f"{a:<{w0}}  {b:>{w1}}  {c}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
