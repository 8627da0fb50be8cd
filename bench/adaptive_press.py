"""Adaptive against fixed scaling factors on a guarded press (issue 24): a table.

The press is :mod:`fuzzkit.studies.spring_loop`'s bench: the tool approaches a flat spring at
0.2 mm/s, the nominal path stops 0.3 mm past the surface, set point 12 N, 0.1 N sensor noise,
6 s. Per stiffness (N/mm) and latency (periods each way) over SEEDS noise seeds, for the
adaptive spec ``docs/examples/controller_adaptive.yaml`` (its estimator delay matched to the
latency), the same spec self-tuning (``mode: self-tuning``, alpha in [0.2, 1], the fuzzy-PI's
own input scaling) and the same spec with fixed gains (the shipped ones): trips, runs settled
within 5 % of the set point over the last second, and the mean ITAE (N s^2) of those that did
not trip.

    .venv/bin/python bench/adaptive_press.py [SEEDS]
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np

from fuzzkit.control import status as st
from fuzzkit.control.adaptation_spec import NONE, Adaptation
from fuzzkit.control.reference import Controller
from fuzzkit.control.spec import ControllerSpec
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.studies.spring_loop import SpringBench, run_spring

SPEC = Path(__file__).resolve().parent.parent / "docs" / "examples" / "controller_adaptive.yaml"
STIFFNESS_N_MM = (5.0, 20.0, 100.0, 500.0, 1000.0)
LATENCIES = (0, 1, 2, 3)
SETPOINT_N = 12.0


def one(spec: ControllerSpec, k: float, latency: int, seed: int) -> tuple[bool, bool, float]:
    bench = SpringBench(
        stiffness=((0.0, k),), duration_s=6.0, stop_s=2.5, latency_in=latency,
        latency_out=latency, seed=seed,
    )  # fmt: skip
    res = run_spring(bench, Controller(spec).step)
    tripped = bool(np.any(res.status & st.TRIPPED))
    t = np.arange(len(res.force_n)) * bench.period_s
    tail = res.force_n[t >= bench.duration_s - 1.0]
    settled = not tripped and bool(np.all(np.abs(tail - SETPOINT_N) <= 0.05 * SETPOINT_N))
    contact = t >= bench.start_gap_m / bench.approach_m_s
    err = np.abs(res.force_n - SETPOINT_N)[contact]
    itae = float(np.sum((t[contact] - t[contact][0]) * err) * bench.period_s)
    return tripped, settled, itae


def main() -> None:
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    adaptive = load_spec(SPEC)
    print(f"guarded press, 12 N, {seeds} seeds: trips / settled (5 %, last 1 s) / mean ITAE")
    print(
        f"{'k N/mm':>7} {'lat':>4} | {'stiffness-scheduled':>22} | {'self-tuning':>22} | "
        f"{'fixed (shipped gains)':>22}"
    )
    tuning = dataclasses.replace(adaptive, adaptation=Adaptation("self-tuning"))
    for k in STIFFNESS_N_MM:
        for lat in LATENCIES:
            est = dataclasses.replace(adaptive.adaptation.estimator, delay_periods=1 + 2 * lat)
            ad = dataclasses.replace(
                adaptive, adaptation=dataclasses.replace(adaptive.adaptation, estimator=est)
            )
            cells = []
            for spec in (ad, tuning, dataclasses.replace(adaptive, adaptation=NONE)):
                runs = [one(spec, k, lat, s) for s in range(seeds)]
                trips = sum(r[0] for r in runs)
                settled = sum(r[1] for r in runs)
                itaes = [r[2] for r in runs if not r[0]]
                itae = f"{np.mean(itaes):8.1f}" if itaes else f"{'-':>8}"
                cells.append(f"{trips:>3} / {settled:>3} / {itae}")
            print(f"{k:>7g} {lat:>2}+{lat} | " + " | ".join(f"{c:>22}" for c in cells), flush=True)


if __name__ == "__main__":
    main()
