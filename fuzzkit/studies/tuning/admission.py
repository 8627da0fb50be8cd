"""Admission: which priced gain sets the search may return (no worse than the default gains on
every case, or on every experiment's mean), and the penalty that steers the search towards them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

#: Weight of the search's penalty for being worse than the default gains on a case
#: (or an experiment, with ``admit="experiment"``).
PENALTY = 10.0

#: Admission rules: no worse than the defaults on every case, or on every experiment's mean.
ADMIT_RULES = ("case", "experiment")


@dataclass(frozen=True, slots=True)
class Evaluation:
    """One priced gain set: the searched gains, per-case costs, per-experiment costs, cost."""

    gains: dict[str, float]
    case_costs: tuple[float, ...]
    experiment_costs: tuple[float, ...]
    cost: float


def compared_pairs(
    ev: Evaluation, baseline: Evaluation | None, admit: str
) -> list[tuple[float, float]]:
    """(candidate, baseline) costs on each unit the admission rule ``admit`` compares."""
    if baseline is None:
        return []
    if admit == "case":
        return list(zip(ev.case_costs, baseline.case_costs, strict=True))
    return list(zip(ev.experiment_costs, baseline.experiment_costs, strict=True))


def admissible(ev: Evaluation, baseline: Evaluation | None, admit: str) -> bool:
    """No worse than the baseline on any case (or experiment, per ``admit``)."""
    return bool(ev.case_costs) and all(
        c <= b + 1e-12 for c, b in compared_pairs(ev, baseline, admit)
    )


def score(ev: Evaluation, baseline: Evaluation | None, admit: str) -> float:
    """What the search minimises: the cost plus :data:`PENALTY` times how much worse than the
    baseline ``ev`` is on each case (or experiment), which steers the search towards gain sets
    that :func:`choose` may return."""
    if baseline is None or not ev.experiment_costs:
        return ev.cost
    worse = sum(max(0.0, c - b) for c, b in compared_pairs(ev, baseline, admit))
    return ev.cost + PENALTY * worse


def choose(records: Sequence[Evaluation], baseline: Evaluation, admit: str) -> Evaluation:
    """The cheapest admissible evaluation of ``records`` (the baseline itself is admissible)."""
    ok = [ev for ev in records if admissible(ev, baseline, admit)]
    return min(ok or [baseline], key=lambda ev: ev.cost)


def means_by_experiment(case_costs: Mapping[str, float]) -> dict[str, float]:
    """Per-experiment means of costs keyed by case label (``E1@10N/mm``)."""
    groups: dict[str, list[float]] = {}
    for label, c in case_costs.items():
        groups.setdefault(label.split("@", 1)[0], []).append(c)
    return {k: sum(v) / len(v) for k, v in groups.items()}
