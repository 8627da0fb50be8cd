"""The search: differential evolution then a compass polish over a problem's gain space, under
an evaluation budget, returning the cheapest admissible gain set (details:
:mod:`fuzzkit.studies.tuning`); :func:`tune` builds the problem and runs it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import ConfigError
from fuzzkit.studies.batch import default_workers
from fuzzkit.studies.experiments import DEFAULT_GAINS, Experiment
from fuzzkit.studies.tuning.admission import ADMIT_RULES, Evaluation, admissible, choose, score
from fuzzkit.studies.tuning.cost import CostWeights
from fuzzkit.studies.tuning.pricing import CaseRunner, problem_key, worker_costs
from fuzzkit.studies.tuning.problem import (
    DEFAULT_STIFFNESSES_N_PER_MM,
    PlantSpec,
    SurfaceSpec,
    TuningProblem,
)
from fuzzkit.studies.tuning.result import TuneResult
from fuzzkit.studies.tuning.spaces import GainSpace

Vec = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Progress:
    """Where a search is; handed to the ``callback`` of :func:`optimise` after every batch."""

    stage: str  # "baseline", "global" or "polish"
    evaluations: int
    budget: int
    best_cost: float  # cost of the cheapest *admissible* gain set so far (what would be saved)
    baseline_cost: float
    elapsed_s: float
    #: cost of the cheapest gain set so far, admissible or not (inf before any)
    cheapest_cost: float = math.inf


class _Pricer:
    """Prices batches of log10 points (in a process pool or in-process), remembers every
    result, enforces the budget and reports progress."""

    def __init__(
        self,
        problem: TuningProblem,
        workers: int,
        budget: int,
        callback: Callable[[Progress], None] | None,
        admit: str = "case",
        scheduler: str | None = None,
        constraint: Callable[[Mapping[str, float]], bool] | None = None,
    ) -> None:
        from fuzzkit.studies.batch import BatchExecutor

        self.problem = problem
        self.constraint = constraint
        self.rejected = 0  # gain sets the constraint refused
        self.budget = budget
        self.admit = admit
        self.cheapest: Evaluation | None = None
        self.best_admissible: Evaluation | None = None
        self.callback = callback
        self.records: list[Evaluation] = []
        self.memo: dict[tuple[float, ...], Evaluation] = {}
        self.stage = "baseline"
        self.baseline: Evaluation | None = None
        self.best: Evaluation | None = None
        self.history: list[float] = []
        self.t0 = time.perf_counter()
        self.runner: CaseRunner | None = None
        self.key = problem_key(problem)
        # candidates run on the sweep's executor: local processes or a Dask cluster
        self.executor: BatchExecutor | None = None
        if workers > 1 or scheduler is not None:
            self.executor = BatchExecutor(workers, scheduler)
        else:
            self.runner = CaseRunner(problem)

    @property
    def remaining(self) -> int:
        """Evaluations left in the budget."""
        return self.budget - len(self.records)

    def close(self, abort: bool = False) -> None:
        """Stop the workers (``abort``: without waiting for running tasks)."""
        if self.executor is not None:
            self.executor.close(abort)
            self.executor = None

    def price(
        self, gains_list: Sequence[Mapping[str, float]], constrained: bool = True
    ) -> list[Evaluation]:
        """Price ``gains_list`` (memoised; new points beyond the budget are priced inf).

        With a ``constraint`` (and ``constrained``), a gain set it rejects is not simulated:
        it is priced inf with no case costs, so it is never admissible.
        """
        keyed = [
            tuple(round(math.log10(g[n]), 12) for n in self.problem.space.names) for g in gains_list
        ]
        todo: list[int] = []
        for i, key in enumerate(keyed):
            if key not in self.memo and key not in (keyed[j] for j in todo):
                todo.append(i)
        todo = todo[: max(0, self.remaining)]
        fresh = [dict(gains_list[i]) for i in todo]
        if fresh:
            check = self.constraint if constrained else None
            allowed = [check is None or check(g) for g in fresh]
            run = [g for g, ok in zip(fresh, allowed, strict=True) if ok]
            if not run:
                simulated: list[tuple[float, ...]] = []
            elif self.executor is not None:
                simulated = self.executor.map(
                    worker_costs, [(self.key, self.problem, g) for g in run]
                )
            else:
                if self.runner is None:  # pragma: no cover - set in __init__ without a pool
                    raise RuntimeError("no runner for in-process pricing")
                simulated = [self.runner.case_costs(g) for g in run]
            it = iter(simulated)
            for i, g, ok in zip(todo, fresh, allowed, strict=True):
                if not ok:  # rejected, not simulated: remembered, not counted in the budget
                    self.memo[keyed[i]] = Evaluation(g, (), (), math.inf)
                    self.rejected += 1
                    continue
                costs = next(it)
                ev = Evaluation(
                    g, costs, self.problem.experiment_costs(costs), self.problem.aggregate(costs)
                )
                self.records.append(ev)
                self.memo[keyed[i]] = ev
                if self.best is None or self.score(ev) < self.score(self.best):
                    self.best = ev
                if self.cheapest is None or ev.cost < self.cheapest.cost:
                    self.cheapest = ev
                if self.admissible(ev) and (
                    self.best_admissible is None or ev.cost < self.best_admissible.cost
                ):
                    self.best_admissible = ev
            self.history.append(self.best.cost if self.best else math.inf)
            self._report()
        inf = Evaluation({}, (), (), math.inf)
        return [self.memo.get(k, inf) for k in keyed]

    def admissible(self, ev: Evaluation) -> bool:
        """No worse than the baseline on any case (or experiment, per ``admit``)."""
        return admissible(ev, self.baseline, self.admit)

    def score(self, ev: Evaluation) -> float:
        """What the search minimises (:func:`fuzzkit.studies.tuning.admission.score`)."""
        return score(ev, self.baseline, self.admit)

    def _report(self) -> None:
        if self.callback is None or self.best is None:
            return
        base = self.baseline.cost if self.baseline is not None else self.best.cost
        admissible = self.best_admissible.cost if self.best_admissible is not None else base
        self.callback(
            Progress(
                stage=self.stage,
                evaluations=len(self.records),
                budget=self.budget,
                best_cost=admissible,
                baseline_cost=base,
                elapsed_s=time.perf_counter() - self.t0,
                cheapest_cost=self.cheapest.cost if self.cheapest is not None else math.inf,
            )
        )

    def choose(self) -> Evaluation:
        """The cheapest admissible evaluation (the baseline itself is admissible)."""
        if self.baseline is None:
            raise RuntimeError("no baseline evaluation")
        return choose(self.records, self.baseline, self.admit)


def _plan(budget: int, ndim: int) -> tuple[int, int]:
    """Population size and generations of the global stage for ``budget`` evaluations.

    About 70 % of the budget goes to differential evolution, the rest to the polish.
    """
    pop = max(5, min(5 * ndim, budget // 6))
    generations = max(0, int(0.7 * budget) // pop - 1)
    return pop, generations


def optimise(
    problem: TuningProblem,
    budget: int = 120,
    seed: int = 0,
    workers: int | None = None,
    callback: Callable[[Progress], None] | None = None,
    baseline: Mapping[str, float] | None = None,
    admit: str = "case",
    scheduler: str | None = None,
    constraint: Callable[[Mapping[str, float]], bool] | None = None,
) -> TuneResult:
    """Search ``problem.space`` for the gain set of least cost (see the module docstring).

    Parameters
    ----------
    problem : from :meth:`TuningProblem.build`.
    budget : most gain sets simulated (each on every case), the baseline included; >= 10.
    seed : seeds the optimiser (the sensor noise has ``problem.noise_seed``).
    workers : worker processes (None: every core this process may use; 1: in-process).
    callback : called with a :class:`Progress` after every batch; it may raise
        ``KeyboardInterrupt`` (as Ctrl-C does) to stop the search.
    baseline : the reference gains (default: ``fuzzkit.studies.experiments.DEFAULT_GAINS``).
    admit : ``case`` (no worse than the baseline on every experiment x stiffness case) or
        ``experiment`` (no worse on each experiment's mean over the stiffnesses).
    scheduler : a ``dask.distributed`` scheduler address: price the candidates on its workers.
    constraint : when given, only gain sets it accepts are simulated and may be returned
        (``fuzzkit tune --certify``: certified stable); the baseline is priced regardless and
        is returned when no accepted candidate beats it (the caller checks it).

    Returns
    -------
    The cheapest admissible gain set; ``interrupted`` is True when Ctrl-C
    (KeyboardInterrupt) stopped the search early.

    Raises
    ------
    ConfigError
        ``budget`` below 10, ``workers`` below 1 or an unknown ``admit`` rule.
    """
    from scipy.optimize import differential_evolution
    from scipy.stats import qmc

    if budget < 10:
        raise ConfigError(f"budget must be >= 10 evaluations (got {budget})")
    if admit not in ADMIT_RULES:
        raise ConfigError(f"unknown admission rule {admit!r} (expected case or experiment)")
    nworkers = default_workers() if workers is None else workers
    if nworkers < 1:
        raise ConfigError(f"workers must be >= 1 (got {nworkers})")
    space = problem.space
    base_gains = dict(baseline or DEFAULT_GAINS[problem.controller])
    missing = [n for n in space.names if n not in base_gains]
    if missing:
        raise ConfigError(f"baseline gains lack {', '.join(missing)}")
    lo, hi = space.log_bounds
    ndim = len(space.names)
    baseline_gains = {n: base_gains[n] for n in space.names}
    # said before the search, from the loop itself (a refusal shows here, not in a worker)
    implementation = CaseRunner(problem).implementation(baseline_gains)
    pricer = _Pricer(problem, nworkers, budget, callback, admit, scheduler, constraint)
    interrupted = False
    try:
        pricer.baseline = pricer.price([baseline_gains], constrained=False)[0]
        pricer.stage = "global"
        pop, generations = _plan(budget, ndim)
        rng = np.random.default_rng(seed)
        sample = qmc.LatinHypercube(d=ndim, rng=rng).random(pop)
        init = lo + sample * (hi - lo)
        init[0] = space.to_x(base_gains)  # the search starts from the defaults too

        def batch(x: Vec) -> Vec:
            pts = np.atleast_2d(x.T) if x.ndim == 2 else x[None, :]
            evs = pricer.price([space.to_gains(p) for p in pts])
            return np.array([pricer.score(ev) for ev in evs])

        if generations >= 0:
            differential_evolution(
                batch,
                bounds=list(zip(lo, hi, strict=True)),
                init=init,
                maxiter=generations,
                popsize=pop,
                tol=0.0,
                atol=0.0,
                polish=False,
                updating="deferred",
                vectorized=True,
                rng=rng,
            )
        pricer.stage = "polish"
        _compass(pricer, space)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        pricer.close(abort=interrupted)
    if pricer.baseline is None:  # interrupted before the first evaluation finished
        raise KeyboardInterrupt
    chosen = pricer.choose()
    base = pricer.baseline
    cheapest = pricer.cheapest or base
    names = problem.experiments
    return TuneResult(
        controller=problem.controller,
        gains=problem.full_gains(chosen.gains),
        cost=chosen.cost,
        experiment_costs=dict(zip(names, chosen.experiment_costs, strict=True)),
        case_costs=dict(zip(problem.labels, chosen.case_costs, strict=True)),
        baseline_gains=problem.full_gains(base_gains),
        baseline_cost=base.cost,
        baseline_experiment_costs=dict(zip(names, base.experiment_costs, strict=True)),
        evaluations=len(pricer.records),
        budget=budget,
        seed=seed,
        interrupted=interrupted,
        wall_time_s=time.perf_counter() - pricer.t0,
        experiments=names,
        stiffnesses_n_per_mm=problem.stiffnesses_n_per_mm,
        plant=problem.plant_name,
        rulebase=problem.rulebase_name,
        history=tuple(pricer.history),
        baseline_case_costs=dict(zip(problem.labels, base.case_costs, strict=True)),
        admit=admit,
        cheapest_gains=problem.full_gains(cheapest.gains),
        cheapest_cost=cheapest.cost,
        cheapest_case_costs=dict(zip(problem.labels, cheapest.case_costs, strict=True)),
        problem=problem,
        controller_impl=implementation,
    )


def _compass(pricer: _Pricer, space: GainSpace) -> None:
    """Bounded compass search from the best point so far, until the budget is spent.

    Each iteration prices the ``2 * dims`` points one step away along each axis (in parallel);
    it moves to the best if that is cheaper, else halves the step. Derivative-free, because the
    cost of a simulated run is only piecewise smooth in the gains.
    """
    lo, hi = space.log_bounds
    if pricer.best is None:
        return
    x = space.to_x(pricer.best.gains)
    fx = pricer.score(pricer.best)
    step = 0.05 * (hi - lo)
    min_step = 0.002  # decades: 0.5 % of a gain, finer than any simulation can tell apart
    while pricer.remaining > 0 and float(np.max(step)) > min_step:
        trials: list[Vec] = []
        for i in range(len(x)):
            for sign in (1.0, -1.0):
                y = x.copy()
                y[i] = min(max(y[i] + sign * step[i], lo[i]), hi[i])
                if y[i] != x[i]:
                    trials.append(y)
        if not trials:
            break
        evs = pricer.price([space.to_gains(y) for y in trials])
        scores = [pricer.score(ev) for ev in evs]
        j = int(np.argmin(scores))
        if scores[j] < fx:
            x, fx = trials[j], scores[j]
        else:
            step = step * 0.5


def tune(
    experiments: Sequence[str | Experiment] = ("E1",),
    controller: str = "pi",
    rulebase: SurfaceSpec = "macvicar_whelan",
    plant: PlantSpec = "planar",
    stiffnesses_n_per_mm: Sequence[float] | None = DEFAULT_STIFFNESSES_N_PER_MM,
    budget: int = 120,
    seed: int = 0,
    workers: int | None = None,
    *,
    callback: Callable[[Progress], None] | None = None,
    space: GainSpace | None = None,
    weights: CostWeights = CostWeights(),
    horizon_s: float | None = None,
    baseline: Mapping[str, float] | None = None,
    noise_seed: int = 0,
    admit: str = "case",
    latencies: Sequence[tuple[int, int]] | None = None,
    loop: str = "auto",
    scheduler: str | None = None,
    controller_impl: str = "auto",
    constraint: Callable[[Mapping[str, float]], bool] | None = None,
) -> TuneResult:
    """Find the gains of least cost for ``controller`` over experiments and stiffnesses.

    Parameters
    ----------
    experiments : names (E1, E2, E3) or ``Experiment`` objects, tuned for together.
    controller : ``pi`` (tunes kp, ki) or ``fuzzy-pi`` (tunes kp, ki, kx).
    rulebase : fuzzy-PI rule base (shipped name or YAML path) or a picklable surface function.
    plant : plant name (``fuzzkit.plants.contract.PLANTS``) or a picklable factory returning a
    plant. stiffnesses_n_per_mm : environment stiffnesses to tune over at once (None: each
        experiment's own).
    budget : most gain sets simulated, the default gains included (>= 10).
    seed : optimiser seed; the same seed gives the same gains.
    workers : worker processes (None: all cores; 1: in this process).
    callback : progress callback (see :func:`optimise`).
    space : the searched gains and bounds (default :data:`SPACES` for the controller).
    weights : cost weights (:class:`CostWeights`).
    horizon_s : simulated time per run (default :data:`TUNING_HORIZON_S`).
    baseline : reference gains (default ``DEFAULT_GAINS``).
    noise_seed : sensor-noise seed of every run.
    admit : admission rule, ``case`` (default) or ``experiment`` (see :func:`optimise`).
    latencies : ``(sensor, command)`` delays (periods) to tune over at once (default: each
        experiment's own).
    loop : ``auto`` (compiled where the plant has a compiled loop), ``compiled`` or ``python``.
    scheduler : a ``dask.distributed`` scheduler address to price the candidates on.
    controller_impl : ``auto`` (the generated C controller in the compiled loop where the
        plant has one), ``c`` (that, or an error) or ``python`` (the reference controller in
        the Python loop).
    constraint : only gain sets it accepts are searched (see :func:`optimise`).

    Returns
    -------
    A :class:`TuneResult`; write it with ``fuzzkit.control.gains.write_gains(path,
    result.to_entry())``.

    Raises
    ------
    ConfigError
        Bad arguments (see :meth:`TuningProblem.build` and :func:`optimise`).

    Examples
    --------
    >>> r = tune(["E1"], "pi", budget=20, workers=1)  # doctest: +SKIP
    >>> r.cost <= r.baseline_cost  # doctest: +SKIP
    True
    """
    problem = TuningProblem.build(
        experiments,
        controller,
        rulebase,
        plant,
        stiffnesses_n_per_mm,
        space=space,
        weights=weights,
        horizon_s=horizon_s,
        noise_seed=noise_seed,
        latencies=latencies,
        loop=loop,
        controller_impl=controller_impl,
    )
    return optimise(
        problem, budget, seed, workers, callback, baseline, admit, scheduler, constraint
    )


def progress_callback(bar: Any) -> Callable[[Progress], None]:
    """A ``callback`` for :func:`optimise` that moves a tqdm bar (``fuzzkit.progress``) to
    each :class:`Progress`: evaluations out of the budget, ETA, stage and best cost so far."""

    def show(p: Progress) -> None:
        bar.total = p.budget
        bar.update(p.evaluations - bar.n)
        text = f"{p.stage}, best admissible {p.best_cost:.4g} (default {p.baseline_cost:.4g}"
        if p.cheapest_cost < p.best_cost - 1e-12:
            text += f"; cheapest {p.cheapest_cost:.4g} is worse than the default somewhere"
        bar.set_postfix_str(text + ")", refresh=True)

    return show
