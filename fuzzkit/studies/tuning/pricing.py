"""Pricing a gain set: simulating every case of a problem and costing each run, in this process
or in a worker process (one :class:`CaseRunner` per problem and process).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from fuzzkit.control.controllers import Surface
from fuzzkit.loop.adapter import make_plant
from fuzzkit.loop.result import RunResult
from fuzzkit.plants.contract import UnsupportedPlant
from fuzzkit.studies.tuning.cost import run_cost
from fuzzkit.studies.tuning.problem import TuningProblem


class CaseRunner:
    """Prices gain sets for one problem in this process.

    Each candidate runs through the loop's entry point (:func:`fuzzkit.loop.run.run_loop`), as
    ``fuzzkit simulate`` runs it: the candidate's controller spec as the generated controller
    (what ``fuzzkit compile`` emits, compiled once per structure, the candidate's gains set as
    run-time parameters), in the plant's compiled loop where it has one, else in the Python
    loop; the reference controller when asked for (``controller_impl == "reference"``). A
    surface given as a function has no generated code: the problem runs it on the reference
    controller, asked for by name (:meth:`TuningProblem.build`), and each run says so.
    """

    def __init__(self, problem: TuningProblem) -> None:
        self.problem = problem
        self.surface: Surface | None = None
        if problem.surface is not None and not isinstance(problem.surface, str):
            self.surface = problem.surface

    def run_case(
        self, case: int, gains: Mapping[str, float], duration_s: float | None
    ) -> RunResult:
        """Run case ``case`` with ``gains`` (searched names only, or complete) for
        ``duration_s`` (None: the experiment's whole duration)."""
        from fuzzkit.loop.run import run_loop
        from fuzzkit.loop.spec import RunSpec
        from fuzzkit.studies.batch import gains_items

        p = self.problem
        full = p.full_gains(gains)
        exp = p.cases[case]
        plant: Any = p.plant_of(case)
        if plant is None:
            plant = make_plant(p.plant) if isinstance(p.plant, str) else p.plant()
        spec = RunSpec(
            exp.name,
            p.controller,
            # a plant factory's name is no registered plant: it runs in the Python loop
            p.plant if isinstance(p.plant, str) else p.plant_name,
            latency=p.latency_of(case),
            seed=p.noise_seed,
            gains=gains_items(full),
            rulebase=p.rulebase_name or "macvicar_whelan",
            loop=p.loop,
            duration_s=duration_s,
            controller_impl=p.controller_impl,
        )
        return run_loop(spec, exp, plant, surface=self.surface)

    def implementation(self, gains: Mapping[str, float]) -> str:
        """What runs the problem's candidates, from the runs themselves: each experiment's
        first case run for one period with ``gains``, its ``controller_impl`` and ``loop``
        (``controller [loop]``; several, joined by ``; ``, when the experiments differ)."""
        p = self.problem
        seen: list[str] = []
        for group in range(len(p.experiments)):
            case = p.groups.index(group)
            r = self.run_case(case, gains, p.cases[case].scenario.period_s)
            label = f"{r.controller_impl} [{r.loop}]"
            if label not in seen:
                seen.append(label)
        return "; ".join(seen)

    def case_costs(self, gains: Mapping[str, float]) -> tuple[float, ...]:
        """The cost of ``gains`` (searched names only, or complete) on every case."""
        p = self.problem
        out = []
        for i, horizon in enumerate(p.horizons):
            try:
                result = self.run_case(i, gains, horizon)
            except UnsupportedPlant:
                raise  # a scenario the loop asked for cannot run: the user's to fix, every time
            except (ArithmeticError, ValueError):
                # Gains that break the simulation (overflow, unreachable targets) are merely
                # bad candidates: price them like a run that failed.
                out.append(p.weights.none)
                continue
            out.append(run_cost(result, p.weights))
        return tuple(out)


def evaluate_gains(problem: TuningProblem, gains: Mapping[str, float]) -> tuple[float, ...]:
    """The cost of ``gains`` on every case of ``problem``, computed in this process.

    The independent way to price a gain set (tests, benchmarks, the report); :func:`optimise`
    prices candidates the same way in worker processes.
    """
    return CaseRunner(problem).case_costs(gains)


# Worker-side state: one runner per problem and process, built on the first task that needs it.
_RUNNERS: dict[str, CaseRunner] = {}


def problem_key(problem: TuningProblem) -> str:
    import hashlib
    import pickle

    return hashlib.sha256(pickle.dumps(problem)).hexdigest()


def worker_costs(task: tuple[str, TuningProblem, dict[str, float]]) -> tuple[float, ...]:
    """Price one gain set in a worker (local process or Dask worker)."""
    key, problem, gains = task
    runner = _RUNNERS.get(key)
    if runner is None:
        _RUNNERS.clear()  # one problem at a time: keep the memory of one table
        runner = _RUNNERS[key] = CaseRunner(problem)
    return runner.case_costs(gains)
