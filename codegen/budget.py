"""The time a compile may spend in the exact engine, checked before the work is done.

``fuzzkit compile`` of any type-1 rule base that validates finishes or refuses within about a
minute. The expensive part is the exact engine's evaluation of the points a table search
certifies its bound on, or ``--verify`` compares on: for smooth output terms that the exact
method cannot compile (bell, sigmoid, MATLAB's shapes, Gaussians under a sum aggregation) the
engine integrates every point on a grid of up to a million points, milliseconds a point. An
:class:`EngineBudget` is charged with every batch of points *before* the engine evaluates it,
at the engine's own estimate of its time per point
(``fuzzkit.fuzzy.inference.Engine.work_per_point``: each output path's cost calibrated
against this project's 2-core machine, at about twice what it measures), after the engine's
construction (``Engine.construction_work``), and refuses with the reason once a batch would
pass its seconds: the answer does not depend on the machine's load (a calibrated model, not a
clock), and no work is started that the budget cannot pay.
"""

from __future__ import annotations

from fuzzkit.errors import CodegenError
from fuzzkit.fuzzy.inference import OPERATIONS_PER_SECOND, Engine

#: Engine seconds a table search may spend (node values and the check grids the compiled
#: exact method cannot take), and ``--verify``'s engine evaluation.
SEARCH_SECONDS = 40.0
VERIFY_SECONDS = 20.0
#: The hint in the refusal: what compiles fast.
FAST_CHOICES = (
    "the exact method compiles piecewise-linear output terms, Gaussian ones under max "
    "aggregation, Sugeno outputs and the weighted_average defuzzifier"
)


class EngineBudget:
    """Estimated engine seconds spent so far for one ``task`` against a limit of ``seconds``;
    the engine's construction is the first thing it counts."""

    def __init__(self, engine: Engine, task: str, seconds: float) -> None:
        self.name = engine.rulebase.name
        self.per_point = engine.work_per_point() / OPERATIONS_PER_SECOND
        self.task = task
        self.seconds = seconds
        self.spent = engine.construction_work() / OPERATIONS_PER_SECOND

    def charge(self, points: int) -> None:
        """Book ``points`` engine evaluations, or refuse (CodegenError) if they would pass the
        budget; call it before evaluating them."""
        cost = points * self.per_point
        if self.spent + cost > self.seconds:
            raise CodegenError(
                f"rule base {self.name}: {self.task} would need the exact engine for about "
                f"{self.spent + cost:,.0f} s ({points:,} more points at about "
                f"{1e3 * self.per_point:.3g} ms a point), more than the {self.seconds:.0f} s a "
                f"compile may spend there; {FAST_CHOICES}"
            )
        self.spent += cost


__all__ = ["SEARCH_SECONDS", "VERIFY_SECONDS", "EngineBudget"]
