"""``compile`` of any rule base that validates finishes or refuses with the reason, in bounded
work (``codegen/budget.py``): the exact engine's estimated time is charged before each batch of
points, and a batch that would pass the budget is refused, not run.

Not timed: the bound is in the code. Each compile here counts every point the exact engine
evaluates, at the engine's own estimate of its time per point, and that total must stay within
the budget; speed itself is measured in ``make bench``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from _random_rulebases import random_rulebase

from fuzzkit.codegen.budget import SEARCH_SECONDS, VERIFY_SECONDS
from fuzzkit.codegen.method import compile_rulebase
from fuzzkit.codegen.verify import verify_exact_python
from fuzzkit.errors import CodegenError
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy import inference
from fuzzkit.fuzzy.model import RuleBase, Term

GAUSSIAN = Path(__file__).parent / "data" / "gaussian3x3.yaml"


@pytest.fixture
def engine_seconds(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[float]]:
    """The estimated engine seconds of every point any Engine evaluates (summed in [0])."""
    spent = [0.0]
    evaluate = inference.Engine.evaluate

    def counting(self: inference.Engine, inputs: Mapping[str, Any]) -> dict[str, Any]:
        size = math.prod(np.broadcast_shapes(*[np.shape(v) for v in inputs.values()]))
        spent[0] += size * self.work_per_point() / inference.OPERATIONS_PER_SECOND
        return evaluate(self, inputs)

    monkeypatch.setattr(inference.Engine, "evaluate", counting)
    yield spent


def _compile_or_refuse(rb: RuleBase) -> str:
    try:
        result = compile_rulebase(rb, "c", "double")
    except CodegenError as exc:
        message = str(exc)
        assert rb.name in message and len(message) > 60  # names the rule base and says why
        return "refused"
    assert result.files
    return result.method


def test_a_smooth_output_table_search_is_refused_before_the_engine_passes_its_budget(
    engine_seconds: list[float],
) -> None:
    base = load(GAUSSIAN)
    out = base.outputs[0]
    bells = tuple(Term(t.name, "bell", (0.3, 2.0, t.params[0])) for t in out.terms)
    rb = dataclasses.replace(base, name="bell3x3", outputs=(dataclasses.replace(out, terms=bells),))
    with pytest.raises(CodegenError, match=r"bell3x3: the table search would need the exact "
                       r"engine for about [\d,]+ s .* more than the 40 s"):  # fmt: skip
        compile_rulebase(rb, "c", "double")
    assert 0 < engine_seconds[0] <= SEARCH_SECONDS


def test_verify_is_refused_before_the_engine_passes_its_budget(
    monkeypatch: pytest.MonkeyPatch, engine_seconds: list[float]
) -> None:
    rb = load(GAUSSIAN)
    files = compile_rulebase(rb, "python", "double", method="exact").files
    monkeypatch.setattr(inference, "OPERATIONS_PER_SECOND", 1.0)  # every point costs a lot
    monkeypatch.setattr("fuzzkit.codegen.budget.OPERATIONS_PER_SECOND", 1.0)
    engine_seconds[0] = 0.0
    with pytest.raises(CodegenError, match=r"--verify would need the exact engine"):
        verify_exact_python(rb, files, n=100)
    assert engine_seconds[0] == 0.0  # refused before a single point
    assert VERIFY_SECONDS > 0


#: Random rule bases (seed, MATLAB shapes): every shape, operator and defuzzifier between
#: them; make test's are the quick ones (a refusal by the budget, one for a discontinuous
#: defuzzifier without an exact form, an exact compile), make verify's cost up to a minute.
COVER = [(0, True), (2, True), (10, True), (0, False), (5, True)]
FULL = [(1, True), (6, True), (12, True), (13, True), (1, False), (5, False), (10, False),
        (11, False)]  # fmt: skip


@pytest.mark.parametrize(
    ("seed", "matlab"),
    [pytest.param(*c, id=f"cover-{c[0]}-{'matlab' if c[1] else 'plain'}") for c in COVER]
    + [
        pytest.param(*c, id=f"full-{c[0]}-{'matlab' if c[1] else 'plain'}",
                     marks=pytest.mark.verify)
        for c in FULL
    ],
)  # fmt: skip
def test_random_rule_bases_compile_or_refuse_with_the_reason_in_bounded_work(
    seed: int, matlab: bool, engine_seconds: list[float]
) -> None:
    rb = random_rulebase(seed, "clamp", matlab_shapes=matlab)
    assert _compile_or_refuse(rb) in ("exact", "table", "refused")
    assert engine_seconds[0] <= SEARCH_SECONDS


@pytest.mark.verify  # about 6 CPU-s of search
def test_a_partition_table_without_a_compiler_is_searched_not_refused(
    monkeypatch: pytest.MonkeyPatch, engine_seconds: list[float]
) -> None:
    """Without a C compiler every check grid of the search is the engine's. MacVicar-Whelan's
    fast centroid costs about 2 us a point measured; the budget once charged it as the
    breakpoint sweep (0.077 ms a point) and refused this search at 41 estimated seconds."""
    monkeypatch.setattr("fuzzkit.codegen.toolchain.find_compiler", lambda *a, **k: None)
    rb = load("macvicar_whelan")
    result = compile_rulebase(rb, "python", "double", method="table", tolerance=0.0005)
    assert result.method == "table" and result.table is not None
    assert result.table.bound[0] <= 0.0005 * (
        rb.outputs[0].high - rb.outputs[0].low
    )  # of the range
    assert 0 < engine_seconds[0] <= SEARCH_SECONDS
