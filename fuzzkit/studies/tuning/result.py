"""The outcome of a search (:class:`TuneResult`) and its gains-file entry with provenance."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from fuzzkit.studies.tuning.admission import means_by_experiment
from fuzzkit.studies.tuning.problem import TuningProblem


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
    #: what ran the candidates, as the runs name it (``controller_impl [loop]``,
    #: :meth:`~fuzzkit.studies.tuning.pricing.CaseRunner.implementation`); empty when unknown
    controller_impl: str = ""

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
            per = means_by_experiment(self.cheapest_case_costs)
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
            "controller_impl": self.controller_impl,
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
        if not self.controller_impl:
            del prov["controller_impl"]
        return GainsEntry(self.controller, dict(self.gains), prov)
