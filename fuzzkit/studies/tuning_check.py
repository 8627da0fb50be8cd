"""What tuned gains do per stiffness: full runs of tuned and default gains side by side.

Tuning prices gain sets over short horizons (``fuzzkit.studies.tuning.TUNING_HORIZON_S``); a
user then runs the whole experiment (``fuzzkit simulate E1 --gains gains.yaml``). This module
re-runs every (experiment, stiffness) case of a :class:`~fuzzkit.studies.tuning.TuneResult`
over its full duration with the default and with the tuned gains, so that ``fuzzkit tune`` can
say, per stiffness, whether the tuned gains settle faster or overshoot less than the defaults,
and by how much they are a compromise where they do not.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fuzzkit.errors import ConfigError
from fuzzkit.studies.experiments import experiment, with_stiffness
from fuzzkit.studies.metrics import summary
from fuzzkit.studies.runner import load_surface, run
from fuzzkit.studies.tuning import TuneResult


@dataclass(frozen=True, slots=True)
class CaseComparison:
    """One (experiment, stiffness) case: tuning costs and full-run metrics, default vs tuned.

    ``default_axes`` / ``tuned_axes`` are :func:`fuzzkit.studies.metrics.summary`'s per-axis
    metrics (``overshoot_pct``, ``settling_time_s`` ...) of the full-length runs.
    """

    label: str
    experiment: str
    stiffness_n_per_mm: float
    default_cost: float
    tuned_cost: float
    default_axes: dict[str, dict[str, Any]]
    tuned_axes: dict[str, dict[str, Any]]
    default_tripped: bool
    tuned_tripped: bool

    @property
    def cost_change_pct(self) -> float:
        """Tuned cost relative to the defaults' (negative: better), percent."""
        if self.default_cost <= 0.0:
            return 0.0
        return 100.0 * (self.tuned_cost - self.default_cost) / self.default_cost


def compare_cases(result: TuneResult, seed: int = 0) -> list[CaseComparison]:
    """Run every case of ``result`` in full with the default and the tuned gains.

    Parameters
    ----------
    result : from :func:`fuzzkit.studies.tuning.tune` with experiments given by name and a
        plant given by name (what ``fuzzkit tune`` does).
    seed : sensor-noise seed of the runs.

    Raises
    ------
    ConfigError
        A fuzzy-PI result whose rule base was given as a function, not a name.
    """
    surface = None
    if result.controller == "fuzzy-pi":
        if result.rulebase is None:
            raise ConfigError("compare_cases needs a tuning result with a named rule base")
        surface = load_surface(result.rulebase)
    out: list[CaseComparison] = []
    for label, tuned_cost in result.case_costs.items():
        name = label.split("@", 1)[0]
        exp = experiment(name)
        k_mm = exp.scenario.contact.stiffness_n_per_m / 1e3
        if result.stiffnesses_n_per_mm is not None:
            k_mm = float(label.split("@", 1)[1].removesuffix("N/mm"))
            exp = with_stiffness(exp, k_mm * 1e3)
        runs = [
            run(exp, result.plant, result.controller, gains=g, surface=surface, seed=seed)
            for g in (result.baseline_gains, result.gains)
        ]
        out.append(
            CaseComparison(
                label=label,
                experiment=name,
                stiffness_n_per_mm=k_mm,
                default_cost=result.baseline_case_costs.get(label, float("nan")),
                tuned_cost=tuned_cost,
                default_axes=summary(runs[0])["axes"],
                tuned_axes=summary(runs[1])["axes"],
                default_tripped=runs[0].tripped,
                tuned_tripped=runs[1].tripped,
            )
        )
    return out
