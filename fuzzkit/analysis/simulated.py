"""Each cell's simulated outcome, to check the certificate against: settled, oscillating or
tripped, from a closed-loop run of the scenario at that stiffness and latency (compiled loop).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple

from fuzzkit.loop.result import RunResult
from fuzzkit.loop.task import Experiment
from fuzzkit.studies.batch import map_runs
from fuzzkit.studies.experiments import with_stiffness
from fuzzkit.studies.outcome import END_STATES, end_state


@dataclass(frozen=True, slots=True)
class SimCase:
    """One run: everything picklable a worker needs."""

    experiment: Experiment
    plant: str
    controller: str
    gains: tuple[tuple[str, float], ...]
    stiffness_n_per_mm: float
    latency: tuple[int, int]
    rulebase: str = "macvicar_whelan"
    seed: int = 0


def outcome(result: RunResult) -> str:
    """``settled``, ``oscillating`` (neither tripped nor settled) or ``tripped``
    (:func:`fuzzkit.studies.outcome.end_state`)."""
    return end_state(result)


class Simulated(NamedTuple):
    """One simulated cell: its :func:`outcome` and the ``controller_impl`` of the run (what
    ran the controller, as the run itself reports it)."""

    outcome: str
    controller_impl: str


def simulate_case(case: SimCase) -> Simulated:
    """The outcome of one case (:func:`run_case`) and the implementation that ran it."""
    result = run_case(case)
    return Simulated(outcome(result), result.controller_impl)


def run_case(case: SimCase) -> RunResult:
    """Run one case as ``fuzzkit simulate SCENARIO --stiffness K --latency S,C --seed N``
    runs it (:func:`fuzzkit.loop.run.run_loop`: the compiled loop and its generated C
    controller where the plant has one): the scenario at that stiffness (``regulate``: its
    approach speed follows the stiffness)."""
    from fuzzkit.loop.run import run_loop
    from fuzzkit.loop.spec import RunSpec

    exp = with_stiffness(case.experiment, case.stiffness_n_per_mm * 1e3)
    spec = RunSpec(
        experiment=exp.name,
        controller=case.controller,
        plant=case.plant,
        latency=case.latency,
        seed=case.seed,
        gains=case.gains,
        rulebase=case.rulebase,
    )
    return run_loop(spec, exp, case.plant)


def simulate_cells(
    exp: Experiment,
    plant: str,
    controller: str,
    gains: Mapping[str, float],
    stiffnesses_n_per_mm: Sequence[float],
    latencies: Sequence[tuple[int, int]],
    *,
    rulebase: str = "macvicar_whelan",
    workers: int | None = None,
    seed: int = 0,
) -> list[Simulated]:
    """The outcome of every (stiffness, latency) cell, stiffness-major as the certificate's,
    with the sensor noise seeded by ``seed``, each with the implementation that ran it."""
    return simulated_runs(
        exp,
        plant,
        controller,
        gains,
        stiffnesses_n_per_mm,
        latencies,
        (seed,),
        rulebase=rulebase,
        workers=workers,
    )[0]


def simulated_runs(
    exp: Experiment,
    plant: str,
    controller: str,
    gains: Mapping[str, float],
    stiffnesses_n_per_mm: Sequence[float],
    latencies: Sequence[tuple[int, int]],
    seeds: Sequence[int],
    *,
    rulebase: str = "macvicar_whelan",
    workers: int | None = None,
) -> list[list[Simulated]]:
    """Per seed, every cell (stiffness-major) as :class:`Simulated`; all runs in one batch."""
    items = tuple(sorted((str(k), float(v)) for k, v in gains.items()))
    cases = [
        SimCase(exp, plant, controller, items, float(k), (int(s), int(c)), rulebase, int(seed))
        for seed in seeds
        for k in stiffnesses_n_per_mm
        for s, c in latencies
    ]
    flat = map_runs(simulate_case, cases, workers=workers)
    n = len(stiffnesses_n_per_mm) * len(latencies)
    return [flat[i * n : (i + 1) * n] for i in range(len(seeds))]


def worst_outcome(outcomes: Sequence[str]) -> str:
    """``settled`` only when every seed settled; else the worst seen (tripped over oscillating)."""
    return max(outcomes, key=END_STATES.index)
