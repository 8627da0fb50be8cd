"""The report's runs as data: every plant x experiment x controller x gains x condition.

A *condition* is where the claims are judged besides the nominal one (each experiment's own
latency, 1:1 periods, and stiffness, 10 N/mm): another latency at the nominal stiffness, or
another stiffness at the nominal latency. Each run is a :class:`~fuzzkit.studies.batch.RunSpec`
(the compiled loop where the plant has one, as ``fuzzkit simulate`` runs it), executed once per
report whatever asks for it (:class:`RunCache`), on local worker processes.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from fuzzkit.loop.spec import RunSpec
from fuzzkit.report.verdicts import NOMINAL, Key
from fuzzkit.studies.batch import gains_items, map_runs
from fuzzkit.studies.experiments import DEFAULT_LATENCY
from fuzzkit.units import latency_text

#: The stiffness of every shipped experiment (N/mm): the nominal condition's.
NOMINAL_STIFFNESS_N_PER_MM = 10.0


@dataclass(frozen=True, slots=True)
class Condition:
    """Where claims are judged: a latency and a stiffness (None: the experiment's own)."""

    label: str
    latency: tuple[int, int] | None = None
    stiffness_n_per_mm: float | None = None


def conditions(
    latencies: Sequence[tuple[int, int]], stiffnesses_n_per_mm: Sequence[float]
) -> list[Condition]:
    """The nominal condition, then each latency at the nominal stiffness, then each stiffness
    at the nominal latency (values equal to the nominal ones are the nominal condition)."""
    out = [Condition(NOMINAL)]
    for a, b in latencies:
        if (a, b) != DEFAULT_LATENCY:
            out.append(Condition(f"latency {latency_text((a, b))}", latency=(a, b)))
    for k in stiffnesses_n_per_mm:
        if k != NOMINAL_STIFFNESS_N_PER_MM:
            out.append(Condition(f"{k:g} N/mm", stiffness_n_per_mm=float(k)))
    return out


def spec(
    plant: str,
    experiment: str,
    controller: str,
    gains: Mapping[str, float],
    condition: Condition,
    rulebase: str,
) -> RunSpec:
    """The run of one cell (noise seed 0, as ``fuzzkit compare``)."""
    return RunSpec(
        experiment=experiment,
        controller=controller,
        plant=plant,
        stiffness_n_per_mm=condition.stiffness_n_per_mm,
        latency=condition.latency,
        gains=gains_items(gains),
        gains_label="report",
        rulebase=rulebase,
    )


def _summary(s: RunSpec) -> dict[str, Any]:
    from fuzzkit.studies.batch import run_spec
    from fuzzkit.studies.metrics import summary

    return summary(run_spec(s))


class RunCache:
    """Run summaries by :class:`RunSpec`: each distinct run is simulated once per report (the
    matched PI is the default PI; the nominal cell of every sweep is the main table's run)."""

    def __init__(self) -> None:
        self.summaries: dict[RunSpec, dict[str, Any]] = {}

    def put(self, s: RunSpec, summary: dict[str, Any]) -> None:
        """Remember the summary of a run made elsewhere (the report's traced runs)."""
        self.summaries[s] = summary

    def run(
        self,
        specs: Sequence[RunSpec],
        workers: int | None = None,
        progress: Callable[[int], None] | None = None,
    ) -> list[dict[str, Any]]:
        """The summaries of ``specs``, in order; the runs not yet made run on ``workers``
        local processes (None: every core). ``progress`` gets the count of new runs done."""
        todo = [s for s in dict.fromkeys(specs) if s not in self.summaries]
        rows = map_runs(_summary, todo, workers=workers, progress=progress)
        self.summaries.update(zip(todo, rows, strict=True))
        return [self.summaries[s] for s in specs]

    def missing(self, specs: Sequence[RunSpec]) -> int:
        """How many distinct runs of ``specs`` are not made yet."""
        return len([s for s in dict.fromkeys(specs) if s not in self.summaries])


def grid_summaries(
    cache: RunCache,
    plants: Sequence[str],
    experiments: Sequence[str],
    controllers: Sequence[str],
    gains: Mapping[tuple[str, str], Mapping[str, float]],
    labels: Sequence[str],
    conds: Sequence[Condition],
    rulebase: str,
    workers: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> dict[str, dict[Key, dict[str, Any]]]:
    """Per condition label, ``{(plant, experiment, controller, gains label): summary}`` for
    every combination (what :func:`fuzzkit.report.verdicts.assess_claims` reads)."""
    cells: list[tuple[str, Key, RunSpec]] = [
        (
            c.label,
            (plant, exp, ctrl, label),
            spec(plant, exp, ctrl, gains[(ctrl, label)], c, rulebase),
        )
        for c in conds
        for plant in plants
        for exp in experiments
        for ctrl in controllers
        for label in labels
    ]
    rows = cache.run([s for _, _, s in cells], workers, progress)
    out: dict[str, dict[Key, dict[str, Any]]] = {c.label: {} for c in conds}
    for (cond, key, _), row in zip(cells, rows, strict=True):
        out[cond][key] = row
    return out
