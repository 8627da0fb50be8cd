"""Sugeno rule bases through the table target: generated C and Python against a hand formula."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc, skip_no_cc
from _sugeno_reference import sugeno_pi_by_hand

from fuzzkit.codegen.emit import emit
from fuzzkit.codegen.lookup_table import LookupTable
from fuzzkit.codegen.table_search import make_table
from fuzzkit.codegen.verify import (
    load_module,
    python_outputs,
    verify_c,
    verify_python,
)
from fuzzkit.errors import CodegenError
from fuzzkit.formats.registry import load, loads
from fuzzkit.fuzzy.inference import Engine

RESOLUTION = 17
RULEBASES = Path(__file__).resolve().parent.parent / "rulebases"


def _hand(points: np.ndarray) -> np.ndarray:
    return np.array([sugeno_pi_by_hand(e, de) for e, de in points])


def _table(number_type: str) -> LookupTable:
    return make_table(load("sugeno_pi"), number_type=number_type, resolution=RESOLUTION)  # type: ignore[arg-type]


def test_generated_python_matches_the_engine_and_the_hand_formula_within_its_bound() -> None:
    rb = load("sugeno_pi")
    tab = _table("double")
    files = emit(rb, tab, "python")
    result = verify_python(rb, tab, files, n=20_000)
    assert result.ok, result.describe()
    points = np.random.default_rng(15).uniform(-1.3, 1.3, (5_000, 2))
    got = python_outputs(load_module(files, rb.name).eval, points)[:, 0]
    assert np.max(np.abs(got - _hand(points))) <= tab.bound[0] + 1e-12
    assert tab.bound[0] > 0  # linear consequents blend into a curved surface: not exact


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("number_type", ["float", "q15"])
def test_generated_c_matches_the_engine_and_the_hand_formula_within_its_bound(
    number_type: str,
) -> None:
    rb = load("sugeno_pi")
    tab = _table(number_type)
    result = verify_c(rb, tab, emit(rb, tab, "c"), n=20_000)
    assert result.ok, result.describe()
    # the engine the verification compares with agrees with the hand formula everywhere
    pts = np.random.default_rng(3).uniform(-1.3, 1.3, (2_000, 2))
    exact = Engine(rb).evaluate({"e": pts[:, 0], "de": pts[:, 1]})["du"]
    np.testing.assert_allclose(exact, _hand(pts), atol=1e-14)


def test_q15_refuses_a_sugeno_output_beyond_its_full_scale() -> None:
    text = (RULEBASES / "sugeno_pi.yaml").read_text(encoding="utf-8")
    rb = loads(text.replace("range: [-2, 2]", "range: [-1, 1]"))
    with pytest.raises(CodegenError, match=r"output du reaches 1\.6.*beyond the Q15 full scale 1"):
        make_table(rb, number_type="q15", resolution=RESOLUTION)
    # float and double hold any value: the same rule base compiles
    assert make_table(rb, number_type="float", resolution=RESOLUTION).bound[0] > 0
