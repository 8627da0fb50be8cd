"""What tuned gains do per case: full runs of tuned and default gains side by side.

Tuning prices gain sets over short horizons (``fuzzkit.studies.tuning.TUNING_HORIZON_S``); a
user then runs the whole experiment (``fuzzkit simulate E1 --gains gains.yaml``). This module
re-runs every (experiment, stiffness, latency) case of a
:class:`~fuzzkit.studies.tuning.TuneResult` over its full duration with the default and with the
tuned gains, on the same plant, loop and latency as the tuning, so that ``fuzzkit tune`` can say,
per stiffness and latency, whether the tuned gains settle faster or overshoot less than the
defaults, and by how much they are a compromise where they do not.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from fuzzkit.errors import ConfigError
from fuzzkit.studies.metrics import summary
from fuzzkit.studies.tuning import CaseRunner, TuneResult, TuningProblem


@dataclass(frozen=True, slots=True)
class CaseComparison:
    """One (experiment, stiffness, latency) case: tuning costs and full-run metrics, default vs
    tuned.

    ``default_axes`` / ``tuned_axes`` are :func:`fuzzkit.studies.metrics.summary`'s per-axis
    metrics (``overshoot_pct``, ``settling_time_s`` ...) of the full-length runs. ``latency``
    is None where the case kept its experiment's own.
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
    latency: tuple[int, int] | None = None

    @property
    def cost_change_pct(self) -> float:
        """Tuned cost relative to the defaults' (negative: better), percent."""
        if self.default_cost <= 0.0:
            return 0.0
        return 100.0 * (self.tuned_cost - self.default_cost) / self.default_cost


def compare_cases(result: TuneResult, seed: int | None = None) -> list[CaseComparison]:
    """Run every case of ``result`` in full with the default and the tuned gains.

    Parameters
    ----------
    result : from :func:`fuzzkit.studies.tuning.tune` (it carries the problem it solved).
    seed : sensor-noise seed of the runs (None: the tuning's own).

    Raises
    ------
    ConfigError
        A result that does not carry its tuning problem.
    """
    import dataclasses

    problem = result.problem
    if problem is None:
        raise ConfigError("compare_cases needs a tuning result that carries its problem")
    if seed is not None and seed != problem.noise_seed:
        problem = dataclasses.replace(problem, noise_seed=seed)
    return compare_gains(
        problem,
        result.baseline_gains,
        result.gains,
        [result.baseline_case_costs.get(c.label, float("nan")) for c in problem.case_keys],
        [result.case_costs[c.label] for c in problem.case_keys],
    )


def compare_gains(
    problem: TuningProblem,
    default_gains: Mapping[str, float],
    tuned_gains: Mapping[str, float],
    default_costs: Sequence[float] | None = None,
    tuned_costs: Sequence[float] | None = None,
) -> list[CaseComparison]:
    """Every case of ``problem`` run in full with ``default_gains`` and ``tuned_gains``.

    ``default_costs`` / ``tuned_costs``: the tuning costs per case when known (None: priced
    here, as the tuning prices them).
    """
    runner = CaseRunner(problem)
    if default_costs is None:
        default_costs = runner.case_costs(default_gains)
    if tuned_costs is None:
        tuned_costs = runner.case_costs(tuned_gains)
    out: list[CaseComparison] = []
    for i, case in enumerate(problem.case_keys):
        runs = [runner.run_case(i, g, None) for g in (default_gains, tuned_gains)]
        out.append(
            CaseComparison(
                label=case.label,
                experiment=case.experiment,
                stiffness_n_per_mm=case.stiffness_n_per_mm,
                default_cost=default_costs[i],
                tuned_cost=tuned_costs[i],
                default_axes=summary(runs[0])["axes"],
                tuned_axes=summary(runs[1])["axes"],
                default_tripped=runs[0].tripped,
                tuned_tripped=runs[1].tripped,
                latency=case.latency,
            )
        )
    return out
