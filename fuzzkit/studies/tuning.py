"""Optimal gains: PI ``Kp, Ki`` and fuzzy-PI scaling factors ``Kp, Ki, Kx`` by simulation.

The paper set its scaling factors "by trial and error" (sec. 3.2.4). Here they minimise a
documented closed-loop cost over one or more experiments and several environment stiffnesses at
once (a robust optimum, not one tuned to a single surface).

Cost (:func:`run_cost`, dimensionless, lower is better), per run from the first contact on::

    J = ITAE + w_os * overshoot + w_peak * excess_peak + w_trip * tripped + w_loss * loss

* ``ITAE = sum_axes  integral (t - t0) |f_d - f| dt / (F * T^2 / 2)``: the time-weighted mean of
  the true force error over the controlled axes, relative to ``F`` = the experiment's largest
  set point (at least 1 N); ``T`` is the time from first contact to the end of the horizon.
  Weighting by time forgives the unavoidable impact transient and punishes slow settling and a
  steady error.
* ``overshoot``: largest excursion past each non-zero set point, as a fraction of it (summed).
* ``excess_peak``: how far the largest force exceeds the experiment's safety limit, as a
  fraction of the limit; ``tripped`` is 1 when the safety limit tripped the controller.
* ``loss``: fraction of the time after first contact spent without contact.
* A run that never touches anything, or produces non-finite numbers, costs ``w_none`` (10).

The cost of a gain set is the mean over every (experiment, stiffness) case, i.e. the mean over
experiments of each experiment's mean over the stiffnesses.

Search (:func:`optimise`): gains are searched as ``log10`` values within bounds
(:data:`SPACES`), because good gains span decades across stiffnesses. Stage 1 is
``scipy.optimize.differential_evolution`` (seeded Latin-hypercube population holding the default
gains, ``updating="deferred"``, ``vectorized`` so each generation is one batch that a process
pool evaluates in parallel); stage 2 is a bounded compass (pattern) search around the best
point, whose ``2 * dims`` trial points per iteration also run in parallel. Both stages minimise
the cost plus ``PENALTY`` times how much worse than the default gains a candidate is on each
experiment, which steers the search towards candidates the final choice may return.
``budget`` caps the number of gain sets simulated, the default gains included. The result is
the cheapest *admissible* gain set found: by default (``admit="case"``) one that is no worse
than the default gains on *every case*, i.e. every (experiment, stiffness) pair it was tuned
for, so robust gains never trade the nominal stiffness away for a stiffer one; with
``admit="experiment"`` one no worse on each experiment's mean over the stiffnesses (a
compromise: it may be worse at some stiffness, and the CLI says by how much). The defaults
themselves are admissible, so this never fails; when nothing beats them, they are returned
and :attr:`TuneResult.kept_defaults` says so, with the cheapest candidate that was refused.

Speed: experiments are simulated over short horizons (:data:`TUNING_HORIZON_S`: first contact
plus the transient that the gains decide), and the fuzzy surface is a 201 x 201 bilinear lookup
table sampled once from the exact engine (``fuzzkit.control.controllers.engine_table_surface``).

Determinism: the same arguments and ``seed`` give the same gains for any number of workers (the
simulations are deterministic, the pool preserves order, the optimiser is seeded).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.control.controllers import Surface, engine_table_surface, tabulated_surface
from fuzzkit.errors import ConfigError
from fuzzkit.plants.arm6 import Arm6Plant
from fuzzkit.plants.contract import ContactPlant
from fuzzkit.studies.batch import default_workers
from fuzzkit.studies.e3_arm6 import make_e3_arm6_plant, resolve
from fuzzkit.studies.experiments import DEFAULT_GAINS, Experiment, experiment, with_stiffness
from fuzzkit.studies.plants import make_plant
from fuzzkit.studies.runner import RunResult, run

Vec = npt.NDArray[np.float64]

#: Environment stiffnesses (N/mm) tuned over by default: half and twice the experiments' own
#: 10 N/mm, so the optimum tolerates a softer or stiffer part than the one programmed for.
DEFAULT_STIFFNESSES_N_PER_MM: tuple[float, ...] = (5.0, 10.0, 20.0)

#: Simulated time per experiment while tuning (s). First contact is at about 1.9 s (E1) and
#: 1.0 s (E2, E3); each horizon keeps the contact transient and 1-4 s of holding or sliding,
#: where the gains make the difference, and drops the rest of the path.
TUNING_HORIZON_S: dict[str, float] = {"E1": 3.5, "E2": 4.5, "E3": 6.0, "press": 1.5}

#: Weight of the search's penalty for being worse than the default gains on a case
#: (or an experiment, with ``admit="experiment"``).
PENALTY = 10.0

#: Admission rules: no worse than the defaults on every case, or on every experiment's mean.
ADMIT_RULES = ("case", "experiment")

#: Samples per side of the lookup table standing in for the exact fuzzy engine while tuning.
TABLE_SIZE = 201


@dataclass(frozen=True, slots=True)
class GainSpace:
    """The searched gains and their bounds (gain units, both > 0; searched as log10)."""

    names: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]

    def __post_init__(self) -> None:
        if not (len(self.names) == len(self.lower) == len(self.upper)) or not self.names:
            raise ConfigError("GainSpace: names, lower and upper must have the same length > 0")
        for n, lo, hi in zip(self.names, self.lower, self.upper, strict=True):
            if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
                raise ConfigError(f"GainSpace: bounds of {n} must satisfy 0 < lower < upper")

    @property
    def log_bounds(self) -> tuple[Vec, Vec]:
        """Lower and upper bounds of the searched log10 values."""
        return np.log10(np.asarray(self.lower)), np.log10(np.asarray(self.upper))

    def to_gains(self, x: Sequence[float] | Vec) -> dict[str, float]:
        """The gains at the log10 point ``x``."""
        return {n: float(10.0 ** float(v)) for n, v in zip(self.names, x, strict=True)}

    def to_x(self, gains: Mapping[str, float]) -> Vec:
        """The log10 point of ``gains`` (clipped into the bounds)."""
        lo, hi = self.log_bounds
        x = np.array([math.log10(gains[n]) for n in self.names])
        return np.asarray(np.clip(x, lo, hi), dtype=np.float64)


#: Search spaces per controller. PI gains in m/N: loop gain ``Ki*k`` per period must stay
#: below about 1, so ``ki`` reaches down to 1e-8 m/N for stiff (1000 N/mm) environments. Fuzzy
#: ``ki``, ``kp``: 1/N (full scale of e from 1 N to 1000 N); ``kx``: metres per step.
SPACES: dict[str, GainSpace] = {
    "pi": GainSpace(("kp", "ki"), (1.0e-7, 1.0e-8), (1.0e-3, 1.0e-3)),
    "fuzzy-pi": GainSpace(("kp", "ki", "kx"), (1.0e-3, 1.0e-3, 1.0e-6), (10.0, 1.0, 1.0e-2)),
}


@dataclass(frozen=True, slots=True)
class CostWeights:
    """Weights of the penalty terms of :func:`run_cost` (the ITAE term has weight 1)."""

    overshoot: float = 0.5
    peak: float = 2.0
    trip: float = 1.0
    contact_loss: float = 2.0
    none: float = 10.0


def run_cost(result: RunResult, weights: CostWeights = CostWeights()) -> float:
    """The tuning cost of one closed-loop run (module docstring: formula and reasons).

    Parameters
    ----------
    result : a run from ``fuzzkit.studies.experiments.run``.
    weights : penalty weights.

    Returns
    -------
    The cost (>= 0); ``weights.none`` for a run without contact or with non-finite forces.
    """
    exp = result.experiment
    contact = np.nonzero(result.in_contact)[0]
    if len(contact) == 0 or not np.all(np.isfinite(result.force_true)):
        return weights.none
    i0 = int(contact[0])
    t = result.t[i0:]
    span = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    if span <= 0.0:
        return weights.none
    axes = [i for i in range(3) if exp.selection[i]]
    scale = max([abs(float(exp.setpoints[i])) for i in axes] + [1.0])
    dt = float(exp.scenario.period_s)
    tau = t - t[0]
    itae = overshoot = 0.0
    for i in axes:
        sp = float(exp.setpoints[i])
        f = result.force_true[i0:, i]
        itae += float(np.sum(tau * np.abs(sp - f))) * dt / (scale * 0.5 * span * span)
        if sp != 0.0:
            overshoot += max(0.0, float(np.max((f - sp) * math.copysign(1.0, sp)))) / abs(sp)
    peak = float(np.max(np.abs(result.force_true[i0:])))
    excess = max(0.0, peak - exp.force_limit_n) / exp.force_limit_n
    loss = float(np.count_nonzero(~result.in_contact[i0:])) / len(t)
    cost = (
        itae
        + weights.overshoot * overshoot
        + weights.peak * excess
        + weights.trip * float(result.tripped)
        + weights.contact_loss * loss
    )
    return cost if math.isfinite(cost) else weights.none


# --------------------------------------------------------------------------------------------
# The problem: what one gain set costs
# --------------------------------------------------------------------------------------------

PlantSpec = str | Callable[[], ContactPlant]
SurfaceSpec = str | Surface


@dataclass(frozen=True, slots=True)
class TuningCase:
    """One case a gain set is priced on: an experiment at a stiffness and a latency.

    ``label`` is the key of :attr:`TuneResult.case_costs` (``E1@10N/mm``, with ``@lat1:1``
    appended when several latencies are tuned over); ``latency`` is None for the experiment's
    own.
    """

    label: str
    experiment: str
    stiffness_n_per_mm: float
    latency: tuple[int, int] | None


@dataclass(frozen=True)
class TuningProblem:
    """Everything needed to price a gain set; picklable, so worker processes get a copy.

    Build it with :meth:`build`. ``cases`` are (experiment, stiffness) pairs; ``groups[i]`` is
    the index in ``experiments`` of case i's experiment.
    """

    controller: str
    experiments: tuple[str, ...]
    cases: tuple[Experiment, ...]
    labels: tuple[str, ...]
    groups: tuple[int, ...]
    horizons: tuple[float, ...]
    plant: PlantSpec
    surface: SurfaceSpec | None
    space: GainSpace
    fixed: dict[str, float]
    weights: CostWeights
    noise_seed: int
    stiffnesses_n_per_mm: tuple[float, ...] | None
    #: ``(sensor, command)`` delay of each case, in periods (parallel to ``cases``; None: the
    #: experiment's own)
    case_latencies: tuple[tuple[int, int] | None, ...] = ()
    latencies: tuple[tuple[int, int], ...] | None = None
    #: ``auto`` (the compiled loop where the plant has one), ``compiled`` or ``python``
    loop: str = "auto"
    #: what each case is (parallel to ``cases``)
    case_keys: tuple[TuningCase, ...] = ()
    #: cases that run the paper's 3-D E3 on its own arm6 world (:mod:`fuzzkit.studies.e3_arm6`)
    paper_e3_cases: tuple[bool, ...] = ()

    def latency_of(self, case: int) -> tuple[int, int] | None:
        """The latency of case ``case`` (None: its experiment's own)."""
        return self.case_latencies[case] if self.case_latencies else None

    @classmethod
    def build(
        cls,
        experiments: Sequence[str | Experiment],
        controller: str = "pi",
        rulebase: SurfaceSpec = "macvicar_whelan",
        plant: PlantSpec = "planar",
        stiffnesses_n_per_mm: Sequence[float] | None = DEFAULT_STIFFNESSES_N_PER_MM,
        *,
        space: GainSpace | None = None,
        weights: CostWeights = CostWeights(),
        horizon_s: float | None = None,
        noise_seed: int = 0,
        latencies: Sequence[tuple[int, int]] | None = None,
        loop: str = "auto",
    ) -> TuningProblem:
        """Check the arguments and assemble the problem (arguments as for :func:`tune`).

        Raises
        ------
        ConfigError
            Unknown controller, experiment, plant or rule base; no experiments; a stiffness or
            horizon that is not a positive finite number.
        """
        if controller not in SPACES:
            raise ConfigError(f"unknown controller {controller!r} (expected pi or fuzzy-pi)")
        if not experiments:
            raise ConfigError("tuning needs at least one experiment")
        # A name resolves as ``simulate`` resolves it: E3 on arm6 is the paper's 3-D E3.
        paper_e3 = [
            isinstance(e, str) and plant == "arm6" and e.upper() == "E3" for e in experiments
        ]
        exps = [
            (resolve(e, str(plant))[0] if paper else experiment(e)) if isinstance(e, str) else e
            for e, paper in zip(experiments, paper_e3, strict=True)
        ]
        names = tuple(e.name for e in exps)
        if len(set(names)) != len(names):
            raise ConfigError(f"experiments listed twice: {', '.join(names)}")
        if stiffnesses_n_per_mm is not None:
            ks = tuple(float(k) for k in stiffnesses_n_per_mm)
            if not ks or not all(math.isfinite(k) and k > 0.0 for k in ks):
                raise ConfigError(
                    f"stiffnesses must be positive finite numbers in N/mm (got {list(ks)})"
                )
        else:
            ks = None
        if horizon_s is not None and not (math.isfinite(horizon_s) and horizon_s > 0.0):
            raise ConfigError(f"horizon must be > 0 s (got {horizon_s})")
        if isinstance(plant, str):
            make_plant(plant)  # an unknown name fails here, not in a worker
        surface: SurfaceSpec | None = None
        if controller == "fuzzy-pi":
            if isinstance(rulebase, str):
                from fuzzkit.formats.registry import load

                load(rulebase)  # a bad rule base fails here, with its own message
            surface = rulebase
        cases: list[Experiment] = []
        labels: list[str] = []
        groups: list[int] = []
        horizons: list[float] = []
        stiffness_of: list[float] = []
        for gi, exp in enumerate(exps):
            h = horizon_s or TUNING_HORIZON_S.get(exp.name, exp.scenario.duration_s)
            h = min(h, exp.scenario.duration_s)
            for k in ks if ks is not None else (None,):
                if k is None:
                    cases.append(exp)
                    k_mm = exp.scenario.contact.stiffness_n_per_m / 1e3
                else:
                    cases.append(with_stiffness(exp, k * 1e3))
                    k_mm = k
                labels.append(f"{exp.name}@{k_mm:g}N/mm")
                stiffness_of.append(k_mm)
                groups.append(gi)
                horizons.append(h)
        lats = None if latencies is None else tuple((int(a), int(b)) for a, b in latencies)
        if lats is not None and (not lats or any(min(pair) < 0 for pair in lats)):
            raise ConfigError(f"latencies must be (sensor, command) pairs >= 0 (got {lats})")
        if loop not in ("auto", "compiled", "python"):
            raise ConfigError(f"unknown loop {loop!r} (expected auto, compiled or python)")
        case_lats: tuple[tuple[int, int] | None, ...]
        if lats is not None:
            n_cases = len(cases)
            cases = [c for c in cases for _ in lats]
            labels = (
                [f"{lab}@lat{a}:{b}" for lab in labels for a, b in lats]
                if len(lats) > 1
                else labels
            )
            groups = [g for g in groups for _ in lats]
            horizons = [h for h in horizons for _ in lats]
            stiffness_of = [k for k in stiffness_of for _ in lats]
            case_lats = tuple(pair for _ in range(n_cases) for pair in lats)
        else:
            case_lats = tuple(None for _ in cases)  # each experiment's own latency
        paper_cases = tuple(paper_e3[g] for g in groups)
        keys = tuple(
            TuningCase(lab, names[g], k, lat)
            for lab, g, k, lat in zip(labels, groups, stiffness_of, case_lats, strict=True)
        )
        sp = space or SPACES[controller]
        fixed = {k: v for k, v in DEFAULT_GAINS[controller].items() if k not in sp.names}
        return cls(
            controller=controller,
            experiments=names,
            cases=tuple(cases),
            labels=tuple(labels),
            groups=tuple(groups),
            horizons=tuple(horizons),
            plant=plant,
            surface=surface,
            space=sp,
            fixed=fixed,
            weights=weights,
            noise_seed=noise_seed,
            stiffnesses_n_per_mm=ks,
            case_latencies=case_lats,
            latencies=lats,
            loop=loop,
            case_keys=keys,
            paper_e3_cases=paper_cases,
        )

    def plant_of(self, case: int) -> Arm6Plant | None:
        """A fresh plant for case ``case`` when it needs its own world (the paper's E3 on
        arm6), else None: the problem's ``plant``."""
        if self.paper_e3_cases and self.paper_e3_cases[case]:
            return make_e3_arm6_plant()
        return None

    def full_gains(self, gains: Mapping[str, float]) -> dict[str, float]:
        """``gains`` completed with the fixed entries (output limits) of the defaults."""
        out = dict(self.fixed)
        out.update(gains)
        return out

    def experiment_costs(self, case_costs: Sequence[float]) -> tuple[float, ...]:
        """Per-experiment costs: the mean over each experiment's stiffness cases."""
        sums = [0.0] * len(self.experiments)
        counts = [0] * len(self.experiments)
        for g, c in zip(self.groups, case_costs, strict=True):
            sums[g] += c
            counts[g] += 1
        return tuple(s / n for s, n in zip(sums, counts, strict=True))

    def aggregate(self, case_costs: Sequence[float]) -> float:
        """The cost of a gain set: mean of the per-experiment costs."""
        per = self.experiment_costs(case_costs)
        return float(sum(per) / len(per))

    @property
    def plant_name(self) -> str:
        """A name for the plant, for messages and provenance."""
        if isinstance(self.plant, str):
            return self.plant
        return str(getattr(self.plant, "__name__", type(self.plant).__name__))

    @property
    def rulebase_name(self) -> str | None:
        """The rule base name or path (None for PI or a surface given as a function)."""
        return self.surface if isinstance(self.surface, str) else None


class CaseRunner:
    """Prices gain sets for one problem in this process (the surface table is built once).

    Runs the compiled loop (:mod:`fuzzkit.studies.compiled`) where the plant has one, with the
    rule base's double lookup table as the fuzzy surface; the Python loop otherwise, with a
    201 x 201 bilinear table.
    """

    def __init__(self, problem: TuningProblem) -> None:
        from fuzzkit.studies.compiled.loop import compiled_supports, compiled_table

        self.problem = problem
        self.surface: Surface | None = None
        self.table: Any = None
        self.compiled = (
            problem.loop != "python"
            and isinstance(problem.plant, str)
            and compiled_supports(problem.plant)
            and (problem.surface is None or isinstance(problem.surface, str))
        )
        if problem.loop == "compiled" and not self.compiled:
            raise ConfigError(
                f"the compiled loop does not run plant {problem.plant_name} "
                "(or a surface given as a function); use loop='python'"
            )
        if self.compiled:
            if isinstance(problem.surface, str):
                self.table = compiled_table(problem.surface)
        elif isinstance(problem.surface, str):
            from fuzzkit.formats.registry import load
            from fuzzkit.fuzzy.inference import Engine

            self.surface = engine_table_surface(Engine(load(problem.surface)), n=TABLE_SIZE)
        elif problem.surface is not None:
            self.surface = tabulated_surface(problem.surface, n=TABLE_SIZE)

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
                p.controller,
                gains=full,
                table=self.table,
                seed=p.noise_seed,
                duration_s=duration_s,
                latency=p.latency_of(case),
            )
        plant = own or (make_plant(p.plant) if isinstance(p.plant, str) else p.plant())
        return run(
            exp,
            plant,
            p.controller,
            gains=full,
            surface=self.surface,
            seed=p.noise_seed,
            duration_s=duration_s,
            latency=p.latency_of(case),
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


def evaluate_gains(problem: TuningProblem, gains: Mapping[str, float]) -> tuple[float, ...]:
    """The cost of ``gains`` on every case of ``problem``, computed in this process.

    The independent way to price a gain set (tests, benchmarks, the report); :func:`optimise`
    prices candidates the same way in worker processes.
    """
    return CaseRunner(problem).case_costs(gains)


# Worker-side state: one runner per problem and process, built on the first task that needs it.
_RUNNERS: dict[str, CaseRunner] = {}


def _problem_key(problem: TuningProblem) -> str:
    import hashlib
    import pickle

    return hashlib.sha256(pickle.dumps(problem)).hexdigest()


def _worker_costs(task: tuple[str, TuningProblem, dict[str, float]]) -> tuple[float, ...]:
    """Price one gain set in a worker (local process or Dask worker)."""
    key, problem, gains = task
    runner = _RUNNERS.get(key)
    if runner is None:
        _RUNNERS.clear()  # one problem at a time: keep the memory of one table
        runner = _RUNNERS[key] = CaseRunner(problem)
    return runner.case_costs(gains)


# --------------------------------------------------------------------------------------------
# The search
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Evaluation:
    """One priced gain set: the searched gains, per-case costs, per-experiment costs, cost."""

    gains: dict[str, float]
    case_costs: tuple[float, ...]
    experiment_costs: tuple[float, ...]
    cost: float


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


@dataclass(frozen=True, slots=True)
class TuneResult:
    """The outcome of a search.

    ``gains`` are complete (searched gains plus the fixed output limits) and ready for
    ``fuzzkit.studies.experiments.run``; ``baseline_*`` describe the default gains on the same cost.
    ``interrupted``: the search stopped early (Ctrl-C); the result is the best so far.
    """

    controller: str
    gains: dict[str, float]
    cost: float
    experiment_costs: dict[str, float]
    case_costs: dict[str, float]
    baseline_gains: dict[str, float]
    baseline_cost: float
    baseline_experiment_costs: dict[str, float]
    evaluations: int
    budget: int
    seed: int
    interrupted: bool
    wall_time_s: float
    experiments: tuple[str, ...]
    stiffnesses_n_per_mm: tuple[float, ...] | None
    plant: str
    rulebase: str | None
    history: tuple[float, ...] = field(default=())
    #: per-case costs of the default gains
    baseline_case_costs: dict[str, float] = field(default_factory=dict)
    #: the admission rule used (:data:`ADMIT_RULES`)
    admit: str = "case"
    #: the cheapest gain set found, admissible or not, and its per-case costs: when it was
    #: refused, it says why the result is not cheaper
    cheapest_gains: dict[str, float] = field(default_factory=dict)
    cheapest_cost: float = math.inf
    cheapest_case_costs: dict[str, float] = field(default_factory=dict)
    #: the problem solved (its cases: :attr:`TuningProblem.case_keys`); None when unknown
    problem: TuningProblem | None = None

    @property
    def latencies(self) -> tuple[tuple[int, int], ...] | None:
        """The ``(sensor, command)`` latencies tuned over (None: each experiment's own)."""
        return None if self.problem is None else self.problem.latencies

    @property
    def kept_defaults(self) -> bool:
        """True when no candidate was admissible and cheaper: the result is the defaults."""
        return self.gains == self.baseline_gains

    def refusals(self) -> list[tuple[str, float, float]]:
        """Why the cheapest candidate was refused: ``(case, its cost, the defaults' cost)`` for
        every case (or experiment, with ``admit="experiment"``) on which it is worse than the
        defaults; empty when it was admissible."""
        if not self.cheapest_case_costs or self.cheapest_cost >= self.cost - 1e-12:
            return []
        if self.admit == "case":
            pairs = [
                (k, c, self.baseline_case_costs[k]) for k, c in self.cheapest_case_costs.items()
            ]
        else:
            per = _means_by_experiment(self.cheapest_case_costs)
            pairs = [(k, c, self.baseline_experiment_costs[k]) for k, c in per.items()]
        return [(k, c, b) for k, c, b in pairs if c > b + 1e-12]

    @property
    def improvement_pct(self) -> float:
        """How much cheaper than the defaults, in % of the defaults' cost."""
        if self.baseline_cost <= 0.0:
            return 0.0
        return 100.0 * (self.baseline_cost - self.cost) / self.baseline_cost

    def to_entry(self) -> Any:
        """The result as a gains-file entry (``fuzzkit.control.gains.GainsEntry``) with
        provenance."""
        from fuzzkit import __version__
        from fuzzkit.control.gains import GainsEntry

        prov: dict[str, Any] = {
            "tool": f"fuzzkit {__version__} tune",
            "experiments": list(self.experiments),
            "plant": self.plant,
            "stiffness_n_per_mm": (
                list(self.stiffnesses_n_per_mm) if self.stiffnesses_n_per_mm else "as defined"
            ),
            "latency_periods": (
                [list(pair) for pair in self.latencies] if self.latencies else "as defined"
            ),
            "rulebase": self.rulebase,
            "cost": round(self.cost, 6),
            "default_cost": round(self.baseline_cost, 6),
            "experiment_costs": {k: round(v, 6) for k, v in self.experiment_costs.items()},
            "seed": self.seed,
            "budget": self.budget,
            "evaluations": self.evaluations,
            "admit": self.admit,
            "kept_defaults": self.kept_defaults,
            "interrupted": self.interrupted,
            "cost_definition": (
                "fuzzkit.studies.tuning.run_cost (ITAE + overshoot, peak, trip, loss)"
            ),
        }
        if self.rulebase is None:
            del prov["rulebase"]
        return GainsEntry(self.controller, dict(self.gains), prov)


def _means_by_experiment(case_costs: Mapping[str, float]) -> dict[str, float]:
    """Per-experiment means of costs keyed by case label (``E1@10N/mm``)."""
    groups: dict[str, list[float]] = {}
    for label, c in case_costs.items():
        groups.setdefault(label.split("@", 1)[0], []).append(c)
    return {k: sum(v) / len(v) for k, v in groups.items()}


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
    ) -> None:
        from fuzzkit.studies.batch import BatchExecutor

        self.problem = problem
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
        self.key = _problem_key(problem)
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

    def price(self, gains_list: Sequence[Mapping[str, float]]) -> list[Evaluation]:
        """Price ``gains_list`` (memoised; new points beyond the budget are priced inf)."""
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
            if self.executor is not None:
                results = self.executor.map(
                    _worker_costs, [(self.key, self.problem, g) for g in fresh]
                )
            else:
                if self.runner is None:  # pragma: no cover - set in __init__ without a pool
                    raise RuntimeError("no runner for in-process pricing")
                results = [self.runner.case_costs(g) for g in fresh]
            for i, g, costs in zip(todo, fresh, results, strict=True):
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

    def _pairs(self, ev: Evaluation) -> list[tuple[float, float]]:
        """(candidate, baseline) costs on each unit the admission rule compares."""
        if self.baseline is None:
            return []
        if self.admit == "case":
            return list(zip(ev.case_costs, self.baseline.case_costs, strict=True))
        return list(zip(ev.experiment_costs, self.baseline.experiment_costs, strict=True))

    def admissible(self, ev: Evaluation) -> bool:
        """No worse than the baseline on any case (or experiment, per ``admit``)."""
        return bool(ev.case_costs) and all(c <= b + 1e-12 for c, b in self._pairs(ev))

    def score(self, ev: Evaluation) -> float:
        """What the search minimises: the cost plus a penalty for each case (or experiment) on
        which ``ev`` is worse than the baseline, which steers the search towards gain sets
        that :meth:`choose` may return."""
        if self.baseline is None or not ev.experiment_costs:
            return ev.cost
        worse = sum(max(0.0, c - b) for c, b in self._pairs(ev))
        return ev.cost + PENALTY * worse

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
        ok = [ev for ev in self.records if self.admissible(ev)]
        return min(ok or [self.baseline], key=lambda ev: ev.cost)


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
    pricer = _Pricer(problem, nworkers, budget, callback, admit, scheduler)
    interrupted = False
    try:
        pricer.baseline = pricer.price([{n: base_gains[n] for n in space.names}])[0]
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
    )
    return optimise(problem, budget, seed, workers, callback, baseline, admit, scheduler)


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
