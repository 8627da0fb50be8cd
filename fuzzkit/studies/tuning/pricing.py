"""Pricing a gain set: simulating every case of a problem and costing each run, in this process
or in a worker process (one :class:`CaseRunner` per problem and process).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from fuzzkit.control.controllers import Surface
from fuzzkit.errors import ConfigError
from fuzzkit.studies.plants import make_plant
from fuzzkit.studies.runner import RunResult, run
from fuzzkit.studies.tuning.cost import run_cost
from fuzzkit.studies.tuning.problem import TuningProblem


def adapts(exp: Any) -> bool:
    """True when the experiment's controller spec adapts its gains (the compiled loop runs
    fixed gains only)."""
    spec = exp.controller_spec
    return spec is not None and spec.adaptation.mode != "none"


class CaseRunner:
    """Prices gain sets for one problem in this process.

    Each candidate's controller spec runs as the generated controller (what ``fuzzkit
    compile`` emits, compiled once per structure, the candidate's gains set as run-time
    parameters): in the compiled loop (:mod:`fuzzkit.studies.compiled`) where the plant has
    one, else in the Python loop (:class:`~fuzzkit.studies.loop_controller.
    GeneratedLoopController`). The reference controller runs when asked for
    (``controller_impl == "python"``, ``loop == "python"``), for a surface given as a function,
    and for a controller spec that adapts its gains; its fuzzy surface is then the exact
    engine (in the spec's input roles) or that function.
    """

    def __init__(self, problem: TuningProblem) -> None:
        from fuzzkit.studies.compiled.loop import compiled_supports

        self.problem = problem
        self.surface: Surface | None = None
        self.compiled = (
            problem.loop != "python"
            and problem.controller_impl != "python"
            and isinstance(problem.plant, str)
            and compiled_supports(problem.plant)
            and (problem.surface is None or isinstance(problem.surface, str))
            and not any(adapts(exp) for exp in problem.cases)
        )
        if problem.loop == "compiled" and not self.compiled:
            raise ConfigError(
                f"the compiled loop does not run plant {problem.plant_name} "
                "(or a surface given as a function); use loop='python'"
            )
        self.generated = self.compiled or (
            problem.loop != "python"
            and problem.controller_impl != "python"
            and (problem.surface is None or isinstance(problem.surface, str))
            and not any(adapts(exp) for exp in problem.cases)
        )
        if self.generated:
            pass  # the generated controller holds the surface
        elif isinstance(problem.surface, str):
            self.surface = _rulebase_surface(problem)
        else:
            self.surface = problem.surface

    def run_case(
        self, case: int, gains: Mapping[str, float], duration_s: float | None
    ) -> RunResult:
        """Run case ``case`` with ``gains`` (searched names only, or complete) for
        ``duration_s`` (None: the experiment's whole duration)."""
        from fuzzkit.studies.compiled.loop import run_compiled

        p = self.problem
        full = p.full_gains(gains)
        exp = p.cases[case]
        own = p.plant_of(case)
        if self.compiled:
            return run_compiled(
                exp,
                own if own is not None else str(p.plant),
                seed=p.noise_seed,
                duration_s=duration_s,
                latency=p.latency_of(case),
                generated_controller=self._generated(exp, full),
            )
        plant = own or (make_plant(p.plant) if isinstance(p.plant, str) else p.plant())
        hybrid = self._python_loop_controller(exp, full, p.latency_of(case))
        return run(
            exp,
            plant,
            p.controller,
            gains=full,
            surface=self.surface,
            hybrid=hybrid,
            seed=p.noise_seed,
            duration_s=duration_s,
            latency=p.latency_of(case),
        )

    def _python_loop_controller(
        self, exp: Any, gains: Mapping[str, float], latency: tuple[int, int] | None
    ) -> Any:
        """The candidate's generated controller for the Python loop (None: the reference)."""
        if not self.generated:
            return None
        from fuzzkit.studies.loop_controller import run_controller

        p = self.problem
        rulebase = p.rulebase_name or "macvicar_whelan"
        impl_c = p.controller_impl == "c"
        return run_controller(
            exp, p.controller, gains, rulebase, p.noise_seed, None, latency, impl_c
        )

    def _generated(self, exp: Any, gains: Mapping[str, float]) -> Any:
        """The generated C controller of the candidate ``gains`` on ``exp`` (compiled once
        per distinct code and process)."""
        from fuzzkit.studies.compiled.generated_controller import (
            load_generated_controller,
            run_controller_spec,
        )

        rulebase = self.problem.rulebase_name or "macvicar_whelan"
        return load_generated_controller(
            run_controller_spec(exp, self.problem.controller, gains, rulebase)
        )

    def case_costs(self, gains: Mapping[str, float]) -> tuple[float, ...]:
        """The cost of ``gains`` (searched names only, or complete) on every case."""
        p = self.problem
        out = []
        for i, horizon in enumerate(p.horizons):
            try:
                result = self.run_case(i, gains, horizon)
            except (ArithmeticError, ValueError):
                # Gains that break the simulation (overflow, unreachable targets) are merely
                # bad candidates: price them like a run that failed.
                out.append(p.weights.none)
                continue
            out.append(run_cost(result, p.weights))
        return tuple(out)


def _rulebase_surface(problem: TuningProblem) -> Surface:
    """The exact engine's surface of the problem's rule base for the reference controller, its
    inputs in the roles the cases' spec gives them (by position without one)."""
    from fuzzkit.control.loop_rulebase import POSITIONAL_ROLES, exact_surface, load_loop_rulebase
    from fuzzkit.control.spec import surface_inputs

    spec = problem.cases[0].controller_spec if problem.cases else None
    if spec is not None and spec.rulebase is not None:
        rb, roles = spec.rulebase, surface_inputs(spec, spec.rulebase)
    else:
        rb, roles = load_loop_rulebase(str(problem.surface)), POSITIONAL_ROLES
    return exact_surface(rb, roles)


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
