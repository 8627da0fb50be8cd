"""Latency stability study: for each gain factor, how many periods of delay the loop survives.

The test problem is :func:`~fuzzkit.studies.experiments.press_experiment` (press 10 N on the
hammer from 0.2 mm above it, 10 N/mm): it isolates the force loop from the approach. The gains
are the defaults times a factor (PI: ``kp`` and ``ki``; fuzzy-PI: ``kx``), the delay is sensor
delay with no command delay (the loop only sees the sum; the correction always reaches the
plant one period after it is computed).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from fuzzkit.loop.result import RunResult
from fuzzkit.studies.experiments import press_experiment, scaled_default_gains
from fuzzkit.studies.outcome import SETTLED, end_state

__all__ = ["StabilityMap", "is_stable", "scaled_default_gains", "stability_map"]


@dataclass(frozen=True, slots=True)
class StabilityMap:
    """``stable[i][j]``: the loop with ``factors[i]`` x the default gains and ``delays[j]``
    periods of sensor delay settles (see :func:`is_stable`); ``controller_impl``: what ran the
    controller, as the runs report it (:func:`fuzzkit.loop.result.implementations`)."""

    controller: str
    factors: tuple[float, ...]
    delays: tuple[int, ...]
    stable: tuple[tuple[bool, ...], ...]
    controller_impl: str = ""

    def boundary(self) -> dict[float, int | None]:
        """Per gain factor, the largest delay up to which every delay of the sweep is stable
        (None: unstable even without delay)."""
        out: dict[float, int | None] = {}
        for factor, row in zip(self.factors, self.stable, strict=True):
            last: int | None = None
            for delay, ok in zip(self.delays, row, strict=True):
                if not ok:
                    break
                last = delay
            out[factor] = last
        return out


def is_stable(result: RunResult) -> bool:
    """True when the run ended settled (:func:`fuzzkit.studies.outcome.end_state`)."""
    return end_state(result) == SETTLED


def stability_map(
    controller: str,
    factors: Sequence[float],
    delays: Sequence[int],
    rulebase: str = "macvicar_whelan",
    plant: str = "planar",
    duration_s: float = 2.0,
) -> StabilityMap:
    """Run the press experiment for every gain factor and delay (one seed: 1), each run as
    ``fuzzkit simulate`` runs it (:func:`fuzzkit.loop.run.run_loop`: the generated
    controller, in the compiled loop where the plant has one)."""
    from fuzzkit.loop.result import implementations
    from fuzzkit.loop.run import run_loop
    from fuzzkit.loop.spec import RunSpec
    from fuzzkit.studies.batch import gains_items

    exp = press_experiment(1.0e4)
    rows = []
    ran: list[str] = []
    for factor in factors:
        gains = gains_items(scaled_default_gains(controller, factor))
        runs = [
            RunSpec(exp.name, controller, plant, seed=1, gains=gains, rulebase=rulebase,
                    latency=(delay, 0), duration_s=duration_s)
            for delay in delays
        ]  # fmt: skip
        results = [run_loop(r, exp, plant) for r in runs]
        ran += (r.controller_impl for r in results)
        rows.append(tuple(is_stable(r) for r in results))
    return StabilityMap(
        controller, tuple(factors), tuple(delays), tuple(rows), implementations(ran)
    )
